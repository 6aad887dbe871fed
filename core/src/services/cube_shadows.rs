//! Rendering cube shadow maps into a reused depth atlas, with per-light and per-face chunk culling.
//!
//! Shared by every technique that renders cube maps (the reference per light, LightCluster per cluster, INSM per
//! light from its reconstructed meshes). What is drawn is a [`CubeGeometry`] (`cube_geometry.rs`): a vertex and an
//! index buffer cut into chunks with bounds, which is the scene's geometry for most techniques; the culled draw
//! lists of a pass are built in `cube_draws.rs`.
//! A batch of up to `capacity` cube maps is drawn in a single render pass: each face is a square tile of the
//! atlas, selected with a viewport; clip-space clipping keeps triangles inside their tile. The atlas is
//! reused batch after batch, so memory depends on the batch size, never on the number of lights.
//!
//! Culling (lavapipe is vertex-bound, so triangles are what costs):
//! 1. a chunk is drawn for a caster only if its bounds touch the caster's range sphere,
//! 2. and for a face only if its bounds touch the face's 90 degree pyramid,
//! 3. and, with [`CubeGeometry::receivers`], only if they touch the box of the caster and the receivers its
//!    lookups reach (receiver-aware caster culling, exact).

use glam::Vec3;

pub use super::cube_atlas::{CubeAtlas, CubeStats, DistanceReader, TileProjection};
use super::cube_draws::{push_tile, DrawLists, TileScratch};
pub use super::cube_geometry::{receiver_bounds, CubeGeometry, Cutouts, MapGeometry};
use super::gpu_data::MatrixUniform;
use crate::gpu::GpuContext;
use crate::math::{Aabb, CUBE_FACES};
use crate::scene::chunks::Chunk;
use crate::shaders;
use crate::timing::PassTimer;

mod pipelines;

pub const SHADOW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Default memory for one batch's atlas. 128 MiB holds 85 cube maps at 256 texels per face, 5 at 1024.
pub const DEFAULT_ATLAS_BUDGET_BYTES: u64 = 128 << 20;
/// Upper bound of cube maps per batch (the per-face matrix buffer is sized for it).
pub const MAX_CUBES_PER_BATCH: usize = 256;

/// One cube map to render: its centre and depth range.
#[derive(Clone, Copy, Debug)]
pub struct CubeCaster {
    pub position: Vec3,
    pub near: f32,
    pub far: f32,
    /// How far from a receiver its lookups into this map reach, in world units (normal offset, filter taps,
    /// PCSS's search): receiver-aware culling keeps every chunk that far around the receivers.
    pub lookup_radius: f32,
}

impl CubeCaster {
    /// A hard-shadow lookup's reach: `normal_offset_texels` plus two texels of a `resolution`-texel face at the
    /// range `far`, plus the depth bias.
    pub fn hard_lookup_radius(far: f32, resolution: u32, normal_offset_texels: f32, bias_world: f32) -> f32 {
        (normal_offset_texels.max(0.0) + 2.0) * 2.0 * far / resolution.max(1) as f32 + bias_world.max(0.0)
    }
}

/// One paraboloid shadow map to render (a VPL's hemisphere): its centre, the direction it faces and its depth
/// range.
#[derive(Clone, Copy, Debug)]
pub struct ParaboloidCaster {
    pub centre: Vec3,
    pub normal: Vec3,
    pub near: f32,
    pub far: f32,
}

/// Mirrors `ParaboloidView` in `paraboloid_depth.wgsl`, padded to a 256-byte slot like [`MatrixUniform`].
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ParaboloidView {
    centre: [f32; 4],
    normal: [f32; 4],
    _pad: [[f32; 4]; 14],
}
const _: () = assert!(std::mem::size_of::<ParaboloidView>() == std::mem::size_of::<MatrixUniform>());

pub struct CubeShadowRenderer {
    pipeline: wgpu::RenderPipeline,
    /// Paraboloid depth pipeline, created on first use.
    paraboloid_pipeline: Option<wgpu::RenderPipeline>,
    /// Alpha-tested variants (cube faces and views, paraboloids), created when cut-out chunks are first drawn.
    masked_pipeline: Option<wgpu::RenderPipeline>,
    paraboloid_masked_pipeline: Option<wgpu::RenderPipeline>,
    faces_layout: wgpu::BindGroupLayout,
    vertex_stride: u64,
    faces: wgpu::Buffer,
    faces_bind_group: wgpu::BindGroup,
    atlas: Option<CubeAtlas>,
    /// Chunks within the current caster's range (the cube faces' candidates).
    visible: Vec<u32>,
    scratch: TileScratch,
}

