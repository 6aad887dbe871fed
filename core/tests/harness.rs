//! The test harness (issue 20): every technique of the two registries that is not a preview, rendered on small
//! scenes against its declared comparison target within its declared tolerance (display-referred, see
//! `common::display_difference`); a technique without visibility (the registry's preview) must fail those
//! tolerances, so a technique that loses its shadows fails the harness; and every entry creates the technique of
//! its key, which accepts the entry's software defaults.
//!
//! `cargo test -p shadowlab-core --test harness -- --nocapture` prints every measured error (the numbers the
//! tolerances in `core/src/technique/registry.rs` were set from); with `SHADOWLAB_HARNESS_IMAGES=1` it also
//! writes the images of the comparisons that pass (failures always write theirs) to `target/test-output/`.

mod common;

use common::*;
use glam::Vec3;
use shadowlab_core::scene::{Camera, PointLight, Scene};
use shadowlab_core::technique::registry::{
    self, Role, TechniqueEntry, INDIRECT_REFERENCE, INDIRECT_REGISTRY, REFERENCE, REGISTRY,
};
use shadowlab_core::technique::{CameraPose, ParamValue, Technique};
use shadowlab_core::vpl::VplSettings;
use shadowlab_core::{RenderSettings, Renderer};

const W: u32 = 96;
const H: u32 = 72;
/// VPLs of the indirect cases.
const VPLS: u32 = 256;

/// A scene, its lights, and the parameters some techniques need on it (after their software defaults).
struct Case {
    name: &'static str,
    scene: Scene,
    lights: Vec<PointLight>,
    params: Vec<(&'static str, Vec<(&'static str, ParamValue)>)>,
}

impl Case {
    fn new(name: &'static str, scene: Scene, lights: Vec<PointLight>) -> Case {
        Case { name, scene, lights, params: Vec::new() }
    }

    /// `key` renders with `params` on this case.
    fn with(mut self, key: &'static str, params: Vec<(&'static str, ParamValue)>) -> Case {
        self.params.push((key, params));
        self
    }

    fn params_of(&self, key: &str) -> &[(&'static str, ParamValue)] {
        self.params.iter().find(|(k, _)| *k == key).map_or(&[], |(_, p)| p)
    }
}

/// INSM's viewpoints for the plate scenes: four above the plate looking down at it, as a user would place them
/// (the paper's bounding-box placement puts its cameras 10 m away from the 1 m plate on the 20 m ground, too
/// far to sample it).
fn insm_over_the_plate() -> Vec<(&'static str, ParamValue)> {
    let cameras = [(2.0, 2.0), (-2.0, 2.0), (2.0, -2.0), (-2.0, -2.0)]
        .iter()
        .map(|&(x, z)| CameraPose { position: Vec3::new(x, 4.0, z), target: Vec3::new(0.0, 0.5, 0.0), fov_y_deg: 60.0 })
        .collect();
    vec![("placement", ParamValue::Choice("custom".into())), ("viewpoints", ParamValue::Cameras(cameras))]
}

/// INSM inside a closed room: the bounding-box placement sees only the outside of its walls.
fn insm_inside() -> Vec<(&'static str, ParamValue)> {
    vec![("placement", ParamValue::Choice("inside".into()))]
}

fn cornell() -> Scene {
    Scene::builtin("cornell").unwrap()
}

/// The plate and its shadow from close above: three lights close together low on one side throw overlapping
/// shadows that fill much of the view (so a technique that loses its shadows is far off here), and LightCluster
/// makes one cluster of them (a soft shadow).
fn plate_shadow() -> Case {
    let mut scene = plane_and_occluder();
    scene.camera = Camera::look_at(Vec3::new(0.9, 4.5, 2.2), Vec3::new(0.9, 0.0, 0.0), 35f32.to_radians(), 0.1, 20.0);
    let lights = vec![
        white_light(Vec3::new(-2.0, 2.5, -0.1), 6.0, 10.0),
        white_light(Vec3::new(-2.0, 2.5, 0.1), 6.0, 10.0),
        PointLight::new(Vec3::new(-1.9, 2.6, 0.0), Vec3::new(1.0, 0.7, 0.4), 6.0, 10.0),
    ];
    Case::new("plate-shadow", scene, lights).with("insm", insm_over_the_plate())
}

