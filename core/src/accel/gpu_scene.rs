//! A scene uploaded to the GPU: one vertex and one index buffer for all chunks, a bind group per material
//! (uniform, base-colour texture with mipmaps generated on the CPU, sampler).

use std::sync::Arc;

use wgpu::util::DeviceExt;

use glam::Vec3;

use super::scene_bvh::{cutout_alpha, CutoutAlpha, SceneBvh};
use crate::gpu::GpuContext;
use crate::scene::chunks::{Chunk, ChunkedGeometry};
use crate::scene::proxy::ProxyParams;
use crate::scene::{Material, Scene, TextureImage};

/// Geometry copies a scene keeps at once ([`GpuScene::proxy`]).
pub const MAX_PROXIES: usize = 2;

/// A copy of a scene's geometry on the GPU for paraboloid maps ([`crate::scene::proxy`]: long edges cut, and
/// simplified when asked): the scene's vertex layout, chunks for culling, the scene's materials.
pub struct GpuProxy {
    pub params: ProxyParams,
    pub vertex_buffer: wgpu::Buffer,
    pub index_buffer: wgpu::Buffer,
    pub chunks: Vec<Chunk>,
    pub triangle_count: u64,
}

pub struct GpuScene {
    pub vertex_buffer: wgpu::Buffer,
    /// The second UV channel per vertex (`[f32; 2]`), for the G-buffer pass.
    pub uv1_buffer: wgpu::Buffer,
    pub index_buffer: wgpu::Buffer,
    /// CPU copy of the chunks for culling.
    pub chunks: Vec<Chunk>,
    /// Bounds of all chunks (the drawn geometry), computed once.
    pub bounds: crate::scene::Aabb,
    /// CPU copy of the merged geometry (vertices, indices, chunks), for techniques that need the triangles
    /// themselves (the ray tracer builds its BVH from it). Shared, so a technique can cache by pointer.
    pub geometry: std::sync::Arc<ChunkedGeometry>,
    pub triangle_count: u64,
    pub material_bind_groups: Vec<wgpu::BindGroup>,
    /// Per material, true when it cuts out some of its surface (a cutoff above 0 and alpha below it in its
    /// factor or texture): the depth passes alpha-test its chunks.
    pub material_cutout: Vec<bool>,
    /// Per material, its alpha for the ray tracers' alpha test when it cuts out (`material_cutout`).
    pub cutout_alpha: Vec<Option<CutoutAlpha>>,
    /// Per material, the mean linear albedo (factor times the texture's mean): what a ray hit reflects.
    pub material_albedo: Vec<glam::Vec3>,
    /// The BVH, built on first use ([`GpuScene::bvh`]).
    pub(crate) bvh_cell: std::sync::OnceLock<Arc<SceneBvh>>,
    /// Copies of the geometry for paraboloid maps, built on first use ([`GpuScene::proxy`]).
    proxies: std::sync::Mutex<Vec<Arc<GpuProxy>>>,
    /// The scene's valid directional lights (the renderer's directional-light service shades them).
    pub directional: Vec<crate::scene::DirectionalLight>,
}

