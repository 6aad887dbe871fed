//! The headless command line: `shadowlab render`, `shadowlab info`.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use glam::Vec3;
use serde::Serialize;
use shadowlab_core::renderer::Component;
use shadowlab_core::scene::layout::{self, LightLayout};
use shadowlab_core::scene::{Camera, PointLight, Scene};
use shadowlab_core::technique::{self, Technique};
use shadowlab_core::vpl::{VplSettings, VplSource};
use shadowlab_core::{AutoExposure, FrameReport, GpuContext, RenderSettings, Renderer, ToneMap};

use crate::files::{check_output_path, encode_png, write_atomic};
use crate::measure::apply_params;

#[derive(Parser, Debug)]
#[command(
    name = "shadowlab",
    version,
    about = "See and measure how many-light shadow techniques trade quality for speed"
)]
#[command(args_conflicts_with_subcommands = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Open this scene file (.ron) or model (.obj, .gltf, .glb) in the app.
    pub path: Option<PathBuf>,
    /// App: start with this technique (e.g. lightcluster).
    #[arg(long = "app-technique", value_name = "KEY")]
    pub app_technique: Option<String>,
    /// App: start in this view: single, side, split or difference.
    #[arg(long = "app-view", value_name = "VIEW")]
    pub app_view: Option<String>,
    /// App: start on this built-in scene (cornell, arcade, restaurant).
    #[arg(long = "app-scene", value_name = "NAME")]
    pub app_scene: Option<String>,
    /// App: start with this indirect technique (vpl-shadowmaps, vpl-raytraced, vpl-unshadowed, val, pathtraced).
    #[arg(long = "app-indirect", value_name = "KEY")]
    pub app_indirect: Option<String>,
    /// App: save a screenshot of the window to this PNG when quitting (with --quit-after).
    #[arg(long, hide = true)]
    pub screenshot: Option<PathBuf>,
    /// App: quit after this many seconds (smoke tests, README pictures).
    #[arg(long, hide = true)]
    pub quit_after: Option<f32>,
    /// App: window size in points, `WIDTHxHEIGHT` (default 1400x860; 1024x640 on a software rasterizer).
    #[arg(long = "window-size", value_name = "WxH")]
    pub window_size: Option<String>,
    /// App: orbit the camera continuously (UI frame-rate measurement).
    #[arg(long, hide = true)]
    pub orbit_demo: bool,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene with a technique to a PNG, with a JSON frame report.
    Render(RenderArgs),
    /// Render a technique and a comparison target; write the difference image and the error metrics.
    Compare(CompareArgs),
    /// Render a technique for every combination of parameter values, compared with the reference; CSV rows.
    Sweep(SweepArgs),
    /// The standard suite: every technique on the built-in scenes (and the shared real scenes when present),
    /// timed in one run, compared with the reference; writes a Markdown table.
    Bench(BenchArgs),
    /// Print a scene's statistics (triangles, materials, lights, bounds) and the GPU adapter.
    Info(SceneArgs),
    /// Move the lights in small steps over a number of frames and measure the flicker: the mean
    /// frame-to-frame change of the chosen component (and the technique's figures per frame); CSV rows.
    Animate(AnimateArgs),
    /// Render an image sequence, every frame complete: the camera orbiting its target once, or the lights
    /// moving by a step a frame; numbered PNGs in a folder and, with `--gif`, one looping animated GIF.
    Sequence(SequenceArgs),
}

#[derive(Args, Debug)]
pub struct SequenceArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    #[arg(long, default_value = "reference")]
    pub technique: String,
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// Frames of the sequence.
    #[arg(long, default_value_t = 36)]
    pub frames: u32,
    #[arg(long, value_enum, default_value = "orbit")]
    pub motion: crate::sequence::Motion,
    /// With `--motion lights`: the move of every light per frame, `DX,DY,DZ` in world units.
    #[arg(long, value_name = "DX,DY,DZ", default_value = "0.02,0,0")]
    pub step: String,
    /// Folder for `frame-0000.png`, `frame-0001.png`, ... (created when missing).
    #[arg(long)]
    pub out_dir: PathBuf,
    /// Also write the frames as one looping animated GIF.
    #[arg(long)]
    pub gif: Option<PathBuf>,
    /// How long the GIF shows each frame, in milliseconds (GIF counts hundredths of a second).
    #[arg(long, default_value_t = 80)]
    pub frame_ms: u32,
    /// Draw the overlay layers the techniques show by default over every frame; `--overlay-layer NAME` picks
    /// layers by name instead (repeatable).
    #[arg(long)]
    pub overlays: bool,
    #[arg(long = "overlay-layer", value_name = "NAME")]
    pub overlay_layers: Vec<String>,
}

#[derive(Args, Debug)]
pub struct AnimateArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    #[arg(long, default_value = "reference")]
    pub technique: String,
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// Frames rendered; the lights move by `--step` between frames.
    #[arg(long, default_value_t = 30)]
    pub frames: u32,
    /// The move of every light per frame, `DX,DY,DZ` in world units.
    #[arg(long, value_name = "DX,DY,DZ", default_value = "0.02,0,0")]
    pub step: String,
    /// One row per frame (CSV).
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    #[arg(long, default_value_t = 360)]
    pub height: u32,
    #[arg(long, default_value_t = 512)]
    pub shadow_res: u32,
    #[arg(long, default_value_t = 1)]
    pub warmup: u32,
    #[arg(long, default_value_t = 3)]
    pub repeat: u32,
    /// Folder of the shared real scenes (dabrovic-sponza, conference); skipped when absent.
    #[arg(long, default_value = "../shared/scenes")]
    pub scenes: PathBuf,
    /// Only the built-in scenes.
    #[arg(long)]
    pub builtin_only: bool,
    /// Markdown table output.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug, Clone)]
pub struct SceneArgs {
    /// A built-in scene (cornell, arcade, restaurant) or a .obj/.gltf/.glb file.
    #[arg(long, default_value = "arcade")]
    pub scene: String,
    /// Unit scale applied to a scene file's positions (the conference room is in centimetres: 0.01).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f32,
    /// Lights: `scene` (from the scene), `paper` (the scene's paper layout), `random:COUNT:L_ATT[:SEED]`,
    /// `circles:CIRCLES:PER_CIRCLE:L_ATT`, `grid:NXxNY:L_ATT`.
    #[arg(long, default_value = "scene")]
    pub lights: String,
}

