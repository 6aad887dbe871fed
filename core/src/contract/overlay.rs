//! What a technique draws over the 3D view (overlay primitives and layers, legends, hover points) and what it
//! teaches (Explain steps). Plain data: the overlay renderer draws it, the app lists and toggles it.

use glam::{Mat4, Vec3};

use crate::scene::{Aabb, DirectionalLight, PointLight};

/// Above this many spheres in one draw, the overlay renderer draws each as one horizontal circle instead of
/// three great circles (24x fewer vertices): 100,000 range spheres would otherwise be ~600 MB of line vertices
/// every UI frame. Here, with the primitives, because a layer's legend says which form it is drawn in.
pub const MAX_FULL_SPHERES: usize = 2048;
/// Spheres drawn at all; the rest are left out (the lights' own dots still show where they are).
pub const MAX_SPHERES: usize = 32_768;

/// A primitive drawn over the 3D view (by the app), in world space unless noted.
#[derive(Clone, Debug, PartialEq)]
pub enum Overlay {
    /// A dot of `radius_px` screen pixels.
    Point {
        position: Vec3,
        color: [f32; 4],
        radius_px: f32,
    },
    Line {
        from: Vec3,
        to: Vec3,
        color: [f32; 4],
    },
    /// A wireframe sphere.
    Sphere {
        center: Vec3,
        radius: f32,
        color: [f32; 4],
    },
    /// The frustum of a camera, given by its clip-from-world matrix.
    Frustum {
        clip_from_world: Mat4,
        color: [f32; 4],
    },
    /// A rectangle outline: `center ± half_u ± half_v` (image planes, rectangular lights).
    Rect {
        center: Vec3,
        half_u: Vec3,
        half_v: Vec3,
        color: [f32; 4],
    },
    /// A per-pixel ID map over the whole view (e.g. the cluster of each pixel): `ids` row-major at
    /// `width x height`, `u32::MAX` = no ID; each ID gets a distinct colour, blended with `alpha`.
    IdMap {
        width: u32,
        height: u32,
        ids: std::sync::Arc<Vec<u32>>,
        alpha: f32,
    },
    /// A per-pixel colour map over the whole view (e.g. a blend of the clusters a pixel belongs to): `rgba`
    /// row-major at `width x height`, straight (not premultiplied) alpha.
    ColorMap {
        width: u32,
        height: u32,
        rgba: std::sync::Arc<Vec<[u8; 4]>>,
    },
}

/// A distinct, stable colour per index, for clusters and ID maps: a golden-ratio walk of the hue (neighbouring
/// indices far apart on the colour wheel), with saturation and brightness stepping through three levels every
/// 16 indices, so hundreds of clusters stay distinguishable from their neighbours.
pub fn index_color(index: usize) -> [f32; 4] {
    let h = (index as f64 * 0.618_033_988_75).fract() as f32;
    let (saturation, value) = [(0.85, 1.0), (0.55, 0.95), (0.95, 0.7)][(index / 16) % 3];
    let k = |n: f32| {
        let k = (n + h * 6.0) % 6.0;
        value * (1.0 - (k.min(4.0 - k).clamp(0.0, 1.0)) * saturation)
    };
    [k(5.0), k(3.0), k(1.0), 1.0]
}

/// What a legend line shows next to its text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Glyph {
    Dot,
    Line,
    Circle,
    Frustum,
    Rect,
    /// Coloured pixels over the view (ID maps).
    Pixels,
    /// Many colours: one per cluster (or per index).
    Palette,
}

/// One line of an overlay layer's legend: what a glyph of a colour means.
#[derive(Clone, Debug, PartialEq)]
pub struct LegendEntry {
    pub glyph: Glyph,
    pub color: [f32; 4],
    pub text: String,
}

impl LegendEntry {
    pub fn new(glyph: Glyph, color: [f32; 4], text: impl Into<String>) -> LegendEntry {
        LegendEntry { glyph, color, text: text.into() }
    }
}

