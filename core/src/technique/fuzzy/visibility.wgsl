// Step 5 of Colom et al. 2022: visibility between every shading-point cluster's representative and every light
// (a VPL cluster's representative, or each VPL when VPLs are not clustered) by one shadow ray through the scene
// BVH (raytrace_bvh.wgsl, group 1), one bit each: row r of `vis_bits` holds words_per_row words, bit j of the
// row is light j. One invocation per word (32 rays), so no atomics. Both ends are pushed off their surfaces as
// vpl_vis_raytraced.wgsl does (the same bias, scaled by the representative's camera distance).
// Composed after raytrace_bvh.wgsl. `VisParams` mirrors core/src/technique/fuzzy/mod.rs.

struct VisParams {
    sp_count: u32,
    light_count: u32,
    words_per_row: u32,
    first_row: u32,
    row_count: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    // xyz: camera position, w: ray offset per metre of camera distance
    camera_bias: vec4<f32>,
}

// A representative or a light (`KmPoint` / `Vpl` layout): position (w: 1 when it exists), normal, flux.
struct Endpoint {
    position: vec4<f32>,
    normal: vec4<f32>,
    flux: vec4<f32>,
}

@group(0) @binding(0) var<uniform> vis: VisParams;
// [0, sp_count): the shading-point representatives; [sp_count, sp_count + light_count): the lights.
@group(0) @binding(1) var<storage, read> endpoints: array<Endpoint>;
@group(0) @binding(2) var<storage, read_write> vis_bits: array<u32>;

@compute @workgroup_size(64)
fn visibility_main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let t = id.x + id.y * groups.x * 64u;
    if t >= vis.row_count * vis.words_per_row {
        return;
    }
    let row = vis.first_row + t / vis.words_per_row;
    let word = t % vis.words_per_row;
    let sp = endpoints[row];
    var bits = 0u;
    if sp.position.w > 0.5 {
        let eps = vis.camera_bias.w * max(1.0, length(vis.camera_bias.xyz - sp.position.xyz));
        let origin = sp.position.xyz + sp.normal.xyz * eps;
        for (var b = 0u; b < 32u; b++) {
            let j = word * 32u + b;
            if j >= vis.light_count {
                break;
            }
            let light = endpoints[vis.sp_count + j];
            if light.position.w < 0.5 {
                continue;
            }
            let target_point = light.position.xyz + light.normal.xyz * eps;
            let to_light = target_point - origin;
            let distance = length(to_light);
            var visible = true;
            if distance > 2.0 * eps {
                visible = !bvh_occluded(origin, to_light / distance, distance - eps);
            }
            if visible {
                bits |= 1u << b;
            }
        }
    }
    vis_bits[row * vis.words_per_row + word] = bits;
}
