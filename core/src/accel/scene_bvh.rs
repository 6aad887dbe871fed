//! The scene's BVH as a renderer service: built once per scene on the CPU (binned SAH,
//! [`crate::accel::bvh`]), uploaded once, and shared by everything that traces rays: the
//! ray-traced shadows, the VPL generator (closest hits on the CPU), the VPL ray-traced gather and the path
//! tracer (closest hits on the GPU). It lives in `GpuScene` behind a `OnceLock`, so a scene that never
//! traces a ray never pays for it.
//!
//! Besides the traversal layout (`raytrace_bvh.wgsl`) it keeps, per BVH triangle, what a hit needs to shade:
//! the geometric normal and the material's mean albedo ([`BvhSurface`] on the CPU; on the GPU the albedo rides
//! in the unused `w` components of the triangle and the normal is `cross(e1, e2)`). Hits use
//! the material's *mean* albedo (its factor times the mean of its texture) rather than the texel under the hit:
//! a GPU hit shader cannot sample an arbitrary material's texture without bindless textures, and the CPU VPL
//! generator and the path tracer must agree. Receivers (the G-buffer) keep their textured albedo.
//!
//! Cut-out materials (a cutoff and alpha below it, `GpuScene::material_cutout`) are alpha-tested by every
//! traversal, on the GPU and on the CPU alike ([`BvhCutouts`]): a hit on a cut-out texel is no hit, as in the
//! shadow maps' alpha-tested depth passes. Without bindless textures, the masks are copied into one
//! `R8Unorm` array (one layer per cut-out material, resampled to a common size of at most
//! [`MASK_SIZE`] texels) and bound with the BVH as textures, so no pass needs another storage buffer.

use glam::Vec3;
use wgpu::util::DeviceExt;

use crate::accel::bvh::{self, Bvh, Hit};
use crate::gpu::GpuContext;
use crate::scene::chunks::ChunkedGeometry;

/// Per BVH triangle: geometric normal (xyz) and the material's mean albedo (rgb).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhSurface {
    pub normal: [f32; 4],
    pub albedo: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<BvhSurface>() == 32);

/// The BVH of a scene, on the CPU and on the GPU.
pub struct SceneBvh {
    pub cpu: Bvh,
    /// Per entry of `cpu.triangles`.
    pub surfaces: Vec<BvhSurface>,
    pub nodes: wgpu::Buffer,
    /// `BvhTriangle`s with the albedo in the `w` of `v0`, `e1`, `e2` (r, g, b).
    pub triangles: wgpu::Buffer,
    /// The alpha test of cut-out triangles, on the CPU.
    pub cutouts: BvhCutouts,
    /// The same on the GPU: bindings 10 to 13 of every tracer's BVH group.
    pub cutout_textures: CutoutTextures,
}

/// Largest side of a cut-out mask layer: masks of bigger textures are box-filtered down to it. The shadow
/// maps alpha-test the texture itself at level 0, so silhouettes of finer textures are a little softer in the
/// ray tracer's view than in theirs.
pub const MASK_SIZE: u32 = 512;
/// The cut-out data's WGSL bindings in group 1 (after any pass's own: they start at 10).
pub const CUTOUT_BINDINGS: [u32; 4] = [10, 11, 12, 13];

/// A cut-out material's alpha for the ray tracers: its cutoff and its alpha (base-colour factor times the
/// texture's alpha, 8-bit), `width x height` texels (1 x 1 when it has no texture).
#[derive(Clone, Debug, PartialEq)]
pub struct CutoutAlpha {
    pub cutoff: f32,
    pub width: u32,
    pub height: u32,
    pub alpha: Vec<u8>,
}

