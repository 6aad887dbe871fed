//! Image correctness of the reference with analytic expectations, on the software adapter:
//! a ground plane, a square occluder and point lights, compared pixel by pixel with a CPU ray cast.

mod common;

use common::analytic::{self, cast, Hit, AMBIENT, H, W};
use common::*;
use glam::Vec3;
use shadowlab_core::scene::{Camera, PointLight, Scene};
use shadowlab_core::technique::ParamValue;
use shadowlab_core::{AutoExposure, RenderSettings, Renderer, ToneMap};

fn settings() -> RenderSettings {
    RenderSettings {
        width: W,
        height: H,
        ambient: Vec3::splat(AMBIENT),
        background: Vec3::new(0.0, 0.0, 1.0),
        tonemap: ToneMap::Linear,
        ..Default::default()
    }
}

/// The reference's cube-map resolution and batch memory (MiB).
fn maps(shadow_res: i64, atlas_mib: i64) -> [(&'static str, ParamValue); 2] {
    [("shadow_res", ParamValue::Int(shadow_res)), ("atlas_mib", ParamValue::Int(atlas_mib))]
}

/// The reference is exact up to shadow-map texels: 6 cm around each shadow boundary is left out.
const MARGIN: f32 = 0.06;

fn expected(camera: &Camera, lights: &[PointLight], px: u32, py: u32) -> Option<[f32; 4]> {
    analytic::expected(camera, lights, px, py, MARGIN, &|p| p)
}

fn ground_visibility(p: Vec3, light: &PointLight) -> Option<bool> {
    analytic::ground_visibility(p, light, MARGIN)
}

/// Compare every pixel that has an expectation; relative tolerance plus a small absolute one (f16 target,
/// 8-bit sRGB albedo). Writes actual/expected/difference PNGs on failure.
fn assert_matches_analytic(name: &str, camera: &Camera, lights: &[PointLight], hdr: &[[f32; 4]]) -> (usize, usize) {
    let mut bad = vec![false; (W * H) as usize];
    let mut exp = vec![None; (W * H) as usize];
    let (mut checked, mut wrong) = (0, 0);
    let mut first_wrong = None;
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            exp[i] = expected(camera, lights, x, y);
            if let Some(e) = exp[i] {
                checked += 1;
                let a = hdr[i];
                let ok = (0..3).all(|c| (a[c] - e[c]).abs() <= 0.02 * e[c].abs() + 2e-3);
                if !ok {
                    wrong += 1;
                    bad[i] = true;
                    first_wrong.get_or_insert((x, y, a, e));
                }
            }
        }
    }
    if wrong > 0 {
        let dir = write_failure_images(name, W, H, hdr, &exp, &bad);
        panic!(
            "{name}: {wrong} of {checked} pixels differ from the analytic answer, first {first_wrong:?}; images in {}",
            dir.display()
        );
    }
    assert!(checked > (W * H / 2) as usize, "{name}: too few pixels checked ({checked})");
    (checked, wrong)
}

#[test]
fn umbra_is_unlit_and_lit_pixels_follow_the_attenuation() {
    let scene = plane_and_occluder();
    let light = white_light(Vec3::new(-1.5, 3.0, 0.2), 20.0, 8.0);
    let r = Shot::direct(&scene, &[light], settings(), "reference").params(&maps(256, 128)).render_keeping();
    assert_matches_analytic("umbra", &scene.camera, &[light], &r.hdr);
    // The test must have seen both umbra and lit ground pixels.
    let (mut umbra, mut lit) = (0, 0);
    for y in 0..H {
        for x in 0..W {
            if let Hit::Ground(p) = cast(&scene.camera, x, y) {
                match ground_visibility(p, &light) {
                    Some(false) => umbra += 1,
                    Some(true) => lit += 1,
                    None => {}
                }
            }
        }
    }
    assert!(umbra > 150 && lit > 2000, "umbra {umbra}, lit {lit}");
    assert_eq!(r.report.counts.technique.lights_visible, 1);
    assert_eq!(r.report.counts.technique.shadow_maps, 1);
}

