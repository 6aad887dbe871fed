//! Imperfect shadow maps (Ritschel et al. 2008) on the software adapter: the GPU pull-push is its CPU twin and
//! fills holes; against the reference the error falls as the points and the resolution grow and becomes small
//! with enough of both; bad parameters are refused or clamped and said; zero lights, a scene without
//! triangles and 100,000 lights work; the inspector, overlays and counts; and `vpl-ism` is closer to
//! `vpl-shadowmaps` than `vpl-unshadowed` is.

mod common;

use common::*;
use glam::{Vec2, Vec3, Vec4};
use shadowlab_core::scene::{Aabb, Camera, Material, Mesh, PointLight, Scene, SceneSource};
use shadowlab_core::technique::ism::pull_push::{pull_push, EMPTY};
use shadowlab_core::technique::ism::IsmMaps;
use shadowlab_core::technique::{ParamError, ParamValue, Technique};
use shadowlab_core::vpl::VplSettings;
use shadowlab_core::Renderer;

const W: u32 = 64;
const H: u32 = 48;

fn int(v: i64) -> ParamValue {
    ParamValue::Int(v)
}

/// An axis-aligned box of half-size `half` around `center`, outward normals, counter-clockwise faces.
fn cube(center: Vec3, half: f32) -> Mesh {
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y, Vec3::X),
    ];
    let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::new());
    for (n, u, v) in faces {
        let base = positions.len() as u32;
        for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            positions.push(center + (n + u * a + v * b) * half);
            normals.push(n);
        }
        indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    let uvs = vec![Vec2::ZERO; positions.len()];
    Mesh { name: "box".into(), positions, normals, uvs, uvs1: Vec::new(), indices, material: 0 }
}

/// A 6 m ground and a floating 0.8 m box, seen from above, two lights on either side: the box's shadows on the
/// ground fill much of the view.
fn box_scene() -> (Scene, Vec<PointLight>) {
    let grey = Material { name: "grey".into(), base_color: Vec4::new(0.5, 0.5, 0.5, 1.0), ..Default::default() };
    let mut scene = Scene {
        name: "ground-and-box".into(),
        source: SceneSource::Builtin("test".into()),
        meshes: vec![quad("ground", Vec3::ZERO, 6.0, 0), cube(Vec3::new(0.0, 0.9, 0.0), 0.4)],
        materials: vec![grey],
        textures: vec![],
        lights: vec![],
        directional: vec![],
        camera: Camera::look_at(Vec3::new(0.0, 5.0, 3.0), Vec3::new(0.0, 0.0, 0.2), 55f32.to_radians(), 0.1, 30.0),
        bounds: Aabb::EMPTY,
        warnings: vec![],
    };
    scene.finalize(std::path::Path::new("test")).unwrap();
    let lights = vec![
        white_light(Vec3::new(-1.6, 3.0, 0.4), 8.0, 10.0),
        PointLight::new(Vec3::new(1.3, 2.6, -0.7), Vec3::new(1.0, 0.7, 0.4), 7.0, 10.0),
    ];
    (scene, lights)
}

/// An ISM frame with `params` on `renderer`: the image and the technique's counts.
fn ism(
    r: &mut Renderer,
    scene: &Scene,
    lights: &[PointLight],
    params: Params,
) -> (Vec<[f32; 4]>, Box<dyn Technique>, shadowlab_core::technique::TechniqueCounts) {
    let mut t = create(r, "ism", params);
    let (image, report) = frame(r, t.as_mut(), &scene.camera, lights);
    (image, t, report.counts.technique)
}