impl OverlayLayer {
    /// Counts per primitive kind, with the first colour of each, and the cheaper forms the overlay renderer
    /// switches to for this many primitives: a legend any layer has without describing itself.
    pub fn summary(&self) -> Vec<LegendEntry> {
        // Per glyph: its first colour, its count, and its distinct colours (up to 64, as 8-bit RGB).
        type Kind = (Glyph, [f32; 4], usize, Vec<[u32; 3]>);
        let mut counts: Vec<Kind> = Vec::new();
        for p in &self.primitives {
            let (glyph, color) = match p {
                Overlay::Point { color, .. } => (Glyph::Dot, *color),
                Overlay::Line { color, .. } => (Glyph::Line, *color),
                Overlay::Sphere { color, .. } => (Glyph::Circle, *color),
                Overlay::Frustum { color, .. } => (Glyph::Frustum, *color),
                Overlay::Rect { color, .. } => (Glyph::Rect, *color),
                Overlay::IdMap { .. } | Overlay::ColorMap { .. } => (Glyph::Pixels, [1.0; 4]),
            };
            let key = [color[0], color[1], color[2]].map(|c| (c * 255.0) as u32);
            match counts.iter_mut().find(|(g, ..)| *g == glyph) {
                Some((_, _, n, colors)) => {
                    *n += 1;
                    if colors.len() < 64 && !colors.contains(&key) {
                        colors.push(key);
                    }
                }
                None => counts.push((glyph, color, 1, vec![key])),
            }
        }
        let mut out: Vec<LegendEntry> = counts
            .into_iter()
            .map(|(glyph, color, n, colors)| {
                let what = match glyph {
                    Glyph::Dot => "dots",
                    Glyph::Line => "lines",
                    Glyph::Circle => "spheres",
                    Glyph::Frustum => "frusta",
                    Glyph::Rect => "rectangles",
                    Glyph::Pixels | Glyph::Palette => "per-pixel maps",
                };
                let many = colors.len() > 1;
                let text =
                    format!("{n} {what}{}", if many { format!(", {} colours", colors.len()) } else { String::new() });
                LegendEntry::new(if many && glyph != Glyph::Pixels { Glyph::Palette } else { glyph }, color, text)
            })
            .collect();
        let spheres = self.primitives.iter().filter(|p| matches!(p, Overlay::Sphere { .. })).count();
        if spheres > MAX_SPHERES {
            out.push(LegendEntry::new(
                Glyph::Circle,
                [1.0; 4],
                format!("cheaper form: the first {} as one circle each", MAX_SPHERES),
            ));
        } else if spheres > MAX_FULL_SPHERES {
            out.push(LegendEntry::new(
                Glyph::Circle,
                [1.0; 4],
                format!("cheaper form: over {} spheres, each is one horizontal circle", MAX_FULL_SPHERES),
            ));
        }
        out
    }
}

/// What a technique knows of one light of the last frame, for the app's hover tooltip: lines of text, and the
/// lights of the light's group (e.g. its cluster, the light itself included) to highlight when it is selected.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightDetails {
    pub lines: Vec<String>,
    pub group: Vec<usize>,
}

/// Something a technique's overlays draw that the app's view gives a hover tooltip (a VAL, a VPL, a cluster's
/// representative): where it is, the overlay layer that draws it (the app offers only those of visible
/// layers), and an index the technique understands in `Technique::hover_details`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HoverPoint {
    pub layer: &'static str,
    pub position: Vec3,
    pub index: usize,
}

/// One step of a technique's paper, for teaching ("Explain" in the app): what it does, and what shows it: the
/// overlay layers to switch on (the technique's others are switched off), whether its maps show it (and which:
/// `maps` 0 is `Technique::shadow_atlas`, `i` ≥ 1 the i-th of `Technique::depth_images`, [`RSM_MAPS`] a light's
/// reflective shadow map, where the shared VPLs come from), and parameter
/// values that make the image show the step (e.g. one cluster's visibility alone), as text the parameter's kind
/// parses; the app sets them while the step is chosen and restores the user's values for the other steps.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExplainStep {
    pub title: &'static str,
    pub text: &'static str,
    pub layers: &'static [&'static str],
    pub shows_shadow_maps: bool,
    pub maps: usize,
    pub params: &'static [(&'static str, &'static str)],
}

/// [`ExplainStep::maps`] of a step shown by a light's reflective shadow map (the selected light's), with the
/// texels the frame's VPLs came from: no technique's own maps, the renderer's shared VPL source.
pub const RSM_MAPS: usize = usize::MAX;

/// The legend of the layers of [`light_overlays`], which every technique offers; None for other layers.
pub fn light_layer_legend(layer: &OverlayLayer) -> Option<Vec<LegendEntry>> {
    let white = [1.0, 1.0, 1.0, 1.0];
    Some(match layer.name {
        "lights" => {
            vec![LegendEntry::new(Glyph::Dot, white, "a light, in its colour; size √intensity, less in a crowd")]
        }
        "light ranges" => vec![LegendEntry::new(Glyph::Circle, white, "L_att: where the light's falloff reaches 0")],
        "spot cones" => vec![LegendEntry::new(Glyph::Line, white, "a spot light's axis and cone, ¼ of L_att long")],
        SUNS_LAYER => vec![
            LegendEntry::new(Glyph::Line, white, "a sun, in its colour: its light travels along the arrow"),
            LegendEntry::new(Glyph::Dot, white, "where the arrow starts: half the scene's size towards the sun"),
        ],
        _ => return None,
    })
}

