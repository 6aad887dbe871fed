//! What fuzzy clustering shows and teaches: its overlay layers (clusters of shading points and of VPLs, the
//! probe's memberships), their legends and hover texts, the per-pixel cluster maps and the probe's shadow rays,
//! and the Explain steps of the paper.

use super::*;

impl FuzzyClustering {
    pub(super) fn explain_steps(&self) -> Vec<crate::technique::ExplainStep> {
        use crate::technique::ExplainStep;
        vec![
            ExplainStep {
                title: "1. VPLs",
                text:
                    "Particles traced from the lights leave virtual point lights where they land (the shared VPL set).",
                layers: &["vpls (flux)", "vpls (flux, every n-th)"],
                shows_shadow_maps: true,
                maps: crate::technique::RSM_MAPS,
                ..Default::default()
            },
            ExplainStep {
                title: "2. VPL clusters",
                text: "K_vpl clusters by k-means over position and normal (equation 7: no two normals more than 30 \
                       degrees apart); each becomes one light at its representative with its members' flux. Shown: \
                       the VPLs clustered alone, every pixel tracing its own ray to each representative (section \
                       4's ablation, 'Clustered' = vpl).",
                layers: &["vpls by cluster", "vpls by cluster (every n-th)", "vpl cluster representatives"],
                shows_shadow_maps: false,
                params: &[("cluster", "vpl")],
                ..Default::default()
            },
            ExplainStep {
                title: "3-4. Shading-point clusters",
                text: "The pixels' positions and normals clustered the same way (every gamma-th pixel in the \
                       iterations), then every pixel assigned to its F nearest clusters. Shown: the shading points \
                       clustered alone, every VPL its own light ('Clustered' = sp).",
                layers: &["shading-point clusters", "shading-point centroids"],
                shows_shadow_maps: false,
                params: &[("cluster", "sp")],
                ..Default::default()
            },
            ExplainStep {
                title: "5. Visibility between representatives",
                text: "One shadow ray from each shading-point cluster's representative to each light: K_sp x K_vpl \
                       rays instead of one per pixel and VPL. Alt+click a pixel to see its clusters' rays (green \
                       visible, red blocked). Shown: both clustered, each pixel with its nearest cluster's visibility \
                       alone ('Visibility' = hard): the clusters' borders show.",
                layers: &[
                    "probe: clusters and visibility rays (green visible, red blocked)",
                    "vpl cluster representatives",
                ],
                shows_shadow_maps: false,
                params: &[("cluster", "both"), ("mode", "hard")],
                ..Default::default()
            },
            ExplainStep {
                title: "6. Weighted visibility",
                text: "Each pixel shades every light with its own BRDF and geometry term and the visibility of its F \
                       clusters, weighted by inverse distance (weighted), equally (fuzzy) or its nearest only (hard). \
                       Shown: the panel's choices again (both clustered, weighted, by default).",
                layers: &["shading-point clusters (blended as the visibility mode weighs them)"],
                shows_shadow_maps: false,
                ..Default::default()
            },
        ]
    }

    pub(super) fn legend_of(&self, layer: &OverlayLayer) -> Vec<crate::technique::LegendEntry> {
        use crate::technique::{Glyph, LegendEntry};
        let palette = index_color(0);
        let mut legend = match layer.name {
            "vpls by cluster" | "vpls by cluster (every n-th)" => {
                vec![LegendEntry::new(Glyph::Palette, palette, "a VPL, in its cluster's colour")]
            }
            "vpl cluster representatives" => vec![LegendEntry::new(
                Glyph::Palette,
                palette,
                "a VPL cluster's representative: the light it becomes (members' flux, mean normal)",
            )],
            "shading-point clusters" => {
                vec![LegendEntry::new(
                    Glyph::Pixels,
                    palette,
                    "each pixel in its nearest shading-point cluster's colour",
                )]
            }
            "shading-point clusters (blended as the visibility mode weighs them)" => vec![LegendEntry::new(
                Glyph::Pixels,
                palette,
                "each pixel: its F clusters' colours blended by the visibility weights",
            )],
            "shading-point centroids" => {
                vec![LegendEntry::new(Glyph::Palette, palette, "a shading-point cluster's centroid")]
            }
            "probe: clusters and visibility rays (green visible, red blocked)" => vec![
                LegendEntry::new(Glyph::Dot, palette, "the probed pixel's F clusters' representatives"),
                LegendEntry::new(Glyph::Line, [0.2, 1.0, 0.3, 0.8], "a shadow ray that reaches its light"),
                LegendEntry::new(Glyph::Line, [1.0, 0.2, 0.2, 0.8], "a shadow ray that is blocked"),
            ],
            _ => crate::services::vpl_gather::vpl_layer_legend(layer)
                .or_else(|| crate::technique::light_layer_legend(layer))
                .unwrap_or_default(),
        };
        legend.extend(layer.summary());
        legend
    }

