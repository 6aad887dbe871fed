//! Rendering cube shadow maps into a reused depth atlas, with per-light and per-face chunk culling.
//!
//! Shared by every technique that renders cube maps (the reference per light, LightCluster per cluster, INSM per
//! light from its reconstructed meshes). What is drawn is a [`CubeGeometry`]: a vertex and an index buffer cut into
//! chunks with bounds, which is the scene's geometry for most techniques.
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
use super::gpu_data::MatrixUniform;
use crate::accel::gpu_scene::{GpuProxy, GpuScene};
use crate::gpu::GpuContext;
use crate::math::{Aabb, CUBE_FACES};
use crate::scene::chunks::{merge_draw_ranges, Chunk};
use crate::scene::proxy::ProxyParams;
use crate::shaders;
use crate::timing::{PassTime, PassTimer};

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

/// Geometry drawn into cube maps: positions (`Float32x3` at offset 0 of each `vertex_stride`-byte vertex), `u32`
/// indices, and chunks (index ranges with bounds) for culling.
#[derive(Clone, Copy)]
pub struct CubeGeometry<'a> {
    pub vertex_buffer: &'a wgpu::Buffer,
    pub index_buffer: &'a wgpu::Buffer,
    pub chunks: &'a [Chunk],
    /// Triangles of all chunks, for the culled count.
    pub triangle_count: u64,
    /// Cull chunks per caster (range sphere) and per face (pyramid); false draws every chunk into every face.
    pub cull: bool,
    /// The materials of geometry that has them (the scene's; None for INSM's meshes): chunks of a cut-out
    /// material are drawn alpha-tested, so leaves cast leaf-shaped shadows.
    pub cutouts: Option<Cutouts<'a>>,
    /// The bounds of every point the maps are looked up from this frame ([`receiver_bounds`]; with `cull`).
    /// Receiver-aware caster culling: a shadow ray from a receiver `r` to a caster's centre `c` lies in the
    /// convex hull of `c` and the receivers within its range, so a chunk outside the box of `c` and those
    /// receivers occludes nothing that is looked up, and is not drawn (exact: the images do not change). A
    /// caster with no receiver in its range draws nothing. None: every chunk in range (maps looked up from
    /// anywhere).
    pub receivers: Option<Aabb>,
    /// With a renderer made by [`CubeShadowRenderer::with_pushed_vertices`]: how far each vertex moves away
    /// from the cube's centre per unit of the view depth its fourth float holds the inverse of (0: not at all).
    pub push_per_depth: f32,
}

/// The box of the surfaces a frame of `camera` (at `aspect`) can shade: its view frustum's corners' box within
/// the scene's box (a superset of the frustum's part of the scene). None when the view holds nothing of it.
pub fn receiver_bounds(camera: &crate::scene::Camera, aspect: f32, scene: &Aabb) -> Option<Aabb> {
    if scene.is_empty() || !scene.min.is_finite() || !scene.max.is_finite() {
        return None;
    }
    let clip_from_world = camera.clip_from_world(aspect);
    if !crate::math::Frustum::from_clip_from_world(&clip_from_world).intersects_aabb(scene) {
        return None;
    }
    let world_from_clip = clip_from_world.inverse();
    let corners = (0..8).map(|i| {
        let ndc = glam::Vec4::new(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { -1.0 } else { 1.0 },
            if i & 4 == 0 { 0.0 } else { 1.0 },
            1.0,
        );
        let w = world_from_clip * ndc;
        w.truncate() / w.w
    });
    let frustum = Aabb::from_points(corners);
    let inside = frustum.intersection(scene);
    (frustum.min.is_finite() && frustum.max.is_finite() && !inside.is_empty()).then_some(inside)
}

/// Per material: its bind group (`GpuScene::material_layout`) and whether it is cut out (alpha-tested).
#[derive(Clone, Copy)]
pub struct Cutouts<'a> {
    pub bind_groups: &'a [wgpu::BindGroup],
    pub masked: &'a [bool],
}

impl CubeGeometry<'_> {
    fn masked(&self, chunk: usize) -> bool {
        self.cutouts.is_some_and(|c| c.masked.get(self.chunks[chunk].material as usize).copied().unwrap_or(false))
    }
}

/// One tile's draws: its opaque ranges `all_ranges[first..first + count]` and its cut-out chunks
/// `all_masked[first_masked..first_masked + masked]`.
#[derive(Clone, Copy)]
struct TileDraw {
    tile: u32,
    first: usize,
    count: usize,
    first_masked: usize,
    masked: usize,
}

/// Splits `ids` into `opaque` (merged into draw ranges by the caller) and `masked` chunks.
fn split_cutouts(geometry: &CubeGeometry<'_>, ids: &[u32], opaque: &mut Vec<u32>, masked: &mut Vec<u32>) {
    opaque.clear();
    for &id in ids {
        if geometry.masked(id as usize) {
            masked.push(id);
        } else {
            opaque.push(id);
        }
    }
}

