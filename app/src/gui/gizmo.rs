//! Screen-space tools over the 3D view: projecting points, picking lights near the cursor, a ray pick against
//! the scene, and a move gizmo (three axis handles and a screen-plane handle) drawn with egui.

use eframe::egui;
use glam::{Mat4, Vec3, Vec4Swizzles};
use shadowlab_core::scene::{Camera, PointLight, Scene};

/// Maps between world space and a screen rectangle (egui points).
#[derive(Clone, Copy, Debug)]
pub struct Projection {
    pub clip_from_world: Mat4,
    pub rect: egui::Rect,
    pub camera: Camera,
}

impl Projection {
    pub fn new(camera: &Camera, rect: egui::Rect) -> Projection {
        let aspect = (rect.width() / rect.height().max(1.0)).max(1e-3);
        Projection { clip_from_world: camera.clip_from_world(aspect), rect, camera: *camera }
    }

    /// Screen position of a world point, None when behind the camera.
    pub fn to_screen(&self, p: Vec3) -> Option<egui::Pos2> {
        let c = self.clip_from_world * p.extend(1.0);
        if c.w <= 1e-6 {
            return None;
        }
        let ndc = c.xy() / c.w;
        Some(egui::pos2(
            self.rect.left() + (ndc.x * 0.5 + 0.5) * self.rect.width(),
            self.rect.top() + (0.5 - ndc.y * 0.5) * self.rect.height(),
        ))
    }

    /// World-space ray (origin, unit direction) through a screen position.
    pub fn ray(&self, pos: egui::Pos2) -> (Vec3, Vec3) {
        let x = (pos.x - self.rect.left()) / self.rect.width() * 2.0 - 1.0;
        let y = 1.0 - (pos.y - self.rect.top()) / self.rect.height() * 2.0;
        let inv = self.clip_from_world.inverse();
        let a = inv * glam::Vec4::new(x, y, 0.0, 1.0);
        let b = inv * glam::Vec4::new(x, y, 1.0, 1.0);
        let a = a.xyz() / a.w;
        let b = b.xyz() / b.w;
        (a, (b - a).normalize_or(Vec3::NEG_Z))
    }
}

/// The light nearest to `pos` on screen within `radius_points`.
pub fn pick_light(
    projection: &Projection,
    lights: &[PointLight],
    pos: egui::Pos2,
    radius_points: f32,
) -> Option<usize> {
    pick_point(projection, lights.iter().map(|l| l.position), pos, radius_points)
}

/// The point nearest to `pos` on screen within `radius_points`.
pub fn pick_point(
    projection: &Projection,
    points: impl Iterator<Item = Vec3>,
    pos: egui::Pos2,
    radius_points: f32,
) -> Option<usize> {
    points
        .enumerate()
        .filter_map(|(i, p)| projection.to_screen(p).map(|s| (i, s.distance(pos))))
        .filter(|&(_, d)| d <= radius_points)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// Nearest hit of a ray with the scene's triangles: (distance, normal facing the ray).
pub fn pick_surface(scene: &Scene, origin: Vec3, dir: Vec3) -> Option<(f32, Vec3)> {
    let mut best: Option<(f32, Vec3)> = None;
    for mesh in &scene.meshes {
        for t in mesh.indices.chunks_exact(3) {
            let (a, b, c) =
                (mesh.positions[t[0] as usize], mesh.positions[t[1] as usize], mesh.positions[t[2] as usize]);
            // Möller-Trumbore.
            let e1 = b - a;
            let e2 = c - a;
            let p = dir.cross(e2);
            let det = e1.dot(p);
            if det.abs() < 1e-12 {
                continue;
            }
            let inv = 1.0 / det;
            let s = origin - a;
            let u = s.dot(p) * inv;
            if !(0.0..=1.0).contains(&u) {
                continue;
            }
            let q = s.cross(e1);
            let v = dir.dot(q) * inv;
            if v < 0.0 || u + v > 1.0 {
                continue;
            }
            let dist = e2.dot(q) * inv;
            if dist > 1e-5 && best.is_none_or(|(d, _)| dist < d) {
                let n = e1.cross(e2).normalize_or(Vec3::Y);
                best = Some((dist, if n.dot(dir) > 0.0 { -n } else { n }));
            }
        }
    }
    best
}

/// Which part of the gizmo is under the cursor or being dragged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Handle {
    Axis(usize),
    ScreenPlane,
}

const AXIS_LENGTH_POINTS: f32 = 70.0;
const AXIS_COLORS: [egui::Color32; 3] =
    [egui::Color32::from_rgb(230, 70, 70), egui::Color32::from_rgb(80, 200, 80), egui::Color32::from_rgb(80, 120, 240)];
const AXES: [Vec3; 3] = [Vec3::X, Vec3::Y, Vec3::Z];

/// Screen end points of the three axis handles.
fn axis_ends(projection: &Projection, at: Vec3) -> Option<(egui::Pos2, [egui::Pos2; 3])> {
    let center = projection.to_screen(at)?;
    // One world unit along each axis, in screen points, normalised to a fixed on-screen length.
    let ends = AXES.map(|axis| {
        let p = projection.to_screen(at + axis * 0.01).unwrap_or(center);
        let d = p - center;
        let len = d.length();
        if len < 1e-6 {
            center
        } else {
            center + d / len * AXIS_LENGTH_POINTS
        }
    });
    Some((center, ends))
}

