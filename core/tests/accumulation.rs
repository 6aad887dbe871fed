//! The HDR target every shading pass adds its batch of lights into: f32 where the device can blend it, so a
//! technique's image does not depend on how its lights are batched (an f16 target rounded every batch's sum to
//! 11 bits: the reference against itself was 0.77 % off in shadow error at 512 MiB batches instead of 128).

mod common;

use common::*;
use shadowlab_core::scene::layout::{generate, parse};
use shadowlab_core::scene::Scene;
use shadowlab_core::services::layouts::SharedLayouts;
use shadowlab_core::technique::ParamValue;

#[test]
fn the_reference_image_does_not_depend_on_its_batch_size() {
    let gpu = gpu();
    let format = SharedLayouts::hdr_format(&gpu.device);
    let blendable = gpu.device.features().contains(wgpu::Features::FLOAT32_BLENDABLE);
    assert_eq!(format == wgpu::TextureFormat::Rgba32Float, blendable, "f32 exactly where it can be blended");
    let scene = Scene::builtin("cornell").unwrap();
    let lights = generate(&parse("random:96:6:1").unwrap(), &scene).unwrap();
    let render = |mib: i64| {
        let params = [("shadow_res", ParamValue::Int(64)), ("atlas_mib", ParamValue::Int(mib))];
        Shot::direct(&scene, &lights, linear_settings(64, 48), "reference").params(&params).on(gpu.clone()).render()
    };
    // 64-texel faces take 96 KiB a light: one MiB holds 10 lights a batch, 64 MiB all 96 in one.
    let ((small, small_report), (large, large_report)) = (render(1), render(64));
    assert!(small_report.counts.technique.batches > large_report.counts.technique.batches);
    let worst = small
        .iter()
        .zip(&large)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs() / b[c].abs().max(1e-3)))
        .fold(0f32, f32::max);
    eprintln!(
        "{format:?}: largest relative difference {worst:e} between {} and {} batches",
        small_report.counts.technique.batches, large_report.counts.technique.batches
    );
    if format == wgpu::TextureFormat::Rgba32Float {
        assert!(worst < 1e-5, "the batch size changed the image: {worst}");
    } else {
        // An adapter without f32 blending keeps f16 and its rounding (said in docs/techniques/reference.md).
        assert!(worst < 2e-2, "more than f16 rounding: {worst}");
    }
}
