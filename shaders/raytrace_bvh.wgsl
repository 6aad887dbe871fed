// Ray-traced shadows: the scene BVH and any-hit traversal for shadow rays. The layout and every operation mirror
// core/src/technique/raytraced/bvh.rs (`BvhNode`, `BvhTriangle`, `occluded_cpu`), the CPU twin the tests compare
// this with. Composed in front of raytrace_shadow.wgsl (after common.wgsl) and of raytrace_test.wgsl.

// 32 bytes. Interior: count == 0, children at first and first + 1. Leaf: `count` triangles from `first`.
struct BvhNode {
    min: vec3<f32>,
    first: u32,
    max: vec3<f32>,
    count: u32,
}

// v0 and the two edges from it; w unused.
struct BvhTriangle {
    v0: vec4<f32>,
    e1: vec4<f32>,
    e2: vec4<f32>,
}

@group(1) @binding(0) var<storage, read> bvh_nodes: array<BvhNode>;
@group(1) @binding(1) var<storage, read> bvh_triangles: array<BvhTriangle>;

// = MAX_DEPTH in bvh.rs: the builder caps the depth so a ray never pushes more.
const BVH_STACK_SIZE: u32 = 32u;
// = MIN_DIR in bvh.rs.
const BVH_MIN_DIR: f32 = 1e-20;
const BVH_MISS: f32 = 3.0e38;

fn bvh_safe_inverse(dir: vec3<f32>) -> vec3<f32> {
    let d = select(dir, vec3<f32>(BVH_MIN_DIR), abs(dir) < vec3<f32>(BVH_MIN_DIR));
    return vec3<f32>(1.0) / d;
}

// Entry distance when the ray meets the box within [0, t_max], else BVH_MISS.
fn bvh_ray_box(origin: vec3<f32>, inv_dir: vec3<f32>, bmin: vec3<f32>, bmax: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (bmin - origin) * inv_dir;
    let t1 = (bmax - origin) * inv_dir;
    let tn = min(t0, t1);
    let tf = max(t0, t1);
    let enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
    let exit = min(min(tf.x, tf.y), min(tf.z, t_max));
    return select(BVH_MISS, enter, enter <= exit);
}

fn bvh_dot(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

// Möller–Trumbore: true when the ray hits the triangle at 0 < t < t_max.
fn bvh_ray_triangle(origin: vec3<f32>, dir: vec3<f32>, tri: BvhTriangle, t_max: f32) -> bool {
    let e1 = tri.e1.xyz;
    let e2 = tri.e2.xyz;
    let p = cross(dir, e2);
    let det = bvh_dot(e1, p);
    if det == 0.0 {
        return false;
    }
    let inv_det = 1.0 / det;
    let s = origin - tri.v0.xyz;
    let u = bvh_dot(s, p) * inv_det;
    if u < 0.0 || u > 1.0 {
        return false;
    }
    let q = cross(s, e1);
    let v = bvh_dot(dir, q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = bvh_dot(e2, q) * inv_det;
    return t > 0.0 && t < t_max;
}

// Any-hit: true when a triangle lies on origin + t * dir for 0 < t < t_max. Stack-based, near child first.
// (Carrying the near child's record instead of reloading it measured no faster on lavapipe.)
fn bvh_occluded(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    let inv = bvh_safe_inverse(dir);
    let root = bvh_nodes[0];
    if bvh_ray_box(origin, inv, root.min, root.max, t_max) >= BVH_MISS {
        return false;
    }
    var stack: array<u32, BVH_STACK_SIZE>;
    var sp = 0u;
    var node = 0u;
    loop {
        let n = bvh_nodes[node];
        if n.count > 0u {
            for (var i = n.first; i < n.first + n.count; i++) {
                if bvh_ray_triangle(origin, dir, bvh_triangles[i], t_max) {
                    return true;
                }
            }
            if sp == 0u {
                return false;
            }
            sp -= 1u;
            node = stack[sp];
            continue;
        }
        let a = n.first;
        let na = bvh_nodes[a];
        let nb = bvh_nodes[a + 1u];
        let ta = bvh_ray_box(origin, inv, na.min, na.max, t_max);
        let tb = bvh_ray_box(origin, inv, nb.min, nb.max, t_max);
        let a_first = ta <= tb;
        let t_near = select(tb, ta, a_first);
        let t_far = select(ta, tb, a_first);
        if t_near >= BVH_MISS {
            if sp == 0u {
                return false;
            }
            sp -= 1u;
            node = stack[sp];
            continue;
        }
        node = select(a + 1u, a, a_first);
        if t_far < BVH_MISS && sp < BVH_STACK_SIZE {
            stack[sp] = select(a, a + 1u, a_first);
            sp += 1u;
        }
    }
    return false;
}
