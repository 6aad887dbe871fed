//! LightCluster's min-distance clustering (paper section 3.1): properties over many seeded random light sets,
//! and equality with a brute-force O(n * k) reference implementation of the same four steps.

use std::alloc::{GlobalAlloc, Layout as AllocLayout, System};
use std::cell::Cell;

use glam::Vec3;
use shadowlab_core::math::Frustum;
use shadowlab_core::scene::{Camera, PointLight};
use shadowlab_core::technique::lightcluster::clustering::{
    cluster_lights, ClusterParams, Clusterer, Clustering, GridKind,
};

/// Counts this thread's allocations, to check that a reused `Clusterer` does not allocate.
struct CountingAllocator;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: every call is forwarded unchanged to the system allocator; counting touches only a thread-local
// `Cell` without destructor.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: AllocLayout) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: AllocLayout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: AllocLayout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

// ---------------------------------------------------------------------------------------------------------------
// Inputs
// ---------------------------------------------------------------------------------------------------------------

/// SplitMix64: tiny, seeded, good enough for test data.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    fn vec3(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(self.range(lo.x, hi.x), self.range(lo.y, hi.y), self.range(lo.z, hi.z))
    }
}

fn light(position: Vec3, range: f32) -> PointLight {
    PointLight::new(position, Vec3::ONE, 1.0, range)
}

/// The lights' box: 30 m wide, from a bit behind the camera at z = 1 to past its far plane.
const BOX_MIN: Vec3 = Vec3::new(-15.0, -15.0, -32.0);
const BOX_MAX: Vec3 = Vec3::new(15.0, 15.0, 3.0);

#[derive(Clone, Copy, Debug)]
enum Layout {
    /// Uniform in the box, random ranges.
    Uniform,
    /// Gaussian-ish blobs of lights around a few points.
    Blobs,
    /// All on the plane y = 0.
    Planar,
    /// All with the same range (the sort keeps input order).
    EqualRanges,
    /// Every light duplicated at the same position (coincident lights).
    Duplicates,
    /// On an integer lattice with few distinct ranges: many exactly equal distances (ties).
    Lattice,
}

const LAYOUTS: [Layout; 6] =
    [Layout::Uniform, Layout::Blobs, Layout::Planar, Layout::EqualRanges, Layout::Duplicates, Layout::Lattice];

fn make_lights(layout: Layout, n: usize, seed: u64) -> Vec<PointLight> {
    let mut rng = Rng(seed);
    let mut lights = Vec::with_capacity(n);
    let blobs: Vec<Vec3> = (0..5).map(|_| rng.vec3(BOX_MIN, BOX_MAX)).collect();
    while lights.len() < n {
        let range = rng.range(0.5, 7.0);
        match layout {
            Layout::Uniform => lights.push(light(rng.vec3(BOX_MIN, BOX_MAX), range)),
            Layout::Blobs => {
                let c = blobs[rng.below(blobs.len())];
                let spread = Vec3::splat(0.8);
                let offset = rng.vec3(-spread, spread) + rng.vec3(-spread, spread) - rng.vec3(-spread, spread);
                lights.push(light(c + offset, range));
            }
            Layout::Planar => {
                let mut p = rng.vec3(BOX_MIN, BOX_MAX);
                p.y = 0.0;
                lights.push(light(p, range));
            }
            Layout::EqualRanges => lights.push(light(rng.vec3(BOX_MIN, BOX_MAX), 3.0)),
            Layout::Duplicates => {
                let p = rng.vec3(BOX_MIN, BOX_MAX);
                lights.push(light(p, range));
                if lights.len() < n {
                    lights.push(light(p, rng.range(0.5, 7.0)));
                }
            }
            Layout::Lattice => {
                let p = rng.vec3(BOX_MIN, BOX_MAX).round() * 0.5;
                lights.push(light(p, 1.0 + rng.below(3) as f32));
            }
        }
    }
    lights
}

/// Camera at one end of the box looking down it (the paper's setting), or inside looking diagonally.
fn cameras() -> [Camera; 2] {
    [
        Camera::look_at(Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -30.0), 60f32.to_radians(), 0.1, 30.0),
        Camera::look_at(Vec3::new(-3.0, 2.0, -10.0), Vec3::new(10.0, -5.0, -25.0), 75f32.to_radians(), 0.05, 20.0),
    ]
}

fn frustum_of(camera: &Camera) -> Frustum {
    Frustum::from_clip_from_world(&camera.clip_from_world(16.0 / 9.0))
}

const D_INITS: [f32; 8] = [0.0, 1e-4, 0.05, 0.3, 0.5, 1.0, 1.6, 100.0];

struct Case {
    name: String,
    lights: Vec<PointLight>,
    camera: Camera,
    frustum: Frustum,
    params: ClusterParams,
}

