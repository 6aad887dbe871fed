// ReSTIR's reservoirs (Bitterli et al. 2020), shared by its passes: the reservoir record, the streaming update
// of weighted reservoir sampling (Algorithm 2), the target function p̂ and the frame's random numbers.
// Composed after common.wgsl (and raytrace_bvh.wgsl in the compute passes), before a pass's own file.
// `RestirFrame` mirrors `FrameUniform` and `Reservoir` mirrors `GpuReservoir` in core/src/technique/restir/mod.rs;
// `SourceEntry` mirrors `SourceEntry` in restir/alias.rs.

const RESTIR_NONE: u32 = 0xffffffffu;

// A reservoir (y, w_sum, M, W) and the surface of the pixel that wrote it, so the next frame's temporal reuse
// can reject it by depth and normal and the unbiased combination can ask whether that surface could have drawn
// a sample.
struct Reservoir {
    // y: an index into the frame's lights, RESTIR_NONE when the reservoir holds none
    light: u32,
    w_sum: f32,
    // M: the candidates seen (a float: capped histories are fractions of the stream)
    m: f32,
    // W = w_sum / (M p̂(y)) (biased), w_sum / (Z p̂(y)) (unbiased: 0 when y is occluded from the pixel)
    w: f32,
    position: vec3<f32>,
    // octahedral normal (2 x 15 bits) | bit 30: geometry | bit 31: the BRDF is not black
    surface: u32,
}

// One slot of the source pdf's table: keep the slot when a uniform number is below `threshold`, else take
// `alias_slot`; `pdf` is p(x) of the slot's light.
struct SourceEntry {
    threshold: f32,
    alias_slot: u32,
    pdf: f32,
    light: u32,
}

