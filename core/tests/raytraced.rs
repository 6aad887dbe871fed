//! The ray-traced ground truth: BVH traversal (CPU twin against brute force, GPU against the CPU twin) and
//! images (hard shadows against the reference and the analytic answer, soft shadows against the analytic
//! penumbra of a disc light behind a straight edge), on the software adapter.

mod common;

use common::analytic::{self, camera_ray, cast, ground_visibility, Hit, AMBIENT, H, W};
use common::*;
use glam::{Vec2, Vec3, Vec4};
use shadowlab_core::accel::bvh::{occluded_brute_force, occluded_cpu, Bvh, Ray};
use shadowlab_core::accel::gpu_trace::gpu_occluded;
use shadowlab_core::scene::chunks::ChunkedGeometry;
use shadowlab_core::scene::{attenuation, Aabb, Camera, Material, Mesh, PointLight, Scene, SceneSource};
use shadowlab_core::technique::{ParamError, ParamValue};
use shadowlab_core::{RenderSettings, Renderer, ToneMap};

/// The ray offset the image tests set ("bias": world units per metre of camera distance).
const BIAS: f32 = 0.001;

// ---------------------------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------------------------

/// SplitMix64: deterministic test randomness.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
    fn direction(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.range(-1.0, 1.0), self.range(-1.0, 1.0), self.range(-1.0, 1.0));
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
}

fn settings() -> RenderSettings {
    RenderSettings {
        width: W,
        height: H,
        ambient: Vec3::splat(AMBIENT),
        background: Vec3::new(0.0, 0.0, 1.0),
        tonemap: ToneMap::Linear,
        ..Default::default()
    }
}

/// What the image tests set on the ray tracer before their own parameters.
const TRACED: Params = &[("bias", ParamValue::Float(BIAS))];

/// Share of pixels whose largest per-channel relative difference exceeds `tol`, and the largest difference.
fn compare(a: &[[f32; 4]], b: &[[f32; 4]], tol: f32) -> (f32, f32) {
    let mut worst = 0f32;
    let mut over = 0usize;
    for (p, q) in a.iter().zip(b) {
        let d = (0..3).map(|c| (p[c] - q[c]).abs() / (1e-3 + q[c].abs())).fold(0f32, f32::max);
        worst = worst.max(d);
        if d > tol {
            over += 1;
        }
    }
    (over as f32 / a.len() as f32, worst)
}

/// Shadow-ray-like rays over a scene: between random points on random triangles (they graze and hit geometry),
/// from random points in the bounds in random directions, and, one in four, ties: rays aimed exactly at a
/// vertex or an edge midpoint, half of them along a coordinate axis (zero direction components).
fn random_rays(bvh: &Bvh, bounds: &Aabb, count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng(seed);
    let size = bounds.size();
    let diag = size.length();
    let point_on_triangle = |rng: &mut Rng| {
        let t = &bvh.triangles[(rng.next_u64() % bvh.triangles.len() as u64) as usize];
        let [a, b, c] = t.vertices();
        let (mut u, mut v) = (rng.unit(), rng.unit());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let n = (b - a).cross(c - a).normalize();
        (a + (b - a) * u + (c - a) * v, n)
    };
    (0..count)
        .map(|i| {
            if i % 4 == 3 {
                let t = &bvh.triangles[(rng.next_u64() % bvh.triangles.len() as u64) as usize];
                let v = t.vertices();
                let k = (rng.next_u64() % 3) as usize;
                let target = if rng.unit() < 0.5 { v[k] } else { (v[k] + v[(k + 1) % 3]) * 0.5 };
                let dir = if i % 8 == 3 {
                    let axis = (rng.next_u64() % 3) as usize;
                    let sign = if rng.unit() < 0.5 { 1.0 } else { -1.0 };
                    Vec3::AXES[axis] * sign
                } else {
                    rng.direction()
                };
                let back = rng.range(0.01, diag * 0.5);
                Ray::new(target - dir * back, dir, back * 2.0)
            } else if i % 2 == 0 {
                let (p, n) = point_on_triangle(&mut rng);
                let (q, _) = point_on_triangle(&mut rng);
                let side = if rng.unit() < 0.5 { 1.0 } else { -1.0 };
                let origin = p + n * side * 1e-3;
                let to = q - origin;
                let d = to.length().max(1e-6);
                Ray::new(origin, to / d, d - 1e-3)
            } else {
                let origin = bounds.min - size * 0.1 + size * 1.2 * Vec3::new(rng.unit(), rng.unit(), rng.unit());
                Ray::new(origin, rng.direction(), rng.range(0.0, diag))
            }
        })
        .collect()
}

