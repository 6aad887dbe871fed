//! The first view of a model that brings no camera: from outside for an object, from inside for an enclosed
//! interior (a courtyard, a hall, a room), where a camera framing the bounds from outside sees the roof.
//!
//! Enclosed means that rays from the middle of the bounds hit the model in most directions at or below the
//! horizon ([`ENCLOSED_SHARE`] of those of [`PROBE_DIRECTIONS`], through the scene's BVH): walls all around and
//! a floor, whether or not there is a roof (a courtyard open to the sky is an interior; an object on a floor,
//! seen from the middle of its bounds, has no walls); an interior is then seen from a
//! point with room around it, near one end of its longest horizontal axis, at a third of its height, looking
//! along that axis; unless one of its sides is open (a Cornell box without its front wall, whose floor or water
//! catches the low rays): then it is framed from outside that side ([`first_view`]).

use glam::Vec3;

use super::bvh::{closest_hit_cpu, Bvh};
use crate::math::Aabb;
use crate::scene::Camera;

/// Directions the enclosure and the clearance are probed in (a Fibonacci sphere).
pub const PROBE_DIRECTIONS: usize = 96;

/// The share of the probe rays at or below the horizon (up to [`HORIZON`]) from the middle of the bounds that
/// must hit the model for it to be an interior.
pub const ENCLOSED_SHARE: f32 = 0.85;

/// The highest `y` of a probe direction counted for the enclosure: a little above the horizon.
pub const HORIZON: f32 = 0.25;

fn directions() -> impl Iterator<Item = Vec3> {
    let n = PROBE_DIRECTIONS as f32;
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..PROBE_DIRECTIONS).map(move |i| {
        let y = 1.0 - (i as f32 + 0.5) / n * 2.0;
        let r = (1.0 - y * y).max(0.0).sqrt();
        let phi = golden * i as f32;
        Vec3::new(r * phi.cos(), y, r * phi.sin())
    })
}

/// The share of the probe directions at or below [`HORIZON`] in which a ray from `point` hits the model within
/// `t_max`, and the nearest hit distance over all directions (`t_max` when none hits).
pub fn probe(bvh: &Bvh, point: Vec3, t_max: f32) -> (f32, f32) {
    let (mut low, mut low_hits) = (0, 0);
    let mut nearest = t_max;
    for dir in directions() {
        let hit = closest_hit_cpu(bvh, point, dir, t_max);
        if let Some(hit) = hit {
            nearest = nearest.min(hit.t);
        }
        if dir.y <= HORIZON {
            low += 1;
            low_hits += hit.is_some() as usize;
        }
    }
    (low_hits as f32 / low.max(1) as f32, nearest)
}

/// The share of the probe rays from `point` that hit the back of a triangle first: near 1 inside a closed
/// solid (a model whose body fills the middle of its bounds), near 0 in the open.
pub fn back_face_share(bvh: &Bvh, point: Vec3, t_max: f32) -> f32 {
    let (mut hits, mut back) = (0, 0);
    for dir in directions() {
        if let Some(hit) = closest_hit_cpu(bvh, point, dir, t_max) {
            let t = &bvh.triangles[hit.triangle as usize];
            let normal = Vec3::from_slice(&t.e1[..3]).cross(Vec3::from_slice(&t.e2[..3]));
            hits += 1;
            back += usize::from(normal.dot(dir) > 0.0);
        }
    }
    back as f32 / hits.max(1) as f32
}

/// The least distance to the model, as a share of the bounds' diagonal, of a point the enclosure is probed
/// from: a point on or right beside a surface sees that surface in half the directions, whatever the model.
pub const PROBE_CLEARANCE: f32 = 0.02;

