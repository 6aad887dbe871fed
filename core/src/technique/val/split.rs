//! Splitting VALs that span several surfaces (our addition to section 5; issue 23).
//!
//! Section 5.1 of the paper names the two faults of a VAL whose VPLs lie on several surfaces (Fig. 7): its
//! centre can lie inside geometry (so geometry near it must be ignored and real occluders are lost), and
//! receivers in its negative half-space are lit by some of its VPLs with no visibility at all. The paper's
//! remedy is a high weight on the normals' angle; measured on Sponza (30 VALs, FLIP against one map per VPL)
//! raising `w_a` from 0.3 to 1 and 5 made things worse (0.20 -> 0.27, 0.28): normal-pure clusters then spread
//! over whole walls. So the paper's k-means result is refined the way bisecting k-means does:
//!
//! 1. k-means (the paper's, on the GPU or its CPU twin) for `ceil(share * M)` VALs (at least one).
//! 2. While there are fewer than `M` VALs, bisect one. *Which* one: while there are fewer than `gain_until`
//!    (default 16), the VAL whose bisection lowers `sum_i Y(Phi_i) d_i^2` most (every VAL's bisection tried:
//!    the first, coarse VALs then improve at every step, so Sponza's error falls at every M; from 64 VALs up the
//!    result is the flux rank's on the three scenes measured); then by `rank`: by default (`Rank::Light`) the
//!    VAL of largest light-weighted distance, `sum_i Y(Phi_i) d_i` over its members (`Y` the flux's luminance,
//!    `d` the paper's distance to the VAL's centre and normal): the error a VAL's visibility makes in the image
//!    grows with the light it carries and, about linearly, with how far its VPLs are from its centre (the
//!    receivers a VPL's own visibility would light differently grow with the width of the penumbra between the
//!    two points). `Rank::Flux`, the default before, squares `d` (k-means' objective): it left a bright, compact
//!    VAL of 49 VPLs on Sponza's ceiling whole until M = 161. That key counts
//!    `1 + hidden_weight * h` times (default 2), `h` the share of the VAL's luminance whose VPLs its map's centre
//!    does not see (a ray each against the scene's BVH, [`Sight`]): the paper's Fig. 7 fault, a centre inside
//!    geometry or behind an occluder from some of its VPLs, whose one map then shows them a different world
//!    (on Sponza, VALs whose VPLs lie on both sides of a pillar or an arch). Only a VAL that may be next is
//!    tested (its key is bounded by `1 + hidden_weight` times its error), so a frame casts a few thousand rays.
//!    (`Rank::Rule`, the first version, took every VAL that breaks a rule below before any other, by unweighted
//!    error within a class; on the conference room it then spent bisections 2-173 of 192 on VALs of two to
//!    twenty VPLs that spread in depth while a 10 m VAL of 46 VPLs on the ceiling stayed whole: FLIP 0.11 at
//!    M = 160, 0.063 ranked by flux.) *How* it is split depends on the rule it breaks: a *normal cone* (the largest angle between a
//!    member's normal and the VAL's normal) wider than `max_cone` splits it by normal (a room corner into its
//!    walls); else a *depth spread* (its members' extent along its normal: the floor and a table top, a
//!    column's face and the wall behind it) over `max_depth` splits it by depth; else the paper's metric. A
//!    bisection is a 2-means over the VAL's members in that metric, seeded by the member farthest from the
//!    centre and the member farthest from that one.
//! 3. Each VAL's centre, normal and rectangle are recomputed from its members (section 6, as [`super::kmeans`]
//!    does), and `C` is the bisection's membership (a VPL is not necessarily in the VAL of least `d` any
//!    more).
//!
//! The result never has more than `M` VALs (so the number of maps, the method's cost, is what `M` says) and
//! every VPL stays in exactly one. A pure, deterministic function. The technique's defaults (see
//! `docs/techniques/val.md` for the measurements) start from one VAL (`share = 0`): the bisections do not
//! depend on `M`, so the VALs for `M + 1` are those for `M` with one more bisected, and the error falls with
//! `M` far more regularly than when k-means restarts at every `M`. The cone rule is 40 degrees: with
//! `Rank::Rule` it had to be off, since on the conference room's curved chairs nearly every VAL broke a 30
//! degree cone and the rule spent the budget on small VALs (FLIP at M = 64 0.18 with it, 0.12 without); ranked
//! by flux it only decides how a VAL is cut, and cutting corners by normal made the Cornell box's error fall
//! at every M and the conference room's reach 0.076 at M = 64.

use glam::Vec3;

use super::kmeans::{self, Clustering, KMeansParams, Val};
use crate::vpl::Vpl;

