//! The deferred renderer shared by all techniques.
//!
//! A frame: (1) G-buffer pass (depth, normal, albedo, emission; chunks culled against the view frustum),
//! (2) ambient pass that starts the HDR target with ambient + emission, (3) the technique's steps, each adding
//! its lights' shadowed radiance into the HDR target and submitted on its own, (4) tone mapping to sRGB.
//! Every pass is timed (see [`crate::timing`]). A frame can run to completion ([`Renderer::render_frame`]) or be
//! advanced a few steps at a time ([`Renderer::begin_frame`], [`Renderer::advance`], [`Renderer::finish_frame`])
//! so an interactive app stays responsive while a slow technique accumulates.

pub mod cube_params;
pub mod cube_shadows;
pub mod exposure;
pub mod gpu_data;
pub mod layouts;
pub mod light_tiles;
pub mod lights;
pub mod overlay;
pub mod per_light_shadows;
pub mod shade_pass;
pub mod targets;
pub mod vpl_gather;

use std::time::Instant;

use glam::Vec3;
use serde::Serialize;

use crate::accel::gpu_scene::GpuScene;
use crate::error::GpuError;
use crate::gpu::readback;
use crate::gpu::GpuContext;
use crate::math::Frustum;
use crate::scene::chunks::merge_draw_ranges;
use crate::scene::{Camera, PointLight, Scene};
use crate::shaders;
use crate::technique::{FrameContext, Technique, TechniqueCounts};
use crate::timing::{PassTime, PassTimer, TimingSource};
use crate::vpl::{GpuVpl, VplFrame, VplSet, VplSettings};
use gpu_data::{FrameUniform, MatrixUniform};
use layouts::SharedLayouts;
use targets::FrameTargets;

/// Largest render target side accepted.
pub const MAX_RENDER_SIZE: u32 = 8192;

/// How the HDR image becomes display colours.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ToneMap {
    Aces,
    Reinhard,
    /// Exposure then clamp: radiance 1 maps to white.
    Linear,
}

/// Settings of the renderer (not of a technique).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub exposure: f32,
    /// Multiply `exposure` by the scale that maps the image's log-average luminance to middle grey (metered on
    /// the GPU each complete frame, [`exposure`]); `exposure` is then a compensation. On in the app, off in
    /// the CLI (`--auto-exposure`), so renders of the same scene stay comparable.
    pub auto_exposure: AutoExposure,
    pub tonemap: ToneMap,
    /// Ambient radiance factor: ambient term = `ambient * albedo`.
    pub ambient: Vec3,
    pub background: Vec3,
    /// Blinn-Phong specular on top of Lambert.
    pub specular: bool,
    /// At most this many lights (cube maps) per step; 0 = as many as the technique's memory budget allows.
    /// The app lowers it on slow adapters so each UI frame does a bounded amount of work.
    pub max_lights_per_step: usize,
    /// The VPLs every indirect technique of a frame shares.
    pub vpl: VplSettings,
    /// Which part of the light the output, `read_hdr` and so every comparison show.
    pub component: Component,
    /// Display gain of the indirect part when [`Component::Indirect`] is shown (not applied to `read_hdr`).
    pub indirect_gain: f32,
    /// Tiled light lists ([`light_tiles`]): shading passes visit only the lights (clusters) that reach their
    /// pixel's 16x16 tile. The image is the same either way; off loops over every light of a batch.
    pub light_tiles: bool,
}

/// Whether the tone mapping scales the exposure by a metered one ([`exposure`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum AutoExposure {
    /// The exposure as set.
    #[default]
    Off,
    /// Meter every complete frame (and a preview before the first), and scale by it.
    Meter,
    /// Scale by the last metered value without metering (the app's fast preview while the user drags, so the
    /// brightness does not jump between the preview and the full image).
    Hold,
}

/// A part of the image: everything, the ambient + direct part, or the indirect part alone.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Component {
    /// Ambient + emission + direct + indirect.
    #[default]
    Total,
    /// Ambient + emission + direct (the whole image without an indirect technique).
    Direct,
    /// Indirect light only (zero without an indirect technique).
    Indirect,
}

impl Component {
    pub const NAMES: &'static [&'static str] = &["total", "direct", "indirect"];
    pub fn parse(text: &str) -> Option<Component> {
        match text.trim() {
            "total" => Some(Component::Total),
            "direct" => Some(Component::Direct),
            "indirect" => Some(Component::Indirect),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        Component::NAMES[self as usize]
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 640,
            height: 360,
            exposure: 1.0,
            auto_exposure: AutoExposure::Off,
            tonemap: ToneMap::Aces,
            ambient: Vec3::splat(0.03),
            background: Vec3::new(0.05, 0.06, 0.08),
            specular: false,
            max_lights_per_step: 0,
            vpl: VplSettings::default(),
            component: Component::Total,
            indirect_gain: 1.0,
            light_tiles: true,
        }
    }
}

