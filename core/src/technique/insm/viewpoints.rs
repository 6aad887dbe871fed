//! Reference viewpoints `V_j` of the intermediate shadow maps (paper section 3.1, Fig. 2 and Fig. 6).
//!
//! - `box` (the paper's default, Fig. 2): the midpoints of the eight horizontal edges of the scene's bounding
//!   box and the centres of its left and right faces, looking at the box centre. Good for scenes seen from
//!   outside (a model on a ground plane).
//! - `inside` (after the paper's 14 hand-placed Sponza cameras, Fig. 6): for scenes seen from inside (rooms,
//!   atria), where cameras on the bounding box would only see the outside of the walls. Eight cameras at mid
//!   height on a ring inside the box looking horizontally inwards, then cameras near the floor looking at the
//!   centre. The paper does not give their coordinates; this ring is our placement of the same idea.
//! - custom: a list the user edits (the app's gizmo) and saves in the scene file.
//!
//! Each list is ordered so that its first `k` entries spread around the scene for any `k`, which is how the
//! `k` parameter picks viewpoints (the paper's Table 4 varies `k` from 6 to 12).

use glam::{Mat4, Vec3};

use crate::math::{look_to_rh, perspective_rh};
use crate::scene::Aabb;

/// Largest field of view of an automatically placed viewpoint. A camera on a box edge needs 180 degrees to see
/// the whole box; beyond ~120 degrees a perspective image wastes most samples on its borders.
pub const MAX_AUTO_FOV_DEG: f32 = 120.0;

/// One reference viewpoint: where it is, where it looks, its (square) field of view.
pub type Viewpoint = crate::technique::CameraPose;

impl Viewpoint {
    pub fn is_valid(&self) -> bool {
        self.position.is_finite()
            && self.target.is_finite()
            && (self.target - self.position).length_squared() > 1e-12
            && self.fov_y_deg.is_finite()
            && self.fov_y_deg > 1.0
            && self.fov_y_deg < 170.0
    }

    pub fn forward(&self) -> Vec3 {
        (self.target - self.position).normalize_or(Vec3::NEG_Z)
    }

    fn up(&self) -> Vec3 {
        let f = self.forward();
        if f.cross(Vec3::Y).length_squared() < 1e-6 {
            Vec3::Z
        } else {
            Vec3::Y
        }
    }

    /// Near and far planes that hold the whole of `bounds` in front of this viewpoint.
    pub fn depth_range(&self, bounds: &Aabb) -> (f32, f32) {
        let far = bounds.corners().iter().map(|c| c.distance(self.position)).fold(0.0f32, f32::max).max(1e-3) * 1.01;
        (far * 1e-3, far)
    }

    /// Clip-from-world of this viewpoint's square depth image, with the depth range of `bounds`.
    pub fn clip_from_world(&self, bounds: &Aabb) -> Mat4 {
        let (near, far) = self.depth_range(bounds);
        self.clip_from_world_range(near, far)
    }

    /// Clip-from-world with an explicit depth range.
    pub fn clip_from_world_range(&self, near: f32, far: f32) -> Mat4 {
        perspective_rh(self.fov_y_deg.to_radians(), 1.0, near, far)
            * look_to_rh(self.position, self.forward(), self.up())
    }
}

/// The field of view (degrees) a camera at `position` looking at `target` needs to see all of `bounds`, clamped
/// to 30..=[`MAX_AUTO_FOV_DEG`].
fn fov_to_fit(position: Vec3, target: Vec3, bounds: &Aabb) -> f32 {
    let f = (target - position).normalize_or(Vec3::NEG_Z);
    let max_angle = bounds
        .corners()
        .iter()
        .map(|c| {
            let d = *c - position;
            if d.length_squared() < 1e-12 {
                0.0
            } else {
                d.normalize().dot(f).clamp(-1.0, 1.0).acos()
            }
        })
        .fold(0.0f32, f32::max);
    (2.0 * max_angle.to_degrees() * 1.02).clamp(30.0, MAX_AUTO_FOV_DEG)
}

