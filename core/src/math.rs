//! Geometry used on the CPU side: view frustum planes, sphere and box culling, the six cube-map faces; and
//! Rec. 709 luminance.

use glam::{Mat4, Vec3, Vec4};

use serde::{Deserialize, Serialize};

/// Rec. 709 luminance of a linear RGB colour (the shaders' `luminance` in `shaders/common.wgsl`).
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

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

/// Spheres binned into a uniform grid, to find those containing a point without testing all of them (the
/// app's per-pixel cluster map and LightCluster's covering ask this). Cells are about the median radius (at most
/// eight a sphere); a sphere that would span more than [`SphereGrid::MAX_CELLS_PER_SPHERE`] cells is kept in a
/// list tested for every point.
pub struct SphereGrid {
    origin: Vec3,
    cell: f32,
    dims: [usize; 3],
    start: Vec<u32>,
    items: Vec<u32>,
    big: Vec<u32>,
}

impl SphereGrid {
    pub const MAX_CELLS_PER_SPHERE: usize = 512;
    const MAX_CELLS: usize = 1 << 18;

    /// `spheres`: (centre, radius); non-finite or negative radii contain nothing.
    pub fn new(spheres: &[(Vec3, f32)]) -> SphereGrid {
        let ok = |(c, r): &(Vec3, f32)| c.is_finite() && r.is_finite() && *r >= 0.0;
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let mut radii: Vec<f32> = Vec::new();
        for s in spheres.iter().filter(|s| ok(s)) {
            lo = lo.min(s.0 - Vec3::splat(s.1));
            hi = hi.max(s.0 + Vec3::splat(s.1));
            radii.push(s.1);
        }
        if radii.is_empty() {
            return SphereGrid {
                origin: Vec3::ZERO,
                cell: 1.0,
                dims: [1, 1, 1],
                start: vec![0, 0],
                items: vec![],
                big: vec![],
            };
        }
        radii.sort_by(f32::total_cmp);
        let extent = (hi - lo).max(Vec3::splat(1e-6));
        let mut cell = (radii[radii.len() / 2] * 2.0).max(extent.max_element() / 64.0).max(1e-6);
        let cells = |c: f32| (extent / c).ceil().max(Vec3::ONE);
        // At most eight cells a sphere (and MAX_CELLS): a few spheres over a wide extent would otherwise lay out
        // 64^3 empty cells (LightCluster's covering builds two grids a frame, for 80 lights 0.35 ms instead of
        // 0.05 ms).
        let max_cells = (8 * radii.len()).clamp(64, Self::MAX_CELLS) as f32;
        while cells(cell).x * cells(cell).y * cells(cell).z > max_cells {
            cell *= 1.5;
        }
        let n = cells(cell);
        let dims = [n.x as usize, n.y as usize, n.z as usize];
        let index = |c: [usize; 3]| c[0] + dims[0] * (c[1] + dims[1] * c[2]);
        let clamp_cell = |p: Vec3| {
            let c = ((p - lo) / cell).floor();
            [0, 1, 2].map(|a| (c[a].max(0.0) as usize).min(dims[a] - 1))
        };
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        let mut big = Vec::new();
        for (i, s) in spheres.iter().enumerate().filter(|(_, s)| ok(s)) {
            let (a, b) = (clamp_cell(s.0 - Vec3::splat(s.1)), clamp_cell(s.0 + Vec3::splat(s.1)));
            let span = (b[0] - a[0] + 1) * (b[1] - a[1] + 1) * (b[2] - a[2] + 1);
            if span > Self::MAX_CELLS_PER_SPHERE {
                big.push(i as u32);
                continue;
            }
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        lists[index([x, y, z])].push(i as u32);
                    }
                }
            }
        }
        let mut start = Vec::with_capacity(lists.len() + 1);
        let mut items = Vec::new();
        start.push(0);
        for l in &lists {
            items.extend_from_slice(l);
            start.push(items.len() as u32);
        }
        SphereGrid { origin: lo, cell, dims, start, items, big }
    }

    /// The indices of the spheres that may contain `p` (a superset; test each), in increasing order per cell.
    pub fn candidates(&self, p: Vec3) -> impl Iterator<Item = u32> + '_ {
        let c = ((p - self.origin) / self.cell).floor();
        let inside = p.is_finite() && (0..3).all(|a| c[a] >= 0.0 && (c[a] as usize) < self.dims[a]);
        let cell = if inside {
            let i = c.x as usize + self.dims[0] * (c.y as usize + self.dims[1] * c.z as usize);
            &self.items[self.start[i] as usize..self.start[i + 1] as usize]
        } else {
            &self.items[0..0]
        };
        cell.iter().chain(self.big.iter()).copied()
    }
}

/// An axis-aligned box. `Aabb::EMPTY` grows with [`Aabb::extend`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in points {
            b.extend(p);
        }
        b
    }
    pub fn extend(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb { min: self.min.min(o.min), max: self.max.max(o.max) }
    }
    /// The eight corners.
    pub fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }

    /// The box both boxes hold (empty when they do not overlap).
    pub fn intersection(&self, o: &Aabb) -> Aabb {
        Aabb { min: self.min.max(o.min), max: self.max.min(o.max) }
    }

    /// Whether the boxes overlap (touching counts).
    pub fn intersects(&self, o: &Aabb) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }

    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }
    /// Squared distance from `p` to the box (0 inside).
    pub fn distance_squared(&self, p: Vec3) -> f32 {
        let d = (self.min - p).max(p - self.max).max(Vec3::ZERO);
        d.length_squared()
    }
    pub fn intersects_sphere(&self, center: Vec3, radius: f32) -> bool {
        self.distance_squared(center) <= radius * radius
    }
}

/// A small deterministic generator (xorshift) for the property tests.
#[cfg(test)]
pub(crate) struct TestRng(pub u64);

#[cfg(test)]
impl TestRng {
    /// The next value in [0, 1).
    pub fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    /// A random unit vector (uniform in direction).
    pub fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.next(), self.next(), self.next()) * 2.0 - 1.0;
            if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frustum_culls_sphere_behind_camera() {
        let cam = crate::scene::Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, 1.0, 0.1, 100.0);
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

    #[test]
    fn sphere_grid_finds_what_brute_force_finds() {
        let mut rng = TestRng(12345);
        let mut next = || rng.next();
        let spheres: Vec<(Vec3, f32)> = (0..300)
            .map(|i| {
                let c = Vec3::new(next(), next(), next()) * 20.0;
                let r = if i % 50 == 0 { 30.0 } else { next() * 2.0 };
                (c, r)
            })
            .chain([(Vec3::NAN, 1.0), (Vec3::ZERO, f32::NAN)])
            .collect();
        let grid = SphereGrid::new(&spheres);
        for _ in 0..2000 {
            let p = Vec3::new(next(), next(), next()) * 24.0 - Vec3::splat(2.0);
            let mut got: Vec<u32> =
                grid.candidates(p).filter(|&i| spheres[i as usize].0.distance(p) <= spheres[i as usize].1).collect();
            got.sort();
            let want: Vec<u32> = (0..spheres.len() as u32)
                .filter(|&i| spheres[i as usize].0.distance(p) <= spheres[i as usize].1)
                .collect();
            assert_eq!(got, want, "at {p:?}");
        }
        assert_eq!(SphereGrid::new(&[]).candidates(Vec3::ZERO).count(), 0);
    }
}
