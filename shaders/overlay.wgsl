// Overlays drawn over the tone-mapped 3D view: lines (light ranges, cluster links, frusta) as screen-space quads
// of `style.x` pixels, and screen-sized dots (lights, centers). Depth-tested against the G-buffer depth, with
// the occluded parts drawn again faded (`style.y` of their alpha); or all drawn on top in x-ray mode.
// `View` mirrors `OverlayUniform` in core/src/services/overlay.rs.

struct View {
    clip_from_world: mat4x4<f32>,
    // width, height, 1/width, 1/height
    viewport: vec4<f32>,
    // line width in pixels, alpha factor of occluded parts, unused, unused
    style: vec4<f32>,
}

@group(0) @binding(0) var<uniform> view: View;

// One instance per segment; six vertices make its quad.
struct SegmentIn {
    @location(0) a: vec3<f32>,
    @location(1) b: vec3<f32>,
    @location(2) color: vec4<f32>,
}

struct Out {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
}

// Clip the segment a-b against the near plane (clip z >= 0), moving the endpoint `a` when it is behind.
fn clip_near(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    if a.z >= 0.0 {
        return a;
    }
    let t = a.z / (a.z - b.z);
    return mix(a, b, t);
}

@vertex
fn line_vs(v: SegmentIn, @builtin(vertex_index) i: u32) -> Out {
    var out: Out;
    out.color = v.color;
    let ca0 = view.clip_from_world * vec4<f32>(v.a, 1.0);
    let cb0 = view.clip_from_world * vec4<f32>(v.b, 1.0);
    if ca0.z < 0.0 && cb0.z < 0.0 {
        // Wholly behind the camera: outside the clip volume.
        out.clip = vec4<f32>(0.0, 0.0, -1.0, 1.0);
        return out;
    }
    let ca = clip_near(ca0, cb0);
    let cb = clip_near(cb0, ca0);
    // Corners of the quad: along (0 = a, 1 = b) and across (-1, +1).
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(0.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(0.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(0.0, 1.0),
    );
    let corner = corners[i % 6u];
    let half_size = view.viewport.xy * 0.5;
    let pa = ca.xy / max(ca.w, 1e-6) * half_size;
    let pb = cb.xy / max(cb.w, 1e-6) * half_size;
    let d = pb - pa;
    let len = length(d);
    var dir = vec2<f32>(1.0, 0.0);
    if len > 1e-6 {
        dir = d / len;
    }
    let normal = vec2<f32>(-dir.y, dir.x);
    let half_width = view.style.x * 0.5;
    // The ends are extended by half the width, so segments of a polyline join without gaps.
    let offset_px = normal * corner.y * half_width + dir * (corner.x * 2.0 - 1.0) * half_width;
    let c = select(ca, cb, corner.x > 0.5);
    out.clip = vec4<f32>(c.xy + offset_px / half_size * c.w, c.z, c.w);
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

// The parts behind the scene's surfaces, faded.
@fragment
fn line_faded_fs(in: Out) -> @location(0) vec4<f32> {
    return vec4<f32>(in.color.rgb, in.color.a * view.style.y);
}

// A round dot with a dark rim.
fn dot_color(in: DotOut) -> vec4<f32> {
    let d = length(in.local);
    if d > 1.0 {
        discard;
    }
    let rim = smoothstep(0.7, 0.85, d);
    return vec4<f32>(mix(in.color.rgb, vec3<f32>(0.0), rim * 0.8), in.color.a);
}

@fragment
fn dot_fs(in: DotOut) -> @location(0) vec4<f32> {
    return dot_color(in);
}

@fragment
fn dot_faded_fs(in: DotOut) -> @location(0) vec4<f32> {
    let c = dot_color(in);
    return vec4<f32>(c.rgb, c.a * view.style.y);
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
