//! The bisection's unit tests (`split.rs`).

use super::*;

/// A room corner: a floor, two walls and a column's face 1 m in front of one wall (same normal).
fn corner(n: usize) -> Vec<Vpl> {
    (0..n)
        .map(|i| {
            let u = crate::vpl::halton::radical_inverse(0, i as u64 + 1);
            let v = crate::vpl::halton::radical_inverse(1, i as u64 + 1);
            let (position, normal) = match i % 4 {
                0 => (Vec3::new(u * 4.0, 0.0, v * 4.0), Vec3::Y),
                1 => (Vec3::new(0.0, u * 3.0, v * 4.0), Vec3::X),
                2 => (Vec3::new(u * 4.0, v * 3.0, 0.0), Vec3::Z),
                _ => (Vec3::new(1.0 + u * 0.5, v * 3.0, 1.0), Vec3::Z),
            };
            Vpl { position, normal, flux: Vec3::ONE, light: 0, from: Vec3::ZERO }
        })
        .collect()
}

fn km(m: usize) -> KMeansParams {
    KMeansParams { vals: m, iterations: 10, w_x: 0.7, w_a: 0.3, scene_length: 0.64 }
}

fn sp(m: usize) -> SplitParams {
    SplitParams {
        vals: m,
        rank: Rank::Rule,
        gain_until: 0,
        max_cone: 30f32.to_radians(),
        max_depth: 0.1,
        iterations: 8,
        hidden_weight: 0.0,
    }
}

#[test]
fn a_split_keeps_every_vpl_in_exactly_one_val_and_never_exceeds_m() {
    let v = corner(800);
    for m in [1usize, 2, 3, 5, 8, 30, 100] {
        let base = kmeans::cluster(&v, &km(m.div_ceil(2)), None);
        let c = split(&v, &km(m), &sp(m), None, &base);
        assert!(c.vals.len() <= m && c.vals.len() >= base.non_empty.min(m), "M = {m}: {}", c.vals.len());
        assert_eq!(c.assignment.len(), v.len());
        assert!(c.assignment.iter().all(|&k| (k as usize) < c.vals.len()));
        // Counts are the memberships: each VPL counted once.
        assert_eq!(c.vals.iter().map(|x| x.count).sum::<u32>() as usize, v.len());
        for (k, val) in c.vals.iter().enumerate() {
            let members = c.assignment.iter().filter(|&&a| a as usize == k).count();
            assert_eq!(members as u32, val.count, "M = {m}, VAL {k}");
        }
        assert_eq!(c, split(&v, &km(m), &sp(m), None, &base), "not deterministic");
    }
}

/// `n` VPLs of `flux` facing up, spread evenly (Halton) over a `side` square on the floor from `origin`.
fn patch(n: usize, origin: Vec3, side: f32, flux: f32) -> impl Iterator<Item = Vpl> {
    (0..n).map(move |i| {
        let u = crate::vpl::halton::radical_inverse(0, i as u64 + 1);
        let v = crate::vpl::halton::radical_inverse(1, i as u64 + 1);
        let position = origin + Vec3::new(u * side, 0.0, v * side);
        Vpl { position, normal: Vec3::Y, flux: Vec3::splat(flux), light: 0, from: Vec3::ZERO }
    })
}

/// How many of `c`'s VALs hold the VPLs `patch` (one of two patches laid one after the other), asserting that no
/// VAL holds VPLs both in and out of it.
fn vals_holding(c: &Clustering, patch: std::ops::Range<usize>) -> usize {
    (0..c.vals.len())
        .filter(|&k| {
            let ids: Vec<usize> = (0..c.assignment.len()).filter(|&i| c.assignment[i] as usize == k).collect();
            let inside = ids.iter().filter(|i| patch.contains(i)).count();
            assert!(inside == 0 || inside == ids.len(), "VAL {k} mixes the patches");
            inside > 0
        })
        .count()
}

/// Two patches on one floor, far apart: `dim` VPLs of flux 0.01 over 4 m and `bright` VPLs of flux 10 over
/// 2 m. The unweighted error is the dim patch's; the light, and so the image's error, is the bright one's.
fn two_patches(dim: usize, bright: usize) -> Vec<Vpl> {
    patch(dim, Vec3::ZERO, 4.0, 0.01).chain(patch(bright, Vec3::new(20.0, 0.0, 0.0), 2.0, 10.0)).collect()
}

