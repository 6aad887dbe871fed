//! The GPU side the two ISM techniques share ([`IsmMaps`]): the point pool on the GPU, the views of a batch of
//! maps, the depth pyramid and the atlas, and one function per pass: clear, splat (step 2), pull and push
//! (step 3), resolve into the atlas. The shading (step 4) is the technique's: `shade.wgsl` through a
//! [`ShadePass`](crate::services::shade_pass::ShadePass) for lights, the shared VPL gather for VPLs.

use std::sync::Arc;

use glam::Vec3;

use super::points::{pool_size, sample_points};
use super::pull_push::{level_resolution, usable_levels, MAX_LEVELS};
use crate::accel::gpu_scene::GpuScene;
use crate::error::GpuError;
use crate::gpu::bind::{storage_entry, storage_rw_entry, uniform_entry};
use crate::gpu::buffer::GrowableBuffer;
use crate::gpu::pipeline::create_module;
use crate::gpu::GpuContext;
use crate::services::cube_shadows::{CubeAtlas, TileProjection};
use crate::timing::PassTimer;

/// Its WGSL modules (listed by the technique's `SHADERS`).
pub const SPLAT: crate::shaders::WgslModule = crate::shaders::wgsl!(
    "ism_splat",
    ["shaders/vpl_basis.wgsl", "core/src/technique/ism/paraboloid.wgsl", "core/src/technique/ism/splat.wgsl"]
);
pub const PULL_PUSH: crate::shaders::WgslModule = crate::shaders::wgsl!(
    "ism_pull_push",
    ["shaders/vpl_basis.wgsl", "core/src/technique/ism/paraboloid.wgsl", "core/src/technique/ism/pull_push.wgsl"]
);

/// The atlas format: one f32 depth per texel, written by the resolve pass as a storage texture, read by the
/// lookups with `textureLoad` and by the inspector as any depth atlas (4 bytes, 1.0 empty).
pub const ATLAS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

/// One map of a batch. Mirrors `IsmView` in `ism/paraboloid.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuIsmView {
    pub centre: [f32; 4],
    pub axis: [f32; 4],
    pub subset: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<GpuIsmView>() == 48);

impl GpuIsmView {
    /// A map centred at `centre`, facing `axis` (a dual paraboloid's upper half), depth range `near..far`,
    /// splatting `points` pool points from `first`, into tile `tile` (and `tile + 1` when `dual`).
    #[allow(clippy::too_many_arguments)]
    pub fn new(centre: Vec3, axis: Vec3, near: f32, far: f32, first: u32, points: u32, tile: u32, dual: bool) -> Self {
        GpuIsmView {
            centre: centre.extend(near).to_array(),
            axis: axis.extend(far).to_array(),
            subset: [first, points, tile, dual as u32],
        }
    }

    pub fn tiles(&self) -> usize {
        1 + (self.subset[3] != 0) as usize
    }
}

/// Mirrors `SplatParams` in `ism/splat.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct SplatUniform {
    views: u32,
    points_per_map: u32,
    pool: u32,
    resolution: u32,
}

/// Mirrors `PullPushLevel` in `ism/pull_push.wgsl`; one per dispatch, in 256-byte slots (dynamic offsets).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct LevelUniform {
    fine_res: u32,
    coarse_res: u32,
    fine_offset: u32,
    coarse_offset: u32,
    tiles: u32,
    threshold: f32,
    tiles_per_row: u32,
    _pad: u32,
}
const _: () = assert!(std::mem::size_of::<LevelUniform>() == 32);
const SLOT: u64 = 256;
/// Dispatches of one batch's hole filling: clear, `levels` pulls and pushes, resolve.
const SLOTS: u64 = 2 + 2 * MAX_LEVELS as u64;

/// How a batch's maps are made (the parameters steps 2-3 read).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapSettings {
    pub resolution: u32,
    pub points_per_map: u32,
    pub levels: u32,
    pub threshold: f32,
}

/// The point pool of a scene, on the CPU (for the overlays) and the GPU.
pub struct PointPool {
    pub points: Arc<Vec<Vec3>>,
    buffer: wgpu::Buffer,
    /// The scene geometry (by pointer), pool size and seed it was sampled for.
    key: (usize, usize, u32),
}

