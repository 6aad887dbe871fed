//! Indirect light: VPL generation (energy, determinism, sources), the gathers against analytic answers and a CPU
//! gather, batching, the component switch, and bad input. On the software adapter.

mod common;

use common::*;
use glam::{Vec2, Vec3};
use shadowlab_core::renderer::Component;
use shadowlab_core::scene::{attenuation, Camera, DirectionalLight, Mesh, PointLight, Scene};
use shadowlab_core::technique::ParamValue;
use shadowlab_core::vpl::{self, Vpl, VplSet, VplSettings, VplSource};
use shadowlab_core::{RenderSettings, Renderer, ToneMap};

const W: u32 = 64;
const H: u32 = 48;

fn settings(component: Component, vpl: VplSettings) -> RenderSettings {
    RenderSettings {
        width: W,
        height: H,
        tonemap: ToneMap::Linear,
        ambient: Vec3::ZERO,
        background: Vec3::ZERO,
        component,
        vpl,
        ..Default::default()
    }
}

/// A UV sphere of radius `r` around the origin with inward normals.
fn inward_sphere(r: f32, stacks: u32, slices: u32) -> Mesh {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for i in 0..=stacks {
        let theta = std::f32::consts::PI * i as f32 / stacks as f32;
        for j in 0..=slices {
            let phi = 2.0 * std::f32::consts::PI * j as f32 / slices as f32;
            let d = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            positions.push(d * r);
            normals.push(-d);
        }
    }
    let mut indices = Vec::new();
    let row = slices + 1;
    for i in 0..stacks {
        for j in 0..slices {
            let a = i * row + j;
            let b = a + row;
            // Counter-clockwise seen from inside (the G-buffer turns normals towards the viewer by winding).
            indices.extend_from_slice(&[a, b, a + 1, a + 1, b, b + 1]);
        }
    }
    let uvs = vec![Vec2::ZERO; positions.len()];
    Mesh { name: "sphere".into(), positions, normals, uvs, uvs1: Vec::new(), indices, material: 0 }
}

// --- VPL generation -------------------------------------------------------------------------------------------

#[test]
fn vpls_carry_the_flux_the_plane_reflects_for_both_sources() {
    let (side, h, albedo) = (8.0, 2.0, 0.6);
    let scene = plane_scene(side, albedo);
    let bvh = scene_bvh(&scene);
    let light = PointLight::new(Vec3::new(0.0, h, 0.0), Vec3::new(1.0, 0.5, 0.25), 10.0, 50.0);
    let expected = albedo as f64 * intercepted_flux(10.0, 50.0, h, side);
    let mut totals = Vec::new();
    for source in [VplSource::Rsm, VplSource::Traced] {
        let s = VplSettings { count: 1024, source, ..Default::default() };
        let set = vpl::generate(&bvh, &[light], &[], &s);
        assert!(!set.vpls.is_empty());
        let flux = set.total_flux();
        // Colour carried: red = 1, green = 0.5, blue = 0.25 of the light.
        let red = flux.x as f64;
        let err = (red - expected).abs() / expected;
        assert!(err < 0.02, "{source:?}: VPL flux {red:.4} vs reflected {expected:.4} ({:.2} %)", err * 100.0);
        assert!((flux.y / flux.x - 0.5).abs() < 1e-4 && (flux.z / flux.x - 0.25).abs() < 1e-4);
        // Every VPL lies on the plane, facing the light.
        assert!(set.vpls.iter().all(|v| v.position.y.abs() < 1e-4 && v.normal.y > 0.99));
        totals.push(red);
    }
    let agree = (totals[0] - totals[1]).abs() / totals[0];
    assert!(agree < 0.02, "rsm and traced disagree on total flux by {:.2} %", agree * 100.0);
}

#[test]
fn the_same_seed_gives_the_same_vpls_and_a_small_light_move_moves_them_a_little() {
    let scene = plane_scene(8.0, 0.5);
    let bvh = scene_bvh(&scene);
    let light = PointLight::new(Vec3::new(0.3, 2.0, -0.2), Vec3::ONE, 5.0, 50.0);
    for source in [VplSource::Rsm, VplSource::Traced] {
        let s = VplSettings { count: 256, source, bounces: 3, ..Default::default() };
        let a = vpl::generate(&bvh, &[light], &[], &s);
        let b = vpl::generate(&bvh, &[light], &[], &s);
        assert_eq!(a, b, "{source:?}: not deterministic");
        let c = vpl::generate(&bvh, &[light], &[], &VplSettings { seed: 7, ..s });
        assert_ne!(a.vpls, c.vpls, "{source:?}: the seed changes nothing");
        // Quasi-random coherence: moving the light 1 cm moves the first-bounce VPLs by centimetres, not metres.
        let mut moved = light;
        moved.position.x += 0.01;
        let m = vpl::generate(&bvh, &[moved], &[], &VplSettings { bounces: 1, ..s });
        let a1 = vpl::generate(&bvh, &[light], &[], &VplSettings { bounces: 1, ..s });
        assert_eq!(m.vpls.len(), a1.vpls.len());
        let worst = a1.vpls.iter().zip(&m.vpls).map(|(p, q)| p.position.distance(q.position)).fold(0.0, f32::max);
        assert!(worst < 0.05, "{source:?}: a VPL jumped {worst} m");
    }
}