#[test]
fn two_lights_add_up() {
    let scene = plane_and_occluder();
    let a = white_light(Vec3::new(-1.0, 2.5, 0.0), 12.0, 6.0);
    let b = PointLight::new(Vec3::new(1.5, 2.0, 1.0), Vec3::new(1.0, 0.5, 0.25), 15.0, 5.0);
    let ra = Shot::direct(&scene, &[a], settings(), "reference").params(&maps(256, 128)).render_keeping();
    let rb = Shot::direct(&scene, &[b], settings(), "reference").params(&maps(256, 128)).render_keeping();
    let rab = Shot::direct(&scene, &[a, b], settings(), "reference").params(&maps(256, 128)).render_keeping();
    assert_matches_analytic("two-lights", &scene.camera, &[a, b], &rab.hdr);
    let mut compared = 0;
    for i in 0..(W * H) as usize {
        for c in 0..3 {
            let sum = ra.hdr[i][c] + rb.hdr[i][c] - if i_is_background(&ra.hdr[i]) { 0.0 } else { AMBIENT * ALBEDO };
            let both = rab.hdr[i][c];
            if i_is_background(&ra.hdr[i]) {
                continue;
            }
            compared += 1;
            assert!((both - sum).abs() <= 0.01 * sum.abs() + 2e-3, "pixel {i} channel {c}: {both} vs {sum}");
        }
    }
    assert!(compared > 1000);
}

fn i_is_background(p: &[f32; 4]) -> bool {
    p[2] == 1.0 && p[0] == 0.0 && p[1] == 0.0
}

#[test]
fn a_light_out_of_range_contributes_nothing() {
    let scene = plane_and_occluder();
    // In view, but 3 m above the plate with a 2.5 m range: it reaches no surface.
    let far_light = white_light(Vec3::new(0.0, 4.0, 0.5), 1000.0, 2.5);
    let r = Shot::direct(&scene, &[far_light], settings(), "reference").params(&maps(256, 128)).render_keeping();
    let none = Shot::direct(&scene, &[], settings(), "reference").params(&maps(256, 128)).render_keeping();
    assert_eq!(r.report.counts.technique.lights_visible, 1, "the light's sphere is in view");
    assert_eq!(r.hdr, none.hdr, "a light beyond its range must not change a pixel");
    // Its range sphere is outside the view: culled before any shadow map.
    let behind = white_light(Vec3::new(0.0, 6.0, 30.0), 1000.0, 2.0);
    let r = Shot::direct(&scene, &[behind], settings(), "reference").params(&maps(256, 128)).render_keeping();
    assert_eq!(r.report.counts.technique.lights_visible, 0);
    assert_eq!(r.report.counts.technique.shadow_maps, 0);
    assert_eq!(r.hdr, none.hdr);
}

#[test]
fn zero_lights_render_ambient_only() {
    let scene = plane_and_occluder();
    let r = Shot::direct(&scene, &[], settings(), "reference").params(&maps(256, 128)).render_keeping();
    assert_matches_analytic("ambient-only", &scene.camera, &[], &r.hdr);
    assert_eq!(r.report.counts.technique.shadow_maps, 0);
    assert_eq!(r.report.counts.lights_total, 0);
    // The G-buffer is timed: its pass in the timestamps, or its step ("gbuffer + ambient") when
    // `SHADOWLAB_TIMING=auto` fell back to the steps (timestamps covering under half a step, as on a loaded
    // machine: this test once failed so while other runs shared the CPU).
    assert!(r.report.passes.iter().any(|p| p.name.starts_with("gbuffer")), "{:?}", r.report.passes);
    assert!(r.report.steps.iter().any(|p| p.name.starts_with("gbuffer")), "{:?}", r.report.steps);
}

