//! INSM Algorithm 2 on the CPU: the twin of `core/src/technique/insm/triangulate.wgsl`, run on the vertices the GPU wrote
//! (world position and inverse depth per sample). The technique uses it for its overlays (the reconstructed
//! mesh, its samples and the dropped edges); the tests check the GPU against it.
//!
//! See the shader for the connectivity test, the tile merging of the adaptive mesh and the covered triangles
//! ([`covered_samples`], [`meshes`]: the maps' meshes together). Samples are indexed
//! `(u, v)` = `(x, y)`, row-major per image.

use glam::{Mat4, Vec2, Vec3, Vec4};

mod adaptive;
pub use adaptive::TILE_BIT;

/// Neighbourhoods per tile side; the workgroup size of `insm/triangulate.wgsl`.
pub const TILE: u32 = 8;
/// Triangle slots per tile: two per neighbourhood.
pub const MAX_TRIANGLES_PER_TILE: u32 = 2 * TILE * TILE;

/// Mirrors `Tile` in `insm/triangulate.wgsl`: the triangles a tile kept and their bounds.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTile {
    pub count: u32,
    /// The tile's planar mask ([`SampledImage::planar_mask`]): which of its blocks the adaptive mesh may merge.
    pub merged: u32,
    /// Bit `y * TILE + x` (low word, then high): neighbourhood `(x, y)` of the tile keeps both triangles.
    pub full: [u32; 2],
    pub bounds_min: [f32; 4],
    pub bounds_max: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<GpuTile>() == 48);

/// Tiles per image side for `resolution` samples per side (every sample belongs to one tile).
pub fn tiles_per_side(resolution: u32) -> u32 {
    resolution.div_ceil(TILE)
}

/// How the meshes are built: the connectivity test's `epsilon`, and the two steps beyond the paper.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshSettings {
    pub epsilon: f32,
    /// The tolerance for a step ([`Connectivity::step`]); at or above `epsilon` it changes nothing.
    pub step_epsilon: f32,
    /// Merge planar blocks (the adaptive mesh).
    pub adaptive: bool,
    /// Relative tolerance of the merge test ([`SampledImage::block_planar`]).
    pub merge_epsilon: f32,
    /// The smallest block the adaptive mesh merges, in neighbourhoods a side: 2, 4 or `TILE` (whole tiles only).
    pub min_block: u32,
    /// Drop the triangles another map reconstructs more finely ([`covered_samples`]).
    pub drop_covered: bool,
}

/// Algorithm 2 exactly.
impl Default for MeshSettings {
    fn default() -> Self {
        MeshSettings {
            epsilon: 0.01,
            step_epsilon: 0.01,
            adaptive: false,
            merge_epsilon: 0.002,
            min_block: 2,
            drop_covered: false,
        }
    }
}

impl MeshSettings {
    /// The connectivity test's tolerances.
    pub fn connectivity(&self) -> Connectivity {
        Connectivity { epsilon: self.epsilon, step: self.step_epsilon, steep: 0.0 }
    }
}

/// The connectivity test's tolerances (relative second differences of inverse depth): `epsilon`, the paper's,
/// and `step`, a tighter one for a steep edge (beyond the paper, [`SampledImage::edge_connected`]), one whose
/// relative change of inverse depth per sample exceeds `steep` (the map's [`MapView::steep`]; 0: none is). A
/// bare `f32` is the paper's test alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Connectivity {
    pub epsilon: f32,
    pub step: f32,
    pub steep: f32,
}

impl From<f32> for Connectivity {
    fn from(epsilon: f32) -> Connectivity {
        Connectivity { epsilon, step: epsilon, steep: 0.0 }
    }
}

impl Connectivity {
    /// These tolerances for the map seen through `view` (its steepness).
    pub fn for_view(self, view: &MapView) -> Connectivity {
        Connectivity { steep: view.steep, ..self }
    }
}

/// The camera of an intermediate map: its clip-from-world and the depth range it was rendered with (the
/// inverse depth of a point is `(far - d (far - near)) / (near far)` for its depth-buffer value `d`).
#[derive(Clone, Copy, Debug)]
pub struct MapView {
    pub clip_from_world: Mat4,
    pub near: f32,
    pub far: f32,
    /// The relative change of inverse depth per sample above which an edge of this map is steep
    /// ([`steep_slope`] of its field of view and resolution; 0: none is).
    pub steep: f32,
}

