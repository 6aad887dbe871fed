//! Scene loading: small hand-written fixtures (`tests/fixtures/`) and the real scenes in `../shared/scenes`
//! (or `$SHADOWLAB_SCENES`). The real-scene tests fail, not skip, when that folder is missing.

mod common;

use std::path::{Path, PathBuf};

use common::scenes_dir;
use std::time::Instant;

use glam::{Vec3, Vec4};
use shadowlab_core::scene::gltf_loader::load_gltf;
use shadowlab_core::scene::obj_loader::load_obj;
use shadowlab_core::scene::texture::{decode_texture_bytes, find_file_case_insensitive, load_texture};
use shadowlab_core::{LoadError, Scene};

fn fixtures() -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/fixtures")).to_path_buf()
}

fn fixture(name: &str) -> PathBuf {
    fixtures().join(name)
}

fn assert_close(a: Vec3, b: Vec3, eps: f32) {
    assert!((a - b).abs().max_element() <= eps, "{a} != {b} (eps {eps})");
}

fn material<'a>(scene: &'a Scene, name: &str) -> &'a shadowlab_core::Material {
    scene.materials.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no material '{name}'"))
}

fn has_warning(scene: &Scene, needle: &str) -> bool {
    scene.warnings.iter().any(|w| w.contains(needle))
}

/// Every mesh is well formed: indices in range, one normal/uv per position, unit normals.
fn assert_well_formed(scene: &Scene) {
    assert!(!scene.meshes.is_empty());
    for mesh in &scene.meshes {
        let n = mesh.positions.len();
        assert_eq!(mesh.normals.len(), n, "mesh {}", mesh.name);
        assert_eq!(mesh.uvs.len(), n, "mesh {}", mesh.name);
        assert_eq!(mesh.indices.len() % 3, 0);
        assert!(mesh.indices.iter().all(|&i| (i as usize) < n), "mesh {}", mesh.name);
        assert!(mesh.material < scene.materials.len());
        for normal in &mesh.normals {
            assert!((normal.length() - 1.0).abs() < 1e-3, "mesh {}: normal {normal} is not unit length", mesh.name);
        }
    }
    for m in &scene.materials {
        if let Some(t) = m.base_color_texture {
            let tex = &scene.textures[t];
            assert_eq!(tex.rgba8.len(), (tex.width * tex.height * 4) as usize);
        }
    }
    assert!(!scene.bounds.is_empty());
    assert!(scene.camera.is_valid(), "{:?}", scene.camera);
}

fn mesh_of_material<'a>(scene: &'a Scene, material: &str) -> &'a shadowlab_core::Mesh {
    let index = scene.materials.iter().position(|m| m.name == material).expect("material");
    scene.meshes.iter().find(|m| m.material == index).expect("mesh with material")
}

// ---------------------------------------------------------------------------------------------------------
// Textures

#[test]
fn finds_files_regardless_of_case_and_separators() {
    let dir = fixtures();
    assert_eq!(find_file_case_insensitive(&dir, "checker.png"), Some(dir.join("checker.png")));
    let found = find_file_case_insensitive(&dir, "Checker.PNG").expect("case-insensitive match");
    assert_eq!(found.file_name().unwrap(), "checker.png");
    let nested = find_file_case_insensitive(&dir, r"TEXTURES\tiny.PNG").expect("backslashes and case");
    assert!(nested.ends_with("textures/Tiny.png"), "{}", nested.display());
    let nested = find_file_case_insensitive(&dir, r".\textures\Tiny.png").expect("leading .\\");
    assert!(nested.ends_with("Tiny.png"));
    let absolute = find_file_case_insensitive(&dir, r"C:\Users\artist\maps\CHECKER.png").expect("file name fallback");
    assert_eq!(absolute.file_name().unwrap(), "checker.png");
    assert_eq!(find_file_case_insensitive(&dir, "no_such_file.png"), None);
    assert_eq!(find_file_case_insensitive(&dir, "textures"), None, "a directory is not a texture");
    assert_eq!(find_file_case_insensitive(&dir, ""), None);
}

#[test]
fn decodes_png_to_rgba8() {
    let texture = load_texture(&fixture("checker.png")).unwrap();
    assert_eq!((texture.width, texture.height), (4, 4));
    assert_eq!(texture.rgba8.len(), 4 * 4 * 4);
    assert_eq!(&texture.rgba8[0..4], &[255, 0, 0, 255], "texel (0,0) is red");
    assert_eq!(&texture.rgba8[4..8], &[255, 255, 255, 255], "texel (1,0) is white");
    assert_eq!(texture.name, "checker.png");

    assert!(load_texture(&fixture("no_such_file.png")).unwrap_err().contains("no_such_file.png"));
    let err = decode_texture_bytes("junk.png", b"definitely not an image").unwrap_err();
    assert!(err.contains("junk.png"), "{err}");
    let bytes = std::fs::read(fixture("checker.png")).unwrap();
    assert!(decode_texture_bytes("cut.png", &bytes[..40]).is_err(), "a truncated PNG is an error");
}

#[test]
fn downscales_textures_larger_than_2048() {
    let image = image::RgbaImage::from_pixel(4096, 1024, image::Rgba([10, 20, 30, 255]));
    let mut png = Vec::new();
    image::DynamicImage::ImageRgba8(image)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let texture = decode_texture_bytes("wide.png", &png).unwrap();
    assert_eq!((texture.width, texture.height), (2048, 512), "aspect ratio kept");
    assert_eq!(&texture.rgba8[0..4], &[10, 20, 30, 255]);
}

// ---------------------------------------------------------------------------------------------------------
// OBJ fixtures

