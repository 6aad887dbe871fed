// Virtual area lights (Dong et al. 2009, section 4): every pixel is lit by all VPLs of the batch (or, with
// interleaving, by its 1/B^2 share, the paper's 1/64), VPL i using the visibility of its VAL C(i). A VAL's
// visibility is computed at most once per pixel (at most MAX_VALS; with interleaving only for the VALs of the
// pixel's VPLs), then shared by the VAL's VPLs. Visibility of VAL m from its paraboloid map (tile m of the
// atlas, the map facing the VAL's normal, vpl_basis.wgsl):
// - hard: one depth test (the banding the paper avoids);
// - cssm (the paper): convolution soft shadow maps, Fourier basis textures filtered by mip-mapping (below);
// - pcss: blocker search over the VAL's angular size, z_avg, the paper's penumbra
//   p cos(beta) = (d - z_avg) Delta / z_avg, filter angle alpha = arctan(p cos(beta) / d), kernel width
//   alpha / pi of the map (section 4.2), then percentage-closer filtering over a grid of `grid^2` texels (not
//   run again when the kernel is the search region: the search's own comparisons give it).
// Receivers in a VAL's negative half-space take full visibility (section 5.1).
// Without interleaving a pixel walks the VALs' member lists (`val_lists`) and skips a VAL none of whose VPLs can
// light it (`may_light`, val/cull.rs; beyond the paper, which evaluates every VPL: the same sum).
// Composed after common.wgsl, vpl_common.wgsl and vpl_basis.wgsl. `GpuVal` and `ValParams` mirror
// core/src/technique/val/mod.rs.

const MAX_VALS: u32 = 256u;

struct GpuVal {
    // xyz: centre of the map, w: Delta (the VAL's size)
    centre: vec4<f32>,
    // xyz: unit normal, w: VPLs assigned (0: empty, visibility 1)
    normal: vec4<f32>,
    // x: near, y: far of its map, z: the radius of its VPLs' bounding sphere about `centre`
    depth: vec4<f32>,
    // The VPLs' normal cone about `normal` (val/cull.rs): x cos(theta), y sin(theta), z the furthest a VPL lies
    // behind `centre` along `normal`; w 1 when the emitter-side test applies (theta below 90 degrees)
    cone: vec4<f32>,
}

struct ValParams {
    val_count: u32,
    // 0 hard, 1 pcss, 2 cssm
    mode: u32,
    // PCF and blocker-search grid side
    grid: u32,
    tiles_per_row: u32,
    resolution: u32,
    // constant depth bias, world units
    bias: f32,
    // receiver normal offset in texels
    normal_offset: f32,
    // extra bias per texel of a sample's offset from the receiver's texel, in texel footprints (a receiver
    // sloped by up to atan(slope_bias) against the map's view direction does not shadow itself)
    slope_bias: f32,
    // >= 0: only the VPLs of this VAL light the image (its contribution alone, the paper's Fig. 9)
    solo: i32,
    // cssm: mip levels of the basis textures
    levels: u32,
    // cssm: the receiver's depth moved toward the VAL by this share of the map's depth range (the Fourier
    // step of 4 terms at half phase rises over about 1/4 of the range, so a receiver at its own depth would be
    // half lit)
    cssm_offset: f32,
    // Without interleaving, a VAL carrying less than this share of the pixel's unshadowed indirect light gets
    // one depth test instead of soft visibility (0: every VAL soft)
    soft_share: f32,
    // VPLs per batch (the member lists are per batch and VAL)
    batch_size: u32,
    // 1: walk the VALs' member lists and skip VALs that cannot light the pixel
    skip_unlit: u32,
    // where the VPL indices start in `val_lists`, in words
    members_offset: u32,
    _pad: u32,
}

@group(1) @binding(0) var val_atlas: texture_2d<f32>;
@group(1) @binding(1) var<storage, read> vals: array<GpuVal>;
@group(1) @binding(2) var<storage, read> vpl_val: array<u32>;
@group(1) @binding(3) var<uniform> val_params: ValParams;
// cssm: the mip-mapped Fourier basis textures of the atlas (val/cssm.wgsl) and a linear sampler.
@group(1) @binding(4) var cssm_a: texture_2d<f32>;
@group(1) @binding(5) var cssm_b: texture_2d<f32>;
@group(1) @binding(6) var cssm_za: texture_2d<f32>;
@group(1) @binding(7) var cssm_zb: texture_2d<f32>;
@group(1) @binding(8) var cssm_sampler: sampler;
// The VPLs by batch and VAL (val/cull.rs): `[start, count]` of batch b's members of VAL m at word 2 (b M + m),
// then the VPL indices from `members_offset` on.
@group(1) @binding(9) var<storage, read> val_lists: array<u32>;

