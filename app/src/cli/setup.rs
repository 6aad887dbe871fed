//! What the subcommands share: the scene, its lights, the camera and a renderer from the arguments, the
//! checks of technique keys, and the overlays drawn over an output.

use std::time::Instant;

use anyhow::{anyhow, bail, Result};
use glam::Vec3;
use shadowlab_core::renderer::Component;
use shadowlab_core::scene::layout::{self, LightLayout};
use shadowlab_core::scene::{sun_direction, Camera, DirectionalLight, PointLight, Scene, MAX_DIRECTIONAL_LIGHTS};
use shadowlab_core::technique::{self, Technique};
use shadowlab_core::vpl::{VplSettings, VplSource};
use shadowlab_core::{AutoExposure, GpuContext, RenderSettings, Renderer, ToneMap};

use super::args::{check_indirect, FrameArgs, SceneArgs};

/// Parse `--sun AZIMUTH,ELEVATION,ILLUMINANCE[,R,G,B]` (degrees, degrees, W/m², linear colour).
pub fn parse_sun(text: &str) -> Result<DirectionalLight> {
    let usage = "expected AZIMUTH,ELEVATION,ILLUMINANCE[,R,G,B] (degrees from -Z towards +X, degrees above the \
                 horizon, W/m², linear colour)";
    let v: Vec<f32> = text
        .split(',')
        .map(|s| s.trim().parse::<f32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| anyhow!("--sun '{text}': {usage}"))?;
    if !(v.len() == 3 || v.len() == 6) || v.iter().any(|x| !x.is_finite()) {
        bail!("--sun '{text}': {usage}, all finite");
    }
    if !(-90.0..=90.0).contains(&v[1]) {
        bail!("--sun '{text}': the elevation {} must be between -90 and 90 degrees", v[1]);
    }
    let color = if v.len() == 6 { Vec3::new(v[3], v[4], v[5]) } else { Vec3::ONE };
    let sun = DirectionalLight { direction: sun_direction(v[0], v[1]), color, illuminance: v[2] };
    if !sun.is_valid() {
        bail!("--sun '{text}': the illuminance and colour must be >= 0");
    }
    Ok(sun)
}

/// Load the scene and its lights as the arguments say (`--sun` replaces the scene's own suns).
pub fn load_scene(args: &SceneArgs) -> Result<(Scene, Vec<PointLight>)> {
    let mut scene = Scene::load_any(&args.scene, args.scale)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if !args.suns.is_empty() {
        if args.suns.len() > MAX_DIRECTIONAL_LIGHTS {
            bail!("{} --sun options: at most {MAX_DIRECTIONAL_LIGHTS} suns are shaded", args.suns.len());
        }
        scene.directional = args.suns.iter().map(|s| parse_sun(s)).collect::<Result<_>>()?;
    }
    let mut layout: LightLayout = layout::parse(&args.lights)?;
    if layout == LightLayout::Scene && scene.lights.is_empty() {
        layout = layout::default_for_unlit(&scene);
        eprintln!("note: {} has no lights; using --lights {layout} (give --lights to choose)", scene.name);
    }
    let lights = layout::generate(&layout, &scene)?;
    Ok((scene, lights))
}

pub fn parse_vec3s(text: &str) -> Result<(Vec3, Vec3)> {
    let v: Vec<f32> = text
        .split(',')
        .map(|s| s.trim().parse::<f32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| anyhow!("--camera '{text}': expected six numbers EX,EY,EZ,TX,TY,TZ"))?;
    if v.len() != 6 || v.iter().any(|x| !x.is_finite()) {
        bail!("--camera '{text}': expected six finite numbers EX,EY,EZ,TX,TY,TZ");
    }
    Ok((Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5])))
}

pub fn camera_from_args(scene: &Scene, args: &FrameArgs) -> Result<Camera> {
    let mut camera = scene.camera;
    if let Some(text) = &args.camera {
        let (eye, target) = parse_vec3s(text)?;
        if (target - eye).length() < 1e-6 {
            bail!("--camera: eye and target are the same point");
        }
        camera = Camera::look_at(eye, target, camera.fov_y, camera.near, camera.z_far);
    }
    if let Some(fov) = args.fov {
        if !(fov.is_finite() && fov > 1.0 && fov < 179.0) {
            bail!("--fov {fov}: must be between 1 and 179 degrees");
        }
        camera.fov_y = fov.to_radians();
    }
    if let Some(z_far) = args.z_far {
        if !(z_far.is_finite() && z_far > camera.near) {
            bail!("--z-far {z_far}: must be a number larger than the near plane ({})", camera.near);
        }
        camera.z_far = z_far;
    }
    Ok(camera)
}

