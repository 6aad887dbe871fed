// The shading main of a per-light technique with binary visibility (the reference, ISM): every light of the
// batch that reaches the pixel's tile (light_tiles.wgsl), in batch order, its unshadowed light times its
// visibility; one texel per lookup in the work counters. Composed after common.wgsl, light_tiles.wgsl and the
// technique's own file, which binds `lights` and `batch` (with `first_light` and `light_count`) and defines
// `light_visibility(s, light, slot)` for the light at `slot` of the batch.

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.position.xy);
    let s = load_surface(pixel);
    if !s.is_geometry {
        discard;
    }
    var sum = vec3<f32>(0.0);
    var lookups = 0u;
    let span = tile_span(pixel, batch.first_light, batch.light_count);
    for (var j = span.start; j < span.end; j++) {
        let index = tile_item(span, j);
        let light = lights[index];
        let unshadowed = shade_light(s, light);
        if any(unshadowed > vec3<f32>(0.0)) {
            sum += unshadowed * light_visibility(s, light, index - batch.first_light);
            lookups += 1u;
        }
    }
    count_work(pixel, WORK_LIGHT_EVALUATIONS, span.end - span.start);
    count_work(pixel, WORK_SHADOW_LOOKUPS, lookups);
    count_work(pixel, WORK_FILTER_TAPS, lookups);
    return vec4<f32>(sum, 0.0);
}