// A VAL whose every VPL meets the pixel at a cosine at most this is skipped (`CULL_COSINE` in val/cull.rs).
const CULL_COSINE: f32 = 1e-3;

// The four basis textures filtered over 2^lod texels around texel t of VAL m's tile (kept inside the tile).
struct CssmSample {
    a: vec4<f32>,
    b: vec4<f32>,
    za: vec4<f32>,
    zb: vec4<f32>,
}

// VAL-map lookups of this invocation and the texels (or filtered CSSM fetches) they read, for the work
// counters.
var<private> val_lookups: u32 = 0u;
var<private> val_taps: u32 = 0u;

fn cssm_fetch(m: u32, t: vec2<f32>, lod: f32) -> CssmSample {
    val_taps += 1u;
    let res = f32(val_params.resolution);
    let half = 0.5 * exp2(ceil(lod));
    let inside = clamp(t, vec2<f32>(half), vec2<f32>(res - half));
    let origin = vec2<f32>(vec2<u32>(m % val_params.tiles_per_row, m / val_params.tiles_per_row)) * res;
    let uv = (origin + inside) / vec2<f32>(textureDimensions(cssm_a));
    var out: CssmSample;
    out.a = textureSampleLevel(cssm_a, cssm_sampler, uv, lod) * 2.0 - 1.0;
    out.b = textureSampleLevel(cssm_b, cssm_sampler, uv, lod) * 2.0 - 1.0;
    out.za = textureSampleLevel(cssm_za, cssm_sampler, uv, lod);
    out.zb = textureSampleLevel(cssm_zb, cssm_sampler, uv, lod);
    return out;
}

// sum_k (1/c_k) [cos(c_k d) <sin(c_k z)> - sin(c_k d) <cos(c_k z)>] for (cos, sin) pairs of terms 1-4.
fn cssm_series(d: f32, t12: vec4<f32>, t34: vec4<f32>, terms: u32) -> f32 {
    var sum = 0.0;
    for (var k = 0u; k < terms; k++) {
        let c = PI * f32(2u * k + 1u);
        var cs = t12.xy;
        if k == 1u {
            cs = t12.zw;
        } else if k == 2u {
            cs = t34.xy;
        } else if k == 3u {
            cs = t34.zw;
        }
        sum += (cos(c * d) * cs.y - sin(c * d) * cs.x) / c;
    }
    return sum;
}

// CSSM visibility of VAL m at the receiver's normalised depth `dn` around texel t (section 4.1-4.2): the
// blocker search over the VAL's angular size from the filtered basis-z (z_avg = <z (1 - f)> / <1 - f>), the
// penumbra p cos(beta) = (d - z_avg) Delta / z_avg, alpha = arctan(p cos(beta) / d), and the filtered step
// over a kernel of alpha / pi of the map.
fn cssm_visibility(m: u32, t: vec2<f32>, d: f32, dn: f32, search: f32, delta: f32, near: f32, far: f32) -> f32 {
    let res = f32(val_params.resolution);
    let max_lod = f32(val_params.levels) - 1.0;
    // Half phase, as the basis (val/cssm.wgsl): the step over z - d in (-1/2, 1/2).
    let ds = 0.5 * (dn - val_params.cssm_offset);
    let region = cssm_fetch(m, t, clamp(log2(search), 0.0, max_lod));
    let lit = clamp(0.5 + 2.0 * cssm_series(ds, region.a, region.b, 4u), 0.0, 1.0);
    let blocked = 1.0 - lit;
    if blocked < 1e-3 {
        return 1.0;
    }
    // <z f> over the region from basis-z (3 terms), so <z (1 - f)> = <z> - <z f>.
    let z_mean = region.zb.z;
    let z_lit = 0.5 * z_mean + 2.0 * cssm_series(ds, region.za, vec4<f32>(region.zb.xy, 0.0, 0.0), 3u);
    let z_blockers = clamp((z_mean - z_lit) / blocked, 0.0, dn);
    let z_avg = max(near + z_blockers * (far - near), 1e-6);
    let p_cos_beta = max(d - z_avg, 0.0) * delta / z_avg;
    let alpha = atan(p_cos_beta / d);
    let width = clamp(alpha / PI * res, 1.0, search);
    let kernel = cssm_fetch(m, t, clamp(log2(width), 0.0, max_lod));
    return clamp(0.5 + 2.0 * cssm_series(ds, kernel.a, kernel.b, 4u), 0.0, 1.0);
}

