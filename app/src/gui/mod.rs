//! The interactive app: a 3D view of the scene rendered by the core (progressively, on eframe's device),
//! light editing with picking, a move gizmo and undo/redo, technique selection with generated parameter panels,
//! overlays, side-by-side and split comparison with the reference, live timings, screenshots and scene files.
//! An indirect technique (`INDIRECT_REGISTRY`, none by default) can be added to every view, with its own
//! generated panel, the shared VPL settings and the component (total, direct, indirect) the views show.

pub mod camera;
pub mod capture;
pub mod chrome;
pub mod document;
pub mod gizmo;
pub mod inspector;
pub mod layout;
pub mod legend;
pub mod menu;
pub mod panels;
pub mod session;
pub mod sweep;
pub mod tiles;
pub mod views;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{anyhow, Context, Result};
use eframe::{egui, egui_wgpu};
use glam::Vec3;
use shadowlab_core::scene::{Scene, SceneSource};
use shadowlab_core::technique::ParamValue;
use shadowlab_core::GpuContext;

use camera::{CameraInput, CameraMode};
use chrome::Chrome;
use document::{SceneFile, ViewMode};
use gizmo::{Handle, Projection};
pub use session::Animation;
use session::{DragTarget, Session};
use views::view::{StepSizer, View};
use views::{Gpu, Views};

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
    /// The renderers and what is derived from their frames (difference, ID maps, legends, timings).
    pub views: Views,
    /// The panels around the views and their state, the toasts.
    pub chrome: Chrome,
    drag: Option<GizmoDrag>,
    data_dir: PathBuf,
    /// When the app started (the time axis of the timings; `quit_after_secs`).
    started: Instant,
    last_interaction: Option<Instant>,
    window_shot: Arc<std::sync::Mutex<Option<Arc<egui::ColorImage>>>>,
    last_frame: Instant,
    exit_screenshot: Option<PathBuf>,
    quit_after_secs: Option<f32>,
    quitting: bool,
    orbit_demo: bool,
    ui_frames: u64,
    /// wgpu errors outside any error scope (egui's own painting, say), shown instead of panicking.
    uncaptured_errors: Arc<std::sync::Mutex<Vec<String>>>,
    relaunch_on_device_loss: bool,
    /// Set once the device was lost: the state was saved and the window says what happens next.
    pub recovery: Option<Recovery>,
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
        let started = Instant::now();
        let mut app = ShadowLabApp {
            session: Session::new(scene),
            views: Views::new(started, !startup.synchronous),
            chrome: Chrome::new(layout, load_recent(&data_dir)),
            drag: None,
            data_dir,
            started,
            last_interaction: None,
            window_shot: Default::default(),
            last_frame: Instant::now(),
            exit_screenshot: startup.screenshot.clone(),
            quit_after_secs: startup.quit_after_secs,
            quitting: false,
            orbit_demo: startup.orbit_demo,
            ui_frames: 0,
            uncaptured_errors: Default::default(),
            relaunch_on_device_loss: startup.relaunch_on_device_loss,
            recovery: None,
        };
        let render_state = cc.wgpu_render_state.clone().ok_or_else(|| anyhow!("ShadowLab needs the wgpu renderer"))?;
        app.init_gpu(render_state)?;
        if startup.synchronous {
            if let Some(gpu) = &mut app.views.gpu {
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
        self.views.gpu = Some(Gpu { ctx, render_state: rs, main, reference, sizer });
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
        self.views.gpu = None;
        self.views.sweep = None;
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
        self.chrome.status = recovery.message.clone();
        self.recovery = Some(recovery);
    }

    pub fn toast(&mut self, text: impl Into<String>) {
        self.chrome.toasts.say(text);
    }

    pub fn error(&mut self, text: impl Into<String>) {
        self.chrome.toasts.error(text);
    }

    // ----- scenes and files -----

    /// Replace the scene (and its lights and camera). The previous scene stays when `scene` failed to load.
    pub fn set_scene(&mut self, scene: Scene) {
        self.views.set_scene(&scene);
        for text in self.session.set_scene(scene) {
            self.chrome.toasts.note(text, 6);
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
        if let Some(gpu) = &mut self.views.gpu {
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
        self.chrome.recent.retain(|p| p != &path);
        self.chrome.recent.insert(0, path);
        self.chrome.recent.truncate(10);
        save_recent(&self.data_dir, &self.chrome.recent);
    }

    // ----- lights -----

    pub fn apply_layout(&mut self, spec: &str) {
        match self.session.apply_layout(spec) {
            Ok(n) => self.toast(format!("{n} lights from '{spec}'")),
            Err(e) => self.error(e.to_string()),
        }
    }

    // ----- rendering -----

    // ----- the views -----

    /// Names of the overlay layers the current technique offers, with their state.
    pub fn overlay_layers(&mut self) -> Vec<(String, bool)> {
        self.views.overlay_layers(&self.session)
    }

    /// What the current technique made of light `index` in its last frame (its cluster, say).
    pub fn light_details(&mut self, index: usize) -> Option<shadowlab_core::technique::LightDetails> {
        self.views.light_details(&self.session, index)
    }

    /// The tooltip of a light in the view: its fields, and what the technique made of it.
    pub fn light_tooltip(&mut self, index: usize) -> Vec<String> {
        self.views.light_tooltip(&self.session, index)
    }

    /// The tooltip of a camera the technique used (a `Cameras` parameter's, e.g. an INSM viewpoint) under `pos`.
    pub fn camera_tooltip(&mut self, projection: &Projection, pos: egui::Pos2) -> Vec<String> {
        self.views.camera_tooltip(&self.session, projection, pos)
    }

    /// The tooltip of what a visible overlay layer draws under `pos` (see [`Views::overlay_tooltip`]).
    pub fn overlay_tooltip(&mut self, projection: &Projection, pos: egui::Pos2) -> Vec<String> {
        self.views.overlay_tooltip(&self.session, projection, pos)
    }

    /// Start a sweep of `key` over `values` for the current technique, view and lights.
    pub fn start_sweep(&mut self, key: &str, values: Vec<ParamValue>) -> Result<()> {
        self.views.start_sweep(&self.session, key, values)
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
        let gpu = self.views.gpu.as_ref().ok_or_else(|| anyhow!("no GPU"))?;
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
            self.chrome.layout.toggle_full_view();
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
        self.views.last_viewport_rect = Some(rect);
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
                    if let Some(status) = self.views.probe_at(&mut self.session, pos, projection.rect) {
                        self.chrome.status = status;
                    }
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
        self.views.last_view_pixels = rect.size() * ppp;
        if let Err(e) = self.views.render(&self.session, rect.size() * ppp, ppp, interacting) {
            self.chrome.status = format!("render error: {e:#}");
        }
        if self.session.view.mode == ViewMode::Difference {
            if let Err(e) = self.views.update_difference(&self.session, ui.ctx()) {
                self.chrome.status = format!("difference: {e:#}");
            }
        }

        // Show the images.
        let painter = ui.painter_at(rect);
        self.views.paint(ui, &painter, rect, &mut self.session);
        if let Some(at) = self.session.gizmo_target().and_then(|t| self.session.target_position(&t)) {
            let hover = pointer.and_then(|p| gizmo::hit_handle(&projection, at, p));
            gizmo::paint(&painter, &projection, at, self.drag.as_ref().map(|d| d.handle).or(hover));
        }
        if self.session.view.legend {
            legend::paint_in_view(&painter, rect, &self.views.legends);
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
        self.chrome.ui_frame_ms.push_back(dt);
        if self.chrome.ui_frame_ms.len() > 120 {
            self.chrome.ui_frame_ms.pop_front();
        }
        if self.session.animation != Animation::Off {
            self.session.animation_time += ctx.input(|i| i.stable_dt).min(0.1);
        }
        // wgpu reports a lost device from its poll: poll (without waiting) before touching the device this
        // frame, so a loss is handled before anything is created on it (wgpu's buffer helpers panic then).
        // (GpuContext's device-lost callback records the loss; every renderer call refuses work after it.)
        let lost = self.views.gpu.as_ref().and_then(|gpu| {
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
        if self.session.selected != self.chrome.last_selected {
            if self.session.selected.is_some() {
                self.chrome.layout.focus(layout::Pane::Lights);
            }
            self.chrome.last_selected = self.session.selected;
        }
        if self.chrome.layout.full_view {
            egui::CentralPanel::default().frame(egui::Frame::NONE).show(ui, |ui| {
                self.viewport_ui(ui);
                let at = ui.max_rect().right_top() + egui::vec2(-8.0, 8.0);
                egui::Area::new(egui::Id::unique("leave full view")).fixed_pos(at).pivot(egui::Align2::RIGHT_TOP).show(
                    ui.ctx(),
                    |ui| {
                        if ui.button("Show panels (Tab)").clicked() {
                            self.chrome.layout.toggle_full_view();
                        }
                    },
                );
            });
        } else {
            menu::menu_bar(self, ui);
            egui::CentralPanel::default().frame(egui::Frame::NONE).show(ui, |ui| tiles::tiles_ui(self, ui));
        }
        self.chrome.layout.save_if_changed(&self.data_dir, &ctx);
        self.chrome.toasts.ui(&ctx);
    }

    fn on_exit(&mut self) {
        if let Err(e) = self.chrome.layout.save(&self.data_dir) {
            log::warn!("cannot save the layout: {e:#}");
        }
    }
}
