//! One-bounce path tracing: the truth for one-bounce indirect light itself, so a user sees the VPLs'
//! discretisation and clamping error apart from their visibility error. Needs no VPLs.
//!
//! Per pixel and sample (`pathtraced/pathtrace.wgsl`):
//! 1. a cosine-distributed direction around the receiver's normal (pdf `cos/pi`),
//! 2. the closest hit `y` through the scene BVH (the renderer's service),
//! 3. direct light at `y` from one light picked in proportion to its power, with a shadow ray:
//!    `L(y -> x) = rho(y)/pi * I * attenuation(d) * cos(theta_y) / p_light`,
//!    plus every sun's (at most four, each with its own shadow ray along the sun's direction):
//!    `L_sun(y -> x) = rho(y)/pi * E * cos(theta_y) * V`,
//! 4. the estimate `rho(x) * L(y -> x)`, averaged over `samples`.
//!
//! Progressive: each step adds `samples_per_step` samples (weighted by `1/samples`), so the app shows the
//! image converging; seeded (a PCG hash of pixel, sample and `seed`), so a frame is reproducible.
//! Unlike the VPL gathers there is no `d_clamp`: the difference to `vpl-raytraced` is the VPLs' discretisation
//! and clamping bias. Emissive surfaces do not light others here (nor in the VPL sources).

use std::sync::Arc;

use wgpu::util::DeviceExt;

use super::{
    check_param, FrameContext, OverlayLayer, Param, ParamError, ParamKind, ParamValue, Technique, TechniqueCounts,
};
use crate::accel::scene_bvh::SceneBvh;
use crate::error::GpuError;
use crate::gpu::bind::storage_rw_entry;
use crate::gpu::bind::{storage_entry, uniform_entry};
use crate::gpu::buffer::GrowableBuffer;
use crate::gpu::GpuContext;
use crate::scene::{PointLight, MAX_DIRECTIONAL_LIGHTS};
use crate::services::gpu_data::GpuLight;
use crate::services::layouts::compute_pipeline;
use crate::services::layouts::SharedLayouts;
use crate::services::vpl_gather::pixel_workgroups;
use crate::timing::PassTime;

use crate::shaders::WgslModule;
/// This technique's own WGSL modules; its registry entry lists them and the naga test validates them.
pub const SHADERS: &[WgslModule] = &[PATHTRACE];
const PATHTRACE: WgslModule = crate::shaders::wgsl!(
    "pathtrace",
    [
        "shaders/common.wgsl",
        "shaders/raytrace_bvh.wgsl",
        "shaders/vpl_basis.wgsl",
        "core/src/technique/pathtraced/pathtrace.wgsl"
    ]
);

/// Mirrors `PtStep` in `pathtraced/pathtrace.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct PtStepUniform {
    first_sample: u32,
    sample_count: u32,
    total_samples: u32,
    light_count: u32,
    bias: f32,
    seed: u32,
    sun_count: u32,
    /// Length of a sun's shadow ray: twice the scene's diagonal.
    sun_ray_length: f32,
    /// Per sun, the direction its light travels (xyz).
    sun_direction: [[f32; 4]; MAX_DIRECTIONAL_LIGHTS],
    /// Per sun, colour times illuminance (xyz).
    sun_radiance: [[f32; 4]; MAX_DIRECTIONAL_LIGHTS],
}
const _: () = assert!(std::mem::size_of::<PtStepUniform>() == 32 + 32 * MAX_DIRECTIONAL_LIGHTS);

#[derive(Clone, Debug, PartialEq)]
pub struct PathTracedParams {
    /// Samples per pixel.
    pub samples: u32,
    pub samples_per_step: u32,
    /// Ray origin offset along the normal, world units per metre of camera distance.
    pub bias: f32,
    pub seed: u32,
}

