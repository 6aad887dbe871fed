//! Section 5 of Dong et al. 2009: k-means clustering of N VPLs into M virtual area lights (VALs).
//!
//! 1. Initial centres (section 6, temporal coherence 5.2): VAL `k` starts at VPL `k * N / M`, every frame.
//! 2. Assignment: each VPL goes to the VAL of least `d = w_x * dx / L + w_a * da` (section 5.1), `dx` the
//!    position distance normalised by the scene length `L` (the diagonal of the scene's bounds, so `w_x` and
//!    `w_a` weigh metres and radians comparably whatever the scene's scale), `da` the angle between normals in
//!    radians. Ties go to the lower VAL index. (The technique passes `L` = a share of the diagonal, a tenth by
//!    default: the paper's raw metres correspond to about that in its scenes.)
//! 3. Update: each VAL's position and normal become the mean of its VPLs' (the normal renormalised); a VAL that
//!    lost all its VPLs keeps its last centre (it may win VPLs back in a later iteration).
//! 4. Steps 2-3 repeat `iterations` times; a final assignment gives the map `C` (VPL -> VAL).
//! 5. Each VAL's area: the 2D bounding rectangle of its VPLs projected on the plane perpendicular to its normal
//!    (section 6), as half-extents along two tangent axes.
//!
//! A pure, deterministic function. `warm_start` replaces step 1 with the previous frame's centres, the
//! variant the paper rejects (Fig. 8: VALs get lost when the light moves), kept for the temporal-coherence
//! measurement.

use glam::Vec3;

use crate::vpl::Vpl;

/// The clustering weights and iteration count.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KMeansParams {
    /// `M`, the number of VALs asked for (clamped to the VPL count).
    pub vals: usize,
    pub iterations: u32,
    pub w_x: f32,
    pub w_a: f32,
    /// `L`: position distances are divided by it.
    pub scene_length: f32,
}

/// One virtual area light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Val {
    pub position: Vec3,
    /// Unit normal (the VPLs' mean, renormalised).
    pub normal: Vec3,
    /// Tangent axes of the bounding rectangle (perpendicular to `normal`).
    pub axis_u: Vec3,
    pub axis_v: Vec3,
    /// Half-extents of the bounding rectangle along `axis_u`, `axis_v` (0 for one VPL or VPLs on a line).
    pub half_u: f32,
    pub half_v: f32,
    /// The rectangle's centre offset from `position` along the axes (the rectangle need not be centred).
    pub offset_u: f32,
    pub offset_v: f32,
    /// VPLs assigned to it.
    pub count: u32,
    /// Sum of its VPLs' flux.
    pub flux: Vec3,
}

impl Val {
    /// `Delta`, the sender's size in the penumbra estimate: the rectangle's diagonal.
    pub fn size(&self) -> f32 {
        2.0 * (self.half_u * self.half_u + self.half_v * self.half_v).sqrt()
    }
}

/// The result: the VALs and the map `C`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Clustering {
    pub vals: Vec<Val>,
    /// `C`: for each VPL, its VAL.
    pub assignment: Vec<u32>,
    /// VALs with at least one VPL.
    pub non_empty: usize,
}

/// The clustering distance `d` of a VPL (position, normal) to a centre.
pub fn distance(p: &KMeansParams, position: Vec3, normal: Vec3, centre: Vec3, centre_normal: Vec3) -> f32 {
    let dx = position.distance(centre) / p.scene_length.max(1e-20);
    let da = normal.dot(centre_normal).clamp(-1.0, 1.0).acos();
    p.w_x * dx + p.w_a * da
}

fn nearest(p: &KMeansParams, v: &Vpl, centres: &[(Vec3, Vec3)]) -> u32 {
    let mut best = (f32::INFINITY, 0u32);
    for (k, (c, n)) in centres.iter().enumerate() {
        let d = distance(p, v.position, v.normal, *c, *n);
        if d < best.0 {
            best = (d, k as u32);
        }
    }
    best.1
}

