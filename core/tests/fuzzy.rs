//! Fuzzy clustering (Colom 2022) on the software adapter: the GPU k-means agrees with its CPU twin; one
//! cluster per VPL and per pixel is `vpl-raytraced` exactly; weighted visibility beats hard (the paper's
//! Fig. 5); the error falls as K_sp grows; bad parameters and a sky-only view give defined images.

mod common;

use common::*;
use glam::Vec3;
use shadowlab_core::scene::PointLight;
use shadowlab_core::technique::ParamValue;
use shadowlab_core::vpl::VplSettings;
use shadowlab_core::RenderSettings;

const W: u32 = 80;
const H: u32 = 60;

fn settings(vpls: u32) -> RenderSettings {
    indirect_settings(W, H, VplSettings { count: vpls, ..Default::default() })
}

fn lights() -> Vec<PointLight> {
    vec![white_light(Vec3::new(0.5, 3.0, 0.5), 8.0, 30.0)]
}

/// MSE of the green channel, as the paper reports it (over linear radiance).
fn mse(a: &[[f32; 4]], b: &[[f32; 4]]) -> f64 {
    a.iter().zip(b).map(|(p, q)| ((p[1] - q[1]) as f64).powi(2)).sum::<f64>() / a.len() as f64
}

fn rel_rmse(a: &[[f32; 4]], b: &[[f32; 4]]) -> f64 {
    let den: f64 = b.iter().map(|q| (q[1] as f64).powi(2)).sum::<f64>() / b.len() as f64;
    (mse(a, b) / den.max(1e-30)).sqrt()
}

fn int(k: &'static str, v: i64) -> (&'static str, ParamValue) {
    (k, ParamValue::Int(v))
}

fn choice(k: &'static str, v: &str) -> (&'static str, ParamValue) {
    (k, ParamValue::Choice(v.into()))
}

#[test]
fn one_cluster_per_vpl_and_per_pixel_is_vpl_raytraced() {
    let scene = room();
    let n = 128;
    // Traced particles: no two VPLs coincide (RSM texels drawn twice would share a cluster).
    let mut s = settings(n);
    s.vpl.source = shadowlab_core::vpl::VplSource::Traced;
    let (truth, _) = Shot::indirect(&scene, &lights(), s.clone(), "vpl-raytraced").render();
    let exact =
        [int("k_vpl", n as i64), int("k_sp", (W * H) as i64), int("gamma", 1), int("f", 1), choice("mode", "hard")];
    for cluster in ["both", "sp", "vpl"] {
        let mut params = exact.to_vec();
        params.push(choice("cluster", cluster));
        let (img, report) = Shot::indirect(&scene, &lights(), s.clone(), "fuzzy").params(&params).render();
        let err = rel_rmse(&img, &truth);
        if err >= 2e-3 {
            let expected: Vec<Option<[f32; 4]>> = truth.iter().map(|&p| Some(p)).collect();
            let bad: Vec<bool> = img.iter().zip(&truth).map(|(a, b)| (a[1] - b[1]).abs() > 1e-3).collect();
            write_failure_images(&format!("fuzzy_exact_{cluster}"), W, H, &img, &expected, &bad);
        }
        assert!(err < 2e-3, "cluster = {cluster}: one cluster each differs from vpl-raytraced by {err:.5}");
        let indirect = report.indirect.unwrap();
        let figures = &indirect.counts.figures;
        if cluster != "sp" {
            assert_eq!(figures["k_vpl"] as usize, indirect.vpls, "{cluster}: every VPL its own cluster");
        }
        if cluster != "vpl" {
            // Every geometry pixel is its own cluster (the sky's centroids stay inactive).
            assert_eq!(figures["k_sp"], figures["shading points"], "{cluster}");
            assert_eq!(figures["shadow rays"], figures["k_sp"] * figures["lights shaded"]);
        }
    }
}

#[test]
fn weighted_visibility_beats_hard_and_the_error_falls_with_k_sp() {
    let scene = room();
    let n = 128;
    let (truth, _) = Shot::indirect(&scene, &lights(), settings(n), "vpl-raytraced").render();
    let at_with = |percent: f32, mode: &str, assign: &str| {
        let params = [
            choice("cluster", "sp"),
            choice("mode", mode),
            ("k_sp_percent", ParamValue::Float(percent)),
            int("gamma", 2),
            choice("assign", assign),
        ];
        let (img, report) = Shot::indirect(&scene, &lights(), settings(n), "fuzzy").params(&params).render();
        assert!(img.iter().all(|p| p.iter().all(|c| c.is_finite())), "{mode} at {percent} %: NaN");
        let k = report.indirect.unwrap().counts.figures["k_sp"];
        (mse(&img, &truth), k, img)
    };
    let at = |percent: f32, mode: &str| {
        let (e, k, _) = at_with(percent, mode, "neighbours");
        (e, k)
    };
    // Weighted interpolation wins once the clusters are small against the shadows' features (here from about
    // 4 % of this 80x60 image, 190 clusters; measured: at 1 % hard is 4.4e-8, weighted 9.2e-8, fuzzy 1.7e-7;
    // at 8 % 9.0e-9, 5.0e-9, 9.2e-9).
    let (hard, _) = at(8.0, "hard");
    let (fuzzy, _) = at(8.0, "fuzzy");
    let (weighted, k) = at(8.0, "weighted");
    assert!(k > 100.0 && k <= 384.0, "8 % of 4,800 pixels: {k} clusters");
    assert!(weighted < hard, "weighted {weighted:.3e} is not better than hard {hard:.3e} (fuzzy {fuzzy:.3e})");
    assert!(weighted < fuzzy, "weighted {weighted:.3e} is not better than the plain mean {fuzzy:.3e}");
    let (coarse, _) = at(1.0, "weighted");
    assert!(weighted < coarse, "8 % of the pixels ({weighted:.3e}) is no better than 1 % ({coarse:.3e})");
    // The pixels between samples from their samples' lists (the default) against every pixel searching the
    // grid (the paper's Algorithm 2): a different image, about as close to the truth (measured: 8.92e-8 against
    // 9.22e-8).
    let (_, _, neighbours) = at_with(1.0, "weighted", "neighbours");
    let (searched, _, searched_img) = at_with(1.0, "weighted", "search");
    assert!(neighbours != searched_img, "assign=search renders the same image: the parameter is not used");
    assert!(coarse <= 1.25 * searched, "neighbour lists {coarse:.3e} against the search's {searched:.3e}");
}

