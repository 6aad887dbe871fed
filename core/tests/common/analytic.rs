//! The analytic answer for `plane_and_occluder` (ground plane, square plate, point lights): what a camera ray
//! through a pixel centre hits, whether a ground point sees a light past the plate, and the expected HDR
//! radiance. Shared by the reference's and the ray tracer's image tests.

use glam::{Vec3, Vec4, Vec4Swizzles};
use shadowlab_core::scene::{attenuation, Camera, PointLight};

use super::{ALBEDO, GROUND_SIZE, PLATE_CENTER, PLATE_SIZE};

pub const W: u32 = 160;
pub const H: u32 = 120;
/// Ambient radiance factor of the analytic tests' render settings.
pub const AMBIENT: f32 = 0.1;

/// What a camera ray through a pixel centre hits.
#[derive(Clone, Copy, PartialEq, Debug)]
pub enum Hit {
    Background,
    Ground(Vec3),
    Plate(Vec3),
}

pub fn camera_ray(camera: &Camera, px: u32, py: u32) -> (Vec3, Vec3) {
    let world_from_clip = camera.clip_from_world(W as f32 / H as f32).inverse();
    let ndc_x = (px as f32 + 0.5) / W as f32 * 2.0 - 1.0;
    let ndc_y = 1.0 - (py as f32 + 0.5) / H as f32 * 2.0;
    let a = world_from_clip * Vec4::new(ndc_x, ndc_y, 0.0, 1.0);
    let b = world_from_clip * Vec4::new(ndc_x, ndc_y, 1.0, 1.0);
    let origin = a.xyz() / a.w;
    (origin, (b.xyz() / b.w - origin).normalize())
}

pub fn cast(camera: &Camera, px: u32, py: u32) -> Hit {
    let (origin, dir) = camera_ray(camera, px, py);
    let hit_plane = |y: f32, half: f32| -> Option<(f32, Vec3)> {
        let t = (y - origin.y) / dir.y;
        let p = origin + dir * t;
        (t > 0.0 && p.x.abs() <= half && p.z.abs() <= half).then_some((t, p))
    };
    let plate = hit_plane(PLATE_CENTER.y, PLATE_SIZE * 0.5);
    let ground = hit_plane(0.0, GROUND_SIZE * 0.5);
    match (plate, ground) {
        (Some((tp, p)), Some((tg, _))) if tp < tg => Hit::Plate(p),
        (Some((_, p)), None) => Hit::Plate(p),
        (_, Some((_, g))) => Hit::Ground(g),
        (None, None) => Hit::Background,
    }
}

/// Visibility of `light` from ground point `p`: Some(true) lit, Some(false) umbra, None within `margin` of the
/// shadow boundary (shadow-map texels or position reconstruction blur it by a little).
pub fn ground_visibility(p: Vec3, light: &PointLight, margin: f32) -> Option<bool> {
    if light.position.y <= PLATE_CENTER.y {
        return Some(true);
    }
    let t = (PLATE_CENTER.y - p.y) / (light.position.y - p.y);
    let q = p + (light.position - p) * t;
    let inf = (q.x - PLATE_CENTER.x).abs().max((q.z - PLATE_CENTER.z).abs());
    if inf < PLATE_SIZE * 0.5 - margin {
        Some(false)
    } else if inf > PLATE_SIZE * 0.5 + margin {
        Some(true)
    } else {
        None
    }
}

/// Expected HDR radiance of a pixel, or None where the answer is ambiguous (silhouettes, shadow edges within
/// `margin`). `shadow_origin` maps a ground point to where its shadow test starts (the ray tracer offsets it).
pub fn expected(
    camera: &Camera,
    lights: &[PointLight],
    px: u32,
    py: u32,
    margin: f32,
    shadow_origin: &dyn Fn(Vec3) -> Vec3,
) -> Option<[f32; 4]> {
    let hit = cast(camera, px, py);
    // Pixels next to a silhouette may be covered by either surface.
    for (dx, dy) in [(-1i32, 0i32), (1, 0), (0, -1), (0, 1)] {
        let (nx, ny) = (px as i32 + dx, py as i32 + dy);
        if nx >= 0 && ny >= 0 && nx < W as i32 && ny < H as i32 {
            let other = cast(camera, nx as u32, ny as u32);
            if std::mem::discriminant(&other) != std::mem::discriminant(&hit) {
                return None;
            }
        }
    }
    let p = match hit {
        Hit::Background => return Some([0.0, 0.0, 1.0, 1.0]),
        Hit::Ground(p) | Hit::Plate(p) => p,
    };
    let mut radiance = Vec3::splat(AMBIENT * ALBEDO);
    for light in lights {
        let to_light = light.position - p;
        let d = to_light.length();
        let n_dot_l = (to_light / d).dot(Vec3::Y);
        if n_dot_l <= 0.0 || d >= light.range {
            continue;
        }
        let visible = match hit {
            Hit::Ground(_) => ground_visibility(shadow_origin(p), light, margin)?,
            _ => true,
        };
        if visible {
            radiance +=
                ALBEDO / std::f32::consts::PI * light.color * light.intensity * attenuation(d, light.range) * n_dot_l;
        }
    }
    Some([radiance.x, radiance.y, radiance.z, 1.0])
}