#[test]
fn a_thousand_lights_render_in_bounded_batches_with_the_same_result() {
    let scene = plane_and_occluder();
    // 1,000 dim lights above the plane, a grid with jitter, all in view.
    let lights: Vec<PointLight> = (0..1000)
        .map(|i| {
            let x = (i % 40) as f32 / 39.0 * 8.0 - 4.0;
            let z = (i / 40) as f32 / 24.0 * 6.0 - 3.0;
            white_light(Vec3::new(x, 1.5 + 0.5 * ((i * 7) % 5) as f32 / 5.0, z), 0.5, 2.0)
        })
        .collect();
    // 1 MiB per batch at 32 texels per face: 42 cube maps per batch.
    let small = Shot::direct(&scene, &lights, settings(), "reference").params(&maps(32, 1)).render_keeping();
    let big = Shot::direct(&scene, &lights, settings(), "reference").params(&maps(32, 64)).render_keeping();
    let c = &small.report.counts.technique;
    assert_eq!(c.lights_visible, 1000);
    assert_eq!(c.shadow_maps, 1000);
    assert!(c.batches >= 20, "a 1 MiB budget must split 1,000 cube maps into many batches, got {}", c.batches);
    assert!(big.report.counts.technique.batches < c.batches);
    // Batching changes memory, never the picture (up to f16 rounding of the accumulation order).
    let mut max_diff = 0f32;
    for (a, b) in small.hdr.iter().zip(&big.hdr) {
        for ch in 0..3 {
            max_diff = max_diff.max((a[ch] - b[ch]).abs() / (1e-3 + b[ch].abs()));
        }
    }
    assert!(max_diff < 0.01, "batched and unbatched images differ by {max_diff}");
    // And the lights did light the plane.
    let center = small.hdr[(H / 2 * W + W / 2) as usize][0];
    assert!(center > AMBIENT * ALBEDO * 1.5, "centre radiance {center}");
}

#[test]
fn the_gl_backend_renders_the_same_analytic_image() {
    // llvmpipe through EGL, the second software path (scripts/setup installs it).
    let gl = shadowlab_core::GpuContext::headless_on(wgpu::Backends::GL)
        .unwrap_or_else(|e| panic!("no GL adapter ({e}): install libegl1 libegl-mesa0 libgl1-mesa-dri"));
    assert_eq!(gl.adapter_info.backend, wgpu::Backend::Gl);
    let scene = plane_and_occluder();
    let light = white_light(Vec3::new(-1.5, 3.0, 0.2), 20.0, 8.0);
    let r = Shot::direct(&scene, &[light], settings(), "reference").params(&maps(256, 128)).on(gl).render_keeping();
    assert_matches_analytic("gl-umbra", &scene.camera, &[light], &r.hdr);
    assert_eq!(r.report.counts.technique.shadow_maps, 1);
}

/// A depth texture cleared to `value`, read back as the renderer reads its G-buffer depth.
fn cleared_depth_reads_back(gpu: &shadowlab_core::GpuContext, value: f32) -> Vec<f32> {
    let (w, h) = (37u32, 21u32);
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Depth32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = texture.create_view(&Default::default());
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &view,
            depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(value), store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }),
        ..Default::default()
    });
    gpu.queue.submit([encoder.finish()]);
    let bytes = shadowlab_core::gpu::readback::read_texture(gpu, &texture, w, h, 4).unwrap();
    assert_eq!(bytes.len(), (w * h * 4) as usize);
    bytes.chunks_exact(4).map(|d| f32::from_le_bytes([d[0], d[1], d[2], d[3]])).collect()
}

#[test]
fn depth_reads_back_on_gl_which_cannot_copy_depth_to_a_buffer() {
    // GL lacks DEPTH_TEXTURE_AND_BUFFER_COPIES: the readback draws the depth into a colour target instead (it
    // panicked in wgpu's validation before, so every comparison on GL did).
    let gl = shadowlab_core::GpuContext::headless_on(wgpu::Backends::GL)
        .unwrap_or_else(|e| panic!("no GL adapter ({e}): install libegl1 libegl-mesa0 libgl1-mesa-dri"));
    assert_eq!(gl.adapter_info.backend, wgpu::Backend::Gl);
    for ctx in [&gl, &gpu()] {
        let depths = cleared_depth_reads_back(ctx, 0.25);
        assert!(depths.iter().all(|&d| d == 0.25), "{:?}: {:?}", ctx.adapter_info.backend, &depths[..4]);
    }
}