/// Settings, scene, lights, camera and a renderer for the frame arguments.
pub fn setup(
    scene_args: &SceneArgs,
    frame: &FrameArgs,
) -> Result<(GpuContext, Renderer, Scene, Vec<PointLight>, Camera)> {
    let tonemap = match frame.tonemap.as_str() {
        "aces" => ToneMap::Aces,
        "reinhard" => ToneMap::Reinhard,
        "linear" => ToneMap::Linear,
        other => bail!("--tonemap '{other}': choose aces, reinhard or linear"),
    };
    let source = match frame.vpl_source.as_str() {
        "auto" => shadowlab_core::technique::registry::preferred_vpl_source(&frame.indirect).unwrap_or_default(),
        other => VplSource::parse(other)
            .ok_or_else(|| anyhow!("--vpl-source '{other}': choose {} or auto", VplSource::NAMES.join(", ")))?,
    };
    let component = Component::parse(&frame.component)
        .ok_or_else(|| anyhow!("--component '{}': choose {}", frame.component, Component::NAMES.join(", ")))?;
    check_indirect(&frame.indirect)?;
    let settings = RenderSettings {
        width: frame.width,
        height: frame.height,
        exposure: frame.exposure,
        auto_exposure: if frame.auto_exposure { AutoExposure::Meter } else { AutoExposure::Off },
        tonemap,
        specular: frame.specular,
        vpl: VplSettings {
            count: frame.vpls,
            source,
            bounces: frame.bounces,
            clamp_world: frame.vpl_clamp,
            seed: frame.vpl_seed,
        },
        component,
        indirect_gain: frame.indirect_gain,
        light_tiles: !frame.no_light_tiles,
        receiver_culling: !frame.no_receiver_culling,
        ..Default::default()
    };
    settings.validate()?;
    if frame.vpls == 0 && frame.indirect != "none" && !frame.quiet {
        eprintln!("note: --vpls 0: the VPL techniques add no indirect light");
    }
    if frame.warmup > 20 || frame.repeat > 1000 {
        bail!("--warmup {} / --repeat {}: at most 20 warm-up and 1000 measured frames", frame.warmup, frame.repeat);
    }
    let load_start = Instant::now();
    let (scene, lights) = load_scene(scene_args)?;
    let camera = camera_from_args(&scene, frame)?;
    if !frame.quiet {
        eprintln!(
            "{}: {} triangles, {} lights, loaded in {:.2} s",
            scene.name,
            scene.triangle_count(),
            lights.len(),
            load_start.elapsed().as_secs_f32()
        );
    }
    let gpu = GpuContext::headless()?;
    let renderer = Renderer::new(&gpu, &scene, settings)?;
    Ok((gpu, renderer, scene, lights, camera))
}

/// Draw the overlay layers of the technique and the indirect technique over the last frame: the layers
/// named in `names`, or those shown by default when it is empty.
pub fn draw_overlays(
    renderer: &mut Renderer,
    technique: &dyn Technique,
    camera: &Camera,
    lights: &[PointLight],
    names: &[String],
) -> Result<()> {
    let mut layers = technique.overlays(lights);
    if let Some(i) = renderer.indirect() {
        layers.extend(i.overlays(lights));
    }
    // The suns, which the renderer shades for every technique (the app offers the same layer).
    if !renderer.directional_lights().is_empty() {
        layers.push(technique::sun_overlays(renderer.directional_lights(), &renderer.scene().bounds));
    }
    for name in names {
        if !layers.iter().any(|l| l.name == name) {
            bail!(
                "--overlay-layer '{name}': the techniques have the layers {}",
                layers.iter().map(|l| format!("'{}'", l.name)).collect::<Vec<_>>().join(", ")
            );
        }
    }
    let primitives: Vec<technique::Overlay> = layers
        .into_iter()
        .filter(|l| if names.is_empty() { l.visible_by_default } else { names.iter().any(|n| n == l.name) })
        .flat_map(|l| l.primitives)
        .collect();
    Ok(renderer.draw_overlays(camera, &primitives, false)?)
}
