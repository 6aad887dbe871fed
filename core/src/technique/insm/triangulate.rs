//! INSM Algorithm 2 on the CPU: the twin of `core/src/technique/insm/triangulate.wgsl`, run on the vertices the GPU wrote
//! (world position and inverse depth per sample). The technique uses it for its overlays (the reconstructed
//! mesh, its samples and the dropped edges); the tests check the GPU against it.
//!
//! See the shader for the connectivity test, the tile merging of the adaptive mesh and the covered triangles
//! ([`covered_samples`], [`meshes`]: the maps' meshes together). Samples are indexed
//! `(u, v)` = `(x, y)`, row-major per image.

use glam::{Mat4, Vec2, Vec3, Vec4};

/// Neighbourhoods per tile side; the workgroup size of `insm/triangulate.wgsl`.
pub const TILE: u32 = 8;
/// Triangle slots per tile: two per neighbourhood.
pub const MAX_TRIANGLES_PER_TILE: u32 = 2 * TILE * TILE;

/// Mirrors `Tile` in `insm/triangulate.wgsl`: the triangles a tile kept and their bounds.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTile {
    pub count: u32,
    /// 1 when the adaptive mesh merged the tile.
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
    /// Merge planar tiles (the adaptive mesh).
    pub adaptive: bool,
    /// Relative tolerance of the merge test ([`SampledImage::tile_merged`]).
    pub merge_epsilon: f32,
    /// Drop the triangles another map reconstructs more finely ([`covered_samples`]).
    pub drop_covered: bool,
}