/// The point the enclosure is probed from: the middle of `bounds`, or, when that lies inside a solid (the
/// Dragon's body on its floor) or touches a surface (a logo hung in the middle of a Cornell box, whose every
/// probe ray hit it at once), the first of a few points above and around it that does not. When every one
/// seems to (a room modelled with its faces turned outwards), the middle. None without triangles or bounds.
pub fn open_middle(bvh: &Bvh, bounds: &Aabb) -> Option<Vec3> {
    if !(bounds.min.is_finite() && bounds.max.is_finite()) || bvh.triangles.is_empty() {
        return None;
    }
    let (c, size) = (bounds.center(), bounds.size());
    let diagonal = size.length().max(1e-6);
    let candidates = [
        Vec3::ZERO,
        Vec3::new(0.0, 0.25, 0.0),
        Vec3::new(0.0, 0.4, 0.0),
        Vec3::new(0.3, 0.0, 0.0),
        Vec3::new(-0.3, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 0.3),
        Vec3::new(0.0, 0.0, -0.3),
    ];
    let open = candidates
        .iter()
        .map(|o| c + *o * size)
        .find(|&p| back_face_share(bvh, p, diagonal) <= 0.5 && probe(bvh, p, diagonal).1 >= PROBE_CLEARANCE * diagonal);
    Some(open.unwrap_or(c))
}

/// Whether the model in `bounds` encloses its middle (an interior to be seen from inside): probed from
/// [`open_middle`], so that a model whose body fills the middle of its bounds is not taken for a room.
pub fn is_interior(bvh: &Bvh, bounds: &Aabb) -> bool {
    let Some(point) = open_middle(bvh, bounds) else { return false };
    let diagonal = bounds.size().length().max(1e-6);
    probe(bvh, point, diagonal).0 >= ENCLOSED_SHARE
}

/// The share of all the probe directions from [`open_middle`] that must hit the model for [`is_enclosed`]: the
/// Cornell box (closed above, open at the front) 0.84, an object on a floor 0.44-0.66.
pub const CLOSED_SHARE: f32 = 0.8;

/// Whether cameras around the bounds would see mostly the outside of the model's walls: an interior
/// ([`is_interior`]) or a room closed above and open on one side ([`CLOSED_SHARE`] of all directions, the
/// Cornell box). INSM's `auto` placement puts its cameras inside such a model.
pub fn is_enclosed(bvh: &Bvh, bounds: &Aabb) -> bool {
    let Some(point) = open_middle(bvh, bounds) else { return false };
    let diagonal = bounds.size().length().max(1e-6);
    probe(bvh, point, diagonal).0 >= ENCLOSED_SHARE || enclosed_share(bvh, point, diagonal) >= CLOSED_SHARE
}

/// The share of all the probe directions (up as well as down) in which a ray from `point` hits the model
/// within `t_max`: a room closed above and open on one side (a Cornell box) is enclosed by most of them.
pub fn enclosed_share(bvh: &Bvh, point: Vec3, t_max: f32) -> f32 {
    let hits = directions().filter(|&d| closest_hit_cpu(bvh, point, d, t_max).is_some()).count();
    hits as f32 / PROBE_DIRECTIONS as f32
}

/// The share of near-horizontal rays (at most [`OPEN_SIDE_SECTOR`] degrees off `side`'s azimuth, elevations
/// from a little below to a little above the horizon) from `point` that leave the model within `t_max`.
pub fn miss_share_towards(bvh: &Bvh, point: Vec3, side: Vec3, t_max: f32) -> f32 {
    let side_azimuth = side.z.atan2(side.x);
    let (mut rays, mut misses) = (0, 0);
    for step in -8..=8 {
        let azimuth = side_azimuth + (step as f32 / 8.0 * OPEN_SIDE_SECTOR).to_radians();
        for y in [-0.3f32, -0.15, 0.0, 0.15] {
            let r = (1.0 - y * y).sqrt();
            let dir = Vec3::new(r * azimuth.cos(), y, r * azimuth.sin());
            rays += 1;
            misses += usize::from(closest_hit_cpu(bvh, point, dir, t_max).is_none());
        }
    }
    misses as f32 / rays as f32
}

/// Half the width of the sector [`open_side`] looks through, in degrees.
pub const OPEN_SIDE_SECTOR: f32 = 40.0;

/// The share of a side's near-horizontal rays that must leave the model for that side to be open.
pub const OPEN_SIDE_SHARE: f32 = 0.5;

/// The side (+X, -X, +Z or -Z) through which an enclosed model is open, when one is: a Cornell box's missing
/// front wall, a stage. Seen from [`open_middle`]; the most open side when several are (a hall open at both
/// ends).
pub fn open_side(bvh: &Bvh, bounds: &Aabb) -> Option<Vec3> {
    let point = open_middle(bvh, bounds)?;
    open_side_from(bvh, point, bounds.size().length().max(1e-6))
}

