// HDR radiance to display: exposure (times the metered auto-exposure when frame.tonemap.z is 1), a tone-map
// operator, then the sRGB target encodes. Composed after common.wgsl and display.wgsl.

// x: the auto-exposure scale the meter (exposure.wgsl) found, y: the log-average luminance it metered.
@group(1) @binding(2) var<storage, read> auto_exposure: array<vec4<f32>>;

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
    var radiance = displayed_radiance(pixel);
    radiance *= frame.tonemap.x * select(1.0, auto_exposure[0].x, frame.tonemap.z > 0.5);
    var mapped: vec3<f32>;
    switch u32(frame.tonemap.y) {
        case 0u: { mapped = aces(radiance); }
        case 1u: { mapped = radiance / (1.0 + radiance); }
        default: { mapped = clamp(radiance, vec3<f32>(0.0), vec3<f32>(1.0)); }
    }
    return vec4<f32>(mapped, 1.0);
}
