// The depth readback of adapters that cannot copy depth to a buffer (GL; core/src/gpu/readback.rs): one
// triangle over an R32Uint target of the depth texture's size, each fragment writing its texel's depth bits.
// The depth is bound as an unfilterable float texture: naga's GLSL output cannot load from a depth texture.

@group(0) @binding(0) var depth: texture_2d<f32>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<u32> {
    return vec4<u32>(bitcast<u32>(textureLoad(depth, vec2<i32>(p.xy), 0).r), 0u, 0u, 1u);
}
