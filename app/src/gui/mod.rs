//! The interactive app: a 3D view of the scene rendered by the core (progressively, on eframe's device),
//! light editing with picking, a move gizmo and undo/redo, technique selection with generated parameter panels,
//! overlays, side-by-side and split comparison with the reference, live timings, screenshots and scene files.
//! An indirect technique (`INDIRECT_REGISTRY`, none by default) can be added to every view, with its own
//! generated panel, the shared VPL settings and the component (total, direct, indirect) the views show.

pub mod camera;
pub mod capture;
pub mod document;
pub mod gizmo;
pub mod inspector;
pub mod layout;
pub mod legend;
pub mod panels;
pub mod session;
pub mod sweep;
pub mod viewport;

use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{anyhow, Context, Result};
use eframe::{egui, egui_wgpu};
use glam::Vec3;
use shadowlab_core::renderer::overlay::OverlayStyle;
use shadowlab_core::renderer::Component;
use shadowlab_core::scene::{PointLight, Scene, SceneSource};
use shadowlab_core::technique::{LegendEntry, Overlay, OverlayLayer, ParamValue, Technique};
use shadowlab_core::timing::PassTime;
use shadowlab_core::{AutoExposure, GpuContext, RenderSettings};

use camera::{CameraInput, CameraMode};
use document::{SceneFile, ViewMode};
use gizmo::{Handle, Projection};
pub use session::Animation;
use session::{DragTarget, Session};
use viewport::{FrameInputs, StepSizer, View, PREVIEW_TECHNIQUE};

/// What to open at start.
#[derive(Clone, Debug, Default)]
pub struct Startup {
    /// A scene file (.ron) or a model (.obj/.gltf/.glb); the built-in `arcade` when None.
    pub path: Option<PathBuf>,
    /// Where screenshots and recent files go (tests point this at a temp folder).
    pub data_dir: Option<PathBuf>,
    /// Save a screenshot of the whole window to this path after `quit_after_secs` and quit (smoke tests,
    /// README pictures).
    pub screenshot: Option<PathBuf>,
    pub quit_after_secs: Option<f32>,
    /// Finish every frame within one UI frame, whatever it costs (deterministic tests).
    pub synchronous: bool,
    /// Orbit the camera continuously, as a user dragging would (UI frame-rate measurements).
    pub orbit_demo: bool,
    /// Start with this technique key.
    pub technique: Option<String>,
    /// Start in this view: single, side, split or difference.
    pub view: Option<String>,
    /// Start on this built-in scene.
    pub builtin: Option<String>,
    /// Start with this indirect technique key.
    pub indirect: Option<String>,
    /// Window size in points.
    pub window_size: Option<(f32, f32)>,
    /// When the GPU device is lost, start a new ShadowLab on the saved recovery file and close this one
    /// (the binary does; tests only record the command).
    pub relaunch_on_device_loss: bool,
}

/// What the app did when its GPU device was lost.
#[derive(Clone, Debug)]
pub struct Recovery {
    /// Why wgpu says the device was lost.
    pub reason: String,
    /// The scene file the current state was saved to (None when saving failed, with the error in `message`).
    pub file: Option<PathBuf>,
    /// The command that starts a new ShadowLab on it (program, arguments), when it is relaunched.
    pub relaunch: Option<(PathBuf, Vec<String>)>,
    /// What the window says.
    pub message: String,
}

/// Set by a recovered process, so a device lost again is not relaunched in a loop.
const RECOVERED_ENV: &str = "SHADOWLAB_RECOVERED";

/// The device setup ShadowLab asks eframe for: timestamp queries when the adapter has them, and the adapter's
/// texture and buffer limits (cube-map atlases are large).
pub fn wgpu_setup() -> egui_wgpu::WgpuSetup {
    let mut setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    setup.device_descriptor = Arc::new(|adapter| {
        let base = if adapter.get_info().backend == wgpu::Backend::Gl {
            wgpu::Limits::downlevel_webgl2_defaults()
        } else {
            wgpu::Limits::default()
        };
        let a = adapter.limits();
        wgpu::DeviceDescriptor {
            label: Some("shadowlab"),
            required_features: adapter.features() & shadowlab_core::gpu::TIMER_FEATURES,
            required_limits: wgpu::Limits {
                max_texture_dimension_2d: a.max_texture_dimension_2d.max(8192).min(a.max_texture_dimension_2d),
                max_storage_buffer_binding_size: a.max_storage_buffer_binding_size,
                max_buffer_size: a.max_buffer_size,
                max_storage_buffers_per_shader_stage: a.max_storage_buffers_per_shader_stage.min(8),
                ..base
            },
            ..Default::default()
        }
    });
    egui_wgpu::WgpuSetup::CreateNew(setup)
}

/// The window size when none is given: 1400x860, or 1024x640 on a software rasterizer (`software`), where
/// egui's drawing and the presentation of the window cost in proportion to its area (README, "The app").
pub fn default_window_size(software: bool) -> [f32; 2] {
    if software {
        eprintln!("software rasterizer: opening a 1024x640 window (--window-size to choose)");
        [1024.0, 640.0]
    } else {
        [1400.0, 860.0]
    }
}

/// Open the window.
pub fn run(startup: Startup) -> Result<()> {
    let software = shadowlab_core::gpu::GpuContext::default_adapter_is_software() == Some(true);
    let size = startup.window_size.map(|(w, h)| [w, h]).unwrap_or_else(|| default_window_size(software));
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default().with_inner_size(size).with_title("ShadowLab"),
        renderer: eframe::Renderer::Wgpu,
        wgpu_options: egui_wgpu::WgpuConfiguration { wgpu_setup: wgpu_setup(), ..Default::default() },
        // egui's dithering is per-pixel noise in its fragment shader, over the whole window every frame: on a
        // software rasterizer that costs, and banding in 8-bit UI colours is invisible.
        dithering: !software,
        ..Default::default()
    };
    eframe::run_native("ShadowLab", options, Box::new(move |cc| Ok(Box::new(ShadowLabApp::new(cc, startup)?))))
        .map_err(|e| anyhow!("cannot open the window: {e}"))
}

/// A short message shown over the view.
struct Toast {
    text: String,
    error: bool,
    until: Instant,
}

/// GPU state, created from eframe's render state.
/// The difference view's image and metrics, for one pair of converged frames.
pub struct Difference {
    pub texture: egui::TextureHandle,
    pub metrics: shadowlab_core::compare::Metrics,
    /// What it was computed from (both views' frame keys and the diff settings).
    key: (u64, u64, bool, bool, u32),
}

/// A difference image and its metrics on their way from a worker thread.
struct PendingDifference {
    key: (u64, u64, bool, bool, u32),
    size: (u32, u32),
    result: std::sync::mpsc::Receiver<Result<(shadowlab_core::compare::Metrics, image::RgbaImage)>>,
}

pub struct Gpu {
    pub ctx: GpuContext,
    pub render_state: egui_wgpu::RenderState,
    pub main: View,
    pub reference: View,
    pub sizer: StepSizer,
}

/// A technique's per-pixel ID map: (frame key, layer name, ids, render size).
pub type PixelIds = (u64, &'static str, Arc<Vec<u32>>, (u32, u32));

/// A drag of the gizmo in progress.
#[derive(Clone, Debug)]
struct GizmoDrag {
    handle: Handle,
    target: DragTarget,
    /// Position at the start of the drag (the undo snapshot is taken then).
    start: Vec3,
    accumulated: egui::Vec2,
}

pub struct ShadowLabApp {
    /// The scene, lights, camera, techniques and settings the user edits (what a scene file saves).
    pub session: Session,
    pub gpu: Option<Gpu>,
    drag: Option<GizmoDrag>,
    toasts: Vec<Toast>,
    pub recent: Vec<PathBuf>,
    data_dir: PathBuf,
    /// Timings of completed frames: (seconds since start, GPU total ms, passes).
    pub timings: VecDeque<(f64, f64, Vec<PassTime>)>,
    /// Same-session reference time, for the speedup column.
    started: Instant,
    last_interaction: Option<Instant>,
    pub last_viewport_rect: Option<egui::Rect>,
    pub status: String,
    window_shot: Arc<std::sync::Mutex<Option<Arc<egui::ColorImage>>>>,
    pub ui_frame_ms: VecDeque<f64>,
    pub difference: Option<Difference>,
    /// The difference being computed on a worker thread (metrics with FLIP cost seconds on large images).
    pending_difference: Option<PendingDifference>,
    /// False in tests (`Startup::synchronous`): the difference is then computed on the UI thread.
    background_work: bool,
    pub sweep: Option<sweep::Sweep>,
    /// Last complete frame time (GPU ms) of every technique seen this session, with its parameters, for the
    /// comparison table (technique vs reference, same session).
    pub session_times: BTreeMap<String, (f64, String)>,
    /// The technique's per-pixel ID map for a converged frame.
    pub pixel_ids: Option<PixelIds>,
    /// Sweep panel inputs: parameter key, start, end, number of values.
    pub sweep_input: (String, f64, f64, usize),
    last_frame: Instant,
    exit_screenshot: Option<PathBuf>,
    quit_after_secs: Option<f32>,
    quitting: bool,
    orbit_demo: bool,
    ui_frames: u64,
    /// The tiles of the window (panels around the 3D view) and the full-view flag.
    pub layout: layout::Layout,
    /// The selection of the last UI frame: a new one brings the light inspector forward.
    last_selected: Option<usize>,
    /// The legends of the overlay layers drawn in the last UI frame: (layer name, entries).
    pub legends: Vec<(String, Vec<LegendEntry>)>,
    /// The 3D view's size in physical pixels (captures render at its render resolution).
    pub last_view_pixels: egui::Vec2,
    /// Frames of an orbit image sequence (File menu).
    pub orbit_frames: usize,
    /// Draw the view's visible overlay layers over the frames of image sequences (File menu).
    pub sequence_overlays: bool,
    /// The shadow-map inspector's state.
    pub inspector: inspector::Inspector,
    /// The Explain panel's chosen step: (technique key, step index).
    pub explain_step: Option<(String, usize)>,
    /// wgpu errors outside any error scope (egui's own painting, say), shown instead of panicking.
    uncaptured_errors: Arc<std::sync::Mutex<Vec<String>>>,
    relaunch_on_device_loss: bool,
    /// Set once the device was lost: the state was saved and the window says what happens next.
    pub recovery: Option<Recovery>,
    /// The last complete frame's auto-exposure: (scale, log-average luminance), shown in the Render panel.
    pub metered_exposure: Option<(f32, f32)>,
    /// Parameter values from before an Explain step set them, per (technique, parameter): restored when a step
    /// that does not set them is chosen.
    explain_saved: BTreeMap<(String, String), shadowlab_core::technique::ParamValue>,
}

fn default_data_dir() -> PathBuf {
    std::env::var_os("XDG_DATA_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local/share")))
        .unwrap_or_else(std::env::temp_dir)
        .join("shadowlab")
}

