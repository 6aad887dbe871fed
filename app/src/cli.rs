//! The headless command line: `shadowlab render`, `shadowlab info`.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use glam::Vec3;
use serde::Serialize;
use shadowlab_core::scene::layout::{self, LightLayout};
use shadowlab_core::scene::{Camera, PointLight, Scene};
use shadowlab_core::technique::{self, Technique};
use shadowlab_core::{FrameReport, GpuContext, RenderSettings, Renderer, ToneMap};

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
    /// App: save a screenshot of the window to this PNG when quitting (with --quit-after).
    #[arg(long, hide = true)]
    pub screenshot: Option<PathBuf>,
    /// App: quit after this many seconds (smoke tests, README pictures).
    #[arg(long, hide = true)]
    pub quit_after: Option<f32>,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene with a technique to a PNG, with a JSON frame report.
    Render(RenderArgs),
    /// Print a scene's statistics (triangles, materials, lights, bounds) and the GPU adapter.
    Info(SceneArgs),
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

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Technique key (see `--technique help`).
    #[arg(long, default_value = "reference")]
    pub technique: String,
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    #[arg(long, default_value_t = 360)]
    pub height: u32,
    /// Texels per cube-map face (the technique's `shadow_res` parameter).
    #[arg(long)]
    pub shadow_res: Option<u32>,
    /// A technique parameter, `key=value`; repeatable.
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// Camera `EX,EY,EZ,TX,TY,TZ` (eye and target); the scene's camera when absent.
    #[arg(long, value_name = "EX,EY,EZ,TX,TY,TZ")]
    pub camera: Option<String>,
    /// Vertical field of view in degrees.
    #[arg(long)]
    pub fov: Option<f32>,
    /// Far plane (`z_far`).
    #[arg(long)]
    pub z_far: Option<f32>,
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// Tone mapping: aces, reinhard or linear.
    #[arg(long, default_value = "aces")]
    pub tonemap: String,
    /// Blinn-Phong specular on top of Lambert.
    #[arg(long)]
    pub specular: bool,
    /// Output PNG.
    #[arg(long)]
    pub out: PathBuf,
    /// Frame report as JSON.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Frames rendered and thrown away before the measured one (the first frame also compiles pipelines).
    #[arg(long, default_value_t = 1)]
    pub warmup: u32,
    /// No progress output.
    #[arg(long)]
    pub quiet: bool,
}

pub fn run(command: Command) -> Result<()> {
    match command {
        Command::Render(args) => render(args),
        Command::Info(args) => info(args),
    }
}

/// Load the scene and its lights as the arguments say.
pub fn load_scene(args: &SceneArgs) -> Result<(Scene, Vec<PointLight>)> {
    let scene = Scene::load_any(&args.scene, args.scale)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let layout: LightLayout = layout::parse(&args.lights)?;
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

fn camera_from_args(scene: &Scene, args: &RenderArgs) -> Result<Camera> {
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

/// Apply `--shadow-res` and `--param key=value` to a technique.
pub fn apply_params(technique: &mut dyn Technique, shadow_res: Option<u32>, params: &[String]) -> Result<()> {
    let mut all: Vec<(String, String)> = Vec::new();
    if let Some(r) = shadow_res {
        all.push(("shadow_res".into(), r.to_string()));
    }
    for p in params {
        let (k, v) = p.split_once('=').ok_or_else(|| anyhow!("--param '{p}': expected KEY=VALUE"))?;
        all.push((k.trim().to_string(), v.trim().to_string()));
    }
    let specs = technique.params();
    for (key, text) in all {
        let spec = specs.iter().find(|s| s.key == key).ok_or_else(|| {
            anyhow!(
                "technique '{}' has no parameter '{key}' (it has: {})",
                technique.key(),
                specs.iter().map(|s| s.key).collect::<Vec<_>>().join(", ")
            )
        })?;
        let value = spec.kind.parse(&key, &text)?;
        technique.set_param(&key, &value)?;
    }
    Ok(())
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
}

/// Progress on stderr: a rewritten line on a terminal, a line per 10% otherwise.
pub struct Progress {
    label: String,
    tty: bool,
    last_decile: usize,
    started: Instant,
    quiet: bool,
}

impl Progress {
    pub fn new(label: &str, quiet: bool) -> Progress {
        Progress {
            label: label.into(),
            tty: std::io::stderr().is_terminal(),
            last_decile: usize::MAX,
            started: Instant::now(),
            quiet,
        }
    }
    pub fn update(&mut self, done: usize, total: usize) {
        if self.quiet || total == 0 {
            return;
        }
        let secs = self.started.elapsed().as_secs_f32();
        if self.tty {
            eprint!("\r{}: batch {done}/{total} ({secs:.1} s)", self.label);
            if done == total {
                eprintln!();
            }
            let _ = std::io::stderr().flush();
        } else {
            let decile = done * 10 / total;
            if decile != self.last_decile {
                self.last_decile = decile;
                eprintln!("{}: batch {done}/{total} ({secs:.1} s)", self.label);
            }
        }
    }
}

fn check_output_path(path: &Path, ext: &str) -> Result<()> {
    let ok = path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case(ext));
    if !ok {
        bail!("{}: the file name must end in .{ext}", path.display());
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            bail!("{}: the folder {} does not exist", path.display(), dir.display());
        }
    }
    Ok(())
}