/// Per material of `scene`, its alpha when it cuts out some of its surface (a cutoff above 0 and alpha below
/// it in its factor or texture), else `None`.
pub fn cutout_alpha(scene: &crate::scene::Scene) -> Vec<Option<CutoutAlpha>> {
    scene
        .materials
        .iter()
        .map(|m| {
            let cutoff = m.alpha_cutoff;
            if cutoff <= 0.0 || cutoff.is_nan() {
                return None;
            }
            let factor = m.base_color.w.clamp(0.0, 1.0);
            let scaled = |a: u8| (a as f32 * factor).round().clamp(0.0, 255.0) as u8;
            let texture = m
                .base_color_texture
                .and_then(|i| scene.textures.get(i))
                .filter(|t| t.width > 0 && t.height > 0 && t.rgba8.len() == (t.width * t.height * 4) as usize);
            let alpha = match texture {
                Some(t) => CutoutAlpha {
                    cutoff,
                    width: t.width,
                    height: t.height,
                    alpha: t.rgba8.chunks_exact(4).map(|p| scaled(p[3])).collect(),
                },
                None => CutoutAlpha { cutoff, width: 1, height: 1, alpha: vec![scaled(255)] },
            };
            // The factor's alpha is tested exactly (not after rounding to 8 bits), as the G-buffer does.
            let cuts = m.base_color.w < cutoff || alpha.alpha.iter().any(|&a| (a as f32 / 255.0) < cutoff);
            cuts.then_some(alpha)
        })
        .collect()
}

/// The alpha test of a BVH's cut-out triangles (CPU side; [`CutoutTextures`] holds the GPU copy). Mirrors
/// `bvh_cut_out` in `raytrace_bvh.wgsl`.
#[derive(Clone, Debug, Default)]
pub struct BvhCutouts {
    /// Per BVH triangle (entry of `Bvh::triangles`): 0 when opaque, else 1 + its record.
    pub ids: Vec<u32>,
    /// Per cut-out triangle: the UVs of v0, v1, v2 and (mask layer, cutoff).
    pub records: Vec<[f32; 8]>,
    /// Side of every mask layer.
    pub mask_size: u32,
    /// One `mask_size^2` layer per cut-out material, rows top to bottom as in the texture.
    pub masks: Vec<Vec<u8>>,
}

impl BvhCutouts {
    /// Records of `bvh`'s triangles whose material cuts out (`alpha[material]` is `Some`), with UVs from
    /// `geometry`. At most `max_layers` materials get a mask (the rest stay opaque, said in the log).
    pub fn build(bvh: &Bvh, geometry: &ChunkedGeometry, alpha: &[Option<CutoutAlpha>], max_layers: u32) -> Self {
        Self::build_with(bvh, geometry, &triangle_materials(geometry), alpha, max_layers)
    }

    /// [`BvhCutouts::build`] with each input triangle's material already known.
    fn build_with(
        bvh: &Bvh,
        geometry: &ChunkedGeometry,
        triangle_material: &[u32],
        alpha: &[Option<CutoutAlpha>],
        max_layers: u32,
    ) -> Self {
        let mut layer_of = vec![None; alpha.len()];
        let mut sources = Vec::new();
        for (m, a) in alpha.iter().enumerate() {
            let Some(a) = a else { continue };
            if sources.len() as u32 >= max_layers {
                log::warn!("more than {max_layers} cut-out materials: the rest are opaque to rays");
                break;
            }
            layer_of[m] = Some(sources.len() as u32);
            sources.push(a);
        }
        if sources.is_empty() {
            return BvhCutouts::default();
        }
        let mask_size = sources.iter().map(|a| a.width.max(a.height)).max().unwrap_or(1).clamp(1, MASK_SIZE);
        let masks = sources
            .iter()
            .map(|a| {
                let source = image::GrayImage::from_raw(a.width, a.height, a.alpha.clone())
                    .unwrap_or_else(|| image::GrayImage::from_pixel(1, 1, image::Luma([255])));
                if source.width() == mask_size && source.height() == mask_size {
                    return source.into_raw();
                }
                image::imageops::resize(&source, mask_size, mask_size, image::imageops::FilterType::Triangle).into_raw()
            })
            .collect();
        let mut ids = vec![0u32; bvh.triangles.len()];
        let mut records = Vec::new();
        for (k, &id) in bvh.triangle_ids.iter().enumerate() {
            let material = triangle_material.get(id as usize).copied().unwrap_or(u32::MAX) as usize;
            let Some(layer) = layer_of.get(material).copied().flatten() else { continue };
            let uv = |j: usize| {
                let v = geometry.indices.get(id as usize * 3 + j).and_then(|&i| geometry.vertices.get(i as usize));
                v.map_or([0.0; 2], |v| v.uv)
            };
            let (a, b, c) = (uv(0), uv(1), uv(2));
            let cutoff = alpha[material].as_ref().map_or(0.0, |a| a.cutoff);
            records.push([a[0], a[1], b[0], b[1], c[0], c[1], layer as f32, cutoff]);
            ids[k] = records.len() as u32;
        }
        BvhCutouts { ids, records, mask_size, masks }
    }