impl CubeShadowRenderer {
    /// A renderer for the scene's geometry ([`GpuScene::cube_geometry`]).
    pub fn new(gpu: &GpuContext) -> CubeShadowRenderer {
        Self::with_vertex_stride(gpu, std::mem::size_of::<crate::scene::chunks::Vertex>() as u64)
    }

    /// A renderer for geometry whose vertices are `vertex_stride` bytes with the position first.
    pub fn with_vertex_stride(gpu: &GpuContext, vertex_stride: u64) -> CubeShadowRenderer {
        Self::with_layout(gpu, vertex_stride, false)
    }

    /// A renderer for geometry whose 16-byte vertices are a position and an inverse view depth, each vertex
    /// pushed away from the cube's centre by [`CubeGeometry::push_per_depth`] times its view depth
    /// (`vs_pushed` in `shadow_depth.wgsl`; INSM's meshes). Cube maps only.
    pub fn with_pushed_vertices(gpu: &GpuContext) -> CubeShadowRenderer {
        Self::with_layout(gpu, 16, true)
    }

    /// Render `geometry` into one paraboloid map per caster, tiles `first_tile + i` of the atlas (sized by
    /// `ensure_tiles`), in one render pass named `label` that clears the atlas first. With `geometry.cull` a chunk
    /// is drawn for a caster only if its bounds reach into the caster's front half-space within `far`.
    #[allow(clippy::too_many_arguments)]
    pub fn render_paraboloids(
        &mut self,
        gpu: &GpuContext,
        geometry: CubeGeometry<'_>,
        timer: &PassTimer,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        casters: &[ParaboloidCaster],
        first_tile: usize,
    ) -> CubeStats {
        let atlas = self.atlas.as_ref().expect("ensure_tiles before render_paraboloids");
        let r = atlas.resolution as u64;
        assert!(first_tile + casters.len() <= atlas.tiles && first_tile + casters.len() <= MAX_CUBES_PER_BATCH * 6);
        if self.paraboloid_pipeline.is_none() {
            let module =
                crate::gpu::pipeline::create_module(&gpu.device, "paraboloid_depth", shaders::PARABOLOID_DEPTH.source);
            self.paraboloid_pipeline = Some(Self::depth_pipeline(
                &gpu.device,
                &self.faces_layout,
                &module,
                self.vertex_stride,
                "paraboloid depth",
                true,
            ));
        }
        let views: Vec<ParaboloidView> = casters
            .iter()
            .map(|c| ParaboloidView {
                centre: c.centre.extend(c.near).to_array(),
                normal: c.normal.extend(c.far).to_array(),
                _pad: [[0.0; 4]; 14],
            })
            .collect();
        let offset = (first_tile * std::mem::size_of::<MatrixUniform>()) as u64;
        gpu.queue.write_buffer(&self.faces, offset, bytemuck::cast_slice(&views));
        let projections =
            casters.iter().map(|c| TileProjection::Paraboloid { centre: c.centre, near: c.near, far: c.far });
        // The paraboloid pass clears the atlas (`record(.., true)` below).
        self.atlas.as_mut().expect("checked above").record_projections(true, first_tile, projections);
        self.ensure_masked(gpu, &geometry, true);
        let mut stats =
            CubeStats { cubes: casters.len(), texels_written: casters.len() as u64 * r * r, ..Default::default() };
        let mut lists = DrawLists::default();
        let all = 0..geometry.chunks.len() as u32;
        for (i, c) in casters.iter().enumerate() {
            let keep = |chunk: &Chunk| {
                !geometry.cull
                    || (in_front_of(&chunk.bounds, c.centre, c.normal)
                        && chunk.bounds.intersects_sphere(c.centre, c.far))
            };
            push_tile(&mut lists, &mut self.scratch, &geometry, first_tile + i, all.clone(), keep, &mut stats);
        }
        let pipeline = self.paraboloid_pipeline.as_ref().expect("created above");
        let masked = self.paraboloid_masked_pipeline.as_ref();
        self.record(pipeline, masked, geometry, timer, encoder, label, &lists, true);
        stats
    }

