//! ReSTIR's GPU side: its pipelines, buffers and bind groups, and one function per pass of a ReSTIR frame
//! (the steps of the module doc of [`super`]).

use wgpu::util::DeviceExt;

use super::state::{GpuReservoir, Groups, History, Inspection, Reservoirs};
use super::{alias, params, BiasMode, Restir, RestirParams, Source, CANDIDATES, OUTPUT, SHADE, SPATIAL, TEMPORAL};
use crate::accel::scene_bvh::SceneBvh;
use crate::error::GpuError;
use crate::fingerprint::lights_fingerprint;
use crate::gpu::bind::{storage_entry, storage_rw_entry, uniform_entry};
use crate::gpu::buffer::GrowableBuffer;
use crate::gpu::GpuContext;
use crate::services::gpu_data::GpuLight;
use crate::services::layouts::{compute_pipeline, SharedLayouts};
use crate::services::shade_pass::ShadePass;
use crate::services::vpl_gather::pixel_workgroups;
use crate::shaders::WgslModule;
use crate::technique::{FrameContext, TechniqueCounts};

/// Mirrors `RestirFrame` in `restir/reservoir.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct FrameUniform {
    prev_clip_from_world: [[f32; 4]; 4],
    prev_camera: [f32; 4],
    source_count: u32,
    light_count: u32,
    candidates: u32,
    frame_index: u32,
    seed: u32,
    temporal: u32,
    history_cap: f32,
    spatial: u32,
    radius: f32,
    unbiased: u32,
    bias: f32,
    weight: f32,
    depth_threshold: f32,
    normal_cos: f32,
    first_frame: u32,
    tiled: u32,
    shown_scale: f32,
    _pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<FrameUniform>() == 160);