// Occluder distance stored at texel `t` (clamped into the tile) of VAL m's map.
fn val_occluder(m: u32, t: vec2<f32>, near: f32, far: f32) -> f32 {
    val_taps += 1u;
    let res = val_params.resolution;
    let texel = clamp(vec2<i32>(floor(t)), vec2<i32>(0), vec2<i32>(i32(res) - 1));
    let origin = vec2<i32>(vec2<u32>(m % val_params.tiles_per_row, m / val_params.tiles_per_row) * res);
    let stored = textureLoad(val_atlas, origin + texel, 0).r;
    return near + stored * (far - near);
}

// The receiver around a VAL map's lookup: a point of its plane (the map's frame), the plane's normal, the
// receiver's biased depth, the world size of a map texel there, and the distance to the map's centre.
struct ReceiverPlane {
    point: vec3<f32>,
    normal: vec3<f32>,
    receiver: f32,
    texel: f32,
    distance: f32,
}

// The depth a filter sample at texel `t`, `offset` texels from the receiver's, is compared with: the receiver's
// plane along the sample's direction (the paraboloid inverted: uv -> (2 uv, 1 - |uv|^2) / (1 + |uv|^2)), kept
// within 4 texels of depth per texel of offset of the receiver's own depth (a grazing plane runs off to
// infinity), less `slope_bias` texels per texel of offset for curvature (a concave receiver, as inside the closed
// sphere, bends toward the VAL away from its tangent plane). A deviation from the earlier
// `receiver - offset * slope_bias * texel`, which also had to cover the plane's own slope (`slope_bias = 2`)
// and so, on a flat receiver, let occluders up to `2 offset` texels in front of it through: the wide kernels of
// large VALs leaked light (Sponza, 30 VALs: see docs/techniques/val.md). Directions that miss the plane keep
// the earlier form.
fn receiver_depth(r: ReceiverPlane, t: vec2<f32>, offset: f32) -> f32 {
    let res = f32(val_params.resolution);
    let uv = vec2<f32>(t.x / res * 2.0 - 1.0, 1.0 - 2.0 * t.y / res);
    let r2 = dot(uv, uv);
    let w = vec3<f32>(2.0 * uv, 1.0 - r2) / (1.0 + r2);
    let curvature = offset * r.texel * val_params.slope_bias;
    let den = dot(r.normal, w);
    if abs(den) > 1e-6 {
        let along = dot(r.normal, r.point) / den;
        if along > 0.0 {
            let reach = 4.0 * offset * r.texel;
            return r.receiver + clamp(along - r.distance, -reach, reach) - curvature;
        }
    }
    return r.receiver - curvature;
}

// Where a receiver meets VAL m's map: its texel, distance and direction in the map's frame, its biased depth.
// `valid` false: the VAL cannot shadow the receiver (no VPLs, all behind the receiver's tangent plane, or the
// receiver in the VAL's negative half-space), so its visibility is 1.
struct ValLookup {
    valid: bool,
    t: vec2<f32>,
    d: f32,
    dir: vec3<f32>,
    local: vec3<f32>,
    basis: mat3x3<f32>,
    receiver: f32,
}

