//! The deferred renderer shared by all techniques: the [`Renderer`] that owns the scene on the GPU, the
//! direct and indirect techniques (made by [`crate::technique::registry`]) and the frame, above the techniques
//! and the services they use ([`crate::services`]).
//!
//! A frame: (1) G-buffer pass (depth, normal, albedo, emission; chunks culled against the view frustum),
//! (2) ambient pass that starts the HDR target with ambient + emission, (3) the technique's steps, each adding
//! its lights' shadowed radiance into the HDR target and submitted on its own, (4) tone mapping to sRGB.
//! Every pass is timed (see [`crate::timing`]). A frame can run to completion ([`Renderer::render_frame`]) or be
//! advanced a few steps at a time ([`Renderer::begin_frame`], [`Renderer::advance`], [`Renderer::finish_frame`])
//! so an interactive app stays responsive while a slow technique accumulates.

mod display;
pub mod exposure;
mod frame;
mod read;
pub mod report;
pub mod settings;
mod setup;
pub mod targets;

use std::time::Instant;

use crate::accel::gpu_scene::GpuScene;
use crate::error::GpuError;
use crate::gpu::GpuContext;
use crate::math::Frustum;
use crate::scene::chunks::merge_draw_ranges;
use crate::scene::{Camera, PointLight, Scene};
use crate::services::gpu_data::{FrameUniform, MatrixUniform};
use crate::services::layouts::SharedLayouts;
use crate::services::{cube_shadows, directional, light_tiles, lights, overlay, work_counters};
use crate::shaders;
use crate::technique::{FrameContext, Technique};
use crate::timing::{PassTime, PassTimer};
use crate::vpl::{GpuVpl, VplFrame, VplSet};
use targets::FrameTargets;

pub use report::{FrameCounts, FrameJob, FrameReport, IndirectReport};
pub use settings::{AutoExposure, Component, RenderSettings, ToneMap, MAX_RENDER_SIZE};

pub struct Renderer {
    gpu: GpuContext,
    /// Shared with the renderers made by [`Renderer::new_view`] (the scene's material bind groups use them).
    pub layouts: std::sync::Arc<SharedLayouts>,
    settings: RenderSettings,
    scene: std::sync::Arc<GpuScene>,
    targets: FrameTargets,
    frame_uniform: wgpu::Buffer,
    camera_uniform: wgpu::Buffer,
    camera_bind_group: wgpu::BindGroup,
    screen_bind_group: wgpu::BindGroup,
    /// The G-buffer pass of cut-out materials (alpha-tested) and of opaque ones.
    gbuffer_pipeline: wgpu::RenderPipeline,
    gbuffer_opaque_pipeline: wgpu::RenderPipeline,
    ambient_pipeline: wgpu::RenderPipeline,
    tonemap_pipeline: wgpu::RenderPipeline,
    tonemap_layout: wgpu::BindGroupLayout,
    tonemap_bind_group: wgpu::BindGroup,
    exposure: exposure::ExposureMeter,
    timer: PassTimer,
    draw_ranges: Vec<(u32, u32)>,
    overlay: Option<overlay::OverlayRenderer>,
    overlay_style: overlay::OverlayStyle,
    /// The indirect technique, when one is chosen; its steps run after the direct technique's.
    indirect: Option<Box<dyn Technique>>,
    /// Indirect radiance per pixel, linear RGBA f32 (a tiny placeholder without an indirect technique).
    indirect_buffer: wgpu::Buffer,
    vpls: VplFrame,
    visible_lights: lights::VisibleLights,
    /// Per screen tile, the visible lights that reach it; built in `begin_frame` for techniques that read it.
    light_tiles: light_tiles::TileLists,
    light_spheres: Vec<[f32; 4]>,
    /// What only the GPU knows of a frame's work (work_counters.rs).
    work_counters: work_counters::WorkCounters,
    /// The scene's directional lights, added to every direct technique's frame.
    directional: directional::DirectionalLights,
    /// True when [`Renderer::set_fixed_vpls`] gave the VPLs.
    fixed_vpls: bool,
}

/// Bytes of the indirect buffer for a `width x height` image.
fn indirect_bytes(width: u32, height: u32) -> u64 {
    width as u64 * height as u64 * 16
}

