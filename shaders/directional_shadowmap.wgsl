// A directional light's visibility from its orthographic shadow map (services/directional.rs): 3x3 PCF of depth
// comparisons around the receiver's texel, the receiver pushed along its normal by the light's normal offset
// and its depth lowered by the bias; 1 outside the map and for mode 0 (the unshadowed preview). Composed
// before directional_light.wgsl (which declares `Directionals`).

@group(1) @binding(3) var directional_map: texture_2d<f32>;

fn directional_visibility(s: Surface, d: DirectionalOne) -> f32 {
    if directionals.mode == 0u {
        return 1.0;
    }
    let clip = d.clip_from_world * vec4<f32>(s.position + s.normal * d.radiance.w, 1.0);
    let uv = vec2<f32>(clip.x * 0.5 + 0.5, 0.5 - clip.y * 0.5);
    if any(uv < vec2<f32>(0.0)) || any(uv >= vec2<f32>(1.0)) || clip.z > 1.0 {
        return 1.0;
    }
    let resolution = i32(d.tile.z);
    let origin = vec2<i32>(d.tile.xy);
    let texel = vec2<i32>(uv * d.tile.z);
    let depth = clip.z - d.direction.w;
    var lit = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let t = clamp(texel + vec2<i32>(dx, dy), vec2<i32>(0), vec2<i32>(resolution - 1));
            lit += select(0.0, 1.0, depth <= textureLoad(directional_map, origin + t, 0).r);
        }
    }
    return lit / 9.0;
}