/// The direct techniques' scenes: the plate's shadow from close above, the plate's hard shadows on the ground
/// from three lights (one coloured), the same with the back wall and a light low enough to shadow it, and the
/// Cornell box with its 32 lights.
fn direct_cases() -> Vec<Case> {
    let cornell = cornell();
    let lights = cornell.lights.clone();
    vec![
        plate_shadow(),
        Case::new(
            "plane-occluder",
            plane_and_occluder(),
            vec![
                white_light(Vec3::new(-1.5, 3.0, 0.2), 12.0, 8.0),
                PointLight::new(Vec3::new(1.2, 2.5, -0.5), Vec3::new(1.0, 0.6, 0.3), 10.0, 7.0),
                white_light(Vec3::new(0.0, 3.5, 1.5), 8.0, 8.0),
            ],
        )
        .with("insm", insm_over_the_plate()),
        Case::new(
            "room",
            room(),
            vec![white_light(Vec3::new(0.5, 3.0, 0.5), 8.0, 30.0), white_light(Vec3::new(0.3, 1.4, 2.0), 4.0, 10.0)],
        )
        .with("insm", insm_over_the_plate()),
        Case::new("cornell", cornell, lights).with("insm", insm_inside()),
    ]
}

/// A ground, a ceiling 2.2 m above it and a 2 m plate between them at 1 m, seen from between plate and ceiling;
/// a light under the plate lights the ground, whose VPLs light the ceiling except above the plate: an indirect
/// shadow that fills much of the view.
fn ceiling() -> Case {
    let mut scene = plane_and_occluder();
    scene.meshes = vec![quad("ground", Vec3::ZERO, 8.0, 0), quad("plate", PLATE_CENTER, 2.0, 0)];
    let mut ceiling = quad("ceiling", Vec3::new(0.0, 2.2, 0.0), 8.0, 0);
    ceiling.normals = vec![Vec3::NEG_Y; 4];
    ceiling.indices = vec![0, 1, 2, 0, 2, 3];
    scene.meshes.push(ceiling);
    scene.camera = Camera::look_at(Vec3::new(0.0, 1.5, 3.5), Vec3::new(0.0, 2.2, 0.0), 60f32.to_radians(), 0.05, 20.0);
    scene.finalize(std::path::Path::new("test")).unwrap();
    Case::new("ceiling", scene, vec![white_light(Vec3::new(0.2, 0.4, 0.1), 4.0, 20.0)])
}

/// The indirect techniques' scenes: the ceiling's indirect shadow, the room lit from above (the ground's VPLs
/// light the wall past the plate) and the Cornell box with four of its lights. The path tracer takes 512 paths
/// per pixel: at its default 64 its noise alone puts 27-42 % of the pixels more than 0.1 off.
fn indirect_cases() -> Vec<Case> {
    let cornell = cornell();
    let lights = cornell.lights[..4].to_vec();
    let pt = || vec![("samples", ParamValue::Int(512)), ("samples_per_step", ParamValue::Int(64))];
    vec![
        ceiling().with("pathtraced", pt()),
        Case::new("room", room(), vec![white_light(Vec3::new(0.5, 3.0, 0.5), 8.0, 30.0)]).with("pathtraced", pt()),
        Case::new("cornell", cornell, lights).with("pathtraced", pt()),
    ]
}

/// An entry's software defaults as values, parsed with its parameters' kinds; a default the technique does not
/// have or that does not parse fails the test.
fn software_defaults(entry: &TechniqueEntry, technique: &dyn Technique) -> Vec<(&'static str, ParamValue)> {
    let params = technique.params();
    entry
        .software_defaults
        .iter()
        .map(|&(key, text)| {
            let p = params.iter().find(|p| p.key == key).unwrap_or_else(|| {
                let known: Vec<&str> = params.iter().map(|p| p.key).collect();
                panic!("{}: software default '{key}' is not one of its parameters {known:?}", entry.key)
            });
            let value = p.kind.parse(key, text).unwrap_or_else(|e| panic!("{}: software default: {e}", entry.key));
            (key, value)
        })
        .collect()
}

