//! What LightCluster shows and teaches: its overlay layers (lights by cluster, centers, member lines, `d_min` and
//! `C_att` spheres), the cluster-per-pixel ID map, legends, a light's cluster details and the Explain steps of the
//! paper.

use glam::Vec3;

use super::{cluster_color, Centers, LightCluster};
use crate::scene::PointLight;
use crate::technique::{ExplainStep, Glyph, LegendEntry, LightDetails, Overlay, OverlayLayer};

impl LightCluster {
    /// Per pixel, the cluster whose center is nearest among those whose `C_att` reaches the pixel: the cluster
    /// whose shadow map shades it most.
    pub(super) fn pixel_id_map(&self, positions: &[Option<Vec3>]) -> Option<(&'static str, Vec<u32>)> {
        let clusters = &self.clustering.clusters;
        // A grid of the C_att spheres: each pixel tests the clusters of its cell, not all (the app draws this map
        // on its UI thread; testing every cluster is 460 M distance tests for 0.9 M pixels and 500 clusters).
        let grid = crate::math::SphereGrid::new(&clusters.iter().map(|c| (c.position, c.c_att)).collect::<Vec<_>>());
        let ids = positions
            .iter()
            .map(|p| {
                let Some(p) = p else { return u32::MAX };
                let mut best = (u32::MAX, f32::INFINITY);
                for i in grid.candidates(*p) {
                    let c = &clusters[i as usize];
                    let d = c.position.distance_squared(*p);
                    // Ties to the lower index, as the full scan had it.
                    if d <= c.c_att * c.c_att && (d < best.1 || (d == best.1 && i < best.0)) {
                        best = (i, d);
                    }
                }
                best.0
            })
            .collect();
        Some(("cluster per pixel", ids))
    }

    pub(super) fn overlay_layers(&self, lights: &[PointLight]) -> Vec<OverlayLayer> {
        let clusters = &self.clustering.clusters;
        let valid = |i: usize| i < lights.len();
        let mut by_cluster = Vec::new();
        let mut centers = Vec::new();
        let mut lines = Vec::new();
        let mut d_min_spheres = Vec::new();
        let mut c_att_spheres = Vec::new();
        for (ci, c) in clusters.iter().enumerate() {
            let color = cluster_color(ci);
            for &m in c.members.iter().filter(|&&m| valid(m)) {
                by_cluster.push(Overlay::Point { position: lights[m].position, color, radius_px: 4.0 });
                if m != c.center {
                    lines.push(Overlay::Line { from: lights[m].position, to: c.position, color });
                }
            }
            centers.push(Overlay::Point { position: c.position, color: [1.0, 1.0, 1.0, 1.0], radius_px: 7.0 });
            let translucent = [color[0], color[1], color[2], 0.5];
            d_min_spheres.push(Overlay::Sphere { center: c.position, radius: c.d_min, color: translucent });
            c_att_spheres.push(Overlay::Sphere {
                center: c.position,
                radius: c.c_att,
                color: [color[0], color[1], color[2], 0.2],
            });
        }
        vec![
            OverlayLayer { name: "lights by cluster", visible_by_default: true, primitives: by_cluster },
            OverlayLayer { name: "cluster centers", visible_by_default: true, primitives: centers },
            OverlayLayer { name: "member -> center", visible_by_default: true, primitives: lines },
            OverlayLayer { name: "d_min spheres", visible_by_default: false, primitives: d_min_spheres },
            OverlayLayer { name: "C_att spheres", visible_by_default: false, primitives: c_att_spheres },
        ]
    }

