// HDR radiance to display: exposure, a tone-map operator, then the sRGB target encodes.
// Composed after common.wgsl (for `frame` and the full-screen triangle).

@group(1) @binding(0) var hdr: texture_2d<f32>;

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
    let radiance = textureLoad(hdr, vec2<i32>(in.position.xy), 0).rgb * frame.tonemap.x;
    var mapped: vec3<f32>;
    switch u32(frame.tonemap.y) {
        case 0u: { mapped = aces(radiance); }
        case 1u: { mapped = radiance / (1.0 + radiance); }
        default: { mapped = clamp(radiance, vec3<f32>(0.0), vec3<f32>(1.0)); }
    }
    return vec4<f32>(mapped, 1.0);
}
