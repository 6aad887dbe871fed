//! CPU traversal of the [`Bvh`]: the twin of `raytrace_bvh.wgsl`, operation for operation (any hit and closest
//! hit, with a filter for cut-out materials), and the brute-force oracles the tests hold both against.

use glam::Vec3;

use super::{Bvh, BvhNode, BvhTriangle, MAX_DEPTH, MIN_DIR};

#[inline]
fn v3(a: &[f32; 4]) -> [f32; 3] {
    [a[0], a[1], a[2]]
}
#[inline]
fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline]
fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Reciprocal of a ray direction with tiny components replaced by [`MIN_DIR`] (`bvh_safe_inverse`).
pub fn safe_inverse(dir: Vec3) -> Vec3 {
    let d = Vec3::select(dir.abs().cmplt(Vec3::splat(MIN_DIR)), Vec3::splat(MIN_DIR), dir);
    Vec3::ONE / d
}

/// Slab test (`bvh_ray_box`): the entry distance when the ray meets the box within `[0, t_max]`, else +inf.
pub fn ray_box(origin: Vec3, inv_dir: Vec3, min: [f32; 3], max: [f32; 3], t_max: f32) -> f32 {
    let t0 = (Vec3::from_array(min) - origin) * inv_dir;
    let t1 = (Vec3::from_array(max) - origin) * inv_dir;
    let tn = t0.min(t1);
    let tf = t0.max(t1);
    let enter = tn.x.max(tn.y).max(tn.z.max(0.0));
    let exit = tf.x.min(tf.y).min(tf.z.min(t_max));
    if enter <= exit {
        enter
    } else {
        f32::INFINITY
    }
}

/// Whether the ray meets the root's box within `t_max` (false for an empty tree): where both traversals start.
fn enters_root(nodes: &[BvhNode], origin: Vec3, inv: Vec3, t_max: f32) -> bool {
    nodes.first().is_some_and(|root| ray_box(origin, inv, root.min, root.max, t_max) != f32::INFINITY)
}

/// The two children of an inner node whose first child is `a`, the nearer first, with their entry distances
/// within `t_max` (+inf for a child the ray misses): the child order both traversals share with the WGSL.
fn ordered_children(nodes: &[BvhNode], a: usize, origin: Vec3, inv: Vec3, t_max: f32) -> (usize, usize, f32, f32) {
    let ta = ray_box(origin, inv, nodes[a].min, nodes[a].max, t_max);
    let tb = ray_box(origin, inv, nodes[a + 1].min, nodes[a + 1].max, t_max);
    if ta <= tb {
        (a, a + 1, ta, tb)
    } else {
        (a + 1, a, tb, ta)
    }
}

/// Möller–Trumbore (`bvh_ray_triangle`): true when the ray hits the triangle at `0 < t < t_max`.
pub fn ray_triangle(origin: Vec3, dir: Vec3, tri: &BvhTriangle, t_max: f32) -> bool {
    ray_triangle_hit(origin, dir, tri, t_max).is_some()
}

/// Any-hit traversal, the CPU twin of `bvh_occluded` in `raytrace_bvh.wgsl`: same layout, same order, same
/// stack bound. True when a triangle lies on `origin + t * dir` for `0 < t < t_max`.
pub fn occluded_cpu(bvh: &Bvh, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
    occluded_cpu_filtered(bvh, origin, dir, t_max, &|_, _, _| true)
}