#[test]
fn lights_that_hit_nothing_black_albedo_and_zero_vpls_make_no_vpls_and_no_error() {
    let bvh = scene_bvh(&plane_scene(8.0, 0.5));
    // Below the plane and facing nowhere it is single-sided? No: planes are hit from both sides; a light far
    // outside the scene with a short range reaches nothing.
    let away = PointLight::new(Vec3::new(0.0, 100.0, 0.0), Vec3::ONE, 5.0, 1.0);
    let set = vpl::generate(&bvh, &[away], &[], &VplSettings::default());
    assert!(set.vpls.is_empty() && set.misses == set.samples && set.samples > 0);
    let none = vpl::generate(&bvh, &[], &[], &VplSettings::default());
    assert!(none.vpls.is_empty());
    let zero = vpl::generate(&bvh, &[away], &[], &VplSettings { count: 0, ..Default::default() });
    assert!(zero.vpls.is_empty() && zero.samples == 0);
    let black_bvh = scene_bvh(&plane_scene(8.0, 0.0));
    let light = PointLight::new(Vec3::new(0.0, 2.0, 0.0), Vec3::ONE, 5.0, 50.0);
    assert!(vpl::generate(&black_bvh, &[light], &[], &VplSettings::default()).vpls.is_empty());
    // A million VPLs is refused with a message naming the limit.
    let err = VplSettings { count: 1_000_000, ..Default::default() }.validate().unwrap_err();
    assert!(err.contains("65536"), "{err}");
    assert!(RenderSettings { vpl: VplSettings { count: 1_000_000, ..Default::default() }, ..Default::default() }
        .validate()
        .is_err());
}

// --- Gathers --------------------------------------------------------------------------------------------------

#[test]
fn closed_sphere_gives_rho_squared_e0_over_pi_everywhere() {
    // A point light at the centre of a closed sphere of albedo rho: the one-bounce radiance is rho^2 E0 / pi at
    // every point (cos cos / d^2 = 1 / (4 R^2) between any two points of a sphere).
    let (r, rho, intensity, range) = (2.0f32, 0.5f32, 4.0f32, 1000.0f32);
    let camera = Camera::look_at(Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.3, -0.2, -1.0), 70f32.to_radians(), 0.05, 10.0);
    let scene = scene_of("sphere", vec![inward_sphere(r, 48, 96)], rho, camera);
    let lights = [PointLight::new(Vec3::new(0.0, 0.0, 0.0), Vec3::ONE, intensity, range)];
    let e0 = intensity * attenuation(r, range);
    let expected = rho * rho * e0 / std::f32::consts::PI;
    let vpl = VplSettings { count: 1024, clamp_world: 0.05, ..Default::default() };
    let cases: [(&str, Vec<(&str, ParamValue)>); 4] = [
        ("vpl-raytraced", vec![]),
        ("val", vec![("shadow_res", ParamValue::Int(256))]),
        ("vpl-shadowmaps", vec![("shadow_res", ParamValue::Int(256))]),
        ("pathtraced", vec![("samples", ParamValue::Int(256)), ("samples_per_step", ParamValue::Int(64))]),
    ];
    for (key, params) in cases {
        let (hdr, report) =
            Shot::indirect(&scene, &lights, settings(Component::Indirect, vpl), key).params(&params).render();
        let indirect = report.indirect.as_ref().expect("the report has the indirect technique");
        assert_eq!(indirect.technique, key);
        let mean: f32 = hdr.iter().map(|p| p[0]).sum::<f32>() / hdr.len() as f32;
        let worst = hdr.iter().map(|p| (p[0] - expected).abs() / expected).fold(0.0, f32::max);
        let err = (mean - expected).abs() / expected;
        if err >= 0.03 || (key != "pathtraced" && worst >= 0.05) {
            save_hdr(&format!("sphere-{key}-actual.png"), W, H, &hdr, 0.5 / expected);
        }
        assert!(err < 0.03, "{key}: mean indirect {mean:.5} vs rho^2 E0/pi = {expected:.5} ({:.2} %)", err * 100.0);
        // The VPL gathers are the same everywhere (no noise); the path tracer's pixels are noisy.
        if key != "pathtraced" {
            assert!(worst < 0.05, "{key}: worst pixel off by {:.2} %", worst * 100.0);
        }
        assert!(hdr.iter().all(|p| p.iter().all(|c| c.is_finite())), "{key}: non-finite pixel");
    }
}

/// One VPL above the ground facing down, the square plate between them: the plate's shadow on the ground.
fn one_vpl() -> (Scene, VplSet, Vpl) {
    let scene = plane_and_occluder();
    let v = Vpl {
        position: Vec3::new(0.2, 2.0, 0.1),
        normal: Vec3::NEG_Y,
        flux: Vec3::splat(20.0),
        light: 0,
        from: Vec3::new(0.2, 3.0, 0.1),
    };
    let set = VplSet { settings: None, vpls: vec![v], samples: 1, misses: 0, point_lights: 1 };
    (scene, set, v)
}

