//! A light's reflective shadow map (Dachsbacher & Stamminger 2005; Dong et al. 2009 section 6): its texels'
//! geometry, and the whole map as an image for inspection.
//!
//! The `rsm` VPL source ([`super::generate`]) never stores a map: it draws `N` texels of a map of
//! [`RSM_RESOLUTION`](super::RSM_RESOLUTION)² texels a face and casts each one's central ray. What those `N`
//! were drawn from is shown here: [`rsm_image`] casts every texel's central ray of a map at a (smaller)
//! resolution the caller picks and keeps, per texel, what Dachsbacher's RSM stores:
//! 1. the position `x_p` of the surface the texel sees (and its distance from the light),
//! 2. its normal `n_p`,
//! 3. its reflected flux `Phi_p = rho * I * cone(omega) * att(d) d^2 * Omega_texel` (a sun's:
//!    `rho * E * A_texel`), the flux the texel's solid angle (or area) sends to the surface times its albedo.
//!
//! Summed over the texels, `Phi_p` is the light's one-bounce reflected flux, which the VPL set estimates with
//! `N` samples: the two agree (a test). [`RsmImage::texel_of`] finds the texel a first-bounce VPL of the light
//! was drawn from, so the drawn texels can be marked on the image.
//!
//! Layouts: a cube of six faces for a point light (and a spot wider than `SPOT_RSM_MAX_ANGLE`), one face
//! around the axis for a narrower spot, one orthographic square over the scene's bounding sphere for a sun.

use glam::Vec3;

use crate::accel::scene_bvh::SceneBvh;
use crate::scene::{attenuation, DirectionalLight, PointLight};

/// Spots narrower than this get a single-face RSM (Dachsbacher's spot-light RSM); wider ones the cube.
pub const SPOT_RSM_MAX_ANGLE: f32 = 80.0 * std::f32::consts::PI / 180.0;

/// Largest resolution of an inspection image (a face of `MAX_IMAGE_RESOLUTION`² texels; a cube casts six
/// times that many rays on the CPU).
pub const MAX_IMAGE_RESOLUTION: u32 = 512;

/// The direction through the centre of texel `(x, y)` of a single RSM face of `r`² texels looking along `axis`
/// with a half-angle whose tangent is `tan_half`, and the texel's solid angle.
pub(crate) fn spot_texel(r: u32, axis: Vec3, tan_half: f32, x: u32, y: u32) -> (Vec3, f32) {
    let r = r as f32;
    let s = ((x as f32 + 0.5) / r * 2.0 - 1.0) * tan_half;
    let t = ((y as f32 + 0.5) / r * 2.0 - 1.0) * tan_half;
    let (u, v) = axis.any_orthonormal_pair();
    let texel_area = (2.0 * tan_half / r) * (2.0 * tan_half / r);
    ((axis + u * s + v * t).normalize(), texel_area / (1.0 + s * s + t * t).powf(1.5))
}

/// The texel of a single spot face (see [`spot_texel`]) whose solid angle holds direction `dir`.
fn spot_texel_of(r: u32, axis: Vec3, tan_half: f32, dir: Vec3) -> Option<(u32, u32)> {
    let along = dir.dot(axis);
    if along <= 0.0 || tan_half <= 0.0 {
        return None;
    }
    let (u, v) = axis.any_orthonormal_pair();
    let d = dir / along;
    texel_of_square(r, d.dot(u) / tan_half, d.dot(v) / tan_half)
}

/// The texel `(x, y)` of an `r`² square holding the point `(s, t)` of `[-1, 1]^2`.
fn texel_of_square(r: u32, s: f32, t: f32) -> Option<(u32, u32)> {
    let at = |c: f32| {
        let i = ((c + 1.0) * 0.5 * r as f32).floor();
        (i >= 0.0 && i < r as f32).then_some(i as u32)
    };
    (s.is_finite() && t.is_finite()).then(|| Some((at(s)?, at(t)?))).flatten()
}

