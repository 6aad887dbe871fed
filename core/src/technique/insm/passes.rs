//! INSM's GPU passes, one function each: the intermediate maps (rendered as the reference renders a view),
//! Algorithm 2's triangulation on the GPU, and reading the tiles back; and the mesh buffers they share.

use super::*;

impl Insm {
    /// Steps 1-2's viewpoints for the scene in `bounds`: `auto` asks the scene whether it is enclosed (once per
    /// scene: its bounds; `first_view::is_enclosed`) and `walls` finds the walls, both through the scene's BVH
    /// (built once per scene, shared with the tracers; its build and the test are CPU stages of the frame that
    /// pays them). Sets `placement_used`.
    pub(super) fn place_viewpoints(&mut self, ctx: &FrameContext, bounds: &Aabb) -> Vec<Viewpoint> {
        use viewpoints::Placement;
        let placement = match self.params.placement {
            Placement::Auto => match self.auto_placement {
                Some((b, p)) if b == *bounds => p,
                _ => {
                    let (bvh, build_ms) = ctx.scene.bvh(ctx.gpu);
                    if let Some(ms) = build_ms {
                        self.cpu_times.push(PassTime { name: "bvh build".into(), ms, count: 1 });
                    }
                    let start = std::time::Instant::now();
                    let enclosed = crate::accel::first_view::is_enclosed(&bvh.cpu, bounds);
                    let ms = start.elapsed().as_secs_f64() * 1e3;
                    self.cpu_times.push(PassTime { name: "placement test".into(), ms, count: 1 });
                    let p = if enclosed { Placement::Inside } else { Placement::Box };
                    self.auto_placement = Some((*bounds, p));
                    p
                }
            },
            p => p,
        };
        self.placement_used = placement;
        let bvh = (placement == Placement::Walls).then(|| ctx.scene.bvh(ctx.gpu).0);
        let hit = |o: Vec3, d: Vec3, t: f32| {
            bvh.as_ref().and_then(|b| crate::accel::bvh::closest_hit_cpu(&b.cpu, o, d, t)).map(|h| h.t)
        };
        viewpoints::select(
            placement,
            bounds,
            &self.custom_viewpoints,
            self.params.viewpoints as usize,
            self.params.box_distance,
            bvh.as_ref().map(|_| &hit as &dyn Fn(Vec3, Vec3, f32) -> Option<f32>),
        )
    }

    /// Steps `0..k`: Algorithm 1 line 2 for viewpoint `j`, one map per step so that a slow scene never holds the
    /// app for all `k` at once. The first step clears the atlas, the others draw into their own tile.
    pub(super) fn encode_intermediate_map(&mut self, ctx: &FrameContext, j: usize, encoder: &mut wgpu::CommandEncoder) {
        let stats = self.images.render_views(
            ctx.gpu,
            ctx.scene.cube_geometry(),
            ctx.timer,
            encoder,
            "intermediate shadow maps",
            &self.view_matrices[j..j + 1],
            j,
            j == 0,
        );
        self.counts.add_cube_stats(&stats);
    }

    /// With `mesh_views`, step `k + 1`: the reconstructed meshes as the per-light maps draw them (simplified
    /// when `simplify` is below 1), unpushed, seen from every viewpoint into their own atlas, tile `j` from
    /// viewpoint `j` as the intermediate images: side by side, what the triangulation kept, bridged or lost
    /// (inspection; not in the frame's counts, in its time).
    pub(super) fn encode_mesh_views(&mut self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) {
        let (Some(mesh), Some(images)) = (self.mesh.as_ref(), self.mesh_images.as_mut()) else { return };
        let geometry = mesh.geometry(self.simplified.as_ref(), &self.tiles, self.tiles_triangles, 0.0);
        let label = "insm meshes from the viewpoints (inspection)";
        images.render_views(ctx.gpu, geometry, ctx.timer, encoder, label, &self.view_matrices, 0, true);
    }

    /// Step `k`: Algorithm 1 line 3 for all maps, and the copies the first light batch reads back.
    pub(super) fn encode_triangulation(&mut self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) {
        let mesh = self.mesh.as_ref().expect("prepare created the mesh buffers");
        let tps = triangulate::tiles_per_side(mesh.resolution);
        let (pipeline, group, k) = (&self.triangulate_pipeline, &mesh.bind_group, self.views.len() as u32);
        let classify = &self.classify_pipeline;
        ctx.timer.compute_pass(encoder, "triangulation", |pass| {
            // Without `adaptive`, `classify` only clears the flags.
            pass.set_pipeline(classify);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(tps, tps, k);
            pass.set_pipeline(pipeline);
            pass.dispatch_workgroups(tps, tps, k);
        });
        let tile_bytes = (k * tps * tps) as u64 * std::mem::size_of::<GpuTile>() as u64;
        encoder.copy_buffer_to_buffer(&mesh.tiles, 0, &mesh.tiles_readback, 0, tile_bytes);
        self.tiles_ready = false;
    }

