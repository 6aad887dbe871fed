// ReSTIR's output: the mean of the rendered frame's ReSTIR frames (restir/shade.wgsl, f32), added into the HDR
// target once, after the last of them. Composed after common.wgsl.

@group(1) @binding(0) var<storage, read> restir_mean: array<vec4<f32>>;

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<u32>(in.position.xy);
    let c = restir_mean[pixel.y * u32(frame.viewport.x) + pixel.x];
    if !any(c.rgb > vec3<f32>(0.0)) {
        discard;
    }
    return vec4<f32>(c.rgb, 0.0);
}
