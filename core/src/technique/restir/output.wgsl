// ReSTIR's output: after every ReSTIR frame, the change of the running mean of the rendered frame's ReSTIR frames
// (restir/shade.wgsl, f32) added into the HDR target, so a progressive display shows the mean so far and the last
// frame leaves the mean of all. Composed after common.wgsl.

@group(1) @binding(0) var<storage, read> restir_delta: array<vec4<f32>>;

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<u32>(in.position.xy);
    let c = restir_delta[pixel.y * u32(frame.viewport.x) + pixel.x];
    if all(c.rgb == vec3<f32>(0.0)) {
        discard;
    }
    return vec4<f32>(c.rgb, 0.0);
}
