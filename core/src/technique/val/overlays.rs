//! What virtual area lights show and teach: their overlay layers (VPLs by VAL, the VALs' rectangles, normals and
//! centres), legends, hover texts and the Explain steps of the paper.

use super::*;

impl VirtualAreaLights {
    pub(super) fn explain_steps(&self) -> Vec<crate::technique::ExplainStep> {
        use crate::technique::ExplainStep;
        vec![
            ExplainStep {
                title: "1. VPLs",
                text: "The lights' reflective shadow maps leave virtual point lights on the surfaces they light.",
                layers: &["vpls by val"],
                shows_shadow_maps: true,
                maps: crate::technique::RSM_MAPS,
                ..Default::default()
            },
            ExplainStep {
                title: "2. Clustering into VALs",
                text: if self.params.split {
                    "From k-means over position and normal (d = w_x dx / L + w_a da; by default one VAL), the VAL \
                     carrying the most light times its VPLs' distance d (weighted up by the share of its light whose VPLs \
                     its map's centre cannot see: 'Hidden VPL weight') is cut in two until there are M: by normal \
                     across a corner, by depth across a column and the wall behind it, else in the paper's metric \
                     (our addition; 'split' off gives the paper's k-means alone). Each VAL gets its VPLs' mean \
                     position and normal, their bounding rectangle and a size Δ (by default from how their light spreads)."
                } else {
                    "k-means over position and normal (d = w_x dx / L + w_a da), restarted every frame from VAL k = \
                     VPL kN/M; each VAL gets its VPLs' mean position and normal and their bounding rectangle."
                },
                layers: &["vpls by val", "val rectangles", "val normals", "val centres"],
                shows_shadow_maps: false,
                ..Default::default()
            },
            ExplainStep {
                title: "3. A paraboloid map per VAL",
                text: if self.params.proxy < 1.0 {
                    "One shadow map per VAL, facing its normal, all in one atlas (see Shadow maps), drawn from a \
                     simplified copy of the scene ('Map geometry kept': the paper's future work, not its method), \
                     its long edges cut since a paraboloid draws edges straight."
                } else {
                    "One shadow map per VAL, facing its normal, all in one atlas (see Shadow maps); the scene's long \
                     edges are cut first, since a paraboloid draws edges straight ('Longest edge'). A map stands \
                     off its VAL's mean, or, for a small VAL, off its VPL nearest the mean, or off a member nearby \
                     with clearer space when geometry lies right beside that one ('Map centre', 'Clear member \
                     centre'; white dots)."
                },
                layers: &["val centres", "val map centres", "val normals"],
                shows_shadow_maps: true,
                ..Default::default()
            },
            ExplainStep {
                title: "4. One VAL's soft shadow",
                text: "Each pixel sums its VPLs' light per VAL, then looks up each VAL that lights it once in that \
                       VAL's map (PCSS: a blocker search, then a penumbra from the VAL's size Δ; or CSSM, or hard) and \
                       weighs the VAL's light by that visibility. Shown: VAL 0's contribution alone, its VPLs' light \
                       with its soft shadow ('Show one VAL' picks another; -1 shows them all).",
                layers: &["val centres", "val normals"],
                shows_shadow_maps: false,
                params: &[("solo", "0")],
                ..Default::default()
            },
            ExplainStep {
                title: "5. Every VAL: the indirect light",
                text: "The sum over the VALs (interleaved: each pixel its share of the VPLs, a 64th with the 8x8 block, \
                       then the blur; otherwise each pixel skips the VALs whose VPLs all lie behind it or face away from \
                       it, and a VAL under 'Soft above share' of its light gets one depth test). Compare it with one \
                       shadow map per VPL (View: Difference, against vpl-shadowmaps).",
                layers: &[],
                shows_shadow_maps: false,
                ..Default::default()
            },
        ]
    }

    pub(super) fn legend_of(&self, layer: &OverlayLayer) -> Vec<crate::technique::LegendEntry> {
        use crate::technique::{Glyph, LegendEntry};
        let palette = index_color(0);
        let mut legend = match layer.name {
            "vpls by val" => vec![LegendEntry::new(Glyph::Palette, palette, "a VPL, in its VAL's colour")],
            "val rectangles" => {
                vec![LegendEntry::new(Glyph::Rect, palette, "a VAL's area: its VPLs' bounding rectangle")]
            }
            "val normals" => vec![LegendEntry::new(Glyph::Line, palette, "a VAL's mean normal")],
            "val centres" => vec![LegendEntry::new(Glyph::Dot, palette, "a VAL's centre: its VPLs' mean position")],
            "val map centres" => vec![LegendEntry::new(
                Glyph::Line,
                palette,
                "where a VAL's map stands: off its mean, or (a small VAL, centre = auto) off its VPL nearest the mean \
                 or a clearer one nearby",
            )],
            "vpl -> val" => vec![LegendEntry::new(Glyph::Line, palette, "a VPL joined to its VAL's centre")],
            _ => crate::technique::light_layer_legend(layer).unwrap_or_default(),
        };
        legend.extend(layer.summary());
        legend
    }

    pub(super) fn hover_list(&self) -> Vec<crate::technique::HoverPoint> {
        let c = &self.clustering;
        let vals = c.vals.iter().enumerate().filter(|(_, v)| v.count > 0);
        let centres =
            vals.map(|(index, v)| crate::technique::HoverPoint { layer: "val centres", position: v.position, index });
        // The VPLs the "vpls by val" layer draws (every n-th past 4,096, as it does).
        let stride = self.vpls.vpls.len().div_ceil(4096).max(1);
        let vpls = self.vpls.vpls.iter().enumerate().step_by(stride);
        centres
            .chain(vpls.map(|(index, v)| crate::technique::HoverPoint {
                layer: "vpls by val",
                position: v.position,
                index,
            }))
            .collect()
    }