/// Cluster `vpls` (steps 1-5). `warm_start`: the previous frame's centres instead of step 1 (used only when
/// it has exactly `M` entries).
pub fn cluster(vpls: &[Vpl], params: &KMeansParams, warm_start: Option<&[(Vec3, Vec3)]>) -> Clustering {
    let n = vpls.len();
    let m = params.vals.min(n);
    if m == 0 {
        return Clustering { assignment: vec![0; n], ..Default::default() };
    }
    // Step 1.
    let mut centres: Vec<(Vec3, Vec3)> = match warm_start {
        Some(w) if w.len() == m => w.to_vec(),
        _ => (0..m).map(|k| (vpls[k * n / m].position, vpls[k * n / m].normal)).collect(),
    };
    let mut assignment = vec![0u32; n];
    for _ in 0..params.iterations {
        // Step 2.
        for (a, v) in assignment.iter_mut().zip(vpls) {
            *a = nearest(params, v, &centres);
        }
        // Step 3.
        let mut sums = vec![(Vec3::ZERO, Vec3::ZERO, 0u32); m];
        for (&a, v) in assignment.iter().zip(vpls) {
            let s = &mut sums[a as usize];
            s.0 += v.position;
            s.1 += v.normal;
            s.2 += 1;
        }
        for (c, s) in centres.iter_mut().zip(&sums) {
            if s.2 > 0 {
                *c = (s.0 / s.2 as f32, s.1.try_normalize().unwrap_or(c.1));
            }
        }
    }
    // Step 4: the final map C.
    for (a, v) in assignment.iter_mut().zip(vpls) {
        *a = nearest(params, v, &centres);
    }
    // Step 5: their bounding rectangles.
    let vals = vals_of(vpls, &centres, &assignment);
    let non_empty = vals.iter().filter(|v| v.count > 0).count();
    Clustering { vals, assignment, non_empty }
}

/// Step 5: VALs at `centres` (position, unit normal) with the members `assignment` gives them: counts, flux and
/// the bounding rectangle of the members' projection on the plane perpendicular to the normal (section 6).
pub fn vals_of(vpls: &[Vpl], centres: &[(Vec3, Vec3)], assignment: &[u32]) -> Vec<Val> {
    let m = centres.len();
    let mut vals: Vec<Val> = centres
        .iter()
        .map(|&(position, normal)| {
            let (axis_u, axis_v) = normal.any_orthonormal_pair();
            Val {
                position,
                normal,
                axis_u,
                axis_v,
                half_u: 0.0,
                half_v: 0.0,
                offset_u: 0.0,
                offset_v: 0.0,
                count: 0,
                flux: Vec3::ZERO,
            }
        })
        .collect();
    let mut bounds = vec![(f32::INFINITY, f32::NEG_INFINITY, f32::INFINITY, f32::NEG_INFINITY); m];
    for (&a, v) in assignment.iter().zip(vpls) {
        let val = &mut vals[a as usize];
        val.count += 1;
        val.flux += v.flux;
        let rel = v.position - val.position;
        let (s, t) = (rel.dot(val.axis_u), rel.dot(val.axis_v));
        let b = &mut bounds[a as usize];
        *b = (b.0.min(s), b.1.max(s), b.2.min(t), b.3.max(t));
    }
    for (val, b) in vals.iter_mut().zip(&bounds) {
        if val.count > 0 {
            val.half_u = 0.5 * (b.1 - b.0);
            val.half_v = 0.5 * (b.3 - b.2);
            val.offset_u = 0.5 * (b.1 + b.0);
            val.offset_v = 0.5 * (b.3 + b.2);
        }
    }
    vals
}

