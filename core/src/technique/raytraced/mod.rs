//! Ray traced: shadow rays through a BVH of the scene's triangles, the ground truth the cube-map techniques
//! approximate. Hard shadows cast one ray per pixel and light to the light's centre (what the reference's cube
//! maps approximate); soft shadows cast `samples` rays to stratified points on a disc of `light_radius` centred
//! at the light and facing the receiver (what PCSS approximates), visibility being the unoccluded fraction.
//!
//! Per frame:
//! 1. The scene's BVH from the renderer's service ([`GpuScene::bvh`](crate::accel::gpu_scene::GpuScene::bvh)),
//!    built on the CPU (binned SAH) and uploaded the first time any tracer asks for it.
//! 2. The lights whose range sphere touches the view frustum: the renderer's culling, shared with the reference.
//! 3. Per batch of `lights_per_step` lights (one step): a full-screen pass traces every pixel's shadow rays in
//!    the fragment shader (`raytraced/shadow.wgsl`, stack-based any-hit traversal) and adds the lights' shading
//!    (the reference's `shade_light`) times visibility into the HDR target.
//!
//! The ray origin is the G-buffer position pushed along the normal by `bias * max(1, camera distance)` (the
//! reconstruction error grows with distance), and rays stop that far before the light.
//!
//! [`occluded_cpu`] is the CPU twin of the GPU traversal and [`gpu_occluded`] runs the GPU traversal on given
//! rays, so the tests can compare GPU, CPU and brute force.

use std::sync::Arc;

use super::{
    check_param, FrameContext, Overlay, OverlayLayer, Param, ParamError, ParamKind, ParamValue, Technique,
    TechniqueCounts,
};
use crate::accel::bvh::BvhStats;
use crate::accel::scene_bvh::SceneBvh;
use crate::error::GpuError;
use crate::gpu::bind::{storage_entry, uniform_entry};
use crate::gpu::GpuContext;
use crate::scene::PointLight;
use crate::services::layouts::SharedLayouts;
use crate::services::shade_pass::ShadePass;
use crate::timing::PassTime;

use crate::shaders::WgslModule;
/// This technique's own WGSL modules; its registry entry lists them and the naga test validates them.
pub const SHADERS: &[WgslModule] = &[SHADOW];
const SHADOW: WgslModule = crate::shaders::wgsl!(
    "raytrace_shadow",
    [
        "shaders/common.wgsl",
        "shaders/light_tiles.wgsl",
        "shaders/raytrace_bvh.wgsl",
        "core/src/technique/raytraced/shadow.wgsl"
    ]
);

/// Mirrors `RtBatch` in `raytraced/shadow.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct RtBatchUniform {
    first_light: u32,
    light_count: u32,
    soft: u32,
    samples: u32,
    light_radius: f32,
    bias: f32,
    seed: u32,
    _pad: u32,
}
const _: () = assert!(std::mem::size_of::<RtBatchUniform>() == 32);

/// The ray tracer's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct RaytracedParams {
    /// Soft shadows from disc lights instead of hard shadows from points.
    pub soft: bool,
    /// Radius of the disc light in world units (soft shadows).
    pub light_radius: f32,
    /// Shadow rays per pixel and light (soft shadows).
    pub samples: u32,
    /// Lights per step (one full-screen pass each).
    pub lights_per_step: u32,
    /// Ray origin offset along the normal, world units per metre of camera distance (at least one metre).
    pub bias: f32,
    /// Seed of the per-pixel rotation of the sample pattern (soft shadows).
    pub seed: u32,
}

impl Default for RaytracedParams {
    fn default() -> Self {
        RaytracedParams { soft: false, light_radius: 0.1, samples: 16, lights_per_step: 32, bias: 0.001, seed: 0 }
    }
}

pub struct Raytraced {
    pub params: RaytracedParams,
    shade: ShadePass,
    /// The generation of the renderer's light buffer the bind group was made with.
    lights_generation: Option<u64>,
    bind_group: Option<wgpu::BindGroup>,
    /// The scene BVH this frame's bind group uses (the renderer's service, shared with other tracers).
    bvh: Option<Arc<SceneBvh>>,
    /// Indices of the visible lights of this frame (the renderer's culling), in batch order.
    visible: Vec<usize>,
    batch_size: usize,
    counts: TechniqueCounts,
    /// BVH build time of this frame's `prepare`, when it built one.
    build_ms: Option<f64>,
}

impl Raytraced {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts) -> Raytraced {
        let _device = &gpu.device;
        let entries = [SceneBvh::layout_entries(), vec![storage_entry(2), uniform_entry(3)]].concat();
        let shade = ShadePass::new::<RtBatchUniform>(gpu, layouts, "raytraced shade", &SHADOW, &entries, true);
        Raytraced {
            params: RaytracedParams::default(),
            shade,
            lights_generation: None,
            bind_group: None,
            bvh: None,
            visible: Vec::new(),
            batch_size: 1,
            counts: TechniqueCounts::default(),
            build_ms: None,
        }
    }

    /// The lights of this frame that passed view-frustum culling (indices into the frame's lights).
    pub fn visible_lights(&self) -> &[usize] {
        &self.visible
    }

    /// Facts about the BVH in use (None before the first frame).
    pub fn bvh_stats(&self) -> Option<&BvhStats> {
        self.bvh.as_ref().map(|b| &b.cpu.stats)
    }
}