/// Many seeded light sets: every layout, several sizes, every `d_init`, adaptive on and off, two cameras.
fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    let mut seed = 1u64;
    for layout in LAYOUTS {
        for n in [1usize, 2, 7, 60, 400, 1500] {
            for (ci, camera) in cameras().into_iter().enumerate() {
                for d_init in D_INITS {
                    for adaptive in [true, false] {
                        // Large sets only for some combinations, to keep the brute-force reference quick.
                        if n == 1500 && (ci == 1 || !adaptive) {
                            continue;
                        }
                        seed += 1;
                        out.push(Case {
                            name: format!(
                                "{layout:?} n={n} camera={ci} d_init={d_init} adaptive={adaptive} seed={seed}"
                            ),
                            lights: make_lights(layout, n, seed),
                            camera,
                            frustum: frustum_of(&camera),
                            params: ClusterParams { d_init, z_far: camera.z_far, adaptive },
                        });
                    }
                }
            }
        }
    }
    out
}

fn run(case: &Case) -> Clustering {
    cluster_lights(&case.lights, case.camera.position, &case.frustum, &case.params)
}

// ---------------------------------------------------------------------------------------------------------------
// Brute-force reference of the same four steps
// ---------------------------------------------------------------------------------------------------------------

fn reference(lights: &[PointLight], camera: Vec3, frustum: &Frustum, params: &ClusterParams) -> Clustering {
    // 1. Cull.
    let mut visible: Vec<usize> = (0..lights.len())
        .filter(|&i| lights[i].is_valid() && frustum.intersects_sphere(lights[i].position, lights[i].range))
        .collect();
    // 2. Sort by range, largest first; `sort_by` is stable, so ties keep index order.
    visible.sort_by(|&a, &b| lights[b].range.partial_cmp(&lights[a].range).unwrap());
    // 3. Centers: farther than d_min(c) from every center c (a center with d_min 0 covers nothing).
    let mut centers: Vec<(usize, Vec3, f32)> = Vec::new();
    let mut remaining = Vec::new();
    for &i in &visible {
        let p = lights[i].position;
        if centers.iter().all(|&(_, c, d_min)| !(d_min > 0.0 && p.distance(c) <= d_min)) {
            centers.push((i, p, params.d_min_at(p, camera)));
        } else {
            remaining.push(i);
        }
    }
    let mut out = Clustering { clusters: Vec::new(), cluster_of: vec![None; lights.len()], visible: visible.len() };
    for (k, &(i, p, d_min)) in centers.iter().enumerate() {
        out.clusters.push(shadowlab_core::technique::lightcluster::clustering::Cluster {
            center: i,
            members: vec![i],
            d_min,
            c_att: lights[i].range,
            position: p,
            radius: 0.0,
        });
        out.cluster_of[i] = Some(k as u32);
    }
    // 4. Nearest center (squared distance, then lowest cluster index), grow C_att.
    for &i in &remaining {
        let p = lights[i].position;
        let mut best = (usize::MAX, f32::INFINITY);
        for (k, &(_, c, _)) in centers.iter().enumerate() {
            let d2 = p.distance_squared(c);
            if d2 < best.1 {
                best = (k, d2);
            }
        }
        let d = best.1.sqrt();
        let cluster = &mut out.clusters[best.0];
        cluster.members.push(i);
        cluster.c_att = cluster.c_att.max(d + lights[i].range);
        cluster.radius = cluster.radius.max(d);
        out.cluster_of[i] = Some(best.0 as u32);
    }
    out
}

// ---------------------------------------------------------------------------------------------------------------
// Property checks
// ---------------------------------------------------------------------------------------------------------------

fn is_visible(l: &PointLight, frustum: &Frustum) -> bool {
    l.is_valid() && frustum.intersects_sphere(l.position, l.range)
}

fn check_culling(name: &str, lights: &[PointLight], frustum: &Frustum, c: &Clustering) {
    assert_eq!(c.cluster_of.len(), lights.len(), "{name}");
    for (i, l) in lights.iter().enumerate() {
        assert_eq!(c.cluster_of[i].is_some(), is_visible(l, frustum), "{name}: light {i} culling");
    }
    assert_eq!(c.visible, lights.iter().filter(|l| is_visible(l, frustum)).count(), "{name}");
}

fn check_partition(name: &str, c: &Clustering) {
    let mut seen = vec![0u32; c.cluster_of.len()];
    for (k, cluster) in c.clusters.iter().enumerate() {
        for &m in &cluster.members {
            seen[m] += 1;
            assert_eq!(c.cluster_of[m], Some(k as u32), "{name}: light {m} listed in cluster {k}");
        }
    }
    for (i, of) in c.cluster_of.iter().enumerate() {
        assert_eq!(seen[i], of.is_some() as u32, "{name}: light {i} must be in exactly one cluster iff visible");
    }
    assert_eq!(c.clusters.iter().map(|k| k.members.len()).sum::<usize>(), c.visible, "{name}");
}