/// [`open_side`] seen from `point`, rays up to `diagonal` long.
fn open_side_from(bvh: &Bvh, point: Vec3, diagonal: f32) -> Option<Vec3> {
    [Vec3::Z, Vec3::X, Vec3::NEG_X, Vec3::NEG_Z]
        .into_iter()
        .map(|side| (miss_share_towards(bvh, point, side, diagonal), side))
        .filter(|(share, _)| *share >= OPEN_SIDE_SHARE)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, side)| side)
}

/// The first view of a model without a camera: inside an interior ([`interior_view`]); from the open side of a
/// room open on one side (a Cornell box whose probe rays mostly hit it, but whose front is missing); else None
/// (keep the framing from +Z).
pub fn first_view(bvh: &Bvh, bounds: &Aabb, fov_y: f32) -> Option<Camera> {
    // The probe point and the enclosure once, for both questions.
    let point = open_middle(bvh, bounds)?;
    let diagonal = bounds.size().length().max(1e-6);
    if probe(bvh, point, diagonal).0 < ENCLOSED_SHARE {
        return None;
    }
    match open_side_from(bvh, point, diagonal) {
        Some(side) => Some(Camera::framing_from(bounds, side)),
        None => inside_view(bvh, bounds, fov_y),
    }
}

/// A camera inside the interior in `bounds`, or None when the model is not one (keep the outside view).
pub fn interior_view(bvh: &Bvh, bounds: &Aabb, fov_y: f32) -> Option<Camera> {
    if !is_interior(bvh, bounds) {
        return None;
    }
    inside_view(bvh, bounds, fov_y)
}

