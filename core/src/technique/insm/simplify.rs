//! The reconstructed meshes simplified before the per-light maps draw them (beyond the paper, `simplify` below
//! 1; off by default).
//!
//! Algorithm 2 makes two triangles per 2x2 samples and the adaptive mesh merges only planar blocks (2x2 to 8x8
//! neighbourhoods), so every neighbourhood at a crease, an edge or a silhouette keeps its triangles: the
//! meshes are 5-21 times the built-in scenes they stand for (Cornell box: 48,100 triangles for 2,292; 95,524
//! when only whole tiles merged). Every light's cube map draws them, so INSM is slower than the reference there. Here
//! the triangles the GPU wrote are read back once per mesh and collapsed with meshoptimizer's quadric edge
//! collapse ([`meshopt::simplify`]) toward `keep` of their count, never moving the surface by more than
//! `max_error` (world units). The meshes' borders (cut edges, holes, image borders) are not locked: a border
//! vertex collapses only along its border, so a silhouette moves by no more than the bound either (unlike the
//! scene's copy in [`crate::scene::proxy`], whose materials are simplified apart and would open cracks between
//! them; each map's mesh here is one piece). Vertices keep their inverse view depth (the fourth float), so each is still pushed by its own sample's width. The
//! result is cut into chunks like the scene's ([`crate::scene::chunks::push_chunks`]), each covering about as
//! much surface as a tile did, for the same per-light and per-face culling.

use glam::Vec4;

use crate::scene::chunks::{push_chunks, Chunk};

use super::triangulate::MAX_TRIANGLES_PER_TILE;

/// The fewest triangles a chunk of the simplified mesh holds (smaller ones would make draw calls the cost).
const MIN_CHUNK_TRIANGLES: u32 = 16;

/// A simplified mesh: indices into the samples the GPU wrote, and its chunks.
#[derive(Clone, Debug, Default)]
pub struct SimplifiedMesh {
    pub indices: Vec<u32>,
    pub chunks: Vec<Chunk>,
}

impl SimplifiedMesh {
    pub fn triangle_count(&self) -> u64 {
        self.indices.len() as u64 / 3
    }
}