    /// True when the hit at barycentrics `(u, v)` (of v1, v2) of BVH triangle `triangle` lands on a cut-out
    /// texel: the mask sampled bilinearly with repeat, as the GPU's sampler does, below the cutoff.
    pub fn cut_out(&self, triangle: u32, u: f32, v: f32) -> bool {
        let Some(&id) = self.ids.get(triangle as usize) else { return false };
        let Some(r) = id.checked_sub(1).and_then(|r| self.records.get(r as usize)) else { return false };
        let w = 1.0 - u - v;
        let uv = [r[0] * w + r[2] * u + r[4] * v, r[1] * w + r[3] * u + r[5] * v];
        let Some(mask) = self.masks.get(r[6] as usize) else { return false };
        sample_bilinear_repeat(mask, self.mask_size, uv) < r[7]
    }

    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }
}

/// The material of each input triangle of `geometry` (chunks are index ranges with one material each).
fn triangle_materials(geometry: &ChunkedGeometry) -> Vec<u32> {
    let mut out = vec![u32::MAX; geometry.triangle_count()];
    for c in &geometry.chunks {
        let first = (c.first_index / 3) as usize;
        let end = (first + c.triangle_count() as usize).min(out.len());
        for m in &mut out[first.min(end)..end] {
            *m = c.material;
        }
    }
    out
}

