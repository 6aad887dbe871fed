// Depth-only rendering of one cube-map face. `clip_from_world` comes per face through a dynamic offset.

struct Face {
    clip_from_world: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> face: Face;

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return face.clip_from_world * vec4<f32>(position, 1.0);
}
