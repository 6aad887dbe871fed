// Depth-only rendering of one cube-map face. `clip_from_world` comes per face through a dynamic offset.

struct Face {
    clip_from_world: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> face: Face;

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return face.clip_from_world * vec4<f32>(position, 1.0);
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
