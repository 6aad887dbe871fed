// Ray-traced shadows, shading of one batch of lights: per pixel and light, shadow rays through the scene BVH
// (raytrace_bvh.wgsl) give the visibility the cube-map techniques approximate. Hard: one ray to the light's
// centre. Soft: `samples` rays to stratified points on a disc of `light_radius` centred at the light and facing
// the receiver; visibility = the unoccluded fraction. Shading is the reference's (`shade_light`) times visibility.
// Composed after common.wgsl, light_tiles.wgsl and raytrace_bvh.wgsl. `RtBatch` mirrors `RtBatchUniform` in
// core/src/technique/raytraced/mod.rs.

struct RtBatch {
    first_light: u32,
    light_count: u32,
    // 1: soft shadows from a disc light
    soft: u32,
    samples: u32,
    light_radius: f32,
    // ray origin offset along the normal, world units per metre of camera distance (at least one metre)
    bias: f32,
    seed: u32,
    _pad: u32,
}

@group(1) @binding(2) var<storage, read> lights: array<Light>;
@group(1) @binding(3) var<uniform> batch: RtBatch;

// PCG hash (Jarzynski & Olano 2020).
fn rt_hash(x: u32) -> u32 {
    let state = x * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn rt_unit(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

// Shirley-Chiu concentric map of the unit square onto the unit disc (keeps stratification).
fn rt_concentric_disc(u: vec2<f32>) -> vec2<f32> {
    let a = 2.0 * u - 1.0;
    if a.x == 0.0 && a.y == 0.0 {
        return vec2<f32>(0.0);
    }
    var r: f32;
    var phi: f32;
    if abs(a.x) > abs(a.y) {
        r = a.x;
        phi = (PI / 4.0) * (a.y / a.x);
    } else {
        r = a.y;
        phi = PI / 2.0 - (PI / 4.0) * (a.x / a.y);
    }
    return r * vec2<f32>(cos(phi), sin(phi));
}

// Visibility of a disc light: Hammersley points (i + 0.5) / N, radical inverse of i, rotated per pixel and light
// (Cranley-Patterson) and mapped onto the disc facing the receiver.
fn rt_soft_visibility(origin: vec3<f32>, light_position: vec3<f32>, eps: f32, rotation: vec2<f32>) -> f32 {
    let w = normalize(origin - light_position);
    // Orthonormal basis around w (Duff et al. 2017).
    let sign = select(-1.0, 1.0, w.z >= 0.0);
    let a = -1.0 / (sign + w.z);
    let b = w.x * w.y * a;
    let tangent = vec3<f32>(1.0 + sign * w.x * w.x * a, sign * b, -sign * w.x);
    let bitangent = vec3<f32>(b, sign + w.y * w.y * a, -w.y);
    let n = max(batch.samples, 1u);
    var unoccluded = 0u;
    for (var k = 0u; k < n; k++) {
        let u = fract(vec2<f32>((f32(k) + 0.5) / f32(n), f32(reverseBits(k)) * 2.3283064e-10) + rotation);
        let d = rt_concentric_disc(u) * batch.light_radius;
        let to_sample = light_position + tangent * d.x + bitangent * d.y - origin;
        let distance = length(to_sample);
        if distance <= eps || !bvh_occluded(origin, to_sample / distance, distance - eps) {
            unoccluded += 1u;
        }
    }
    return f32(unoccluded) / f32(n);
}

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.position.xy);
    let s = load_surface(pixel);
    if !s.is_geometry {
        discard;
    }
    // The reconstructed position's error grows with the distance from the camera; so does the offset.
    let eps = batch.bias * max(1.0, distance(frame.camera_position.xyz, s.position));
    let origin = s.position + s.normal * eps;
    let pixel_hash = rt_hash(u32(pixel.x) ^ rt_hash(u32(pixel.y) ^ rt_hash(batch.seed)));
    var sum = vec3<f32>(0.0);
    // The batch's lights that reach this pixel's tile (light_tiles.wgsl), in batch order.
    let span = tile_span(pixel, batch.first_light, batch.light_count);
    for (var j = span.start; j < span.end; j++) {
        let index = tile_item(span, j);
        let light = lights[index];
        let unshadowed = shade_light(s, light);
        if !any(unshadowed > vec3<f32>(0.0)) {
            continue;
        }
        var visibility = 0.0;
        if batch.soft != 0u {
            let h = rt_hash(pixel_hash ^ index);
            let rotation = vec2<f32>(rt_unit(h), rt_unit(rt_hash(h)));
            visibility = rt_soft_visibility(origin, light.position, eps, rotation);
        } else {
            let to_light = light.position - origin;
            let distance = length(to_light);
            if distance <= eps || !bvh_occluded(origin, to_light / distance, distance - eps) {
                visibility = 1.0;
            }
        }
        sum += unshadowed * visibility;
    }
    count_work(pixel, WORK_LIGHT_EVALUATIONS, span.end - span.start);
    count_work(pixel, WORK_SHADOW_RAYS, bvh_shadow_rays);
    return vec4<f32>(sum, 0.0);
}
