//! Intermediate shadow maps (INSM), after Wang, Zhang, Li, Zhang and Popescu 2016
//! (`../shared/papers/intermediate-shadow-maps-wang-2016.md`), Algorithm 1:
//!
//! 1-2. Render `k` intermediate shadow maps `INSM_j` (depth images of `w x w`) from reference viewpoints `V_j`
//!      ([`viewpoints`]: the paper's bounding-box placement, an inside placement, or the user's own).
//! 3.   Reconstruct a triangle mesh `TM_j` from each `INSM_j` on the GPU (Algorithm 2,
//!      `core/src/technique/insm/triangulate.wgsl`): two triangles per 2x2 neighbourhood, an edge dropped only when
//!      neither second-order depth difference at its ends is below `epsilon` (a step across it), background
//!      samples dropped.
//! 4.   Render the scene without shadows: the renderer's G-buffer and ambient pass.
//! 5-9. For each light `L_i`, render all `TM_j` into its cube shadow map `SM_i` and add its shadowed light, in
//!      batches exactly as the reference does ([`PerLightShadows`]), so memory stays bounded for any number of
//!      lights and the only difference to the reference is the geometry in the cube maps.
//!
//! Deviations, each for a reason:
//! - The reconstructed triangles are written per tile of 8x8 neighbourhoods, compacted within the tile's
//!   fixed slot, with the tile's bounds. The CPU reads the tile list back once per frame and culls tiles per
//!   light and per cube face like the reference culls scene chunks: without it every light would draw every
//!   reconstructed triangle six times, and the comparison with the (culled) reference would not be fair.
//!   With culling the paper's bound `k*N + 2*n*k*w²` still holds; [`TechniqueCounts`] reports the real count.
//! - `epsilon` is relative (see the shader): the paper's is in depth units and scene dependent.
//! - The connectivity test (`edge_connected` in the shader): the paper keeps an edge when *both* second
//!   differences (at either end) are below epsilon. That also drops the edge next to every step, so each
//!   surface erodes by a sample and a half, three times the half sample the paper reports (section 4.1).
//!   Measured: a 1 m plate 3-4 samples wide in the box placement's maps vanished (INSM rendered the
//!   unshadowed image). Here an edge is kept when one known second difference is below epsilon, so a step cuts
//!   only the edge across it and a surface keeps its last sample: the paper's half sample.
//! - Beyond the paper, `adaptive` meshes (on by default): Algorithm 2 gives two triangles per 2x2 samples, so
//!   a wall costs as many triangles as a statue. A first pass asks of each 8x8-neighbourhood tile a quadtree
//!   of blocks (the tile, its 4x4 quadrants, its 2x2 blocks; `merge_block` the smallest) whether each is
//!   planar: whole, every neighbourhood keeping both triangles, and every sample's inverse depth (affine in
//!   image coordinates on a plane) within `merge_epsilon` (relative) of the affine function through the
//!   block's corners. Every neighbourhood then belongs to the largest planar block around it, or to itself
//!   alone; a sample is a vertex when it is a corner of one of those leaves around it, and a merged leaf is two
//!   triangles when its sides hold no vertex but its corners, else a fan from its centre sample over every
//!   vertex of its boundary: neighbouring leaves share every vertex of their common side, so the mesh has no
//!   T-junctions and no cracks (tested on the CPU twin: areas and edge counts). With whole tiles only (the
//!   first version, `merge_block = 8x8`) the tiles a crease, an edge or a silhouette crosses kept all of
//!   Algorithm 2's triangles, 90 % of the mesh; their planar quadrants and 2x2 blocks take 37-50 % off the
//!   meshes (the Cornell box's halved; measured: `docs/techniques/insm.md`). A quadtree across
//!   tiles would take off about 1 % more (measured on the CPU twin, not built). `adaptive = off` is Algorithm
//!   2 exactly. The plane test's tolerance `merge_epsilon` (0.002, relative inverse depth) is its own: real
//!   planes pass it to rounding, and it bounds how far a merged block may stray from its samples; with
//!   `epsilon` (0.01) merged tiles stood up to 1 % of the depth off the surface (10 cm at 10 m) and the
//!   conference room's error against the ray tracer rose from 11.38 % to 11.65 %.
//! - Beyond the paper, `drop_covered` (on by default): `k` viewpoints in a room see the same walls, so each
//!   wall was reconstructed up to ten times and every cube map rasterised all the copies. A sample of map `j`
//!   is covered when another map `i` reconstructs it more finely: the sample projects into a neighbourhood of
//!   `i` that keeps both triangles, lies on `i`'s triangle there (inverse depth within `epsilon`, relative),
//!   and that neighbourhood's world area is smaller than the one the sample starts in map `j` (within 5 %:
//!   the lower-numbered map). A triangle whose three corners are covered is dropped (a merged block when all
//!   its samples are). The surface stays in the finest map that sees it: for any point, the finest map
//!   covering it is covered by none, so it keeps its triangles. The argument is the paper's own premise (the
//!   union of the meshes stands for the scene's surfaces, and each map's mesh is accurate to its sampling):
//!   a coarser copy of a surface a finer map already holds adds no blocker, only raster work, and it is the
//!   coarser copy whose eroded edges and bridged steps stray furthest from the surface. Left: a one-sample
//!   overlap at the seams (a triangle with any uncovered corner stays), and holes where a finer map's kept
//!   region has a hole narrower than the coarser map's triangle (between its corners). Tested on the CPU
//!   twin (a finer map keeps everything, a coarser one loses what lies over it and keeps the rest, another
//!   surface is never covered) and GPU = CPU.
//!
//! - Beyond the paper, `box_distance` (4 by default; 1 is the paper's): the `box` placement's cameras stand
//!   along the paper's lines to the box centre at four times the distance, so the box fits in 35-45 degrees instead
//!   of ~120 and is sampled almost uniformly (a wide perspective image spends its samples on its borders). On
//!   the paper's Dragon the error against the ray tracer fell from 3.75 % to 1.05 % ([`viewpoints`]).
//! - Beyond the paper, `bias_samples` (0.5 by default since issue 23's push; 0 is the paper's plain depth bias):
//!   the lookup's depth bias is at least that many widths of an intermediate sample at the viewpoints' mean
//!   distance to the scene's centre
//!   ([`viewpoints::mean_sample_width`]). The mesh stands for the surface only to within about a sample (chords
//!   across curves, bridged folds of a curtain), and a bias in metres or per-light texels lets it shadow the
//!   very surface it stands for (the paper's "superfluous blockers"). Conference room 11.1 % to 7.9 %, the
//!   Dragon 1.05 % to 0.96 %, the restaurant 1.9 % to 1.6 %; Sponza, the arcade and the tori 0.1-0.2 points
//!   worse (more light past contacts).
//! - Beyond the paper, `dilate` (on by default): each sample at a cut edge moves half a sample across it along
//!   its surface, undoing the half-sample erosion (the shader's `dilated_position`, the CPU twin's
//!   `SampledImage::dilated`). Alone it hurt tubes a few samples wide (their extended silhouettes shadowed
//!   themselves); with `bias_samples` it lowers the error on every scene measured (docs/techniques/insm.md).
//! - Beyond the paper, `push_samples` (1.5 by default): every mesh vertex is drawn into the per-light maps that
//!   many widths of *its own* sample further from the light (`vs_pushed` in `shaders/shadow_depth.wgsl`; the
//!   width is its view depth times 2 tan(fov / 2) / w): a depth bias that follows how coarsely each surface was
//!   sampled, where `bias_samples` uses one mean width for all. A normal offset in mean sample widths instead
//!   was measured and helped less than either (not kept).
//! - Beyond the paper, ε is given at 128² (0.02 for the box placement, 0.04 for the inside ones, as the paper
//!   says ε "depends on the scene") and scales as 128 / w down to 0.01 ([`InsmParams::epsilon_at`]): a bridged
//!   step must stay under the push, which shrinks with the samples.
//! - Beyond the paper, a steep edge (the surface across it seen at more than `steep_angle`, 75°, from face-on:
//!   its inverse depth changes by more than tan 75° sample widths) is held to `step_epsilon` (0.02 at 128²,
//!   scaled as ε) instead of ε ([`triangulate::steep_slope`], the shader's `edge_connected`). The inside
//!   placements' larger ε keeps curved surfaces whole, and it also joined samples metres apart: on the arcade
//!   with its own lights a ring camera looking down the hall joined its columns to one another and to the walls
//!   behind them, a curtain that shadowed the hall's floor (shadow error against the ray tracer 20.3 % without
//!   the rule, 6.5 % with it; docs/techniques/insm.md). For the box placement `step_epsilon` is ε: no change.
//!
//! Frame steps: steps `0..k` render one intermediate shadow map each, step `k` triangulates them all, steps
//! `k+1..` are the light batches (the first reads the tile list back).