    pub(super) fn hover_list(&self) -> Vec<crate::technique::HoverPoint> {
        let ins = &self.inspection;
        let clusters = |layer: &'static str, points: &[GpuPoint]| -> Vec<crate::technique::HoverPoint> {
            let live = points.iter().enumerate().filter(|(_, c)| c.exists());
            live.map(|(index, c)| crate::technique::HoverPoint { layer, position: c.position(), index }).collect()
        };
        let mut points = clusters("vpl cluster representatives", &ins.vpl_clusters);
        points.extend(clusters("shading-point centroids", &ins.sp_centroids));
        // The VPLs of the "vpls by cluster" layer (every n-th past 4,096, as it draws them), then the shared layers'.
        let vpls = &self.vpls.vpls;
        let stride = vpls.len().div_ceil(4096).max(1);
        let layer = if stride > 1 { "vpls by cluster (every n-th)" } else { "vpls by cluster" };
        let assigned =
            vpls.iter().zip(&ins.vpl_assignment).enumerate().step_by(stride).filter(|(_, (_, &k))| k != u32::MAX);
        points.extend(assigned.map(|(index, (v, _))| crate::technique::HoverPoint {
            layer,
            position: v.position,
            index,
        }));
        points.extend(crate::services::vpl_gather::vpl_hover_points(&self.vpls));
        points
    }

    pub(super) fn hover_text(&self, layer: &str, index: usize) -> Vec<String> {
        let ins = &self.inspection;
        let cluster = |what: &str, points: &[GpuPoint]| -> Vec<String> {
            let Some(c) = points.get(index).filter(|c| c.exists()) else { return Vec::new() };
            let live = points.iter().filter(|c| c.exists()).count();
            let n = c.normal();
            vec![
                format!("{what} {index} ({live} with members)"),
                format!("{} members", c.members()),
                format!("normal ({:.2}, {:.2}, {:.2})", n.x, n.y, n.z),
            ]
        };
        match layer {
            "vpl cluster representatives" => cluster("VPL cluster", &ins.vpl_clusters),
            "shading-point centroids" => cluster("shading-point cluster", &ins.sp_centroids),
            // A pixel's cluster in the per-pixel map: the cluster's representative.
            "shading-point clusters" => cluster("shading-point cluster", &ins.sp_clusters),
            l if l.starts_with("vpls by cluster") || crate::services::vpl_gather::is_vpl_layer(&self.vpls, l) => {
                let mut lines = crate::services::vpl_gather::vpl_details(&self.vpls, index);
                if let Some(k) = ins.vpl_assignment.get(index).filter(|k| **k != u32::MAX) {
                    lines.push(format!("in VPL cluster {k}"));
                }
                lines
            }
            _ => Vec::new(),
        }
    }

    /// The overlays while a light or the camera moves: step 2 again on the CPU twin ([`kmeans::cluster`], the
    /// GPU run's algorithm) over the preview's VPLs, so the VPL clusters and their representatives follow a
    /// dragged light in the same UI frame. The shading-point clusters are of the last frame's G-buffer: live
    /// while only lights move, stale once the camera moved; the probe's rays (step 5) are always stale.
    pub(super) fn follow(&mut self, ctx: &crate::technique::OverlayContext) -> crate::technique::OverlayUpdate {
        const SP_LAYERS: [&str; 3] = [
            "shading-point clusters",
            "shading-point clusters (blended as the visibility mode weighs them)",
            "shading-point centroids",
        ];
        // The VPL clusters were made from this very set (the last frame's, the lights unmoved): kept.
        let same_set = Arc::ptr_eq(&self.vpls, ctx.vpls);
        self.vpls = ctx.vpls.clone();
        self.scene_size = ctx.scene_bounds.size().length().max(1e-6);
        let vpls = &self.vpls.vpls;
        if !same_set && self.params.cluster_mode() != ClusterMode::ShadingPoints && !vpls.is_empty() {
            let points: Vec<kmeans::Point> =
                vpls.iter().map(|v| kmeans::Point { position: v.position, normal: v.normal, valid: true }).collect();
            let kp = self.kmeans_params(ctx.scene_bounds, self.params.k_vpl as usize, vpls.len() as u32, 1, 1, 1);
            let c = kmeans::cluster(&points, &kp);
            let mut flux = vec![Vec3::ZERO; c.centroids.len()];
            for (m, v) in vpls.iter().enumerate() {
                if let Some(&k) = c.assignment.get(m * c.fuzziness).filter(|&&k| k != u32::MAX) {
                    flux[k as usize] += v.flux;
                }
            }
            // As `rep_finish` of `fuzzy/kmeans.wgsl` stores a cluster: its representative's position, the members'
            // mean normal and count, their summed flux.
            self.inspection.vpl_clusters = (0..c.centroids.len())
                .map(|k| match c.representative[k] {
                    Some(r) if c.members[k] > 0 => gpu::GpuPoint {
                        position: vpls[r as usize].position.extend(1.0).to_array(),
                        normal: c.member_normal[k].extend(c.members[k] as f32).to_array(),
                        flux: flux[k].extend(0.0).to_array(),
                    },
                    _ => gpu::GpuPoint { normal: [0.0, 0.0, 1.0, 0.0], ..Default::default() },
                })
                .collect();
            if self.params.inspect {
                self.inspection.vpl_assignment = (0..vpls.len()).map(|m| c.assignment[m * c.fuzziness]).collect();
            }
        }
        const PROBE: &str = "probe: clusters and visibility rays (green visible, red blocked)";
        let mut stale_layers = Vec::new();
        let mut note = ctx.vpl_note();
        if self.frame_camera.as_ref() != Some(ctx.camera) {
            // The camera moved: the shading points (and the probe) again on the CPU, or the last frame's layers,
            // said stale.
            match self.follow_view(ctx) {
                Some(view) => note = Some(note.map_or(view.clone(), |n| format!("{n}; {view}"))),
                None => stale_layers.extend(SP_LAYERS.iter().chain([&PROBE])),
            }
        } else if !same_set {
            // Only the lights moved: the probe's rays go to the frame's VPL clusters, which moved with them.
            stale_layers.push(PROBE);
        }
        crate::technique::OverlayUpdate::Live { note, stale_layers }
    }

    pub(super) fn overlay_layers(&self, _lights: &[PointLight]) -> Vec<OverlayLayer> {
        let ins = &self.inspection;
        let half = self.scene_size * 0.004;
        let vpls = &self.vpls.vpls;
        let stride = vpls.len().div_ceil(4096).max(1);
        let mut layers = Vec::new();
        if !ins.vpl_assignment.is_empty() {
            layers.push(OverlayLayer {
                name: if stride > 1 { "vpls by cluster (every n-th)" } else { "vpls by cluster" },
                visible_by_default: true,
                primitives: vpls
                    .iter()
                    .zip(&ins.vpl_assignment)
                    .step_by(stride)
                    .filter(|(_, &k)| k != u32::MAX)
                    .map(|(v, &k)| {
                        let (t, b) = v.normal.any_orthonormal_pair();
                        Overlay::Rect {
                            center: v.position,
                            half_u: t * half,
                            half_v: b * half,
                            color: index_color(k as usize),
                        }
                    })
                    .collect(),
            });
        }
        if !ins.vpl_clusters.is_empty() {
            layers.push(OverlayLayer {
                name: "vpl cluster representatives",
                visible_by_default: true,
                primitives: ins
                    .vpl_clusters
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| c.exists())
                    .map(|(k, c)| Overlay::Point { position: c.position(), color: index_color(k), radius_px: 5.0 })
                    .collect(),
            });
        }
        let (w, h) = ins.map_size;
        if let Some(ids) = &ins.hard_map {
            layers.push(OverlayLayer {
                name: "shading-point clusters",
                visible_by_default: false,
                primitives: vec![Overlay::IdMap { width: w, height: h, ids: ids.clone(), alpha: 0.5 }],
            });
        }
        if let Some(rgba) = &ins.blend_map {
            layers.push(OverlayLayer {
                name: "shading-point clusters (blended as the visibility mode weighs them)",
                visible_by_default: false,
                primitives: vec![Overlay::ColorMap { width: w, height: h, rgba: rgba.clone() }],
            });
        }
        if !ins.sp_centroids.is_empty() {
            layers.push(OverlayLayer {
                name: "shading-point centroids",
                visible_by_default: false,
                primitives: ins
                    .sp_centroids
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| c.exists())
                    .map(|(k, c)| Overlay::Point { position: c.position(), color: index_color(k), radius_px: 3.0 })
                    .collect(),
            });
        }
        layers.push(OverlayLayer {
            name: "probe: clusters and visibility rays (green visible, red blocked)",
            visible_by_default: true,
            primitives: ins.probe.clone(),
        });
        layers.extend(vpl_overlays(&self.vpls, self.scene_size, 0).into_iter().map(|mut l| {
            l.visible_by_default = false;
            l
        }));
        layers
    }
}