fn val_lookup(s: Surface, m: u32) -> ValLookup {
    var out: ValLookup;
    out.valid = false;
    let val = vals[m];
    if val.normal.w < 0.5 {
        return out;
    }
    let n = val.normal.xyz;
    let centre = val.centre.xyz;
    // Every VPL of the VAL behind the receiver's tangent plane: none lights it (`vpl_term` is 0), so its
    // visibility is never used; skipped (exact: the image does not change).
    if dot(s.normal, centre - s.position) + val.depth.z <= 0.0 {
        return out;
    }
    let rel0 = s.position - centre;
    if dot(rel0, n) <= 0.0 {
        return out;
    }
    let res = f32(val_params.resolution);
    let d0 = length(rel0);
    let cos0 = dot(rel0, n) / max(d0, 1e-20);
    let footprint = d0 * 2.0 / res * (1.0 + max(cos0, 0.0));
    let p = s.position + s.normal * (val_params.normal_offset * footprint);
    out.basis = vpl_basis(n);
    let rel = p - centre;
    out.local = vec3<f32>(dot(rel, out.basis[0]), dot(rel, out.basis[1]), dot(rel, out.basis[2]));
    out.d = length(out.local);
    if !(out.d > 0.0) {
        return out;
    }
    out.dir = out.local / out.d;
    if out.dir.z <= 0.0 {
        return out;
    }
    let uv = out.dir.xy / (1.0 + out.dir.z);
    out.t = vec2<f32>(uv.x * 0.5 + 0.5, 0.5 - uv.y * 0.5) * res;
    out.receiver = out.d - val_params.bias;
    out.valid = true;
    return out;
}

// One depth test (`hard`, or a VAL under `soft_share` of the pixel's light).
fn val_hard(m: u32, lk: ValLookup) -> f32 {
    let val = vals[m];
    return select(0.0, 1.0, lk.receiver <= val_occluder(m, lk.t, val.depth.x, val.depth.y));
}

fn val_visibility(s: Surface, m: u32, soft: bool) -> f32 {
    let lk = val_lookup(s, m);
    if !lk.valid {
        return 1.0;
    }
    val_lookups += 1u;
    if val_params.mode == 0u || !soft {
        return val_hard(m, lk);
    }
    return val_soft(s, m, lk);
}

// Soft visibility of VAL m (`cssm` or `pcss`) at a valid lookup.
fn val_soft(s: Surface, m: u32, lk: ValLookup) -> f32 {
    let val = vals[m];
    let res = f32(val_params.resolution);
    let t = lk.t;
    let d = lk.d;
    let dir = lk.dir;
    let local = lk.local;
    let basis = lk.basis;
    let receiver = lk.receiver;
    let near = val.depth.x;
    let far = val.depth.y;
    // Blocker search over the VAL's angular size seen from the receiver, as a width in texels (alpha / pi).
    let delta = val.centre.w;
    if val_params.mode == 2u {
        let search_cssm = max(atan(0.5 * delta / d) / PI * res, 1.0);
        return cssm_visibility(m, t, d, (receiver - near) / max(far - near, 1e-20), search_cssm, delta, near, far);
    }
    // World size of a texel at the receiver: the bias of a sample grows with its offset.
    let texel_world = d * 2.0 / res * (1.0 + dir.z);
    // The receiver's plane in the map's frame: a sample is compared with the plane's depth along its own
    // direction (a receiver-plane depth bias), so a flat receiver tilted against the map needs no slope
    // allowance; `slope_bias` is left for curved receivers (see receiver_depth).
    let receiver_normal = vec3<f32>(dot(s.normal, basis[0]), dot(s.normal, basis[1]), dot(s.normal, basis[2]));
    let plane = ReceiverPlane(local, receiver_normal, receiver, texel_world, d);
    let grid = max(val_params.grid, 2u);
    // The VAL's half-size seen from the receiver: blockers further off-axis than the VAL's edge cannot hide it.
    let search = max(atan(0.5 * delta / d) / PI * res, 1.0);
    var z_sum = 0.0;
    var blockers = 0.0;
    for (var j = 0u; j < grid; j++) {
        for (var i = 0u; i < grid; i++) {
            let o = (vec2<f32>(f32(i), f32(j)) / f32(grid - 1u) - 0.5) * search;
            let z = val_occluder(m, t + o, near, far);
            if z < receiver_depth(plane, t + o, length(o)) {
                z_sum += z;
                blockers += 1.0;
            }
        }
    }
    if blockers == 0.0 {
        return 1.0;
    }
    let z_avg = max(z_sum / blockers, 1e-6);
    let p_cos_beta = (d - z_avg) * delta / z_avg;
    let alpha = atan(p_cos_beta / d);
    // The kernel never exceeds the search region (as in PCSS): a penumbra wider than the VAL's own angular size
    // would average in texels that no part of the VAL is hidden by.
    let width = clamp(alpha / PI * res, 1.0, search);
    if width >= search {
        // The kernel is the search region (a blocker in the nearer two thirds of the way, roughly): the filter's
        // texels and comparisons are the search's, each lit exactly where the search found no blocker.
        return 1.0 - blockers / f32(grid * grid);
    }
    var lit = 0.0;
    for (var j = 0u; j < grid; j++) {
        for (var i = 0u; i < grid; i++) {
            let o = (vec2<f32>(f32(i), f32(j)) / f32(grid - 1u) - 0.5) * width;
            lit += select(0.0, 1.0, receiver_depth(plane, t + o, length(o)) <= val_occluder(m, t + o, near, far));
        }
    }
    return lit / f32(grid * grid);
}