/// The direction through the centre of texel `(x, y)` of cube face `face` of `r`² texels (the renderer's face
/// order is irrelevant here: all six faces are drawn uniformly), and the texel's solid angle.
pub(crate) fn cube_texel(r: u32, face: u32, x: u32, y: u32) -> (Vec3, f32) {
    let r = r as f32;
    let s = (x as f32 + 0.5) / r * 2.0 - 1.0;
    let t = (y as f32 + 0.5) / r * 2.0 - 1.0;
    let dir = match face {
        0 => Vec3::new(1.0, -t, -s),
        1 => Vec3::new(-1.0, -t, s),
        2 => Vec3::new(s, 1.0, t),
        3 => Vec3::new(s, -1.0, -t),
        4 => Vec3::new(s, -t, 1.0),
        _ => Vec3::new(-s, -t, -1.0),
    };
    let texel_area = (2.0 / r) * (2.0 / r);
    let omega = texel_area / (1.0 + s * s + t * t).powf(1.5);
    (dir.normalize(), omega)
}

/// The face and texel of a cube of `r`² texels a face (see [`cube_texel`]) whose solid angle holds `dir`.
fn cube_texel_of(r: u32, dir: Vec3) -> Option<(u32, u32, u32)> {
    let a = dir.abs();
    let (face, m) = if a.x >= a.y && a.x >= a.z {
        (if dir.x > 0.0 { 0 } else { 1 }, a.x)
    } else if a.y >= a.z {
        (if dir.y > 0.0 { 2 } else { 3 }, a.y)
    } else {
        (if dir.z > 0.0 { 4 } else { 5 }, a.z)
    };
    if m.is_nan() || m <= 0.0 {
        return None;
    }
    let d = dir / m;
    // The inverse of `cube_texel`'s table.
    let (s, t) = match face {
        0 => (-d.z, -d.y),
        1 => (d.z, -d.y),
        2 => (d.x, d.z),
        3 => (d.x, -d.z),
        4 => (d.x, -d.y),
        _ => (-d.x, -d.y),
    };
    let (x, y) = texel_of_square(r, s, t)?;
    Some((face, x, y))
}

/// The square a sun's RSM covers: perpendicular to its direction, over the scene's bounding sphere `(c, R)`,
/// outside it towards the sun.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunSquare {
    /// Centre of the square (on the sun's side of the sphere).
    pub origin: Vec3,
    /// Unit axes of its plane.
    pub u: Vec3,
    pub v: Vec3,
    /// The direction the sun's light travels (unit).
    pub dir: Vec3,
    /// The bounding sphere's radius: the square's half side.
    pub radius: f32,
}

impl SunSquare {
    pub fn new(bvh: &SceneBvh, sun: &DirectionalLight) -> Option<SunSquare> {
        let root = bvh.cpu.nodes.first()?;
        let (min, max) = (Vec3::from_array(root.min), Vec3::from_array(root.max));
        let centre = (min + max) * 0.5;
        let radius = ((max - min).length() * 0.5).max(1e-6);
        let dir = sun.direction.try_normalize()?;
        let (u, v) = dir.any_orthonormal_pair();
        (centre.is_finite() && radius.is_finite()).then_some(SunSquare {
            origin: centre - dir * (radius * 1.01),
            u,
            v,
            dir,
            radius,
        })
    }

    /// The centre of texel `(x, y)` of the square cut into `r`² texels.
    pub fn texel_point(&self, r: u32, x: u32, y: u32) -> Vec3 {
        let c = |i: u32| (i as f32 + 0.5) / r as f32 * 2.0 - 1.0;
        self.origin + (self.u * c(x) + self.v * c(y)) * self.radius
    }

    /// The texel whose column of light reaches `p`.
    fn texel_of(&self, r: u32, p: Vec3) -> Option<(u32, u32)> {
        let d = p - self.origin;
        texel_of_square(r, d.dot(self.u) / self.radius, d.dot(self.v) / self.radius)
    }
}

/// Whose map: a point (or spot) light or a sun.
#[derive(Clone, Copy, Debug)]
pub enum RsmEmitter<'a> {
    Point(&'a PointLight),
    Sun(&'a DirectionalLight),
}

/// How a map's texels are laid out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RsmLayout {
    /// Six faces around a point light, in [`cube_texel`]'s order (+x, −x, +y, −y, +z, −z).
    Cube { eye: Vec3 },
    /// One face around a spot's axis, `tan_half` the tangent of its outer angle.
    Spot { eye: Vec3, axis: Vec3, tan_half: f32 },
    /// One orthographic square facing a sun.
    Sun { square: SunSquare },
}

