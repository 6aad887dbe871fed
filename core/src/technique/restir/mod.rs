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
//! 5. Shading ([`Restir::shade_pass`], `restir/shade.wgsl`): `f(y) W / frames` added into the HDR target.
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

use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::{FrameContext, OverlayLayer, Param, ParamError, ParamValue, Technique, TechniqueCounts};
use crate::accel::scene_bvh::SceneBvh;
use crate::error::GpuError;
use crate::gpu::bind::{storage_entry, storage_rw_entry, uniform_entry};
use crate::gpu::buffer::GrowableBuffer;
use crate::gpu::GpuContext;
use crate::renderer::gpu_data::GpuLight;
use crate::renderer::layouts::{compute_pipeline, SharedLayouts};
use crate::renderer::report::lights_fingerprint;
use crate::renderer::shade_pass::ShadePass;
use crate::renderer::vpl_gather::pixel_workgroups;
use crate::scene::PointLight;
use crate::shaders::WgslModule;
use crate::timing::PassTime;
pub use params::{BiasMode, RestirParams, Source};
use wgpu::util::DeviceExt;

/// This technique's own WGSL modules; its registry entry lists them and the naga test validates them.
pub const SHADERS: &[WgslModule] = &[CANDIDATES, TEMPORAL, SPATIAL, SHADE, OUTPUT];
const CANDIDATES: WgslModule = crate::wgsl!(
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
const TEMPORAL: WgslModule = crate::wgsl!(
    "restir_temporal",
    [
        "shaders/common.wgsl",
        "shaders/raytrace_bvh.wgsl",
        "core/src/technique/restir/reservoir.wgsl",
        "core/src/technique/restir/trace.wgsl",
        "core/src/technique/restir/temporal.wgsl"
    ]
);
const SPATIAL: WgslModule = crate::wgsl!(
    "restir_spatial",
    [
        "shaders/common.wgsl",
        "shaders/raytrace_bvh.wgsl",
        "core/src/technique/restir/reservoir.wgsl",
        "core/src/technique/restir/trace.wgsl",
        "core/src/technique/restir/spatial.wgsl"
    ]
);
const SHADE: WgslModule = crate::wgsl!(
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
    crate::wgsl!("restir_output", ["shaders/common.wgsl", "core/src/technique/restir/output.wgsl"]);

/// Mirrors `RestirFrame` in `restir/reservoir.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct FrameUniform {
    prev_clip_from_world: [[f32; 4]; 4],
    prev_camera: [f32; 4],
    source_count: u32,
    light_count: u32,
    candidates: u32,
    frame_index: u32,
    seed: u32,
    temporal: u32,
    history_cap: f32,
    spatial: u32,
    radius: f32,
    unbiased: u32,
    bias: f32,
    weight: f32,
    depth_threshold: f32,
    normal_cos: f32,
    first_frame: u32,
    tiled: u32,
}
const _: () = assert!(std::mem::size_of::<FrameUniform>() == 144);

/// A reservoir as the shaders store it. Mirrors `Reservoir` in `restir/reservoir.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuReservoir {
    /// `y`: an index into the frame's lights, `u32::MAX` when none.
    pub light: u32,
    pub w_sum: f32,
    pub m: f32,
    pub w: f32,
    pub position: [f32; 3],
    /// Octahedral normal (2 x 15 bits), bit 30 geometry, bit 31 a non-black BRDF.
    pub surface: u32,
}
const _: () = assert!(std::mem::size_of::<GpuReservoir>() == 32);

impl GpuReservoir {
    pub fn is_geometry(&self) -> bool {
        self.surface & (1 << 30) != 0
    }
}

/// The camera of the last ReSTIR frame: the next one reprojects onto its reservoirs.
#[derive(Clone, Copy, Debug)]
struct History {
    clip_from_world: Mat4,
    camera_position: Vec3,
}

/// The two reservoir buffers of a size: this frame's per pixel (steps 1-3) and the final ones (step 4), which
/// the shading reads and the next frame's temporal reuse reprojects onto.
struct Reservoirs {
    size: (u32, u32),
    working: wgpu::Buffer,
    last: wgpu::Buffer,
    /// The mean of the rendered frame's ReSTIR frames, linear RGBA f32 per pixel.
    mean: wgpu::Buffer,
}

