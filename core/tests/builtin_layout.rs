//! Tests of the built-in scenes (`scene::builtin`) and the light layouts (`scene::layout`).
//!
//! Geometry checks use a small CPU ray caster: every built-in object is a closed solid, so a point is inside
//! geometry exactly when a ray from it crosses the surface an odd number of times.

use glam::{Vec3, Vec4Swizzles};
use shadowlab_core::scene::layout::{self, LightLayout, MAX_LIGHTS};
use shadowlab_core::scene::{attenuation, builtin};
use shadowlab_core::{Aabb, Camera, LayoutError, LoadError, Mesh, PointLight, Scene, SceneSource};

// -------------------------------------------------------------------------------------------------------------
// Helpers
// -------------------------------------------------------------------------------------------------------------

fn build(name: &str) -> Scene {
    builtin::build(name).unwrap_or_else(|e| panic!("built-in scene '{name}' failed to build: {e}"))
}

/// Every triangle of the scene as three world-space corners.
fn triangles(scene: &Scene) -> Vec<[Vec3; 3]> {
    scene.meshes.iter().flat_map(|m| m.indices.chunks_exact(3).map(|t| corners(m, t))).collect()
}

/// The corners of triangle `t` (three indices) of `mesh`.
fn corners(mesh: &Mesh, t: &[u32]) -> [Vec3; 3] {
    [0, 1, 2].map(|k| mesh.positions[t[k] as usize])
}

/// Möller-Trumbore: the distance along `dir` at which the ray hits the triangle (either side), if it does.
fn ray_triangle(origin: Vec3, dir: Vec3, [a, b, c]: [Vec3; 3]) -> Option<f32> {
    let (e1, e2) = (b - a, c - a);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let s = origin - a;
    let u = s.dot(p) / det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) / det;
    (t > 1e-6).then_some(t)
}

fn crossings(tris: &[[Vec3; 3]], origin: Vec3, dir: Vec3) -> usize {
    tris.iter().filter(|t| ray_triangle(origin, dir, **t).is_some()).count()
}

fn first_hit(tris: &[[Vec3; 3]], origin: Vec3, dir: Vec3) -> Option<f32> {
    tris.iter().filter_map(|t| ray_triangle(origin, dir, *t)).min_by(f32::total_cmp)
}

/// True when `p` is inside some solid: odd crossings along two unrelated directions (two, so a ray that
/// happens to graze an edge cannot fool the test).
fn inside_geometry(tris: &[[Vec3; 3]], p: Vec3) -> bool {
    let dirs = [Vec3::new(0.1234, 0.9871, 0.0456).normalize(), Vec3::new(-0.577, 0.3141, 0.7543).normalize()];
    let odd: Vec<bool> = dirs.iter().map(|&d| crossings(tris, p, d) % 2 == 1).collect();
    assert_eq!(odd[0], odd[1], "inside/outside test disagrees at {p}: a ray grazed an edge");
    odd[0]
}

/// Radiance (luminance) at sampled surface points from all lights, ignoring shadows: the renderer's
/// `albedo / pi * color * intensity * attenuation * cos`. Returns the sorted values of the lit samples and the
/// fraction of samples that are lit. Deterministic (an LCG picks area-weighted triangles).
fn unshadowed_radiance(scene: &Scene, lights: &[PointLight], samples: usize) -> (Vec<f32>, f32) {
    let mut tris = Vec::new();
    for m in &scene.meshes {
        let albedo = scene.materials[m.material].base_color.xyz();
        for t in m.indices.chunks_exact(3) {
            let p = corners(m, t);
            let area = (p[1] - p[0]).cross(p[2] - p[0]).length() * 0.5;
            tris.push((p, albedo, area));
        }
    }
    let total: f32 = tris.iter().map(|t| t.2).sum();
    let mut cdf = Vec::with_capacity(tris.len());
    let mut acc = 0.0;
    for t in &tris {
        acc += t.2 / total;
        cdf.push(acc);
    }
    let mut state = 12345u64;
    let mut rand = || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut lit = Vec::new();
    for _ in 0..samples {
        let pick = cdf.partition_point(|&c| c < rand()).min(tris.len() - 1);
        let ([a, b, c], albedo, _) = tris[pick];
        let (mut u, mut v) = (rand(), rand());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let p = a + (b - a) * u + (c - a) * v;
        let n = (b - a).cross(c - a).normalize();
        let mut radiance = Vec3::ZERO;
        for l in lights {
            let to_light = l.position - p;
            let d = to_light.length();
            let cos = n.dot(to_light / d).max(0.0);
            radiance += albedo / std::f32::consts::PI * l.color * l.intensity * attenuation(d, l.range) * cos;
        }
        let luminance = radiance.dot(Vec3::new(0.2126, 0.7152, 0.0722));
        if luminance > 1e-3 {
            lit.push(luminance);
        }
    }
    lit.sort_by(f32::total_cmp);
    let fraction = lit.len() as f32 / samples as f32;
    (lit, fraction)
}

