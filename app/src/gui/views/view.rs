//! The 3D view's GPU side: a core `Renderer` on eframe's device, rendering progressively into an offscreen
//! texture shown by egui. A frame's steps (batches of lights) are spread over UI frames within a time budget,
//! and the work per step adapts to the adapter's speed, so the UI stays responsive on a software GPU and a real
//! GPU still finishes in one UI frame. While the user drags, a cheap preview (unshadowed, lower resolution)
//! is shown instead, and the full technique restarts when the input settles.
//!
//! A view may also have an indirect technique (`INDIRECT_REGISTRY`), which its renderer runs after the direct
//! one. The view keeps one instance per indirect key and lends the renderer a [`SharedTechnique`] handle to it,
//! so the preview can switch indirect light off (and back on) without recreating its pipelines, and the panels
//! read the instance the renderer used (parameters, overlays) whether or not it is installed right now.

use std::cell::RefCell;
use std::collections::hash_map::DefaultHasher;
use std::collections::BTreeMap;
use std::hash::{Hash, Hasher};
use std::rc::Rc;
use std::time::Instant;

use anyhow::{anyhow, Result};
use eframe::{egui, egui_wgpu};
use shadowlab_core::renderer::FrameJob;
use shadowlab_core::scene::{Camera, DirectionalLight, PointLight, Scene};
use shadowlab_core::technique::{
    CameraPose, FrameContext, LegendEntry, LightDetails, Overlay, OverlayLayer, OverlayUpdate, Param, ParamError,
    ParamValue, Technique, TechniqueCounts,
};
use shadowlab_core::timing::{PassTime, StepWait};
use shadowlab_core::GpuError;
use shadowlab_core::{FrameReport, GpuContext, RenderSettings, Renderer};

/// Milliseconds of GPU work one UI frame may wait for.
const FRAME_BUDGET_MS: f64 = 30.0;
/// The technique used while the camera or a light moves: the registry's preview (no visibility).
pub fn preview_technique() -> &'static str {
    shadowlab_core::technique::registry::preview().key
}

/// What an image depends on; a change restarts the progressive frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameInputs {
    pub camera: Camera,
    pub lights: Vec<PointLight>,
    pub technique: String,
    pub params: BTreeMap<String, ParamValue>,
    /// The indirect technique's key (None: direct light only) and the parameters the user set for it.
    pub indirect: Option<String>,
    pub indirect_params: BTreeMap<String, ParamValue>,
    pub settings: RenderSettings,
    /// The session's directional lights (the renderer's are replaced by them).
    pub suns: Vec<DirectionalLight>,
}

impl FrameInputs {
    /// Runs every UI frame over every light: hash the bits, never format (100k lights would cost milliseconds).
    fn key(&self) -> u64 {
        let mut h = DefaultHasher::new();
        let mut floats = |v: &[f32]| v.iter().for_each(|x| x.to_bits().hash(&mut h));
        let c = &self.camera;
        floats(&c.position.to_array());
        floats(&c.orientation.to_array());
        floats(&[c.fov_y, c.near, c.z_far]);
        for l in &self.lights {
            floats(&l.position.to_array());
            floats(&l.color.to_array());
            floats(&[l.intensity, l.range]);
            if let Some(spot) = &l.spot {
                floats(&spot.direction.to_array());
                floats(&[spot.inner_angle, spot.outer_angle]);
            }
        }
        for d in &self.suns {
            floats(&d.direction.to_array());
            floats(&d.color.to_array());
            floats(&[d.illuminance]);
        }
        self.technique.hash(&mut h);
        self.indirect.hash(&mut h);
        // Parameters and settings are a handful of values.
        format!("{:?}{:?}{:?}", self.params, self.indirect_params, self.settings).hash(&mut h);
        h.finish()
    }
}

/// An indirect technique instance shared by a view and its renderer (see the module documentation).
pub type SharedIndirect = Rc<RefCell<Box<dyn Technique>>>;

/// The handle a renderer holds to a view's indirect technique: every call goes to the shared instance.
/// (Every method of [`Technique`] is forwarded, the provided ones too, so none falls back to its default.)
pub struct SharedTechnique(pub SharedIndirect);

