//! A binary BVH over the scene's triangles for shadow rays, built on the CPU with binned SAH and laid out for
//! the GPU, plus the CPU twin of the GPU traversal (`raytrace_bvh.wgsl`) and a brute-force oracle ([`traverse`]).
//!
//! Layout (mirrored in `raytrace_bvh.wgsl`):
//! - [`BvhNode`], 32 bytes: the node's box, and `first`/`count`. An interior node has `count == 0` and its two
//!   children at `first` and `first + 1` (allocated as a pair); a leaf has `count > 0` triangles starting at
//!   `first` in [`Bvh::triangles`]. Node 0 is the root.
//! - [`BvhTriangle`], 48 bytes: `v0`, `e1 = v1 - v0`, `e2 = v2 - v0` (Möller–Trumbore's inputs), triangles
//!   reordered so every leaf's are contiguous.
//!
//! Node boxes are padded by a tiny absolute margin (a 1e-5 fraction of the scene's size) so the box test is
//! conservative against the rounding of the triangle test: traversal then finds exactly the hits brute force
//! finds. The depth is capped at [`MAX_DEPTH`] (the traversal stack size): a node that deep becomes a leaf.

use std::time::Instant;

use glam::Vec3;

use crate::scene::chunks::ChunkedGeometry;
use crate::scene::Aabb;

mod traverse;
pub use traverse::*;

/// Deepest node level; equals the traversal stack size in `raytrace_bvh.wgsl` (`BVH_STACK_SIZE`): a ray
/// pushes at most one node per interior level on its path.
pub const MAX_DEPTH: usize = 32;
/// SAH bins per axis.
const BINS: usize = 16;
/// Leaves hold at most this many triangles unless the triangles cannot be split (coincident centroids at
/// [`MAX_DEPTH`]).
pub const MAX_LEAF: usize = 4;
/// SAH cost of visiting a node, relative to one triangle test.
const TRAVERSAL_COST: f32 = 1.0;
/// Direction components smaller than this are replaced by it before the reciprocal (no `0 * inf` NaNs in the
/// slab test). Same constant in `raytrace_bvh.wgsl`.
pub const MIN_DIR: f32 = 1e-20;

/// Mirrors `BvhNode` in `raytrace_bvh.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhNode {
    pub min: [f32; 3],
    /// Interior: index of the first child (the second is `first + 1`); leaf: first triangle.
    pub first: u32,
    pub max: [f32; 3],
    /// Triangles in a leaf; 0 for an interior node.
    pub count: u32,
}
const _: () = assert!(std::mem::size_of::<BvhNode>() == 32);

/// Mirrors `BvhTriangle` in `raytrace_bvh.wgsl`: `w` components unused.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhTriangle {
    pub v0: [f32; 4],
    pub e1: [f32; 4],
    pub e2: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<BvhTriangle>() == 48);

impl BvhTriangle {
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Self {
        BvhTriangle {
            v0: a.extend(0.0).to_array(),
            e1: (b - a).extend(0.0).to_array(),
            e2: (c - a).extend(0.0).to_array(),
        }
    }
    pub fn vertices(&self) -> [Vec3; 3] {
        let v0 = Vec3::new(self.v0[0], self.v0[1], self.v0[2]);
        let e1 = Vec3::new(self.e1[0], self.e1[1], self.e1[2]);
        let e2 = Vec3::new(self.e2[0], self.e2[1], self.e2[2]);
        [v0, v0 + e1, v0 + e2]
    }
}

/// Facts about a built BVH.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BvhStats {
    pub triangles: usize,
    /// Zero-area triangles left out (they cannot block a ray).
    pub degenerate_skipped: usize,
    pub nodes: usize,
    pub leaves: usize,
    /// Deepest leaf (root = 0).
    pub max_depth: usize,
    pub max_leaf_triangles: usize,
    /// Leaves forced at [`MAX_DEPTH`] with more than [`MAX_LEAF`] triangles.
    pub depth_capped_leaves: usize,
    pub build_ms: f64,
}

/// A BVH ready for upload: nodes (root first) and triangles in leaf order.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    pub triangles: Vec<BvhTriangle>,
    /// For each entry of `triangles`, the index of the input triangle it came from.
    pub triangle_ids: Vec<u32>,
    pub stats: BvhStats,
}

/// A shadow ray: `origin + t * dir` for `t` in `(0, t_max)`. Mirrors `TestRay` in `raytrace_test.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Ray {
    pub origin: [f32; 3],
    pub t_max: f32,
    pub dir: [f32; 3],
    pub _pad: f32,
}
const _: () = assert!(std::mem::size_of::<Ray>() == 32);

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3, t_max: f32) -> Ray {
        Ray { origin: origin.to_array(), t_max, dir: dir.to_array(), _pad: 0.0 }
    }
}

