//! Tiled light lists, a renderer service (after Olsson and Assarsson 2011's tiled shading, with per-tile depth
//! bounds as in Olsson et al. 2012): once per frame, after the G-buffer, a compute pass bins spheres (the
//! visible lights' range spheres, or a technique's own, e.g. clusters' `C_att`) into 16x16-pixel screen tiles,
//! and every shading pass loops over its pixel's tile list intersected with its batch, instead of over the
//! whole batch.
//!
//! 1. Per tile, the world-space box of its geometry pixels, from the G-buffer depth (`light_tiles_build.wgsl`).
//! 2. Per tile, the spheres that touch the box (with a margin for rounding) and whose range of distances to the
//!    camera meets one of the 32 distance bins the tile's pixels occupy (2.5D culling), in sphere order, up to
//!    `capacity` (at most [`ITEM_BUDGET_BYTES`] for the whole screen); a tile with more loops over every sphere.
//! 3. A shading pass binds [`TileLists::bind_group`] as its group 2 and calls `tile_span` / `tile_item`
//!    (`light_tiles.wgsl`): a binary search for the batch's first and last index in the sorted list.
//!
//! The image does not change: a sphere not in a pixel's list cannot reach the pixel, so the pixel only skips
//! terms that are exactly zero, and the others are summed in the same order (tested bit for bit in
//! `core/tests/light_tiles.rs`). `RenderSettings::light_tiles` off skips the build and
//! makes every span the whole batch.

use wgpu::util::DeviceExt;

use crate::gpu::bind::{storage_entry, storage_rw_entry, uniform_entry};
use crate::gpu::buffer::GrowableBuffer;
use crate::gpu::GpuContext;
use crate::shaders;
use crate::timing::PassTimer;

/// Pixels per tile side (`TILE_SIZE` in the WGSL files).
pub const TILE_SIZE: u32 = 16;
/// The most memory the lists of one screen may take; a tile's capacity is this divided by the tile count.
pub const ITEM_BUDGET_BYTES: u64 = 32 << 20;
/// A tile's count when its list overflowed (`TILE_OVERFLOW`).
pub const TILE_OVERFLOW: u32 = u32::MAX;

/// Mirrors `TileGrid` in `light_tiles.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct TileGridUniform {
    tiles_x: u32,
    tiles_y: u32,
    capacity: u32,
    enabled: u32,
}
const _: () = assert!(std::mem::size_of::<TileGridUniform>() == 16);

/// Mirrors `TileBuild` in `light_tiles_build.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct TileBuildUniform {
    tiles_x: u32,
    tiles_y: u32,
    capacity: u32,
    sphere_count: u32,
}
const _: () = assert!(std::mem::size_of::<TileBuildUniform>() == 16);

/// The layout of group 2 of the shading passes that read tile lists (`light_tiles.wgsl`).
pub fn read_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("light tiles (read)"),
        entries: &[uniform_entry(0), storage_entry(1)],
    })
}

/// Tiles and their capacity for a `width x height` screen, `spheres` spheres and lists of at most
/// `budget_bytes` in all (a tile holds at least 16).
pub fn grid(width: u32, height: u32, spheres: usize, budget_bytes: u64) -> (u32, u32, u32) {
    let tiles_x = width.div_ceil(TILE_SIZE).max(1);
    let tiles_y = height.div_ceil(TILE_SIZE).max(1);
    let tiles = tiles_x as u64 * tiles_y as u64;
    let by_budget = (budget_bytes / 4 / tiles).max(16);
    let capacity = (spheres as u64).clamp(1, by_budget) as u32;
    (tiles_x, tiles_y, capacity)
}

/// One set of tile lists (the renderer's of the visible lights, or a technique's of its own spheres).
pub struct TileLists {
    pipeline: wgpu::ComputePipeline,
    build_layout: wgpu::BindGroupLayout,
    build_uniform: wgpu::Buffer,
    grid_uniform: wgpu::Buffer,
    spheres: GrowableBuffer,
    /// Per tile its count, then per tile `capacity` item slots (`tile_lists` in the WGSL files).
    lists: wgpu::Buffer,
    build_group: wgpu::BindGroup,
    read_group: wgpu::BindGroup,
    /// (tiles_x, tiles_y, capacity) of the last build; capacity 0 when disabled.
    grid: (u32, u32, u32),
    item_budget_bytes: u64,
}