#[test]
fn one_vpl_over_an_occluder_matches_a_cpu_gather() {
    let (scene, set, v) = one_vpl();
    let clamp = 0.1f32;
    let vs = VplSettings { clamp_world: clamp, ..Default::default() };
    for (key, tolerance, bad_share) in [("vpl-raytraced", 0.01, 0.005), ("vpl-shadowmaps", 0.02, 0.03)] {
        let params = if key == "vpl-shadowmaps" { vec![("shadow_res", ParamValue::Int(512))] } else { vec![] };
        let Rendered { renderer, hdr, .. } = Shot::indirect(&scene, &[], settings(Component::Indirect, vs), key)
            .params(&params)
            .fixed_vpls(Some(set.clone()))
            .render_keeping();
        let positions = renderer.read_world_positions(&scene.camera).unwrap();
        let (mut checked, mut bad, mut shadowed) = (0, 0, 0);
        let mut expected_img = vec![None; hdr.len()];
        let mut bad_img = vec![false; hdr.len()];
        for (i, p) in positions.iter().enumerate() {
            let Some(p) = p else { continue };
            if p.y.abs() > 1e-3 {
                continue; // the plate itself
            }
            // CPU gather: rho/pi * Phi/pi * cos_i cos_x / max(d^2, c^2) * V, V by the plate's square.
            let to_x = *p - v.position;
            let d2 = to_x.length_squared();
            let w = to_x / d2.sqrt();
            let (cos_i, cos_x) = (v.normal.dot(w), w.dot(Vec3::NEG_Y));
            let t = (PLATE_CENTER.y - v.position.y) / w.y;
            let hit = v.position + w * t;
            let half = PLATE_SIZE * 0.5;
            let dx = (hit.x - PLATE_CENTER.x).abs().max((hit.z - PLATE_CENTER.z).abs()) - half;
            if dx.abs() < 0.03 {
                continue; // within 3 cm of the shadow's edge (on the plate's plane)
            }
            let visible = dx > 0.0;
            shadowed += !visible as u32;
            let e = ALBEDO / std::f32::consts::PI * 20.0 / std::f32::consts::PI * cos_i.max(0.0) * cos_x.max(0.0)
                / d2.max(clamp * clamp)
                * visible as u32 as f32;
            checked += 1;
            expected_img[i] = Some([e, e, e, 1.0]);
            if (hdr[i][0] - e).abs() > tolerance * e.max(1e-3) + 1e-5 {
                bad += 1;
                bad_img[i] = true;
            }
        }
        assert!(checked > 1000 && shadowed > 50, "{key}: the test checks {checked} pixels, {shadowed} shadowed");
        let share = bad as f32 / checked as f32;
        if share > bad_share {
            let dir = write_failure_images(&format!("one-vpl-{key}"), W, H, &hdr, &expected_img, &bad_img);
            panic!("{key}: {bad} of {checked} ground pixels differ from the CPU gather (see {})", dir.display());
        }
    }
}

#[test]
fn paraboloid_maps_of_the_cornell_box_need_their_edges_cut() {
    // A paraboloid map projects a triangle's corners exactly but draws its edges straight and its depth linearly
    // between them; the Cornell box's walls and blocks are two triangles a side, which from a VPL beside them span
    // large angles, so drawn as they are they land in the wrong place and their depth is too far: the blocks'
    // shadows leak. With the edges cut to a twentieth of the diagonal (the default) the maps come close to the ray
    // tracer. (A box of two triangles a side built here with one VPL did not show it: the leak needs receivers
    // close behind an occluder, as the real scene's walls are behind its blocks.)
    let Some(scenes) = scenes_dir("paraboloid_maps_of_the_cornell_box_need_their_edges_cut") else { return };
    let mut scene = Scene::load(&scenes.join("cornell-box/CornellBox-Original.obj"), 1.0).unwrap();
    let layout = shadowlab_core::scene::layout::parse("random:16:1.16244:1").unwrap();
    let lights = shadowlab_core::scene::layout::generate(&layout, &scene).unwrap();
    scene.lights.clear();
    let vs = VplSettings { count: 256, ..Default::default() };
    let shot = |key: &str, params: &[(&str, ParamValue)]| {
        Shot::indirect(&scene, &lights, settings(Component::Indirect, vs), key).params(params).render()
    };
    let (exact, _) = shot("vpl-raytraced", &[]);
    let lit = exact.iter().map(|p| p[0]).fold(0.0, f32::max);
    assert!(lit > 0.0, "the VPLs light the box");
    let error = |hdr: &[[f32; 4]]| {
        let sq: f32 = hdr.iter().zip(&exact).map(|(a, b)| (a[0] - b[0]).powi(2)).sum();
        (sq / hdr.len() as f32).sqrt() / lit
    };
    let res = ("shadow_res", ParamValue::Int(256));
    let (cut, report) = shot("vpl-shadowmaps", std::slice::from_ref(&res));
    let (uncut, _) = shot("vpl-shadowmaps", &[res, ("max_edge", ParamValue::Float(0.0))]);
    let (cut_error, uncut_error) = (error(&cut), error(&uncut));
    eprintln!("RMSE / brightest against the ray tracer: cut {cut_error}, uncut {uncut_error}");
    if uncut_error < 1.5 * cut_error {
        save_hdr("cornell-exact.png", W, H, &exact, 1.0 / lit);
        save_hdr("cornell-cut-actual.png", W, H, &cut, 1.0 / lit);
        save_hdr("cornell-uncut-actual.png", W, H, &uncut, 1.0 / lit);
    }
    // The defect the cut repairs: if the uncut maps ever come as close, they draw long edges right and the default
    // can go.
    assert!(uncut_error > 1.5 * cut_error, "uncut {uncut_error} against cut {cut_error}");
    let figures = &report.indirect.as_ref().unwrap().counts.figures;
    assert!(figures.get("map_geometry_triangles").is_some_and(|&t| t > 36.0), "{figures:?}");
}

