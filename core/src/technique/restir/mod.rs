//! ReSTIR: spatiotemporal reservoir resampling for many-light direct lighting (Bitterli, Wyman, Pharr, Shirley,
//! Lefohn, Jarosz 2020). Each pixel keeps one light sample `y` in a reservoir, chosen by resampled importance
//! sampling (RIS) from a few cheap candidates and improved by reusing the reservoirs of the previous frame and
//! of neighbouring pixels; one shadow ray per pixel (plus those of the reuse) decides the hard shadow of the
//! chosen point light. Its target is `raytraced` (the same shadow rays, to every light).
//!
//! The paper's symbols: the integrand `f(x)` (the unshadowed contribution of light `x` at pixel `q` times its
//! visibility `V`), the source pdf `p(x)`, the target function `p̂_q(x)` (here the luminance of the unshadowed
//! contribution, `common.wgsl`'s `shade_light`, so with every light visible the result is the other techniques'
//! shading), a reservoir `(y, w_sum, M, W)` with `W = w_sum / (M p̂_q(y))` the unbiased contribution weight, and
//! the pixel estimate `f(y) W`.
//!
//! Per frame (Algorithm 5), one compute pass per step, one function each:
//! 1. Candidates and RIS (Algorithm 3, [`Restir::candidates_pass`], `restir/candidates.wgsl`): `M = candidates`
//!    lights `x_i ~ p`, `p` uniform over the visible lights or by power through an alias table built on the CPU
//!    once per light set ([`alias`]: one uniform slot and one threshold test per draw, O(1) for 100k lights);
//!    each streamed into the reservoir with `w_i = p̂_q(x_i) / p(x_i)` (Algorithm 2, `update`: `y = x_i` with
//!    probability `w_i / w_sum`).
//! 2. Visibility reuse (Algorithm 5, lines 6-9, same pass): one shadow ray from the pixel to `y` through the
//!    scene BVH (the renderer's service, the ray tracer's offsets and `bias`); `W = 0` when it is blocked, before
//!    any reuse.
//! 3. Temporal reuse ([`Restir::temporal_pass`], `restir/temporal.wgsl`): the pixel's surface reprojected with
//!    the previous frame's `clip_from_world` onto that frame's final reservoirs (two storage buffers: this
//!    frame's and the last final ones), rejected when camera distances differ by more than `depth_threshold`
//!    (10 %) or normals by more than `normal_threshold` (25°), the history's `M` capped at `history` (20) times
//!    `M`; combined by Algorithm 4 (`s.update(r.y, p̂_q(r.y) r.W r.M)` per input, `s.M = Σ r.M`).
//! 4. Spatial reuse ([`Restir::spatial_pass`], `restir/spatial.wgsl`): `spatial` (5) neighbours uniform in a
//!    disc of `radius` (30) pixels, rejected by the same depth and normal test, combined the same way; then one
//!    shadow ray from the pixel to the final `y` (`W = 0` when blocked).
//! 5. Shading ([`Restir::shade_pass`], `restir/shade.wgsl`): `f(y) W / frames` summed in f32; after frames 1,
//!    2, 4, ... and the last, the running mean's change added into the HDR target ([`Restir::output_pass`]), so
//!    a progressive display shows the mean so far.
//!
//! `bias_mode`: `biased` normalises every combination by `1/M` (Algorithm 4: darker where neighbours see other
//! lights, e.g. at shadow edges); `unbiased` by the paper's `1/Z` (Algorithm 6): `Z` is the sum of the `M` of
//! the inputs whose surface could have drawn `y`, `p̂_{q_i}(y) > 0` and `y` visible from `q_i` (visibility is
//! part of a reservoir's support because every reservoir's `W` is 0 where its own pixel cannot see its sample:
//! visibility reuse, and the final ray of step 4 for the history), one shadow ray per input but the one `y`
//! came from. The paper's MIS weights (its alternative to `1/Z`) are not implemented.
//!
//! Progressive: `frames` ReSTIR frames per rendered frame, one step each, each reusing the one before (its
//! camera is the previous camera), their images averaged as the path tracer averages its steps; reservoirs
//! are also kept from one rendered frame to the next (reprojected when the camera moved), until the size, the
//! number of lights or the scene changes. Seeded: random numbers are a PCG hash of pixel, pass, ReSTIR frame
//! counter and `seed`, so a new technique with the same seed renders the same frames.
//!
//! Deviations from the paper, and why:
//! - Lights are point and spot lights (the scene's), not emissive triangles; `p̂` and `f` are `shade_light`,
//!   the hard shadow one ray to the light's centre: what `raytraced` computes for every light.
//! - Candidates come from the lights whose range touches the view frustum (the renderer's culling); the others
//!   light no visible pixel. "Power" is the luminance of colour times intensity (a spot's cone not counted).
//! - One spatial pass (Algorithm 5 allows `n` iterations).
//! - The final sample's visibility is traced in the spatial pass and kept in `W` (shading needs no ray, and the
//!   next frame's history holds only samples its pixels see); in unbiased mode not when `y` is the pixel's own
//!   sample, which its `W > 0` says it sees.
//! - The unbiased `Z` test at the previous frame's surface uses the normal stored with its reservoir (15 bits
//!   per octahedral coordinate) and a flag for a non-black BRDF, not that frame's G-buffer.