#[test]
fn the_gpu_pull_push_fills_holes_as_its_cpu_twin() {
    let gpu = gpu();
    let res = 32u32;
    // Two maps: a tilted plane in front of a far background with 80 % of the texels empty (a seeded pattern),
    // and one with a single point.
    let mut plane = vec![EMPTY; (res * res) as usize];
    let mut state = 12345u32;
    for y in 0..res {
        for x in 0..res {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            if state >> 24 < 52 {
                let near = x > 8 && x < 24 && y > 6 && y < 26;
                plane[(y * res + x) as usize] = if near { 0.2 + 0.004 * x as f32 } else { 0.8 };
            }
        }
    }
    let mut single = vec![EMPTY; (res * res) as usize];
    single[(17 * res + 5) as usize] = 0.35;
    let holes = plane.iter().filter(|&&z| z >= EMPTY).count();
    assert!(holes > 700, "{holes} holes");
    let mut maps = IsmMaps::new(&gpu);
    for levels in [0u32, 1, 3, 5] {
        let gpu_maps = maps.pull_push_on(&gpu, &[plane.clone(), single.clone()], res, levels, 0.1).unwrap();
        for (i, source) in [&plane, &single].into_iter().enumerate() {
            let mut cpu = source.clone();
            pull_push(&mut cpu, res, levels, 0.1);
            let worst = cpu.iter().zip(&gpu_maps[i]).map(|(a, b)| (a - b).abs()).fold(0f32, f32::max);
            assert!(worst < 1e-5, "map {i}, {levels} levels: GPU and CPU differ by {worst}");
        }
        let left = gpu_maps[0].iter().filter(|&&z| z >= EMPTY).count();
        eprintln!("{levels} levels: {left} of {holes} holes left");
        if levels == 0 {
            assert_eq!(gpu_maps[0], plane, "no levels: the splats as they are");
        }
        if levels >= 3 {
            assert_eq!(left, 0, "{levels} levels fill every hole");
            // Inside the near plane the holes take near depths, never the background's.
            let inside = gpu_maps[0][(16 * res + 16) as usize];
            assert!(inside < 0.4, "a hole inside the near plane reads {inside}");
        }
    }
    // Five levels take the single point across the whole 32² map.
    let filled = &maps.pull_push_on(&gpu, &[single.clone()], res, 5, 0.1).unwrap()[0];
    assert!(filled.iter().all(|&z| (z - 0.35).abs() < 1e-6));
}

#[test]
fn the_error_falls_as_points_and_resolution_grow_and_becomes_small() {
    let (scene, lights) = box_scene();
    let mut r = renderer(&scene, linear_settings(W, H));
    let reference = frame_of(&mut r, "reference", &[("shadow_res", int(512))], &scene.camera, &lights).0;
    let unshadowed = frame_of(&mut r, "unshadowed", &[], &scene.camera, &lights).0;
    let none = display_difference(&unshadowed, &reference, W, H, 1.0, None);
    let mut errors = Vec::new();
    for (points, res) in [(500, 32), (4_000, 64), (30_000, 128), (200_000, 256)] {
        let (image, _, counts) = ism(&mut r, &scene, &lights, &[("points", int(points)), ("resolution", int(res))]);
        let d = display_difference(&image, &reference, W, H, 1.0, None);
        eprintln!("ism {points} points, {res}²: {d}");
        assert_eq!(counts.figures["ism point splats"], (points * 2) as f64, "two lights, a subset each");
        errors.push((points, res, d, image));
    }
    eprintln!("unshadowed against the reference: {none}");
    for w in errors.windows(2) {
        assert!(
            w[1].2.mean_abs < w[0].2.mean_abs,
            "{} points at {}² ({}) is no better than {} at {}² ({})",
            w[1].0,
            w[1].1,
            w[1].2,
            w[0].0,
            w[0].1,
            w[0].2
        );
    }
    let (_, _, best, image) = errors.last().unwrap();
    // Measured: mean abs 0.0060, 0.0026, 0.0016, 0.0006 (0.20 % of the pixels over 0.1, at the shadow edges);
    // unshadowed is 0.0090 off.
    let within = best.mean_abs < 0.002 && best.bad_share < 0.01;
    if !within {
        let exp: Vec<Option<[f32; 4]>> = reference.iter().copied().map(Some).collect();
        let path = write_failure_images("ism-enough-points", W, H, image, &exp, &best.bad);
        panic!("200,000 points at 256² are not the reference: {best}; see {}", path.display());
    }
    assert!(none.mean_abs > 5.0 * best.mean_abs, "the scene's shadows are too small to tell: {none}");
}