/// Which VAL is bisected next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rank {
    /// Largest light-weighted distance `sum_i Y(Phi_i) d_i` (the default since the twenty-second session): the
    /// receivers where a VPL's visibility differs from that of a point `r` away grow about linearly in `r` (a
    /// penumbra's width), so a VAL's error in the image goes with the light it carries times how far its VPLs
    /// are from its centre, not with the square of that distance.
    Light,
    /// Largest flux-weighted error `sum_i Y(Phi_i) d_i^2` (k-means' own objective weighted by flux; the default
    /// before, kept for the measurements that compare them).
    Flux,
    /// Every VAL breaking the cone rule, then the depth rule, before any other; unweighted error within a
    /// class (the first version, kept for the measurements that compare them).
    Rule,
}

/// The refinement's rules.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplitParams {
    /// `M`: the VAL count to reach (clamped to the VPL count).
    pub vals: usize,
    /// Which VAL is bisected next.
    pub rank: Rank,
    /// While there are fewer VALs than this, the next bisection is the one that lowers the sum of `Y d^2` most
    /// (every VAL's bisection tried); `rank` decides from then on.
    pub gain_until: usize,
    /// Largest angle between a member's normal and its VAL's normal, radians.
    pub max_cone: f32,
    /// Largest spread of a VAL's members along its normal, world units.
    pub max_depth: f32,
    /// 2-means rounds of one bisection.
    pub iterations: u32,
    /// Ranked by light or flux, a VAL's key counts `1 + hidden_weight * h` times, `h` the share of its
    /// members' luminance hidden from its map's centre (needs a [`Sight`]; 0: the rank alone).
    pub hidden_weight: f32,
}

/// What a VAL's map sees, for the hidden members' weight: `occluded(from, to)` is true when geometry lies
/// between the two points (the scene's BVH); the map's centre is the VAL's position moved `offset` along its
/// normal (as the technique places it).
#[derive(Clone, Copy)]
pub struct Sight<'a> {
    pub occluded: &'a dyn Fn(Vec3, Vec3) -> bool,
    pub offset: f32,
}

/// Why a VAL is bisected, in priority order (a higher variant goes first).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Rule {
    Error,
    Depth,
    Cone,
}

/// A cluster under refinement: its members and their statistics.
struct Group {
    members: Vec<usize>,
    position: Vec3,
    normal: Vec3,
    /// Sum of `d^2` of its members to (position, normal).
    error: f32,
    /// Sum of `Y(Phi) d^2` of its members.
    flux_error: f32,
    /// Sum of `Y(Phi) d` of its members.
    light_distance: f32,
    cone: f32,
    depth: f32,
    size: f32,
    /// Set when a bisection found no two distinct halves.
    stuck: bool,
    /// The share of its members' luminance hidden from its map's centre, once tested (`None`: not yet; each
    /// test casts a ray per member, so it is made only for a VAL that may be the next one bisected).
    hidden: Option<f32>,
}

fn mean(vpls: &[Vpl], members: &[usize]) -> (Vec3, Vec3) {
    let n = members.len().max(1) as f32;
    let p = members.iter().map(|&i| vpls[i].position).sum::<Vec3>() / n;
    let s = members.iter().map(|&i| vpls[i].normal).sum::<Vec3>();
    let fallback = members.first().map_or(Vec3::Y, |&i| vpls[i].normal);
    (p, s.try_normalize().unwrap_or(fallback))
}

/// Rec. 709 luminance of a linear RGB flux (negative components, which a VPL never has, count as none).
fn luminance(c: Vec3) -> f32 {
    crate::math::luminance(c.max(Vec3::ZERO))
}

/// The bisection order of `g` under `rank`: a larger key goes first (the rule is the class a VAL is in; ranked
/// by flux, every VAL is in the same one).
fn priority(g: &Group, sp: &SplitParams) -> (Rule, f32) {
    let hidden = 1.0 + sp.hidden_weight * g.hidden.unwrap_or(1.0);
    match sp.rank {
        Rank::Light => (Rule::Error, g.light_distance * hidden),
        Rank::Flux => (Rule::Error, g.flux_error * hidden),
        Rank::Rule => (rule(g, sp), g.error),
    }
}

/// At most this many of a VAL's members are tested (every `len / SIGHT_SAMPLES`-th, rounded up): with 1,024 VPLs
/// the VALs tested have fewer, and 65,536 VPLs cast about 0.1 M rays instead of 0.5 M (Sponza: the clustering
/// 144 ms without the weight, 413 ms testing every member).
const SIGHT_SAMPLES: usize = 256;