#[test]
fn batched_gathers_equal_one_batch() {
    let scene = room();
    let lights = [white_light(Vec3::new(0.5, 3.0, 0.5), 8.0, 30.0)];
    let vs = VplSettings { count: 1024, ..Default::default() };
    // Also interleaved with the ratio estimator and a 3x3 block (9 classes, batches of 37 VPLs: a batch's
    // first VPL is of any class, and the ratio's sums start with the frame's first batch only).
    let interleaved = |n: i64| {
        vec![
            ("vpls_per_step", ParamValue::Int(n)),
            ("interleave", ParamValue::Bool(true)),
            ("ratio", ParamValue::Bool(true)),
            ("block", ParamValue::Int(3)),
        ]
    };
    let runs = [
        ("vpl-raytraced", vec![("vpls_per_step", ParamValue::Int(1024))], vec![("vpls_per_step", ParamValue::Int(37))]),
        (
            "vpl-unshadowed",
            vec![("vpls_per_step", ParamValue::Int(1024))],
            vec![("vpls_per_step", ParamValue::Int(37))],
        ),
        ("vpl-raytraced", interleaved(1024), interleaved(37)),
    ];
    for (key, one, many) in &runs {
        let key = *key;
        let (a, ra) = Shot::indirect(&scene, &lights, settings(Component::Indirect, vs), key).params(one).render();
        let (b, rb) = Shot::indirect(&scene, &lights, settings(Component::Indirect, vs), key).params(many).render();
        assert_eq!(ra.indirect.as_ref().unwrap().counts.batches, 1, "{key}");
        // The report separates the indirect technique's passes from the direct one's.
        let names: Vec<&str> = ra.indirect.as_ref().unwrap().passes.iter().map(|p| p.name.as_str()).collect();
        assert!(names.contains(&"vpl gather") && !names.contains(&"shading"), "{names:?}");
        let n = ra.indirect.as_ref().unwrap().vpls;
        assert!(n > 500, "{n} VPLs");
        assert_eq!(rb.indirect.as_ref().unwrap().counts.batches, n.div_ceil(37));
        assert_eq!(n, rb.indirect.as_ref().unwrap().vpls);
        let max = a.iter().map(|p| p[0]).fold(0.0, f32::max);
        assert!(max > 0.0, "{key}: no indirect light at all");
        for (p, q) in a.iter().zip(&b) {
            for c in 0..3 {
                assert!((p[c] - q[c]).abs() <= 1e-3 * p[c].abs().max(1e-3 * max), "{key}: {p:?} vs {q:?}");
            }
        }
    }
}

#[test]
fn direct_light_is_bit_identical_with_or_without_an_indirect_technique() {
    let scene = room();
    let lights = [white_light(Vec3::new(0.5, 3.0, 0.5), 8.0, 30.0)];
    let gpu = gpu();
    let s = settings(Component::Total, VplSettings { count: 64, ..Default::default() });
    let mut renderer = Renderer::new(&gpu, &scene, s.clone()).unwrap();
    let mut reference = renderer.create_technique("reference").unwrap();
    let (alone, _) = frame(&mut renderer, reference.as_mut(), &scene.camera, &lights);
    let output_alone = renderer.read_output().unwrap();
    let t = renderer.create_indirect_technique("vpl-unshadowed").unwrap();
    renderer.set_indirect(Some(t)).unwrap();
    let report = renderer.render_frame(reference.as_mut(), &scene.camera, &lights, &mut |_, _| {}).unwrap();
    assert!(report.indirect.as_ref().unwrap().vpls > 0);
    let direct = renderer.read_component(Component::Direct).unwrap();
    assert!(alone == direct, "the direct part changed when an indirect technique joined");
    let total = renderer.read_component(Component::Total).unwrap();
    let indirect = renderer.read_component(Component::Indirect).unwrap();
    assert!(indirect.iter().any(|p| p[0] > 0.0));
    for ((t, d), i) in total.iter().zip(&direct).zip(&indirect) {
        assert!((t[0] - d[0] - i[0]).abs() < 1e-6);
    }
    // Back to no indirect technique: the output is what it was.
    renderer.set_indirect(None).unwrap();
    renderer.render_frame(reference.as_mut(), &scene.camera, &lights, &mut |_, _| {}).unwrap();
    assert!(renderer.read_output().unwrap() == output_alone);
    assert!(renderer.read_component(Component::Indirect).unwrap().iter().all(|p| p[0] == 0.0));
}

#[test]
fn zero_vpls_and_a_light_on_a_surface_give_a_defined_image() {
    let scene = room();
    // A light exactly on the ground: VPLs at distance ~0 from it, receivers at d = 0 from VPLs.
    let lights = [white_light(Vec3::new(0.0, 0.0, 2.0), 8.0, 30.0), white_light(Vec3::new(0.0, 1.0, 0.0), 4.0, 30.0)];
    for key in ["vpl-raytraced", "vpl-shadowmaps", "vpl-unshadowed", "pathtraced"] {
        for count in [0, 64] {
            let vs = VplSettings { count, clamp_world: 0.0, ..Default::default() };
            let params = if key == "pathtraced" { vec![("samples", ParamValue::Int(4))] } else { vec![] };
            let (hdr, report) =
                Shot::indirect(&scene, &lights, settings(Component::Total, vs), key).params(&params).render();
            assert!(hdr.iter().all(|p| p.iter().all(|c| c.is_finite())), "{key} with {count} VPLs: NaN pixel");
            if count == 0 && key != "pathtraced" {
                assert_eq!(report.indirect.unwrap().vpls, 0);
            }
        }
    }
}