/// An overlay layer a technique offers; the app toggles layers individually.
#[derive(Clone, Debug, PartialEq)]
pub struct OverlayLayer {
    pub name: &'static str,
    pub visible_by_default: bool,
    pub primitives: Vec<Overlay>,
}

/// A light's overlay colour: its colour normalised to full brightness.
pub fn light_overlay_color(l: &PointLight) -> [f32; 4] {
    let c = l.color / l.color.max_element().max(1e-6);
    [c.x, c.y, c.z, 1.0]
}

/// Up to this many lights their dots keep their full size; beyond it they shrink as `sqrt(n)` grows, so that
/// thousands of lights stay a cloud of points instead of a solid sheet (100,000 dots of 2-6 pixels covered the
/// whole view), down to [`MIN_LIGHT_DOT_SCALE`] of it.
pub const FULL_SIZE_LIGHT_DOTS: usize = 256;
/// The smallest share of their size light dots shrink to.
pub const MIN_LIGHT_DOT_SCALE: f32 = 0.25;

/// The share of their size light dots keep among `lights` lights: 1 up to [`FULL_SIZE_LIGHT_DOTS`], then
/// `sqrt(FULL_SIZE_LIGHT_DOTS / lights)`, at least [`MIN_LIGHT_DOT_SCALE`].
pub fn light_dot_scale(lights: usize) -> f32 {
    (FULL_SIZE_LIGHT_DOTS as f32 / lights.max(1) as f32).sqrt().clamp(MIN_LIGHT_DOT_SCALE, 1.0)
}

/// The radius in pixels of a light's dot: 2 to 6 pixels with √intensity, times the crowd's `scale`
/// ([`light_dot_scale`]), never under a pixel.
pub fn light_dot_radius(intensity: f32, max_intensity: f32, scale: f32) -> f32 {
    ((2.0 + 4.0 * (intensity / max_intensity.max(1e-6)).clamp(0.0, 1.0).sqrt()) * scale).max(1.0)
}

/// The overlays every technique offers for its lights: dots sized by intensity, and range spheres (`L_att`).
pub fn light_overlays(lights: &[PointLight]) -> Vec<OverlayLayer> {
    let max_intensity = lights.iter().map(|l| l.intensity).fold(0.0f32, f32::max).max(1e-6);
    let scale = light_dot_scale(lights.len());
    let mut layers = vec![
        OverlayLayer {
            name: "lights",
            visible_by_default: true,
            primitives: lights
                .iter()
                .map(|l| Overlay::Point {
                    position: l.position,
                    color: light_overlay_color(l),
                    radius_px: light_dot_radius(l.intensity, max_intensity, scale),
                })
                .collect(),
        },
        OverlayLayer {
            name: "light ranges",
            visible_by_default: false,
            primitives: lights
                .iter()
                .map(|l| {
                    let [r, g, b, _] = light_overlay_color(l);
                    Overlay::Sphere { center: l.position, radius: l.range, color: [r, g, b, 0.35] }
                })
                .collect(),
        },
    ];
    // Only scenes with spot lights get the layer, so the layer list of the others stays as it was.
    if lights.iter().any(|l| l.spot.is_some()) {
        layers.push(OverlayLayer {
            name: "spot cones",
            visible_by_default: true,
            primitives: lights
                .iter()
                .filter_map(|l| l.spot.map(|s| (l, s)))
                .flat_map(|(l, s)| {
                    // The cone's axis and four edges, a quarter of the range long.
                    let len = l.range * 0.25;
                    let (u, v) = s.direction.any_orthonormal_pair();
                    let (sin, cos) = s.outer_angle.sin_cos();
                    let [r, g, b, _] = light_overlay_color(l);
                    let color = [r, g, b, 0.8];
                    let mut lines = vec![Overlay::Line { from: l.position, to: l.position + s.direction * len, color }];
                    for side in [u, -u, v, -v] {
                        let edge = s.direction * cos + side * sin;
                        lines.push(Overlay::Line { from: l.position, to: l.position + edge * len, color });
                    }
                    lines
                })
                .collect(),
        });
    }
    layers
}