#[test]
fn the_val_carrying_the_most_light_is_bisected_first() {
    let (dim, bright) = (200, 20);
    let v = two_patches(dim, bright);
    let base = kmeans::cluster(&v, &km(2), None);
    // k-means keeps the patches apart: every VAL holds one patch only.
    let vals_on_bright = |c: &Clustering| vals_holding(c, dim..v.len());
    assert_eq!(vals_on_bright(&base), 1);
    let by = |rank: Rank| split(&v, &km(3), &SplitParams { rank, ..sp(3) }, None, &base);
    // Ranked by flux the bright patch is bisected; ranked by the unweighted error the dim one is.
    assert_eq!(vals_on_bright(&by(Rank::Flux)), 2);
    assert_eq!(vals_on_bright(&by(Rank::Rule)), 1);
    // NaN flux does not panic the ranking.
    let mut bad = v.clone();
    bad[0].flux = Vec3::NAN;
    assert_eq!(split(&bad, &km(3), &SplitParams { rank: Rank::Flux, ..sp(3) }, None, &base).vals.len(), 3);
}

#[test]
fn ranked_by_light_a_bright_compact_val_goes_before_a_dim_spread_one_of_larger_squared_error() {
    // A: 20 VPLs of flux 20 over 1 m (luminance 400); B: 100 VPLs of flux 1 over 3 m (luminance 100), far
    // apart on one floor. sum Y d: A's is 4/3 of B's (4 times the light, a third of the spread); sum Y d^2: B's
    // is 9/4 of A's. The light rank bisects A, the flux rank B.
    let v: Vec<Vpl> = patch(20, Vec3::ZERO, 1.0, 20.0).chain(patch(100, Vec3::new(20.0, 0.0, 0.0), 3.0, 1.0)).collect();
    let base = kmeans::cluster(&v, &km(2), None);
    let on_a = |c: &Clustering| vals_holding(c, 0..20);
    assert_eq!(on_a(&base), 1);
    let by = |rank: Rank| split(&v, &km(3), &SplitParams { rank, ..sp(3) }, None, &base);
    assert_eq!(on_a(&by(Rank::Light)), 2, "the light rank bisects the bright patch");
    assert_eq!(on_a(&by(Rank::Flux)), 1, "the flux rank bisects the spread patch");
    // The light rank keeps the split's invariants: every VPL in exactly one VAL, never more than M.
    for m in [1, 2, 5, 40, 120, 500] {
        let c = split(&v, &km(m), &SplitParams { rank: Rank::Light, ..sp(m) }, None, &base);
        assert!(c.vals.len() <= m.max(2));
        assert_eq!(c.vals.iter().map(|x| x.count).sum::<u32>() as usize, v.len());
    }
    // NaN flux does not panic the light rank either.
    let mut bad = v.clone();
    bad[3].flux = Vec3::NAN;
    assert_eq!(split(&bad, &km(3), &SplitParams { rank: Rank::Light, ..sp(3) }, None, &base).vals.len(), 3);
}

