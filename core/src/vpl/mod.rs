//! Virtual point lights (VPLs): the light the scene's lights reflect once (or `bounces` times), as a set of
//! points that every indirect technique of a frame shares (instant radiosity, Keller 1997). A VPL has a
//! position, a normal and the flux it reflects (RGB); the set is a pure function of the scene's BVH, the lights
//! and [`VplSettings`], so two indirect techniques of one frame see the same VPLs and difference images show
//! visibility error only.
//!
//! Two sources (`vpl_source`):
//! 1. `rsm` (Dachsbacher & Stamminger 2005, Dong et al. 2009 section 6): a reflective shadow map per light, a
//!    cube of `6 R^2` texels (`R` = [`RSM_RESOLUTION`]) holding the position, normal and reflected flux of the
//!    surface each texel sees. `N` texels are drawn by a Halton sequence; a texel's flux is what the light sends
//!    through its solid angle `Omega_texel = (2/R)^2 / (1 + s^2 + t^2)^(3/2)` times the albedo, divided by the
//!    probability of drawing it. Deviation: only the drawn texels are computed, by casting each texel's central
//!    ray through the scene BVH, instead of rasterising all `6 R^2` texels and reading back `N` of them. The
//!    texel's content is the same (the first surface along its centre ray); nothing else of the map is ever read.
//! 2. `traced` (Keller 1997, Colom et al. 2022 section 3.1): particles shot from the lights in Halton
//!    directions (uniform on the sphere), a VPL at each closest hit carrying the particle's flux times the
//!    surface's albedo; with `bounces > 1` the particle continues in a cosine-distributed direction with Russian
//!    roulette (survival probability = mean albedo, so the flux stays unbiased).
//!
//! Spot lights: `rsm` draws texels of one face covering the cone (a cube beyond 80 degrees), `traced` draws
//! directions uniformly within the cone; both weight by the cone's falloff.
//!
//! Directional lights (suns, [`DirectionalLight`]): parallel rays along the sun's direction through a square
//! (`rsm`: Dachsbacher's orthographic RSM, [`RSM_RESOLUTION`]² texels over the square that covers the scene's
//! bounding sphere `(c, R)` seen from the sun) or a disc (`traced`: uniform points of the disc of radius `R`
//! perpendicular to the direction), started outside the sphere. A sample of area `A / N_sun` (`A` the square's
//! `4R^2` or the disc's `pi R^2`) carries the flux `E * A / N_sun` through it, whatever the orientation of the
//! surface it meets (the surface's projected area is the sample's); rays that miss the scene count as misses.
//! A sun's power, for sharing the samples, is `E * A` times its mean colour: the flux it sends through the
//! scene's bounding sphere.
//!
//! Both share the `N` samples among the lights in proportion to their power (the first Halton dimension picks
//! a light through the cumulative power table), and both are quasi-random: a small move of a light moves its
//! VPLs a little (Dong section 5.2 relies on it for temporal coherence).
//!
//! The flux a light sends through a solid angle `dw` towards a surface at distance `d` is
//! `I * attenuation(d) * d^2 * dw` (the renderer's falloff `attenuation` replaces `1/d^2`, so direct and
//! indirect light stay consistent). The indirect radiance VPL `i` sends to a receiver `x` (every gather uses
//! it, `vpl_common.wgsl`): `rho(x)/pi * Phi_i/pi * cos(theta_i) cos(theta_x) / max(d^2, d_clamp^2)`.

pub mod halton;
pub mod rsm;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::accel::scene_bvh::SceneBvh;
use crate::gpu::buffer::GrowableBuffer;
use crate::scene::{attenuation, DirectionalLight, PointLight};

