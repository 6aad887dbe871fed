//! Shadow techniques. Every technique has the same shape, so adding one touches one folder and one line of
//! [`REGISTRY`]:
//! - a long-lived struct that owns its pipelines and GPU resources (`new`),
//! - its parameters, described for the UI and the CLI ([`Technique::params`], [`Technique::set_param`]),
//! - `prepare`: the CPU work of a frame (culling, clustering, batching), returning how many steps it needs,
//! - `encode_step`: one function per pass, called once per step; each step is submitted on its own, which
//!   bounds memory (a reused shadow-map pool) and lets the app spread a slow frame over UI frames,
//! - its counts for the frame report and its overlays for the 3D view.
//!
//! The renderer owns what all techniques share: the G-buffer, the HDR accumulation target (already holding
//! ambient and emission when steps run), tone mapping and timing.

pub mod fuzzy;
pub mod insm;
pub mod lightcluster;
pub mod pathtraced;
pub mod raytraced;
pub mod reference;
pub mod unshadowed;
pub mod val;
pub mod vpl_gather;

use glam::{Mat4, Vec3};
use serde::{Deserialize, Serialize};

use crate::error::GpuError;
use crate::gpu::GpuContext;
use crate::math::Frustum;
use crate::renderer::gpu_scene::GpuScene;
use crate::renderer::SharedLayouts;
use crate::scene::{Camera, PointLight};
use crate::timing::PassTimer;

/// Everything a technique may read during a frame.
pub struct FrameContext<'a> {
    pub gpu: &'a GpuContext,
    pub scene: &'a GpuScene,
    pub layouts: &'a SharedLayouts,
    /// Group 0 of every full-screen pass: the frame uniform and the G-buffer (see `common.wgsl`).
    pub screen_bind_group: &'a wgpu::BindGroup,
    /// HDR radiance target (`SharedLayouts::HDR_FORMAT`); techniques add their lights' radiance into it.
    pub hdr_view: &'a wgpu::TextureView,
    pub camera: &'a Camera,
    pub aspect: f32,
    pub frustum: Frustum,
    pub lights: &'a [PointLight],
    pub timer: &'a PassTimer,
    /// Upper bound on the lights (or clusters, cube maps) one step may handle, so an interactive caller can keep
    /// each step short; `usize::MAX` when unlimited. Never changes the image, only how the work is split.
    pub max_lights_per_step: usize,
    /// Render target size in pixels.
    pub size: (u32, u32),
    /// Indirect radiance per pixel (`array<vec4<f32>>`, row-major), cleared at the start of every frame;
    /// indirect techniques add into it. A placeholder without an indirect technique.
    pub indirect_buffer: &'a wgpu::Buffer,
    /// The frame's VPLs (empty unless the indirect technique [`Technique::uses_vpls`]).
    pub vpls: &'a crate::renderer::VplFrame,
    pub vpl_settings: &'a crate::vpl::VplSettings,
    /// The lights whose range touches the view frustum, uploaded once for every technique.
    pub visible_lights: &'a crate::renderer::lights::VisibleLights,
    /// Per 16x16-pixel tile, the visible lights that reach it (group 2 of a shading pass, `light_tiles.wgsl`),
    /// built after `prepare` when the technique [`Technique::uses_light_tiles`]; encode steps read it.
    pub light_tiles: &'a crate::renderer::light_tiles::TileLists,
    /// [`crate::renderer::RenderSettings::light_tiles`]: techniques that bin their own spheres follow it too.
    pub light_tiles_enabled: bool,
}

/// What a technique did in a frame, for the frame report.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TechniqueCounts {
    /// Lights whose range sphere touches the view frustum.
    pub lights_visible: usize,
    pub shadow_maps: usize,
    /// Steps (batches) the frame was split into.
    pub batches: usize,
    pub shadow_triangles_submitted: u64,
    /// Triangles a shadow map would have drawn without chunk culling, minus those it drew.
    pub shadow_triangles_culled: u64,
    /// Light clusters (LightCluster), when the technique clusters.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clusters: Option<usize>,
    /// Triangles of INSM's reconstructed meshes (all `k` intermediate shadow maps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub insm_mesh_triangles: Option<u64>,
    /// INSM's bound on rendered triangles, `k*N + 2*n*k*w²` (paper section 4.2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub insm_triangle_budget: Option<u64>,
    /// True when the technique handed the frame to the reference path (LightCluster's worst case).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub fell_back_to_reference: bool,
    /// Further named figures a technique reports (`vpls`, `samples`, ...): reports, CSV columns and panels list
    /// them without knowing the technique.
    #[serde(flatten)]
    pub figures: std::collections::BTreeMap<String, f64>,
}