    /// Where VAL `k`'s map stood in the last frame (None before one, or when the VALs changed since: the preview's).
    fn map_centre(&self, k: usize) -> Option<glam::Vec3> {
        (self.casters.len() == self.clustering.vals.len()).then(|| self.casters.get(k).map(|c| c.centre)).flatten()
    }

    pub(super) fn hover_text(&self, layer: &str, index: usize) -> Vec<String> {
        let c = &self.clustering;
        match layer {
            "val centres" => {
                let Some(v) = c.vals.get(index) else { return Vec::new() };
                vec![
                    format!("VAL {index} ({} with VPLs)", c.non_empty),
                    format!("{} VPLs, flux ({:.3}, {:.3}, {:.3})", v.count, v.flux.x, v.flux.y, v.flux.z),
                    match self.sizes(&self.vpls.vpls).get(index).filter(|&&d| d != v.size()) {
                        Some(d) => format!(
                            "rectangle {:.3} x {:.3} (diagonal {:.3}), Δ {d:.3} from the spread",
                            2.0 * v.half_u,
                            2.0 * v.half_v,
                            v.size()
                        ),
                        None => format!("rectangle {:.3} x {:.3} (Δ {:.3})", 2.0 * v.half_u, 2.0 * v.half_v, v.size()),
                    },
                    {
                        // The cone a pixel's skip test uses (val/cull.rs): VPLs all facing away skip the VAL.
                        let members = self
                            .vpls
                            .vpls
                            .iter()
                            .zip(&c.assignment)
                            .filter(|(_, &k)| k as usize == index)
                            .map(|(p, _)| (p.position, p.normal));
                        let cone = super::cull::cone_bound(members, v.position, v.normal);
                        let spread = match cone[3] > 0.5 {
                            true => format!("VPL normals within {:.0}°", cone[0].clamp(-1.0, 1.0).acos().to_degrees()),
                            false => "VPL normals 90° or more apart".to_string(),
                        };
                        format!("normal ({:.2}, {:.2}, {:.2}), {spread}", v.normal.x, v.normal.y, v.normal.z)
                    },
                    match self.map_centre(index) {
                        Some(m) if m.distance(v.position) > self.scene_size * 0.01 => {
                            format!("map at a member VPL, {:.3} from the mean", m.distance(v.position))
                        }
                        Some(_) => "map at the mean".to_string(),
                        None => "map: not rendered yet".to_string(),
                    },
                ]
            }
            "vpls by val" => {
                let mut lines = crate::services::vpl_gather::vpl_details(&self.vpls, index);
                if let Some(k) = c.assignment.get(index) {
                    lines.push(format!("in VAL {k}"));
                }
                lines
            }
            _ => Vec::new(),
        }
    }

    pub(super) fn overlay_layers(&self, _lights: &[PointLight]) -> Vec<OverlayLayer> {
        let vpls = &self.vpls.vpls;
        let c = &self.clustering;
        let half = self.scene_size * 0.004;
        let stride = vpls.len().div_ceil(4096).max(1);
        let by_val: Vec<Overlay> = vpls
            .iter()
            .zip(&c.assignment)
            .step_by(stride)
            .map(|(v, &k)| {
                let (t, b) = v.normal.any_orthonormal_pair();
                Overlay::Rect { center: v.position, half_u: t * half, half_v: b * half, color: index_color(k as usize) }
            })
            .collect();
        let live = || c.vals.iter().enumerate().filter(|(_, v)| v.count > 0);
        let rects: Vec<Overlay> = live()
            .map(|(k, v)| Overlay::Rect {
                center: v.position + v.axis_u * v.offset_u + v.axis_v * v.offset_v,
                half_u: v.axis_u * v.half_u.max(half),
                half_v: v.axis_v * v.half_v.max(half),
                color: index_color(k),
            })
            .collect();
        let normals: Vec<Overlay> = live()
            .map(|(k, v)| Overlay::Line {
                from: v.position,
                to: v.position + v.normal * (self.scene_size * 0.03),
                color: index_color(k),
            })
            .collect();
        let centres: Vec<Overlay> = live()
            .map(|(k, v)| Overlay::Point { position: v.position, color: index_color(k), radius_px: 5.0 })
            .collect();
        // From each VAL's mean to where its map stands (the last frame's maps; none while the preview moves).
        let map_centres: Vec<Overlay> = live()
            .filter_map(|(k, v)| {
                let m = self.map_centre(k)?;
                Some(Overlay::Line { from: v.position, to: m, color: index_color(k) })
            })
            .chain(live().filter_map(|(k, _)| {
                let m = self.map_centre(k)?;
                Some(Overlay::Point { position: m, color: [1.0, 1.0, 1.0, 1.0], radius_px: 3.0 })
            }))
            .collect();
        let lines: Vec<Overlay> = vpls
            .iter()
            .zip(&c.assignment)
            .step_by(stride)
            .map(|(v, &k)| {
                let [r, g, b, _] = index_color(k as usize);
                Overlay::Line { from: v.position, to: c.vals[k as usize].position, color: [r, g, b, 0.35] }
            })
            .collect();
        vec![
            OverlayLayer { name: "vpls by val", visible_by_default: true, primitives: by_val },
            OverlayLayer { name: "val rectangles", visible_by_default: true, primitives: rects },
            OverlayLayer { name: "val normals", visible_by_default: true, primitives: normals },
            OverlayLayer { name: "val centres", visible_by_default: true, primitives: centres },
            OverlayLayer { name: "val map centres", visible_by_default: false, primitives: map_centres },
            OverlayLayer { name: "vpl -> val", visible_by_default: false, primitives: lines },
        ]
    }
}
