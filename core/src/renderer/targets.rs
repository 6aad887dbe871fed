//! Screen-sized render targets: the G-buffer, the HDR accumulation target and the tone-mapped output.

use crate::gpu::GpuContext;
use crate::services::layouts::SharedLayouts;

pub struct FrameTargets {
    pub width: u32,
    pub height: u32,
    pub albedo: wgpu::TextureView,
    pub normal: wgpu::TextureView,
    pub emissive: wgpu::TextureView,
    pub depth: wgpu::TextureView,
    pub depth_texture: wgpu::Texture,
    pub hdr_texture: wgpu::Texture,
    pub hdr: wgpu::TextureView,
    /// sRGB output; the app shows it, the CLI saves it.
    pub output_texture: wgpu::Texture,
    pub output: wgpu::TextureView,
    /// The same texels as plain `Rgba8Unorm`: what egui samples. egui expects textures that are not
    /// sRGB-aware (its shader treats texels as gamma-encoded); through the sRGB view the screen showed the
    /// encoded image decoded once more, darker than every screenshot and figure (which read these bytes).
    /// A view of `output_texture` where the device can view it in another format, else of `display_copy`.
    pub output_display: wgpu::TextureView,
    /// On GL, which cannot view a texture in another format (`DownlevelFlags::VIEW_FORMATS`): a plain
    /// `Rgba8Unorm` texture the output's bytes are copied into when the app is about to show them
    /// ([`FrameTargets::encode_display_copy`]), so the app shows the same image on GL as elsewhere.
    display_copy: Option<wgpu::Texture>,
    /// The output changed since the display copy was last made (GL only; the CLI never shows the output, so its
    /// measured steps never pay for a copy).
    display_stale: bool,
}

/// The plain view format of the output (see `FrameTargets::output_display`).
pub const OUTPUT_DISPLAY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

fn target(gpu: &GpuContext, label: &str, w: u32, h: u32, format: wgpu::TextureFormat, copy: bool) -> wgpu::Texture {
    let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
    if copy {
        usage |= wgpu::TextureUsages::COPY_SRC;
    }
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: if format == SharedLayouts::OUTPUT_FORMAT && plain_view(gpu) {
            &[OUTPUT_DISPLAY_FORMAT]
        } else {
            &[]
        },
    })
}

/// Whether the device can view the output as plain `Rgba8Unorm`: GL lacks `DownlevelFlags::VIEW_FORMATS`, so
/// there the output is copied into a plain texture for display instead.
fn plain_view(gpu: &GpuContext) -> bool {
    gpu.adapter_info.backend != wgpu::Backend::Gl
}

impl FrameTargets {
    pub fn new(gpu: &GpuContext, width: u32, height: u32) -> FrameTargets {
        let view = |t: wgpu::Texture| t.create_view(&Default::default());
        let hdr_texture = target(gpu, "hdr", width, height, SharedLayouts::hdr_format(&gpu.device), true);
        let output_texture = target(gpu, "output", width, height, SharedLayouts::OUTPUT_FORMAT, true);
        let depth_texture = target(gpu, "gbuffer depth", width, height, SharedLayouts::DEPTH_FORMAT, true);
        let display_copy = (!plain_view(gpu)).then(|| {
            gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("output for display"),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: OUTPUT_DISPLAY_FORMAT,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            })
        });
        FrameTargets {
            width,
            height,
            albedo: view(target(gpu, "gbuffer albedo", width, height, SharedLayouts::ALBEDO_FORMAT, false)),
            normal: view(target(gpu, "gbuffer normal", width, height, SharedLayouts::NORMAL_FORMAT, false)),
            emissive: view(target(gpu, "gbuffer emissive", width, height, SharedLayouts::EMISSIVE_FORMAT, false)),
            depth: depth_texture.create_view(&Default::default()),
            depth_texture,
            hdr: hdr_texture.create_view(&Default::default()),
            hdr_texture,
            output: output_texture.create_view(&Default::default()),
            output_display: match &display_copy {
                Some(copy) => copy.create_view(&Default::default()),
                None => output_texture.create_view(&wgpu::TextureViewDescriptor {
                    format: Some(OUTPUT_DISPLAY_FORMAT),
                    ..Default::default()
                }),
            },
            display_copy,
            display_stale: false,
            output_texture,
        }
    }

    /// A pass wrote the output (the tone mapping, the overlays): the display copy, where there is one, is stale.
    pub fn output_written(&mut self) {
        self.display_stale = self.display_copy.is_some();
    }

    /// Whether the display copy is behind the output (GL, after a pass wrote it).
    pub fn display_stale(&self) -> bool {
        self.display_stale
    }

    /// Where the output cannot be viewed as plain `Rgba8Unorm` (GL) and changed since the last copy: copy it
    /// into the display texture (true when a copy was encoded). Nothing elsewhere.
    pub fn encode_display_copy(&mut self, encoder: &mut wgpu::CommandEncoder) -> bool {
        let Some(copy) = self.display_copy.as_ref().filter(|_| self.display_stale) else { return false };
        encoder.copy_texture_to_texture(
            self.output_texture.as_image_copy(),
            copy.as_image_copy(),
            wgpu::Extent3d { width: self.width, height: self.height, depth_or_array_layers: 1 },
        );
        self.display_stale = false;
        true
    }
}