mod mesh;
mod overlays;
mod params;
mod passes;
pub mod simplify;
pub mod triangulate;
pub mod viewpoints;

use std::sync::Arc;

use glam::{Mat4, Vec3, Vec4};
use wgpu::util::DeviceExt;

use super::{
    check_param, FrameContext, Overlay, OverlayLayer, Param, ParamError, ParamValue, Technique, TechniqueCounts,
};
use crate::error::GpuError;
use crate::gpu::readback::{map_read, read_buffer};
use crate::gpu::GpuContext;
use crate::scene::chunks::Chunk;
use crate::scene::{Aabb, PointLight};
use crate::services::cube_params::CubeMapParams;
use crate::services::cube_shadows::{CubeGeometry, CubeShadowRenderer};
use crate::services::layouts::SharedLayouts;
use crate::services::per_light_shadows::PerLightShadows;
use crate::timing::PassTime;
use mesh::{MeshBuffers, MESH_VERTEX_BYTES};
pub use params::{InsmParams, MAX_INSM_RESOLUTION, MAX_VIEWPOINTS};
use triangulate::{GpuTile, MapView, MeshSettings, SampledImage, MAX_TRIANGLES_PER_TILE};
use viewpoints::Viewpoint;

use crate::shaders::WgslModule;
/// This technique's own WGSL modules; its registry entry lists them and the naga test validates them.
pub const SHADERS: &[WgslModule] = &[TRIANGULATE];
const TRIANGULATE: WgslModule = crate::shaders::wgsl!(
    "insm_triangulate",
    ["core/src/technique/insm/triangulate.wgsl", "core/src/technique/insm/triangulate_adaptive.wgsl"]
);

