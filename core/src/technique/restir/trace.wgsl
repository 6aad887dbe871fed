// What ReSTIR's compute passes share besides the reservoirs: the source table, the reservoirs a pass writes,
// the pixel of an invocation and the shadow ray through the scene BVH (raytrace_bvh.wgsl) with the ray
// tracer's offsets. Composed after common.wgsl, raytrace_bvh.wgsl and restir/reservoir.wgsl.

@group(1) @binding(3) var<storage, read> source_table: array<SourceEntry>;
@group(1) @binding(6) var<storage, read_write> reservoirs_out: array<Reservoir>;

fn restir_size() -> vec2<u32> {
    return vec2<u32>(frame.viewport.xy);
}

fn restir_index(pixel: vec2<u32>) -> u32 {
    return pixel.y * restir_size().x + pixel.x;
}

// True when the segment from the surface (position, normal) to light `light` is blocked. The origin is pushed
// along the normal by `bias * max(1, camera distance)` and the ray stops that far before the light, as the
// ray tracer's (raytraced/shadow.wgsl), so the two see the same shadows.
fn restir_occluded(position: vec3<f32>, normal: vec3<f32>, light: u32) -> bool {
    let eps = restir.bias * max(1.0, distance(frame.camera_position.xyz, position));
    let origin = position + normal * eps;
    let to_light = lights[light].position - origin;
    let d = length(to_light);
    return d > eps && bvh_occluded(origin, to_light / d, d - eps);
}