#[test]
fn a_gltf_emissive_texture_modulates_the_emission_instead_of_a_flat_glow() {
    // lit_quad.gltf's material emits (4, 2, 0); with its checker as the emissive texture the quad shows the
    // checker in emission, without it a flat colour.
    let fixture = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/fixtures/lit_quad.gltf"));
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(fixture).unwrap()).unwrap();
    let render_emission = |doc: &serde_json::Value, name: &str| -> (Scene, Vec<[f32; 4]>) {
        let path = std::env::temp_dir().join(name);
        std::fs::write(&path, serde_json::to_vec(doc).unwrap()).unwrap();
        let scene = Scene::load(&path, 1.0).unwrap();
        let s = RenderSettings { width: 64, height: 64, ambient: Vec3::ZERO, ..settings() };
        let (hdr, _) = Shot::direct(&scene, &[], s, "unshadowed").render();
        (scene, hdr)
    };
    let distinct = |img: &[[f32; 4]]| {
        let mut colours: Vec<[u32; 3]> =
            img.iter().filter(|p| p[0] > 0.01).map(|p| [0, 1, 2].map(|c| (p[c] * 64.0) as u32)).collect();
        colours.sort();
        colours.dedup();
        colours.len()
    };
    let (_, flat) = render_emission(&doc, "shadowlab-emissive-flat.gltf");
    doc["materials"][0]["emissiveTexture"] = serde_json::json!({"index": 0});
    let (scene, textured) = render_emission(&doc, "shadowlab-emissive-textured.gltf");
    assert_eq!(scene.materials[0].emissive_texture, Some(0));
    assert!(flat.iter().any(|p| p[0] > 0.01), "the quad is not in view");
    assert!(distinct(&flat) <= 2, "flat emission should be one colour, got {}", distinct(&flat));
    assert!(distinct(&textured) >= 2, "the emissive texture's pattern is missing");
    // Where the checker is dark in a channel the emission is dimmed there.
    let dimmed = textured
        .iter()
        .zip(&flat)
        .filter(|(t, f)| f[0] > 0.01 && (0..3).any(|c| f[c] > 0.05 && t[c] < 0.7 * f[c]))
        .count();
    assert!(dimmed > 0, "no texel dimmed the emission");
}

#[test]
fn a_gltf_occlusion_texture_darkens_the_ambient_term_only() {
    let fixture = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/fixtures/lit_quad.gltf"));
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(fixture).unwrap()).unwrap();
    // No emission, so the image is the ambient term alone.
    doc["materials"][0]["emissiveFactor"] = serde_json::json!([0.0, 0.0, 0.0]);
    let render = |doc: &serde_json::Value, name: &str| -> Vec<[f32; 4]> {
        let path = std::env::temp_dir().join(name);
        std::fs::write(&path, serde_json::to_vec(doc).unwrap()).unwrap();
        let scene = Scene::load(&path, 1.0).unwrap();
        let s = RenderSettings { width: 64, height: 64, ambient: Vec3::splat(1.0), ..settings() };
        Shot::direct(&scene, &[], s, "unshadowed").render().0
    };
    let plain = render(&doc, "shadowlab-ao-none.gltf");
    // A 2x2 occlusion texture, red 255 (unoccluded) in one column and 0 (fully occluded) in the other.
    let ao = image::RgbaImage::from_fn(2, 2, |x, _| {
        if x == 0 {
            image::Rgba([255, 0, 0, 255])
        } else {
            image::Rgba([0, 0, 0, 255])
        }
    });
    ao.save(std::env::temp_dir().join("shadowlab-ao.png")).unwrap();
    doc["images"].as_array_mut().unwrap().push(serde_json::json!({"uri": "shadowlab-ao.png"}));
    doc["textures"].as_array_mut().unwrap().push(serde_json::json!({"source": 1}));
    doc["materials"][0]["occlusionTexture"] = serde_json::json!({"index": 1, "strength": 1.0});
    let occluded = render(&doc, "shadowlab-ao.gltf");
    // Brightness as the sum of the channels (the checker's texels differ in hue).
    let sum = |p: &[f32; 4]| p[0] + p[1] + p[2];
    let lit: Vec<(f32, f32)> =
        plain.iter().zip(&occluded).filter(|(p, _)| sum(p) > 0.01).map(|(p, q)| (sum(p), sum(q))).collect();
    assert!(!lit.is_empty(), "the quad is not in view");
    // Unoccluded in one column, occluded in the other.
    assert!(lit.iter().any(|(p, q)| (p - q).abs() < 0.02 * p), "nowhere unoccluded");
    assert!(lit.iter().any(|(p, q)| *q < 0.5 * p), "nowhere occluded");
    assert!(lit.iter().all(|(p, q)| *q <= p * 1.001), "occlusion brightened something");
}

