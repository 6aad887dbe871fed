//! The shading pass every light-by-light technique has: a full-screen pass over the G-buffer that adds its
//! lights' radiance into the HDR target. Group 0 is the screen group, group 1 the pass's own (its entries,
//! usually the visible lights, a batch uniform and a shadow atlas), group 2 the tile lists when it reads them.
//! The reference's per-light shading, the unshadowed preview, the ray tracer and LightCluster build theirs here
//! instead of each repeating the layout, module, pipeline and zeroed batch uniform.

use wgpu::util::DeviceExt;

use super::context::{accumulate_pass, FrameContext};
use crate::gpu::pipeline::create_module;
use crate::gpu::GpuContext;
use crate::services::layouts::SharedLayouts;
use crate::shaders::WgslModule;

pub struct ShadePass {
    pipeline: wgpu::RenderPipeline,
    group_layout: wgpu::BindGroupLayout,
    batch_uniform: wgpu::Buffer,
    label: &'static str,
    reads_tiles: bool,
}

impl ShadePass {
    /// A pass running `module`'s `fs_main` with group 1 made of `entries`, a batch uniform of `U` (zeroed until
    /// the first [`ShadePass::write_batch`]) and, when `reads_tiles`, the tile lists as group 2.
    pub fn new<U: bytemuck::Pod>(
        gpu: &GpuContext,
        layouts: &SharedLayouts,
        label: &'static str,
        module: &WgslModule,
        entries: &[wgpu::BindGroupLayoutEntry],
        reads_tiles: bool,
    ) -> ShadePass {
        let device = &gpu.device;
        let group_layout =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries });
        let shader = create_module(device, module.name, module.source);
        let mut groups = vec![&group_layout];
        if reads_tiles {
            groups.push(&layouts.light_tiles);
        }
        let pipeline =
            layouts.fullscreen_pipeline(device, label, &shader, &groups, SharedLayouts::hdr_format(device), true);
        let batch_uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::bytes_of(&<U as bytemuck::Zeroable>::zeroed()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        ShadePass { pipeline, group_layout, batch_uniform, label, reads_tiles }
    }

    /// The batch uniform, to bind in group 1.
    pub fn batch_uniform(&self) -> &wgpu::Buffer {
        &self.batch_uniform
    }

    /// A group 1 for this pass.
    pub fn bind_group(&self, gpu: &GpuContext, entries: &[wgpu::BindGroupEntry]) -> wgpu::BindGroup {
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.label),
            layout: &self.group_layout,
            entries,
        })
    }

    /// Set the batch uniform for the next [`ShadePass::encode`].
    pub fn write_batch<U: bytemuck::Pod>(&self, gpu: &GpuContext, uniform: &U) {
        gpu.queue.write_buffer(&self.batch_uniform, 0, bytemuck::bytes_of(uniform));
    }

    /// Add the pass's output into the HDR target, timed as `span`: group 1 is `group`, group 2 (when the pass
    /// reads tiles) `tiles`, or the renderer's tile lists when None (LightCluster passes its clusters' lists).
    pub fn encode(
        &self,
        ctx: &FrameContext,
        encoder: &mut wgpu::CommandEncoder,
        span: &str,
        group: &wgpu::BindGroup,
        tiles: Option<&wgpu::BindGroup>,
    ) {
        if self.reads_tiles {
            let tiles = tiles.unwrap_or_else(|| ctx.light_tiles.bind_group());
            accumulate_pass(ctx, encoder, span, &self.pipeline, &[group, tiles]);
        } else {
            accumulate_pass(ctx, encoder, span, &self.pipeline, &[group]);
        }
    }
}