/// The camera of [`interior_view`], for bounds already known to hold an interior.
fn inside_view(bvh: &Bvh, bounds: &Aabb, fov_y: f32) -> Option<Camera> {
    let size = bounds.size();
    let center = bounds.center();
    let diagonal = size.length();
    // The longest horizontal axis, walked from one end towards the middle.
    let axis = if size.x >= size.z { Vec3::X } else { Vec3::Z };
    let half = 0.5 * axis.dot(size);
    let mut best: Option<(f32, Vec3)> = None;
    for along in [-0.6f32, -0.45, -0.3, 0.6, 0.45, 0.3, 0.0] {
        for height in [0.3f32, 0.2, 0.45] {
            let p = center + axis * (along * half) + Vec3::Y * ((height - 0.5) * size.y);
            let (_, clearance) = probe(bvh, p, diagonal);
            // Prefer the first candidates (a long view from near an end), as long as there is room around.
            let score = clearance / diagonal;
            if score >= 0.04 {
                best = Some((score, p));
                break;
            }
            if best.is_none_or(|(s, _)| score > s) {
                best = Some((score, p));
            }
        }
        if best.is_some_and(|(s, _)| s >= 0.04) {
            break;
        }
    }
    let (score, position) = best?;
    // Look along the axis towards the middle (from the middle itself: towards the far end), level.
    let towards = if axis.dot(position - center) > 0.0 { -axis } else { axis };
    let target = position + towards * half.max(1e-3);
    let near = (score * diagonal * 0.05).max(diagonal * 1e-5);
    Some(Camera::look_at(position, target, fov_y, near, diagonal * 1.5))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The six faces of the box from `min` to `max` as triangles (a closed room), or five (open at the top).
    fn room(min: Vec3, max: Vec3, closed: bool) -> Vec<[Vec3; 3]> {
        let c = |x: usize, y: usize, z: usize| Vec3::new([min.x, max.x][x], [min.y, max.y][y], [min.z, max.z][z]);
        let quads = [
            [c(0, 0, 0), c(1, 0, 0), c(1, 0, 1), c(0, 0, 1)], // floor
            [c(0, 1, 0), c(1, 1, 0), c(1, 1, 1), c(0, 1, 1)], // roof
            [c(0, 0, 0), c(0, 1, 0), c(0, 1, 1), c(0, 0, 1)],
            [c(1, 0, 0), c(1, 1, 0), c(1, 1, 1), c(1, 0, 1)],
            [c(0, 0, 0), c(1, 0, 0), c(1, 1, 0), c(0, 1, 0)],
            [c(0, 0, 1), c(1, 0, 1), c(1, 1, 1), c(0, 1, 1)],
        ];
        quads
            .iter()
            .enumerate()
            .filter(|(i, _)| closed || *i != 1)
            .flat_map(|(_, q)| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect()
    }

    #[test]
    fn a_room_is_seen_from_inside_and_an_object_from_outside() {
        let (min, max) = (Vec3::new(-10.0, 0.0, -4.0), Vec3::new(10.0, 6.0, 4.0));
        let bounds = Aabb { min, max };
        let bvh = Bvh::build(&room(min, max, true));
        let cam = interior_view(&bvh, &bounds, 0.9).expect("a closed room is an interior");
        let p = cam.position;
        assert!(p.x > min.x && p.x < max.x && p.y > min.y && p.y < max.y && p.z > min.z && p.z < max.z, "{p}");
        assert!(cam.forward().x.abs() > 0.99, "looks along the room's long axis: {}", cam.forward());
        // A courtyard open to the sky is still an interior (most directions hit a wall or the floor).
        let courtyard = Bvh::build(&room(min, max, false));
        assert!(is_interior(&courtyard, &bounds));
        // A floor with a block on it is an object: most rays from the middle of its bounds miss.
        let mut floor = room(Vec3::new(-10.0, 0.0, -10.0), Vec3::new(10.0, 0.01, 10.0), true);
        floor.extend(room(Vec3::new(5.0, 0.0, 5.0), Vec3::new(7.0, 3.0, 7.0), true));
        let object = Aabb { min: Vec3::new(-10.0, 0.0, -10.0), max: Vec3::new(10.0, 3.0, 10.0) };
        assert!(interior_view(&Bvh::build(&floor), &object, 0.9).is_none());
        assert!(interior_view(&Bvh::build(&[]), &object, 0.9).is_none(), "no triangles: keep the framing");
    }

    /// `room` with every triangle turned the other way.
    fn flipped(triangles: Vec<[Vec3; 3]>) -> Vec<[Vec3; 3]> {
        triangles.into_iter().map(|[a, b, c]| [a, c, b]).collect()
    }

    /// `triangles` each turned to face away from `centre` (a solid's faces, seen from outside).
    fn outwards(triangles: Vec<[Vec3; 3]>, centre: Vec3) -> Vec<[Vec3; 3]> {
        let facing_out = |[a, b, c]: [Vec3; 3]| (b - a).cross(c - a).dot((a + b + c) / 3.0 - centre) > 0.0;
        triangles.into_iter().map(|t| if facing_out(t) { t } else { [t[0], t[2], t[1]] }).collect()
    }

    #[test]
    fn a_solid_in_the_middle_of_its_bounds_is_probed_from_the_open_and_a_room_open_at_the_front_is_enclosed() {
        // A solid block filling the middle of a floor's bounds (the Dragon's body): its middle lies inside the
        // block, where every ray hits a back face; the probe moves above it, and the model is an object.
        let (min, max) = (Vec3::new(-10.0, 0.0, -10.0), Vec3::new(10.0, 8.0, 10.0));
        let mut model = room(Vec3::new(-10.0, -0.01, -10.0), Vec3::new(10.0, 0.0, 10.0), true);
        // The block's faces turned outwards (a solid): from its middle every ray hits a back face.
        model.extend(outwards(room(Vec3::new(-3.0, 0.0, -3.0), Vec3::new(3.0, 5.0, 3.0), true), Vec3::Y * 2.5));
        let bvh = Bvh::build(&model);
        let bounds = Aabb { min, max };
        assert!(back_face_share(&bvh, bounds.center(), 50.0) > 0.9);
        let p = open_middle(&bvh, &bounds).unwrap();
        assert!(p.y > 5.0, "probed from above the block: {p}");
        assert!(back_face_share(&bvh, p, 50.0) <= 0.5);
        assert!(!is_interior(&bvh, &bounds) && !is_enclosed(&bvh, &bounds));
        // A room closed above and open at the front (a Cornell box): not an interior to frame from inside,
        // but enclosed (most directions hit it), whichever way its faces turn.
        let (rmin, rmax) = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 1.0));
        let open_front: Vec<[Vec3; 3]> =
            room(rmin, rmax, true).into_iter().filter(|t| t.iter().any(|v| v.z < 0.999)).collect();
        let rbounds = Aabb { min: rmin, max: rmax };
        let inwards = flipped(outwards(open_front, Vec3::Y));
        for tris in [inwards.clone(), flipped(inwards)] {
            let bvh = Bvh::build(&tris);
            assert!(is_enclosed(&bvh, &rbounds));
        }
        // A closed room whose faces turn outwards (every probe point sees back faces) is still an interior, as
        // is one whose faces turn inwards.
        let out = outwards(room(min, max, true), bounds.center());
        assert!(back_face_share(&Bvh::build(&out), bounds.center(), 50.0) > 0.9);
        assert!(is_interior(&Bvh::build(&out), &bounds));
        assert!(is_interior(&Bvh::build(&flipped(out)), &bounds));
    }

    #[test]
    fn a_room_open_on_one_side_is_seen_from_that_side_and_a_closed_one_from_inside() {
        // A room whose floor is a shallow pool (the Cornell box with water): low rays hit the floor, so it is an
        // interior, but its -X wall is missing, and a camera inside near one end looked out of that opening.
        let (min, max) = (Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 3.0, 2.0));
        let bounds = Aabb { min, max };
        let mut tris: Vec<[Vec3; 3]> =
            room(min, max, true).into_iter().filter(|t| t.iter().any(|v| v.x > -1.999)).collect();
        tris.extend(
            room(Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 1.2, 2.0), true)
                .into_iter()
                .take(2)
                .map(|t| t.map(|v| v + Vec3::Y * 1.2)),
        );
        let bvh = Bvh::build(&tris);
        assert!(is_interior(&bvh, &bounds));
        assert_eq!(open_side(&bvh, &bounds), Some(Vec3::NEG_X));
        let cam = first_view(&bvh, &bounds, 0.9).expect("a camera at the opening");
        assert!(cam.position.x < min.x, "outside the open side: {}", cam.position);
        assert!(cam.forward().x > 0.9, "looking in: {}", cam.forward());
        // Closed all round: no open side, the camera inside as before.
        let closed = Bvh::build(&room(Vec3::new(-10.0, 0.0, -4.0), Vec3::new(10.0, 6.0, 4.0), true));
        let closed_bounds = Aabb { min: Vec3::new(-10.0, 0.0, -4.0), max: Vec3::new(10.0, 6.0, 4.0) };
        assert_eq!(open_side(&closed, &closed_bounds), None);
        let inside = first_view(&closed, &closed_bounds, 0.9).expect("an interior");
        assert_eq!(Some(inside), interior_view(&closed, &closed_bounds, 0.9));
    }

    #[test]
    fn the_probe_moves_off_a_surface_in_the_middle_of_the_bounds() {
        // A small plate hung just under the middle of a room open at the front (the glTF Cornell box's logo,
        // which the middle of its bounds touches): probed from there every ray downwards hit the plate at once,
        // and the room passed for a closed interior, seen from inside.
        let (min, max) = (Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 3.0, 2.0));
        let bounds = Aabb { min, max };
        let open_front = room(min, max, true).into_iter().filter(|t| t.iter().any(|v| v.z < 1.999)).collect();
        let mut tris = flipped(outwards(open_front, bounds.center()));
        let plate = |x: f32, z: f32| Vec3::new(x, 1.499, z);
        tris.push([plate(-0.3, -0.3), plate(0.3, 0.3), plate(0.3, -0.3)]);
        tris.push([plate(-0.3, -0.3), plate(-0.3, 0.3), plate(0.3, 0.3)]);
        let (share, nearest) = probe(&Bvh::build(&tris), bounds.center(), 10.0);
        assert!(nearest < 2e-3 && share >= ENCLOSED_SHARE, "the middle touches the plate: {nearest}, {share}");
        let bvh = Bvh::build(&tris);
        let p = open_middle(&bvh, &bounds).unwrap();
        assert!(probe(&bvh, p, 10.0).1 >= PROBE_CLEARANCE * bounds.size().length(), "probed away from the plate: {p}");
        assert!(first_view(&bvh, &bounds, 0.9).is_none_or(|c| c.position.z > max.z), "seen from the open front");
    }
}
