//! The technique interface. Every technique has the same shape, so adding one touches its folder
//! (`technique/<name>/`: its Rust, its WGSL, its shader list) and one entry of [`registry`]:
//! - a long-lived struct that owns its pipelines and GPU resources (`new`),
//! - its parameters, described for the UI and the CLI ([`Technique::params`], [`Technique::set_param`]),
//! - `prepare`: the CPU work of a frame (culling, clustering, batching), returning how many steps it needs,
//! - `encode_step`: one function per pass, called once per step; each step is submitted on its own, which
//!   bounds memory (a reused shadow-map pool) and lets the app spread a slow frame over UI frames,
//! - its counts for the frame report and its overlays for the 3D view.
//!
//! The renderer owns what all techniques share: the G-buffer, the HDR accumulation target (already holding
//! ambient and emission when steps run), tone mapping and timing.
//!
//! Layers: [`params`], [`overlay`] and [`work`] are plain data ([`crate::contract`]), below the renderer's
//! services (which draw overlays and describe parameters); the [`FrameContext`] lives with the services
//! ([`crate::services::context`]), since the services that run a technique's passes take it; this file holds the
//! trait, above them; the technique folders sit above it, [`registry`], which names them, above those, and the
//! `Renderer` that drives a frame (`renderer/`) on top.

pub mod registry;

pub mod fuzzy;
pub mod insm;
pub mod ism;
pub mod lightcluster;
pub mod pathtraced;
pub mod raytraced;
pub mod reference;
pub mod restir;
pub mod unshadowed;
pub mod val;
pub mod vpl_gather;

pub use crate::contract::{overlay, params, work};
pub use crate::services::context::{accumulate_pass, DirectionalVisibility, FrameContext, MAX_LIGHT_WORK_PER_PASS};

pub use overlay::{
    index_color, light_layer_legend, light_overlay_color, light_overlays, sun_overlays, ExplainStep, Glyph, HoverPoint,
    LegendEntry, LightDetails, Overlay, OverlayLayer, RSM_MAPS, SUNS_LAYER,
};
pub use params::{check_param, CameraPose, Param, ParamError, ParamKind, ParamValue};
pub use work::WorkCounts;

use glam::Vec3;
use serde::Serialize;

use crate::error::GpuError;
use crate::math::Frustum;
use crate::scene::{Camera, PointLight};
use crate::services::cube_shadows::{CubeAtlas, CubeStats};
use crate::timing::PassTime;

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
    /// The work counts the CPU decides (shadow texels written, k-means distances, ...); the renderer adds what
    /// the GPU counted and the triangles of the depth passes.
    #[serde(skip)]
    pub work: work::WorkCounts,
    /// Further named figures a technique reports (`vpls`, `samples`, ...): reports, CSV columns and panels list
    /// them without knowing the technique.
    #[serde(flatten)]
    pub figures: std::collections::BTreeMap<String, f64>,
}

impl TechniqueCounts {
    /// Add what one cube-map (or intermediate-map) render pass drew and culled.
    pub fn add_cube_stats(&mut self, stats: &CubeStats) {
        self.shadow_maps += stats.cubes;
        self.shadow_triangles_submitted += stats.triangles_submitted;
        self.shadow_triangles_culled += stats.triangles_culled;
        self.work.shadow_texels_written += stats.texels_written;
    }

    /// The frame's work map of this technique: its CPU-decided counts, what the GPU counted for it and the
    /// triangles its depth passes submitted.
    pub fn work_map(
        &self,
        gpu_counted: &work::WorkCounts,
        shaded_pixels: u64,
    ) -> std::collections::BTreeMap<String, f64> {
        let mut w = self.work;
        w.add(gpu_counted);
        w.depth_triangles += self.shadow_triangles_submitted;
        w.to_map(shaded_pixels)
    }
}