pub mod alias;
mod overlays;
pub mod params;
mod passes;
mod state;

use std::sync::Arc;

use glam::Vec3;

use super::{FrameContext, OverlayLayer, Param, ParamError, ParamValue, Technique, TechniqueCounts};
use crate::accel::scene_bvh::SceneBvh;
use crate::error::GpuError;
use crate::gpu::buffer::GrowableBuffer;
use crate::gpu::GpuContext;
use crate::scene::PointLight;
use crate::services::shade_pass::ShadePass;
use crate::shaders::WgslModule;
use crate::timing::PassTime;
pub use params::{BiasMode, RestirParams, Source};
use state::{GpuReservoir, Groups, History, Inspection, Reservoirs};

/// This technique's own WGSL modules; its registry entry lists them and the naga test validates them.
pub const SHADERS: &[WgslModule] = &[CANDIDATES, TEMPORAL, SPATIAL, SHADE, OUTPUT];
const CANDIDATES: WgslModule = crate::shaders::wgsl!(
    "restir_candidates",
    [
        "shaders/common.wgsl",
        "shaders/light_tiles.wgsl",
        "shaders/raytrace_bvh.wgsl",
        "core/src/technique/restir/reservoir.wgsl",
        "core/src/technique/restir/trace.wgsl",
        "core/src/technique/restir/candidates.wgsl"
    ]
);
const TEMPORAL: WgslModule = crate::shaders::wgsl!(
    "restir_temporal",
    [
        "shaders/common.wgsl",
        "shaders/raytrace_bvh.wgsl",
        "core/src/technique/restir/reservoir.wgsl",
        "core/src/technique/restir/trace.wgsl",
        "core/src/technique/restir/temporal.wgsl"
    ]
);
const SPATIAL: WgslModule = crate::shaders::wgsl!(
    "restir_spatial",
    [
        "shaders/common.wgsl",
        "shaders/raytrace_bvh.wgsl",
        "core/src/technique/restir/reservoir.wgsl",
        "core/src/technique/restir/trace.wgsl",
        "core/src/technique/restir/spatial.wgsl"
    ]
);
const SHADE: WgslModule = crate::shaders::wgsl!(
    "restir_shade",
    [
        "shaders/common.wgsl",
        "shaders/raytrace_bvh.wgsl",
        "core/src/technique/restir/reservoir.wgsl",
        "core/src/technique/restir/trace.wgsl",
        "core/src/technique/restir/shade.wgsl"
    ]
);
const OUTPUT: WgslModule =
    crate::shaders::wgsl!("restir_output", ["shaders/common.wgsl", "core/src/technique/restir/output.wgsl"]);

pub struct Restir {
    pub params: RestirParams,
    candidates_pipeline: wgpu::ComputePipeline,
    temporal_pipeline: wgpu::ComputePipeline,
    spatial_pipeline: wgpu::ComputePipeline,
    shade_pipeline: wgpu::ComputePipeline,
    group_layout: wgpu::BindGroupLayout,
    shade_layout: wgpu::BindGroupLayout,
    /// `FrameUniform`, bound by every compute pass.
    uniform: wgpu::Buffer,
    /// The pass adding the running mean's change into the HDR target after every ReSTIR frame.
    output: ShadePass,
    /// Every light of the frame, in the frame's order (invalid ones zeroed: they light nothing).
    lights: GrowableBuffer,
    /// The fingerprint and count of the uploaded lights.
    lights_key: Option<(u64, usize)>,
    /// The source table over the visible lights, and what it was built from.
    source: GrowableBuffer,
    source_key: Option<(u64, Vec<usize>, Source)>,
    source_count: usize,
    reservoirs: Option<Reservoirs>,
    groups: Option<Groups>,
    bvh: Option<Arc<SceneBvh>>,
    history: Option<History>,
    /// ReSTIR frames run since creation: the random numbers' frame counter.
    frame_index: u32,
    /// ReSTIR frames of this rendered frame (0: nothing to shade) and steps (one more to read back).
    frames: usize,
    last_step: &'static str,
    counts: TechniqueCounts,
    build_ms: Option<f64>,
    table_ms: f64,
    inspection: Inspection,
}

impl Restir {
    /// The final reservoirs of the last frame, read back (blocking).
    pub fn read_reservoirs(&self, gpu: &GpuContext) -> Result<Vec<GpuReservoir>, GpuError> {
        let Some(res) = &self.reservoirs else { return Ok(Vec::new()) };
        let bytes = crate::gpu::readback::read_buffer(gpu, &res.last)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}

impl Technique for Restir {
    fn key(&self) -> &'static str {
        "restir"
    }

