// k-means of the frame's VPLs into M VALs on the GPU (Dong et al. 2009 sections 5-6), the twin of
// core/src/technique/val/kmeans.rs: the same initial assignment (VAL k starts at VPL k*N/M), distance
// d = w_x |dp| / L + w_a acos(n . n_k), tie rule (lowest index) and mean update. The paper scatters with additive
// blending; WGSL has no float atomics, so the sums are fixed point in atomic<u32>: positions as fractions of the
// scene's bounds and normals as (n + 1) / 2, both in [0, 1], times `scale` = floor((2^32 - 1) / N), so N values
// never overflow; scale is at most 2^24 (exact in f32), so 1 / min(2^24, (2^32 - 1) / N) of the bounds is the
// precision kept: 6e-8 of the scene up to N = 256, 1.5e-5 at N = 65,536. The bounding
// rectangles use atomicMin/atomicMax on i32 fixed point (units of L / 2^29).
// Entry points, one dispatch each: km_init (M), then per iteration km_clear (M), km_assign (N), km_update (M);
// then km_clear, km_final (N: the map C and the members' sums and bounds), km_finish (M).
// Composed after vpl_basis.wgsl. `KmParams`, `ValState` mirror core/src/technique/val/gpu_kmeans.rs.

struct KmParams {
    vpl_count: u32,
    val_count: u32,
    scale: f32,
    w_x: f32,
    w_a: f32,
    scene_length: f32,
    _pad0: u32,
    _pad1: u32,
    bounds_min: vec4<f32>,
    bounds_extent: vec4<f32>,
}

struct Vpl {
    position: vec4<f32>,
    normal: vec4<f32>,
    flux: vec4<f32>,
}

// Per VAL: the centre (xyz), count (w, after km_finish); the normal (xyz); the rectangle: min s, max s, min t,
// max t along the Duff basis of the normal (after km_finish).
struct ValState {
    position: vec4<f32>,
    normal: vec4<f32>,
    rect: vec4<f32>,
}

// Per VAL: 6 fixed-point sums, the count, 4 rectangle bounds (i32 bits), one spare.
const ACC: u32 = 12u;

@group(0) @binding(0) var<uniform> km: KmParams;
@group(0) @binding(1) var<storage, read> km_vpls: array<Vpl>;
@group(0) @binding(2) var<storage, read_write> vals: array<ValState>;
@group(0) @binding(3) var<storage, read_write> acc: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> assignment: array<u32>;

fn km_distance(p: vec3<f32>, n: vec3<f32>, k: u32) -> f32 {
    let dx = length(p - vals[k].position.xyz) / max(km.scene_length, 1e-20);
    let da = acos(clamp(dot(n, vals[k].normal.xyz), -1.0, 1.0));
    return km.w_x * dx + km.w_a * da;
}

fn km_nearest(i: u32) -> u32 {
    let p = km_vpls[i].position.xyz;
    let n = km_vpls[i].normal.xyz;
    var best = 3.0e38;
    var best_k = 0u;
    for (var k = 0u; k < km.val_count; k++) {
        let d = km_distance(p, n, k);
        if d < best {
            best = d;
            best_k = k;
        }
    }
    return best_k;
}

@compute @workgroup_size(64)
fn km_init(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= km.val_count {
        return;
    }
    let v = km_vpls[k * km.vpl_count / km.val_count];
    vals[k].position = vec4<f32>(v.position.xyz, 0.0);
    vals[k].normal = vec4<f32>(v.normal.xyz, 0.0);
    vals[k].rect = vec4<f32>(0.0);
}

@compute @workgroup_size(64)
fn km_clear(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= km.val_count {
        return;
    }
    for (var j = 0u; j < ACC; j++) {
        atomicStore(&acc[k * ACC + j], 0u);
    }
    // Rectangle bounds start empty. They are i32 with the sign bit flipped, so unsigned order is signed order:
    // the largest i32 is 0xffffffff, the smallest 0.
    atomicStore(&acc[k * ACC + 7u], 0xffffffffu);
    atomicStore(&acc[k * ACC + 9u], 0xffffffffu);
}