/// Write a file atomically: a temporary file beside it, then a rename, so a failure never leaves half a file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension(format!("{}.tmp", path.extension().and_then(|e| e.to_str()).unwrap_or("out")));
    std::fs::write(&tmp, bytes).with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

fn render(args: RenderArgs) -> Result<()> {
    check_output_path(&args.out, "png")?;
    if let Some(r) = &args.report {
        check_output_path(r, "json")?;
    }
    let tonemap = match args.tonemap.as_str() {
        "aces" => ToneMap::Aces,
        "reinhard" => ToneMap::Reinhard,
        "linear" => ToneMap::Linear,
        other => bail!("--tonemap '{other}': choose aces, reinhard or linear"),
    };
    let settings = RenderSettings {
        width: args.width,
        height: args.height,
        exposure: args.exposure,
        tonemap,
        specular: args.specular,
        ..Default::default()
    };
    settings.validate()?;
    if technique::REGISTRY.iter().all(|e| e.key != args.technique) {
        bail!("unknown technique '{}' (choose one of: {})", args.technique, technique::keys());
    }

    let load_start = Instant::now();
    let (scene, lights) = load_scene(&args.scene)?;
    let camera = camera_from_args(&scene, &args)?;
    if !args.quiet {
        eprintln!(
            "{}: {} triangles, {} lights, loaded in {:.2} s",
            scene.name,
            scene.triangle_count(),
            lights.len(),
            load_start.elapsed().as_secs_f32()
        );
    }
    let gpu = GpuContext::headless()?;
    let mut renderer = Renderer::new(&gpu, &scene, settings)?;
    let mut technique =
        renderer.create_technique(&args.technique).ok_or_else(|| anyhow!("unknown technique '{}'", args.technique))?;
    apply_params(technique.as_mut(), args.shadow_res, &args.params)?;

    if args.warmup > 20 {
        bail!("--warmup {}: at most 20 frames", args.warmup);
    }
    for i in 0..args.warmup {
        let mut progress = Progress::new(&format!("warm-up {}/{}", i + 1, args.warmup), args.quiet);
        renderer.render_frame(technique.as_mut(), &camera, &lights, &mut |d, t| progress.update(d, t))?;
    }
    let mut progress = Progress::new(&format!("{} / {}", scene.name, technique.key()), args.quiet);
    let report = renderer.render_frame(technique.as_mut(), &camera, &lights, &mut |d, t| progress.update(d, t))?;
    let image = renderer.read_output()?;
    let mut png = Vec::new();
    image.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).context("cannot encode the PNG")?;
    write_atomic(&args.out, &png)?;

    if !args.quiet {
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
        };
        write_atomic(path, serde_json::to_string_pretty(&r)?.as_bytes())?;
        if !args.quiet {
            eprintln!("wrote {}", path.display());
        }
    }
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
