// VPL visibility by a shadow ray through the scene BVH (raytrace_bvh.wgsl, group 1): exact, the ground truth of
// every VPL visibility approximation. Both ends are pushed off their surfaces by the bias (scaled by the camera
// distance, as the ray-traced shadows do: the G-buffer's position error grows with it).

fn count_visibility_work(pixel: vec2<i32>) {
    count_work(pixel, WORK_INDIRECT_SHADOW_RAYS, bvh_shadow_rays);
}

fn vpl_visibility(s: Surface, v: Vpl, k: u32) -> f32 {
    let eps = gather.bias * max(1.0, length(frame.camera_position.xyz - s.position));
    let origin = s.position + s.normal * eps;
    let target_point = v.position.xyz + v.normal.xyz * eps;
    let to_vpl = target_point - origin;
    let distance = length(to_vpl);
    if distance <= 2.0 * eps {
        return 1.0;
    }
    return select(1.0, 0.0, bvh_occluded(origin, to_vpl / distance, distance - eps));
}
