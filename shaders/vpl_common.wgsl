// What every VPL gather shares: the VPL layout, the batch uniform, the indirect output and the radiance one VPL
// sends to a receiver. Composed after common.wgsl (and the visibility's own files), before vpl_gather.wgsl.
// `Vpl` mirrors `GpuVpl` in core/src/vpl/mod.rs; `GatherBatch` mirrors `GatherBatchUniform` in
// core/src/services/vpl_gather.rs.

struct Vpl {
    // xyz: position
    position: vec4<f32>,
    // xyz: unit normal
    normal: vec4<f32>,
    // rgb: reflected flux
    flux: vec4<f32>,
}

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
    // 1: interleaved sampling, each pixel of a B x B block gathers every B^2-th VPL (times B^2); 2: the same
    // with the ratio estimator (`gather_out`)
    interleave: u32,
    // B, the interleaving block's side (2-8; the paper's 8)
    block: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(2) @binding(0) var<storage, read> vpls: array<Vpl>;
@group(2) @binding(1) var<uniform> gather: GatherBatch;
@group(2) @binding(2) var<storage, read_write> indirect_out: array<vec4<f32>>;
// Interleave 2 only: per pixel, the luminance of its share of the VPLs shadowed (x) and unshadowed (y), over pi.
@group(2) @binding(3) var<storage, read_write> ratio_out: array<vec2<f32>>;

// Which of the batch's VPLs a pixel gathers: all of them, or with interleaved sampling the pixel of class
// c = (x mod B) + B (y mod B) takes those whose frame index is c mod B^2, weighted by B^2 (vpl_blur.wgsl spreads
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
        let b = clamp(gather.block, 2u, 8u);
        let classes = b * b;
        let pixel_class = (pixel.x % b) + b * (pixel.y % b);
        r.start = (pixel_class + classes - gather.first_vpl % classes) % classes;
        r.stride = classes;
        r.scale = f32(classes);
    }
    return r;
}

// Irradiance-like term of one VPL at a receiver, before visibility and the receiver's rho/pi:
// Phi/pi * cos(theta_i) cos(theta_x) / max(d^2, d_clamp^2). Zero (never NaN) when the receiver lies on the VPL,
// behind it, or faces away.
fn vpl_term(s: Surface, v: Vpl) -> vec3<f32> {
    let to_x = s.position - v.position.xyz;
    let d2 = dot(to_x, to_x);
    if !(d2 > 1e-12) {
        return vec3<f32>(0.0);
    }
    let w = to_x * inverseSqrt(d2);
    let cos_i = dot(v.normal.xyz, w);
    let cos_x = -dot(s.normal, w);
    if cos_i <= 0.0 || cos_x <= 0.0 {
        return vec3<f32>(0.0);
    }
    return v.flux.rgb * (cos_i * cos_x / (PI * max(d2, gather.clamp_sq)));
}

// The ratio estimator's unshadowed light from every VPL of the batch (interleave 2; none otherwise), and the VPL
// evaluations it took. A loop of its own: inside a range's loop with its visibility tests, the neighbouring
// pixels' ranges (other classes, the same SIMD group) would run those tests at every VPL.
struct EveryVpl {
    light: vec3<f32>,
    evaluations: u32,
}

fn every_vpl_unshadowed(s: Surface) -> EveryVpl {
    var out = EveryVpl(vec3<f32>(0.0), 0u);
    if gather.interleave == 2u {
        for (var k = 0u; k < gather.vpl_count; k++) {
            out.light += vpl_term(s, vpls[gather.first_vpl + k]);
        }
        out.evaluations = gather.vpl_count;
    }
    return out;
}

// A pixel's part of a batch, added into the indirect buffer: `lit` and `open` its range's VPLs with and without
// visibility, `all` every VPL's unshadowed light (the ratio estimator's; zero otherwise). Plain: rho/pi times the
// shadowed sum, weighted by the range. With the ratio estimator (interleave 2): rho/pi times every VPL's
// unshadowed light, and in `ratio_out` the weighted luminances of the range's with and without visibility, which
// vpl_blur.wgsl turns into the window's visibility share.
fn gather_out(index: u32, albedo: vec3<f32>, range: GatherRange, lit: vec3<f32>, open: vec3<f32>, all: vec3<f32>) {
    if gather.interleave == 2u {
        indirect_out[index] += vec4<f32>(albedo / PI * all, 0.0);
        ratio_out[index] += vec2<f32>(luminance(lit), luminance(open)) * (range.scale / PI);
        return;
    }
    indirect_out[index] += vec4<f32>(albedo / PI * lit * range.scale, 0.0);
}