impl Technique for SharedTechnique {
    fn key(&self) -> &'static str {
        self.0.borrow().key()
    }
    fn label(&self) -> &'static str {
        self.0.borrow().label()
    }
    fn params(&self) -> Vec<Param> {
        self.0.borrow().params()
    }
    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        self.0.borrow_mut().set_param(key, value)
    }
    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        self.0.borrow_mut().prepare(ctx)
    }
    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        self.0.borrow_mut().encode_step(ctx, step, encoder)
    }
    fn step_label(&self) -> &'static str {
        self.0.borrow().step_label()
    }
    fn counts(&self) -> TechniqueCounts {
        self.0.borrow().counts()
    }
    fn cpu_times(&self) -> Vec<PassTime> {
        self.0.borrow().cpu_times()
    }
    fn overlays(&self, lights: &[PointLight]) -> Vec<OverlayLayer> {
        self.0.borrow().overlays(lights)
    }
    fn pixel_ids(&self, positions: &[Option<glam::Vec3>]) -> Option<(&'static str, Vec<u32>)> {
        self.0.borrow().pixel_ids(positions)
    }
    fn overlay_legend(&self, layer: &OverlayLayer) -> Vec<LegendEntry> {
        self.0.borrow().overlay_legend(layer)
    }
    fn light_details(&self, index: usize) -> Option<LightDetails> {
        self.0.borrow().light_details(index)
    }
    fn explain(&self) -> Vec<shadowlab_core::technique::ExplainStep> {
        self.0.borrow().explain()
    }
    fn cameras_in_use(&self, key: &str) -> Vec<CameraPose> {
        self.0.borrow().cameras_in_use(key)
    }
    fn uses_vpls(&self) -> bool {
        self.0.borrow().uses_vpls()
    }
}

/// One progressively rendered image: a renderer, its techniques, the egui texture that shows it.
pub struct View {
    pub renderer: Renderer,
    techniques: BTreeMap<&'static str, Box<dyn Technique>>,
    /// Indirect technique instances by key, created on first use.
    indirect: BTreeMap<&'static str, SharedIndirect>,
    /// The key of the indirect technique installed in the renderer.
    installed_indirect: Option<&'static str>,
    pub texture_id: egui::TextureId,
    job: Option<(FrameJob, String)>,
    key: u64,
    pub last_report: Option<FrameReport>,
    /// Set when `last_report` is a frame that completed since the caller last looked.
    pub new_report: bool,
    /// Progress of the current frame, 0..1 (1 when complete).
    pub progress: f32,
    pub size: (u32, u32),
    /// Deferred steps: the frame's steps (first, count) submitted by the last UI frame that submitted any...
    batch: Option<(usize, usize)>,
    /// ...and, once they completed, the slowest one's ms and their count: the next batch's size.
    step_estimate: Option<(f64, usize)>,
}

impl View {
    pub fn new(gpu: &GpuContext, render_state: &egui_wgpu::RenderState, scene: &Scene) -> Result<View> {
        let renderer = Renderer::new(gpu, scene, Self::initial_settings())?;
        Self::with_renderer(gpu, render_state, renderer)
    }

    /// A second view of `other`'s scene: the scene's GPU buffers, textures and BVH are shared, not copied.
    pub fn sharing(gpu: &GpuContext, render_state: &egui_wgpu::RenderState, other: &View) -> Result<View> {
        let renderer = other.renderer.new_view(Self::initial_settings())?;
        Self::with_renderer(gpu, render_state, renderer)
    }

    fn initial_settings() -> RenderSettings {
        RenderSettings { width: 64, height: 64, max_lights_per_step: 4, ..Default::default() }
    }

    fn with_renderer(gpu: &GpuContext, render_state: &egui_wgpu::RenderState, renderer: Renderer) -> Result<View> {
        let texture_id = render_state.renderer.write().register_native_texture(
            &gpu.device,
            &renderer.targets().output_display,
            wgpu::FilterMode::Linear,
        );
        Ok(View {
            renderer,
            techniques: BTreeMap::new(),
            indirect: BTreeMap::new(),
            installed_indirect: None,
            texture_id,
            job: None,
            key: 0,
            last_report: None,
            new_report: false,
            progress: 0.0,
            size: (64, 64),
            batch: None,
            step_estimate: None,
        })
    }

