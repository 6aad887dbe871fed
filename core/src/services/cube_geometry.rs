//! What cube and paraboloid shadow maps draw ([`CubeGeometry`]): a vertex and an index buffer cut into chunks
//! with bounds, the scene's own ([`GpuScene::cube_geometry`]) or a technique's copy of it ([`MapGeometry`]), and
//! the box of the receivers a frame looks its maps up from ([`receiver_bounds`]). Drawn by
//! `cube_shadows.rs`'s `CubeShadowRenderer`.

use crate::accel::gpu_scene::{GpuProxy, GpuScene};
use crate::gpu::GpuContext;
use crate::math::Aabb;
use crate::scene::chunks::Chunk;
use crate::scene::proxy::ProxyParams;
use crate::timing::PassTime;

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
    /// With a renderer made by `CubeShadowRenderer::with_pushed_vertices`: how far each vertex moves away
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
    pub(super) fn masked(&self, chunk: usize) -> bool {
        self.cutouts.is_some_and(|c| c.masked.get(self.chunks[chunk].material as usize).copied().unwrap_or(false))
    }
}

impl GpuScene {
    /// The scene's triangles as cube-map geometry (32-byte vertices, `CubeShadowRenderer::new`).
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
