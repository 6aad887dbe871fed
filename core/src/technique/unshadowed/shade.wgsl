// Unshadowed: every light with visibility 1. The cheap preview of the app, and the denominator of
// visibility (shadow factor) comparisons. Composed after common.wgsl and light_tiles.wgsl.
// `Batch` mirrors `UnshadowedBatchUniform` in core/src/technique/unshadowed/mod.rs.

struct Batch {
    first_light: u32,
    light_count: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(1) @binding(0) var<storage, read> lights: array<Light>;
@group(1) @binding(1) var<uniform> batch: Batch;

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.position.xy);
    let s = load_surface(pixel);
    if !s.is_geometry {
        discard;
    }
    var sum = vec3<f32>(0.0);
    let span = tile_span(pixel, batch.first_light, batch.light_count);
    for (var j = span.start; j < span.end; j++) {
        sum += shade_light(s, lights[tile_item(span, j)]);
    }
    count_work(pixel, WORK_LIGHT_EVALUATIONS, span.end - span.start);
    return vec4<f32>(sum, 0.0);
}
