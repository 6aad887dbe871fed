//! Trace given rays through a given BVH on the GPU (`test_rays` in `raytrace_test.wgsl`), so tests can hold the
//! GPU traversal against its CPU twin ([`super::bvh::occluded_cpu`]) and brute force.

use wgpu::util::DeviceExt;

use super::bvh::{Bvh, Ray};
use super::scene_bvh::{BvhCutouts, CutoutTextures};
use crate::error::GpuError;
use crate::gpu::pipeline::create_module;
use crate::gpu::readback::map_read;
use crate::gpu::GpuContext;
use crate::shaders;

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
    let module = create_module(device, "raytrace_test", shaders::RAYTRACE_TEST.source);
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
    let data = map_read(gpu, &readback, hits_size)?;
    let flags: Vec<bool> = bytemuck::cast_slice::<u8, u32>(&data).iter().map(|&h| h != 0).collect();
    Ok(flags)
}