fn cpu_hits(bvh: &Bvh, rays: &[Ray]) -> Vec<bool> {
    rays.iter().map(|r| occluded_cpu(bvh, Vec3::from_array(r.origin), Vec3::from_array(r.dir), r.t_max)).collect()
}

// ---------------------------------------------------------------------------------------------------------------
// Traversal
// ---------------------------------------------------------------------------------------------------------------

#[test]
fn cpu_traversal_equals_brute_force_on_builtin_scenes() {
    for name in ["cornell", "arcade"] {
        let scene = Scene::builtin(name).unwrap();
        let geometry = ChunkedGeometry::build(&scene);
        let bvh = Bvh::from_geometry(&geometry);
        let s = &bvh.stats;
        eprintln!("{name}: {s:?}");
        assert_eq!(s.triangles + s.degenerate_skipped, geometry.triangle_count());
        assert!(s.max_depth <= shadowlab_core::accel::bvh::MAX_DEPTH);
        // Every input triangle is in exactly one leaf.
        let mut ids = bvh.triangle_ids.clone();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), bvh.triangles.len());

        let rays = random_rays(&bvh, &scene.bounds, 4000, 7);
        let bvh_hits = cpu_hits(&bvh, &rays);
        let mut hits = 0;
        for (r, &hit) in rays.iter().zip(&bvh_hits) {
            let brute = occluded_brute_force(&bvh, Vec3::from_array(r.origin), Vec3::from_array(r.dir), r.t_max);
            assert_eq!(hit, brute, "{name}: BVH and brute force disagree on {r:?}");
            hits += hit as usize;
        }
        eprintln!("{name}: {hits} of {} rays occluded", rays.len());
        assert!(hits > rays.len() / 10 && hits < rays.len() * 9 / 10, "{name}: {hits} hits is not a useful mix");
    }
}

#[test]
fn gpu_traversal_equals_cpu_traversal() {
    let gpu = gpu();
    for name in ["cornell", "arcade"] {
        let scene = Scene::builtin(name).unwrap();
        let bvh = Bvh::from_geometry(&ChunkedGeometry::build(&scene));
        let rays = random_rays(&bvh, &scene.bounds, 20_000, 11);
        let cpu = cpu_hits(&bvh, &rays);
        let gpu_flags = gpu_occluded(&gpu, &bvh, &rays).unwrap();
        assert_eq!(gpu_flags.len(), rays.len());
        let differ: Vec<usize> = (0..rays.len()).filter(|&i| cpu[i] != gpu_flags[i]).collect();
        let hits = cpu.iter().filter(|&&h| h).count();
        eprintln!("{name}: GPU and CPU differ on {} of {} rays ({hits} occluded)", differ.len(), rays.len());
        for &i in differ.iter().take(5) {
            eprintln!("  {:?}: cpu {} gpu {}", rays[i], cpu[i], gpu_flags[i]);
        }
        // Floating-point ties (a ray through an edge or a vertex, FMA contraction on the GPU) may differ.
        assert!(differ.len() * 1000 <= rays.len(), "{name}: {} of {} rays differ", differ.len(), rays.len());
    }
}