/// The reconstructed samples are read back for the overlays when they take at most this many bytes
/// (10 maps of 256² are 10 MiB); beyond, the overlays show the viewpoints only.
const OVERLAY_READBACK_LIMIT: u64 = 12 << 20;
/// Caps of overlay primitives, so the overlay stays interactive.
const MAX_WIREFRAME_TRIANGLES: usize = 40_000;
const MAX_OVERLAY_POINTS: usize = 40_000;
const MAX_DROPPED_EDGES: usize = 60_000;

/// Mirrors `Params` in `insm/triangulate.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct TriangulateUniform {
    resolution: u32,
    tiles_per_side: u32,
    epsilon: f32,
    atlas_tiles_per_row: u32,
    adaptive: u32,
    merge_epsilon: f32,
    drop_covered: u32,
    dilate: u32,
    step_epsilon: f32,
    min_block: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<TriangulateUniform>() == 48);

/// Mirrors `View` in `insm/triangulate.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuView {
    world_from_clip: [[f32; 4]; 4],
    clip_from_world: [[f32; 4]; 4],
    near: f32,
    far: f32,
    /// The relative change of view depth from one sample to the next above which an edge is steep
    /// ([`triangulate::steep_slope`]).
    steep: f32,
    _pad: f32,
}
const _: () = assert!(std::mem::size_of::<GpuView>() == 144);