#[test]
fn bad_parameters_are_refused_or_clamped_and_said() {
    let (scene, lights) = box_scene();
    let mut r = renderer(&scene, linear_settings(W, H));
    let mut t = create(&r, "ism", &[]);
    for (key, value) in [
        ("points", int(0)),
        ("resolution", int(0)),
        ("resolution", int(1 << 20)),
        ("levels", int(-1)),
        ("bias", ParamValue::Float(-1.0)),
    ] {
        match t.set_param(key, &value) {
            Err(ParamError::Invalid { reason, .. }) => assert!(reason.contains("outside"), "{key}: {reason}"),
            other => panic!("{key} = {value}: {other:?}"),
        }
    }
    // More pull-push levels than an 8² map has: clamped to its 3, and the counts say what was asked.
    let (image, _, counts) = ism(&mut r, &scene, &lights, &[("resolution", int(8)), ("levels", int(12))]);
    assert!(image.iter().all(|p| p.iter().all(|c| c.is_finite())));
    assert_eq!(counts.figures["ism pull-push levels"], 3.0);
    assert_eq!(counts.figures["ism pull-push levels asked"], 12.0);
    // No lights: no steps, the ambient image.
    let (_, _, counts) = ism(&mut r, &scene, &[], &[]);
    assert_eq!((counts.batches, counts.shadow_maps), (0, 0));
    // 100,000 lights (tiny maps so it stays quick): every visible one gets its map, in batches.
    let many: Vec<PointLight> = (0..100_000)
        .map(|i| {
            let a = i as f32 * 0.618;
            white_light(Vec3::new(2.5 * a.cos(), 2.0 + (i % 7) as f32 * 0.2, 2.5 * a.sin()), 0.002, 1.5)
        })
        .collect();
    let started = std::time::Instant::now();
    let (image, _, counts) =
        ism(&mut r, &scene, &many, &[("points", int(16)), ("resolution", int(8)), ("levels", int(1))]);
    eprintln!(
        "100,000 lights: {} visible, {} maps in {} batches, {:.1} s",
        counts.lights_visible,
        counts.shadow_maps,
        counts.batches,
        started.elapsed().as_secs_f64()
    );
    assert!(image.iter().all(|p| p.iter().all(|c| c.is_finite())));
    assert_eq!(counts.shadow_maps, counts.lights_visible);
    assert!(counts.lights_visible > 1000);
    // A scene without a triangle is refused by its loader ("the file contains no triangles"); one whose only
    // triangle has no area leaves an empty pool: every light unshadowed.
    let mut empty = scene.clone();
    empty.meshes.truncate(1);
    empty.meshes[0].positions = vec![Vec3::ONE; 4];
    empty.finalize(std::path::Path::new("test")).unwrap();
    let mut r = renderer(&empty, linear_settings(W, H));
    let (image, _, counts) = ism(&mut r, &empty, &lights, &[]);
    assert_eq!(counts.figures["ism pool points"], 0.0);
    assert!(image.iter().all(|p| p.iter().all(|c| c.is_finite())));
    let mut cleared = scene.clone();
    cleared.meshes.clear();
    assert!(cleared.finalize(std::path::Path::new("test")).is_err());
}

#[test]
fn the_inspector_overlays_and_counts_show_the_maps() {
    let (scene, lights) = box_scene();
    let mut r = renderer(&scene, linear_settings(W, H));
    let params: Params = &[("points", int(3_000)), ("resolution", int(32)), ("inspect", int(1)), ("seed", int(3))];
    let (first, t, counts) = ism(&mut r, &scene, &lights, params);
    assert_eq!(counts.shadow_maps, 2);
    assert_eq!(counts.work.shadow_texels_written, 2 * 2 * 32 * 32, "two paraboloids of 32² per light");
    assert_eq!(counts.shadow_triangles_submitted, 0, "no triangle is drawn into an ISM");
    let (atlas, _) = t.shadow_atlas().expect("the last batch's atlas");
    assert_eq!(atlas.projections.iter().flatten().count(), 4);
    let images = t.depth_images();
    assert_eq!(images.len(), 1, "the inspected light's map");
    let inspected = images[0].0;
    assert_eq!(inspected.tiles, 2);
    let eye = inspected.projections[0].unwrap().eye();
    assert!(eye.distance(lights[1].position) < 1e-5, "the inspected map is light 1's: {eye}");
    let depths = shadowlab_core::gpu::readback::read_texture(r.gpu(), &inspected.texture, 64, 32, 4).unwrap();
    let depths: Vec<f32> = bytemuck::cast_slice(&depths).to_vec();
    let drawn = depths.iter().filter(|&&d| d < 1.0).count();
    assert!(drawn > 32 * 32 / 2, "the lower paraboloid sees the ground: {drawn} texels drawn");
    let layers = t.overlays(&lights);
    let subset = layers.iter().find(|l| l.name == "ism points of the inspected map").unwrap();
    assert_eq!(subset.primitives.len(), 3_000);
    assert!(!layers.iter().find(|l| l.name.starts_with("ism points (")).unwrap().primitives.is_empty());
    let steps = t.explain();
    assert_eq!(steps.len(), 4);
    for step in &steps {
        for (key, text) in step.params {
            let p = t.params().into_iter().find(|p| p.key == *key).unwrap();
            p.kind.parse(key, text).unwrap();
        }
    }
    // The same seed renders the same image; another seed another (nearly the same) one.
    let (again, _, _) = ism(&mut r, &scene, &lights, params);
    assert_eq!(first, again);
    let reseeded: Params = &[("points", int(3_000)), ("resolution", int(32)), ("seed", int(4))];
    let (other, _, _) = ism(&mut r, &scene, &lights, reseeded);
    assert_ne!(first, other);
}

