//! Step 5 VAL by VAL: which VALs can light a pixel at all, and each VAL's VPLs listed together.
//!
//! The paper sums all N VPLs at every pixel (section 4: `L(x) ~ sum_i L_i(x) V~_C(i)(x)`). Without
//! interleaving the gather (`val/gather.wgsl`, `sum_by_val`) walks the VALs and their member lists instead, and
//! skips a VAL none of whose VPLs can light the pixel, so its members are never evaluated. A deviation in cost
//! only (the same sum), beyond the paper: at 320x180 on Sponza the loop over 1,024 VPLs was about 40 % of the
//! visibility pass (docs/techniques/val.md, "skipping VALs that cannot light a pixel").
//!
//! VPL `i` (position `x_i`, normal `n_i`) lights receiver `p` (normal `n_p`) only where `cos_i = n_i . w > 0`
//! and `cos_x = -n_p . w > 0`, `w = (p - x_i) / |p - x_i|` (`vpl_term` in shaders/vpl_common.wgsl). For a VAL
//! with map centre `c`, its members within `r` of `c`, their normals within `theta` of the axis `a` and at most
//! `h` behind `c` along it (`h = max_i a . (c - x_i)`):
//! - receiver side: `n_p . (x_i - p) <= n_p . (c - p) + r`, so nothing lights `p` when that is `<= 0`;
//! - emitter side: writing `n_i = cos(alpha) a + t` with `|t| = sin(alpha) <= sin(theta)` and
//!   `X = a . (p - c) + h >= a . (p - x_i)`, `n_i . (p - x_i) <= B = (X >= 0 ? X : X cos(theta)) + sin(theta)
//!   (|p - c| + r)` (for `theta` below 90 degrees), and `|p - x_i| >= |p - c| - r`, so every member meets `p` at
//!   `cos_i <= B / (|p - c| - r)`. The VAL is skipped when that is at most [`CULL_COSINE`]: on a floor lit by
//!   VPLs on the same floor `cos_i` is zero but for rounding, which a bound of exactly zero would never skip.

use glam::Vec3;

use crate::vpl::Vpl;

/// A VAL whose every VPL meets the pixel at a cosine at most this is skipped (its light there is at most this
/// share of the same VPLs' head-on light); the image changes by less than rounding (measured in the test of
/// `core/tests/val.rs` and in docs/techniques/val.md).
pub const CULL_COSINE: f32 = 1e-3;

/// The VPLs of every (batch, VAL) pair together: `order` holds VPL indices sorted by batch (`i / batch_size`)
/// and then by VAL; `ranges[b * vals + m]` is `[start, count]` of batch `b`'s members of VAL `m` in `order`.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct MemberLists {
    pub order: Vec<u32>,
    pub ranges: Vec<[u32; 2]>,
}

/// Counting sort of the VPLs by (batch, VAL); a VPL assigned past `vals` goes to the last VAL, as the gather's
/// `min(C(i), MAX_VALS - 1)` does.
pub fn member_lists(assignment: &[u32], vals: usize, batch_size: usize) -> MemberLists {
    let batch_size = batch_size.max(1);
    let vals = vals.max(1);
    let batches = assignment.len().div_ceil(batch_size);
    let key = |i: usize| (i / batch_size) * vals + (assignment[i] as usize).min(vals - 1);
    let mut counts = vec![0u32; batches * vals];
    for i in 0..assignment.len() {
        counts[key(i)] += 1;
    }
    let mut ranges = Vec::with_capacity(counts.len());
    let mut start = 0u32;
    for &c in &counts {
        ranges.push([start, c]);
        start += c;
    }
    let mut next: Vec<u32> = ranges.iter().map(|r| r[0]).collect();
    let mut order = vec![0u32; assignment.len()];
    for i in 0..assignment.len() {
        let k = key(i);
        order[next[k] as usize] = i as u32;
        next[k] += 1;
    }
    MemberLists { order, ranges }
}

/// One VAL's bounds, gathered VPL by VPL: the radius of its VPLs' sphere about the map's centre, and their
/// normal cone about the axis with how far they lie behind the centre along it.
#[derive(Clone, Copy, Debug)]
struct Reach {
    centre: Vec3,
    axis: Vec3,
    radius: f32,
    cos_theta: f32,
    sin_theta: f32,
    h: f32,
}