fn km_accumulate(i: u32, k: u32) {
    let p01 = clamp((km_vpls[i].position.xyz - km.bounds_min.xyz) / km.bounds_extent.xyz, vec3<f32>(0.0), vec3<f32>(1.0));
    let n01 = clamp(km_vpls[i].normal.xyz * 0.5 + 0.5, vec3<f32>(0.0), vec3<f32>(1.0));
    let base = k * ACC;
    atomicAdd(&acc[base + 0u], u32(p01.x * km.scale));
    atomicAdd(&acc[base + 1u], u32(p01.y * km.scale));
    atomicAdd(&acc[base + 2u], u32(p01.z * km.scale));
    atomicAdd(&acc[base + 3u], u32(n01.x * km.scale));
    atomicAdd(&acc[base + 4u], u32(n01.y * km.scale));
    atomicAdd(&acc[base + 5u], u32(n01.z * km.scale));
    atomicAdd(&acc[base + 6u], 1u);
}

@compute @workgroup_size(64)
fn km_assign(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= km.vpl_count {
        return;
    }
    km_accumulate(i, km_nearest(i));
}

@compute @workgroup_size(64)
fn km_update(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= km.val_count {
        return;
    }
    let base = k * ACC;
    let count = atomicLoad(&acc[base + 6u]);
    if count == 0u {
        // Lost all its VPLs: keeps its centre, may win some back.
        return;
    }
    let c = f32(count) * km.scale;
    let p = vec3<f32>(f32(atomicLoad(&acc[base + 0u])), f32(atomicLoad(&acc[base + 1u])),
        f32(atomicLoad(&acc[base + 2u]))) / c;
    let n = vec3<f32>(f32(atomicLoad(&acc[base + 3u])), f32(atomicLoad(&acc[base + 4u])),
        f32(atomicLoad(&acc[base + 5u]))) / c * 2.0 - 1.0;
    vals[k].position = vec4<f32>(km.bounds_min.xyz + p * km.bounds_extent.xyz, 0.0);
    if dot(n, n) > 1e-12 {
        vals[k].normal = vec4<f32>(normalize(n), 0.0);
    }
}

@compute @workgroup_size(64)
fn km_final(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= km.vpl_count {
        return;
    }
    let k = km_nearest(i);
    assignment[i] = k;
    atomicAdd(&acc[k * ACC + 6u], 1u);
    // The Duff et al. basis (vpl_basis.wgsl; glam's any_orthonormal_pair on the CPU): columns 0 and 1.
    let axes = vpl_basis(vals[k].normal.xyz);
    let rel = km_vpls[i].position.xyz - vals[k].position.xyz;
    let unit = f32(1 << 29u) / max(km.scene_length, 1e-20);
    let s = i32(clamp(dot(rel, axes[0]) * unit, -2.0e9, 2.0e9));
    let t = i32(clamp(dot(rel, axes[1]) * unit, -2.0e9, 2.0e9));
    // atomicMin/Max on the i32 bits: compare as signed by flipping the sign bit.
    atomicMin(&acc[k * ACC + 7u], bitcast<u32>(s) ^ 0x80000000u);
    atomicMax(&acc[k * ACC + 8u], bitcast<u32>(s) ^ 0x80000000u);
    atomicMin(&acc[k * ACC + 9u], bitcast<u32>(t) ^ 0x80000000u);
    atomicMax(&acc[k * ACC + 10u], bitcast<u32>(t) ^ 0x80000000u);
}

@compute @workgroup_size(64)
fn km_finish(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= km.val_count {
        return;
    }
    let base = k * ACC;
    let count = atomicLoad(&acc[base + 6u]);
    vals[k].position.w = f32(count);
    if count == 0u {
        vals[k].rect = vec4<f32>(0.0);
        return;
    }
    let to_world = max(km.scene_length, 1e-20) / f32(1 << 29u);
    let bits = vec4<u32>(atomicLoad(&acc[base + 7u]), atomicLoad(&acc[base + 8u]), atomicLoad(&acc[base + 9u]),
        atomicLoad(&acc[base + 10u])) ^ vec4<u32>(0x80000000u);
    vals[k].rect = vec4<f32>(bitcast<vec4<i32>>(bits)) * to_world;
}
