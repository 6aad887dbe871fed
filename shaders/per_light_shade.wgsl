// Reference technique, shading of one batch of lights: every light has its own cube shadow map in the batch's atlas
// and binary (hard) visibility. Composed after common.wgsl, light_tiles.wgsl and cube_shadow.wgsl, before
// per_light_main.wgsl (the shading loop).
// `Batch` mirrors `PerLightBatchUniform` in core/src/services/per_light_shadows.rs.

struct Batch {
    first_light: u32,
    light_count: u32,
    // texels per cube face
    resolution: f32,
    // constant bias in world units, added to the normal offset
    bias_world: f32,
    // normal offset in shadow-map texels
    normal_offset_texels: f32,
    tiles_per_row: u32,
    _pad1: f32,
    _pad2: f32,
}

@group(1) @binding(0) var<storage, read> lights: array<Light>;
@group(1) @binding(1) var<uniform> batch: Batch;
@group(1) @binding(2) var shadow_atlas: texture_2d<f32>;

fn light_visibility(s: Surface, light: Light, cube_index: u32) -> f32 {
    let d = distance(s.position, light.position);
    // Normal offset grows with the texel footprint (2 d / resolution) so acne stays away at every distance.
    let texel_world = 2.0 * d / batch.resolution;
    let p = s.position + s.normal * (texel_world * batch.normal_offset_texels);
    let look = cube_lookup(p - light.position, cube_index, batch.resolution, batch.tiles_per_row);
    let depth = textureLoad(shadow_atlas, look.texel, 0).r;
    if depth >= 1.0 {
        return 1.0;
    }
    let occluder = cube_depth_to_distance(depth, light.shadow_near, light.range);
    return select(0.0, 1.0, look.axis_distance - batch.bias_world <= occluder);
}
