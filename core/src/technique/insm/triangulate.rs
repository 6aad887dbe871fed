//! INSM Algorithm 2 on the CPU: the twin of `shaders/insm_triangulate.wgsl`, run on the vertices the GPU wrote
//! (world position and inverse depth per sample). The technique uses it for its overlays (the reconstructed
//! mesh, its samples and the dropped edges); the tests check the GPU against it.
//!
//! See the shader for the connectivity test. Samples are indexed `(u, v)` = `(x, y)`, row-major per image.

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
    pub _pad: [u32; 3],
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

    #[test]
    fn every_sample_belongs_to_one_tile() {
        assert_eq!(tiles_per_side(16 * TILE), 16);
        assert_eq!(tiles_per_side(16 * TILE + 1), 17);
    }
}
