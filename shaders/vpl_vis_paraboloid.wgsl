// VPL visibility from one paraboloid shadow map per VPL (Brabec et al. 2002, as Dong et al. 2009 section 4.2
// use it): the map faces the VPL's normal, a direction `dir` in the VPL's frame lands at
// `dir.xy / (1 + dir.z)`; the atlas tile of VPL k of the batch is `first_tile + k`. Depth is the linear distance
// from the map's centre, (d - near) / (far - near), as paraboloid_depth.wgsl writes it. Hard visibility, one
// texel. Group 1: the atlas.

@group(1) @binding(0) var paraboloid_atlas: texture_2d<f32>;

// Lookups of this invocation (one texel each), for the work counters.
var<private> vpl_lookups: u32 = 0u;

fn count_visibility_work(pixel: vec2<i32>) {
    count_work(pixel, WORK_INDIRECT_SHADOW_LOOKUPS, vpl_lookups);
    count_work(pixel, WORK_INDIRECT_FILTER_TAPS, vpl_lookups);
}

fn vpl_visibility(s: Surface, v: Vpl, k: u32) -> f32 {
    vpl_lookups += 1u;
    let basis = vpl_basis(v.normal.xyz);
    let centre = v.position.xyz + v.normal.xyz * gather.origin_offset;
    // Normal offset in texels of the map at the receiver: a texel spans about (2 / res)(1 + cos) radians.
    let rel0 = s.position - centre;
    let d0 = length(rel0);
    let cos0 = dot(rel0, v.normal.xyz) / max(d0, 1e-20);
    let footprint = d0 * 2.0 / f32(gather.resolution) * (1.0 + max(cos0, 0.0));
    let p = s.position + s.normal * (gather.normal_offset * footprint);
    let rel = p - centre;
    let local = vec3<f32>(dot(rel, basis[0]), dot(rel, basis[1]), dot(rel, basis[2]));
    let d = length(local);
    if !(d > 0.0) {
        return 1.0;
    }
    let dir = local / d;
    if dir.z <= 0.0 {
        // Behind the VPL: its term is zero anyway.
        return 1.0;
    }
    let uv = dir.xy / (1.0 + dir.z);
    let res = gather.resolution;
    let texel = clamp(vec2<u32>(vec2<f32>(uv.x * 0.5 + 0.5, 0.5 - uv.y * 0.5) * f32(res)), vec2<u32>(0u),
        vec2<u32>(res - 1u));
    let tile = gather.first_tile + k;
    let origin = vec2<u32>(tile % gather.tiles_per_row, tile / gather.tiles_per_row) * res;
    let stored = textureLoad(paraboloid_atlas, vec2<i32>(origin + texel), 0).r;
    let occluder = gather.depth_near + stored * (gather.depth_far - gather.depth_near);
    return select(0.0, 1.0, d - gather.bias <= occluder);
}