/// tan 60°: the steepest surface (against the image plane) whose samples [`SampledImage::dilated`] moves; a
/// steeper one is at a curved silhouette, where the tangent would leave the surface by up to half a sample and
/// shadow it. Keep in sync with `GRAZING_SLOPE` in `insm/triangulate.wgsl`.
const GRAZING_SLOPE: f32 = 1.732_050_8;

/// The relative change of view depth between neighbouring samples (`|z_a - z_b| / max(z_a, z_b)` of inverse
/// depths) above which the surface between them is seen at more than `angle_deg` from face-on: `tan(angle)`
/// times a sample's angular width `2 tan(fov / 2) / resolution` (at the image's centre). 0 (no edge is steep)
/// from 90° up or for a bad value; at 0° every edge whose depth changes at all is steep.
pub fn steep_slope(angle_deg: f32, fov_y_deg: f32, resolution: u32) -> f32 {
    if !(0.0..90.0).contains(&angle_deg) {
        return 0.0;
    }
    let slope = angle_deg.to_radians().tan() * 2.0 * (0.5 * fov_y_deg.to_radians()).tan() / resolution.max(1) as f32;
    if slope.is_finite() {
        slope.max(f32::MIN_POSITIVE)
    } else {
        0.0
    }
}

impl MapView {
    /// The world point that sample `(x, y)` of a `resolution`² map saw at inverse view depth `inv_depth`: the
    /// depth-buffer value `d = (far - inv_depth near far) / (far - near)` unprojected through the sample's centre,
    /// as the shader's `world_position` does from the depth atlas.
    /// `world_from_clip` is the inverse of `clip_from_world`, computed once by the caller.
    pub fn sample_position(&self, world_from_clip: &Mat4, x: u32, y: u32, resolution: u32, inv_depth: f32) -> Vec3 {
        let r = resolution as f32;
        let ndc = Vec2::new((x as f32 + 0.5) / r * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / r * 2.0);
        let d = (self.far - inv_depth * self.near * self.far) / (self.far - self.near);
        world_from_clip.project_point3(ndc.extend(d))
    }
}

/// Slack of the finer-sampling comparison of [`covered_samples`]: a map whose neighbourhood is within 5 % of
/// the other's area is neither finer nor coarser, and the lower-numbered map keeps the surface.
const FINER_SLACK: f32 = 0.95;

/// Area of the quad of samples `p00, p10, p01, p11` (half the cross product of its diagonals).
fn quad_area(p00: Vec3, p10: Vec3, p01: Vec3, p11: Vec3) -> f32 {
    0.5 * (p11 - p00).cross(p01 - p10).length()
}

/// Map `i` reconstructs world point `w` more finely than a map whose neighbourhood at `w` spans `area_j`:
/// `w` projects into a neighbourhood of `i` that keeps both triangles, lies on its triangle there (inverse
/// depth within `epsilon`, relative), and that neighbourhood is smaller (or, within [`FINER_SLACK`], `i` is
/// the lower-numbered map, `lower`). The twin of `reconstructs_better` in the shader.
fn reconstructs_better(
    image: &SampledImage,
    view: &MapView,
    w: Vec3,
    area_j: f32,
    lower: bool,
    epsilon: Connectivity,
) -> bool {
    let c = view.clip_from_world * w.extend(1.0);
    if c.w <= 0.0 {
        return false;
    }
    let ndc = c.truncate() / c.w;
    // Written so that NaN fails.
    if !(ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0 && ndc.z >= 0.0 && ndc.z <= 1.0) {
        return false;
    }
    let r = image.resolution as f32;
    let f = Vec2::new((ndc.x + 1.0) * 0.5 * r - 0.5, (1.0 - ndc.y) * 0.5 * r - 0.5);
    let n = f.floor();
    if n.x < 0.0 || n.y < 0.0 || n.x + 1.0 >= r || n.y + 1.0 >= r {
        return false;
    }
    let (x, y) = (n.x as u32, n.y as u32);
    if !image.neighbourhood(x, y, epsilon.for_view(view)).iter().all(Option::is_some) {
        return false;
    }
    let ri = image.resolution;
    let s = |dx: u32, dy: u32| image.samples[((y + dy) * ri + x + dx) as usize];
    let (s00, s10, s01, s11) = (s(0, 0), s(1, 0), s(0, 1), s(1, 1));
    let a = f - n;
    // The neighbourhood's triangles [(0,0), (0,1), (1,1)] (a.x <= a.y) and [(1,1), (1,0), (0,0)]: inverse depth
    // is affine on each.
    let fit = if a.x <= a.y {
        s00.w + a.x * (s11.w - s01.w) + a.y * (s01.w - s00.w)
    } else {
        s00.w + a.x * (s10.w - s00.w) + a.y * (s11.w - s10.w)
    };
    let zp = (view.far - ndc.z * (view.far - view.near)) / (view.near * view.far);
    // Written so that NaN fails.
    let on_surface = (zp - fit).abs() < epsilon.epsilon * zp;
    if !on_surface {
        return false;
    }
    let area_i = quad_area(s00.truncate(), s10.truncate(), s01.truncate(), s11.truncate());
    area_i < area_j * FINER_SLACK || (lower && area_i * FINER_SLACK <= area_j)
}