#[test]
fn clustered_vpls_approach_the_reference_as_k_vpl_grows() {
    let scene = room();
    let n = 256;
    let (truth, _) = Shot::indirect(&scene, &lights(), settings(n), "vpl-raytraced").render();
    let mut errors = Vec::new();
    for k in [4i64, 32, 256] {
        let (img, report) = Shot::indirect(&scene, &lights(), settings(n), "fuzzy")
            .params(&[choice("cluster", "vpl"), int("k_vpl", k)])
            .render();
        let figures = &report.indirect.unwrap().counts.figures;
        assert!(figures["k_vpl"] >= 1.0 && figures["k_vpl"] <= k as f64);
        errors.push(rel_rmse(&img, &truth));
    }
    assert!(errors[2] < errors[0], "{errors:?}");
    assert!(errors[2] < 2e-3, "K_vpl = N: {errors:?}");
}

#[test]
fn bad_parameters_and_a_sky_only_view_give_defined_images() {
    let scene = room();
    for params in [
        vec![int("k_vpl", 65_536), int("k_sp", 65_536)], // more clusters than VPLs and than pixels
        vec![int("k_sp", 2), int("f", 8)],               // F above K
        vec![int("iterations", 0)],
        vec![("n_t", ParamValue::Float(1.0))], // nothing is compatible: by position
        vec![int("gamma", 64)],                // one sample
        vec![int("rays_per_step", 1024), int("lights_per_step", 7)],
    ] {
        let (img, report) = Shot::indirect(&scene, &lights(), settings(64), "fuzzy").params(&params).render();
        assert!(img.iter().all(|p| p.iter().all(|c| c.is_finite())), "{params:?}: NaN");
        assert!(img.iter().any(|p| p[1] > 0.0), "{params:?}: no indirect light");
        let figures = &report.indirect.unwrap().counts.figures;
        assert!(figures["k_vpl"] <= 64.0 && figures["k_sp"] <= (W * H) as f64, "{params:?}: {figures:?}");
    }
    // Steps change nothing.
    let (a, _) = Shot::indirect(&scene, &lights(), settings(64), "fuzzy").render();
    let (b, _) = Shot::indirect(&scene, &lights(), settings(64), "fuzzy")
        .params(&[int("rays_per_step", 1024), int("lights_per_step", 5)])
        .render();
    assert!(rel_rmse(&a, &b) < 1e-6);
    // No VPLs.
    let (img, _) = Shot::indirect(&scene, &lights(), settings(0), "fuzzy").render();
    assert!(img.iter().all(|p| p[1] == 0.0));
    // A view of the sky only: no shading point, nothing lit, no error.
    let mut sky = room();
    sky.camera =
        shadowlab_core::scene::Camera::look_at(Vec3::new(0.0, 50.0, 0.0), Vec3::new(0.3, 100.0, 0.0), 0.8, 0.1, 100.0);
    let (img, report) = Shot::indirect(&sky, &lights(), settings(64), "fuzzy").render();
    assert!(img.iter().all(|p| p[1] == 0.0));
    assert_eq!(report.indirect.unwrap().counts.figures["k_sp"], 0.0);
}

/// `km_blocks`: each block's merged list is its four corner samples' lists, each cluster once, in the order of
/// the corners and of each list (what a pixel of the block considered before), on an image whose last column and
/// row of pixels lie after the last sample (gamma 3 on 64 x 47: clamped corners).
#[test]
fn a_blocks_merged_list_holds_each_cluster_of_its_four_samples_once() {
    use shadowlab_core::technique::fuzzy::gpu::GpuKMeans;
    use shadowlab_core::technique::fuzzy::kmeans::{self, KMeansParams, Point};
    let gpu = gpu();
    let timer = shadowlab_core::timing::PassTimer::new(&gpu).unwrap();
    let (w, h) = (64u32, 47u32);
    let points: Vec<Point> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
            let (position, normal) = if (i / 5 + i / 200) % 3 == 0 {
                (Vec3::new(x * 4.0 - 2.0, 0.0, y * 4.0 - 2.0), Vec3::Y)
            } else {
                (Vec3::new(x * 4.0 - 2.0, y * 3.0, -2.0), Vec3::Z)
            };
            Point { position, normal, valid: i % 17 != 3 }
        })
        .collect();
    let buffer = upload_points(&gpu, &points);
    let mut km = GpuKMeans::new(&gpu, "test");
    for (gamma, f) in [(3u32, 6usize), (2, 8), (4, 3)] {
        let p = KMeansParams { iterations: 4, ..room_kmeans_params(w, h, 60, gamma, f, true) };
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        km.encode(&gpu, &timer, &mut encoder, &buffer, &p, None, false).unwrap();
        gpu.queue.submit([encoder.finish()]);
        let (assignment, _) = km.read_assignment(&gpu).unwrap();
        let blocks = km.read_block_lists(&gpu, &p).unwrap();
        let (g, wu) = (gamma as usize, w as usize);
        let per_row = wu.div_ceil(g);
        assert_eq!(blocks.len(), per_row * (h as usize).div_ceil(g), "gamma {gamma}");
        let mut longest = 0;
        for (s, list) in blocks.iter().enumerate() {
            // The block's top left pixel: its corners as kmeans.rs finds them for a pixel of the block.
            let (sx, sy) = (s % per_row, s / per_row);
            let corners = kmeans::sample_corners(&p, sy * g * wu + sx * g);
            let mut expected = Vec::new();
            for c in corners {
                for &k in assignment[c * f..c * f + f].iter().take_while(|&&k| k != u32::MAX) {
                    if !expected.contains(&k) {
                        expected.push(k);
                    }
                }
            }
            assert_eq!(list, &expected, "gamma {gamma} F {f} block {s}");
            longest = longest.max(list.len());
        }
        // The four lists differ somewhere: a block holds more than one sample's F.
        assert!(longest > f, "gamma {gamma}: the longest merged list has {longest} clusters");
    }
}

