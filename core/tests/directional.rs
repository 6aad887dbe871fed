//! Directional lights (a glTF sun), the renderer's service for every direct technique: the glTF loader reads
//! them; the reference's orthographic shadow map agrees with the ray tracer's shadow rays; the unshadowed
//! preview has no shadow; every registered direct technique renders one.

mod common;

use common::*;
use glam::Vec3;
use shadowlab_core::scene::gltf_loader::{load_gltf, LUMENS_PER_WATT};
use shadowlab_core::scene::{DirectionalLight, Scene, MAX_DIRECTIONAL_LIGHTS};
use shadowlab_core::technique::registry::REGISTRY;

const W: u32 = 96;
const H: u32 = 72;

fn sun() -> DirectionalLight {
    DirectionalLight { direction: Vec3::new(0.35, -1.0, 0.25).normalize(), color: Vec3::ONE, illuminance: 2.0 }
}

fn sunlit() -> Scene {
    let mut scene = plane_and_occluder();
    scene.directional = vec![sun()];
    scene
}

#[test]
fn gltf_directional_lights_are_loaded_with_their_direction_and_illuminance() {
    let fixture = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/lit_quad.gltf");
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(fixture).unwrap()).unwrap();
    let lights = doc["extensions"]["KHR_lights_punctual"]["lights"].as_array_mut().unwrap();
    lights.push(serde_json::json!({"type": "directional", "intensity": 683.0, "color": [1.0, 0.9, 0.8]}));
    let light = lights.len() - 1;
    let nodes = doc["nodes"].as_array_mut().unwrap();
    let first = nodes.len();
    // A quarter turn about +X: the node's -Z (the light's direction) becomes -Y (straight down); one more than
    // the limit.
    let h = std::f32::consts::FRAC_1_SQRT_2;
    for _ in 0..MAX_DIRECTIONAL_LIGHTS + 1 {
        nodes.push(serde_json::json!({
            "rotation": [-h, 0.0, 0.0, h],
            "extensions": {"KHR_lights_punctual": {"light": light}}
        }));
    }
    let roots = doc["scenes"][0]["nodes"].as_array_mut().unwrap();
    roots.extend((first..first + MAX_DIRECTIONAL_LIGHTS + 1).map(|i| serde_json::json!(i)));
    let path = std::env::temp_dir().join("shadowlab-directional.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let scene = load_gltf(&path, 1.0).unwrap();
    assert_eq!(scene.directional.len(), MAX_DIRECTIONAL_LIGHTS);
    let d = scene.directional[0];
    assert!((d.direction - Vec3::NEG_Y).length() < 1e-5, "{:?}", d.direction);
    assert!((d.illuminance - 683.0 / LUMENS_PER_WATT).abs() < 1e-6 && d.color == Vec3::new(1.0, 0.9, 0.8));
    assert!(scene.warnings.iter().any(|w| w.contains("at most 4 directional lights")), "{:?}", scene.warnings);
    assert!(!scene.warnings.iter().any(|w| w.contains("skipped (only point")), "{:?}", scene.warnings);
}

#[test]
fn the_reference_shadow_map_agrees_with_the_ray_tracer_and_the_preview_has_no_shadow() {
    let scene = sunlit();
    let settings = linear_settings(W, H);
    let render = |key| Shot::direct(&scene, &[], settings.clone(), key).render().0;
    let (reference, traced, unshadowed) = (render("reference"), render("raytraced"), render("unshadowed"));
    let luminance = |p: &[f32; 4]| p[0] + p[1] + p[2];
    // The plate's shadow on the ground: pixels the ray tracer sees much darker than the preview.
    let shadow: Vec<bool> = traced.iter().zip(&unshadowed).map(|(t, u)| luminance(t) < 0.5 * luminance(u)).collect();
    let in_shadow = shadow.iter().filter(|&&s| s).count();
    assert!(in_shadow > 50, "the sun casts the plate's shadow: {in_shadow} pixels");
    // Lit by the sun: the preview is not the ambient image.
    let ambient = Shot::direct(&plane_and_occluder(), &[], settings.clone(), "unshadowed").render().0;
    let lit = unshadowed.iter().zip(&ambient).filter(|(u, a)| luminance(u) > 2.0 * luminance(a) + 1e-3).count();
    assert!(lit > (W * H) as usize / 2, "the sun lights the ground: {lit} pixels");
    let d = display_difference(&reference, &traced, W, H, 1.0, None);
    eprintln!("reference against raytraced under a sun: {d}; {in_shadow} shadow pixels");
    if d.mean_abs > 0.01 || d.bad_share > 0.02 {
        let exp: Vec<Option<[f32; 4]>> = traced.iter().copied().map(Some).collect();
        let paths = write_failure_images("directional", W, H, &reference, &exp, &d.bad);
        panic!("the sun's shadow map is not the ray tracer's shadow: {d}; see {paths:?}");
    }
}