#[test]
fn gpu_traversal_of_an_empty_bvh_and_of_many_rays() {
    let gpu = gpu();
    let empty = Bvh::build(&[]);
    let rays = vec![Ray::new(Vec3::ZERO, Vec3::X, 10.0); 3];
    assert_eq!(gpu_occluded(&gpu, &empty, &rays).unwrap(), vec![false; 3]);
    assert!(gpu_occluded(&gpu, &empty, &[]).unwrap().is_empty());
    // One triangle, rays in a row straddling it: exercises a partly filled last workgroup.
    let bvh = Bvh::build(&[[Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)]]);
    let rays: Vec<Ray> =
        (0..1000).map(|i| Ray::new(Vec3::new(0.0, 0.0, 1.0), Vec3::NEG_Z, i as f32 * 0.002 + 0.0005)).collect();
    let flags = gpu_occluded(&gpu, &bvh, &rays).unwrap();
    for (i, f) in flags.iter().enumerate() {
        assert_eq!(*f, rays[i].t_max > 1.0, "ray {i}");
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Hard shadows
// ---------------------------------------------------------------------------------------------------------------

fn lights_around_occluder() -> Vec<PointLight> {
    vec![
        white_light(Vec3::new(-1.5, 3.0, 0.2), 12.0, 8.0),
        PointLight::new(Vec3::new(1.2, 2.5, -0.5), Vec3::new(1.0, 0.6, 0.3), 10.0, 7.0),
        white_light(Vec3::new(0.0, 3.5, 1.5), 8.0, 8.0),
    ]
}

#[test]
fn hard_shadows_match_the_reference_at_1024() {
    let scene = plane_and_occluder();
    let lights = lights_around_occluder();
    let (reference, _) = Shot::direct(&scene, &lights, settings(), "reference")
        .params(&[("shadow_res", ParamValue::Int(1024))])
        .render();
    let (traced, report) = Shot::direct(&scene, &lights, settings(), "raytraced").params(TRACED).render();
    let c = &report.counts.technique;
    assert_eq!((c.lights_visible, c.shadow_maps, c.batches), (3, 0, 1));
    let (over, worst) = compare(&traced, &reference, 0.02);
    eprintln!("ray traced vs reference: {:.3}% of pixels over 2%, worst {worst}", over * 100.0);
    if over > 0.01 {
        let bad: Vec<bool> = traced.iter().zip(&reference).map(|(p, q)| compare(&[*p], &[*q], 0.02).0 > 0.0).collect();
        let exp: Vec<Option<[f32; 4]>> = reference.iter().map(|p| Some(*p)).collect();
        let dir = write_failure_images("raytraced-vs-reference", W, H, &traced, &exp, &bad);
        panic!("{:.2}% of pixels differ from the reference by more than 2%; images in {}", over * 100.0, dir.display());
    }
}

fn expected(camera: &Camera, lights: &[PointLight], px: u32, py: u32, margin: f32) -> Option<[f32; 4]> {
    // Shadow rays start at the surface point pushed along the normal by the technique's offset.
    let origin = |p: Vec3| p + Vec3::Y * BIAS * (p - camera.position).length().max(1.0);
    analytic::expected(camera, lights, px, py, margin, &origin)
}

#[test]
fn hard_shadows_match_the_analytic_answer() {
    let scene = plane_and_occluder();
    let lights = lights_around_occluder();
    let (hdr, _) = Shot::direct(&scene, &lights, settings(), "raytraced").params(TRACED).render();
    let mut exp = vec![None; (W * H) as usize];
    let mut bad = vec![false; (W * H) as usize];
    let (mut checked, mut wrong, mut umbra) = (0, 0, 0);
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            // A 2 mm band around each shadow boundary is left out (the reference's test needs 6 cm).
            exp[i] = expected(&scene.camera, &lights, x, y, 0.002);
            if let Some(e) = exp[i] {
                checked += 1;
                if let Hit::Ground(p) = cast(&scene.camera, x, y) {
                    umbra += lights.iter().any(|l| ground_visibility(p, l, 0.01) == Some(false)) as usize;
                }
                if !(0..3).all(|c| (hdr[i][c] - e[c]).abs() <= 0.02 * e[c].abs() + 2e-3) {
                    wrong += 1;
                    bad[i] = true;
                }
            }
        }
    }
    if wrong > 0 {
        let dir = write_failure_images("raytraced-analytic", W, H, &hdr, &exp, &bad);
        panic!("{wrong} of {checked} pixels differ from the analytic answer; images in {}", dir.display());
    }
    assert!(checked > (W * H * 9 / 10) as usize, "too few pixels checked: {checked}");
    assert!(umbra > 300, "the test must see shadowed ground: {umbra}");
}