fn percentile(sorted: &[f32], q: f32) -> f32 {
    sorted[((sorted.len() - 1) as f32 * q).round() as usize]
}

fn inside_bounds(bounds: &Aabb, p: Vec3) -> bool {
    p.cmpge(bounds.min).all() && p.cmple(bounds.max).all()
}

/// A scene with Dabrovic Sponza's name and bounds (in metres) but no geometry: enough for the paper layout.
fn sponza_stand_in() -> Scene {
    let bounds = Aabb { min: Vec3::new(-17.40, -0.91, -7.80), max: Vec3::new(17.42, 15.65, 7.80) };
    Scene {
        name: "sponza".into(),
        source: SceneSource::File { path: "sponza.obj".into(), unit_scale: 1.0 },
        meshes: Vec::new(),
        materials: Vec::new(),
        textures: Vec::new(),
        lights: Vec::new(),
        directional: vec![],
        camera: Camera::framing(&bounds),
        bounds,
        warnings: Vec::new(),
    }
}

fn parse_ok(spec: &str) -> LightLayout {
    layout::parse(spec).unwrap_or_else(|e| panic!("'{spec}' should parse: {e}"))
}

fn assert_invalid(spec: &str) {
    match layout::parse(spec) {
        Err(LayoutError::Invalid { spec: s, reason }) => {
            assert_eq!(s, spec);
            assert!(!reason.is_empty());
        }
        other => panic!("'{spec}' should be invalid, got {other:?}"),
    }
}

// -------------------------------------------------------------------------------------------------------------
// Built-in scenes
// -------------------------------------------------------------------------------------------------------------

#[test]
fn every_builtin_builds_with_its_name_and_source() {
    for &name in builtin::NAMES {
        let scene = build(name);
        assert_eq!(scene.name, name);
        assert_eq!(scene.source, SceneSource::Builtin(name.to_string()));
        assert!(scene.warnings.is_empty(), "{name}: {:?}", scene.warnings);
        assert!(!scene.bounds.is_empty());
        assert!(scene.textures.is_empty());
        for mesh in &scene.meshes {
            assert!(mesh.material < scene.materials.len());
            assert_eq!(mesh.normals.len(), mesh.positions.len());
            assert_eq!(mesh.uvs.len(), mesh.positions.len());
            assert!(mesh.positions.iter().all(|p| p.is_finite()));
            assert!(mesh.uvs.iter().all(|uv| uv.is_finite()));
        }
        println!(
            "{name}: {} triangles, {} meshes, {} lights",
            scene.triangle_count(),
            scene.meshes.len(),
            scene.lights.len()
        );
    }
}

#[test]
fn unknown_builtin_is_an_error_listing_the_choices() {
    match builtin::build("sponza") {
        Err(LoadError::UnknownBuiltin { name, choices }) => {
            assert_eq!(name, "sponza");
            assert_eq!(choices, "cornell, arcade, restaurant");
        }
        other => panic!("expected UnknownBuiltin, got {other:?}"),
    }
    assert!(builtin::paper_lights("sponza").is_none());
}

