//! Receiver-aware caster culling in the cube shadow maps: a chunk that cannot lie between a light and the view's
//! surfaces in its range is not drawn. Exact: the reference's and LightCluster's images do not change, and
//! fewer triangles are drawn when the camera sees part of the scene.

mod common;

use common::*;
use shadowlab_core::scene::Scene;

#[test]
fn culling_casters_outside_the_receivers_box_keeps_the_image_and_draws_less() {
    let scene = Scene::builtin("arcade").unwrap();
    let lights = scene.lights.clone();
    // A close view of the floor sees a small part of the scene (the far plane short of the walls).
    let c = scene.bounds.center();
    let camera = shadowlab_core::scene::Camera::look_at(
        glam::Vec3::new(c.x, scene.bounds.min.y + 2.0, c.z),
        glam::Vec3::new(c.x + 0.5, scene.bounds.min.y, c.z + 0.3),
        0.8,
        0.05,
        6.0,
    );
    for key in ["reference", "lightcluster"] {
        let render = |culling: bool| {
            let mut settings = linear_settings(96, 54);
            settings.receiver_culling = culling;
            let shot = Shot::direct(&scene, &lights, settings, key).camera(&camera);
            shot.params(&[("shadow_res", shadowlab_core::technique::ParamValue::Int(128))]).render()
        };
        let (culled, culled_report) = render(true);
        let (all, all_report) = render(false);
        let drawn = |r: &shadowlab_core::FrameReport| r.counts.technique.shadow_triangles_submitted;
        eprintln!(
            "{key}: {} triangles drawn with receiver culling, {} without",
            drawn(&culled_report),
            drawn(&all_report)
        );
        assert!(culled == all, "{key}: receiver culling changed the image");
        assert!(drawn(&culled_report) < drawn(&all_report), "{key}: nothing was culled");
    }
}