/// The box the `box` placement uses: the scene's bounds, raised to at least half their horizontal extent.
/// Deviation: for a flat scene (a model on a wide ground plane) the paper's cameras would lie in the plane of
/// the ground and see every flat occluder edge-on; raising the top lets the top cameras look down on them.
pub fn placement_box(bounds: &Aabb) -> Aabb {
    let size = bounds.size();
    let min_height = 0.5 * size.x.max(size.z);
    let mut b = *bounds;
    b.max.y = b.max.y.max(b.min.y + min_height);
    b
}

/// How far the `box` placement's cameras stand from the box centre by default, in multiples of the paper's
/// distance (a camera on the box): see [`box_viewpoints`].
pub const DEFAULT_BOX_DISTANCE: f32 = 4.0;

/// The paper's placement (Fig. 2) on [`placement_box`], ordered for any prefix: left and right face centres,
/// then the eight horizontal edge midpoints alternating top and bottom, then front, back, top and bottom face
/// centres (for `k` above 10). At most 14.
///
/// `distance` moves each camera along its line to the centre, in multiples of its distance on the box: 1 is the
/// paper's. Deviation (the default [`DEFAULT_BOX_DISTANCE`]): a camera on the box needs a field of view of
/// ~120 degrees to see the box, and a perspective image that wide spends its samples on its borders: the
/// centre of the image, where the model stands, gets a quarter of the samples per degree that the borders get
/// (the density goes as 1 / cos³ of the angle off axis). From four times as far the same box fits in 35-45
/// degrees (the Dragon's), sampled almost uniformly, and the model gets about four times the samples. Measured
/// on the paper's Dragon (the Stanford dragon on a floor, `scripts/measure-insm`): shadow error against the ray
/// tracer 3.75 % at distance 1, 3.18 % at 2, 1.56 % at 3, 1.05 % at 4, 1.21 % at 6, without `bias_samples` and
/// `dilate` (the paper: 0.12 %).
pub fn box_viewpoints(scene_bounds: &Aabb, distance: f32) -> Vec<Viewpoint> {
    let bounds = &placement_box(scene_bounds);
    let c = bounds.center();
    let (lo, hi) = (bounds.min, bounds.max);
    let positions = [
        Vec3::new(lo.x, c.y, c.z),
        Vec3::new(hi.x, c.y, c.z),
        Vec3::new(c.x, hi.y, hi.z),
        Vec3::new(c.x, lo.y, lo.z),
        Vec3::new(lo.x, hi.y, c.z),
        Vec3::new(hi.x, lo.y, c.z),
        Vec3::new(c.x, hi.y, lo.z),
        Vec3::new(c.x, lo.y, hi.z),
        Vec3::new(hi.x, hi.y, c.z),
        Vec3::new(lo.x, lo.y, c.z),
        Vec3::new(c.x, c.y, hi.z),
        Vec3::new(c.x, c.y, lo.z),
        Vec3::new(c.x, hi.y, c.z),
        Vec3::new(c.x, lo.y, c.z),
    ];
    let distance = if distance.is_finite() { distance.max(1.0) } else { 1.0 };
    positions
        .iter()
        .map(|&on_box| {
            let p = c + (on_box - c) * distance;
            Viewpoint { position: p, target: c, fov_y_deg: fov_to_fit(p, c, scene_bounds) }
        })
        .collect()
}

/// Cameras inside the box (after the paper's Sponza placement, Fig. 6): a ring of eight at mid height, 15 % in
/// from the walls, looking horizontally at the vertical axis through the centre; then six at 10 % of the height
/// on a smaller ring looking at the centre. Ordered for any prefix. At most 14.
pub fn inside_viewpoints(bounds: &Aabb) -> Vec<Viewpoint> {
    let c = bounds.center();
    let half = bounds.size() * 0.5;
    let mut out = Vec::with_capacity(14);
    // Ring order alternating across the centre so prefixes spread: 0, 4, 2, 6, 1, 5, 3, 7 (eighths of a turn).
    for i in [0u32, 4, 2, 6, 1, 5, 3, 7] {
        let a = i as f32 * std::f32::consts::FRAC_PI_4;
        let p = Vec3::new(c.x + a.cos() * half.x * INSIDE_WALL_SHARE, c.y, c.z + a.sin() * half.z * INSIDE_WALL_SHARE);
        let target = Vec3::new(c.x, c.y, c.z);
        out.push(Viewpoint { position: p, target, fov_y_deg: INSIDE_FOV_DEG });
    }
    let low_y = bounds.min.y + bounds.size().y * 0.1;
    for i in [0u32, 3, 1, 4, 2, 5] {
        let a = (i as f32 + 0.5) * std::f32::consts::TAU / 6.0;
        let p = Vec3::new(c.x + a.cos() * half.x * 0.5, low_y, c.z + a.sin() * half.z * 0.5);
        out.push(Viewpoint { position: p, target: c, fov_y_deg: INSIDE_FOV_DEG });
    }
    out
}

