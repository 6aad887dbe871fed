//! INSM on outside-in scenes (the paper's regime: a model on a floor, lights above it) with its DEFAULT settings:
//! the paper's bounding-box placement, 10 maps of 128², against the per-light reference (the oracle), in the
//! paper's metric (mean shadow intensity error, from visibility factors against the unshadowed frame).
//!
//! Before the connectivity fix (`insm/triangulate.wgsl`, `edge_connected`) the paper's "both second differences
//! below ε" eroded every surface by a sample and a half (the paper reports half a sample): the 1 m plate, 3-4
//! samples wide in the box placement's 128² maps, vanished and INSM rendered the unshadowed image.

mod common;

use common::*;
use glam::Vec3;
use shadowlab_core::compare::{visibility_image, Image};
use shadowlab_core::scene::{Camera, PointLight, Scene};
use shadowlab_core::technique::ParamValue;
use shadowlab_core::Renderer;

const W: u32 = 160;
const H: u32 = 120;

/// Six lights on a ring above the plate.
fn lights_above() -> Vec<PointLight> {
    (0..6)
        .map(|i| {
            let a = i as f32 * std::f32::consts::TAU / 6.0;
            white_light(Vec3::new(a.cos() * 1.2, 3.0, a.sin() * 1.2), 3.0, 8.0)
        })
        .collect()
}

/// Visibility factors of `key` with `params` (an empty list: the defaults), from the frame and the unshadowed one.
fn visibility(
    r: &mut Renderer,
    key: &str,
    params: Params,
    camera: &Camera,
    lights: &[PointLight],
    unshadowed: &Image,
) -> Vec<f32> {
    let (pixels, _) = frame_of(r, key, params, camera, lights);
    let image = Image::new(W, H, pixels).unwrap();
    visibility_image(&image, unshadowed, None).unwrap()
}

/// Mean |V_a - V_b| and mean (1 - V) of `a` and `b`: the shadow intensity error and how much shadow each casts.
fn errors(a: &[f32], b: &[f32]) -> (f32, f32, f32) {
    let n = a.len() as f32;
    let err = a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<f32>() / n;
    let shadow = |v: &[f32]| v.iter().map(|x| 1.0 - x).sum::<f32>() / n;
    (err, shadow(a), shadow(b))
}

/// The plate-and-ground scene lit by the ring of lights: its renderer, the unshadowed frame and the reference's
/// visibility factors (256 texels per face).
struct Plate {
    scene: Scene,
    lights: Vec<PointLight>,
    r: Renderer,
    open: Image,
    reference: Vec<f32>,
}

fn plate() -> Plate {
    let scene = plane_and_occluder();
    let lights = lights_above();
    let mut r = renderer(&scene, linear_settings(W, H));
    let (open, _) = frame_of(&mut r, "unshadowed", &[], &scene.camera, &lights);
    let open = Image::new(W, H, open).unwrap();
    let res = [("shadow_res", ParamValue::Int(256))];
    let reference = visibility(&mut r, "reference", &res, &scene.camera, &lights, &open);
    Plate { scene, lights, r, open, reference }
}

#[test]
fn the_default_box_placement_casts_the_plates_shadow() {
    let Plate { scene, lights, mut r, open, reference } = plate();
    // INSM as a user gets it (the paper's box placement), the per-light resolution aside, at 256²: the plate is
    // then 6-8 samples wide in the maps (at 128² it is 3-4 and the half-sample erosion left nothing of it).
    let params = [("shadow_res", ParamValue::Int(256)), ("insm_res", ParamValue::Int(256))];
    let insm = visibility(&mut r, "insm", &params, &scene.camera, &lights, &open);
    let (err, shadow_insm, shadow_ref) = errors(&insm, &reference);
    // Measured: the reference's mean shadow (1 - V over the image) is 1.03 %; INSM's 0.96 % at an error of
    // 0.13 % with the defaults (0.87 % at 0.16 % without `dilate`, the test below). With the paper's "both second
    // differences below ε" (a sample and a half of erosion): 0.27 % at an error of 0.77 %; at 128² it cast none
    // at all (the box placement's top cameras see the 1 m plate obliquely, two samples deep at 128²).
    eprintln!("error {err}, shadow INSM {shadow_insm}, reference {shadow_ref}");
    assert!(shadow_ref > 0.005, "the plate shadows {shadow_ref}");
    assert!(shadow_insm > 0.8 * shadow_ref, "INSM casts {shadow_insm} of the reference's {shadow_ref} shadow");
    assert!(err < 0.2 * shadow_ref, "shadow intensity error {err} against the reference's shadow {shadow_ref}");
}

#[test]
fn undoing_the_erosion_casts_more_of_the_plates_shadow() {
    let Plate { scene, lights, mut r, open, reference } = plate();
    // The plate is 6-8 samples wide in the 256² maps: its mesh ends at its last samples, half a sample short of
    // its edges on every side (the paper's half-sample erosion), unless `dilate` moves them across.
    let run = |r: &mut Renderer, dilate: bool| {
        let params = [
            ("shadow_res", ParamValue::Int(256)),
            ("insm_res", ParamValue::Int(256)),
            ("dilate", ParamValue::Bool(dilate)),
        ];
        visibility(r, "insm", &params, &scene.camera, &lights, &open)
    };
    let (plain, dilated) = (run(&mut r, false), run(&mut r, true));
    let (err_plain, shadow_plain, shadow_ref) = errors(&plain, &reference);
    let (err_dilated, shadow_dilated, _) = errors(&dilated, &reference);
    eprintln!(
        "without dilate: error {err_plain}, shadow {shadow_plain}; with: error {err_dilated}, shadow \
         {shadow_dilated}; reference {shadow_ref}"
    );
    assert!(shadow_dilated > shadow_plain, "dilated {shadow_dilated}, plain {shadow_plain}");
    assert!(err_dilated < err_plain, "error dilated {err_dilated}, plain {err_plain}");
}