// --- Spot lights ----------------------------------------------------------------------------------------------

fn spot_over_plane(cone_deg: f32) -> PointLight {
    let layout = shadowlab_core::scene::layout::parse(&format!("spot:0.5,3,0.2:0.5,0,0.2:{cone_deg}:20")).unwrap();
    // The canonical spec reads back to the same layout.
    assert_eq!(shadowlab_core::scene::layout::parse(&layout.to_string()).unwrap(), layout);
    let lights = shadowlab_core::scene::layout::generate(&layout, &plane_scene(8.0, 0.5)).unwrap();
    assert_eq!(lights.len(), 1);
    lights[0]
}

#[test]
fn spot_lights_light_their_cone_only_in_every_direct_technique() {
    let scene = plane_scene(8.0, 0.5);
    let spot = spot_over_plane(30.0);
    let cone = spot.spot.unwrap();
    assert!((cone.outer_angle - 30f32.to_radians()).abs() < 1e-6 && cone.inner_angle < cone.outer_angle);
    let gpu = gpu();
    for key in ["reference", "unshadowed", "raytraced", "lightcluster", "insm"] {
        let spots = [spot];
        let Rendered { renderer, hdr, .. } =
            Shot::direct(&scene, &spots, settings(Component::Total, VplSettings::default()), key)
                .on(gpu.clone())
                .render_keeping();
        let positions = renderer.read_world_positions(&scene.camera).unwrap();
        let (mut inside, mut outside) = (0, 0);
        for (p, px) in positions.iter().zip(&hdr) {
            let Some(p) = p else { continue };
            let dir = (*p - spot.position).normalize();
            let angle = dir.dot(cone.direction).clamp(-1.0, 1.0).acos();
            let d = p.distance(spot.position);
            let expected = 0.5 / std::f32::consts::PI
                * spot.intensity
                * attenuation(d, spot.range)
                * (-dir.y)
                * spot.cone_factor(dir);
            if angle > cone.outer_angle * 1.02 {
                outside += 1;
                assert!(px[0].abs() < 1e-4, "{key}: lit outside the cone ({} at {angle} rad)", px[0]);
            } else if angle < cone.inner_angle * 0.98 {
                inside += 1;
                assert!((px[0] - expected).abs() < 0.01 * expected + 1e-4, "{key}: {} vs {expected} inside", px[0]);
            }
        }
        assert!(inside > 50 && outside > 500, "{key}: {inside} pixels inside, {outside} outside the cone");
    }
}

#[test]
fn spot_vpls_lie_in_the_cone_and_carry_its_flux_and_a_zero_cone_is_dark() {
    let scene = plane_scene(8.0, 0.5);
    let bvh = scene_bvh(&scene);
    let spot = spot_over_plane(25.0);
    let cone = spot.spot.unwrap();
    // The flux the plane reflects, by quadrature over the plane, the cone's falloff included.
    let n = 800;
    let (side, mut expected) = (8.0f64, 0.0f64);
    let cell = side / n as f64;
    for i in 0..n {
        for j in 0..n {
            let p = Vec3::new(((i as f64 + 0.5) * cell - 4.0) as f32, 0.0, ((j as f64 + 0.5) * cell - 4.0) as f32);
            let to = p - spot.position;
            let d = to.length();
            let dir = to / d;
            let e = spot.intensity * attenuation(d, spot.range) * (-dir.y) * spot.cone_factor(dir);
            expected += e as f64 * cell * cell;
        }
    }
    expected *= 0.5 * 0.9; // albedo, and the red of warm white (1, 0.9, 0.75) is 1: use green
    for source in [VplSource::Rsm, VplSource::Traced] {
        let set = vpl::generate(&bvh, &[spot], &[], &VplSettings { count: 2048, source, ..Default::default() });
        assert!(!set.vpls.is_empty());
        for v in &set.vpls {
            let angle = (v.position - spot.position).normalize().dot(cone.direction).acos();
            assert!(angle <= cone.outer_angle + 1e-3, "{source:?}: a VPL outside the cone ({angle} rad)");
        }
        let green = set.total_flux().y as f64;
        let err = (green - expected).abs() / expected;
        assert!(err < 0.02, "{source:?}: spot VPL flux {green:.4} vs {expected:.4} ({:.2} %)", err * 100.0);
    }
    // A zero cone lights nothing and makes no VPL: a defined, dark image.
    let zero = spot_over_plane(0.0);
    let set = vpl::generate(&bvh, &[zero], &[], &VplSettings::default());
    assert!(set.vpls.iter().all(|v| v.flux.max_element() < 1e-6 * spot.intensity));
    let (hdr, _) =
        Shot::indirect(&scene, &[zero], settings(Component::Total, VplSettings::default()), "vpl-raytraced").render();
    assert!(hdr.iter().all(|p| p.iter().all(|c| c.is_finite()) && p[0] < 1e-4), "a zero cone lit something");
}

/// The interleaving tests' setup: the room lit from above, 1,024 VPLs, 128x96, the indirect component.
fn interleaving_room() -> (Scene, [PointLight; 1], RenderSettings) {
    let lights = [white_light(Vec3::new(0.5, 3.0, 0.5), 8.0, 30.0)];
    let vs = VplSettings { count: 1024, ..Default::default() };
    (room(), lights, RenderSettings { width: 128, height: 96, ..settings(Component::Indirect, vs) })
}