fn distance_to_segment(p: egui::Pos2, a: egui::Pos2, b: egui::Pos2) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_sq().max(1e-6)).clamp(0.0, 1.0);
    (a + ab * t).distance(p)
}

/// The handle under `pos`, if any.
pub fn hit_handle(projection: &Projection, at: Vec3, pos: egui::Pos2) -> Option<Handle> {
    let (center, ends) = axis_ends(projection, at)?;
    if (pos - center).abs().max_elem() <= 8.0 {
        return Some(Handle::ScreenPlane);
    }
    (0..3)
        .map(|i| (i, distance_to_segment(pos, center, ends[i])))
        .filter(|&(_, d)| d <= 6.0)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| Handle::Axis(i))
}

/// World-space move for a drag of `delta` points on `handle` of a gizmo at `at`.
pub fn drag_delta(projection: &Projection, at: Vec3, handle: Handle, delta: egui::Vec2) -> Vec3 {
    let Some(center) = projection.to_screen(at) else {
        return Vec3::ZERO;
    };
    match handle {
        Handle::Axis(i) => {
            // Screen points per world unit along the axis, from a small step (exact for small drags).
            let step = 0.01;
            let Some(p) = projection.to_screen(at + AXES[i] * step) else {
                return Vec3::ZERO;
            };
            let screen_dir = p - center;
            let per_unit = screen_dir.length() / step;
            if per_unit < 1e-3 {
                return Vec3::ZERO;
            }
            let along = delta.dot(screen_dir.normalized());
            AXES[i] * (along / per_unit)
        }
        Handle::ScreenPlane => {
            // Move in the plane facing the camera through the gizmo.
            let cam = &projection.camera;
            let depth = (at - cam.position).dot(cam.forward()).max(1e-4);
            let world_per_point = 2.0 * depth * (cam.fov_y * 0.5).tan() / projection.rect.height().max(1.0);
            (cam.right() * delta.x - cam.up() * delta.y) * world_per_point
        }
    }
}

/// Draw the gizmo; `active` is highlighted.
pub fn paint(painter: &egui::Painter, projection: &Projection, at: Vec3, active: Option<Handle>) {
    let Some((center, ends)) = axis_ends(projection, at) else {
        return;
    };
    for i in 0..3 {
        let width = if active == Some(Handle::Axis(i)) { 4.0 } else { 2.5 };
        painter.line_segment([center, ends[i]], egui::Stroke::new(width, AXIS_COLORS[i]));
        painter.circle_filled(ends[i], 4.0, AXIS_COLORS[i]);
    }
    let color = if active == Some(Handle::ScreenPlane) { egui::Color32::WHITE } else { egui::Color32::LIGHT_GRAY };
    painter.rect_stroke(
        egui::Rect::from_center_size(center, egui::vec2(12.0, 12.0)),
        0.0,
        egui::Stroke::new(2.0, color),
        egui::StrokeKind::Middle,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn projection() -> Projection {
        let cam = Camera::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, 60f32.to_radians(), 0.1, 100.0);
        Projection::new(&cam, egui::Rect::from_min_size(egui::pos2(0.0, 0.0), egui::vec2(400.0, 300.0)))
    }

    #[test]
    fn projects_the_target_to_the_center_and_rays_go_back() {
        let p = projection();
        let s = p.to_screen(Vec3::ZERO).unwrap();
        assert!((s - egui::pos2(200.0, 150.0)).length() < 1e-3);
        let (o, d) = p.ray(s);
        assert!((o + d * (5.0 - o.z).abs() * (1.0 / d.z.abs()) * d.z.abs()).x.abs() < 1e-3);
        assert!(d.dot(Vec3::NEG_Z) > 0.9999);
    }

    #[test]
    fn dragging_the_x_handle_moves_along_x_by_the_screen_distance() {
        let p = projection();
        let at = Vec3::ZERO;
        let center = p.to_screen(at).unwrap();
        assert_eq!(hit_handle(&p, at, center), Some(Handle::ScreenPlane));
        assert_eq!(hit_handle(&p, at, center + egui::vec2(50.0, 0.0)), Some(Handle::Axis(0)));
        assert_eq!(hit_handle(&p, at, center + egui::vec2(0.0, -50.0)), Some(Handle::Axis(1)));
        let moved = drag_delta(&p, at, Handle::Axis(0), egui::vec2(40.0, 7.0));
        assert!(moved.y == 0.0 && moved.z == 0.0 && moved.x > 0.0);
        // The moved point lands under the cursor's x.
        let s = p.to_screen(at + moved).unwrap();
        assert!((s.x - (center.x + 40.0)).abs() < 0.5, "{s:?}");
        let plane = drag_delta(&p, at, Handle::ScreenPlane, egui::vec2(0.0, -30.0));
        let s = p.to_screen(at + plane).unwrap();
        assert!((s.y - (center.y - 30.0)).abs() < 0.5);
    }

    #[test]
    fn picks_the_nearest_light_within_the_radius() {
        let p = projection();
        let lights = [
            PointLight::new(Vec3::ZERO, Vec3::ONE, 1.0, 1.0),
            PointLight::new(Vec3::new(1.0, 0.0, 0.0), Vec3::ONE, 1.0, 1.0),
        ];
        let s = p.to_screen(lights[1].position).unwrap();
        assert_eq!(pick_light(&p, &lights, s + egui::vec2(3.0, 0.0), 10.0), Some(1));
        assert_eq!(pick_light(&p, &lights, egui::pos2(5.0, 5.0), 10.0), None);
    }
}