#[test]
fn obj_quad_materials_textures_and_quirks() {
    let scene = load_obj(&fixture("quad.obj"), 1.0).unwrap();
    assert_well_formed(&scene);
    assert_eq!(scene.name, "quad");
    assert_eq!(
        scene.source,
        shadowlab_core::SceneSource::File { path: fixture("quad.obj"), unit_scale: 1.0 },
        "the source re-creates the scene"
    );
    // 1 (no material) + 2 (quad) + 1 (negative indices) + 1 + 1 + 1; the `l` element adds nothing.
    assert_eq!(scene.triangle_count(), 7);
    assert!(scene.lights.is_empty());
    // Four MTL materials plus the default for faces without a (known) material.
    assert_eq!(scene.materials.len(), 5, "{:?}", scene.materials.iter().map(|m| &m.name).collect::<Vec<_>>());

    // The MTL says "Checker.PNG" and ".\CHECKER.png"; the file is checker.png. Loaded once.
    assert_eq!(scene.textures.len(), 1, "the same file is decoded once");
    assert_eq!(material(&scene, "Checker").base_color_texture, Some(0));
    assert_eq!(material(&scene, "checker_again").base_color_texture, Some(0));
    assert_eq!(material(&scene, "Checker").base_color, Vec4::ONE);
    assert!(!has_warning(&scene, "missing texture"), "{:?}", scene.warnings);

    let red = material(&scene, "red");
    assert_eq!(red.base_color, Vec4::new(0.8, 0.1, 0.05, 0.75), "Kd (trailing comment ignored) and d");
    assert_eq!(red.emissive, Vec3::new(2.0, 1.0, 0.5));
    assert_eq!(red.specular, Vec3::splat(0.5));
    assert_eq!(red.shininess, 64.0);
    assert_eq!(red.base_color_texture, None);
    let grey = material(&scene, "grey");
    assert_eq!(grey.base_color.truncate(), Vec3::splat(0.5), "a one-value Kd is grey");
    assert_eq!(grey.specular, Vec3::ZERO, "illum 1 has no highlight");

    // Faces before any usemtl and with an unknown material use the default material.
    let default = scene.materials.iter().position(|m| m.name == "default").expect("default material");
    assert_eq!(scene.meshes.iter().filter(|m| m.material == default).map(|m| m.triangle_count()).sum::<usize>(), 2);

    // The textured quad has the file's normals and flipped v (OBJ's origin is bottom left).
    let quad = mesh_of_material(&scene, "Checker");
    assert_eq!(quad.triangle_count(), 2);
    assert!(quad.normals.iter().all(|n| *n == Vec3::Y));
    let corner = quad.positions.iter().position(|p| *p == Vec3::new(-1.0, 0.0, -1.0)).unwrap();
    assert_eq!(quad.uvs[corner], glam::Vec2::new(0.0, 1.0));

    // Negative indices -3 -2 -1 refer to the three vertices just above them.
    let red_mesh = mesh_of_material(&scene, "red");
    let mut positions: Vec<[f32; 3]> = red_mesh.positions.iter().map(|p| p.to_array()).collect();
    positions.sort_by(|a, b| a.partial_cmp(b).unwrap());
    assert_eq!(positions, vec![[0.0, 1.0, 0.0], [0.0, 2.0, 0.0], [1.0, 1.0, 0.0]]);
    assert_close(scene.bounds.min, Vec3::new(-1.0, 0.0, -1.0), 0.0);
    assert_close(scene.bounds.max, Vec3::new(1.0, 2.0, 1.0), 0.0);
}

#[test]
fn obj_without_normals_gets_unit_normals_and_unit_scale() {
    let scene = load_obj(&fixture("no_normals.obj"), 1.0).unwrap();
    assert_well_formed(&scene);
    assert_eq!(scene.triangle_count(), 12);
    assert_eq!(scene.materials.len(), 1, "only the default material");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // Smooth normals of a cube point away from the centre, roughly along the diagonals (area weighting over
    // the triangulated quads tilts them a little).
    for mesh in &scene.meshes {
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!(n.dot(p.normalize()) > 0.9, "normal {n} at {p}");
        }
    }

    let scaled = load_obj(&fixture("no_normals.obj"), 0.01).unwrap();
    assert_close(scaled.bounds.min, Vec3::splat(-0.01), 1e-7);
    assert_close(scaled.bounds.max, Vec3::splat(0.01), 1e-7);
    assert!(scaled.camera.is_valid());
    assert!(scaled.camera.z_far < 1.0, "the camera frames the scaled scene: {:?}", scaled.camera);
    assert_eq!(scaled.source, shadowlab_core::SceneSource::File { path: fixture("no_normals.obj"), unit_scale: 0.01 });
    // The camera looks at the scene.
    let to_center = (scaled.bounds.center() - scaled.camera.position).normalize();
    assert!(scaled.camera.forward().dot(to_center) > 0.99);
}

#[test]
fn obj_with_missing_mtl_warns_and_uses_default_material() {
    let scene = load_obj(&fixture("missing_mtl.obj"), 1.0).unwrap();
    assert_well_formed(&scene);
    assert_eq!(scene.triangle_count(), 1);
    assert!(has_warning(&scene, "does_not_exist.mtl"), "{:?}", scene.warnings);
    assert_eq!(scene.materials.len(), 1);
    assert_eq!(scene.materials[0], shadowlab_core::Material::default());
}

#[test]
fn obj_with_missing_texture_warns_and_keeps_colour() {
    let scene = load_obj(&fixture("missing_texture.obj"), 1.0).unwrap();
    assert_well_formed(&scene);
    assert!(has_warning(&scene, "missing texture 'no_such_texture.jpg'"), "{:?}", scene.warnings);
    assert!(scene.textures.is_empty());
    let blue = material(&scene, "blue");
    assert_eq!(blue.base_color_texture, None);
    assert_eq!(blue.base_color, Vec4::new(0.2, 0.4, 0.6, 1.0));
}