#[test]
fn the_searches_a_workgroup_finishes_find_the_clusters_one_invocation_finds() {
    // A CPU rasterizer's schedule (every search by one invocation; km_fill's short lists queued for km_search)
    // against a real GPU's (the grid's first shells, then a workgroup per unfinished search, over the queue): the
    // same clusters, weights and members, and the workgroups' path taken.
    use shadowlab_core::technique::fuzzy::gpu::GpuKMeans;
    use shadowlab_core::technique::fuzzy::kmeans::KMeansParams;
    let gpu = gpu();
    let timer = shadowlab_core::timing::PassTimer::new(&gpu).unwrap();
    let (w, h) = (64u32, 48u32);
    // Tilted normals: many pixels find fewer than F compatible clusters in their block's list and search.
    let points = room_points(w, h, 1.2);
    let buffer = upload_points(&gpu, &points);
    let mut km = GpuKMeans::new(&gpu, "test");
    for (k, f, gamma, max_ring) in [(20usize, 6usize, 2u32, 0u32), (600, 3, 4, 0), (150, 6, 3, 1), (150, 8, 2, 0)] {
        let p = KMeansParams { max_ring, ..room_kmeans_params(w, h, k, gamma, f, true) };
        let mut runs = Vec::new();
        // The last: searches that stop alone after 16 cells and centroids.
        for (gpu_schedule, near_shells, fine_levels, near_budget) in
            [(false, 2, 0, 0), (true, 2, 1, 0), (true, 0, 3, 0), (true, 2, 2, 0), (true, 2, 1, 16)]
        {
            km.set_gpu_schedule(&gpu, gpu_schedule);
            km.set_near_shells(near_shells);
            km.set_near_budget(near_budget);
            km.set_fine_levels(fine_levels, 1);
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            km.encode(&gpu, &timer, &mut encoder, &buffer, &p, None, false).unwrap();
            gpu.queue.submit([encoder.finish()]);
            let queued = km.read_queue_len(&gpu, &p).unwrap();
            runs.push((km.read_assignment(&gpu).unwrap(), km.read_clusters(&gpu).unwrap(), queued));
        }
        let members = |c: &Vec<shadowlab_core::technique::fuzzy::gpu::GpuPoint>| -> Vec<u32> {
            c.iter().map(|c| c.members()).collect()
        };
        let ((alone, alone_w), alone_clusters, alone_queued) = &runs[0];
        for ((wide, wide_w), wide_clusters, _) in &runs[1..] {
            assert_eq!(alone, wide, "K = {k} F = {f}: the clusters differ");
            assert_eq!(alone_w, wide_w, "K = {k} F = {f}: the weights differ");
            assert_eq!(members(alone_clusters), members(wide_clusters), "K = {k} F = {f}");
        }
        // The paths are taken: km_fill queued pixels short of F compatible clusters for km_search; with no shell
        // walked first (the paper's ring-limited search aside, which the buckets do not serve) the real GPU's
        // schedule queued pixels for the workgroups.
        assert!(*alone_queued > 0, "K = {k} F = {f}: km_fill queued nothing");
        if max_ring == 0 {
            assert!(runs[2].2 > 0, "K = {k} F = {f}: no search went to a workgroup");
            // A work budget of 16 sends more of km_fill's searches to the workgroups than two shells alone do.
            assert!(runs[4].2 > runs[1].2, "K = {k} F = {f}: the budget queued {} against {}", runs[4].2, runs[1].2);
        }
        // Some pixels hold a cluster that their block's merged list does not (they searched).
        let blocks = km.read_block_lists(&gpu, &p).unwrap();
        let (g, wu) = (gamma as usize, w as usize);
        let searched = (0..points.len())
            .filter(|&m| (m % wu) % g != 0 || (m / wu) % g != 0)
            .filter(|&m| {
                let block = &blocks[(m / wu / g) * wu.div_ceil(g) + (m % wu) / g];
                alone[m * f..m * f + f].iter().any(|&c| c != u32::MAX && !block.contains(&c))
            })
            .count();
        assert!(searched > 0, "K = {k} F = {f}: no pixel searched beyond its block's list");
    }
}

/// Points on the five walls of a room of bounds (-2, 0, -2) + (4, 3, 4) as an image of `w` x `h`, some invalid,
/// their normals tilted by up to `tilt` (1.2: about 50 degrees, as on curved or slanted surfaces).
fn room_points(w: u32, h: u32, tilt: f32) -> Vec<shadowlab_core::technique::fuzzy::kmeans::Point> {
    use shadowlab_core::technique::fuzzy::kmeans::Point;
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
            let wall = (i / 7 + i / 311) % 5;
            let (position, normal) = match wall {
                0 => (Vec3::new(x * 4.0 - 2.0, 0.0, y * 4.0 - 2.0), Vec3::Y),
                1 => (Vec3::new(x * 4.0 - 2.0, y * 3.0, -2.0), Vec3::Z),
                2 => (Vec3::new(-2.0, y * 3.0, x * 4.0 - 2.0), Vec3::X),
                3 => (Vec3::new(2.0, y * 3.0, x * 4.0 - 2.0), -Vec3::X),
                _ => (Vec3::new(x * 4.0 - 2.0, 3.0, y * 4.0 - 2.0), -Vec3::Y),
            };
            let hash = |k: u32| ((i.wrapping_mul(2_654_435_761).wrapping_add(k * 40_503)) % 1000) as f32 / 1000.0 - 0.5;
            let normal = (normal + tilt * Vec3::new(hash(1), hash(2), hash(3))).normalize();
            Point { position, normal, valid: i % 13 != 4 }
        })
        .collect()
}

/// The GPU k-means tests' parameters: an image of `w` x `h` points of the room of bounds (-2, 0, -2) + (4, 3, 4),
/// the paper's n_t, exact searches, neighbour lists as given; the rest as each test sets it.
fn room_kmeans_params(
    w: u32,
    h: u32,
    clusters: usize,
    gamma: u32,
    fuzziness: usize,
    neighbour_lists: bool,
) -> shadowlab_core::technique::fuzzy::kmeans::KMeansParams {
    shadowlab_core::technique::fuzzy::kmeans::KMeansParams {
        clusters,
        iterations: 6,
        gamma,
        fuzziness,
        n_t: 3f32.sqrt() / 2.0,
        min_distance: 1e-6,
        max_ring: 0,
        neighbour_lists,
        width: w,
        height: h,
        bounds_min: Vec3::new(-2.0, 0.0, -2.0),
        bounds_extent: Vec3::new(4.0, 3.0, 4.0),
    }
}

/// Surface points as the GPU k-means reads them (the `GpuVpl` layout; position w: 1 when valid).
fn upload_points(
    gpu: &shadowlab_core::gpu::GpuContext,
    points: &[shadowlab_core::technique::fuzzy::kmeans::Point],
) -> wgpu::Buffer {
    use shadowlab_core::technique::fuzzy::gpu::GpuPoint;
    use wgpu::util::DeviceExt;
    let gpu_points: Vec<GpuPoint> = points
        .iter()
        .map(|p| GpuPoint {
            position: p.position.extend(if p.valid { 1.0 } else { 0.0 }).to_array(),
            normal: p.normal.extend(0.0).to_array(),
            flux: [0.0; 4],
        })
        .collect();
    gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(&gpu_points),
        usage: wgpu::BufferUsages::STORAGE,
    })
}

