//! Timing of LightCluster's min-distance clustering (paper section 3.1) on one core.
//!
//! `cargo bench -p shadowlab-core --bench clustering` prints a Markdown table. Lights are uniform in a 30 m box
//! with ranges in 0.5..7 m; the camera sits at one end looking down the box (60 degree vertical field of view,
//! 16:9, `z_far` 30 as in the paper); view-adaptive `d_min`. "median ms" is the steady state of a frame: a
//! long-lived `Clusterer` writing into a reused `Clustering`. "fresh ms" is `cluster_lights`, which allocates
//! its buffers and every cluster's member list on each call. `CLUSTERING_LIGHTS=2048` runs one light count only.
//! The goals: 2,048 lights in under 0.05 ms, 100,000 in under 10 ms. Timings are wall-clock medians of
//! 31 samples, so a busy machine inflates them. "cover" is `centers=cover` (greedy covering, beyond the paper:
//! `lightcluster::cover`) on the same visible lights: its clusters and median ms.

use std::hint::black_box;
use std::time::Instant;

use glam::Vec3;
use shadowlab_core::math::Frustum;
use shadowlab_core::scene::{Camera, PointLight};
use shadowlab_core::technique::lightcluster::clustering::{cluster_lights, ClusterParams, Clusterer, Clustering};
use shadowlab_core::technique::lightcluster::cover::cluster_cover;

const COUNTS: [usize; 7] = [64, 256, 1024, 2048, 4096, 16384, 100_000];
const D_INITS: [f32; 2] = [0.5, 1.6];
const SAMPLES: usize = 31;

/// SplitMix64.
struct Rng(u64);

impl Rng {
    fn f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }
}

fn lights(n: usize, seed: u64) -> Vec<PointLight> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|_| {
            let p = Vec3::new(rng.range(-15.0, 15.0), rng.range(-15.0, 15.0), rng.range(-30.0, 0.0));
            PointLight::new(p, Vec3::ONE, 1.0, rng.range(0.5, 7.0))
        })
        .collect()
}

/// Median time per call in milliseconds, each sample averaging enough calls to last about 0.2 ms or more.
fn median_ms(mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    f();
    let once = start.elapsed().as_secs_f64();
    let batch = ((2e-4 / once.max(1e-9)) as usize).clamp(1, 10_000);
    for _ in 0..batch.min(100) {
        f(); // warm-up
    }
    let mut samples: Vec<f64> = (0..SAMPLES)
        .map(|_| {
            let start = Instant::now();
            for _ in 0..batch {
                f();
            }
            start.elapsed().as_secs_f64() * 1e3 / batch as f64
        })
        .collect();
    samples.sort_by(f64::total_cmp);
    samples[SAMPLES / 2]
}

fn main() {
    let camera = Camera::look_at(Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -30.0), 60f32.to_radians(), 0.1, 30.0);
    let frustum = Frustum::from_clip_from_world(&camera.clip_from_world(16.0 / 9.0));
    println!(
        "| lights | visible | d_init | clusters | grid | median ms | ms per 1000 lights | fresh ms | cover clusters | \
         cover ms |"
    );
    println!("|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|");
    // `CLUSTERING_LIGHTS=2048` restricts the run to one light count (for profiling). `cargo test --all-targets`
    // runs this file without `--bench`: then only the smallest count runs, as a smoke test.
    let smoke = !std::env::args().any(|a| a == "--bench");
    let only: Option<usize> =
        std::env::var("CLUSTERING_LIGHTS").ok().and_then(|v| v.parse().ok()).or(smoke.then_some(COUNTS[0]));
    for &n in COUNTS.iter().filter(|&&n| only.is_none_or(|o| o == n)) {
        let lights = lights(n, n as u64);
        for &d_init in &D_INITS {
            let params = ClusterParams { d_init, z_far: camera.z_far, adaptive: true };
            let mut clusterer = Clusterer::new();
            let mut out = Clustering::default();
            let ms = median_ms(|| {
                clusterer.cluster_into(black_box(&lights), camera.position, &frustum, &params, &mut out);
                black_box(&out);
            });
            let fresh = median_ms(|| {
                black_box(cluster_lights(black_box(&lights), camera.position, &frustum, &params));
            });
            let visible: Vec<usize> = (0..n).filter(|&i| out.cluster_of[i].is_some()).collect();
            let mut covered = Clustering::default();
            let cover_ms = median_ms(|| {
                black_box(cluster_cover(black_box(&lights), &visible, camera.position, &params, &mut covered));
            });
            let cover_clusters = if cluster_cover(&lights, &visible, camera.position, &params, &mut covered) {
                covered.clusters.len().to_string()
            } else {
                "fallback".into()
            };
            let info = clusterer.grid_info();
            println!(
                "| {n} | {} | {d_init} | {} | {:?}, {} levels, {:.2}..{:.2} m | {ms:.4} | {:.4} | {fresh:.4} | \
                 {cover_clusters} | {cover_ms:.4} |",
                out.visible,
                out.clusters.len(),
                info.kind,
                info.levels,
                info.coarsest_cell,
                info.finest_cell,
                ms * 1000.0 / n as f64,
            );
        }
    }
}
