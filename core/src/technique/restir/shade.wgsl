// ReSTIR step 5, shading (Algorithm 5, lines 20-22): f(y) W of the pixel's final reservoir, f the light's
// unshadowed contribution (common.wgsl's shade_light, whose luminance p̂ is) times its visibility, times 1/frames,
// into the frame's mean in f32 (an Rgba16Float target loses about 1 % of the light over 64 additions: its
// blending rounds every sum to 11 bits). Unbiased mode: the visibility is in W already (the spatial pass traced
// it); biased mode: one shadow ray here, the reservoir keeps its W for the next frame, as in the paper.
// Composed after common.wgsl, raytrace_bvh.wgsl, restir/reservoir.wgsl and restir/trace.wgsl.

@group(1) @binding(7) var<storage, read_write> restir_mean: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn shade_main(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= restir_size()) {
        return;
    }
    let pixel = vec2<i32>(id.xy);
    let index = restir_index(id.xy);
    let s = load_surface(pixel);
    let r = reservoirs_in[index];
    var c = vec3<f32>(0.0);
    if s.is_geometry && r.light != RESTIR_NONE && r.w > 0.0 && r.light < restir.light_count {
        if restir.unbiased != 0u || !restir_occluded(s.position, s.normal, r.light) {
            c = shade_light(s, lights[r.light]) * (r.w * restir.weight);
        }
        count_work(pixel, WORK_LIGHT_EVALUATIONS, 1u);
        count_work(pixel, WORK_SHADOW_RAYS, bvh_shadow_rays);
    }
    if restir.first_frame != 0u {
        restir_mean[index] = vec4<f32>(c, 0.0);
    } else {
        restir_mean[index] += vec4<f32>(c, 0.0);
    }
}