    /// The technique instance for `key`, created on first use.
    pub fn technique(&mut self, key: &str) -> Result<&mut Box<dyn Technique>> {
        let entry = shadowlab_core::technique::registry::REGISTRY
            .iter()
            .find(|e| e.key == key)
            .ok_or_else(|| anyhow!("unknown technique '{key}'"))?;
        if !self.techniques.contains_key(entry.key) {
            let t = self.renderer.create_technique(entry.key).ok_or_else(|| anyhow!("cannot create '{key}'"))?;
            self.techniques.insert(entry.key, t);
        }
        Ok(self.techniques.get_mut(entry.key).expect("inserted above"))
    }

    /// Run the overlay stages of `key` (and of the indirect technique `indirect`) for `camera` and `lights`
    /// without rendering, while the preview renders the image: what each one's overlays now show (direct,
    /// indirect).
    pub fn update_overlays(
        &mut self,
        key: &str,
        indirect: Option<&str>,
        camera: &shadowlab_core::scene::Camera,
        lights: &[PointLight],
    ) -> Result<(OverlayUpdate, OverlayUpdate)> {
        self.technique(key)?;
        let technique = self.techniques.get_mut(key).ok_or_else(|| anyhow!("unknown technique '{key}'"))?;
        let direct = self.renderer.update_overlays(technique.as_mut(), camera, lights);
        let indirect = match indirect {
            Some(k) => {
                let t = self.indirect_technique(k)?;
                let update = self.renderer.update_overlays(t.borrow_mut().as_mut(), camera, lights);
                update
            }
            None => OverlayUpdate::live(),
        };
        Ok((direct, indirect))
    }

    /// The indirect technique instance for `key` (an `INDIRECT_REGISTRY` key), created on first use. Its
    /// parameters are the ones the renderer uses when it is installed.
    pub fn indirect_technique(&mut self, key: &str) -> Result<SharedIndirect> {
        let entry =
            shadowlab_core::technique::registry::INDIRECT_REGISTRY.iter().find(|e| e.key == key).ok_or_else(|| {
                anyhow!(
                    "unknown indirect technique '{key}' (choose one of: {})",
                    shadowlab_core::technique::registry::indirect_keys()
                )
            })?;
        if !self.indirect.contains_key(entry.key) {
            let t = self
                .renderer
                .create_indirect_technique(entry.key)
                .ok_or_else(|| anyhow!("cannot create the indirect technique '{key}'"))?;
            self.indirect.insert(entry.key, Rc::new(RefCell::new(t)));
        }
        Ok(self.indirect[entry.key].clone())
    }

    /// Install `key`'s instance in the renderer (None: none). Cancels a frame in progress, since its steps were
    /// counted with the previous indirect technique.
    fn install_indirect(&mut self, key: Option<&str>) -> Result<()> {
        let wanted = match key {
            Some(k) => Some(self.indirect_technique(k)?),
            None => None,
        };
        let wanted_key = wanted.as_ref().map(|t| t.borrow().key());
        if wanted_key == self.installed_indirect {
            return Ok(());
        }
        if let Some((job, _)) = self.job.take() {
            self.renderer.cancel_frame(job)?;
        }
        self.renderer.set_indirect(wanted.map(|t| Box::new(SharedTechnique(t)) as Box<dyn Technique>))?;
        self.installed_indirect = wanted_key;
        self.key = 0;
        Ok(())
    }

    /// Forget the instance of indirect technique `key`, so the next use creates it with default parameters.
    pub fn reset_indirect(&mut self, key: &str) -> Result<()> {
        if self.installed_indirect.is_some_and(|k| k == key) {
            self.install_indirect(None)?;
        }
        self.indirect.retain(|k, _| *k != key);
        self.key = 0;
        Ok(())
    }

    pub fn set_scene(&mut self, scene: &Scene) {
        self.renderer.set_scene(scene);
        self.key = 0;
    }

    /// Show the scene `other` uploaded (no second copy on the GPU).
    pub fn share_scene_of(&mut self, other: &View) {
        self.renderer.set_shared_scene(other.renderer.shared_scene());
        self.key = 0;
    }