/// What the overlays show of the last frame's meshes.
#[derive(Default)]
struct MeshSnapshot {
    resolution: u32,
    settings: MeshSettings,
    views: Vec<MapView>,
    /// Where the samples are read from, when an overlay asks for them (None: too large to read back).
    source: Option<SampleSource>,
    /// `k * resolution²` samples, read back on first use: a frame whose mesh overlays nobody shows (every CLI
    /// frame, most of the app's) copies nothing back.
    samples: std::sync::OnceLock<Arc<Vec<Vec4>>>,
    /// The mesh overlay layers, built on first use (the app asks for overlays every UI frame).
    layers: std::sync::OnceLock<Vec<OverlayLayer>>,
    /// The simplified meshes' wireframe (`simplify` below 1): what the per-light maps draw.
    simplified: Option<OverlayLayer>,
}

/// The GPU samples of a frame's meshes and the buffer they are copied to for reading.
struct SampleSource {
    gpu: GpuContext,
    vertices: wgpu::Buffer,
    readback: wgpu::Buffer,
    bytes: u64,
}

/// The mesh overlay layers: built only when one of them is shown.
const MESH_LAYERS: [&str; 4] = ["INSM samples", "INSM mesh (wireframe)", "INSM dropped edges", "INSM merged blocks"];
/// The simplified meshes' wireframe (`simplify` below 1), built when they are.
const SIMPLIFIED_LAYER: &str = "INSM simplified mesh (wireframe)";

pub struct Insm {
    pub params: InsmParams,
    /// The viewpoints of `placement = custom` (edited in the app, saved in scene files).
    pub custom_viewpoints: Vec<Viewpoint>,
    /// `auto` resolved for the scene of these bounds.
    auto_placement: Option<(Aabb, viewpoints::Placement)>,
    /// The placement the last frame used.
    placement_used: viewpoints::Placement,
    images: CubeShadowRenderer,
    /// The meshes seen from the viewpoints (`mesh_views`, inspection), and whether this frame renders them.
    mesh_images: Option<CubeShadowRenderer>,
    frame_mesh_views: bool,
    shadows: PerLightShadows,
    triangulate_pipeline: wgpu::ComputePipeline,
    /// Pass 1 of the adaptive mesh: which tiles merge.
    classify_pipeline: wgpu::ComputePipeline,
    triangulate_layout: wgpu::BindGroupLayout,
    uniform: wgpu::Buffer,
    views_buffer: wgpu::Buffer,
    mesh: Option<MeshBuffers>,
    /// This frame's viewpoints and their clip-from-world matrices.
    views: Vec<Viewpoint>,
    view_matrices: Vec<Mat4>,
    /// The scene's bounds in the last frame.
    bounds: Aabb,
    /// The per-light maps' parameters of the last frame, with the lookup's bias ([`Insm::lookup_params`]).
    lookup: CubeMapParams,
    /// How far the meshes' vertices move away from a light per unit of their view depth ([`InsmParams::push_per_depth`]).
    push_per_depth: f32,
    /// Non-empty tiles of the reconstructed meshes, read back before the first light batch (with `simplify`
    /// below 1: the simplified mesh's chunks, whose indices are in `simplified`).
    tiles: Vec<Chunk>,
    mesh_triangles: u64,
    /// Triangles of `tiles`, what the per-light maps draw from (`mesh_triangles`, or the simplified meshes').
    tiles_triangles: u64,
    /// The simplified meshes' index buffer (`simplify` below 1), into the same vertex buffer.
    simplified: Option<wgpu::Buffer>,
    tiles_ready: bool,
    snapshot: MeshSnapshot,
    counts: TechniqueCounts,
    cpu_times: Vec<PassTime>,
}