/// Image size, camera and shading settings shared by `render`, `compare` and `sweep`.
#[derive(Args, Debug, Clone)]
pub struct FrameArgs {
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    #[arg(long, default_value_t = 360)]
    pub height: u32,
    /// Texels per cube-map face (the technique's `shadow_res` parameter).
    #[arg(long)]
    pub shadow_res: Option<u32>,
    /// Camera `EX,EY,EZ,TX,TY,TZ` (eye and target); the scene's camera when absent.
    #[arg(long, value_name = "EX,EY,EZ,TX,TY,TZ")]
    pub camera: Option<String>,
    /// Vertical field of view in degrees.
    #[arg(long)]
    pub fov: Option<f32>,
    /// Far plane (`z_far`).
    #[arg(long)]
    pub z_far: Option<f32>,
    /// Exposure (a compensation with --auto-exposure).
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// Scale the exposure so the image's log-average luminance lands on middle grey (the app's default; off
    /// here so renders of one scene stay comparable).
    #[arg(long)]
    pub auto_exposure: bool,
    /// Tone mapping: aces, reinhard or linear.
    #[arg(long, default_value = "aces")]
    pub tonemap: String,
    /// Blinn-Phong specular on top of Lambert.
    #[arg(long)]
    pub specular: bool,
    /// Frames rendered and thrown away before the measured ones (the first frame also compiles pipelines).
    #[arg(long, default_value_t = 1)]
    pub warmup: u32,
    /// Measured frames; timings report the median, the minimum and the mean of the 3 fastest.
    #[arg(long, default_value_t = 1)]
    pub repeat: u32,
    /// No progress output.
    #[arg(long)]
    pub quiet: bool,
    /// Indirect technique added to the direct one: none, vpl-shadowmaps, vpl-raytraced, vpl-unshadowed,
    /// pathtraced.
    #[arg(long, default_value = "none")]
    pub indirect: String,
    /// A parameter of the indirect technique, `key=value` (in `sweep`: `key=VALUES` like `--param`); repeatable.
    #[arg(long = "indirect-param", value_name = "KEY=VALUE")]
    pub indirect_params: Vec<String>,
    /// VPLs (RSM texels or traced particles) shared by every VPL technique; 0 = no indirect light.
    #[arg(long, default_value_t = 1024)]
    pub vpls: u32,
    /// Where VPLs come from: rsm (reflective shadow maps), traced (particles through the BVH) or auto (the
    /// indirect technique's paper's choice: traced for fuzzy, else rsm).
    #[arg(long, default_value = "auto")]
    pub vpl_source: String,
    /// Bounces of traced particles (the rsm source is one bounce).
    #[arg(long, default_value_t = 1)]
    pub bounces: u32,
    /// d_clamp of the VPL gathers in world units: 1/d^2 is clamped to 1/d_clamp^2.
    #[arg(long, default_value_t = 0.1)]
    pub vpl_clamp: f32,
    /// Seed of the VPLs' quasi-random sequence.
    #[arg(long, default_value_t = 0)]
    pub vpl_seed: u32,
    /// What images, metrics and difference images show: total, direct or indirect.
    #[arg(long, default_value = "total")]
    pub component: String,
    /// Display gain of the indirect component in saved images (metrics never use it).
    #[arg(long, default_value_t = 1.0)]
    pub indirect_gain: f32,
    /// Loop every shading pass over all the lights of its batch instead of its 16x16 tile's list (the image
    /// is the same; for measuring what the tiled light lists save).
    #[arg(long)]
    pub no_light_tiles: bool,
}