impl FuzzyClustering {
    /// The per-pixel ID maps of the shading-point clusters (hard, and blended by the mode's weights) from the
    /// read-back assignment.
    pub(super) fn build_pixel_maps(&mut self) {
        let ins = &mut self.inspection;
        let (w, h) = ins.size;
        let f = self.sp_kmeans.shape.fuzziness.max(1);
        let pixels = w as usize * h as usize;
        if ins.sp_assignment.is_empty() || ins.sp_assignment.len() != pixels * f {
            return;
        }
        let (hard, blend) = pixel_maps(self.params.shade_mode(), f, &ins.sp_assignment, &ins.sp_inverse);
        ins.map_size = (w, h);
        ins.hard_map = Some(Arc::new(hard));
        ins.blend_map = Some(Arc::new(blend));
    }

    /// The probe overlay: the chosen pixel's F clusters (their representatives) and a shadow ray from each to
    /// every light (at most 4,096 lines), green when visible, red when blocked, traced on the CPU through the
    /// BVH with the same offsets as the GPU.
    pub(super) fn probe_overlay(&self, ctx: &FrameContext, lights: &[GpuPoint]) -> Vec<Overlay> {
        let (w, h) = self.inspection.size;
        let (x, y) = (self.params.probe_x, self.params.probe_y);
        let f = self.sp_kmeans.shape.fuzziness;
        if x < 0 || y < 0 || x as u32 >= w || y as u32 >= h || self.inspection.sp_assignment.is_empty() {
            return Vec::new();
        }
        let pixel = (y as usize) * w as usize + x as usize;
        let entries = &self.inspection.sp_assignment[pixel * f..pixel * f + f];
        self.probe_rays(ctx.camera.position, entries, &self.inspection.sp_clusters, lights)
    }