    /// Before the first light batch: read the tiles back and make the tile list the lights cull against (the
    /// samples stay on the GPU until an overlay asks for them).
    pub(super) fn read_tiles(&mut self, gpu: &GpuContext) -> Result<(), GpuError> {
        let start = std::time::Instant::now();
        let mesh = self.mesh.as_ref().expect("prepare created the mesh buffers");
        let k = self.views.len() as u64;
        let tps = triangulate::tiles_per_side(mesh.resolution) as u64;
        let tile_bytes = k * tps * tps * std::mem::size_of::<GpuTile>() as u64;
        let tiles: Vec<GpuTile> = bytemuck::cast_slice(&map_read(gpu, &mesh.tiles_readback, tile_bytes)?).to_vec();
        self.tiles.clear();
        self.mesh_triangles = 0;
        // What the adaptive mesh merged: whole tiles (how much a merge across tiles could still save) and tiles
        // merged in part (planar blocks beside a crease, an edge or a silhouette).
        let (mut merged_tiles, mut merged_triangles, mut partly_merged) = (0u64, 0u64, 0u64);
        for (i, t) in tiles.iter().enumerate() {
            let count = t.count.min(MAX_TRIANGLES_PER_TILE);
            if count == 0 {
                continue;
            }
            self.mesh_triangles += count as u64;
            if t.merged & triangulate::TILE_BIT != 0 {
                merged_tiles += 1;
                merged_triangles += count as u64;
            } else if t.merged != 0 {
                partly_merged += 1;
            }
            let min = Vec3::from_slice(&t.bounds_min[..3]);
            let max = Vec3::from_slice(&t.bounds_max[..3]);
            // Bounds that are not finite (never, unless the depth atlas holds garbage) make the tile always drawn.
            let bounds = if min.is_finite() && max.is_finite() && min.cmple(max).all() {
                Aabb { min, max }
            } else {
                Aabb { min: Vec3::splat(-f32::MAX), max: Vec3::splat(f32::MAX) }
            };
            self.tiles.push(Chunk {
                first_index: i as u32 * MAX_TRIANGLES_PER_TILE * 3,
                index_count: count * 3,
                material: 0,
                bounds,
            });
        }
        self.snapshot = MeshSnapshot {
            resolution: mesh.resolution,
            settings: self.mesh_settings(),
            views: self.map_views(),
            source: mesh.vertices_readback.as_ref().map(|rb| SampleSource {
                gpu: gpu.clone(),
                vertices: mesh.vertices.clone(),
                readback: rb.clone(),
                bytes: k * (mesh.resolution as u64).pow(2) * MESH_VERTEX_BYTES,
            }),
            samples: Default::default(),
            layers: Default::default(),
            simplified: None,
        };
        self.tiles_ready = true;
        self.counts.insm_mesh_triangles = Some(self.mesh_triangles);
        self.tiles_triangles = self.mesh_triangles;
        self.counts.figures.insert("mesh_tiles".into(), self.tiles.len() as f64);
        self.counts.figures.insert("mesh_merged_tiles".into(), merged_tiles as f64);
        self.counts.figures.insert("mesh_merged_triangles".into(), merged_triangles as f64);
        self.counts.figures.insert("mesh_partly_merged_tiles".into(), partly_merged as f64);
        self.cpu_times.push(PassTime {
            name: "mesh readback".into(),
            ms: start.elapsed().as_secs_f64() * 1e3,
            count: 1,
        });
        self.simplified = None;
        if self.params.simplify < 1.0 && self.mesh_triangles > 0 {
            self.simplify_meshes(gpu, &tiles)?;
        }
        Ok(())
    }

    /// `simplify` below 1: the meshes read back whole (the tiles `read_tiles` just read), simplified on the CPU ([`simplify`]), and their indices
    /// uploaded; the per-light maps then draw those chunks instead of the tiles. The triangulation's count stays
    /// in `insm_mesh_triangles`; the figure `mesh_simplified_triangles` is what the maps draw from.
    fn simplify_meshes(&mut self, gpu: &GpuContext, tiles: &[GpuTile]) -> Result<(), GpuError> {
        let start = std::time::Instant::now();
        let (samples, triangles) = self.read_mesh_triangles(gpu, tiles)?;
        let diagonal = self.bounds.size().length();
        let max_error = self.params.simplify_error * if diagonal.is_finite() { diagonal } else { 0.0 };
        let mesh = simplify::simplify(&samples, &triangles, self.params.simplify, max_error);
        let indices: &[u8] = if mesh.indices.is_empty() { &[0u8; 12] } else { bytemuck::cast_slice(&mesh.indices) };
        self.simplified = Some(gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("insm simplified indices"),
            contents: indices,
            usage: wgpu::BufferUsages::INDEX,
        }));
        self.counts.figures.insert("mesh_simplified_triangles".into(), mesh.triangle_count() as f64);
        // Its wireframe, one colour: every `stride`-th triangle when large (the triangulation's layer caps alike).
        let stride = (mesh.triangle_count() as usize).div_ceil(MAX_WIREFRAME_TRIANGLES).max(1);
        let color = [0.2, 1.0, 0.6, 0.9];
        let primitives = mesh
            .indices
            .chunks_exact(3)
            .step_by(stride)
            .flat_map(|t| {
                let p = [t[0], t[1], t[2]].map(|i| samples[i as usize].truncate());
                [(p[0], p[1]), (p[1], p[2]), (p[2], p[0])].map(|(from, to)| Overlay::Line { from, to, color })
            })
            .collect();
        self.snapshot.simplified = Some(OverlayLayer { name: SIMPLIFIED_LAYER, visible_by_default: false, primitives });
        self.tiles_triangles = mesh.triangle_count();
        self.tiles = mesh.chunks;
        self.cpu_times.push(PassTime {
            name: "mesh simplification".into(),
            ms: start.elapsed().as_secs_f64() * 1e3,
            count: 1,
        });
        Ok(())
    }
}
