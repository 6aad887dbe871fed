// HDR radiance to display: exposure, a tone-map operator, then the sRGB target encodes.
// Composed after common.wgsl (for `frame` and the full-screen triangle).

@group(1) @binding(0) var hdr: texture_2d<f32>;
// Indirect radiance per pixel (f32 RGBA, row-major), written by the indirect technique; a placeholder when
// frame.indirect.z is 0.
@group(1) @binding(1) var<storage, read> indirect_radiance: array<vec4<f32>>;

// Narkowicz's fit of the ACES filmic curve.
fn aces(x: vec3<f32>) -> vec3<f32> {
    let a = 2.51;
    let b = 0.03;
    let c = 2.43;
    let d = 0.59;
    let e = 0.14;
    return clamp((x * (a * x + b)) / (x * (c * x + d) + e), vec3<f32>(0.0), vec3<f32>(1.0));
}

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.position.xy);
    var radiance = textureLoad(hdr, pixel, 0).rgb;
    if frame.indirect.z > 0.5 {
        let indirect = indirect_radiance[u32(pixel.y) * u32(frame.viewport.x) + u32(pixel.x)].rgb;
        switch u32(frame.indirect.x) {
            case 0u: { radiance += indirect; }
            case 1u: { }
            default: { radiance = indirect * frame.indirect.y; }
        }
    } else if u32(frame.indirect.x) == 2u {
        radiance = vec3<f32>(0.0);
    }
    radiance *= frame.tonemap.x;
    var mapped: vec3<f32>;
    switch u32(frame.tonemap.y) {
        case 0u: { mapped = aces(radiance); }
        case 1u: { mapped = radiance / (1.0 + radiance); }
        default: { mapped = clamp(radiance, vec3<f32>(0.0), vec3<f32>(1.0)); }
    }
    return vec4<f32>(mapped, 1.0);
}
