//! Reading a frame back: the output image, the geometry mask, world positions, HDR radiance and components.

use glam::Vec3;

use super::{Component, Renderer};
use crate::error::GpuError;
use crate::gpu::readback;
use crate::scene::Camera;

impl Renderer {
    /// The tone-mapped output as an sRGB RGBA8 image.
    pub fn read_output(&self) -> Result<image::RgbaImage, GpuError> {
        let t = &self.targets;
        let bytes = readback::read_texture(&self.gpu, &t.output_texture, t.width, t.height, 4)?;
        image::RgbaImage::from_raw(t.width, t.height, bytes).ok_or_else(|| GpuError::Readback("size mismatch".into()))
    }

    /// Per pixel, true where the G-buffer holds geometry (not background): the pixels comparisons count.
    pub fn read_geometry_mask(&self) -> Result<Vec<bool>, GpuError> {
        let t = &self.targets;
        Ok(readback::read_depths(&self.gpu, &t.depth_texture)?.into_iter().map(|d| d < 1.0).collect())
    }

    /// World position of every pixel of the last frame (None for background), from the G-buffer depth.
    pub fn read_world_positions(&self, camera: &Camera) -> Result<Vec<Option<Vec3>>, GpuError> {
        let t = &self.targets;
        let depths = readback::read_depths(&self.gpu, &t.depth_texture)?;
        let world_from_clip = camera.clip_from_world(t.width as f32 / t.height as f32).inverse();
        Ok(depths
            .into_iter()
            .enumerate()
            .map(|(i, depth)| {
                if depth >= 1.0 {
                    return None;
                }
                let (x, y) = ((i as u32 % t.width) as f32 + 0.5, (i as u32 / t.width) as f32 + 0.5);
                let ndc = glam::Vec4::new(x / t.width as f32 * 2.0 - 1.0, 1.0 - y / t.height as f32 * 2.0, depth, 1.0);
                let w = world_from_clip * ndc;
                Some(w.truncate() / w.w)
            })
            .collect())
    }

    /// The HDR radiance of the chosen [`RenderSettings::component`], linear RGBA, row-major (no gain).
    pub fn read_hdr(&self) -> Result<Vec<[f32; 4]>, GpuError> {
        self.read_component(self.settings.component)
    }

    /// The HDR radiance of one component, linear RGBA, row-major (no gain).
    pub fn read_component(&self, component: Component) -> Result<Vec<[f32; 4]>, GpuError> {
        let t = &self.targets;
        let direct = || -> Result<Vec<[f32; 4]>, GpuError> {
            if t.hdr_texture.format() == wgpu::TextureFormat::Rgba32Float {
                let bytes = readback::read_texture(&self.gpu, &t.hdr_texture, t.width, t.height, 16)?;
                let values: &[f32] = bytemuck::cast_slice(&bytes);
                return Ok(values.chunks_exact(4).map(|v| [v[0], v[1], v[2], v[3]]).collect());
            }
            let bytes = readback::read_texture(&self.gpu, &t.hdr_texture, t.width, t.height, 8)?;
            Ok(bytes
                .chunks_exact(8)
                .map(|p| {
                    let h = |i: usize| readback::f16_to_f32(u16::from_le_bytes([p[i], p[i + 1]]));
                    [h(0), h(2), h(4), h(6)]
                })
                .collect())
        };
        let indirect = || -> Result<Vec<[f32; 4]>, GpuError> {
            let bytes = readback::read_buffer(&self.gpu, &self.indirect_buffer)?;
            let values: &[f32] = bytemuck::cast_slice(&bytes);
            Ok(values.chunks_exact(4).map(|v| [v[0], v[1], v[2], 1.0]).collect())
        };
        let pixels = (t.width * t.height) as usize;
        match (component, self.indirect.is_some()) {
            (Component::Direct, _) | (Component::Total, false) => direct(),
            (Component::Indirect, false) => Ok(vec![[0.0, 0.0, 0.0, 1.0]; pixels]),
            (Component::Indirect, true) => indirect(),
            (Component::Total, true) => {
                let mut d = direct()?;
                for (p, i) in d.iter_mut().zip(indirect()?) {
                    for c in 0..3 {
                        p[c] += i[c];
                    }
                }
                Ok(d)
            }
        }
    }
}