#[test]
fn soft_shadows_of_a_zero_radius_light_are_the_hard_shadows() {
    let scene = plane_and_occluder();
    let lights = lights_around_occluder();
    let (hard, _) = Shot::direct(&scene, &lights, settings(), "raytraced").params(TRACED).render();
    let (soft, _) = Shot::direct(&scene, &lights, settings(), "raytraced")
        .params(TRACED)
        .params(&[
            ("soft", ParamValue::Bool(true)),
            ("light_radius", ParamValue::Float(0.0)),
            ("samples", ParamValue::Int(3)),
        ])
        .render();
    assert_eq!(hard, soft);
}

#[test]
fn batches_and_culling_change_counts_not_the_image() {
    let scene = plane_and_occluder();
    let mut lights: Vec<PointLight> = (0..12)
        .map(|i| {
            let a = i as f32 / 12.0 * std::f32::consts::TAU;
            white_light(Vec3::new(2.0 * a.cos(), 2.0 + 0.1 * i as f32, 2.0 * a.sin()), 2.0, 6.0)
        })
        .collect();
    // Out of view: culled.
    lights.push(white_light(Vec3::new(0.0, 6.0, 30.0), 100.0, 2.0));
    let (one, r1) = Shot::direct(&scene, &lights, settings(), "raytraced")
        .params(TRACED)
        .params(&[("lights_per_step", ParamValue::Int(1))])
        .render();
    let (all, r32) = Shot::direct(&scene, &lights, settings(), "raytraced")
        .params(TRACED)
        .params(&[("lights_per_step", ParamValue::Int(32))])
        .render();
    assert_eq!(r1.counts.technique.lights_visible, 12);
    assert_eq!(r1.counts.technique.batches, 12);
    assert_eq!(r32.counts.technique.batches, 1);
    assert_eq!(r32.counts.technique.shadow_maps, 0);
    let (over, worst) = compare(&one, &all, 0.01);
    assert!(over == 0.0, "batching changed the image: worst {worst}");
}

#[test]
fn zero_lights_render_ambient_only() {
    let scene = plane_and_occluder();
    let (traced, report) = Shot::direct(&scene, &[], settings(), "raytraced").params(TRACED).render();
    let c = &report.counts.technique;
    assert_eq!((c.lights_visible, c.batches, c.shadow_maps), (0, 0, 0));
    let (reference, _) = Shot::direct(&scene, &[], settings(), "reference").render();
    assert_eq!(traced, reference);
    for y in 0..H {
        for x in 0..W {
            if let Some(e) = expected(&scene.camera, &[], x, y, 0.0) {
                let a = traced[(y * W + x) as usize];
                assert!((0..3).all(|c| (a[c] - e[c]).abs() <= 2e-3), "pixel {x},{y}: {a:?} vs {e:?}");
            }
        }
    }
}