#[test]
fn gpu_kmeans_matches_its_cpu_twin() {
    use shadowlab_core::technique::fuzzy::gpu::GpuKMeans;
    use shadowlab_core::technique::fuzzy::kmeans::{self, KMeansParams};
    let gpu = gpu();
    let timer = shadowlab_core::timing::PassTimer::new(&gpu).unwrap();
    // Points on the five walls of a room, some invalid, as an image of 64 x 48; then the same with normals
    // tilted by up to 50 degrees (normals off the axes, as on curved or slanted surfaces).
    let (w, h) = (64u32, 48u32);
    for tilt in [0.0f32, 1.2] {
        let points = room_points(w, h, tilt);
        let buffer = upload_points(&gpu, &points);
        let mut km = GpuKMeans::new(&gpu, "test");
        // The last three: Algorithm 2 from the neighbouring samples' lists (km_final over the samples, km_fill);
        // every case with the exact searches walking the grid, scanning the normal buckets, or either by count,
        // in a CPU rasterizer's schedule and in a real GPU's (the first shells, then a workgroup per unfinished
        // search; with 0 shells nearly every search is a workgroup's).
        let limit = shadowlab_core::technique::fuzzy::gpu::BUCKET_SCAN_LIMIT;
        // A real GPU's grid levels: the defaults, none, and two or three with every cell of two or more centroids
        // descending (a crowd of 1). A CPU rasterizer's grid is the coarse level alone.
        use shadowlab_core::technique::fuzzy::gpu::{FINE_ABOVE as CROWD, FINE_LEVELS as LEVELS};
        for (scan_limit, gpu_schedule, near_shells, (fine_levels, fine_above)) in [
            (0, false, 2, (0, CROWD)),
            (u32::MAX, false, 2, (0, CROWD)),
            (limit, false, 2, (0, CROWD)),
            (limit, true, 2, (LEVELS, CROWD)),
            (u32::MAX, true, 2, (3, 1)),
            (limit, true, 0, (0, CROWD)),
            (limit, true, 1, (2, 1)),
        ] {
            km.set_bucket_scan_limit(scan_limit);
            km.set_gpu_schedule(&gpu, gpu_schedule);
            km.set_near_shells(near_shells);
            km.set_fine_levels(fine_levels, fine_above);
            for (k, f, gamma, max_ring, neighbour_lists) in [
                (1usize, 1usize, 1u32, 0u32, false),
                (20, 6, 2, 0, false),
                (150, 8, 1, 0, false),
                (600, 3, 4, 0, false),
                (150, 6, 2, 1, false),
                (20, 6, 2, 0, true),
                (600, 3, 4, 0, true),
                (150, 6, 3, 1, true),
            ] {
                let p = KMeansParams { max_ring, ..room_kmeans_params(w, h, k, gamma, f, neighbour_lists) };
                let cpu = kmeans::cluster(&points, &p);
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                km.encode(&gpu, &timer, &mut encoder, &buffer, &p, None, false).unwrap();
                gpu.queue.submit([encoder.finish()]);
                let (assignment, inverse) = km.read_assignment(&gpu).unwrap();
                let clusters = km.read_clusters(&gpu).unwrap();
                assert_eq!(clusters.len(), cpu.centroids.len());
                let f = cpu.fuzziness;
                // Nearest clusters agree for all but near-ties moved by rounding.
                let same = (0..points.len()).filter(|&m| assignment[m * f] == cpu.assignment[m * f]).count();
                assert!(same as f32 >= 0.98 * points.len() as f32, "K = {k}: {same} of {} agree", points.len());
                let all_same = (0..points.len())
                    .filter(|&m| assignment[m * f..m * f + f] == cpu.assignment[m * f..m * f + f])
                    .count();
                // Measured: every F-list agrees, tilted normals or not.
                assert!(
                    all_same as f32 >= 0.995 * points.len() as f32,
                    "tilt {tilt} K = {k} scan limit {scan_limit} GPU schedule {gpu_schedule} shells {near_shells} \
                     fine levels {fine_levels} above {fine_above}: {all_same} F-lists agree"
                );
                for m in (0..points.len()).filter(|&m| assignment[m * f] == cpu.assignment[m * f]) {
                    let (a, b) = (inverse[m * f], cpu.inverse_distance[m * f]);
                    assert!((a - b).abs() <= 1e-3 * b.max(1.0), "K = {k} point {m}: W {a} vs {b}");
                }
                // Members add up to the valid points.
                let members: u32 = clusters.iter().map(|c| c.members()).sum();
                assert_eq!(members as usize, points.iter().filter(|p| p.valid).count(), "K = {k}");
                assert_eq!(clusters.iter().filter(|c| c.exists()).count(), cpu.non_empty(), "K = {k}");
            }
        }
    }
}

