//! Ray traced: shadow rays through a BVH of the scene's triangles, the ground truth the cube-map techniques
//! approximate. Hard shadows cast one ray per pixel and light to the light's centre (what the reference's cube
//! maps approximate); soft shadows cast `samples` rays to stratified points on a disc of `light_radius` centred
//! at the light and facing the receiver (what PCSS approximates), visibility being the unoccluded fraction.
//!
//! Per frame:
//! 1. The scene's BVH from the renderer's service ([`GpuScene::bvh`](crate::renderer::gpu_scene::GpuScene::bvh)),
//!    built on the CPU (binned SAH) and uploaded the first time any tracer asks for it.
//! 2. The lights whose range sphere touches the view frustum: the renderer's culling, shared with the reference.
//! 3. Per batch of `lights_per_step` lights (one step): a full-screen pass traces every pixel's shadow rays in
//!    the fragment shader (`raytrace_shadow.wgsl`, stack-based any-hit traversal) and adds the lights' shading
//!    (the reference's `shade_light`) times visibility into the HDR target.
//!
//! The ray origin is the G-buffer position pushed along the normal by `bias * max(1, camera distance)` (the
//! reconstruction error grows with distance), and rays stop that far before the light.
//!
//! [`occluded_cpu`] is the CPU twin of the GPU traversal and [`gpu_occluded`] runs the GPU traversal on given
//! rays, so the tests can compare GPU, CPU and brute force.

pub mod bvh;

use std::sync::Arc;

use wgpu::util::DeviceExt;

pub use bvh::{
    closest_hit_brute_force, closest_hit_cpu, closest_hit_cpu_filtered, occluded_brute_force, occluded_cpu,
    occluded_cpu_filtered, Bvh, BvhNode, BvhStats, BvhTriangle, Hit, Ray,
};

use super::{
    accumulate_pass, check_param, storage_entry, uniform_entry, FrameContext, Overlay, OverlayLayer, Param, ParamError,
    ParamKind, ParamValue, Technique, TechniqueCounts,
};
use crate::error::GpuError;
use crate::gpu::GpuContext;
use crate::renderer::scene_bvh::{BvhCutouts, CutoutTextures, SceneBvh};
use crate::renderer::SharedLayouts;
use crate::scene::PointLight;
use crate::shaders;
use crate::timing::PassTime;

/// Mirrors `RtBatch` in `raytrace_shadow.wgsl`.
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

/// A BVH on the GPU (for [`gpu_occluded`], which traces a BVH it is given rather than a scene's).
struct GpuBvh {
    nodes: wgpu::Buffer,
    triangles: wgpu::Buffer,
    /// No cut-outs (a bare BVH has no materials), bound because the traversal reads them.
    cutouts: CutoutTextures,
}