#[test]
fn builtin_scenes_have_distinct_materials() {
    for &name in builtin::NAMES {
        let scene = build(name);
        assert!(scene.materials.len() >= 4, "{name}: only {} materials", scene.materials.len());
        for m in &scene.materials {
            assert!(m.base_color.is_finite() && m.base_color.min_element() >= 0.0 && m.base_color.max_element() <= 1.0);
            assert!(m.specular.is_finite() && m.shininess > 0.0);
        }
    }
    let cornell = build("cornell");
    let color = |mesh: &str| {
        let m = cornell.meshes.iter().find(|m| m.name == mesh).unwrap();
        cornell.materials[m.material].base_color
    };
    assert!(color("left wall").x > 0.5 && color("left wall").y < 0.2, "left wall should be red");
    assert!(color("right wall").y > color("right wall").x, "right wall should be green");
}

#[test]
fn triangle_counts_stay_moderate() {
    for &name in builtin::NAMES {
        let count = build(name).triangle_count();
        assert!((1_000..50_000).contains(&count), "{name}: {count} triangles");
    }
}

#[test]
fn light_counts_and_ranges_follow_the_paper() {
    let cornell = build("cornell");
    assert_eq!(cornell.lights.len(), 32);
    assert!(cornell.lights.iter().all(|l| (0.6..=1.6).contains(&l.range)));
    // Random ranges, spread over the interval rather than all alike.
    let ranges = cornell.lights.iter().map(|l| l.range);
    let (lo, hi) = ranges.fold((f32::INFINITY, 0.0f32), |(lo, hi), r| (lo.min(r), hi.max(r)));
    assert!(hi - lo > 0.5, "ranges span only [{lo}, {hi}]");

    let arcade = build("arcade");
    assert_eq!(arcade.lights.len(), 80);
    assert!(arcade.lights.iter().all(|l| l.range == 7.0));
    assert_eq!(arcade.camera.z_far, 30.0);

    let restaurant = build("restaurant");
    assert_eq!(restaurant.lights.len(), 14);
    assert!(restaurant.lights.iter().all(|l| l.range == 2.0));
}

#[test]
fn lights_are_valid_inside_bounds_and_outside_every_solid() {
    for &name in builtin::NAMES {
        let scene = build(name);
        let tris = triangles(&scene);
        for (i, l) in scene.lights.iter().enumerate() {
            assert!(l.is_valid(), "{name}: light {i} invalid: {l:?}");
            assert!(l.intensity > 0.0);
            assert!(inside_bounds(&scene.bounds, l.position), "{name}: light {i} at {} outside bounds", l.position);
            assert!(!inside_geometry(&tris, l.position), "{name}: light {i} at {} is inside a solid", l.position);
        }
    }
}

#[test]
fn cornell_lights_are_in_the_room_and_clear_of_the_objects() {
    let scene = build("cornell");
    let tris = triangles(&scene);
    for l in &scene.lights {
        let p = l.position;
        assert!(p.x.abs() < 1.0 && p.z.abs() < 1.0 && p.y > 0.0 && p.y < 2.0, "light at {p} not in the room");
        // Nothing within 5 cm in any of the axis directions.
        for dir in [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z] {
            if let Some(t) = first_hit(&tris, p, dir) {
                assert!(t > 0.05, "light at {p} is {t} m from a surface");
            }
        }
    }
}

#[test]
fn meshes_are_closed_outward_and_consistently_wound() {
    for &name in builtin::NAMES {
        let scene = build(name);
        for mesh in &scene.meshes {
            let mut volume = 0.0f64;
            for t in mesh.indices.chunks_exact(3) {
                let [a, b, c] = corners(mesh, t);
                let geometric = (b - a).cross(c - a);
                let shading: Vec3 = t.iter().map(|&i| mesh.normals[i as usize]).sum();
                assert!(
                    geometric.dot(shading) > 0.0,
                    "{name}/{}: a triangle's winding disagrees with its normals",
                    mesh.name
                );
                volume += a.dot(b.cross(c)) as f64 / 6.0;
            }
            // Closed solids with outward normals enclose a positive volume (divergence theorem).
            assert!(volume > 0.0, "{name}/{}: signed volume {volume} (normals point inwards?)", mesh.name);
        }
    }
}