    pub(super) fn explain_steps(&self) -> Vec<ExplainStep> {
        use ExplainStep;
        vec![
            ExplainStep {
                title: "1. Visible lights",
                text: "Lights whose range sphere (L_att) misses the view frustum are culled; the visible ones are \
                       sorted by L_att, largest first. Each dot is a visible light.",
                layers: &["lights by cluster"],
                shows_shadow_maps: false,
                ..Default::default()
            },
            ExplainStep {
                title: "2. Cluster centers",
                text: if self.params.centers == Centers::Cover {
                    "A center covers the lights within its d_min = d_init·(1 − |C_pos|/z_far): clusters are smaller \
                     far from the camera. Next comes the light that covers the most lights not covered yet \
                     ('Cluster centers: cover', beyond the paper, whose order takes more centers). White dots: \
                     centers; circles: d_min."
                } else {
                    "A light becomes a center when it is farther than d_min = d_init·(1 − |C_pos|/z_far) from \
                     every center so far: clusters are smaller far from the camera. White dots: centers; circles: \
                     d_min."
                },
                layers: &["cluster centers", "d_min spheres"],
                shows_shadow_maps: false,
                ..Default::default()
            },
            ExplainStep {
                title: "3. Members joined to centers",
                text: "Every other light joins its nearest center; the cluster's range grows to \
                       C_att = max(C_att, d_C + L_att). Lines: member -> center; large circles: C_att.",
                layers: &["lights by cluster", "member -> center", "C_att spheres"],
                shows_shadow_maps: false,
                ..Default::default()
            },
            ExplainStep {
                title: "4. One cube map per cluster",
                text: if self.params.proxy < 1.0 {
                    "One cube shadow map per cluster, rendered from its center with far plane C_att (the Shadow \
                     maps panel shows the last batch's), drawn from a simplified copy of the scene ('Map geometry \
                     kept', beyond the paper; the depth bias grows by its 'Proxy error')."
                } else {
                    "One cube shadow map per cluster, rendered from its center with far plane C_att (the Shadow \
                     maps panel shows the last batch's)."
                },
                layers: &["cluster centers"],
                shows_shadow_maps: true,
                ..Default::default()
            },
            ExplainStep {
                title: "5. Soft visibility per cluster",
                text: "Per pixel and cluster within C_att: visibility of a disc light of radius d_min (PCF, or \
                       PCSS: blocker search, penumbra w = d_min (d_r − d_b) / d_b), multiplied into the summed \
                       light of the cluster's members. Shown: cluster 0's visibility alone, in grey (white lit, \
                       black shadowed; the parameter visibility_of picks another cluster).",
                layers: &["cluster centers"],
                shows_shadow_maps: false,
                params: &[("visibility_of", "0")],
                ..Default::default()
            },
            ExplainStep {
                title: "6. Final image",
                text: "The sum over clusters; compare it with the reference (View, Difference).",
                layers: &[],
                shows_shadow_maps: false,
                ..Default::default()
            },
        ]
    }

    pub(super) fn cluster_details(&self, index: usize) -> Option<LightDetails> {
        let (ci, c) = self.clustering.clusters.iter().enumerate().find(|(_, c)| c.members.contains(&index))?;
        let role = if c.center == index { "its center" } else { "a member" };
        Some(LightDetails {
            lines: vec![
                format!("cluster {ci} ({role}): {} lights, center light {}", c.members.len(), c.center),
                format!("d_min {:.3} · C_att {:.3} · radius d_C {:.3}", c.d_min, c.c_att, c.radius),
            ],
            group: c.members.clone(),
        })
    }

    pub(super) fn legend_of(&self, layer: &OverlayLayer) -> Vec<LegendEntry> {
        let n = self.clustering.clusters.len();
        let white = [1.0; 4];
        let palette = cluster_color(0);
        let mut legend = match layer.name {
            "lights by cluster" => vec![LegendEntry::new(
                Glyph::Palette,
                palette,
                format!("a visible light, in its cluster's colour ({n} clusters)"),
            )],
            "cluster centers" => {
                vec![LegendEntry::new(Glyph::Dot, white, "a cluster's center: its cube map is rendered from here")]
            }
            "member -> center" => vec![LegendEntry::new(Glyph::Palette, palette, "joins a member light to its center")],
            "d_min spheres" => vec![LegendEntry::new(
                Glyph::Circle,
                palette,
                "d_min = d_init·(1 − |C_pos|/z_far): the cluster's disc-light radius",
            )],
            "C_att spheres" => vec![LegendEntry::new(
                Glyph::Circle,
                palette,
                "C_att: the cluster's range; pixels beyond it skip the cluster",
            )],
            _ => crate::technique::light_layer_legend(layer).unwrap_or_default(),
        };
        legend.extend(layer.summary());
        legend
    }
}