impl Default for PathTracedParams {
    fn default() -> Self {
        PathTracedParams { samples: 64, samples_per_step: 8, bias: 0.001, seed: 0 }
    }
}

pub struct PathTraced {
    pub params: PathTracedParams,
    pipeline: wgpu::ComputePipeline,
    group_layout: wgpu::BindGroupLayout,
    output_layout: wgpu::BindGroupLayout,
    step_uniform: wgpu::Buffer,
    lights: GrowableBuffer,
    bvh: Option<Arc<SceneBvh>>,
    light_count: u32,
    /// The frame's valid suns: (direction, colour times illuminance), and their shadow rays' length.
    suns: Vec<([f32; 4], [f32; 4])>,
    sun_ray_length: f32,
    steps: usize,
    counts: TechniqueCounts,
    build_ms: Option<f64>,
}

impl PathTraced {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts) -> PathTraced {
        let device = &gpu.device;
        let group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("pathtrace"),
            entries: &[SceneBvh::layout_entries(), vec![storage_entry(2), uniform_entry(3)]].concat(),
        });
        let output_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("pathtrace output"),
            entries: &[storage_rw_entry(0)],
        });
        let pipeline = compute_pipeline(
            gpu,
            layouts,
            "pathtrace",
            PATHTRACE.source,
            "pathtrace_main",
            &[&group_layout, &output_layout],
        );
        let step_uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("pathtrace step"),
            contents: bytemuck::bytes_of(&<PtStepUniform as bytemuck::Zeroable>::zeroed()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        PathTraced {
            params: PathTracedParams::default(),
            pipeline,
            group_layout,
            output_layout,
            step_uniform,
            lights: GrowableBuffer::new(device, "pathtrace lights", 32 * 16),
            bvh: None,
            light_count: 0,
            suns: Vec::new(),
            sun_ray_length: 0.0,
            steps: 0,
            counts: TechniqueCounts::default(),
            build_ms: None,
        }
    }
}

