//! The interactive app: a 3D view of the scene rendered by the core (progressively, on eframe's device),
//! light editing with picking, a move gizmo and undo/redo, technique selection with generated parameter panels,
//! overlays, side-by-side and split comparison with the reference, live timings, screenshots and scene files.
//! An indirect technique (`INDIRECT_REGISTRY`, none by default) can be added to every view, with its own
//! generated panel, the shared VPL settings and the component (total, direct, indirect) the views show.
//!
//! [`ShadowLabApp`] is made of parts, each in its own module: the [`session`] (what the user edits and a scene
//! file saves, with the undo history and the selection), the [`views`] (the renderers and what their frames
//! give: overlays, ID maps, the difference, timings, tooltips, painting), the [`chrome`] around them (the
//! [`layout`] of the [`tiles`], the [`panels`], the [`menu`], toasts), the 3D view's input ([`interact`]), and
//! the window's life (opening and saving in [`open`], screenshots and figures in [`capture`], device loss in
//! [`recovery`]). The panels take the parts they show, not the app; only the menu, the tiles, the input and
//! the file and capture code work on the whole app.

pub mod camera;
pub mod capture;
pub mod chrome;
pub mod document;
pub mod gizmo;
pub mod image_view;
pub mod inspector;
pub mod interact;
pub mod layout;
pub mod legend;
pub mod menu;
pub mod open;
pub mod panels;
pub mod recovery;
pub mod rsm_view;
pub mod session;
pub mod session_times;
pub mod soak;
pub mod start;
pub mod state;
pub mod sweep;
pub mod tiles;
pub mod toasts;
pub mod tradeoff_input;
pub mod tradeoff_run;
pub mod views;
pub mod worker;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{anyhow, Result};
use eframe::{egui, egui_wgpu};
use shadowlab_core::scene::Scene;
use shadowlab_core::technique::ParamValue;
use shadowlab_core::GpuContext;

use camera::CameraMode;
use chrome::Chrome;
use gizmo::Projection;
pub use session::Animation;
use session::Session;
use state::Interaction;
pub use state::Recovery;
pub use state::StartState;
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
    /// Start on this built-in scene.
    pub builtin: Option<String>,
    /// Start with these techniques, parameters, view and comparison target.
    pub start: StartState,
    /// Answer every file dialog with Cancel (tests that drive the app with random input).
    pub no_file_dialogs: bool,
    /// A long run of this many seconds: lights animated, techniques switched in turn, memory printed
    /// ([`soak`]); quits at the end.
    pub soak_secs: Option<f32>,
    /// Window size in points.
    pub window_size: Option<(f32, f32)>,
    /// When the GPU device is lost, start a new ShadowLab on the saved recovery file and close this one
    /// (the binary does; tests only record the command).
    pub relaunch_on_device_loss: bool,
}

/// The device setup ShadowLab asks eframe for: the adapter [`select_adapter`] picks among the backends
/// `WGPU_BACKEND` allows, and the device the CLI asks for too ([`shadowlab_core::gpu::device_descriptor`]:
/// compute shaders, timestamp queries when the adapter has them, the adapter's texture and buffer limits).
pub fn wgpu_setup() -> egui_wgpu::WgpuSetup {
    wgpu_setup_with(egui_wgpu::WgpuSetupCreateNew::without_display_handle())
}

/// [`wgpu_setup`] on the given backends only (tests of one backend, e.g. `wgpu::Backends::GL`).
pub fn wgpu_setup_on(backends: wgpu::Backends) -> egui_wgpu::WgpuSetup {
    let mut setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    setup.instance_descriptor.backends = backends;
    wgpu_setup_with(setup)
}

fn wgpu_setup_with(mut setup: egui_wgpu::WgpuSetupCreateNew) -> egui_wgpu::WgpuSetup {
    setup.native_adapter_selector = Some(Arc::new(select_adapter));
    setup.device_descriptor = Arc::new(shadowlab_core::gpu::device_descriptor);
    egui_wgpu::WgpuSetup::CreateNew(setup)
}