fn check_centers(name: &str, lights: &[PointLight], camera: Vec3, params: &ClusterParams, c: &Clustering) {
    for (k, cluster) in c.clusters.iter().enumerate() {
        assert_eq!(cluster.members.first(), Some(&cluster.center), "{name}: center first in cluster {k}");
        assert_eq!(c.cluster_of[cluster.center], Some(k as u32), "{name}");
        assert_eq!(cluster.position, lights[cluster.center].position, "{name}: center is a real light");
        assert_eq!(cluster.d_min, params.d_min_at(cluster.position, camera), "{name}");
    }
    // Selection order is the sort order: ranges never increase, equal ranges by index.
    for w in c.clusters.windows(2) {
        let (a, b) = (&lights[w[0].center], &lights[w[1].center]);
        assert!(a.range > b.range || (a.range == b.range && w[0].center < w[1].center), "{name}: center order");
    }
}

fn check_center_spacing(name: &str, c: &Clustering) {
    for (ka, a) in c.clusters.iter().enumerate() {
        for b in &c.clusters[ka + 1..] {
            let d = a.position.distance(b.position);
            assert!(
                d > a.d_min || a.d_min == 0.0,
                "{name}: centers {} and {} at {d} <= d_min {}",
                a.center,
                b.center,
                a.d_min
            );
        }
    }
}

fn check_nearest(name: &str, lights: &[PointLight], c: &Clustering, sample: impl Iterator<Item = usize>) {
    for i in sample {
        let Some(k) = c.cluster_of[i] else { continue };
        if c.clusters[k as usize].center == i {
            continue; // a center is its own cluster (it may coincide with another center whose d_min is 0)
        }
        let p = lights[i].position;
        let d2 = p.distance_squared(c.clusters[k as usize].position);
        for (j, other) in c.clusters.iter().enumerate() {
            let o2 = p.distance_squared(other.position);
            assert!(
                o2 > d2 || (o2 == d2 && j >= k as usize),
                "{name}: light {i} in cluster {k} at d2 {d2}, but cluster {j} is at d2 {o2}"
            );
        }
    }
}

fn check_c_att(name: &str, lights: &[PointLight], c: &Clustering) {
    for cluster in &c.clusters {
        assert!(cluster.c_att >= lights[cluster.center].range, "{name}");
        for &m in &cluster.members {
            let d = lights[m].position.distance(cluster.position);
            assert!(
                cluster.c_att >= d + lights[m].range,
                "{name}: C_att {} < {d} + {}",
                cluster.c_att,
                lights[m].range
            );
            assert!(cluster.radius >= d, "{name}");
        }
    }
}

/// Every light that is no center was covered by a center selected before it (step 3's rule).
fn check_non_centers_covered(name: &str, lights: &[PointLight], c: &Clustering) {
    let rank = |i: usize| (std::cmp::Reverse(lights[i].range.to_bits()), i);
    for cluster in &c.clusters {
        for &m in &cluster.members[1..] {
            let p = lights[m].position;
            let covered = c
                .clusters
                .iter()
                .any(|o| rank(o.center) < rank(m) && o.d_min > 0.0 && p.distance(o.position) <= o.d_min);
            assert!(covered, "{name}: light {m} is no center but no earlier center covers it");
        }
    }
}

fn check_all(case: &Case, c: &Clustering) {
    let n = &case.name;
    check_culling(n, &case.lights, &case.frustum, c);
    check_partition(n, c);
    check_centers(n, &case.lights, case.camera.position, &case.params, c);
    check_center_spacing(n, c);
    check_nearest(n, &case.lights, c, 0..case.lights.len());
    check_c_att(n, &case.lights, c);
    check_non_centers_covered(n, &case.lights, c);
}

// ---------------------------------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------------------------------

#[test]
fn matches_brute_force_reference() {
    let mut clusterer = Clusterer::new();
    let mut reused = Clustering::default();
    let mut kinds = [0usize; 4];
    for case in cases() {
        let expected = reference(&case.lights, case.camera.position, &case.frustum, &case.params);
        let got = run(&case);
        assert_eq!(got, expected, "{}", case.name);
        // The reusing path gives the same result after arbitrary previous inputs.
        clusterer.cluster_into(&case.lights, case.camera.position, &case.frustum, &case.params, &mut reused);
        assert_eq!(reused, expected, "{} (reused)", case.name);
        // With step 1 done by the renderer's light list (the same test), the same result.
        let visible: Vec<usize> = (0..case.lights.len())
            .filter(|&i| {
                let l = &case.lights[i];
                l.is_valid() && case.frustum.intersects_sphere(l.position, l.range)
            })
            .collect();
        clusterer.cluster_visible_into(&case.lights, &visible, case.camera.position, &case.params, &mut reused);
        assert_eq!(reused, expected, "{} (pre-culled)", case.name);
        kinds[clusterer.grid_info().kind as usize] += 1;
    }
    assert!(kinds[0] > 0 && kinds[1] > 0, "grid kinds used (none, dense, hash, mixed): {kinds:?}");
}