/// The name of [`sun_overlays`]' layer.
pub const SUNS_LAYER: &str = "suns";

/// The layer of the directional lights (the renderer's service shades them for every technique, so the app
/// offers it beside every technique's layers): per sun, an arrow along its direction ending at the centre of
/// `bounds`, half the bounds' diagonal long, in the sun's colour, and a dot where it starts. Empty without suns.
pub fn sun_overlays(suns: &[DirectionalLight], bounds: &Aabb) -> OverlayLayer {
    let centre = (bounds.min + bounds.max) * 0.5;
    let size = (bounds.max - bounds.min).length();
    let (centre, len) =
        if centre.is_finite() && size.is_finite() && size > 0.0 { (centre, size * 0.5) } else { (Vec3::ZERO, 1.0) };
    let primitives = suns
        .iter()
        .filter(|d| d.is_valid())
        .flat_map(|d| {
            let dir = d.direction.normalize();
            let c = d.color / d.color.max_element().max(1e-6);
            let color = [c.x, c.y, c.z, 1.0];
            let from = centre - dir * len;
            // The head: two strokes a tenth of the length back from the tip, at 25 degrees.
            let (u, _) = dir.any_orthonormal_pair();
            let back = -dir * (len * 0.1);
            let side = u * (len * 0.1 * 25f32.to_radians().tan());
            vec![
                Overlay::Point { position: from, color, radius_px: 6.0 },
                Overlay::Line { from, to: centre, color },
                Overlay::Line { from: centre, to: centre + back + side, color },
                Overlay::Line { from: centre, to: centre + back - side, color },
            ]
        })
        .collect();
    OverlayLayer { name: SUNS_LAYER, visible_by_default: true, primitives }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn light_dots_grow_with_intensity_and_shrink_in_a_crowd() {
        let radius = |intensity: f32, lights: usize| light_dot_radius(intensity, 1.0, light_dot_scale(lights));
        assert_eq!(radius(1.0, 10), 6.0);
        assert_eq!(radius(0.0, 10), 2.0);
        assert_eq!(radius(1.0, FULL_SIZE_LIGHT_DOTS), 6.0, "full size up to the threshold");
        assert!((radius(1.0, 4 * FULL_SIZE_LIGHT_DOTS) - 3.0).abs() < 1e-5, "half at four times");
        assert_eq!(radius(1.0, 100_000), 6.0 * MIN_LIGHT_DOT_SCALE);
        assert_eq!(radius(0.0, 100_000), 1.0, "never under a pixel");
        // The layer itself: a crowd's dots are smaller than a few lights' of the same intensity.
        let light = |x: f32| PointLight::new(Vec3::new(x, 0.0, 0.0), Vec3::ONE, 1.0, 1.0);
        let dot =
            |n: usize| match &light_overlays(&(0..n).map(|i| light(i as f32)).collect::<Vec<_>>())[0].primitives[0] {
                Overlay::Point { radius_px, .. } => *radius_px,
                other => panic!("a dot, not {other:?}"),
            };
        assert_eq!((dot(4), dot(4096)), (6.0, 1.5));
    }

    #[test]
    fn a_suns_arrow_points_along_its_light_to_the_scenes_centre() {
        let bounds = Aabb { min: Vec3::new(-2.0, 0.0, -2.0), max: Vec3::new(2.0, 4.0, 2.0) };
        let d = Vec3::new(0.3, -1.0, 0.2).normalize();
        let sun = DirectionalLight { direction: d, color: Vec3::new(2.0, 1.0, 0.5), illuminance: 3.0 };
        let bad = DirectionalLight { direction: Vec3::ZERO, ..sun };
        let layer = sun_overlays(&[sun, bad], &bounds);
        assert_eq!(layer.name, SUNS_LAYER);
        assert!(light_layer_legend(&layer).is_some_and(|l| !l.is_empty()));
        // One sun drawn (the invalid one is not): a dot and three strokes.
        assert_eq!(layer.primitives.len(), 4);
        let Overlay::Line { from, to, color } = layer.primitives[1] else { panic!("{:?}", layer.primitives[1]) };
        assert!(to.distance(Vec3::new(0.0, 2.0, 0.0)) < 1e-5, "the arrow ends at the centre: {to}");
        assert!((to - from).normalize().dot(d) > 0.9999, "the arrow goes the way the light travels");
        assert_eq!(color, [1.0, 0.5, 0.25, 1.0], "in the sun's colour at full brightness");
        assert!(sun_overlays(&[], &bounds).primitives.is_empty());
    }
}