/// The draw lists of one depth pass: per tile its merged opaque index ranges and its cut-out chunks.
#[derive(Default)]
struct DrawLists {
    draws: Vec<TileDraw>,
    ranges: Vec<(u32, u32)>,
    masked: Vec<u32>,
}

/// Reused per-tile scratch of the culled draw loop.
#[derive(Default)]
struct TileScratch {
    selected: Vec<u32>,
    opaque: Vec<u32>,
    ranges: Vec<(u32, u32)>,
}

/// The culled draw loop of every view (cube face, paraboloid, perspective): of the chunks `candidates`, those
/// `keep` accepts are drawn into `tile`, opaque ones merged into ranges, cut-outs one by one; the triangles
/// submitted and culled are added to `stats`.
fn push_tile(
    lists: &mut DrawLists,
    scratch: &mut TileScratch,
    geometry: &CubeGeometry<'_>,
    tile: usize,
    candidates: impl Iterator<Item = u32>,
    keep: impl Fn(&Chunk) -> bool,
    stats: &mut CubeStats,
) {
    scratch.selected.clear();
    let mut tris = 0u64;
    for id in candidates {
        let chunk = &geometry.chunks[id as usize];
        if keep(chunk) {
            scratch.selected.push(id);
            tris += chunk.triangle_count() as u64;
        }
    }
    stats.triangles_submitted += tris;
    stats.triangles_culled += geometry.triangle_count - tris;
    let first_masked = lists.masked.len();
    split_cutouts(geometry, &scratch.selected, &mut scratch.opaque, &mut lists.masked);
    merge_draw_ranges(geometry.chunks, scratch.opaque.iter().copied(), &mut scratch.ranges);
    lists.draws.push(TileDraw {
        tile: tile as u32,
        first: lists.ranges.len(),
        count: scratch.ranges.len(),
        first_masked,
        masked: lists.masked.len() - first_masked,
    });
    lists.ranges.extend_from_slice(&scratch.ranges);
}

impl GpuScene {
    /// The scene's triangles as cube-map geometry (32-byte vertices, [`CubeShadowRenderer::new`]).
    pub fn cube_geometry(&self) -> CubeGeometry<'_> {
        CubeGeometry {
            vertex_buffer: &self.vertex_buffer,
            index_buffer: &self.index_buffer,
            chunks: &self.chunks,
            triangle_count: self.triangle_count,
            cull: true,
            cutouts: Some(Cutouts { bind_groups: &self.material_bind_groups, masked: &self.material_cutout }),
            receivers: None,
            push_per_depth: 0.0,
        }
    }
}

/// The geometry a technique's shadow maps draw: the scene itself, or a copy of it ([`GpuScene::proxy`]: long
/// edges cut for paraboloid maps, simplified when asked). One per technique; `update` once per frame in
/// `prepare`, then `geometry` for every map pass.
#[derive(Default)]
pub struct MapGeometry {
    copy: Option<std::sync::Arc<GpuProxy>>,
    /// The copy's build time, in the frame that built it.
    built_ms: Option<f64>,
}

impl MapGeometry {
    /// The copy `params` ask for (none when they ask for nothing, [`ProxyParams::is_identity`]), built on first
    /// use and then shared through the scene.
    pub fn update(&mut self, gpu: &GpuContext, scene: &GpuScene, params: ProxyParams) {
        (self.copy, self.built_ms) = match scene.proxy(gpu, params) {
            Some((copy, built)) => (Some(copy), built),
            None => (None, None),
        };
    }

    /// What the maps draw: [`GpuScene::cube_geometry`], with the copy's triangles when there is one.
    pub fn geometry<'a>(&'a self, scene: &'a GpuScene) -> CubeGeometry<'a> {
        match &self.copy {
            Some(copy) => CubeGeometry {
                vertex_buffer: &copy.vertex_buffer,
                index_buffer: &copy.index_buffer,
                chunks: &copy.chunks,
                triangle_count: copy.triangle_count,
                ..scene.cube_geometry()
            },
            None => scene.cube_geometry(),
        }
    }

    /// Whether the maps draw a copy.
    pub fn is_copy(&self) -> bool {
        self.copy.is_some()
    }

    /// The copy's triangles, for the figure `map_geometry_triangles` (None: the scene's own).
    pub fn copy_triangles(&self) -> Option<u64> {
        self.copy.as_ref().map(|c| c.triangle_count)
    }