impl TechniqueCounts {
    /// Add what one cube-map (or intermediate-map) render pass drew and culled.
    pub fn add_cube_stats(&mut self, stats: &crate::renderer::cube_shadows::CubeStats) {
        self.shadow_maps += stats.cubes;
        self.shadow_triangles_submitted += stats.triangles_submitted;
        self.shadow_triangles_culled += stats.triangles_culled;
    }
}

/// A camera a technique renders from (INSM's reference viewpoints): position, target, vertical field of view.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraPose {
    pub position: Vec3,
    pub target: Vec3,
    pub fov_y_deg: f32,
}

/// A parameter value.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ParamValue {
    Float(f32),
    Int(i64),
    Bool(bool),
    Choice(String),
    /// A list of cameras the user places (the app's gizmo moves their positions).
    Cameras(Vec<CameraPose>),
}

impl std::fmt::Display for ParamValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamValue::Float(v) => write!(f, "{v}"),
            ParamValue::Int(v) => write!(f, "{v}"),
            ParamValue::Bool(v) => write!(f, "{v}"),
            ParamValue::Choice(v) => write!(f, "{v}"),
            ParamValue::Cameras(v) => {
                let poses: Vec<String> = v
                    .iter()
                    .map(|c| {
                        let (p, t) = (c.position, c.target);
                        format!("{},{},{},{},{},{},{}", p.x, p.y, p.z, t.x, t.y, t.z, c.fov_y_deg)
                    })
                    .collect();
                write!(f, "{}", poses.join(";"))
            }
        }
    }
}

/// The kind and range of a parameter, enough for the UI to build a widget and for the CLI to parse text.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamKind {
    Float {
        min: f32,
        max: f32,
    },
    Int {
        min: i64,
        max: i64,
    },
    Bool,
    Choice(&'static [&'static str]),
    /// Up to `max` cameras. On the command line: `px,py,pz,tx,ty,tz,fov` per camera, separated by `;` (numbers may
    /// also be separated by spaces, which `sweep` needs: there commas separate swept values).
    Cameras {
        max: usize,
        /// A choice parameter and the value that makes the technique use these cameras (INSM: `placement` =
        /// `custom`); the app sets it when the user edits the list.
        selected_by: Option<(&'static str, &'static str)>,
    },
}

/// A technique parameter with its current value.
#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    pub key: &'static str,
    pub label: &'static str,
    pub help: &'static str,
    pub kind: ParamKind,
    pub value: ParamValue,
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ParamError {
    #[error("technique '{technique}' has no parameter '{key}' (it has: {known})")]
    Unknown { technique: String, key: String, known: String },
    #[error("parameter '{key}': {reason}")]
    Invalid { key: String, reason: String },
}

impl ParamKind {
    /// Parse and range-check text for this kind (`--param key=value` on the command line).
    pub fn parse(&self, key: &str, text: &str) -> Result<ParamValue, ParamError> {
        let invalid = |reason: String| ParamError::Invalid { key: key.to_string(), reason };
        match self {
            ParamKind::Float { .. } => {
                let v: f32 = text.trim().parse().map_err(|_| invalid(format!("'{text}' is not a number")))?;
                self.check(key, &ParamValue::Float(v))?;
                Ok(ParamValue::Float(v))
            }
            ParamKind::Int { .. } => {
                let v: i64 = text.trim().parse().map_err(|_| invalid(format!("'{text}' is not an integer")))?;
                self.check(key, &ParamValue::Int(v))?;
                Ok(ParamValue::Int(v))
            }
            ParamKind::Bool => match text.trim() {
                "true" | "on" | "1" | "yes" => Ok(ParamValue::Bool(true)),
                "false" | "off" | "0" | "no" => Ok(ParamValue::Bool(false)),
                _ => Err(invalid(format!("'{text}' is not on/off"))),
            },
            ParamKind::Choice(_) => {
                let v = ParamValue::Choice(text.trim().to_string());
                self.check(key, &v)?;
                Ok(v)
            }
            ParamKind::Cameras { .. } => {
                let mut cameras = Vec::new();
                for (i, item) in text.split(';').map(str::trim).filter(|s| !s.is_empty()).enumerate() {
                    let numbers: Result<Vec<f32>, _> = item
                        .split(|c: char| c == ',' || c.is_whitespace())
                        .filter(|n| !n.is_empty())
                        .map(|n| n.parse::<f32>())
                        .collect();
                    match numbers.as_deref() {
                        Ok([px, py, pz, tx, ty, tz, fov]) => cameras.push(CameraPose {
                            position: Vec3::new(*px, *py, *pz),
                            target: Vec3::new(*tx, *ty, *tz),
                            fov_y_deg: *fov,
                        }),
                        _ => {
                            return Err(invalid(format!(
                                "camera {} '{item}' is not px,py,pz,tx,ty,tz,fov (7 numbers)",
                                i + 1
                            )))
                        }
                    }
                }
                let v = ParamValue::Cameras(cameras);
                self.check(key, &v)?;
                Ok(v)
            }
        }
    }