#[test]
fn a_warm_started_gpu_kmeans_matches_its_cpu_twin_and_reseeds_centroids_that_left_the_view() {
    // A view clustered from Algorithm 1's samples, then a moved view (the points shifted and half of them
    // replaced by another wall) clustered from those centroids: the GPU's warm start against the twin's
    // `cluster_from` with the centroids the GPU left.
    use shadowlab_core::technique::fuzzy::gpu::GpuKMeans;
    use shadowlab_core::technique::fuzzy::kmeans::{self, Centroid, KMeansParams, Point};
    let gpu = gpu();
    let timer = shadowlab_core::timing::PassTimer::new(&gpu).unwrap();
    let (w, h) = (64u32, 48u32);
    let view = |shift: f32, wall_from: u32| -> Vec<Point> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
                let (position, normal) = if i % w >= wall_from {
                    (Vec3::new(2.0, y * 3.0, x * 4.0 - 2.0), -Vec3::X)
                } else {
                    (Vec3::new(x * 4.0 - 2.0 + shift, 0.0, y * 4.0 - 2.0), Vec3::Y)
                };
                Point { position, normal, valid: i % 17 != 3 }
            })
            .collect()
    };
    let upload = |points: &[Point]| upload_points(&gpu, points);
    // The room's bounds widened along x: the shifted views stay inside them.
    let p = KMeansParams { bounds_extent: Vec3::new(4.5, 3.0, 4.0), ..room_kmeans_params(w, h, 60, 2, 4, true) };
    let mut km = GpuKMeans::new(&gpu, "test");
    let run = |km: &mut GpuKMeans, points: &wgpu::Buffer, p: &KMeansParams, warm: bool| {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        km.encode(&gpu, &timer, &mut encoder, points, p, None, warm).unwrap();
        gpu.queue.submit([encoder.finish()]);
    };
    // Both schedules: a CPU rasterizer's and a real GPU's (whose workgroup-wide searches this view's new wall,
    // with no compatible centroid near it, takes; with 0 shells nearly every search).
    for (gpu_schedule, near_shells) in [(false, 2), (true, 2), (true, 0)] {
        km.set_gpu_schedule(&gpu, gpu_schedule);
        km.set_near_shells(near_shells);
        let first = view(0.0, w);
        run(&mut km, &upload(&first), &p, false);
        let start: Vec<Centroid> = km
            .read_centroids(&gpu)
            .unwrap()
            .iter()
            .map(|c| Centroid { position: c.position(), normal: c.normal(), active: c.exists() })
            .collect();
        assert_eq!(
            start,
            kmeans::cluster(&first, &p).centroids,
            "the cold run is the twin's (GPU schedule {gpu_schedule})"
        );
        // The floor moved by 0.3 and the right half of the image is a wall none of the centroids is on.
        let moved = view(0.3, w / 2);
        let warm = KMeansParams { iterations: 2, ..p };
        run(&mut km, &upload(&moved), &warm, true);
        let cpu = kmeans::cluster_from(&moved, &warm, Some(&start));
        let gpu_centroids = km.read_centroids(&gpu).unwrap();
        let (assignment, _) = km.read_assignment(&gpu).unwrap();
        let f = cpu.fuzziness;
        let same =
            (0..moved.len()).filter(|&m| assignment[m * f..m * f + f] == cpu.assignment[m * f..m * f + f]).count();
        assert!(
            same as f32 >= 0.995 * moved.len() as f32,
            "GPU schedule {gpu_schedule}: {same} of {} F-lists agree",
            moved.len()
        );
        for (g, c) in gpu_centroids.iter().zip(&cpu.centroids) {
            assert_eq!(g.exists(), c.active);
            assert!(!c.active || (g.position() - c.position).length() < 1e-4, "{g:?} vs {c:?}");
        }
        // Centroids whose floor points left the view started again on this view's samples: the wall has
        // clusters (its points are not all taken by floor clusters by position), and none is inactive.
        let on_wall = cpu.centroids.iter().filter(|c| c.active && c.normal.dot(-Vec3::X) > 0.9).count();
        assert!(on_wall >= 10, "{on_wall} centroids on the wall that came into view");
        let wall_points: Vec<usize> = (0..moved.len()).filter(|&m| moved[m].valid && m as u32 % w >= w / 2).collect();
        assert!(wall_points.iter().all(|&m| {
            let k = cpu.assignment[m * f];
            k != u32::MAX && cpu.inverse_distance[m * f] > 0.0
        }));
        // Without a warm start the same call clusters from the samples, as `cluster` does.
        run(&mut km, &upload(&moved), &warm, false);
        assert_eq!(km.read_assignment(&gpu).unwrap().0, kmeans::cluster(&moved, &warm).assignment);
        // Asked to start warm with another K, it starts from the samples: the last run's centroids are not this K's.
        let other_k = KMeansParams { clusters: 40, ..warm };
        run(&mut km, &upload(&moved), &other_k, true);
        assert_eq!(km.read_assignment(&gpu).unwrap().0, kmeans::cluster(&moved, &other_k).assignment);
    }
}

#[test]
fn the_explain_steps_of_the_indirect_techniques_name_layers_they_have_and_parameters_they_take() {
    // Every step that shows layers names at least one layer the technique offers after a frame, every step's
    // parameters are the technique's and parse, and every layer has a legend line of its own beyond the
    // primitive counts.
    let scene = room();
    for key in ["fuzzy", "val", "vpl-shadowmaps", "vpl-raytraced", "vpl-unshadowed"] {
        let renderer = Shot::indirect(&scene, &lights(), settings(64), key).render_keeping().renderer;
        let technique = renderer.indirect().unwrap();
        let layers = technique.overlays(&lights());
        let names: Vec<&str> = layers.iter().map(|l| l.name).collect();
        let steps = technique.explain();
        assert!(steps.len() >= 4, "{key}: {} steps", steps.len());
        for step in steps.iter().filter(|s| !s.layers.is_empty()) {
            assert!(
                step.layers.iter().any(|l| names.contains(l)),
                "{key} '{}': none of {:?} in {names:?}",
                step.title,
                step.layers
            );
        }
        let params = technique.params();
        for step in &steps {
            for (k, text) in step.params {
                let p = params.iter().find(|p| p.key == *k).unwrap_or_else(|| panic!("{key} '{}': no {k}", step.title));
                p.kind.parse(k, text).unwrap_or_else(|e| panic!("{key} '{}': {k}={text}: {e:?}", step.title));
            }
        }
        for layer in &layers {
            let legend = technique.overlay_legend(layer);
            let summary = layer.summary().len();
            assert!(legend.len() > summary, "{key}: layer '{}' has no legend of its own", layer.name);
        }
    }
}

/// The points of `layer` in `technique`'s overlays.
fn layer_points(technique: &dyn shadowlab_core::technique::Technique, lights: &[PointLight], layer: &str) -> Vec<Vec3> {
    use shadowlab_core::technique::Overlay;
    let layers = technique.overlays(lights);
    let layer = layers.into_iter().find(|l| l.name == layer).unwrap_or_else(|| panic!("no layer '{layer}'"));
    layer
        .primitives
        .iter()
        .filter_map(|o| if let Overlay::Point { position, .. } = o { Some(*position) } else { None })
        .collect()
}