impl Reach {
    fn new(centre: Vec3, axis: Vec3) -> Reach {
        Reach { centre, axis, radius: 0.0, cos_theta: f32::INFINITY, sin_theta: 0.0, h: f32::NEG_INFINITY }
    }

    fn add(&mut self, position: Vec3, normal: Vec3) {
        let along = normal.dot(self.axis);
        self.radius = self.radius.max(position.distance(self.centre));
        self.cos_theta = self.cos_theta.min(along);
        // The normal's part across the axis, measured (not sqrt(1 - cos^2), whose rounding alone is 1e-3).
        self.sin_theta = self.sin_theta.max((normal - along * self.axis).length());
        self.h = self.h.max(self.axis.dot(self.centre - position));
    }

    /// `[cos(theta), sin(theta), h, 1]`, or all zero (no emitter test) when the normals spread 90 degrees or
    /// more from the axis or there are no members.
    fn cone(&self) -> [f32; 4] {
        let (c, s, h) = (self.cos_theta, self.sin_theta, self.h);
        if c.is_nan() || c <= 0.0 || !h.is_finite() || !s.is_finite() {
            return [0.0; 4];
        }
        // Rounded outward: a bound a hair too loose skips a little less, never a VPL that lights the pixel.
        [(c - 1e-6).max(0.0), (s + 1e-6).min(1.0), h + 1e-6 * (1.0 + h.abs()), 1.0]
    }
}

/// One VAL's emitter-side bound: `[cos(theta), sin(theta), h, 1]`, or all zero (no emitter test) when its
/// normals spread 90 degrees or more from the axis or it has no members.
pub fn cone_bound(members: impl Iterator<Item = (Vec3, Vec3)>, centre: Vec3, axis: Vec3) -> [f32; 4] {
    let mut reach = Reach::new(centre, axis);
    for (position, normal) in members {
        reach.add(position, normal);
    }
    reach.cone()
}

/// Each VAL's bounds for [`may_light`], in one pass over the VPLs: the radius of its VPLs' sphere about its
/// map's centre, widened by `pad` for rounding, and its normal cone about `axes[k]` ([`cone_bound`]).
/// `assignment[i]` is VPL `i`'s VAL; one past the VALs bounds nothing.
pub fn val_bounds(vpls: &[Vpl], assignment: &[u32], centres: &[Vec3], axes: &[Vec3], pad: f32) -> Vec<(f32, [f32; 4])> {
    let mut reach: Vec<Reach> = centres.iter().zip(axes).map(|(&c, &a)| Reach::new(c, a)).collect();
    for (v, &k) in vpls.iter().zip(assignment) {
        if let Some(r) = reach.get_mut(k as usize) {
            r.add(v.position, v.normal);
        }
    }
    reach.iter().map(|r| (r.radius + pad, r.cone())).collect()
}