#[test]
fn flat_box_faces_have_flat_normals() {
    // The Cornell walls are boxes: every vertex normal of a wall is one of the six axis directions.
    let scene = build("cornell");
    let wall = scene.meshes.iter().find(|m| m.name == "left wall").unwrap();
    for n in &wall.normals {
        assert!((n.abs().max_element() - 1.0).abs() < 1e-5, "box normal {n} is not axis aligned");
    }
}

#[test]
fn cameras_are_valid_and_look_at_the_scene() {
    for &name in builtin::NAMES {
        let scene = build(name);
        let cam = scene.camera;
        assert!(cam.is_valid(), "{name}: {cam:?}");
        // The bounds' centre is in view.
        let clip = cam.clip_from_world(16.0 / 9.0) * scene.bounds.center().extend(1.0);
        let ndc = clip.truncate() / clip.w;
        assert!(clip.w > 0.0 && ndc.x.abs() < 1.0 && ndc.y.abs() < 1.0, "{name}: bounds centre not in view: {ndc}");
        assert!((0.0..1.0).contains(&ndc.z), "{name}: bounds centre outside the depth range: {ndc}");
        // Looking straight ahead hits geometry within the far plane, not a wall in the camera's face.
        let hit = first_hit(&triangles(&scene), cam.position, cam.forward())
            .unwrap_or_else(|| panic!("{name}: the camera looks into the void"));
        assert!(hit > 1.0 && hit < cam.z_far, "{name}: first surface ahead at {hit} m");
    }
    // Inside the arcade and the restaurant; in front of the Cornell box's open side.
    assert!(inside_bounds(&build("arcade").bounds, build("arcade").camera.position));
    assert!(inside_bounds(&build("restaurant").bounds, build("restaurant").camera.position));
    let cornell = build("cornell");
    assert!(cornell.camera.position.z > cornell.bounds.max.z);
}

#[test]
fn builtin_lights_give_a_reasonable_exposure() {
    // Without shadows, lit surfaces should land in the range where ACES at exposure 1 shows detail.
    let stats: Vec<(&str, f32, f32)> = builtin::NAMES
        .iter()
        .map(|&name| {
            let scene = build(name);
            let (lit, fraction) = unshadowed_radiance(&scene, &scene.lights, 4000);
            let (p10, p50, p90) = (percentile(&lit, 0.1), percentile(&lit, 0.5), percentile(&lit, 0.9));
            println!("{name}: lit {:.0}%, radiance p10 {p10:.3} p50 {p50:.3} p90 {p90:.3}", fraction * 100.0);
            (name, p50, p90)
        })
        .collect();
    // The restaurant's 2 m lights leave much of its 8 x 6 m room dim (as in the paper), hence the low floor
    // for the median; the brightly lit surfaces (90th percentile) must be well exposed everywhere.
    for (name, p50, p90) in stats {
        assert!((0.1..2.0).contains(&p50), "{name}: median lit radiance {p50}");
        assert!((0.5..4.0).contains(&p90), "{name}: 90th percentile radiance {p90}");
    }
}

#[test]
fn builtins_are_deterministic_and_paper_lights_match() {
    for &name in builtin::NAMES {
        let (a, b) = (build(name), build(name));
        assert_eq!(a.lights, b.lights);
        assert_eq!(a.triangle_count(), b.triangle_count());
        assert_eq!(a.meshes[0].positions, b.meshes[0].positions);
        assert_eq!(builtin::paper_lights(name).unwrap(), a.lights);
        assert_eq!(layout::generate(&LightLayout::Paper, &a).unwrap(), a.lights);
    }
}

// -------------------------------------------------------------------------------------------------------------
// Layout specs
// -------------------------------------------------------------------------------------------------------------

