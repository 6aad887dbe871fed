//! Work counts on a tiny scene, against values computed by hand: a 20 x 20 floor that fills a 32 x 24 view
//! seen from above, two lights over it whose ranges cover every pixel and a third far outside the view.
//! Every pixel holds geometry (768 shaded pixels) and faces both lights, so each technique's per-pixel work is
//! known exactly.

mod common;

use common::*;
use glam::{Vec3, Vec4};
use shadowlab_core::scene::{Aabb, Camera, Material, Scene, SceneSource};
use shadowlab_core::technique::ParamValue;
use shadowlab_core::vpl::VplSettings;

const W: u32 = 32;
const H: u32 = 24;
const PIXELS: f64 = (W * H) as f64;
const RES: i64 = 64;

fn floor() -> Scene {
    let grey = Material { name: "grey".into(), base_color: Vec4::new(0.5, 0.5, 0.5, 1.0), ..Default::default() };
    let mut scene = Scene {
        name: "floor".into(),
        source: SceneSource::Builtin("test".into()),
        meshes: vec![quad("floor", Vec3::ZERO, 20.0, 0)],
        materials: vec![grey],
        textures: vec![],
        lights: vec![],
        directional: vec![],
        // From 5 above, tilted a little (a camera looking straight down has no up): the view spans about
        // +-3 units, well inside the floor.
        camera: Camera::look_at(Vec3::new(0.0, 5.0, 0.3), Vec3::ZERO, 60f32.to_radians(), 0.1, 50.0),
        bounds: Aabb::EMPTY,
        warnings: vec![],
    };
    scene.finalize(std::path::Path::new("test")).unwrap();
    scene
}

fn lights() -> Vec<shadowlab_core::scene::PointLight> {
    vec![
        white_light(Vec3::new(-0.5, 3.0, 0.0), 1.0, 50.0),
        white_light(Vec3::new(0.5, 3.0, 0.0), 1.0, 50.0),
        // Far outside the view frustum and its range: culled before shading.
        white_light(Vec3::new(500.0, 3.0, 0.0), 1.0, 5.0),
    ]
}

fn work(
    key: &str,
    params: &[(&str, ParamValue)],
) -> (std::collections::BTreeMap<String, f64>, shadowlab_core::FrameReport) {
    let scene = floor();
    let mut r = renderer(&scene, linear_settings(W, H));
    let camera = scene.camera;
    let (_, report) = frame_of(&mut r, key, params, &camera, &lights());
    (report.work.clone(), report)
}

fn res() -> (&'static str, ParamValue) {
    ("shadow_res", ParamValue::Int(RES))
}

#[test]
fn the_reference_counts_one_lookup_and_one_tap_per_light_and_pixel() {
    let (w, report) = work("reference", &[res()]);
    assert_eq!(w["shaded_pixels"], PIXELS, "{w:?}");
    assert_eq!(w["light_pixel_evaluations"], 2.0 * PIXELS);
    assert_eq!(w["shadow_lookups"], 2.0 * PIXELS);
    assert_eq!(w["shadow_lookups_per_pixel"], 2.0);
    assert_eq!(w["filter_taps_per_pixel"], 2.0, "binary visibility: one texel per lookup");
    assert_eq!(w["shadow_rays"], 0.0);
    // Two cube maps of six 64 x 64 faces.
    assert_eq!(w["shadow_texels_written"], (2 * 6 * RES * RES) as f64);
    // The floor's two triangles in all six faces of each light: the chunk lies in both ranges, and the face
    // test is conservative (each of the +Y face's four planes alone passes a floor reaching 10 units aside).
    assert_eq!(w["depth_triangles"], 2.0 * 6.0 * 2.0);
    assert_eq!(w["depth_triangles"], report.counts.technique.shadow_triangles_submitted as f64);
}

#[test]
fn the_ray_tracer_traces_one_ray_per_light_and_pixel() {
    let (w, _) = work("raytraced", &[]);
    assert_eq!(w["light_pixel_evaluations"], 2.0 * PIXELS, "{w:?}");
    assert_eq!(w["shadow_rays"], 2.0 * PIXELS);
    assert_eq!(w["shadow_lookups"], 0.0);
    assert_eq!(w["shadow_texels_written"], 0.0);
    let (w, _) = work("unshadowed", &[]);
    assert_eq!(w["light_pixel_evaluations"], 2.0 * PIXELS, "{w:?}");
    assert_eq!(w["shadow_rays"] + w["shadow_lookups"] + w["depth_triangles"], 0.0);
}

#[test]
fn lightcluster_counts_one_lookup_per_cluster_and_its_filter_taps() {
    // One cluster holds both lights (d_init far larger than their distance); PCF takes every sample.
    let samples = 12;
    let params = [
        res(),
        ("d_init", ParamValue::Float(4.0)),
        ("filter", ParamValue::Choice("pcf".into())),
        ("samples", ParamValue::Int(samples)),
    ];
    let (w, report) = work("lightcluster", &params);
    assert_eq!(report.counts.technique.clusters, Some(1), "{:?}", report.counts);
    assert_eq!(w["light_pixel_evaluations"], 2.0 * PIXELS, "{w:?}");
    assert_eq!(w["shadow_lookups"], PIXELS);
    assert_eq!(w["filter_taps"], PIXELS * samples as f64);
    assert_eq!(w["shadow_texels_written"], (6 * RES * RES) as f64);
}

#[test]
fn the_vpl_gather_evaluates_every_vpl_at_every_pixel() {
    let scene = floor();
    let n = 16;
    let settings = indirect_settings(W, H, VplSettings { count: n, ..Default::default() });
    for key in ["vpl-raytraced", "vpl-shadowmaps"] {
        let mut r = renderer(&scene, settings.clone());
        let params = [("interleave", ParamValue::Bool(false))];
        r.set_indirect(Some(create_indirect(&r, key, &params))).unwrap();
        let camera = scene.camera;
        let (_, report) = frame_of(&mut r, "unshadowed", &[], &camera, &lights());
        let vpls = report.indirect.as_ref().unwrap().vpls as f64;
        assert!(vpls > 0.0);
        let w = &report.indirect.as_ref().unwrap().work;
        assert_eq!(w["vpl_pixel_evaluations"], vpls * PIXELS, "{key}: {w:?}");
        // Every VPL lies in the floor's plane, so no term is above zero: no ray, no lookup.
        assert_eq!(w["shadow_rays"] + w["shadow_lookups"], 0.0, "{key}: {w:?}");
        // The direct part is the unshadowed technique's.
        assert_eq!(report.work["light_pixel_evaluations"], 2.0 * PIXELS);
        if key == "vpl-shadowmaps" {
            let res = report.indirect.as_ref().unwrap().parameters["shadow_res"].parse::<f64>().unwrap();
            assert_eq!(w["shadow_texels_written"], vpls * res * res, "one paraboloid map per VPL");
        }
    }
}