#[test]
fn indirect_overlays_follow_moved_lights_as_the_next_frame_shows_them() {
    // The preview's overlay stages (`update_overlays`, run while a light is dragged) on a fresh instance that
    // never rendered: for the frame's lights they give the clusters the frame found (the CPU twins of the GPU
    // k-means), and for moved lights the ones the next frame finds, before it runs.
    use shadowlab_core::technique::OverlayUpdate;
    let scene = room();
    let first = lights();
    let moved = vec![white_light(Vec3::new(-0.6, 2.2, -0.4), 8.0, 30.0)];
    for (key, layer) in [("val", "val centres"), ("fuzzy", "vpl cluster representatives")] {
        let mut rendered = Shot::indirect(&scene, &first, settings(64), key).render_keeping();
        let renderer = &mut rendered.renderer;
        let camera = scene.camera;
        let mut follower = create_indirect(renderer, key, &[]);
        let update = renderer.update_overlays(follower.as_mut(), &camera, &first);
        // 64 VPLs: the preview's VPLs are the frame's (no note). An instance that never rendered has no
        // shading-point clusters to show.
        assert!(matches!(update, OverlayUpdate::Live { note: None, .. }), "{key}: {update:?}");
        assert!(!update.is_stale(layer), "{key}: {update:?}");
        assert_eq!(update.is_stale("shading-point clusters"), key == "fuzzy", "{key}: {update:?}");
        let close =
            |a: &[Vec3], b: &[Vec3]| a.len() == b.len() && a.iter().zip(b).all(|(p, q)| (*p - *q).length() < 1e-3);
        let framed = layer_points(renderer.indirect().unwrap(), &first, layer);
        let followed = layer_points(follower.as_ref(), &first, layer);
        assert!(!framed.is_empty() && close(&framed, &followed), "{key}: {framed:?} against {followed:?}");
        renderer.update_overlays(follower.as_mut(), &camera, &moved);
        let during = layer_points(follower.as_ref(), &moved, layer);
        assert!(!close(&during, &framed), "{key}: the overlay did not change for the moved light");
        let mut direct = create(renderer, "unshadowed", &[]);
        frame(renderer, direct.as_mut(), &camera, &moved);
        let next = layer_points(renderer.indirect().unwrap(), &moved, layer);
        assert!(close(&next, &during), "{key}: the next frame shows {next:?}, the preview showed {during:?}");
        // The rendered instance: its shading-point clusters are live while only a light moves, and said to be
        // stale (of the last frame's G-buffer) once the camera moved.
        let update = renderer.update_indirect_overlays(&camera, &first).unwrap();
        assert!(!update.is_stale("shading-point clusters") && !update.is_stale(layer), "{key}: {update:?}");
        let mut turned = camera;
        turned.position += Vec3::new(0.3, 0.0, 0.0);
        let update = renderer.update_indirect_overlays(&turned, &moved).unwrap();
        // Fuzzy clustering's shading-point clusters follow the moved camera too (clustered again on the CPU).
        assert!(!update.is_stale("shading-point clusters") && !update.is_stale(layer), "{key}: {update:?}");
        if key == "fuzzy" {
            let note = update.note("shading-point clusters").unwrap_or_default();
            assert!(note.contains("grid of rays on the CPU"), "{note}");
        }
    }
}

/// The layer's per-pixel map: (width, height, ids).
fn id_map(technique: &dyn shadowlab_core::technique::Technique, lights: &[PointLight]) -> (u32, u32, Vec<u32>) {
    use shadowlab_core::technique::Overlay;
    let layers = technique.overlays(lights);
    let layer = layers.iter().find(|l| l.name == "shading-point clusters").expect("the per-pixel map's layer");
    match &layer.primitives[..] {
        [Overlay::IdMap { width, height, ids, .. }] => (*width, *height, ids.to_vec()),
        other => panic!("{other:?}"),
    }
}

#[test]
fn the_shading_point_clusters_follow_a_moving_camera_as_the_next_frame_clusters_that_view() {
    // While the camera moves the preview renders no G-buffer; the overlay stage clusters a grid of the moved
    // camera's rays on the CPU. Its map covers what the next frame's does (the same surfaces and sky), with about
    // as many clusters, and its centroids lie on the surfaces the new view sees.
    const PROBE: &str = "probe: clusters and visibility rays (green visible, red blocked)";
    let scene = room();
    let probe = [int("probe_x", W as i64 / 2), int("probe_y", H as i64 * 2 / 3)];
    let Rendered { mut renderer, .. } =
        Shot::indirect(&scene, &lights(), settings(64), "fuzzy").params(&probe).render_keeping();
    let framed = id_map(renderer.indirect().unwrap(), &lights());
    assert_eq!((framed.0, framed.1), (W, H));
    let mut turned = scene.camera;
    turned.position += Vec3::new(1.5, 0.5, 0.0);
    turned.orientation *= glam::Quat::from_rotation_y(0.4);
    let update = renderer.update_indirect_overlays(&turned, &lights()).unwrap();
    assert!(!update.is_stale("shading-point clusters") && !update.is_stale(PROBE), "{update:?}");
    let live = id_map(renderer.indirect().unwrap(), &lights());
    let centroids = layer_points(renderer.indirect().unwrap(), &lights(), "shading-point centroids");
    let probe_points = |t: &dyn shadowlab_core::technique::Technique| layer_points(t, &lights(), PROBE);
    let live_probe = probe_points(renderer.indirect().unwrap());
    // The next frame, at the turned camera.
    let mut direct = create(&renderer, "unshadowed", &[]);
    frame(&mut renderer, direct.as_mut(), &turned, &lights());
    let next = id_map(renderer.indirect().unwrap(), &lights());
    let next_probe = probe_points(renderer.indirect().unwrap());
    assert_ne!(next.2, framed.2, "the turned view clusters other pixels");
    let (pw, ph) = (live.0, live.1);
    assert_eq!((pw, ph), (W / 2, H / 2), "80x60 is past 4,096 points: every second pixel");
    // Sky or surface at each grid pixel's centre, as the frame sees it there.
    let (mut agree, mut total) = (0, 0);
    for y in 0..ph {
        for x in 0..pw {
            let (fx, fy) =
                (((x as f32 + 0.5) / pw as f32 * W as f32) as u32, ((y as f32 + 0.5) / ph as f32 * H as f32) as u32);
            let framed_valid = next.2[(fy * W + fx) as usize] != u32::MAX;
            let live_valid = live.2[(y * pw + x) as usize] != u32::MAX;
            agree += usize::from(framed_valid == live_valid);
            total += 1;
        }
    }
    assert!(agree * 100 >= total * 97, "{agree} of {total} grid pixels agree on sky and surface");
    let count = |ids: &[u32]| ids.iter().filter(|&&k| k != u32::MAX).collect::<std::collections::BTreeSet<_>>().len();
    let (live_k, next_k) = (count(&live.2), count(&next.2));
    assert!(live_k * 2 >= next_k && live_k <= next_k * 2, "{live_k} clusters in the preview, {next_k} in the frame");
    // The centroids are the view's: each near one of the next frame's (the same surfaces, clustered alike).
    let frame_centroids = layer_points(renderer.indirect().unwrap(), &lights(), "shading-point centroids");
    let mut nearest: Vec<f32> = centroids
        .iter()
        .map(|c| frame_centroids.iter().map(|f| f.distance(*c)).fold(f32::INFINITY, f32::min))
        .collect();
    nearest.sort_by(f32::total_cmp);
    let spacing = {
        let mut d: Vec<f32> = frame_centroids
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let others = frame_centroids.iter().enumerate().filter(|(j, _)| *j != i);
                others.map(|(_, b)| a.distance(*b)).fold(f32::INFINITY, f32::min)
            })
            .collect();
        d.sort_by(f32::total_cmp);
        d[d.len() / 2]
    };
    let median = nearest[nearest.len() / 2];
    // (Measured: 0.17 against a spacing of 1.42.)
    assert!(median <= 0.5 * spacing, "median {median} against the frame's spacing {spacing}");
    // The probed pixel's nearest cluster in the preview stands where the next frame's does, within about a
    // cluster (both hold the surface point the pixel sees).
    assert!(!live_probe.is_empty() && !next_probe.is_empty(), "{live_probe:?} {next_probe:?}");
    let apart = live_probe[0].distance(next_probe[0]);
    // (Measured: 0.12, each with 6 clusters.)
    assert!(apart <= 2.0 * spacing, "the probe's cluster {apart} from the next frame's (spacing {spacing})");
}