struct RestirFrame {
    // the camera of the frame whose reservoirs are reused (the last ReSTIR frame)
    prev_clip_from_world: mat4x4<f32>,
    prev_camera: vec4<f32>,
    // slots of the source table (the visible lights)
    source_count: u32,
    // the frame's lights (the array's length)
    light_count: u32,
    candidates: u32,
    frame_index: u32,
    seed: u32,
    // 1: combine with the previous frame's reservoirs
    temporal: u32,
    // the history's M is capped at this
    history_cap: f32,
    spatial: u32,
    radius: f32,
    // 1: Algorithm 6's 1/Z, 0: Algorithm 4's 1/M
    unbiased: u32,
    // ray origin offset, world units per metre of camera distance
    bias: f32,
    // 1 / frames: each frame's share of the averaged image
    weight: f32,
    depth_threshold: f32,
    // cos of the normal threshold
    normal_cos: f32,
    // 1: the first ReSTIR frame of the rendered frame (the mean starts over)
    first_frame: u32,
    // 1: candidates drawn uniformly from the pixel's tile list instead of the source table
    tiled: u32,
    // frames / (this frame's index + 1): the sum so far shown as the mean so far
    shown_scale: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(1) @binding(2) var<storage, read> lights: array<Light>;
@group(1) @binding(4) var<uniform> restir: RestirFrame;
// The reservoirs a pass reads (its output lies in `reservoirs_out`, in the compute passes' own bindings).
@group(1) @binding(5) var<storage, read> reservoirs_in: array<Reservoir>;

// ---- random numbers: a PCG hash (Jarzynski & Olano 2020) of the pixel, the pass, the frame and the seed ----

var<private> restir_rng: u32;

fn restir_hash(x: u32) -> u32 {
    let state = x * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn restir_seed(pixel: vec2<u32>, pass_id: u32) {
    let frame_hash = restir_hash(restir.seed ^ restir_hash(restir.frame_index * 4u + pass_id));
    restir_rng = restir_hash(pixel.x ^ restir_hash(pixel.y ^ frame_hash));
}

// Uniform in [0, 1).
fn restir_random() -> f32 {
    restir_rng = restir_hash(restir_rng);
    return f32(restir_rng >> 8u) * (1.0 / 16777216.0);
}

// ---- the target function ----

// p̂_q(x): the luminance of light x's unshadowed contribution at surface s, the shading every direct technique
// uses (common.wgsl's shade_light: BRDF, falloff, cosine, spot cone). 0 for RESTIR_NONE.
fn restir_target(s: Surface, light: u32) -> f32 {
    if light >= restir.light_count {
        return 0.0;
    }
    return luminance(shade_light(s, lights[light]));
}

// W from a reservoir's w_sum, its normalisation (M or Z) and p̂(y); 0 where either is 0.
fn restir_contribution_weight(w_sum: f32, normalisation: f32, p_hat: f32) -> f32 {
    if normalisation <= 0.0 || p_hat <= 0.0 {
        return 0.0;
    }
    return w_sum / (normalisation * p_hat);
}

// ---- weighted reservoir sampling (Algorithm 2) ----

fn restir_empty() -> Reservoir {
    var r: Reservoir;
    r.light = RESTIR_NONE;
    r.w_sum = 0.0;
    r.m = 0.0;
    r.w = 0.0;
    r.position = vec3<f32>(0.0);
    r.surface = 0u;
    return r;
}

// update(x, w) over a stream of `m` candidates: w_sum += w, M += m, y = x with probability w / w_sum.
// True when x was taken.
fn restir_update(r: ptr<function, Reservoir>, light: u32, weight: f32, m: f32) -> bool {
    (*r).w_sum += weight;
    (*r).m += m;
    if weight > 0.0 && restir_random() * (*r).w_sum < weight {
        (*r).light = light;
        return true;
    }
    return false;
}

// ---- the surface stored with a reservoir ----

struct RestirPoint {
    position: vec3<f32>,
    normal: vec3<f32>,
    geometry: bool,
    // the BRDF is not black (albedo or specular): p̂ > 0 is possible
    lit: bool,
}

fn restir_octahedral(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if n.z < 0.0 {
        return (1.0 - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
    }
    return p;
}

fn restir_from_octahedral(e: vec2<f32>) -> vec3<f32> {
    var v = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-v.z, 0.0);
    v.x += select(t, -t, v.x >= 0.0);
    v.y += select(t, -t, v.y >= 0.0);
    return normalize(v);
}

// The reservoir `r` stamped with the surface of its pixel.
fn restir_stamp(r: Reservoir, s: Surface) -> Reservoir {
    var stamped = r;
    stamped.position = s.position;
    if !s.is_geometry {
        stamped.surface = 0u;
        return stamped;
    }
    let q = vec2<u32>(round((restir_octahedral(s.normal) * 0.5 + 0.5) * 32767.0));
    let lit = any(s.albedo > vec3<f32>(0.0)) || (frame.ambient.w > 0.5 && s.specular > 0.0);
    stamped.surface = q.x | (q.y << 15u) | (1u << 30u) | select(0u, 1u << 31u, lit);
    return stamped;
}

fn restir_point(r: Reservoir) -> RestirPoint {
    var p: RestirPoint;
    p.position = r.position;
    let q = vec2<u32>(r.surface & 0x7fffu, (r.surface >> 15u) & 0x7fffu);
    p.normal = restir_from_octahedral(vec2<f32>(q) / 32767.0 * 2.0 - 1.0);
    p.geometry = (r.surface & (1u << 30u)) != 0u;
    p.lit = (r.surface & (1u << 31u)) != 0u;
    return p;
}

// p̂_p(x) > 0 at a stored surface: x in range, in front of the surface, inside its cone, the BRDF not black.
// (shade_light's conditions, with the stored normal; exact unless albedo and light colour share no channel.)
fn restir_supports(p: RestirPoint, light: u32) -> bool {
    if !p.geometry || !p.lit || light >= restir.light_count {
        return false;
    }
    let l = lights[light];
    let to_light = l.position - p.position;
    let d = length(to_light);
    if d >= l.range || d <= 0.0 || !any(l.radiance > vec3<f32>(0.0)) {
        return false;
    }
    let dir = to_light / d;
    return dot(p.normal, dir) > 0.0 && spot_factor(l, -dir) > 0.0;
}

// True when two surfaces are alike enough to share reservoirs (the paper's heuristic): camera distances within
// `depth_threshold` of `depth`'s and normals within the normal threshold.
fn restir_similar(depth: f32, normal: vec3<f32>, other_depth: f32, other_normal: vec3<f32>) -> bool {
    return abs(other_depth - depth) <= restir.depth_threshold * depth && dot(normal, other_normal) >= restir.normal_cos;
}