impl TileLists {
    /// `read_layout` is [`crate::services::layouts::SharedLayouts::light_tiles`].
    pub fn new(gpu: &GpuContext, screen_layout: &wgpu::BindGroupLayout, read_layout: &wgpu::BindGroupLayout) -> Self {
        let device = &gpu.device;
        let build_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("light tiles (build)"),
            entries: &[uniform_entry(0), storage_entry(1), storage_rw_entry(2)],
        });
        let module =
            crate::gpu::pipeline::create_module(device, "light_tiles_build", shaders::LIGHT_TILES_BUILD.source);
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("light tiles"),
            bind_group_layouts: &[Some(screen_layout), Some(&build_layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("light tiles"),
            layout: Some(&layout),
            module: &module,
            entry_point: Some("build_main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let uniform = |label, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            })
        };
        let zero = [0u8; 16];
        let build_uniform = uniform("light tiles build", &zero);
        let grid_uniform = uniform("light tiles grid", &zero);
        let spheres = GrowableBuffer::new(device, "light tile spheres", 16 * 64);
        let lists = Self::list_buffer(device, "light tile lists", 16);
        let build_group = Self::make_build_group(device, &build_layout, &build_uniform, &spheres.buffer, &lists);
        let read_group = Self::make_read_group(device, read_layout, &grid_uniform, &lists);
        TileLists {
            pipeline,
            build_layout,
            build_uniform,
            grid_uniform,
            spheres,
            lists,
            build_group,
            read_group,
            grid: (1, 1, 0),
            item_budget_bytes: ITEM_BUDGET_BYTES,
        }
    }

    fn list_buffer(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: size.max(16),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    }

    fn make_build_group(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        uniform: &wgpu::Buffer,
        spheres: &wgpu::Buffer,
        lists: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("light tiles (build)"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: spheres.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: lists.as_entire_binding() },
            ],
        })
    }

    fn make_read_group(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        uniform: &wgpu::Buffer,
        lists: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("light tiles (read)"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: lists.as_entire_binding() },
            ],
        })
    }

    /// Group 2 of a shading pass that reads these lists.
    pub fn bind_group(&self) -> &wgpu::BindGroup {
        &self.read_group
    }

    /// Steps 1-2: bin `spheres` (xyz centre, w radius, in the order the shading passes index them) into the
    /// tiles of a `size` screen, reading the G-buffer depth through `screen_bind_group`. With `enabled` false
    /// (or no spheres) nothing is encoded and every span is the whole batch.
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        &mut self,
        gpu: &GpuContext,
        read_layout: &wgpu::BindGroupLayout,
        screen_bind_group: &wgpu::BindGroup,
        timer: &PassTimer,
        encoder: &mut wgpu::CommandEncoder,
        size: (u32, u32),
        spheres: &[[f32; 4]],
        enabled: bool,
    ) {
        let (tiles_x, tiles_y, capacity) = grid(size.0, size.1, spheres.len(), self.item_budget_bytes);
        if !enabled || spheres.is_empty() {
            self.grid = (tiles_x, tiles_y, 0);
            let uniform = TileGridUniform { tiles_x, tiles_y, capacity: 0, enabled: 0 };
            gpu.queue.write_buffer(&self.grid_uniform, 0, bytemuck::bytes_of(&uniform));
            return;
        }
        let tiles = tiles_x as u64 * tiles_y as u64;
        let mut rebind = self.spheres.write(gpu, spheres);
        let bytes = tiles * (1 + capacity as u64) * 4;
        if self.lists.size() < bytes {
            self.lists = Self::list_buffer(&gpu.device, "light tile lists", bytes.next_power_of_two());
            rebind = true;
        }
        if rebind {
            let device = &gpu.device;
            self.build_group = Self::make_build_group(
                device,
                &self.build_layout,
                &self.build_uniform,
                &self.spheres.buffer,
                &self.lists,
            );
            self.read_group = Self::make_read_group(device, read_layout, &self.grid_uniform, &self.lists);
        }
        self.grid = (tiles_x, tiles_y, capacity);
        let build = TileBuildUniform { tiles_x, tiles_y, capacity, sphere_count: spheres.len() as u32 };
        gpu.queue.write_buffer(&self.build_uniform, 0, bytemuck::bytes_of(&build));
        let uniform = TileGridUniform { tiles_x, tiles_y, capacity, enabled: 1 };
        gpu.queue.write_buffer(&self.grid_uniform, 0, bytemuck::bytes_of(&uniform));
        let (pipeline, group) = (&self.pipeline, &self.build_group);
        timer.compute_pass(encoder, "light tiles", |pass| {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, screen_bind_group, &[]);
            pass.set_bind_group(1, group, &[]);
            pass.dispatch_workgroups(tiles_x, tiles_y, 1);
        });
    }

    /// Limit the memory of all lists (default [`ITEM_BUDGET_BYTES`]); a smaller budget makes more tiles
    /// overflow (for tests of that path).
    pub fn set_item_budget(&mut self, bytes: u64) {
        self.item_budget_bytes = bytes;
    }

    /// (tiles_x, tiles_y, capacity) of the last build; capacity 0 when no lists were built.
    pub fn grid(&self) -> (u32, u32, u32) {
        self.grid
    }

    /// The lists of the last build, read back (blocking): per tile `None` when it overflowed, else its
    /// sphere indices. Empty when no lists were built. For tests and statistics.
    pub fn read(&self, gpu: &GpuContext) -> Result<Vec<Option<Vec<u32>>>, crate::error::GpuError> {
        let (tiles_x, tiles_y, capacity) = self.grid;
        if capacity == 0 {
            return Ok(Vec::new());
        }
        let bytes = crate::gpu::readback::read_buffer(gpu, &self.lists)?;
        let lists: &[u32] = bytemuck::cast_slice(&bytes);
        let tiles = (tiles_x * tiles_y) as usize;
        Ok((0..tiles)
            .map(|t| {
                let n = lists[t];
                (n != TILE_OVERFLOW).then(|| {
                    let base = tiles + t * capacity as usize;
                    lists[base..base + n as usize].to_vec()
                })
            })
            .collect())
    }
}
