// Directional lights (services/directional.rs): every geometry pixel adds each light's unshadowed radiance,
// the surface's BRDF times its irradiance along the light's direction, times `directional_visibility` (from
// directional_shadowmap.wgsl or directional_traced.wgsl, composed before this file). Composed after
// common.wgsl. `Directionals` mirrors `DirectionalUniform` in core/src/services/directional.rs.

struct DirectionalOne {
    // the orthographic map's clip-from-world (x, y in -1..1, depth 0..1 from the light)
    clip_from_world: mat4x4<f32>,
    // xyz: the direction the light travels (unit); w: the map's depth bias
    direction: vec4<f32>,
    // rgb: colour times illuminance; w: normal offset in world units
    radiance: vec4<f32>,
    // xy: the tile's first texel in the atlas, z: its resolution, w: unused
    tile: vec4<f32>,
}

struct Directionals {
    count: u32,
    // 0: no visibility (the preview), 1: the shadow map, 2: shadow rays
    mode: u32,
    // shadow rays: origin offset along the normal, world units per metre of camera distance
    ray_bias: f32,
    // shadow rays: their length (twice the scene's diagonal)
    ray_length: f32,
    lights: array<DirectionalOne, 4>,
}

@group(1) @binding(2) var<uniform> directionals: Directionals;

fn shade_directional(s: Surface, d: DirectionalOne) -> vec3<f32> {
    let l = -d.direction.xyz;
    let n_dot_l = dot(s.normal, l);
    if n_dot_l <= 0.0 {
        return vec3<f32>(0.0);
    }
    return surface_brdf(s, l) * d.radiance.rgb * n_dot_l;
}

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.position.xy);
    let s = load_surface(pixel);
    if !s.is_geometry {
        discard;
    }
    var c = vec3<f32>(0.0);
    for (var i = 0u; i < min(directionals.count, 4u); i++) {
        let d = directionals.lights[i];
        let unshadowed = shade_directional(s, d);
        if any(unshadowed > vec3<f32>(0.0)) {
            c += unshadowed * directional_visibility(s, d);
        }
    }
    return vec4<f32>(c, 0.0);
}
