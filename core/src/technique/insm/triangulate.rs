//! INSM Algorithm 2 on the CPU: the twin of `shaders/insm_triangulate.wgsl`, run on the vertices the GPU wrote
//! (world position and inverse depth per sample). The technique uses it for its overlays (the reconstructed
//! mesh, its samples and the dropped edges); the tests check the GPU against it.
//!
//! See the shader for the connectivity test and the tile merging of the adaptive mesh. Samples are indexed
//! `(u, v)` = `(x, y)`, row-major per image.

use glam::{Vec3, Vec4};

/// Neighbourhoods per tile side; the workgroup size of `insm_triangulate.wgsl`.
pub const TILE: u32 = 8;
/// Triangle slots per tile: two per neighbourhood.
pub const MAX_TRIANGLES_PER_TILE: u32 = 2 * TILE * TILE;

/// Mirrors `Tile` in `insm_triangulate.wgsl`: the triangles a tile kept and their bounds.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTile {
    pub count: u32,
    /// 1 when the adaptive mesh merged the tile.
    pub merged: u32,
    pub _pad: [u32; 2],
    pub bounds_min: [f32; 4],
    pub bounds_max: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<GpuTile>() == 48);

/// Tiles per image side for `resolution` samples per side (every sample belongs to one tile).
pub fn tiles_per_side(resolution: u32) -> u32 {
    resolution.div_ceil(TILE)
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

    /// `IsConnected` for one edge (a, b): both valid, both second differences below `epsilon` (relative).
    pub fn edge_connected(&self, a: (i64, i64), b: (i64, i64), epsilon: f32) -> bool {
        let za = self.z(a.0, a.1);
        let zb = self.z(b.0, b.1);
        if za <= 0.0 || zb <= 0.0 {
            return false;
        }
        let d = (b.0 - a.0, b.1 - a.1);
        let ok = |prev: f32, mid: f32, next: f32| {
            prev < 0.0 || next < 0.0 || (prev + next - 2.0 * mid).abs() < epsilon * mid
        };
        ok(self.z(a.0 - d.0, a.1 - d.1), za, zb) && ok(za, zb, self.z(b.0 + d.0, b.1 + d.1))
    }

    /// The kept triangles of neighbourhood `(u, v)` (Algorithm 2, lines 2-5), as sample indices.
    pub fn neighbourhood(&self, u: u32, v: u32, epsilon: f32) -> [Option<[u32; 3]>; 2] {
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
    /// triangles, and every sample's inverse depth is within `epsilon` (relative, as the connectivity test) of
    /// the affine function through the tile's corners `z(0,0)`, `z(TILE,0)`, `z(0,TILE)`: on a plane inverse depth
    /// is affine in image coordinates, so this is the second-difference test taken across the whole tile.
    pub fn tile_merged(&self, tx: u32, ty: u32, epsilon: f32) -> bool {
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
                let on_plane = (zs - fit).abs() < epsilon * zs;
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
    /// `merged` is the flags of every tile, row-major (`tiles_per_side(resolution)²`).
    pub fn tile_triangles(&self, tx: u32, ty: u32, epsilon: f32, merged: &[bool]) -> Vec<[u32; 3]> {
        let r = self.resolution;
        let tps = tiles_per_side(r);
        let (u0, v0) = (tx * TILE, ty * TILE);
        let mut out = Vec::new();
        if !merged[(ty * tps + tx) as usize] {
            for v in v0..(v0 + TILE).min(r.saturating_sub(1)) {
                for u in u0..(u0 + TILE).min(r.saturating_sub(1)) {
                    out.extend(self.neighbourhood(u, v, epsilon).into_iter().flatten());
                }
            }
            return out;
        }
        let index = |i: u32, j: u32| (v0 + j) * r + u0 + i;
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
    pub fn merged_tiles(&self, epsilon: f32) -> Vec<bool> {
        let tps = tiles_per_side(self.resolution);
        (0..tps * tps).map(|t| self.tile_merged(t % tps, t / tps, epsilon)).collect()
    }

    /// The reconstructed mesh: the adaptive one when `adaptive`, else Algorithm 2's ([`SampledImage::triangles`]).
    pub fn mesh(&self, epsilon: f32, adaptive: bool) -> Vec<[u32; 3]> {
        if !adaptive {
            return self.triangles(epsilon);
        }
        let tps = tiles_per_side(self.resolution);
        let merged = self.merged_tiles(epsilon);
        (0..tps * tps).flat_map(|t| self.tile_triangles(t % tps, t / tps, epsilon, &merged)).collect()
    }

    /// Every kept triangle, neighbourhood by neighbourhood.
    pub fn triangles(&self, epsilon: f32) -> Vec<[u32; 3]> {
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
    pub fn dropped_edges(&self, epsilon: f32) -> Vec<DroppedEdge> {
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

    /// A `r x r` image of inverse depths from `f(x, y)` (positions on a fake grid).
    fn image(r: u32, f: impl Fn(u32, u32) -> f32) -> Vec<Vec4> {
        (0..r * r).map(|i| Vec4::new((i % r) as f32, (i / r) as f32, 0.0, f(i % r, i / r))).collect()
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
        // The paper's test also drops the edges next to the step (their second difference sees it): the
        // neighbourhoods at columns 2, 3 and 4 lose their triangles, columns 0, 1, 5 and 6 keep theirs.
        assert_eq!(tris.len(), 2 * 7 * (2 + 2));
        let dropped = img.dropped_edges(0.05);
        assert!(dropped.iter().any(|e| e.from.x == 3.0 && e.to.x == 4.0));
    }

    #[test]
    fn background_samples_drop_their_triangles() {
        let s = image(6, |x, y| if x == 2 && y == 2 { 0.0 } else { 0.5 });
        let img = SampledImage { resolution: 6, samples: &s };
        let tris = img.triangles(0.01);
        assert!(tris.iter().all(|t| !t.contains(&(2 * 6 + 2))));
        assert!(tris.len() < 2 * 5 * 5);
        assert_eq!(img.valid_samples(), 35);
        // A background image has no triangles at all.
        let empty = image(6, |_, _| 0.0);
        assert!(SampledImage { resolution: 6, samples: &empty }.triangles(1.0).is_empty());
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
            let adaptive = img.mesh(1e-3, true);
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
        assert!(img.merged_tiles(0.01).iter().all(|m| !m));
        let sorted = |mut t: Vec<[u32; 3]>| {
            t.sort();
            t
        };
        assert_eq!(sorted(img.mesh(0.01, true)), sorted(img.triangles(0.01)));
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
        let merged = img.merged_tiles(0.01);
        let tps = tiles_per_side(r) as usize;
        assert!(!merged[tps + 1], "the bump's tile must not merge");
        assert!(merged.iter().filter(|&&m| m).count() >= 8, "the flat tiles merge: {merged:?}");
        let mesh = img.mesh(0.01, true);
        assert!(mesh.len() < img.triangles(0.01).len() / 2);
        assert_watertight(r, &mesh);
    }

    #[test]
    fn every_sample_belongs_to_one_tile() {
        assert_eq!(tiles_per_side(16 * TILE), 16);
        assert_eq!(tiles_per_side(16 * TILE + 1), 17);
    }
}
