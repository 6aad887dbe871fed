//! The clustering's parameters (Wiesenhütter et al. 2013, section 3.1.2): `d_init`, `z_far` and the view-adaptive
//! `d_min = d_init * (1 - |C_pos| / z_far)` of a center (symbols as in [`super::clustering`]'s module docs).

use glam::Vec3;

/// Parameters of the clustering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusterParams {
    /// The paper's `d_init`: the largest minimum distance between cluster centers, in world units.
    /// 0 gives one cluster per visible light.
    pub d_init: f32,
    /// The paper's `z_far`: the view distance at which `d_min` reaches 0 (normally [`crate::scene::Camera::z_far`]).
    pub z_far: f32,
    /// Scale `d_min` by the center's distance to the camera (the paper's method). Off: `d_min = d_init` for
    /// every center, which avoids clusters changing while the camera moves.
    pub adaptive: bool,
}

impl Default for ClusterParams {
    /// The paper's settings for its scenes: `d_init = 0.5`, `z_far = 30`, view-adaptive.
    fn default() -> Self {
        ClusterParams { d_init: 0.5, z_far: 30.0, adaptive: true }
    }
}

impl ClusterParams {
    /// Check the parameters for a UI or CLI: `d_init` finite and `>= 0`, `z_far > 0` (infinity allowed: no
    /// view-adaptive shrinking), whether or not `adaptive` is on. Clustering never panics on invalid values (see
    /// [`ClusterParams::effective_d_init`] and [`ClusterParams::scale_at`] for what it does instead).
    pub fn validate(&self) -> Result<(), String> {
        if !(self.d_init.is_finite() && self.d_init >= 0.0) {
            return Err(format!("d_init must be a finite distance >= 0, got {}", self.d_init));
        }
        if self.z_far.is_nan() || self.z_far <= 0.0 {
            return Err(format!("z_far must be > 0, got {}", self.z_far));
        }
        Ok(())
    }

    /// The `d_init` the clustering uses: NaN, negative and zero give 0 (one cluster per visible light),
    /// infinity gives `f32::MAX`.
    pub fn effective_d_init(&self) -> f32 {
        if self.d_init > 0.0 {
            self.d_init.min(f32::MAX)
        } else {
            0.0
        }
    }

    /// The view-adaptive scale `1 - |C_pos| / z_far` for a center at `distance_to_camera`, clamped to `[0, 1]`
    /// (0 at and beyond `z_far`, and for a NaN distance). 1 when `adaptive` is off, and when `z_far` is NaN
    /// or not positive (invalid: no scaling).
    pub fn scale_at(&self, distance_to_camera: f32) -> f32 {
        if !self.is_view_adaptive() {
            return 1.0;
        }
        let scale = 1.0 - distance_to_camera / self.z_far;
        if scale > 0.0 {
            scale.min(1.0)
        } else {
            0.0
        }
    }

    /// The paper's `d_min = d_init * (1 - |C_pos| / z_far)` of a center at `center` seen from `camera`,
    /// with [`ClusterParams::effective_d_init`] and [`ClusterParams::scale_at`]. Always finite and `>= 0`.
    pub fn d_min_at(&self, center: Vec3, camera: Vec3) -> f32 {
        self.d_min_at_distance(center.distance(camera))
    }

    /// [`ClusterParams::d_min_at`] for a center `distance_to_camera` (`|C_pos|`) from the camera.
    pub fn d_min_at_distance(&self, distance_to_camera: f32) -> f32 {
        let d_init = self.effective_d_init();
        if d_init == 0.0 {
            return 0.0;
        }
        d_init * self.scale_at(distance_to_camera)
    }

    /// Whether `d_min` depends on the distance to the camera (`adaptive` and a positive `z_far`).
    pub fn is_view_adaptive(&self) -> bool {
        self.adaptive && self.z_far > 0.0
    }
}
