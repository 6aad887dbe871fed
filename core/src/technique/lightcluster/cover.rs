//! Cluster centers by greedy covering (beyond the paper; `centers=cover`, off by default).
//!
//! The paper's step 3 ([`super::clustering`]) takes the lights in order of `L_att` and makes a light a center
//! when no center so far covers it (`distance <= d_min(c)`). That keeps every member within `d_min` of its
//! center, but the order decides how many centers it takes: on a circle of eight lights whose neighbours are
//! closer than `d_min` and whose second neighbours are not, the first light covers its two neighbours, the
//! third light the fourth, and so on: four centers where three (the 2nd, 5th and 8th, each covering both
//! neighbours) do. On Dabrovic Sponza with the LightCluster paper's 80 lights and `d_init` 0.5 that is 26
//! clusters against 20. Here, with the same covering relation (a center `c` covers a light within `d_min(c)`),
//! the next center is the light that covers the most lights not covered yet (greedy set cover; ties to the
//! light of larger `L_att`, then the lower index, as step 2 sorts them). Step 4 is the paper's: every other
//! light joins its nearest center. So every cluster keeps the paper's bound (its members within `d_min` of some
//! center, its disc light of radius `d_min`), with fewer cube maps where the lights are dense.
//!
//! Each light's neighbours within its `d_min` are listed once (the lights' `d_min` spheres in a
//! [`SphereGrid`], asked which contain each light); the greedy
//! picks are lazy (a light's count only falls, so a popped count that is still current is the largest). When
//! the neighbour lists would hold more than [`MAX_PAIRS`] entries (many lights within `d_init` of each other),
//! [`cluster_cover`] returns `false` and the caller uses the paper's selection.

use std::collections::BinaryHeap;

use glam::Vec3;

use super::clustering::{Cluster, ClusterParams, Clustering};
use crate::math::SphereGrid;
use crate::scene::PointLight;

/// The most (light, covered light) pairs listed before the covering gives up (64 MiB of `u32`s).
pub const MAX_PAIRS: usize = 16 << 20;