impl GpuScene {
    pub fn material_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
        let texture = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("material"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                texture(1),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
                // The emissive texture (white when the material has none).
                texture(3),
                // The ambient-occlusion texture (white when none).
                texture(4),
            ],
        })
    }

    pub fn new(gpu: &GpuContext, scene: &Scene, material_layout: &wgpu::BindGroupLayout) -> GpuScene {
        let device = &gpu.device;
        let geometry = ChunkedGeometry::build(scene);
        let vertex_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene vertices"),
            contents: bytemuck::cast_slice(&geometry.vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let uv1_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene uv1"),
            // Never empty: a scene without vertices still binds a valid buffer.
            contents: if geometry.uv1.is_empty() { &[0u8; 8] } else { bytemuck::cast_slice(&geometry.uv1) },
            usage: wgpu::BufferUsages::VERTEX,
        });
        let index_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene indices"),
            contents: bytemuck::cast_slice(&geometry.indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("material sampler"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            anisotropy_clamp: 1,
            ..Default::default()
        });
        let max_dim = device.limits().max_texture_dimension_2d;
        let textures: Vec<wgpu::TextureView> = scene.textures.iter().map(|t| upload_texture(gpu, t, max_dim)).collect();
        let white = upload_texture(
            gpu,
            &TextureImage { name: "white".into(), width: 1, height: 1, rgba8: vec![255; 4] },
            max_dim,
        );
        let material_bind_groups = scene
            .materials
            .iter()
            .map(|m| {
                let texture = m.base_color_texture.and_then(|i| textures.get(i));
                let emissive = m.emissive_texture.and_then(|i| textures.get(i));
                let occlusion = m.occlusion_texture.and_then(|(i, s)| textures.get(i).map(|t| (t, s)));
                let uniform =
                    MaterialUniform::new(m, texture.is_some(), emissive.is_some(), occlusion.map_or(0.0, |o| o.1));
                let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("material"),
                    contents: bytemuck::bytes_of(&uniform),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(&m.name),
                    layout: material_layout,
                    entries: &[
                        wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: wgpu::BindingResource::TextureView(texture.unwrap_or(&white)),
                        },
                        wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(&sampler) },
                        wgpu::BindGroupEntry {
                            binding: 3,
                            resource: wgpu::BindingResource::TextureView(emissive.unwrap_or(&white)),
                        },
                        wgpu::BindGroupEntry {
                            binding: 4,
                            resource: wgpu::BindingResource::TextureView(occlusion.map_or(&white, |o| o.0)),
                        },
                    ],
                })
            })
            .collect();
        let material_albedo = scene.materials.iter().map(|m| mean_albedo(scene, m)).collect();
        let cutout_alpha = cutout_alpha(scene);
        let material_cutout = cutout_alpha.iter().map(Option::is_some).collect();
        GpuScene {
            cutout_alpha,
            material_cutout,
            bounds: geometry.chunks.iter().fold(crate::scene::Aabb::EMPTY, |b, c| b.union(&c.bounds)),
            material_albedo,
            bvh_cell: std::sync::OnceLock::new(),
            proxies: std::sync::Mutex::new(Vec::new()),
            directional: scene
                .directional
                .iter()
                .filter(|d| d.is_valid())
                .take(crate::scene::MAX_DIRECTIONAL_LIGHTS)
                .map(|d| crate::scene::DirectionalLight { direction: d.direction.normalize(), ..*d })
                .collect(),
            vertex_buffer,
            uv1_buffer,
            index_buffer,
            triangle_count: geometry.triangle_count() as u64,
            chunks: geometry.chunks.clone(),
            geometry: std::sync::Arc::new(geometry),
            material_bind_groups,
        }
    }
}

/// A material's mean linear albedo: its base-colour factor times the mean of its texture (decoded from sRGB),
/// clamped to [0, 1].
pub fn mean_albedo(scene: &Scene, m: &crate::scene::Material) -> glam::Vec3 {
    let factor = m.base_color.truncate();
    let texture_mean = m
        .base_color_texture
        .and_then(|i| scene.textures.get(i))
        .filter(|t| !t.rgba8.is_empty())
        .map(|t| {
            let to_linear = |c: u8| {
                let c = c as f32 / 255.0;
                if c <= 0.04045 {
                    c / 12.92
                } else {
                    ((c + 0.055) / 1.055).powf(2.4)
                }
            };
            // At most ~64k texels are averaged: a mean does not need every texel of a 4k texture.
            let texels = t.rgba8.len() / 4;
            let stride = (texels / 65_536).max(1);
            let mut sum = glam::Vec3::ZERO;
            let mut n = 0u32;
            for px in t.rgba8.chunks_exact(4).step_by(stride) {
                sum += glam::Vec3::new(to_linear(px[0]), to_linear(px[1]), to_linear(px[2]));
                n += 1;
            }
            sum / n.max(1) as f32
        })
        .unwrap_or(glam::Vec3::ONE);
    (factor * texture_mean).clamp(glam::Vec3::ZERO, glam::Vec3::ONE)
}

/// Upload an sRGB texture with a full mip chain (box-filtered on the CPU).
fn upload_texture(gpu: &GpuContext, t: &TextureImage, max_dim: u32) -> wgpu::TextureView {
    let mut level = image::RgbaImage::from_raw(t.width, t.height, t.rgba8.clone())
        .unwrap_or_else(|| image::RgbaImage::from_pixel(1, 1, image::Rgba([255, 0, 255, 255])));
    if level.width() > max_dim || level.height() > max_dim {
        level = image::imageops::thumbnail(&level, level.width().min(max_dim), level.height().min(max_dim));
    }
    let mip_count = 32 - level.width().max(level.height()).leading_zeros();
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(&t.name),
        size: wgpu::Extent3d { width: level.width(), height: level.height(), depth_or_array_layers: 1 },
        mip_level_count: mip_count,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8UnormSrgb,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for mip in 0..mip_count {
        if mip > 0 {
            let w = (level.width() / 2).max(1);
            let h = (level.height() / 2).max(1);
            level = image::imageops::resize(&level, w, h, image::imageops::FilterType::Triangle);
        }
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: mip,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            level.as_raw(),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * level.width()), rows_per_image: None },
            wgpu::Extent3d { width: level.width(), height: level.height(), depth_or_array_layers: 1 },
        );
    }
    texture.create_view(&wgpu::TextureViewDescriptor::default())
}