#[test]
fn gltf_alpha_modes_cut_out_only_masked_materials() {
    // lit_quad.gltf's base colour made fully transparent: OPAQUE ignores alpha (the quad is drawn), MASK cuts it
    // out below alphaCutoff, BLEND is drawn opaque with a warning.
    let fixture = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/fixtures/lit_quad.gltf"));
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(fixture).unwrap()).unwrap();
    let drawn = |doc: &serde_json::Value, name: &str| -> (Scene, usize) {
        let path = std::env::temp_dir().join(name);
        std::fs::write(&path, serde_json::to_vec(doc).unwrap()).unwrap();
        let scene = Scene::load(&path, 1.0).unwrap();
        let s = RenderSettings { width: 48, height: 48, background: Vec3::ZERO, ..settings() };
        let (img, _) = Shot::direct(&scene, &[], s, "unshadowed").render();
        (scene, img.iter().filter(|p| p[0] + p[1] + p[2] > 1e-4).count())
    };
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = serde_json::json!([1.0, 1.0, 1.0, 0.2]);
    doc["materials"][0]["emissiveFactor"] = serde_json::json!([1.0, 1.0, 1.0]);
    let (_, opaque) = drawn(&doc, "shadowlab-alpha-opaque.gltf");
    assert!(opaque > 0, "OPAQUE must ignore alpha");
    doc["materials"][0]["alphaMode"] = serde_json::json!("MASK");
    let (scene, masked) = drawn(&doc, "shadowlab-alpha-mask.gltf");
    assert_eq!(scene.materials[0].alpha_cutoff, 0.5, "the default alphaCutoff");
    assert_eq!(masked, 0, "alpha 0.2 under the default cutoff 0.5 is cut out");
    doc["materials"][0]["alphaCutoff"] = serde_json::json!(0.1);
    let (_, low) = drawn(&doc, "shadowlab-alpha-mask-low.gltf");
    assert_eq!(low, opaque, "alpha 0.2 over a cutoff of 0.1 is kept");
    doc["materials"][0]["alphaMode"] = serde_json::json!("BLEND");
    let (scene, blend) = drawn(&doc, "shadowlab-alpha-blend.gltf");
    assert_eq!(blend, opaque, "BLEND is drawn opaque");
    assert!(scene.warnings.iter().any(|w| w.contains("BLEND")), "{:?}", scene.warnings);
}

/// The plane-and-occluder scene with the plate's material cut out on one half (a texture whose left two
/// columns are transparent) when `cutoff` > 0.
fn half_cut_plate(cutoff: f32) -> Scene {
    let mut scene = plane_and_occluder();
    let texture = shadowlab_core::scene::TextureImage {
        name: "half".into(),
        width: 4,
        height: 1,
        rgba8: [[255, 255, 255, 0], [255, 255, 255, 0], [255, 255, 255, 255], [255, 255, 255, 255]].concat(),
    };
    scene.textures.push(texture);
    let mut cut = scene.materials[0].clone();
    cut.name = "cut".into();
    cut.base_color_texture = Some(scene.textures.len() - 1);
    cut.alpha_cutoff = cutoff;
    scene.materials.push(cut);
    let plate = scene.meshes.iter_mut().find(|m| m.name == "plate").unwrap();
    plate.material = 1;
    scene.finalize(std::path::Path::new("test")).unwrap();
    scene
}