#[test]
fn every_visible_light_belongs_to_exactly_one_cluster() {
    for case in cases() {
        check_partition(&case.name, &run(&case));
    }
}

#[test]
fn culled_lights_are_exactly_those_outside_the_frustum() {
    for case in cases() {
        check_culling(&case.name, &case.lights, &case.frustum, &run(&case));
    }
}

#[test]
fn centers_are_real_lights_and_first_members() {
    for case in cases() {
        check_centers(&case.name, &case.lights, case.camera.position, &case.params, &run(&case));
    }
}

#[test]
fn each_light_joins_its_nearest_center() {
    for case in cases() {
        let c = run(&case);
        check_nearest(&case.name, &case.lights, &c, 0..case.lights.len());
        check_non_centers_covered(&case.name, &case.lights, &c);
    }
}

#[test]
fn no_two_centers_closer_than_their_d_min() {
    for case in cases() {
        check_center_spacing(&case.name, &run(&case));
    }
}

#[test]
fn c_att_covers_every_member() {
    for case in cases() {
        check_c_att(&case.name, &case.lights, &run(&case));
    }
}

#[test]
fn deterministic_for_the_same_input() {
    let mut clusterer = Clusterer::new();
    for case in cases().into_iter().step_by(7) {
        let a = run(&case);
        let b = run(&case);
        let c = clusterer.cluster(&case.lights, case.camera.position, &case.frustum, &case.params);
        assert_eq!(a, b, "{}", case.name);
        assert_eq!(a, c, "{}", case.name);
    }
}

#[test]
fn a_reused_clusterer_does_not_allocate_in_steady_state() {
    let camera = cameras()[0];
    let frustum = frustum_of(&camera);
    // Frames alternating between inputs with different cluster counts, view-adaptive and not.
    let frames = [
        (make_lights(Layout::Uniform, 3000, 1), ClusterParams { d_init: 0.5, z_far: 30.0, adaptive: true }),
        (make_lights(Layout::Blobs, 6000, 2), ClusterParams { d_init: 1.6, z_far: 30.0, adaptive: true }),
        (make_lights(Layout::Uniform, 500, 3), ClusterParams { d_init: 1.0, z_far: 30.0, adaptive: false }),
        (make_lights(Layout::Blobs, 6000, 2), ClusterParams { d_init: 0.001, z_far: 30.0, adaptive: false }),
    ];
    let mut clusterer = Clusterer::new();
    let mut out = Clustering::default();
    let run_all = |clusterer: &mut Clusterer, out: &mut Clustering| {
        for (lights, params) in &frames {
            clusterer.cluster_into(lights, camera.position, &frustum, params, out);
            assert_eq!(*out, reference(lights, camera.position, &frustum, params));
        }
    };
    // Warm up: buffers grow to the largest frame.
    for _ in 0..3 {
        run_all(&mut clusterer, &mut out);
    }
    for _ in 0..3 {
        for (lights, params) in &frames {
            let before = allocations();
            clusterer.cluster_into(lights, camera.position, &frustum, params, &mut out);
            assert_eq!(allocations() - before, 0, "{} lights {params:?}", lights.len());
        }
    }
}

#[test]
fn empty_input_gives_empty_clustering() {
    let camera = cameras()[0];
    let c = cluster_lights(&[], camera.position, &frustum_of(&camera), &ClusterParams::default());
    assert_eq!(c, Clustering::default());
}

#[test]
fn zero_or_tiny_d_init_gives_one_cluster_per_light() {
    let camera = cameras()[0];
    let frustum = frustum_of(&camera);
    // Duplicates included: with d_min = 0 even coincident lights stay apart.
    for layout in [Layout::Uniform, Layout::Duplicates, Layout::Lattice] {
        let lights = make_lights(layout, 3000, 77);
        for d_init in [0.0, -1.0, f32::NAN, f32::NEG_INFINITY, 1e-7] {
            if d_init > 0.0 && matches!(layout, Layout::Duplicates | Layout::Lattice) {
                continue; // a positive d_min merges coincident lights
            }
            for adaptive in [true, false] {
                let params = ClusterParams { d_init, z_far: 30.0, adaptive };
                let c = cluster_lights(&lights, camera.position, &frustum, &params);
                assert!(c.visible > 1000, "{layout:?}");
                assert_eq!(c.clusters.len(), c.visible, "{layout:?} d_init={d_init}");
                assert!(c.clusters.iter().all(|k| k.members.len() == 1 && k.c_att == lights[k.center].range));
            }
        }
    }
}

