//! A light's reflective shadow map as an image (`vpl::rsm`): its texels hold the surface, normal and reflected
//! flux the `rsm` VPL source draws from; the map's total is the one-bounce flux the VPLs estimate; each VPL
//! is found at the texel it was drawn from. On the software adapter (the scene's BVH is the renderer's).

mod common;

use common::*;
use glam::Vec3;
use shadowlab_core::scene::{DirectionalLight, PointLight};
use shadowlab_core::vpl::rsm::{rsm_image, RsmEmitter, RsmError, RsmLayout, MAX_IMAGE_RESOLUTION};
use shadowlab_core::vpl::{self, VplSettings, VplSource, RSM_RESOLUTION};

fn spot(cone_deg: f32) -> PointLight {
    let spec = format!("spot:0.5,3,0.2:0.5,0,0.2:{cone_deg}:20");
    let layout = shadowlab_core::scene::layout::parse(&spec).unwrap();
    shadowlab_core::scene::layout::generate(&layout, &plane_scene(8.0, 0.5)).unwrap()[0]
}

#[test]
fn a_point_lights_rsm_holds_the_plane_it_sees_and_sums_to_the_flux_the_plane_reflects() {
    let (side, h, albedo) = (8.0, 2.0, 0.6);
    let bvh = scene_bvh(&plane_scene(side, albedo));
    let light = PointLight::new(Vec3::new(0.0, h, 0.0), Vec3::new(1.0, 0.5, 0.25), 10.0, 50.0);
    let image = rsm_image(&bvh, RsmEmitter::Point(&light), 128).unwrap();
    assert_eq!((image.faces, image.resolution, image.texels.len()), (6, 128, 6 * 128 * 128));
    assert_eq!(image.layout, RsmLayout::Cube { eye: light.position });
    // The -y face (3) looks straight down: its centre sees the plane below the light, 2 away, facing up.
    let below = image.texel(3, 64, 64).expect("the plane below the light");
    assert!(below.position.y.abs() < 1e-4 && below.normal.y > 0.99 && (below.distance - h).abs() < 0.03);
    assert!(image.texel(2, 64, 64).is_none(), "nothing above the light");
    // Every texel that sees something sees the plane.
    assert!(image.texels.iter().flatten().all(|t| t.position.y.abs() < 1e-4 && t.flux.min_element() > 0.0));
    let expected = albedo as f64 * intercepted_flux(10.0, 50.0, h, side);
    let total = image.total_flux();
    let err = (total.x as f64 - expected).abs() / expected;
    assert!(err < 0.01, "RSM flux {} vs reflected {expected:.4} ({:.2} %)", total.x, err * 100.0);
    assert!((total.y / total.x - 0.5).abs() < 1e-4 && (total.z / total.x - 0.25).abs() < 1e-4);
    // The VPLs estimate the same one bounce: their total agrees with the map's.
    let set = vpl::generate(&bvh, &[light], &[], &VplSettings { count: 4096, ..Default::default() });
    let vpls = set.total_flux().x as f64;
    assert!((vpls - total.x as f64).abs() / (total.x as f64) < 0.02, "VPLs {vpls} vs RSM {}", total.x);
    // Each VPL was drawn from a texel of the map; at a coarser map it falls in the texel whose footprint
    // holds it, which sees the plane near it.
    for v in &set.vpls {
        let (face, x, y) = image.texel_of(v.position).expect("a VPL of the light is in its RSM");
        let inside = v.position.x.abs().max(v.position.z.abs()) < side / 2.0 - 0.1;
        let Some(t) = image.texel(face, x, y) else {
            assert!(!inside, "the texel of a VPL away from the plane's edge sees nothing: {v:?}");
            continue;
        };
        let footprint = 2.0 * t.distance / 128.0 * 2.0;
        assert!(t.position.distance(v.position) < footprint * 2.0, "VPL {v:?} vs texel {t:?}");
    }
}

#[test]
fn at_the_sources_resolution_every_vpl_is_the_central_ray_of_its_texel() {
    // A narrow spot: one face; its VPLs are the central rays of texels of a 256² face.
    let bvh = scene_bvh(&plane_scene(8.0, 0.5));
    let light = spot(25.0);
    let image = rsm_image(&bvh, RsmEmitter::Point(&light), RSM_RESOLUTION).unwrap();
    assert_eq!(image.faces, 1);
    assert!(matches!(image.layout, RsmLayout::Spot { .. }));
    let set = vpl::generate(&bvh, &[light], &[], &VplSettings { count: 512, ..Default::default() });
    assert!(set.vpls.len() > 100);
    for v in &set.vpls {
        let (face, x, y) = image.texel_of(v.position).expect("in the spot's face");
        let t = image.texel(face, x, y).expect("the texel sees the plane");
        assert!(
            t.position.distance(v.position) < 1e-4,
            "texel ({x}, {y}) sees {:?}, the VPL is at {:?}",
            t.position,
            v.position
        );
        // The VPL's flux is the texel's times the texels of the face over the samples drawn (all of this light).
        let scale = (RSM_RESOLUTION * RSM_RESOLUTION) as f32 / 512.0;
        assert!((v.flux - t.flux * scale).abs().max_element() < 1e-3 * v.flux.max_element(), "{v:?} {t:?}");
    }
    // Outside the cone the map is empty: texels whose rays leave it hold nothing.
    let corner = image.texel(0, 0, 0);
    assert!(corner.is_none(), "the face's corner lies outside the cone: {corner:?}");
}