/// The relative RMSE of `img` against `full` (green channel).
fn relative_rmse(full: &[[f32; 4]], img: &[[f32; 4]]) -> f64 {
    let (mut e, mut r) = (0.0f64, 0.0f64);
    for (p, q) in full.iter().zip(img) {
        e += ((p[1] - q[1]) as f64).powi(2);
        r += (p[1] as f64).powi(2);
    }
    (e / r).sqrt()
}

#[test]
fn interleaved_sampling_with_the_blur_stays_close_to_the_full_gather() {
    let (scene, lights, s) = interleaving_room();
    let (full, _) = Shot::indirect(&scene, &lights, s.clone(), "vpl-raytraced").render();
    let on = [("interleave", ParamValue::Bool(true)), ("vpls_per_step", ParamValue::Int(100))];
    let (inter, report) = Shot::indirect(&scene, &lights, s, "vpl-raytraced").params(&on).render();
    let c = &report.indirect.as_ref().unwrap().counts;
    let n = report.indirect.as_ref().unwrap().vpls;
    assert_eq!(c.batches, n.div_ceil(100), "the blur is a step of its own, not a batch");
    let mean = |img: &[[f32; 4]]| img.iter().map(|p| p[1] as f64).sum::<f64>() / img.len() as f64;
    let (a, b) = (mean(&full), mean(&inter));
    assert!(a > 0.0 && ((a - b) / a).abs() < 0.03, "mean indirect {b} vs {a} without interleaving");
    // Per pixel: most within 15 % of the full gather (edges of the blur's window differ more).
    let lit: Vec<(f32, f32)> =
        full.iter().zip(&inter).filter(|(p, _)| p[1] > 1e-3).map(|(p, q)| (p[1], q[1])).collect();
    let close = lit.iter().filter(|(p, q)| (p - q).abs() < 0.15 * p).count();
    assert!(close as f32 > 0.8 * lit.len() as f32, "{close} of {} pixels within 15 %", lit.len());
    // Without the blur the pixels of a block would differ wildly; the blur makes neighbours agree.
    assert!(inter.iter().all(|p| p.iter().all(|c| c.is_finite())));
}

#[test]
fn the_interleaving_blur_keeps_a_floor_seen_at_a_grazing_angle_free_of_row_stripes() {
    // Seen from 0.4 m above it, the floor's rows lie far apart in the world, so a blur that keeps only
    // neighbours within a small sphere averages along the rows alone: each row keeps its own eight of the 64
    // VPL shares and the floor shows stripes. The blur tests the distance to the pixel's tangent plane and
    // lets the same class's pixel one block over stand in for one on another surface.
    let (scene, lights, s) = interleaving_room();
    let camera = Camera::look_at(Vec3::new(-2.5, 0.4, 4.0), Vec3::new(0.5, 0.0, -3.0), 60f32.to_radians(), 0.1, 50.0);
    let (full, _) = Shot::indirect(&scene, &lights, s.clone(), "vpl-raytraced").camera(&camera).render();
    // The plain blur (the ratio estimator blurs visibility alone: the next test).
    let on = [("interleave", ParamValue::Bool(true)), ("ratio", ParamValue::Bool(false))];
    let (inter, _) = Shot::indirect(&scene, &lights, s, "vpl-raytraced").params(&on).camera(&camera).render();
    // Per row of the floor's lower half (the plate and the wall stand above it): the interleaved light over
    // the full gather's.
    let (w, h) = (128usize, 96usize);
    let ratios: Vec<f64> = (h * 3 / 5..h)
        .map(|y| {
            let row = |img: &[[f32; 4]]| (0..w).map(|x| img[y * w + x][1] as f64).sum::<f64>();
            row(&inter) / row(&full).max(1e-9)
        })
        .collect();
    let stripes = ratios.windows(2).map(|p| (p[0] - p[1]).abs()).sum::<f64>() / (ratios.len() - 1) as f64;
    let lit: Vec<(f32, f32)> =
        full.iter().zip(&inter).filter(|(p, _)| p[1] > 1e-3).map(|(p, q)| (p[1], q[1])).collect();
    let close = lit.iter().filter(|(p, q)| (p - q).abs() < 0.1 * p).count() as f64 / lit.len() as f64;
    // The blur before this one: 0.063 and 56 % of the pixels within 10 %; this one 0.023 and 88 %.
    assert!(stripes < 0.04, "the floor's rows differ from each other by {stripes:.4} (interleaved / full)");
    assert!(close > 0.75, "{:.1} % of the lit pixels within 10 % of the full gather", close * 100.0);
}