#[test]
fn cut_out_casters_cast_cut_out_shadows() {
    // The reference's cube maps and the ray tracer both alpha-test the plate, so the ground under its cut half
    // is lit; with the cutoff off it is shadowed.
    // On GL too: its one cut-out mask is a texture array of one layer, which GL took for a plain 2D texture and
    // the ray tracer's `D2Array` view sampled nothing (`scene_bvh::array_layers`).
    let gl = shadowlab_core::GpuContext::headless_on(wgpu::Backends::GL)
        .unwrap_or_else(|e| panic!("no GL adapter ({e}): install libegl1 libegl-mesa0 libgl1-mesa-dri"));
    for (technique, on_gl) in [("reference", false), ("raytraced", false), ("raytraced", true)] {
        let render = |cutoff: f32| -> (Vec<[f32; 4]>, Scene) {
            let scene = half_cut_plate(cutoff);
            let light = [white_light(Vec3::new(0.0, 4.0, 0.0), 10.0, 20.0)];
            let shot = Shot::direct(&scene, &light, settings(), technique);
            let shot = if on_gl { shot.on(gl.clone()) } else { shot };
            (shot.render().0, scene)
        };
        let technique = if on_gl { format!("{technique} on GL") } else { technique.to_string() };
        let (opaque, _) = render(0.0);
        let (cut, scene) = render(0.5);
        // The ground under the plate's transparent half: lit only when the caster is cut out.
        let probe = Vec3::new(-0.35, 0.0, 0.0) * 4.0 / 3.0; // under x = -0.26 of the plate (its cut half)
        let (px, py) = project(&scene.camera, probe);
        let (o, c) = (opaque[py * W as usize + px][1], cut[py * W as usize + px][1]);
        assert!(c > o * 1.5 + 1e-3, "{technique}, under the cut half: {c} (cut out) vs {o} (opaque caster)");
        // Under the opaque half both shadow.
        let probe = Vec3::new(0.3, 0.0, 0.0) * 4.0 / 3.0;
        let (px, py) = project(&scene.camera, probe);
        let (o, c) = (opaque[py * W as usize + px][1], cut[py * W as usize + px][1]);
        assert!((c - o).abs() <= 0.05 * o.max(1e-3) + 1e-4, "{technique}, under the opaque half: {c} vs {o}");
    }
}

#[test]
fn the_cpu_traversal_alpha_tests_cut_outs() {
    // The CPU twin of the tracers' alpha test (what VPL tracing and fuzzy's probe use): a ray down through the
    // plate's cut half passes, through its opaque half it stops; with the cutoff off both stop.
    use shadowlab_core::accel::bvh::{occluded_cpu_filtered, Bvh};
    use shadowlab_core::accel::scene_bvh::{cutout_alpha, BvhCutouts};
    use shadowlab_core::scene::chunks::ChunkedGeometry;
    for (cutoff, cut_half_blocks) in [(0.5, false), (0.0, true)] {
        let scene = half_cut_plate(cutoff);
        let geometry = ChunkedGeometry::build(&scene);
        let bvh = Bvh::from_geometry(&geometry);
        let alpha = cutout_alpha(&scene);
        assert_eq!(alpha.iter().filter(|a| a.is_some()).count(), usize::from(cutoff > 0.0));
        let cutouts = BvhCutouts::build(&bvh, &geometry, &alpha, 256);
        let down = |x: f32| {
            occluded_cpu_filtered(&bvh, Vec3::new(x, 4.0, 0.0), Vec3::NEG_Y, 3.9, &|t, u, v| !cutouts.cut_out(t, u, v))
        };
        assert_eq!(down(-0.3), cut_half_blocks, "cutoff {cutoff}: through the cut half");
        assert!(down(0.3), "cutoff {cutoff}: through the opaque half");
    }
}

/// The pixel a world point lands on.
fn project(camera: &shadowlab_core::scene::Camera, p: Vec3) -> (usize, usize) {
    let clip = camera.clip_from_world(W as f32 / H as f32) * p.extend(1.0);
    let ndc = clip.truncate() / clip.w;
    (((ndc.x * 0.5 + 0.5) * W as f32) as usize, ((0.5 - ndc.y * 0.5) * H as f32) as usize)
}