impl Insm {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts) -> Insm {
        let device = &gpu.device;
        let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let triangulate_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("insm triangulate"),
            entries: &[
                crate::gpu::bind::uniform_entry(0),
                storage(1, true),
                crate::gpu::bind::depth_texture_entry(2),
                storage(3, false),
                storage(4, false),
                storage(5, false),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("insm triangulate"),
            bind_group_layouts: &[Some(&triangulate_layout)],
            immediate_size: 0,
        });
        let module = crate::gpu::pipeline::create_module(device, "insm_triangulate", TRIANGULATE.source);
        let entry = |label, entry_point| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry_point),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let classify_pipeline = entry("insm classify", "classify");
        let triangulate_pipeline = entry("insm triangulate", "triangulate");
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("insm triangulate params"),
            contents: bytemuck::bytes_of(&TriangulateUniform {
                resolution: 0,
                tiles_per_side: 0,
                epsilon: 0.0,
                atlas_tiles_per_row: 1,
                adaptive: 0,
                merge_epsilon: 0.0,
                drop_covered: 0,
                dilate: 0,
                step_epsilon: 0.0,
                min_block: 2,
                _pad: [0; 2],
            }),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let views_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("insm views"),
            size: (MAX_VIEWPOINTS * std::mem::size_of::<GpuView>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Insm {
            params: InsmParams::default(),
            custom_viewpoints: Vec::new(),
            auto_placement: None,
            placement_used: viewpoints::Placement::Box,
            images: CubeShadowRenderer::new(gpu),
            mesh_images: None,
            frame_mesh_views: false,
            shadows: PerLightShadows::new(gpu, layouts, CubeShadowRenderer::with_pushed_vertices(gpu)),
            triangulate_pipeline,
            classify_pipeline,
            triangulate_layout,
            uniform,
            views_buffer,
            mesh: None,
            views: Vec::new(),
            view_matrices: Vec::new(),
            bounds: Aabb::from_points(std::iter::empty()),
            lookup: CubeMapParams::default(),
            push_per_depth: 0.0,
            tiles: Vec::new(),
            mesh_triangles: 0,
            tiles_triangles: 0,
            tiles_ready: false,
            simplified: None,
            snapshot: MeshSnapshot::default(),
            counts: TechniqueCounts::default(),
            cpu_times: Vec::new(),
        }
    }

    /// The viewpoints used by the last frame.
    pub fn viewpoints(&self) -> &[Viewpoint] {
        &self.views
    }

    /// How the meshes are built, for the CPU twin.
    pub fn mesh_settings(&self) -> MeshSettings {
        let res = self.mesh.as_ref().map_or(self.params.insm_resolution, |m| m.resolution);
        self.placed().mesh_settings(res)
    }

    /// The parameters with `auto` resolved to the placement the last frame used (whose ε it is).
    fn placed(&self) -> InsmParams {
        InsmParams { placement: self.placement_used, ..self.params.clone() }
    }

    /// The placement the last frame used (`auto` resolved for its scene).
    pub fn placement_used(&self) -> viewpoints::Placement {
        self.placement_used
    }

    /// The per-light maps' parameters with the lookup's bias for `views` at `resolution`
    /// ([`InsmParams::lookup_params`]).
    pub fn lookup_params(&self, views: &[Viewpoint], bounds: &Aabb, resolution: u32) -> CubeMapParams {
        self.params.lookup_params(views, bounds, resolution)
    }

    /// The cameras of the last frame's intermediate maps, for the CPU twin.
    pub fn map_views(&self) -> Vec<MapView> {
        let res = self.mesh.as_ref().map_or(self.params.insm_resolution, |m| m.resolution);
        self.views
            .iter()
            .zip(&self.view_matrices)
            .map(|(v, m)| {
                let (near, far) = v.depth_range(&self.bounds);
                MapView { clip_from_world: *m, near, far, steep: self.params.steep_slope(v.fov_y_deg, res) }
            })
            .collect()
    }
}

/// The scene's bounds from its chunks.
fn scene_bounds(chunks: &[Chunk]) -> Aabb {
    let mut b = Aabb::from_points(std::iter::empty());
    for c in chunks {
        b = b.union(&c.bounds);
    }
    b
}