/// The adapter the app runs on, among those `WGPU_BACKEND` allows: the one `WGPU_ADAPTER_NAME` names when set,
/// else a real GPU before a software one and any backend before GL (where Mesa offers both lavapipe (Vulkan)
/// and llvmpipe (GL), wgpu's own choice can fall on GL). Adapters without compute shaders, which every technique
/// needs, are passed over, and when only those are left the error says so.
pub fn select_adapter(
    adapters: &[wgpu::Adapter],
    surface: Option<&wgpu::Surface<'_>>,
) -> Result<wgpu::Adapter, String> {
    let shown: Vec<&wgpu::Adapter> =
        adapters.iter().filter(|a| surface.is_none_or(|s| a.is_surface_supported(s))).collect();
    let usable: Vec<&wgpu::Adapter> = shown.iter().copied().filter(|a| shadowlab_core::gpu::has_compute(a)).collect();
    let no_compute = |a: &wgpu::Adapter| {
        shadowlab_core::GpuError::NoCompute(format!("{} ({:?})", a.get_info().name, a.get_info().backend)).to_string()
    };
    if let Ok(wanted) = std::env::var("WGPU_ADAPTER_NAME") {
        let wanted = wanted.to_lowercase();
        let named = |a: &&&wgpu::Adapter| a.get_info().name.to_lowercase().contains(&wanted);
        return match (usable.iter().find(named), shown.iter().find(named)) {
            (Some(a), _) => Ok((*a).clone()),
            (None, Some(a)) => Err(no_compute(a)),
            (None, None) => Err(format!("no adapter named like WGPU_ADAPTER_NAME={wanted}")),
        };
    }
    if usable.is_empty() {
        if let Some(a) = shown.first() {
            return Err(no_compute(a));
        }
    }
    let rank = |a: &&wgpu::Adapter| {
        let info = a.get_info();
        let kind = match info.device_type {
            wgpu::DeviceType::DiscreteGpu => 0,
            wgpu::DeviceType::IntegratedGpu => 1,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Cpu => 3,
            wgpu::DeviceType::Other => 4,
        };
        (info.backend == wgpu::Backend::Gl, kind)
    };
    usable.into_iter().min_by_key(rank).cloned().ok_or_else(|| "no graphics adapter found".to_string())
}

/// The window size when none is given: 1400x860, or 1024x640 on a software rasterizer (`software`), where
/// egui's drawing and the presentation of the window cost in proportion to its area (`docs/measurements.md`,
/// UI frame rate of the app).
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

/// The app: the session the user edits, the views that render it, the chrome around them, the 3D view's
/// input and the window's lifecycle.
pub struct ShadowLabApp {
    /// The scene, lights, camera, techniques and settings the user edits (what a scene file saves).
    pub session: Session,
    /// The renderers and what is derived from their frames (difference, ID maps, legends, timings).
    pub views: Views,
    /// The panels around the views and their state, the toasts.
    pub chrome: Chrome,
    /// The 3D view's input state (the gizmo drag).
    interaction: Interaction,
    lifecycle: Lifecycle,
    /// Set once the device was lost: the state was saved and the window says what happens next.
    pub recovery: Option<Recovery>,
    /// A long run in progress (`Startup::soak_secs`).
    soak: Option<state::Soak>,
}

/// The window's life: where its files go, its clocks, screenshots of it, quitting after a time, GPU errors
/// outside any error scope, and whether a lost device starts a new ShadowLab.
struct Lifecycle {
    data_dir: PathBuf,
    /// When the app started (the time axis of the timings; `quit_after_secs`).
    started: Instant,
    last_frame: Instant,
    ui_frames: u64,
    window_shot: Arc<std::sync::Mutex<Option<Arc<egui::ColorImage>>>>,
    exit_screenshot: Option<PathBuf>,
    quit_after_secs: Option<f32>,
    quitting: bool,
    /// Where the UI frames' time went (printed at quit).
    breakdown: FrameBreakdown,
    /// wgpu errors outside any error scope (egui's own painting, say), shown instead of panicking.
    uncaptured_errors: Arc<std::sync::Mutex<Vec<String>>>,
    relaunch_on_device_loss: bool,
    /// `--app-overlay` layers (as given, and their names) to check once a frame has completed.
    start_overlays: Vec<(String, String)>,
}