#[test]
fn auto_exposure_meters_the_log_average_and_cancels_light_scale() {
    // Auto-exposure maps the log-average luminance of the geometry pixels to 0.18: the scale it meters equals
    // the CPU's log-average of the same HDR image, and a scene ten times brighter (light and ambient) gives
    // (nearly) the same displayed geometry, where a fixed exposure does not.
    let scene = plane_and_occluder();
    let render = |k: f32, auto: bool| {
        let s = RenderSettings {
            auto_exposure: if auto { AutoExposure::Meter } else { AutoExposure::Off },
            tonemap: ToneMap::Aces,
            ambient: Vec3::splat(AMBIENT * k),
            ..settings()
        };
        let light = [white_light(Vec3::new(0.5, 3.0, 0.5), 2.0 * k, 20.0)];
        let Rendered { renderer, hdr, .. } = Shot::direct(&scene, &light, s, "reference").render_keeping();
        let mask = renderer.read_geometry_mask().unwrap();
        let metered = renderer.auto_exposure().unwrap();
        (renderer.read_output().unwrap(), hdr, mask, metered)
    };
    let (dim, hdr, mask, metered) = render(1.0, true);
    let (scale, average) = metered.expect("auto exposure is on");
    let (sum, n) = hdr.iter().zip(&mask).filter(|(_, &g)| g).fold((0.0f64, 0usize), |(s, n), (c, _)| {
        let y = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        (s + (1e-4 + y.max(0.0) as f64).ln(), n + 1)
    });
    assert!(n > 100, "the view shows geometry");
    let expected = (sum / n as f64).exp() as f32;
    assert!((average - expected).abs() <= 1e-3 * expected, "metered {average}, CPU {expected}");
    assert!((scale - 0.18 / expected).abs() <= 1e-3 * scale, "scale {scale}");
    // Mean difference of the green channel over the geometry pixels, in 8-bit steps.
    let diff = |a: &image::RgbaImage, b: &image::RgbaImage| {
        let d: i32 = a
            .pixels()
            .zip(b.pixels())
            .zip(&mask)
            .filter(|(_, &g)| g)
            .map(|((p, q), _)| (p[1] as i32 - q[1] as i32).abs())
            .sum();
        d as f32 / n as f32
    };
    let (bright, ..) = render(10.0, true);
    let auto_difference = diff(&dim, &bright);
    let (fixed_dim, ..) = render(1.0, false);
    let (fixed_bright, _, _, none) = render(10.0, false);
    assert_eq!(none, None, "off: nothing metered");
    let fixed_difference = diff(&fixed_dim, &fixed_bright);
    assert!(auto_difference < 1.0, "x10 brighter with auto-exposure: mean difference {auto_difference} steps");
    assert!(fixed_difference > 20.0, "x10 brighter with a fixed exposure: {fixed_difference} steps");
}

#[test]
fn auto_exposure_of_an_empty_view_stays_one() {
    // No geometry pixel: nothing to meter, the scale goes back to 1 (no division by zero, no NaN exposure),
    // after a view of the scene metered another one.
    let scene = plane_and_occluder();
    let gpu = gpu();
    let mut renderer =
        Renderer::new(&gpu, &scene, RenderSettings { auto_exposure: AutoExposure::Meter, ..settings() }).unwrap();
    let mut t = renderer.create_technique("reference").unwrap();
    let lights = [white_light(Vec3::new(0.0, 3.0, 0.0), 5.0, 20.0)];
    renderer.render_frame(t.as_mut(), &scene.camera, &lights, &mut |_, _| {}).unwrap();
    let scene_scale = renderer.auto_exposure().unwrap().unwrap().0;
    assert!(scene_scale.is_finite() && (scene_scale - 1.0).abs() > 0.05, "the scene metered a scale: {scene_scale}");
    let c = scene.camera;
    let camera = shadowlab_core::scene::Camera::look_at(c.position, c.position + Vec3::Y, c.fov_y, c.near, c.z_far);
    renderer.render_frame(t.as_mut(), &camera, &[], &mut |_, _| {}).unwrap();
    assert!(renderer.read_geometry_mask().unwrap().iter().all(|g| !g), "the view shows no geometry");
    assert_eq!(renderer.auto_exposure().unwrap().map(|e| e.0), Some(1.0));
}

