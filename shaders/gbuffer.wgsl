// G-buffer pass: albedo, normal + shininess, emissive + specular, hardware depth.
// Vertex layout: `Vertex` in core/src/scene/chunks.rs (buffer 0) and the second UV channel (buffer 1,
// `ChunkedGeometry::uv1`). Composed after material.wgsl (group 1).

struct Camera {
    clip_from_world: mat4x4<f32>,
}


@group(0) @binding(0) var<uniform> camera: Camera;
@group(1) @binding(3) var emissive_texture: texture_2d<f32>;
@group(1) @binding(4) var occlusion_texture: texture_2d<f32>;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) uv1: vec2<f32>,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) world: vec3<f32>,
    @location(3) uv1: vec2<f32>,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = camera.clip_from_world * vec4<f32>(v.position, 1.0);
    out.normal = v.normal;
    out.uv = v.uv;
    out.uv1 = v.uv1;
    out.world = v.position;
    return out;
}

struct GBufferOut {
    @location(0) albedo: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) emissive: vec4<f32>,
}

// The material's base colour at the fragment (its texture when it has one).
fn base_color(in: VertexOut) -> vec4<f32> {
    var color = material.base_color;
    if material.emissive.w > 0.5 {
        color *= textureSample(base_color_texture, material_sampler, in.uv);
    }
    return color;
}

// Alpha-tested materials (glTF MASK, OBJ cut-outs: foliage and the like): cut out below the material's cutoff.
// The discard keeps a rasterizer from testing depth before the shader, so opaque materials use `fs_opaque`.
@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> GBufferOut {
    let color = base_color(in);
    if color.a < material.alpha.x {
        discard;
    }
    return gbuffer(in, front, color);
}

// Opaque materials: the same outputs without the alpha test, so hidden fragments are rejected by the depth test
// before they are shaded.
@fragment
fn fs_opaque(in: VertexOut, @builtin(front_facing) front: bool) -> GBufferOut {
    return gbuffer(in, front, base_color(in));
}

fn gbuffer(in: VertexOut, front: bool, color: vec4<f32>) -> GBufferOut {
    // Two-sided lighting: real scenes have single-sided walls seen from both sides.
    var n = normalize(in.normal);
    if !front {
        n = -n;
    }
    var out: GBufferOut;
    // Ambient occlusion rides in the albedo's alpha (the ambient pass multiplies the ambient term by it).
    var occlusion = 1.0;
    if material.specular.w > 0.0 {
        // Textures are uploaded as sRGB; occlusion is stored linear, so undo the decode for the raw value.
        let x = textureSample(occlusion_texture, material_sampler, select(in.uv, in.uv1, material.alpha.z > 0.5)).r;
        let raw = select(1.055 * pow(x, 1.0 / 2.4) - 0.055, 12.92 * x, x <= 0.0031308);
        occlusion = 1.0 + material.specular.w * (clamp(raw, 0.0, 1.0) - 1.0);
    }
    out.albedo = vec4<f32>(color.rgb, occlusion);
    out.normal = vec4<f32>(n, material.specular.y);
    var emission = material.emissive.rgb;
    if material.specular.z > 0.5 {
        emission *= textureSample(emissive_texture, material_sampler, select(in.uv, in.uv1, material.alpha.y > 0.5)).rgb;
    }
    out.emissive = vec4<f32>(emission, material.specular.x);
    return out;
}