/// Where a UI frame's time goes, from one `ui` call to the next: our rendering ([`Views::render`]), the rest of
/// building the UI in `ui` (panels, overlays' primitives, egui's layout), and what eframe does between two `ui`
/// calls (egui's tessellation, the wgpu painting of the window, presentation and waiting for the next frame).
#[derive(Default)]
struct FrameBreakdown {
    /// Per UI frame: (interval to the next one, ui() total, our rendering), in ms.
    frames: Vec<(f64, f64, f64)>,
    /// The last frame's (ui() total, our rendering), waiting for the next frame's start.
    last: Option<(f64, f64)>,
}

impl FrameBreakdown {
    /// A frame started `interval` ms after the last one started.
    fn next_frame(&mut self, interval: f64) {
        if let Some((ui, render)) = self.last.take() {
            if self.frames.len() < 100_000 {
                self.frames.push((interval, ui, render));
            }
        }
    }

    /// The frame that started last spent `ui` ms in ui(), `render` of them in our rendering.
    fn frame_done(&mut self, ui: f64, render: f64) {
        self.last = Some((ui, render));
    }

    /// "UI frame (median of N): 120.3 ms = our rendering 80.1 + the rest of ui() 10.2 + tessellation, painting and
    /// presentation 30.0" (the parts are medians of their own; their sum is near the interval's median).
    fn text(&self) -> Option<String> {
        // The first frames build fonts and pipelines: left out.
        let frames = self.frames.get(10..).filter(|f| !f.is_empty())?;
        let median = |f: &dyn Fn(&(f64, f64, f64)) -> f64| {
            let mut v: Vec<f64> = frames.iter().map(f).collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let (interval, ui, render) = (median(&|f| f.0), median(&|f| f.1), median(&|f| f.2));
        let outside = median(&|f| (f.0 - f.1).max(0.0));
        Some(format!(
            "UI frame (median of {}): {interval:.1} ms = our rendering {render:.1} + the rest of ui() {:.1} + egui's \
             tessellation, painting and presentation (between ui() calls) {outside:.1}",
            frames.len(),
            (ui - render).max(0.0)
        ))
    }
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
            chrome: Chrome::new(layout, state::load_recent(&data_dir)),
            interaction: Interaction::new(startup.orbit_demo),
            lifecycle: Lifecycle {
                data_dir,
                started,
                last_frame: Instant::now(),
                ui_frames: 0,
                breakdown: FrameBreakdown::default(),
                window_shot: Default::default(),
                exit_screenshot: startup.screenshot.clone(),
                quit_after_secs: startup.soak_secs.or(startup.quit_after_secs),
                quitting: false,
                uncaptured_errors: Default::default(),
                relaunch_on_device_loss: startup.relaunch_on_device_loss,
                start_overlays: Vec::new(),
            },
            recovery: None,
            soak: startup.soak_secs.map(|_| state::Soak::new()),
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
        app.chrome.file_dialogs = !startup.no_file_dialogs;
        app.apply_start(startup.start);
        Ok(app)
    }