/// `triangles` (indices into `samples`: world position and inverse view depth) simplified toward `keep` of
/// their count within `max_error` world units. Triangles with a corner that is not a finite surface sample are
/// dropped first; `keep` and `max_error` that are not finite leave the mesh as it is.
pub fn simplify(samples: &[Vec4], triangles: &[[u32; 3]], keep: f32, max_error: f32) -> SimplifiedMesh {
    let valid = |i: u32| samples.get(i as usize).is_some_and(|s| s.is_finite() && s.w > 0.0);
    let source: Vec<u32> = triangles.iter().filter(|t| t.iter().all(|&i| valid(i))).flatten().copied().collect();
    let mut out = SimplifiedMesh::default();
    if source.is_empty() {
        return out;
    }
    let keep = if keep.is_finite() { keep.clamp(1e-4, 1.0) } else { 1.0 };
    let max_error = if max_error.is_finite() { max_error.max(0.0) } else { 0.0 };
    let mut indices = source.clone();
    if keep < 1.0 {
        let target = ((source.len() / 3) as f32 * keep).ceil().max(1.0) as usize * 3;
        let bytes: &[u8] = bytemuck::cast_slice(samples);
        if let Ok(adapter) = meshopt::VertexDataAdapter::new(bytes, std::mem::size_of::<Vec4>(), 0) {
            indices = meshopt::simplify(
                &source,
                &adapter,
                target,
                max_error,
                // Borders free: a border vertex collapses only along its border (meshoptimizer's rule), within
                // the bound. Locked, the simplified meshes kept 2.2 times the triangles (the conference room
                // x1.31 instead of x1.50, docs/techniques/insm.md).
                meshopt::SimplifyOptions::ErrorAbsolute,
                None,
            );
        }
    }
    let tris: Vec<[u32; 3]> = indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    let before = (source.len() / 3) as u32;
    let per_chunk = (MAX_TRIANGLES_PER_TILE * tris.len() as u32).div_ceil(before.max(1));
    let per_chunk = per_chunk.clamp(MIN_CHUNK_TRIANGLES, MAX_TRIANGLES_PER_TILE) as usize;
    let position = |i: u32| samples[i as usize].truncate();
    push_chunks(&mut out.indices, &mut out.chunks, position, tris, 0, per_chunk);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// An `n` x `n` grid of samples on the plane y = 0 (inverse depth 1), as Algorithm 2 triangulates it, and
    /// a second, separate grid 0.5 above it shifted by half its size (a step: two meshes with borders).
    fn two_grids(n: u32) -> (Vec<Vec4>, Vec<[u32; 3]>) {
        let mut samples = Vec::new();
        let mut tris = Vec::new();
        for (g, (dx, y)) in [(0.0, 0.0), (0.5 * n as f32, 0.5)].into_iter().enumerate() {
            let base = (g as u32) * n * n;
            for j in 0..n {
                for i in 0..n {
                    samples.push(Vec4::new(i as f32 + dx, y, j as f32, 1.0));
                }
            }
            for j in 0..n - 1 {
                for i in 0..n - 1 {
                    let a = base + j * n + i;
                    tris.push([a, a + n, a + n + 1]);
                    tris.push([a + n + 1, a + 1, a]);
                }
            }
        }
        (samples, tris)
    }

    fn area(samples: &[Vec4], indices: &[u32]) -> f32 {
        indices
            .chunks_exact(3)
            .map(|t| {
                let p = [t[0], t[1], t[2]].map(|i| samples[i as usize].truncate());
                0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
            })
            .sum()
    }

    #[test]
    fn flat_meshes_collapse_to_their_borders_and_keep_their_area_and_planes() {
        let (samples, tris) = two_grids(17);
        let s = simplify(&samples, &tris, 0.01, 0.01);
        let before = tris.len() as u64;
        assert!(s.triangle_count() * 4 < before, "{} of {before} triangles kept", s.triangle_count());
        let full: Vec<u32> = tris.iter().flatten().copied().collect();
        let (a, b) = (area(&samples, &s.indices), area(&samples, &full));
        assert!((a - b).abs() < 1e-3 * b, "area {b} -> {a}");
        // Every vertex is one of the samples.
        assert!(s.indices.iter().all(|&i| (i as usize) < samples.len()));
        // Chunks cover the indices exactly once, and hold at most a tile's worth.
        let covered: u32 = s.chunks.iter().map(|c| c.index_count).sum();
        assert_eq!(covered as usize, s.indices.len());
        assert!(s.chunks.iter().all(|c| c.triangle_count() <= MAX_TRIANGLES_PER_TILE));
        // Kept whole (keep = 1): the same triangles.
        let same = simplify(&samples, &tris, 1.0, 0.01);
        assert_eq!(same.triangle_count(), before);
    }

    #[test]
    fn a_curved_border_collapses_only_along_itself() {
        // A disc of radius 8 cut out of a flat grid (the border a silhouette makes in a depth image): the
        // interior collapses, the border may lose vertices along itself but not cut across the disc.
        let n = 19u32;
        let samples: Vec<Vec4> =
            (0..n * n).map(|k| Vec4::new((k % n) as f32 - 9.0, 0.0, (k / n) as f32 - 9.0, 1.0)).collect();
        let inside = |i: u32| samples[i as usize].truncate().length() <= 8.0;
        let mut tris = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = j * n + i;
                for t in [[a, a + n, a + n + 1], [a + n + 1, a + 1, a]] {
                    if t.iter().all(|&v| inside(v)) {
                        tris.push(t);
                    }
                }
            }
        }
        let s = simplify(&samples, &tris, 0.01, 0.05);
        assert!(s.triangle_count() * 2 < tris.len() as u64, "{} of {} kept", s.triangle_count(), tris.len());
        let full: Vec<u32> = tris.iter().flatten().copied().collect();
        let (a, b) = (area(&samples, &s.indices), area(&samples, &full));
        assert!((a - b).abs() < 0.02 * b, "the disc's area {b} became {a}");
        // No vertex left the disc or the plane.
        assert!(s.indices.iter().all(|&i| inside(i) && samples[i as usize].y == 0.0));
    }

    #[test]
    fn a_bent_surface_is_kept_within_the_error_bound() {
        // A grid folded along x = 8 (a crease of 45 degrees): the collapse may flatten each side, not the crease.
        let n = 17u32;
        let mut samples = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let x = i as f32;
                samples.push(Vec4::new(x, (x - 8.0).max(0.0), j as f32, 1.0));
            }
        }
        let mut tris = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = j * n + i;
                tris.push([a, a + n, a + n + 1]);
                tris.push([a + n + 1, a + 1, a]);
            }
        }
        let s = simplify(&samples, &tris, 0.01, 0.01);
        assert!(s.triangle_count() < tris.len() as u64 / 4);
        // Every kept triangle's centroid lies on the folded surface (within the bound).
        for t in s.indices.chunks_exact(3) {
            let c = t.iter().map(|&i| samples[i as usize].truncate()).sum::<Vec3>() / 3.0;
            let on = (c.x - 8.0).max(0.0);
            assert!((c.y - on).abs() < 0.02, "a triangle left the surface: centroid {c}");
        }
    }

    #[test]
    fn broken_input_gives_a_defined_mesh() {
        let (mut samples, tris) = two_grids(5);
        samples[0] = Vec4::new(f32::NAN, 0.0, 0.0, 1.0);
        samples[1].w = 0.0; // background
        let mut bad = tris.clone();
        bad.push([0, 1, 9999]); // out of range
        for (keep, err) in [(0.5, 0.01), (f32::NAN, f32::INFINITY), (-1.0, -1.0)] {
            let s = simplify(&samples, &bad, keep, err);
            assert!(s.indices.iter().all(|&i| samples[i as usize].is_finite() && samples[i as usize].w > 0.0));
        }
        assert_eq!(simplify(&samples, &[], 0.5, 0.01).triangle_count(), 0);
    }
}