/// Which registry, for rendering and messages.
#[derive(Clone, Copy, PartialEq)]
enum Registry {
    Direct,
    Indirect,
}

impl Registry {
    fn entries(self) -> &'static [TechniqueEntry] {
        match self {
            Registry::Direct => REGISTRY,
            Registry::Indirect => INDIRECT_REGISTRY,
        }
    }

    fn entry(self, key: &str) -> &'static TechniqueEntry {
        match self {
            Registry::Direct => registry::entry(key),
            Registry::Indirect => registry::indirect_entry(key),
        }
        .unwrap_or_else(|| panic!("'{key}' is not registered"))
    }

    fn name(self) -> &'static str {
        match self {
            Registry::Direct => "direct",
            Registry::Indirect => "indirect",
        }
    }

    fn reference(self) -> &'static str {
        match self {
            Registry::Direct => REFERENCE,
            Registry::Indirect => INDIRECT_REFERENCE,
        }
    }

    /// The renderer settings of a case: linear; for the indirect registry the indirect part alone, with the
    /// VPLs from the source the technique's paper uses (its target is rendered from the same VPLs).
    fn settings(self, entry: &TechniqueEntry) -> RenderSettings {
        match self {
            Registry::Direct => linear_settings(W, H),
            Registry::Indirect => {
                let mut vpl = VplSettings { count: VPLS, ..Default::default() };
                if let Some(source) = entry.vpl_source {
                    vpl.source = source;
                }
                indirect_settings(W, H, vpl)
            }
        }
    }

    /// One frame of `entry` (with its software defaults) on `renderer` with `settings`: a direct technique
    /// alone, or an indirect one over the unshadowed direct light (which the indirect component leaves out).
    fn render(
        self,
        renderer: &mut Renderer,
        settings: RenderSettings,
        case: &Case,
        entry: &TechniqueEntry,
    ) -> Vec<[f32; 4]> {
        renderer.set_settings(settings).unwrap();
        let mut technique = (entry.create)(renderer.gpu(), renderer.layouts());
        let defaults = software_defaults(entry, technique.as_ref());
        set_params(technique.as_mut(), &defaults);
        set_params(technique.as_mut(), case.params_of(entry.key));
        match self {
            Registry::Direct => frame(renderer, technique.as_mut(), &case.scene.camera, &case.lights).0,
            Registry::Indirect => {
                let uses_vpls = technique.uses_vpls();
                renderer.set_indirect(Some(technique)).unwrap();
                let mut direct = create(renderer, "unshadowed", &[]);
                let (hdr, report) = frame(renderer, direct.as_mut(), &case.scene.camera, &case.lights);
                renderer.set_indirect(None).unwrap();
                let vpls = report.indirect.map(|i| i.vpls);
                assert!(vpls.is_some_and(|n| n > 0 || !uses_vpls), "{} on {}: VPLs {vpls:?}", entry.key, case.name);
                hdr
            }
        }
    }
}

/// What an entry is compared with: its target, or for a ground truth (its own target) the reference's target;
/// None when that is the entry itself.
fn comparison_target(registry: Registry, entry: &TechniqueEntry) -> Option<&'static TechniqueEntry> {
    let target = registry.entry(entry.target);
    if target.key != entry.key {
        return Some(target);
    }
    let fallback = registry.entry(registry.entry(registry.reference()).target);
    (fallback.key != entry.key).then_some(fallback)
}

