//! Where each VAL's map stands (beyond the paper; `centre`, `docs/techniques/val.md`).
//!
//! The paper puts a VAL's paraboloid map at its VPLs' mean, moved off their surface along the VAL's normal
//! (section 5). The mean of VPLs on both sides of an arch floats in the open or sits inside a column (its
//! Fig. 7 fault), so a VAL of at most `max_members` VPLs stands at a *member* instead:
//!
//! 1. The VAL's members, nearest the mean first; each candidate's eye is the member moved `offset` along its
//!    own normal (a point just off a surface the VAL lies on). A member whose eye is not finite is no
//!    candidate; a VAL with none keeps the paper's centre.
//! 2. With a [`Clearance`] (the scene's BVH), the nearest candidate is probed: [`PROBES`] segments over the
//!    hemisphere about its normal, [`REACH`] of the maps' longest edge long. When one meets geometry, the
//!    members within [`NEIGHBOURHOOD`] of the VAL's size of it (at most [`CANDIDATES`]) are probed too and the
//!    one whose probes meet the least geometry wins (ties: nearer the mean). Why: a paraboloid map draws each
//!    triangle by projecting its corners and interpolating between them (depth and the near plane's clip
//!    too), which is exact only for a triangle small against its distance to the centre; the maps cut edges at
//!    `max_edge` (0.05 of the scene) and no finer, so a surface passing a few millimetres from the centre (the
//!    shared Cornell box with water's light fixture, a quad 1 cm below the ceiling, 6 mm from a ceiling VAL's
//!    nearest member, inside the VAL's near plane) is drawn as a blocker far from where it is and shadows a
//!    whole wall in rings (FLIP 0.0171 -> 0.0252 when that VAL appears at M = 42; with this step 0.0168).
//!
//! The probes' reach and the neighbourhood were chosen on the five real scenes (docs/techniques/val.md, "A map
//! beside a nearby surface"): a reach of a quarter of an edge or more moved centres that drew well enough and
//! raised the error at larger M on the water box; a tenth and a twentieth gave the same curve there.
//!
//! One pass over the VPLs gathers the small VALs' members; a frame casts [`PROBES`] rays per small VAL and, only
//! for a VAL whose nearest member is crowded, up to [`CANDIDATES`] times that.

use glam::Vec3;

use super::kmeans::Val;
use crate::vpl::Vpl;

/// The probes' length as a share of the maps' longest triangle edge (`max_edge`).
pub const REACH: f32 = 0.1;

/// Members probed as a crowded VAL's map centre (the nearest the mean).
pub const CANDIDATES: usize = 8;

/// Candidates stand within this share of the VAL's size (its rectangle's diagonal) of the member nearest the
/// mean: a map further off no longer stands for the VAL's middle (without it, on Sponza, VALs of two VPLs
/// metres apart traded one for the other: FLIP 0.0587 -> 0.0690 at M = 192 with a fifth of an edge's reach).
pub const NEIGHBOURHOOD: f32 = 0.25;

/// Probe segments per candidate, spread evenly in solid angle over its hemisphere (a Fibonacci spiral); the
/// grazing band (beyond 63 degrees from the normal), where a nearby surface beside the centre lies, gets 45 %.
pub const PROBES: usize = 32;

/// What the centre choice sees of the scene: `occluded(from, to)` is true when geometry lies between the two
/// points (the scene's BVH).
#[derive(Clone, Copy)]
pub struct Clearance<'a> {
    pub occluded: &'a dyn Fn(Vec3, Vec3) -> bool,
    /// The probes' length ([`REACH`] of the maps' longest triangle edge).
    pub reach: f32,
}

/// How many of the [`PROBES`] from `eye` over the hemisphere about `normal` meet geometry within `reach`.
fn crowding(eye: Vec3, normal: Vec3, clearance: &Clearance) -> usize {
    let (u, v) = normal.any_orthonormal_pair();
    const GOLDEN_ANGLE: f32 = 2.399_963;
    (0..PROBES)
        .filter(|&j| {
            let cos_t = 1.0 - (j as f32 + 0.5) / PROBES as f32;
            let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
            let (s, c) = (j as f32 * GOLDEN_ANGLE).sin_cos();
            let d = (u * c + v * s) * sin_t + normal * cos_t;
            (clearance.occluded)(eye, eye + d * clearance.reach)
        })
        .count()
}