#[test]
fn parameters_are_checked() {
    let gpu = gpu();
    let scene = plane_and_occluder();
    let renderer = Renderer::new(&gpu, &scene, settings()).unwrap();
    let mut t = renderer.create_technique("raytraced").unwrap();
    assert_eq!(t.key(), "raytraced");
    assert!(t.set_param("samples", &ParamValue::Int(0)).is_err());
    assert!(t.set_param("samples", &ParamValue::Int(257)).is_err());
    assert!(t.set_param("light_radius", &ParamValue::Float(-1.0)).is_err());
    assert!(matches!(t.set_param("shadow_res", &ParamValue::Int(64)), Err(ParamError::Unknown { .. })));
    t.set_param("samples", &ParamValue::Int(256)).unwrap();
    let p = t.params();
    assert_eq!(p.iter().find(|p| p.key == "samples").unwrap().value, ParamValue::Int(256));
    for key in ["soft", "light_radius", "samples", "lights_per_step", "bias", "seed"] {
        assert!(p.iter().any(|p| p.key == key), "{key}");
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Soft shadows: a disc light behind a straight edge
// ---------------------------------------------------------------------------------------------------------------

/// Height of the half-plane occluder `{y = EDGE_HEIGHT, x < 0}`.
const EDGE_HEIGHT: f32 = 1.0;

fn rect(name: &str, y: f32, x0: f32, x1: f32, z0: f32, z1: f32) -> Mesh {
    Mesh {
        name: name.into(),
        positions: vec![Vec3::new(x0, y, z0), Vec3::new(x1, y, z0), Vec3::new(x1, y, z1), Vec3::new(x0, y, z1)],
        normals: vec![Vec3::Y; 4],
        uvs: vec![Vec2::ZERO; 4],
        uvs1: Vec::new(),
        indices: vec![0, 2, 1, 0, 3, 2],
        material: 0,
    }
}

/// A ground plane (y = 0) and a large occluder covering x < 0 at `EDGE_HEIGHT`; the camera sits below the
/// occluder, looking down at the penumbra across the edge's shadow.
fn edge_scene() -> Scene {
    let grey =
        Material { name: "grey".into(), base_color: Vec4::new(ALBEDO, ALBEDO, ALBEDO, 1.0), ..Default::default() };
    let mut scene = Scene {
        name: "edge".into(),
        source: SceneSource::Builtin("test".into()),
        meshes: vec![rect("ground", 0.0, -30.0, 30.0, -30.0, 30.0), rect("edge", EDGE_HEIGHT, -30.0, 0.0, -30.0, 30.0)],
        materials: vec![grey],
        textures: vec![],
        lights: vec![],
        directional: vec![],
        camera: Camera::look_at(Vec3::new(1.2, 0.9, 0.0), Vec3::new(-0.3, 0.0, 0.0), 70f32.to_radians(), 0.05, 50.0),
        bounds: Aabb::EMPTY,
        warnings: vec![],
    };
    scene.finalize(std::path::Path::new("edge")).unwrap();
    scene
}

/// Fraction of a disc light (centre `light`, radius `r`, facing `p`) visible from `p` past the half-plane
/// `{y = EDGE_HEIGHT, x < 0}`. A disc point s is hidden when the segment p-s crosses the occluder, i.e. when
/// f(s) = n·s - c < 0 for the plane through p and the edge (n = (h - p.y, p.x, 0), c = h p.x). On the disc,
/// f = f(L) + r m a with a uniform over the unit disc along the in-plane direction of n (m = |n| without
/// its component along the disc normal), so the hidden part is a circular segment.
fn disc_visibility(p: Vec3, light: Vec3, r: f32) -> f32 {
    let h = EDGE_HEIGHT;
    let n = Vec3::new(h - p.y, p.x, 0.0);
    let c = h * p.x;
    let w = (light - p).normalize();
    let m = (n.length_squared() - n.dot(w).powi(2)).max(0.0).sqrt();
    let f = n.dot(light) - c;
    if r * m <= 0.0 {
        return if f >= 0.0 { 1.0 } else { 0.0 };
    }
    let delta = (f / (r * m)).clamp(-1.0, 1.0);
    // Share of the unit disc beyond a chord at distance |delta| from the centre.
    let segment = |d: f32| (d.acos() - d * (1.0 - d * d).sqrt()) / std::f32::consts::PI;
    let hidden = if delta >= 0.0 { segment(delta) } else { 1.0 - segment(-delta) };
    1.0 - hidden
}

#[test]
fn soft_penumbra_follows_the_visible_fraction_of_the_disc() {
    let scene = edge_scene();
    let light = white_light(Vec3::new(0.1, 3.0, 0.0), 20.0, 12.0);
    let radius = 0.5;
    let samples = 128;
    let (hdr, _) = Shot::direct(&scene, &[light], settings(), "raytraced")
        .params(TRACED)
        .params(&[
            ("soft", ParamValue::Bool(true)),
            ("light_radius", ParamValue::Float(radius)),
            ("samples", ParamValue::Int(samples)),
        ])
        .render();
    // The albedo as the GPU sees it (8-bit sRGB: 0.5 becomes 0.497), from the ambient term alone.
    let (ambient_only, _) = Shot::direct(&scene, &[], settings(), "raytraced").params(TRACED).render();
    let camera = &scene.camera;
    let mut measured = vec![[0.0f32; 4]; hdr.len()];
    let mut analytic = vec![None; hdr.len()];
    let mut errors = Vec::new();
    let mut penumbra = 0;
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            let (o, d) = camera_ray(camera, x, y);
            if d.y >= -1e-3 {
                continue;
            }
            let p = o + d * (-o.y / d.y);
            if p.x.abs() > 3.0 || p.z.abs() > 3.0 {
                continue;
            }
            let to_light = light.position - p;
            let dist = to_light.length();
            let albedo = ambient_only[i][0] / AMBIENT;
            let unshadowed =
                albedo / std::f32::consts::PI * light.intensity * attenuation(dist, light.range) * (to_light / dist).y;
            let vis = (hdr[i][0] - ambient_only[i][0]) / unshadowed;
            // The shader's ray origin: the surface point pushed up by the offset.
            let eps = BIAS * (p - camera.position).length().max(1.0);
            let expected = disc_visibility(p + Vec3::Y * eps, light.position, radius);
            measured[i] = [vis, vis, vis, 1.0];
            analytic[i] = Some([expected, expected, expected, 1.0]);
            let is_penumbra = expected > 0.02 && expected < 0.98;
            penumbra += is_penumbra as usize;
            errors.push((vis - expected, x, y, is_penumbra));
        }
    }
    save_hdr("raytraced-penumbra-visibility.png", W, H, &measured, 1.0);
    // Statistics over the penumbra, where sampling errs; everywhere else the answer is 0 or 1.
    let in_penumbra: Vec<f32> = errors.iter().filter(|e| e.3).map(|e| e.0).collect();
    let n = in_penumbra.len().max(1) as f32;
    let mean_abs = in_penumbra.iter().map(|e| e.abs()).sum::<f32>() / n;
    let mean = in_penumbra.iter().sum::<f32>() / n;
    let worst = errors.iter().copied().fold((0f32, 0, 0, false), |a, e| if e.0.abs() > a.0.abs() { e } else { a });
    eprintln!(
        "soft penumbra: {} ground pixels, {penumbra} in the penumbra: mean |error| {mean_abs:.4}, mean error \
         {mean:.4}; worst {worst:?}",
        errors.len()
    );
    // 128 stratified samples: errors of about 1/128^(3/4) = 0.026 at most.
    let ok = mean_abs < 0.01 && mean.abs() < 0.004 && worst.0.abs() < 0.05;
    if !ok {
        let bad: Vec<bool> =
            measured.iter().zip(&analytic).map(|(m, a)| a.is_some_and(|a| (m[0] - a[0]).abs() > 0.04)).collect();
        let dir = write_failure_images("raytraced-penumbra", W, H, &measured, &analytic, &bad);
        panic!("the penumbra does not follow the disc fraction; images in {}", dir.display());
    }
    assert!(penumbra > 1500, "the test must see the penumbra: {penumbra} pixels");
    assert!(errors.len() > (W * H / 2) as usize);
}