/// Algorithm 2 exactly.
impl Default for MeshSettings {
    fn default() -> Self {
        MeshSettings { epsilon: 0.01, step_epsilon: 0.01, adaptive: false, merge_epsilon: 0.002, drop_covered: false }
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
    (0..images.len())
        .map(|j| {
            let covered = settings.drop_covered.then(|| covered_samples(images, views, j, settings.connectivity()));
            images[j].mesh_with(settings, settings.connectivity().for_view(&views[j]), covered.as_deref())
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
        let epsilon: Connectivity = epsilon.into();
        let za = self.z(a.0, a.1);
        let zb = self.z(b.0, b.1);
        let Connectivity { epsilon, step, steep } = epsilon;
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

    /// True when tile `(tx, ty)` (of [`TILE`]² neighbourhoods) is merged into a few large triangles: it is
    /// whole (its `(TILE + 1)²` samples lie in the image), every one of its neighbourhoods keeps both
    /// triangles (by `epsilon`), and every sample's inverse depth is within `merge_epsilon` (relative) of the
    /// affine function through the tile's corners `z(0,0)`, `z(TILE,0)`, `z(0,TILE)`: on a plane inverse depth
    /// is affine in image coordinates, so this is the second-difference test taken across the whole tile, with a
    /// tolerance that planes pass to rounding and that bounds how far a merged tile strays from its samples.
    pub fn tile_merged(&self, tx: u32, ty: u32, epsilon: impl Into<Connectivity>, merge_epsilon: f32) -> bool {
        let epsilon: Connectivity = epsilon.into();
        let (u0, v0) = (tx * TILE, ty * TILE);
        if u0 + TILE >= self.resolution || v0 + TILE >= self.resolution {
            return false;
        }
        let z = |i: u32, j: u32| self.z((u0 + i) as i64, (v0 + j) as i64);
        let (z00, z10, z01) = (z(0, 0), z(TILE, 0), z(0, TILE));
        for j in 0..=TILE {
            for i in 0..=TILE {
                let fit = z00 + (z10 - z00) * (i as f32 / TILE as f32) + (z01 - z00) * (j as f32 / TILE as f32);
                let zs = z(i, j);
                // Written so that NaN fails.
                let on_plane = (zs - fit).abs() < merge_epsilon * zs;
                if !on_plane {
                    return false;
                }
            }
        }
        (0..TILE).all(|j| (0..TILE).all(|i| self.neighbourhood(u0 + i, v0 + j, epsilon).iter().all(Option::is_some)))
    }

    /// The triangles of the adaptive mesh (a deviation beyond the paper, see `insm/mod.rs`): a merged tile
    /// ([`SampledImage::tile_merged`]) is two triangles when its four neighbours are merged (or absent), else
    /// a fan from its centre sample over its boundary, where each side facing a merged (or absent) neighbour
    /// is one segment and each other side keeps all `TILE + 1` samples; other tiles keep Algorithm 2's
    /// triangles. Neighbours share every vertex of a common side, so there are no T-junctions, hence no cracks.
    /// `merged` is the flags of every tile, row-major (`tiles_per_side(resolution)²`). With `covered` (per
    /// sample, [`covered_samples`]) a triangle whose three corners are covered is dropped, and a merged tile
    /// whose samples are all covered.
    pub fn tile_triangles(
        &self,
        tx: u32,
        ty: u32,
        epsilon: impl Into<Connectivity>,
        merged: &[bool],
        covered: Option<&[bool]>,
    ) -> Vec<[u32; 3]> {
        let epsilon: Connectivity = epsilon.into();
        let r = self.resolution;
        let tps = tiles_per_side(r);
        let (u0, v0) = (tx * TILE, ty * TILE);
        let is_covered = |i: u32| covered.is_some_and(|c| c[i as usize]);
        let mut out = Vec::new();
        if !merged[(ty * tps + tx) as usize] {
            for v in v0..(v0 + TILE).min(r.saturating_sub(1)) {
                for u in u0..(u0 + TILE).min(r.saturating_sub(1)) {
                    let kept = self.neighbourhood(u, v, epsilon).into_iter().flatten();
                    out.extend(kept.filter(|t| !t.iter().all(|&i| is_covered(i))));
                }
            }
            return out;
        }
        let index = |i: u32, j: u32| (v0 + j) * r + u0 + i;
        if (0..=TILE).all(|j| (0..=TILE).all(|i| is_covered(index(i, j)))) {
            return out;
        }
        // A neighbour without neighbourhoods (outside the image, or past its last sample) has no side to meet.
        let neighbourhoods = r.saturating_sub(1) as i64;
        let neighbour_merged = |dx: i64, dy: i64| {
            let (nx, ny) = (tx as i64 + dx, ty as i64 + dy);
            let absent = nx < 0 || ny < 0 || nx * TILE as i64 >= neighbourhoods || ny * TILE as i64 >= neighbourhoods;
            absent || merged[(ny as u32 * tps + nx as u32) as usize]
        };
        // Sides in fan order (top right to left, left down, bottom left to right, right up), each as its
        // boundary point k = 0..=TILE and its neighbour.
        type SidePoint = fn(u32) -> (u32, u32);
        let sides: [(SidePoint, (i64, i64)); 4] = [
            (|k| (TILE - k, 0), (0, -1)),
            (|k| (0, k), (-1, 0)),
            (|k| (k, TILE), (0, 1)),
            (|k| (TILE, TILE - k), (1, 0)),
        ];
        let coarse: Vec<bool> = sides.iter().map(|(_, (dx, dy))| neighbour_merged(*dx, *dy)).collect();
        if coarse.iter().all(|&c| c) {
            out.push([index(0, 0), index(0, TILE), index(TILE, TILE)]);
            out.push([index(TILE, TILE), index(TILE, 0), index(0, 0)]);
            return out;
        }
        let centre = index(TILE / 2, TILE / 2);
        for ((point, _), coarse) in sides.iter().zip(coarse) {
            let step = if coarse { TILE } else { 1 };
            for k in (0..TILE).step_by(step as usize) {
                let (a, b) = (point(k), point(k + step));
                out.push([centre, index(a.0, a.1), index(b.0, b.1)]);
            }
        }
        out
    }

    /// The merge flag of every tile, row-major.
    pub fn merged_tiles(&self, epsilon: impl Into<Connectivity>, merge_epsilon: f32) -> Vec<bool> {
        let epsilon: Connectivity = epsilon.into();
        let tps = tiles_per_side(self.resolution);
        (0..tps * tps).map(|t| self.tile_merged(t % tps, t / tps, epsilon, merge_epsilon)).collect()
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
        let tps = tiles_per_side(self.resolution);
        let merged = if settings.adaptive {
            self.merged_tiles(connectivity, settings.merge_epsilon)
        } else {
            vec![false; (tps * tps) as usize]
        };
        (0..tps * tps).flat_map(|t| self.tile_triangles(t % tps, t / tps, connectivity, &merged, covered)).collect()
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
mod tests {
    use super::*;

    fn adaptive_mesh(epsilon: f32) -> MeshSettings {
        MeshSettings { epsilon, step_epsilon: epsilon, adaptive: true, ..MeshSettings::default() }
    }

    /// A `r x r` image of inverse depths from `f(x, y)` (positions on a fake grid).
    fn image(r: u32, f: impl Fn(u32, u32) -> f32) -> Vec<Vec4> {
        (0..r * r).map(|i| Vec4::new((i % r) as f32, (i / r) as f32, 0.0, f(i % r, i / r))).collect()
    }

    #[test]
    fn a_steep_edge_is_held_to_the_tighter_tolerance_and_only_a_steep_one() {
        // Rows of inverse depth bending by about 3 % a sample: between the step tolerance (2 %) and ε (4 %).
        let tolerances = |steep: f32| Connectivity { epsilon: 0.04, step: 0.02, steep };
        let steep_row = [0.100, 0.103, 0.109, 0.118];
        let s = image(4, |x, _| steep_row[x as usize]);
        let img = SampledImage { resolution: 4, samples: &s };
        // Edge (1, 2) changes inverse depth by 5.5 % (relative): steep above a slope of 0.03, not below 0.1.
        assert!(img.edge_connected((1, 0), (2, 0), tolerances(0.0)), "no edge is steep: ε holds");
        assert!(img.edge_connected((1, 0), (2, 0), tolerances(0.1)), "not steep for this map: ε holds");
        assert!(!img.edge_connected((1, 0), (2, 0), tolerances(0.03)), "steep: the 2 % tolerance cuts it");
        // A diagonal edge's change is over √2 samples: steep only above √2 times the slope.
        let d = image(4, |x, y| steep_row[x.max(y) as usize]);
        let diag = SampledImage { resolution: 4, samples: &d };
        assert!(diag.edge_connected((1, 1), (2, 2), tolerances(0.05)), "5.5 % over √2 samples is under 0.05");
        assert!(!diag.edge_connected((1, 1), (2, 2), tolerances(0.03)));
        // A row that bends as much but changes little (1.5 % a sample) is not steep: ε keeps it.
        let zigzag = [0.100, 0.1015, 0.100, 0.1015];
        let z = image(4, |x, _| zigzag[x as usize]);
        let flat = SampledImage { resolution: 4, samples: &z };
        assert!(flat.edge_connected((1, 0), (2, 0), tolerances(0.03)));
        assert!(!flat.edge_connected((1, 0), (2, 0), Connectivity::from(0.02)), "the step tolerance alone cuts it");
        // The steepness of a map: tan(angle) sample widths; none at 90° or for a bad angle.
        let slope = steep_slope(75.0, 100.0, 128);
        assert!((slope - 75f32.to_radians().tan() * 2.0 * 50f32.to_radians().tan() / 128.0).abs() < 1e-6);
        assert!((steep_slope(75.0, 100.0, 256) - 0.5 * slope).abs() < 1e-6, "finer maps, finer samples");
        for bad in [90.0, 120.0, -5.0, f32::NAN] {
            assert_eq!(steep_slope(bad, 100.0, 128), 0.0, "{bad}");
        }
        // At 0° every edge whose depth changes is steep (the tighter tolerance everywhere but on flat rows).
        assert!(steep_slope(0.0, 100.0, 128) > 0.0);
        assert!(!img.edge_connected((1, 0), (2, 0), tolerances(steep_slope(0.0, 100.0, 128))));
    }

    #[test]
    fn a_plane_is_fully_connected_whatever_its_slope() {
        for (a, b, c) in [(0.5, 0.0, 0.0), (0.5, 0.01, 0.02), (0.9, -0.03, 0.005)] {
            let s = image(9, |x, y| a + b * x as f32 + c * y as f32);
            let img = SampledImage { resolution: 9, samples: &s };
            assert_eq!(img.triangles(1e-4).len(), 2 * 8 * 8, "plane {a} {b} {c}");
            assert!(img.dropped_edges(1e-4).is_empty());
        }
    }

    #[test]
    fn a_depth_step_is_not_bridged() {
        // Left half near (z=1), right half far (z=0.25): a discontinuity between x=3 and x=4.
        let s = image(8, |x, _| if x < 4 { 1.0 } else { 0.25 });
        let img = SampledImage { resolution: 8, samples: &s };
        let tris = img.triangles(0.05);
        for t in &tris {
            let xs: Vec<u32> = t.iter().map(|&i| i % 8).collect();
            assert!(xs.iter().all(|&x| x < 4) || xs.iter().all(|&x| x >= 4), "triangle {t:?} spans the step");
        }
        // Only the edges across the step go (both second differences fail, with opposite signs): in the inner
        // rows the neighbourhoods of column 3 lose their triangles, every other column keeps them, so each side
        // keeps its last sample (the paper's half-sample erosion). The paper's "both below ε" also dropped
        // columns 2 and 4. (In the first and last rows a diagonal next to the step has one outer sample outside
        // the image and the other across the step: it is dropped, the ambiguous case.)
        let inner = |t: &&[u32; 3]| t.iter().all(|&i| (1..7).contains(&(i / 8)));
        assert_eq!(tris.iter().filter(inner).count(), 2 * 5 * 6);
        let dropped = img.dropped_edges(0.05);
        let across = |e: &DroppedEdge| e.from.x == 3.0 && e.to.x == 4.0;
        assert!(dropped.iter().all(|e| across(e) || e.from.y == 0.0 || e.to.y == 7.0), "{dropped:?}");
        assert_eq!(dropped.iter().filter(|e| across(e)).count(), 8 + 7, "the step's horizontal and diagonal edges");
    }

    #[test]
    fn a_crease_cuts_one_edge_and_a_spike_is_not_bridged() {
        // A crease (a roof: inverse depth rising then falling, the kink between x = 3 and x = 4): only the edges
        // across the kink go (the paper's "both below ε" also dropped the columns either side).
        let roof = image(8, |x, _| if x < 4 { 0.5 + 0.05 * x as f32 } else { 0.5 + 0.05 * (7 - x) as f32 });
        let img = SampledImage { resolution: 8, samples: &roof };
        let inner = |t: &&[u32; 3]| t.iter().all(|&i| (1..7).contains(&(i / 8)));
        assert_eq!(img.triangles(0.01).iter().filter(inner).count(), 2 * 6 * 5);
        // A one-sample spike in front of the ground is not bridged to it.
        let spike = image(8, |x, _| if x == 3 { 1.0 } else { 0.25 });
        let img = SampledImage { resolution: 8, samples: &spike };
        assert!(img.triangles(0.01).iter().all(|t| t.iter().all(|&i| i % 8 != 3)));
    }

    #[test]
    fn dilation_moves_the_samples_at_a_cut_edge_half_a_sample_across_it_and_no_other() {
        // A step between x = 3 (near, z = 1) and x = 4 (far, z = 0.25) on a grid of unit spacing: both sides
        // end at their last sample, so the union of the meshes misses the strip 3..4 (the half-sample erosion
        // on each side). Dilated, the near side reaches 3.5 and the far side starts there.
        let s = image(8, |x, _| if x < 4 { 1.0 } else { 0.25 });
        let img = SampledImage { resolution: 8, samples: &s };
        let d = img.dilated(0.05);
        for (i, (before, after)) in s.iter().zip(&d).enumerate() {
            let (x, y) = (i % 8, i / 8);
            assert_eq!(after.w, before.w, "inverse depth is kept");
            let expected_x = match x {
                3 | 4 => 3.5,
                _ => x as f32,
            };
            // (In the first and last rows the diagonal next to the step is ambiguous, but dilation only looks
            // along the axes.)
            assert_eq!((after.x, after.y), (expected_x, y as f32), "sample ({x}, {y})");
        }
        // A bar three samples wide in front of the ground grows to three samples' width (2.5 to 5.5); a bar one
        // sample wide has no triangle and does not move; the ground's samples next to a bar move under it.
        let bar = image(14, |x, _| if (3..=5).contains(&x) || x == 9 { 1.0 } else { 0.25 });
        let img = SampledImage { resolution: 14, samples: &bar };
        let d = img.dilated(0.05);
        let x_at = |x: usize| d[5 * 14 + x].x;
        assert_eq!([x_at(3), x_at(4), x_at(5)], [2.5, 4.0, 5.5]);
        assert_eq!(x_at(9), 9.0, "a one-sample bar has no kept edge behind it");
        assert_eq!([x_at(2), x_at(6), x_at(8), x_at(10)], [2.5, 5.5, 8.5, 9.5]);
        // Nothing moves on a plane, nor at the image's border (the surface goes on outside it).
        let plane = image(9, |x, y| 0.5 + 0.01 * x as f32 + 0.02 * y as f32);
        let img = SampledImage { resolution: 9, samples: &plane };
        assert_eq!(img.dilated(1e-3), plane);
    }

    #[test]
    fn dilation_extrapolates_along_a_slanted_surface() {
        // World positions along a slope (z rises by 0.3 per sample) ending at a step: the last sample moves
        // half a step along the slope, in depth too, not in the image plane alone.
        let r = 8;
        let s: Vec<Vec4> = (0..r * r)
            .map(|i| {
                let (x, y) = (i % r, i / r);
                if x < 5 {
                    Vec4::new(x as f32, y as f32, 0.3 * x as f32, 1.0 / (2.0 + 0.1 * x as f32))
                } else {
                    Vec4::new(x as f32, y as f32, 5.0, 0.1)
                }
            })
            .collect();
        let img = SampledImage { resolution: r, samples: &s };
        let d = img.dilated(0.01);
        let last = d[(3 * r + 4) as usize];
        assert!((last.x - 4.5).abs() < 1e-6 && (last.z - 1.35).abs() < 1e-6, "{last}");
    }

    #[test]
    fn dilation_leaves_a_surface_seen_at_a_grazing_angle() {
        // A plane (inverse depth affine in the image) ending at a step to a far surface; its view depth grows by
        // 0.2-0.4 per sample. Spaced 1 apart sideways it is seen nearly face-on and its last sample moves; spaced
        // 0.05 apart it is seen almost edge-on (depth changing six times faster than the spacing) and stays.
        let r = 10;
        for (spacing, moves) in [(1.0f32, true), (0.05, false)] {
            let s: Vec<Vec4> = (0..r * r)
                .map(|i| {
                    let (x, y) = (i % r, i / r);
                    let w = if x < 5 { 0.5 - 0.04 * x as f32 } else { 0.05 };
                    Vec4::new(spacing * x as f32, spacing * y as f32, 1.0 / w, w)
                })
                .collect();
            let img = SampledImage { resolution: r, samples: &s };
            let last = img.dilated(0.01)[(4 * r + 4) as usize];
            assert_eq!(last.x != s[(4 * r + 4) as usize].x, moves, "spacing {spacing}: {last}");
        }
    }

    /// Checks a mesh of an image whose neighbourhoods all keep their triangles: it covers the image's square
    /// exactly (the triangles' areas sum to it and every interior edge joins exactly two triangles, so there is
    /// no hole, overlap or T-junction crack), and every triangle has Algorithm 2's winding.
    fn assert_watertight(r: u32, tris: &[[u32; 3]]) {
        let xy = |i: u32| ((i % r) as i64, (i / r) as i64);
        let mut area2 = 0i64;
        let mut edges: std::collections::HashMap<(u32, u32), u32> = Default::default();
        for t in tris {
            let [a, b, c] = t.map(xy);
            let cross = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
            assert!(cross < 0, "triangle {t:?} is degenerate or wound the other way");
            area2 -= cross;
            for (p, q) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((p.min(q), p.max(q))).or_default() += 1;
            }
        }
        let side = (r - 1) as i64;
        assert_eq!(area2, 2 * side * side, "the triangles do not cover the image exactly once");
        for (&(p, q), &n) in &edges {
            let (a, b) = (xy(p), xy(q));
            let on_border = (a.0 == b.0 && (a.0 == 0 || a.0 == side)) || (a.1 == b.1 && (a.1 == 0 || a.1 == side));
            assert!(n == 2 || (n == 1 && on_border), "edge {a:?}-{b:?} is used {n} times (a crack or T-junction)");
        }
    }

    #[test]
    fn a_planar_image_becomes_a_few_triangles_per_tile_and_stays_watertight() {
        let r = 8 * TILE + 1;
        for (a, b, c) in [(0.5, 0.0, 0.0), (0.5, 0.002, 0.003), (0.9, -0.004, 0.001)] {
            let s = image(r, |x, y| a + b * x as f32 + c * y as f32);
            let img = SampledImage { resolution: r, samples: &s };
            let full = img.triangles(1e-3);
            let adaptive = img.mesh(&adaptive_mesh(1e-3));
            assert_eq!(full.len(), 2 * 64 * 64);
            // 8x8 merged tiles of two triangles each (the ninth tile column and row hold no neighbourhood).
            assert_eq!(adaptive.len(), 2 * 64, "plane {a} {b} {c}");
            assert_watertight(r, &adaptive);
        }
    }

    #[test]
    fn a_curved_image_keeps_full_resolution() {
        // Second differences 0.002 pass the edge test at epsilon 0.01, but across a tile the surface bends by
        // far more than 1 % of its depth: no tile merges.
        let r = 4 * TILE + 1;
        let s = image(r, |x, y| 0.5 + 0.001 * (x * x + y * y) as f32);
        let img = SampledImage { resolution: r, samples: &s };
        assert!(img.merged_tiles(0.01, MeshSettings::default().merge_epsilon).iter().all(|m| !m));
        let sorted = |mut t: Vec<[u32; 3]>| {
            t.sort();
            t
        };
        assert_eq!(sorted(img.mesh(&adaptive_mesh(0.01))), sorted(img.triangles(0.01)));
        assert_eq!(img.triangles(0.01).len(), 2 * 32 * 32);
    }

    #[test]
    fn merged_and_full_tiles_meet_without_cracks() {
        // A plane with a bump in one tile: that tile and its neighbours' shared sides keep every sample.
        let r = 4 * TILE + 1;
        let bump = |x: u32, y: u32| {
            let (dx, dy) = (x as f32 - 12.0, y as f32 - 12.0);
            0.012 * (-(dx * dx + dy * dy) / 16.0).exp()
        };
        let s = image(r, |x, y| 0.6 + 0.001 * x as f32 + bump(x, y));
        let img = SampledImage { resolution: r, samples: &s };
        // The crack test, at a merge tolerance as loose as epsilon so that the bump's neighbours merge.
        let settings = MeshSettings {
            epsilon: 0.01,
            step_epsilon: 0.01,
            adaptive: true,
            merge_epsilon: 0.01,
            drop_covered: false,
        };
        let merged = img.merged_tiles(0.01, settings.merge_epsilon);
        let tps = tiles_per_side(r) as usize;
        assert!(!merged[tps + 1], "the bump's tile must not merge");
        assert!(merged.iter().filter(|&&m| m).count() >= 8, "the flat tiles merge: {merged:?}");
        let mesh = img.mesh(&settings);
        assert!(mesh.len() < img.triangles(0.01).len() / 2);
        assert_watertight(r, &mesh);
    }

    #[test]
    fn the_default_merge_tolerance_keeps_curved_tiles_that_epsilon_would_merge() {
        // A gentle bend: within epsilon (1 %) of each tile's plane, not within the merge tolerance.
        let r = 4 * TILE + 1;
        let s = image(r, |x, y| 0.5 + 0.00004 * (x * x + y * y) as f32);
        let img = SampledImage { resolution: r, samples: &s };
        assert!(img.merged_tiles(0.01, 0.01).iter().filter(|&&m| m).count() >= 4);
        assert!(img.merged_tiles(0.01, MeshSettings::default().merge_epsilon).iter().filter(|&&m| m).count() < 4);
    }

    /// A camera at `eye` looking straight down (up = -z), 60°, with near and far as INSM sets them.
    fn looking_down(eye: Vec3) -> MapView {
        let (near, far) = (0.01, 20.0);
        let clip_from_world = crate::math::perspective_rh(60f32.to_radians(), 1.0, near, far)
            * crate::math::look_to_rh(eye, -Vec3::Y, Vec3::NEG_Z);
        MapView { clip_from_world, near, far, steep: 0.0 }
    }

    /// The `r x r` samples of `view` seeing the plane y = `height` (world position, inverse view depth), as
    /// the GPU writes them: a ray through each sample's centre.
    fn samples_of_plane(view: &MapView, r: u32, height: f32) -> Vec<Vec4> {
        let world_from_clip = view.clip_from_world.inverse();
        (0..r * r)
            .map(|i| {
                let ndc = Vec2::new(
                    ((i % r) as f32 + 0.5) / r as f32 * 2.0 - 1.0,
                    1.0 - ((i / r) as f32 + 0.5) / r as f32 * 2.0,
                );
                let a = world_from_clip.project_point3(ndc.extend(0.0));
                let b = world_from_clip.project_point3(ndc.extend(1.0));
                let p = a + (b - a) * ((height - a.y) / (b.y - a.y));
                let c = view.clip_from_world * p.extend(1.0);
                let z = c.z / c.w;
                p.extend((view.far - z * (view.far - view.near)) / (view.near * view.far))
            })
            .collect()
    }

    /// Sample `i` of a map of `r²` projected into `view`'s image: inside it with a margin of `margin` samples.
    fn inside(view: &MapView, p: Vec3, r: u32, margin: f32) -> bool {
        let c = view.clip_from_world * p.extend(1.0);
        let ndc = c.truncate() / c.w;
        let (fx, fy) = ((ndc.x + 1.0) * 0.5 * r as f32 - 0.5, (1.0 - ndc.y) * 0.5 * r as f32 - 0.5);
        let hi = r as f32 - 1.0 - margin;
        fx >= margin && fy >= margin && fx <= hi && fy <= hi
    }

    #[test]
    fn a_map_drops_what_a_finer_map_reconstructs_and_keeps_the_rest() {
        // A near map (2 m above the ground) and a far one (6 m, three times coarser, seeing three times as
        // much): the far map's triangles over the near map's footprint go, the rest stay, the near map keeps all.
        let r = 33;
        let settings = MeshSettings { drop_covered: true, ..MeshSettings::default() };
        for near_first in [true, false] {
            let (near, far) = (looking_down(Vec3::new(0.0, 2.0, 0.0)), looking_down(Vec3::new(0.3, 6.0, 0.0)));
            let (near_s, far_s) = (samples_of_plane(&near, r, 0.0), samples_of_plane(&far, r, 0.0));
            let (views, samples, n, f) = if near_first {
                ([near, far], [&near_s, &far_s], 0, 1)
            } else {
                ([far, near], [&far_s, &near_s], 1, 0)
            };
            let images: Vec<SampledImage> =
                samples.iter().map(|s| SampledImage { resolution: r, samples: s }).collect();
            let meshes = meshes(&images, &views, &settings);
            assert_eq!(meshes[n].len(), images[n].triangles(settings.epsilon).len(), "the finest map keeps everything");
            let kept: std::collections::HashSet<[u32; 3]> = meshes[f].iter().copied().collect();
            let (mut dropped, mut outside) = (0, 0);
            for t in images[f].triangles(settings.epsilon) {
                let corners = t.map(|i| images[f].samples[i as usize].truncate());
                if corners.iter().all(|&p| inside(&views[n], p, r, 1.0)) {
                    assert!(!kept.contains(&t), "near first {near_first}: {t:?} is over the near map and kept");
                    dropped += 1;
                } else if corners.iter().any(|&p| !inside(&views[n], p, r, -0.5)) {
                    assert!(kept.contains(&t), "near first {near_first}: {t:?} is outside the near map and dropped");
                    outside += 1;
                }
            }
            assert!(dropped > 100 && outside > 1000, "{dropped} dropped, {outside} outside the near map");
            // Without the option nothing is dropped.
            let all = self::meshes(&images, &views, &MeshSettings { drop_covered: false, ..settings });
            assert_eq!(all[f].len(), images[f].triangles(settings.epsilon).len());
        }
    }

    #[test]
    fn the_covered_test_asks_of_the_point_a_sample_saw_not_of_its_moved_vertex() {
        let r = 33;
        let (near, far) = (looking_down(Vec3::new(0.0, 2.0, 0.0)), looking_down(Vec3::new(0.3, 6.0, 0.0)));
        let (near_s, far_s) = (samples_of_plane(&near, r, 0.0), samples_of_plane(&far, r, 0.0));
        // The point a sample saw, from its inverse depth and its map's camera, is where the sample is.
        let world_from_clip = far.clip_from_world.inverse();
        for (i, s) in far_s.iter().enumerate() {
            let seen = far.sample_position(&world_from_clip, i as u32 % r, i as u32 / r, r, s.w);
            assert!(seen.distance(s.truncate()) < 1e-3 * (1.0 + s.truncate().length()), "{seen} vs {s}");
        }
        let views = [near, far];
        let covered = |far_samples: &[Vec4]| {
            let images = [
                SampledImage { resolution: r, samples: &near_s },
                SampledImage { resolution: r, samples: far_samples },
            ];
            covered_samples(&images, &views, 1, 0.01)
        };
        let plain = covered(&far_s);
        assert!(plain.iter().filter(|&&c| c).count() > 100, "the near map covers part of the far one");
        // The far map's vertices moved 30 cm off the plane (as dilation moves the ones at a cut edge), their
        // inverse depths kept: the same samples are covered, since the test asks of the points they saw.
        let moved: Vec<Vec4> = far_s.iter().map(|s| (s.truncate() + Vec3::Y * 0.3).extend(s.w)).collect();
        assert_eq!(covered(&moved), plain);
    }

    #[test]
    fn equal_maps_keep_one_copy_and_other_surfaces_are_not_covered() {
        let r = 17;
        let settings = MeshSettings { drop_covered: true, ..MeshSettings::default() };
        let view = looking_down(Vec3::new(0.0, 3.0, 0.0));
        let ground = samples_of_plane(&view, r, 0.0);
        // The same map twice: the lower-numbered one keeps every triangle, the other only those touching its
        // border (a border sample projects onto the first map's border, half a sample from its neighbourhoods'
        // edge, rounded either way).
        let images =
            [SampledImage { resolution: r, samples: &ground }, SampledImage { resolution: r, samples: &ground }];
        let m = meshes(&images, &[view, view], &settings);
        let full = images[0].triangles(settings.epsilon).len();
        assert_eq!(m[0].len(), full);
        let border = |i: u32| i.is_multiple_of(r) || i / r == 0 || i % r == r - 1 || i / r == r - 1;
        assert!(m[1].iter().all(|t| t.iter().any(|&i| border(i))), "an inner triangle of the copy is kept");
        assert!(m[1].len() <= 2 * 4 * (r as usize - 2), "{} of {full} triangles kept by the copy", m[1].len());
        // A map of a plane 0.5 m above the ground (a table top): the ground map does not reconstruct it, and
        // the table does not cover the ground map.
        let top = samples_of_plane(&view, r, 0.5);
        let images = [SampledImage { resolution: r, samples: &ground }, SampledImage { resolution: r, samples: &top }];
        let m = meshes(&images, &[view, view], &settings);
        assert_eq!(m[0].len(), full);
        assert_eq!(m[1].len(), full);
    }

    #[test]
    fn every_sample_belongs_to_one_tile() {
        assert_eq!(tiles_per_side(16 * TILE), 16);
        assert_eq!(tiles_per_side(16 * TILE + 1), 17);
    }
}