impl Technique for Raytraced {
    fn key(&self) -> &'static str {
        "raytraced"
    }

    fn label(&self) -> &'static str {
        "Ray traced"
    }

    fn params(&self) -> Vec<Param> {
        let p = &self.params;
        vec![
            Param {
                key: "soft",
                label: "Soft shadows",
                help: "Disc lights of the given radius (several rays per pixel and light) instead of points",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(p.soft),
            },
            Param {
                key: "light_radius",
                label: "Light radius",
                help: "Radius of the disc light in world units (soft shadows)",
                kind: ParamKind::Float { min: 0.0, max: 10.0 },
                value: ParamValue::Float(p.light_radius),
            },
            Param {
                key: "samples",
                label: "Samples",
                help: "Shadow rays per pixel and light (soft shadows)",
                kind: ParamKind::Int { min: 1, max: 256 },
                value: ParamValue::Int(p.samples as i64),
            },
            Param {
                key: "lights_per_step",
                label: "Lights per step",
                help: "Lights traced in one full-screen pass; fewer means shorter steps",
                kind: ParamKind::Int { min: 1, max: 4096 },
                value: ParamValue::Int(p.lights_per_step as i64),
            },
            Param::ray_bias(p.bias),
            Param::seed("Seed of the per-pixel rotation of the sample pattern (soft shadows)", p.seed),
        ]
    }

    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        check_param(self.key(), &self.params(), key, value)?;
        match (key, value) {
            ("soft", ParamValue::Bool(v)) => self.params.soft = *v,
            ("light_radius", ParamValue::Float(v)) => self.params.light_radius = *v,
            ("samples", ParamValue::Int(v)) => self.params.samples = *v as u32,
            ("lights_per_step", ParamValue::Int(v)) => self.params.lights_per_step = *v as u32,
            ("bias", ParamValue::Float(v)) => self.params.bias = *v,
            ("seed", ParamValue::Int(v)) => self.params.seed = *v as u32,
            _ => unreachable!("check_param accepted an unknown key"),
        }
        Ok(())
    }

    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        self.build_ms = None;
        // Step 1: view-frustum culling of range spheres (the renderer's, `ctx.visible_lights`).
        self.visible.clear();
        self.visible.extend_from_slice(&ctx.visible_lights.indices);

        // Step 2: batches of lights.
        // Bounded work per pass: lights x rays per pixel at most `MAX_LIGHT_WORK_PER_PASS`.
        let rays = if self.params.soft { self.params.samples.max(1) as usize } else { 1 };
        let by_work = (super::MAX_LIGHT_WORK_PER_PASS / rays).max(1);
        self.batch_size = (self.params.lights_per_step as usize).min(ctx.max_lights_per_step).min(by_work).max(1);
        let batches = self.visible.len().div_ceil(self.batch_size);
        self.counts = TechniqueCounts { lights_visible: self.visible.len(), batches, ..Default::default() };
        if self.visible.is_empty() {
            return Ok(0);
        }

        // The BVH, built the first time this geometry is seen.
        let mut rebind = self.bind_group.is_none();
        let (bvh, build_ms) = ctx.scene.bvh(ctx.gpu);
        self.build_ms = build_ms;
        rebind |= self.bvh.as_ref().is_none_or(|b| !Arc::ptr_eq(b, &bvh));
        self.bvh = Some(bvh);
        rebind |= self.lights_generation != Some(ctx.visible_lights.generation);
        self.lights_generation = Some(ctx.visible_lights.generation);
        if rebind {
            let bvh = self.bvh.as_ref().expect("set above");
            self.bind_group = Some(
                self.shade.bind_group(
                    ctx.gpu,
                    &[
                        bvh.bind_entries(),
                        vec![
                            wgpu::BindGroupEntry {
                                binding: 2,
                                resource: ctx.visible_lights.buffer.buffer.as_entire_binding(),
                            },
                            wgpu::BindGroupEntry {
                                binding: 3,
                                resource: self.shade.batch_uniform().as_entire_binding(),
                            },
                        ],
                    ]
                    .concat(),
                ),
            );
        }
        Ok(batches)
    }

    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        // Step 3: trace and shade this batch.
        let first = step * self.batch_size;
        let last = (first + self.batch_size).min(self.visible.len());
        let p = &self.params;
        let uniform = RtBatchUniform {
            first_light: first as u32,
            light_count: (last - first) as u32,
            soft: p.soft as u32,
            samples: p.samples.clamp(1, 256),
            light_radius: p.light_radius,
            bias: p.bias,
            seed: p.seed,
            _pad: 0,
        };
        self.shade.write_batch(ctx.gpu, &uniform);
        let group = self.bind_group.as_ref().expect("prepare created the bind group");
        self.shade.encode(ctx, encoder, "ray traced shading", group, None);
        Ok(())
    }

    /// Directional lights: the ground truth: one shadow ray per pixel, as for its point lights.
    fn directional_visibility(&self) -> super::DirectionalVisibility {
        super::DirectionalVisibility::Traced
    }

    fn step_label(&self) -> &'static str {
        "ray traced shading"
    }

    fn counts(&self) -> TechniqueCounts {
        self.counts.clone()
    }

    fn cpu_times(&self) -> Vec<PassTime> {
        self.build_ms.map(|ms| PassTime { name: "bvh build".into(), ms, count: 1 }).into_iter().collect()
    }

    fn uses_light_tiles(&self) -> bool {
        true
    }

    fn overlays(&self, lights: &[PointLight]) -> Vec<OverlayLayer> {
        let mut layers = super::light_overlays(lights);
        if self.params.soft {
            layers.push(OverlayLayer {
                name: "light discs",
                visible_by_default: true,
                primitives: lights
                    .iter()
                    .map(|l| Overlay::Sphere {
                        center: l.position,
                        radius: self.params.light_radius,
                        color: super::light_overlay_color(l),
                    })
                    .collect(),
            });
        }
        layers
    }
}