/// The share of `g`'s members' luminance whose VPL its map's centre does not see (estimated from
/// [`SIGHT_SAMPLES`] evenly strided members of a larger VAL).
fn hidden_share(vpls: &[Vpl], g: &Group, sight: &Sight) -> f32 {
    let eye = g.position + g.normal * sight.offset;
    let (mut hidden, mut total) = (0.0f32, 0.0f32);
    let stride = g.members.len().div_ceil(SIGHT_SAMPLES).max(1);
    for &i in g.members.iter().step_by(stride) {
        let y = luminance(vpls[i].flux);
        total += y;
        if (sight.occluded)(eye, vpls[i].position) {
            hidden += y;
        }
    }
    if total > 0.0 && hidden.is_finite() {
        (hidden / total).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

fn group(vpls: &[Vpl], km: &KMeansParams, members: Vec<usize>) -> Group {
    let (position, normal) = mean(vpls, &members);
    let (u, v) = normal.any_orthonormal_pair();
    let (mut error, mut flux_error, mut light_distance, mut cone) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for &i in &members {
        let x = &vpls[i];
        let d = kmeans::distance(km, x.position, x.normal, position, normal);
        error += d * d;
        let y = luminance(x.flux);
        flux_error += d * d * y;
        light_distance += d * y;
        cone = cone.max(x.normal.dot(normal).clamp(-1.0, 1.0).acos());
        let r = x.position - position;
        let local = Vec3::new(r.dot(u), r.dot(v), r.dot(normal));
        lo = lo.min(local);
        hi = hi.max(local);
    }
    let ext = (hi - lo).max(Vec3::ZERO);
    Group {
        members,
        position,
        normal,
        error,
        flux_error,
        light_distance,
        cone,
        depth: ext.z,
        size: ext.truncate().length(),
        stuck: false,
        hidden: None,
    }
}

fn rule(g: &Group, sp: &SplitParams) -> Rule {
    if g.cone > sp.max_cone {
        Rule::Cone
    } else if g.depth > sp.max_depth {
        Rule::Depth
    } else {
        Rule::Error
    }
}

/// The bisection's distance of a VPL to a half's (position, normal), by rule.
fn metric(km: &KMeansParams, rule: Rule, axis: Vec3, x: &Vpl, c: (Vec3, Vec3)) -> f32 {
    match rule {
        Rule::Cone => x.normal.dot(c.1).clamp(-1.0, 1.0).acos(),
        Rule::Depth => (x.position - c.0).dot(axis).abs(),
        Rule::Error => kmeans::distance(km, x.position, x.normal, c.0, c.1),
    }
}

/// Split `g` in two by `rule`; `None` when its members do not separate.
fn bisect(vpls: &[Vpl], km: &KMeansParams, sp: &SplitParams, g: &Group, rule: Rule) -> Option<[Vec<usize>; 2]> {
    let axis = g.normal;
    let at = |i: usize| (vpls[i].position, vpls[i].normal);
    let far_from = |c: (Vec3, Vec3)| {
        let mut best = (f32::NEG_INFINITY, g.members[0]);
        for &i in &g.members {
            let d = metric(km, rule, axis, &vpls[i], c);
            if d > best.0 {
                best = (d, i);
            }
        }
        best
    };
    let (_, a) = far_from((g.position, g.normal));
    let (spread, b) = far_from(at(a));
    if spread.is_nan() || spread <= 0.0 {
        return None;
    }
    let mut centres = [at(a), at(b)];
    let mut halves: [Vec<usize>; 2] = [Vec::new(), Vec::new()];
    for _ in 0..sp.iterations.max(1) {
        halves = [Vec::new(), Vec::new()];
        for &i in &g.members {
            let d0 = metric(km, rule, axis, &vpls[i], centres[0]);
            let d1 = metric(km, rule, axis, &vpls[i], centres[1]);
            halves[usize::from(d1 < d0)].push(i);
        }
        if halves.iter().any(Vec::is_empty) {
            return None;
        }
        let next = [mean(vpls, &halves[0]), mean(vpls, &halves[1])];
        if next == centres {
            break;
        }
        centres = next;
    }
    Some(halves)
}

/// `g` bisected by the rule it breaks; a cone or depth rule that does not separate the members falls back to the
/// paper's metric. `None` when nothing separates them.
fn bisect_by_rule(vpls: &[Vpl], km: &KMeansParams, sp: &SplitParams, g: &Group) -> Option<[Vec<usize>; 2]> {
    let r = rule(g, sp);
    bisect(vpls, km, sp, g, r).or_else(|| if r != Rule::Error { bisect(vpls, km, sp, g, Rule::Error) } else { None })
}

/// Refine `clustering` of `vpls` (steps 2-3 of the module comment) to at most `sp.vals` VALs.
pub fn split(
    vpls: &[Vpl],
    km: &KMeansParams,
    sp: &SplitParams,
    sight: Option<&Sight>,
    clustering: &Clustering,
) -> Clustering {
    let n = vpls.len();
    let target = sp.vals.min(n);
    if n == 0 || target == 0 {
        return Clustering { assignment: vec![0; n], ..Default::default() };
    }
    // Non-empty k-means VALs, in their order (an empty one costs a map and lights nothing).
    let mut lists: Vec<Vec<usize>> = vec![Vec::new(); clustering.vals.len().max(1)];
    let last = lists.len() - 1;
    for (i, &k) in clustering.assignment.iter().enumerate().take(n) {
        lists[(k as usize).min(last)].push(i);
    }
    let mut groups: Vec<Group> = lists.into_iter().filter(|l| !l.is_empty()).map(|l| group(vpls, km, l)).collect();
    // The gain phase: each group's bisection (its halves as groups, and the error it removes), made once per
    // group and kept until that group is the one bisected.
    type Cut = Option<(f32, [Group; 2])>;
    let mut cuts: Vec<Option<Cut>> = groups.iter().map(|_| None).collect();
    while groups.len() < target {
        if groups.len() < sp.gain_until {
            // The bisection that lowers the flux-weighted error most.
            let mut best: Option<(f32, usize)> = None;
            for (k, g) in groups.iter().enumerate() {
                if g.stuck || g.members.len() <= 1 {
                    continue;
                }
                let cut = cuts[k].get_or_insert_with(|| {
                    bisect_by_rule(vpls, km, sp, g).map(|[a, b]| {
                        let (a, b) = (group(vpls, km, a), group(vpls, km, b));
                        (g.flux_error - a.flux_error - b.flux_error, [a, b])
                    })
                });
                // NaN (a VPL of NaN flux) never wins over a number, and a first candidate is always taken.
                if let Some((gain, _)) = cut {
                    if best.is_none_or(|(g0, _)| *gain > g0 || g0.is_nan()) {
                        best = Some((*gain, k));
                    }
                }
            }
            let Some((_, k)) = best else { break };
            let Some(Some((_, [a, b]))) = cuts[k].take() else { unreachable!("the best cut was made above") };
            groups[k] = a;
            groups.push(b);
            cuts.push(None);
            continue;
        }
        // With a hidden weight, an untested VAL ranks by its bound (every member hidden); the best is tested and
        // the pick repeated until it is a tested one, whose key then beats every bound (lazy greedy: the same
        // pick as testing every VAL, with rays for a few).
        let weighted = sp.rank != Rank::Rule && sp.hidden_weight > 0.0 && sight.is_some();
        let k = loop {
            let pick =
                groups.iter().enumerate().filter(|(_, g)| !g.stuck && g.members.len() > 1).max_by(|(_, a), (_, b)| {
                    priority(a, sp).partial_cmp(&priority(b, sp)).unwrap_or(std::cmp::Ordering::Equal)
                });
            let Some((k, g)) = pick else { break None };
            match (weighted, sight, g.hidden) {
                (true, Some(s), None) => groups[k].hidden = Some(hidden_share(vpls, &groups[k], s)),
                _ => break Some(k),
            }
        };
        let Some(k) = k else { break };
        match bisect_by_rule(vpls, km, sp, &groups[k]) {
            Some([a, b]) => {
                groups[k] = group(vpls, km, a);
                groups.push(group(vpls, km, b));
            }
            None => groups[k].stuck = true,
        }
    }
    let mut assignment = vec![0u32; n];
    for (k, g) in groups.iter().enumerate() {
        for &i in &g.members {
            assignment[i] = k as u32;
        }
    }
    let centres: Vec<(Vec3, Vec3)> = groups.iter().map(|g| (g.position, g.normal)).collect();
    let vals: Vec<Val> = kmeans::vals_of(vpls, &centres, &assignment);
    let non_empty = vals.iter().filter(|v| v.count > 0).count();
    Clustering { vals, assignment, non_empty }
}

/// The largest normal cone and relative depth spread over the non-empty VALs of `c` (radians, share of size):
/// for tests and the figures.
pub fn worst(vpls: &[Vpl], km: &KMeansParams, c: &Clustering) -> (f32, f32) {
    let mut lists: Vec<Vec<usize>> = vec![Vec::new(); c.vals.len()];
    for (i, &k) in c.assignment.iter().enumerate() {
        if let Some(l) = lists.get_mut(k as usize) {
            l.push(i);
        }
    }
    lists
        .into_iter()
        .filter(|l| !l.is_empty())
        .map(|l| group(vpls, km, l))
        .fold((0.0, 0.0), |acc, g| (acc.0.max(g.cone), acc.1.max(if g.size > 0.0 { g.depth / g.size } else { 0.0 })))
}

#[cfg(test)]
mod tests;