/// Whether any VPL of a VAL (map centre `centre`, members within `radius`, emitter bound `cone` from
/// [`cone_bound`], axis `axis`) can light receiver `p` with normal `n_p`: the CPU twin of `may_light` in
/// `val/gather.wgsl`.
pub fn may_light(centre: Vec3, radius: f32, axis: Vec3, cone: [f32; 4], p: Vec3, n_p: Vec3) -> bool {
    let to_centre = centre - p;
    if n_p.dot(to_centre) + radius <= 0.0 {
        return false;
    }
    if cone[3] > 0.5 {
        let x = axis.dot(-to_centre) + cone[2];
        let distance = to_centre.length();
        let b = if x >= 0.0 { x } else { x * cone[0] } + cone[1] * (distance + radius);
        if b <= CULL_COSINE * (distance - radius) {
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::TestRng as Rng;

    #[test]
    fn member_lists_hold_every_vpl_once_in_its_batch_and_val() {
        let assignment: Vec<u32> = (0..103u32).map(|i| (i * 7 + i / 5) % 9).collect();
        for batch_size in [1, 10, 64, 103, 1000] {
            let lists = member_lists(&assignment, 9, batch_size);
            let mut seen = vec![false; assignment.len()];
            for (k, &[start, count]) in lists.ranges.iter().enumerate() {
                let (b, m) = (k / 9, k % 9);
                for &i in &lists.order[start as usize..(start + count) as usize] {
                    assert_eq!(assignment[i as usize] as usize, m, "VPL {i} listed under another VAL");
                    assert_eq!(i as usize / batch_size, b, "VPL {i} listed under another batch");
                    assert!(!seen[i as usize], "VPL {i} listed twice");
                    seen[i as usize] = true;
                }
            }
            assert!(seen.iter().all(|&s| s), "a VPL missing (batch size {batch_size})");
        }
        // Past the last VAL: listed under the last one, as the gather clamps it.
        let lists = member_lists(&[0, 5, 1], 2, 8);
        assert_eq!(lists.ranges, vec![[0, 1], [1, 2]]);
    }

    #[test]
    fn val_bounds_hold_each_vals_members_and_ignore_an_unknown_val() {
        let vpl = |x: f32, n: Vec3| Vpl {
            position: Vec3::new(x, 0.0, 0.0),
            normal: n,
            flux: Vec3::ONE,
            light: 0,
            from: Vec3::ZERO,
        };
        let vpls = [vpl(0.0, Vec3::Y), vpl(2.0, Vec3::Y), vpl(5.0, Vec3::X), vpl(9.0, Vec3::Z)];
        // VPL 3 names a VAL that does not exist: it bounds nothing.
        let bounds =
            val_bounds(&vpls, &[0, 0, 1, 7], &[Vec3::ZERO, Vec3::new(5.0, 0.0, 0.0)], &[Vec3::Y, Vec3::X], 0.5);
        assert_eq!(bounds.len(), 2);
        assert_eq!(bounds[0].0, 2.5, "the radius reaches the farthest member, plus the pad");
        assert_eq!(bounds[1].0, 0.5);
        assert_eq!(bounds[0].1[3], 1.0, "normals along the axis: a cone");
        assert!(bounds[0].1[0] > 0.999 && bounds[0].1[1] < 1e-5);
    }

    #[test]
    fn a_skipped_val_has_no_vpl_that_lights_the_pixel_and_a_floor_skips_its_own_vals() {
        let mut rng = Rng(0x9e3779b97f4a7c15);
        let mut skipped = 0;
        for _ in 0..400 {
            // A VAL: members around a centre, normals within a random cone of the axis.
            let axis = rng.unit();
            let spread = rng.next() * 1.2;
            let centre = (Vec3::new(rng.next(), rng.next(), rng.next()) - 0.5) * 10.0;
            let members: Vec<(Vec3, Vec3)> = (0..12)
                .map(|_| {
                    let position = centre + rng.unit() * rng.next() * 1.5;
                    let normal = (axis + rng.unit() * spread * rng.next()).normalize();
                    (position, normal)
                })
                .collect();
            let radius = members.iter().map(|(x, _)| x.distance(centre)).fold(0.0, f32::max);
            let cone = cone_bound(members.iter().copied(), centre, axis);
            for _ in 0..200 {
                let p = centre + (Vec3::new(rng.next(), rng.next(), rng.next()) - 0.5) * 20.0;
                let n_p = rng.unit();
                if may_light(centre, radius, axis, cone, p, n_p) {
                    continue;
                }
                skipped += 1;
                for &(x, n) in &members {
                    let w = (p - x).normalize();
                    let (cos_i, cos_x) = (n.dot(w), -n_p.dot(w));
                    assert!(
                        cos_i <= CULL_COSINE || cos_x <= 0.0,
                        "skipped a VAL whose VPL meets the pixel at cos_i {cos_i}, cos_x {cos_x}"
                    );
                }
            }
        }
        assert!(skipped > 10_000, "only {skipped} of 80,000 receivers skipped a VAL: the bound is too loose");

        // VPLs on a floor never light the floor (cos_i is 0): every floor pixel skips every floor VAL, though
        // each is within the other's tangent plane; a wall pixel facing the VAL keeps it.
        let up = Vec3::Y;
        let members: Vec<(Vec3, Vec3)> =
            (0..16).map(|k| (Vec3::new((k % 4) as f32 * 0.3, 0.0, (k / 4) as f32 * 0.3), up)).collect();
        let centre = Vec3::new(0.45, 0.0, 0.45);
        let cone = cone_bound(members.iter().copied(), centre, up);
        for k in 0..50 {
            let p = Vec3::new(k as f32 * 0.4 - 10.0, 0.0, 3.0 + k as f32 * 0.1);
            assert!(!may_light(centre, 0.7, up, cone, p, up), "floor pixel {p} keeps a floor VAL");
        }
        assert!(may_light(centre, 0.7, up, cone, Vec3::new(-3.0, 1.0, 0.0), Vec3::X));
    }
}
