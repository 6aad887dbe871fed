// First pass into the HDR target: ambient * albedo + emission on geometry, the background elsewhere.
// Composed after common.wgsl.

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let s = load_surface(vec2<i32>(in.position.xy));
    if !s.is_geometry {
        return vec4<f32>(frame.background.rgb, 1.0);
    }
    count_work(vec2<i32>(in.position.xy), WORK_SHADED_PIXELS, 1u);
    // The albedo's alpha holds the material's ambient occlusion (1 without an occlusion texture).
    let occlusion = textureLoad(gbuffer_albedo, vec2<i32>(in.position.xy), 0).a;
    return vec4<f32>(frame.ambient.rgb * s.albedo * occlusion + s.emissive, 1.0);
}