/// A ground, a ceiling 2.2 m above it and a 2 m plate between them at 1 m, seen from between plate and ceiling;
/// a light under the plate lights the ground, whose VPLs light the ceiling except above the plate (the harness's
/// indirect-shadow case).
fn ceiling() -> Scene {
    let mut scene = plane_and_occluder();
    scene.meshes = vec![quad("ground", Vec3::ZERO, 8.0, 0), quad("plate", PLATE_CENTER, 2.0, 0)];
    let mut ceiling = quad("ceiling", Vec3::new(0.0, 2.2, 0.0), 8.0, 0);
    ceiling.normals = vec![Vec3::NEG_Y; 4];
    ceiling.indices = vec![0, 1, 2, 0, 2, 3];
    scene.meshes.push(ceiling);
    scene.camera = Camera::look_at(Vec3::new(0.0, 1.5, 3.5), Vec3::new(0.0, 2.2, 0.0), 60f32.to_radians(), 0.05, 20.0);
    scene.finalize(std::path::Path::new("test")).unwrap();
    scene
}

#[test]
fn vpl_ism_is_closer_to_vpl_shadowmaps_than_no_visibility() {
    let scene = ceiling();
    let lights = vec![white_light(Vec3::new(0.2, 0.4, 0.1), 4.0, 20.0)];
    let settings = indirect_settings(W, H, VplSettings { count: 64, ..Default::default() });
    let (target, _) = Shot::indirect(&scene, &lights, settings.clone(), "vpl-shadowmaps").render();
    let (none, _) = Shot::indirect(&scene, &lights, settings.clone(), "vpl-unshadowed").render();
    let (image, report) = Shot::indirect(&scene, &lights, settings, "vpl-ism").params(&[("inspect", int(5))]).render();
    let ind = report.indirect.unwrap();
    assert_eq!(ind.counts.shadow_maps, ind.vpls);
    assert_eq!(ind.counts.figures["ism maps"] as usize, ind.vpls);
    let exposure = metered_exposure(&target, &vec![true; target.len()]);
    let d = display_difference(&image, &target, W, H, exposure, None);
    let d_none = display_difference(&none, &target, W, H, exposure, None);
    let mean = |img: &[[f32; 4]]| img.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / (3 * img.len()) as f64;
    let brighter = image.iter().zip(&target).filter(|(a, b)| a[1] > b[1] * 1.05 + 1e-4).count();
    let darker = image.iter().zip(&target).filter(|(a, b)| a[1] < b[1] * 0.95 - 1e-4).count();
    eprintln!(
        "vpl-ism vs vpl-shadowmaps: {d}; vpl-unshadowed vs vpl-shadowmaps: {d_none}; means {:.5} / {:.5} / {:.5}, \
         {brighter} pixels brighter, {darker} darker",
        mean(&image),
        mean(&target),
        mean(&none)
    );
    assert!(image.iter().all(|p| p.iter().all(|c| c.is_finite())));
    // Measured: 0.018 against 0.026 (points of the ceiling behind the plate leak through its gaps: ISM's
    // imperfection at 12,000 points per map).
    if d.mean_abs >= 0.85 * d_none.mean_abs {
        let scaled = |img: &[[f32; 4]]| -> Vec<[f32; 4]> { img.iter().map(|p| p.map(|c| c * exposure)).collect() };
        let exp: Vec<Option<[f32; 4]>> = scaled(&target).into_iter().map(Some).collect();
        let path = write_failure_images("vpl-ism", W, H, &scaled(&image), &exp, &d.bad);
        panic!("vpl-ism ({d}) is not much closer than no visibility ({d_none}); see {}", path.display());
    }
}
