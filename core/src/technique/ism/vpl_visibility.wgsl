// vpl-ism: VPL visibility from one imperfect shadow map per VPL (Ritschel et al. 2008: a hemispherical paraboloid
// along the VPL's normal), one texel per lookup, hard, with the bias and normal offset in texel footprints as the
// direct lookup (ism/shade.wgsl). Tile of the batch's VPL k: `first_tile + k`; depth (d - near) / (far - near) of
// the distance from the map's centre, `origin_offset` off the VPL along its normal (as vpl-shadowmaps). Composed
// after common.wgsl, vpl_common.wgsl, vpl_basis.wgsl and ism/paraboloid.wgsl, before vpl_gather.wgsl. Group 1:
// the ISM atlas.

@group(1) @binding(0) var ism_atlas: texture_2d<f32>;

// Lookups of this invocation (one texel each), for the work counters.
var<private> vpl_lookups: u32 = 0u;

fn count_visibility_work(pixel: vec2<i32>) {
    count_work(pixel, WORK_INDIRECT_SHADOW_LOOKUPS, vpl_lookups);
    count_work(pixel, WORK_INDIRECT_FILTER_TAPS, vpl_lookups);
}

fn vpl_visibility(s: Surface, v: Vpl, k: u32) -> f32 {
    vpl_lookups += 1u;
    let centre = v.position.xyz + v.normal.xyz * gather.origin_offset;
    let rel0 = s.position - centre;
    let d0 = length(rel0);
    let footprint = ism_footprint(d0, dot(rel0, v.normal.xyz) / max(d0, 1e-20), gather.resolution);
    let rel = s.position + s.normal * (gather.normal_offset * footprint) - centre;
    let look = ism_project(rel, v.normal.xyz, gather.resolution);
    if !(look.distance > 0.0) || look.cos_axis <= 0.0 {
        // Behind the VPL: its term is zero anyway.
        return 1.0;
    }
    let texel = ism_atlas_texel(gather.first_tile + k, look.texel, gather.tiles_per_row, gather.resolution);
    let stored = textureLoad(ism_atlas, texel, 0).r;
    if stored >= ISM_EMPTY {
        return 1.0;
    }
    let occluder = gather.depth_near + stored * (gather.depth_far - gather.depth_near);
    return select(0.0, 1.0, look.distance - gather.bias * footprint <= occluder);
}