/// Each VAL's `Delta` from how its VPLs' flux spreads (`size=spread`, beyond the paper), instead of the diagonal
/// of their bounding rectangle (section 6): the side of the square whose uniform emission has the same
/// flux-weighted second moment in the VAL's plane, `sqrt(6)` times the RMS distance of the VPLs from their
/// flux-weighted centre (a uniform square of side `W` has `W^2 / 6`), at most the rectangle's diagonal. A VAL
/// whose flux comes from a small patch with a few faint VPLs far off gets the patch's size, and a square VAL its
/// side rather than its diagonal: the penumbra of a square light of side `W` is `W (d - z) / z` across it. Flux is
/// weighed by the sum of its RGB components. A VAL without VPLs (or with one) gets 0.
pub fn spread_sizes(clustering: &Clustering, vpls: &[Vpl]) -> Vec<f32> {
    let m = clustering.vals.len();
    let mut weight = vec![0.0f64; m];
    let mut first = vec![glam::DVec2::ZERO; m];
    let mut second = vec![0.0f64; m];
    for (v, &k) in vpls.iter().zip(&clustering.assignment) {
        let Some(val) = clustering.vals.get(k as usize) else { continue };
        let w = (v.flux.x + v.flux.y + v.flux.z) as f64;
        if !w.is_finite() || w <= 0.0 {
            continue;
        }
        let rel = v.position - val.position;
        let q = glam::DVec2::new(rel.dot(val.axis_u) as f64, rel.dot(val.axis_v) as f64);
        let k = k as usize;
        weight[k] += w;
        first[k] += q * w;
        second[k] += q.length_squared() * w;
    }
    clustering
        .vals
        .iter()
        .enumerate()
        .map(|(k, val)| {
            if weight[k] <= 0.0 {
                return 0.0;
            }
            let mean = first[k] / weight[k];
            let variance = (second[k] / weight[k] - mean.length_squared()).max(0.0);
            ((6.0 * variance).sqrt() as f32).min(val.size())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vpls(n: usize, seed: u32) -> Vec<Vpl> {
        // Two walls and a floor, quasi-random points on each.
        (0..n)
            .map(|i| {
                let u = crate::vpl::halton::radical_inverse(0, (i as u64) + 1 + seed as u64 * 1000);
                let v = crate::vpl::halton::radical_inverse(1, (i as u64) + 1 + seed as u64 * 1000);
                let (position, normal) = match i % 3 {
                    0 => (Vec3::new(u * 4.0, 0.0, v * 4.0), Vec3::Y),
                    1 => (Vec3::new(0.0, u * 3.0, v * 4.0), Vec3::X),
                    _ => (Vec3::new(u * 4.0, v * 3.0, 0.0), Vec3::Z),
                };
                Vpl { position, normal, flux: Vec3::splat(1.0), light: 0, from: Vec3::ZERO }
            })
            .collect()
    }

    fn params(m: usize) -> KMeansParams {
        KMeansParams { vals: m, iterations: 8, w_x: 0.7, w_a: 0.3, scene_length: 6.4 }
    }

    #[test]
    fn every_vpl_is_assigned_to_its_nearest_val() {
        let v = vpls(600, 0);
        let p = params(30);
        let c = cluster(&v, &p, None);
        assert_eq!(c.vals.len(), 30);
        for (i, vpl) in v.iter().enumerate() {
            let own = &c.vals[c.assignment[i] as usize];
            // The VALs' positions are the centres of the final assignment: brute force over all of them agrees.
            let d_own = distance(&p, vpl.position, vpl.normal, own.position, own.normal);
            let d_best = c
                .vals
                .iter()
                .map(|x| distance(&p, vpl.position, vpl.normal, x.position, x.normal))
                .fold(f32::INFINITY, f32::min);
            assert!(d_own <= d_best, "VPL {i}: own {d_own} best {d_best}");
        }
        // Counts add up, and planar clusters form: no VAL mixes normals of different walls.
        assert_eq!(c.vals.iter().map(|x| x.count).sum::<u32>(), 600);
        for (k, val) in c.vals.iter().enumerate() {
            let normals: Vec<Vec3> =
                v.iter().zip(&c.assignment).filter(|(_, &a)| a as usize == k).map(|(x, _)| x.normal).collect();
            assert!(normals.windows(2).all(|w| w[0] == w[1]), "VAL {k} mixes walls");
            assert!((val.normal.length() - 1.0).abs() < 1e-4 || val.count == 0);
        }
    }

    #[test]
    fn deterministic_and_no_val_is_lost_when_vpls_stay_put() {
        let v = vpls(1024, 1);
        let p = params(30);
        let a = cluster(&v, &p, None);
        assert_eq!(a, cluster(&v, &p, None));
        // Restarting from the same initial assignment: the same VALs, all non-empty, frame after frame.
        assert_eq!(a.non_empty, 30);
        let mut warm = a.clone();
        for _ in 0..5 {
            let centres: Vec<(Vec3, Vec3)> = warm.vals.iter().map(|x| (x.position, x.normal)).collect();
            warm = cluster(&v, &p, Some(&centres));
            assert_eq!(warm.non_empty, 30, "a VAL was lost");
        }
    }

    #[test]
    fn m_equal_to_n_gives_one_vpl_each_and_degenerate_inputs_are_defined() {
        let v = vpls(40, 2);
        let c = cluster(&v, &params(40), None);
        assert!(c.vals.iter().all(|x| x.count == 1));
        assert!(c.vals.iter().all(|x| x.half_u == 0.0 && x.half_v == 0.0 && x.size() == 0.0));
        // More VALs than VPLs: clamped to the VPL count.
        assert_eq!(cluster(&v, &params(100), None).vals.len(), 40);
        // Zero iterations: the initial centres, every VPL still assigned.
        let z = cluster(&v, &KMeansParams { iterations: 0, ..params(4) }, None);
        assert_eq!(z.vals.len(), 4);
        assert_eq!(z.vals[1].position, v[10].position);
        assert_eq!(z.vals.iter().map(|x| x.count).sum::<u32>(), 40);
        // VPLs on a line: a zero-width rectangle, finite.
        let line: Vec<Vpl> = (0..10)
            .map(|i| Vpl {
                position: Vec3::new(i as f32, 0.0, 0.0),
                normal: Vec3::Y,
                flux: Vec3::ONE,
                light: 0,
                from: Vec3::ZERO,
            })
            .collect();
        let l = cluster(&line, &params(1), None);
        assert!(l.vals[0].half_u.min(l.vals[0].half_v) < 1e-5 && l.vals[0].size() > 8.0);
        // Opposite normals in one cluster: the mean normal is still a unit vector (or the last one kept).
        let opposite: Vec<Vpl> = (0..2)
            .map(|i| Vpl {
                position: Vec3::ZERO,
                normal: if i == 0 { Vec3::Y } else { Vec3::NEG_Y },
                flux: Vec3::ONE,
                light: 0,
                from: Vec3::ZERO,
            })
            .collect();
        let o = cluster(&opposite, &params(1), None);
        assert!(o.vals[0].normal.is_finite() && (o.vals[0].normal.length() - 1.0).abs() < 1e-4);
        assert!(cluster(&[], &params(30), None).vals.is_empty());
    }

    #[test]
    fn a_vals_spread_size_is_the_side_of_its_uniform_square_and_ignores_faint_outliers() {
        let val = |vpls: &[Vpl]| {
            let assignment = vec![0u32; vpls.len()];
            let vals = vals_of(vpls, &[(Vec3::ZERO, Vec3::Y)], &assignment);
            Clustering { vals, assignment, non_empty: 1 }
        };
        let at = |x: f32, z: f32, flux: f32| Vpl {
            position: Vec3::new(x, 0.0, z),
            normal: Vec3::Y,
            flux: Vec3::splat(flux),
            light: 0,
            from: Vec3::ZERO,
        };
        // A 41 x 41 grid over a 2 m square: side 2 (the grid's variance is (n + 1) / (n - 1) of the continuum's),
        // the rectangle's diagonal 2 sqrt(2).
        let square: Vec<Vpl> =
            (0..41 * 41).map(|i| at((i % 41) as f32 / 20.0 - 1.0, (i / 41) as f32 / 20.0 - 1.0, 1.0)).collect();
        let c = val(&square);
        let spread = spread_sizes(&c, &square)[0];
        assert!((spread - 2.0 * (42.0f32 / 40.0).sqrt()).abs() < 1e-3, "{spread}");
        assert!((c.vals[0].size() - 2.0 * 2f32.sqrt()).abs() < 1e-4);
        // The same patch with one VPL of a thousandth of its flux 10 m away: the rectangle grows past 10 m, the
        // spread barely moves.
        let mut outlier = square.clone();
        outlier.push(at(10.0, 0.0, 1e-3 * square.len() as f32));
        let c = val(&outlier);
        let spread = spread_sizes(&c, &outlier)[0];
        assert!(c.vals[0].size() > 10.0 && spread < 2.4, "{} {spread}", c.vals[0].size());
        // One VPL, or none with flux: no size.
        assert_eq!(spread_sizes(&val(&square[..1]), &square[..1]), vec![0.0]);
        let dark: Vec<Vpl> = square.iter().map(|v| Vpl { flux: Vec3::ZERO, ..*v }).collect();
        assert_eq!(spread_sizes(&val(&dark), &dark), vec![0.0]);
    }
}
