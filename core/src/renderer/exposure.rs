//! Auto-exposure ([`RenderSettings::auto_exposure`](super::RenderSettings)): the displayed image's log-average
//! luminance over its geometry pixels (Reinhard et al. 2002, equation 1), metered on the GPU when a frame is
//! tone-mapped (`shaders/exposure.wgsl`: per-tile sums, then one resolve), and the scale `0.18 / L_avg` that
//! the tone mapping multiplies the user's exposure by (then a compensation). The scale stays on the GPU; the
//! tone mapping reads it from the buffer, so nothing waits for a readback. Progressive previews reuse the last
//! metered scale, so a frame that is still accumulating lights does not pump the exposure.

use wgpu::util::DeviceExt;

use super::targets::FrameTargets;
use crate::error::GpuError;
use crate::gpu::bind::storage_entry;
use crate::gpu::bind::storage_rw_entry;
use crate::gpu::GpuContext;
use crate::services::layouts::compute_pipeline;
use crate::services::layouts::SharedLayouts;

pub struct ExposureMeter {
    layout: wgpu::BindGroupLayout,
    meter: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    partials: wgpu::Buffer,
    /// `vec4`: scale, L_avg, pixels metered, 1 once metered. Bound by the tone mapping at binding 2.
    pub result: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    /// True once a frame was metered since the last reset (a preview before that meters too).
    pub metered: bool,
}

fn tiles(width: u32, height: u32) -> u64 {
    width.div_ceil(16) as u64 * height.div_ceil(16) as u64
}

impl ExposureMeter {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts, targets: &FrameTargets, indirect: &wgpu::Buffer) -> Self {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("exposure meter"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                storage_entry(1),
                storage_rw_entry(2),
                storage_rw_entry(3),
            ],
        });
        let meter =
            compute_pipeline(gpu, layouts, "exposure meter", crate::shaders::EXPOSURE.source, "meter_main", &[&layout]);
        let resolve = compute_pipeline(
            gpu,
            layouts,
            "exposure resolve",
            crate::shaders::EXPOSURE.source,
            "meter_resolve",
            &[&layout],
        );
        let result = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("auto exposure"),
            contents: bytemuck::cast_slice(&[1.0f32, 0.0, 0.0, 0.0]),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        });
        let partials = Self::partials(gpu, targets);
        let bind_group = Self::bind_group(gpu, &layout, targets, indirect, &partials, &result);
        ExposureMeter { layout, meter, resolve, partials, result, bind_group, metered: false }
    }

    fn partials(gpu: &GpuContext, targets: &FrameTargets) -> wgpu::Buffer {
        gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("exposure partials"),
            size: tiles(targets.width, targets.height) * 8,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        })
    }

    fn bind_group(
        gpu: &GpuContext,
        layout: &wgpu::BindGroupLayout,
        targets: &FrameTargets,
        indirect: &wgpu::Buffer,
        partials: &wgpu::Buffer,
        result: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("exposure meter"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&targets.hdr) },
                wgpu::BindGroupEntry { binding: 1, resource: indirect.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: partials.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: result.as_entire_binding() },
            ],
        })
    }

    /// New targets or a new indirect buffer: bind them (the partial sums follow the size).
    pub fn rebind(&mut self, gpu: &GpuContext, targets: &FrameTargets, indirect: &wgpu::Buffer) {
        if self.partials.size() != tiles(targets.width, targets.height) * 8 {
            self.partials = Self::partials(gpu, targets);
        }
        self.bind_group = Self::bind_group(gpu, &self.layout, targets, indirect, &self.partials, &self.result);
    }

    /// Meter the displayed image into `result` (before the tone mapping, in the same encoder).
    /// Meter the HDR image (two dispatches). With `timer`, timed as the pass "exposure meter" of the frame, so
    /// the step that holds it is covered by timestamps (timing.rs judges steps by their coverage).
    pub fn encode(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        screen: &wgpu::BindGroup,
        width: u32,
        height: u32,
        timer: Option<&crate::timing::PassTimer>,
    ) {
        let record = |pass: &mut wgpu::ComputePass<'_>| {
            pass.set_bind_group(0, screen, &[]);
            pass.set_bind_group(1, &self.bind_group, &[]);
            pass.set_pipeline(&self.meter);
            pass.dispatch_workgroups(width.div_ceil(16), height.div_ceil(16), 1);
            pass.set_pipeline(&self.resolve);
            pass.dispatch_workgroups(1, 1, 1);
        };
        match timer {
            Some(t) => t.compute_pass(encoder, "exposure meter", record),
            None => record(&mut encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("exposure meter"),
                timestamp_writes: None,
            })),
        }
        self.metered = true;
    }

    /// Use this scale (metered elsewhere: the view a comparison is made with) as if it had been metered here.
    pub fn hold(&mut self, gpu: &GpuContext, scale: f32, average: f32) {
        gpu.queue.write_buffer(&self.result, 0, bytemuck::cast_slice(&[scale, average, 0.0, 1.0]));
        self.metered = true;
    }

    /// The last metered scale and log-average luminance (a small blocking readback).
    pub fn read(&self, gpu: &GpuContext) -> Result<(f32, f32), GpuError> {
        let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("auto exposure readback"),
            size: 16,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&self.result, 0, &staging, 0, 16);
        gpu.queue.submit([encoder.finish()]);
        let data = crate::gpu::readback::map_read(gpu, &staging, 16)?;
        let v: &[f32] = bytemuck::cast_slice(&data);
        Ok((v[0], v[1]))
    }
}