fn create_indirect_buffer(gpu: &GpuContext, width: u32, height: u32, enabled: bool) -> Result<wgpu::Buffer, GpuError> {
    let size = if enabled { indirect_bytes(width, height) } else { 16 };
    let limits = gpu.device.limits();
    let max = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    if size > max {
        return Err(GpuError::InvalidSettings(format!(
            "indirect light at {width}x{height} needs a {} MiB buffer; this GPU allows {} MiB (lower the image size)",
            size >> 20,
            max >> 20
        )));
    }
    Ok(gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("indirect radiance"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    }))
}

impl Renderer {
    pub fn new(gpu: &GpuContext, scene: &Scene, settings: RenderSettings) -> Result<Renderer, GpuError> {
        settings.validate()?;
        gpu.guarded(|| Self::new_unguarded(gpu, scene, settings))
    }

    fn new_unguarded(gpu: &GpuContext, scene: &Scene, settings: RenderSettings) -> Result<Renderer, GpuError> {
        let layouts = std::sync::Arc::new(SharedLayouts::new(&gpu.device));
        let gpu_scene = std::sync::Arc::new(GpuScene::new(gpu, scene, &layouts.material));
        Self::with_scene(gpu, gpu_scene, layouts, settings)
    }

    /// Another renderer (a second view, a sweep worker, a comparison) of this renderer's scene on the same
    /// device: the scene's buffers, textures and BVH are shared, not copied; targets and pipelines are its own.
    /// Its directional lights are this renderer's (the scene's, or those [`Renderer::set_directional_lights`]
    /// gave).
    pub fn new_view(&self, settings: RenderSettings) -> Result<Renderer, GpuError> {
        settings.validate()?;
        let mut view = Self::with_scene(&self.gpu, self.scene.clone(), self.layouts.clone(), settings)?;
        view.directional.set_lights(self.directional.lights());
        Ok(view)
    }

    /// The scene on the GPU, to share with [`Renderer::set_shared_scene`] of another view.
    pub fn shared_scene(&self) -> std::sync::Arc<GpuScene> {
        self.scene.clone()
    }

    /// The layouts the scene's bind groups were made with, for [`Renderer::for_scene`] on another thread.
    pub fn shared_layouts(&self) -> std::sync::Arc<SharedLayouts> {
        self.layouts.clone()
    }

    /// A renderer of a scene another renderer uploaded ([`Renderer::shared_scene`], [`Renderer::shared_layouts`]):
    /// what [`Renderer::new_view`] does, for a worker thread that cannot borrow the first renderer.
    pub fn for_scene(
        gpu: &GpuContext,
        scene: std::sync::Arc<GpuScene>,
        layouts: std::sync::Arc<SharedLayouts>,
        settings: RenderSettings,
    ) -> Result<Renderer, GpuError> {
        settings.validate()?;
        Self::with_scene(gpu, scene, layouts, settings)
    }

    /// Show a scene another renderer uploaded (made by [`Renderer::new_view`] of it or sharing its layouts).
    pub fn set_shared_scene(&mut self, scene: std::sync::Arc<GpuScene>) {
        self.directional.set_lights(&scene.directional);
        self.scene = scene;
    }

    /// The directional lights shaded from the next frame on: the scene's until
    /// [`Renderer::set_directional_lights`].
    pub fn directional_lights(&self) -> &[crate::scene::DirectionalLight] {
        self.directional.lights()
    }

    /// Replace the scene's directional lights (the app's sun editing), at most
    /// [`crate::scene::MAX_DIRECTIONAL_LIGHTS`], each valid ([`crate::scene::DirectionalLight::is_valid`]);
    /// a bad list is refused and the lights stay as they were.
    pub fn set_directional_lights(&mut self, lights: &[crate::scene::DirectionalLight]) -> Result<(), GpuError> {
        let max = crate::scene::MAX_DIRECTIONAL_LIGHTS;
        if lights.len() > max {
            return Err(GpuError::InvalidSettings(format!(
                "{} directional lights; at most {max} are shaded",
                lights.len()
            )));
        }
        if let Some(i) = lights.iter().position(|l| !l.is_valid()) {
            return Err(GpuError::InvalidSettings(format!(
                "directional light {i} has a zero or non-finite direction, or a negative or non-finite colour or \
                 illuminance"
            )));
        }
        self.directional.set_lights(lights);
        Ok(())
    }