#[test]
fn huge_d_init_without_adaptive_gives_one_cluster() {
    let camera = cameras()[0];
    let frustum = frustum_of(&camera);
    for (seed, layout) in LAYOUTS.into_iter().enumerate() {
        let lights = make_lights(layout, 2000, seed as u64 + 500);
        for d_init in [1000.0, 1e30, f32::INFINITY] {
            let params = ClusterParams { d_init, z_far: 30.0, adaptive: false };
            let c = cluster_lights(&lights, camera.position, &frustum, &params);
            assert_eq!(c.clusters.len(), 1, "{layout:?} d_init={d_init}");
            let max_range = lights.iter().filter(|l| is_visible(l, &frustum)).map(|l| l.range).fold(0.0, f32::max);
            assert_eq!(lights[c.clusters[0].center].range, max_range, "the largest range is the first center");
            check_c_att("huge", &lights, &c);
        }
    }
}

#[test]
fn hundred_thousand_lights() {
    let camera = cameras()[0];
    let frustum = frustum_of(&camera);
    let lights = make_lights(Layout::Uniform, 100_000, 4242);
    let mut clusterer = Clusterer::new();
    for d_init in [0.0, 0.01, 0.5, 1.6] {
        let params = ClusterParams { d_init, z_far: 30.0, adaptive: true };
        let c = clusterer.cluster(&lights, camera.position, &frustum, &params);
        let name = format!("100k d_init={d_init}");
        assert!(c.visible > 10_000, "{name}");
        check_culling(&name, &lights, &frustum, &c);
        check_partition(&name, &c);
        check_centers(&name, &lights, camera.position, &params, &c);
        check_c_att(&name, &lights, &c);
        // Brute force over all centers for a sample of the lights.
        let mut rng = Rng(d_init.to_bits() as u64);
        check_nearest(&name, &lights, &c, (0..300).map(|_| rng.below(lights.len())));
        if d_init == 0.0 {
            assert_eq!(c.clusters.len(), c.visible);
        } else if d_init >= 0.5 {
            assert!(c.clusters.len() < c.visible, "{name}: some lights cluster");
        }
    }
}

#[test]
fn nan_and_invalid_lights_are_culled_without_panic() {
    let camera = cameras()[0];
    let frustum = frustum_of(&camera);
    let mut lights = make_lights(Layout::Uniform, 500, 9);
    let good = light(Vec3::new(0.0, 0.0, -5.0), 2.0);
    let bad = [
        light(Vec3::new(f32::NAN, 0.0, -5.0), 2.0),
        light(Vec3::new(0.0, f32::INFINITY, -5.0), 2.0),
        light(Vec3::NAN, f32::NAN),
        light(Vec3::new(0.0, 0.0, -5.0), 0.0),
        light(Vec3::new(0.0, 0.0, -5.0), -1.0),
        light(Vec3::new(0.0, 0.0, -5.0), f32::INFINITY),
        PointLight::new(Vec3::new(0.0, 0.0, -5.0), Vec3::ONE, f32::NAN, 2.0),
        PointLight::new(Vec3::new(0.0, 0.0, -5.0), Vec3::new(-1.0, 0.0, 0.0), 1.0, 2.0),
    ];
    let first_bad = lights.len();
    lights.push(good);
    lights.extend(bad);
    for d_init in [0.0, 0.5, 1e6] {
        let params = ClusterParams { d_init, z_far: 30.0, adaptive: true };
        let c = cluster_lights(&lights, camera.position, &frustum, &params);
        assert!(c.cluster_of[first_bad].is_some());
        assert!(c.cluster_of[first_bad + 1..].iter().all(Option::is_none), "d_init={d_init}");
        assert_eq!(c, reference(&lights, camera.position, &frustum, &params));
        // Only NaN lights.
        let nan_only = vec![light(Vec3::NAN, 1.0); 10];
        let c = cluster_lights(&nan_only, camera.position, &frustum, &params);
        assert_eq!((c.visible, c.clusters.len(), c.cluster_of.len()), (0, 0, 10));
    }
}