    /// How many cube maps of `resolution` texels per face one batch holds within `budget_bytes`.
    pub fn batch_capacity(gpu: &GpuContext, resolution: u32, budget_bytes: u64) -> usize {
        let tiles_per_row = (gpu.device.limits().max_texture_dimension_2d / resolution.max(1)).max(1) as usize;
        let by_size = tiles_per_row * tiles_per_row / 6;
        let bytes_per_cube = 6 * (resolution as u64) * (resolution as u64) * 4;
        let by_budget = (budget_bytes / bytes_per_cube.max(1)) as usize;
        by_size.min(by_budget).clamp(1, MAX_CUBES_PER_BATCH)
    }

    /// The atlas of the last `render` call.
    pub fn atlas(&self) -> Option<&CubeAtlas> {
        self.atlas.as_ref()
    }

    /// Make sure the atlas holds `cubes` cube maps of `resolution`; reuses it when it is big enough.
    /// Returns true when a new atlas was created (bind groups that use its view must be rebuilt).
    pub fn ensure_atlas(&mut self, gpu: &GpuContext, resolution: u32, cubes: usize) -> bool {
        self.ensure_tiles(gpu, resolution, cubes * 6)
    }

    /// Make sure the atlas holds `tiles` square tiles of `resolution` (for [`Self::render_views`]).
    pub fn ensure_tiles(&mut self, gpu: &GpuContext, resolution: u32, tiles: usize) -> bool {
        if let Some(a) = &self.atlas {
            if a.resolution == resolution && a.tiles >= tiles {
                return false;
            }
        }
        let (tiles_per_row, rows) = super::cube_atlas::atlas_grid(&gpu.device, resolution, tiles);
        let tiles = tiles.max(1) as u32;
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("cube shadow atlas"),
            size: wgpu::Extent3d {
                width: tiles_per_row * resolution,
                height: rows * resolution,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: SHADOW_FORMAT,
            // COPY_SRC: the atlas can be saved for inspection (`shadowlab render --maps-out`).
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        let tiles = tiles as usize;
        let projections = vec![None; tiles];
        self.atlas =
            Some(CubeAtlas { texture, view, resolution, tiles_per_row, capacity: tiles / 6, tiles, projections });
        true
    }

    /// Render `geometry` seen through each of `views` (clip-from-world matrices of square images) into atlas tiles
    /// `first_tile + i`, chunks culled against each view's frustum, in one render pass named `label`. With `clear`
    /// the whole atlas is cleared first; without, the other tiles keep what earlier passes drew (so views can be
    /// rendered one step at a time). `ensure_tiles` must have sized the atlas.
    #[allow(clippy::too_many_arguments)]
    pub fn render_views(
        &mut self,
        gpu: &GpuContext,
        geometry: CubeGeometry<'_>,
        timer: &PassTimer,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        views: &[glam::Mat4],
        first_tile: usize,
        clear: bool,
    ) -> CubeStats {
        let atlas = self.atlas.as_ref().expect("ensure_tiles before render_views");
        let r = atlas.resolution as u64;
        assert!(first_tile + views.len() <= atlas.tiles && first_tile + views.len() <= MAX_CUBES_PER_BATCH * 6);
        let matrices: Vec<MatrixUniform> = views.iter().map(|m| MatrixUniform::new(*m)).collect();
        let projections = views.iter().map(|&clip_from_world| TileProjection::Perspective { clip_from_world });
        self.atlas.as_mut().expect("checked above").record_projections(clear, first_tile, projections);
        let offset = (first_tile * std::mem::size_of::<MatrixUniform>()) as u64;
        gpu.queue.write_buffer(&self.faces, offset, bytemuck::cast_slice(&matrices));
        self.ensure_masked(gpu, &geometry, false);
        let mut stats = CubeStats { texels_written: views.len() as u64 * r * r, ..Default::default() };
        let mut lists = DrawLists::default();
        let all = 0..geometry.chunks.len() as u32;
        for (vi, m) in views.iter().enumerate() {
            let frustum = crate::math::Frustum::from_clip_from_world(m);
            let keep = |chunk: &Chunk| frustum.intersects_aabb(&chunk.bounds);
            push_tile(&mut lists, &mut self.scratch, &geometry, first_tile + vi, all.clone(), keep, &mut stats);
        }
        let masked = self.masked_pipeline.as_ref();
        self.record(&self.pipeline, masked, geometry, timer, encoder, label, &lists, clear);
        stats
    }

    /// Render `geometry` for `casters` into tiles `6*i .. 6*i+6` of the atlas (which `ensure_atlas` must have
    /// sized), in one render pass named `label`; chunks culled per caster and face when `geometry.cull`.
    pub fn render(
        &mut self,
        gpu: &GpuContext,
        geometry: CubeGeometry<'_>,
        timer: &PassTimer,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        casters: &[CubeCaster],
    ) -> CubeStats {
        let cull = geometry.cull;
        let atlas = self.atlas.as_ref().expect("ensure_atlas before render");
        assert!(casters.len() <= atlas.capacity && casters.len() <= MAX_CUBES_PER_BATCH);
        let clip_from_world: Vec<glam::Mat4> = casters
            .iter()
            .flat_map(|c| CUBE_FACES.iter().map(|f| f.clip_from_world(c.position, c.near, c.far)))
            .collect();
        let eyes = casters.iter().flat_map(|c| [c.position.extend(geometry.push_per_depth).to_array(); 6]);
        let matrices: Vec<MatrixUniform> = clip_from_world
            .iter()
            .zip(eyes)
            .map(|(m, eye_push)| MatrixUniform { eye_push, ..MatrixUniform::new(*m) })
            .collect();
        gpu.queue.write_buffer(&self.faces, 0, bytemuck::cast_slice(&matrices));
        let projections =
            clip_from_world.iter().map(|&clip_from_world| TileProjection::Perspective { clip_from_world });
        self.atlas.as_mut().expect("checked above").record_projections(true, 0, projections);

        // Culling on the CPU, draw lists per face.
        self.ensure_masked(gpu, &geometry, false);
        let r = self.atlas.as_ref().map_or(0, |a| a.resolution as u64);
        let mut stats =
            CubeStats { cubes: casters.len(), texels_written: casters.len() as u64 * 6 * r * r, ..Default::default() };
        let mut lists = DrawLists::default();
        for (ci, caster) in casters.iter().enumerate() {
            // A chunk outside the caster's range sphere, or outside the box of the caster and the receivers in
            // its range, is culled for all six faces at once.
            let hull = geometry.receivers.map(|r| {
                let range = Aabb { min: caster.position - caster.far, max: caster.position + caster.far };
                let seen = r.intersection(&range);
                let reach = Vec3::splat(caster.lookup_radius.max(0.0));
                let looked_up = Aabb { min: seen.min - reach, max: seen.max + reach };
                (!seen.is_empty()).then(|| looked_up.union(&Aabb { min: caster.position, max: caster.position }))
            });
            self.visible.clear();
            self.visible.extend(
                geometry
                    .chunks
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| {
                        !cull
                            || (c.bounds.intersects_sphere(caster.position, caster.far)
                                && hull.is_none_or(|h| h.is_some_and(|h| c.bounds.intersects(&h))))
                    })
                    .map(|(i, _)| i as u32),
            );
            for (fi, face) in CUBE_FACES.iter().enumerate() {
                let keep = |c: &Chunk| !cull || face.intersects_aabb(caster.position, &c.bounds);
                let candidates = self.visible.iter().copied();
                push_tile(&mut lists, &mut self.scratch, &geometry, ci * 6 + fi, candidates, keep, &mut stats);
            }
        }

        let masked = self.masked_pipeline.as_ref();
        self.record(&self.pipeline, masked, geometry, timer, encoder, label, &lists, true);
        stats
    }

