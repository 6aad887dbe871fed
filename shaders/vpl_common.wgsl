// What every VPL gather shares: the VPL layout, the batch uniform, the indirect output and the radiance one VPL
// sends to a receiver. Composed after common.wgsl (and the visibility's own files), before vpl_gather.wgsl.
// Composed after vpl_term.wgsl (the VPL layout and its radiance). `GatherBatch` mirrors `GatherBatchUniform` in
// core/src/services/vpl_gather.rs.

struct GatherBatch {
    first_vpl: u32,
    vpl_count: u32,
    // d_clamp^2: 1/d^2 is clamped to 1/d_clamp^2
    clamp_sq: f32,
    // ray or shadow-map bias, world units (per metre of camera distance for rays)
    bias: f32,
    // atlas tile of the batch's first VPL (shadow maps)
    first_tile: u32,
    tiles_per_row: u32,
    resolution: u32,
    // normal offset of the receiver, in texels of the map at the receiver (shadow maps)
    normal_offset: f32,
    // shadow-map depth range: near, far (world units)
    depth_near: f32,
    depth_far: f32,
    // offset of the map's centre from the VPL along its normal, world units
    origin_offset: f32,
    // 1: interleaved sampling, each pixel of an 8x8 block gathers every 64th VPL (times 64); 2: the same for
    // the ratio estimator, the output holding the luminance of the shadowed and the unshadowed sums
    // (`interleave_out`) for vpl_blur.wgsl
    interleave: u32,
}

@group(2) @binding(0) var<storage, read> vpls: array<Vpl>;
@group(2) @binding(1) var<uniform> gather: GatherBatch;
@group(2) @binding(2) var<storage, read_write> indirect_out: array<vec4<f32>>;

// Which of the batch's VPLs a pixel gathers: all of them, or with interleaved sampling the pixel of class
// c = (x mod 8) + 8 (y mod 8) takes those whose frame index is c mod 64, weighted by 64 (vpl_blur.wgsl spreads
// them over the block again).
struct GatherRange {
    start: u32,
    stride: u32,
    scale: f32,
}

fn gather_range(pixel: vec2<u32>) -> GatherRange {
    var r: GatherRange;
    r.start = 0u;
    r.stride = 1u;
    r.scale = 1.0;
    if gather.interleave != 0u {
        let pixel_class = (pixel.x % 8u) + 8u * (pixel.y % 8u);
        r.start = (pixel_class + 64u - gather.first_vpl % 64u) % 64u;
        r.stride = 64u;
        r.scale = 64.0;
    }
    return r;
}

// Irradiance-like term of one VPL at a receiver with the batch's clamp (`vpl_radiance`, vpl_term.wgsl).
fn vpl_term(s: Surface, v: Vpl) -> vec3<f32> {
    return vpl_radiance(s, v, gather.clamp_sq);
}

// What a gather adds into the indirect buffer for a pixel of albedo `albedo`: the shadowed sum `lit` and the
// unshadowed one `open` of its VPLs, both already scaled by the range's weight. With the ratio estimator
// (interleave 2) the luminances of both, irradiance-like (over pi, no albedo), which vpl_blur.wgsl turns into a
// visibility share; otherwise rho/pi times the shadowed sum.
fn interleave_out(albedo: vec3<f32>, lit: vec3<f32>, open: vec3<f32>) -> vec4<f32> {
    if gather.interleave == 2u {
        return vec4<f32>(luminance(lit) / PI, luminance(open) / PI, 0.0, 0.0);
    }
    return vec4<f32>(albedo / PI * lit, 0.0);
}
