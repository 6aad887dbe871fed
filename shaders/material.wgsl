// A material (group 1 of the G-buffer pass and of the alpha-tested depth passes): `Material` mirrors
// `MaterialUniform` in core/src/services/gpu_data.rs; the layout is `GpuScene::material_layout` (bindings 3 and
// 4, the emissive and occlusion textures, are declared by gbuffer.wgsl, the only pass that reads them).

struct Material {
    base_color: vec4<f32>,
    // rgb emissive, w: 1 when the base colour texture is used
    emissive: vec4<f32>,
    // x: specular intensity, y: shininess, z: 1 when the emissive texture is used, w: occlusion strength (0: no
    // occlusion texture)
    specular: vec4<f32>,
    // x: alpha cutoff (0: opaque, alpha ignored), y / z: 1 when the emissive / occlusion texture is mapped
    // with the second UV channel
    alpha: vec4<f32>,
}

@group(1) @binding(0) var<uniform> material: Material;
@group(1) @binding(1) var base_color_texture: texture_2d<f32>;
@group(1) @binding(2) var material_sampler: sampler;

// True when the material cuts this texel out (its alpha, factor times texture, below the cutoff). Sampled at
// level 0: the depth passes have no derivatives to choose one.
fn material_cut_out(uv: vec2<f32>) -> bool {
    var alpha = material.base_color.a;
    if material.emissive.w > 0.5 {
        alpha *= textureSampleLevel(base_color_texture, material_sampler, uv, 0.0).a;
    }
    return alpha < material.alpha.x;
}