/// A broken OBJ gives `LoadError::Obj` naming the file and the problem.
fn expect_obj_error(name: &str, needles: &[&str]) {
    let path = fixture(name);
    let err = match load_obj(&path, 1.0) {
        Ok(scene) => panic!("{name} loaded ({} triangles), expected an error", scene.triangle_count()),
        Err(e) => e,
    };
    assert!(matches!(err, LoadError::Obj { .. }), "{name}: {err:?}");
    let message = err.to_string();
    assert!(message.contains(name), "the message names the file: {message}");
    for needle in needles {
        assert!(message.contains(needle), "{name}: '{needle}' not in: {message}");
    }
}

#[test]
fn broken_obj_files_are_errors_not_panics() {
    expect_obj_error("broken_index.obj", &["face vertex index out of bounds", "line 6", "f 1 2 9"]);
    expect_obj_error("truncated.obj", &["position", "line 6", "v 1.000000 2.0"]);
    expect_obj_error("binary_junk.obj", &["binary"]);
    expect_obj_error("empty.obj", &["empty"]);
    // tobj's index arithmetic overflows on this one (a panic in debug builds); it must come back as an error.
    expect_obj_error("bad_texcoord_index.obj", &["line 7"]);
}

#[test]
fn obj_without_geometry_is_invalid_data() {
    let err = load_obj(&fixture("text_junk.obj"), 1.0).unwrap_err();
    assert!(matches!(err, LoadError::InvalidData { .. }), "{err:?}");
    assert!(err.to_string().contains("text_junk.obj") && err.to_string().contains("no triangles"), "{err}");
}

#[test]
fn missing_files_are_not_found() {
    assert!(matches!(load_obj(&fixture("nope.obj"), 1.0), Err(LoadError::NotFound { .. })));
    assert!(matches!(load_gltf(&fixture("nope.gltf"), 1.0), Err(LoadError::NotFound { .. })));
}

// ---------------------------------------------------------------------------------------------------------
// glTF fixtures

/// lit_quad.gltf and lit_quad.glb hold the same scene (see make_fixtures.py).
fn check_lit_quad(scene: &Scene, unit_scale: f32) {
    assert_well_formed(scene);
    // Two instances of a 2-triangle quad; the LINES primitive is skipped.
    assert_eq!(scene.triangle_count(), 4);
    assert!(has_warning(scene, "only TRIANGLES"), "{:?}", scene.warnings);
    assert_eq!(scene.warnings.len(), 1, "the instanced mesh warns once: {:?}", scene.warnings);

    assert_eq!(scene.materials.len(), 1);
    let m = &scene.materials[0];
    assert_eq!(m.name, "checker_mat");
    assert_eq!(m.base_color, Vec4::new(0.5, 0.25, 1.0, 1.0));
    assert_eq!(m.emissive, Vec3::new(4.0, 2.0, 0.0), "emissive factor x KHR_materials_emissive_strength");
    assert_eq!(m.base_color_texture, Some(0));
    assert_eq!(scene.textures.len(), 1);
    assert_eq!((scene.textures[0].width, scene.textures[0].height), (4, 4));
    assert_eq!(&scene.textures[0].rgba8[0..4], &[255, 0, 0, 255]);

    // The quad node sits under root (translation (1,2,3), scale 2): x in [-1,3], y in [0,4], z = 3; the
    // mirrored copy is at z = 3 + 2 * -2 = -1.
    let s = unit_scale;
    assert_close(scene.bounds.min, Vec3::new(-1.0, 0.0, -1.0) * s, 1e-5);
    assert_close(scene.bounds.max, Vec3::new(3.0, 4.0, 3.0) * s, 1e-5);
    for mesh in &scene.meshes {
        // Transformed normals stay +Z, and every triangle's winding agrees with them, mirrored or not.
        assert!(mesh.normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-5), "{:?}", mesh.normals);
        for tri in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
            assert!((b - a).cross(c - a).dot(Vec3::Z) > 0.0, "mesh {}: winding disagrees with the normal", mesh.name);
        }
        let uv_of = |p: Vec3| mesh.uvs[mesh.positions.iter().position(|q| (*q - p).length() < 1e-5).unwrap()];
        let z = mesh.positions[0].z;
        if (z - 3.0 * s).abs() < 1e-5 {
            // Un-mirrored: local (-1,-1) -> world (-1, 0); its uv is (0, 1).
            assert_eq!(uv_of(Vec3::new(-1.0, 0.0, 3.0) * s), glam::Vec2::new(0.0, 1.0));
        }
    }

    // Point light 0 at local (0,1,0) under root: (1,2,3) + 2 * (0,1,0) = (1,4,3). Light 2 has no range.
    assert_eq!(scene.lights.len(), 3, "{:?}", scene.lights);
    // The spot light loads as a spot: its cone as the file gives it, shining down its node's -Z.
    let spots: Vec<_> = scene.lights.iter().filter_map(|l| l.spot).collect();
    assert_eq!(spots.len(), 1, "{:?}", scene.lights);
    assert!((spots[0].inner_angle - 0.2).abs() < 1e-6 && (spots[0].outer_angle - 0.5).abs() < 1e-6);
    assert_close(spots[0].direction, Vec3::NEG_Z, 1e-5);
    let points: Vec<_> = scene.lights.iter().filter(|l| l.spot.is_none()).copied().collect();
    let key = points[0];
    assert_close(key.position, Vec3::new(1.0, 4.0, 3.0) * s, 1e-5);
    assert_eq!(key.color, Vec3::new(1.0, 0.5, 0.25));
    // 20 cd in the file: photometric, converted to the renderer's W/sr through 683 lm/W.
    assert!((key.intensity - 20.0 / 683.0).abs() < 1e-7, "{}", key.intensity);
    assert!((key.range - 12.0 * s).abs() < 1e-5);
    let lamp = points[1];
    assert_close(lamp.position, Vec3::new(0.0, 5.0, 0.0) * s, 1e-5);
    assert_eq!(lamp.color, Vec3::ONE);
    assert!((lamp.range - scene.bounds.size().length()).abs() < 1e-4, "default range = bounds diagonal");

    // The file's perspective camera at (0,0,10).
    assert_close(scene.camera.position, Vec3::new(0.0, 0.0, 10.0) * s, 1e-5);
    assert!((scene.camera.fov_y - 0.8).abs() < 1e-6);
    assert!((scene.camera.near - 0.1 * s).abs() < 1e-6);
    assert!((scene.camera.z_far - 100.0 * s).abs() < 1e-3);
    assert_close(scene.camera.forward(), Vec3::NEG_Z, 1e-5);
}