impl ShadowLabApp {
    pub fn new(cc: &eframe::CreationContext<'_>, startup: Startup) -> Result<ShadowLabApp> {
        let scene = Scene::builtin("arcade")?;
        let data_dir = startup.data_dir.clone().unwrap_or_else(default_data_dir);
        let layout = layout::Layout::load(&data_dir);
        let mut app = ShadowLabApp {
            session: Session::new(scene),
            gpu: None,
            drag: None,
            toasts: Vec::new(),
            recent: load_recent(&data_dir),
            data_dir,
            timings: VecDeque::new(),
            started: Instant::now(),
            last_interaction: None,
            last_viewport_rect: None,
            status: String::new(),
            window_shot: Default::default(),
            ui_frame_ms: VecDeque::new(),
            difference: None,
            pending_difference: None,
            background_work: !startup.synchronous,
            sweep: None,
            pixel_ids: None,
            session_times: BTreeMap::new(),
            sweep_input: ("d_init".into(), 0.1, 1.6, 6),
            last_frame: Instant::now(),
            exit_screenshot: startup.screenshot.clone(),
            quit_after_secs: startup.quit_after_secs,
            quitting: false,
            orbit_demo: startup.orbit_demo,
            ui_frames: 0,
            layout,
            last_selected: None,
            legends: Vec::new(),
            last_view_pixels: egui::vec2(640.0, 360.0),
            orbit_frames: 36,
            sequence_overlays: true,
            inspector: inspector::Inspector::default(),
            explain_step: None,
            uncaptured_errors: Default::default(),
            relaunch_on_device_loss: startup.relaunch_on_device_loss,
            recovery: None,
            metered_exposure: None,
            explain_saved: BTreeMap::new(),
        };
        let render_state = cc.wgpu_render_state.clone().ok_or_else(|| anyhow!("ShadowLab needs the wgpu renderer"))?;
        app.init_gpu(render_state)?;
        if startup.synchronous {
            if let Some(gpu) = &mut app.gpu {
                gpu.sizer = StepSizer { max_lights_per_step: 1 << 20, budget_ms: f64::INFINITY };
            }
        }
        if let Some(name) = &startup.builtin {
            app.load_builtin(name);
        }
        if let Some(path) = startup.path {
            app.open_path(&path);
        }
        if let Some(t) = startup.technique {
            if shadowlab_core::technique::REGISTRY.iter().any(|e| e.key == t) {
                app.session.technique = t;
            } else {
                app.error(format!("unknown technique '{t}' (choose one of: {})", shadowlab_core::technique::keys()));
            }
        }
        if let Some(k) = startup.indirect {
            if shadowlab_core::technique::INDIRECT_REGISTRY.iter().any(|e| e.key == k) {
                if let Some(source) = shadowlab_core::technique::preferred_vpl_source(&k) {
                    app.session.indirect.vpl.source = source;
                }
                app.session.indirect.technique = Some(k);
            } else {
                app.error(format!(
                    "unknown indirect technique '{k}' (choose one of: {})",
                    shadowlab_core::technique::indirect_keys()
                ));
            }
        }
        match startup.view.as_deref() {
            None => {}
            Some("single") => app.session.view.mode = ViewMode::Single,
            Some("side") => app.session.view.mode = ViewMode::SideBySide,
            Some("split") => app.session.view.mode = ViewMode::Split,
            Some("difference") => app.session.view.mode = ViewMode::Difference,
            Some(other) => app.error(format!("unknown view '{other}' (single, side, split, difference)")),
        }
        Ok(app)
    }

    fn init_gpu(&mut self, rs: egui_wgpu::RenderState) -> Result<()> {
        // wgpu's default handler panics; core's calls run in error scopes, so what reaches this is egui's
        // painting or a bug: shown as an error instead of killing the window.
        let errors = self.uncaptured_errors.clone();
        rs.device.on_uncaptured_error(Arc::new(move |e| {
            log::error!("wgpu: {e}");
            if let Ok(mut v) = errors.lock() {
                if v.len() < 16 {
                    v.push(e.to_string());
                }
            }
        }));
        let ctx = GpuContext::from_device(rs.device.clone(), rs.queue.clone(), rs.adapter.get_info());
        let main = View::new(&ctx, &rs, &self.session.scene)?;
        let reference = View::sharing(&ctx, &rs, &main)?;
        // A real GPU renders a whole frame in one step; a software one starts small and adapts, and starts at
        // half resolution with 256-texel cube faces (lavapipe is ~100x slower; the user can raise both).
        let software = rs.adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        let sizer =
            if software { StepSizer::default() } else { StepSizer { max_lights_per_step: 256, ..Default::default() } };
        if software {
            self.session.view.resolution_scale = 0.5;
            for key in ["reference", "lightcluster"] {
                self.session.params.entry(key.into()).or_default().insert("shadow_res".into(), ParamValue::Int(256));
            }
        }
        self.gpu = Some(Gpu { ctx, render_state: rs, main, reference, sizer });
        Ok(())
    }

    /// The GPU device is gone (a driver reset, a shader that ran too long, an unplugged GPU): eframe's device
    /// is the one egui paints with, so neither the renderers nor the window can be recreated in this process.
    /// Save everything to a recovery scene file, stop rendering, say so, and (in the binary) start a new
    /// ShadowLab on that file and close this window. A process that was itself started this way does not
    /// relaunch again; it only saves and says so.
    pub fn handle_device_lost(&mut self, ctx: &egui::Context, reason: String) {
        if self.recovery.is_some() {
            return;
        }
        log::error!("GPU device lost: {reason}");
        self.gpu = None;
        self.sweep = None;
        let file = self.data_dir.join("recovery.ron");
        let saved = std::fs::create_dir_all(&self.data_dir)
            .map_err(anyhow::Error::from)
            .and_then(|_| self.session.scene_file_data().save(&file));
        let relaunch_allowed = self.relaunch_on_device_loss && std::env::var_os(RECOVERED_ENV).is_none();
        let mut recovery = Recovery { reason: reason.clone(), file: None, relaunch: None, message: String::new() };
        recovery.message = match saved {
            Err(e) => format!(
                "The GPU device was lost ({reason}). ShadowLab could not save a recovery file ({e:#}); save your \
                 scene with File → Save scene file if the menu still responds, then restart ShadowLab."
            ),
            Ok(()) => {
                recovery.file = Some(file.clone());
                let program = std::env::current_exe().unwrap_or_else(|_| PathBuf::from("shadowlab"));
                let args = vec![file.display().to_string()];
                if relaunch_allowed {
                    let spawned = std::process::Command::new(&program).args(&args).env(RECOVERED_ENV, "1").spawn();
                    match spawned {
                        Ok(_) => {
                            recovery.relaunch = Some((program, args));
                            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                            format!(
                                "The GPU device was lost ({reason}). Your scene, lights, camera and settings were \
                                 saved to {}; a new ShadowLab window opens on them.",
                                file.display()
                            )
                        }
                        Err(e) => format!(
                            "The GPU device was lost ({reason}). Your scene was saved to {}, but a new ShadowLab \
                             could not be started ({e}); start it with that file.",
                            file.display()
                        ),
                    }
                } else {
                    // Tests record the command the binary would run; a recovered process runs none.
                    if !self.relaunch_on_device_loss {
                        recovery.relaunch = Some((program, args));
                    }
                    format!(
                        "The GPU device was lost ({reason}). Your scene, lights, camera and settings were saved to {}; \
                         restart ShadowLab with that file (`shadowlab {}`) to go on.",
                        file.display(),
                        file.display()
                    )
                }
            }
        };
        self.error(recovery.message.clone());
        self.status = recovery.message.clone();
        self.recovery = Some(recovery);
    }

    pub fn toast(&mut self, text: impl Into<String>) {
        let text = text.into();
        log::info!("{text}");
        self.toasts.push(Toast { text, error: false, until: Instant::now() + std::time::Duration::from_secs(4) });
    }

    pub fn error(&mut self, text: impl Into<String>) {
        let text = text.into();
        log::warn!("{text}");
        self.toasts.push(Toast { text, error: true, until: Instant::now() + std::time::Duration::from_secs(8) });
    }

    // ----- scenes and files -----

    /// Replace the scene (and its lights and camera). The previous scene stays when `scene` failed to load.
    pub fn set_scene(&mut self, scene: Scene) {
        if let Some(gpu) = &mut self.gpu {
            gpu.main.set_scene(&scene);
            gpu.reference.share_scene_of(&gpu.main);
        }
        for text in self.session.set_scene(scene) {
            self.toasts.push(Toast { text, error: false, until: Instant::now() + std::time::Duration::from_secs(6) });
        }
    }