#[test]
fn the_ratio_estimator_is_exact_without_shadows_and_nearer_the_full_gather_than_the_plain_blur_with_them() {
    let (scene, lights, s) = interleaving_room();
    let interleaved = |ratio: bool| {
        [
            ("interleave", ParamValue::Bool(true)),
            ("ratio", ParamValue::Bool(ratio)),
            ("vpls_per_step", ParamValue::Int(300)),
        ]
    };
    // Without visibility every window's share is 1: the pixel's own sum over every VPL, to f32 rounding.
    let (full, _) = Shot::indirect(&scene, &lights, s.clone(), "vpl-unshadowed").render();
    let (ratio, report) =
        Shot::indirect(&scene, &lights, s.clone(), "vpl-unshadowed").params(&interleaved(true)).render();
    let mut lit = 0;
    for (p, q) in full.iter().zip(&ratio) {
        if p[1] > 1e-3 {
            lit += 1;
            assert!((p[1] - q[1]).abs() <= 1e-4 * p[1] + 1e-6, "unshadowed: {} interleaved, {} in full", q[1], p[1]);
        }
    }
    assert!(lit > 5000, "{lit} lit pixels");
    let n = report.indirect.as_ref().unwrap().vpls as f64;
    let evaluations = report.indirect.as_ref().unwrap().work["vpl_pixel_evaluations"];
    assert!(evaluations >= n * lit as f64, "the blur's sum over every VPL is counted: {evaluations} evaluations");
    // With the plate's shadows: nearer the full gather than the window's light averaged.
    let (full, _) = Shot::indirect(&scene, &lights, s.clone(), "vpl-raytraced").render();
    let (ratio, _) = Shot::indirect(&scene, &lights, s.clone(), "vpl-raytraced").params(&interleaved(true)).render();
    let (plain, _) = Shot::indirect(&scene, &lights, s, "vpl-raytraced").params(&interleaved(false)).render();
    let (e_ratio, e_plain) = (relative_rmse(&full, &ratio), relative_rmse(&full, &plain));
    // Measured: 0.010 against 0.260.
    assert!(
        e_ratio < 0.05 && e_ratio < 0.2 * e_plain,
        "relative RMSE against the full gather: ratio {e_ratio:.4}, plain {e_plain:.4}"
    );
}

#[test]
fn a_smaller_interleaving_block_traces_more_rays_a_pixel_and_comes_nearer_the_full_gather() {
    let (scene, lights, s) = interleaving_room();
    let (full, _) = Shot::indirect(&scene, &lights, s.clone(), "vpl-raytraced").render();
    let mut runs = Vec::new();
    for block in [8i64, 4] {
        for ratio in [true, false] {
            let params = [
                ("interleave", ParamValue::Bool(true)),
                ("ratio", ParamValue::Bool(ratio)),
                ("block", ParamValue::Int(block)),
            ];
            let (img, report) = Shot::indirect(&scene, &lights, s.clone(), "vpl-raytraced").params(&params).render();
            let rays = report.indirect.as_ref().unwrap().work["shadow_rays"];
            runs.push((block, ratio, relative_rmse(&full, &img), rays));
        }
    }
    for ratio in [true, false] {
        let [(_, _, e8, rays8), (_, _, e4, rays4)] =
            [8, 4].map(|b| *runs.iter().find(|r| r.0 == b && r.1 == ratio).unwrap());
        // A pixel of a 4x4 block traces a 16th of the VPLs' rays, of an 8x8 block a 64th.
        let more = rays4 / rays8;
        assert!((3.6..4.4).contains(&more), "ratio {ratio}: {rays4} rays with block 4, {rays8} with 8");
        assert!(e4 < e8, "ratio {ratio}: relative RMSE {e4:.4} with block 4, {e8:.4} with 8");
    }
}

#[test]
fn views_of_one_scene_share_its_gpu_copy_and_bvh_and_render_the_same() {
    let scene = room();
    let lights = [white_light(Vec3::new(0.5, 3.0, 0.5), 8.0, 30.0)];
    let gpu = gpu();
    let s = settings(Component::Total, VplSettings { count: 128, ..Default::default() });
    let mut a = Renderer::new(&gpu, &scene, s.clone()).unwrap();
    let mut b = a.new_view(s).unwrap();
    assert!(std::sync::Arc::ptr_eq(&a.shared_scene(), &b.shared_scene()), "the view copied the scene");
    let (_, built_a) = a.scene().bvh(&gpu);
    let (_, built_b) = b.scene().bvh(&gpu);
    assert!(built_a.is_some() && built_b.is_none(), "the BVH was built twice");
    let mut images = Vec::new();
    for r in [&mut a, &mut b] {
        let t = r.create_indirect_technique("vpl-raytraced").unwrap();
        r.set_indirect(Some(t)).unwrap();
        let mut reference = r.create_technique("reference").unwrap();
        images.push(frame(r, reference.as_mut(), &scene.camera, &lights).0);
    }
    assert!(images[0] == images[1], "two views of one scene render differently");
}

#[test]
fn a_light_exactly_on_a_surface_gives_no_nan_in_any_direct_technique() {
    let scene = room();
    // On the ground, on the wall, and on the plate's corner: d = 0 for the pixels under it.
    let lights = [
        white_light(Vec3::new(0.0, 0.0, 1.0), 5.0, 10.0),
        white_light(Vec3::new(1.0, 1.0, -3.0), 5.0, 10.0),
        white_light(Vec3::new(0.5, 1.0, 0.5), 5.0, 10.0),
    ];
    let gpu = gpu();
    for key in ["reference", "unshadowed", "raytraced", "lightcluster", "insm"] {
        let settings = settings(Component::Total, VplSettings::default());
        let (hdr, _) = Shot::direct(&scene, &lights, settings, key).on(gpu.clone()).render();
        assert!(hdr.iter().all(|p| p.iter().all(|c| c.is_finite())), "{key}: a NaN or infinite pixel");
        assert!(hdr.iter().any(|p| p[0] > 0.0), "{key}: nothing lit");
    }
}