/// What one texel of a reflective shadow map holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RsmTexel {
    /// `x_p`: the surface the texel's central ray meets.
    pub position: Vec3,
    /// `n_p`: its normal, facing the light.
    pub normal: Vec3,
    /// `Phi_p`: the flux it reflects (linear RGB, already times the albedo).
    pub flux: Vec3,
    /// Distance from the light (a sun: from its square) along the ray.
    pub distance: f32,
}

/// A light's whole reflective shadow map at one resolution: `faces` faces of `resolution`² texels, face-major
/// then row-major; `None` where the texel's ray meets nothing (or leaves a spot's cone).
#[derive(Clone, Debug, PartialEq)]
pub struct RsmImage {
    pub layout: RsmLayout,
    pub resolution: u32,
    pub faces: u32,
    pub texels: Vec<Option<RsmTexel>>,
}

impl RsmImage {
    /// Texel `(x, y)` of face `face`.
    pub fn texel(&self, face: u32, x: u32, y: u32) -> Option<&RsmTexel> {
        let r = self.resolution;
        if face >= self.faces || x >= r || y >= r {
            return None;
        }
        self.texels[((face * r + y) * r + x) as usize].as_ref()
    }

    /// Total reflected flux: the light's one bounce, as the map resolves it.
    pub fn total_flux(&self) -> Vec3 {
        self.texels.iter().flatten().map(|t| t.flux).sum()
    }

    /// The texels the first-bounce VPLs of `set` that came from emitter `emitter` (its index in the set: point
    /// lights, then suns) were drawn from, each with how many: the marks of "where the VPLs came from". VPLs of
    /// later bounces (`from` not the light, or not on the sun's square) and of other lights are left out.
    pub fn drawn_texels(&self, set: &super::VplSet, emitter: u32) -> std::collections::BTreeMap<(u32, u32, u32), u32> {
        let first_bounce = |from: Vec3| match self.layout {
            RsmLayout::Cube { eye } | RsmLayout::Spot { eye, .. } => from == eye,
            RsmLayout::Sun { square } => (from - square.origin).dot(square.dir).abs() <= 1e-3 * square.radius,
        };
        let mut drawn = std::collections::BTreeMap::new();
        for v in set.vpls.iter().filter(|v| v.light == emitter && first_bounce(v.from)) {
            if let Some(texel) = self.texel_of(v.position) {
                *drawn.entry(texel).or_insert(0) += 1;
            }
        }
        drawn
    }

    /// The texel (face, x, y) a first-bounce VPL at `position` was drawn from: the one whose ray (or column,
    /// for a sun) reaches it.
    pub fn texel_of(&self, position: Vec3) -> Option<(u32, u32, u32)> {
        let r = self.resolution;
        match self.layout {
            RsmLayout::Cube { eye } => cube_texel_of(r, (position - eye).try_normalize()?),
            RsmLayout::Spot { eye, axis, tan_half } => {
                spot_texel_of(r, axis, tan_half, (position - eye).try_normalize()?).map(|(x, y)| (0, x, y))
            }
            RsmLayout::Sun { square } => square.texel_of(r, position).map(|(x, y)| (0, x, y)),
        }
    }
}

/// Why no image could be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RsmError {
    #[error("an RSM of {0}² texels a face: choose 1 to {MAX_IMAGE_RESOLUTION}")]
    Resolution(u32),
    #[error("the light is not valid (a non-finite position, colour or intensity, or a zero range)")]
    InvalidLight,
    #[error("the sun has no direction, or the scene is empty")]
    NoSunSquare,
}

