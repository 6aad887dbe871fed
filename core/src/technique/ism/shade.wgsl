// ISM step 4, the shadow lookup in the shading of one batch of lights: every light has its dual paraboloid
// (tiles 2k and 2k + 1 of the batch's atlas), one texel per lookup, hard visibility with a bias; the batch's
// lights that reach the pixel's tile (light_tiles.wgsl), in the reference's loop (shaders/per_light_main.wgsl).
// Composed after common.wgsl, light_tiles.wgsl, vpl_basis.wgsl and ism/paraboloid.wgsl, before
// per_light_main.wgsl. `IsmBatch` mirrors `ShadeUniform` in
// core/src/technique/ism/passes.rs.

struct IsmBatch {
    first_light: u32,
    light_count: u32,
    resolution: u32,
    tiles_per_row: u32,
    // constant bias, in texel footprints at the receiver
    bias: f32,
    // receiver offset along its normal, in texel footprints at the receiver
    normal_offset: f32,
    _pad0: f32,
    _pad1: f32,
}

@group(1) @binding(0) var<storage, read> lights: array<Light>;
@group(1) @binding(1) var<uniform> batch: IsmBatch;
@group(1) @binding(2) var ism_atlas: texture_2d<f32>;

fn light_visibility(s: Surface, light: Light, k: u32) -> f32 {
    let rel0 = s.position - light.position;
    let d0 = length(rel0);
    let footprint = ism_footprint(d0, abs(rel0.y) / max(d0, 1e-20), batch.resolution);
    let rel = s.position + s.normal * (batch.normal_offset * footprint) - light.position;
    let upper = rel.y >= 0.0;
    let look = ism_project(rel, select(-ISM_UP, ISM_UP, upper), batch.resolution);
    let tile = 2u * k + select(1u, 0u, upper);
    let stored = textureLoad(ism_atlas, ism_atlas_texel(tile, look.texel, batch.tiles_per_row, batch.resolution), 0).r;
    if stored >= ISM_EMPTY {
        return 1.0;
    }
    let occluder = light.shadow_near + stored * (light.range - light.shadow_near);
    return select(0.0, 1.0, look.distance - batch.bias * footprint <= occluder);
}
