// ISM step 4, the shadow lookup in the shading of one batch of lights: every light has its dual paraboloid
// (tiles 2k and 2k + 1 of the batch's atlas), one texel per lookup, hard visibility with a bias; the batch's
// lights that reach the pixel's tile (light_tiles.wgsl), as the reference's per_light_shade.wgsl. Composed after
// common.wgsl, light_tiles.wgsl, vpl_basis.wgsl and ism/paraboloid.wgsl. `IsmBatch` mirrors `ShadeUniform` in
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

fn ism_visibility(s: Surface, light: Light, k: u32) -> f32 {
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

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.position.xy);
    let s = load_surface(pixel);
    if !s.is_geometry {
        discard;
    }
    var sum = vec3<f32>(0.0);
    var lookups = 0u;
    let span = tile_span(pixel, batch.first_light, batch.light_count);
    for (var j = span.start; j < span.end; j++) {
        let index = tile_item(span, j);
        let light = lights[index];
        let unshadowed = shade_light(s, light);
        if any(unshadowed > vec3<f32>(0.0)) {
            sum += unshadowed * ism_visibility(s, light, index - batch.first_light);
            lookups += 1u;
        }
    }
    count_work(pixel, WORK_LIGHT_EVALUATIONS, span.end - span.start);
    count_work(pixel, WORK_SHADOW_LOOKUPS, lookups);
    count_work(pixel, WORK_FILTER_TAPS, lookups);
    return vec4<f32>(sum, 0.0);
}