#[test]
fn specs_parse_to_the_expected_layouts() {
    assert_eq!(parse_ok("random:1024:1.5"), LightLayout::Random { count: 1024, range: 1.5, seed: 1 });
    assert_eq!(parse_ok("random:1024:1.5:7"), LightLayout::Random { count: 1024, range: 1.5, seed: 7 });
    assert_eq!(parse_ok("above:256:4"), LightLayout::Above { count: 256, range: 4.0, seed: 1 });
    assert_eq!(parse_ok("Above:256:4:9"), LightLayout::Above { count: 256, range: 4.0, seed: 9 });
    // What `sweep --param lights=N` varies: the count of the layouts that have a free one.
    assert_eq!(parse_ok("above:256:4:9").with_count(8), Some(LightLayout::Above { count: 8, range: 4.0, seed: 9 }));
    assert_eq!(parse_ok("random:64:2:3").with_count(5), Some(LightLayout::Random { count: 5, range: 2.0, seed: 3 }));
    assert_eq!(parse_ok("grid:4x4:2").with_count(8), None);
    assert_eq!(parse_ok("paper").with_count(8), None);
    assert_eq!(parse_ok("circles:10:8:7"), LightLayout::Circles { circles: 10, per_circle: 8, range: 7.0 });
    assert_eq!(parse_ok("grid:8x4:2"), LightLayout::Grid { nx: 8, ny: 4, range: 2.0 });
    assert_eq!(parse_ok("grid:8X4:2"), LightLayout::Grid { nx: 8, ny: 4, range: 2.0 });
    assert_eq!(parse_ok("paper"), LightLayout::Paper);
    assert_eq!(parse_ok("scene"), LightLayout::Scene);
    assert_eq!(parse_ok("  Random:5:0.25 "), LightLayout::Random { count: 5, range: 0.25, seed: 1 });
    assert_eq!(
        "circles:2:3:1e1".parse::<LightLayout>().unwrap(),
        LightLayout::Circles { circles: 2, per_circle: 3, range: 10.0 }
    );
}

#[test]
fn specs_round_trip_through_display() {
    for spec in [
        "random:1024:1.5",
        "random:3:0.1:18446744073709551615",
        "circles:10:8:7",
        "grid:8x8:2",
        "grid:1x100:0.333",
        "paper",
        "scene",
        "random:0:1",
        "above:256:4:3",
    ] {
        let layout = parse_ok(spec);
        let text = layout.to_string();
        assert_eq!(parse_ok(&text), layout, "'{spec}' -> '{text}'");
    }
    assert_eq!(parse_ok("random:1024:1.5").to_string(), "random:1024:1.5:1");
    assert_eq!(parse_ok("grid:8x8:2").to_string(), "grid:8x8:2");
}

#[test]
fn bad_specs_are_invalid() {
    for spec in [
        "",
        "   ",
        "spiral:3:2",
        "random",
        "random:abc",
        "random:abc:1",
        "random:10",
        "random:10:-1",
        "random:10:0",
        "random:10:nan",
        "random:10:NaN",
        "random:10:inf",
        "random:10:-inf",
        "random:10:1e39",
        "random:10:x",
        "random:-5:1",
        "random:+5:1",
        "random:1.5:1",
        "random:10:1:-3",
        "random:10:1:seed",
        "random:10:1:2:3",
        "random:10::",
        "circles:1:2",
        "circles:1:2:3:4",
        "circles:a:2:3",
        "circles:1:2:0",
        "grid:8:2",
        "grid:8x:2",
        "grid:x8:2",
        "grid:axb:2",
        "grid:8x8x8:2",
        "grid:8x8",
        "grid:8x8:nan",
        "paper:1",
        "scene:",
    ] {
        assert_invalid(spec);
    }
}

