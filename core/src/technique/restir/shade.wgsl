// ReSTIR step 5, shading (Algorithm 5, lines 20-22): f(y) W of the pixel's final reservoir, f the light's
// unshadowed contribution (common.wgsl's shade_light, whose luminance p̂ is) times its visibility, times 1/frames,
// into the frame's mean in f32, and the change of the running mean for the output pass to add (so a progressive
// display shows the mean so far). Unbiased mode: the visibility is in W already (the spatial pass traced
// it); biased mode: one shadow ray here, the reservoir keeps its W for the next frame, as in the paper.
// Composed after common.wgsl, raytrace_bvh.wgsl, restir/reservoir.wgsl and restir/trace.wgsl.

@group(1) @binding(7) var<storage, read_write> restir_mean: array<vec4<f32>>;
// The running mean the HDR target holds so far, and what the output pass adds to it after this frame.
@group(1) @binding(8) var<storage, read_write> restir_shown: array<vec4<f32>>;
@group(1) @binding(9) var<storage, read_write> restir_delta: array<vec4<f32>>;

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
    var sum = vec4<f32>(c, 0.0);
    var shown = vec4<f32>(0.0);
    if restir.first_frame == 0u {
        sum += restir_mean[index];
        shown = restir_shown[index];
    }
    restir_mean[index] = sum;
    // After frames 1, 2, 4, 8, ... and the last (shown_scale > 0): the running mean of the frames so far, and its
    // change since the last one shown for the output pass. After the last frame it is the sum itself (scale 1).
    // Only log2(frames) + 1 changes are added: the Rgba16Float target rounds every addition to 11 bits, and a
    // change per frame (ever smaller against the value) would lose about 1 % of the light over 64 frames.
    if restir.shown_scale > 0.0 {
        let mean_so_far = select(sum * restir.shown_scale, sum, restir.shown_scale == 1.0);
        restir_shown[index] = mean_so_far;
        restir_delta[index] = mean_so_far - shown;
    }
}