/// `textureSampleLevel` of an `R8Unorm` `size x size` texture with a linear, repeating sampler.
fn sample_bilinear_repeat(mask: &[u8], size: u32, uv: [f32; 2]) -> f32 {
    if size == 0 || mask.len() < (size * size) as usize || !(uv[0].is_finite() && uv[1].is_finite()) {
        return 1.0;
    }
    let s = size as f32;
    let (x, y) = (uv[0] * s - 0.5, uv[1] * s - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let wrap = |i: f32| (i.rem_euclid(s) as u32).min(size - 1);
    let texel = |i: f32, j: f32| mask[(wrap(j) * size + wrap(i)) as usize] as f32 / 255.0;
    let top = texel(x0, y0) * (1.0 - fx) + texel(x0 + 1.0, y0) * fx;
    let bottom = texel(x0, y0 + 1.0) * (1.0 - fx) + texel(x0 + 1.0, y0 + 1.0) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// The cut-out data on the GPU, bound with the BVH at [`CUTOUT_BINDINGS`]: per BVH triangle its record
/// (`R32Uint`, 0 = opaque), the records (`Rgba32Float`, two texels each), the masks (`R8Unorm` array) and a
/// linear repeating sampler. A scene without cut-outs binds 1 x 1 textures.
pub struct CutoutTextures {
    ids: wgpu::TextureView,
    records: wgpu::TextureView,
    masks: wgpu::TextureView,
    sampler: wgpu::Sampler,
    /// False when the scene has cut-outs but the device's texture limits cannot hold them (the rays then see
    /// every caster whole, as before).
    pub enabled: bool,
}

/// Texels per row of the id and record textures (the downlevel limit of a 2D texture's side).
const CUTOUT_ROW: u32 = 2048;

impl CutoutTextures {
    pub fn new(gpu: &GpuContext, cutouts: &BvhCutouts) -> CutoutTextures {
        let limits = gpu.device.limits();
        let row = CUTOUT_ROW.min(limits.max_texture_dimension_2d);
        let rows = |texels: usize| (texels as u32).div_ceil(row).max(1);
        let fits = !cutouts.is_empty()
            && rows(cutouts.ids.len()) <= limits.max_texture_dimension_2d
            && rows(cutouts.records.len() * 2) <= limits.max_texture_dimension_2d;
        if !cutouts.is_empty() && !fits {
            log::warn!(
                "{} triangles: too many for this device's textures, rays see cut-out casters whole",
                cutouts.ids.len()
            );
        }
        let empty = BvhCutouts::default();
        let c = if fits { cutouts } else { &empty };
        // Width `row` unless everything fits in one shorter row.
        let texture_2d = |label, texels: usize, format: wgpu::TextureFormat, texel_bytes: usize, data: &[u8]| {
            let width = (texels as u32).clamp(1, row);
            let height = rows(texels);
            let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let mut padded = data.to_vec();
            padded.resize((width * height) as usize * texel_bytes, 0);
            gpu.queue.write_texture(
                texture.as_image_copy(),
                &padded,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(width * texel_bytes as u32),
                    rows_per_image: None,
                },
                wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            );
            texture.create_view(&Default::default())
        };
        let ids =
            texture_2d("bvh cutout ids", c.ids.len(), wgpu::TextureFormat::R32Uint, 4, bytemuck::cast_slice(&c.ids));
        let records = texture_2d(
            "bvh cutout records",
            c.records.len() * 2,
            wgpu::TextureFormat::Rgba32Float,
            16,
            bytemuck::cast_slice(&c.records),
        );
        let size = c.mask_size.max(1);
        let layers = array_layers(c.masks.len() as u32);
        let masks = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("bvh cutout masks"),
            size: wgpu::Extent3d { width: size, height: size, depth_or_array_layers: layers },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let mut mask_data: Vec<u8> = c.masks.concat();
        mask_data.resize((size * size * layers) as usize, 255);
        // R8 rows need no padding for write_texture (only copies between buffers and textures do).
        gpu.queue.write_texture(
            masks.as_image_copy(),
            &mask_data,
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(size), rows_per_image: Some(size) },
            wgpu::Extent3d { width: size, height: size, depth_or_array_layers: layers },
        );
        let masks = masks.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("bvh cutout sampler"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        CutoutTextures { ids, records, masks, sampler, enabled: fits }
    }

    /// The four layout entries to add to a tracer's BVH group (group 1).
    pub fn layout_entries() -> [wgpu::BindGroupLayoutEntry; 4] {
        let visibility = wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let texture = |binding, sample_type, view_dimension| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Texture { sample_type, view_dimension, multisampled: false },
            count: None,
        };
        let [ids, records, masks, sampler] = CUTOUT_BINDINGS;
        [
            texture(ids, wgpu::TextureSampleType::Uint, wgpu::TextureViewDimension::D2),
            texture(records, wgpu::TextureSampleType::Float { filterable: false }, wgpu::TextureViewDimension::D2),
            texture(masks, wgpu::TextureSampleType::Float { filterable: true }, wgpu::TextureViewDimension::D2Array),
            wgpu::BindGroupLayoutEntry {
                binding: sampler,
                visibility,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
        ]
    }

    /// The four bind-group entries matching [`CutoutTextures::layout_entries`].
    pub fn bind_entries(&self) -> [wgpu::BindGroupEntry<'_>; 4] {
        let [ids, records, masks, sampler] = CUTOUT_BINDINGS;
        [
            wgpu::BindGroupEntry { binding: ids, resource: wgpu::BindingResource::TextureView(&self.ids) },
            wgpu::BindGroupEntry { binding: records, resource: wgpu::BindingResource::TextureView(&self.records) },
            wgpu::BindGroupEntry { binding: masks, resource: wgpu::BindingResource::TextureView(&self.masks) },
            wgpu::BindGroupEntry { binding: sampler, resource: wgpu::BindingResource::Sampler(&self.sampler) },
        ]
    }
}

/// What a closest hit found, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    pub t: f32,
    pub position: Vec3,
    /// Geometric normal, facing the ray's origin.
    pub normal: Vec3,
    pub albedo: Vec3,
}

