// A directional light's visibility by one shadow ray through the scene BVH (raytrace_bvh.wgsl): exact, for the
// ground truths and the ray-traced techniques (services/directional.rs). Composed after raytrace_bvh.wgsl and
// before directional_light.wgsl.

fn directional_visibility(s: Surface, d: DirectionalOne) -> f32 {
    let eps = directionals.ray_bias * max(length(frame.camera_position.xyz - s.position), 1.0);
    if bvh_occluded(s.position + s.normal * eps, -d.direction.xyz, directionals.ray_length) {
        return 0.0;
    }
    return 1.0;
}