/// The side of each face of a light's reflective shadow map.
pub const RSM_RESOLUTION: u32 = 256;
/// Largest `--vpls` accepted: the gathers are O(pixels x VPLs), and a frame of more than this on a software
/// rasterizer takes minutes.
pub const MAX_VPLS: u32 = 65_536;
/// Largest `--bounces`.
pub const MAX_BOUNCES: u32 = 8;
/// Most VPLs the overlay stages of an indirect technique use while a light or the camera moves (the preview):
/// the default `N`, so at the defaults the preview's overlays are a frame's; past it, the first `PREVIEW_VPLS`
/// samples of the same sequence, so the overlays stay within a UI frame's time.
pub const PREVIEW_VPLS: u32 = 1024;

/// Where VPLs come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum VplSource {
    /// Reflective shadow maps (one bounce).
    #[default]
    Rsm,
    /// Particles traced from the lights through the BVH.
    Traced,
}

impl VplSource {
    pub const NAMES: &'static [&'static str] = &["rsm", "traced"];
    pub fn parse(text: &str) -> Option<VplSource> {
        match text.trim() {
            "rsm" => Some(VplSource::Rsm),
            "traced" => Some(VplSource::Traced),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            VplSource::Rsm => "rsm",
            VplSource::Traced => "traced",
        }
    }
}

/// The VPL settings every indirect technique of a frame shares (render settings, not technique parameters).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct VplSettings {
    /// `N`: samples drawn (RSM texels or particles). 0 = no indirect light.
    pub count: u32,
    pub source: VplSource,
    /// Bounces of a traced particle (the RSM source is always one bounce).
    pub bounces: u32,
    /// `d_clamp` in world units: `1/d^2` is clamped to `1/d_clamp^2`. Removes the singularity near a VPL
    /// (bright splotches) at the price of bias: light between surfaces closer than `d_clamp` (corners, contact)
    /// is underestimated.
    pub clamp_world: f32,
    /// Offset of the quasi-random sequence: another seed gives another, equally good, VPL set.
    pub seed: u32,
}

impl Default for VplSettings {
    fn default() -> Self {
        VplSettings { count: 1024, source: VplSource::Rsm, bounces: 1, clamp_world: 0.1, seed: 0 }
    }
}

impl VplSettings {
    pub fn validate(&self) -> Result<(), String> {
        if self.count > MAX_VPLS {
            return Err(format!("{} VPLs requested; the limit is {MAX_VPLS}", self.count));
        }
        if self.bounces == 0 || self.bounces > MAX_BOUNCES {
            return Err(format!("bounces {} must be between 1 and {MAX_BOUNCES}", self.bounces));
        }
        if !(self.clamp_world.is_finite() && self.clamp_world >= 0.0) {
            return Err(format!("VPL clamp distance {} must be finite and >= 0", self.clamp_world));
        }
        Ok(())
    }
}

/// One virtual point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vpl {
    pub position: Vec3,
    /// Unit normal of the surface it sits on, facing where the light came from.
    pub normal: Vec3,
    /// Reflected flux, linear RGB (already times the surface's albedo).
    pub flux: Vec3,
    /// The light it came from: an index into the point lights, or `point lights + k` for sun `k` (see
    /// [`VplSet::light_name`]).
    pub light: u32,
    /// Where the light reaching it left from (the light, or the previous bounce): for the overlays.
    pub from: Vec3,
}

/// Mirrors `Vpl` in `vpl_common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuVpl {
    pub position: [f32; 4],
    pub normal: [f32; 4],
    pub flux: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<GpuVpl>() == 48);

impl GpuVpl {
    pub fn new(v: &Vpl) -> GpuVpl {
        GpuVpl {
            position: v.position.extend(1.0).to_array(),
            normal: v.normal.extend(0.0).to_array(),
            flux: v.flux.extend(0.0).to_array(),
        }
    }
}

/// The VPLs of a frame and what made them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VplSet {
    pub settings: Option<VplSettings>,
    pub vpls: Vec<Vpl>,
    /// Samples drawn (texels or particles); misses make no VPL.
    pub samples: u32,
    /// Samples that hit nothing (open scenes).
    pub misses: u32,
    /// The point lights the set was made from: VPLs with `light` at or past it came from the suns.
    pub point_lights: u32,
}

