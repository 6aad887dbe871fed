// The VPL gather: every pixel sums the radiance of the batch's VPLs times their visibility
// (`vpl_visibility`, defined by the file composed before this one) and adds rho/pi times the sum into the
// indirect buffer. One invocation per pixel, so the f32 read-modify-write needs no atomics; the batch's terms
// are summed in f32 registers, so splitting the VPLs into batches changes the result by f32 rounding only.

@compute @workgroup_size(8, 8)
fn gather_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let width = u32(frame.viewport.x);
    let height = u32(frame.viewport.y);
    if id.x >= width || id.y >= height {
        return;
    }
    let s = load_surface(vec2<i32>(id.xy));
    if !s.is_geometry {
        return;
    }
    let range = gather_range(id.xy);
    var sum = vec3<f32>(0.0);
    var open = vec3<f32>(0.0);
    var evaluations = 0u;
    for (var k = range.start; k < gather.vpl_count; k += range.stride) {
        let v = vpls[gather.first_vpl + k];
        let term = vpl_term(s, v);
        evaluations += 1u;
        if max(term.x, max(term.y, term.z)) > 0.0 {
            sum += term * vpl_visibility(s, v, k);
            open += term;
        }
    }
    let all = every_vpl_unshadowed(s);
    count_work(vec2<i32>(id.xy), WORK_VPL_EVALUATIONS, evaluations + all.evaluations);
    count_visibility_work(vec2<i32>(id.xy));
    gather_out(id.y * width + id.x, s.albedo, range, sum, open, all.light);
}
