//! A set of compute kernels over one bind group: entry points of one module, group 0 holding a uniform at
//! binding 0 and storage buffers at 1.. . Both GPU k-means (VAL's and fuzzy clustering's) are built on it:
//! their plumbing is the same (a parameter block, points in, clusters, sums and assignments out, one pipeline
//! per step); their steps are not (fuzzy clustering searches a centroid grid and keeps the F nearest with
//! inverse distances, VAL runs plain Lloyd iterations), so each keeps its own dispatch sequence.

use super::pipeline::create_module;
use super::GpuContext;

pub struct Kernels {
    label: &'static str,
    layout: wgpu::BindGroupLayout,
    pipelines: Vec<(&'static str, wgpu::ComputePipeline)>,
    uniform: wgpu::Buffer,
}

impl Kernels {
    /// The entry points `entries` of `source`, over a uniform of `uniform_bytes` and one storage buffer per
    /// flag of `read_only` (binding `1 + i`, read-only when the flag is set), with the module's pipeline-overridable
    /// constants set to `constants` (compiled in: code a constant rules out costs nothing).
    pub fn new(
        gpu: &GpuContext,
        label: &'static str,
        source: &str,
        entries: &[&'static str],
        uniform_bytes: u64,
        read_only: &[bool],
        constants: &[(&str, f64)],
    ) -> Kernels {
        let device = &gpu.device;
        let buffer = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let mut layout_entries = vec![buffer(0, wgpu::BufferBindingType::Uniform)];
        for (i, &read_only) in read_only.iter().enumerate() {
            layout_entries.push(buffer(1 + i as u32, wgpu::BufferBindingType::Storage { read_only }));
        }
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &layout_entries,
        });
        let module = create_module(device, label, source);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipelines = entries
            .iter()
            .map(|&entry| {
                let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: wgpu::PipelineCompilationOptions { constants, ..Default::default() },
                    cache: None,
                });
                (entry, pipeline)
            })
            .collect();
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: uniform_bytes,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Kernels { label, layout, pipelines, uniform }
    }

    /// The pipeline of entry point `entry` (one of those given to [`Kernels::new`]).
    pub fn pipeline(&self, entry: &str) -> &wgpu::ComputePipeline {
        &self.pipelines.iter().find(|(e, _)| *e == entry).expect("every entry point has a pipeline").1
    }

    /// Set the parameter block.
    pub fn write_uniform<U: bytemuck::Pod>(&self, gpu: &GpuContext, uniform: &U) {
        gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(uniform));
    }

    /// Group 0: the parameter block and `storage` in binding order.
    pub fn bind_group(&self, gpu: &GpuContext, storage: &[&wgpu::Buffer]) -> wgpu::BindGroup {
        let mut entries = vec![wgpu::BindGroupEntry { binding: 0, resource: self.uniform.as_entire_binding() }];
        for (i, buffer) in storage.iter().enumerate() {
            entries.push(wgpu::BindGroupEntry { binding: 1 + i as u32, resource: buffer.as_entire_binding() });
        }
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.label),
            layout: &self.layout,
            entries: &entries,
        })
    }
}