impl Technique for Insm {
    fn key(&self) -> &'static str {
        "insm"
    }

    fn label(&self) -> &'static str {
        "INSM"
    }

    fn params(&self) -> Vec<Param> {
        self.params.describe(&self.custom_viewpoints)
    }

    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        check_param(self.key(), &self.params(), key, value)?;
        self.params.set(&mut self.custom_viewpoints, key, value);
        Ok(())
    }

    fn explain(&self) -> Vec<super::ExplainStep> {
        self.explain_steps()
    }

    fn overlay_legend(&self, layer: &OverlayLayer) -> Vec<super::LegendEntry> {
        self.legend_of(layer)
    }

    fn overlays_shown(&self, lights: &[PointLight], shown: &dyn Fn(&str, bool) -> bool) -> Vec<OverlayLayer> {
        self.overlay_layers(lights, shown)
    }

    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        self.cpu_times.clear();
        self.tiles_ready = false;
        let res = self.params.insm_resolution.min(ctx.gpu.device.limits().max_texture_dimension_2d);
        let bounds = scene_bounds(&ctx.scene.chunks);
        let views = self.place_viewpoints(ctx, &bounds);
        let placement = self.placement_used;
        use viewpoints::Placement;
        self.lookup = self.params.lookup_params(&views, &bounds, res);
        self.push_per_depth = self.params.push_per_depth(&views, res);
        let batches = self.shadows.prepare(ctx, &self.lookup);
        self.counts = TechniqueCounts { lights_visible: self.shadows.visible_lights(), ..Default::default() };
        // Which placement `auto` (or the user) chose: 1 for the cameras inside the scene, 0 around it (or custom).
        let inside = matches!(placement, Placement::Inside | Placement::Walls);
        self.counts.figures.insert("placement_inside".into(), f64::from(u8::from(inside)));
        if batches == 0 {
            return Ok(0);
        }
        self.bounds = bounds;
        self.views = views;
        if self.views.is_empty() {
            return Err(GpuError::InvalidSettings(
                "INSM has no viewpoint: place at least one (or choose the box or inside placement)".into(),
            ));
        }
        self.view_matrices = self.views.iter().map(|v| v.clip_from_world(&bounds)).collect();
        let gpu_views: Vec<GpuView> = self
            .views
            .iter()
            .zip(&self.view_matrices)
            .map(|(v, m)| {
                let (near, far) = v.depth_range(&bounds);
                GpuView {
                    world_from_clip: m.inverse().to_cols_array_2d(),
                    clip_from_world: m.to_cols_array_2d(),
                    near,
                    far,
                    steep: self.params.steep_slope(v.fov_y_deg, res),
                    _pad: 0.0,
                }
            })
            .collect();
        ctx.gpu.queue.write_buffer(&self.views_buffer, 0, bytemuck::cast_slice(&gpu_views));

        let k = self.views.len() as u32;
        // The largest buffer is the tiles' index slots; refuse settings the device cannot hold, instead of
        // letting wgpu fail on creation.
        let limits = ctx.gpu.device.limits();
        let tps = triangulate::tiles_per_side(res) as u64;
        let largest = (k as u64 * tps * tps * MAX_TRIANGLES_PER_TILE as u64 * 12)
            .max(k as u64 * (res as u64).pow(2) * MESH_VERTEX_BYTES);
        let allowed = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        if largest > allowed {
            return Err(GpuError::InvalidSettings(format!(
                "INSM with k = {k} maps of {res}x{res} needs a {} MiB buffer; this device allows {} MiB: lower k or \
                 insm_res",
                largest >> 20,
                allowed >> 20
            )));
        }
        let new_atlas = self.images.ensure_tiles(ctx.gpu, res, k as usize);
        let atlas_tiles_per_row = self.images.atlas().expect("ensured").tiles_per_row;
        let had_mesh = self.mesh.as_ref().is_some_and(|m| m.k == k && m.resolution == res);
        self.ensure_mesh(ctx.gpu, k, res);
        if new_atlas && had_mesh {
            let mesh = self.mesh.as_ref().expect("ensured");
            let group = self.bind_group_for(ctx.gpu, &mesh.vertices, &mesh.indices, &mesh.tiles);
            self.mesh.as_mut().expect("ensured").bind_group = group;
        }
        // The same settings the CPU twin builds with (`mesh_settings`).
        let mesh = self.placed().mesh_settings(res);
        let uniform = TriangulateUniform {
            resolution: res,
            tiles_per_side: triangulate::tiles_per_side(res),
            epsilon: mesh.epsilon,
            atlas_tiles_per_row,
            adaptive: u32::from(mesh.adaptive),
            merge_epsilon: mesh.merge_epsilon,
            drop_covered: u32::from(mesh.drop_covered),
            dilate: u32::from(self.params.dilate),
            step_epsilon: mesh.step_epsilon,
            min_block: mesh.min_block,
            _pad: [0; 2],
        };
        ctx.gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));

        // The paper's bound on rendered triangles: k N + 2 n k w².
        let n = self.shadows.visible_lights() as u64;
        let budget = k as u64 * ctx.scene.triangle_count + 2 * n * k as u64 * (res as u64).pow(2);
        self.counts.insm_triangle_budget = Some(budget);
        self.frame_mesh_views = self.params.mesh_views;
        if self.frame_mesh_views {
            // Made the first time it is asked for: most frames never draw the meshes' views.
            let images = self.mesh_images.get_or_insert_with(|| CubeShadowRenderer::with_pushed_vertices(ctx.gpu));
            images.ensure_tiles(ctx.gpu, res, k as usize);
        }
        // Steps: one per intermediate map, the triangulation, the meshes' views (`mesh_views`), the light batches.
        self.counts.batches = k as usize + 1 + usize::from(self.frame_mesh_views) + batches;
        Ok(self.counts.batches)
    }

    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        let k = self.views.len();
        if step < k {
            self.encode_intermediate_map(ctx, step, encoder);
            return Ok(());
        }
        if step == k {
            self.encode_triangulation(ctx, encoder);
            return Ok(());
        }
        if !self.tiles_ready {
            self.read_tiles(ctx.gpu)?;
        }
        let views_step = usize::from(self.frame_mesh_views);
        if views_step == 1 && step == k + 1 {
            self.encode_mesh_views(ctx, encoder);
            return Ok(());
        }
        let mesh = self.mesh.as_ref().expect("prepare created the mesh buffers");
        let geometry = mesh.geometry(self.simplified.as_ref(), &self.tiles, self.tiles_triangles, self.push_per_depth);
        let stats = self.shadows.encode_batch(ctx, step - k - 1 - views_step, encoder, geometry, &self.lookup);
        self.counts.add_cube_stats(&stats);
        Ok(())
    }

    fn step_label(&self) -> &'static str {
        "intermediate maps / shadow maps + shading"
    }

    fn counts(&self) -> TechniqueCounts {
        self.counts.clone()
    }

    fn cpu_times(&self) -> Vec<PassTime> {
        self.cpu_times.clone()
    }

    fn cameras_in_use(&self, key: &str) -> Vec<super::CameraPose> {
        if key == "viewpoints" {
            self.views.clone()
        } else {
            Vec::new()
        }
    }

    fn uses_light_tiles(&self) -> bool {
        true
    }

    fn shadow_atlas(&self) -> Option<(&crate::services::cube_shadows::CubeAtlas, &'static str)> {
        let what = "cube maps of the last batch, drawn from the meshes, six faces per light (+x -x +y -y +z -z)";
        self.shadows.atlas().map(|a| (a, what))
    }

    fn depth_images(&self) -> Vec<(&crate::services::cube_shadows::CubeAtlas, &'static str)> {
        let mut images: Vec<_> =
            self.images.atlas().map(|a| (a, "intermediate depth images, one per viewpoint")).into_iter().collect();
        if let Some(a) = self.mesh_images.as_ref().and_then(|m| m.atlas()).filter(|_| self.frame_mesh_views) {
            images.push((a, "the meshes seen from the viewpoints (mesh_views), tile by tile as the images"));
        }
        images
    }

    fn tuning_params(&self) -> &'static [&'static str] {
        &["mesh_views"]
    }

    fn overlays(&self, lights: &[PointLight]) -> Vec<OverlayLayer> {
        self.overlays_shown(lights, &|_, _| true)
    }
}