#[test]
fn a_frame_with_the_last_frames_vpls_reuses_their_clusters_and_renders_the_same() {
    // The renderer keeps its VPL set while the lights do not change (only the camera moves, or the same view
    // again): fuzzy clustering then reuses the VPL clusters on the GPU instead of clustering them again.
    let scene = room();
    let Rendered { mut renderer, hdr: first, report } =
        Shot::indirect(&scene, &lights(), settings(256), "fuzzy").params(&[int("k_vpl", 32)]).render_keeping();
    let reused = |r: &shadowlab_core::FrameReport| r.indirect.as_ref().unwrap().counts.figures["vpl clusters reused"];
    assert_eq!(reused(&report), 0.0, "the first frame clusters");
    let mut direct = create(&renderer, "unshadowed", &[]);
    let (again, report) = frame(&mut renderer, direct.as_mut(), &scene.camera, &lights());
    assert!(report.indirect.as_ref().unwrap().vpls_reused);
    assert_eq!(reused(&report), 1.0, "the same VPLs are clustered again");
    assert!(again == first, "reused clusters render another image");
    assert_eq!(report.indirect.as_ref().unwrap().counts.figures["k_vpl"], 32.0);
    // A moved light makes new VPLs: clustered again, and the image changes.
    let moved = vec![white_light(Vec3::new(-0.6, 2.2, -0.4), 8.0, 30.0)];
    let (other, report) = frame(&mut renderer, direct.as_mut(), &scene.camera, &moved);
    assert_eq!(reused(&report), 0.0);
    assert!(other != first);
    // Another K_vpl with the same VPLs: clustered again.
    renderer.indirect_mut().unwrap().set_param("k_vpl", &ParamValue::Int(16)).unwrap();
    let (_, report) = frame(&mut renderer, direct.as_mut(), &scene.camera, &moved);
    assert_eq!(reused(&report), 0.0, "new settings reuse old clusters");
    assert_eq!(report.indirect.as_ref().unwrap().counts.figures["k_vpl"], 16.0);
    let (_, report) = frame(&mut renderer, direct.as_mut(), &scene.camera, &moved);
    assert_eq!(reused(&report), 1.0);
}

#[test]
fn a_frame_of_the_same_view_reuses_the_shading_point_clusters_and_renders_what_clustering_again_would() {
    // The shading-point clusters depend on the G-buffer alone: while the view stays (a light dragged, the same
    // frame again) they are reused; a moved camera or `reuse=vpls` / `none` clusters again.
    let scene = room();
    let Rendered { mut renderer, hdr: first, report } =
        Shot::indirect(&scene, &lights(), settings(256), "fuzzy").params(&[int("k_vpl", 32)]).render_keeping();
    let reused = |r: &shadowlab_core::FrameReport| r.indirect.as_ref().unwrap().counts.figures["sp clusters reused"];
    assert_eq!(reused(&report), 0.0, "the first frame clusters");
    let mut direct = create(&renderer, "unshadowed", &[]);
    let (again, report) = frame(&mut renderer, direct.as_mut(), &scene.camera, &lights());
    assert_eq!(reused(&report), 1.0, "the same view is clustered again");
    assert!(again == first, "reused clusters render another image");
    // A moved light: the view's clusters are kept, the light's shading is new.
    let moved = vec![white_light(Vec3::new(-0.6, 2.2, -0.4), 8.0, 30.0)];
    let (kept, report) = frame(&mut renderer, direct.as_mut(), &scene.camera, &moved);
    assert_eq!(reused(&report), 1.0, "a moved light re-clusters the unchanged view");
    assert!(kept != first);
    // Clustering every frame from Algorithm 1's initial samples renders the same image.
    let set = |r: &mut shadowlab_core::Renderer, k: &str, v: ParamValue| r.indirect_mut().unwrap().set_param(k, &v);
    set(&mut renderer, "warm_iterations", ParamValue::Int(0)).unwrap();
    for (reuse, vpls_reused) in [("vpls", 1.0), ("none", 0.0)] {
        set(&mut renderer, "reuse", ParamValue::Choice(reuse.into())).unwrap();
        let (fresh, report) = frame(&mut renderer, direct.as_mut(), &scene.camera, &moved);
        let figures = &report.indirect.as_ref().unwrap().counts.figures;
        assert_eq!(figures["sp clusters reused"], 0.0, "reuse={reuse} reused the view's clusters");
        assert_eq!(figures["sp clusters warm-started"], 0.0, "warm_iterations=0 started warm");
        assert_eq!(figures["vpl clusters reused"], vpls_reused, "reuse={reuse}: VPL clusters");
        assert!(fresh == kept, "the reused clusters shade differently from clustering again (reuse={reuse})");
    }
    // A turned camera started from the last view's centroids (the default): two iterations from there are about
    // as close to the unclustered gather as eight from the initial samples (checked at the end).
    let mut turned = scene.camera;
    turned.position += Vec3::new(0.3, 0.1, 0.0);
    set(&mut renderer, "warm_iterations", ParamValue::Int(2)).unwrap();
    let warm_started =
        |r: &shadowlab_core::FrameReport| r.indirect.as_ref().unwrap().counts.figures["sp clusters warm-started"];
    let (warm, report) = frame(&mut renderer, direct.as_mut(), &turned, &moved);
    assert_eq!(warm_started(&report), 1.0, "a step of a camera motion starts from the last view's centroids");
    set(&mut renderer, "warm_iterations", ParamValue::Int(0)).unwrap();
    let (cold, _) = frame(&mut renderer, direct.as_mut(), &turned, &moved);
    assert!(warm != cold);
    set(&mut renderer, "warm_iterations", ParamValue::Int(2)).unwrap();
    // A jump (the camera turned by 60 degrees) starts from the samples: the view a user stops on after a long
    // drag is clustered as fully as a first frame.
    let mut jumped = turned;
    jumped.orientation = glam::Quat::from_rotation_y(60f32.to_radians()) * turned.orientation;
    let (_, report) = frame(&mut renderer, direct.as_mut(), &jumped, &moved);
    assert_eq!(warm_started(&report), 0.0, "a 60 degree turn started from the last view's centroids");
    set(&mut renderer, "reuse", ParamValue::Choice("all".into())).unwrap();
    // A moved camera clusters again.
    let mut turned = scene.camera;
    turned.position += Vec3::new(0.05, 0.0, 0.0);
    let (_, report) = frame(&mut renderer, direct.as_mut(), &turned, &moved);
    assert_eq!(reused(&report), 0.0, "a moved camera reused the old view's clusters");
    let (_, report) = frame(&mut renderer, direct.as_mut(), &turned, &moved);
    assert_eq!(reused(&report), 1.0);
    // The warm and cold frames of the turned view against the unclustered gather (measured: 0.387 / 0.391).
    let truth = create_indirect(&renderer, "vpl-raytraced", &[]);
    renderer.set_indirect(Some(truth)).unwrap();
    let (truth, _) = frame(&mut renderer, direct.as_mut(), &turned, &moved);
    let (e_warm, e_cold) = (rel_rmse(&warm, &truth), rel_rmse(&cold, &truth));
    assert!(e_warm <= 1.1 * e_cold, "warm start {e_warm} against {e_cold} from the initial samples");
}

