//! What ISM shows and teaches: the scene's point pool and the inspected map's subset as point layers, their
//! legends, and the Explain steps of the paper.

use glam::Vec3;

use crate::technique::{ExplainStep, Glyph, LegendEntry, Overlay, OverlayLayer};

pub const POOL_LAYER: &str = "ism points (the scene's pool, every n-th)";
pub const SUBSET_LAYER: &str = "ism points of the inspected map";
/// Points one layer draws at most (the overlay renderer draws each as a quad).
const MAX_OVERLAY_POINTS: usize = 20_000;
const POOL_COLOR: [f32; 4] = [0.55, 0.8, 1.0, 0.7];
const SUBSET_COLOR: [f32; 4] = [1.0, 0.6, 0.2, 1.0];

/// The pool (every n-th, at most 20,000) and the `n` points from `start` (wrapping) that the inspected map
/// splats, when there is one.
pub(super) fn point_layers(pool: &[Vec3], start: Option<usize>, n: usize) -> Vec<OverlayLayer> {
    let stride = pool.len().div_ceil(MAX_OVERLAY_POINTS).max(1);
    let dot = |p: &Vec3, color, radius_px| Overlay::Point { position: *p, color, radius_px };
    let pool_layer = OverlayLayer {
        name: POOL_LAYER,
        visible_by_default: false,
        primitives: pool.iter().step_by(stride).map(|p| dot(p, POOL_COLOR, 1.5)).collect(),
    };
    let subset = match (start, pool.is_empty()) {
        (Some(start), false) => {
            let count = n.min(pool.len());
            let stride = count.div_ceil(MAX_OVERLAY_POINTS).max(1);
            (0..count).step_by(stride).map(|k| dot(&pool[(start + k) % pool.len()], SUBSET_COLOR, 2.0)).collect()
        }
        _ => Vec::new(),
    };
    vec![pool_layer, OverlayLayer { name: SUBSET_LAYER, visible_by_default: true, primitives: subset }]
}

pub(super) fn legend(layer: &OverlayLayer) -> Vec<LegendEntry> {
    let mut legend = match layer.name {
        POOL_LAYER => vec![LegendEntry::new(
            Glyph::Dot,
            POOL_COLOR,
            "a point of the scene's pool (uniform by area, seeded; every n-th past 20,000)",
        )],
        SUBSET_LAYER => vec![LegendEntry::new(
            Glyph::Dot,
            SUBSET_COLOR,
            "a point the inspected light's (VPL's) map splats: its own subset of the pool",
        )],
        _ => crate::technique::light_layer_legend(layer).unwrap_or_default(),
    };
    legend.extend(layer.summary());
    legend
}

pub(super) fn explain_steps(vpls: bool) -> Vec<ExplainStep> {
    let splat_text = if vpls {
        "Each VPL's map is one paraboloid hemisphere along its normal (Ritschel's): every point of its subset in \
         front of it goes into the one texel its direction lands in, nearest first (atomicMin). With no hole \
         filling (levels 0) the map is mostly holes: few points, many texels."
    } else {
        "Each light's map is a dual paraboloid (two hemispheres, +y and -y, two tiles): every point of its subset \
         goes into the one texel its direction lands in, nearest first (atomicMin). With no hole filling \
         (levels 0) the map is mostly holes: few points, many texels, so light leaks through the occluders."
    };
    vec![
        ExplainStep {
            title: "1. Point samples",
            text: "The scene is replaced by points uniform by area over its triangles, sampled once per scene \
                   (seeded) and shuffled; each map takes its own subset of `points` of them. The orange points are \
                   the inspected map's.",
            layers: &[SUBSET_LAYER],
            ..Default::default()
        },
        ExplainStep {
            title: "2. Splatting",
            text: splat_text,
            layers: &[],
            shows_shadow_maps: true,
            maps: 1,
            params: &[("levels", "0")],
        },
        ExplainStep {
            title: "3. Pull-push",
            text: "A pyramid is pulled up (each coarse texel the mean of its children near the nearest one) and \
                   pushed back down (each empty texel the interpolated coarser level), a few levels: the holes \
                   close. Points of the background that fell into a gap stay: ISM's imperfection.",
            layers: &[],
            shows_shadow_maps: true,
            maps: 1,
            params: &[("levels", "4")],
        },
        ExplainStep {
            title: "4. Shadow lookup",
            text: "Each pixel moves along its normal by `normal_offset` texel footprints and reads one texel of each \
                   map: lit when its distance less `bias` footprints is no farther than the stored one. Compare with \
                   the target (one exact map per light): the shadows are blurrier and leak where points were few.",
            layers: &[],
            ..Default::default()
        },
    ]
}