impl FrameArgs {
    /// The indirect technique of the technique side.
    pub fn indirect_choice(&self) -> crate::measure::IndirectChoice {
        crate::measure::IndirectChoice { key: self.indirect.clone(), params: self.indirect_params.clone() }
    }
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Technique key (reference, lightcluster, unshadowed, ...).
    #[arg(long, default_value = "reference")]
    pub technique: String,
    /// A technique parameter, `key=value`; repeatable.
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// Output PNG.
    #[arg(long)]
    pub out: PathBuf,
    /// Frame report as JSON.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Draw the overlay layers the techniques show by default (lights, clusters, VPLs, ...) over the image;
    /// `--overlay-layer NAME` picks layers by name instead (repeatable).
    #[arg(long)]
    pub overlays: bool,
    #[arg(long = "overlay-layer", value_name = "NAME")]
    pub overlay_layers: Vec<String>,
    /// Save the technique's shadow-map atlas (near white, far black) as this PNG, the indirect
    /// technique's as `<name>-indirect.png` (the last batch when a frame had several), and other depth
    /// images the technique renders (INSM's intermediate images) as `<name>-images.png`.
    #[arg(long)]
    pub maps_out: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    #[arg(long, default_value = "lightcluster")]
    pub technique: String,
    /// A technique parameter, `key=value`; repeatable.
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// What to compare against: `reference` (cube map per light) or another technique such as `raytraced`.
    #[arg(long, default_value = "reference")]
    pub against: String,
    /// A parameter of the comparison target, `key=value`; repeatable.
    #[arg(long = "against-param", value_name = "KEY=VALUE")]
    pub against_params: Vec<String>,
    /// The comparison target's indirect technique (default: the same as `--indirect`).
    #[arg(long = "against-indirect", value_name = "KEY")]
    pub against_indirect: Option<String>,
    /// A parameter of the target's indirect technique, `key=value`; repeatable.
    #[arg(long = "against-indirect-param", value_name = "KEY=VALUE")]
    pub against_indirect_params: Vec<String>,
    /// Difference image mode.
    #[arg(long, value_enum, default_value = "absolute")]
    pub mode: crate::measure::DiffKind,
    /// Gain of the difference image (1, 5, 10, ...).
    #[arg(long, default_value_t = 1.0)]
    pub gain: f32,
    /// Skip the FLIP metric (the slowest one).
    #[arg(long)]
    pub no_flip: bool,
    /// Difference image (PNG).
    #[arg(long)]
    pub out: PathBuf,
    /// The technique's own image (PNG).
    #[arg(long)]
    pub image: Option<PathBuf>,
    /// A paper-style figure (PNG): the technique, the target and the difference side by side, with captions.
    #[arg(long)]
    pub figure: Option<PathBuf>,
    /// Metrics and timings as JSON.
    #[arg(long)]
    pub report: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct SweepArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    #[arg(long, default_value = "lightcluster")]
    pub technique: String,
    /// A swept parameter: `key=START:END:STEP`, `key=v1,v2,...` or `key=value`; repeatable (all combinations).
    /// `lights=N1,N2,...` sweeps the number of lights of a `--lights random:...` layout (put it first to plot
    /// time against the light count, the comparison target's time included).
    #[arg(long = "param", value_name = "KEY=VALUES")]
    pub params: Vec<String>,
    #[arg(long, default_value = "reference")]
    pub against: String,
    #[arg(long = "against-param", value_name = "KEY=VALUE")]
    pub against_params: Vec<String>,
    /// The comparison target's indirect technique (default: the same as `--indirect`).
    #[arg(long = "against-indirect", value_name = "KEY")]
    pub against_indirect: Option<String>,
    /// A parameter of the target's indirect technique, `key=value`; repeatable.
    #[arg(long = "against-indirect-param", value_name = "KEY=VALUE")]
    pub against_indirect_params: Vec<String>,
    /// Skip the FLIP metric.
    #[arg(long)]
    pub no_flip: bool,
    /// One row per setting (CSV).
    #[arg(long)]
    pub out: PathBuf,
    /// The same rows as a Markdown table.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    /// A PNG plot of time and RMSE against the first swept (numeric) parameter.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

pub fn run(command: Command) -> Result<()> {
    match command {
        Command::Render(args) => render(args),
        Command::Compare(args) => compare(args),
        Command::Sweep(args) => sweep(args),
        Command::Bench(args) => bench(args),
        Command::Info(args) => info(args),
        Command::Animate(args) => animate(args),
        Command::Sequence(args) => sequence(args),
    }
}

/// Load the scene and its lights as the arguments say.
pub fn load_scene(args: &SceneArgs) -> Result<(Scene, Vec<PointLight>)> {
    let scene = Scene::load_any(&args.scene, args.scale)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let mut layout: LightLayout = layout::parse(&args.lights)?;
    if layout == LightLayout::Scene && scene.lights.is_empty() {
        layout = layout::default_for_unlit(&scene);
        eprintln!("note: {} has no lights; using --lights {layout} (give --lights to choose)", scene.name);
    }
    let lights = layout::generate(&layout, &scene)?;
    Ok((scene, lights))
}

fn parse_vec3s(text: &str) -> Result<(Vec3, Vec3)> {
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

fn camera_from_args(scene: &Scene, args: &FrameArgs) -> Result<Camera> {
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

#[derive(Serialize)]
struct RenderReport<'a> {
    adapter: String,
    scene: &'a str,
    scene_triangles: usize,
    scale: f32,
    lights: &'a str,
    technique: &'a str,
    parameters: std::collections::BTreeMap<String, String>,
    width: u32,
    height: u32,
    camera: Camera,
    frame: &'a FrameReport,
    timing: &'a crate::measure::TimingSummary,
}

/// Progress on stderr: a rewritten line on a terminal, a line per 10% otherwise.
pub struct Progress {
    label: String,
    unit: &'static str,
    tty: bool,
    last_decile: usize,
    started: Instant,
    quiet: bool,
}

impl Progress {
    pub fn new(label: &str, quiet: bool) -> Progress {
        Progress {
            label: label.into(),
            unit: "batch",
            tty: std::io::stderr().is_terminal(),
            last_decile: usize::MAX,
            started: Instant::now(),
            quiet,
        }
    }
    /// Count `unit`s instead of batches.
    pub fn with_unit(mut self, unit: &'static str) -> Progress {
        self.unit = unit;
        self
    }

    pub fn update(&mut self, done: usize, total: usize) {
        if self.quiet || total == 0 {
            return;
        }
        let secs = self.started.elapsed().as_secs_f32();
        if self.tty {
            let width = 30;
            let filled = done * width / total;
            eprint!(
                "\r{}: [{}{}] {} {done}/{total} ({secs:.1} s)",
                self.label,
                "#".repeat(filled),
                "-".repeat(width - filled),
                self.unit
            );
            if done == total {
                eprintln!();
            }
            let _ = std::io::stderr().flush();
        } else {
            let decile = done * 10 / total;
            if decile != self.last_decile {
                self.last_decile = decile;
                eprintln!("{}: {} {done}/{total} ({secs:.1} s)", self.label, self.unit);
            }
        }
    }
}

/// Settings, scene, lights, camera and a renderer for the frame arguments.
fn setup(scene_args: &SceneArgs, frame: &FrameArgs) -> Result<(GpuContext, Renderer, Scene, Vec<PointLight>, Camera)> {
    let tonemap = match frame.tonemap.as_str() {
        "aces" => ToneMap::Aces,
        "reinhard" => ToneMap::Reinhard,
        "linear" => ToneMap::Linear,
        other => bail!("--tonemap '{other}': choose aces, reinhard or linear"),
    };
    let source = match frame.vpl_source.as_str() {
        "auto" => shadowlab_core::technique::preferred_vpl_source(&frame.indirect).unwrap_or_default(),
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

/// `none` or a key of the indirect registry.
pub fn check_indirect(key: &str) -> Result<()> {
    if key != "none" && technique::INDIRECT_REGISTRY.iter().all(|e| e.key != key) {
        bail!("unknown indirect technique '{key}' (choose none or one of: {})", technique::indirect_keys());
    }
    Ok(())
}

fn check_technique(key: &str) -> Result<()> {
    if technique::REGISTRY.iter().all(|e| e.key != key) {
        bail!("unknown technique '{key}' (choose one of: {})", technique::keys());
    }
    Ok(())
}

fn render(args: RenderArgs) -> Result<()> {
    check_output_path(&args.out, "png")?;
    if let Some(m) = &args.maps_out {
        check_output_path(m, "png")?;
    }
    if let Some(r) = &args.report {
        check_output_path(r, "json")?;
    }
    check_technique(&args.technique)?;
    let (gpu, mut renderer, scene, lights, camera) = setup(&args.scene, &args.frame)?;
    let frame = &args.frame;
    let mut technique =
        renderer.create_technique(&args.technique).ok_or_else(|| anyhow!("unknown technique '{}'", args.technique))?;
    apply_params(technique.as_mut(), frame.shadow_res, &args.params)?;
    crate::measure::apply_indirect(&mut renderer, &frame.indirect_choice())?;

    let mut reports = Vec::new();
    let total = frame.warmup + frame.repeat.max(1);
    for i in 0..total {
        let label = if i < frame.warmup {
            format!("warm-up {}/{}", i + 1, frame.warmup)
        } else {
            format!("{} / {} {}/{}", scene.name, technique.key(), i + 1 - frame.warmup, frame.repeat.max(1))
        };
        let mut progress = Progress::new(&label, frame.quiet);
        let r = renderer.render_frame(technique.as_mut(), &camera, &lights, &mut |d, t| progress.update(d, t))?;
        if i >= frame.warmup {
            reports.push(r);
        }
    }
    let timing = crate::measure::summarize(&reports);
    let report = reports.pop().expect("at least one measured frame");
    if let Some(path) = &args.maps_out {
        let mut wrote = 0;
        if let Some((atlas, what)) = technique.shadow_atlas() {
            let img = shadowlab_core::renderer::readback::depth_atlas_image(renderer.gpu(), atlas)?;
            write_atomic(path, &encode_png(&img)?)?;
            wrote += 1;
            if !frame.quiet {
                eprintln!("wrote {} ({what}, {} tiles of {}²)", path.display(), atlas.tiles, atlas.resolution);
            }
        }
        if let Some((atlas, what)) = renderer.indirect().and_then(|t| t.shadow_atlas()) {
            let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("maps");
            let indirect_path = path.with_file_name(format!("{stem}-indirect.png"));
            let img = shadowlab_core::renderer::readback::depth_atlas_image(renderer.gpu(), atlas)?;
            write_atomic(&indirect_path, &encode_png(&img)?)?;
            wrote += 1;
            if !frame.quiet {
                eprintln!("wrote {} ({what}, {} tiles of {}²)", indirect_path.display(), atlas.tiles, atlas.resolution);
            }
        }
        // Other depth images the technique rendered (INSM's intermediate images): `<name>-images.png`.
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("maps").to_string();
        let images = technique.depth_images();
        for (i, (atlas, what)) in images.iter().enumerate() {
            let suffix = if images.len() == 1 { String::new() } else { format!("-{i}") };
            let images_path = path.with_file_name(format!("{stem}-images{suffix}.png"));
            let img = shadowlab_core::renderer::readback::depth_atlas_image(renderer.gpu(), atlas)?;
            write_atomic(&images_path, &encode_png(&img)?)?;
            wrote += 1;
            if !frame.quiet {
                eprintln!("wrote {} ({what}, {} tiles of {}²)", images_path.display(), atlas.tiles, atlas.resolution);
            }
        }
        if wrote == 0 {
            bail!("--maps-out: neither '{}' nor the indirect technique renders shadow maps", args.technique);
        }
    }
    if args.overlays || !args.overlay_layers.is_empty() {
        draw_overlays(&mut renderer, technique.as_ref(), &camera, &lights, &args.overlay_layers)?;
    }
    write_atomic(&args.out, &encode_png(&renderer.read_output()?)?)?;

    if !frame.quiet {
        eprintln!(
            "{}x{} on {}: {:.1} ms GPU ({:?}), {:.0} ms wall; {} of {} lights visible, {} shadow maps in {} batches; \
             {} shadow triangles drawn, {} culled",
            report.width,
            report.height,
            gpu.adapter_description(),
            report.gpu_total_ms,
            report.timing_source,
            report.wall_ms,
            report.counts.technique.lights_visible,
            report.counts.lights_total,
            report.counts.technique.shadow_maps,
            report.counts.technique.batches,
            report.counts.technique.shadow_triangles_submitted,
            report.counts.technique.shadow_triangles_culled,
        );
        if let Some(c) = report.counts.technique.clusters {
            eprintln!(
                "  {c} clusters{}",
                if report.counts.technique.fell_back_to_reference { " (= visible lights: reference path)" } else { "" }
            );
        }
        for p in &report.passes {
            eprintln!("  {:<14} {:>10.2} ms  ({} passes)", p.name, p.ms, p.count);
        }
        for p in &report.cpu_stages {
            eprintln!("  {:<14} {:>10.3} ms  (CPU)", p.name, p.ms);
        }
        if let Some((scale, average)) = renderer.auto_exposure()? {
            eprintln!(
                "  auto exposure: log-average luminance {average:.4}, scale x{scale:.3} (times --exposure {})",
                frame.exposure
            );
        }
        if timing.frames > 1 {
            eprintln!(
                "  {} frames: median {:.2} ms, min {:.2} ms, mean of 3 best {:.2} ms",
                timing.frames, timing.median_ms, timing.min_ms, timing.best3_mean_ms
            );
        }
        eprintln!("wrote {}", args.out.display());
    }
    if let Some(path) = &args.report {
        let parameters = technique.params().into_iter().map(|p| (p.key.to_string(), p.value.to_string())).collect();
        let r = RenderReport {
            adapter: gpu.adapter_description(),
            scene: &args.scene.scene,
            scene_triangles: scene.triangle_count(),
            scale: args.scene.scale,
            lights: &args.scene.lights,
            technique: technique.key(),
            parameters,
            width: report.width,
            height: report.height,
            camera,
            frame: &report,
            timing: &timing,
        };
        write_atomic(path, serde_json::to_string_pretty(&r)?.as_bytes())?;
        if !frame.quiet {
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
}

#[derive(Serialize)]
struct CompareReport<'a> {
    adapter: String,
    scene: &'a str,
    lights: usize,
    width: u32,
    height: u32,
    technique: &'a str,
    technique_parameters: &'a std::collections::BTreeMap<String, String>,
    against: &'a str,
    against_parameters: &'a std::collections::BTreeMap<String, String>,
    metrics: &'a shadowlab_core::compare::Metrics,
    technique_timing: &'a crate::measure::TimingSummary,
    against_timing: &'a crate::measure::TimingSummary,
    /// Same-run speedup of the technique over the comparison target (median frame times).
    speedup: f64,
    technique_counts: &'a shadowlab_core::renderer::FrameCounts,
    /// The component the metrics were computed on.
    component: &'a str,
    indirect: &'a crate::measure::IndirectChoice,
    against_indirect: &'a crate::measure::IndirectChoice,
    /// VPLs the technique side used (absent without an indirect technique).
    vpls: Option<usize>,
    technique_indirect: Option<&'a shadowlab_core::renderer::IndirectReport>,
    against_report_indirect: Option<&'a shadowlab_core::renderer::IndirectReport>,
}

/// The target's indirect technique: `--against-indirect` (with its parameters) or the technique side's.
fn against_indirect(
    key: &Option<String>,
    params: &[String],
    same: &crate::measure::IndirectChoice,
) -> Result<crate::measure::IndirectChoice> {
    match key {
        Some(k) => {
            check_indirect(k)?;
            Ok(crate::measure::IndirectChoice { key: k.clone(), params: params.to_vec() })
        }
        None if params.is_empty() => Ok(same.clone()),
        None => bail!("--against-indirect-param needs --against-indirect"),
    }
}

fn compare(args: CompareArgs) -> Result<()> {
    check_output_path(&args.out, "png")?;
    if let Some(r) = &args.report {
        check_output_path(r, "json")?;
    }
    if let Some(r) = &args.image {
        check_output_path(r, "png")?;
    }
    if let Some(r) = &args.figure {
        check_output_path(r, "png")?;
    }
    check_technique(&args.technique)?;
    check_technique(&args.against)?;
    if !(args.gain.is_finite() && args.gain > 0.0) {
        bail!("--gain {}: must be a number > 0", args.gain);
    }
    let (gpu, mut renderer, scene, lights, camera) = setup(&args.scene, &args.frame)?;
    let f = &args.frame;
    let quiet = f.quiet;
    let mut say = |m: &str| {
        if !quiet {
            eprintln!("{m}");
        }
    };
    let indirect = f.indirect_choice();
    let against_indirect = against_indirect(&args.against_indirect, &args.against_indirect_params, &indirect)?;
    let target = crate::measure::render_technique(
        &mut renderer,
        &args.against,
        f.shadow_res,
        &args.against_params,
        &camera,
        &lights,
        &against_indirect,
        f.warmup,
        f.repeat,
        &mut say,
    )?;
    let target_image = args.figure.as_ref().map(|_| renderer.read_output()).transpose()?;
    let tech = crate::measure::render_technique(
        &mut renderer,
        &args.technique,
        f.shadow_res,
        &args.params,
        &camera,
        &lights,
        &indirect,
        f.warmup,
        f.repeat,
        &mut say,
    )?;
    let tech_image = renderer.read_output()?;
    if let Some(path) = &args.image {
        write_atomic(path, &encode_png(&tech_image)?)?;
    }
    let inputs = crate::measure::compare_inputs(&mut renderer, &camera, &lights)?;
    let (metrics, diff) = crate::measure::compare_images(
        &tech.image,
        &target.image,
        &inputs,
        args.mode,
        args.gain,
        !args.no_flip,
        f.exposure,
    )?;
    let speedup = target.timing.median_ms / tech.timing.median_ms.max(1e-9);
    if let (Some(path), Some(target_image)) = (&args.figure, target_image) {
        use crate::figure::{compose, metrics_caption, FigurePane};
        let metrics_lines = metrics_caption(&metrics);
        let params = |p: &[String]| if p.is_empty() { "default parameters".to_string() } else { p.join(" ") };
        let title = format!(
            "{} · {} lights · {}x{} · {}",
            scene.name,
            lights.len(),
            f.width,
            f.height,
            gpu.adapter_description()
        );
        let figure = compose(
            &title,
            &[
                FigurePane {
                    image: tech_image,
                    caption: vec![
                        args.technique.clone(),
                        params(&args.params),
                        format!("{:.1} ms (median of {}), ×{speedup:.2}", tech.timing.median_ms, tech.timing.frames),
                    ],
                },
                FigurePane {
                    image: target_image,
                    caption: vec![
                        args.against.clone(),
                        params(&args.against_params),
                        format!("{:.1} ms (median of {})", target.timing.median_ms, target.timing.frames),
                    ],
                },
                FigurePane {
                    image: diff.clone(),
                    caption: vec![
                        format!("{:?} difference ×{}", args.mode, args.gain).to_lowercase(),
                        metrics_lines[0].clone(),
                        metrics_lines[1].clone(),
                    ],
                },
            ],
        )?;
        write_atomic(path, &encode_png(&figure)?)?;
    }
    write_atomic(&args.out, &encode_png(&diff)?)?;
    if !quiet {
        eprintln!(
            "{} vs {} on {} ({}x{}): RMSE {:.5}, PSNR {}, FLIP {}, shadow error {}, {:.2}% of pixels over {:.0}%",
            args.technique,
            args.against,
            scene.name,
            f.width,
            f.height,
            metrics.rmse,
            metrics.psnr_db.map(|p| format!("{p:.2} dB")).unwrap_or_else(|| "inf".into()),
            metrics.flip_mean.map(|v| format!("{v:.4}")).unwrap_or_else(|| "-".into()),
            metrics.shadow_intensity_error.map(|v| format!("{:.2}%", v * 100.0)).unwrap_or_else(|| "-".into()),
            metrics.share_over_threshold * 100.0,
            metrics.threshold * 100.0,
        );
        eprintln!(
            "time (median of {}): {} {:.2} ms, {} {:.2} ms, speedup x{:.2}",
            tech.timing.frames, args.technique, tech.timing.median_ms, args.against, target.timing.median_ms, speedup
        );
        eprintln!("wrote {}", args.out.display());
    }
    if let Some(path) = &args.report {
        let r = CompareReport {
            adapter: gpu.adapter_description(),
            scene: &args.scene.scene,
            lights: lights.len(),
            width: f.width,
            height: f.height,
            technique: &args.technique,
            technique_parameters: &tech.parameters,
            against: &args.against,
            against_parameters: &target.parameters,
            metrics: &metrics,
            technique_timing: &tech.timing,
            against_timing: &target.timing,
            speedup,
            technique_counts: &tech.report.counts,
            component: &f.component,
            indirect: &indirect,
            against_indirect: &against_indirect,
            vpls: tech.report.indirect.as_ref().map(|i| i.vpls),
            technique_indirect: tech.report.indirect.as_ref(),
            against_report_indirect: target.report.indirect.as_ref(),
        };
        write_atomic(path, serde_json::to_string_pretty(&r)?.as_bytes())?;
    }
    Ok(())
}

/// The swept pseudo-parameter that changes the number of lights, not a technique parameter.
const LIGHTS_KEY: &str = "lights";

/// Prefix of swept indirect-technique parameters in a sweep setting (`--indirect-param key=VALUES`).
const INDIRECT_PREFIX: &str = "indirect.";

/// A sweep setting's technique parameters as `key=value` (without `lights` and the indirect ones).
fn technique_params(setting: &[(String, String)]) -> Vec<String> {
    setting
        .iter()
        .filter(|(k, _)| k != LIGHTS_KEY && !k.starts_with(INDIRECT_PREFIX))
        .map(|(k, v)| format!("{k}={v}"))
        .collect()
}

/// A sweep setting's indirect technique, its swept parameters included.
fn indirect_for(setting: &[(String, String)], key: &str) -> crate::measure::IndirectChoice {
    crate::measure::IndirectChoice {
        key: key.to_string(),
        params: setting
            .iter()
            .filter_map(|(k, v)| k.strip_prefix(INDIRECT_PREFIX).map(|k| format!("{k}={v}")))
            .collect(),
    }
}

fn sweep(args: SweepArgs) -> Result<()> {
    check_output_path(&args.out, "csv")?;
    if let Some(m) = &args.markdown {
        check_output_path(m, "md")?;
    }
    check_technique(&args.technique)?;
    check_technique(&args.against)?;
    if let Some(p) = &args.plot {
        check_output_path(p, "png")?;
    }
    let mut swept: Vec<(String, Vec<String>)> =
        args.params.iter().map(|p| crate::measure::sweep_values(p)).collect::<Result<_>>()?;
    for p in &args.frame.indirect_params {
        let (k, v) = crate::measure::sweep_values(p)?;
        swept.push((format!("{INDIRECT_PREFIX}{k}"), v));
    }
    if args.frame.indirect == "none" && !args.frame.indirect_params.is_empty() {
        bail!("--indirect-param given without an --indirect technique");
    }
    if swept.is_empty() {
        bail!("sweep needs at least one --param KEY=VALUES (or --indirect-param) to sweep");
    }
    crate::measure::check_combinations(&swept)?;
    let settings = crate::measure::combinations(&swept);
    let (_gpu, mut renderer, scene, lights, camera) = setup(&args.scene, &args.frame)?;
    let f = &args.frame;
    let quiet = f.quiet;
    let no_progress = &mut |_: &str| {};
    // Check every setting before the first (slow) render.
    {
        let mut probe = renderer.create_technique(&args.technique).ok_or_else(|| anyhow!("unknown technique"))?;
        for setting in &settings {
            apply_params(probe.as_mut(), f.shadow_res, &technique_params(setting))?;
            crate::measure::apply_indirect(&mut renderer, &indirect_for(setting, &f.indirect))?;
        }
    }
    let same_indirect = f.indirect_choice();
    let target_indirect = against_indirect(&args.against_indirect, &args.against_indirect_params, &same_indirect)?;
    // `--param lights=N1,N2,...` sweeps the light count of a `random:` layout: the comparison target is rendered
    // again for each count.
    let layout: LightLayout = layout::parse(&args.scene.lights)?;
    let lights_for = |setting: &[(String, String)]| -> Result<Option<Vec<PointLight>>> {
        let Some((_, n)) = setting.iter().find(|(k, _)| k == LIGHTS_KEY) else { return Ok(None) };
        let count: usize = n.parse().map_err(|_| anyhow!("--param lights: '{n}' is not a light count"))?;
        match layout {
            LightLayout::Random { range, seed, .. } => {
                Ok(Some(layout::generate(&LightLayout::Random { count, range, seed }, &scene)?))
            }
            _ => bail!("--param lights needs a random layout (--lights random:COUNT:L_ATT:SEED)"),
        }
    };
    for setting in &settings {
        lights_for(setting)?;
    }
    let render_target = |renderer: &mut Renderer, lights: &[PointLight]| -> Result<_> {
        let target = crate::measure::render_technique(
            renderer,
            &args.against,
            f.shadow_res,
            &args.against_params,
            &camera,
            lights,
            &target_indirect,
            f.warmup,
            f.repeat,
            &mut |_: &str| {},
        )?;
        let inputs = crate::measure::compare_inputs(renderer, &camera, lights)?;
        Ok((target, inputs))
    };
    let mut lights = lights;
    let mut light_count = None;
    if let Some(l) = settings.first().map(|s| lights_for(s)).transpose()?.flatten() {
        light_count = Some(l.len());
        lights = l;
    }
    let (mut target, mut inputs) = render_target(&mut renderer, &lights)?;
    let keys: Vec<&str> = swept.iter().map(|(k, _)| k.as_str()).collect();
    let mut header: Vec<String> = keys.iter().map(|k| k.to_string()).collect();
    header.extend(
        [
            "clusters",
            "visible_lights",
            "shadow_maps",
            "batches",
            "shadow_maps_ms",
            "shading_ms",
            "total_ms",
            "min_ms",
            "against_ms",
            "speedup",
            "rmse",
            "psnr_db",
            "flip",
            "shadow_error",
            "share_over_5pct",
            "fallback",
            "vpls",
            "indirect_ms",
            "wall_ms",
            "against_wall_ms",
            "wall_min_ms",
            "against_wall_min_ms",
            "wall_speedup",
        ]
        .map(String::from),
    );
    if args.plot.is_some() && swept.first().is_none_or(|(_, v)| v.iter().any(|x| x.parse::<f64>().is_err())) {
        bail!("--plot needs a numeric first --param (the x axis)");
    }
    let mut rows: Vec<Vec<String>> = Vec::new();
    // Named figures the techniques report (`vpls`, `samples`, ...), one column each after the fixed ones.
    let mut row_figures: Vec<std::collections::BTreeMap<String, f64>> = Vec::new();
    let mut plot_rows: Vec<crate::plot::PlotRow> = Vec::new();
    let mut progress = Progress::new(&format!("sweep {}", args.technique), quiet).with_unit("setting");
    progress.update(0, settings.len());
    let mut plotted_counts: Vec<usize> = Vec::new();
    for (i, setting) in settings.iter().enumerate() {
        if let Some(l) = lights_for(setting)? {
            if light_count != Some(l.len()) {
                light_count = Some(l.len());
                lights = l;
                (target, inputs) = render_target(&mut renderer, &lights)?;
            }
            // The comparison target's time is a curve of its own when the light count is the x axis.
            if setting[0].0 == LIGHTS_KEY && !plotted_counts.contains(&lights.len()) {
                plotted_counts.push(lights.len());
                plot_rows.push(crate::plot::PlotRow {
                    x: lights.len() as f64,
                    series: format!("{} (against)", args.against),
                    ms: target.timing.median_ms,
                    rmse: None,
                });
            }
        }
        let strings = technique_params(setting);
        let r = crate::measure::render_technique(
            &mut renderer,
            &args.technique,
            f.shadow_res,
            &strings,
            &camera,
            &lights,
            &indirect_for(setting, &f.indirect),
            f.warmup,
            f.repeat,
            no_progress,
        )?;
        let (m, _) = crate::measure::compare_images(
            &r.image,
            &target.image,
            &inputs,
            crate::measure::DiffKind::Absolute,
            1.0,
            !args.no_flip,
            f.exposure,
        )?;
        plot_rows.push(crate::plot::PlotRow {
            x: setting[0].1.parse().unwrap_or(0.0),
            series: setting[1..].iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(" "),
            ms: r.timing.median_ms,
            rmse: Some(m.rmse),
        });
        let c = &r.report.counts.technique;
        let pass = |name: &str| r.timing.passes_median_ms.iter().filter(|p| p.name == name).map(|p| p.ms).sum::<f64>();
        let mut row: Vec<String> = setting.iter().map(|(_, v)| v.clone()).collect();
        row.extend([
            c.clusters.map(|n| n.to_string()).unwrap_or_default(),
            c.lights_visible.to_string(),
            c.shadow_maps.to_string(),
            c.batches.to_string(),
            format!("{:.2}", pass("shadow maps")),
            format!("{:.2}", pass("shading")),
            format!("{:.2}", r.timing.median_ms),
            format!("{:.2}", r.timing.min_ms),
            format!("{:.2}", target.timing.median_ms),
            format!("{:.2}", target.timing.median_ms / r.timing.median_ms.max(1e-9)),
            format!("{:.5}", m.rmse),
            m.psnr_db.map(|p| format!("{p:.2}")).unwrap_or_else(|| "inf".into()),
            m.flip_mean.map(|v| format!("{v:.4}")).unwrap_or_default(),
            m.shadow_intensity_error.map(|v| format!("{:.4}", v)).unwrap_or_default(),
            format!("{:.4}", m.share_over_threshold),
            c.fell_back_to_reference.to_string(),
            r.report.indirect.as_ref().map(|i| i.vpls.to_string()).unwrap_or_default(),
            // The indirect technique's passes, by the renderer's account (whatever their names).
            r.report
                .indirect
                .as_ref()
                .map(|i| format!("{:.2}", i.passes.iter().map(|p| pass(&p.name)).sum::<f64>()))
                .unwrap_or_default(),
            format!("{:.2}", r.timing.wall_median_ms),
            format!("{:.2}", target.timing.wall_median_ms),
            format!("{:.2}", r.timing.wall_min_ms),
            format!("{:.2}", target.timing.wall_min_ms),
            // Of the fastest frames: on a shared machine the least disturbed ones.
            format!("{:.2}", target.timing.wall_min_ms / r.timing.wall_min_ms.max(1e-9)),
        ]);
        rows.push(row);
        let mut figures: std::collections::BTreeMap<String, f64> =
            c.figures.iter().map(|(k, v)| (format!("figure.{k}"), *v)).collect();
        if let Some(ind) = &r.report.indirect {
            figures.extend(ind.counts.figures.iter().map(|(k, v)| (format!("indirect.figure.{k}"), *v)));
            // The indirect technique's own passes and CPU stages, one column each (medians over frames).
            for p in &ind.passes {
                figures.insert(format!("indirect.pass.{}_ms", p.name), pass(&p.name));
            }
        }
        for st in &r.timing.cpu_stages_median_ms {
            figures.insert(format!("cpu.{}_ms", st.name), st.ms);
        }
        row_figures.push(figures);
        progress.update(i + 1, settings.len());
    }
    let figure_keys: std::collections::BTreeSet<&String> = row_figures.iter().flat_map(|f| f.keys()).collect();
    header.extend(figure_keys.iter().map(|k| k.to_string()));
    for (row, figures) in rows.iter_mut().zip(&row_figures) {
        row.extend(figure_keys.iter().map(|k| figures.get(*k).map(|v| v.to_string()).unwrap_or_default()));
    }
    let mut csv = header.join(",") + "\n";
    for row in &rows {
        csv += &(row.join(",") + "\n");
    }
    write_atomic(&args.out, csv.as_bytes())?;
    let mut md = format!("| {} |\n|{}\n", header.join(" | "), "---|".repeat(header.len()));
    for row in &rows {
        md += &format!("| {} |\n", row.join(" | "));
    }
    if !quiet {
        eprintln!(
            "{} on {} ({} lights, {}x{}), against {} at {:.2} ms:",
            args.technique,
            scene.name,
            lights.len(),
            f.width,
            f.height,
            args.against,
            target.timing.median_ms
        );
        eprint!("{md}");
        eprintln!("wrote {}", args.out.display());
    }
    if let Some(path) = &args.markdown {
        write_atomic(path, md.as_bytes())?;
    }
    if let Some(path) = &args.plot {
        // Drawn to a temporary file, then renamed, like every output.
        let tmp = path.with_extension("png.tmp.png");
        let lights_swept = swept[0].0 == LIGHTS_KEY;
        // With indirect techniques the names say both parts (`unshadowed + val`).
        let with = |direct: &str, indirect: &str| {
            if indirect == "none" {
                direct.to_string()
            } else {
                format!("{direct} + {indirect}")
            }
        };
        let technique_name = with(&args.technique, &f.indirect);
        let against_name = with(&args.against, &target_indirect.key);
        let component = if f.component == "total" { String::new() } else { format!(", {} light", f.component) };
        let title = if lights_swept {
            format!("{technique_name} and {against_name} on {} ({}x{}{component})", scene.name, f.width, f.height)
        } else {
            format!("{technique_name} on {} ({} lights, {}x{}{component})", scene.name, lights.len(), f.width, f.height)
        };
        let reference_ms = (!lights_swept).then_some(target.timing.median_ms);
        crate::plot::sweep_plot(&tmp, &title, &swept[0].0, &plot_rows, &against_name, reference_ms)?;
        std::fs::rename(&tmp, path).with_context(|| format!("cannot write {}", path.display()))?;
        if !quiet {
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
}

/// Draw the overlay layers of the technique and the indirect technique over the last frame: the layers
/// named in `names`, or those shown by default when it is empty.
fn draw_overlays(
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

/// `--step DX,DY,DZ`.
fn parse_step(text: &str) -> Result<Vec3> {
    let step: Vec<f32> = text
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow!("--step '{text}': expected DX,DY,DZ"))?;
    match step.as_slice() {
        [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => Ok(Vec3::new(*x, *y, *z)),
        _ => bail!("--step '{text}': expected three finite numbers DX,DY,DZ"),
    }
}

fn sequence(args: SequenceArgs) -> Result<()> {
    let frames = args.frames as usize;
    crate::sequence::check_frames(frames).map_err(|e| anyhow!("--frames {frames}: {e}"))?;
    if let Some(g) = &args.gif {
        check_output_path(g, "gif")?;
    }
    check_technique(&args.technique)?;
    let step = parse_step(&args.step)?;
    if args.out_dir.exists() && !args.out_dir.is_dir() {
        bail!("--out-dir {}: not a folder", args.out_dir.display());
    }
    let (_gpu, mut renderer, scene, lights, camera) = setup(&args.scene, &args.frame)?;
    let f = &args.frame;
    let mut technique =
        renderer.create_technique(&args.technique).ok_or_else(|| anyhow!("unknown technique '{}'", args.technique))?;
    apply_params(technique.as_mut(), f.shadow_res, &args.params)?;
    crate::measure::apply_indirect(&mut renderer, &f.indirect_choice())?;
    std::fs::create_dir_all(&args.out_dir).with_context(|| format!("cannot create {}", args.out_dir.display()))?;
    let target = match &f.camera {
        Some(text) => parse_vec3s(text)?.1,
        None => crate::sequence::orbit_target(&camera, &scene.bounds),
    };
    let mut gif = args.gif.as_deref().map(|g| crate::sequence::GifWriter::new(g, args.frame_ms)).transpose()?;
    let mut gif_secs = 0.0;
    let mut progress = Progress::new(&format!("sequence {}", args.technique), f.quiet).with_unit("frame");
    for i in 0..frames {
        let (camera, moved) = match args.motion {
            crate::sequence::Motion::Orbit => {
                let angle = std::f32::consts::TAU * i as f32 / frames as f32;
                (crate::sequence::orbit_camera(&camera, target, angle), lights.clone())
            }
            crate::sequence::Motion::Lights => {
                let moved = lights.iter().map(|l| PointLight { position: l.position + step * i as f32, ..*l });
                (camera, moved.collect())
            }
        };
        renderer.render_frame(technique.as_mut(), &camera, &moved, &mut |_, _| {})?;
        if args.overlays || !args.overlay_layers.is_empty() {
            draw_overlays(&mut renderer, technique.as_ref(), &camera, &moved, &args.overlay_layers)?;
        }
        let image = renderer.read_output()?;
        write_atomic(&crate::sequence::frame_path(&args.out_dir, i), &encode_png(&image)?)?;
        if let Some(gif) = &mut gif {
            let start = Instant::now();
            gif.add(&image)?;
            gif_secs += start.elapsed().as_secs_f32();
        }
        progress.update(i + 1, frames);
    }
    if let Some(gif) = gif {
        gif.finish()?;
    }
    if !f.quiet {
        eprintln!("wrote {frames} frames in {}", args.out_dir.display());
        if let Some(g) = &args.gif {
            let kib = std::fs::metadata(g).map(|m| m.len() / 1024).unwrap_or(0);
            eprintln!("wrote {} ({frames} frames, {kib} KiB, encoded in {gif_secs:.2} s)", g.display());
        }
    }
    Ok(())
}

fn animate(args: AnimateArgs) -> Result<()> {
    check_output_path(&args.out, "csv")?;
    check_technique(&args.technique)?;
    if args.frames < 2 || args.frames > 1000 {
        bail!("--frames {}: between 2 and 1000", args.frames);
    }
    let step = parse_step(&args.step)?;
    let (_gpu, mut renderer, scene, lights, camera) = setup(&args.scene, &args.frame)?;
    let f = &args.frame;
    let mut technique =
        renderer.create_technique(&args.technique).ok_or_else(|| anyhow!("unknown technique '{}'", args.technique))?;
    apply_params(technique.as_mut(), f.shadow_res, &args.params)?;
    crate::measure::apply_indirect(&mut renderer, &f.indirect_choice())?;
    let mut previous: Option<Vec<[f32; 4]>> = None;
    // Per frame: index, change against the previous frame, mean radiance, figures.
    type FrameRow = (u32, Option<f64>, f64, std::collections::BTreeMap<String, f64>);
    let mut rows: Vec<FrameRow> = Vec::new();
    let mut progress = Progress::new(&format!("animate {}", args.technique), f.quiet).with_unit("frame");
    for i in 0..args.frames {
        let moved: Vec<PointLight> =
            lights.iter().map(|l| PointLight { position: l.position + step * i as f32, ..*l }).collect();
        let report = renderer.render_frame(technique.as_mut(), &camera, &moved, &mut |_, _| {})?;
        let image = renderer.read_hdr()?;
        let mean = image.iter().map(|p| ((p[0] + p[1] + p[2]) / 3.0) as f64).sum::<f64>() / image.len() as f64;
        // Mean absolute change of luminance-like (mean RGB) radiance against the previous frame.
        let change = previous.as_ref().map(|prev| {
            prev.iter()
                .zip(&image)
                .map(|(a, b)| (((a[0] + a[1] + a[2]) - (b[0] + b[1] + b[2])) / 3.0).abs() as f64)
                .sum::<f64>()
                / image.len() as f64
        });
        let mut figures: std::collections::BTreeMap<String, f64> =
            report.counts.technique.figures.iter().map(|(k, v)| (format!("figure.{k}"), *v)).collect();
        if let Some(ind) = &report.indirect {
            figures.extend(ind.counts.figures.iter().map(|(k, v)| (format!("indirect.figure.{k}"), *v)));
        }
        rows.push((i, change, mean, figures));
        previous = Some(image);
        progress.update(i as usize + 1, args.frames as usize);
    }
    let keys: std::collections::BTreeSet<String> = rows.iter().flat_map(|r| r.3.keys().cloned()).collect();
    let mut csv = String::from("frame,mean_change,mean_radiance");
    for k in &keys {
        csv += &format!(",{k}");
    }
    csv += "\n";
    for (i, change, mean, figures) in &rows {
        csv += &format!("{i},{},{mean:.6}", change.map(|c| format!("{c:.6}")).unwrap_or_default());
        for k in &keys {
            csv += &format!(",{}", figures.get(k).map(|v| v.to_string()).unwrap_or_default());
        }
        csv += "\n";
    }
    write_atomic(&args.out, csv.as_bytes())?;
    let changes: Vec<f64> = rows.iter().filter_map(|r| r.1).collect();
    let mean_change = changes.iter().sum::<f64>() / changes.len().max(1) as f64;
    let mean_radiance = rows.iter().map(|r| r.2).sum::<f64>() / rows.len() as f64;
    if !f.quiet {
        eprintln!(
            "{} + {} on {}: mean frame-to-frame change {:.3e} ({:.2} % of the mean {} radiance {:.3e})",
            args.technique,
            f.indirect,
            scene.name,
            mean_change,
            100.0 * mean_change / mean_radiance.max(1e-30),
            f.component,
            mean_radiance
        );
        eprintln!("wrote {}", args.out.display());
    }
    Ok(())
}

/// One scene of the benchmark suite: name, scene arguments, camera.
struct BenchScene {
    name: &'static str,
    scene: SceneArgs,
    camera: Option<&'static str>,
    z_far: Option<f32>,
}

fn bench(args: BenchArgs) -> Result<()> {
    check_output_path(&args.out, "md")?;
    let builtin = |name: &'static str| BenchScene {
        name,
        scene: SceneArgs { scene: name.into(), scale: 1.0, lights: "scene".into() },
        camera: None,
        z_far: None,
    };
    let mut suite = vec![builtin("cornell"), builtin("arcade"), builtin("restaurant")];
    let sponza = args.scenes.join("dabrovic-sponza/sponza.obj");
    let conference = args.scenes.join("conference/conference.obj");
    if !args.builtin_only {
        if sponza.is_file() {
            suite.push(BenchScene {
                name: "sponza",
                scene: SceneArgs { scene: sponza.display().to_string(), scale: 1.0, lights: "paper".into() },
                camera: Some("-14,2.5,0,10,3,0"),
                z_far: Some(30.0),
            });
        } else {
            eprintln!("warning: {} not found: Sponza skipped", sponza.display());
        }
        if conference.is_file() {
            suite.push(BenchScene {
                name: "conference",
                scene: SceneArgs {
                    scene: conference.display().to_string(),
                    scale: 0.01,
                    lights: "random:64:3:1".into(),
                },
                camera: None,
                z_far: None,
            });
        }
    }
    // (technique, parameters) in the order of the table; the reference comes first: the others are compared
    // with it.
    let techniques: [(&str, &[&str]); 5] = [
        ("reference", &[]),
        ("unshadowed", &[]),
        ("lightcluster", &["d_init=0.5", "filter=pcss"]),
        ("lightcluster", &["d_init=0.5", "filter=pcf"]),
        ("raytraced", &[]),
    ];
    let mut md = String::from(
        "| scene | technique | parameters | shadow maps | median ms | min ms | speedup vs reference | RMSE | shadow error |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut adapter = String::new();
    for s in &suite {
        let frame = FrameArgs {
            width: args.width,
            height: args.height,
            shadow_res: Some(args.shadow_res),
            camera: s.camera.map(String::from),
            fov: None,
            z_far: s.z_far,
            exposure: 1.0,
            auto_exposure: false,
            tonemap: "aces".into(),
            specular: false,
            warmup: args.warmup,
            repeat: args.repeat,
            quiet: true,
            indirect: "none".into(),
            indirect_params: Vec::new(),
            vpls: VplSettings::default().count,
            vpl_source: "auto".into(),
            bounces: 1,
            vpl_clamp: VplSettings::default().clamp_world,
            vpl_seed: 0,
            component: "total".into(),
            indirect_gain: 1.0,
            no_light_tiles: false,
        };
        eprintln!("{}: loading", s.name);
        let (gpu, mut renderer, _scene, lights, camera) = setup(&s.scene, &frame)?;
        adapter = gpu.adapter_description();
        let inputs = crate::measure::compare_inputs(&mut renderer, &camera, &lights)?;
        let mut reference: Option<crate::measure::Rendered> = None;
        for (key, params) in techniques {
            eprintln!("{}: {key} {}", s.name, params.join(" "));
            let params: Vec<String> = params.iter().map(|p| p.to_string()).collect();
            let r = crate::measure::render_technique(
                &mut renderer,
                key,
                frame.shadow_res,
                &params,
                &camera,
                &lights,
                &crate::measure::IndirectChoice::none(),
                frame.warmup,
                frame.repeat,
                &mut |_| {},
            )?;
            let (rmse, shadow, speedup) = match &reference {
                Some(reference) => {
                    let (m, _) = crate::measure::compare_images(
                        &r.image,
                        &reference.image,
                        &inputs,
                        crate::measure::DiffKind::Absolute,
                        1.0,
                        false,
                        1.0,
                    )?;
                    (
                        format!("{:.5}", m.rmse),
                        m.shadow_intensity_error.map(|e| format!("{:.2}%", e * 100.0)).unwrap_or_default(),
                        format!("{:.2}", reference.timing.median_ms / r.timing.median_ms.max(1e-9)),
                    )
                }
                None => ("0".into(), "0%".into(), "1.00".into()),
            };
            let c = &r.report.counts.technique;
            md += &format!(
                "| {} | {} | {} | {}{} | {:.1} | {:.1} | {} | {} | {} |\n",
                s.name,
                key,
                params.join(" "),
                c.shadow_maps,
                c.clusters.map(|n| format!(" ({n} clusters)")).unwrap_or_default(),
                r.timing.median_ms,
                r.timing.min_ms,
                speedup,
                rmse,
                shadow
            );
            if reference.is_none() {
                reference = Some(r);
            }
        }
    }
    md += &format!(
        "\n{}x{}, {} texels per cube face, median of {} frames after {} warm-up, on {adapter}.\n",
        args.width, args.height, args.shadow_res, args.repeat, args.warmup
    );
    write_atomic(&args.out, md.as_bytes())?;
    print!("{md}");
    Ok(())
}

fn info(args: SceneArgs) -> Result<()> {
    let (scene, lights) = load_scene(&args)?;
    let b = scene.bounds;
    println!("scene      {}", scene.name);
    println!("triangles  {}", scene.triangle_count());
    println!("meshes     {}", scene.meshes.len());
    println!("materials  {}", scene.materials.len());
    println!("textures   {}", scene.textures.len());
    println!("lights     {}", lights.len());
    println!(
        "bounds     [{:.2}, {:.2}, {:.2}] .. [{:.2}, {:.2}, {:.2}]",
        b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
    );
    match GpuContext::headless() {
        Ok(gpu) => println!("adapter    {}", gpu.adapter_description()),
        Err(e) => println!("adapter    none ({e})"),
    }
    Ok(())
}