    /// Check a value against this kind's type and range.
    pub fn check(&self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        let invalid = |reason: String| Err(ParamError::Invalid { key: key.to_string(), reason });
        match (self, value) {
            (ParamKind::Float { min, max }, ParamValue::Float(v)) => {
                if !v.is_finite() || v < min || v > max {
                    return invalid(format!("{v} is outside {min}..={max}"));
                }
            }
            (ParamKind::Int { min, max }, ParamValue::Int(v)) => {
                if v < min || v > max {
                    return invalid(format!("{v} is outside {min}..={max}"));
                }
            }
            (ParamKind::Bool, ParamValue::Bool(_)) => {}
            (ParamKind::Cameras { max, .. }, ParamValue::Cameras(v)) => {
                if v.len() > *max {
                    return invalid(format!("{} cameras, at most {max}", v.len()));
                }
                for (i, c) in v.iter().enumerate() {
                    let ok = c.position.is_finite()
                        && c.target.is_finite()
                        && c.position.distance_squared(c.target) > 1e-12
                        && c.fov_y_deg.is_finite()
                        && c.fov_y_deg > 1.0
                        && c.fov_y_deg < 170.0;
                    if !ok {
                        return invalid(format!(
                            "camera {}: position and target must be finite and distinct, fov in 1..170 degrees",
                            i + 1
                        ));
                    }
                }
            }
            (ParamKind::Choice(options), ParamValue::Choice(v)) => {
                if !options.contains(&v.as_str()) {
                    return invalid(format!("'{v}' is not one of {}", options.join(", ")));
                }
            }
            _ => return invalid(format!("wrong type of value {value}")),
        }
        Ok(())
    }
}

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
        if spheres > crate::renderer::overlay::MAX_SPHERES {
            out.push(LegendEntry::new(
                Glyph::Circle,
                [1.0; 4],
                format!("cheaper form: the first {} as one circle each", crate::renderer::overlay::MAX_SPHERES),
            ));
        } else if spheres > crate::renderer::overlay::MAX_FULL_SPHERES {
            out.push(LegendEntry::new(
                Glyph::Circle,
                [1.0; 4],
                format!(
                    "cheaper form: over {} spheres, each is one horizontal circle",
                    crate::renderer::overlay::MAX_FULL_SPHERES
                ),
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
/// layers), and an index the technique understands in [`Technique::hover_details`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HoverPoint {
    pub layer: &'static str,
    pub position: Vec3,
    pub index: usize,
}

/// One step of a technique's paper, for teaching ("Explain" in the app): what it does, and what shows it: the
/// overlay layers to switch on (the technique's others are switched off), whether its maps show it (and which:
/// `maps` 0 is [`Technique::shadow_atlas`], `i` ≥ 1 the i-th of [`Technique::depth_images`]), and parameter
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

/// The legend of the layers of [`light_overlays`], which every technique offers; None for other layers.
pub fn light_layer_legend(layer: &OverlayLayer) -> Option<Vec<LegendEntry>> {
    let white = [1.0, 1.0, 1.0, 1.0];
    Some(match layer.name {
        "lights" => vec![LegendEntry::new(Glyph::Dot, white, "a light, in its colour; size grows with √intensity")],
        "light ranges" => vec![LegendEntry::new(Glyph::Circle, white, "L_att: where the light's falloff reaches 0")],
        "spot cones" => vec![LegendEntry::new(Glyph::Line, white, "a spot light's axis and cone, ¼ of L_att long")],
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

pub trait Technique {
    /// Stable identifier used by the CLI and scene files (`reference`).
    fn key(&self) -> &'static str;
    /// Name shown to people.
    fn label(&self) -> &'static str;
    fn params(&self) -> Vec<Param>;
    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError>;
    /// CPU work of a frame; returns the number of steps `encode_step` will be called for.
    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError>;
    /// Encode step `step` (0-based, < the count `prepare` returned). The renderer submits after each step, so
    /// buffers written with `queue.write_buffer` here are seen by this step only.
    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError>;
    /// Label of a step's work when the CPU fallback times whole steps.
    fn step_label(&self) -> &'static str;
    fn counts(&self) -> TechniqueCounts;
    /// CPU stages of the last `prepare` (e.g. clustering), in milliseconds.
    fn cpu_times(&self) -> Vec<crate::timing::PassTime> {
        Vec::new()
    }
    fn overlays(&self, lights: &[PointLight]) -> Vec<OverlayLayer>;
    /// [`Technique::overlays`] with primitives only in the layers `shown(name, visible_by_default)` accepts; the
    /// others keep their name and default and no primitives (the layer list needs them). The app asks this every
    /// UI frame, so a technique whose layers cost a readback (INSM's meshes) overrides it to build only those
    /// shown; the default builds everything and empties the hidden layers.
    fn overlays_shown(&self, lights: &[PointLight], shown: &dyn Fn(&str, bool) -> bool) -> Vec<OverlayLayer> {
        let mut layers = self.overlays(lights);
        for layer in &mut layers {
            if !shown(layer.name, layer.visible_by_default) {
                layer.primitives.clear();
            }
        }
        layers
    }
    /// A per-pixel ID map of the last frame, from the world position of each pixel (None: background), with
    /// the name of its overlay layer; None when the technique has none.
    fn pixel_ids(&self, _positions: &[Option<Vec3>]) -> Option<(&'static str, Vec<u32>)> {
        None
    }
    /// The cameras the last frame used for a [`ParamKind::Cameras`] parameter `key`, including automatically
    /// placed ones (so the app can start editing from them).
    fn cameras_in_use(&self, _key: &str) -> Vec<CameraPose> {
        Vec::new()
    }
    /// The integer parameters `(x, y)` that a click in the view sets to the clicked pixel, for a technique
    /// that can show what happens at one pixel (e.g. a shading point's clusters and rays); None when it has
    /// no such probe.
    fn probe_params(&self) -> Option<(&'static str, &'static str)> {
        None
    }
    /// True for indirect techniques that gather the frame's VPLs (the renderer generates them only then).
    fn uses_vpls(&self) -> bool {
        false
    }
    /// The legend of one of this technique's overlay layers (as returned by `overlays`): what its glyphs and
    /// colours mean. The default describes the shared light layers and otherwise counts the layer's primitives.
    fn overlay_legend(&self, layer: &OverlayLayer) -> Vec<LegendEntry> {
        let mut legend = light_layer_legend(layer).unwrap_or_default();
        legend.extend(layer.summary());
        legend
    }
    /// The steps of the technique's paper, in order, with what shows each (empty: none described).
    fn explain(&self) -> Vec<ExplainStep> {
        Vec::new()
    }
    /// What the last frame made of light `index` (of the lights it was given): e.g. its cluster, with that
    /// cluster's members. None: nothing beyond the light's own fields.
    fn light_details(&self, _index: usize) -> Option<LightDetails> {
        None
    }
    /// The points of the last frame's overlays that have a hover tooltip (beyond the lights, which every
    /// technique has through [`Self::light_details`]); empty: none.
    fn hover_points(&self) -> Vec<HoverPoint> {
        Vec::new()
    }
    /// The tooltip of hover point `index` of `layer` (as [`Self::hover_points`] gave it): lines of text.
    fn hover_details(&self, _layer: &str, _index: usize) -> Vec<String> {
        Vec::new()
    }
    /// True when this frame's shading passes read the renderer's tile lists of the visible lights
    /// ([`FrameContext::light_tiles`]); asked after `prepare`, so the renderer builds them only then.
    fn uses_light_tiles(&self) -> bool {
        false
    }
    /// The shadow-map atlas of the last step (the last batch when the frame had several), with what its tiles
    /// are, for inspection; None for techniques without one.
    fn shadow_atlas(&self) -> Option<(&crate::renderer::cube_shadows::CubeAtlas, &'static str)> {
        None
    }
    /// Depth images the last frame rendered besides its shadow maps (INSM's intermediate images), each with
    /// what its tiles are, for inspection; empty for most techniques.
    fn depth_images(&self) -> Vec<(&crate::renderer::cube_shadows::CubeAtlas, &'static str)> {
        Vec::new()
    }
}

/// Most light evaluations (lights x shadow rays) one full-screen pass may do per pixel: a single pass over
/// 100,000 lights (or 4,096 lights x 256 rays) can run for seconds and lose a real GPU's device to its
/// watchdog, so passes are split to stay under this. The image does not change.
pub const MAX_LIGHT_WORK_PER_PASS: usize = 4096;

/// A full-screen pass that adds `pipeline`'s output into the HDR target: group 0 is the screen bind group,
/// groups 1.. are `groups` (the technique's, then the tile lists' when it reads them). The shading passes of all techniques go through here.
pub fn accumulate_pass(
    ctx: &FrameContext,
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::RenderPipeline,
    groups: &[&wgpu::BindGroup],
) {
    ctx.timer.render_pass(
        encoder,
        label,
        wgpu::RenderPassDescriptor {
            label: None,
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: ctx.hdr_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        },
        |pass| {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, ctx.screen_bind_group, &[]);
            for (i, group) in groups.iter().enumerate() {
                pass.set_bind_group(1 + i as u32, *group, &[]);
            }
            pass.draw(0..3, 0..1);
        },
    );
}

/// A storage-buffer layout entry for fragment shaders, read only.
pub fn storage_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A uniform-buffer layout entry for fragment shaders.
pub fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A depth-texture layout entry (cube shadow atlases) for fragment shaders. Bound as an unfilterable float
/// texture (allowed for Depth32Float): `textureLoad` on a depth texture has no GLSL form, so the GL backend needs this.
pub fn depth_texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// A storage buffer of `T` that grows (to the next power of two) when a frame needs more.
pub struct GrowableBuffer {
    pub buffer: wgpu::Buffer,
    capacity_bytes: u64,
    label: &'static str,
}

impl GrowableBuffer {
    pub fn new(device: &wgpu::Device, label: &'static str, capacity_bytes: u64) -> Self {
        let capacity_bytes = capacity_bytes.max(256);
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: capacity_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        GrowableBuffer { buffer, capacity_bytes, label }
    }

    /// Upload `data`; returns true when the buffer was recreated (bind groups must be rebuilt).
    pub fn write<T: bytemuck::Pod>(&mut self, gpu: &GpuContext, data: &[T]) -> bool {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut grown = false;
        if bytes.len() as u64 > self.capacity_bytes {
            *self = GrowableBuffer::new(&gpu.device, self.label, (bytes.len() as u64).next_power_of_two());
            grown = true;
        }
        if !bytes.is_empty() {
            gpu.queue.write_buffer(&self.buffer, 0, bytes);
        }
        grown
    }
}

/// The parameters every cube-shadow-map technique has (the reference, LightCluster, ...), described and set
/// in one place.
#[derive(Clone, Debug, PartialEq)]
pub struct CubeMapParams {
    /// Texels per cube face.
    pub shadow_resolution: u32,
    /// Constant depth bias in world units.
    pub bias_world: f32,
    /// Normal offset in shadow-map texels.
    pub normal_offset_texels: f32,
    /// Memory for one batch's atlas, in MiB.
    pub atlas_budget_mib: u32,
    /// Cull chunks per light and per cube face. Off draws every chunk into every face, which is the
    /// conventional shadow mapping the INSM paper compares with (`n N` triangles).
    pub cull: bool,
}

impl Default for CubeMapParams {
    fn default() -> Self {
        CubeMapParams {
            shadow_resolution: 1024,
            bias_world: 0.01,
            normal_offset_texels: 1.5,
            atlas_budget_mib: (crate::renderer::cube_shadows::DEFAULT_ATLAS_BUDGET_BYTES >> 20) as u32,
            cull: true,
        }
    }
}

impl CubeMapParams {
    pub fn params(&self) -> Vec<Param> {
        vec![
            Param {
                key: "shadow_res",
                label: "Cube resolution",
                help: "Texels per cube-map face",
                kind: ParamKind::Int { min: 16, max: 4096 },
                value: ParamValue::Int(self.shadow_resolution as i64),
            },
            Param {
                key: "bias",
                label: "Depth bias",
                help: "Constant bias in world units",
                kind: ParamKind::Float { min: 0.0, max: 1.0 },
                value: ParamValue::Float(self.bias_world),
            },
            Param {
                key: "normal_offset",
                label: "Normal offset",
                help: "Receiver offset along its normal, in shadow-map texels",
                kind: ParamKind::Float { min: 0.0, max: 16.0 },
                value: ParamValue::Float(self.normal_offset_texels),
            },
            Param {
                key: "atlas_mib",
                label: "Batch memory (MiB)",
                help: "Memory of one batch of cube maps; more per batch means fewer passes",
                kind: ParamKind::Int { min: 1, max: 4096 },
                value: ParamValue::Int(self.atlas_budget_mib as i64),
            },
            Param {
                key: "cull",
                label: "Cull per light and face",
                help: "Draw only the chunks within a light's range and a face's pyramid (off: every chunk into every \
                       face, conventional shadow mapping)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(self.cull),
            },
        ]
    }

    /// Set one of these parameters (already range-checked); false when `key` is not one of them.
    pub fn set(&mut self, key: &str, value: &ParamValue) -> bool {
        match (key, value) {
            ("shadow_res", ParamValue::Int(v)) => self.shadow_resolution = *v as u32,
            ("bias", ParamValue::Float(v)) => self.bias_world = *v,
            ("normal_offset", ParamValue::Float(v)) => self.normal_offset_texels = *v,
            ("atlas_mib", ParamValue::Int(v)) => self.atlas_budget_mib = *v as u32,
            ("cull", ParamValue::Bool(v)) => self.cull = *v,
            _ => return false,
        }
        true
    }

    /// Cube-map resolution the device allows, and the atlas budget in bytes.
    pub fn resolution_and_budget(&self, gpu: &GpuContext) -> (u32, u64) {
        let res = self.shadow_resolution.min(gpu.device.limits().max_texture_dimension_2d);
        (res, self.atlas_budget_mib as u64 * (1 << 20))
    }
}

/// A light's overlay colour: its colour normalised to full brightness.
pub fn light_overlay_color(l: &PointLight) -> [f32; 4] {
    let c = l.color / l.color.max_element().max(1e-6);
    [c.x, c.y, c.z, 1.0]
}

/// The overlays every technique offers for its lights: dots sized by intensity, and range spheres (`L_att`).
pub fn light_overlays(lights: &[PointLight]) -> Vec<OverlayLayer> {
    let max_intensity = lights.iter().map(|l| l.intensity).fold(0.0f32, f32::max).max(1e-6);
    let mut layers = vec![
        OverlayLayer {
            name: "lights",
            visible_by_default: true,
            primitives: lights
                .iter()
                .map(|l| Overlay::Point {
                    position: l.position,
                    color: light_overlay_color(l),
                    radius_px: 2.0 + 4.0 * (l.intensity / max_intensity).sqrt(),
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

/// Helper for `set_param`: find the parameter, check the value's range, or say what exists.
pub fn check_param(technique: &str, params: &[Param], key: &str, value: &ParamValue) -> Result<(), ParamError> {
    match params.iter().find(|p| p.key == key) {
        Some(p) => p.kind.check(key, value),
        None => Err(ParamError::Unknown {
            technique: technique.to_string(),
            key: key.to_string(),
            known: params.iter().map(|p| p.key).collect::<Vec<_>>().join(", "),
        }),
    }
}

/// A registered technique: its key, and how to create it on a device.
pub struct TechniqueEntry {
    pub key: &'static str,
    pub label: &'static str,
    pub create: fn(&GpuContext, &SharedLayouts) -> Box<dyn Technique>,
    /// The VPL source an indirect technique's paper uses, taken when the user chose none (`--vpl-source auto`).
    pub vpl_source: Option<crate::vpl::VplSource>,
}

/// Every technique ShadowLab has. The app's selector and the CLI's `--technique` read this list.
pub const REGISTRY: &[TechniqueEntry] = &[
    TechniqueEntry {
        key: "reference",
        label: "Reference (cube shadow map per light)",
        create: |gpu, layouts| Box::new(reference::Reference::new(gpu, layouts)),
        vpl_source: None,
    },
    TechniqueEntry {
        key: "unshadowed",
        label: "Unshadowed (no shadows, preview)",
        create: |gpu, layouts| Box::new(unshadowed::Unshadowed::new(gpu, layouts)),
        vpl_source: None,
    },
    TechniqueEntry {
        key: "lightcluster",
        label: "LightCluster (clustered cube maps, PCF/PCSS)",
        create: |gpu, layouts| Box::new(lightcluster::LightCluster::new(gpu, layouts)),
        vpl_source: None,
    },
    TechniqueEntry {
        key: "insm",
        label: "INSM (intermediate shadow maps)",
        create: |gpu, layouts| Box::new(insm::Insm::new(gpu, layouts)),
        vpl_source: None,
    },
    TechniqueEntry {
        key: "raytraced",
        label: "Ray traced (ground truth)",
        create: |gpu, layouts| Box::new(raytraced::Raytraced::new(gpu, layouts)),
        vpl_source: None,
    },
];

/// Every indirect technique: each adds the frame's indirect light into [`FrameContext::indirect_buffer`].
/// The app's second selector and the CLI's `--indirect` read this list.
pub const INDIRECT_REGISTRY: &[TechniqueEntry] = &[
    TechniqueEntry {
        key: "vpl-shadowmaps",
        label: "VPLs, a shadow map each (instant radiosity)",
        create: |gpu, layouts| Box::new(vpl_gather::VplGather::new(gpu, layouts, vpl_gather::Visibility::ShadowMaps)),
        vpl_source: None,
    },
    TechniqueEntry {
        key: "vpl-raytraced",
        label: "VPLs, ray-traced visibility (ground truth)",
        create: |gpu, layouts| Box::new(vpl_gather::VplGather::new(gpu, layouts, vpl_gather::Visibility::RayTraced)),
        vpl_source: None,
    },
    TechniqueEntry {
        key: "vpl-unshadowed",
        label: "VPLs, no visibility",
        create: |gpu, layouts| Box::new(vpl_gather::VplGather::new(gpu, layouts, vpl_gather::Visibility::None)),
        vpl_source: None,
    },
    TechniqueEntry {
        key: "val",
        label: "Virtual area lights (Dong 2009)",
        create: |gpu, layouts| Box::new(val::VirtualAreaLights::new(gpu, layouts)),
        vpl_source: None,
    },
    TechniqueEntry {
        key: "fuzzy",
        label: "Fuzzy clustering of shading points and VPLs (Colom 2022)",
        create: |gpu, layouts| Box::new(fuzzy::FuzzyClustering::new(gpu, layouts)),
        vpl_source: Some(crate::vpl::VplSource::Traced),
    },
    TechniqueEntry {
        key: "pathtraced",
        label: "Path traced one bounce (truth)",
        create: |gpu, layouts| Box::new(pathtraced::PathTraced::new(gpu, layouts)),
        vpl_source: None,
    },
];

/// Create an indirect technique by key.
pub fn create_indirect(key: &str, gpu: &GpuContext, layouts: &SharedLayouts) -> Option<Box<dyn Technique>> {
    INDIRECT_REGISTRY.iter().find(|e| e.key == key).map(|e| (e.create)(gpu, layouts))
}

/// The VPL source the indirect technique `key`'s paper uses (Colom 2022 traces particles), None when it has
/// no preference or is unknown.
pub fn preferred_vpl_source(key: &str) -> Option<crate::vpl::VplSource> {
    INDIRECT_REGISTRY.iter().find(|e| e.key == key).and_then(|e| e.vpl_source)
}

/// The keys of all indirect techniques, for error messages.
pub fn indirect_keys() -> String {
    INDIRECT_REGISTRY.iter().map(|e| e.key).collect::<Vec<_>>().join(", ")
}

/// Create a technique by key.
pub fn create(key: &str, gpu: &GpuContext, layouts: &SharedLayouts) -> Option<Box<dyn Technique>> {
    REGISTRY.iter().find(|e| e.key == key).map(|e| (e.create)(gpu, layouts))
}

/// The keys of all techniques, for error messages.
pub fn keys() -> String {
    REGISTRY.iter().map(|e| e.key).collect::<Vec<_>>().join(", ")
}
