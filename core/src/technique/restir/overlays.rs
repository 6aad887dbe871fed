//! What ReSTIR shows and teaches: the per-pixel maps of its final reservoirs (the light each pixel sampled, the
//! weight `W`, the length `M`), their legends and hover text, and the Explain steps of the paper.

use std::sync::Arc;

use super::state::{LENGTH_MAP, LIGHT_MAP, WEIGHT_MAP};
use super::Restir;
use crate::compare::colormap;
use crate::scene::PointLight;
use crate::technique::{ExplainStep, Glyph, LegendEntry, Overlay, OverlayLayer};

impl Restir {
    /// The Explain steps of the paper.
    pub(super) fn explain_steps() -> Vec<ExplainStep> {
        vec![
            ExplainStep {
                title: "1. Candidates",
                text:
                    "Each pixel draws M lights from the source pdf p: every visible light alike, or by power through \
                       an alias table (one table lookup a draw, whatever the light count). With one candidate and no \
                       reuse the image is one random light per pixel: noise.",
                layers: &[LIGHT_MAP],
                params: &[("candidates", "1"), ("history", "0"), ("spatial", "0"), ("inspect", "on")],
                ..Default::default()
            },
            ExplainStep {
                title: "2. Resampled importance sampling (Algorithm 3)",
                text:
                    "Each candidate x is weighted w = p̂(x)/p(x), p̂ its unshadowed contribution; a reservoir keeps one \
                       of them, y, with probability w/w_sum, streaming (Algorithm 2), and W = w_sum/(M p̂(y)). Pixels \
                       now sample the lights that light them most.",
                layers: &[LIGHT_MAP],
                params: &[("history", "0"), ("spatial", "0"), ("inspect", "on")],
                ..Default::default()
            },
            ExplainStep {
                title: "3. Visibility reuse",
                text:
                    "One shadow ray from the pixel to y; W = 0 when it is blocked, before any reuse, so no neighbour \
                       inherits a sample its source cannot see. Black in the W map: occluded samples.",
                layers: &[WEIGHT_MAP],
                params: &[("history", "0"), ("spatial", "0"), ("inspect", "on")],
                ..Default::default()
            },
            ExplainStep {
                title: "4. Temporal reuse",
                text: "The pixel's surface is reprojected into the previous frame; where that frame saw the same \
                       surface (depth and normal alike) its final reservoir is combined with this one (Algorithm 4), \
                       its M capped at `history` times M. Over 8 frames M grows; it stays low where the history was \
                       rejected.",
                layers: &[LENGTH_MAP],
                params: &[("spatial", "0"), ("frames", "8"), ("inspect", "on")],
                ..Default::default()
            },
            ExplainStep {
                title: "5. Spatial reuse",
                text: "k random neighbours within the radius whose surfaces are alike are combined too. Biased: 1/M; \
                       unbiased: 1/Z, Z the M of the inputs that could have drawn y (a shadow ray from each). Then one \
                       shadow ray from the pixel to the final y.",
                layers: &[WEIGHT_MAP],
                params: &[("inspect", "on")],
                ..Default::default()
            },
            ExplainStep {
                title: "6. Shading",
                text:
                    "Each pixel adds f(y) W: the chosen light's unshadowed contribution, its visibility already in W. \
                       `frames` ReSTIR frames per image are averaged.",
                layers: &[],
                params: &[],
                ..Default::default()
            },
        ]
    }

    pub(super) fn overlay_layers(&self, lights: &[PointLight]) -> Vec<OverlayLayer> {
        let ins = &self.inspection;
        let (width, height) = ins.size;
        let map = |rgba: &Option<Arc<Vec<[u8; 4]>>>| -> Vec<Overlay> {
            rgba.iter().map(|rgba| Overlay::ColorMap { width, height, rgba: rgba.clone() }).collect()
        };
        let mut layers = super::super::light_overlays(lights);
        layers.push(OverlayLayer { name: WEIGHT_MAP, visible_by_default: false, primitives: map(&ins.weight_map) });
        layers.push(OverlayLayer { name: LENGTH_MAP, visible_by_default: false, primitives: map(&ins.length_map) });
        layers
    }

    pub(super) fn legend_of(&self, layer: &OverlayLayer) -> Vec<LegendEntry> {
        let ins = &self.inspection;
        let cold = colormap(0.0).map(|c| c as f32 / 255.0);
        let hot = colormap(1.0).map(|c| c as f32 / 255.0);
        let rgba = |c: [f32; 3]| [c[0], c[1], c[2], 1.0];
        let off = "switch on 'inspect' (Read reservoirs back) for the map";
        let mut legend = match layer.name {
            WEIGHT_MAP if layer.primitives.is_empty() => vec![LegendEntry::new(Glyph::Pixels, [1.0; 4], off)],
            WEIGHT_MAP => vec![
                LegendEntry::new(Glyph::Pixels, rgba(cold), format!("W ≤ {:.3e} (1st percentile)", ins.weight_range.0)),
                LegendEntry::new(Glyph::Pixels, rgba(hot), format!("W ≥ {:.3e} (99th percentile)", ins.weight_range.1)),
                LegendEntry::new(Glyph::Pixels, [0.0, 0.0, 0.0, 1.0], "W = 0: the sample is occluded, or none"),
            ],
            LENGTH_MAP if layer.primitives.is_empty() => vec![LegendEntry::new(Glyph::Pixels, [1.0; 4], off)],
            LENGTH_MAP => vec![
                LegendEntry::new(
                    Glyph::Pixels,
                    rgba(cold),
                    format!("M = {:.0}: one frame's candidates", ins.length_range.0),
                ),
                LegendEntry::new(
                    Glyph::Pixels,
                    rgba(hot),
                    format!("M = {:.0}: the longest history", ins.length_range.1),
                ),
            ],
            LIGHT_MAP => vec![LegendEntry::new(
                Glyph::Pixels,
                crate::technique::index_color(0),
                "each pixel in the colour of the light its final reservoir holds",
            )],
            _ => crate::technique::light_layer_legend(layer).unwrap_or_default(),
        };
        legend.extend(layer.summary());
        legend
    }

    pub(super) fn hover_text(&self, layer: &str, index: usize) -> Vec<String> {
        if layer != LIGHT_MAP {
            return Vec::new();
        }
        let pixels = self.inspection.lights.iter().filter(|&&l| l == index as u32).count();
        vec![format!("light {index}: the sample y of {pixels} pixels' final reservoirs")]
    }
}
