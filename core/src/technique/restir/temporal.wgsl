// ReSTIR step 3, temporal reuse (Algorithm 5, lines 10-13): the pixel's reservoir (after visibility reuse,
// in reservoirs_out) combined with the previous frame's final reservoir (reservoirs_in) where the pixel's
// surface was in the previous frame's view (reprojected with that frame's clip_from_world), and only when that
// surface is alike (depth, normal). The history's M is capped at `history` times the candidates.
// Biased: Algorithm 4 (W = w_sum / (M p̂(y))). Unbiased: Algorithm 6 (W = w_sum / (Z p̂(y))); Z counts an
// input's M when it could have drawn y: p̂ > 0 and y visible from its surface (every reservoir's W is 0 where
// its own pixel cannot see its sample, so visibility is part of its support): one shadow ray, from the pixel
// when y came from the history (y's visibility here), from the history's surface when y is the pixel's own.
// Composed after common.wgsl, raytrace_bvh.wgsl, restir/reservoir.wgsl and restir/trace.wgsl.

@compute @workgroup_size(8, 8)
fn temporal_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = restir_size();
    if any(id.xy >= size) {
        return;
    }
    let pixel = vec2<i32>(id.xy);
    let s = load_surface(pixel);
    if !s.is_geometry {
        return;
    }
    let index = restir_index(id.xy);
    let current = reservoirs_out[index];

    // The previous frame's pixel of this surface.
    let clip = restir.prev_clip_from_world * vec4<f32>(s.position, 1.0);
    if clip.w <= 0.0 {
        return;
    }
    let ndc = clip.xy / clip.w;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    if any(uv < vec2<f32>(0.0)) || any(uv >= vec2<f32>(1.0)) {
        return;
    }
    let prev_pixel = min(vec2<u32>(uv * vec2<f32>(size)), size - 1u);
    let history = reservoirs_in[restir_index(prev_pixel)];
    let hp = restir_point(history);
    let prev_camera = restir.prev_camera.xyz;
    if !hp.geometry
        || !restir_similar(distance(prev_camera, s.position), s.normal, distance(prev_camera, hp.position), hp.normal) {
        return;
    }

    // Algorithm 4 over (current, history).
    restir_seed(id.xy, 1u);
    var r = restir_empty();
    var p_hat_y = 0.0;
    var from_history = false;
    let p_current = restir_target(s, current.light);
    if restir_update(&r, current.light, p_current * current.w * current.m, current.m) {
        p_hat_y = p_current;
    }
    let m_history = min(history.m, restir.history_cap);
    let p_history = restir_target(s, history.light);
    if restir_update(&r, history.light, p_history * history.w * m_history, m_history) {
        p_hat_y = p_history;
        from_history = true;
    }
    if restir.unbiased != 0u {
        // The taken input could draw y (its W > 0); the other is asked with a shadow ray.
        var visible_here = true;
        var history_could = true;
        if from_history {
            visible_here = !restir_occluded(s.position, s.normal, r.light);
        } else if r.light != RESTIR_NONE {
            history_could = restir_supports(hp, r.light) && !restir_occluded(hp.position, hp.normal, r.light);
        }
        var z = 0.0;
        if p_hat_y > 0.0 && visible_here {
            z += current.m;
        }
        if history_could {
            z += m_history;
        }
        r.w = restir_contribution_weight(r.w_sum, z, p_hat_y);
        if !visible_here {
            r.w = 0.0;
        }
    } else {
        r.w = restir_contribution_weight(r.w_sum, r.m, p_hat_y);
    }
    count_work(pixel, WORK_LIGHT_EVALUATIONS, 2u);
    count_work(pixel, WORK_SHADOW_RAYS, bvh_shadow_rays);
    reservoirs_out[index] = restir_stamp(r, s);
}