#[test]
fn an_emissive_texture_on_the_second_uv_channel_is_sampled_with_it() {
    // The plate's emissive texture is [black, white]; its first UV channel points at the black texel's centre
    // and its second at the white one's. The emission follows the channel the material names.
    let render = |uv1: bool| -> (Vec<[f32; 4]>, Scene) {
        let mut scene = plane_and_occluder();
        scene.textures.push(shadowlab_core::scene::TextureImage {
            name: "black-white".into(),
            width: 2,
            height: 1,
            rgba8: [[0, 0, 0, 255], [255, 255, 255, 255]].concat(),
        });
        let mut glow = scene.materials[0].clone();
        glow.name = "glow".into();
        glow.emissive = Vec3::ONE;
        glow.emissive_texture = Some(scene.textures.len() - 1);
        glow.emissive_uv1 = uv1;
        scene.materials.push(glow);
        let plate = scene.meshes.iter_mut().find(|m| m.name == "plate").unwrap();
        plate.material = 1;
        let n = plate.positions.len();
        plate.uvs = vec![glam::Vec2::new(0.25, 0.5); n];
        plate.uvs1 = vec![glam::Vec2::new(0.75, 0.5); n];
        scene.finalize(std::path::Path::new("test")).unwrap();
        (Shot::direct(&scene, &[], settings(), "reference").render().0, scene)
    };
    for (uv1, lo, hi) in [(false, 0.0, 0.1), (true, 0.9, 1.2)] {
        let (hdr, scene) = render(uv1);
        let (px, py) = project(&scene.camera, PLATE_CENTER);
        let g = hdr[py * W as usize + px][1];
        assert!((lo..=hi).contains(&g), "second channel {uv1}: emission {g} at the plate's centre");
    }
}

#[test]
fn unchanged_overlays_are_drawn_from_the_last_upload() {
    // The app draws the same overlays every UI frame: they are tessellated and uploaded once, and drawn the same.
    use shadowlab_core::technique::Overlay;
    let scene = plane_and_occluder();
    let gpu = gpu();
    let mut renderer = Renderer::new(&gpu, &scene, settings()).unwrap();
    let mut t = renderer.create_technique("reference").unwrap();
    let lights = [white_light(Vec3::new(0.0, 3.0, 0.0), 5.0, 20.0)];
    renderer.render_frame(t.as_mut(), &scene.camera, &lights, &mut |_, _| {}).unwrap();
    let a = vec![
        Overlay::Sphere { center: Vec3::ZERO, radius: 1.0, color: [1.0, 0.0, 0.0, 1.0] },
        Overlay::Point { position: Vec3::new(0.0, 1.0, 0.0), color: [0.0, 1.0, 0.0, 1.0], radius_px: 6.0 },
    ];
    let draw = |renderer: &mut Renderer, primitives: &[Overlay]| {
        renderer.tonemap().unwrap();
        renderer.draw_overlays(&scene.camera, primitives, false).unwrap();
        renderer.read_output().unwrap()
    };
    let first = draw(&mut renderer, &a);
    let second = draw(&mut renderer, &a.clone());
    assert_eq!(renderer.overlay_uploads(), 1, "equal primitives are not uploaded again");
    assert_eq!(first, second, "and are drawn the same");
    let mut b = a.clone();
    b[1] = Overlay::Point { position: Vec3::new(0.5, 1.0, 0.0), color: [0.0, 1.0, 0.0, 1.0], radius_px: 6.0 };
    let third = draw(&mut renderer, &b);
    assert_eq!(renderer.overlay_uploads(), 2, "changed primitives are");
    assert_ne!(third, second, "and drawn where they now are");
}