#[test]
fn too_many_lights_are_rejected_and_zero_is_allowed() {
    assert_eq!(
        layout::parse("random:100001:1"),
        Err(LayoutError::TooManyLights { spec: "random:100001:1".into(), count: 100_001, max: MAX_LIGHTS })
    );
    assert!(layout::parse("random:100000:1").is_ok());
    assert!(matches!(layout::parse("circles:1000:1000:1"), Err(LayoutError::TooManyLights { count: 1_000_000, .. })));
    assert!(matches!(layout::parse("grid:400x400:1"), Err(LayoutError::TooManyLights { count: 160_000, .. })));
    // Numbers too big for any integer type are too many lights, not garbage.
    assert!(matches!(layout::parse("random:99999999999999999999999:1"), Err(LayoutError::TooManyLights { .. })));
    assert!(matches!(layout::parse("circles:99999999999:99999999999:1"), Err(LayoutError::TooManyLights { .. })));

    let scene = build("cornell");
    for spec in ["random:0:1", "circles:0:8:7", "circles:3:0:7", "grid:0x3:2"] {
        let lights = layout::generate(&parse_ok(spec), &scene).unwrap();
        assert!(lights.is_empty(), "{spec}");
    }
}

#[test]
fn hand_made_layouts_are_validated_by_generate() {
    let scene = build("cornell");
    let nan = LightLayout::Random { count: 4, range: f32::NAN, seed: 1 };
    assert!(matches!(layout::generate(&nan, &scene), Err(LayoutError::Invalid { .. })));
    let huge = LightLayout::Grid { nx: usize::MAX, ny: 2, range: 1.0 };
    assert!(matches!(layout::generate(&huge, &scene), Err(LayoutError::TooManyLights { .. })));
    assert!(huge.light_count().is_none());
    assert_eq!(LightLayout::Circles { circles: 10, per_circle: 8, range: 7.0 }.light_count(), Some(80));
}

#[test]
fn error_messages_are_helpful() {
    let message = layout::parse("random:10:nan").unwrap_err().to_string();
    assert!(message.contains("random:10:nan") && message.contains("L_ATT"), "{message}");
    let message = layout::parse("spiral").unwrap_err().to_string();
    assert!(message.contains("spiral") && message.contains("circles"), "{message}");
    let message = layout::parse("random:100001:1").unwrap_err().to_string();
    assert!(message.contains("100001") && message.contains("100000"), "{message}");
}

// -------------------------------------------------------------------------------------------------------------
// Layout generation
// -------------------------------------------------------------------------------------------------------------

#[test]
fn generation_is_deterministic() {
    for &name in builtin::NAMES {
        let scene = build(name);
        for spec in ["random:500:1.5", "random:500:1.5:9", "circles:10:8:7", "grid:8x8:2", "paper", "scene"] {
            let layout = parse_ok(spec);
            assert_eq!(
                layout::generate(&layout, &scene).unwrap(),
                layout::generate(&layout, &scene).unwrap(),
                "{spec}"
            );
        }
    }
    let scene = build("arcade");
    let a = layout::generate(&parse_ok("random:50:1.5:1"), &scene).unwrap();
    let b = layout::generate(&parse_ok("random:50:1.5:2"), &scene).unwrap();
    assert_ne!(a, b, "different seeds should give different lights");
    assert_eq!(a, layout::generate(&parse_ok("random:50:1.5"), &scene).unwrap(), "the default seed is 1");
}

#[test]
fn random_lights_fill_the_shrunk_bounds() {
    for &name in builtin::NAMES {
        let scene = build(name);
        let lights = layout::generate(&parse_ok("random:2000:1.5:3"), &scene).unwrap();
        assert_eq!(lights.len(), 2000);
        let inset = scene.bounds.size() * 0.05;
        let shrunk = Aabb { min: scene.bounds.min + inset, max: scene.bounds.max - inset };
        for l in &lights {
            assert!(l.is_valid());
            assert_eq!(l.range, 1.5);
            assert!(inside_bounds(&shrunk, l.position), "{name}: {} outside {shrunk:?}", l.position);
        }
        // Spread out: the lights' own bounds cover most of the shrunk box.
        let spread = Aabb::from_points(lights.iter().map(|l| l.position)).size();
        assert!(spread.cmpge(shrunk.size() * 0.9).all(), "{name}: {spread} vs {}", shrunk.size());
        // Warm colours: red is the largest channel.
        assert!(lights.iter().all(|l| l.color.x == 1.0 && l.color.max_element() == 1.0 && l.color.z < 1.0));
    }
}