/// The depth pyramid and atlas of a batch of `tiles` maps of a resolution and level count.
struct Batch {
    tiles: usize,
    resolution: u32,
    levels: u32,
    pyramid: wgpu::Buffer,
    /// Texel offset of each level's first tile in `pyramid`.
    offsets: Vec<u32>,
    atlas: CubeAtlas,
    levels_group: wgpu::BindGroup,
    atlas_group: wgpu::BindGroup,
}

pub struct IsmMaps {
    splat_pipeline: wgpu::ComputePipeline,
    clear_pipeline: wgpu::ComputePipeline,
    pull_pipeline: wgpu::ComputePipeline,
    push_pipeline: wgpu::ComputePipeline,
    resolve_pipeline: wgpu::ComputePipeline,
    splat_layout: wgpu::BindGroupLayout,
    levels_layout: wgpu::BindGroupLayout,
    atlas_layout: wgpu::BindGroupLayout,
    splat_uniform: wgpu::Buffer,
    level_uniforms: wgpu::Buffer,
    views: GrowableBuffer,
    pool: Option<PointPool>,
    batch: Option<Batch>,
    splat_group: Option<wgpu::BindGroup>,
    generation: u64,
}

/// A compute pass timed by `timer` when there is one (a frame), plain otherwise (tests).
fn compute_pass(
    timer: Option<&PassTimer>,
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    record: impl FnOnce(&mut wgpu::ComputePass<'_>),
) {
    match timer {
        Some(t) => t.compute_pass(encoder, label, record),
        None => {
            let mut pass =
                encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(label), timestamp_writes: None });
            record(&mut pass);
        }
    }
}