/// The mean width (world units) of one sample of a `resolution`² map of `views` at each viewpoint's distance to
/// the centre of `bounds`: the scale to which the reconstructed meshes stand for the surfaces. 0 without views.
pub fn mean_sample_width(views: &[Viewpoint], bounds: &Aabb, resolution: u32) -> f32 {
    if views.is_empty() || resolution == 0 {
        return 0.0;
    }
    let c = bounds.center();
    let sum: f32 = views
        .iter()
        .map(|v| 2.0 * v.position.distance(c) * (0.5 * v.fov_y_deg.to_radians()).tan() / resolution as f32)
        .sum();
    sum / views.len() as f32
}

/// Field of view of the `inside` placement's cameras. 120 degrees was tried (160x90, 1,024 random lights, against
/// the ray tracer): the Cornell box 4.36 to 2.59 %, the conference room 7.49 to 7.06 %, but the arcade 9.25 to
/// 10.49 % and the restaurant 1.37 to 1.42 % (Sponza equal): not a change for every scene, so 100 stays.
pub const INSIDE_FOV_DEG: f32 = 100.0;

/// The inside placement fitted to the walls (`walls`): a camera of `views` (made by [`inside_viewpoints`] for
/// `bounds`) that stands behind a wall moves in, along its line from the vertical axis through the centre, to
/// [`INSIDE_WALL_SHARE`] of the way to that wall. A wall is a surface that `hit(origin, direction, t_max)` finds
/// nearer than the camera's box position at the camera's height and at a quarter of the box's height above and
/// below it (the farthest of the three is taken): an object of part of the room's height (a block, a table) does
/// not move a camera, a wall does, which the box alone cannot tell (an arcade's aisles lie inside its box, with
/// two of the ring's cameras behind their outer walls). A surface within a fifth of the camera's distance from
/// the axis (a column at the centre) moves nothing.
pub fn fit_inside(
    views: Vec<Viewpoint>,
    bounds: &Aabb,
    hit: impl Fn(Vec3, Vec3, f32) -> Option<f32>,
) -> Vec<Viewpoint> {
    let c = bounds.center();
    let rise = Vec3::Y * (0.25 * bounds.size().y);
    views
        .into_iter()
        .map(|v| {
            let origin = Vec3::new(c.x, v.position.y, c.z);
            let out = v.position - origin;
            let r = out.length();
            if !(r > 0.0 && r.is_finite()) {
                return v;
            }
            let dir = out / r;
            let wall = r / INSIDE_WALL_SHARE;
            let farthest = [origin - rise, origin, origin + rise]
                .into_iter()
                .map(|o| hit(o, dir, wall))
                .try_fold(0.0f32, |acc, t| t.map(|t| acc.max(t)));
            match farthest {
                Some(t) if t < wall && t > 0.2 * r => {
                    Viewpoint { position: origin + dir * (INSIDE_WALL_SHARE * t), ..v }
                }
                _ => v,
            }
        })
        .collect()
}

/// How far the inside ring stands from the centre towards the walls.
pub const INSIDE_WALL_SHARE: f32 = 0.85;

