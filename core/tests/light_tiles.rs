//! Tiled light lists (`core/src/services/light_tiles.rs`): the built-in scenes render the same image with and
//! without tiles for every technique that reads them, whatever the batching; and every light that reaches a
//! pixel is in its tile's list, in order.

mod common;

use common::*;
use shadowlab_core::scene::{builtin, layout, PointLight, Scene};
use shadowlab_core::technique::ParamValue;
use shadowlab_core::{RenderSettings, Renderer, ToneMap};

// Not multiples of 16, so the last row and column of tiles are partial.
const W: u32 = 200;
const H: u32 = 120;

fn settings(light_tiles: bool, max_lights_per_step: usize) -> RenderSettings {
    RenderSettings {
        width: W,
        height: H,
        tonemap: ToneMap::Linear,
        light_tiles,
        max_lights_per_step,
        ..Default::default()
    }
}

/// The parameters each technique renders with here (small maps: the images are compared with each other).
fn params(technique: &str) -> Params<'static> {
    match technique {
        "lightcluster" => &[("d_init", ParamValue::Float(0.6)), ("shadow_res", ParamValue::Int(64))],
        "insm" => &[("insm_res", ParamValue::Int(32)), ("k", ParamValue::Int(2)), ("shadow_res", ParamValue::Int(64))],
        // Soft shadows: the per-light random rotation must follow the light's index, not its place in the list.
        "raytraced" => &[("soft", ParamValue::Bool(true)), ("samples", ParamValue::Int(4))],
        "unshadowed" => &[],
        _ => &[("shadow_res", ParamValue::Int(64))],
    }
}

fn max_abs_difference(a: &[[f32; 4]], b: &[[f32; 4]]) -> f32 {
    a.iter().zip(b).flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs())).fold(0.0, f32::max)
}

fn scenes_and_lights() -> Vec<(String, Scene, Vec<PointLight>)> {
    let mut out = Vec::new();
    for name in ["cornell", "arcade", "restaurant"] {
        let scene = builtin::build(name).unwrap();
        out.push((format!("{name}-own"), scene.clone(), scene.lights.clone()));
        // Many short lights: most of them reach few tiles.
        let many = layout::generate(&layout::parse("random:300:0.7:3").unwrap(), &scene).unwrap();
        out.push((format!("{name}-random300"), scene, many));
    }
    out
}

