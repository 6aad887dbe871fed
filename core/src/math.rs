//! Geometry used on the CPU side: view frustum planes, sphere and box culling, the six cube-map faces.

use glam::{Mat4, Vec3, Vec4};

use crate::scene::Aabb;

/// Right-handed view matrix looking along `dir` (view space: X right, Y up, -Z forward).
pub fn look_to_rh(eye: Vec3, dir: Vec3, up: Vec3) -> Mat4 {
    glam::camera::rh::view::look_to_mat4(eye, dir, up)
}

/// Right-handed perspective projection for wgpu (NDC z in 0..1, y up).
pub fn perspective_rh(fov_y: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
    glam::camera::rh::proj::directx::perspective(fov_y, aspect, near, far)
}

/// The six planes of a view frustum, normals pointing inwards (`dot(n, p) + d >= 0` inside).
#[derive(Clone, Copy, Debug)]
pub struct Frustum {
    pub planes: [Vec4; 6],
}

impl Frustum {
    /// Gribb-Hartmann extraction from a clip-from-world matrix with wgpu's 0..1 depth.
    pub fn from_clip_from_world(m: &Mat4) -> Frustum {
        let r0 = m.row(0);
        let r1 = m.row(1);
        let r2 = m.row(2);
        let r3 = m.row(3);
        let planes = [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2].map(|p| {
            let len = p.truncate().length();
            if len > 0.0 {
                p / len
            } else {
                p
            }
        });
        Frustum { planes }
    }

    /// False only when the sphere lies completely outside one plane.
    pub fn intersects_sphere(&self, center: Vec3, radius: f32) -> bool {
        self.planes.iter().all(|p| p.truncate().dot(center) + p.w >= -radius)
    }

    /// False only when the box lies completely outside one plane (conservative).
    pub fn intersects_aabb(&self, b: &Aabb) -> bool {
        self.planes.iter().all(|p| {
            let n = p.truncate();
            let corner = Vec3::select(n.cmpge(Vec3::ZERO), b.max, b.min);
            n.dot(corner) + p.w >= 0.0
        })
    }
}

/// One face of a cube shadow map: the axis it looks down and its up vector.
/// Keep in sync with `cube_lookup` in `cube_shadow.wgsl`, which selects faces by the same table.
#[derive(Clone, Copy, Debug)]
pub struct CubeFace {
    pub forward: Vec3,
    pub up: Vec3,
}

/// +X, -X, +Y, -Y, +Z, -Z.
pub const CUBE_FACES: [CubeFace; 6] = [
    CubeFace { forward: Vec3::X, up: Vec3::Y },
    CubeFace { forward: Vec3::NEG_X, up: Vec3::Y },
    CubeFace { forward: Vec3::Y, up: Vec3::Z },
    CubeFace { forward: Vec3::NEG_Y, up: Vec3::NEG_Z },
    CubeFace { forward: Vec3::Z, up: Vec3::Y },
    CubeFace { forward: Vec3::NEG_Z, up: Vec3::Y },
];

impl CubeFace {
    /// Right-handed view looking down `forward` from `light`, 90 degree projection with `near`..`far` depth.
    pub fn clip_from_world(&self, light: Vec3, near: f32, far: f32) -> Mat4 {
        perspective_rh(std::f32::consts::FRAC_PI_2, 1.0, near, far) * look_to_rh(light, self.forward, self.up)
    }

    /// True when the box may overlap this face's 90 degree pyramid with apex at `light`.
    /// The pyramid is `dot(v,F) >= |dot(v,R)|` and `dot(v,F) >= |dot(v,U)|` for `v = p - light`.
    pub fn intersects_aabb(&self, light: Vec3, b: &Aabb) -> bool {
        let right = self.forward.cross(self.up);
        let normals = [self.forward - right, self.forward + right, self.forward - self.up, self.forward + self.up];
        let min = b.min - light;
        let max = b.max - light;
        normals.iter().all(|n| {
            let corner = Vec3::select(n.cmpge(Vec3::ZERO), max, min);
            n.dot(corner) >= 0.0
        })
    }
}

/// Which face a direction falls on (the major axis), matching `cube_shadow.wgsl`.
pub fn cube_face_of(v: Vec3) -> usize {
    let a = v.abs();
    if a.x >= a.y && a.x >= a.z {
        if v.x >= 0.0 {
            0
        } else {
            1
        }
    } else if a.y >= a.z {
        if v.y >= 0.0 {
            2
        } else {
            3
        }
    } else if v.z >= 0.0 {
        4
    } else {
        5
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frustum_culls_sphere_behind_camera() {
        let cam = crate::Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, 1.0, 0.1, 100.0);
        let f = Frustum::from_clip_from_world(&cam.clip_from_world(1.0));
        assert!(f.intersects_sphere(Vec3::new(0.0, 0.0, -10.0), 1.0));
        assert!(!f.intersects_sphere(Vec3::new(0.0, 0.0, 10.0), 1.0));
        assert!(f.intersects_sphere(Vec3::new(0.0, 0.0, 0.5), 1.0));
        assert!(!f.intersects_sphere(Vec3::new(0.0, 0.0, -200.0), 1.0));
    }

    #[test]
    fn each_direction_is_inside_its_own_face_pyramid_and_projects_inside() {
        let light = Vec3::new(1.0, 2.0, 3.0);
        for (i, d) in
            [Vec3::new(1.0, 0.3, -0.2), Vec3::new(-0.1, -1.0, 0.5), Vec3::new(0.2, 0.1, -2.0)].iter().enumerate()
        {
            let f = cube_face_of(*d);
            let face = CUBE_FACES[f];
            let p = light + *d;
            let b = Aabb { min: p - 0.01, max: p + 0.01 };
            assert!(face.intersects_aabb(light, &b), "case {i}");
            let clip = face.clip_from_world(light, 0.05, 10.0) * p.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            assert!(ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0 && (0.0..=1.0).contains(&ndc.z), "case {i}: {ndc}");
            // The opposite face never sees it.
            let opposite = CUBE_FACES[f ^ 1];
            assert!(!opposite.intersects_aabb(light, &b));
        }
    }
}