/// Cluster the `visible` lights (indices into `lights`, as the renderer's culling lists them) with centers
/// chosen by greedy covering (the module docs), into `out`. `false` (and `out` untouched) when the lights are
/// too dense for the neighbour lists ([`MAX_PAIRS`]).
pub fn cluster_cover(
    lights: &[PointLight],
    visible: &[usize],
    camera_position: Vec3,
    params: &ClusterParams,
    out: &mut Clustering,
) -> bool {
    // Step 2's order: larger L_att first, then input order.
    let mut order: Vec<usize> = visible.iter().copied().filter(|&i| i < lights.len()).collect();
    order.sort_unstable();
    order.dedup();
    order.sort_by(|&a, &b| lights[b].range.total_cmp(&lights[a].range).then(a.cmp(&b)));
    let n = order.len();
    let pos: Vec<Vec3> = order.iter().map(|&i| lights[i].position).collect();
    let d_min: Vec<f32> = pos.iter().map(|&p| params.d_min_at(p, camera_position)).collect();
    let d_init = params.effective_d_init();
    // Who covers whom: per light (sorted order), the other lights within its d_min. The spheres that contain each
    // light are its coverers (a non-finite position or d_min 0 covers nothing; a non-finite light is in no
    // sphere), turned round by a counting pass into each light's covered list.
    let spheres: Vec<(Vec3, f32)> =
        pos.iter().zip(&d_min).map(|(&p, &r)| (p, if r > 0.0 { r } else { -1.0 })).collect();
    let grid = SphereGrid::new(&spheres);
    let (grid, pos_of, reach_of) = (&grid, &pos, &d_min);
    let covered_by = |j: usize| {
        grid.candidates(pos_of[j])
            .filter(move |&i| i as usize != j && pos_of[i as usize].distance(pos_of[j]) <= reach_of[i as usize])
    };
    let mut starts = vec![0u32; n + 1];
    let mut pairs = 0usize;
    for j in 0..n {
        for i in covered_by(j) {
            starts[i as usize + 1] += 1;
            pairs += 1;
        }
        if pairs > MAX_PAIRS {
            return false;
        }
    }
    for i in 0..n {
        starts[i + 1] += starts[i];
    }
    let mut fill = starts.clone();
    let mut covered_by_me = vec![0u32; pairs];
    for j in 0..n {
        for i in covered_by(j) {
            covered_by_me[fill[i as usize] as usize] = j as u32;
            fill[i as usize] += 1;
        }
    }
    let covers = |i: usize| &covered_by_me[starts[i] as usize..starts[i + 1] as usize];
    // Lazy greedy: (uncovered lights a pick would cover, then the earlier light in step 2's order).
    let mut covered = vec![false; n];
    let gain = |i: usize, covered: &[bool]| {
        u32::from(!covered[i]) + covers(i).iter().filter(|&&j| !covered[j as usize]).count() as u32
    };
    let mut heap: BinaryHeap<(u32, std::cmp::Reverse<u32>)> =
        (0..n).map(|i| (gain(i, &covered), std::cmp::Reverse(i as u32))).collect();
    let mut centers: Vec<usize> = Vec::new();
    let mut left = n;
    while left > 0 {
        let Some((g, std::cmp::Reverse(i))) = heap.pop() else { break };
        let i = i as usize;
        let now = gain(i, &covered);
        if now < g {
            if now > 0 {
                heap.push((now, std::cmp::Reverse(i as u32)));
            }
            continue;
        }
        if now == 0 {
            continue;
        }
        centers.push(i);
        for j in std::iter::once(i).chain(covers(i).iter().map(|&j| j as usize)) {
            if !covered[j] {
                covered[j] = true;
                left -= 1;
            }
        }
    }
    // Step 4: every other light joins its nearest center (ties to the center chosen first). It is covered by a
    // center within d_min <= d_init, so the nearest is within d_init too; a light no center covers (a non-finite
    // position) is a center already.
    let mut cluster = vec![u32::MAX; n];
    for (k, &c) in centers.iter().enumerate() {
        cluster[c] = k as u32;
    }
    // Every center within d_init of a light (spheres of radius d_init about the centers) holds its nearest.
    let center_pos: Vec<Vec3> = centers.iter().map(|&c| pos[c]).collect();
    let reach: Vec<(Vec3, f32)> = center_pos.iter().map(|&c| (c, d_init)).collect();
    let near = SphereGrid::new(&reach);
    for i in 0..n {
        if cluster[i] != u32::MAX {
            continue;
        }
        let mut best = (f32::INFINITY, u32::MAX);
        for k in near.candidates(pos[i]) {
            let d = pos[i].distance(center_pos[k as usize]);
            if d < best.0 || (d == best.0 && k < best.1) {
                best = (d, k);
            }
        }
        cluster[i] = best.1;
    }
    // Never a light left out: one no center was found for (not expected: its coverer lies in those cells) is a
    // center of its own.
    for (i, k) in cluster.iter_mut().enumerate() {
        if *k == u32::MAX {
            *k = centers.len() as u32;
            centers.push(i);
        }
    }
    // The output, as the paper's: centers in selection order, each center first among its members, the others
    // in step 2's order; C_att grown by every member.
    out.clusters.clear();
    out.clusters.extend(centers.iter().map(|&c| Cluster {
        center: order[c],
        members: vec![order[c]],
        d_min: d_min[c],
        c_att: lights[order[c]].range,
        position: pos[c],
        radius: 0.0,
    }));
    out.cluster_of.clear();
    out.cluster_of.resize(lights.len(), None);
    for i in 0..n {
        let k = cluster[i];
        if k == u32::MAX {
            continue;
        }
        out.cluster_of[order[i]] = Some(k);
        let c = &mut out.clusters[k as usize];
        if c.center != order[i] {
            let d = pos[i].distance(c.position);
            c.members.push(order[i]);
            c.radius = c.radius.max(d);
            c.c_att = c.c_att.max(d + lights[order[i]].range);
        }
    }
    out.visible = n;
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The LightCluster paper's Sponza lights: ten circles of eight, radius 0.14 m, in the side arcades.
    fn sponza_circles() -> Vec<PointLight> {
        let mut lights = Vec::new();
        for side in [-1.0f32, 1.0] {
            for x in [-8.85f32, -4.4, 0.0, 4.4, 8.85] {
                for k in 0..8 {
                    let a = k as f32 * std::f32::consts::TAU / 8.0;
                    let p = Vec3::new(x + 0.14 * a.cos(), 1.59, side * 5.2 + 0.14 * a.sin());
                    lights.push(PointLight::new(p, Vec3::ONE, 1.0, 7.0));
                }
            }
        }
        lights
    }

    fn check(lights: &[PointLight], c: &Clustering, params: &ClusterParams, camera: Vec3) {
        let visible = c.visible;
        assert_eq!(c.clusters.iter().map(|k| k.members.len()).sum::<usize>(), visible, "each light once");
        for (k, cl) in c.clusters.iter().enumerate() {
            assert_eq!(cl.members[0], cl.center);
            assert_eq!(cl.d_min, params.d_min_at(cl.position, camera));
            for &m in &cl.members {
                assert_eq!(c.cluster_of[m], Some(k as u32));
                let d = lights[m].position.distance(cl.position);
                assert!(d <= cl.radius + 1e-6 && d + lights[m].range <= cl.c_att + 1e-5);
                // Step 4: no other center is nearer.
                for other in &c.clusters {
                    assert!(lights[m].position.distance(other.position) >= d - 1e-6);
                }
            }
        }
        // The covering's bound: every light lies within d_min of some center.
        for (i, l) in lights.iter().enumerate() {
            if c.cluster_of[i].is_some() {
                assert!(c.clusters.iter().any(|k| l.position.distance(k.position) <= k.d_min || k.center == i));
            }
        }
    }

    #[test]
    fn covering_the_papers_sponza_lights_takes_fewer_centers_than_the_papers_order() {
        let lights = sponza_circles();
        let visible: Vec<usize> = (0..lights.len()).collect();
        let camera = Vec3::new(-14.0, 2.5, 0.0);
        for (d_init, paper, cover) in [(0.1f32, 80usize, 80usize), (0.3, 44, 38), (0.5, 26, 20), (1.6, 10, 10)] {
            let params = ClusterParams { d_init, z_far: 30.0, adaptive: true };
            let mut by_paper = Clustering::default();
            super::super::clustering::Clusterer::default().cluster_visible_into(
                &lights,
                &visible,
                camera,
                &params,
                &mut by_paper,
            );
            assert_eq!(by_paper.clusters.len(), paper, "the paper's count at d_init {d_init}");
            let mut c = Clustering::default();
            assert!(cluster_cover(&lights, &visible, camera, &params, &mut c));
            assert_eq!(c.clusters.len(), cover, "covering at d_init {d_init}");
            check(&lights, &c, &params, camera);
        }
    }

    #[test]
    fn covering_handles_no_lights_zero_d_init_culled_and_non_finite_lights() {
        let mut lights = sponza_circles();
        lights[3].position = Vec3::NAN;
        let camera = Vec3::new(-14.0, 2.5, 0.0);
        let params = ClusterParams { d_init: 0.5, z_far: 30.0, adaptive: true };
        let mut c = Clustering::default();
        assert!(cluster_cover(&lights, &[], camera, &params, &mut c));
        assert!(c.clusters.is_empty() && c.visible == 0);
        // Half the lights visible (and an index past the end, ignored): the others stay unclustered.
        let visible: Vec<usize> = (0..lights.len()).step_by(2).chain([10_000]).collect();
        assert!(cluster_cover(&lights, &visible, camera, &params, &mut c));
        assert_eq!(c.visible, 40);
        assert!(c.cluster_of[1].is_none() && c.cluster_of[0].is_some());
        // The NaN light (index 3 is odd: add it) is a center of its own.
        let visible: Vec<usize> = (0..lights.len()).collect();
        assert!(cluster_cover(&lights, &visible, camera, &params, &mut c));
        let k = c.cluster_of[3].unwrap() as usize;
        assert_eq!(c.clusters[k].members, vec![3]);
        // Lights beyond the grid's range (cells past i32) and at infinity: no overflow, each clustered.
        let mut far = lights.clone();
        far[0].position = Vec3::splat(1e30);
        far[1].position = Vec3::splat(1e30) + Vec3::X * 0.1;
        far[2].position = Vec3::INFINITY;
        assert!(cluster_cover(&far, &visible, camera, &params, &mut c));
        assert!((0..3).all(|i| c.cluster_of[i].is_some()));
        // An infinite d_init (f32::MAX, `effective_d_init`) without view-adaptive scaling: every light covers every
        // other, one cluster.
        let huge = ClusterParams { d_init: f32::INFINITY, z_far: 30.0, adaptive: false };
        let few: Vec<PointLight> = sponza_circles().into_iter().take(8).collect();
        assert!(cluster_cover(&few, &(0..8).collect::<Vec<_>>(), camera, &huge, &mut c));
        assert_eq!(c.clusters.len(), 1);
        // d_init 0: one cluster per light.
        let zero = ClusterParams { d_init: 0.0, ..params };
        assert!(cluster_cover(&lights, &visible, camera, &zero, &mut c));
        assert_eq!(c.clusters.len(), lights.len());
    }

    #[test]
    fn lights_too_dense_for_the_neighbour_lists_fall_back() {
        // 6,000 lights in a 1 m cube with d_init 10 (every light covers every other): 36 M pairs.
        let lights: Vec<PointLight> = (0..6000)
            .map(|i| {
                let f = |k: u32| crate::vpl::halton::radical_inverse(k, i as u64 + 1);
                PointLight::new(Vec3::new(f(0), f(1), f(2)), Vec3::ONE, 1.0, 5.0)
            })
            .collect();
        let visible: Vec<usize> = (0..lights.len()).collect();
        let params = ClusterParams { d_init: 10.0, z_far: 1000.0, adaptive: false };
        let mut c = Clustering::default();
        assert!(!cluster_cover(&lights, &visible, Vec3::ZERO, &params, &mut c));
        assert!(c.clusters.is_empty(), "a refused covering leaves the output untouched");
    }
}