    pub fn gpu(&self) -> &GpuContext {
        &self.gpu
    }

    /// Choose the clock of the reports from the next frame on (`SHADOWLAB_TIMING` chose it at creation).
    pub fn set_timing_mode(&mut self, mode: crate::timing::TimingMode) {
        self.timer.set_mode(mode);
    }

    /// Block on each step (the default) or submit and go on ([`crate::timing::StepWait`]); returns the way
    /// chosen (steps always block on the GL backend). A caller that defers polls [`Renderer::steps_in_flight`]
    /// and finishes a frame once it is 0 ([`Renderer::finish_frame`] waits otherwise).
    pub fn set_step_wait(&mut self, wait: crate::timing::StepWait) -> crate::timing::StepWait {
        self.timer.set_step_wait(&self.gpu, wait)
    }

    pub fn step_wait(&self) -> crate::timing::StepWait {
        self.timer.step_wait()
    }

    /// Deferred steps submitted and not yet complete.
    pub fn steps_in_flight(&self) -> usize {
        self.timer.steps_in_flight()
    }

    /// How many steps (submissions) the current frame has made, its `begin_frame` included.
    pub fn frame_steps(&self) -> usize {
        self.timer.frame_steps()
    }

    /// The wall time of the current frame's step `i` once it completed, for sizing the next ones.
    pub fn frame_step_ms(&self, i: usize) -> Option<f64> {
        self.timer.frame_step_ms(i)
    }

    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }
    pub fn targets(&self) -> &FrameTargets {
        &self.targets
    }
    pub fn scene(&self) -> &GpuScene {
        &self.scene
    }

    /// Change settings; resizes the targets when the size changed.
    pub fn set_settings(&mut self, settings: RenderSettings) -> Result<(), GpuError> {
        let gpu = self.gpu.clone();
        gpu.guarded(|| self.set_settings_unguarded(settings))
    }

    fn set_settings_unguarded(&mut self, settings: RenderSettings) -> Result<(), GpuError> {
        settings.validate()?;
        if settings.width != self.settings.width || settings.height != self.settings.height {
            // Checked first, so a refused size leaves the renderer as it was.
            let indirect = create_indirect_buffer(&self.gpu, settings.width, settings.height, self.indirect.is_some())?;
            self.indirect_buffer = indirect;
            self.targets = FrameTargets::new(&self.gpu, settings.width, settings.height);
            self.screen_bind_group = Self::screen_bind_group(
                &self.gpu.device,
                &self.layouts,
                &self.frame_uniform,
                &self.targets,
                &self.work_counters,
            );
            self.rebind_tonemap();
        }
        self.settings = settings;
        Ok(())
    }

    /// Choose the indirect technique (None: direct light only, the default). Its steps run after the direct
    /// technique's in every frame.
    pub fn set_indirect(&mut self, technique: Option<Box<dyn Technique>>) -> Result<(), GpuError> {
        let gpu = self.gpu.clone();
        gpu.guarded(|| self.set_indirect_unguarded(technique))
    }

    fn set_indirect_unguarded(&mut self, technique: Option<Box<dyn Technique>>) -> Result<(), GpuError> {
        let (w, h) = (self.settings.width, self.settings.height);
        self.indirect_buffer = create_indirect_buffer(&self.gpu, w, h, technique.is_some())?;
        self.indirect = technique;
        self.rebind_tonemap();
        Ok(())
    }

    /// The indirect technique, to read or change its parameters.
    pub fn indirect(&self) -> Option<&dyn Technique> {
        self.indirect.as_deref()
    }
    pub fn indirect_mut(&mut self) -> Option<&mut (dyn Technique + 'static)> {
        self.indirect.as_deref_mut()
    }

    /// Create an indirect technique by key on this renderer's device.
    pub fn create_indirect_technique(&self, key: &str) -> Option<Box<dyn Technique>> {
        crate::technique::registry::create_indirect(key, &self.gpu, &self.layouts)
    }

    /// Use these VPLs instead of generating them from the lights (None: generate again). For tests with
    /// hand-placed VPLs, and for VPL sets made elsewhere.
    pub fn set_fixed_vpls(&mut self, set: Option<VplSet>) {
        self.fixed_vpls = set.is_some();
        if let Some(set) = set {
            let gpu: Vec<GpuVpl> = set.vpls.iter().map(GpuVpl::new).collect();
            self.vpls.buffer.write(&self.gpu, &gpu);
            self.vpls.set = std::sync::Arc::new(set);
        }
        self.vpls.key = None;
    }

    /// Regenerate the frame's VPLs when the lights, the VPL settings or the scene changed; false when the
    /// previous set was kept.
    fn update_vpls(&mut self, technique: &dyn Technique, lights: &[PointLight]) -> bool {
        if self.fixed_vpls {
            return false;
        }
        if !technique.uses_vpls() {
            self.vpls.set = Default::default();
            self.vpls.key = None;
            return true;
        }
        let suns = self.directional.lights().to_vec();
        let key = (lights.to_vec(), suns, self.settings.vpl, std::sync::Arc::as_ptr(&self.scene.geometry) as usize);
        if self.vpls.key.as_ref() == Some(&key) {
            return false;
        }
        let (bvh, _) = self.scene.bvh(&self.gpu);
        let set = crate::vpl::generate(&bvh, lights, &key.1, &self.settings.vpl);
        let gpu: Vec<GpuVpl> = set.vpls.iter().map(GpuVpl::new).collect();
        self.vpls.buffer.write(&self.gpu, &gpu);
        self.vpls.set = std::sync::Arc::new(set);
        self.vpls.key = Some(key);
        true
    }

    /// Whether the last frame's VPLs were generated for these lights and the current suns, settings and scene.
    fn vpls_are_of(&self, lights: &[PointLight]) -> bool {
        self.vpls.key.as_ref().is_some_and(|(l, suns, settings, scene)| {
            l.as_slice() == lights
                && suns.as_slice() == self.directional.lights()
                && *settings == self.settings.vpl
                && *scene == std::sync::Arc::as_ptr(&self.scene.geometry) as usize
        })
    }

    /// The VPLs of the last frame (empty without an indirect technique).
    pub fn vpls(&self) -> &VplSet {
        &self.vpls.set
    }

    /// The same, shared: a new set is a new allocation, so the pointer tells whether the VPLs changed.
    pub fn shared_vpls(&self) -> std::sync::Arc<VplSet> {
        self.vpls.set.clone()
    }

    /// Replace the scene's geometry and materials.
    pub fn set_scene(&mut self, scene: &Scene) {
        self.scene = std::sync::Arc::new(GpuScene::new(&self.gpu, scene, &self.layouts.material));
    }

    /// Create a technique by key on this renderer's device.
    /// The bind group layouts techniques are created with (to create one directly, by its type).
    pub fn layouts(&self) -> &SharedLayouts {
        &self.layouts
    }

    pub fn create_technique(&self, key: &str) -> Option<Box<dyn Technique>> {
        crate::technique::registry::create(key, &self.gpu, &self.layouts)
    }

    fn aspect(&self) -> f32 {
        self.settings.width as f32 / self.settings.height as f32
    }

    fn context<'a>(&'a self, camera: &'a Camera, lights: &'a [PointLight]) -> FrameContext<'a> {
        let aspect = self.aspect();
        FrameContext {
            gpu: &self.gpu,
            scene: &self.scene,
            layouts: &self.layouts,
            screen_bind_group: &self.screen_bind_group,
            hdr_view: &self.targets.hdr,
            camera,
            aspect,
            frustum: Frustum::from_clip_from_world(&camera.clip_from_world(aspect)),
            lights,
            directional_lights: self.directional.lights(),
            timer: &self.timer,
            size: (self.settings.width, self.settings.height),
            indirect_buffer: &self.indirect_buffer,
            vpls: &self.vpls,
            vpl_settings: &self.settings.vpl,
            visible_lights: &self.visible_lights,
            light_tiles: &self.light_tiles,
            light_tiles_enabled: self.settings.light_tiles,
            receivers: self
                .settings
                .receiver_culling
                .then(|| cube_shadows::receiver_bounds(camera, aspect, &self.scene.bounds))
                .flatten(),
            max_lights_per_step: match self.settings.max_lights_per_step {
                0 => usize::MAX,
                n => n,
            },
        }
    }
}