    /// The CPU stage `map geometry build`, in the frame that built the copy.
    pub fn build_time(&self) -> Option<PassTime> {
        self.built_ms.map(|ms| PassTime { name: "map geometry build".into(), ms, count: 1 })
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

    fn with_layout(gpu: &GpuContext, vertex_stride: u64, pushed: bool) -> CubeShadowRenderer {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cube face"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: true,
                    min_binding_size: wgpu::BufferSize::new(80),
                },
                count: None,
            }],
        });
        let faces = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("cube face matrices"),
            size: (MAX_CUBES_PER_BATCH * 6 * std::mem::size_of::<MatrixUniform>()) as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let faces_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("cube face matrices"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &faces,
                    offset: 0,
                    size: wgpu::BufferSize::new(80),
                }),
            }],
        });
        let module = crate::gpu::pipeline::create_module(device, "shadow_depth", shaders::SHADOW_DEPTH.source);
        let pipeline = if pushed {
            Self::depth_pipeline_with(
                device,
                &layout,
                None,
                &module,
                vertex_stride,
                "shadow depth (pushed)",
                false,
                true,
            )
        } else {
            Self::depth_pipeline(device, &layout, &module, vertex_stride, "shadow depth", false)
        };
        CubeShadowRenderer {
            pipeline,
            paraboloid_pipeline: None,
            masked_pipeline: None,
            paraboloid_masked_pipeline: None,
            faces_layout: layout,
            vertex_stride,
            faces,
            faces_bind_group,
            atlas: None,
            visible: Vec::new(),
            scratch: TileScratch::default(),
        }
    }

    fn depth_pipeline(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        module: &wgpu::ShaderModule,
        vertex_stride: u64,
        label: &str,
        with_fragment: bool,
    ) -> wgpu::RenderPipeline {
        Self::depth_pipeline_with(device, layout, None, module, vertex_stride, label, with_fragment, false)
    }

    /// The depth pipeline; with `material` the alpha-tested variant (`vs_masked`/`fs_masked`, group 1 the
    /// material, the UVs at location 2); `pushed`: `vs_pushed` (the inverse depth at location 1, offset 12).
    #[allow(clippy::too_many_arguments)]
    fn depth_pipeline_with(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        material: Option<&wgpu::BindGroupLayout>,
        module: &wgpu::ShaderModule,
        vertex_stride: u64,
        label: &str,
        with_fragment: bool,
        pushed: bool,
    ) -> wgpu::RenderPipeline {
        let mut groups = vec![Some(layout)];
        groups.extend(material.map(Some));
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &groups,
            immediate_size: 0,
        });
        let masked = material.is_some();
        let attributes: &[wgpu::VertexAttribute] = if masked {
            &wgpu::vertex_attr_array![0 => Float32x3, 2 => Float32x2]
        } else if pushed {
            &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32]
        } else {
            &wgpu::vertex_attr_array![0 => Float32x3]
        };
        let offset = |location| match location {
            1 => 12,
            2 => 24,
            _ => 0,
        };
        let attributes: Vec<wgpu::VertexAttribute> =
            attributes.iter().map(|a| wgpu::VertexAttribute { offset: offset(a.shader_location), ..*a }).collect();
        let entry = if masked {
            "vs_masked"
        } else if pushed {
            "vs_pushed"
        } else {
            "vs_main"
        };
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: vertex_stride,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attributes,
                })],
            },
            // No back-face culling: real scenes have single-sided walls that must still cast shadows.
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: SHADOW_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            // Depth-only; a fragment stage only where it must discard (paraboloids), as it costs early depth tests.
            fragment: (with_fragment || masked).then_some(wgpu::FragmentState {
                module,
                entry_point: Some(if masked { "fs_masked" } else { "fs_main" }),
                compilation_options: Default::default(),
                targets: &[],
            }),
            multiview_mask: None,
            cache: None,
        })
    }

    /// Create the alpha-tested pipelines when `geometry` has cut-out materials.
    fn ensure_masked(&mut self, gpu: &GpuContext, geometry: &CubeGeometry<'_>, paraboloid: bool) {
        if !geometry.cutouts.is_some_and(|c| c.masked.iter().any(|&m| m)) {
            return;
        }
        let slot_empty =
            if paraboloid { self.paraboloid_masked_pipeline.is_none() } else { self.masked_pipeline.is_none() };
        if !slot_empty {
            return;
        }
        let material_layout = crate::accel::gpu_scene::GpuScene::material_layout(&gpu.device);
        let (label, source) = if paraboloid {
            ("paraboloid depth (alpha-tested)", shaders::PARABOLOID_DEPTH.source)
        } else {
            ("shadow depth (alpha-tested)", shaders::SHADOW_DEPTH.source)
        };
        let module = crate::gpu::pipeline::create_module(&gpu.device, label, source);
        let pipeline = Self::depth_pipeline_with(
            &gpu.device,
            &self.faces_layout,
            Some(&material_layout),
            &module,
            self.vertex_stride,
            label,
            true,
            false,
        );
        if paraboloid {
            self.paraboloid_masked_pipeline = Some(pipeline);
        } else {
            self.masked_pipeline = Some(pipeline);
        }
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