    fn label(&self) -> &'static str {
        "ReSTIR (spatiotemporal reservoir resampling)"
    }

    fn params(&self) -> Vec<Param> {
        self.params.list()
    }

    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        self.params.set(key, value)
    }

    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        self.build_ms = None;
        self.table_ms = 0.0;
        self.frames = 0;
        self.last_step = "restir frame";
        self.upload_lights(ctx);
        self.build_source(ctx);
        let visible = ctx.visible_lights.indices.len();
        self.counts = TechniqueCounts { lights_visible: visible, ..Default::default() };
        let pixels = ctx.size.0 as u64 * ctx.size.1 as u64;
        if self.source_count == 0 || pixels == 0 {
            // Nothing lights a visible pixel: the ambient image.
            self.inspection = Inspection::default();
            return Ok(0);
        }
        self.ensure_reservoirs(ctx)?;
        let (bvh, build_ms) = ctx.scene.bvh(ctx.gpu);
        self.build_ms = build_ms;
        if self.bvh.as_ref().is_none_or(|b| !Arc::ptr_eq(b, &bvh)) {
            self.groups = None;
            self.history = None;
        }
        self.bvh = Some(bvh);
        self.bind_groups(ctx);
        self.frames = self.params.frames.max(1) as usize;
        self.counts.batches = self.frames;
        // The first frame reuses the last rendered frame's reservoirs when there are any, the others the one
        // before them.
        let temporal = match (self.params.history, self.history) {
            (0, _) => 0,
            (_, Some(_)) => self.frames,
            (_, None) => self.frames - 1,
        };
        let figures = &mut self.counts.figures;
        figures.insert("restir frames".into(), self.frames as f64);
        figures.insert("candidates".into(), self.params.candidates as f64);
        figures.insert("temporal reuse frames".into(), temporal as f64);
        figures.insert("spatial neighbours".into(), self.params.spatial as f64);
        Ok(self.frames + self.params.inspect as usize)
    }

    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        if step >= self.frames {
            // The step after the last frame: its reservoirs, for the per-pixel maps.
            self.last_step = "restir readback";
            let reservoirs = self.read_reservoirs(ctx.gpu)?;
            self.inspection = state::inspect(&reservoirs, ctx.size, self.params.candidates);
            return Ok(());
        }
        self.last_step = "restir frame";
        let history = self.history.filter(|_| self.params.history > 0);
        let uniform = self.frame_uniform(ctx, history, step);
        ctx.gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        self.candidates_pass(ctx, encoder);
        if history.is_some() {
            self.temporal_pass(ctx, encoder);
        }
        self.spatial_pass(ctx, encoder);
        self.shade_pass(ctx, encoder);
        if Self::shows(step, self.frames) {
            self.output_pass(ctx, encoder);
        }
        self.history = Some(History {
            clip_from_world: ctx.camera.clip_from_world(ctx.aspect),
            camera_position: ctx.camera.position,
        });
        self.frame_index = self.frame_index.wrapping_add(1);
        Ok(())
    }

    /// Directional lights: its visibility is ray traced: one shadow ray per pixel (a sun needs no resampling).
    fn directional_visibility(&self) -> super::DirectionalVisibility {
        super::DirectionalVisibility::Traced
    }

    fn step_label(&self) -> &'static str {
        self.last_step
    }

    fn counts(&self) -> TechniqueCounts {
        self.counts.clone()
    }

    fn cpu_times(&self) -> Vec<PassTime> {
        let mut times: Vec<PassTime> =
            self.build_ms.map(|ms| PassTime { name: "bvh build".into(), ms, count: 1 }).into_iter().collect();
        if self.table_ms > 0.0 {
            times.push(PassTime { name: "restir source table".into(), ms: self.table_ms, count: 1 });
        }
        times
    }

    fn uses_light_tiles(&self) -> bool {
        self.params.source == Source::Tiles
    }

    fn overlays(&self, lights: &[PointLight]) -> Vec<OverlayLayer> {
        self.overlay_layers(lights)
    }

    fn overlay_legend(&self, layer: &OverlayLayer) -> Vec<super::LegendEntry> {
        self.legend_of(layer)
    }

    fn explain(&self) -> Vec<super::ExplainStep> {
        Self::explain_steps()
    }

    fn pixel_ids(&self, positions: &[Option<Vec3>]) -> Option<(&'static str, Vec<u32>)> {
        if positions.is_empty() {
            return Some((state::LIGHT_MAP, Vec::new()));
        }
        let ins = &self.inspection;
        (ins.lights.len() == positions.len()).then(|| (state::LIGHT_MAP, ins.lights.to_vec()))
    }

    fn hover_details(&self, layer: &str, index: usize) -> Vec<String> {
        self.hover_text(layer, index)
    }
}