/// Render every non-preview entry of `registry` on `cases` against its comparison target, and every preview
/// against the targets of the approximations and references: each entry within its tolerance, each preview
/// outside the tolerance of every entry with its target on at least one case. Panics with every failure, the
/// numbers and the images' paths.
fn run_registry(registry: Registry, cases: &[Case]) {
    let started = std::time::Instant::now();
    let gpu = gpu();
    let mut lines = Vec::new();
    let mut failures = Vec::new();
    // The ground truths whose target is themselves and the reference's target: nothing to compare with here.
    for entry in registry.entries().iter().filter(|e| e.role != Role::Preview) {
        if comparison_target(registry, entry).is_none() {
            lines.push(format!(
                "{} {}: skipped: a ground truth is its own target and the reference's target ({}), so the harness \
                 has nothing to compare it with; it is checked against analytic answers in its own tests",
                registry.name(),
                entry.key,
                registry.entry(registry.reference()).key
            ));
        }
    }
    // Per preview and per entry it must be rejected by: whether some case rejected it.
    let previews: Vec<&'static TechniqueEntry> =
        registry.entries().iter().filter(|e| e.role == Role::Preview).collect();
    let mut rejected: Vec<(&str, &str, &str, bool)> = Vec::new();
    for case in cases {
        let mut renderer = Renderer::new(&gpu, &case.scene, linear_settings(W, H)).unwrap();
        // Images by (key, VPL source), rendered once per case.
        let mut images: Vec<(&str, String, Vec<[f32; 4]>)> = Vec::new();
        // `like`: the entry the image is for, whose settings (VPL source) it is rendered with.
        let mut image = |renderer: &mut Renderer, entry: &'static TechniqueEntry, like: &TechniqueEntry| {
            let settings = registry.settings(like);
            let source = format!("{:?}", settings.vpl.source);
            if let Some((_, _, img)) = images.iter().find(|(k, s, _)| *k == entry.key && *s == source) {
                return img.clone();
            }
            let img = registry.render(renderer, settings, case, entry);
            images.push((entry.key, source, img.clone()));
            img
        };
        for entry in registry.entries().iter().filter(|e| e.role != Role::Preview) {
            let Some(target) = comparison_target(registry, entry) else { continue };
            let expected = image(&mut renderer, target, entry);
            let actual = image(&mut renderer, entry, entry);
            let exposure = exposure(registry, &expected);
            let d = display_difference(&actual, &expected, W, H, exposure, None);
            let t = entry.tolerance;
            let within = d.mean_abs <= t.mean_abs && d.bad_share <= t.bad_pixel_share;
            let line = format!(
                "{} {} vs {} on {}: {d} (tolerance mean abs {}, share {})",
                registry.name(),
                entry.key,
                target.key,
                case.name,
                t.mean_abs,
                t.bad_pixel_share
            );
            let name = format!("harness-{}-{}-{}", registry.name(), entry.key, case.name);
            if !within {
                let [actual, _, difference] = failure_images(&name, &actual, &expected, exposure, &d.bad);
                failures.push(format!(
                    "{line}: over the tolerance; see {} and {} (and -expected.png)",
                    actual.display(),
                    difference.display()
                ));
            } else if std::env::var_os("SHADOWLAB_HARNESS_IMAGES").is_some() {
                failure_images(&name, &actual, &expected, exposure, &d.bad);
            }
            lines.push(line);
            // The previews (no visibility) against this entry's target: outside its tolerance somewhere.
            for preview in &previews {
                let img = image(&mut renderer, preview, entry);
                let p = display_difference(&img, &expected, W, H, exposure, None);
                let out = p.mean_abs > t.mean_abs || p.bad_share > t.bad_pixel_share;
                let verdict = if out { "outside" } else { "within" };
                lines.push(format!(
                    "  {} (no visibility) vs {} on {}: {p}: {verdict} {}'s tolerance",
                    preview.key, target.key, case.name, entry.key
                ));
                match rejected.iter_mut().find(|r| r.0 == entry.key && r.1 == preview.key) {
                    Some(r) => r.3 |= out,
                    None => rejected.push((entry.key, preview.key, target.key, out)),
                }
            }
        }
    }
    for (key, preview, target, out) in &rejected {
        if !out {
            failures.push(format!(
                "{} {key}: its tolerance accepts {preview} (no visibility) against {target} on every case: it \
                 cannot tell a technique that lost its shadows",
                registry.name()
            ));
        }
    }
    eprintln!("{}\n{} registry: {:.1} s", lines.join("\n"), registry.name(), started.elapsed().as_secs_f32());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The display exposure of a comparison: the renderer's default (1) for direct light; for the indirect part
