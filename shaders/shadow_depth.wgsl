// Depth-only rendering of one cube-map face. `clip_from_world` comes per face through a dynamic offset.

struct Face {
    clip_from_world: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> face: Face;

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return face.clip_from_world * vec4<f32>(position, 1.0);
}

// Alpha-tested casters (cut-out materials: leaves, fences): the material of gbuffer.wgsl (keep `Material` in sync),
// its base colour's alpha against its cutoff, so they cast the shape the view shows.
struct Material {
    base_color: vec4<f32>,
    // w: 1 when the base colour texture is used
    emissive: vec4<f32>,
    specular: vec4<f32>,
    // x: alpha cutoff
    alpha: vec4<f32>,
}

@group(1) @binding(0) var<uniform> material: Material;
@group(1) @binding(1) var base_color_texture: texture_2d<f32>;
@group(1) @binding(2) var material_sampler: sampler;

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
    var alpha = material.base_color.a;
    if material.emissive.w > 0.5 {
        alpha *= textureSampleLevel(base_color_texture, material_sampler, in.uv, 0.0).a;
    }
    if alpha < material.alpha.x {
        discard;
    }
}