struct Prim {
    min: Vec3,
    max: Vec3,
    centroid: Vec3,
}

#[derive(Clone, Copy)]
struct Bin {
    min: Vec3,
    max: Vec3,
    count: u32,
}

impl Bin {
    const EMPTY: Bin = Bin { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY), count: 0 };
    fn grow(&mut self, min: Vec3, max: Vec3, count: u32) {
        self.min = self.min.min(min);
        self.max = self.max.max(max);
        self.count += count;
    }
}

fn half_area(min: Vec3, max: Vec3) -> f32 {
    let d = (max - min).max(Vec3::ZERO);
    d.x * d.y + d.y * d.z + d.z * d.x
}

impl Bvh {
    /// BVH over every triangle of the merged scene geometry (triangle `i` = indices `3i..3i+3`).
    pub fn from_geometry(geometry: &ChunkedGeometry) -> Bvh {
        let p = |i: u32| Vec3::from_array(geometry.vertices[i as usize].position);
        let triangles: Vec<[Vec3; 3]> = geometry.indices.chunks_exact(3).map(|t| [p(t[0]), p(t[1]), p(t[2])]).collect();
        Bvh::build(&triangles)
    }

    /// Binned-SAH build over `triangles`. Zero-area and non-finite triangles are left out.
    pub fn build(triangles: &[[Vec3; 3]]) -> Bvh {
        let start = Instant::now();
        let mut prims = Vec::with_capacity(triangles.len());
        let mut ids: Vec<u32> = Vec::with_capacity(triangles.len());
        let mut scene = Aabb::EMPTY;
        let mut degenerate = 0;
        for (i, t) in triangles.iter().enumerate() {
            let finite = t.iter().all(|v| v.is_finite());
            if !finite || (t[1] - t[0]).cross(t[2] - t[0]) == Vec3::ZERO {
                degenerate += 1;
                continue;
            }
            let min = t[0].min(t[1]).min(t[2]);
            let max = t[0].max(t[1]).max(t[2]);
            scene.extend(min);
            scene.extend(max);
            prims.push(Prim { min, max, centroid: (min + max) * 0.5 });
            ids.push(i as u32);
        }
        let mut bvh = Bvh::default();
        bvh.stats.degenerate_skipped = degenerate;
        if prims.is_empty() {
            // No nodes: every ray misses (the GPU copy is one leaf with one zero-area triangle, see
            // `Bvh::gpu_buffers`).
            bvh.stats.build_ms = start.elapsed().as_secs_f64() * 1000.0;
            return bvh;
        }
        let scale = scene.min.abs().max(scene.max.abs()).max_element().max(scene.size().max_element());
        let pad = Vec3::splat(scale * 1e-5);

        let mut order: Vec<u32> = (0..prims.len() as u32).collect();
        bvh.nodes.reserve(prims.len() * 2 / MAX_LEAF.max(1) + 1);
        bvh.nodes.push(BvhNode::zeroed_node());
        let mut builder =
            Builder { prims: &prims, order: &mut order, nodes: &mut bvh.nodes, stats: &mut bvh.stats, pad };
        // Explicit stack of (node, start, end, depth).
        let mut todo = vec![(0usize, 0usize, prims.len(), 0usize)];
        while let Some((node, s, e, depth)) = todo.pop() {
            if let Some((mid, left)) = builder.split_node(node, s, e, depth) {
                // Push right first so the left subtree is laid out right after the pair (depth-first order).
                todo.push((left + 1, mid, e, depth + 1));
                todo.push((left, s, mid, depth + 1));
            }
        }
        bvh.triangle_ids = order.iter().map(|&o| ids[o as usize]).collect();
        bvh.triangles = bvh
            .triangle_ids
            .iter()
            .map(|&i| {
                let t = &triangles[i as usize];
                BvhTriangle::new(t[0], t[1], t[2])
            })
            .collect();
        bvh.stats.triangles = bvh.triangles.len();
        bvh.stats.nodes = bvh.nodes.len();
        bvh.stats.build_ms = start.elapsed().as_secs_f64() * 1000.0;
        bvh
    }

    /// The node and triangle arrays to upload. An empty BVH becomes one leaf holding one zero-area triangle,
    /// which no ray hits (`det == 0`), so the GPU traversal needs no special case and no binding is empty.
    pub fn gpu_buffers(&self) -> (Vec<BvhNode>, Vec<BvhTriangle>) {
        if self.nodes.is_empty() {
            let leaf = BvhNode { min: [0.0; 3], first: 0, max: [0.0; 3], count: 1 };
            (vec![leaf], vec![bytemuck::Zeroable::zeroed()])
        } else {
            (self.nodes.clone(), self.triangles.clone())
        }
    }