    pub fn load_builtin(&mut self, name: &str) {
        match Scene::builtin(name) {
            Ok(s) => {
                self.set_scene(s);
                self.session.scene_file = None;
            }
            Err(e) => self.error(e.to_string()),
        }
    }

    /// Open a scene file (.ron) or a model; errors become a message and the current state stays.
    pub fn open_path(&mut self, path: &Path) {
        let is_ron = path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("ron"));
        let result = if is_ron { self.load_scene_file(path) } else { self.load_model(path, 1.0) };
        match result {
            Ok(()) => {
                self.remember_recent(path);
                self.toast(format!("opened {}", path.display()));
            }
            Err(e) => self.error(format!("{:#}", e)),
        }
    }

    fn load_model(&mut self, path: &Path, scale: f32) -> Result<()> {
        let scene = Scene::load(path, scale)?;
        self.set_scene(scene);
        self.session.scene_file = None;
        Ok(())
    }

    pub fn save_scene_file(&mut self, path: &Path) -> Result<()> {
        self.session.scene_file_data().save(path)?;
        self.session.scene_file = Some(path.to_path_buf());
        self.remember_recent(path);
        Ok(())
    }

    /// Load a scene file. Everything is checked before anything changes.
    pub fn load_scene_file(&mut self, path: &Path) -> Result<()> {
        let (file, warnings) = SceneFile::load(path)?;
        let scene = match &file.scene {
            SceneSource::Builtin(name) => Scene::builtin(name)?,
            SceneSource::File { path: model, unit_scale } => {
                // A relative model path is relative to the scene file.
                let model = if model.is_relative() {
                    path.parent().unwrap_or(Path::new(".")).join(model)
                } else {
                    model.clone()
                };
                Scene::load(&model, *unit_scale).with_context(|| "the scene file's model".to_string())?
            }
        };
        if shadowlab_core::technique::REGISTRY.iter().all(|e| e.key != file.technique) {
            return Err(anyhow!("unknown technique '{}'", file.technique));
        }
        // Every saved parameter is checked against its technique's ranges before anything changes, so a bad
        // value (an edited file, a viewpoint at NaN) is an error here and the current state stays.
        if let Some(gpu) = &mut self.gpu {
            for (key, values) in &file.params {
                let technique = gpu.main.technique(key).with_context(|| "the scene file's parameters".to_string())?;
                let params = technique.params();
                for (name, value) in values {
                    shadowlab_core::technique::check_param(key, &params, name, value)
                        .map_err(|e| anyhow!("technique '{key}': {e}"))?;
                }
            }
            // The indirect technique's too (its key and the VPL settings were checked when the file was read).
            for (key, values) in &file.indirect.params {
                let technique = gpu.main.indirect_technique(key).context("the scene file's indirect parameters")?;
                let params = technique.borrow().params();
                for (name, value) in values {
                    shadowlab_core::technique::check_param(key, &params, name, value)
                        .map_err(|e| anyhow!("indirect technique '{key}': {e}"))?;
                }
            }
        }
        self.set_scene(scene);
        self.session.apply_file(file);
        self.session.scene_file = Some(path.to_path_buf());
        for w in warnings {
            self.toast(format!("{}: {w}", path.display()));
        }
        Ok(())
    }

    fn remember_recent(&mut self, path: &Path) {
        let path = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        self.recent.retain(|p| p != &path);
        self.recent.insert(0, path);
        self.recent.truncate(10);
        save_recent(&self.data_dir, &self.recent);
    }

    // ----- lights -----

    pub fn apply_layout(&mut self, spec: &str) {
        match self.session.apply_layout(spec) {
            Ok(n) => self.toast(format!("{n} lights from '{spec}'")),
            Err(e) => self.error(e.to_string()),
        }
    }

    // ----- rendering -----

    /// Alt+click: hand the clicked pixel to the indirect technique's probe (the parameters it names), so its
    /// probe overlay shows that pixel; the app knows no technique, only `probe_params`.
    fn probe_at(&mut self, pos: egui::Pos2, rect: egui::Rect) {
        let (Some(key), Some(gpu)) = (self.session.indirect.technique.clone(), &mut self.gpu) else { return };
        let size = gpu.main.size;
        let Ok(technique) = gpu.main.indirect_technique(&key) else { return };
        let Some((px, py)) = technique.borrow().probe_params() else { return };
        let u = ((pos.x - rect.min.x) / rect.width().max(1.0)).clamp(0.0, 1.0);
        let v = ((pos.y - rect.min.y) / rect.height().max(1.0)).clamp(0.0, 1.0);
        let x = ((u * size.0 as f32) as i64).min(size.0 as i64 - 1);
        let y = ((v * size.1 as f32) as i64).min(size.1 as i64 - 1);
        let params = self.session.indirect.params.entry(key).or_default();
        params.insert(px.to_string(), ParamValue::Int(x));
        params.insert(py.to_string(), ParamValue::Int(y));
        self.status = format!("probe at pixel ({x}, {y})");
    }

    /// The overlay layers of the indirect technique, from the instance the main view renders with.
    fn indirect_overlay_layers(&mut self, lights: &[PointLight]) -> Vec<shadowlab_core::technique::OverlayLayer> {
        let (Some(key), Some(gpu)) = (self.session.indirect.technique.clone(), &mut self.gpu) else {
            return Vec::new();
        };
        match gpu.main.indirect_technique(&key) {
            Ok(t) => t.borrow().overlays(lights),
            Err(_) => Vec::new(),
        }
    }

    /// The overlay primitives of the current technique that the user has switched on, plus the selection, and
    /// the legend of each of those layers (as the layers describe themselves through their technique).
    fn overlay_primitives(&mut self, lights: &[PointLight]) -> (Vec<Overlay>, Vec<(String, Vec<LegendEntry>)>) {
        let mut out = Vec::new();
        let mut legends = Vec::new();
        let overlays = &self.session.view.overlays;
        let is_on = |layer: &OverlayLayer| *overlays.get(layer.name).unwrap_or(&layer.visible_by_default);
        let mut take = |technique: &dyn Technique, layers: Vec<OverlayLayer>, out: &mut Vec<Overlay>| {
            for layer in layers.into_iter().filter(|l| is_on(l)) {
                legends.push((layer.name.to_string(), technique.overlay_legend(&layer)));
                out.extend(layer.primitives);
            }
        };
        let shown = |name: &str, default: bool| *overlays.get(name).unwrap_or(&default);
        let Some(gpu) = &mut self.gpu else { return (out, Vec::new()) };
        if let Ok(technique) = gpu.main.technique(&self.session.technique) {
            // Only the shown layers are built (INSM's meshes cost a readback).
            let layers = technique.overlays_shown(lights, &shown);
            take(technique.as_ref(), layers, &mut out);
        }
        if self.session.technique != "reference" {
            if let Ok(reference) = gpu.main.technique("reference") {
                let layers = reference.overlays(lights).into_iter().filter(|l| l.name == "light ranges").collect();
                take(reference.as_ref(), layers, &mut out);
            }
        }
        if let Some(key) = self.session.indirect.technique.clone() {
            if let Ok(t) = gpu.main.indirect_technique(&key) {
                let t = t.borrow();
                let layers = t.overlays_shown(lights, &shown);
                take(t.as_ref(), layers, &mut out);
            }
        }
        // A selected light's group (its cluster): the primitives at its members stay, the rest is dimmed.
        if let Some(group) =
            self.session.selected.and_then(|i| self.light_details(i)).map(|d| d.group).filter(|g| g.len() > 1)
        {
            let at: Vec<Vec3> = group.iter().filter_map(|&m| lights.get(m)).map(|l| l.position).collect();
            let member = |p: &Vec3| at.contains(p);
            for o in &mut out {
                let keep = match o {
                    Overlay::Point { position, .. } => member(position),
                    Overlay::Line { from, to, .. } => member(from) || member(to),
                    Overlay::Sphere { center, .. } => member(center),
                    _ => true,
                };
                if !keep {
                    if let Overlay::Point { color, .. } | Overlay::Line { color, .. } | Overlay::Sphere { color, .. } =
                        o
                    {
                        color[3] *= 0.2;
                    }
                }
            }
        }
        if let Some(l) = self.session.selected.and_then(|i| lights.get(i)) {
            out.push(Overlay::Sphere { center: l.position, radius: l.range, color: [1.0, 1.0, 0.3, 0.6] });
            out.push(Overlay::Point { position: l.position, color: [1.0, 1.0, 0.2, 1.0], radius_px: 8.0 });
        }
        (out, legends)
    }

    /// Show what step `index` of technique `key`'s Explain `steps` shows: its overlay layers on, the
    /// technique's others off; the shadow-map panel in front with the step's maps when it is about them; the
    /// parameter values it sets, and the values from before for parameters that only other steps set.
    pub fn show_explain_step(&mut self, key: &str, steps: &[shadowlab_core::technique::ExplainStep], index: usize) {
        let Some(step) = steps.get(index) else { return };
        for (name, _) in self.overlay_layers() {
            let on = step.layers.contains(&name.as_str());
            self.session.view.overlays.insert(name, on);
        }
        let indirect = key != self.session.technique;
        if step.shows_shadow_maps {
            self.inspector.source = inspector::MapSource { indirect, set: step.maps };
            self.layout.request_focus(layout::Pane::Maps);
        }
        let named: std::collections::BTreeSet<&str> =
            steps.iter().flat_map(|s| s.params.iter().map(|(k, _)| *k)).collect();
        if named.is_empty() {
            return;
        }
        let Some(gpu) = &mut self.gpu else { return };
        let specs = if indirect {
            gpu.main.indirect_technique(key).map(|t| t.borrow().params())
        } else {
            gpu.main.technique(key).map(|t| t.params())
        };
        let Ok(specs) = specs else { return };
        let mut errors = Vec::new();
        for name in named {
            let Some(spec) = specs.iter().find(|p| p.key == name) else { continue };
            let saved = (key.to_string(), name.to_string());
            let value = match step.params.iter().find(|(k, _)| *k == name) {
                Some((_, text)) => match spec.kind.parse(name, text) {
                    Ok(v) => {
                        self.explain_saved.entry(saved).or_insert_with(|| spec.value.clone());
                        v
                    }
                    Err(e) => {
                        errors.push(e.to_string());
                        continue;
                    }
                },
                None => match self.explain_saved.remove(&saved) {
                    Some(v) => v,
                    None => continue,
                },
            };
            let params = if indirect { &mut self.session.indirect.params } else { &mut self.session.params };
            params.entry(key.to_string()).or_default().insert(name.to_string(), value);
        }
        for e in errors {
            self.error(e);
        }
    }

    /// The shadow-map inspector: reads the chosen maps back once per completed frame (not for the preview while
    /// the camera moves), then shows them; a selected light shows its cube map.
    pub fn maps_ui(&mut self, ui: &mut egui::Ui) {
        use inspector::{AtlasDepths, MapSource};
        use shadowlab_core::technique::Technique;
        // Every map set of the direct and the indirect technique: shadow maps first, then depth images.
        fn sets(t: &dyn Technique) -> Vec<(&shadowlab_core::renderer::cube_shadows::CubeAtlas, &'static str)> {
            t.shadow_atlas().into_iter().chain(t.depth_images()).collect()
        }
        fn labelled(t: &dyn Technique, indirect: bool) -> Vec<(MapSource, String)> {
            let shadow = usize::from(t.shadow_atlas().is_none());
            let images = t.depth_images().into_iter().map(|(_, what)| what);
            let names = t.shadow_atlas().map(|_| "shadow maps").into_iter().chain(images);
            let who = if indirect { "indirect" } else { "direct" };
            names
                .enumerate()
                .map(|(i, name)| (MapSource { indirect, set: i + shadow }, format!("{} ({who}): {name}", t.label())))
                .collect()
        }
        let key = self.session.technique.clone();
        let indirect_key = self.session.indirect.technique.clone();
        let selected = self.session.selected;
        let mut sources = Vec::new();
        let mut follow: Option<(usize, Vec<Vec3>)> = None;
        if let Some(gpu) = &mut self.gpu {
            if let Ok(t) = gpu.main.technique(&key) {
                sources.extend(labelled(t.as_ref(), false));
            }
            if let Some(k) = &indirect_key {
                if let Ok(t) = gpu.main.indirect_technique(k) {
                    sources.extend(labelled(t.borrow().as_ref(), true));
                }
            }
            if !sources.iter().any(|(s, _)| *s == self.inspector.source) {
                self.inspector.source = sources.first().map(|(s, _)| *s).unwrap_or(MapSource::DIRECT);
            }
            let complete = gpu.main.last_report.as_ref().is_some_and(|r| r.technique == key);
            let source = self.inspector.source;
            let from = (gpu.main.frame_key(), source);
            if gpu.main.is_converged() && complete && self.inspector.read_from != Some(from) {
                let ctx = gpu.ctx.clone();
                // `set` 0 is the shadow atlas; without one the depth images still start at 1.
                let read = |t: &dyn Technique| {
                    let offset = usize::from(t.shadow_atlas().is_none());
                    let all = sets(t);
                    source
                        .set
                        .checked_sub(offset)
                        .and_then(|i| all.get(i))
                        .map(|(a, what)| AtlasDepths::read(&ctx, a, what))
                        .transpose()
                };
                let result = if source.indirect {
                    match &indirect_key {
                        Some(k) => gpu.main.indirect_technique(k).and_then(|t| read(t.borrow().as_ref())),
                        None => Ok(None),
                    }
                } else {
                    gpu.main.technique(&key).and_then(|t| read(t.as_ref()))
                };
                self.inspector.set_atlas(result.map_err(|e| format!("{e:#}")), from);
            }
        }
        if let Some(i) = selected {
            let lights = self.session.animated_lights();
            if let Some(light) = lights.get(i) {
                let mut positions = vec![light.position];
                let group = self.light_details(i).map(|d| d.group).unwrap_or_default();
                positions.extend(group.iter().filter_map(|&m| lights.get(m)).map(|l| l.position));
                follow = Some((i, positions));
            }
        }
        if let Some((i, positions)) = follow {
            self.inspector.follow_light(i, &positions);
        }
        self.inspector.ui(ui, sources);
    }

    /// What the current technique made of light `index` in its last frame (its cluster, say).
    pub fn light_details(&mut self, index: usize) -> Option<shadowlab_core::technique::LightDetails> {
        let gpu = self.gpu.as_mut()?;
        gpu.main.technique(&self.session.technique).ok()?.light_details(index)
    }

    /// The tooltip of a light in the view: its fields, and what the technique made of it.
    pub fn light_tooltip(&mut self, index: usize) -> Vec<String> {
        let Some(l) = self.session.lights.get(index).copied() else { return Vec::new() };
        let mut lines = vec![
            format!("light {index}{}", if l.spot.is_some() { " (spot)" } else { "" }),
            format!("position ({:.2}, {:.2}, {:.2})", l.position.x, l.position.y, l.position.z),
            format!("intensity {:.2} · L_att {:.2}", l.intensity, l.range),
        ];
        if let Some(d) = self.light_details(index) {
            lines.extend(d.lines);
        }
        lines
    }

    /// The tooltip of a camera the technique used (a `Cameras` parameter's, e.g. an INSM viewpoint) under `pos`.
    pub fn camera_tooltip(&mut self, projection: &Projection, pos: egui::Pos2) -> Vec<String> {
        let Some(gpu) = &mut self.gpu else { return Vec::new() };
        let Ok(technique) = gpu.main.technique(&self.session.technique) else { return Vec::new() };
        for p in technique.params() {
            if let shadowlab_core::technique::ParamKind::Cameras { .. } = p.kind {
                let cameras = technique.cameras_in_use(p.key);
                if let Some(i) = gizmo::pick_point(projection, cameras.iter().map(|c| c.position), pos, 10.0) {
                    let c = cameras[i];
                    return vec![
                        format!("{} #{} of {}", p.label, i + 1, cameras.len()),
                        format!("position ({:.2}, {:.2}, {:.2})", c.position.x, c.position.y, c.position.z),
                        format!(
                            "looking at ({:.2}, {:.2}, {:.2}) · fov {:.0}°",
                            c.target.x, c.target.y, c.target.z, c.fov_y_deg
                        ),
                    ];
                }
            }
        }
        Vec::new()
    }

    /// The tooltip of what a visible overlay layer draws under `pos` (a VAL, a VPL, a cluster's
    /// representative), from the direct or the indirect technique's hover points
    /// ([`Technique::hover_points`](shadowlab_core::technique::Technique::hover_points)).
    pub fn overlay_tooltip(&mut self, projection: &Projection, pos: egui::Pos2) -> Vec<String> {
        use shadowlab_core::technique::Technique;
        let visible: Vec<String> = self.overlay_layers().into_iter().filter(|(_, on)| *on).map(|(n, _)| n).collect();
        let indirect_key = self.session.indirect.technique.clone();
        let Some(gpu) = &mut self.gpu else { return Vec::new() };
        let pick = |t: &dyn Technique| {
            let points: Vec<_> =
                t.hover_points().into_iter().filter(|p| visible.iter().any(|v| v == p.layer)).collect();
            let i = gizmo::pick_point(projection, points.iter().map(|p| p.position), pos, 8.0)?;
            Some(points[i]).map(|p| t.hover_details(p.layer, p.index)).filter(|lines| !lines.is_empty())
        };
        if let Some(lines) = gpu.main.technique(&self.session.technique).ok().and_then(|t| pick(t.as_ref())) {
            return lines;
        }
        let indirect = indirect_key.and_then(|k| gpu.main.indirect_technique(&k).ok());
        if let Some(lines) = indirect.as_ref().and_then(|t| pick(t.borrow().as_ref())) {
            return lines;
        }
        // A visible per-pixel ID map (a cluster per pixel) under the pointer: the ID there, and what the
        // technique says of that ID as a hover index of the map's layer. Only in the single view, which the
        // render target fills.
        let Some(rect) = self.last_viewport_rect.filter(|_| self.session.view.mode == ViewMode::Single) else {
            return Vec::new();
        };
        // (layer, size, ids, from the indirect technique)
        type IdMapLayer = (&'static str, (u32, u32), Arc<Vec<u32>>, bool);
        let mut maps: Vec<IdMapLayer> = Vec::new();
        if let Some((_, name, ids, size)) = &self.pixel_ids {
            maps.push((name, *size, ids.clone(), false));
        }
        if let Some(t) = &indirect {
            for layer in t.borrow().overlays(&[]) {
                for o in &layer.primitives {
                    if let Overlay::IdMap { width, height, ids, .. } = o {
                        maps.push((layer.name, (*width, *height), ids.clone(), true));
                    }
                }
            }
        }
        let uv = (pos - rect.min) / rect.size();
        for (name, (w, h), ids, from_indirect) in maps {
            if !visible.iter().any(|v| v == name) || !(0.0..1.0).contains(&uv.x) || !(0.0..1.0).contains(&uv.y) {
                continue;
            }
            let (x, y) = ((uv.x * w as f32) as u32, (uv.y * h as f32) as u32);
            let Some(&id) = ids.get((y * w + x) as usize).filter(|id| **id != u32::MAX) else { continue };
            let mut lines = vec![format!("{name}: {id} (pixel {x}, {y})")];
            let details = if from_indirect {
                indirect.as_ref().map(|t| t.borrow().hover_details(name, id as usize))
            } else {
                gpu.main.technique(&self.session.technique).ok().map(|t| t.hover_details(name, id as usize))
            };
            lines.extend(details.unwrap_or_default());
            return lines;
        }
        Vec::new()
    }

    /// Names of the overlay layers the current technique offers, with their state.
    pub fn overlay_layers(&mut self) -> Vec<(String, bool)> {
        let Some(gpu) = &mut self.gpu else { return Vec::new() };
        let mut names: Vec<(String, bool)> = Vec::new();
        // Only the names are needed: asking with no lights builds (almost) no primitives, every UI frame; one spot
        // light, when the scene has one, brings the layers that only spot lights have.
        let probe: Vec<PointLight> =
            self.session.lights.iter().find(|l| l.spot.is_some()).copied().into_iter().collect();
        if let Ok(t) = gpu.main.technique(&self.session.technique) {
            let layers = t.overlays_shown(&probe, &|_, _| false);
            names.extend(layers.into_iter().map(|l| (l.name.to_string(), l.visible_by_default)));
        }
        if self.session.technique != "reference" {
            names.push(("light ranges".into(), false));
        }
        if let Ok(t) = gpu.main.technique(&self.session.technique) {
            if let Some((name, _)) = t.pixel_ids(&[]) {
                names.push((name.to_string(), false));
            }
        }
        names.extend(self.indirect_overlay_layers(&[]).into_iter().map(|l| (l.name.to_string(), l.visible_by_default)));
        names.into_iter().map(|(n, d)| (n.clone(), *self.session.view.overlays.get(&n).unwrap_or(&d))).collect()
    }

    fn render_views(&mut self, size: egui::Vec2, pixels_per_point: f32, interacting: bool) -> Result<()> {
        let lights = self.session.animated_lights();
        let camera = self.session.camera.camera();
        let (mut overlays, legends) = self.overlay_primitives(&lights);
        self.legends = legends;
        let technique = if interacting { PREVIEW_TECHNIQUE.to_string() } else { self.session.technique.clone() };
        let two = self.session.view.mode != ViewMode::Single;
        let per_view =
            if self.session.view.mode == ViewMode::SideBySide { egui::vec2(size.x * 0.5, size.y) } else { size };
        let settings = self.session.render_settings(per_view, interacting);
        // Dot sizes are in screen points; the render target may be smaller or larger than the view.
        let render_pixels_per_point = pixels_per_point * settings.width as f32 / per_view.x.max(1.0);
        for o in &mut overlays {
            if let Overlay::Point { radius_px, .. } = o {
                *radius_px *= render_pixels_per_point;
            }
        }
        // Lines about 2 points wide on screen, whatever the render resolution; occluded parts faded.
        let style = OverlayStyle { line_width_px: (2.0 * render_pixels_per_point).max(1.0), occluded_alpha: 0.25 };
        let params = self.session.params.get(&technique).cloned().unwrap_or_default();
        // Both views get the same indirect technique and parameters, so a comparison compares the same light.
        let (indirect, indirect_params) = self.session.indirect_inputs(interacting);
        let x_ray = self.session.view.x_ray;
        let Some(gpu) = &mut self.gpu else { return Ok(()) };
        let main_inputs = FrameInputs {
            camera,
            lights: lights.clone(),
            technique,
            params,
            indirect: indirect.clone(),
            indirect_params: indirect_params.clone(),
            settings: settings.clone(),
        };
        // While the user drags, keep the UI fluid: the preview gets a third of the budget.
        let budget = if interacting { gpu.sizer.budget_ms() / 3.0 } else { gpu.sizer.budget_ms() };
        let (spent, steps) = gpu.main.update(&gpu.render_state, &main_inputs, budget, gpu.sizer.max_lights_per_step)?;
        // The comparison view shows the technique's exposure (held, never metered itself), so the same radiance
        // looks the same on both sides of a split or side-by-side view.
        if gpu.main.new_report && settings.auto_exposure == AutoExposure::Meter {
            if let Some((scale, average)) = gpu.main.renderer.auto_exposure()? {
                gpu.reference.renderer.set_held_exposure(scale, average)?;
                self.metered_exposure = Some((scale, average));
            }
        }
        // The technique's per-pixel ID map, once per converged frame, when its layer is on.
        if gpu.main.is_converged() {
            let key = gpu.main.frame_key();
            let technique_key = main_inputs.technique.clone();
            let view_overlays = &self.session.view.overlays;
            let technique = gpu.main.technique(&technique_key)?;
            let layer = technique.pixel_ids(&[]).map(|(name, _)| name);
            let wanted = layer.is_some_and(|name| *view_overlays.get(name).unwrap_or(&false));
            if wanted && self.pixel_ids.as_ref().is_none_or(|(k, ..)| *k != key) {
                let positions = gpu.main.renderer.read_world_positions(&camera)?;
                let technique = gpu.main.technique(&technique_key)?;
                if let Some((name, ids)) = technique.pixel_ids(&positions) {
                    self.pixel_ids = Some((key, name, Arc::new(ids), gpu.main.size));
                }
            }
            if let Some((k, name, ids, (w, h))) = &self.pixel_ids {
                if *k == key && wanted && layer == Some(*name) {
                    overlays.insert(0, Overlay::IdMap { width: *w, height: *h, ids: ids.clone(), alpha: 0.45 });
                }
            }
        }
        gpu.main.renderer.set_overlay_style(style);
        gpu.reference.renderer.set_overlay_style(style);
        gpu.main.overlays(&camera, &overlays, x_ray)?;
        let mut total_spent = spent;
        let mut total_steps = steps;
        if two {
            let against = self.session.view.compare_against.clone();
            let reference_technique = if interacting { PREVIEW_TECHNIQUE } else { against.as_str() };
            let reference_inputs = FrameInputs {
                camera,
                lights,
                technique: reference_technique.into(),
                params: self.session.params.get(reference_technique).cloned().unwrap_or_default(),
                indirect,
                indirect_params,
                settings: RenderSettings {
                    auto_exposure: match settings.auto_exposure {
                        AutoExposure::Off => AutoExposure::Off,
                        _ => AutoExposure::Hold,
                    },
                    ..settings
                },
            };
            // The reference gets what is left of the budget once the technique's image is complete.
            let left = if gpu.main.is_converged() { budget - spent } else { budget * 0.25 };
            let (s, n) = gpu.reference.update(
                &gpu.render_state,
                &reference_inputs,
                left.max(1.0),
                gpu.sizer.max_lights_per_step,
            )?;
            gpu.reference.overlays(&camera, &overlays, x_ray)?;
            total_spent += s;
            total_steps += n;
        }
        gpu.sizer.observe(total_spent, total_steps);
        let describe = |params: &BTreeMap<String, ParamValue>| {
            params.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(" ")
        };
        let indirect_params = &main_inputs.indirect_params;
        let describe_report = |r: &shadowlab_core::FrameReport, params: &BTreeMap<String, ParamValue>| {
            let mut p = describe(params);
            if r.indirect.is_some() && !indirect_params.is_empty() {
                p = format!("{p} | {}", describe(indirect_params)).trim().to_string();
            }
            p
        };
        if std::mem::take(&mut gpu.reference.new_report) {
            if let Some(r) = gpu.reference.last_report.as_ref().filter(|r| r.technique != PREVIEW_TECHNIQUE) {
                let p = describe_report(r, &self.session.params.get(&r.technique).cloned().unwrap_or_default());
                self.session_times.insert(session_name(r), (r.gpu_total_ms, p));
            }
        }
        if std::mem::take(&mut gpu.main.new_report) {
            if let Some(r) = gpu.main.last_report.as_ref().filter(|r| r.technique != PREVIEW_TECHNIQUE) {
                let p = describe_report(r, &main_inputs.params);
                self.session_times.insert(session_name(r), (r.gpu_total_ms, p));
            }
            if let Some(r) = &gpu.main.last_report {
                let t = self.started.elapsed().as_secs_f64();
                if r.technique != PREVIEW_TECHNIQUE {
                    self.timings.push_back((t, r.gpu_total_ms, r.passes.clone()));
                    while self.timings.front().is_some_and(|(t0, _, _)| t - t0 > 60.0) {
                        self.timings.pop_front();
                    }
                }
            }
        }
        Ok(())
    }

    /// Recompute the difference image when both views have converged on new frames.
    fn update_difference(&mut self, ctx: &egui::Context) -> Result<()> {
        let camera = self.session.camera.camera();
        let lights = self.session.animated_lights();
        let Some(gpu) = &mut self.gpu else { return Ok(()) };
        if !(gpu.main.is_converged() && gpu.reference.is_converged()) {
            return Ok(());
        }
        let key = (
            gpu.main.frame_key(),
            gpu.reference.frame_key(),
            self.session.view.diff_signed,
            self.session.view.diff_visibility,
            self.session.view.diff_gain.to_bits(),
        );
        if self.difference.as_ref().is_some_and(|d| d.key == key) {
            return Ok(());
        }
        // A worker is on it: show its result when it arrives (an older key's result is dropped).
        if let Some(p) = &self.pending_difference {
            match p.result.try_recv() {
                Ok(result) => {
                    let (pkey, (w, h)) = (p.key, p.size);
                    self.pending_difference = None;
                    let (metrics, image) = result?;
                    let color = egui::ColorImage::from_rgba_unmultiplied([w as usize, h as usize], image.as_raw());
                    let texture = ctx.load_texture("difference", color, egui::TextureOptions::NEAREST);
                    self.difference = Some(Difference { texture, metrics, key: pkey });
                    if pkey == key {
                        return Ok(());
                    }
                }
                Err(std::sync::mpsc::TryRecvError::Empty) if p.key == key => {
                    ctx.request_repaint_after(std::time::Duration::from_millis(50));
                    return Ok(());
                }
                Err(_) => self.pending_difference = None,
            }
        }
        use shadowlab_core::compare::{self, CompareOptions, DiffMode, Image, Visibility};
        let (w, h) = gpu.main.size;
        // Shadow factors are those of the direct light, whatever component the views show; otherwise the
        // component shown is compared.
        let read = |renderer: &shadowlab_core::Renderer| {
            if self.session.view.diff_visibility {
                renderer.read_component(Component::Direct)
            } else {
                renderer.read_hdr()
            }
        };
        let technique = Image::new(w, h, read(&gpu.main.renderer)?)?;
        let reference = Image::new(w, h, read(&gpu.reference.renderer)?)?;
        let mask = gpu.main.renderer.read_geometry_mask()?;
        let mode = if self.session.view.diff_signed { DiffMode::Signed } else { DiffMode::Absolute };
        let gain = self.session.view.diff_gain;
        // The GPU part (readbacks, and for shadow factors the unshadowed and ambient-only images of the same
        // view) here; the CPU part (metrics with FLIP, the colour map) on a worker thread unless synchronous.
        let lit_ambient = if self.session.view.diff_visibility {
            let settings = RenderSettings { component: Component::Direct, ..gpu.main.renderer.settings().clone() };
            let mut aux = gpu.main.renderer.new_view(settings)?;
            let mut unshadowed = aux.create_technique("unshadowed").ok_or_else(|| anyhow!("no unshadowed"))?;
            aux.render_frame(unshadowed.as_mut(), &camera, &lights, &mut |_, _| {})?;
            let lit = Image::new(w, h, aux.read_hdr()?)?;
            aux.render_frame(unshadowed.as_mut(), &camera, &[], &mut |_, _| {})?;
            let ambient = Image::new(w, h, aux.read_hdr()?)?;
            Some((lit, ambient))
        } else {
            None
        };
        let work = move || -> Result<(shadowlab_core::compare::Metrics, image::RgbaImage)> {
            Ok(match &lit_ambient {
                Some((lit, ambient)) => {
                    let v_t = compare::visibility_image(&technique, lit, Some(ambient))?;
                    let v_r = compare::visibility_image(&reference, lit, Some(ambient))?;
                    let options = CompareOptions {
                        visibility: Some(Visibility { technique: &v_t, reference: &v_r }),
                        ..Default::default()
                    };
                    let m = compare::compare(&technique, &reference, Some(&mask), &options)?;
                    (m, compare::visibility_difference_image(&v_t, &v_r, w, h, Some(&mask), mode, gain)?)
                }
                None => {
                    let m = compare::compare(&technique, &reference, Some(&mask), &CompareOptions::default())?;
                    (m, compare::difference_image(&technique, &reference, Some(&mask), mode, gain)?)
                }
            })
        };
        if self.background_work {
            let (tx, rx) = std::sync::mpsc::channel();
            let repaint = ctx.clone();
            std::thread::Builder::new().name("difference".into()).spawn(move || {
                let _ = tx.send(work());
                repaint.request_repaint();
            })?;
            self.pending_difference = Some(PendingDifference { key, size: (w, h), result: rx });
            return Ok(());
        }
        let (metrics, image) = work()?;
        let color = egui::ColorImage::from_rgba_unmultiplied([w as usize, h as usize], image.as_raw());
        let texture = ctx.load_texture("difference", color, egui::TextureOptions::NEAREST);
        self.difference = Some(Difference { texture, metrics, key });
        Ok(())
    }

    /// Start a sweep of `key` over `values` for the current technique, view and lights.
    pub fn start_sweep(&mut self, key: &str, values: Vec<ParamValue>) -> Result<()> {
        let gpu = self.gpu.as_ref().ok_or_else(|| anyhow!("no GPU"))?;
        let settings = gpu.main.renderer.settings().clone();
        let fixed: Vec<(String, ParamValue)> = self
            .session
            .params
            .get(&self.session.technique)
            .map(|p| p.iter().filter(|(k, _)| k.as_str() != key).map(|(k, v)| (k.clone(), v.clone())).collect())
            .unwrap_or_default();
        self.sweep = Some(sweep::Sweep::start(sweep::SweepJob {
            gpu: gpu.ctx.clone(),
            scene: gpu.main.renderer.shared_scene(),
            layouts: gpu.main.renderer.shared_layouts(),
            lights: self.session.animated_lights(),
            camera: self.session.camera.camera(),
            settings,
            technique: self.session.technique.clone(),
            fixed,
            indirect: self.session.indirect.technique.clone().map(|k| {
                let params = self.session.indirect.params.get(&k).cloned().unwrap_or_default().into_iter().collect();
                (k, params)
            }),
            key: key.to_string(),
            values,
        }));
        Ok(())
    }

    // ----- screenshots -----

    fn screenshot_name(&self, what: &str) -> PathBuf {
        let params: String = self
            .session
            .params
            .get(&self.session.technique)
            .map(|p| p.iter().map(|(k, v)| format!("-{k}{v}")).collect())
            .unwrap_or_default();
        let stamp = chrono_like_stamp();
        let indirect = self.session.indirect.technique.as_ref().map(|k| format!("+{k}")).unwrap_or_default();
        let name = format!(
            "shadowlab-{}-{}{}{}-{}-{}.png",
            self.session.scene.name, self.session.technique, params, indirect, what, stamp
        )
        .replace(['/', '\\', ' ', ':'], "_");
        self.data_dir.join("screenshots").join(name)
    }

    /// Export a figure and say where it went (or why not).
    pub fn export_figure(&mut self) {
        match self.save_figure() {
            Ok(p) => self.toast(format!("saved {}", p.display())),
            Err(e) => self.error(format!("figure export failed: {e:#}")),
        }
    }

    /// Save the 3D view at its render resolution (no UI). Returns the path.
    pub fn save_view_screenshot(&mut self) -> Result<PathBuf> {
        let path = self.screenshot_name("view");
        let gpu = self.gpu.as_ref().ok_or_else(|| anyhow!("no GPU"))?;
        let image = gpu.main.renderer.read_output()?;
        std::fs::create_dir_all(path.parent().expect("has a parent"))?;
        image.save(&path).with_context(|| format!("cannot write {}", path.display()))?;
        Ok(path)
    }

    fn save_window_screenshot(&mut self, image: &egui::ColorImage) -> Result<PathBuf> {
        let path = self.screenshot_name("window");
        let [w, h] = image.size;
        let bytes: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
        let img = image::RgbaImage::from_raw(w as u32, h as u32, bytes).ok_or_else(|| anyhow!("bad screenshot"))?;
        std::fs::create_dir_all(path.parent().expect("has a parent"))?;
        img.save(&path).with_context(|| format!("cannot write {}", path.display()))?;
        Ok(path)
    }

    // ----- UI -----

    fn handle_shortcuts(&mut self, ctx: &egui::Context) {
        let full_view = ctx.input_mut(|i| i.consume_key(egui::Modifiers::NONE, egui::Key::F11))
            || (!ctx.egui_wants_keyboard_input()
                && ctx.input_mut(|i| i.consume_key(egui::Modifiers::NONE, egui::Key::Tab)));
        if full_view {
            self.layout.toggle_full_view();
        }
        let (undo, redo, duplicate, f12, shift_f12, figure) = ctx.input_mut(|i| {
            // Redo first: Ctrl+Shift+Z would otherwise also match Ctrl+Z.
            let redo = i.consume_key(egui::Modifiers::COMMAND | egui::Modifiers::SHIFT, egui::Key::Z)
                || i.consume_key(egui::Modifiers::COMMAND, egui::Key::Y);
            let undo = i.consume_key(egui::Modifiers::COMMAND, egui::Key::Z);
            let figure = i.consume_key(egui::Modifiers::COMMAND, egui::Key::F12);
            let shift_f12 = i.consume_key(egui::Modifiers::SHIFT, egui::Key::F12);
            let f12 = i.consume_key(egui::Modifiers::NONE, egui::Key::F12);
            let duplicate = i.consume_key(egui::Modifiers::COMMAND, egui::Key::D);
            (undo, redo, duplicate, f12, shift_f12, figure)
        });
        // Plain keys belong to a text field when one has the focus.
        let (delete, frame) = if ctx.egui_wants_keyboard_input() {
            (false, false)
        } else {
            ctx.input_mut(|i| {
                (
                    i.consume_key(egui::Modifiers::NONE, egui::Key::Delete),
                    i.consume_key(egui::Modifiers::NONE, egui::Key::F) && self.session.camera.mode == CameraMode::Orbit,
                )
            })
        };
        if undo {
            self.session.undo();
        }
        if redo {
            self.session.redo();
        }
        if delete {
            self.session.delete_selected();
        }
        if duplicate {
            self.session.duplicate_selected();
        }
        if frame {
            let b = self.session.scene.bounds;
            self.session.camera.frame(&b);
        }
        if f12 {
            match self.save_view_screenshot() {
                Ok(p) => self.toast(format!("saved {}", p.display())),
                Err(e) => self.error(format!("screenshot failed: {e:#}")),
            }
        }
        if shift_f12 {
            self.request_window_screenshot(ctx);
        }
        if figure {
            self.export_figure();
        }
    }

    /// Ask the integration for a picture of the whole window; it arrives a frame or two later.
    pub fn request_window_screenshot(&mut self, ctx: &egui::Context) {
        let slot = self.window_shot.clone();
        let repaint = ctx.clone();
        ctx.request_screenshot(move |image| {
            if let Ok(mut s) = slot.lock() {
                *s = Some(image);
            }
            repaint.request_repaint();
        });
    }

    fn receive_screenshots(&mut self, ctx: &egui::Context) {
        let shot = self.window_shot.lock().ok().and_then(|mut s| s.take());
        if let Some(image) = shot {
            if let (true, Some(path)) = (self.quitting, self.exit_screenshot.take()) {
                let [w, h] = image.size;
                let bytes: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
                match image::RgbaImage::from_raw(w as u32, h as u32, bytes).map(|img| img.save(&path)) {
                    Some(Ok(())) => eprintln!("saved {}", path.display()),
                    _ => eprintln!("error: cannot save {}", path.display()),
                }
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                return;
            }
            match self.save_window_screenshot(&image) {
                Ok(p) => self.toast(format!("saved {}", p.display())),
                Err(e) => self.error(format!("screenshot failed: {e:#}")),
            }
        }
    }

    fn handle_dropped_files(&mut self, ctx: &egui::Context) {
        let dropped: Vec<PathBuf> = ctx.input(|i| i.raw.dropped_files.iter().map(|f| f.path().to_path_buf()).collect());
        if let Some(path) = dropped.first() {
            self.open_path(path);
        }
    }

    /// Camera input from the view's response and the keyboard.
    fn camera_input(&self, ctx: &egui::Context, response: &egui::Response, gizmo_active: bool) -> CameraInput {
        let dt = ctx.input(|i| i.stable_dt).min(0.1);
        let mut input = CameraInput { dt_secs: dt, ..Default::default() };
        if !gizmo_active && response.dragged_by(egui::PointerButton::Primary) {
            let d = response.drag_delta();
            input.rotate = glam::Vec2::new(d.x, d.y);
        }
        if response.dragged_by(egui::PointerButton::Middle) || response.dragged_by(egui::PointerButton::Secondary) {
            let d = response.drag_delta();
            input.pan = glam::Vec2::new(d.x, d.y);
        }
        if response.hovered() {
            input.zoom = ctx.input(|i| i.smooth_scroll_delta.y);
        }
        if self.session.camera.mode == CameraMode::Fly && !ctx.egui_wants_keyboard_input() {
            ctx.input(|i| {
                let axis = |pos: egui::Key, neg: egui::Key| (i.key_down(pos) as i32 - i.key_down(neg) as i32) as f32;
                input.movement = Vec3::new(
                    axis(egui::Key::W, egui::Key::S),
                    axis(egui::Key::D, egui::Key::A),
                    axis(egui::Key::E, egui::Key::Q),
                );
                input.fast = i.modifiers.shift;
            });
        }
        input
    }

    /// The central 3D view: image(s), gizmo, picking, camera.
    fn viewport_ui(&mut self, ui: &mut egui::Ui) {
        if let Some(recovery) = &self.recovery {
            // No device to render with: the view says why and where the state went, until the window closes.
            let message = recovery.message.clone();
            ui.centered_and_justified(|ui| {
                ui.label(egui::RichText::new(message).color(ui.visuals().error_fg_color).size(16.0));
            });
            return;
        }
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
        self.last_viewport_rect = Some(rect);
        let projection_rect = if self.session.view.mode == ViewMode::SideBySide {
            egui::Rect::from_min_size(rect.min, egui::vec2(rect.width() * 0.5, rect.height()))
        } else {
            rect
        };
        let camera = self.session.camera.camera();
        let projection = Projection::new(&camera, projection_rect);

        // Gizmo and picking: a light, or a camera of the technique (INSM's viewpoints).
        let pointer = response.interact_pointer_pos().or(response.hover_pos());
        let selected_target = self.session.gizmo_target();
        let selected_pos = selected_target.as_ref().and_then(|t| self.session.target_position(t));
        if response.drag_started_by(egui::PointerButton::Primary) {
            if let (Some(pos), Some(at), Some(target)) = (pointer, selected_pos, selected_target.clone()) {
                if let Some(handle) = gizmo::hit_handle(&projection, at, pos) {
                    if matches!(target, DragTarget::Light(_)) {
                        self.session.begin_edit();
                    }
                    self.drag = Some(GizmoDrag { handle, target, start: at, accumulated: egui::Vec2::ZERO });
                }
            }
        }
        if let Some(drag) = self.drag.clone() {
            if response.dragged_by(egui::PointerButton::Primary) {
                let accumulated = drag.accumulated + response.drag_delta();
                let delta = gizmo::drag_delta(&projection, drag.start, drag.handle, accumulated);
                self.session.set_target_position(&drag.target, drag.start + delta);
                if let Some(d) = &mut self.drag {
                    d.accumulated = accumulated;
                }
                self.last_interaction = Some(Instant::now());
            }
            if response.drag_stopped() || !ui.input(|i| i.pointer.primary_down()) {
                self.drag = None;
            }
        }
        let gizmo_active = self.drag.is_some();
        if response.clicked() {
            if let Some(pos) = response.interact_pointer_pos() {
                let ctrl = ui.input(|i| i.modifiers.command);
                let alt = ui.input(|i| i.modifiers.alt);
                if alt {
                    self.probe_at(pos, projection.rect);
                } else if ctrl {
                    let (o, d) = projection.ray(pos);
                    if let Some((t, n)) = gizmo::pick_surface(&self.session.scene, o, d) {
                        self.session.add_light_at(o + d * t, n);
                    }
                } else if selected_pos.and_then(|at| gizmo::hit_handle(&projection, at, pos)).is_none() {
                    self.session.selected = gizmo::pick_light(&projection, &self.session.animated_lights(), pos, 12.0);
                    self.session.selected_camera = None;
                    if self.session.selected.is_none() {
                        self.session.selected_camera = self.session.technique_cameras().and_then(|(key, cameras)| {
                            gizmo::pick_point(&projection, cameras.iter().map(|c| c.position), pos, 12.0)
                                .map(|i| (key, i))
                        });
                    }
                }
            }
        }
        response.context_menu(|ui| {
            if ui.button("Add light here").clicked() {
                if let Some(pos) = ui.ctx().input(|i| i.pointer.interact_pos()) {
                    let (o, d) = projection.ray(pos);
                    if let Some((t, n)) = gizmo::pick_surface(&self.session.scene, o, d) {
                        self.session.add_light_at(o + d * t, n);
                    }
                }
                ui.close();
            }
        });

        let mut input = self.camera_input(ui.ctx(), &response, gizmo_active);
        if self.orbit_demo {
            // About 40 points of drag per second, like a slow orbit by hand.
            input.rotate.x += 40.0 * input.dt_secs;
            ui.ctx().request_repaint();
        }
        if self.session.camera.update(&input) {
            self.last_interaction = Some(Instant::now());
        }
        let interacting = gizmo_active
            || input.is_active()
            || self.last_interaction.is_some_and(|t| t.elapsed().as_secs_f32() < 0.25);

        let ppp = ui.ctx().pixels_per_point();
        self.last_view_pixels = rect.size() * ppp;
        if let Err(e) = self.render_views(rect.size() * ppp, ppp, interacting) {
            self.status = format!("render error: {e:#}");
        }
        if self.session.view.mode == ViewMode::Difference {
            if let Err(e) = self.update_difference(ui.ctx()) {
                self.status = format!("difference: {e:#}");
            }
        }

        // Show the images.
        let painter = ui.painter_at(rect);
        let indirect = self.session.indirect.technique.as_deref();
        let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
        if let Some(gpu) = &self.gpu {
            match self.session.view.mode {
                ViewMode::Single => {
                    painter.image(gpu.main.texture_id, rect, uv, egui::Color32::WHITE);
                }
                ViewMode::SideBySide => {
                    let (l, r) = rect.split_left_right_at_fraction(0.5);
                    painter.image(gpu.main.texture_id, l, uv, egui::Color32::WHITE);
                    painter.image(gpu.reference.texture_id, r, uv, egui::Color32::WHITE);
                    painter.line_segment([r.left_top(), r.left_bottom()], egui::Stroke::new(2.0, egui::Color32::BLACK));
                    label(&painter, l.left_top(), &technique_pair(&self.session.technique, indirect));
                    label(&painter, r.left_top(), &technique_pair(&self.session.view.compare_against, indirect));
                }
                ViewMode::Difference => match &self.difference {
                    Some(d) => {
                        painter.image(d.texture.id(), rect, uv, egui::Color32::WHITE);
                        let m = &d.metrics;
                        label(
                            &painter,
                            rect.left_top(),
                            &format!(
                                "{} vs {}: RMSE {:.4}  PSNR {}  FLIP {}  shadow error {}",
                                technique_pair(&self.session.technique, indirect),
                                technique_pair(&self.session.view.compare_against, indirect),
                                m.rmse,
                                m.psnr_db.map(|p| format!("{p:.1} dB")).unwrap_or_else(|| "inf".into()),
                                m.flip_mean.map(|f| format!("{f:.3}")).unwrap_or_else(|| "-".into()),
                                m.shadow_intensity_error
                                    .map(|e| format!("{:.2}%", e * 100.0))
                                    .unwrap_or_else(|| "-".into()),
                            ),
                        );
                        legend(&painter, rect, self.session.view.diff_signed, self.session.view.diff_gain);
                    }
                    None => {
                        painter.image(gpu.main.texture_id, rect, uv, egui::Color32::from_gray(90));
                        label(&painter, rect.left_top(), "computing the difference when both images are complete…");
                    }
                },
                ViewMode::Split => {
                    let x = rect.left() + rect.width() * self.session.view.split.clamp(0.0, 1.0);
                    let s = self.session.view.split.clamp(0.0, 1.0);
                    let left = egui::Rect::from_min_max(rect.min, egui::pos2(x, rect.bottom()));
                    let right = egui::Rect::from_min_max(egui::pos2(x, rect.top()), rect.max);
                    painter.image(
                        gpu.main.texture_id,
                        left,
                        egui::Rect::from_min_max(uv.min, egui::pos2(s, 1.0)),
                        egui::Color32::WHITE,
                    );
                    painter.image(
                        gpu.reference.texture_id,
                        right,
                        egui::Rect::from_min_max(egui::pos2(s, 0.0), uv.max),
                        egui::Color32::WHITE,
                    );
                    painter.line_segment(
                        [egui::pos2(x, rect.top()), egui::pos2(x, rect.bottom())],
                        egui::Stroke::new(2.0, egui::Color32::WHITE),
                    );
                    label(&painter, rect.left_top(), &technique_pair(&self.session.technique, indirect));
                    label(
                        &painter,
                        egui::pos2(x, rect.top()),
                        &technique_pair(&self.session.view.compare_against, indirect),
                    );
                    // The split line is draggable from a handle at its middle.
                    let handle = egui::Rect::from_center_size(egui::pos2(x, rect.center().y), egui::vec2(14.0, 40.0));
                    let h = ui.interact(handle, ui.scope_id().with("split"), egui::Sense::drag());
                    painter.rect_filled(handle, 3.0, egui::Color32::from_white_alpha(200));
                    if h.dragged() {
                        self.session.view.split = ((x + h.drag_delta().x - rect.left()) / rect.width()).clamp(0.0, 1.0);
                    }
                }
            }
            // Progress of the frame being refined.
            let progress = gpu.main.progress.min(if self.session.view.mode == ViewMode::Single {
                1.0
            } else {
                gpu.reference.progress
            });
            if progress < 1.0 {
                let bar = egui::Rect::from_min_size(
                    rect.left_bottom() - egui::vec2(0.0, 4.0),
                    egui::vec2(rect.width() * progress, 4.0),
                );
                painter.rect_filled(bar, 0.0, egui::Color32::from_rgb(90, 170, 255));
                ui.ctx().request_repaint();
            }
        }
        if let Some(at) = self.session.gizmo_target().and_then(|t| self.session.target_position(&t)) {
            let hover = pointer.and_then(|p| gizmo::hit_handle(&projection, at, p));
            gizmo::paint(&painter, &projection, at, self.drag.as_ref().map(|d| d.handle).or(hover));
        }
        if self.session.view.legend {
            legend::paint_in_view(&painter, rect, &self.legends);
        }
        // A light under the pointer: its details in a tooltip.
        if self.drag.is_none() && !interacting {
            if let Some(pos) = response.hover_pos() {
                let lines = match gizmo::pick_light(&projection, &self.session.animated_lights(), pos, 10.0) {
                    Some(i) => self.light_tooltip(i),
                    None => {
                        let camera = self.camera_tooltip(&projection, pos);
                        if camera.is_empty() {
                            self.overlay_tooltip(&projection, pos)
                        } else {
                            camera
                        }
                    }
                };
                if !lines.is_empty() {
                    response.clone().on_hover_ui_at_pointer(|ui| {
                        for l in &lines {
                            ui.label(l);
                        }
                    });
                }
            }
        }
        if interacting || self.session.animation != Animation::Off {
            ui.ctx().request_repaint();
        }
    }

    fn toasts_ui(&mut self, ctx: &egui::Context) {
        let now = Instant::now();
        self.toasts.retain(|t| t.until > now);
        if self.toasts.is_empty() {
            return;
        }
        egui::Area::new(egui::Id::unique("toasts")).anchor(egui::Align2::RIGHT_BOTTOM, egui::vec2(-12.0, -40.0)).show(
            ctx,
            |ui| {
                for t in &self.toasts {
                    let color =
                        if t.error { egui::Color32::from_rgb(255, 120, 120) } else { egui::Color32::LIGHT_GREEN };
                    egui::Frame::popup(ui.style()).show(ui, |ui| {
                        ui.colored_label(color, &t.text);
                    });
                }
            },
        );
        ctx.request_repaint_after(std::time::Duration::from_millis(500));
    }
}