impl IsmMaps {
    pub fn new(gpu: &GpuContext) -> IsmMaps {
        let device = &gpu.device;
        let splat_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ism splat"),
            entries: &[storage_entry(0), storage_entry(1), uniform_entry(2), storage_rw_entry(3)],
        });
        let levels_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ism pull-push"),
            entries: &[
                storage_rw_entry(0),
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<LevelUniform>() as u64),
                    },
                    count: None,
                },
            ],
        });
        let atlas_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ism atlas"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::StorageTexture {
                    access: wgpu::StorageTextureAccess::WriteOnly,
                    format: ATLAS_FORMAT,
                    view_dimension: wgpu::TextureViewDimension::D2,
                },
                count: None,
            }],
        });
        let pipeline = |module: &wgpu::ShaderModule, label: &str, entry: &str, groups: &[&wgpu::BindGroupLayout]| {
            let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().map(|g| Some(*g)).collect();
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &groups,
                immediate_size: 0,
            });
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let splat = create_module(device, SPLAT.name, SPLAT.source);
        let pull_push = create_module(device, PULL_PUSH.name, PULL_PUSH.source);
        let uniform = |label, size| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        IsmMaps {
            splat_pipeline: pipeline(&splat, "ism splat", "splat_main", &[&splat_layout]),
            clear_pipeline: pipeline(&pull_push, "ism clear", "clear_main", &[&levels_layout]),
            pull_pipeline: pipeline(&pull_push, "ism pull", "pull_main", &[&levels_layout]),
            push_pipeline: pipeline(&pull_push, "ism push", "push_main", &[&levels_layout]),
            resolve_pipeline: pipeline(&pull_push, "ism resolve", "resolve_main", &[&levels_layout, &atlas_layout]),
            splat_layout,
            levels_layout,
            atlas_layout,
            splat_uniform: uniform("ism splat", std::mem::size_of::<SplatUniform>() as u64),
            level_uniforms: uniform("ism pull-push levels", SLOTS * SLOT),
            views: GrowableBuffer::new(device, "ism views", 64 * 48),
            pool: None,
            batch: None,
            splat_group: None,
            generation: 0,
        }
    }

    /// Step 1: the scene's point pool for maps of `points_per_map` points, sampled once per scene (geometry),
    /// pool size and seed and kept; returns the milliseconds it took when it was sampled now.
    pub fn ensure_pool(&mut self, gpu: &GpuContext, scene: &GpuScene, points_per_map: u32, seed: u32) -> Option<f64> {
        let size = pool_size(points_per_map as usize);
        let key = (Arc::as_ptr(&scene.geometry) as usize, size, seed);
        if self.pool.as_ref().is_some_and(|p| p.key == key) {
            return None;
        }
        let started = std::time::Instant::now();
        let points = sample_points(&scene.geometry, &scene.cutout_alpha, size, seed);
        let data: Vec<[f32; 4]> = points.iter().map(|p| p.extend(1.0).to_array()).collect();
        // Never empty: a scene without triangles still binds a valid buffer (and splats nothing: `pool` is 0).
        let bytes: &[u8] = if data.is_empty() { &[0u8; 16] } else { bytemuck::cast_slice(&data) };
        let buffer = {
            use wgpu::util::DeviceExt;
            gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("ism point pool"),
                contents: bytes,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        self.pool = Some(PointPool { points: Arc::new(points), buffer, key });
        self.splat_group = None;
        Some(started.elapsed().as_secs_f64() * 1000.0)
    }

    /// The pool of the last [`Self::ensure_pool`].
    pub fn pool(&self) -> Option<&PointPool> {
        self.pool.as_ref()
    }

    /// Points in the pool (0 for a scene without area).
    pub fn pool_points(&self) -> usize {
        self.pool.as_ref().map_or(0, |p| p.points.len())
    }

    /// Bytes one tile of `resolution` with `levels` levels costs: the atlas texel and the pyramid's.
    fn bytes_per_tile(resolution: u32, levels: u32) -> u64 {
        let pyramid: u64 = (0..=levels).map(|l| (level_resolution(resolution, l) as u64).pow(2)).sum();
        4 * (pyramid + (resolution as u64).pow(2))
    }

    /// How many tiles of `resolution` one batch holds within `budget_bytes` and the device's limits (at least
    /// `min_tiles`, when the device allows that many at all; an error when it does not).
    pub fn tiles_per_batch(
        gpu: &GpuContext,
        resolution: u32,
        levels: u32,
        budget_bytes: u64,
        min_tiles: usize,
    ) -> Result<usize, GpuError> {
        let limits = gpu.device.limits();
        let levels = usable_levels(resolution, levels);
        let per_row = (limits.max_texture_dimension_2d / resolution.max(1)) as usize;
        let pyramid_texels: u64 = (0..=levels).map(|l| (level_resolution(resolution, l) as u64).pow(2)).sum();
        let max_buffer = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        let by_buffer = (max_buffer / (4 * pyramid_texels).max(1)) as usize;
        let by_device = (per_row * per_row).min(by_buffer).min(limits.max_compute_workgroups_per_dimension as usize);
        if by_device < min_tiles.max(1) {
            return Err(GpuError::InvalidSettings(format!(
                "ism: {min_tiles} maps of {resolution}² do not fit this device's limits (texture side {}, storage \
                 binding {} MiB): lower the resolution",
                limits.max_texture_dimension_2d,
                max_buffer >> 20
            )));
        }
        let by_budget = (budget_bytes / Self::bytes_per_tile(resolution, levels).max(1)) as usize;
        Ok(by_budget.clamp(min_tiles.max(1), by_device))
    }

    /// The pyramid and atlas for `tiles` maps of `resolution` with `levels` levels; reused when they fit.
    pub fn ensure_batch(&mut self, gpu: &GpuContext, resolution: u32, tiles: usize, levels: u32) {
        let levels = usable_levels(resolution, levels);
        if self.batch.as_ref().is_some_and(|b| b.resolution == resolution && b.tiles >= tiles && b.levels == levels) {
            return;
        }
        let device = &gpu.device;
        let tiles = tiles.max(1);
        let mut offsets = Vec::with_capacity(levels as usize + 1);
        let mut texels = 0u64;
        for l in 0..=levels {
            offsets.push(texels as u32);
            texels += tiles as u64 * (level_resolution(resolution, l) as u64).pow(2);
        }
        let pyramid = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ism depth pyramid"),
            size: (texels * 4).max(16),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let (tiles_per_row, rows) = crate::services::cube_atlas::atlas_grid(device, resolution, tiles);
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("ism atlas"),
            size: wgpu::Extent3d {
                width: tiles_per_row * resolution,
                height: rows * resolution,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: ATLAS_FORMAT,
            // COPY_SRC: the inspector and `--maps-out` read it back; the chosen map is copied out of it.
            usage: wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        let levels_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ism pull-push"),
            layout: &self.levels_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: pyramid.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &self.level_uniforms,
                        offset: 0,
                        size: wgpu::BufferSize::new(std::mem::size_of::<LevelUniform>() as u64),
                    }),
                },
            ],
        });
        let atlas_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ism atlas"),
            layout: &self.atlas_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) }],
        });
        let atlas = CubeAtlas {
            texture,
            view,
            resolution,
            tiles_per_row,
            // Not cube maps: the inspector lists tiles.
            capacity: 0,
            tiles,
            projections: vec![None; tiles],
        };
        self.batch = Some(Batch { tiles, resolution, levels, pyramid, offsets, atlas, levels_group, atlas_group });
        self.splat_group = None;
        self.generation += 1;
    }

    /// The atlas of the last batch (None before the first).
    pub fn atlas(&self) -> Option<&CubeAtlas> {
        self.batch.as_ref().map(|b| &b.atlas)
    }

    /// Changes whenever a new atlas is made, so a technique knows to rebuild the bind groups of its view.
    pub fn atlas_generation(&self) -> u64 {
        self.generation
    }

    /// Steps 2 and 3 for one batch: clear the batch's level 0, splat every view's subset, pull and push,
    /// resolve into the atlas. `views` hold at most the batch's tiles (`ensure_batch`).
    pub fn render(
        &mut self,
        gpu: &GpuContext,
        timer: Option<&PassTimer>,
        encoder: &mut wgpu::CommandEncoder,
        views: &[GpuIsmView],
        settings: MapSettings,
    ) {
        let tiles: usize = views.iter().map(|v| v.tiles()).sum();
        let pool = self.pool_points() as u32;
        if self.views.write(gpu, views) {
            self.splat_group = None;
        }
        let splat = SplatUniform {
            views: views.len() as u32,
            points_per_map: settings.points_per_map,
            pool,
            resolution: settings.resolution,
        };
        gpu.queue.write_buffer(&self.splat_uniform, 0, bytemuck::bytes_of(&splat));
        if self.splat_group.is_none() {
            let (Some(batch), Some(pool)) = (&self.batch, &self.pool) else { return };
            self.splat_group = Some(gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("ism splat"),
                layout: &self.splat_layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: pool.buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: self.views.buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 2, resource: self.splat_uniform.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 3, resource: batch.pyramid.as_entire_binding() },
                ],
            }));
        }
        let Some(batch) = self.batch.as_mut() else { return };
        assert!(tiles <= batch.tiles && batch.resolution == settings.resolution, "ensure_batch sized the batch");
        // The tiles' projections, for the inspector (a dual paraboloid's two halves share theirs).
        batch.atlas.projections.clear();
        batch.atlas.projections.resize(batch.tiles, None);
        let mut tile = 0;
        for v in views {
            let centre = Vec3::new(v.centre[0], v.centre[1], v.centre[2]);
            for _ in 0..v.tiles() {
                batch.atlas.projections[tile] =
                    Some(TileProjection::Paraboloid { centre, near: v.centre[3], far: v.axis[3] });
                tile += 1;
            }
        }
        let batch = self.batch.as_ref().expect("checked above");
        Self::encode_clear(gpu, timer, encoder, batch, tiles, &self.clear_pipeline, &self.level_uniforms);
        if pool > 0 && !views.is_empty() {
            let group = self.splat_group.as_ref().expect("made above");
            compute_pass(timer, encoder, "ism splat", |pass| {
                pass.set_pipeline(&self.splat_pipeline);
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(settings.points_per_map.div_ceil(64), views.len() as u32, 1);
            });
        }
        self.encode_pull_push(gpu, timer, encoder, tiles, settings.threshold, true);
    }

    /// Clear level 0 of the first `tiles` tiles to EMPTY (slot 0 of the level uniforms).
    fn encode_clear(
        gpu: &GpuContext,
        timer: Option<&PassTimer>,
        encoder: &mut wgpu::CommandEncoder,
        batch: &Batch,
        tiles: usize,
        pipeline: &wgpu::ComputePipeline,
        uniforms: &wgpu::Buffer,
    ) {
        let res = batch.resolution;
        let clear = LevelUniform {
            fine_res: res,
            fine_offset: batch.offsets[0],
            tiles: tiles as u32,
            tiles_per_row: batch.atlas.tiles_per_row,
            ..Default::default()
        };
        gpu.queue.write_buffer(uniforms, 0, bytemuck::bytes_of(&clear));
        compute_pass(timer, encoder, "ism clear", |pass| {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &batch.levels_group, &[0]);
            pass.dispatch_workgroups((res * res).div_ceil(64), tiles as u32, 1);
        });
    }

    /// Step 3 over the first `tiles` tiles of the pyramid: `levels` pulls, as many pushes, and (with `resolve`)
    /// level 0 into the atlas. Slots 1.. of the level uniforms.
    fn encode_pull_push(
        &self,
        gpu: &GpuContext,
        timer: Option<&PassTimer>,
        encoder: &mut wgpu::CommandEncoder,
        tiles: usize,
        threshold: f32,
        resolve: bool,
    ) {
        let Some(batch) = &self.batch else { return };
        if tiles == 0 {
            return;
        }
        let res = batch.resolution;
        let level = |fine: u32, coarse: u32| LevelUniform {
            fine_res: level_resolution(res, fine),
            coarse_res: level_resolution(res, coarse),
            fine_offset: batch.offsets[fine as usize],
            coarse_offset: batch.offsets[coarse.min(batch.levels) as usize],
            tiles: tiles as u32,
            threshold,
            tiles_per_row: batch.atlas.tiles_per_row,
            _pad: 0,
        };
        // Slot 1 + l: pull l -> l + 1; slot 1 + levels + i: the i-th push (coarsest first); then the resolve.
        let mut slots: Vec<(LevelUniform, &wgpu::ComputePipeline, &str, u32)> = Vec::new();
        for l in 0..batch.levels {
            let u = level(l, l + 1);
            slots.push((u, &self.pull_pipeline, "ism pull", u.coarse_res));
        }
        for l in (0..batch.levels).rev() {
            let u = level(l, l + 1);
            slots.push((u, &self.push_pipeline, "ism push", u.fine_res));
        }
        if resolve {
            slots.push((level(0, 0), &self.resolve_pipeline, "ism resolve", res));
        }
        let mut bytes = vec![0u8; (slots.len() as u64 * SLOT) as usize];
        for (i, (u, ..)) in slots.iter().enumerate() {
            let at = (i as u64 * SLOT) as usize;
            bytes[at..at + std::mem::size_of::<LevelUniform>()].copy_from_slice(bytemuck::bytes_of(u));
        }
        // After slot 0 (the clear's).
        gpu.queue.write_buffer(&self.level_uniforms, SLOT, &bytes);
        for (i, (_, pipeline, label, side)) in slots.iter().enumerate() {
            let offset = ((i as u64 + 1) * SLOT) as u32;
            compute_pass(timer, encoder, label, |pass| {
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &batch.levels_group, &[offset]);
                if std::ptr::eq(*pipeline, &self.resolve_pipeline) {
                    pass.set_bind_group(1, &batch.atlas_group, &[]);
                }
                pass.dispatch_workgroups((side * side).div_ceil(64), tiles as u32, 1);
            });
        }
    }

    /// The GPU twin of [`super::pull_push::pull_push`] on given maps, for tests: `maps` (each `resolution`²,
    /// [`super::pull_push::EMPTY`] for holes) through step 3 with `levels` levels and `threshold`, read back.
    pub fn pull_push_on(
        &mut self,
        gpu: &GpuContext,
        maps: &[Vec<f32>],
        resolution: u32,
        levels: u32,
        threshold: f32,
    ) -> Result<Vec<Vec<f32>>, GpuError> {
        let n = (resolution as usize).pow(2);
        if maps.iter().any(|m| m.len() != n) || resolution == 0 {
            return Err(GpuError::InvalidSettings(format!("pull_push_on: maps must be {resolution}² texels")));
        }
        self.ensure_batch(gpu, resolution, maps.len(), levels);
        let batch = self.batch.as_ref().expect("made above");
        let level0: Vec<f32> = maps.iter().flatten().copied().collect();
        gpu.queue.write_buffer(&batch.pyramid, 0, bytemuck::cast_slice(&level0));
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        self.encode_pull_push(gpu, None, &mut encoder, maps.len(), threshold, false);
        gpu.queue.submit([encoder.finish()]);
        let bytes = crate::gpu::readback::read_buffer(gpu, &batch.pyramid)?;
        let texels: &[f32] = bytemuck::cast_slice(&bytes[..level0.len() * 4]);
        Ok(texels.chunks(n).map(|c| c.to_vec()).collect())
    }
}