#[test]
fn above_lights_lie_over_the_footprint_from_the_top_to_half_the_height_higher() {
    for &name in builtin::NAMES {
        let scene = build(name);
        let lights = layout::generate(&parse_ok("above:500:4:2"), &scene).unwrap();
        assert_eq!(lights.len(), 500);
        let (b, size) = (scene.bounds, scene.bounds.size());
        let depth = (0.5 * size.y).max(0.1 * size.x.max(size.z));
        for l in &lights {
            assert!(l.is_valid() && l.range == 4.0);
            let p = l.position;
            assert!(p.y >= b.max.y - 1e-4 && p.y <= b.max.y + depth, "{name}: {p} not above the top {}", b.max.y);
            let inset = size * 0.05;
            assert!(p.x >= b.min.x + inset.x - 1e-4 && p.x <= b.max.x - inset.x + 1e-4, "{name}: {p}");
            assert!(p.z >= b.min.z + inset.z - 1e-4 && p.z <= b.max.z - inset.z + 1e-4, "{name}: {p}");
        }
        // Spread over the slab: the lowest light near the top, the highest near the slab's top.
        let (lo, hi) =
            lights.iter().fold((f32::MAX, f32::MIN), |(lo, hi), l| (lo.min(l.position.y), hi.max(l.position.y)));
        assert!(lo < b.max.y + 0.05 * depth && hi > b.max.y + 0.85 * depth, "{name}: heights {lo}..{hi}");
        // Seeded: the same spec gives the same lights, another seed others.
        assert_eq!(layout::generate(&parse_ok("above:500:4:2"), &scene).unwrap(), lights);
        assert_ne!(layout::generate(&parse_ok("above:500:4:3"), &scene).unwrap(), lights);
    }
}

#[test]
fn grid_lights_form_a_grid_at_a_third_of_the_height() {
    let scene = build("restaurant");
    let lights = layout::generate(&parse_ok("grid:8x5:2"), &scene).unwrap();
    assert_eq!(lights.len(), 40);
    let height = scene.bounds.min.y + scene.bounds.size().y / 3.0;
    let mut xs: Vec<f32> = lights.iter().map(|l| l.position.x).collect();
    let mut zs: Vec<f32> = lights.iter().map(|l| l.position.z).collect();
    xs.sort_by(f32::total_cmp);
    xs.dedup();
    zs.sort_by(f32::total_cmp);
    zs.dedup();
    assert_eq!((xs.len(), zs.len()), (8, 5));
    for l in &lights {
        assert!((l.position.y - height).abs() < 1e-4);
        assert!(inside_bounds(&scene.bounds, l.position));
        assert!(l.position.x > scene.bounds.min.x && l.position.x < scene.bounds.max.x);
        assert_eq!(l.range, 2.0);
    }
}

#[test]
fn circle_lights_form_circles_in_two_rows() {
    let scene = build("arcade");
    let lights = layout::generate(&parse_ok("circles:10:8:7"), &scene).unwrap();
    assert_eq!(lights.len(), 80);
    let c = scene.bounds.center();
    let below = lights.iter().filter(|l| l.position.z < c.z).count();
    assert_eq!(below, 40, "two rows of five circles");
    for group in lights.chunks(8) {
        let center = group.iter().map(|l| l.position).sum::<Vec3>() / 8.0;
        let radii: Vec<f32> = group.iter().map(|l| l.position.distance(center)).collect();
        assert!(radii.iter().all(|r| (r - radii[0]).abs() < 1e-3 && *r > 0.0), "not a circle: {radii:?}");
    }
    assert!(lights.iter().all(|l| inside_bounds(&scene.bounds, l.position) && l.range == 7.0));
    // An odd number of circles: the extra one goes to the first row.
    assert_eq!(layout::generate(&parse_ok("circles:3:4:2"), &scene).unwrap().len(), 12);
    // Rows follow the longest horizontal axis: turn the arcade's bounds by 90 degrees.
    let mut turned = scene.clone();
    turned.bounds = Aabb {
        min: Vec3::new(scene.bounds.min.z, scene.bounds.min.y, scene.bounds.min.x),
        max: Vec3::new(scene.bounds.max.z, scene.bounds.max.y, scene.bounds.max.x),
    };
    let turned_lights = layout::generate(&parse_ok("circles:10:8:7"), &turned).unwrap();
    let z_spread = Aabb::from_points(turned_lights.iter().map(|l| l.position)).size();
    assert!(z_spread.z > z_spread.x);
}

