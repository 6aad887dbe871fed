//! wgpu errors become typed errors, never panics: an allocation past the device's limits inside
//! `GpuContext::guarded` (every renderer entry point runs in it) is an `Err`, and the device stays usable.

mod common;

use shadowlab_core::GpuError;

#[test]
fn a_buffer_past_the_limits_is_an_error_not_a_panic() {
    let gpu = common::gpu();
    let too_big = gpu.device.limits().max_buffer_size.saturating_mul(2);
    let r = gpu.guarded(|| {
        let _ = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("too big"),
            size: too_big,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        Ok(())
    });
    match r {
        Err(GpuError::Validation(m)) | Err(GpuError::OutOfMemory(m)) => assert!(!m.is_empty()),
        other => panic!("expected a GPU error, got {other:?}"),
    }
    // The device still works: a renderer renders a frame after the error.
    let scene = common::plane_and_occluder();
    let settings = shadowlab_core::RenderSettings { width: 32, height: 24, ..Default::default() };
    let mut renderer = shadowlab_core::Renderer::new(&gpu, &scene, settings).unwrap();
    let mut t = renderer.create_technique("unshadowed").unwrap();
    let lights = [common::white_light(glam::Vec3::new(0.0, 3.0, 0.0), 5.0, 20.0)];
    renderer.render_frame(t.as_mut(), &scene.camera, &lights, &mut |_, _| {}).unwrap();
}

#[test]
fn no_single_pass_shades_more_than_the_bounded_work() {
    let gpu = common::gpu();
    let scene = common::plane_and_occluder();
    let settings = shadowlab_core::RenderSettings { width: 16, height: 12, ..Default::default() };
    let mut renderer = shadowlab_core::Renderer::new(&gpu, &scene, settings).unwrap();
    let max = shadowlab_core::technique::MAX_LIGHT_WORK_PER_PASS;
    // Lights above the plane, all in view.
    let lights: Vec<_> = (0..max + 100)
        .map(|i| {
            common::white_light(
                glam::Vec3::new((i % 100) as f32 * 0.05 - 2.5, 2.0, (i / 100) as f32 * 0.05 - 1.0),
                0.01,
                30.0,
            )
        })
        .collect();
    let mut t = renderer.create_technique("unshadowed").unwrap();
    let report = renderer.render_frame(t.as_mut(), &scene.camera, &lights, &mut |_, _| {}).unwrap();
    assert!(
        report.counts.technique.batches >= 2,
        "{} lights in {} pass(es)",
        lights.len(),
        report.counts.technique.batches
    );
    // Soft ray-traced shadows: lights x rays per pass bounded too.
    let mut rt = renderer.create_technique("raytraced").unwrap();
    rt.set_param("soft", &shadowlab_core::technique::ParamValue::Bool(true)).unwrap();
    rt.set_param("samples", &shadowlab_core::technique::ParamValue::Int(256)).unwrap();
    rt.set_param("lights_per_step", &shadowlab_core::technique::ParamValue::Int(4096)).unwrap();
    let few = &lights[..64];
    let report = renderer.render_frame(rt.as_mut(), &scene.camera, few, &mut |_, _| {}).unwrap();
    assert_eq!(report.counts.technique.batches, 64 * 256 / max, "64 lights x 256 rays in passes of {max}");
}

#[test]
fn after_the_device_is_lost_every_renderer_call_is_a_device_lost_error() {
    // What a driver reset does, by `destroy`: the renderer refuses work with `DeviceLost` instead of running
    // calls that wgpu would void (or panic in, as its buffer helpers do on a lost device).
    let gpu = common::gpu();
    let scene = common::plane_and_occluder();
    let settings = shadowlab_core::RenderSettings { width: 32, height: 24, ..Default::default() };
    let mut renderer = shadowlab_core::Renderer::new(&gpu, &scene, settings).unwrap();
    let mut t = renderer.create_technique("reference").unwrap();
    let lights = [common::white_light(glam::Vec3::new(0.0, 3.0, 0.0), 5.0, 20.0)];
    renderer.render_frame(t.as_mut(), &scene.camera, &lights, &mut |_, _| {}).unwrap();
    assert_eq!(gpu.lost(), None);
    gpu.device.destroy();
    let _ = gpu.device.poll(wgpu::PollType::wait_indefinitely());
    assert!(gpu.lost().is_some_and(|r| r.contains("Destroyed")), "{:?}", gpu.lost());
    match renderer.render_frame(t.as_mut(), &scene.camera, &lights, &mut |_, _| {}) {
        Err(GpuError::DeviceLost(reason)) => assert!(reason.contains("Destroyed")),
        other => panic!("expected DeviceLost, got {:?}", other.map(|_| ())),
    }
    assert!(matches!(renderer.read_hdr(), Err(GpuError::DeviceLost(_))));
}