impl VplSet {
    /// "light i" or "sun k": where VPL light index `light` came from.
    pub fn light_name(&self, light: u32) -> String {
        emitter_name(light as usize, self.point_lights as usize)
    }

    pub fn total_flux(&self) -> Vec3 {
        self.vpls.iter().map(|v| v.flux).sum()
    }
}

/// "light i" or "sun k" for emitter `index` of `point_lights` point lights followed by the suns, the numbering
/// of [`Vpl::light`] (and of `render --rsm-light`).
pub fn emitter_name(index: usize, point_lights: usize) -> String {
    match index.checked_sub(point_lights) {
        Some(k) => format!("sun {k}"),
        None => format!("light {index}"),
    }
}

/// The solid angle a light emits into: the sphere, or a spot's cone.
fn emission_solid_angle(l: &PointLight) -> f32 {
    match l.spot {
        Some(s) => 2.0 * std::f32::consts::PI * (1.0 - s.outer_angle.cos()),
        None => 4.0 * std::f32::consts::PI,
    }
}

/// A light's power as used to share samples: its intensity over its solid angle, times its mean colour.
fn light_power(l: &PointLight) -> f32 {
    if !l.is_valid() {
        return 0.0;
    }
    emission_solid_angle(l) * l.intensity * (l.color.x + l.color.y + l.color.z) / 3.0
}

/// A unit direction uniform in the cone of half-angle `angle` around `axis`.
fn cone_direction(axis: Vec3, angle: f32, u: f32, v: f32) -> Vec3 {
    let cos = 1.0 - u * (1.0 - angle.cos());
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * v;
    let (t, b) = axis.any_orthonormal_pair();
    (axis * cos + t * (sin * phi.cos()) + b * (sin * phi.sin())).normalize_or(axis)
}

/// A unit direction uniform on the sphere from two numbers in [0, 1).
fn sphere_direction(u: f32, v: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A cosine-distributed direction around `n`.
fn cosine_direction(n: Vec3, u: f32, v: f32) -> Vec3 {
    let r = u.sqrt();
    let phi = 2.0 * std::f32::consts::PI * v;
    let (t, b) = n.any_orthonormal_pair();
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u).max(0.0).sqrt()).normalize_or(n)
}

/// Offset of a ray origin from a surface, relative to the scene's size.
fn ray_epsilon(bvh: &SceneBvh) -> f32 {
    let b = bvh.cpu.nodes.first().map(|n| Vec3::from_array(n.max) - Vec3::from_array(n.min)).unwrap_or(Vec3::ONE);
    (b.length() * 1e-5).max(1e-6)
}

/// The square (`rsm`) or disc (`traced`) a sun's samples start from: perpendicular to its direction, covering
/// the scene's bounding sphere, outside it towards the sun ([`rsm::SunSquare`], the disc inscribed in it).
struct SunAperture {
    square: rsm::SunSquare,
    /// Its area: `4 R^2` (square) or `pi R^2` (disc).
    area: f32,
}

impl SunAperture {
    fn new(bvh: &SceneBvh, sun: &DirectionalLight, source: VplSource) -> Option<SunAperture> {
        let square = rsm::SunSquare::new(bvh, sun)?;
        let radius = square.radius;
        let area = match source {
            VplSource::Rsm => 4.0 * radius * radius,
            VplSource::Traced => std::f32::consts::PI * radius * radius,
        };
        Some(SunAperture { square, area })
    }