impl RenderSettings {
    pub fn validate(&self) -> Result<(), GpuError> {
        if self.width == 0 || self.height == 0 || self.width > MAX_RENDER_SIZE || self.height > MAX_RENDER_SIZE {
            return Err(GpuError::InvalidSettings(format!(
                "image size {}x{} must be between 1x1 and {MAX_RENDER_SIZE}x{MAX_RENDER_SIZE}",
                self.width, self.height
            )));
        }
        if !(self.exposure.is_finite() && self.exposure > 0.0) {
            return Err(GpuError::InvalidSettings(format!("exposure {} must be > 0", self.exposure)));
        }
        if !(self.ambient.is_finite() && self.background.is_finite()) {
            return Err(GpuError::InvalidSettings("ambient and background must be finite".into()));
        }
        if !(self.indirect_gain.is_finite() && self.indirect_gain > 0.0 && self.indirect_gain <= 1e6) {
            return Err(GpuError::InvalidSettings(format!("indirect gain {} must be in (0, 1e6]", self.indirect_gain)));
        }
        self.vpl.validate().map_err(GpuError::InvalidSettings)?;
        Ok(())
    }
}

/// Counts of a frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrameCounts {
    pub lights_total: usize,
    pub scene_triangles: u64,
    /// Triangles the G-buffer pass drew after view-frustum culling of chunks.
    pub gbuffer_triangles: u64,
    #[serde(flatten)]
    pub technique: TechniqueCounts,
}

/// What one frame cost and did.
#[derive(Clone, Debug, Serialize)]
pub struct FrameReport {
    pub technique: String,
    pub width: u32,
    pub height: u32,
    pub timing_source: TimingSource,
    /// Per pass, in the order they ran; passes of one name (batches) are summed.
    pub passes: Vec<PassTime>,
    /// Sum of the passes.
    pub gpu_total_ms: f64,
    /// CPU stages of the technique (e.g. clustering), milliseconds.
    pub cpu_stages: Vec<PassTime>,
    /// CPU wall time from the start of the frame to its completion (includes culling and waiting).
    pub wall_ms: f64,
    pub counts: FrameCounts,
    /// The indirect technique of the frame, when there is one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub indirect: Option<IndirectReport>,
}

/// What the indirect technique of a frame did.
#[derive(Clone, Debug, Serialize)]
pub struct IndirectReport {
    pub technique: String,
    /// VPLs used (0 for techniques that use none, e.g. the path tracer).
    pub vpls: usize,
    pub vpl_source: crate::vpl::VplSource,
    /// VPL samples (texels or particles) that hit nothing.
    pub vpl_misses: u32,
    /// True when the frame reused the previous frame's VPLs (same lights, settings and scene), so the
    /// "vpl generation" stage timed only the check.
    pub vpls_reused: bool,
    pub counts: TechniqueCounts,
    /// CPU stages (VPL generation, the technique's own), milliseconds.
    pub cpu_stages: Vec<PassTime>,
    /// The frame's passes that the indirect technique ran (also in the frame's `passes`), and their sum.
    pub passes: Vec<PassTime>,
    pub gpu_ms: f64,
}

/// A frame in progress.
pub struct FrameJob {
    pub steps_total: usize,
    pub steps_done: usize,
    started: Instant,
    camera: Camera,
    lights: Vec<PointLight>,
    gbuffer_triangles: u64,
    /// Steps of the direct technique; the indirect technique's follow.
    direct_steps: usize,
    vpl_ms: f64,
    vpls_reused: bool,
}

