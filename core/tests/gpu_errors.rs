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