// Without interleaving a pixel sums each VAL's unshadowed light over the VPLs first, then tests each VAL that
// lights it once, VAL by VAL, so that neighbouring pixels test the same VAL together (those wholly behind the
// pixel's tangent plane return at once, `val_visibility`); a VAL of less than `soft_share` of the pixel's light
// gets one depth test (twenty-second session; the same image as testing every VAL before the sum at 0). With
// interleaving (the paper's: "when shading from VPL i we use the VAL at index C(i)") a pixel's share holds few
// VPLs (16 of 1,024 with the paper's 8x8 block), so a VAL is tested only at the first of its VPLs that lights the pixel. Measured on lavapipe
// (Sponza, M = 128, 160x90, visibility pass, two builds alternated): with interleaving 306 / 411 ms testing
// every VAL against 58 / 65 ms testing at the first VPL; without it, finding the VALs that light the pixel first
// (a second pass over the VPLs) took 571 / 599 ms against 378 / 525, and testing at the first VPL about 715 (the
// lanes then ran the tests one by one). Twenty-third session: the hard tests run in the loop over the VALs and
// the soft ones from a list after it (lavapipe runs a branch's code for its 8-pixel group whenever any pixel
// takes it, and PCSS's code is long): Sponza, M = 144, 320x180, 625 / 683 -> 432 / 471 ms, the same image.
// The frame-order loop of `sum_by_val` and `sum_testing_at_first_vpl` share their first lines on purpose: one
// loop choosing per VPL between both ways ran both cases at the slower time.
struct VplSum {
    sum: vec3<f32>,
    evaluations: u32,
    // interleaved only: the range's unshadowed sum, and every VPL's (the ratio estimator's, `gather_out`)
    open: vec3<f32>,
    all: vec3<f32>,
}

fn lights_pixel(term: vec3<f32>) -> bool {
    return max(term.x, max(term.y, term.z)) > 0.0;
}

// Whether VAL m's light is shown (`solo`: one VAL alone, else all).
fn val_shown(m: u32) -> bool {
    return val_params.solo < 0 || m == u32(val_params.solo);
}

fn in_solo(i: u32) -> bool {
    return val_shown(vpl_val[i]);
}

// Whether any VPL of VAL m can light the pixel (val/cull.rs, `may_light`, its CPU twin and the bound's
// derivation): its VPLs' bounding sphere wholly behind the pixel's tangent plane, or every VPL facing away from
// the pixel (at a cosine at most CULL_COSINE), bounded by the sphere and the VPLs' normal cone.
fn may_light(s: Surface, m: u32) -> bool {
    let val = vals[m];
    let to_centre = val.centre.xyz - s.position;
    let r = val.depth.z;
    if dot(s.normal, to_centre) + r <= 0.0 {
        return false;
    }
    let cone = val.cone;
    if cone.w > 0.5 {
        let x = dot(val.normal.xyz, -to_centre) + cone.z;
        let distance = length(to_centre);
        let b = select(x * cone.x, x, x >= 0.0) + cone.y * (distance + r);
        if b <= CULL_COSINE * (distance - r) {
            return false;
        }
    }
    return true;
}