#[test]
fn timing_every_clustering_dispatch_and_either_schedule_render_the_same() {
    // `time_dispatches` puts each dispatch of the clustering in a timed pass of its own (profiling on a real GPU)
    // instead of one pass per stage: the report names the kernels, and the image does not change.
    let scene = room();
    let Rendered { mut renderer, hdr: staged, .. } = Shot::indirect(&scene, &lights(), settings(256), "fuzzy")
        .params(&[int("k_vpl", 32), choice("reuse", "none")])
        .render_keeping();
    let names = |r: &shadowlab_core::FrameReport| -> Vec<String> {
        r.indirect.as_ref().unwrap().passes.iter().map(|p| p.name.clone()).collect()
    };
    // GPU timestamps: the clock that times passes apart (auto may leave lavapipe's for the steps' wall time).
    renderer.set_timing_mode(shadowlab_core::timing::TimingMode::Gpu);
    let mut direct = create(&renderer, "unshadowed", &[]);
    let (staged_again, report) = frame(&mut renderer, direct.as_mut(), &scene.camera, &lights());
    assert!(staged_again == staged);
    let staged_names = names(&report);
    for stage in ["iterations", "assignment", "search"] {
        let name = format!("fuzzy clustering (shading points): {stage}");
        assert!(staged_names.contains(&name), "no pass {name:?} in {staged_names:?}");
    }
    renderer.indirect_mut().unwrap().set_param("time_dispatches", &ParamValue::Bool(true)).unwrap();
    let (apart, report) = frame(&mut renderer, direct.as_mut(), &scene.camera, &lights());
    assert!(apart == staged, "timing each dispatch changed the image");
    let apart_names = names(&report);
    // The VPLs have no neighbour lists (every VPL is a sample): their Algorithm 2 is km_final alone.
    let kernels = [
        ("shading points", "iterations: km_assign"),
        ("shading points", "iterations: grid_scan"),
        ("shading points", "assignment: km_fill"),
        ("shading points", "search: rep_pick"),
        ("vpls", "iterations: km_init"),
        ("vpls", "assignment: km_final"),
    ];
    for (label, kernel) in kernels {
        let name = format!("fuzzy clustering ({label}): {kernel}");
        assert!(apart_names.contains(&name), "no pass {name:?} in {apart_names:?}");
    }
    assert!(!apart_names.iter().any(|n| n == "fuzzy clustering (shading points): assignment"));
    // A real GPU's schedule on this adapter (`schedule=gpu`): its kernels run, the image is the same.
    renderer.indirect_mut().unwrap().set_param("schedule", &ParamValue::Choice("gpu".into())).unwrap();
    let (gpu_schedule, report) = frame(&mut renderer, direct.as_mut(), &scene.camera, &lights());
    assert!(gpu_schedule == staged, "a real GPU's schedule changed the image");
    let names = names(&report);
    for kernel in ["iterations: grid_sums", "iterations: km_assign_wide", "search: km_search_wide"] {
        let name = format!("fuzzy clustering (shading points): {kernel}");
        assert!(names.contains(&name), "no pass {name:?} in {names:?}");
    }
}

#[test]
fn the_search_counts_add_up_to_the_points_each_kernel_searched_and_queued() {
    // `count_searches`: per kind of search the points, cells, centroids and queued points. The points queued by
    // one kernel are the points the next searched, and every valid point is searched once per pass over it.
    use shadowlab_core::technique::fuzzy::gpu::{GpuKMeans, SEARCH_KINDS};
    let gpu = gpu();
    let timer = shadowlab_core::timing::PassTimer::new(&gpu).unwrap();
    let (w, h) = (64u32, 48u32);
    let points = room_points(w, h, 1.2);
    let buffer = upload_points(&gpu, &points);
    let p = room_kmeans_params(w, h, 150, 4, 6, true);
    let valid = |m: &usize| points[*m].valid;
    let g = p.gamma as usize;
    let on_grid = |m: &usize| (m % w as usize).is_multiple_of(g) && (m / w as usize).is_multiple_of(g);
    let samples = (0..points.len()).filter(valid).filter(on_grid).count() as u32;
    let between = (0..points.len()).filter(valid).filter(|m| !on_grid(m)).count() as u32;
    let mut km = GpuKMeans::new(&gpu, "test");
    assert_eq!(km.read_search_counts(&gpu).unwrap(), None, "counting is off by default");
    km.set_count_searches(&gpu, true);
    for (gpu_schedule, near_shells) in [(false, 2), (true, 2), (true, 0)] {
        km.set_gpu_schedule(&gpu, gpu_schedule);
        km.set_near_shells(near_shells);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        km.encode(&gpu, &timer, &mut encoder, &buffer, &p, None, false).unwrap();
        gpu.queue.submit([encoder.finish()]);
        let c = km.read_search_counts(&gpu).unwrap().expect("counting");
        let [assign, assign_wide, last, fill, search] = c;
        let at = format!("GPU schedule {gpu_schedule}, {near_shells} shells: {SEARCH_KINDS:?} {c:?}");
        assert_eq!(assign.points, p.iterations * samples, "{at}");
        assert_eq!(last.points, samples, "{at}");
        assert_eq!(fill.points, between, "{at}");
        assert_eq!(assign_wide.points, assign.queued, "{at}");
        assert_eq!(search.points, last.queued + fill.queued, "{at}");
        assert!(fill.queued > 0 && assign.cells > 0 && assign.centroids > 0 && fill.centroids > 0, "{at}");
        if gpu_schedule {
            // With no shell walked alone, every unfinished sample search goes to a workgroup.
            assert!(near_shells > 0 || (assign.queued > 0 && last.queued > 0), "{at}");
        } else {
            assert_eq!(assign.queued + last.queued + assign_wide.points, 0, "{at}");
        }
        assert!(assign.most > 0 && assign.most <= assign.cells + assign.centroids, "{at}");
    }
}
