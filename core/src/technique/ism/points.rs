//! Step 1, the point-based approximation of the scene (Ritschel et al. 2008, section 3.1): a pool of points
//! uniform by area over the scene's triangles, made once per scene on the CPU (deterministic, seeded) and cached
//! with the technique, and the subset of the pool each map splats.
//!
//! The pool is stratified along the triangles' cumulative area (one seeded uniform offset, then evenly spaced:
//! every triangle gets its area's share of the points, within one, and the chunks are Morton-ordered, so the pool
//! covers the scene evenly), then shuffled with the same seed (Fisher-Yates). A map takes `points_per_map`
//! consecutive points of the shuffled pool from its own offset, as Ritschel's VPLs each take their own random
//! subset; consecutive points of a shuffled stratified pool are a random subset of it.

use glam::Vec3;

use crate::accel::scene_bvh::CutoutAlpha;
use crate::scene::chunks::ChunkedGeometry;
use crate::scene::random::SplitMix64;

/// The most points a pool holds (16 MiB on the GPU as `vec4<f32>`).
pub const MAX_POOL_POINTS: usize = 1 << 20;
/// Disjoint subsets of `points_per_map` the pool holds (when that fits [`MAX_POOL_POINTS`]). Ritschel's pool
/// has one subset per VPL (8 M points for 1,024 VPLs); ours is capped for memory, and maps past the 32nd reuse
/// subsets: what matters to one map's quality is its own subset's size, and neighbouring lights rarely share one.
pub const POOL_SUBSETS: usize = 32;

/// The pool size for maps of `points_per_map` points: [`POOL_SUBSETS`] subsets, at most [`MAX_POOL_POINTS`],
/// at least one subset.
pub fn pool_size(points_per_map: usize) -> usize {
    (points_per_map.saturating_mul(POOL_SUBSETS)).min(MAX_POOL_POINTS).max(points_per_map)
}

/// Where map `index` (a light's index among the frame's lights, or a VPL's) starts in a pool of `pool`: its
/// subset is the `points_per_map` points from there, wrapping around. A light keeps its subset whatever the
/// other lights do.
pub fn subset_offset(index: usize, points_per_map: usize, pool: usize) -> u32 {
    if pool == 0 {
        return 0;
    }
    ((index as u64 * points_per_map as u64) % pool as u64) as u32
}

/// `count` points uniform by area over `geometry`'s triangles (degenerate and non-finite ones skipped; points
/// on a cut-out texel of an alpha-tested material dropped, so leaves stay leaf-shaped), stratified and shuffled
/// with `seed`. Empty when the geometry has no area. Fewer than `count` only when cut-outs dropped some.
pub fn sample_points(
    geometry: &ChunkedGeometry,
    cutouts: &[Option<CutoutAlpha>],
    count: usize,
    seed: u32,
) -> Vec<Vec3> {
    let mut rng = SplitMix64::new(0x1575_0000_0000_0000 ^ seed as u64);
    // Triangles with their material, in index order (chunks are index ranges of one material).
    let mut material = vec![u32::MAX; geometry.triangle_count()];
    for c in &geometry.chunks {
        let first = (c.first_index / 3) as usize;
        for m in material.iter_mut().skip(first).take(c.triangle_count() as usize) {
            *m = c.material;
        }
    }
    let corner = |t: usize, j: usize| {
        let i = geometry.indices[t * 3 + j] as usize;
        geometry.vertices.get(i).copied()
    };
    // Cumulative area (f64: a million triangles of very different sizes).
    let mut cumulative = Vec::with_capacity(geometry.triangle_count());
    let mut total = 0f64;
    for t in 0..geometry.triangle_count() {
        let area = match (corner(t, 0), corner(t, 1), corner(t, 2)) {
            (Some(a), Some(b), Some(c)) => {
                let (a, b, c) = (Vec3::from(a.position), Vec3::from(b.position), Vec3::from(c.position));
                let area = 0.5 * (b - a).cross(c - a).length() as f64;
                if area.is_finite() {
                    area
                } else {
                    0.0
                }
            }
            _ => 0.0,
        };
        total += area;
        cumulative.push(total);
    }
    if count == 0 || total <= 0.0 {
        return Vec::new();
    }
    let offset = rng.next_f32() as f64;
    let mut points = Vec::with_capacity(count);
    let mut t = 0usize;
    for k in 0..count {
        let target = (k as f64 + offset) / count as f64 * total;
        while t + 1 < cumulative.len() && cumulative[t] <= target {
            t += 1;
        }
        let (Some(a), Some(b), Some(c)) = (corner(t, 0), corner(t, 1), corner(t, 2)) else { continue };
        // Uniform on the triangle: the square-root warp of two uniforms.
        let (r1, r2) = (rng.next_f32().sqrt(), rng.next_f32());
        let (wa, wb, wc) = (1.0 - r1, r1 * (1.0 - r2), r1 * r2);
        let cut = cutouts
            .get(material[t] as usize)
            .and_then(|m| m.as_ref())
            .is_some_and(|alpha| cut_out(alpha, [a.uv, b.uv, c.uv], [wa, wb, wc]));
        if cut {
            continue;
        }
        let p = Vec3::from(a.position) * wa + Vec3::from(b.position) * wb + Vec3::from(c.position) * wc;
        if p.is_finite() {
            points.push(p);
        }
    }
    // Fisher-Yates with the same generator: any run of consecutive points is a random subset.
    for i in (1..points.len()).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        points.swap(i, j);
    }
    points
}