    /// Resize the targets (and the egui texture) when needed.
    fn ensure_size(&mut self, render_state: &egui_wgpu::RenderState, settings: &RenderSettings) -> Result<()> {
        let mut s = settings.clone();
        s.max_lights_per_step = self.renderer.settings().max_lights_per_step;
        if (s.width, s.height) != self.size || s != *self.renderer.settings() {
            let resized = (s.width, s.height) != self.size;
            self.renderer.set_settings(s)?;
            if resized {
                self.size = (settings.width, settings.height);
                render_state.renderer.write().update_egui_texture_from_wgpu_texture(
                    &self.renderer.gpu().device,
                    &self.renderer.targets().output_display,
                    wgpu::FilterMode::Linear,
                    self.texture_id,
                );
            }
        }
        Ok(())
    }

    /// Restart when the inputs changed, then do up to `budget_ms` of work. Returns the ms spent and the
    /// number of steps run.
    pub fn update(
        &mut self,
        render_state: &egui_wgpu::RenderState,
        inputs: &FrameInputs,
        budget_ms: f64,
        max_lights_per_step: usize,
    ) -> Result<(f64, usize)> {
        let start = Instant::now();
        let mut steps = 0;
        let key = inputs.key();
        if key != self.key {
            if let Some((job, _)) = self.job.take() {
                self.renderer.cancel_frame(job)?;
            }
            self.ensure_size(render_state, &inputs.settings)?;
            if self.renderer.directional_lights() != inputs.suns.as_slice() {
                self.renderer.set_directional_lights(&inputs.suns)?;
            }
            let mut settings = self.renderer.settings().clone();
            settings.max_lights_per_step = max_lights_per_step;
            self.renderer.set_settings(settings)?;
            self.install_indirect(inputs.indirect.as_deref())?;
            if let Some(indirect) = self.renderer.indirect_mut() {
                for (k, v) in &inputs.indirect_params {
                    // Validated when set in the UI or loaded, like the direct technique's.
                    if let Err(e) = indirect.set_param(k, v) {
                        log::warn!("{e}");
                    }
                }
            }
            let technique = self.technique(&inputs.technique)?;
            for (k, v) in &inputs.params {
                // Parameters were validated when set in the UI or loaded; a stale one is skipped.
                if let Err(e) = technique.set_param(k, v) {
                    log::warn!("{e}");
                }
            }
            let mut technique = self.techniques.remove(inputs.technique.as_str()).expect("created above");
            let job = self.renderer.begin_frame(technique.as_mut(), &inputs.camera, &inputs.lights);
            let key_name = technique.key();
            self.techniques.insert(key_name, technique);
            self.job = Some((job?, inputs.technique.clone()));
            self.key = key;
            (self.batch, self.step_estimate) = (None, None);
            self.progress = 0.0;
        }
        // GPU work this UI frame gave the queue: waited for (blocking), or estimated from the last step that
        // completed (deferred), for the step sizer.
        let mut gpu_ms = 0.0;
        if let Some((mut job, name)) = self.job.take() {
            let mut technique = self.techniques.remove(name.as_str()).ok_or_else(|| anyhow!("technique vanished"))?;
            let deferred = self.renderer.step_wait() == StepWait::Deferred;
            let result = (|| -> Result<()> {
                if deferred {
                    // Poll, never wait: while the last UI frame's steps run, this one submits nothing. Then
                    // about `budget_ms` of steps, by the time the last completed step took.
                    if self.renderer.steps_in_flight() > 0 {
                        return Ok(());
                    }
                    // The last batch is done: its slowest step sizes the next batch, which at most doubles.
                    if let Some((first, n)) = self.batch.take() {
                        let slowest =
                            (first..first + n).filter_map(|i| self.renderer.frame_step_ms(i)).fold(0.0, f64::max);
                        self.step_estimate = Some((slowest.max(0.1), n));
                    }
                    let n = match self.step_estimate {
                        None => 1,
                        Some((ms, last)) => ((budget_ms / ms) as usize).clamp(1, (2 * last).min(MAX_DEFERRED_STEPS)),
                    };
                    let first = self.renderer.frame_steps();
                    while !job.is_done() && steps < n {
                        self.renderer.advance(&mut job, technique.as_mut(), 1)?;
                        steps += 1;
                    }
                    self.batch = Some((first, steps));
                    gpu_ms = self.step_estimate.map_or(budget_ms, |(ms, _)| ms) * steps as f64;
                    return Ok(());
                }
                while !job.is_done() && start.elapsed().as_secs_f64() * 1000.0 < budget_ms {
                    self.renderer.advance(&mut job, technique.as_mut(), 1)?;
                    steps += 1;
                    // Wait, so this UI frame pays for exactly the work it submitted.
                    self.renderer.gpu().wait_idle()?;
                }
                gpu_ms = start.elapsed().as_secs_f64() * 1000.0;
                Ok(())
            })();
            self.progress = job.progress();
            // A deferred frame is finished once its last step is seen complete (finishing waits otherwise).
            if result.is_ok() && job.is_done() && self.renderer.steps_in_flight() == 0 {
                self.last_report = Some(self.renderer.finish_frame(job, technique.as_ref())?);
                self.new_report = true;
                self.progress = 1.0;
            } else {
                self.renderer.preview_tonemap()?;
                self.job = Some((job, name));
            }
            self.techniques.insert(technique.key(), technique);
            result?;
        } else {
            // Overlays are drawn over the output each UI frame; start again from the clean image.
            self.renderer.preview_tonemap()?;
        }
        Ok((if steps > 0 { gpu_ms } else { start.elapsed().as_secs_f64() * 1000.0 }, steps))
    }