/// Each VAL's map centre (module comment): for a VAL of at most `max_members` VPLs a member's eye (the nearest
/// the mean, or with a `clearance` the least crowded of at most [`CANDIDATES`] members within [`NEIGHBOURHOOD`]
/// of its size of that one); for a larger VAL, an empty one or one without a finite member, the mean moved
/// `offset` along the VAL's normal (the paper's). `assignment[i]` is VPL `i`'s VAL.
pub fn map_centres(
    vpls: &[Vpl],
    assignment: &[u32],
    vals: &[Val],
    max_members: usize,
    offset: f32,
    clearance: Option<&Clearance>,
) -> Vec<Vec3> {
    let small = |v: &Val| max_members > 0 && v.count as usize <= max_members;
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); vals.len()];
    for (i, &k) in assignment.iter().enumerate().take(vpls.len()) {
        if let Some((list, val)) = members.get_mut(k as usize).zip(vals.get(k as usize)) {
            if small(val) {
                list.push(i);
            }
        }
    }
    let eye = |i: usize| vpls[i].position + vpls[i].normal * offset;
    vals.iter()
        .zip(members)
        .map(|(v, mut list)| {
            list.retain(|&i| eye(i).is_finite() && vpls[i].normal.is_finite());
            list.sort_by(|&a, &b| {
                let da = vpls[a].position.distance_squared(v.position);
                da.total_cmp(&vpls[b].position.distance_squared(v.position))
            });
            let chosen = match (list.first(), clearance) {
                (None, _) => None,
                (Some(&first), None) => Some(first),
                (Some(&first), Some(c)) => {
                    let crowded = |i: usize| crowding(eye(i), vpls[i].normal, c);
                    let first_crowding = crowded(first);
                    if first_crowding == 0 {
                        Some(first)
                    } else {
                        // The least crowded; `min_by_key` keeps the first of equals, the nearer the mean.
                        let near_first =
                            |i: &&usize| vpls[**i].position.distance(vpls[first].position) <= v.size() * NEIGHBOURHOOD;
                        let rest =
                            list.iter().skip(1).filter(near_first).take(CANDIDATES - 1).map(|&i| (crowded(i), i));
                        let best = std::iter::once((first_crowding, first)).chain(rest).min_by_key(|&(n, _)| n);
                        best.map(|(_, i)| i)
                    }
                }
            };
            chosen.map_or(v.position + v.normal * offset, eye)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vpl(position: Vec3, normal: Vec3) -> Vpl {
        Vpl { position, normal, flux: Vec3::ONE, light: 0, from: Vec3::ZERO }
    }

    fn val_of(v: &[Vpl]) -> Val {
        let n = v.len() as f32;
        Val {
            position: v.iter().map(|x| x.position).sum::<Vec3>() / n,
            normal: v.iter().map(|x| x.normal).sum::<Vec3>().normalize(),
            axis_u: Vec3::X,
            axis_v: Vec3::Z,
            half_u: 1.0,
            half_v: 1.0,
            offset_u: 0.0,
            offset_v: 0.0,
            count: v.len() as u32,
            flux: Vec3::ONE,
        }
    }

    #[test]
    fn a_small_vals_map_stands_at_its_vpl_nearest_the_mean_just_off_its_own_surface() {
        // VPLs on a floor (x 0-2.9, facing up) and on a wall (x = 3.2, facing -x), one VAL: their mean floats
        // above the floor, in the open; the member centre is the floor VPL below it, moved off the floor.
        let floor = (0..30).map(|i| vpl(Vec3::new(0.1 * i as f32, 0.0, 0.0), Vec3::Y));
        let wall = (0..10).map(|i| vpl(Vec3::new(3.2, 0.1 * i as f32, 0.0), Vec3::NEG_X));
        let v: Vec<Vpl> = floor.chain(wall).collect();
        let val = val_of(&v);
        assert!(val.position.y > 0.05, "the mean floats: {}", val.position);
        // A second VAL with no VPLs keeps its mean.
        let empty = Val { position: Vec3::splat(9.0), count: 0, ..val };
        let assignment = vec![0u32; v.len()];
        let nearest = (0..v.len())
            .min_by(|&a, &b| v[a].position.distance(val.position).total_cmp(&v[b].position.distance(val.position)))
            .unwrap();
        assert_eq!(v[nearest].normal, Vec3::Y);
        let on_member = v[nearest].position + Vec3::Y * 0.01;
        let at_mean = val.position + val.normal * 0.01;
        let eyes = map_centres(&v, &assignment, &[val, empty], v.len(), 0.01, None);
        assert!((eyes[0] - on_member).length() < 1e-6, "{:?}", eyes[0]);
        assert_eq!(eyes[1], Vec3::splat(9.0) + val.normal * 0.01);
        // A VAL larger than the limit, or no member allowed at all: the paper's centre.
        assert_eq!(map_centres(&v, &assignment, &[val], v.len() - 1, 0.01, None)[0], at_mean);
        assert_eq!(map_centres(&v, &assignment, &[val], 0, 0.01, None)[0], at_mean);
        // A broken nearest member is no candidate: the next nearest stands in; with every member broken, the
        // paper's centre.
        let mut broken = v.clone();
        broken[nearest].normal = Vec3::NAN;
        let eye = map_centres(&broken, &assignment, &[val], v.len(), 0.01, None)[0];
        assert!(eye.is_finite() && eye != on_member && (eye - on_member).length() < 0.11, "{eye}");
        let all_broken: Vec<Vpl> = v.iter().map(|x| Vpl { position: Vec3::NAN, ..*x }).collect();
        assert_eq!(map_centres(&all_broken, &assignment, &[val], v.len(), 0.01, None)[0], at_mean);
    }

    /// A quad at height `y`, covering x < `edge` (any z): the light fixture under the ceiling.
    fn fixture_below(a: Vec3, b: Vec3, y: f32, edge: f32) -> bool {
        let d = b - a;
        if d.y.abs() < 1e-9 {
            return false;
        }
        let t = (y - a.y) / d.y;
        (0.0..=1.0).contains(&t) && a.x + t * d.x < edge
    }

    #[test]
    fn a_vals_map_leaves_a_member_beside_a_nearby_surface_for_one_with_clear_space_around_it() {
        // A ceiling (y = 1.59, facing down) patch of VPLs at x = 0.236 .. 0.50; a fixture 1 cm below the
        // ceiling covers x < 0.23. The member nearest the mean would stand 6 mm from the fixture's edge, 3 mm above
        // its plane (the shared Cornell box with water at M = 42).
        let v: Vec<Vpl> = [0.236f32, 0.30, 0.34, 0.38, 0.42, 0.50]
            .iter()
            .map(|&x| vpl(Vec3::new(x, 1.59, 0.0), Vec3::NEG_Y))
            .collect();
        let mut val = val_of(&v);
        val.position = Vec3::new(0.25, 1.59, 0.0); // pull the mean next to the crowded member
        let assignment = vec![0u32; v.len()];
        let offset = 0.007;
        let occluded = |a: Vec3, b: Vec3| fixture_below(a, b, 1.58, 0.23);
        let clear = Clearance { occluded: &occluded, reach: 0.16 };
        let without = map_centres(&v, &assignment, &[val], v.len(), offset, None)[0];
        assert!((without - Vec3::new(0.236, 1.583, 0.0)).length() < 1e-5, "{without}");
        assert!(
            crowding(without, Vec3::NEG_Y, &clear) >= 4,
            "the fixture beside it: {}",
            crowding(without, Vec3::NEG_Y, &clear)
        );
        let with = map_centres(&v, &assignment, &[val], v.len(), offset, Some(&clear))[0];
        assert!(with.x > 0.29, "moved away from the fixture: {with}");
        assert!(crowding(with, Vec3::NEG_Y, &clear) < crowding(without, Vec3::NEG_Y, &clear));
        // With nothing near, the nearest member stays (one probe round, no other candidate tried).
        let nothing = |_: Vec3, _: Vec3| false;
        let open = Clearance { occluded: &nothing, reach: 0.16 };
        assert_eq!(map_centres(&v, &assignment, &[val], v.len(), offset, Some(&open))[0], without);
        // Every candidate as crowded: the nearest stays too.
        let everything = |_: Vec3, _: Vec3| true;
        let shut = Clearance { occluded: &everything, reach: 0.16 };
        assert_eq!(map_centres(&v, &assignment, &[val], v.len(), offset, Some(&shut))[0], without);
    }
}
