// Ray-traced shadows, test entry point: trace a buffer of rays through the BVH and write one hit flag per ray, so
// the tests can compare the GPU traversal with its CPU twin (`gpu_occluded` in core/src/technique/raytraced).
// Composed after raytrace_bvh.wgsl. `TestRay` mirrors `Ray` in core/src/technique/raytraced/bvh.rs.

struct TestRay {
    origin: vec3<f32>,
    t_max: f32,
    dir: vec3<f32>,
    _pad: f32,
}

@group(1) @binding(2) var<storage, read> test_rays_in: array<TestRay>;
@group(1) @binding(3) var<storage, read_write> test_hits_out: array<u32>;

@compute @workgroup_size(64)
fn test_rays(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    // Rows of `groups.x` workgroups when there are more than 65,535 of them.
    let i = id.x + id.y * groups.x * 64u;
    if i >= arrayLength(&test_rays_in) {
        return;
    }
    let r = test_rays_in[i];
    test_hits_out[i] = select(0u, 1u, bvh_occluded(r.origin, r.dir, r.t_max));
}