#[test]
fn gltf_with_embedded_buffer_lights_and_transforms() {
    let path = fixture("lit_quad.gltf");
    let scene = load_gltf(&path, 1.0).unwrap();
    check_lit_quad(&scene, 1.0);
    assert_eq!(scene.name, "lit_quad");
    assert_eq!(scene.source, shadowlab_core::SceneSource::File { path, unit_scale: 1.0 });
}

#[test]
fn glb_matches_gltf() {
    let scene = load_gltf(&fixture("lit_quad.glb"), 1.0).unwrap();
    check_lit_quad(&scene, 1.0);
}

#[test]
fn gltf_unit_scale_applies_to_geometry_lights_and_camera() {
    let scene = load_gltf(&fixture("lit_quad.glb"), 0.5).unwrap();
    check_lit_quad(&scene, 0.5);
}

#[test]
fn gltf_with_external_buffer_and_image() {
    let scene = load_gltf(&fixture("external.gltf"), 1.0).unwrap();
    assert_well_formed(&scene);
    assert_eq!(scene.triangle_count(), 2);
    assert_eq!(scene.textures.len(), 1);
    assert_eq!(scene.materials[0].base_color_texture, Some(0));
    assert_eq!(scene.materials[0].base_color, Vec4::ONE, "glTF default base colour factor");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert!(scene.lights.is_empty());
}

#[test]
fn gltf_missing_image_warns_and_wrong_case_image_is_found() {
    let scene = load_gltf(&fixture("missing_image.gltf"), 1.0).unwrap();
    assert_well_formed(&scene);
    assert_eq!(scene.triangle_count(), 4);
    assert_eq!(scene.materials.len(), 2);
    assert!(has_warning(&scene, "missing texture 'no_such_image.png'"), "{:?}", scene.warnings);
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    let missing = material(&scene, "missing");
    assert_eq!(missing.base_color_texture, None);
    assert_eq!(missing.base_color, Vec4::new(0.2, 0.4, 0.6, 1.0));
    assert_eq!(material(&scene, "wrong_case").base_color_texture, Some(0), "CHECKER.PNG resolves to checker.png");
}

/// A broken glTF gives `LoadError::Gltf` naming the file and the problem.
fn expect_gltf_error(name: &str, needles: &[&str]) {
    let path = fixture(name);
    let err = match load_gltf(&path, 1.0) {
        Ok(scene) => panic!("{name} loaded ({} triangles), expected an error", scene.triangle_count()),
        Err(e) => e,
    };
    assert!(matches!(err, LoadError::Gltf { .. }), "{name}: {err:?}");
    let message = err.to_string();
    assert!(message.contains(name), "the message names the file: {message}");
    for needle in needles {
        assert!(message.contains(needle), "{name}: '{needle}' not in: {message}");
    }
}

#[test]
fn broken_gltf_files_are_errors_not_panics() {
    expect_gltf_error("missing_bin.gltf", &["does_not_exist.bin", "not found"]);
    expect_gltf_error("truncated.glb", &[]);
    expect_gltf_error("bad_accessor.gltf", &["POSITION", "past the end"]);
    expect_gltf_error("not_gltf.gltf", &[]);
}