/// For every sample of map `j` (row-major), whether another map reconstructs it more finely (beyond the paper,
/// see `insm/mod.rs`). A sample's own footprint is the area of the neighbourhood it is the top-left corner of
/// (the last one of its row or column at the image's edge); one with a background corner is unbounded.
pub fn covered_samples(
    images: &[SampledImage],
    views: &[MapView],
    j: usize,
    epsilon: impl Into<Connectivity>,
) -> Vec<bool> {
    let epsilon = epsilon.into();
    let img = &images[j];
    let r = img.resolution;
    let world_from_clip = views[j].clip_from_world.inverse();
    (0..r * r)
        .map(|s| {
            let (x, y) = (s % r, s / r);
            let w = img.samples[s as usize];
            if w.w <= 0.0 || r < 2 {
                return false;
            }
            // The surface point the sample saw, not its (possibly dilated) vertex, as the shader asks.
            let seen = views[j].sample_position(&world_from_clip, x, y, r, w.w);
            let (qx, qy) = (x.min(r - 2), y.min(r - 2));
            let q = |dx: u32, dy: u32| img.samples[((qy + dy) * r + qx + dx) as usize];
            let corners = [q(0, 0), q(1, 0), q(0, 1), q(1, 1)];
            let area_j = if corners.iter().all(|c| c.w > 0.0) {
                quad_area(corners[0].truncate(), corners[1].truncate(), corners[2].truncate(), corners[3].truncate())
            } else {
                f32::MAX
            };
            (0..images.len())
                .any(|i| i != j && reconstructs_better(&images[i], &views[i], seen, area_j, i < j, epsilon))
        })
        .collect()
}

/// The meshes of all maps (sample indices within each map), as `core/src/technique/insm/triangulate.wgsl` writes them.
pub fn meshes(images: &[SampledImage], views: &[MapView], settings: &MeshSettings) -> Vec<Vec<[u32; 3]>> {
    meshes_with_blocks(images, views, settings).into_iter().map(|(mesh, _)| mesh).collect()
}

/// A map's mesh (sample indices) and the merged blocks of its adaptive mesh (origin x, origin y, side).
pub type MeshAndBlocks = (Vec<[u32; 3]>, Vec<(u32, u32, u32)>);

/// Per map, its mesh (as [`meshes`]) and the merged blocks of its adaptive mesh that keep their triangles
/// ([`SampledImage::merged_leaves`]; none without `adaptive`).
pub fn meshes_with_blocks(images: &[SampledImage], views: &[MapView], settings: &MeshSettings) -> Vec<MeshAndBlocks> {
    (0..images.len())
        .map(|j| {
            let covered = settings.drop_covered.then(|| covered_samples(images, views, j, settings.connectivity()));
            let img = &images[j];
            let connectivity = settings.connectivity().for_view(&views[j]);
            let masks = img.masks(settings, connectivity);
            let mesh = img.mesh_from_masks(connectivity, &masks, covered.as_deref());
            (mesh, img.merged_leaves(&masks, covered.as_deref()))
        })
        .collect()
}

/// One intermediate shadow map as the GPU reconstructed it: `resolution²` samples of (world xyz, inverse depth).
pub struct SampledImage<'a> {
    pub resolution: u32,
    pub samples: &'a [Vec4],
}

/// An edge of the sample grid that joins two valid samples but fails the connectivity test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DroppedEdge {
    pub from: Vec3,
    pub to: Vec3,
}