    /// The start of sample `(a, b)` in [0, 1)^2: an RSM texel's centre, or a uniform point of the disc.
    fn point(&self, source: VplSource, a: f32, b: f32) -> Vec3 {
        match source {
            VplSource::Rsm => {
                let r = RSM_RESOLUTION;
                let texel = |x: f32| ((x * r as f32) as u32).min(r - 1);
                self.square.texel_point(r, texel(a), texel(b))
            }
            VplSource::Traced => {
                let (r, phi) = (a.sqrt(), 2.0 * std::f32::consts::PI * b);
                let sq = &self.square;
                sq.origin + (sq.u * (r * phi.cos()) + sq.v * (r * phi.sin())) * sq.radius
            }
        }
    }
}

/// What the samples are shared among: the point lights, then the suns.
enum Emitter<'a> {
    Point(&'a PointLight),
    /// No aperture for an empty scene or a zero direction: the sun keeps its index, with no power.
    Sun(&'a DirectionalLight, Option<SunAperture>),
}

impl Emitter<'_> {
    fn power(&self) -> f32 {
        match self {
            Emitter::Point(l) => light_power(l),
            Emitter::Sun(sun, Some(aperture)) if sun.is_valid() => {
                let p = sun.illuminance * aperture.area * (sun.color.x + sun.color.y + sun.color.z) / 3.0;
                if p.is_finite() {
                    p
                } else {
                    0.0
                }
            }
            Emitter::Sun(..) => 0.0,
        }
    }
}

/// Generate the VPLs of `lights` and `suns` in the scene of `bvh`. Deterministic: the same inputs give the same
/// set.
pub fn generate(bvh: &SceneBvh, lights: &[PointLight], suns: &[DirectionalLight], settings: &VplSettings) -> VplSet {
    let mut set = VplSet { settings: Some(*settings), point_lights: lights.len() as u32, ..Default::default() };
    let mut emitters: Vec<Emitter> = lights.iter().map(Emitter::Point).collect();
    emitters.extend(suns.iter().map(|sun| Emitter::Sun(sun, SunAperture::new(bvh, sun, settings.source))));
    let powers: Vec<f32> = emitters.iter().map(Emitter::power).collect();
    let total: f32 = powers.iter().sum();
    if settings.count == 0 || !(total > 0.0 && total.is_finite()) || bvh.cpu.triangles.is_empty() {
        return set;
    }
    let mut cdf = Vec::with_capacity(powers.len());
    let mut acc = 0.0f32;
    for p in &powers {
        acc += p / total;
        cdf.push(acc);
    }
    let eps = ray_epsilon(bvh);
    let n = settings.count;
    let base = settings.seed as u64 * n as u64;
    for i in 0..n {
        let index = base + i as u64 + 1;
        let u = [
            halton::radical_inverse(0, index),
            halton::radical_inverse(1, index),
            halton::radical_inverse(2, index),
            halton::radical_inverse(3, index),
        ];
        // Dimension 0 picks a light by power; its rank within the light's share spreads the light's own samples
        // (rescaled to [0, 1)) so they stay stratified.
        let li = cdf.partition_point(|&c| c <= u[0]).min(emitters.len() - 1);
        let p_light = powers[li] / total;
        if p_light <= 0.0 {
            continue;
        }
        // The first hit, where the light reaching it left from, and the flux reaching it.
        let (hit, from, flux) = match &emitters[li] {
            Emitter::Point(light) => {
                let Some((hit, flux)) = point_sample(bvh, light, settings.source, &u, n as f32 * p_light, &mut set)
                else {
                    continue;
                };
                (hit, light.position, flux)
            }
            // A sun without an aperture has no power, so p_light above is 0 for it.
            Emitter::Sun(_, None) => continue,
            Emitter::Sun(sun, Some(aperture)) => {
                set.samples += 1;
                let origin = aperture.point(settings.source, u[2], u[3]);
                let Some(hit) = bvh.closest_hit(origin, aperture.square.dir, f32::INFINITY) else {
                    set.misses += 1;
                    continue;
                };
                (hit, origin, sun.color * (sun.illuminance * aperture.area / (n as f32 * p_light)))
            }
        };
        let mut flux = flux;
        let mut from = from;
        let mut hit = hit;
        for bounce in 0..settings.bounces {
            let reflected = flux * hit.albedo;
            if reflected.max_element() <= 0.0 || !reflected.is_finite() {
                break;
            }
            set.vpls.push(Vpl { position: hit.position, normal: hit.normal, flux: reflected, light: li as u32, from });
            if bounce + 1 == settings.bounces {
                break;
            }
            // Russian roulette on the mean albedo, then a cosine-distributed bounce (throughput = albedo / q).
            let q = ((hit.albedo.x + hit.albedo.y + hit.albedo.z) / 3.0).clamp(0.0, 1.0);
            let dim = 4 + 3 * bounce;
            if q <= 0.0 || halton::radical_inverse(dim, index) >= q {
                break;
            }
            let next = cosine_direction(
                hit.normal,
                halton::radical_inverse(dim + 1, index),
                halton::radical_inverse(dim + 2, index),
            );
            let origin = hit.position + hit.normal * eps;
            let Some(h) = bvh.closest_hit(origin, next, f32::INFINITY) else { break };
            flux = reflected / q;
            from = hit.position;
            hit = h;
        }
    }
    set
}

