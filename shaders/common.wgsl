// Shared by every full-screen shading pass: the frame uniform, the G-buffer, position reconstruction,
// the light falloff and the BRDF. Composed in front of a pass's own WGSL (see core/src/shaders.rs).
// Keep `Frame` in sync with `FrameUniform` in core/src/services/gpu_data.rs.

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_clip: mat4x4<f32>,
    camera_position: vec4<f32>,
    // width, height, 1/width, 1/height
    viewport: vec4<f32>,
    // rgb: ambient radiance factor, w: 1 when Blinn-Phong specular is on
    ambient: vec4<f32>,
    // rgb: background radiance
    background: vec4<f32>,
    // x: exposure, y: tone-map operator (0 ACES, 1 Reinhard, 2 linear), z: 1 when auto-exposure scales x
    tonemap: vec4<f32>,
    // x: component shown (0 total, 1 direct, 2 indirect), y: indirect display gain, z: 1 when an indirect
    // technique runs (the indirect buffer is real)
    indirect: vec4<f32>,
}

// A point light as the shaders see it. Keep in sync with `GpuLight` in core/src/services/gpu_data.rs.
struct Light {
    position: vec3<f32>,
    // the papers' L_att: the light contributes nothing beyond it
    range: f32,
    // colour * intensity, linear
    radiance: vec3<f32>,
    // near plane of the light's cube shadow map
    shadow_near: f32,
    // spot lights: the cone's direction (zero for omnidirectional lights)
    spot_direction: vec3<f32>,
    // cone factor = saturate(cos * spot_scale + spot_offset)^2; 0 and 1 for omnidirectional lights
    spot_scale: f32,
    spot_offset: f32,
}

// The spot cone's factor towards the unit direction `dir` from the light (1 for omnidirectional lights).
// Keep in sync with `Spot::factor` in core/src/scene/mod.rs.
fn spot_factor(light: Light, dir: vec3<f32>) -> f32 {
    let t = clamp(dot(dir, light.spot_direction) * light.spot_scale + light.spot_offset, 0.0, 1.0);
    return t * t;
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var gbuffer_albedo: texture_2d<f32>;
@group(0) @binding(2) var gbuffer_normal: texture_2d<f32>;
@group(0) @binding(3) var gbuffer_emissive: texture_2d<f32>;
@group(0) @binding(4) var gbuffer_depth: texture_2d<f32>;

// Hardware-independent work counters, read by core/src/services/work_counters.rs: keep the slots in sync with
// `slot` there (a test checks). A counter is 64 bits (low, high word) in one of WORK_BUCKETS buckets chosen by
// the pixel's 16x16 tile, so the atomics of a pass spread over many addresses.
const WORK_SHADED_PIXELS: u32 = 0u;
const WORK_LIGHT_EVALUATIONS: u32 = 1u;
const WORK_SHADOW_LOOKUPS: u32 = 2u;
const WORK_FILTER_TAPS: u32 = 3u;
const WORK_SHADOW_RAYS: u32 = 4u;
const WORK_CLOSEST_HIT_RAYS: u32 = 5u;
const WORK_VPL_EVALUATIONS: u32 = 6u;
const WORK_INDIRECT_SHADOW_LOOKUPS: u32 = 7u;
const WORK_INDIRECT_FILTER_TAPS: u32 = 8u;
const WORK_INDIRECT_SHADOW_RAYS: u32 = 9u;
const WORK_INDIRECT_CLOSEST_HIT_RAYS: u32 = 10u;
const WORK_INDIRECT_LIGHT_EVALUATIONS: u32 = 11u;
const WORK_SLOTS: u32 = 12u;
const WORK_BUCKETS: u32 = 1024u;
@group(0) @binding(5) var<storage, read_write> work_counters: array<atomic<u32>>;

// Add `n` to counter `slot` of the bucket of `pixel`'s tile.
fn count_work(pixel: vec2<i32>, slot: u32, n: u32) {
    if n == 0u {
        return;
    }
    let tile = vec2<u32>(max(pixel, vec2<i32>(0))) / 16u;
    let bucket = (tile.y * 61u + tile.x) % WORK_BUCKETS;
    let at = (bucket * WORK_SLOTS + slot) * 2u;
    let old = atomicAdd(&work_counters[at], n);
    if old > 0xffffffffu - n {
        atomicAdd(&work_counters[at + 1u], 1u);
    }
}

const PI: f32 = 3.14159265358979;

struct FullscreenOut {
    @builtin(position) position: vec4<f32>,
}

// One triangle covering the screen.
@vertex
fn fullscreen_vs(@builtin(vertex_index) i: u32) -> FullscreenOut {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    var out: FullscreenOut;
    out.position = vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
    return out;
}

struct Surface {
    position: vec3<f32>,
    normal: vec3<f32>,
    albedo: vec3<f32>,
    emissive: vec3<f32>,
    specular: f32,
    shininess: f32,
    // false for background pixels (nothing was drawn there)
    is_geometry: bool,
}

fn load_surface(pixel: vec2<i32>) -> Surface {
    var s: Surface;
    let depth = textureLoad(gbuffer_depth, pixel, 0).r;
    s.is_geometry = depth < 1.0;
    let uv = (vec2<f32>(pixel) + 0.5) * frame.viewport.zw;
    let ndc = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, depth, 1.0);
    let world = frame.world_from_clip * ndc;
    s.position = world.xyz / world.w;
    let n = textureLoad(gbuffer_normal, pixel, 0);
    s.normal = normalize(n.xyz);
    s.shininess = n.w;
    s.albedo = textureLoad(gbuffer_albedo, pixel, 0).rgb;
    let e = textureLoad(gbuffer_emissive, pixel, 0);
    s.emissive = e.rgb;
    s.specular = e.w;
    return s;
}

// Rec. 709 luminance of a linear RGB colour (`math::luminance` on the CPU).
fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// Windowed inverse square, exactly zero at `range`. Keep in sync with `scene::attenuation`.
fn attenuation(distance: f32, range: f32) -> f32 {
    if distance >= range {
        return 0.0;
    }
    let r = distance / range;
    let window = clamp(1.0 - r * r * r * r, 0.0, 1.0);
    return window * window / (1.0 + distance * distance);
}

// Unshadowed radiance reflected towards the camera from one point light: Lambert, plus normalised
// Blinn-Phong when enabled.
fn shade_light(s: Surface, light: Light) -> vec3<f32> {
    let to_light = light.position - s.position;
    let distance = length(to_light);
    if distance >= light.range || distance <= 0.0 {
        return vec3<f32>(0.0);
    }
    let l = to_light / distance;
    let n_dot_l = dot(s.normal, l);
    if n_dot_l <= 0.0 {
        return vec3<f32>(0.0);
    }
    return surface_brdf(s, l) * light.radiance * (attenuation(distance, light.range) * n_dot_l * spot_factor(light, -l));
}

// The surface's BRDF for light arriving from the unit direction `l`: Lambert, plus normalised Blinn-Phong when
// enabled.
fn surface_brdf(s: Surface, l: vec3<f32>) -> vec3<f32> {
    var brdf = s.albedo / PI;
    if frame.ambient.w > 0.5 && s.specular > 0.0 {
        let v = normalize(frame.camera_position.xyz - s.position);
        let h = normalize(l + v);
        brdf += vec3<f32>(s.specular * (s.shininess + 8.0) / (8.0 * PI) * pow(max(dot(s.normal, h), 0.0), s.shininess));
    }
    return brdf;
}