    /// A probed point's clusters (`entries`, its F nearest, of `clusters`) and a shadow ray from each one's
    /// representative to every light (at most 4,096 lines), green when visible, red when blocked, traced on the
    /// CPU through the BVH with the GPU's offsets (`ray_bias` of the distance from `eye`).
    pub(super) fn probe_rays(
        &self,
        eye: Vec3,
        entries: &[u32],
        clusters: &[GpuPoint],
        lights: &[GpuPoint],
    ) -> Vec<Overlay> {
        let Some(bvh) = &self.bvh else { return Vec::new() };
        let live: Vec<&GpuPoint> = lights.iter().filter(|l| l.exists()).collect();
        let used = entries.iter().take_while(|&&k| k != u32::MAX).count().max(1);
        let stride = (used * live.len()).div_ceil(4096).max(1);
        let mut out = Vec::new();
        for &k in entries.iter().take_while(|&&k| k != u32::MAX) {
            let Some(rep) = clusters.get(k as usize).filter(|r| r.exists()) else { continue };
            out.push(Overlay::Point { position: rep.position(), color: index_color(k as usize), radius_px: 7.0 });
            let eps = self.params.ray_bias * (eye - rep.position()).length().max(1.0);
            let origin = rep.position() + rep.normal() * eps;
            for light in live.iter().step_by(stride) {
                let target = light.position() + light.normal() * eps;
                let to = target - origin;
                let d = to.length();
                let visible = d <= 2.0 * eps || bvh.closest_hit(origin, to / d, d - eps).is_none();
                let color = if visible { [0.2, 1.0, 0.3, 0.8] } else { [1.0, 0.2, 0.2, 0.8] };
                out.push(Overlay::Line { from: rep.position(), to: light.position(), color });
            }
        }
        out
    }
}

/// The per-pixel maps of an assignment of `F` entries a pixel: each pixel's nearest cluster, and the clusters'
/// colours blended by the mode's weights (transparent where the pixel has no cluster).
pub(super) fn pixel_maps(
    mode: kmeans::ShadeMode,
    f: usize,
    assignment: &[u32],
    inverse: &[f32],
) -> (Vec<u32>, Vec<[u8; 4]>) {
    let f = f.max(1);
    let hard = assignment.iter().step_by(f).copied().collect();
    let blend = (0..assignment.len() / f)
        .map(|m| {
            let e = &assignment[m * f..m * f + f];
            if e[0] == u32::MAX {
                return [0, 0, 0, 0];
            }
            let weights = kmeans::weights(mode, e, &inverse[m * f..m * f + f]);
            let mut c = [0.0f32; 3];
            for (&k, &wt) in e.iter().zip(&weights) {
                if k != u32::MAX && wt > 0.0 {
                    let col = index_color(k as usize);
                    for i in 0..3 {
                        c[i] += wt * col[i];
                    }
                }
            }
            [(c[0] * 255.0) as u8, (c[1] * 255.0) as u8, (c[2] * 255.0) as u8, 140]
        })
        .collect();
    (hard, blend)
}