#[test]
fn invalid_params_do_not_panic() {
    let camera = cameras()[0];
    let frustum = frustum_of(&camera);
    let lights = make_lights(Layout::Blobs, 800, 31);
    for d_init in [f32::NAN, -3.0, 0.0, f32::MIN_POSITIVE, 0.5, f32::MAX, f32::INFINITY] {
        for z_far in [f32::NAN, -30.0, 0.0, f32::MIN_POSITIVE, 30.0, f32::INFINITY] {
            for adaptive in [true, false] {
                let params = ClusterParams { d_init, z_far, adaptive };
                let c = cluster_lights(&lights, camera.position, &frustum, &params);
                assert_eq!(c, reference(&lights, camera.position, &frustum, &params), "{params:?}");
                check_partition("params", &c);
                check_center_spacing("params", &c);
            }
        }
    }
    // A NaN camera position: every d_min is 0 with adaptive scaling.
    let params = ClusterParams { d_init: 0.5, z_far: 30.0, adaptive: true };
    let c = cluster_lights(&lights, Vec3::NAN, &frustum, &params);
    assert_eq!(c.clusters.len(), c.visible);
}

#[test]
fn validate_reports_bad_params() {
    let ok = ClusterParams::default();
    assert_eq!(ok, ClusterParams { d_init: 0.5, z_far: 30.0, adaptive: true });
    assert!(ok.validate().is_ok());
    assert!(ClusterParams { d_init: 0.0, ..ok }.validate().is_ok());
    assert!(ClusterParams { z_far: f32::INFINITY, ..ok }.validate().is_ok());
    for bad in [
        ClusterParams { d_init: f32::NAN, ..ok },
        ClusterParams { d_init: -0.1, ..ok },
        ClusterParams { d_init: f32::INFINITY, ..ok },
        ClusterParams { z_far: 0.0, ..ok },
        ClusterParams { z_far: -1.0, ..ok },
        ClusterParams { z_far: f32::NAN, ..ok },
    ] {
        let err = bad.validate().unwrap_err();
        assert!(err.contains("d_init") || err.contains("z_far"), "{err}");
    }
}

#[test]
fn d_min_follows_the_paper_formula() {
    let cam = Vec3::new(1.0, 2.0, 3.0);
    let p = ClusterParams { d_init: 0.5, z_far: 30.0, adaptive: true };
    let at = |d: f32| cam + Vec3::new(0.0, 0.0, -d);
    assert_eq!(p.d_min_at(at(0.0), cam), 0.5);
    assert!((p.d_min_at(at(15.0), cam) - 0.25).abs() < 1e-6);
    assert!((p.d_min_at(at(24.0), cam) - 0.1).abs() < 1e-6);
    // Clamped: 0 at and beyond z_far.
    assert_eq!(p.d_min_at(at(30.0), cam), 0.0);
    assert_eq!(p.d_min_at(at(45.0), cam), 0.0);
    // Not adaptive: d_init everywhere.
    let flat = ClusterParams { adaptive: false, ..p };
    for d in [0.0, 15.0, 30.0, 1000.0] {
        assert_eq!(flat.d_min_at(at(d), cam), 0.5);
    }
    // Invalid z_far: no scaling. Invalid d_init: 0.
    assert_eq!(ClusterParams { z_far: -1.0, ..p }.d_min_at(at(15.0), cam), 0.5);
    assert_eq!(ClusterParams { z_far: f32::NAN, ..p }.d_min_at(at(15.0), cam), 0.5);
    assert_eq!(ClusterParams { d_init: f32::NAN, ..p }.d_min_at(at(1.0), cam), 0.0);
    assert_eq!(ClusterParams { d_init: -2.0, ..p }.d_min_at(at(1.0), cam), 0.0);
    assert_eq!(ClusterParams { d_init: f32::INFINITY, ..p }.d_min_at(at(45.0), cam), 0.0);
    assert_eq!(ClusterParams { d_init: f32::INFINITY, ..flat }.d_min_at(at(45.0), cam), f32::MAX);
}