/// The name of a frame's techniques in the session table: the direct one, and `+ indirect` when it had one.
pub fn session_name(report: &shadowlab_core::FrameReport) -> String {
    technique_pair(&report.technique, report.indirect.as_ref().map(|i| i.technique.as_str()))
}

/// `direct`, or `direct + indirect`.
pub fn technique_pair(direct: &str, indirect: Option<&str>) -> String {
    match indirect {
        Some(i) => format!("{direct} + {i}"),
        None => direct.to_string(),
    }
}

fn label(painter: &egui::Painter, at: egui::Pos2, text: &str) {
    painter.text(
        at + egui::vec2(6.0, 4.0),
        egui::Align2::LEFT_TOP,
        text,
        egui::FontId::proportional(13.0),
        egui::Color32::WHITE,
    );
}

/// Colour legend of the difference view.
fn legend(painter: &egui::Painter, rect: egui::Rect, signed: bool, gain: f32) {
    let w = 160.0;
    let origin = rect.right_bottom() - egui::vec2(w + 16.0, 34.0);
    for i in 0..w as usize {
        let t = i as f32 / (w - 1.0);
        let color = if signed {
            let s = t * 2.0 - 1.0;
            let v = (s.abs() * 255.0) as u8;
            if s >= 0.0 {
                egui::Color32::from_rgb(v, 0, 0)
            } else {
                egui::Color32::from_rgb(0, v, 0)
            }
        } else {
            let [r, g, b] = shadowlab_core::compare::colormap(t);
            egui::Color32::from_rgb(r, g, b)
        };
        painter.rect_filled(
            egui::Rect::from_min_size(origin + egui::vec2(i as f32, 0.0), egui::vec2(1.0, 10.0)),
            0.0,
            color,
        );
    }
    let (lo, hi) = if signed {
        (format!("-{:.2}", 1.0 / gain), format!("+{:.2}", 1.0 / gain))
    } else {
        ("0".into(), format!("{:.2}", 1.0 / gain))
    };
    painter.text(
        origin + egui::vec2(0.0, 12.0),
        egui::Align2::LEFT_TOP,
        lo,
        egui::FontId::proportional(11.0),
        egui::Color32::WHITE,
    );
    painter.text(
        origin + egui::vec2(w, 12.0),
        egui::Align2::RIGHT_TOP,
        hi,
        egui::FontId::proportional(11.0),
        egui::Color32::WHITE,
    );
}