    /// Submit progressive steps and go on (polling them each UI frame) or wait for each (the moving preview,
    /// whose image is shown in the UI frame that asked for it, and synchronous runs). Steps always wait on
    /// the GL backend.
    pub fn set_step_wait(&mut self, wait: StepWait) {
        if self.renderer.step_wait() != wait {
            self.renderer.set_step_wait(wait);
        }
    }

    /// Draw the overlays over the output, the last write of a UI frame, and make the output ready to show.
    pub fn overlays(&mut self, camera: &Camera, primitives: &[Overlay], x_ray: bool) -> Result<()> {
        self.renderer.draw_overlays(camera, primitives, x_ray)?;
        self.renderer.sync_display()?;
        Ok(())
    }

    /// Identifies the inputs of the current frame (0 before the first).
    pub fn frame_key(&self) -> u64 {
        self.key
    }

    /// Forget a technique instance, so the next use creates it with default parameters.
    pub fn reset_technique(&mut self, key: &str) {
        self.techniques.retain(|k, _| *k != key);
        self.key = 0;
    }

    pub fn is_converged(&self) -> bool {
        self.job.is_none() && self.key != 0
    }
}

/// At most this many deferred steps a UI frame (steps of a few lights on a fast GPU would otherwise queue a
/// whole frame at once, and a camera move would wait for all of it).
const MAX_DEFERRED_STEPS: usize = 64;

/// Steps get larger when they are fast and smaller when they are slow, so each UI frame does about
/// `FRAME_BUDGET_MS` of GPU work.
#[derive(Clone, Copy, Debug)]
pub struct StepSizer {
    pub max_lights_per_step: usize,
    /// GPU work a UI frame may wait for.
    pub budget_ms: f64,
}

impl Default for StepSizer {
    fn default() -> Self {
        StepSizer { max_lights_per_step: 4, budget_ms: FRAME_BUDGET_MS }
    }
}

impl StepSizer {
    /// Feed the time and steps of one UI frame's work.
    pub fn observe(&mut self, spent_ms: f64, steps: usize) {
        if steps == 0 {
            return;
        }
        if !self.budget_ms.is_finite() {
            return;
        }
        let per_step = spent_ms / steps as f64;
        if per_step > self.budget_ms && self.max_lights_per_step > 1 {
            self.max_lights_per_step /= 2;
        } else if per_step < self.budget_ms * 0.25 {
            self.max_lights_per_step = (self.max_lights_per_step * 2).min(1024);
        }
    }
    pub fn budget_ms(&self) -> f64 {
        self.budget_ms
    }
}