/// One sample of a point light: the first surface along a direction drawn from `u` and the flux reaching it
/// (None for a miss, counted in `set`, or a direction outside a spot's cone). `share` is `N * p_light`.
fn point_sample(
    bvh: &SceneBvh,
    light: &PointLight,
    source: VplSource,
    u: &[f32; 4],
    share: f32,
    set: &mut VplSet,
) -> Option<(crate::accel::scene_bvh::SurfaceHit, Vec3)> {
    let intensity = light.color * light.intensity;
    // dir, and the radiant intensity divided by the pdf of picking that direction (per steradian).
    let (dir, weight) = match (source, light.spot) {
        (VplSource::Traced, None) => (sphere_direction(u[1], u[2]), 4.0 * std::f32::consts::PI),
        (VplSource::Traced, Some(spot)) => {
            (cone_direction(spot.direction, spot.outer_angle, u[1], u[2]), emission_solid_angle(light))
        }
        (VplSource::Rsm, Some(spot)) if spot.outer_angle <= rsm::SPOT_RSM_MAX_ANGLE => {
            let r = RSM_RESOLUTION;
            let x = ((u[2] * r as f32) as u32).min(r - 1);
            let y = ((u[3] * r as f32) as u32).min(r - 1);
            let (dir, omega) = rsm::spot_texel(r, spot.direction, spot.outer_angle.tan(), x, y);
            (dir, omega * (r * r) as f32)
        }
        (VplSource::Rsm, _) => {
            let r = RSM_RESOLUTION;
            let face = ((u[1] * 6.0) as u32).min(5);
            let x = ((u[2] * r as f32) as u32).min(r - 1);
            let y = ((u[3] * r as f32) as u32).min(r - 1);
            let (dir, omega) = rsm::cube_texel(r, face, x, y);
            (dir, omega * (6 * r * r) as f32)
        }
    };
    set.samples += 1;
    let Some(hit) = bvh.closest_hit(light.position, dir, light.range) else {
        set.misses += 1;
        return None;
    };
    let d = hit.t;
    // Flux reaching the surface through this sample's share of the sphere.
    let cone = light.cone_factor(dir);
    if cone <= 0.0 {
        return None;
    }
    Some((hit, intensity * (weight * cone * attenuation(d, light.range) * d * d / share)))
}

/// The VPLs of the current frame, on the CPU and the GPU (`array<Vpl>`, `vpl_common.wgsl`).
pub struct VplFrame {
    pub set: std::sync::Arc<VplSet>,
    pub buffer: GrowableBuffer,
    /// What the set was generated from (lights, settings, scene geometry), so an unchanged frame reuses it.
    pub(crate) key: Option<(Vec<PointLight>, Vec<DirectionalLight>, VplSettings, usize)>,
}
