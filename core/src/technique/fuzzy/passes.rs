//! The frame's steps of fuzzy clustering (the module comment's numbered steps): 2-4 (the shading points and both
//! clusterings), 5 (visibility, a block of rows a step), 6 (shading, a batch of lights a step), and the last
//! step's readback; `mod.rs` sizes them in `prepare` and dispatches them from `encode_step`.

use super::*;

impl FuzzyClustering {
    pub(super) fn kmeans_params(
        &self,
        bounds: crate::scene::Aabb,
        clusters: usize,
        width: u32,
        height: u32,
        gamma: u32,
        f: usize,
    ) -> KMeansParams {
        // The shading points of the view may lie a little outside the scene's bounds (depth reconstruction):
        // the grid clamps them into its border cells, which keeps the search exact.
        KMeansParams {
            clusters,
            iterations: self.params.iterations,
            gamma,
            fuzziness: f,
            n_t: self.params.n_t,
            min_distance: self.scene_size * 1e-6,
            max_ring: if self.params.search == "paper" { 1 } else { 0 },
            neighbour_lists: self.params.assign == "neighbours",
            width,
            height,
            bounds_min: bounds.min,
            bounds_extent: bounds.size().max(Vec3::splat(1e-6)),
        }
    }

    /// Steps 2-4, the frame's first step: the shading points from the G-buffer, both clusterings.
    pub(super) fn cluster_step(
        &mut self,
        ctx: &FrameContext,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        let (vpl_kp, sp_kp) = self.pending;
        if let Some(kp) = vpl_kp.as_ref().filter(|_| !self.vpl_reused) {
            self.clustered_vpls = None;
            let max_flux = self.vpls.vpls.iter().map(|v| v.flux.max_element()).fold(0.0f32, f32::max);
            let vpls = &ctx.vpls.buffer.buffer;
            configure(&mut self.vpl_kmeans, ctx.gpu, &self.params, false);
            self.vpl_kmeans.encode(ctx.gpu, ctx.timer, encoder, vpls, kp, Some(max_flux), false)?;
            self.clustered_vpls = Some((self.vpls.clone(), *kp));
        }
        if let Some(kp) = sp_kp.as_ref().filter(|_| !self.sp_reused) {
            self.clustered_view = None;
            let pixels = ctx.size.0 as u64 * ctx.size.1 as u64;
            gpu::ensure_storage(&mut self.sp_points, ctx.gpu, "fuzzy shading points", pixels * 48);
            let points = self.sp_points.as_ref().expect("ensured");
            let group = ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("fuzzy shading points"),
                layout: &self.points_layout,
                entries: &[wgpu::BindGroupEntry { binding: 0, resource: points.as_entire_binding() }],
            });
            let (x, y) = crate::services::vpl_gather::pixel_workgroups(ctx.size);
            ctx.timer.compute_pass(encoder, "fuzzy shading points", |pass| {
                pass.set_pipeline(&self.points_pipeline);
                pass.set_bind_group(0, ctx.screen_bind_group, &[]);
                pass.set_bind_group(1, &group, &[]);
                pass.dispatch_workgroups(x, y, 1);
            });
            let points = self.sp_points.as_ref().expect("ensured");
            let run = KMeansParams { iterations: self.params.warm_iterations, ..*kp };
            let (kp_run, warm) = if self.sp_warm { (&run, true) } else { (kp, false) };
            configure(&mut self.sp_kmeans, ctx.gpu, &self.params, self.params.count_searches);
            self.sp_kmeans.encode(ctx.gpu, ctx.timer, encoder, points, kp_run, None, warm)?;
            self.clustered_view = self.bvh.clone().map(|bvh| (bvh, *ctx.camera, ctx.size, *kp));
        }
        Ok(())
    }

    /// The last step: the clusters read back for the counts (and, with `inspect`, the assignments for the
    /// overlays and the probe), after the frame's GPU work, so no step waits for the clustering.
    pub(super) fn readback_step(&mut self, ctx: &FrameContext) -> Result<(), GpuError> {
        let start = std::time::Instant::now();
        let (vpl_clustered, sp_clustered) = (self.pending.0.is_some(), self.pending.1.is_some());
        let inspect = self.params.inspect;
        if vpl_clustered {
            self.inspection.vpl_clusters = self.vpl_kmeans.read_clusters(ctx.gpu)?;
            if inspect {
                self.inspection.vpl_assignment = self.vpl_kmeans.read_assignment(ctx.gpu)?.0;
            }
        }
        if sp_clustered {
            self.inspection.sp_clusters = self.sp_kmeans.read_clusters(ctx.gpu)?;
            if inspect {
                self.inspection.sp_centroids = self.sp_kmeans.read_centroids(ctx.gpu)?;
                let (a, inv) = self.sp_kmeans.read_assignment(ctx.gpu)?;
                self.inspection.sp_assignment = a;
                self.inspection.sp_inverse = inv;
            }
        }
        let live = |c: &[GpuPoint]| c.iter().filter(|p| p.exists()).count();
        if vpl_clustered {
            self.counts.figures.insert("k_vpl".into(), live(&self.inspection.vpl_clusters) as f64);
        }
        if let Some(counts) = self.sp_kmeans.read_search_counts(ctx.gpu)?.filter(|_| sp_clustered) {
            for (kind, c) in gpu::SEARCH_KINDS.iter().zip(counts) {
                let mut put = |what: &str, v: u32| self.counts.figures.insert(format!("sp {kind}: {what}"), v as f64);
                put("points", c.points);
                put("cells visited", c.cells);
                put("centroids considered", c.centroids);
                put("points queued", c.queued);
                put("most cells + centroids of one invocation", c.most);
            }
        }
        if sp_clustered {
            let sp_live = live(&self.inspection.sp_clusters);
            let members: u32 = self.inspection.sp_clusters.iter().map(|c| c.members()).sum();
            self.counts.figures.insert("shading points".into(), members as f64);
            self.counts.figures.insert("k_sp".into(), sp_live as f64);
            self.counts.figures.insert("shadow rays".into(), (sp_live * self.light_count) as f64);
            // Step 5's rays: one per live shading-point cluster and live light (the kernel skips dead ones; a
            // pair closer than twice the bias, which traces none, is counted all the same).
            let lights_live = if vpl_clustered { live(&self.inspection.vpl_clusters) } else { self.light_count };
            self.counts.work.shadow_rays = (sp_live * lights_live) as u64;
            if inspect {
                self.build_pixel_maps();
                if self.params.probe_x >= 0 && self.params.probe_y >= 0 {
                    let lights: Vec<GpuPoint> = match self.mode {
                        ClusterMode::ShadingPoints => self.vpls.vpls.iter().map(GpuPoint::of_vpl).collect(),
                        _ => self.inspection.vpl_clusters.clone(),
                    };
                    self.inspection.probe = self.probe_overlay(ctx, &lights);
                }
            }
        }
        self.readback_ms = start.elapsed().as_secs_f64() * 1000.0;
        Ok(())
    }

    /// Step 5, the `step`-th block of SP clusters' rows of visibility bits (the first also gathers the rays'
    /// endpoints: the SP clusters, then the VPL clusters).
    pub(super) fn visibility_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        let endpoints = self.endpoints.as_ref().expect("prepare sized it");
        if step == 0 {
            let sp = self.sp_kmeans.clusters.as_ref().expect("prepare clustered the shading points");
            encoder.copy_buffer_to_buffer(sp, 0, endpoints, 0, (self.sp_count * 48) as u64);
            if self.mode == ClusterMode::Both {
                let lights = self.vpl_kmeans.clusters.as_ref().expect("prepare clustered the VPLs");
                let at = (self.sp_count * 48) as u64;
                encoder.copy_buffer_to_buffer(lights, 0, endpoints, at, (self.light_count * 48) as u64);
            }
        }
        let first = step * self.rows_per_step;
        let rows = self.rows_per_step.min(self.sp_count - first);
        let uniform = VisParamsUniform {
            sp_count: self.sp_count as u32,
            light_count: self.light_count as u32,
            words_per_row: self.words_per_row as u32,
            first_row: first as u32,
            row_count: rows as u32,
            _pad: [0; 3],
            camera_bias: ctx.camera.position.extend(self.params.ray_bias).to_array(),
        };
        ctx.gpu.queue.write_buffer(&self.vis_uniform, 0, bytemuck::bytes_of(&uniform));
        let group = ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("fuzzy visibility"),
            layout: &self.vis_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.vis_uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: endpoints.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: self.bits.as_ref().expect("prepare sized it").as_entire_binding(),
                },
            ],
        });
        let (x, y) = gpu::groups(rows * self.words_per_row);
        let bvh = self.bvh_group.as_ref().expect("prepare bound the BVH");
        ctx.timer.compute_pass(encoder, "fuzzy visibility", |pass| {
            pass.set_pipeline(&self.vis_pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.set_bind_group(1, bvh, &[]);
            pass.dispatch_workgroups(x, y, 1);
        });
        Ok(())
    }

    /// Step 6, the `batch_index`-th batch of lights: equation 6 with the visibility mode's `V~` (or, clustering
    /// the VPLs alone, the shared gather with a ray per pixel and light).
    pub(super) fn shading_step(
        &mut self,
        ctx: &FrameContext,
        batch_index: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        let first = batch_index * self.lights_per_step;
        let last = (first + self.lights_per_step).min(self.light_count);
        let mut batch =
            GatherBatchUniform { first_vpl: first as u32, vpl_count: (last - first) as u32, ..Default::default() };
        // The lights gathered: the VPLs themselves, or (VPLs clustered) the clusters (fields, not a method: the
        // passes below are borrowed mutably beside them).
        let lights = match self.mode {
            ClusterMode::ShadingPoints => &ctx.vpls.buffer.buffer,
            _ => self.vpl_kmeans.clusters.as_ref().expect("prepare clustered the VPLs"),
        };
        if self.mode == ClusterMode::Vpls {
            batch.bias = self.params.ray_bias;
            let bvh = self.bvh_group.as_ref().expect("prepare bound the BVH");
            self.ray_pass.encode_lights(ctx, encoder, "fuzzy shading", bvh, batch, lights);
            return Ok(());
        }
        let uniform = ShadeUniform {
            fuzziness: self.sp_kmeans.shape.fuzziness as u32,
            mode: self.params.shade_mode().index(),
            words_per_row: self.words_per_row as u32,
            _pad: 0,
        };
        ctx.gpu.queue.write_buffer(&self.shade_uniform, 0, bytemuck::bytes_of(&uniform));
        let group = ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("fuzzy shading"),
            layout: &self.shade_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.shade_uniform.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: self.sp_kmeans.assignment.as_ref().expect("clustered").as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: self.bits.as_ref().expect("prepare sized it").as_entire_binding(),
                },
            ],
        });
        self.shade_pass.encode_lights(ctx, encoder, "fuzzy shading", &group, batch, lights);
        Ok(())
    }
}

/// A k-means run's speed-only settings from the technique's parameters (the clusters do not change with them):
/// the schedule (`schedule`: a real GPU's or a CPU rasterizer's, `auto` from the adapter), the dispatches' timing,
/// the searches' work counts, the shells and work a search does alone, the grid's finer levels.
fn configure(km: &mut GpuKMeans, gpu: &crate::gpu::GpuContext, params: &FuzzyParams, count_searches: bool) {
    let gpu_schedule = match params.schedule.as_str() {
        "gpu" => true,
        "cpu" => false,
        _ => gpu.adapter_info.device_type != wgpu::DeviceType::Cpu,
    };
    km.set_gpu_schedule(gpu, gpu_schedule);
    km.set_count_searches(gpu, count_searches);
    km.set_time_dispatches(params.time_dispatches);
    km.set_near_shells(params.near_shells);
    km.set_near_budget(params.near_budget);
    km.set_fine_levels(params.fine_levels, params.fine_above);
}