/// True when the point at barycentric weights `w` of a triangle with corner UVs `uv` lands on a texel of `alpha`
/// below its cutoff (nearest texel, repeat): the depth passes' alpha test, on the CPU.
fn cut_out(alpha: &CutoutAlpha, uv: [[f32; 2]; 3], w: [f32; 3]) -> bool {
    let u = uv[0][0] * w[0] + uv[1][0] * w[1] + uv[2][0] * w[2];
    let v = uv[0][1] * w[0] + uv[1][1] * w[1] + uv[2][1] * w[2];
    if !(u.is_finite() && v.is_finite()) || alpha.width == 0 || alpha.height == 0 {
        return false;
    }
    let x = ((u - u.floor()) * alpha.width as f32) as u32 % alpha.width;
    let y = ((v - v.floor()) * alpha.height as f32) as u32 % alpha.height;
    let a = alpha.alpha.get((y * alpha.width + x) as usize).copied().unwrap_or(255);
    (a as f32 / 255.0) < alpha.cutoff
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::chunks::{Chunk, Vertex};

    /// Two triangles in the plane y = 0: the first of area 0.5, the second of area 1.5.
    fn geometry() -> ChunkedGeometry {
        let v = |x: f32, z: f32| Vertex { position: [x, 0.0, z], normal: [0.0, 1.0, 0.0], uv: [x, z] };
        let vertices = vec![v(0.0, 0.0), v(1.0, 0.0), v(0.0, 1.0), v(10.0, 0.0), v(13.0, 0.0), v(10.0, 1.0)];
        let chunk = Chunk {
            first_index: 0,
            index_count: 6,
            material: 0,
            bounds: crate::scene::Aabb { min: Vec3::ZERO, max: Vec3::new(13.0, 0.0, 1.0) },
        };
        ChunkedGeometry { vertices, uv1: vec![[0.0; 2]; 6], indices: vec![0, 1, 2, 3, 4, 5], chunks: vec![chunk] }
    }

    #[test]
    fn points_are_uniform_by_area_deterministic_and_on_the_triangles() {
        let g = geometry();
        let points = sample_points(&g, &[], 4000, 7);
        assert_eq!(points.len(), 4000);
        assert_eq!(points, sample_points(&g, &[], 4000, 7), "same seed, same pool");
        assert_ne!(points, sample_points(&g, &[], 4000, 8), "another seed, another pool");
        let first = points.iter().filter(|p| p.x <= 1.0).count();
        // Stratified: exactly the area's share within one point.
        assert!((first as i64 - 1000).abs() <= 1, "{first} of 4000 on the triangle of a quarter of the area");
        for p in &points {
            let on_first = p.x >= 0.0 && p.z >= 0.0 && p.x + p.z <= 1.0 + 1e-5;
            let on_second = p.x >= 10.0 && p.z >= 0.0 && (p.x - 10.0) / 3.0 + p.z <= 1.0 + 1e-5;
            assert!(p.y == 0.0 && (on_first || on_second), "{p} is on neither triangle");
        }
        // Shuffled: the first 400 (one map's subset) hold about a quarter from the small triangle too.
        let head = points[..400].iter().filter(|p| p.x <= 1.0).count();
        assert!((60..140).contains(&head), "{head} of the first 400");
    }

    #[test]
    fn no_area_no_points_and_cut_outs_are_dropped() {
        let empty = ChunkedGeometry::default();
        assert!(sample_points(&empty, &[], 100, 0).is_empty());
        let mut degenerate = geometry();
        degenerate.vertices.iter_mut().for_each(|v| v.position = [1.0, 2.0, 3.0]);
        assert!(sample_points(&degenerate, &[], 100, 0).is_empty());
        assert!(sample_points(&geometry(), &[], 0, 0).is_empty());
        // A 2x1 mask: u in [0, 0.5) is cut out. The first triangle (u = x in 0..1) loses about half its points.
        let alpha = CutoutAlpha { cutoff: 0.5, width: 2, height: 1, alpha: vec![0, 255] };
        let points = sample_points(&geometry(), &[Some(alpha)], 4000, 1);
        let kept_first = points.iter().filter(|p| p.x <= 1.0).count();
        assert!(points.len() < 4000 && kept_first < 700, "{} points, {kept_first} on the first", points.len());
        assert!(points.iter().all(|p| (p.x - p.x.floor()) >= 0.5), "a point on a cut-out texel was kept");
    }

    #[test]
    fn subsets_are_disjoint_then_wrap() {
        let pool = pool_size(1000);
        assert_eq!(pool, 32_000);
        assert_eq!(subset_offset(0, 1000, pool), 0);
        assert_eq!(subset_offset(3, 1000, pool), 3000);
        assert_eq!(subset_offset(32, 1000, pool), 0);
        assert_eq!(pool_size(2_000_000), 2_000_000, "a pool holds at least one map's points");
        assert_eq!(pool_size(100_000), MAX_POOL_POINTS);
        assert_eq!(subset_offset(5, 10, 0), 0);
    }
}