/// The reflective shadow map of `emitter` at `resolution`² texels a face: every texel's central ray cast through
/// `bvh` (what the `rsm` VPL source does for the `N` texels it draws).
pub fn rsm_image(bvh: &SceneBvh, emitter: RsmEmitter, resolution: u32) -> Result<RsmImage, RsmError> {
    if resolution == 0 || resolution > MAX_IMAGE_RESOLUTION {
        return Err(RsmError::Resolution(resolution));
    }
    let r = resolution;
    match emitter {
        RsmEmitter::Point(light) => {
            if !light.is_valid() {
                return Err(RsmError::InvalidLight);
            }
            let intensity = light.color * light.intensity;
            let eye = light.position;
            let texel = |dir: Vec3, omega: f32| {
                let hit = bvh.closest_hit(eye, dir, light.range)?;
                let cone = light.cone_factor(dir);
                let d = hit.t;
                let flux = hit.albedo * intensity * (omega * cone * attenuation(d, light.range) * d * d);
                (cone > 0.0).then_some(RsmTexel { position: hit.position, normal: hit.normal, flux, distance: d })
            };
            let (layout, faces) = match light.spot {
                Some(spot) if spot.outer_angle <= SPOT_RSM_MAX_ANGLE => {
                    let (axis, tan_half) = (spot.direction, spot.outer_angle.tan());
                    (RsmLayout::Spot { eye, axis, tan_half }, 1)
                }
                _ => (RsmLayout::Cube { eye }, 6),
            };
            let texels = (0..faces)
                .flat_map(|face| (0..r).flat_map(move |y| (0..r).map(move |x| (face, x, y))))
                .map(|(face, x, y)| {
                    let (dir, omega) = match layout {
                        RsmLayout::Spot { axis, tan_half, .. } => spot_texel(r, axis, tan_half, x, y),
                        _ => cube_texel(r, face, x, y),
                    };
                    texel(dir, omega)
                })
                .collect();
            Ok(RsmImage { layout, resolution: r, faces, texels })
        }
        RsmEmitter::Sun(sun) => {
            let square = SunSquare::new(bvh, sun).ok_or(RsmError::NoSunSquare)?;
            if !sun.is_valid() {
                return Err(RsmError::InvalidLight);
            }
            let side = 2.0 * square.radius / r as f32;
            let irradiance = sun.color * sun.illuminance;
            let texels = (0..r)
                .flat_map(|y| (0..r).map(move |x| (x, y)))
                .map(|(x, y)| {
                    let origin = square.texel_point(r, x, y);
                    let hit = bvh.closest_hit(origin, square.dir, f32::INFINITY)?;
                    let flux = hit.albedo * irradiance * (side * side);
                    Some(RsmTexel { position: hit.position, normal: hit.normal, flux, distance: hit.t })
                })
                .collect();
            Ok(RsmImage { layout: RsmLayout::Sun { square }, resolution: r, faces: 1, texels })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_cube_texels_direction_finds_its_texel_again() {
        for r in [1, 2, 7, 16] {
            for face in 0..6 {
                for y in 0..r {
                    for x in 0..r {
                        let (dir, omega) = cube_texel(r, face, x, y);
                        assert!(omega > 0.0);
                        assert_eq!(cube_texel_of(r, dir), Some((face, x, y)), "r {r}");
                    }
                }
            }
        }
        // The solid angles of a cube's texels sum to the sphere's (each taken at its centre: to 1e-3).
        let sum: f32 =
            (0..6).flat_map(|f| (0..32).flat_map(move |y| (0..32).map(move |x| cube_texel(32, f, x, y).1))).sum();
        assert!((sum / (4.0 * std::f32::consts::PI) - 1.0).abs() < 1e-3, "{sum}");
        assert_eq!(cube_texel_of(4, Vec3::ZERO), None);
        assert_eq!(cube_texel_of(4, Vec3::NAN), None);
    }

    #[test]
    fn every_spot_texels_direction_finds_its_texel_again_and_directions_outside_find_none() {
        let axis = Vec3::new(0.3, -1.0, 0.2).normalize();
        let tan_half = 0.7f32;
        for y in 0..9 {
            for x in 0..9 {
                let (dir, _) = spot_texel(9, axis, tan_half, x, y);
                assert_eq!(spot_texel_of(9, axis, tan_half, dir), Some((x, y)));
            }
        }
        assert_eq!(spot_texel_of(9, axis, tan_half, -axis), None, "behind the spot");
        let (u, _) = axis.any_orthonormal_pair();
        assert_eq!(spot_texel_of(9, axis, tan_half, (axis + u * 0.8).normalize()), None, "past the face");
    }
}