/// The bind groups of a frame: into `working` (candidates, temporal: reads `last`), into `last` (spatial: reads
/// `working`), the shading's (reads `last`, into `mean`) and the output's (reads `mean`).
struct Groups {
    to_working: wgpu::BindGroup,
    to_last: wgpu::BindGroup,
    shade: wgpu::BindGroup,
    output: wgpu::BindGroup,
}

/// What the last frame's final reservoirs were, read back when `inspect` is on (for the per-pixel maps).
#[derive(Default)]
struct Inspection {
    size: (u32, u32),
    /// Per pixel, the light of its final reservoir (`u32::MAX`: none, or background).
    lights: Arc<Vec<u32>>,
    weight_map: Option<Arc<Vec<[u8; 4]>>>,
    length_map: Option<Arc<Vec<[u8; 4]>>>,
    /// The W (positive ones) and M spans the heat maps stretch over.
    weight_range: (f32, f32),
    length_range: (f32, f32),
}

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
    /// The pass adding the mean into the HDR target.
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
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts) -> Restir {
        let device = &gpu.device;
        let entries =
            [SceneBvh::layout_entries(), vec![storage_entry(2), storage_entry(3), uniform_entry(4), storage_entry(5)]]
                .concat();
        let group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("restir"),
            entries: &[entries, vec![storage_rw_entry(6)]].concat(),
        });
        let pipeline = |module: &WgslModule, entry: &str| {
            compute_pipeline(gpu, layouts, module.name, module.source, entry, &[&group_layout])
        };
        // Candidates read the renderer's tile lists too (group 2), for the tile source.
        let candidates_pipeline = compute_pipeline(
            gpu,
            layouts,
            CANDIDATES.name,
            CANDIDATES.source,
            "candidates_main",
            &[&group_layout, &layouts.light_tiles],
        );
        let temporal_pipeline = pipeline(&TEMPORAL, "temporal_main");
        let spatial_pipeline = pipeline(&SPATIAL, "spatial_main");
        let shade_entries = [
            SceneBvh::layout_entries(),
            vec![storage_entry(2), uniform_entry(4), storage_entry(5), storage_rw_entry(7)],
        ]
        .concat();
        let shade_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("restir shade"),
            entries: &shade_entries,
        });
        let shade_pipeline = compute_pipeline(gpu, layouts, SHADE.name, SHADE.source, "shade_main", &[&shade_layout]);
        let output = ShadePass::new::<[u32; 4]>(gpu, layouts, "restir output", &OUTPUT, &[storage_entry(0)], false);
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("restir frame"),
            contents: bytemuck::bytes_of(&<FrameUniform as bytemuck::Zeroable>::zeroed()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        Restir {
            params: RestirParams::default(),
            candidates_pipeline,
            temporal_pipeline,
            spatial_pipeline,
            shade_pipeline,
            group_layout,
            shade_layout,
            uniform,
            output,
            lights: GrowableBuffer::new(device, "restir lights", 64 * 64),
            lights_key: None,
            source: GrowableBuffer::new(device, "restir source table", 16 * 64),
            source_key: None,
            source_count: 0,
            reservoirs: None,
            groups: None,
            bvh: None,
            history: None,
            frame_index: 0,
            frames: 0,
            last_step: "restir frame",
            counts: TechniqueCounts::default(),
            build_ms: None,
            table_ms: 0.0,
            inspection: Inspection::default(),
        }
    }

    /// Upload the frame's lights when they changed; a different count forgets the history (its reservoirs name
    /// lights by index).
    fn upload_lights(&mut self, ctx: &FrameContext) {
        let key = (lights_fingerprint(ctx.lights), ctx.lights.len());
        if self.lights_key == Some(key) {
            return;
        }
        if self.lights_key.is_none_or(|(_, n)| n != key.1) {
            self.history = None;
        }
        let gpu: Vec<GpuLight> = ctx
            .lights
            .iter()
            .map(|l| if l.is_valid() { GpuLight::new(l) } else { bytemuck::Zeroable::zeroed() })
            .collect();
        if self.lights.write(ctx.gpu, &gpu) {
            self.groups = None;
        }
        self.lights_key = Some(key);
    }

    /// The source pdf over the visible lights, rebuilt when they, the lights or the choice changed.
    fn build_source(&mut self, ctx: &FrameContext) {
        let visible = &ctx.visible_lights.indices;
        let fingerprint = self.lights_key.map_or(0, |(f, _)| f);
        let stale = self
            .source_key
            .as_ref()
            .is_none_or(|(f, v, s)| *f != fingerprint || v != visible || *s != self.params.source);
        if !stale {
            return;
        }
        let started = std::time::Instant::now();
        let table = match self.params.source {
            // The tile source draws from the tile lists; the table maps their entries (visible lights) to lights.
            Source::Uniform | Source::Tiles => alias::uniform_table(visible),
            Source::Power => {
                let power: Vec<f64> = visible
                    .iter()
                    .map(|&i| {
                        let l = &ctx.lights[i];
                        let c = l.color * l.intensity;
                        (0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z) as f64
                    })
                    .collect();
                // No power at all: nothing to draw, and nothing would light the pixels.
                alias::alias_table(visible, &power).unwrap_or_default()
            }
        };
        if self.source.write(ctx.gpu, &table) {
            self.groups = None;
        }
        self.source_count = table.len();
        self.source_key = Some((fingerprint, visible.clone(), self.params.source));
        self.table_ms = started.elapsed().as_secs_f64() * 1000.0;
    }

    /// The reservoir buffers of the frame's size (new ones forget the history).
    fn ensure_reservoirs(&mut self, ctx: &FrameContext) -> Result<(), GpuError> {
        if self.reservoirs.as_ref().is_some_and(|r| r.size == ctx.size) {
            return Ok(());
        }
        let (w, h) = ctx.size;
        let pixels = w as u64 * h as u64;
        let bytes = pixels * std::mem::size_of::<GpuReservoir>() as u64;
        let limits = ctx.gpu.device.limits();
        let max = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        if bytes > max {
            return Err(GpuError::InvalidSettings(format!(
                "restir at {w}x{h} needs reservoir buffers of {} MiB; this GPU allows {} MiB (lower the image size)",
                bytes >> 20,
                max >> 20
            )));
        }
        let buffer = |label, bytes: u64| {
            ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(32),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        self.reservoirs = Some(Reservoirs {
            size: ctx.size,
            working: buffer("restir reservoirs", bytes),
            last: buffer("restir final reservoirs", bytes),
            mean: buffer("restir mean", pixels * 16),
        });
        self.groups = None;
        self.history = None;
        Ok(())
    }

    fn bind_groups(&mut self, ctx: &FrameContext) {
        if self.groups.is_some() {
            return;
        }
        let (Some(bvh), Some(res)) = (&self.bvh, &self.reservoirs) else { return };
        let device = &ctx.gpu.device;
        let group = |input: &wgpu::Buffer, output: &wgpu::Buffer| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("restir"),
                layout: &self.group_layout,
                entries: &[
                    bvh.bind_entries(),
                    vec![
                        wgpu::BindGroupEntry { binding: 2, resource: self.lights.buffer.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 3, resource: self.source.buffer.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 4, resource: self.uniform.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 5, resource: input.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 6, resource: output.as_entire_binding() },
                    ],
                ]
                .concat(),
            })
        };
        let shade = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("restir shade"),
            layout: &self.shade_layout,
            entries: &[
                bvh.bind_entries(),
                vec![
                    wgpu::BindGroupEntry { binding: 2, resource: self.lights.buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 4, resource: self.uniform.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 5, resource: res.last.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 7, resource: res.mean.as_entire_binding() },
                ],
            ]
            .concat(),
        });
        let output = self
            .output
            .bind_group(ctx.gpu, &[wgpu::BindGroupEntry { binding: 0, resource: res.mean.as_entire_binding() }]);
        self.groups = Some(Groups {
            to_working: group(&res.last, &res.working),
            to_last: group(&res.working, &res.last),
            shade,
            output,
        });
    }

    /// The uniform of ReSTIR frame `frame_index` from the frame's camera, reusing `history` when there is one;
    /// `first_frame` starts the mean over.
    fn frame_uniform(&self, ctx: &FrameContext, history: Option<History>, first_frame: bool) -> FrameUniform {
        let p = &self.params;
        let prev = history.unwrap_or(History {
            clip_from_world: ctx.camera.clip_from_world(ctx.aspect),
            camera_position: ctx.camera.position,
        });
        FrameUniform {
            prev_clip_from_world: prev.clip_from_world.to_cols_array_2d(),
            prev_camera: prev.camera_position.extend(1.0).to_array(),
            source_count: self.source_count as u32,
            light_count: ctx.lights.len() as u32,
            candidates: p.candidates.max(1),
            frame_index: self.frame_index,
            seed: p.seed,
            temporal: history.is_some() as u32,
            history_cap: p.history as f32 * p.candidates as f32,
            spatial: p.spatial.min(params::MAX_SPATIAL),
            radius: p.radius,
            unbiased: (p.bias_mode == BiasMode::Unbiased) as u32,
            bias: p.bias,
            weight: 1.0 / p.frames.max(1) as f32,
            depth_threshold: p.depth_threshold,
            normal_cos: p.normal_threshold_deg.to_radians().cos(),
            first_frame: first_frame as u32,
            tiled: (p.source == Source::Tiles) as u32,
        }
    }

    fn dispatch(
        &self,
        ctx: &FrameContext,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        pipeline: &wgpu::ComputePipeline,
        group: &wgpu::BindGroup,
    ) {
        let (x, y) = pixel_workgroups(ctx.size);
        ctx.timer.compute_pass(encoder, label, |pass| {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, ctx.screen_bind_group, &[]);
            pass.set_bind_group(1, group, &[]);
            pass.dispatch_workgroups(x, y, 1);
        });
    }

    fn groups(&self) -> &Groups {
        self.groups.as_ref().expect("prepare made the bind groups")
    }

    /// Steps 1-2: candidates, RIS and visibility reuse, into this frame's reservoirs.
    fn candidates_pass(&self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) {
        let (x, y) = pixel_workgroups(ctx.size);
        ctx.timer.compute_pass(encoder, "restir candidates", |pass| {
            pass.set_pipeline(&self.candidates_pipeline);
            pass.set_bind_group(0, ctx.screen_bind_group, &[]);
            pass.set_bind_group(1, &self.groups().to_working, &[]);
            pass.set_bind_group(2, ctx.light_tiles.bind_group(), &[]);
            pass.dispatch_workgroups(x, y, 1);
        });
    }

    /// Step 3: temporal reuse of the last final reservoirs, in place.
    fn temporal_pass(&self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) {
        self.dispatch(ctx, encoder, "restir temporal", &self.temporal_pipeline, &self.groups().to_working);
    }

    /// Step 4: spatial reuse and the final sample's shadow ray, into the final reservoirs.
    fn spatial_pass(&self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) {
        self.dispatch(ctx, encoder, "restir spatial", &self.spatial_pipeline, &self.groups().to_last);
    }

    /// Step 5: `f(y) W / frames` into the mean.
    fn shade_pass(&self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) {
        self.dispatch(ctx, encoder, "restir shade", &self.shade_pipeline, &self.groups().shade);
    }

    /// After the last ReSTIR frame: the mean into the HDR target.
    fn output_pass(&self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) {
        self.output.encode(ctx, encoder, "restir output", &self.groups().output, None);
    }

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
            self.inspection = overlays::inspect(&reservoirs, ctx.size, self.params.candidates);
            return Ok(());
        }
        self.last_step = "restir frame";
        let history = self.history.filter(|_| self.params.history > 0);
        let uniform = self.frame_uniform(ctx, history, step == 0);
        ctx.gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        self.candidates_pass(ctx, encoder);
        if history.is_some() {
            self.temporal_pass(ctx, encoder);
        }
        self.spatial_pass(ctx, encoder);
        self.shade_pass(ctx, encoder);
        if step + 1 == self.frames {
            self.output_pass(ctx, encoder);
        }
        self.history = Some(History {
            clip_from_world: ctx.camera.clip_from_world(ctx.aspect),
            camera_position: ctx.camera.position,
        });
        self.frame_index = self.frame_index.wrapping_add(1);
        Ok(())
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
        overlays::explain_steps()
    }

    fn pixel_ids(&self, positions: &[Option<Vec3>]) -> Option<(&'static str, Vec<u32>)> {
        if positions.is_empty() {
            return Some((overlays::LIGHT_MAP, Vec::new()));
        }
        let ins = &self.inspection;
        (ins.lights.len() == positions.len()).then(|| (overlays::LIGHT_MAP, ins.lights.to_vec()))
    }

    fn hover_details(&self, layer: &str, index: usize) -> Vec<String> {
        self.hover_text(layer, index)
    }
}
