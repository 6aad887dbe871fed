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
pub mod directional;
mod display;
pub mod exposure;
pub mod gpu_data;
pub mod layouts;
pub mod light_tiles;
pub mod lights;
pub mod overlay;
pub mod per_light_shadows;
mod read;
pub mod report;
pub mod settings;
mod setup;
pub mod shade_pass;
pub mod targets;
pub mod vpl_gather;
pub mod work_counters;

use std::time::Instant;

use crate::accel::gpu_scene::GpuScene;
use crate::error::GpuError;
use crate::gpu::GpuContext;
use crate::math::Frustum;
use crate::scene::chunks::merge_draw_ranges;
use crate::scene::{Camera, PointLight, Scene};
use crate::shaders;
use crate::technique::{FrameContext, Technique};
use crate::timing::{PassTime, PassTimer};
use crate::vpl::{GpuVpl, VplFrame, VplSet};
use gpu_data::{FrameUniform, MatrixUniform};
use layouts::SharedLayouts;
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

    pub fn gpu(&self) -> &GpuContext {
        &self.gpu
    }

    /// Choose the clock of the reports from the next frame on (`SHADOWLAB_TIMING` chose it at creation).
    pub fn set_timing_mode(&mut self, mode: crate::timing::TimingMode) {
        self.timer.set_mode(mode);
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
        self.work_counters.clear(&mut encoder);
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
        if !self.scene.directional.is_empty() {
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            let mode = technique.directional_visibility();
            let (scene, timer) = (&self.scene, &self.timer);
            if self.directional.render_maps(&self.gpu, scene, camera, aspect, mode, timer, &mut encoder) {
                self.directional.shade(&self.context(camera, lights), &mut encoder)?;
            }
            self.timer.submit(&self.gpu, encoder, "directional lights")?;
        }

        self.visible_lights.update(&self.gpu, lights, &frustum);
        // GPU work a technique submits and waits for in `prepare` is its CPU stages' time (timing.rs).
        self.timer.set_stage(true);
        let direct_steps = {
            let ctx = self.context(camera, lights);
            technique.prepare(&ctx)
        };
        self.timer.set_stage(false);
        let direct_steps = direct_steps?;
        self.build_light_tiles(technique.uses_light_tiles())?;
        let mut indirect_steps = 0;
        if let Some(mut indirect) = self.indirect.take() {
            let t0 = Instant::now();
            self.timer.set_stage(true);
            vpls_reused = !self.update_vpls(indirect.as_ref(), lights);
            self.timer.set_stage(false);
            vpl_ms = t0.elapsed().as_secs_f64() * 1000.0;
            let ctx = self.context(camera, lights);
            self.timer.set_stage(true);
            let prepared = indirect.prepare(&ctx);
            self.timer.set_stage(false);
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
        let times = self.timer.finish_frame(&self.gpu)?;
        let passes = times.passes;
        let indirect_labels = self.timer.take_indirect_labels();
        let indirect_passes: Vec<PassTime> =
            passes.iter().filter(|p| indirect_labels.contains(&p.name)).cloned().collect();
        let total_ms = passes.iter().map(|p| p.ms).sum();
        let wall_ms = job.started.elapsed().as_secs_f64() * 1000.0;
        // Read after the frame's clock stopped: the readback is in no step's time.
        let gpu_work = self.work_counters.read(&self.gpu)?;
        let counts = technique.counts();
        let parameters =
            |t: &dyn Technique| t.params().into_iter().map(|p| (p.key.to_string(), p.value.to_string())).collect();
        Ok(FrameReport {
            technique: technique.key().to_string(),
            parameters: parameters(technique),
            view_fingerprint: report::fingerprint(&(
                &job.camera,
                report::lights_fingerprint(&job.lights),
                self.settings.work_fingerprint(),
                self.scene.triangle_count,
                self.scene.bounds,
            )),
            width: self.settings.width,
            height: self.settings.height,
            timing: times.timing,
            passes,
            total_ms,
            steps: times.steps,
            stage_passes: times.stage_passes,
            cpu_stages: technique.cpu_times(),
            wall_ms,
            work: counts.work_map(&gpu_work.direct, gpu_work.shaded_pixels),
            counts: FrameCounts {
                lights_total: job.lights.len(),
                scene_triangles: self.scene.triangle_count,
                gbuffer_triangles: job.gbuffer_triangles,
                technique: counts,
            },
            indirect: self.indirect.as_ref().map(|t| {
                let counts = t.counts();
                let mut cpu_stages = vec![PassTime { name: "vpl generation".into(), ms: job.vpl_ms, count: 1 }];
                cpu_stages.extend(t.cpu_times());
                IndirectReport {
                    gpu_ms: indirect_passes.iter().map(|p| p.ms).sum(),
                    passes: indirect_passes,
                    technique: t.key().to_string(),
                    parameters: parameters(t.as_ref()),
                    vpls: if t.uses_vpls() { self.vpls.set.vpls.len() } else { 0 },
                    vpl_source: self.settings.vpl.source,
                    vpl_misses: self.vpls.set.misses,
                    vpls_reused: job.vpls_reused,
                    work: counts.work_map(&gpu_work.indirect, gpu_work.shaded_pixels),
                    counts,
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
}