/// alone (far below 1), what auto-exposure meters on the target's lit pixels (not the G-buffer's geometry
/// mask: the GL backend cannot copy a depth texture).
fn exposure(registry: Registry, expected: &[[f32; 4]]) -> f32 {
    match registry {
        Registry::Direct => 1.0,
        Registry::Indirect => {
            let lit: Vec<bool> = expected.iter().map(|p| shadowlab_core::compare::luminance(*p) > 0.0).collect();
            metered_exposure(expected, &lit)
        }
    }
}

/// Write `<name>-actual.png`, `-expected.png` and `-difference.png` (red: more than `BAD_PIXEL` off) at the
/// comparison's exposure; their paths.
fn failure_images(
    name: &str,
    actual: &[[f32; 4]],
    expected: &[[f32; 4]],
    exposure: f32,
    bad: &[bool],
) -> [std::path::PathBuf; 3] {
    let scale = |img: &[[f32; 4]]| -> Vec<[f32; 4]> {
        img.iter().map(|p| [p[0] * exposure, p[1] * exposure, p[2] * exposure, p[3]]).collect()
    };
    let exp: Vec<Option<[f32; 4]>> = scale(expected).into_iter().map(Some).collect();
    let difference = write_failure_images(name, W, H, &scale(actual), &exp, bad);
    let dir = output_dir();
    [dir.join(format!("{name}-actual.png")), dir.join(format!("{name}-expected.png")), difference]
}

#[test]
fn every_direct_technique_is_within_its_tolerance_of_its_target() {
    run_registry(Registry::Direct, &direct_cases());
}

#[test]
fn every_indirect_technique_is_within_its_tolerance_of_its_target() {
    run_registry(Registry::Indirect, &indirect_cases());
}

#[test]
fn every_entry_creates_its_technique_which_accepts_its_software_defaults() {
    let scene = plane_and_occluder();
    let renderer = renderer(&scene, linear_settings(16, 16));
    for entry in REGISTRY.iter().chain(INDIRECT_REGISTRY) {
        let mut technique = (entry.create)(renderer.gpu(), renderer.layouts());
        assert_eq!(technique.key(), entry.key, "the entry's create makes another technique");
        for (key, value) in software_defaults(entry, technique.as_ref()) {
            technique.set_param(key, &value).unwrap_or_else(|e| panic!("{}: software default {key}: {e}", entry.key));
            let now = technique.params().into_iter().find(|p| p.key == key).unwrap().value;
            assert_eq!(now, value, "{}: software default {key} did not take", entry.key);
        }
        // The app folds the tuning parameters into a section of their own: each must be one of the technique's.
        let keys: Vec<&str> = technique.params().iter().map(|p| p.key).collect();
        for key in technique.tuning_params() {
            assert!(keys.contains(key), "{}: tuning parameter {key} is not a parameter", entry.key);
        }
    }
    // Every direct technique shows the lights, one dot a light, in a layer shown by default ("lights", or
    // LightCluster's "lights by cluster"); the preview showed none, so the lights a user placed were invisible
    // with it chosen.
    let lights = [white_light(Vec3::new(0.0, 2.0, 0.0), 1.0, 5.0), white_light(Vec3::new(1.0, 2.0, 0.0), 2.0, 5.0)];
    for entry in REGISTRY {
        let technique = (entry.create)(renderer.gpu(), renderer.layouts());
        let layers = technique.overlays(&lights);
        let names: Vec<&str> = layers.iter().map(|l| l.name).collect();
        let shown = layers.iter().find(|l| l.name.starts_with("lights") && l.visible_by_default);
        let shown = shown.unwrap_or_else(|| panic!("{}: no lights layer shown by default in {names:?}", entry.key));
        // (LightCluster colours its lights by cluster, once a frame has clustered them.)
        if shown.name == "lights" {
            assert_eq!(shown.primitives.len(), 2, "{}: a dot a light", entry.key);
        }
    }
}