#[test]
fn a_suns_rsm_is_an_orthographic_square_whose_flux_is_the_irradiance_the_plane_reflects() {
    let (side, albedo) = (8.0, 0.6);
    let bvh = scene_bvh(&plane_scene(side, albedo));
    let d = Vec3::new(0.3, -1.0, 0.2).normalize();
    let sun = DirectionalLight { direction: d, color: Vec3::new(1.0, 0.5, 0.25), illuminance: 2.0 };
    let image = rsm_image(&bvh, RsmEmitter::Sun(&sun), RSM_RESOLUTION).unwrap();
    assert!(matches!(image.layout, RsmLayout::Sun { .. }) && image.faces == 1);
    let expected = albedo as f64 * 2.0 * (side * side) as f64 * (-d.y) as f64;
    let red = image.total_flux().x as f64;
    assert!((red - expected).abs() / expected < 0.03, "sun RSM flux {red} vs {expected}");
    let set =
        vpl::generate(&bvh, &[], &[sun], &VplSettings { count: 1024, source: VplSource::Rsm, ..Default::default() });
    for v in &set.vpls {
        let (face, x, y) = image.texel_of(v.position).expect("the sun's VPLs lie in its square");
        assert_eq!(face, 0);
        // At the source's resolution the VPL is the texel's own column.
        assert!(image.texel(0, x, y).is_some_and(|t| t.position.distance(v.position) < 1e-4), "{v:?}");
    }
}

#[test]
fn absurd_resolutions_and_invalid_lights_get_an_error() {
    let bvh = scene_bvh(&plane_scene(8.0, 0.5));
    let light = PointLight::new(Vec3::new(0.0, 2.0, 0.0), Vec3::ONE, 10.0, 50.0);
    for r in [0, MAX_IMAGE_RESOLUTION + 1, u32::MAX] {
        assert_eq!(rsm_image(&bvh, RsmEmitter::Point(&light), r), Err(RsmError::Resolution(r)));
    }
    let nan = PointLight::new(Vec3::new(f32::NAN, 2.0, 0.0), Vec3::ONE, 10.0, 50.0);
    assert_eq!(rsm_image(&bvh, RsmEmitter::Point(&nan), 8), Err(RsmError::InvalidLight));
    let no_direction = DirectionalLight { direction: Vec3::ZERO, color: Vec3::ONE, illuminance: 1.0 };
    assert_eq!(rsm_image(&bvh, RsmEmitter::Sun(&no_direction), 8), Err(RsmError::NoSunSquare));
    // A light that reaches nothing has an empty map, not an error.
    let far = PointLight::new(Vec3::new(0.0, 100.0, 0.0), Vec3::ONE, 10.0, 5.0);
    let empty = rsm_image(&bvh, RsmEmitter::Point(&far), 8).unwrap();
    assert!(empty.texels.iter().all(Option::is_none) && empty.total_flux() == Vec3::ZERO);
}

#[test]
fn the_drawn_texels_are_those_of_the_lights_own_first_bounce_vpls() {
    let bvh = scene_bvh(&room());
    let lights = [
        PointLight::new(Vec3::new(-0.5, 1.5, 0.0), Vec3::ONE, 5.0, 10.0),
        PointLight::new(Vec3::new(0.5, 1.5, 0.3), Vec3::ONE, 5.0, 10.0),
    ];
    let settings = VplSettings { count: 2048, source: VplSource::Traced, bounces: 3, ..Default::default() };
    let set = vpl::generate(&bvh, &lights, &[], &settings);
    for (i, light) in lights.iter().enumerate() {
        let image = rsm_image(&bvh, RsmEmitter::Point(light), 32).unwrap();
        let drawn = image.drawn_texels(&set, i as u32);
        let first = set.vpls.iter().filter(|v| v.light == i as u32 && v.from == light.position).count();
        let later = set.vpls.iter().filter(|v| v.light == i as u32 && v.from != light.position).count();
        assert!(first > 100 && later > 0, "light {i}: {first} first-bounce VPLs, {later} later");
        assert_eq!(drawn.values().sum::<u32>() as usize, first, "light {i}: every first-bounce VPL, once");
        // A marked texel sees a surface, but for a few at silhouettes (the plate's, the wall's and the
        // ground's edges), where the VPL's ray met what the texel's central ray passes.
        let seeing = drawn.keys().filter(|(f, x, y)| image.texel(*f, *x, *y).is_some()).count();
        assert!(seeing * 10 >= drawn.len() * 9, "light {i}: {seeing} of {} marked texels see a surface", drawn.len());
    }
}