impl GpuBvh {
    fn upload(gpu: &GpuContext, bvh: &Bvh) -> GpuBvh {
        let storage = |label, contents: &[u8]| {
            gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let (nodes, triangles) = bvh.gpu_buffers();
        GpuBvh {
            nodes: storage("bvh nodes", bytemuck::cast_slice(&nodes)),
            triangles: storage("bvh triangles", bytemuck::cast_slice(&triangles)),
            cutouts: CutoutTextures::new(gpu, &BvhCutouts::default()),
        }
    }
}

pub struct Raytraced {
    pub params: RaytracedParams,
    pipeline: wgpu::RenderPipeline,
    group_layout: wgpu::BindGroupLayout,
    batch_uniform: wgpu::Buffer,
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
        let device = &gpu.device;
        let group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raytraced shade"),
            entries: &[SceneBvh::layout_entries(), vec![storage_entry(2), uniform_entry(3)]].concat(),
        });
        let module = shaders::create_module(device, "raytrace_shadow", shaders::RAYTRACE_SHADOW);
        let pipeline = layouts.fullscreen_pipeline(
            device,
            "raytraced shade",
            &module,
            &[&group_layout, &layouts.light_tiles],
            SharedLayouts::HDR_FORMAT,
            true,
        );
        let batch_uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("raytraced batch"),
            contents: bytemuck::bytes_of(&<RtBatchUniform as bytemuck::Zeroable>::zeroed()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        Raytraced {
            params: RaytracedParams::default(),
            pipeline,
            group_layout,
            batch_uniform,
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
            Param {
                key: "bias",
                label: "Ray offset",
                help: "Ray origin offset along the normal, world units per metre of camera distance",
                kind: ParamKind::Float { min: 0.0, max: 0.1 },
                value: ParamValue::Float(p.bias),
            },
            Param {
                key: "seed",
                label: "Seed",
                help: "Seed of the per-pixel rotation of the sample pattern (soft shadows)",
                kind: ParamKind::Int { min: 0, max: u32::MAX as i64 },
                value: ParamValue::Int(p.seed as i64),
            },
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
                ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("raytraced shade"),
                    layout: &self.group_layout,
                    entries: &[
                        bvh.bind_entries(),
                        vec![
                            wgpu::BindGroupEntry {
                                binding: 2,
                                resource: ctx.visible_lights.buffer.buffer.as_entire_binding(),
                            },
                            wgpu::BindGroupEntry { binding: 3, resource: self.batch_uniform.as_entire_binding() },
                        ],
                    ]
                    .concat(),
                }),
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
        ctx.gpu.queue.write_buffer(&self.batch_uniform, 0, bytemuck::bytes_of(&uniform));
        let group = self.bind_group.as_ref().expect("prepare created the bind group");
        accumulate_pass(ctx, encoder, "ray traced shading", &self.pipeline, &[group, ctx.light_tiles.bind_group()]);
        Ok(())
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

/// Trace `rays` through `bvh` with the GPU traversal (`test_rays` in `raytrace_test.wgsl`): one hit flag per
/// ray. For tests comparing the GPU with [`occluded_cpu`].
pub fn gpu_occluded(gpu: &GpuContext, bvh: &Bvh, rays: &[Ray]) -> Result<Vec<bool>, GpuError> {
    if rays.is_empty() {
        return Ok(Vec::new());
    }
    let device = &gpu.device;
    let compute_entry = |binding, read_only| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let empty = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &[] });
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("raytrace test"),
        entries: &[
            vec![compute_entry(0, true), compute_entry(1, true), compute_entry(2, true), compute_entry(3, false)],
            CutoutTextures::layout_entries().to_vec(),
        ]
        .concat(),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("raytrace test"),
        bind_group_layouts: &[Some(&empty), Some(&layout)],
        immediate_size: 0,
    });
    let module = shaders::create_module(device, "raytrace_test", shaders::RAYTRACE_TEST);
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("raytrace test"),
        layout: Some(&pipeline_layout),
        module: &module,
        entry_point: Some("test_rays"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bvh_gpu = GpuBvh::upload(gpu, bvh);
    let ray_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("test rays"),
        contents: bytemuck::cast_slice(rays),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let hits_size = (rays.len() * 4) as u64;
    let hits = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("test hits"),
        size: hits_size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("test hits readback"),
        size: hits_size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let empty_group =
        device.create_bind_group(&wgpu::BindGroupDescriptor { label: None, layout: &empty, entries: &[] });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("raytrace test"),
        layout: &layout,
        entries: &[
            vec![
                wgpu::BindGroupEntry { binding: 0, resource: bvh_gpu.nodes.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: bvh_gpu.triangles.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: ray_buffer.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: hits.as_entire_binding() },
            ],
            bvh_gpu.cutouts.bind_entries().to_vec(),
        ]
        .concat(),
    });
    let groups = (rays.len() as u32).div_ceil(64);
    let (x, y) = if groups <= 65_535 { (groups, 1) } else { (65_535, groups.div_ceil(65_535)) };
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("test rays"), timestamp_writes: None });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &empty_group, &[]);
        pass.set_bind_group(1, &group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
    encoder.copy_buffer_to_buffer(&hits, 0, &readback, 0, hits_size);
    gpu.queue.submit([encoder.finish()]);
    let data = crate::renderer::readback::map_read(gpu, &readback, hits_size)?;
    let flags: Vec<bool> = bytemuck::cast_slice::<u8, u32>(&data).iter().map(|&h| h != 0).collect();
    Ok(flags)
}