impl SceneBvh {
    pub fn build(
        gpu: &GpuContext,
        geometry: &ChunkedGeometry,
        material_albedo: &[Vec3],
        cutout_alpha: &[Option<CutoutAlpha>],
    ) -> SceneBvh {
        let cpu = Bvh::from_geometry(geometry);
        let triangle_material = triangle_materials(geometry);
        // One layer kept free for `array_layers`' padding.
        let max_layers = gpu.device.limits().max_texture_array_layers.saturating_sub(1);
        let cutouts = BvhCutouts::build_with(&cpu, geometry, &triangle_material, cutout_alpha, max_layers);
        let cutout_textures = CutoutTextures::new(gpu, &cutouts);
        let surfaces: Vec<BvhSurface> = cpu
            .triangles
            .iter()
            .zip(&cpu.triangle_ids)
            .map(|(t, &id)| {
                let [a, b, c] = t.vertices();
                let n = (b - a).cross(c - a).normalize_or(Vec3::Y);
                let material = triangle_material.get(id as usize).copied().unwrap_or(u32::MAX);
                let albedo = material_albedo.get(material as usize).copied().unwrap_or(Vec3::ZERO);
                BvhSurface { normal: n.extend(0.0).to_array(), albedo: albedo.extend(1.0).to_array() }
            })
            .collect();
        log::info!(
            "scene BVH: {} triangles, {} nodes, depth {}, built in {:.1} ms",
            cpu.stats.triangles,
            cpu.stats.nodes,
            cpu.stats.max_depth,
            cpu.stats.build_ms
        );
        let storage = |label, contents: &[u8]| {
            gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                // An empty scene still binds a valid (one-element) buffer.
                contents: if contents.is_empty() { &[0u8; 64] } else { contents },
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let (nodes, mut triangles) = cpu.gpu_buffers();
        // The unused w of v0, e1, e2 carry the albedo, so a hit shader reads it without another storage buffer
        // (downlevel devices allow four per stage).
        for (t, s) in triangles.iter_mut().zip(&surfaces) {
            t.v0[3] = s.albedo[0];
            t.e1[3] = s.albedo[1];
            t.e2[3] = s.albedo[2];
        }
        SceneBvh {
            nodes: storage("bvh nodes", bytemuck::cast_slice(&nodes)),
            triangles: storage("bvh triangles", bytemuck::cast_slice(&triangles)),
            surfaces,
            cutouts: if cutout_textures.enabled { cutouts } else { BvhCutouts::default() },
            cutout_textures,
            cpu,
        }
    }

    /// The BVH group's layout entries every tracer starts from: nodes (0), triangles (1) and the cut-out data
    /// ([`CUTOUT_BINDINGS`]); a pass appends its own bindings (2 to 9).
    pub fn layout_entries() -> Vec<wgpu::BindGroupLayoutEntry> {
        let mut entries = vec![crate::gpu::bind::storage_entry(0), crate::gpu::bind::storage_entry(1)];
        entries.extend(CutoutTextures::layout_entries());
        entries
    }

    /// The bind-group entries matching [`SceneBvh::layout_entries`].
    pub fn bind_entries(&self) -> Vec<wgpu::BindGroupEntry<'_>> {
        let mut entries = vec![
            wgpu::BindGroupEntry { binding: 0, resource: self.nodes.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: self.triangles.as_entire_binding() },
        ];
        entries.extend(self.cutout_textures.bind_entries());
        entries
    }

    /// Whether a surface lies on `origin + t * dir` (`dir` normalised) for `0 < t < t_max`; cut-out texels are no
    /// surface (the CPU twin of the tracers' shadow rays).
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        bvh::occluded_cpu_filtered(&self.cpu, origin, dir, t_max, &|tri, u, v| !self.cutouts.cut_out(tri, u, v))
    }

    /// Nearest surface on `origin + t * dir` (`dir` normalised) for `0 < t < t_max`; cut-out texels are no
    /// surface.
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<SurfaceHit> {
        let Hit { t, triangle, .. } = bvh::closest_hit_cpu_filtered(&self.cpu, origin, dir, t_max, &|tri, u, v| {
            !self.cutouts.cut_out(tri, u, v)
        })?;
        let s = &self.surfaces[triangle as usize];
        let n = Vec3::from_slice(&s.normal[..3]);
        Some(SurfaceHit {
            t,
            position: origin + dir * t,
            normal: if n.dot(dir) > 0.0 { -n } else { n },
            albedo: Vec3::from_slice(&s.albedo[..3]),
        })
    }
}

/// The layer count of a texture seen as a `D2Array` that holds `n` layers. GL cannot be told a texture's view
/// dimension and guesses it from the layers (wgpu-hal's heuristics): one layer is a plain 2D texture, six a
/// cube map, a larger multiple of six a cube array, and a `D2Array` view of those samples nothing. So a lone
/// layer gets a second, and a multiple of six one more (the extra layers are never read).
pub fn array_layers(n: u32) -> u32 {
    match n {
        0 | 1 => 2,
        n if n % 6 == 0 => n + 1,
        n => n,
    }
}

#[cfg(test)]
mod array_layer_tests {
    use super::array_layers;

    #[test]
    fn array_layers_are_never_what_gl_takes_for_a_2d_texture_a_cube_or_a_cube_array() {
        for n in 0..100 {
            let l = array_layers(n);
            assert!(l >= n.max(1), "{n} layers need room: {l}");
            assert!(l > 1 && !l.is_multiple_of(6), "{n} -> {l}: GL would guess a 2D texture, a cube or a cube array");
            assert!(l <= n + 2, "{n} -> {l}: at most one layer more (two for none)");
        }
    }
}