/// A 1D version of the paper's figure 3, with every number worked out by hand.
#[test]
fn worked_example_assigns_to_the_nearest_center_not_the_first() {
    let camera = Camera::look_at(Vec3::new(0.0, 0.0, 20.0), Vec3::ZERO, 60f32.to_radians(), 0.1, 100.0);
    let frustum = frustum_of(&camera);
    let at = |x: f32| Vec3::new(x, 0.0, 0.0);
    let lights = [
        light(at(0.9), 1.0),  // 0: covered by A (0.9 <= 1), but C is nearer (0.6)
        light(at(0.0), 3.0),  // 1: A, the largest range: first center
        light(at(0.5), 2.0),  // 2: covered by A (0.5), nearest A
        light(at(1.5), 2.0),  // 3: C, 1.5 > 1 from A (same range as 2: sorted after it by index)
        light(at(2.2), 1.0),  // 4: covered by C (0.7), nearest C
        light(at(-1.0), 2.5), // 5: exactly d_min from A: covered ("farther than d_min" fails); grows C_att
        light(at(0.0), 0.5),  // 6: coincident with A: covered, d_C 0
    ];
    let params = ClusterParams { d_init: 1.0, z_far: 100.0, adaptive: false };
    let c = cluster_lights(&lights, camera.position, &frustum, &params);
    assert_eq!(c.visible, 7);
    assert_eq!(c.clusters.len(), 2);
    let (a, cc) = (&c.clusters[0], &c.clusters[1]);
    assert_eq!((a.center, cc.center), (1, 3));
    // Members after the center in sorted order: 5 (range 2.5), 2 (range 2), 6 (range 0.5); 0 and 4 by index.
    assert_eq!(a.members, vec![1, 5, 2, 6]);
    assert_eq!(cc.members, vec![3, 0, 4]);
    assert_eq!(a.c_att, 3.5); // max(3, 1 + 2.5, 0.5 + 2, 0 + 0.5)
    assert_eq!(cc.c_att, 2.0); // max(2, 0.6 + 1, 0.7 + 1)
    assert!((cc.radius - 0.7).abs() < 1e-6);
    assert_eq!(a.radius, 1.0);
    assert_eq!((a.d_min, cc.d_min), (1.0, 1.0));
    assert_eq!(c.cluster_of, vec![Some(1), Some(0), Some(0), Some(1), Some(1), Some(0), Some(0)]);

    // View-adaptive: the lights are about 20 from the camera and z_far is 40, so d_min is about 0.5.
    // Sorted: 1, 5, 2, 3, 0, 4, 6. 1 is a center (d_min exactly 0.5); 5 is 1.0 > 0.5 from it: a center;
    // 2 is exactly 0.5 from 1: covered; 3, 0 and 4 are each more than ~0.4986 from every earlier center:
    // centers; 6 coincides with 1: covered. Step 4: 2 is 0.4 from 0 but 0.5 from 1, so it joins 0.
    let params = ClusterParams { d_init: 1.0, z_far: 40.0, adaptive: true };
    let c = cluster_lights(&lights, camera.position, &frustum, &params);
    let centers: Vec<usize> = c.clusters.iter().map(|k| k.center).collect();
    assert_eq!(centers, vec![1, 5, 3, 0, 4]);
    assert_eq!(c.clusters[0].d_min, 0.5);
    assert_eq!(c.clusters[0].members, vec![1, 6]);
    assert_eq!(c.clusters[3].members, vec![0, 2]);
    assert_eq!(c, reference(&lights, camera.position, &frustum, &params));
}

#[test]
fn distance_exactly_d_min_is_covered_and_ties_go_to_the_first_center() {
    // Non-adaptive, d_init 1: lights at x = 0 (range 3) and x = 2 (range 2) are centers; x = 1 (range 1) is
    // exactly 1 from both: covered by the first and equidistant, so it joins the first-selected center.
    let camera = Camera::look_at(Vec3::new(1.0, 0.0, 20.0), Vec3::new(1.0, 0.0, 0.0), 60f32.to_radians(), 0.1, 100.0);
    let frustum = frustum_of(&camera);
    let lights = [light(Vec3::new(1.0, 0.0, 0.0), 1.0), light(Vec3::ZERO, 3.0), light(Vec3::new(2.0, 0.0, 0.0), 2.0)];
    let params = ClusterParams { d_init: 1.0, z_far: 100.0, adaptive: false };
    let c = cluster_lights(&lights, camera.position, &frustum, &params);
    assert_eq!(c.clusters.iter().map(|k| k.center).collect::<Vec<_>>(), vec![1, 2]);
    assert_eq!(c.cluster_of, vec![Some(0), Some(0), Some(1)]);
    assert_eq!(c.clusters[0].c_att, 3.0);
}

