// ReSTIR steps 1-2 per pixel: RIS (Algorithm 3) over `candidates` lights drawn from the source pdf p (one
// table lookup each: uniform, or an alias table by power; or uniform over the lights of the pixel's tile list,
// light_tiles.wgsl), weights w = p̂(x)/p(x) streamed into one reservoir, W = w_sum / (M p̂(y)); then visibility
// reuse (Algorithm 5, lines 6-9): one shadow ray to y, W = 0 when it is blocked, before any reuse. Composed
// after common.wgsl, light_tiles.wgsl, raytrace_bvh.wgsl, restir/reservoir.wgsl and restir/trace.wgsl.

// A slot of the source table by p: uniform slot, then its threshold test (Walker's alias method).
fn restir_sample_source() -> u32 {
    let n = restir.source_count;
    let slot = min(u32(restir_random() * f32(n)), n - 1u);
    let entry = source_table[slot];
    if restir_random() < entry.threshold {
        return slot;
    }
    return entry.alias_slot;
}

@compute @workgroup_size(8, 8)
fn candidates_main(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= restir_size()) {
        return;
    }
    let pixel = vec2<i32>(id.xy);
    let s = load_surface(pixel);
    var r = restir_empty();
    if s.is_geometry && restir.source_count > 0u {
        restir_seed(id.xy, 0u);
        var p_hat_y = 0.0;
        // The tile source: every light whose range reaches the pixel's tile is listed (the others have p̂ = 0).
        let span = tile_span(pixel, 0u, restir.source_count);
        let listed = span.end - span.start;
        for (var k = 0u; k < restir.candidates; k++) {
            var entry: SourceEntry;
            if restir.tiled != 0u {
                if listed == 0u {
                    break;
                }
                let at = span.start + min(u32(restir_random() * f32(listed)), listed - 1u);
                entry = source_table[tile_item(span, at)];
                entry.pdf = 1.0 / f32(listed);
            } else {
                entry = source_table[restir_sample_source()];
            }
            let p_hat = restir_target(s, entry.light);
            var w = 0.0;
            if entry.pdf > 0.0 {
                w = p_hat / entry.pdf;
            }
            if restir_update(&r, entry.light, w, 1.0) {
                p_hat_y = p_hat;
            }
        }
        // M is every candidate drawn, also those a tile without lights could not draw.
        r.m = f32(restir.candidates);
        r.w = restir_contribution_weight(r.w_sum, r.m, p_hat_y);
        // Visibility reuse: a sample the pixel cannot see is worth nothing to it, nor to its neighbours.
        if r.w > 0.0 && restir_occluded(s.position, s.normal, r.light) {
            r.w = 0.0;
        }
        count_work(pixel, WORK_LIGHT_EVALUATIONS, restir.candidates);
        count_work(pixel, WORK_SHADOW_RAYS, bvh_shadow_rays);
    }
    reservoirs_out[restir_index(id.xy)] = restir_stamp(r, s);
}
