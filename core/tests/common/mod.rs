//! Test support: the GPU (which must exist in CI), small hand-made scenes, image comparison that writes
//! `actual` and `difference` PNGs on failure.
#![allow(dead_code)]

pub mod analytic;
pub mod render;
pub mod vpl_scenes;

#[allow(unused_imports)] // not every test uses the render helpers
pub use render::*;
#[allow(unused_imports)]
pub use vpl_scenes::*;

use std::path::PathBuf;

use glam::{Vec2, Vec3, Vec4};
use shadowlab_core::scene::{Aabb, Camera, Material, Mesh, PointLight, Scene, SceneSource};
use shadowlab_core::GpuContext;

/// The GPU for a test. In CI (`CI` set) a missing adapter fails the test; elsewhere it also fails, with the
/// command that installs the software adapter: a GPU test never passes without running.
pub fn gpu() -> GpuContext {
    match GpuContext::headless() {
        Ok(g) => g,
        Err(e) => panic!(
            "GPU test needs an adapter and found none ({e}). Install Mesa lavapipe: \
             sudo apt-get install -y mesa-vulkan-drivers libvulkan1"
        ),
    }
}

/// A horizontal square of side `size` centred at `center`, normal +Y.
pub fn quad(name: &str, center: Vec3, size: f32, material: usize) -> Mesh {
    let h = size * 0.5;
    let positions = vec![
        center + Vec3::new(-h, 0.0, -h),
        center + Vec3::new(h, 0.0, -h),
        center + Vec3::new(h, 0.0, h),
        center + Vec3::new(-h, 0.0, h),
    ];
    Mesh {
        name: name.into(),
        positions,
        normals: vec![Vec3::Y; 4],
        uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
        uvs1: Vec::new(),
        indices: vec![0, 2, 1, 0, 3, 2],
        material,
    }
}

pub const GROUND_SIZE: f32 = 20.0;
pub const PLATE_CENTER: Vec3 = Vec3::new(0.0, 1.0, 0.0);
pub const PLATE_SIZE: f32 = 1.0;
pub const ALBEDO: f32 = 0.5;

/// A ground plane (y = 0, 20 x 20) and a floating square occluder (1 x 1 at y = 1).
pub fn plane_and_occluder() -> Scene {
    let grey =
        Material { name: "grey".into(), base_color: Vec4::new(ALBEDO, ALBEDO, ALBEDO, 1.0), ..Default::default() };
    let mut scene = Scene {
        name: "plane-occluder".into(),
        source: SceneSource::Builtin("test".into()),
        meshes: vec![quad("ground", Vec3::ZERO, GROUND_SIZE, 0), quad("plate", PLATE_CENTER, PLATE_SIZE, 0)],
        materials: vec![grey],
        textures: vec![],
        lights: vec![],
        directional: vec![],
        camera: Camera::look_at(Vec3::new(0.0, 6.0, 5.0), Vec3::new(0.0, 0.0, 0.5), 60f32.to_radians(), 0.1, 50.0),
        bounds: Aabb::EMPTY,
        warnings: vec![],
    };
    scene.finalize(std::path::Path::new("test")).unwrap();
    scene
}

pub fn white_light(position: Vec3, intensity: f32, range: f32) -> PointLight {
    PointLight::new(position, Vec3::ONE, intensity, range)
}

/// Where test images go: `target/test-output/`.
pub fn output_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/test-output");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Save an HDR image (linear RGBA) as a PNG, values clamped to 0..1 after `scale`.
pub fn save_hdr(name: &str, w: u32, h: u32, pixels: &[[f32; 4]], scale: f32) -> PathBuf {
    let img = image::RgbaImage::from_fn(w, h, |x, y| {
        let p = pixels[(y * w + x) as usize];
        let c = |v: f32| ((v * scale).clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0) as u8;
        image::Rgba([c(p[0]), c(p[1]), c(p[2]), 255])
    });
    let path = output_dir().join(name);
    img.save(&path).unwrap();
    path
}

/// Write `<name>-actual.png`, `<name>-expected.png` and `<name>-difference.png` (red where wrong) to
/// [`output_dir`] and return the difference image's path, for a failing image test to show its pictures.
pub fn write_failure_images(
    name: &str,
    w: u32,
    h: u32,
    actual: &[[f32; 4]],
    expected: &[Option<[f32; 4]>],
    bad: &[bool],
) -> PathBuf {
    save_hdr(&format!("{name}-actual.png"), w, h, actual, 1.0);
    let exp: Vec<[f32; 4]> = expected.iter().map(|e| e.unwrap_or([0.0, 0.0, 0.3, 1.0])).collect();
    save_hdr(&format!("{name}-expected.png"), w, h, &exp, 1.0);
    let diff: Vec<[f32; 4]> =
        bad.iter().map(|&b| if b { [1.0, 0.0, 0.0, 1.0] } else { [0.0, 0.0, 0.1, 1.0] }).collect();
    save_hdr(&format!("{name}-difference.png"), w, h, &diff, 1.0)
}

/// The ground and occluder of [`plane_and_occluder`] with a back wall (z = -3, facing +z, 8 x 8) that the
/// ground's VPLs light and the plate shadows, seen by the default camera: the indirect-light test scene.
pub fn room() -> Scene {
    let mut scene = plane_and_occluder();
    let h = 4.0;
    scene.meshes.push(Mesh {
        name: "wall".into(),
        positions: vec![
            Vec3::new(-h, 0.0, -3.0),
            Vec3::new(h, 0.0, -3.0),
            Vec3::new(h, 2.0 * h, -3.0),
            Vec3::new(-h, 2.0 * h, -3.0),
        ],
        normals: vec![Vec3::Z; 4],
        uvs: vec![Vec2::ZERO; 4],
        uvs1: Vec::new(),
        indices: vec![0, 1, 2, 0, 2, 3],
        material: 0,
    });
    scene.finalize(std::path::Path::new("test")).unwrap();
    scene
}

/// The shared real scenes (`../shared/scenes`, or `SHADOWLAB_SCENES`). In CI (`CI` set, not `false`) a missing
/// folder fails the test with instructions; elsewhere the test says clearly that it did not run and passes, so
/// a fresh clone without the data passes the README's test command.
pub fn scenes_dir(test: &str) -> Option<PathBuf> {
    let dir = std::env::var_os("SHADOWLAB_SCENES").map(PathBuf::from).unwrap_or_else(|| {
        std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/scenes")).to_path_buf()
    });
    if dir.is_dir() {
        return Some(dir);
    }
    let message = format!(
        "the shared scenes folder {} is missing: {test} needs the real scenes (dabrovic-sponza, conference, \
         cornell-box, cornell-box-gltf) next to the project, or SHADOWLAB_SCENES pointing at them",
        dir.display()
    );
    if std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false") {
        panic!("{message}");
    }
    eprintln!("NOT RUN: {message}");
    None
}