impl FrameJob {
    pub fn is_done(&self) -> bool {
        self.steps_done >= self.steps_total
    }
    /// 0..1
    pub fn progress(&self) -> f32 {
        if self.steps_total == 0 {
            1.0
        } else {
            self.steps_done as f32 / self.steps_total as f32
        }
    }
}

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
    gbuffer_pipeline: wgpu::RenderPipeline,
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
    pub fn new_view(&self, settings: RenderSettings) -> Result<Renderer, GpuError> {
        settings.validate()?;
        Self::with_scene(&self.gpu, self.scene.clone(), self.layouts.clone(), settings)
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
        self.scene = scene;
    }

    fn with_scene(
        gpu: &GpuContext,
        gpu_scene: std::sync::Arc<GpuScene>,
        layouts: std::sync::Arc<SharedLayouts>,
        settings: RenderSettings,
    ) -> Result<Renderer, GpuError> {
        let device = &gpu.device;
        let targets = FrameTargets::new(gpu, settings.width, settings.height);
        let frame_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: std::mem::size_of::<FrameUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let camera_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("camera"),
            size: std::mem::size_of::<MatrixUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let camera_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("camera"),
            layout: &layouts.camera,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: camera_uniform.as_entire_binding() }],
        });

        let gbuffer_module = crate::gpu::pipeline::create_module(device, "gbuffer", shaders::GBUFFER.source);
        let gbuffer_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gbuffer"),
            bind_group_layouts: &[Some(&layouts.camera), Some(&layouts.material)],
            immediate_size: 0,
        });
        let gbuffer_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("gbuffer"),
            layout: Some(&gbuffer_layout),
            vertex: wgpu::VertexState {
                module: &gbuffer_module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[
                    Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<crate::scene::chunks::Vertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2],
                    }),
                    // The second UV channel, a stream of its own (the depth passes never read it).
                    Some(wgpu::VertexBufferLayout {
                        array_stride: 8,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![3 => Float32x2],
                    }),
                ],
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: SharedLayouts::DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &gbuffer_module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[
                    Some(SharedLayouts::ALBEDO_FORMAT.into()),
                    Some(SharedLayouts::NORMAL_FORMAT.into()),
                    Some(SharedLayouts::EMISSIVE_FORMAT.into()),
                ],
            }),
            multiview_mask: None,
            cache: None,
        });
        let ambient_module = crate::gpu::pipeline::create_module(device, "ambient", shaders::AMBIENT.source);
        let ambient_pipeline =
            layouts.fullscreen_pipeline(device, "ambient", &ambient_module, &[], SharedLayouts::HDR_FORMAT, false);
        let tonemap_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tonemap"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                crate::gpu::bind::storage_entry(1),
                crate::gpu::bind::storage_entry(2),
            ],
        });
        let tonemap_module = crate::gpu::pipeline::create_module(device, "tonemap", shaders::TONEMAP.source);
        let tonemap_pipeline = layouts.fullscreen_pipeline(
            device,
            "tonemap",
            &tonemap_module,
            &[&tonemap_layout],
            SharedLayouts::OUTPUT_FORMAT,
            false,
        );
        let screen_bind_group = Self::screen_bind_group(device, &layouts, &frame_uniform, &targets);
        let indirect_buffer = create_indirect_buffer(gpu, settings.width, settings.height, false)?;
        let exposure = exposure::ExposureMeter::new(gpu, &layouts, &targets, &indirect_buffer);
        let tonemap_bind_group =
            Self::tonemap_bind_group(device, &tonemap_layout, &targets, &indirect_buffer, &exposure.result);
        let timer = PassTimer::new(gpu)?;
        let light_tiles = light_tiles::TileLists::new(gpu, &layouts.screen, &layouts.light_tiles);
        Ok(Renderer {
            gpu: gpu.clone(),
            layouts,
            settings,
            scene: gpu_scene,
            targets,
            frame_uniform,
            camera_uniform,
            camera_bind_group,
            screen_bind_group,
            gbuffer_pipeline,
            ambient_pipeline,
            tonemap_pipeline,
            tonemap_layout,
            tonemap_bind_group,
            exposure,
            timer,
            draw_ranges: Vec::new(),
            overlay: None,
            overlay_style: Default::default(),
            indirect: None,
            indirect_buffer,
            vpls: VplFrame {
                set: Default::default(),
                buffer: crate::gpu::buffer::GrowableBuffer::new(device, "vpls", 48 * 64),
                key: None,
            },
            fixed_vpls: false,
            visible_lights: lights::VisibleLights::new(gpu),
            light_tiles,
            light_spheres: Vec::new(),
        })
    }

    fn screen_bind_group(
        device: &wgpu::Device,
        layouts: &SharedLayouts,
        frame_uniform: &wgpu::Buffer,
        t: &FrameTargets,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("screen"),
            layout: &layouts.screen,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: frame_uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&t.albedo) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&t.normal) },
                wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&t.emissive) },
                wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(&t.depth) },
            ],
        })
    }

    fn tonemap_bind_group(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        t: &FrameTargets,
        indirect: &wgpu::Buffer,
        exposure: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tonemap"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&t.hdr) },
                wgpu::BindGroupEntry { binding: 1, resource: indirect.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: exposure.as_entire_binding() },
            ],
        })
    }

    pub fn gpu(&self) -> &GpuContext {
        &self.gpu
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
            self.screen_bind_group =
                Self::screen_bind_group(&self.gpu.device, &self.layouts, &self.frame_uniform, &self.targets);
            self.rebind_tonemap();
        }
        self.settings = settings;
        Ok(())
    }

    fn rebind_tonemap(&mut self) {
        self.exposure.rebind(&self.gpu, &self.targets, &self.indirect_buffer);
        self.tonemap_bind_group = Self::tonemap_bind_group(
            &self.gpu.device,
            &self.tonemap_layout,
            &self.targets,
            &self.indirect_buffer,
            &self.exposure.result,
        );
    }

    /// Tone-map with this auto-exposure scale (and its log-average luminance) from now on in
    /// [`AutoExposure::Hold`]: what a view compared with another shows at the other's exposure (the app's
    /// reference view, the panes of a figure), so equal radiance looks equal side by side.
    pub fn set_held_exposure(&mut self, scale: f32, average: f32) -> Result<(), GpuError> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(GpuError::InvalidSettings(format!("auto-exposure scale {scale} must be > 0")));
        }
        self.gpu.check_lost()?;
        self.exposure.hold(&self.gpu, scale, average);
        Ok(())
    }

    /// The auto-exposure scale and the log-average luminance it was metered from, as of the last complete
    /// frame (`None` while [`RenderSettings::auto_exposure`] is off). A small blocking readback.
    pub fn auto_exposure(&self) -> Result<Option<(f32, f32)>, GpuError> {
        if self.settings.auto_exposure == AutoExposure::Off {
            return Ok(None);
        }
        let gpu = self.gpu.clone();
        gpu.guarded(|| self.exposure.read(&self.gpu).map(Some))
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
        let key = (lights.to_vec(), self.settings.vpl, std::sync::Arc::as_ptr(&self.scene.geometry) as usize);
        if self.vpls.key.as_ref() == Some(&key) {
            return false;
        }
        let (bvh, _) = self.scene.bvh(&self.gpu);
        let set = crate::vpl::generate(&bvh, lights, &self.settings.vpl);
        let gpu: Vec<GpuVpl> = set.vpls.iter().map(GpuVpl::new).collect();
        self.vpls.buffer.write(&self.gpu, &gpu);
        self.vpls.set = std::sync::Arc::new(set);
        self.vpls.key = Some(key);
        true
    }

    /// The VPLs of the last frame (empty without an indirect technique).
    pub fn vpls(&self) -> &VplSet {
        &self.vpls.set
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
            timer: &self.timer,
            size: (self.settings.width, self.settings.height),
            indirect_buffer: &self.indirect_buffer,
            vpls: &self.vpls,
            vpl_settings: &self.settings.vpl,
            visible_lights: &self.visible_lights,
            light_tiles: &self.light_tiles,
            light_tiles_enabled: self.settings.light_tiles,
            max_lights_per_step: match self.settings.max_lights_per_step {
                0 => usize::MAX,
                n => n,
            },
        }
    }

    /// Start a frame: upload the camera, let the technique prepare, and render the G-buffer and ambient passes.
    pub fn begin_frame(
        &mut self,
        technique: &mut dyn Technique,
        camera: &Camera,
        lights: &[PointLight],
    ) -> Result<FrameJob, GpuError> {
        let gpu = self.gpu.clone();
        gpu.guarded(|| self.begin_frame_unguarded(technique, camera, lights))
    }

    fn begin_frame_unguarded(
        &mut self,
        technique: &mut dyn Technique,
        camera: &Camera,
        lights: &[PointLight],
    ) -> Result<FrameJob, GpuError> {
        if !camera.is_valid() {
            return Err(GpuError::InvalidSettings("the camera has non-finite or degenerate values".into()));
        }
        let started = Instant::now();
        let aspect = self.aspect();
        let clip_from_world = camera.clip_from_world(aspect);
        let s = &self.settings;
        let uniform = FrameUniform {
            clip_from_world: clip_from_world.to_cols_array_2d(),
            world_from_clip: clip_from_world.inverse().to_cols_array_2d(),
            camera_position: camera.position.extend(1.0).to_array(),
            viewport: [s.width as f32, s.height as f32, 1.0 / s.width as f32, 1.0 / s.height as f32],
            ambient: s.ambient.extend(if s.specular { 1.0 } else { 0.0 }).to_array(),
            background: s.background.extend(1.0).to_array(),
            tonemap: [
                s.exposure,
                match s.tonemap {
                    ToneMap::Aces => 0.0,
                    ToneMap::Reinhard => 1.0,
                    ToneMap::Linear => 2.0,
                },
                if s.auto_exposure == AutoExposure::Off { 0.0 } else { 1.0 },
                0.0,
            ],
            indirect: [
                s.component as u32 as f32,
                s.indirect_gain,
                if self.indirect.is_some() { 1.0 } else { 0.0 },
                0.0,
            ],
        };
        self.gpu.queue.write_buffer(&self.frame_uniform, 0, bytemuck::bytes_of(&uniform));
        self.gpu.queue.write_buffer(&self.camera_uniform, 0, bytemuck::bytes_of(&MatrixUniform::new(clip_from_world)));

        // View-frustum culling of chunks for the G-buffer.
        let frustum = Frustum::from_clip_from_world(&clip_from_world);
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        let mut gbuffer_triangles = 0u64;
        {
            let chunks = &self.scene.chunks;
            let visible: Vec<u32> = (0..chunks.len() as u32)
                .filter(|&i| frustum.intersects_aabb(&chunks[i as usize].bounds))
                .inspect(|&i| gbuffer_triangles += chunks[i as usize].triangle_count() as u64)
                .collect();
            // Draw ranges per material (chunks of a material are contiguous and sorted).
            let mut per_material: Vec<(u32, Vec<(u32, u32)>)> = Vec::new();
            let mut start = 0;
            while start < visible.len() {
                let material = chunks[visible[start] as usize].material;
                let mut end = start;
                while end < visible.len() && chunks[visible[end] as usize].material == material {
                    end += 1;
                }
                merge_draw_ranges(chunks, visible[start..end].iter().copied(), &mut self.draw_ranges);
                per_material.push((material, self.draw_ranges.clone()));
                start = end;
            }
            let t = &self.targets;
            let clear = |c: wgpu::Color| wgpu::Operations { load: wgpu::LoadOp::Clear(c), store: wgpu::StoreOp::Store };
            let attachment = |view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: clear(wgpu::Color::TRANSPARENT),
                })
            };
            let scene = &self.scene;
            let pipeline = &self.gbuffer_pipeline;
            let camera_bg = &self.camera_bind_group;
            self.timer.render_pass(
                &mut encoder,
                "gbuffer",
                wgpu::RenderPassDescriptor {
                    label: None,
                    color_attachments: &[attachment(&t.albedo), attachment(&t.normal), attachment(&t.emissive)],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &t.depth,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                },
                |pass| {
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(0, camera_bg, &[]);
                    pass.set_vertex_buffer(0, scene.vertex_buffer.slice(..));
                    pass.set_vertex_buffer(1, scene.uv1_buffer.slice(..));
                    pass.set_index_buffer(scene.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
                    for (material, ranges) in &per_material {
                        pass.set_bind_group(1, &scene.material_bind_groups[*material as usize], &[]);
                        for &(first, count) in ranges {
                            pass.draw_indexed(first..first + count, 0, 0..1);
                        }
                    }
                },
            );
            let pipeline = &self.ambient_pipeline;
            let screen = &self.screen_bind_group;
            self.timer.render_pass(
                &mut encoder,
                "ambient",
                wgpu::RenderPassDescriptor {
                    label: None,
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &t.hdr,
                        depth_slice: None,
                        resolve_target: None,
                        ops: clear(wgpu::Color::BLACK),
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                },
                |pass| {
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(0, screen, &[]);
                    pass.draw(0..3, 0..1);
                },
            );
        }
        let mut vpl_ms = 0.0;
        let mut vpls_reused = false;
        if self.indirect.is_some() {
            encoder.clear_buffer(&self.indirect_buffer, 0, None);
        }
        self.timer.submit(&self.gpu, encoder, "gbuffer + ambient")?;

        self.visible_lights.update(&self.gpu, lights, &frustum);
        let direct_steps = {
            let ctx = self.context(camera, lights);
            technique.prepare(&ctx)?
        };
        self.build_light_tiles(technique.uses_light_tiles())?;
        let mut indirect_steps = 0;
        if let Some(mut indirect) = self.indirect.take() {
            let t0 = Instant::now();
            vpls_reused = !self.update_vpls(indirect.as_ref(), lights);
            vpl_ms = t0.elapsed().as_secs_f64() * 1000.0;
            let ctx = self.context(camera, lights);
            let prepared = indirect.prepare(&ctx);
            self.indirect = Some(indirect);
            indirect_steps = prepared?;
        }
        Ok(FrameJob {
            steps_total: direct_steps + indirect_steps,
            steps_done: 0,
            started,
            camera: *camera,
            lights: lights.to_vec(),
            gbuffer_triangles,
            direct_steps,
            vpl_ms,
            vpls_reused,
        })
    }

    /// Bin the visible lights' range spheres into screen tiles (its own submission, timed "light tiles"), or,
    /// when `used` is false or tiles are off, mark the lists absent so every span is the whole batch.
    fn build_light_tiles(&mut self, used: bool) -> Result<(), GpuError> {
        self.light_spheres.clear();
        self.light_spheres.extend(self.visible_lights.gpu.iter().map(|l| {
            let [x, y, z] = l.position;
            [x, y, z, l.range]
        }));
        let enabled = used && self.settings.light_tiles;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.light_tiles.build(
            &self.gpu,
            &self.layouts.light_tiles,
            &self.screen_bind_group,
            &self.timer,
            &mut encoder,
            (self.settings.width, self.settings.height),
            &self.light_spheres,
            enabled,
        );
        if enabled && !self.light_spheres.is_empty() {
            self.timer.submit(&self.gpu, encoder, "light tiles")?;
        }
        Ok(())
    }

    /// Limit the memory of the renderer's tile lists (default [`light_tiles::ITEM_BUDGET_BYTES`]): tiles whose
    /// lists do not fit loop over every light of a batch. For tests of that path.
    pub fn set_light_tile_budget(&mut self, bytes: u64) {
        self.light_tiles.set_item_budget(bytes);
    }

    /// The renderer's tile lists of the last frame, read back (blocking): per tile the indices (into the
    /// visible lights) of the lights that may reach it, `None` where it overflowed; empty when none were built.
    pub fn read_light_tiles(&self) -> Result<Vec<Option<Vec<u32>>>, GpuError> {
        self.light_tiles.read(&self.gpu)
    }

    /// Run up to `max_steps` steps of the technique. Returns true when all steps are done.
    pub fn advance(
        &mut self,
        job: &mut FrameJob,
        technique: &mut dyn Technique,
        max_steps: usize,
    ) -> Result<bool, GpuError> {
        let gpu = self.gpu.clone();
        gpu.guarded(|| self.advance_unguarded(job, technique, max_steps))
    }

    fn advance_unguarded(
        &mut self,
        job: &mut FrameJob,
        technique: &mut dyn Technique,
        max_steps: usize,
    ) -> Result<bool, GpuError> {
        let mut n = 0;
        while !job.is_done() && n < max_steps {
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            let label = if job.steps_done < job.direct_steps {
                let ctx = self.context(&job.camera, &job.lights);
                technique.encode_step(&ctx, job.steps_done, &mut encoder)?;
                technique.step_label()
            } else {
                let mut indirect = self.indirect.take().ok_or_else(|| {
                    GpuError::InvalidSettings("the indirect technique was removed during a frame".into())
                })?;
                self.timer.set_indirect(true);
                let result = {
                    let ctx = self.context(&job.camera, &job.lights);
                    indirect.encode_step(&ctx, job.steps_done - job.direct_steps, &mut encoder)
                };
                let label = indirect.step_label();
                self.indirect = Some(indirect);
                if let Err(e) = result {
                    self.timer.set_indirect(false);
                    return Err(e);
                }
                label
            };
            self.timer.submit(&self.gpu, encoder, label)?;
            self.timer.set_indirect(false);
            job.steps_done += 1;
            n += 1;
        }
        Ok(job.is_done())
    }

    /// Tone-map whatever has been accumulated (also of an unfinished job, for progressive display) and, when
    /// the job is done, collect the frame's timings.
    pub fn finish_frame(&mut self, job: FrameJob, technique: &dyn Technique) -> Result<FrameReport, GpuError> {
        let gpu = self.gpu.clone();
        gpu.guarded(|| self.finish_frame_unguarded(job, technique))
    }

    fn finish_frame_unguarded(&mut self, job: FrameJob, technique: &dyn Technique) -> Result<FrameReport, GpuError> {
        self.tonemap()?;
        let passes = self.timer.finish_frame(&self.gpu)?;
        let indirect_labels = self.timer.take_indirect_labels();
        let indirect_passes: Vec<PassTime> =
            passes.iter().filter(|p| indirect_labels.contains(&p.name)).cloned().collect();
        let gpu_total_ms = passes.iter().map(|p| p.ms).sum();
        Ok(FrameReport {
            technique: technique.key().to_string(),
            width: self.settings.width,
            height: self.settings.height,
            timing_source: self.timer.source(),
            passes,
            gpu_total_ms,
            cpu_stages: technique.cpu_times(),
            wall_ms: job.started.elapsed().as_secs_f64() * 1000.0,
            counts: FrameCounts {
                lights_total: job.lights.len(),
                scene_triangles: self.scene.triangle_count,
                gbuffer_triangles: job.gbuffer_triangles,
                technique: technique.counts(),
            },
            indirect: self.indirect.as_ref().map(|t| {
                let mut cpu_stages = vec![PassTime { name: "vpl generation".into(), ms: job.vpl_ms, count: 1 }];
                cpu_stages.extend(t.cpu_times());
                IndirectReport {
                    gpu_ms: indirect_passes.iter().map(|p| p.ms).sum(),
                    passes: indirect_passes,
                    technique: t.key().to_string(),
                    vpls: if t.uses_vpls() { self.vpls.set.vpls.len() } else { 0 },
                    vpl_source: self.settings.vpl.source,
                    vpl_misses: self.vpls.set.misses,
                    vpls_reused: job.vpls_reused,
                    counts: t.counts(),
                    cpu_stages,
                }
            }),
        })
    }

    /// Abandon an unfinished frame (the camera moved): its timings are collected and dropped, so they do not
    /// leak into the next frame's report.
    pub fn cancel_frame(&mut self, job: FrameJob) -> Result<(), GpuError> {
        drop(job);
        self.timer.take_indirect_labels();
        self.timer.finish_frame(&self.gpu).map(|_| ())
    }

    /// Tone-map the HDR target into the output texture (timed as the frame's "tonemap" pass).
    pub fn tonemap(&mut self) -> Result<(), GpuError> {
        self.encode_tonemap(true)
    }

    /// Tone-map what has been accumulated so far, for progressive display; not counted in the frame's timings.
    pub fn preview_tonemap(&mut self) -> Result<(), GpuError> {
        self.encode_tonemap(false)
    }

    fn encode_tonemap(&mut self, timed: bool) -> Result<(), GpuError> {
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        // A complete frame is metered; a progressive preview keeps the last scale unless none was metered yet.
        let meter = match self.settings.auto_exposure {
            AutoExposure::Off => false,
            AutoExposure::Meter => timed || !self.exposure.metered,
            AutoExposure::Hold => !self.exposure.metered,
        };
        if meter {
            self.exposure.encode(&mut encoder, &self.screen_bind_group, self.settings.width, self.settings.height);
        }
        let desc = wgpu::RenderPassDescriptor {
            label: Some("tonemap"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &self.targets.output,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        };
        let record = |pass: &mut wgpu::RenderPass<'_>| {
            pass.set_pipeline(&self.tonemap_pipeline);
            pass.set_bind_group(0, &self.screen_bind_group, &[]);
            pass.set_bind_group(1, &self.tonemap_bind_group, &[]);
            pass.draw(0..3, 0..1);
        };
        if timed {
            self.timer.render_pass(&mut encoder, "tonemap", desc, record);
            self.timer.submit(&self.gpu, encoder, "tonemap")
        } else {
            record(&mut encoder.begin_render_pass(&desc));
            self.gpu.queue.submit([encoder.finish()]);
            Ok(())
        }
    }

    /// Draw overlay primitives over the output (call after [`Renderer::tonemap`]). Depth-tested against the
    /// G-buffer of the last frame, unless `x_ray`.
    pub fn draw_overlays(
        &mut self,
        camera: &Camera,
        primitives: &[crate::technique::Overlay],
        x_ray: bool,
    ) -> Result<(), GpuError> {
        if primitives.is_empty() {
            return Ok(());
        }
        // wgpu's buffer helpers panic on a lost device.
        self.gpu.check_lost()?;
        let overlay = self.overlay.get_or_insert_with(|| overlay::OverlayRenderer::new(&self.gpu));
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        let t = &self.targets;
        overlay.draw(
            &self.gpu,
            &mut encoder,
            &t.output,
            &t.depth,
            camera.clip_from_world(self.settings.width as f32 / self.settings.height as f32),
            (t.width, t.height),
            primitives,
            x_ray,
            self.overlay_style,
        );
        self.gpu.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// How many times [`Renderer::draw_overlays`] tessellated and uploaded primitives (it reuses the last upload
    /// while they stay the same).
    pub fn overlay_uploads(&self) -> u64 {
        self.overlay.as_ref().map_or(0, |o| o.uploads)
    }

    /// Line width and the fading of occluded parts for [`Renderer::draw_overlays`].
    pub fn set_overlay_style(&mut self, style: overlay::OverlayStyle) {
        self.overlay_style = style;
    }

    /// Render a whole frame; `progress(done, total)` is called after each step.
    pub fn render_frame(
        &mut self,
        technique: &mut dyn Technique,
        camera: &Camera,
        lights: &[PointLight],
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<FrameReport, GpuError> {
        let mut job = self.begin_frame(technique, camera, lights)?;
        progress(0, job.steps_total);
        while !self.advance(&mut job, technique, 1)? {
            progress(job.steps_done, job.steps_total);
        }
        if job.steps_total > 0 {
            progress(job.steps_done, job.steps_total);
        }
        self.finish_frame(job, technique)
    }

    /// The tone-mapped output as an sRGB RGBA8 image.
    pub fn read_output(&self) -> Result<image::RgbaImage, GpuError> {
        let t = &self.targets;
        let bytes = readback::read_texture(&self.gpu, &t.output_texture, t.width, t.height, 4)?;
        image::RgbaImage::from_raw(t.width, t.height, bytes).ok_or_else(|| GpuError::Readback("size mismatch".into()))
    }

    /// Per pixel, true where the G-buffer holds geometry (not background): the pixels comparisons count.
    pub fn read_geometry_mask(&self) -> Result<Vec<bool>, GpuError> {
        let t = &self.targets;
        let bytes = readback::read_texture(&self.gpu, &t.depth_texture, t.width, t.height, 4)?;
        Ok(bytes.chunks_exact(4).map(|d| f32::from_le_bytes([d[0], d[1], d[2], d[3]]) < 1.0).collect())
    }

    /// World position of every pixel of the last frame (None for background), from the G-buffer depth.
    pub fn read_world_positions(&self, camera: &Camera) -> Result<Vec<Option<Vec3>>, GpuError> {
        let t = &self.targets;
        let bytes = readback::read_texture(&self.gpu, &t.depth_texture, t.width, t.height, 4)?;
        let world_from_clip = camera.clip_from_world(t.width as f32 / t.height as f32).inverse();
        Ok(bytes
            .chunks_exact(4)
            .enumerate()
            .map(|(i, d)| {
                let depth = f32::from_le_bytes([d[0], d[1], d[2], d[3]]);
                if depth >= 1.0 {
                    return None;
                }
                let (x, y) = ((i as u32 % t.width) as f32 + 0.5, (i as u32 / t.width) as f32 + 0.5);
                let ndc = glam::Vec4::new(x / t.width as f32 * 2.0 - 1.0, 1.0 - y / t.height as f32 * 2.0, depth, 1.0);
                let w = world_from_clip * ndc;
                Some(w.truncate() / w.w)
            })
            .collect())
    }

    /// The HDR radiance of the chosen [`RenderSettings::component`], linear RGBA, row-major (no gain).
    pub fn read_hdr(&self) -> Result<Vec<[f32; 4]>, GpuError> {
        self.read_component(self.settings.component)
    }

    /// The HDR radiance of one component, linear RGBA, row-major (no gain).
    pub fn read_component(&self, component: Component) -> Result<Vec<[f32; 4]>, GpuError> {
        let t = &self.targets;
        let direct = || -> Result<Vec<[f32; 4]>, GpuError> {
            let bytes = readback::read_texture(&self.gpu, &t.hdr_texture, t.width, t.height, 8)?;
            Ok(bytes
                .chunks_exact(8)
                .map(|p| {
                    let h = |i: usize| readback::f16_to_f32(u16::from_le_bytes([p[i], p[i + 1]]));
                    [h(0), h(2), h(4), h(6)]
                })
                .collect())
        };
        let indirect = || -> Result<Vec<[f32; 4]>, GpuError> {
            let bytes = readback::read_buffer(&self.gpu, &self.indirect_buffer)?;
            let values: &[f32] = bytemuck::cast_slice(&bytes);
            Ok(values.chunks_exact(4).map(|v| [v[0], v[1], v[2], 1.0]).collect())
        };
        let pixels = (t.width * t.height) as usize;
        match (component, self.indirect.is_some()) {
            (Component::Direct, _) | (Component::Total, false) => direct(),
            (Component::Indirect, false) => Ok(vec![[0.0, 0.0, 0.0, 1.0]; pixels]),
            (Component::Indirect, true) => indirect(),
            (Component::Total, true) => {
                let mut d = direct()?;
                for (p, i) in d.iter_mut().zip(indirect()?) {
                    for c in 0..3 {
                        p[c] += i[c];
                    }
                }
                Ok(d)
            }
        }
    }
}