fn chrono_like_stamp() -> String {
    let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_millis()).unwrap_or(0);
    format!("{secs}")
}

fn recent_path(dir: &Path) -> PathBuf {
    dir.join("recent.ron")
}

fn load_recent(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_to_string(recent_path(dir)).ok().and_then(|t| ron::from_str(&t).ok()).unwrap_or_default()
}

fn save_recent(dir: &Path, recent: &[PathBuf]) {
    let write = || -> Result<()> {
        std::fs::create_dir_all(dir)?;
        crate::files::write_atomic(&recent_path(dir), ron::to_string(recent)?.as_bytes())
    };
    if let Err(e) = write() {
        log::warn!("cannot save the recent files list: {e:#}");
    }
}

impl eframe::App for ShadowLabApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.ui_frames += 1;
        let now = Instant::now();
        let dt = now.duration_since(self.last_frame).as_secs_f64() * 1000.0;
        self.last_frame = now;
        self.ui_frame_ms.push_back(dt);
        if self.ui_frame_ms.len() > 120 {
            self.ui_frame_ms.pop_front();
        }
        if self.session.animation != Animation::Off {
            self.session.animation_time += ctx.input(|i| i.stable_dt).min(0.1);
        }
        // wgpu reports a lost device from its poll: poll (without waiting) before touching the device this
        // frame, so a loss is handled before anything is created on it (wgpu's buffer helpers panic then).
        // (GpuContext's device-lost callback records the loss; every renderer call refuses work after it.)
        let lost = self.gpu.as_ref().and_then(|gpu| {
            let _ = gpu.ctx.device.poll(wgpu::PollType::Poll);
            gpu.ctx.lost()
        });
        if let Some(reason) = lost {
            self.handle_device_lost(&ctx, reason);
        }
        let uncaptured: Vec<String> =
            self.uncaptured_errors.lock().map(|mut v| std::mem::take(&mut *v)).unwrap_or_default();
        for e in uncaptured {
            self.error(format!("GPU error: {e}"));
        }
        self.receive_screenshots(&ctx);
        if let Some(secs) = self.quit_after_secs {
            if !self.quitting && self.started.elapsed().as_secs_f32() >= secs {
                self.quitting = true;
                let t = self.started.elapsed().as_secs_f64();
                eprintln!("UI frames: {} in {t:.1} s ({:.1} fps)", self.ui_frames, self.ui_frames as f64 / t);
                if self.exit_screenshot.is_some() {
                    self.request_window_screenshot(&ctx);
                } else {
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                }
            }
            ctx.request_repaint();
        }
        self.handle_dropped_files(&ctx);
        self.handle_shortcuts(&ctx);
        if self.session.selected != self.last_selected {
            if self.session.selected.is_some() {
                self.layout.focus(layout::Pane::Lights);
            }
            self.last_selected = self.session.selected;
        }
        if self.layout.full_view {
            egui::CentralPanel::default().frame(egui::Frame::NONE).show(ui, |ui| {
                self.viewport_ui(ui);
                let at = ui.max_rect().right_top() + egui::vec2(-8.0, 8.0);
                egui::Area::new(egui::Id::unique("leave full view")).fixed_pos(at).pivot(egui::Align2::RIGHT_TOP).show(
                    ui.ctx(),
                    |ui| {
                        if ui.button("Show panels (Tab)").clicked() {
                            self.layout.toggle_full_view();
                        }
                    },
                );
            });
        } else {
            panels::menu_bar(self, ui);
            egui::CentralPanel::default().frame(egui::Frame::NONE).show(ui, |ui| layout::tiles_ui(self, ui));
        }
        self.layout.save_if_changed(&self.data_dir, &ctx);
        self.toasts_ui(&ctx);
    }

    fn on_exit(&mut self) {
        if let Err(e) = self.layout.save(&self.data_dir) {
            log::warn!("cannot save the layout: {e:#}");
        }
    }
}