#[test]
fn every_direct_technique_renders_the_sun() {
    // Each registered direct technique adds the sun (the renderer's service), with its shadow except the
    // preview: the shadow's pixels are darker than the preview's in every technique but the preview.
    let scene = sunlit();
    let settings = linear_settings(48, 36);
    let render = |key| Shot::direct(&scene, &[], settings.clone(), key).render().0;
    let unshadowed = render("unshadowed");
    let traced = render("raytraced");
    let luminance = |p: &[f32; 4]| p[0] + p[1] + p[2];
    let shadow: Vec<usize> =
        (0..traced.len()).filter(|&i| luminance(&traced[i]) < 0.5 * luminance(&unshadowed[i])).collect();
    assert!(!shadow.is_empty());
    for entry in REGISTRY {
        let image = render(entry.key);
        let dark = shadow.iter().filter(|&&i| luminance(&image[i]) < 0.75 * luminance(&unshadowed[i])).count();
        let share = dark as f32 / shadow.len() as f32;
        if entry.key == "unshadowed" {
            assert_eq!(dark, 0, "the preview has no shadow");
        } else {
            assert!(share > 0.8, "{}: {dark} of {} shadow pixels dark", entry.key, shadow.len());
        }
    }
}

#[test]
fn set_directional_lights_replaces_the_scenes_suns_and_refuses_bad_ones() {
    // The app's sun editing: a scene without suns lit by one set on the renderer, exactly as a scene that has
    // it; a bad list changes nothing; an empty one removes the scene's.
    let settings = linear_settings(W, H);
    let with_sun = Shot::direct(&sunlit(), &[], settings.clone(), "reference").render().0;
    let scene = plane_and_occluder();
    let mut r = renderer(&scene, settings.clone());
    assert!(r.directional_lights().is_empty());
    let ambient = frame_of(&mut r, "reference", &[], &scene.camera, &[]).0;
    r.set_directional_lights(&[sun()]).unwrap();
    let (set, report) = frame_of(&mut r, "reference", &[], &scene.camera, &[]);
    let worst = set.iter().zip(&with_sun).map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f32::max));
    assert!(worst.fold(0.0, f32::max) < 1e-5, "a sun set on the renderer renders as the scene's own");
    assert!(report.passes.iter().any(|p| p.name.contains("directional")), "{:?}", report.passes);

    let bad = [
        DirectionalLight { direction: Vec3::ZERO, ..sun() },
        DirectionalLight { illuminance: f32::NAN, ..sun() },
        DirectionalLight { color: Vec3::new(-1.0, 1.0, 1.0), ..sun() },
    ];
    for b in bad {
        let e = r.set_directional_lights(&[b]).unwrap_err().to_string();
        assert!(e.contains("directional light 0"), "{e}");
    }
    let e = r.set_directional_lights(&[sun(); MAX_DIRECTIONAL_LIGHTS + 1]).unwrap_err().to_string();
    assert!(e.contains("at most 4"), "{e}");
    assert_eq!(r.directional_lights(), &[sun()], "a refused list leaves the lights as they were");

    let mut r = renderer(&sunlit(), settings);
    assert_eq!(r.directional_lights().len(), 1, "the scene's suns to begin with");
    r.set_directional_lights(&[]).unwrap();
    let none = frame_of(&mut r, "reference", &[], &scene.camera, &[]).0;
    let worst = none.iter().zip(&ambient).map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f32::max));
    assert!(worst.fold(0.0, f32::max) < 1e-6, "no sun: the ambient image");
}