impl SampledImage<'_> {
    /// Inverse depth at `(x, y)`: -1 outside the image, 0 background.
    fn z(&self, x: i64, y: i64) -> f32 {
        let r = self.resolution as i64;
        if x < 0 || y < 0 || x >= r || y >= r {
            return -1.0;
        }
        self.samples[(y * r + x) as usize].w
    }

    pub fn position(&self, x: u32, y: u32) -> Vec3 {
        self.samples[(y * self.resolution + x) as usize].truncate()
    }

    /// `IsConnected` for one edge (a, b): both valid, and the second differences at a and at b do not show a
    /// step between them: one known below `epsilon` (relative), or neither known and one outside the image or
    /// the first difference below `epsilon`.
    /// The twin of `edge_connected` in the shader, which says why this deviates from the paper's "both below".
    pub fn edge_connected(&self, a: (i64, i64), b: (i64, i64), epsilon: impl Into<Connectivity>) -> bool {
        let Connectivity { epsilon, step, steep } = epsilon.into();
        let za = self.z(a.0, a.1);
        let zb = self.z(b.0, b.1);
        // epsilon 0 connects nothing (as the paper's test does): the way to switch the reconstruction off.
        if za <= 0.0 || zb <= 0.0 || epsilon <= 0.0 {
            return false;
        }
        let d = (b.0 - a.0, b.1 - a.1);
        let (z_before, z_after) = (self.z(a.0 - d.0, a.1 - d.1), self.z(b.0 + d.0, b.1 + d.1));
        let (known_a, known_b) = (z_before > 0.0, z_after > 0.0);
        let (s_a, s_b) = (z_before + zb - 2.0 * za, za + z_after - 2.0 * zb);
        // A steep edge is held to `step` (beyond the paper; see the shader).
        let diagonal = if d.0 != 0 && d.1 != 0 { std::f32::consts::SQRT_2 } else { 1.0 };
        let is_steep = steep > 0.0 && (za - zb).abs() > steep * diagonal * za.max(zb);
        let tolerance = if is_steep { step } else { epsilon };
        let ok_a = known_a && s_a.abs() < tolerance * za;
        let ok_b = known_b && s_b.abs() < tolerance * zb;
        if ok_a || ok_b {
            return true;
        }
        // Outside the image (-1) gives no information and does not object, as in the paper's test.
        !known_a && !known_b && (z_before < 0.0 || z_after < 0.0 || (za - zb).abs() < epsilon * za.max(zb))
    }

    /// Half the step from the sample behind `s` (at `s - d`) to `s`, when the edge from `s` to `s + d` is cut
    /// and the one from `s - d` to `s` is kept (both neighbours in the image): how far `s` moves across the cut.
    fn half_step_across(&self, s: (i64, i64), d: (i64, i64), epsilon: Connectivity) -> Vec3 {
        let r = self.resolution as i64;
        let (n, behind) = ((s.0 + d.0, s.1 + d.1), (s.0 - d.0, s.1 - d.1));
        let inside = |p: (i64, i64)| p.0 >= 0 && p.1 >= 0 && p.0 < r && p.1 < r;
        if !inside(n)
            || !inside(behind)
            || self.edge_connected(s, n, epsilon)
            || !self.edge_connected(behind, s, epsilon)
        {
            return Vec3::ZERO;
        }
        let step = self.position(s.0 as u32, s.1 as u32) - self.position(behind.0 as u32, behind.1 as u32);
        let depth_change = (1.0 / self.z(s.0, s.1) - 1.0 / self.z(behind.0, behind.1)).abs();
        let lateral_sq = (step.length_squared() - depth_change * depth_change).max(0.0);
        if depth_change * depth_change > GRAZING_SLOPE * GRAZING_SLOPE * lateral_sq {
            return Vec3::ZERO;
        }
        0.5 * step
    }

    /// The samples with every sample at a cut edge moved half a sample across it, along its own surface (beyond
    /// the paper, INSM's `dilate`): the reconstruction joins sample centres, so a surface ends at its last sample
    /// although its true edge lies anywhere up to the next one, the half-sample erosion of the paper's section
    /// 4.1. In each axis direction `d` where the edge to `s + d` is cut (a step, a crease or the background)
    /// and the edge from `s - d` is kept, `s` moves by half the step from `s - d` (the expected position of
    /// the edge, extrapolated along the surface); a sample with no kept edge behind it has no triangle along
    /// that axis and does not move, nor does one whose surface is seen at more than 60° from face-on (its view
    /// depth changing faster than tan 60° times its lateral spacing: at a curved silhouette the tangent leaves
    /// the surface and would shadow it). Inverse depths are unchanged, so the connectivity tests see the samples
    /// as rendered. The twin of `dilated_position` in the shader (which writes these as the vertices).
    pub fn dilated(&self, epsilon: impl Into<Connectivity>) -> Vec<Vec4> {
        let epsilon: Connectivity = epsilon.into();
        let r = self.resolution as i64;
        (0..r * r)
            .map(|i| {
                let s = self.samples[i as usize];
                if s.w <= 0.0 {
                    return s;
                }
                let p = (i % r, i / r);
                let offset: Vec3 =
                    [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().map(|&d| self.half_step_across(p, d, epsilon)).sum();
                (s.truncate() + offset).extend(s.w)
            })
            .collect()
    }

    /// The kept triangles of neighbourhood `(u, v)` (Algorithm 2, lines 2-5), as sample indices.
    pub fn neighbourhood(&self, u: u32, v: u32, epsilon: impl Into<Connectivity>) -> [Option<[u32; 3]>; 2] {
        let epsilon: Connectivity = epsilon.into();
        let (x, y) = (u as i64, v as i64);
        let r = self.resolution;
        let i00 = v * r + u;
        let diagonal = self.edge_connected((x, y), (x + 1, y + 1), epsilon);
        let t1 = diagonal
            && self.edge_connected((x, y), (x, y + 1), epsilon)
            && self.edge_connected((x, y + 1), (x + 1, y + 1), epsilon);
        let t2 = diagonal
            && self.edge_connected((x + 1, y + 1), (x + 1, y), epsilon)
            && self.edge_connected((x + 1, y), (x, y), epsilon);
        [t1.then_some([i00, i00 + r, i00 + r + 1]), t2.then_some([i00 + r + 1, i00 + 1, i00])]
    }

    /// This map's reconstructed mesh on its own (`drop_covered` needs the other maps: [`meshes`]): the adaptive
    /// one when `adaptive`, else Algorithm 2's ([`SampledImage::triangles`]).
    /// (Without a view, no edge is steep.)
    pub fn mesh(&self, settings: &MeshSettings) -> Vec<[u32; 3]> {
        self.mesh_with(settings, settings.connectivity(), None)
    }

    fn mesh_with(
        &self,
        settings: &MeshSettings,
        connectivity: Connectivity,
        covered: Option<&[bool]>,
    ) -> Vec<[u32; 3]> {
        self.mesh_from_masks(connectivity, &self.masks(settings, connectivity), covered)
    }

    /// Every tile's planar mask under `settings` (all 0 without `adaptive`: Algorithm 2).
    fn masks(&self, settings: &MeshSettings, connectivity: Connectivity) -> Vec<u32> {
        let tps = tiles_per_side(self.resolution);
        if settings.adaptive {
            self.planar_masks(connectivity, settings.merge_epsilon, settings.min_block)
        } else {
            vec![0; (tps * tps) as usize]
        }
    }

    fn mesh_from_masks(&self, connectivity: Connectivity, masks: &[u32], covered: Option<&[bool]>) -> Vec<[u32; 3]> {
        let tps = tiles_per_side(self.resolution);
        (0..tps * tps).flat_map(|t| self.tile_triangles(t % tps, t / tps, connectivity, masks, covered)).collect()
    }

    /// Every kept triangle, neighbourhood by neighbourhood.
    pub fn triangles(&self, epsilon: impl Into<Connectivity>) -> Vec<[u32; 3]> {
        let epsilon: Connectivity = epsilon.into();
        let r = self.resolution;
        let mut out = Vec::new();
        for v in 0..r.saturating_sub(1) {
            for u in 0..r.saturating_sub(1) {
                out.extend(self.neighbourhood(u, v, epsilon).into_iter().flatten());
            }
        }
        out
    }

    /// Grid edges (horizontal, vertical, diagonal) between two valid samples that fail the test: the depth
    /// discontinuities the reconstruction did not bridge.
    pub fn dropped_edges(&self, epsilon: impl Into<Connectivity>) -> Vec<DroppedEdge> {
        let epsilon: Connectivity = epsilon.into();
        let r = self.resolution as i64;
        let mut out = Vec::new();
        for y in 0..r {
            for x in 0..r {
                if self.z(x, y) <= 0.0 {
                    continue;
                }
                for (dx, dy) in [(1, 0), (0, 1), (1, 1)] {
                    let (bx, by) = (x + dx, y + dy);
                    if self.z(bx, by) > 0.0 && !self.edge_connected((x, y), (bx, by), epsilon) {
                        out.push(DroppedEdge {
                            from: self.position(x as u32, y as u32),
                            to: self.position(bx as u32, by as u32),
                        });
                    }
                }
            }
        }
        out
    }

    pub fn valid_samples(&self) -> usize {
        self.samples.iter().filter(|s| s.w > 0.0).count()
    }
}

#[cfg(test)]
mod tests;