    fn init_gpu(&mut self, rs: egui_wgpu::RenderState) -> Result<()> {
        // wgpu's default handler panics; core's calls run in error scopes, so what reaches this is egui's
        // painting or a bug: shown as an error instead of killing the window.
        let errors = self.lifecycle.uncaptured_errors.clone();
        rs.device.on_uncaptured_error(Arc::new(move |e| {
            log::error!("wgpu: {e}");
            if let Ok(mut v) = errors.lock() {
                if v.len() < 16 {
                    v.push(e.to_string());
                }
            }
        }));
        let ctx = GpuContext::from_device(rs.device.clone(), rs.queue.clone(), rs.adapter.get_info());
        let mut main = View::new(&ctx, &rs, &self.session.scene)?;
        let reference = View::sharing(&ctx, &rs, &main)?;
        // A real GPU renders a whole frame in one step; a software one starts small and adapts, and starts at
        // half resolution with 256-texel cube faces (lavapipe is ~100x slower; the user can raise both).
        let software = rs.adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        let sizer =
            if software { StepSizer::default() } else { StepSizer { max_lights_per_step: 256, ..Default::default() } };
        if software {
            self.session.view.resolution_scale = 0.5;
            // What each technique's registry entry says a software adapter starts with, parsed by the
            // parameter's own kind (a technique of the main view describes its parameters).
            for entry in
                shadowlab_core::technique::registry::REGISTRY.iter().filter(|e| !e.software_defaults.is_empty())
            {
                let Ok(technique) = main.technique(entry.key) else { continue };
                let params = technique.params();
                for (key, text) in entry.software_defaults {
                    let Some(param) = params.iter().find(|p| p.key == *key) else { continue };
                    if let Ok(value) = param.kind.parse(key, text) {
                        self.session.params.entry(entry.key.into()).or_default().insert(key.to_string(), value);
                    }
                }
            }
        }
        self.views.gpu = Some(Gpu { ctx, render_state: rs, main, reference, sizer });
        Ok(())
    }

    pub fn toast(&mut self, text: impl Into<String>) {
        self.chrome.toasts.say(text);
    }

    pub fn error(&mut self, text: impl Into<String>) {
        self.chrome.toasts.error(text);
    }

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
            self.views.frame_scene(&mut self.session);
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
}

impl eframe::App for ShadowLabApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.lifecycle.ui_frames += 1;
        let now = Instant::now();
        let dt = now.duration_since(self.lifecycle.last_frame).as_secs_f64() * 1000.0;
        self.views.ui_frame_render_ms = 0.0;
        self.lifecycle.breakdown.next_frame(dt);
        self.lifecycle.last_frame = now;
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
            self.lifecycle.uncaptured_errors.lock().map(|mut v| std::mem::take(&mut *v)).unwrap_or_default();
        for e in uncaptured {
            self.error(format!("GPU error: {e}"));
        }
        self.receive_screenshots(&ctx);
        self.check_start_overlays();
        if let Some(secs) = self.lifecycle.quit_after_secs {
            if !self.lifecycle.quitting && self.lifecycle.started.elapsed().as_secs_f32() >= secs {
                self.lifecycle.quitting = true;
                println!("{}", self.exit_line());
                if let Some(summary) = self.soak_summary() {
                    println!("{summary}");
                }
                let t = self.lifecycle.started.elapsed().as_secs_f64();
                eprintln!(
                    "UI frames: {} in {t:.1} s ({:.1} fps)",
                    self.lifecycle.ui_frames,
                    self.lifecycle.ui_frames as f64 / t
                );
                if let Some(text) = self.lifecycle.breakdown.text() {
                    eprintln!("{text}");
                }
                if self.lifecycle.exit_screenshot.is_some() {
                    self.request_window_screenshot(&ctx);
                } else {
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                }
            }
            ctx.request_repaint();
        }
        self.soak_frame();
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
            self.menu_bar(ui);
            egui::CentralPanel::default().frame(egui::Frame::NONE).show(ui, |ui| self.tiles_ui(ui));
        }
        self.chrome.layout.save_if_changed(&self.lifecycle.data_dir, &ctx);
        self.chrome.toasts.ui(&ctx);
        let ui_ms = now.elapsed().as_secs_f64() * 1000.0;
        self.lifecycle.breakdown.frame_done(ui_ms, self.views.ui_frame_render_ms);
    }

    fn on_exit(&mut self) {
        if let Err(e) = self.chrome.layout.save(&self.lifecycle.data_dir) {
            log::warn!("cannot save the layout: {e:#}");
        }
    }
}