#[test]
fn a_val_whose_map_centre_cannot_see_its_vpls_is_bisected_first_with_a_hidden_weight() {
    // Two patches on one floor, far apart, with the same flux: A (x 0-4) spread a little wider than B (x 20-23.6),
    // so the flux rank bisects A; a wall across B's middle (the plane x = 21.85, just off its centre) hides
    // half of B's VPLs from B's map centre, so with a hidden weight B goes first.
    let v: Vec<Vpl> = patch(200, Vec3::ZERO, 4.0, 1.0).chain(patch(200, Vec3::new(20.0, 0.0, 0.0), 3.6, 1.0)).collect();
    let base = kmeans::cluster(&v, &km(2), None);
    // How many VALs B's VPLs are in.
    let on_b = |c: &Clustering| vals_holding(c, 200..400);
    assert_eq!(on_b(&base), 1, "k-means keeps the patches apart");
    let rays = std::cell::Cell::new(0usize);
    let wall = |a: Vec3, b: Vec3| {
        rays.set(rays.get() + 1);
        (a.x - 21.85) * (b.x - 21.85) < 0.0
    };
    let sight = Sight { occluded: &wall, offset: 0.01 };
    let with = |w: f32, sight: Option<&Sight>| {
        split(&v, &km(3), &SplitParams { rank: Rank::Flux, hidden_weight: w, ..sp(3) }, sight, &base)
    };
    // The flux rank alone, and a weight without a sight, cast no ray and bisect A.
    assert_eq!(on_b(&with(0.0, Some(&sight))), 1);
    assert_eq!(on_b(&with(2.0, None)), 1);
    assert_eq!(rays.get(), 0);
    // Weighted, B's hidden half makes it the next one bisected.
    let c = with(2.0, Some(&sight));
    assert_eq!(on_b(&c), 2);
    assert!(rays.get() > 0 && rays.get() <= 400, "one ray per member of each VAL tested: {}", rays.get());
    // A weight too small to outweigh A's larger error leaves the flux rank's pick.
    assert_eq!(on_b(&with(0.01, Some(&sight))), 1);
}

#[test]
fn a_large_vals_hidden_share_is_estimated_from_a_bounded_sample() {
    // 1,000 VPLs along a line, a wall hiding those past x = 7 from the centre (x = 5): 30 % hidden.
    let v: Vec<Vpl> = (0..1000)
        .map(|i| Vpl {
            position: Vec3::new(i as f32 / 100.0, 0.0, 0.0),
            normal: Vec3::Y,
            flux: Vec3::ONE,
            light: 0,
            from: Vec3::ZERO,
        })
        .collect();
    let g = group(&v, &km(1), (0..1000).collect());
    let rays = std::cell::Cell::new(0usize);
    let wall = |_: Vec3, b: Vec3| {
        rays.set(rays.get() + 1);
        b.x > 7.0
    };
    let h = hidden_share(&v, &g, &Sight { occluded: &wall, offset: 0.01 });
    assert!(rays.get() <= SIGHT_SAMPLES, "{} rays", rays.get());
    assert!((h - 0.3).abs() < 0.02, "hidden share {h}");
}

/// The sum of `Y d^2` over the VALs of `c`.
fn flux_error(v: &[Vpl], km: &KMeansParams, c: &Clustering) -> f32 {
    let mut lists: Vec<Vec<usize>> = vec![Vec::new(); c.vals.len()];
    for (i, &k) in c.assignment.iter().enumerate() {
        lists[k as usize].push(i);
    }
    lists.into_iter().filter(|l| !l.is_empty()).map(|l| group(v, km, l).flux_error).sum()
}

#[test]
fn ranked_by_gain_a_bisection_lowers_the_flux_weighted_error_most() {
    // Two surfaces far apart: a strip spread evenly over 4 m, and two tight patches 2.2 m apart. The strip
    // has the larger error (so the flux rank bisects it next), the patches the larger gain (a cut between
    // them leaves almost none; a cut of the strip leaves a quarter of its error).
    let vpl = |p: Vec3| Vpl { position: p, normal: Vec3::Y, flux: Vec3::ONE, light: 0, from: Vec3::ZERO };
    let mut v: Vec<Vpl> = (0..400).map(|i| vpl(Vec3::new(4.0 * i as f32 / 399.0, 0.0, 0.0))).collect();
    v.extend((0..400).map(|i| vpl(Vec3::new(20.0, 0.0, if i % 2 == 0 { 1.1 } else { -1.1 }))));
    let base = kmeans::cluster(&v, &km(1), None);
    let with = |m: usize, gain_until: usize| {
        split(&v, &km(m), &SplitParams { rank: Rank::Flux, gain_until, ..sp(m) }, None, &base)
    };
    // The first bisection has one candidate: the same either way (the strip from the patches).
    assert_eq!(flux_error(&v, &km(2), &with(2, 2)), flux_error(&v, &km(2), &with(2, 0)));
    let (g, f) = (flux_error(&v, &km(3), &with(3, 3)), flux_error(&v, &km(3), &with(3, 0)));
    assert!(g < 0.95 * f, "ranked by gain {g}, by flux {f}");
    // Past `gain_until` the flux rank decides; every VPL stays in exactly one VAL, at most M.
    assert_eq!(with(3, 2).assignment, with(3, 0).assignment);
    let w = corner(800);
    let corner_base = kmeans::cluster(&w, &km(1), None);
    for m in [1usize, 2, 5, 16, 40] {
        let c = split(&w, &km(m), &SplitParams { rank: Rank::Flux, gain_until: 16, ..sp(m) }, None, &corner_base);
        assert!(c.vals.len() <= m && c.assignment.len() == w.len(), "M = {m}");
        let members: u32 = c.vals.iter().map(|x| x.count).sum();
        assert_eq!(members as usize, w.len(), "M = {m}");
    }
}

