// Ray-traced shadows: the scene BVH and any-hit traversal for shadow rays. The layout and every operation mirror
// core/src/technique/raytraced/bvh.rs (`BvhNode`, `BvhTriangle`, `occluded_cpu`), the CPU twin the tests compare
// this with. Composed in front of raytraced/shadow.wgsl (after common.wgsl) and of raytrace_test.wgsl.

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

// Cut-out casters (core/src/accel/scene_bvh.rs, `BvhCutouts` and `CutoutTextures`): per BVH triangle 0
// (opaque) or 1 + its record; records as two texels (uv0, uv1), (uv2, mask layer, cutoff); the masks (alpha,
// factor times texture) one layer per cut-out material. Textures, not storage buffers: downlevel devices allow
// four of those per stage and the tracers already bind up to four.
@group(1) @binding(10) var bvh_cutout_ids: texture_2d<u32>;
@group(1) @binding(11) var bvh_cutout_records: texture_2d<f32>;
@group(1) @binding(12) var bvh_cutout_masks: texture_2d_array<f32>;
@group(1) @binding(13) var bvh_cutout_sampler: sampler;

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
    return bvh_ray_triangle_hit(origin, dir, tri, t_max).x < BVH_MISS;
}

fn bvh_texel(width: u32, i: u32) -> vec2<u32> {
    return vec2<u32>(i % width, i / width);
}

// True when the hit at barycentrics (u, v) of v1, v2 of BVH triangle `tri` lands on a cut-out texel (the
// twin of `BvhCutouts::cut_out`): such a hit is no hit.
fn bvh_cut_out(tri: u32, u: f32, v: f32) -> bool {
    let dims = textureDimensions(bvh_cutout_ids);
    let at = bvh_texel(dims.x, tri);
    if at.y >= dims.y {
        return false;
    }
    let id = textureLoad(bvh_cutout_ids, at, 0).x;
    if id == 0u {
        return false;
    }
    let width = textureDimensions(bvh_cutout_records).x;
    let r = (id - 1u) * 2u;
    let a = textureLoad(bvh_cutout_records, bvh_texel(width, r), 0);
    let b = textureLoad(bvh_cutout_records, bvh_texel(width, r + 1u), 0);
    let uv = a.xy * (1.0 - u - v) + a.zw * u + b.xy * v;
    let alpha = textureSampleLevel(bvh_cutout_masks, bvh_cutout_sampler, uv, i32(b.z), 0.0).r;
    return alpha < b.w;
}

// Any-hit: true when a triangle lies on origin + t * dir for 0 < t < t_max. Stack-based, near child first.
// (Carrying the near child's record instead of reloading it measured no faster on lavapipe.)
// Rays traced by this invocation, for the work counters (a pass adds them with `count_work`).
var<private> bvh_shadow_rays: u32 = 0u;
var<private> bvh_closest_rays: u32 = 0u;

fn bvh_occluded(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    bvh_shadow_rays += 1u;
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
                let h = bvh_ray_triangle_hit(origin, dir, bvh_triangles[i], t_max);
                if h.x < BVH_MISS && !bvh_cut_out(i, h.y, h.z) {
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

// Nearest hit of a ray; t = BVH_MISS when there is none. Mirrors `Hit` in bvh.rs.
struct BvhHit {
    t: f32,
    // index into bvh_triangles
    triangle: u32,
    // barycentrics of v1 and v2
    u: f32,
    v: f32,
}

// Möller–Trumbore with distance and barycentrics: (t, u, v), t = BVH_MISS unless 0 < t < t_max.
fn bvh_ray_triangle_hit(origin: vec3<f32>, dir: vec3<f32>, tri: BvhTriangle, t_max: f32) -> vec3<f32> {
    let miss = vec3<f32>(BVH_MISS, 0.0, 0.0);
    let e1 = tri.e1.xyz;
    let e2 = tri.e2.xyz;
    let p = cross(dir, e2);
    let det = bvh_dot(e1, p);
    if det == 0.0 {
        return miss;
    }
    let inv_det = 1.0 / det;
    let s = origin - tri.v0.xyz;
    let u = bvh_dot(s, p) * inv_det;
    if u < 0.0 || u > 1.0 {
        return miss;
    }
    let q = cross(s, e1);
    let v = bvh_dot(dir, q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return miss;
    }
    let t = bvh_dot(e2, q) * inv_det;
    if t > 0.0 && t < t_max {
        return vec3<f32>(t, u, v);
    }
    return miss;
}

// Closest hit, the twin of `closest_hit_cpu` in bvh.rs: near child first, subtrees whose box starts beyond the
// nearest hit so far are skipped when popped.
fn bvh_closest_hit(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> BvhHit {
    bvh_closest_rays += 1u;
    var best: BvhHit;
    best.t = BVH_MISS;
    best.triangle = 0u;
    best.u = 0.0;
    best.v = 0.0;
    var t_best = t_max;
    let inv = bvh_safe_inverse(dir);
    let root = bvh_nodes[0];
    if bvh_ray_box(origin, inv, root.min, root.max, t_max) >= BVH_MISS {
        return best;
    }
    var stack: array<u32, BVH_STACK_SIZE>;
    var sp = 0u;
    var node = 0u;
    loop {
        let n = bvh_nodes[node];
        var descend = false;
        if n.count > 0u {
            for (var i = n.first; i < n.first + n.count; i++) {
                let h = bvh_ray_triangle_hit(origin, dir, bvh_triangles[i], t_best);
                if h.x < BVH_MISS && !bvh_cut_out(i, h.y, h.z) {
                    t_best = h.x;
                    best.t = h.x;
                    best.triangle = i;
                    best.u = h.y;
                    best.v = h.z;
                }
            }
        } else {
            let a = n.first;
            let na = bvh_nodes[a];
            let nb = bvh_nodes[a + 1u];
            let ta = bvh_ray_box(origin, inv, na.min, na.max, t_best);
            let tb = bvh_ray_box(origin, inv, nb.min, nb.max, t_best);
            let a_first = ta <= tb;
            let t_near = select(tb, ta, a_first);
            let t_far = select(ta, tb, a_first);
            if t_near < BVH_MISS {
                node = select(a + 1u, a, a_first);
                if t_far < BVH_MISS && sp < BVH_STACK_SIZE {
                    stack[sp] = select(a, a + 1u, a_first);
                    sp += 1u;
                }
                descend = true;
            }
        }
        if !descend {
            var found = false;
            loop {
                if sp == 0u {
                    break;
                }
                sp -= 1u;
                let c = bvh_nodes[stack[sp]];
                if bvh_ray_box(origin, inv, c.min, c.max, t_best) < BVH_MISS {
                    node = stack[sp];
                    found = true;
                    break;
                }
            }
            if !found {
                return best;
            }
        }
    }
    return best;
}