#[test]
fn tiled_shading_gives_the_same_image_for_every_technique_and_batching() {
    let gpu = gpu();
    let mut failures = Vec::new();
    for (name, scene, lights) in scenes_and_lights() {
        let mut renderer = Renderer::new(&gpu, &scene, settings(false, 0)).unwrap();
        let techniques: &[&str] = if name.ends_with("own") {
            &["reference", "unshadowed", "lightcluster", "insm", "raytraced"]
        } else {
            &["reference", "unshadowed", "lightcluster", "raytraced"]
        };
        for &technique in techniques {
            renderer.set_settings(settings(false, 0)).unwrap();
            let untiled = frame_of(&mut renderer, technique, params(technique), &scene.camera, &lights).0;
            // Batches of 7 lights (clusters): a pixel's tile list intersected with each batch's range.
            for max_per_step in [0, 7] {
                renderer.set_settings(settings(true, max_per_step)).unwrap();
                let tiled = frame_of(&mut renderer, technique, params(technique), &scene.camera, &lights).0;
                let reference = if max_per_step == 0 {
                    untiled.clone()
                } else {
                    renderer.set_settings(settings(false, max_per_step)).unwrap();
                    frame_of(&mut renderer, technique, params(technique), &scene.camera, &lights).0
                };
                let diff = max_abs_difference(&tiled, &reference);
                if diff > 1e-5 {
                    let label = format!("light-tiles-{name}-{technique}-{max_per_step}");
                    let bad: Vec<bool> =
                        tiled.iter().zip(&reference).map(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 1e-5)).collect();
                    let expected: Vec<Option<[f32; 4]>> = reference.iter().map(|p| Some(*p)).collect();
                    let dir = write_failure_images(&label, W, H, &tiled, &expected, &bad);
                    failures.push(format!("{label}: max abs difference {diff:e} (images in {})", dir.display()));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn every_light_that_reaches_a_pixel_is_in_its_tile_list_in_order() {
    let gpu = gpu();
    let scene = builtin::build("arcade").unwrap();
    let lights = layout::generate(&layout::parse("random:500:1.0:5").unwrap(), &scene).unwrap();
    let mut renderer = Renderer::new(&gpu, &scene, settings(true, 0)).unwrap();
    frame_of(&mut renderer, "unshadowed", params("unshadowed"), &scene.camera, &lights);
    let tiles = renderer.read_light_tiles().unwrap();
    let positions = renderer.read_world_positions(&scene.camera).unwrap();
    let tiles_x = W.div_ceil(16) as usize;
    assert_eq!(tiles.len(), tiles_x * H.div_ceil(16) as usize);
    // The visible lights, in the renderer's order (its culling keeps the frame's order).
    let frustum =
        shadowlab_core::math::Frustum::from_clip_from_world(&scene.camera.clip_from_world(W as f32 / H as f32));
    let visible: Vec<&PointLight> =
        lights.iter().filter(|l| l.is_valid() && frustum.intersects_sphere(l.position, l.range)).collect();
    let mut listed = 0usize;
    let mut missing = Vec::new();
    for (i, p) in positions.iter().enumerate() {
        let Some(p) = p else { continue };
        let (x, y) = (i % W as usize, i / W as usize);
        let tile = tiles[(y / 16) * tiles_x + x / 16].as_ref().expect("500 lights fit a tile's list at this size");
        for (li, l) in visible.iter().enumerate() {
            // Well inside the range, so rounding of the two reconstructions cannot matter.
            if p.distance(l.position) < l.range * 0.999 && tile.binary_search(&(li as u32)).is_err() {
                missing.push((x, y, li));
            }
        }
    }
    for list in tiles.iter().flatten() {
        assert!(list.windows(2).all(|w| w[0] < w[1]), "a tile list is not in light order: {list:?}");
        listed += list.len();
    }
    assert!(
        missing.is_empty(),
        "lights reaching a pixel but not in its tile list (x, y, light): {:?}",
        &missing[..missing.len().min(10)]
    );
    // The lists cull: on average a tile holds far fewer than the visible lights.
    let mean = listed as f64 / tiles.len() as f64;
    assert!(visible.len() > 100, "the layout should put many lights in view ({})", visible.len());
    assert!(mean < 0.25 * visible.len() as f64, "tiles hold {mean:.1} of {} lights on average", visible.len());
}

#[test]
fn tiles_whose_lists_overflow_loop_over_the_whole_batch_with_the_same_image() {
    let gpu = gpu();
    let scene = builtin::build("cornell").unwrap();
    // 300 lights in a 2 m box: most reach most tiles, far more than 16 per tile.
    let lights = layout::generate(&layout::parse("random:300:1.0:9").unwrap(), &scene).unwrap();
    let mut renderer = Renderer::new(&gpu, &scene, settings(false, 0)).unwrap();
    let untiled = frame_of(&mut renderer, "unshadowed", params("unshadowed"), &scene.camera, &lights).0;
    renderer.set_settings(settings(true, 0)).unwrap();
    // The smallest capacity: 16 lights per tile.
    renderer.set_light_tile_budget(0);
    let tiled = frame_of(&mut renderer, "unshadowed", params("unshadowed"), &scene.camera, &lights).0;
    let tiles = renderer.read_light_tiles().unwrap();
    let overflowed = tiles.iter().filter(|t| t.is_none()).count();
    assert!(overflowed > 0 && overflowed < tiles.len(), "{overflowed} of {} tiles overflowed", tiles.len());
    assert!(tiles.iter().flatten().all(|t| t.len() <= 16));
    let diff = max_abs_difference(&tiled, &untiled);
    assert!(diff <= 1e-5, "overflowed tiles changed the image by {diff:e}");
}

#[test]
fn tiles_off_builds_no_lists() {
    let gpu = gpu();
    let scene = builtin::build("cornell").unwrap();
    let mut renderer = Renderer::new(&gpu, &scene, settings(false, 0)).unwrap();
    frame_of(&mut renderer, "reference", params("reference"), &scene.camera, &scene.lights);
    assert!(renderer.read_light_tiles().unwrap().is_empty());
}