#[test]
fn a_val_wider_than_the_cone_is_bisected_by_normal_whatever_its_rank() {
    // Small steps over a 4 m patch: treads (normal Y) and risers (normal X) interleaved, so position does
    // not tell them apart; only the cone rule splits them into the treads and the risers.
    let h = |d: u32, i: usize| crate::vpl::halton::radical_inverse(d, i as u64 + 1);
    let v: Vec<Vpl> = (0..400)
        .map(|i| Vpl {
            position: Vec3::new(h(0, i) * 4.0, 0.0, h(1, i) * 4.0),
            normal: if h(2, i) < 0.5 { Vec3::Y } else { Vec3::X },
            flux: Vec3::ONE,
            light: 0,
            from: Vec3::ZERO,
        })
        .collect();
    let one = kmeans::cluster(&v, &km(1), None);
    let pure = |c: &Clustering, k: u32| {
        let normals: Vec<Vec3> = (0..v.len()).filter(|&i| c.assignment[i] == k).map(|i| v[i].normal).collect();
        normals.windows(2).all(|w| w[0] == w[1])
    };
    let cone = SplitParams { rank: Rank::Flux, max_cone: 45f32.to_radians(), ..sp(2) };
    let c = split(&v, &km(2), &cone, None, &one);
    assert_eq!(c.vals.len(), 2);
    assert!(pure(&c, 0) && pure(&c, 1), "a VAL mixes treads and risers");
    // Without the cone rule (the depth rule and the paper's metric) both halves mix them.
    let off = SplitParams { max_cone: 180f32.to_radians(), ..cone };
    let c = split(&v, &km(2), &off, None, &one);
    assert!(!pure(&c, 0) && !pure(&c, 1), "the steps separate without the cone rule: the test proves nothing");
}

#[test]
fn enough_vals_leave_no_val_across_surfaces() {
    let v = corner(800);
    // The paper's k-means alone mixes the corner's surfaces at M = 8 ...
    let base = kmeans::cluster(&v, &km(8), None);
    let (cone, _) = worst(&v, &km(8), &base);
    assert!(cone > 30f32.to_radians(), "the test corner does not need splitting: {cone}");
    // ... the refinement from half of them does not: every VAL is on one surface, and no VAL holds both the
    // column's face and the wall behind it.
    let c = split(&v, &km(8), &sp(8), None, &kmeans::cluster(&v, &km(4), None));
    assert_eq!(c.vals.len(), 8);
    for k in 0..c.vals.len() {
        let members: Vec<&Vpl> =
            v.iter().zip(&c.assignment).filter(|(_, &a)| a as usize == k).map(|(x, _)| x).collect();
        assert!(members.windows(2).all(|w| w[0].normal == w[1].normal), "VAL {k} mixes normals");
        let z: Vec<f32> = members.iter().filter(|x| x.normal == Vec3::Z).map(|x| x.position.z).collect();
        assert!(z.iter().all(|&a| a == 0.0) || z.iter().all(|&a| a == 1.0), "VAL {k}: column and wall");
    }
    // Degenerate inputs: no VPLs, one VPL, identical VPLs.
    assert!(split(&[], &km(4), &sp(4), None, &Clustering::default()).vals.is_empty());
    let same = vec![v[0]; 5];
    let c = split(&same, &km(4), &sp(4), None, &kmeans::cluster(&same, &km(1), None));
    assert_eq!(c.vals.len(), 1);
    assert_eq!(c.vals[0].count, 5);
}