impl Restir {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts) -> Restir {
        let device = &gpu.device;
        let entries =
            [SceneBvh::layout_entries(), vec![storage_entry(2), storage_entry(3), uniform_entry(4), storage_entry(5)]]
                .concat();
        let group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("restir"),
            entries: &[entries, vec![storage_rw_entry(6)]].concat(),
        });
        let pipeline = |module: &WgslModule, entry: &str| {
            compute_pipeline(gpu, layouts, module.name, module.source, entry, &[&group_layout])
        };
        // Candidates read the renderer's tile lists too (group 2), for the tile source.
        let candidates_pipeline = compute_pipeline(
            gpu,
            layouts,
            CANDIDATES.name,
            CANDIDATES.source,
            "candidates_main",
            &[&group_layout, &layouts.light_tiles],
        );
        let temporal_pipeline = pipeline(&TEMPORAL, "temporal_main");
        let spatial_pipeline = pipeline(&SPATIAL, "spatial_main");
        let shade_entries = [
            SceneBvh::layout_entries(),
            vec![
                storage_entry(2),
                uniform_entry(4),
                storage_entry(5),
                storage_rw_entry(7),
                storage_rw_entry(8),
                storage_rw_entry(9),
            ],
        ]
        .concat();
        let shade_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("restir shade"),
            entries: &shade_entries,
        });
        let shade_pipeline = compute_pipeline(gpu, layouts, SHADE.name, SHADE.source, "shade_main", &[&shade_layout]);
        let output = ShadePass::new::<[u32; 4]>(gpu, layouts, "restir output", &OUTPUT, &[storage_entry(0)], false);
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("restir frame"),
            contents: bytemuck::bytes_of(&<FrameUniform as bytemuck::Zeroable>::zeroed()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        Restir {
            params: RestirParams::default(),
            candidates_pipeline,
            temporal_pipeline,
            spatial_pipeline,
            shade_pipeline,
            group_layout,
            shade_layout,
            uniform,
            output,
            lights: GrowableBuffer::new(device, "restir lights", 64 * 64),
            lights_key: None,
            source: GrowableBuffer::new(device, "restir source table", 16 * 64),
            source_key: None,
            source_count: 0,
            reservoirs: None,
            groups: None,
            bvh: None,
            history: None,
            frame_index: 0,
            frames: 0,
            last_step: "restir frame",
            counts: TechniqueCounts::default(),
            build_ms: None,
            table_ms: 0.0,
            inspection: Inspection::default(),
        }
    }

    /// Upload the frame's lights when they changed; a different count forgets the history (its reservoirs name
    /// lights by index).
    pub(super) fn upload_lights(&mut self, ctx: &FrameContext) {
        let key = (lights_fingerprint(ctx.lights), ctx.lights.len());
        if self.lights_key == Some(key) {
            return;
        }
        if self.lights_key.is_none_or(|(_, n)| n != key.1) {
            self.history = None;
        }
        let gpu: Vec<GpuLight> = ctx
            .lights
            .iter()
            .map(|l| if l.is_valid() { GpuLight::new(l) } else { bytemuck::Zeroable::zeroed() })
            .collect();
        if self.lights.write(ctx.gpu, &gpu) {
            self.groups = None;
        }
        self.lights_key = Some(key);
    }

    /// The source pdf over the visible lights, rebuilt when they, the lights or the choice changed.
    pub(super) fn build_source(&mut self, ctx: &FrameContext) {
        let visible = &ctx.visible_lights.indices;
        let fingerprint = self.lights_key.map_or(0, |(f, _)| f);
        let stale = self
            .source_key
            .as_ref()
            .is_none_or(|(f, v, s)| *f != fingerprint || v != visible || *s != self.params.source);
        if !stale {
            return;
        }
        let started = std::time::Instant::now();
        let table = match self.params.source {
            // The tile source draws from the tile lists; the table maps their entries (visible lights) to lights.
            Source::Uniform | Source::Tiles => alias::uniform_table(visible),
            Source::Power => {
                let power: Vec<f64> = visible
                    .iter()
                    .map(|&i| {
                        let l = &ctx.lights[i];
                        crate::math::luminance(l.color * l.intensity) as f64
                    })
                    .collect();
                // No power at all: nothing to draw, and nothing would light the pixels.
                alias::alias_table(visible, &power).unwrap_or_default()
            }
        };
        if self.source.write(ctx.gpu, &table) {
            self.groups = None;
        }
        self.source_count = table.len();
        self.source_key = Some((fingerprint, visible.clone(), self.params.source));
        self.table_ms = started.elapsed().as_secs_f64() * 1000.0;
    }

    /// The reservoir buffers of the frame's size (new ones forget the history).
    pub(super) fn ensure_reservoirs(&mut self, ctx: &FrameContext) -> Result<(), GpuError> {
        if self.reservoirs.as_ref().is_some_and(|r| r.size == ctx.size) {
            return Ok(());
        }
        let (w, h) = ctx.size;
        let pixels = w as u64 * h as u64;
        let bytes = pixels * std::mem::size_of::<GpuReservoir>() as u64;
        let limits = ctx.gpu.device.limits();
        let max = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        if bytes > max {
            return Err(GpuError::InvalidSettings(format!(
                "restir at {w}x{h} needs reservoir buffers of {} MiB; this GPU allows {} MiB (lower the image size)",
                bytes >> 20,
                max >> 20
            )));
        }
        let buffer = |label, bytes: u64| {
            ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(32),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        self.reservoirs = Some(Reservoirs {
            size: ctx.size,
            working: buffer("restir reservoirs", bytes),
            last: buffer("restir final reservoirs", bytes),
            mean: buffer("restir mean", pixels * 16),
            shown: buffer("restir shown mean", pixels * 16),
            delta: buffer("restir output delta", pixels * 16),
        });
        self.groups = None;
        self.history = None;
        Ok(())
    }

    pub(super) fn bind_groups(&mut self, ctx: &FrameContext) {
        if self.groups.is_some() {
            return;
        }
        let (Some(bvh), Some(res)) = (&self.bvh, &self.reservoirs) else { return };
        let device = &ctx.gpu.device;
        let group = |input: &wgpu::Buffer, output: &wgpu::Buffer| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("restir"),
                layout: &self.group_layout,
                entries: &[
                    bvh.bind_entries(),
                    vec![
                        wgpu::BindGroupEntry { binding: 2, resource: self.lights.buffer.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 3, resource: self.source.buffer.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 4, resource: self.uniform.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 5, resource: input.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 6, resource: output.as_entire_binding() },
                    ],
                ]
                .concat(),
            })
        };
        let shade = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("restir shade"),
            layout: &self.shade_layout,
            entries: &[
                bvh.bind_entries(),
                vec![
                    wgpu::BindGroupEntry { binding: 2, resource: self.lights.buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 4, resource: self.uniform.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 5, resource: res.last.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 7, resource: res.mean.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 8, resource: res.shown.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 9, resource: res.delta.as_entire_binding() },
                ],
            ]
            .concat(),
        });
        let output = self
            .output
            .bind_group(ctx.gpu, &[wgpu::BindGroupEntry { binding: 0, resource: res.delta.as_entire_binding() }]);
        self.groups = Some(Groups {
            to_working: group(&res.last, &res.working),
            to_last: group(&res.working, &res.last),
            shade,
            output,
        });
    }

    /// The uniform of ReSTIR frame `frame_index` from the frame's camera, reusing `history` when there is one;
    /// `first_frame` starts the mean over.
    /// Whether the HDR target shows the running mean after ReSTIR frame `step` of `frames`: after frames 1, 2, 4,
    /// 8, ... and the last.
    pub(super) fn shows(step: usize, frames: usize) -> bool {
        (step + 1).is_power_of_two() || step + 1 == frames
    }

    /// The uniform of ReSTIR frame `step` (0-based) of the rendered frame.
    pub(super) fn frame_uniform(&self, ctx: &FrameContext, history: Option<History>, step: usize) -> FrameUniform {
        let first_frame = step == 0;
        let p = &self.params;
        let prev = history.unwrap_or(History {
            clip_from_world: ctx.camera.clip_from_world(ctx.aspect),
            camera_position: ctx.camera.position,
        });
        FrameUniform {
            prev_clip_from_world: prev.clip_from_world.to_cols_array_2d(),
            prev_camera: prev.camera_position.extend(1.0).to_array(),
            source_count: self.source_count as u32,
            light_count: ctx.lights.len() as u32,
            candidates: p.candidates.max(1),
            frame_index: self.frame_index,
            seed: p.seed,
            temporal: history.is_some() as u32,
            history_cap: p.history as f32 * p.candidates as f32,
            spatial: p.spatial.min(params::MAX_SPATIAL),
            radius: p.radius,
            unbiased: (p.bias_mode == BiasMode::Unbiased) as u32,
            bias: p.bias,
            weight: 1.0 / p.frames.max(1) as f32,
            depth_threshold: p.depth_threshold,
            normal_cos: p.normal_threshold_deg.to_radians().cos(),
            first_frame: first_frame as u32,
            tiled: (p.source == Source::Tiles) as u32,
            // The sum so far of `step + 1` frames each weighted 1/frames, shown as their mean (0: not shown).
            shown_scale: if Self::shows(step, p.frames.max(1) as usize) {
                p.frames.max(1) as f32 / (step + 1) as f32
            } else {
                0.0
            },
            _pad: [0; 3],
        }
    }

    fn dispatch(
        &self,
        ctx: &FrameContext,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        pipeline: &wgpu::ComputePipeline,
        group: &wgpu::BindGroup,
    ) {
        let (x, y) = pixel_workgroups(ctx.size);
        ctx.timer.compute_pass(encoder, label, |pass| {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, ctx.screen_bind_group, &[]);
            pass.set_bind_group(1, group, &[]);
            pass.dispatch_workgroups(x, y, 1);
        });
    }

    fn groups(&self) -> &Groups {
        self.groups.as_ref().expect("prepare made the bind groups")
    }

    /// Steps 1-2: candidates, RIS and visibility reuse, into this frame's reservoirs.
    pub(super) fn candidates_pass(&self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) {
        let (x, y) = pixel_workgroups(ctx.size);
        ctx.timer.compute_pass(encoder, "restir candidates", |pass| {
            pass.set_pipeline(&self.candidates_pipeline);
            pass.set_bind_group(0, ctx.screen_bind_group, &[]);
            pass.set_bind_group(1, &self.groups().to_working, &[]);
            pass.set_bind_group(2, ctx.light_tiles.bind_group(), &[]);
            pass.dispatch_workgroups(x, y, 1);
        });
    }

    /// Step 3: temporal reuse of the last final reservoirs, in place.
    pub(super) fn temporal_pass(&self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) {
        self.dispatch(ctx, encoder, "restir temporal", &self.temporal_pipeline, &self.groups().to_working);
    }

    /// Step 4: spatial reuse and the final sample's shadow ray, into the final reservoirs.
    pub(super) fn spatial_pass(&self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) {
        self.dispatch(ctx, encoder, "restir spatial", &self.spatial_pipeline, &self.groups().to_last);
    }

    /// Step 5: `f(y) W / frames` into the mean.
    pub(super) fn shade_pass(&self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) {
        self.dispatch(ctx, encoder, "restir shade", &self.shade_pipeline, &self.groups().shade);
    }

    /// After each ReSTIR frame: the change of the running mean into the HDR target, so a progressive display
    /// shows the mean so far and the last step leaves the mean of all.
    pub(super) fn output_pass(&self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) {
        self.output.encode(ctx, encoder, "restir output", &self.groups().output, None);
    }
}