impl GpuScene {
    /// The geometry copy of `params` ([`crate::scene::proxy`]), built and uploaded on first use and kept (the
    /// last [`MAX_PROXIES`] asked for): it and, when this call built it, the build's milliseconds. None when
    /// `params` ask for nothing ([`ProxyParams::is_identity`]): the maps draw [`GpuScene::cube_geometry`].
    pub fn proxy(&self, gpu: &GpuContext, params: ProxyParams) -> Option<(Arc<GpuProxy>, Option<f64>)> {
        if params.is_identity() {
            return None;
        }
        let params = params.normalized();
        let mut proxies = self.proxies.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = proxies.iter().find(|p| p.params == params) {
            return Some((p.clone(), None));
        }
        let started = std::time::Instant::now();
        let mut geometry = crate::scene::proxy::build(&self.geometry, &self.material_cutout, params);
        // A very short `max_edge` on a large scene can outgrow the device's largest buffer: the maps then draw the
        // scene's own triangles (which fit, being uploaded already), and say so.
        let limit = gpu.device.limits().max_buffer_size;
        let bytes = (geometry.vertices.len() * std::mem::size_of::<crate::scene::chunks::Vertex>()) as u64;
        if bytes > limit || geometry.indices.len() as u64 * 4 > limit {
            log::warn!(
                "the maps' geometry for {params:?} needs {} MiB, more than the device's {} MiB buffers: drawing the \
                 scene's own triangles",
                bytes >> 20,
                limit >> 20
            );
            let own = ProxyParams { keep: 1.0, max_error: 0.0, max_edge: 0.0 };
            geometry = crate::scene::proxy::build(&self.geometry, &self.material_cutout, own);
        }
        let build_ms = started.elapsed().as_secs_f64() * 1e3;
        let device = &gpu.device;
        // Never empty: a scene without triangles still binds valid buffers.
        let vertices: &[u8] =
            if geometry.vertices.is_empty() { &[0u8; 32] } else { bytemuck::cast_slice(&geometry.vertices) };
        let indices: &[u8] =
            if geometry.indices.is_empty() { &[0u8; 12] } else { bytemuck::cast_slice(&geometry.indices) };
        let proxy = Arc::new(GpuProxy {
            params,
            vertex_buffer: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("map geometry vertices"),
                contents: vertices,
                usage: wgpu::BufferUsages::VERTEX,
            }),
            index_buffer: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("map geometry indices"),
                contents: indices,
                usage: wgpu::BufferUsages::INDEX,
            }),
            triangle_count: geometry.triangle_count() as u64,
            chunks: geometry.chunks,
        });
        if proxies.len() >= MAX_PROXIES {
            proxies.remove(0);
        }
        proxies.push(proxy.clone());
        Some((proxy, Some(build_ms)))
    }

    /// The scene's BVH, built the first time it is asked for; the second value is its build time when this
    /// call built it.
    pub fn bvh(&self, gpu: &GpuContext) -> (Arc<SceneBvh>, Option<f64>) {
        let mut built = None;
        let bvh = self.bvh_cell.get_or_init(|| {
            let b = Arc::new(SceneBvh::build(gpu, &self.geometry, &self.material_albedo, &self.cutout_alpha));
            built = Some(b.cpu.stats.build_ms);
            b
        });
        (bvh.clone(), built)
    }
}

/// Mirrors `Material` in `material.wgsl` (the G-buffer and the alpha-tested depth passes).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MaterialUniform {
    pub base_color: [f32; 4],
    pub emissive: [f32; 4],
    pub specular: [f32; 4],
    /// x: alpha cutoff (0: opaque).
    pub alpha: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<MaterialUniform>() == 64);

impl MaterialUniform {
    pub fn new(m: &Material, has_texture: bool, has_emissive_texture: bool, occlusion_strength: f32) -> Self {
        let spec: Vec3 = m.specular;
        MaterialUniform {
            base_color: m.base_color.to_array(),
            emissive: [m.emissive.x, m.emissive.y, m.emissive.z, if has_texture { 1.0 } else { 0.0 }],
            specular: [
                (spec.x + spec.y + spec.z) / 3.0,
                m.shininess.clamp(1.0, 4096.0),
                if has_emissive_texture { 1.0 } else { 0.0 },
                occlusion_strength,
            ],
            alpha: [
                if m.alpha_cutoff.is_finite() { m.alpha_cutoff.clamp(0.0, 1.0) } else { 0.0 },
                if m.emissive_uv1 { 1.0 } else { 0.0 },
                if m.occlusion_uv1 { 1.0 } else { 0.0 },
                0.0,
            ],
        }
    }
}