/// How viewpoints are placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    Box,
    Inside,
    Custom,
    /// `Inside` with the cameras behind walls moved in front of them ([`fit_inside`], beyond the paper).
    Walls,
    /// `Inside` for an enclosed model, `Box` for an object (beyond the paper, the default): rays from the middle
    /// of the bounds hit the model all around at and below the horizon, or in most directions
    /// ([`crate::accel::first_view::is_enclosed`]: the built-ins, Sponza and the conference room are enclosed,
    /// the Dragon on its floor is not). The paper places its cameras by hand for Sponza.
    Auto,
}

impl Placement {
    pub const NAMES: &'static [&'static str] = &["auto", "box", "inside", "walls", "custom"];

    pub fn name(self) -> &'static str {
        match self {
            Placement::Box => "box",
            Placement::Inside => "inside",
            Placement::Walls => "walls",
            Placement::Custom => "custom",
            Placement::Auto => "auto",
        }
    }

    pub fn from_name(name: &str) -> Option<Placement> {
        match name {
            "box" => Some(Placement::Box),
            "inside" => Some(Placement::Inside),
            "walls" => Some(Placement::Walls),
            "custom" => Some(Placement::Custom),
            "auto" => Some(Placement::Auto),
            _ => None,
        }
    }
}

/// The first `k` viewpoints of `placement` for `bounds` (custom: the first `k` of `custom`), invalid ones dropped;
/// `box_distance` is [`box_viewpoints`]' `distance`; `hit` finds the walls of `walls` ([`fit_inside`]; without
/// it `walls` is `inside`).
pub fn select(
    placement: Placement,
    bounds: &Aabb,
    custom: &[Viewpoint],
    k: usize,
    box_distance: f32,
    hit: Option<&dyn Fn(Vec3, Vec3, f32) -> Option<f32>>,
) -> Vec<Viewpoint> {
    let all = match (placement, hit) {
        (Placement::Box, _) => box_viewpoints(bounds, box_distance),
        (Placement::Inside, _) | (Placement::Walls, None) => inside_viewpoints(bounds),
        (Placement::Walls, Some(hit)) => fit_inside(inside_viewpoints(bounds), bounds, hit),
        (Placement::Custom, _) => custom.to_vec(),
        // Resolved by the caller, who has the scene ([`Placement::Auto`]); without it, the paper's.
        (Placement::Auto, _) => box_viewpoints(bounds, box_distance),
    };
    all.into_iter().filter(Viewpoint::is_valid).take(k).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Aabb {
        Aabb { min: Vec3::new(-2.0, 0.0, -1.0), max: Vec3::new(2.0, 2.0, 1.0) }
    }

    #[test]
    fn box_placement_is_the_papers_ten_then_four_more() {
        let b = unit_box();
        assert_eq!(placement_box(&b), b, "a box tall enough is used as it is");
        let v = box_viewpoints(&b, 1.0);
        assert_eq!(v.len(), 14);
        // The first ten: two face centres and eight edge midpoints, all on the box surface.
        let on_surface = |p: Vec3| {
            [p.x - b.min.x, b.max.x - p.x, p.y - b.min.y, b.max.y - p.y, p.z - b.min.z, b.max.z - p.z]
                .iter()
                .filter(|d| d.abs() < 1e-6)
                .count()
        };
        assert_eq!(on_surface(v[0].position), 1);
        assert_eq!(on_surface(v[1].position), 1);
        assert_eq!(v[0].position.x, b.min.x);
        assert_eq!(v[1].position.x, b.max.x);
        for vp in &v[2..10] {
            assert_eq!(on_surface(vp.position), 2, "{vp:?} is not an edge midpoint");
            assert!(vp.position.y == b.min.y || vp.position.y == b.max.y, "edges are the horizontal ones");
        }
        // Distinct and all looking at the centre.
        for (i, a) in v.iter().enumerate() {
            assert!(a.is_valid());
            assert!((a.forward() - (b.center() - a.position).normalize()).length() < 1e-5);
            for bb in &v[i + 1..] {
                assert!(a.position.distance(bb.position) > 1e-3);
            }
        }
    }

    #[test]
    fn a_flat_scene_gets_a_taller_box() {
        let flat = Aabb { min: Vec3::new(-10.0, 0.0, -10.0), max: Vec3::new(10.0, 1.0, 10.0) };
        let b = placement_box(&flat);
        assert_eq!(b.max.y, 10.0);
        assert_eq!((b.min, b.max.x, b.max.z), (flat.min, 10.0, 10.0));
        // The top cameras look down.
        assert!(box_viewpoints(&flat, 1.0)[2].forward().y < -0.4);
    }

    #[test]
    fn fov_fits_the_box_up_to_the_cap() {
        let b = unit_box();
        for vp in box_viewpoints(&b, 1.0) {
            assert!((30.0..=MAX_AUTO_FOV_DEG).contains(&vp.fov_y_deg));
        }
        // From far away the box needs a small angle; the corners then project inside the image.
        let far = Viewpoint { position: Vec3::new(0.0, 1.0, 20.0), target: b.center(), fov_y_deg: 0.0 };
        let fov = fov_to_fit(far.position, far.target, &b);
        assert!(fov < 40.0, "{fov}");
        let vp = Viewpoint { fov_y_deg: fov, ..far };
        let m = vp.clip_from_world(&b);
        for c in b.corners() {
            let p = m.project_point3(c);
            assert!(p.x.abs() <= 1.0 && p.y.abs() <= 1.0 && (0.0..=1.0).contains(&p.z), "{c} -> {p}");
        }
    }

    #[test]
    fn box_cameras_at_a_distance_keep_their_directions_and_narrow_their_view() {
        let b = unit_box();
        let (near, far) = (box_viewpoints(&b, 1.0), box_viewpoints(&b, 4.0));
        let c = placement_box(&b).center();
        for (n, f) in near.iter().zip(&far) {
            assert_eq!(f.target, c);
            assert!((f.position - c).abs_diff_eq((n.position - c) * 4.0, 1e-5), "{} vs {}", f.position, n.position);
            assert!(f.fov_y_deg <= n.fov_y_deg);
            // The whole scene stays in view.
            let m = f.clip_from_world(&b);
            for corner in b.corners() {
                let p = m.project_point3(corner);
                assert!(p.x.abs() <= 1.0 && p.y.abs() <= 1.0, "{corner} -> {p}");
            }
        }
        // Below 1 (inside the box) or not finite: the paper's distance.
        assert_eq!(box_viewpoints(&b, 0.2), near);
        assert_eq!(box_viewpoints(&b, f32::NAN), near);
    }

    #[test]
    fn the_mean_sample_width_is_the_width_of_a_sample_at_the_centre() {
        let b = unit_box();
        let c = b.center();
        // 90 degrees at 2 m: the image is 4 m wide at the centre, so 100 samples are 4 cm each.
        let v = Viewpoint { position: c + Vec3::new(0.0, 0.0, 2.0), target: c, fov_y_deg: 90.0 };
        assert!((mean_sample_width(&[v], &b, 100) - 0.04).abs() < 1e-5);
        let far = Viewpoint { position: c + Vec3::new(0.0, 0.0, 6.0), ..v };
        assert!((mean_sample_width(&[v, far], &b, 100) - 0.08).abs() < 1e-5, "the mean of 4 and 12 cm");
        assert_eq!(mean_sample_width(&[], &b, 100), 0.0);
    }

    #[test]
    fn inside_placement_stays_inside_and_prefixes_spread() {
        let b = unit_box();
        let v = inside_viewpoints(&b);
        assert_eq!(v.len(), 14);
        for vp in &v {
            assert!(vp.is_valid());
            assert!(vp.position.cmpgt(b.min).all() && vp.position.cmplt(b.max).all(), "{vp:?}");
        }
        // The first two face each other across the centre.
        assert!((v[0].position + v[1].position - 2.0 * Vec3::new(0.0, 1.0, 0.0)).length() < 1e-4);
    }

    #[test]
    fn select_takes_k_and_drops_invalid_custom_viewpoints() {
        let b = unit_box();
        assert_eq!(select(Placement::Box, &b, &[], 6, 1.0, None).len(), 6);
        assert_eq!(select(Placement::Box, &b, &[], 100, 1.0, None).len(), 14);
        let good = Viewpoint { position: Vec3::ZERO, target: Vec3::X, fov_y_deg: 90.0 };
        let nan = Viewpoint { position: Vec3::NAN, ..good };
        let degenerate = Viewpoint { target: Vec3::ZERO, ..good };
        let custom = [good, nan, degenerate, good];
        assert_eq!(select(Placement::Custom, &b, &custom, 10, 1.0, None), vec![good, good]);
        assert_eq!(Placement::from_name("inside"), Some(Placement::Inside));
        assert_eq!(Placement::from_name("nope"), None);
    }

    #[test]
    fn cameras_parse_from_the_command_line_and_reject_bad_input() {
        use crate::technique::{ParamKind, ParamValue};
        let kind = ParamKind::Cameras { max: 2, selected_by: None };
        let v = kind.parse("viewpoints", "0,5,0, 0,0,0, 90; 1,2,3,4,5,6,45").unwrap();
        let ParamValue::Cameras(c) = &v else { panic!("{v:?}") };
        assert_eq!(c.len(), 2);
        assert_eq!(c[1].target, Vec3::new(4.0, 5.0, 6.0));
        // Display gives back text that parses to the same value.
        assert_eq!(kind.parse("viewpoints", &v.to_string()).unwrap(), v);
        assert_eq!(kind.parse("viewpoints", "").unwrap(), ParamValue::Cameras(vec![]));
        for bad in [
            "1,2,3",
            "0,0,0,0,0,0,90",
            "0,5,0,0,0,0,200",
            "nan,5,0,0,0,0,90",
            "0,1,0,0,0,0,90;0,2,0,0,0,0,90;0,3,0,0,0,0,90",
        ] {
            let e = kind.parse("viewpoints", bad);
            assert!(e.is_err(), "{bad} was accepted");
        }
    }

    #[test]
    fn walls_move_the_cameras_behind_a_wall_and_nothing_else() {
        let b = unit_box();
        let c = b.center();
        let inside = inside_viewpoints(&b);
        // A wall across the box at z = 0.6 (full height): the rays towards +z from the axis meet it at
        // t = 0.6 / dir.z. The ring's camera at +z (a quarter turn) stands at z = 0.85 behind it, the low ring's
        // at z = 0.5 in front of it.
        let wall = |o: Vec3, d: Vec3, t_max: f32| {
            let t = (0.6 - o.z) / d.z;
            (d.z > 1e-6 && t > 0.0 && t < t_max).then_some(t)
        };
        let fitted = select(Placement::Walls, &b, &[], 14, 1.0, Some(&wall));
        assert_eq!(fitted.len(), 14);
        for (f, i) in fitted.iter().zip(&inside) {
            let crosses = i.position.z > 0.6;
            if crosses {
                // Moved along its line from the axis to 0.85 of the way to the wall, looking where it looked.
                assert!((f.position.z - 0.85 * 0.6).abs() < 1e-4, "{f:?}");
                let (a, b2) = ((f.position - c).with_y(0.0), (i.position - c).with_y(0.0));
                assert!(a.normalize().dot(b2.normalize()) > 0.9999, "{f:?} {i:?}");
                assert_eq!((f.position.y, f.target, f.fov_y_deg), (i.position.y, i.target, i.fov_y_deg));
            } else {
                assert_eq!(f, i, "a camera in front of the wall stays");
            }
        }
        assert!(inside.iter().any(|i| i.position.z > 0.6), "the test needs a camera behind the wall");
        // A block of part of the height (only the lowest ray meets it) and a column at the centre move nothing;
        // without a way to find walls, `walls` is `inside`.
        let low_y = c.y - 0.25 * b.size().y;
        let block = |o: Vec3, d: Vec3, t_max: f32| if o.y <= low_y + 1e-4 { wall(o, d, t_max) } else { None };
        assert_eq!(select(Placement::Walls, &b, &[], 14, 1.0, Some(&block)), inside);
        let column = |_: Vec3, _: Vec3, _: f32| Some(0.01);
        assert_eq!(select(Placement::Walls, &b, &[], 14, 1.0, Some(&column)), inside);
        assert_eq!(select(Placement::Walls, &b, &[], 14, 1.0, None), inside);
        assert_eq!(Placement::from_name("walls"), Some(Placement::Walls));
    }
}