    /// One depth pass over the atlas (cleared first when `clear`): for each `(tile, first range, range count)` of
    /// `draws`, the ranges `all_ranges[first..first + count]` drawn with tile `tile`'s matrix and viewport.
    #[allow(clippy::too_many_arguments)]
    fn record(
        &self,
        pipeline: &wgpu::RenderPipeline,
        masked_pipeline: Option<&wgpu::RenderPipeline>,
        geometry: CubeGeometry<'_>,
        timer: &PassTimer,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        lists: &DrawLists,
        clear: bool,
    ) {
        let (draws, all_ranges, all_masked) = (&lists.draws, &lists.ranges, &lists.masked);
        let atlas = self.atlas.as_ref().expect("the atlas exists when recording");
        let res = atlas.resolution;
        let tiles_per_row = atlas.tiles_per_row;
        let bind_group = &self.faces_bind_group;
        timer.render_pass(
            encoder,
            label,
            wgpu::RenderPassDescriptor {
                label: None,
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &atlas.view,
                    depth_ops: Some(wgpu::Operations {
                        load: if clear { wgpu::LoadOp::Clear(1.0) } else { wgpu::LoadOp::Load },
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            },
            |pass| {
                pass.set_pipeline(pipeline);
                pass.set_vertex_buffer(0, geometry.vertex_buffer.slice(..));
                pass.set_index_buffer(geometry.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
                for d in draws {
                    let (tile, first, count) = (d.tile, d.first, d.count);
                    if count == 0 && d.masked == 0 {
                        continue;
                    }
                    let x = (tile % tiles_per_row) * res;
                    let y = (tile / tiles_per_row) * res;
                    pass.set_viewport(x as f32, y as f32, res as f32, res as f32, 0.0, 1.0);
                    pass.set_scissor_rect(x, y, res, res);
                    let offset = tile * std::mem::size_of::<MatrixUniform>() as u32;
                    pass.set_bind_group(0, bind_group, &[offset]);
                    for &(first_index, index_count) in &all_ranges[first..first + count] {
                        pass.draw_indexed(first_index..first_index + index_count, 0, 0..1);
                    }
                    // Cut-out chunks: alpha-tested, one draw each with its material.
                    if let (Some(masked), Some(cutouts), true) = (masked_pipeline, geometry.cutouts, d.masked > 0) {
                        pass.set_pipeline(masked);
                        for &id in &all_masked[d.first_masked..d.first_masked + d.masked] {
                            let chunk = &geometry.chunks[id as usize];
                            let Some(group) = cutouts.bind_groups.get(chunk.material as usize) else { continue };
                            pass.set_bind_group(1, group, &[]);
                            pass.draw_indexed(chunk.first_index..chunk.first_index + chunk.index_count, 0, 0..1);
                        }
                        pass.set_pipeline(pipeline);
                    }
                }
            },
        );
    }
}

/// True when some corner of `b` lies in front of the plane through `p` with normal `n`.
fn in_front_of(b: &crate::scene::Aabb, p: Vec3, n: Vec3) -> bool {
    // The corner furthest along n.
    let corner = Vec3::select(n.cmpge(Vec3::ZERO), b.max, b.min);
    (corner - p).dot(n) > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Project a world point through a tile's projection into its texel and depth, as the depth pass does.
    fn texel_and_depth(clip_from_world: glam::Mat4, p: Vec3, resolution: u32) -> (u32, u32, f32) {
        let clip = clip_from_world * p.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        let u = ((ndc.x * 0.5 + 0.5) * resolution as f32) as u32;
        let v = ((0.5 - ndc.y * 0.5) * resolution as f32) as u32;
        (u, v, ndc.z)
    }

    #[test]
    fn a_cube_faces_depth_reads_back_as_the_distance_from_the_light() {
        let light = Vec3::new(0.3, 1.2, -0.4);
        let (near, far, r) = (0.05, 6.0, 256);
        // A point seen by each face, off the face's axis (the distance is radial, not along the axis).
        for (fi, face) in CUBE_FACES.iter().enumerate() {
            let right = face.forward.cross(face.up);
            let p = light + face.forward * 2.5 + right * 0.9 - face.up * 0.6;
            let m = face.clip_from_world(light, near, far);
            let (u, v, depth) = texel_and_depth(m, p, r);
            let projection = TileProjection::Perspective { clip_from_world: m };
            let d = projection.distance(u, v, r, depth).unwrap();
            // The texel's centre is up to half a texel off the point: 2.5 / 128 * 1.4 of the distance at most.
            assert!((d - p.distance(light)).abs() < 0.02, "face {fi}: {d} vs {}", p.distance(light));
            assert!(projection.eye().distance(light) < 1e-4, "face {fi}: eye {}", projection.eye());
            assert_eq!(projection.distance(u, v, r, 1.0), None, "an empty texel has no distance");
        }
        let paraboloid = TileProjection::Paraboloid { centre: light, near: 0.1, far: 4.1 };
        assert_eq!(paraboloid.distance(3, 4, r, 0.25), Some(1.1));
        assert_eq!(paraboloid.eye(), light);
    }
}