/// [`occluded_cpu`] counting only the hits `accept(triangle, u, v)` keeps (the alpha test of cut-outs,
/// `bvh_cut_out` on the GPU).
pub fn occluded_cpu_filtered(
    bvh: &Bvh,
    origin: Vec3,
    dir: Vec3,
    t_max: f32,
    accept: &dyn Fn(u32, f32, f32) -> bool,
) -> bool {
    let inv = safe_inverse(dir);
    let nodes = &bvh.nodes;
    if !enters_root(nodes, origin, inv, t_max) {
        return false;
    }
    let mut stack = [0u32; MAX_DEPTH];
    let mut sp = 0usize;
    let mut node = 0usize;
    loop {
        let n = &nodes[node];
        if n.count > 0 {
            let first = n.first as usize;
            for (k, tri) in bvh.triangles[first..first + n.count as usize].iter().enumerate() {
                if let Some((_, u, v)) = ray_triangle_hit(origin, dir, tri, t_max) {
                    if accept((first + k) as u32, u, v) {
                        return true;
                    }
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            node = stack[sp] as usize;
            continue;
        }
        let (near, far, t_near, t_far) = ordered_children(nodes, n.first as usize, origin, inv, t_max);
        if t_near == f32::INFINITY {
            if sp == 0 {
                return false;
            }
            sp -= 1;
            node = stack[sp] as usize;
            continue;
        }
        node = near;
        if t_far != f32::INFINITY && sp < MAX_DEPTH {
            stack[sp] = far as u32;
            sp += 1;
        }
    }
}

/// The nearest hit of a ray: distance, triangle (index into [`Bvh::triangles`]) and barycentrics of `v1`, `v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
    pub u: f32,
    pub v: f32,
}

/// Möller–Trumbore with the hit's distance and barycentrics (`bvh_ray_triangle_hit`): `Some((t, u, v))` when
/// the ray hits at `0 < t < t_max`.
pub fn ray_triangle_hit(origin: Vec3, dir: Vec3, tri: &BvhTriangle, t_max: f32) -> Option<(f32, f32, f32)> {
    let (o, d) = (origin.to_array(), dir.to_array());
    let e1 = v3(&tri.e1);
    let e2 = v3(&tri.e2);
    let p = cross(d, e2);
    let det = dot(e1, p);
    if det == 0.0 {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = sub(o, v3(&tri.v0));
    let u = dot(s, p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = cross(s, e1);
    let v = dot(d, q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = dot(e2, q) * inv_det;
    (t > 0.0 && t < t_max).then_some((t, u, v))
}

/// Closest-hit traversal, the CPU twin of `bvh_closest_hit` in `raytrace_bvh.wgsl`: the nearest triangle on
/// `origin + t * dir` for `0 < t < t_max`. Children are visited near first and a subtree is skipped when its
/// box starts beyond the nearest hit so far.
pub fn closest_hit_cpu(bvh: &Bvh, origin: Vec3, dir: Vec3, t_max: f32) -> Option<Hit> {
    closest_hit_cpu_filtered(bvh, origin, dir, t_max, &|_, _, _| true)
}

/// [`closest_hit_cpu`] over the hits `accept(triangle, u, v)` keeps (the alpha test of cut-outs).
pub fn closest_hit_cpu_filtered(
    bvh: &Bvh,
    origin: Vec3,
    dir: Vec3,
    t_max: f32,
    accept: &dyn Fn(u32, f32, f32) -> bool,
) -> Option<Hit> {
    let inv = safe_inverse(dir);
    let nodes = &bvh.nodes;
    if !enters_root(nodes, origin, inv, t_max) {
        return None;
    }
    let mut best: Option<Hit> = None;
    let mut t_best = t_max;
    let mut stack = [0u32; MAX_DEPTH];
    let mut sp = 0usize;
    let mut node = 0usize;
    loop {
        let n = &nodes[node];
        if n.count > 0 {
            let first = n.first as usize;
            for (k, tri) in bvh.triangles[first..first + n.count as usize].iter().enumerate() {
                if let Some((t, u, v)) = ray_triangle_hit(origin, dir, tri, t_best) {
                    if accept((first + k) as u32, u, v) {
                        t_best = t;
                        best = Some(Hit { t, triangle: (first + k) as u32, u, v });
                    }
                }
            }
        } else {
            let (near, far, t_near, t_far) = ordered_children(nodes, n.first as usize, origin, inv, t_best);
            if t_near != f32::INFINITY {
                node = near;
                if t_far != f32::INFINITY && sp < MAX_DEPTH {
                    stack[sp] = far as u32;
                    sp += 1;
                }
                continue;
            }
        }
        // Pop the next subtree that can still hold a nearer hit.
        loop {
            if sp == 0 {
                return best;
            }
            sp -= 1;
            let candidate = stack[sp] as usize;
            if ray_box(origin, inv, nodes[candidate].min, nodes[candidate].max, t_best) != f32::INFINITY {
                node = candidate;
                break;
            }
        }
    }
}

/// Every triangle tested: the oracle of [`closest_hit_cpu`].
pub fn closest_hit_brute_force(bvh: &Bvh, origin: Vec3, dir: Vec3, t_max: f32) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    let mut t_best = t_max;
    for (i, tri) in bvh.triangles.iter().enumerate() {
        if let Some((t, u, v)) = ray_triangle_hit(origin, dir, tri, t_best) {
            t_best = t;
            best = Some(Hit { t, triangle: i as u32, u, v });
        }
    }
    best
}

/// Every triangle tested: the oracle of [`occluded_cpu`].
pub fn occluded_brute_force(bvh: &Bvh, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
    bvh.triangles.iter().any(|t| ray_triangle(origin, dir, t, t_max))
}