#[test]
fn every_prefix_of_a_glb_is_an_error_not_a_panic() {
    let bytes = std::fs::read(fixture("lit_quad.glb")).unwrap();
    let dir = std::env::temp_dir().join(format!("shadowlab-loaders-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("cut.glb");
    for len in (0..bytes.len()).step_by(37) {
        std::fs::write(&path, &bytes[..len]).unwrap();
        assert!(load_gltf(&path, 1.0).is_err(), "a GLB cut at {len} bytes loaded");
    }
    let text = std::fs::read(fixture("lit_quad.gltf")).unwrap();
    let path = dir.join("cut.gltf");
    for len in (0..text.len()).step_by(97) {
        std::fs::write(&path, &text[..len]).unwrap();
        assert!(load_gltf(&path, 1.0).is_err(), "a glTF cut at {len} bytes loaded");
    }
    let obj = std::fs::read(fixture("quad.obj")).unwrap();
    let path = dir.join("cut.obj");
    for len in 0..obj.len() {
        std::fs::write(&path, &obj[..len]).unwrap();
        // A cut OBJ may still be a valid (smaller) OBJ; it only must not panic.
        let _ = load_obj(&path, 1.0);
    }
    std::fs::remove_dir_all(&dir).ok();
}

// ---------------------------------------------------------------------------------------------------------
// Real scenes (../shared/scenes)

#[test]
fn sponza_loads_with_its_textures() {
    let Some(scenes) = scenes_dir("sponza_loads_with_its_textures") else { return };
    let path = scenes.join("dabrovic-sponza/sponza.obj");
    let start = Instant::now();
    let scene = load_obj(&path, 1.0).unwrap();
    let seconds = start.elapsed().as_secs_f64();
    eprintln!(
        "sponza: {} triangles, {} textures, loaded in {seconds:.2} s",
        scene.triangle_count(),
        scene.textures.len()
    );
    assert_well_formed(&scene);
    assert_eq!(scene.triangle_count(), 66_450);
    assert_eq!(scene.materials.len(), 20, "every face has one of the 20 MTL materials");
    // 19 of the 20 materials have a map_Kd, naming 12 distinct files.
    let textured = scene.materials.iter().filter(|m| m.base_color_texture.is_some()).count();
    assert_eq!(textured, 19);
    assert_eq!(scene.textures.len(), 12, "each texture file is loaded once");
    assert!(!has_warning(&scene, "missing texture"), "{:?}", scene.warnings);
    assert!(!has_warning(&scene, "cannot load texture"), "{:?}", scene.warnings);
    assert!(scene.textures.iter().all(|t| t.width <= 2048 && t.height <= 2048 && t.width > 0));
    // Bounds about x[-17.4,17.4] y[-0.9,15.7] z[-7.8,7.8] (SOURCE.md).
    assert_close(scene.bounds.min, Vec3::new(-17.4, -0.9, -7.8), 0.2);
    assert_close(scene.bounds.max, Vec3::new(17.4, 15.7, 7.8), 0.2);
    assert!(scene.lights.is_empty());
    assert!(seconds < 30.0, "sponza took {seconds:.1} s to load");
}

#[test]
fn conference_loads_fast_and_scaled() {
    let Some(scenes) = scenes_dir("conference") else { return };
    let path = scenes.join("conference/conference.obj");
    let start = Instant::now();
    let scene = load_obj(&path, 0.01).unwrap();
    let seconds = start.elapsed().as_secs_f64();
    eprintln!(
        "conference: {} triangles in {} meshes, loaded in {seconds:.2} s",
        scene.triangle_count(),
        scene.meshes.len()
    );
    assert_well_formed(&scene);
    assert_eq!(scene.triangle_count(), 331_179);
    assert!(scene.textures.is_empty());
    // Centimetre-ish units x0.01: about x[-10.2,16.9] y[-0.03,6.5] z[-10.6,6.7].
    assert!(
        (scene.bounds.min.x - -10.2).abs() < 0.05 && (scene.bounds.max.x - 16.9).abs() < 0.05,
        "{:?}",
        scene.bounds
    );
    assert!((scene.bounds.max.y - 6.5).abs() < 0.05, "{:?}", scene.bounds);
    assert!(seconds < 30.0, "conference took {seconds:.1} s to load");
}

#[test]
fn every_cornell_box_obj_loads() {
    let Some(scenes) = scenes_dir("cornell-box") else { return };
    let dir = scenes.join("cornell-box");
    // Triangle counts from cornell-box/SOURCE.md.
    let expected = [
        ("CornellBox-Original.obj", 36),
        ("CornellBox-Mirror.obj", 36),
        ("CornellBox-Sphere.obj", 2188),
        ("CornellBox-Glossy.obj", 1112),
        ("CornellBox-Glossy-Floor.obj", 1112),
        ("CornellBox-Water.obj", 7088),
        ("CornellBox-Empty-CO.obj", 12),
        ("CornellBox-Empty-RG.obj", 12),
        ("CornellBox-Empty-White.obj", 12),
        ("CornellBox-Empty-Squashed.obj", 12),
        ("water.obj", 4900),
    ];
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".obj"))
        .collect();
    files.sort();
    assert_eq!(files.len(), expected.len(), "{files:?}");
    for (name, triangles) in expected {
        let scene = load_obj(&dir.join(name), 1.0).unwrap_or_else(|e| panic!("{e}"));
        assert_well_formed(&scene);
        assert_eq!(scene.triangle_count(), triangles, "{name}");
        assert!(!has_warning(&scene, "cannot parse"), "{name}: {:?}", scene.warnings);
        assert!(scene.bounds.size().max_element() < 3.0, "{name}: {:?}", scene.bounds);
    }

    let original = load_obj(&dir.join("CornellBox-Original.obj"), 1.0).unwrap();
    assert_eq!(material(&original, "light").emissive, Vec3::new(17.0, 12.0, 4.0));
    assert_eq!(material(&original, "leftWall").base_color, Vec4::new(0.63, 0.065, 0.05, 1.0));
    assert!(original.warnings.is_empty(), "{:?}", original.warnings);
    assert_close(original.bounds.min, Vec3::new(-1.0, 0.0, -1.04), 0.05);
    assert_close(original.bounds.max, Vec3::new(1.0, 1.99, 1.0), 0.05);
}

#[test]
fn cornell_box_gltf_loads() {
    let Some(scenes) = scenes_dir("cornell-box-gltf") else { return };
    let path = scenes.join("cornell-box-gltf/cornellBox-2.80-Eevee-gltf.gltf");
    let scene = Scene::load(&path, 1.0).unwrap();
    assert_well_formed(&scene);
    assert_eq!(scene.triangle_count(), 4_410);
    assert_eq!(scene.materials.len(), 13);
    assert_eq!(scene.textures.len(), 2);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(material(&scene, "light.000").emissive, Vec3::ONE);
    assert!(scene.lights.is_empty(), "the file has no KHR_lights_punctual lights");
    // Box spans x,z in [-2,2], y in [0,3] (SOURCE.md).
    assert_close(scene.bounds.min, Vec3::new(-2.0, 0.0, -2.0), 0.1);
    assert_close(scene.bounds.max, Vec3::new(2.0, 3.0, 2.0), 0.1);
}