impl Technique for PathTraced {
    fn key(&self) -> &'static str {
        "pathtraced"
    }

    fn label(&self) -> &'static str {
        "Path traced (one bounce)"
    }

    fn params(&self) -> Vec<Param> {
        let p = &self.params;
        vec![
            Param {
                key: "samples",
                label: "Samples",
                help: "Bounce paths per pixel",
                kind: ParamKind::Int { min: 1, max: 65_536 },
                value: ParamValue::Int(p.samples as i64),
            },
            Param {
                key: "samples_per_step",
                label: "Samples per step",
                help: "Paths per pixel in one pass; fewer means shorter steps (the image does not change)",
                kind: ParamKind::Int { min: 1, max: 1024 },
                value: ParamValue::Int(p.samples_per_step as i64),
            },
            Param::ray_bias(p.bias),
            Param::seed("Seed of the random paths", p.seed),
        ]
    }

    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        check_param(self.key(), &self.params(), key, value)?;
        let p = &mut self.params;
        match (key, value) {
            ("samples", ParamValue::Int(v)) => p.samples = *v as u32,
            ("samples_per_step", ParamValue::Int(v)) => p.samples_per_step = *v as u32,
            ("bias", ParamValue::Float(v)) => p.bias = *v,
            ("seed", ParamValue::Int(v)) => p.seed = *v as u32,
            _ => unreachable!("check_param accepted an unknown key"),
        }
        Ok(())
    }

    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        let (bvh, build_ms) = ctx.scene.bvh(ctx.gpu);
        self.build_ms = build_ms;
        self.bvh = Some(bvh);
        // Every light may light a bounce point, visible or not; pick them by power.
        let lights: Vec<&PointLight> = ctx.lights.iter().filter(|l| l.is_valid()).collect();
        let powers: Vec<f64> =
            lights.iter().map(|l| (l.intensity * (l.color.x + l.color.y + l.color.z)) as f64).collect();
        let total: f64 = powers.iter().sum();
        // The cumulative selection probability rides in `shadow_near`, which no shadow map needs here.
        let mut gpu_lights: Vec<GpuLight> = Vec::new();
        if total > 0.0 && total.is_finite() {
            let mut acc = 0.0f64;
            for (l, p) in lights.iter().zip(&powers) {
                acc += p / total;
                gpu_lights.push(GpuLight { shadow_near: acc as f32, ..GpuLight::new(l) });
            }
            if let Some(last) = gpu_lights.last_mut() {
                last.shadow_near = 1.0;
            }
        }
        self.light_count = gpu_lights.len() as u32;
        self.lights.write(ctx.gpu, &gpu_lights);
        self.suns = ctx
            .directional_lights
            .iter()
            .filter(|d| d.is_valid() && d.illuminance > 0.0)
            .take(MAX_DIRECTIONAL_LIGHTS)
            .map(|d| (d.direction.normalize().extend(0.0).to_array(), (d.color * d.illuminance).extend(0.0).to_array()))
            .collect();
        self.sun_ray_length = 2.0 * ctx.scene.bounds.size().length().max(1e-6);
        let p = &self.params;
        self.steps = if self.light_count == 0 && self.suns.is_empty() {
            0
        } else {
            p.samples.div_ceil(p.samples_per_step.max(1)) as usize
        };
        self.counts = TechniqueCounts { lights_visible: gpu_lights.len(), batches: self.steps, ..Default::default() };
        self.counts.figures.insert("samples".into(), p.samples as f64);
        Ok(self.steps)
    }

    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        let p = &self.params;
        let per_step = p.samples_per_step.max(1);
        let first = step as u32 * per_step;
        let mut uniform = PtStepUniform {
            first_sample: first,
            sample_count: per_step.min(p.samples - first),
            total_samples: p.samples,
            light_count: self.light_count,
            bias: p.bias,
            seed: p.seed,
            sun_count: self.suns.len() as u32,
            sun_ray_length: self.sun_ray_length,
            sun_direction: [[0.0; 4]; MAX_DIRECTIONAL_LIGHTS],
            sun_radiance: [[0.0; 4]; MAX_DIRECTIONAL_LIGHTS],
        };
        for (k, (direction, radiance)) in self.suns.iter().enumerate() {
            uniform.sun_direction[k] = *direction;
            uniform.sun_radiance[k] = *radiance;
        }
        ctx.gpu.queue.write_buffer(&self.step_uniform, 0, bytemuck::bytes_of(&uniform));
        let bvh = self.bvh.as_ref().expect("prepare set the BVH");
        let device = &ctx.gpu.device;
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("pathtrace"),
            layout: &self.group_layout,
            entries: &[
                bvh.bind_entries(),
                vec![
                    wgpu::BindGroupEntry { binding: 2, resource: self.lights.buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 3, resource: self.step_uniform.as_entire_binding() },
                ],
            ]
            .concat(),
        });
        let output = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("pathtrace output"),
            layout: &self.output_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: ctx.indirect_buffer.as_entire_binding() }],
        });
        let (x, y) = pixel_workgroups(ctx.size);
        ctx.timer.compute_pass(encoder, "path tracing", |pass| {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, ctx.screen_bind_group, &[]);
            pass.set_bind_group(1, &group, &[]);
            pass.set_bind_group(2, &output, &[]);
            pass.dispatch_workgroups(x, y, 1);
        });
        Ok(())
    }

    fn step_label(&self) -> &'static str {
        "path tracing"
    }

    fn counts(&self) -> TechniqueCounts {
        self.counts.clone()
    }

    fn cpu_times(&self) -> Vec<PassTime> {
        self.build_ms.map(|ms| PassTime { name: "bvh build".into(), ms, count: 1 }).into_iter().collect()
    }

    fn overlays(&self, _lights: &[PointLight]) -> Vec<OverlayLayer> {
        Vec::new()
    }
}
