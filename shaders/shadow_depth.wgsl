// Depth-only rendering of one cube-map face. `clip_from_world` comes per face through a dynamic offset.

struct Face {
    clip_from_world: mat4x4<f32>,
    // the face's centre (xyz) and the push per unit of view depth (w) of `vs_pushed`
    eye_push: vec4<f32>,
}

@group(0) @binding(0) var<uniform> face: Face;

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return face.clip_from_world * vec4<f32>(position, 1.0);
}

// Geometry whose vertices carry their own uncertainty (INSM's meshes: the fourth float is the sample's inverse
// view depth 1 / z from its intermediate viewpoint): each vertex moves away from the face's centre by
// push * z, a depth bias that grows with the width of the sample it came from. A radial move keeps a vertex in
// the faces and outside the culling hulls it was in (both are cones or convex sets around the centre).
@vertex
fn vs_pushed(@location(0) position: vec3<f32>, @location(1) inverse_depth: f32) -> @builtin(position) vec4<f32> {
    let away = position - face.eye_push.xyz;
    let d = length(away);
    var p = position;
    if d > 0.0 && inverse_depth > 0.0 {
        p += away * (face.eye_push.w / (inverse_depth * d));
    }
    return face.clip_from_world * vec4<f32>(p, 1.0);
}

// Alpha-tested casters (cut-out materials: leaves, fences): material.wgsl's cutoff test, so they cast the shape
// the view shows.

struct MaskedOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

@vertex
fn vs_masked(@location(0) position: vec3<f32>, @location(2) uv: vec2<f32>) -> MaskedOut {
    var out: MaskedOut;
    out.clip = face.clip_from_world * vec4<f32>(position, 1.0);
    out.uv = uv;
    return out;
}

@fragment
fn fs_masked(in: MaskedOut) {
    if material_cut_out(in.uv) {
        discard;
    }
}