// --- Directional lights (suns) ----------------------------------------------------------------------------------

fn sun(direction: Vec3, color: Vec3, illuminance: f32) -> DirectionalLight {
    DirectionalLight { direction: direction.normalize(), color, illuminance }
}

#[test]
fn sun_vpls_carry_the_flux_the_plane_reflects_alone_and_beside_a_point_light() {
    let (side, albedo) = (8.0, 0.6);
    let scene = plane_scene(side, albedo);
    let bvh = scene_bvh(&scene);
    let d = Vec3::new(0.3, -1.0, 0.2).normalize();
    let suns = [sun(d, Vec3::new(1.0, 0.5, 0.25), 2.0)];
    // The plane intercepts E times its area projected along the sun's direction, and reflects rho of it.
    let sun_expected = albedo as f64 * 2.0 * (side * side) as f64 * (-d.y) as f64;
    let light = PointLight::new(Vec3::new(0.0, 2.0, 0.0), Vec3::new(1.0, 0.5, 0.25), 10.0, 50.0);
    let point_expected = albedo as f64 * intercepted_flux(10.0, 50.0, 2.0, side);
    for source in [VplSource::Rsm, VplSource::Traced] {
        let s = VplSettings { count: 4096, source, ..Default::default() };
        let set = vpl::generate(&bvh, &[], &suns, &s);
        assert!(!set.vpls.is_empty(), "{source:?}: a sun over a plane made no VPLs");
        // Rays through the aperture's parts beside the plane miss it.
        assert!(set.misses > 0 && set.misses < set.samples);
        let red = set.total_flux().x as f64;
        let err = (red - sun_expected).abs() / sun_expected;
        eprintln!("{source:?}: sun VPL flux {red:.4} vs reflected {sun_expected:.4}");
        assert!(err < 0.01, "{source:?}: sun VPL flux {red:.4} vs reflected {sun_expected:.4} ({:.2} %)", err * 100.0);
        assert!(set.vpls.iter().all(|v| v.position.y.abs() < 1e-4 && v.normal.y > 0.99 && v.light == 0));
        assert_eq!(set.light_name(0), "sun 0");
        // Beside a point light the samples are shared by power, and the total is both lights' reflected flux.
        let both = vpl::generate(&bvh, &[light], &suns, &s);
        assert_eq!(both.point_lights, 1);
        let from_sun = both.vpls.iter().filter(|v| v.light == 1).count();
        assert!(
            from_sun > 0 && from_sun < both.vpls.len(),
            "{source:?}: {from_sun} of {} from the sun",
            both.vpls.len()
        );
        let red = both.total_flux().x as f64;
        let expected = sun_expected + point_expected;
        let err = (red - expected).abs() / expected;
        assert!(err < 0.03, "{source:?}: flux of both {red:.4} vs {expected:.4} ({:.2} %)", err * 100.0);
        assert_eq!(both.light_name(0), "light 0");
        assert_eq!(both.light_name(1), "sun 0");
    }
    // A sun of zero illuminance or with a non-finite direction makes nothing.
    let dark = [sun(d, Vec3::ONE, 0.0), sun(Vec3::new(f32::NAN, -1.0, 0.0), Vec3::ONE, 1.0)];
    let none = vpl::generate(&bvh, &[], &dark, &VplSettings::default());
    assert!(none.vpls.is_empty() && none.samples == 0);
}

/// The room of [`room`] lit by a sun only: the one-bounce indirect light the path tracer (which sees the sun
/// by a shadow ray at each bounce point) and the VPL ray tracer (which gathers the sun's VPLs) agree on.
#[test]
fn a_suns_indirect_light_is_seen_by_the_vpl_gathers_and_the_path_tracer_alike() {
    let mut scene = room();
    scene.directional = vec![sun(Vec3::new(0.2, -1.0, -0.5), Vec3::ONE, 3.0)];
    let vs = VplSettings { count: 1024, clamp_world: 0.05, ..Default::default() };
    let mean = |hdr: &[[f32; 4]]| hdr.iter().map(|p| p[0] as f64).sum::<f64>() / hdr.len() as f64;
    let (traced, report) = Shot::indirect(&scene, &[], settings(Component::Indirect, vs), "vpl-raytraced").render();
    assert!(report.indirect.as_ref().unwrap().vpls > 0, "the sun made no VPLs");
    let (paths, _) = Shot::indirect(&scene, &[], settings(Component::Indirect, vs), "pathtraced")
        .params(&[("samples", ParamValue::Int(256)), ("samples_per_step", ParamValue::Int(64))])
        .render();
    let (a, b) = (mean(&traced), mean(&paths));
    eprintln!("mean indirect from the sun: VPL ray tracer {a:.5}, path tracer {b:.5}");
    assert!(a > 0.0 && b > 0.0, "no indirect light from the sun: VPLs {a}, paths {b}");
    let err = (a - b).abs() / b;
    if err >= 0.03 {
        save_hdr("sun-room-vpl-raytraced-actual.png", W, H, &traced, 0.5 / b as f32);
        save_hdr("sun-room-pathtraced-actual.png", W, H, &paths, 0.5 / b as f32);
    }
    assert!(err < 0.03, "mean indirect from the sun: VPL ray tracer {a:.5}, path tracer {b:.5} ({:.2} %)", err * 100.0);
    assert!(traced.iter().chain(&paths).all(|p| p.iter().all(|c| c.is_finite())));
}
