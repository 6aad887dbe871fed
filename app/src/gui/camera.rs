//! Camera controllers: orbit (drag to rotate, scroll to zoom, middle-drag to pan) and fly (WASD/QE + mouse).
//! Movement is scaled by frame time and by the scene size, so it feels the same at any frame rate and scale.

use glam::{Quat, Vec2, Vec3};
use shadowlab_core::scene::{Aabb, Camera};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraMode {
    Orbit,
    Fly,
}

/// Input of one frame that concerns the camera.
#[derive(Clone, Copy, Debug, Default)]
pub struct CameraInput {
    /// Primary-button drag in points.
    pub rotate: Vec2,
    /// Middle-button drag in points.
    pub pan: Vec2,
    /// Scroll in points (positive: zoom in).
    pub zoom: f32,
    /// Fly: forward/back, right/left, up/down, each -1..1.
    pub movement: Vec3,
    pub fast: bool,
    pub dt_secs: f32,
}

impl CameraInput {
    pub fn is_active(&self) -> bool {
        self.rotate != Vec2::ZERO || self.pan != Vec2::ZERO || self.zoom != 0.0 || self.movement != Vec3::ZERO
    }
}

#[derive(Clone, Debug)]
pub struct CameraController {
    pub mode: CameraMode,
    pub target: Vec3,
    pub distance: f32,
    /// Radians around +Y.
    pub yaw: f32,
    /// Radians up from the horizon.
    pub pitch: f32,
    pub position: Vec3,
    pub fov_y: f32,
    pub near: f32,
    pub z_far: f32,
    /// Scene size, for speeds.
    pub scene_radius: f32,
}

const ROTATE_RADIANS_PER_POINT: f32 = 0.008;
const PITCH_LIMIT: f32 = 1.55;

impl CameraController {
    pub fn from_camera(camera: &Camera, bounds: &Aabb) -> CameraController {
        let forward = camera.forward();
        let scene_radius = (bounds.size().length() * 0.5).max(0.1);
        // Orbit around the point where the view ray meets the middle of the scene.
        let to_center = bounds.center() - camera.position;
        let distance = to_center.dot(forward).max(scene_radius * 0.1);
        let yaw = forward.x.atan2(-forward.z);
        let pitch = forward.y.clamp(-1.0, 1.0).asin();
        CameraController {
            mode: CameraMode::Orbit,
            target: camera.position + forward * distance,
            distance,
            yaw,
            pitch,
            position: camera.position,
            fov_y: camera.fov_y,
            near: camera.near,
            z_far: camera.z_far,
            scene_radius,
        }
    }

    fn forward(&self) -> Vec3 {
        Vec3::new(self.yaw.sin() * self.pitch.cos(), self.pitch.sin(), -self.yaw.cos() * self.pitch.cos())
    }

    pub fn camera(&self) -> Camera {
        let forward = self.forward();
        let position = match self.mode {
            CameraMode::Orbit => self.target - forward * self.distance,
            CameraMode::Fly => self.position,
        };
        let mut c = Camera::look_at(position, position + forward, self.fov_y, self.near, self.z_far);
        // look_at derives the orientation; keep it exactly level (no roll).
        c.orientation = Quat::from_rotation_y(-self.yaw) * Quat::from_rotation_x(self.pitch);
        c
    }

    /// Apply one frame of input. Returns true when the camera moved.
    pub fn update(&mut self, input: &CameraInput) -> bool {
        if !input.is_active() {
            return false;
        }
        // Keep orbit and fly consistent so switching mode does not jump.
        let before = self.camera();
        self.yaw += input.rotate.x * ROTATE_RADIANS_PER_POINT;
        self.pitch = (self.pitch - input.rotate.y * ROTATE_RADIANS_PER_POINT).clamp(-PITCH_LIMIT, PITCH_LIMIT);
        match self.mode {
            CameraMode::Orbit => {
                let pan_scale = self.distance * (self.fov_y * 0.5).tan() * 0.004;
                self.target += (before.up() * input.pan.y - before.right() * input.pan.x) * pan_scale;
                if input.zoom != 0.0 {
                    self.distance = (self.distance * (-input.zoom * 0.002).exp()).clamp(1e-3, self.z_far * 0.9);
                }
                self.position = self.target - self.forward() * self.distance;
            }
            CameraMode::Fly => {
                let speed = self.scene_radius * 0.4 * if input.fast { 4.0 } else { 1.0 };
                let c = self.camera();
                let step = (c.forward() * input.movement.x + c.right() * input.movement.y + Vec3::Y * input.movement.z)
                    * speed
                    * input.dt_secs.clamp(0.0, 0.25);
                self.position += step;
                self.position += (c.up() * input.pan.y - c.right() * input.pan.x) * self.scene_radius * 0.002;
                self.position += c.forward() * input.zoom * self.scene_radius * 0.001;
                self.target = self.position + self.forward() * self.distance;
            }
        }
        true
    }

    pub fn set_mode(&mut self, mode: CameraMode) {
        if mode == self.mode {
            return;
        }
        let c = self.camera();
        self.position = c.position;
        self.target = c.position + c.forward() * self.distance;
        self.mode = mode;
    }

    /// Look at the whole scene.
    pub fn frame(&mut self, bounds: &Aabb) {
        let radius = (bounds.size().length() * 0.5).max(0.1);
        self.target = bounds.center();
        self.distance = radius / (self.fov_y * 0.5).tan();
        self.z_far = self.z_far.max(self.distance + radius * 2.0);
        self.position = self.target - self.forward() * self.distance;
        self.mode = CameraMode::Orbit;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bounds() -> Aabb {
        Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) }
    }

    #[test]
    fn round_trips_a_camera() {
        let cam = Camera::look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 0.5, 0.0), 0.9, 0.05, 40.0);
        let ctl = CameraController::from_camera(&cam, &bounds());
        let back = ctl.camera();
        assert!((back.position - cam.position).length() < 1e-4, "{} vs {}", back.position, cam.position);
        assert!(back.forward().dot(cam.forward()) > 0.9999);
    }

    #[test]
    fn orbit_keeps_the_distance_to_the_target_and_zoom_changes_it() {
        let cam = Camera::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, 0.9, 0.05, 40.0);
        let mut ctl = CameraController::from_camera(&cam, &bounds());
        let d0 = ctl.camera().position.distance(ctl.target);
        ctl.update(&CameraInput { rotate: Vec2::new(50.0, 20.0), dt_secs: 0.016, ..Default::default() });
        assert!((ctl.camera().position.distance(ctl.target) - d0).abs() < 1e-4);
        ctl.update(&CameraInput { zoom: 100.0, dt_secs: 0.016, ..Default::default() });
        assert!(ctl.camera().position.distance(ctl.target) < d0);
    }

    #[test]
    fn fly_speed_is_frame_rate_independent() {
        let cam = Camera::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, 0.9, 0.05, 40.0);
        let mut a = CameraController::from_camera(&cam, &bounds());
        a.set_mode(CameraMode::Fly);
        let mut b = a.clone();
        let forward = CameraInput { movement: Vec3::X, dt_secs: 0.1, ..Default::default() };
        a.update(&forward);
        for _ in 0..10 {
            b.update(&CameraInput { dt_secs: 0.01, ..forward });
        }
        assert!((a.position - b.position).length() < 1e-4);
        assert!(a.position.z < 5.0, "moved forward");
    }
}
