//! Small scenes for the VPL tests (a lit plane and its analytic flux) and the scene's BVH.

use glam::{Vec3, Vec4};
use shadowlab_core::scene::{attenuation, Aabb, Camera, Material, Mesh, Scene, SceneSource};

use super::{gpu, quad};

/// A scene of `meshes` with one grey material of albedo `albedo`.
pub fn scene_of(name: &str, meshes: Vec<Mesh>, albedo: f32, camera: Camera) -> Scene {
    let m = Material { name: "m".into(), base_color: Vec4::new(albedo, albedo, albedo, 1.0), ..Default::default() };
    let mut scene = Scene {
        name: name.into(),
        source: SceneSource::Builtin("test".into()),
        meshes,
        materials: vec![m],
        textures: vec![],
        lights: vec![],
        directional: vec![],
        camera,
        bounds: Aabb::EMPTY,
        warnings: vec![],
    };
    scene.finalize(std::path::Path::new("test")).unwrap();
    scene
}

/// Flux a point light at height `h` above the centre of a square of side `side` sends onto it, by midpoint
/// quadrature of `I * attenuation(d) * cos` (the renderer's falloff) over the square.
pub fn intercepted_flux(intensity: f32, range: f32, h: f32, side: f32) -> f64 {
    let n = 1000;
    let cell = side as f64 / n as f64;
    let mut sum = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let x = (i as f64 + 0.5) * cell - side as f64 / 2.0;
            let z = (j as f64 + 0.5) * cell - side as f64 / 2.0;
            let d = (x * x + z * z + (h * h) as f64).sqrt();
            let cos = h as f64 / d;
            sum += intensity as f64 * attenuation(d as f32, range) as f64 * cos * cell * cell;
        }
    }
    sum
}

/// The scene's BVH (the renderer's service), on a GPU of its own.
pub fn scene_bvh(scene: &Scene) -> std::sync::Arc<shadowlab_core::accel::scene_bvh::SceneBvh> {
    let gpu = gpu();
    let layout = shadowlab_core::accel::gpu_scene::GpuScene::material_layout(&gpu.device);
    shadowlab_core::accel::gpu_scene::GpuScene::new(&gpu, scene, &layout).bvh(&gpu).0
}

/// A grey square of side `side` on y = 0, seen from above.
pub fn plane_scene(side: f32, albedo: f32) -> Scene {
    let camera = Camera::look_at(Vec3::new(0.0, 6.0, 5.0), Vec3::ZERO, 60f32.to_radians(), 0.1, 50.0);
    scene_of("plane", vec![quad("ground", Vec3::ZERO, side, 0)], albedo, camera)
}