    /// The box of node `i`.
    pub fn node_bounds(&self, i: usize) -> Aabb {
        let n = &self.nodes[i];
        Aabb { min: Vec3::from_array(n.min), max: Vec3::from_array(n.max) }
    }
}

impl BvhNode {
    fn zeroed_node() -> BvhNode {
        bytemuck::Zeroable::zeroed()
    }
}

struct Builder<'a> {
    prims: &'a [Prim],
    order: &'a mut [u32],
    nodes: &'a mut Vec<BvhNode>,
    stats: &'a mut BvhStats,
    pad: Vec3,
}

impl Builder<'_> {
    /// Fill node `node` for primitives `order[s..e]`; when it splits, allocate its two children and return
    /// (the split position, the left child's index).
    fn split_node(&mut self, node: usize, s: usize, e: usize, depth: usize) -> Option<(usize, usize)> {
        let (mut bmin, mut bmax) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let (mut cmin, mut cmax) = (bmin, bmax);
        for &o in &self.order[s..e] {
            let p = &self.prims[o as usize];
            bmin = bmin.min(p.min);
            bmax = bmax.max(p.max);
            cmin = cmin.min(p.centroid);
            cmax = cmax.max(p.centroid);
        }
        self.nodes[node].min = (bmin - self.pad).to_array();
        self.nodes[node].max = (bmax + self.pad).to_array();
        let n = e - s;
        let make_leaf = |stats: &mut BvhStats, nodes: &mut Vec<BvhNode>| {
            nodes[node].first = s as u32;
            nodes[node].count = n as u32;
            stats.leaves += 1;
            stats.max_depth = stats.max_depth.max(depth);
            stats.max_leaf_triangles = stats.max_leaf_triangles.max(n);
            if n > MAX_LEAF {
                stats.depth_capped_leaves += 1;
            }
            None
        };
        if n <= 1 || depth >= MAX_DEPTH {
            return make_leaf(self.stats, self.nodes);
        }

        // Bin centroids along all three axes at once.
        let extent = cmax - cmin;
        let mut bins = [[Bin::EMPTY; BINS]; 3];
        let inv = Vec3::select(extent.cmpgt(Vec3::ZERO), Vec3::splat(BINS as f32) / extent, Vec3::ZERO);
        let bin_of = |c: Vec3, axis: usize| (((c[axis] - cmin[axis]) * inv[axis]) as usize).min(BINS - 1);
        for &o in &self.order[s..e] {
            let p = &self.prims[o as usize];
            for (axis, axis_bins) in bins.iter_mut().enumerate() {
                axis_bins[bin_of(p.centroid, axis)].grow(p.min, p.max, 1);
            }
        }
        // Sweep: cost of splitting after bin k (left = bins 0..=k).
        let mut best: Option<(f32, usize, usize)> = None;
        for axis in 0..3 {
            if extent[axis] <= 0.0 {
                continue;
            }
            let b = &bins[axis];
            let mut right_cost = [0.0f32; BINS];
            let mut acc = Bin::EMPTY;
            for k in (1..BINS).rev() {
                acc.grow(b[k].min, b[k].max, b[k].count);
                right_cost[k] = if acc.count > 0 { half_area(acc.min, acc.max) * acc.count as f32 } else { 0.0 };
            }
            let mut left = Bin::EMPTY;
            for k in 0..BINS - 1 {
                left.grow(b[k].min, b[k].max, b[k].count);
                let right_count = n as u32 - left.count;
                if left.count == 0 || right_count == 0 {
                    continue;
                }
                let cost = half_area(left.min, left.max) * left.count as f32 + right_cost[k + 1];
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, k));
                }
            }
        }
        let parent_area = half_area(bmin, bmax).max(f32::MIN_POSITIVE);
        let mid = match best {
            Some((cost, axis, k)) => {
                let split_cost = TRAVERSAL_COST + cost / parent_area;
                if n <= MAX_LEAF && split_cost >= n as f32 {
                    return make_leaf(self.stats, self.nodes);
                }
                // Partition in place: bins 0..=k to the left.
                let slice = &mut self.order[s..e];
                let mut i = 0;
                let mut j = slice.len();
                while i < j {
                    if bin_of(self.prims[slice[i] as usize].centroid, axis) <= k {
                        i += 1;
                    } else {
                        j -= 1;
                        slice.swap(i, j);
                    }
                }
                s + i
            }
            // All centroids coincide: split by count when the leaf would be too large.
            None if n > MAX_LEAF => s + n / 2,
            None => return make_leaf(self.stats, self.nodes),
        };
        debug_assert!(mid > s && mid < e);
        let left = self.nodes.len();
        self.nodes.push(BvhNode::zeroed_node());
        self.nodes.push(BvhNode::zeroed_node());
        self.nodes[node].first = left as u32;
        self.nodes[node].count = 0;
        Some((mid, left))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize) -> Vec<[Vec3; 3]> {
        let mut out = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let p = Vec3::new(x as f32, 0.0, y as f32);
                out.push([p, p + Vec3::Z, p + Vec3::X]);
                out.push([p + Vec3::X, p + Vec3::Z, p + Vec3::new(1.0, 0.0, 1.0)]);
            }
        }
        out
    }

    #[test]
    fn closest_hit_equals_brute_force() {
        let mut tris = grid(6);
        // A second, raised layer so rays meet several triangles.
        let raised: Vec<[Vec3; 3]> = tris.iter().map(|t| t.map(|p| p + Vec3::new(0.1, 0.5, 0.0))).collect();
        tris.extend(raised);
        let bvh = Bvh::build(&tris);
        let mut hits = 0;
        for i in 0..400u32 {
            let f = |k: u32| ((i.wrapping_mul(2654435761).wrapping_add(k * 40503)) % 1000) as f32 / 1000.0;
            let origin = Vec3::new(f(1) * 6.0, 3.0, f(2) * 6.0 - 0.5);
            let dir = Vec3::new(f(3) - 0.5, -1.0, f(4) - 0.5).normalize();
            let a = closest_hit_cpu(&bvh, origin, dir, 100.0);
            let b = closest_hit_brute_force(&bvh, origin, dir, 100.0);
            assert_eq!(a.map(|h| h.t), b.map(|h| h.t), "ray {i}");
            hits += a.is_some() as u32;
        }
        assert!(hits > 100, "only {hits} rays hit: the test does not test");
    }

    #[test]
    fn every_triangle_lands_in_exactly_one_leaf_and_boxes_nest() {
        let tris = grid(40);
        let bvh = Bvh::build(&tris);
        assert_eq!(bvh.triangles.len(), tris.len());
        let mut seen = vec![0u32; tris.len()];
        let mut stack = vec![(0usize, 0usize)];
        while let Some((i, depth)) = stack.pop() {
            let n = bvh.nodes[i];
            assert!(depth <= MAX_DEPTH);
            if n.count > 0 {
                for k in n.first..n.first + n.count {
                    seen[bvh.triangle_ids[k as usize] as usize] += 1;
                    for v in bvh.triangles[k as usize].vertices() {
                        assert!(bvh.node_bounds(i).distance_squared(v) == 0.0);
                    }
                }
            } else {
                for c in [n.first as usize, n.first as usize + 1] {
                    let (outer, inner) = (bvh.node_bounds(i), bvh.node_bounds(c));
                    assert!(outer.min.cmple(inner.min).all() && outer.max.cmpge(inner.max).all());
                    stack.push((c, depth + 1));
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
        assert!(bvh.stats.max_leaf_triangles <= MAX_LEAF);
        assert!(bvh.stats.max_depth < 20, "{:?}", bvh.stats);
    }

    #[test]
    fn coincident_triangles_and_degenerate_ones() {
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let mut tris = vec![t; 100];
        tris.push([Vec3::ZERO, Vec3::X, Vec3::X * 2.0]);
        let bvh = Bvh::build(&tris);
        assert_eq!(bvh.stats.degenerate_skipped, 1);
        assert_eq!(bvh.triangles.len(), 100);
        assert!(bvh.stats.max_leaf_triangles <= MAX_LEAF);
        let o = Vec3::new(0.2, 0.2, 1.0);
        assert!(occluded_cpu(&bvh, o, Vec3::NEG_Z, 2.0));
        assert!(!occluded_cpu(&bvh, o, Vec3::NEG_Z, 0.5));
        assert!(!occluded_cpu(&bvh, o, Vec3::Z, 2.0));
        assert!(!occluded_cpu(&Bvh::build(&[]), o, Vec3::NEG_Z, 2.0));
    }

    #[test]
    fn axis_parallel_rays_hit_flat_boxes() {
        let bvh = Bvh::build(&grid(8));
        // Straight down onto the grid (dir has zero x and z), and along the plane (zero y).
        assert!(occluded_cpu(&bvh, Vec3::new(3.3, 1.0, 4.6), Vec3::NEG_Y, 5.0));
        assert!(!occluded_cpu(&bvh, Vec3::new(3.3, 1.0, 4.6), Vec3::Y, 5.0));
        assert!(!occluded_cpu(&bvh, Vec3::new(-1.0, 0.5, 4.6), Vec3::X, 50.0));
    }
}
