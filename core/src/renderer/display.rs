//! Showing a frame: tone mapping (with the metered or held exposure) and the overlays drawn over it.

use super::*;

impl Renderer {
    /// Let `technique` run its overlay stages for `camera` and `lights` without rendering (the app's preview
    /// while a light or the camera moves): the same light culling and aspect as a frame of this renderer, and
    /// for a technique that uses VPLs the VPLs of these lights at the preview's size (the fixed set, when one
    /// was given; else at most [`crate::vpl::PREVIEW_VPLS`] of the same sequence).
    pub fn update_overlays(
        &self,
        technique: &mut dyn Technique,
        camera: &Camera,
        lights: &[PointLight],
    ) -> crate::technique::OverlayUpdate {
        let frustum = Frustum::from_clip_from_world(&camera.clip_from_world(self.aspect()));
        let visible: Vec<usize> = lights::visible_indices(lights, &frustum).collect();
        let asked = self.settings.vpl.count;
        let (vpls, vpl_samples) = if !technique.uses_vpls() {
            (std::sync::Arc::new(VplSet::default()), (0, 0))
        } else if self.fixed_vpls || self.vpls_are_of(lights) {
            // The last frame's own set (the camera moves, the lights do not): a technique that made its
            // overlays from this very set has nothing to redo.
            (self.vpls.set.clone(), (asked, asked))
        } else {
            let preview = crate::vpl::VplSettings { count: asked.min(crate::vpl::PREVIEW_VPLS), ..self.settings.vpl };
            let (bvh, _) = self.scene.bvh(&self.gpu);
            (
                std::sync::Arc::new(crate::vpl::generate(&bvh, lights, self.directional.lights(), &preview)),
                (preview.count, asked),
            )
        };
        technique.update_overlays(&crate::technique::OverlayContext {
            camera,
            frustum,
            lights,
            visible: &visible,
            vpls: &vpls,
            vpl_samples,
            scene_bounds: self.scene.bounds,
        })
    }

    /// [`Renderer::update_overlays`] for this renderer's own indirect technique (None without one).
    pub fn update_indirect_overlays(
        &mut self,
        camera: &Camera,
        lights: &[PointLight],
    ) -> Option<crate::technique::OverlayUpdate> {
        let mut technique = self.indirect.take()?;
        let update = self.update_overlays(technique.as_mut(), camera, lights);
        self.indirect = Some(technique);
        Some(update)
    }

    pub(super) fn rebind_tonemap(&mut self) {
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

    /// Tone-map the HDR target into the output texture (timed as the frame's "tonemap" pass).
    pub fn tonemap(&mut self) -> Result<(), GpuError> {
        self.encode_tonemap(true)
    }

    /// Tone-map what has been accumulated so far, for progressive display; not counted in the frame's timings.
    pub fn preview_tonemap(&mut self) -> Result<(), GpuError> {
        self.encode_tonemap(false)
    }

    pub(super) fn encode_tonemap(&mut self, timed: bool) -> Result<(), GpuError> {
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        // A complete frame is metered; a progressive preview keeps the last scale unless none was metered yet.
        let meter = match self.settings.auto_exposure {
            AutoExposure::Off => false,
            AutoExposure::Meter => timed || !self.exposure.metered,
            AutoExposure::Hold => !self.exposure.metered,
        };
        if meter {
            let timer = timed.then_some(&self.timer);
            self.exposure.encode(
                &mut encoder,
                &self.screen_bind_group,
                self.settings.width,
                self.settings.height,
                timer,
            );
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
            self.targets.output_written();
            self.timer.submit(&self.gpu, encoder, "tonemap")
        } else {
            record(&mut encoder.begin_render_pass(&desc));
            self.targets.output_written();
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
        self.targets.output_written();
        Ok(())
    }

    /// Before the app shows [`FrameTargets::output_display`]: on GL, copy the output into it if it changed
    /// (once a UI frame at most, after the tone mapping and the overlays); nothing elsewhere.
    pub fn sync_display(&mut self) -> Result<(), GpuError> {
        if !self.targets.display_stale() {
            return Ok(());
        }
        self.gpu.check_lost()?;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.targets.encode_display_copy(&mut encoder);
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
}
