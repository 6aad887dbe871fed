// Unshadowed: every light with visibility 1. The cheap preview of the app, and the denominator of
// visibility (shadow factor) comparisons. Composed after common.wgsl.
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
    let s = load_surface(vec2<i32>(in.position.xy));
    if !s.is_geometry {
        discard;
    }
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < batch.light_count; i++) {
        sum += shade_light(s, lights[batch.first_light + i]);
    }
    return vec4<f32>(sum, 0.0);
}