fn sum_by_val(s: Surface, range: GatherRange) -> VplSum {
    // Each VAL's unshadowed light at the pixel, then each VAL's visibility once, VAL by VAL: the sum is
    // sum_m V_m sum_{C(i) = m} L_i, the same as sum_i V_C(i) L_i, and a VAL that lights nothing here is not
    // tested. A VAL of less than `soft_share` of the pixel's light gets one depth test (its soft edge is worth
    // less than its taps). With `skip_unlit` the VALs' member lists are walked and a VAL that cannot light the
    // pixel is skipped whole (`may_light`); off, every VPL is evaluated in the frame's order, as the paper.
    var light: array<vec3<f32>, MAX_VALS>;
    let m_count = min(val_params.val_count, MAX_VALS);
    var out = VplSum(vec3<f32>(0.0), 0u, vec3<f32>(0.0), vec3<f32>(0.0));
    var total = 0.0;
    if val_params.skip_unlit != 0u {
        let base = (gather.first_vpl / max(val_params.batch_size, 1u)) * val_params.val_count;
        for (var m = 0u; m < m_count; m++) {
            let start = val_lists[2u * (base + m)];
            let count = val_lists[2u * (base + m) + 1u];
            if count == 0u || !val_shown(m) || !may_light(s, m) {
                continue;
            }
            var l = vec3<f32>(0.0);
            for (var j = start; j < start + count; j++) {
                l += vpl_term(s, vpls[val_lists[val_params.members_offset + j]]);
            }
            out.evaluations += count;
            light[m] = l;
            total += luminance(l);
        }
    } else {
        for (var k = range.start; k < gather.vpl_count; k += range.stride) {
            let i = gather.first_vpl + k;
            if !in_solo(i) {
                continue;
            }
            let term = vpl_term(s, vpls[i]);
            out.evaluations += 1u;
            if lights_pixel(term) {
                let m = min(vpl_val[i], MAX_VALS - 1u);
                light[m] += term;
                total += luminance(term);
            }
        }
    }
    // Hard tests at once, the soft VALs listed and tested after: a software rasterizer runs a branch's code for a
    // group of pixels whenever any of them takes it, so the soft test stays out of the loop over every VAL.
    let cut = val_params.soft_share * total;
    var soft_list: array<u32, MAX_VALS>;
    var soft_count = 0u;
    for (var m = 0u; m < m_count; m++) {
        let l = light[m];
        if lights_pixel(l) {
            let lk = val_lookup(s, m);
            if !lk.valid {
                out.sum += l;
            } else if val_params.mode != 0u && luminance(l) >= cut {
                soft_list[soft_count] = m;
                soft_count += 1u;
            } else {
                val_lookups += 1u;
                out.sum += l * val_hard(m, lk);
            }
        }
    }
    // The lookup again rather than kept: a list of lookups would hold far more per pixel than the VAL indices.
    for (var k = 0u; k < soft_count; k++) {
        let m = soft_list[k];
        val_lookups += 1u;
        out.sum += light[m] * val_soft(s, m, val_lookup(s, m));
    }
    return out;
}

fn sum_testing_at_first_vpl(s: Surface, range: GatherRange) -> VplSum {
    var tested: array<u32, MAX_VALS / 32u>;
    var visibility: array<f32, MAX_VALS>;
    var out = VplSum(vec3<f32>(0.0), 0u, vec3<f32>(0.0), vec3<f32>(0.0));
    for (var k = range.start; k < gather.vpl_count; k += range.stride) {
        let i = gather.first_vpl + k;
        if !in_solo(i) {
            continue;
        }
        let term = vpl_term(s, vpls[i]);
        out.evaluations += 1u;
        if lights_pixel(term) {
            let m = min(vpl_val[i], MAX_VALS - 1u);
            let bit = 1u << (m % 32u);
            if (tested[m / 32u] & bit) == 0u {
                tested[m / 32u] |= bit;
                visibility[m] = val_visibility(s, m, true);
            }
            out.sum += term * visibility[m];
            out.open += term;
        }
    }
    let every = every_vpl_unshadowed(s);
    out.all = every.light;
    out.evaluations += every.evaluations;
    return out;
}

@compute @workgroup_size(8, 8)
fn val_gather_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let width = u32(frame.viewport.x);
    let height = u32(frame.viewport.y);
    if id.x >= width || id.y >= height {
        return;
    }
    let s = load_surface(vec2<i32>(id.xy));
    if !s.is_geometry {
        return;
    }
    let range = gather_range(id.xy);
    var lit: VplSum;
    if range.stride > 1u {
        lit = sum_testing_at_first_vpl(s, range);
    } else {
        lit = sum_by_val(s, range);
    }
    let evaluations = lit.evaluations;
    count_work(vec2<i32>(id.xy), WORK_VPL_EVALUATIONS, evaluations);
    count_work(vec2<i32>(id.xy), WORK_INDIRECT_SHADOW_LOOKUPS, val_lookups);
    count_work(vec2<i32>(id.xy), WORK_INDIRECT_FILTER_TAPS, val_taps);
    let index = id.y * width + id.x;
    gather_out(index, s.albedo, range, lit.sum, lit.open, lit.all);
}
