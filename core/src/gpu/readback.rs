//! Copying textures and buffers back to the CPU (texture rows padded to 256 bytes, as wgpu requires).

use super::GpuContext;
use crate::error::GpuError;

/// Read a 2D texture of `bytes_per_pixel` into tightly packed rows.
pub fn read_texture(
    gpu: &GpuContext,
    texture: &wgpu::Texture,
    width: u32,
    height: u32,
    bytes_per_pixel: u32,
) -> Result<Vec<u8>, GpuError> {
    gpu.check_lost()?;
    // wgpu's GL backend never offers `DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES`; every other one does.
    let copies_depth = gpu.adapter_info.backend != wgpu::Backend::Gl;
    if texture.format().is_depth_stencil_format() && !copies_depth {
        let colour = depth_as_colour(gpu, texture, width, height)?;
        return read_texture(gpu, &colour, width, height, bytes_per_pixel);
    }
    let row = width * bytes_per_pixel;
    let padded = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: (padded * height) as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    gpu.queue.submit([encoder.finish()]);
    let data = map_read(gpu, &buffer, (padded * height) as u64)?;
    let mut out = Vec::with_capacity((row * height) as usize);
    for y in 0..height as usize {
        let start = y * padded as usize;
        out.extend_from_slice(&data[start..start + row as usize]);
    }
    Ok(out)
}

/// Layer 0 of a `Depth32Float` texture drawn, bit for bit, into an `R32Uint` one of the same size (GL cannot
/// render to `R32Float`): the adapters without
/// `DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES` (GL) cannot copy depth to a buffer, but can read it in a
/// fragment shader.
fn depth_as_colour(
    gpu: &GpuContext,
    texture: &wgpu::Texture,
    width: u32,
    height: u32,
) -> Result<wgpu::Texture, GpuError> {
    let unsupported = |why: &str| {
        GpuError::Readback(format!(
            "this adapter ({:?}) cannot copy depth to a buffer, and {why}; use the Vulkan, Metal or DX12 backend",
            gpu.adapter_info.backend
        ))
    };
    if texture.format() != wgpu::TextureFormat::Depth32Float {
        return Err(unsupported("only Depth32Float is drawn instead"));
    }
    if !texture.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) || texture.depth_or_array_layers() != 1 {
        return Err(unsupported("this depth texture is not a single sampled layer"));
    }
    let colour = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("depth readback"),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::R32Uint,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let module = super::pipeline::create_module(&gpu.device, "depth readback", crate::shaders::DEPTH_READBACK.source);
    // The depth bound as an unfilterable float texture: naga's GLSL output cannot load from a depth texture.
    let bind_layout = gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("depth readback"),
        entries: &[super::bind::depth_texture_entry(0)],
    });
    let layout = gpu.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("depth readback"),
        bind_group_layouts: &[Some(&bind_layout)],
        immediate_size: 0,
    });
    let pipeline = gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("depth readback"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::TextureFormat::R32Uint.into())],
        }),
        multiview_mask: None,
        cache: None,
    });
    let view = texture
        .create_view(&wgpu::TextureViewDescriptor { aspect: wgpu::TextureAspect::DepthOnly, ..Default::default() });
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("depth readback"),
        layout: &bind_layout,
        entries: &[wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) }],
    });
    let target = colour.create_view(&Default::default());
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("depth readback"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..3, 0..1);
    }
    gpu.queue.submit([encoder.finish()]);
    Ok(colour)
}

/// Map the first `bytes` of a `MAP_READ` buffer (after the submitted work that fills it), copy them out, unmap.
pub fn map_read(gpu: &GpuContext, buffer: &wgpu::Buffer, bytes: u64) -> Result<Vec<u8>, GpuError> {
    gpu.check_lost()?;
    let slice = buffer.slice(..bytes.max(4));
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.wait_idle()?;
    rx.recv()
        .map_err(|_| GpuError::Readback("the map callback never ran".into()))?
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    let data = slice.get_mapped_range().map_err(|e| GpuError::Readback(e.to_string()))?.to_vec();
    buffer.unmap();
    Ok(data)
}

/// Copy a whole `COPY_SRC` buffer back to the CPU.
pub fn read_buffer(gpu: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    gpu.check_lost()?;
    let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("buffer readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    gpu.queue.submit([encoder.finish()]);
    map_read(gpu, &staging, buffer.size())
}

/// The depths of a whole 32-bit float depth texture, row by row.
pub fn read_depths(gpu: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<f32>, GpuError> {
    let size = texture.size();
    let bytes = read_texture(gpu, texture, size.width, size.height, 4)?;
    Ok(bytes.chunks_exact(4).map(|d| f32::from_le_bytes([d[0], d[1], d[2], d[3]])).collect())
}

/// A depth atlas as a grey PNG-ready image: near is white, far (and empty) is black, stretched between the
/// nearest and farthest drawn depth so both hardware (cube) and linear (paraboloid) depth are readable.
pub fn depth_atlas_image(gpu: &GpuContext, texture: &wgpu::Texture) -> Result<image::RgbaImage, GpuError> {
    let size = texture.size();
    let depths = read_depths(gpu, texture)?;
    let drawn = depths.iter().copied().filter(|&d| d < 1.0);
    let (lo, hi) = drawn.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), d| (lo.min(d), hi.max(d)));
    let span = (hi - lo).max(1e-6);
    let grey: Vec<u8> = depths
        .iter()
        .flat_map(|&d| {
            let g = if d >= 1.0 { 0 } else { (255.0 * (1.0 - 0.85 * (d - lo) / span)) as u8 };
            [g, g, g, 255]
        })
        .collect();
    image::RgbaImage::from_raw(size.width, size.height, grey).ok_or_else(|| GpuError::Readback("size mismatch".into()))
}

/// IEEE half to single precision.
pub fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = ((h >> 10) & 0x1f) as i32;
    let frac = (h & 0x3ff) as f32;
    match exp {
        0 => sign * frac * 2f32.powi(-24),
        31 => {
            if frac == 0.0 {
                sign * f32::INFINITY
            } else {
                f32::NAN
            }
        }
        _ => sign * (1.0 + frac / 1024.0) * 2f32.powi(exp - 15),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn half_floats_decode() {
        use super::f16_to_f32;
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0xc000), -2.0);
        assert_eq!(f16_to_f32(0x0000), 0.0);
        assert_eq!(f16_to_f32(0x3800), 0.5);
        assert_eq!(f16_to_f32(0x7c00), f32::INFINITY);
        assert!((f16_to_f32(0x0001) - 5.96e-8).abs() < 1e-9);
    }
}