#[test]
fn dense_and_hash_grids_agree_with_the_reference() {
    let camera = cameras()[0];
    let frustum = frustum_of(&camera);
    let mut clusterer = Clusterer::new();
    for (seed, layout) in LAYOUTS.into_iter().enumerate() {
        let lights = make_lights(layout, 1200, 900 + seed as u64);
        for d_init in [0.002, 0.01, 0.5, 3.0] {
            for adaptive in [true, false] {
                let params = ClusterParams { d_init, z_far: 30.0, adaptive };
                let c = clusterer.cluster(&lights, camera.position, &frustum, &params);
                let info = clusterer.grid_info();
                // Spread-out layouts fit dense arrays; clumps (blobs) may need the hash table.
                if !matches!(layout, Layout::Blobs) {
                    assert_eq!(info.kind, GridKind::Dense, "{layout:?} d_init={d_init} {info:?}");
                }
                assert!(info.levels == 1 || adaptive, "{info:?}");
                assert_eq!(c, reference(&lights, camera.position, &frustum, &params), "{layout:?} d_init={d_init}");
            }
        }
    }
    // Tight clumps of lights plus far-away lights stretch the bounding box: levels with cells near the clumps'
    // spacing do not fit a dense array over the box, so they are hashed.
    let mut rng = Rng(5);
    let mut lights = Vec::new();
    for blob in 0..4 {
        let c = Vec3::new(blob as f32 * 3.0 - 6.0, 0.0, -10.0);
        for _ in 0..500 {
            lights.push(light(c + rng.vec3(Vec3::splat(-0.05), Vec3::splat(0.05)), rng.range(0.5, 7.0)));
        }
    }
    lights.push(light(Vec3::new(0.0, 0.0, -5000.0), 4990.0));
    lights.push(light(Vec3::new(3000.0, 0.0, -10.0), 3100.0));
    for adaptive in [false, true] {
        for d_init in [0.001, 0.005, 0.3] {
            let params = ClusterParams { d_init, z_far: 30.0, adaptive };
            let c = clusterer.cluster(&lights, camera.position, &frustum, &params);
            let info = clusterer.grid_info();
            if d_init < 0.01 {
                assert!(matches!(info.kind, GridKind::Hash | GridKind::Mixed), "d_init={d_init} {info:?}");
            }
            assert_eq!(c, reference(&lights, camera.position, &frustum, &params), "d_init={d_init} {info:?}");
        }
    }
}

/// Thousands of lights: the radix sort (4096 or more visible lights) and step 4 in grid order (2048 or more lights
/// left for it) against the reference.
#[test]
fn large_sets_match_the_reference() {
    let camera = cameras()[0];
    let frustum = frustum_of(&camera);
    let mut clusterer = Clusterer::new();
    let mut big_step4 = 0;
    for (layout, n, d_init, adaptive) in [
        (Layout::Blobs, 8000, 1.0f32, false),
        (Layout::Blobs, 8000, 0.3, true),
        (Layout::Uniform, 7000, 1.6, true),
        (Layout::EqualRanges, 7000, 0.8, false),
        (Layout::Lattice, 7000, 1.0, true),
        (Layout::Duplicates, 7000, 0.5, true),
    ] {
        let lights = make_lights(layout, n, n as u64 + d_init.to_bits() as u64);
        let params = ClusterParams { d_init, z_far: 30.0, adaptive };
        let c = clusterer.cluster(&lights, camera.position, &frustum, &params);
        let name = format!("{layout:?} n={n} d_init={d_init} adaptive={adaptive}");
        assert!(c.visible >= 4096, "{name}: {} visible", c.visible);
        big_step4 += (c.visible - c.clusters.len() >= 2048) as usize;
        assert_eq!(c, reference(&lights, camera.position, &frustum, &params), "{name}");
    }
    assert!(big_step4 >= 2, "step 4 in grid order was exercised {big_step4} times");
}

#[test]
fn extreme_coordinates_and_ranges() {
    // Positions up to 1e30 with ranges to match, seen by a camera with a huge far plane.
    let camera = Camera::look_at(Vec3::new(0.0, 0.0, 1e30), Vec3::ZERO, 60f32.to_radians(), 1.0, 1e32);
    let frustum = frustum_of(&camera);
    let mut rng = Rng(123);
    let mut lights = Vec::new();
    for i in 0..600 {
        let scale = [1e-3, 1.0, 1e10, 1e30][i % 4];
        let p = rng.vec3(Vec3::splat(-1.0), Vec3::splat(1.0)) * scale;
        lights.push(light(p, scale * rng.range(0.5, 2.0)));
    }
    for d_init in [0.0, 1e-3, 1.0, 1e9, 1e29, f32::MAX] {
        for adaptive in [true, false] {
            let params = ClusterParams { d_init, z_far: 1e32, adaptive };
            let c = cluster_lights(&lights, camera.position, &frustum, &params);
            assert_eq!(c, reference(&lights, camera.position, &frustum, &params), "d_init={d_init}");
            check_partition("extreme", &c);
        }
    }
}

#[test]
fn hundreds_of_random_small_sets_with_all_properties() {
    let mut rng = Rng(2024);
    for round in 0..400 {
        let n = rng.below(40);
        let layout = LAYOUTS[rng.below(LAYOUTS.len())];
        let camera = cameras()[rng.below(2)];
        let case = Case {
            name: format!("round {round}"),
            lights: make_lights(layout, n, rng.next_u64()),
            camera,
            frustum: frustum_of(&camera),
            params: ClusterParams {
                d_init: rng.range(0.0, 8.0),
                z_far: rng.range(5.0, 40.0),
                adaptive: rng.below(2) == 0,
            },
        };
        let c = run(&case);
        check_all(&case, &c);
        assert_eq!(c, reference(&case.lights, case.camera.position, &case.frustum, &case.params), "{}", case.name);
    }
}