#[test]
fn corrupted_files_never_panic() {
    // Deterministic byte corruption of the fixtures: loading may fail, but must return.
    let dir = std::env::temp_dir().join(format!("shadowlab-corrupt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(fixture("checker.png"), dir.join("checker.png")).unwrap();
    std::fs::copy(fixture("quad.mtl"), dir.join("quad.mtl")).unwrap();
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for (name, replacements) in [
        ("lit_quad.glb", &b"\x00\xff\x7f\x80 "[..]),
        ("lit_quad.gltf", &b"0-9\"{}[],:e."[..]),
        ("quad.obj", &b"0-9/ \nfv."[..]),
    ] {
        let original = std::fs::read(fixture(name)).unwrap();
        let path = dir.join(name);
        for _ in 0..200 {
            let mut bytes = original.clone();
            for _ in 0..1 + next() % 4 {
                let at = (next() % bytes.len() as u64) as usize;
                bytes[at] = replacements[(next() % replacements.len() as u64) as usize];
            }
            std::fs::write(&path, &bytes).unwrap();
            let _ = Scene::load(&path, 1.0);
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn gltf_lights_beyond_the_limit_are_skipped_with_one_warning() {
    let max = shadowlab_core::scene::layout::MAX_LIGHTS;
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(fixture("lit_quad.gltf")).unwrap()).unwrap();
    let lights = doc["extensions"]["KHR_lights_punctual"]["lights"].as_array_mut().unwrap();
    lights.push(serde_json::json!({"type": "point", "intensity": 1.0, "range": 1.0}));
    let light_index = lights.len() - 1;
    let nodes = doc["nodes"].as_array_mut().unwrap();
    let first = nodes.len();
    for i in 0..max + 5 {
        nodes.push(serde_json::json!({
            "translation": [i as f32 * 1e-3, 0.0, 0.0],
            "extensions": {"KHR_lights_punctual": {"light": light_index}}
        }));
    }
    let roots = doc["scenes"][0]["nodes"].as_array_mut().unwrap();
    roots.extend((first..first + max + 5).map(|i| serde_json::json!(i)));
    // The fixture's buffer is a data URI, so the file can live anywhere.
    let path = std::env::temp_dir().join("shadowlab-many-lights.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let scene = load_gltf(&path, 1.0).unwrap();
    assert_eq!(scene.lights.len(), max);
    assert_eq!(scene.warnings.iter().filter(|w| w.contains("lights: the rest are skipped")).count(), 1);
    // A scene assembled in code cannot bypass the limit through `--lights scene` either.
    let mut too_many = scene.clone();
    too_many.lights.push(too_many.lights[0]);
    let err = shadowlab_core::scene::layout::generate(&shadowlab_core::scene::layout::LightLayout::Scene, &too_many)
        .unwrap_err();
    assert!(err.to_string().contains("100000"), "{err}");
}

#[test]
fn an_accessor_offset_near_the_end_of_memory_is_a_clear_error() {
    // byteOffset + element size overflows usize: the bounds check must say so, not panic (the loader's
    // catch_unwind backstop would report "malformed data (...)" instead).
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(fixture("lit_quad.gltf")).unwrap()).unwrap();
    doc["accessors"][0]["byteOffset"] = serde_json::json!(u64::MAX - 4);
    let path = std::env::temp_dir().join("shadowlab-offset-overflow.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let err = load_gltf(&path, 1.0).unwrap_err().to_string();
    assert!(!err.contains("malformed data ("), "the loader panicked: {err}");
    assert!(err.contains("reads past the end") || err.contains("offset"), "{err}");
}

#[test]
fn files_requiring_unsupported_compression_are_refused_naming_the_extension_first() {
    for ext in ["KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_texture_basisu"] {
        let mut doc: serde_json::Value =
            serde_json::from_slice(&std::fs::read(fixture("lit_quad.gltf")).unwrap()).unwrap();
        doc["extensionsRequired"] = serde_json::json!([ext]);
        doc["extensionsUsed"].as_array_mut().unwrap().push(serde_json::json!(ext));
        // Break the buffers too: the extension must be reported, not the missing data.
        doc["buffers"][0]["uri"] = serde_json::json!("missing.bin");
        let path = std::env::temp_dir().join(format!("shadowlab-{ext}.gltf"));
        std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
        let err = load_gltf(&path, 1.0).unwrap_err().to_string();
        assert!(err.contains(ext) && err.to_lowercase().contains("unsupported extension"), "{ext}: {err}");
        assert!(!err.contains("missing.bin"), "{ext}: the missing data was reported before the extension: {err}");
    }
}

#[test]
fn khr_texture_transform_is_baked_into_the_uvs() {
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(fixture("lit_quad.gltf")).unwrap()).unwrap();
    let plain = load_gltf(&fixture("lit_quad.gltf"), 1.0).unwrap();
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = serde_json::json!({
        "KHR_texture_transform": {"offset": [0.5, 0.25], "scale": [2.0, 3.0], "rotation": std::f32::consts::FRAC_PI_2}
    });
    doc["extensionsUsed"].as_array_mut().unwrap().push(serde_json::json!("KHR_texture_transform"));
    let path = std::env::temp_dir().join("shadowlab-texture-transform.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let moved = load_gltf(&path, 1.0).unwrap();
    let (a, b) = (&plain.meshes[0].uvs, &moved.meshes[0].uvs);
    assert_eq!(a.len(), b.len());
    for (p, q) in a.iter().zip(b) {
        // Scale (2, 3), rotate 90 degrees counter-clockwise (u' = v, v' = -u), then offset.
        let expected = glam::Vec2::new(p.y * 3.0 + 0.5, -p.x * 2.0 + 0.25);
        assert!((*q - expected).length() < 1e-5, "{p} -> {q}, expected {expected}");
    }
}

#[test]
fn a_texture_on_another_texcoord_set_gets_the_second_uv_channel() {
    let fixture = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/fixtures/lit_quad.gltf"));
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(fixture).unwrap()).unwrap();
    // A TEXCOORD_1 of its own: (0.25 + i, 0.75) for the quad's four vertices.
    let uv1: Vec<f32> = (0..4).flat_map(|i| [0.25 + i as f32, 0.75]).collect();
    let bytes: Vec<u8> = uv1.iter().flat_map(|f| f.to_le_bytes()).collect();
    std::fs::write(std::env::temp_dir().join("shadowlab-texcoord1.bin"), &bytes).unwrap();
    let uri = "shadowlab-texcoord1.bin";
    doc["buffers"].as_array_mut().unwrap().push(serde_json::json!({"byteLength": 32, "uri": uri}));
    let buffer = doc["buffers"].as_array().unwrap().len() - 1;
    doc["bufferViews"].as_array_mut().unwrap().push(serde_json::json!({"buffer": buffer, "byteLength": 32}));
    let view = doc["bufferViews"].as_array().unwrap().len() - 1;
    doc["accessors"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"bufferView": view, "componentType": 5126, "count": 4, "type": "VEC2"}));
    let accessor = doc["accessors"].as_array().unwrap().len() - 1;
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_1"] = serde_json::json!(accessor);
    doc["materials"][0]["emissiveTexture"] = serde_json::json!({"index": 0, "texCoord": 1});
    let path = std::env::temp_dir().join("shadowlab-texcoord1.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let scene = shadowlab_core::scene::Scene::load(&path, 1.0).unwrap();
    let m = &scene.materials[0];
    assert_eq!(m.emissive_texture, Some(0), "the texture is used");
    assert!(m.emissive_uv1 && !m.occlusion_uv1, "the emissive texture reads the second channel");
    let quad = scene.meshes.iter().find(|m| !m.uvs1.is_empty()).expect("a mesh with a second UV channel");
    let read: Vec<f32> = quad.uvs1.iter().flat_map(|v| [v.x, v.y]).collect();
    assert_eq!(read, uv1, "TEXCOORD_1 as the file gives it");
    assert!(!scene.warnings.iter().any(|w| w.contains("TEXCOORD_")), "{:?}", scene.warnings);
    // On the base colour's own set: one channel, no second set read.
    doc["materials"][0]["emissiveTexture"] = serde_json::json!({"index": 0});
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let scene = shadowlab_core::scene::Scene::load(&path, 1.0).unwrap();
    assert!(!scene.materials[0].emissive_uv1);
    assert!(scene.meshes.iter().all(|m| m.uvs1.is_empty()));
    // Emissive on set 1 and occlusion on set 2: the third mapping falls back to the base colour's, said so.
    doc["materials"][0]["emissiveTexture"] = serde_json::json!({"index": 0, "texCoord": 1});
    doc["materials"][0]["occlusionTexture"] = serde_json::json!({"index": 0, "texCoord": 2});
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let scene = shadowlab_core::scene::Scene::load(&path, 1.0).unwrap();
    assert!(scene.materials[0].emissive_uv1 && !scene.materials[0].occlusion_uv1);
    assert!(
        scene.warnings.iter().any(|w| w.contains("occlusion texture's mapping (TEXCOORD_2) is a third one")),
        "{:?}",
        scene.warnings
    );
    // An occlusion texture on the base colour's set with a KHR_texture_transform of its own: the second
    // channel, transformed (uv + (0.5, 0.25)).
    doc["materials"][0].as_object_mut().unwrap().remove("emissiveTexture");
    doc["materials"][0]["occlusionTexture"] = serde_json::json!({
        "index": 0,
        "extensions": {"KHR_texture_transform": {"offset": [0.5, 0.25]}}
    });
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let scene = shadowlab_core::scene::Scene::load(&path, 1.0).unwrap();
    assert!(scene.materials[0].occlusion_uv1, "{:?}", scene.warnings);
    let quad = scene.meshes.iter().find(|m| !m.uvs1.is_empty()).expect("the transformed channel");
    for (a, b) in quad.uvs.iter().zip(&quad.uvs1) {
        assert!((*b - *a - glam::Vec2::new(0.5, 0.25)).length() < 1e-6, "{a} -> {b}");
    }
}

/// The triangles of a scene for a CPU BVH.
fn triangles(scene: &shadowlab_core::scene::Scene) -> Vec<[Vec3; 3]> {
    scene
        .meshes
        .iter()
        .flat_map(|m| m.indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| m.positions[t[k] as usize])))
        .collect()
}

#[test]
fn real_interiors_are_first_seen_from_inside_and_the_cornell_box_from_outside() {
    use shadowlab_core::accel::{bvh::Bvh, first_view};
    let Some(scenes) = scenes_dir("real_interiors_are_first_seen_from_inside") else { return };
    for (path, scale) in [("dabrovic-sponza/sponza.obj", 1.0), ("conference/conference.obj", 0.01)] {
        let scene = load_obj(&scenes.join(path), scale).unwrap();
        assert!(scene.camera_is_framing(), "an OBJ brings no camera");
        let bvh = Bvh::build(&triangles(&scene));
        let b = scene.bounds;
        let cam = first_view::first_view(&bvh, &b, scene.camera.fov_y).expect("an enclosed interior");
        let p = cam.position;
        assert!(p.cmpgt(b.min).all() && p.cmplt(b.max).all(), "{path}: {p} inside {b:?}");
        // Seen from where the framing camera would be, above the roof, the model is behind a wall: the
        // interior camera has room around it.
        let (_, clearance) = first_view::probe(&bvh, p, b.size().length());
        assert!(clearance > 0.02 * b.size().length(), "{path}: {clearance} from the nearest surface");
    }
    let open_box = load_obj(&scenes.join("cornell-box/CornellBox-Original.obj"), 1.0).unwrap();
    let bvh = Bvh::build(&triangles(&open_box));
    assert!(first_view::first_view(&bvh, &open_box.bounds, 0.9).is_none(), "an open box is framed from outside");
    // The glTF Cornell box hangs a logo at the middle of its bounds: probed from it, every ray hit at once and the
    // box was seen from inside, facing a wall; it is framed from outside like the OBJ.
    let gltf = Scene::load(&scenes.join("cornell-box-gltf/cornellBox-2.80-Eevee-gltf.gltf"), 1.0).unwrap();
    let bvh = Bvh::build(&triangles(&gltf));
    assert!(first_view::first_view(&bvh, &gltf.bounds, 0.9).is_none(), "the glTF box is framed from outside");
    // The box with water: the pool catches the low rays, so it is enclosed, but its front is open: seen from
    // the front, looking in (it was seen from its back wall, looking out of the opening).
    let water = load_obj(&scenes.join("cornell-box/CornellBox-Water.obj"), 1.0).unwrap();
    let (bvh, b) = (Bvh::build(&triangles(&water)), water.bounds);
    let cam = first_view::first_view(&bvh, &b, 0.9).expect("a room open at the front");
    assert!(cam.position.z > b.max.z && cam.forward().z < -0.9, "{} looking {}", cam.position, cam.forward());
}

/// A glTF as gltfpack writes it (KHR_mesh_quantization): one triangle with `i16` positions and normalised `i8`
/// normals, dequantised by its node's scale and translation; in `dir`, with its buffer embedded as base64.
fn quantized_gltf(dir: &Path, required: &[&str]) -> PathBuf {
    // Positions (0,0,0), (1000,0,0), (0,1000,0) as i16 + 2 bytes of padding each (stride 8); normals (0,0,127)
    // as i8 + 1 byte of padding (stride 4).
    let mut bytes: Vec<u8> = Vec::new();
    for p in [[0i16, 0, 0], [1000, 0, 0], [0, 1000, 0]] {
        for c in p {
            bytes.extend(c.to_le_bytes());
        }
        bytes.extend([0, 0]);
    }
    for _ in 0..3 {
        bytes.extend([0u8, 0, 127, 0]);
    }
    let b64 = {
        const T: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut s = String::new();
        for c in bytes.chunks(3) {
            let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
            for i in 0..4 {
                s.push(if i <= c.len() { T[(n >> (18 - 6 * i) & 63) as usize] as char } else { '=' });
            }
        }
        s
    };
    let required: Vec<String> = required.iter().map(|e| format!("\"{e}\"")).collect();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":[{r}],"extensionsRequired":[{r}],
        "scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"mesh":0,"scale":[0.002,0.002,0.002],"translation":[1,0,0]}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}}}}]}}],
        "accessors":[
          {{"bufferView":0,"componentType":5122,"count":3,"type":"VEC3","min":[0,0,0],"max":[1000,1000,0]}},
          {{"bufferView":1,"componentType":5120,"normalized":true,"count":3,"type":"VEC3"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":24,"byteStride":8}},
                       {{"buffer":0,"byteOffset":24,"byteLength":12,"byteStride":4}}],
        "buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{b64}"}}]}}"#,
        r = required.join(",")
    );
    let path = dir.join("quantized.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

#[test]
fn gltf_with_khr_mesh_quantization_loads_dequantised() {
    let dir = std::env::temp_dir().join("shadowlab-quantized");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = load_gltf(&quantized_gltf(&dir, &["KHR_mesh_quantization"]), 1.0).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let mesh = &scene.meshes[0];
    // 1000 * 0.002 + 1 = 3: the node's transform dequantises the integers.
    assert_close(mesh.positions[0], Vec3::new(1.0, 0.0, 0.0), 1e-5);
    assert_close(mesh.positions[1], Vec3::new(3.0, 0.0, 0.0), 1e-5);
    assert_close(mesh.positions[2], Vec3::new(1.0, 2.0, 0.0), 1e-5);
    assert_close(mesh.normals[0], Vec3::Z, 1e-5);
}

#[test]
fn gltf_requiring_basisu_is_refused_by_name_before_validation() {
    let dir = std::env::temp_dir().join("shadowlab-basisu");
    std::fs::create_dir_all(&dir).unwrap();
    // KHR_texture_basisu as exporters write it: the texture's image only in the extension, no core `source`;
    // validated first, the file would be refused as "textures[0].source: Missing data".
    let path = quantized_gltf(&dir, &["KHR_texture_basisu"]);
    let text = std::fs::read_to_string(&path).unwrap().replace(
        r#""scene":0,"#,
        r#""images":[{"uri":"t.ktx2"}],"textures":[{"extensions":{"KHR_texture_basisu":{"source":0}}}],"scene":0,"#,
    );
    std::fs::write(&path, text).unwrap();
    let err = load_gltf(&path, 1.0).unwrap_err().to_string();
    assert!(err.contains("unsupported extension KHR_texture_basisu"), "{err}");
}

#[test]
fn gltf_requiring_draco_is_refused_by_name() {
    let dir = std::env::temp_dir().join("shadowlab-draco");
    std::fs::create_dir_all(&dir).unwrap();
    // Draco files carry attribute accessors without a bufferView: validation alone would say "Missing data".
    let path = quantized_gltf(&dir, &["KHR_draco_mesh_compression"]);
    let text =
        std::fs::read_to_string(&path).unwrap().replace(r#""bufferView":0,"#, "").replace(r#""bufferView":1,"#, "");
    std::fs::write(&path, text).unwrap();
    let err = load_gltf(&path, 1.0).unwrap_err().to_string();
    assert!(err.contains("KHR_draco_mesh_compression"), "{err}");
}
