//! A frame: [`Renderer::begin_frame`] (the G-buffer, the ambient pass, the directional lights, the light
//! culling, the technique's `prepare`, the tile lists), [`Renderer::advance`] (the technique's and then the
//! indirect technique's steps, one submission each), [`Renderer::finish_frame`] (tone mapping, the clock, the
//! work counts, the report), and [`Renderer::render_frame`], all of them in one call.

use super::*;

impl Renderer {
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
            // Draw ranges per material (chunks of a material are contiguous and sorted), and whether it is cut out.
            type MaterialDraws = (u32, bool, Vec<(u32, u32)>);
            let mut per_material: Vec<MaterialDraws> = Vec::new();
            let mut start = 0;
            while start < visible.len() {
                let material = chunks[visible[start] as usize].material;
                let mut end = start;
                while end < visible.len() && chunks[visible[end] as usize].material == material {
                    end += 1;
                }
                merge_draw_ranges(chunks, visible[start..end].iter().copied(), &mut self.draw_ranges);
                let cutout = self.scene.material_cutout.get(material as usize).copied().unwrap_or(false);
                per_material.push((material, cutout, self.draw_ranges.clone()));
                start = end;
            }
            // Opaque materials first (no alpha test: hidden fragments are rejected by depth before shading), then
            // the cut-outs, whose fragments behind opaque surfaces are then rejected too.
            per_material.sort_by_key(|&(_, cutout, _)| cutout);
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
            let (masked_pipeline, opaque_pipeline) = (&self.gbuffer_pipeline, &self.gbuffer_opaque_pipeline);
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
                    pass.set_bind_group(0, camera_bg, &[]);
                    pass.set_vertex_buffer(0, scene.vertex_buffer.slice(..));
                    pass.set_vertex_buffer(1, scene.uv1_buffer.slice(..));
                    pass.set_index_buffer(scene.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
                    let mut bound = None;
                    for &(material, masked, ref ranges) in &per_material {
                        if bound != Some(masked) {
                            pass.set_pipeline(if masked { masked_pipeline } else { opaque_pipeline });
                            bound = Some(masked);
                        }
                        pass.set_bind_group(1, &scene.material_bind_groups[material as usize], &[]);
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
        if !self.directional.lights().is_empty() {
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
            view_fingerprint: crate::fingerprint::fingerprint(&(
                &job.camera,
                crate::fingerprint::lights_fingerprint(&job.lights),
                self.directional.lights(),
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
