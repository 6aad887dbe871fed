// Overlays drawn over the tone-mapped 3D view: lines (light ranges, cluster links, frusta) and screen-sized
// dots (lights, centers), depth-tested against the G-buffer depth, or not at all in x-ray mode.
// `View` mirrors `OverlayUniform` in core/src/renderer/overlay.rs.

struct View {
    clip_from_world: mat4x4<f32>,
    // width, height, 1/width, 1/height
    viewport: vec4<f32>,
}

@group(0) @binding(0) var<uniform> view: View;

struct LineIn {
    @location(0) position: vec3<f32>,
    @location(1) color: vec4<f32>,
}

struct Out {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
}

@vertex
fn line_vs(v: LineIn) -> Out {
    var out: Out;
    out.clip = view.clip_from_world * vec4<f32>(v.position, 1.0);
    out.color = v.color;
    return out;
}

struct DotIn {
    @location(0) center: vec3<f32>,
    // offset of this corner from the center, in pixels
    @location(1) corner_px: vec2<f32>,
    @location(2) color: vec4<f32>,
}

struct DotOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
    @location(1) local: vec2<f32>,
}

@vertex
fn dot_vs(v: DotIn) -> DotOut {
    var out: DotOut;
    var clip = view.clip_from_world * vec4<f32>(v.center, 1.0);
    // Pull the dot towards the camera a little so it is not hidden by the surface it sits on.
    clip.z = clip.z - 0.0005 * clip.w;
    clip = vec4<f32>(clip.xy + v.corner_px * 2.0 * view.viewport.zw * clip.w * vec2<f32>(1.0, -1.0), clip.zw);
    out.clip = clip;
    out.color = v.color;
    out.local = v.corner_px / max(abs(v.corner_px.x), 1e-6);
    return out;
}

@fragment
fn line_fs(in: Out) -> @location(0) vec4<f32> {
    return in.color;
}

@fragment
fn dot_fs(in: DotOut) -> @location(0) vec4<f32> {
    // A round dot with a dark rim.
    let d = length(in.local);
    if d > 1.0 {
        discard;
    }
    let rim = smoothstep(0.7, 0.85, d);
    return vec4<f32>(mix(in.color.rgb, vec3<f32>(0.0), rim * 0.8), in.color.a);
}

// Per-pixel ID map, coloured on the CPU (transparent where there is no ID), stretched over the view.
@group(1) @binding(0) var id_colors: texture_2d<f32>;

@vertex
fn idmap_vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn idmap_fs(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<f32>(textureDimensions(id_colors));
    let texel = vec2<i32>(position.xy * view.viewport.zw * size);
    return textureLoad(id_colors, texel, 0);
}