/// What a technique's overlay stages need to run without rendering a frame: the app's preview while a light or
/// the camera moves ([`Technique::update_overlays`], through `Renderer::update_overlays`).
pub struct OverlayContext<'a> {
    pub camera: &'a Camera,
    pub frustum: Frustum,
    pub lights: &'a [PointLight],
    /// Indices of the lights whose range touches the view frustum, as a frame's light culling finds them.
    pub visible: &'a [usize],
    /// The VPLs of these lights for a technique that [uses VPLs](Technique::uses_vpls) (empty otherwise), at the
    /// preview's size: at most [`crate::vpl::PREVIEW_VPLS`] of the frame's `N` ([`OverlayContext::vpl_samples`]).
    pub vpls: &'a std::sync::Arc<crate::vpl::VplSet>,
    /// The VPL samples `vpls` was drawn from and the frame's `N` (fewer when `N` is past the preview's size).
    pub vpl_samples: (u32, u32),
    /// The scene's bounds (what the clusterings normalise by).
    pub scene_bounds: crate::scene::Aabb,
}

impl OverlayContext<'_> {
    /// What to say in a legend when the VPLs are fewer than a frame's.
    pub fn vpl_note(&self) -> Option<String> {
        let (used, asked) = self.vpl_samples;
        (used < asked).then(|| format!("while moving: from {used} of {asked} VPL samples (the preview's size)"))
    }
}

/// What [`Technique::update_overlays`] made of a technique's overlays.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum OverlayUpdate {
    /// The stages did not run: every layer shows the last complete frame.
    #[default]
    Stale,
    /// The stages ran for the new lights and camera.
    Live {
        /// How the live layers differ from a frame's (made at the preview's size), said in their legends.
        note: Option<String>,
        /// Layers that did not follow (their stages need a frame, e.g. the G-buffer of a moved camera).
        stale_layers: Vec<&'static str>,
    },
}

impl OverlayUpdate {
    /// Live, as a frame makes them.
    pub fn live() -> OverlayUpdate {
        OverlayUpdate::Live { note: None, stale_layers: Vec::new() }
    }

    /// Whether `layer` still shows the last complete frame.
    pub fn is_stale(&self, layer: &str) -> bool {
        match self {
            OverlayUpdate::Stale => true,
            OverlayUpdate::Live { stale_layers, .. } => stale_layers.contains(&layer),
        }
    }

    /// The note for the legend of a live `layer`.
    pub fn note(&self, layer: &str) -> Option<&str> {
        match self {
            OverlayUpdate::Live { note: Some(n), .. } if !self.is_stale(layer) => Some(n),
            _ => None,
        }
    }
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
    fn cpu_times(&self) -> Vec<PassTime> {
        Vec::new()
    }
    fn overlays(&self, lights: &[PointLight]) -> Vec<OverlayLayer>;
    /// Run the stages that make the overlays again for `ctx`'s lights and camera, without rendering, so the
    /// overlays follow a dragged light or camera in the same UI frame while the preview renders the image.
    /// Which layers now show `ctx` ([`OverlayUpdate::Stale`], the default: all still show the last complete
    /// frame). Only called between frames: the next `prepare` starts from scratch (and no warm start carries
    /// what this run found into a frame).
    fn update_overlays(&mut self, _ctx: &OverlayContext) -> OverlayUpdate {
        OverlayUpdate::Stale
    }
    /// How this technique's frames see the scene's directional lights (the renderer's service shades them for
    /// every technique, [`crate::services::directional`]): by the orthographic shadow map unless overridden.
    fn directional_visibility(&self) -> DirectionalVisibility {
        DirectionalVisibility::ShadowMap
    }
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
    /// The keys of parameters that change only how the work is scheduled, timed or counted, never the image
    /// (the tests of each technique check that): the app folds them into a "Tuning" section of its panel.
    fn tuning_params(&self) -> &'static [&'static str] {
        &[]
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
    fn shadow_atlas(&self) -> Option<(&CubeAtlas, &'static str)> {
        None
    }
    /// Depth images the last frame rendered besides its shadow maps (INSM's intermediate images), each with
    /// what its tiles are, for inspection; empty for most techniques.
    fn depth_images(&self) -> Vec<(&CubeAtlas, &'static str)> {
        Vec::new()
    }
}