#[test]
fn sponza_paper_layout_has_80_lights_in_the_side_arcades() {
    let scene = sponza_stand_in();
    let lights = layout::generate(&LightLayout::Paper, &scene).unwrap();
    assert_eq!(lights.len(), 80);
    for l in &lights {
        assert_eq!(l.range, 7.0);
        assert!(l.is_valid() && l.intensity > 0.0);
        assert!(inside_bounds(&scene.bounds, l.position));
        // Ground floor (floor at y = 0.09), in the side arcades between the columns (z = ±2.85) and the
        // inner walls (z = ±7.2), clear of the corner piers at x = ±11.1.
        assert!((1.0..2.5).contains(&l.position.y), "{}", l.position);
        assert!((3.5..6.8).contains(&l.position.z.abs()), "{}", l.position);
        assert!(l.position.x.abs() < 10.4, "{}", l.position);
    }
    // Five circles of eight on each side.
    assert_eq!(lights.iter().filter(|l| l.position.z > 0.0).count(), 40);
    // Any capitalisation of the name, and a scene loaded in centimetres gets scaled lights.
    let mut big = sponza_stand_in();
    big.name = "Dabrovic-SPONZA".into();
    big.bounds = Aabb { min: scene.bounds.min * 100.0, max: scene.bounds.max * 100.0 };
    let scaled = layout::generate(&LightLayout::Paper, &big).unwrap();
    assert_eq!(scaled.len(), 80);
    assert!((scaled[0].range - 700.0).abs() < 1.0);
    assert!(scaled[0].position.distance(lights[0].position * 100.0) < 1.0);
}

#[test]
fn paper_layout_is_refused_for_other_scenes() {
    let mut scene = sponza_stand_in();
    scene.name = "conference".into();
    match layout::generate(&LightLayout::Paper, &scene) {
        Err(LayoutError::NoPaperLayout { scene, known }) => {
            assert_eq!(scene, "conference");
            assert!(known.contains("cornell") && known.contains("sponza"));
        }
        other => panic!("expected NoPaperLayout, got {other:?}"),
    }
}

#[test]
fn scene_layout_keeps_the_scene_lights() {
    let scene = build("restaurant");
    assert_eq!(layout::generate(&LightLayout::Scene, &scene).unwrap(), scene.lights);
    let empty = sponza_stand_in();
    assert!(layout::generate(&LightLayout::Scene, &empty).unwrap().is_empty());
}

#[test]
fn generated_intensities_are_reasonable() {
    for r in [0.1f32, 0.5, 1.0, 2.0, 7.0, 50.0] {
        let i = layout::default_intensity_for_range(r);
        assert!(i.is_finite() && i > 0.0, "range {r}: {i}");
    }
    // Denser layouts get dimmer lights.
    assert!(layout::layout_intensity(1.5, 1, 100.0) < layout::layout_intensity(1.5, 1, 0.1));
    // The generated layouts light the arcade to a sensible level (no shadows).
    let scene = build("arcade");
    for spec in ["random:1024:1.5", "random:64:7", "circles:10:8:7", "grid:8x8:4", "random:20000:1"] {
        let lights = layout::generate(&parse_ok(spec), &scene).unwrap();
        let (lit, fraction) = unshadowed_radiance(&scene, &lights, 1500);
        let p50 = percentile(&lit, 0.5);
        println!("arcade {spec}: lit {:.0}%, p50 {p50:.3} p90 {:.3}", fraction * 100.0, percentile(&lit, 0.9));
        assert!((0.05..4.0).contains(&p50), "{spec}: median lit radiance {p50}");
    }
}
