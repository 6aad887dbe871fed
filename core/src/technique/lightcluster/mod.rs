//! LightCluster (Wiesenhuetter, Gerhards, Gerndt, Brunnett, WSCG 2013): lights grouped by min-distance
//! clustering, one cube shadow map per cluster, soft shadows (PCF or PCSS) sized by the cluster radius.
//!
//! Per frame, following the paper:
//! 1. Cluster on the CPU ([`clustering`], section 3.1): cull range spheres against the view frustum, sort by
//!    `L_att`, select centers with `d_min = d_init · (1 − |C_pos| / z_far)`, assign the rest to the nearest
//!    center and grow `C_att = max(C_att, d_C + L_att)`.
//! 2. Worst case (section 5.2): when every visible light is its own cluster, render the reference path instead.
//! 3. Per batch of clusters (one step): render one cube shadow map per cluster at its center light (far plane
//!    `C_att`) into the shared atlas, then one shading pass: per pixel and cluster, skip the pixel beyond
//!    `C_att`, compute the cluster's visibility once as a disc light of radius `d_min` (PCF, or PCSS: blocker
//!    search, penumbra `w = d_min (d_r − d_b) / d_b`, PCF of width `w`) over a Poisson disk, and modulate the
//!    summed radiance of the cluster's member lights with it (section 3.2). The clusters' `C_att` spheres are
//!    binned into screen tiles first (the renderer's tile-list service), so a pixel visits only the batch's
//!    clusters that reach its tile.
//!
//! Deviation from the paper: visibility is not stored in a screen-sized texture per cluster but computed and
//! consumed cluster by cluster in the same pass (the issue allows either). That keeps memory bounded for
//! hundreds of clusters and still samples each cube map once per pixel and cluster, as the paper intends.
//! PCSS limits the filter to 4 cluster radii: wider filters with 8 samples only add noise. The blocker distance
//! `d_b` is measured along the tap's ray, as the receiver's `d_r` is (the cube map stores distances along a
//! face's axis, up to sqrt(3) shorter toward its corners, which widened penumbrae there several times). As
//! production PCSS, it skips the filter where the blocker search's samples all agree: none blocked (lit), or all
//! blocked with a filter no wider than the searched disc (umbra). With `early_out` (the default) PCSS also stops its blocker
//! search and its filter after the first half of their samples when those agree (none blocked in the search;
//! all lit or all shadowed in the filter): the other half only changes penumbrae. PCF keeps the paper's fixed
//! samples.
//!
//! Beyond the paper, off by default (`proxy` below 1): the cluster maps may draw a simplified copy of the scene
//! ([`crate::scene::proxy`]: meshoptimizer's edge collapse of the opaque surfaces together, the surface moved by
//! at most `proxy_error` of the scene's diagonal, cut-outs kept whole). A cluster map is filtered over a disc of the
//! cluster's radius anyway, so a surface moved by a few centimetres changes its penumbrae by less than the
//! filter's width, while the maps, which lavapipe draws at the cost of their triangles, get cheaper. The
//! lookups' bias grows by the error bound: without that, receivers behind a surface the collapse moved toward
//! the light shadowed themselves (Sponza, 2 cm: shadow error against the reference 2.76 % -> 2.95 %). The
//! reference path (and so the worst case's fallback) always draws the scene itself.
//!
//! Also beyond the paper, off by default (`centers=cover`): step 1's centers chosen by greedy covering
//! ([`cover`]: the light that covers the most lights not covered yet, the same covering bound), which takes fewer
//! clusters where the paper's order wastes centers (Sponza's 80 lights at `d_init` 0.5: 20 instead of 26).

mod cluster_params;
pub mod clustering;
pub mod cover;
mod cull_sort;
pub mod grid;
mod overlays;
mod params;

pub use params::{Centers, Filter, LightClusterParams};

use glam::Vec3;

use super::{check_param, FrameContext, OverlayLayer, Param, ParamError, ParamValue, Technique, TechniqueCounts};
use crate::error::GpuError;
use crate::gpu::bind::{depth_texture_entry, storage_entry, uniform_entry};
use crate::gpu::buffer::GrowableBuffer;
use crate::gpu::GpuContext;
use crate::scene::proxy::ProxyParams;
use crate::scene::PointLight;
use crate::services::cube_shadows::{CubeCaster, CubeGeometry, CubeShadowRenderer, MapGeometry};
use crate::services::gpu_data::{shadow_near, GpuLight};
use crate::services::layouts::SharedLayouts;
use crate::services::light_tiles::TileLists;
use crate::services::per_light_shadows::PerLightShadows;
use crate::services::shade_pass::ShadePass;
use crate::timing::PassTime;
use clustering::{ClusterParams, Clusterer, Clustering};

use crate::shaders::WgslModule;
/// This technique's own WGSL modules; its registry entry lists them and the naga test validates them.
pub const SHADERS: &[WgslModule] = &[SHADE];
const SHADE: WgslModule = crate::shaders::wgsl!(
    "lightcluster_shade",
    [
        "shaders/common.wgsl",
        "shaders/light_tiles.wgsl",
        "shaders/cube_shadow.wgsl",
        "core/src/technique/lightcluster/shade.wgsl"
    ]
);

/// Mirrors `Batch` in `lightcluster/shade.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ClusterBatchUniform {
    first_cluster: u32,
    cluster_count: u32,
    resolution: f32,
    bias_world: f32,
    normal_offset_texels: f32,
    tiles_per_row: u32,
    samples: u32,
    /// Bit 0 PCSS, bit 1 early out (`FLAG_*`).
    flags: u32,
    /// The one cluster whose visibility alone is drawn (grey), or `u32::MAX`: every cluster shaded.
    only_cluster: u32,
    _pad: [u32; 3],
}
/// Keep in sync with `FLAG_PCSS` and `FLAG_EARLY_OUT` in `lightcluster/shade.wgsl`.
const FLAG_PCSS: u32 = 1;
const FLAG_EARLY_OUT: u32 = 2;
const _: () = assert!(std::mem::size_of::<ClusterBatchUniform>() == 48);

/// Mirrors `Cluster` in `lightcluster/shade.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuCluster {
    pub position: [f32; 3],
    pub radius: f32,
    pub c_att: f32,
    pub shadow_near: f32,
    pub first_light: u32,
    pub light_count: u32,
    /// No member light lies farther than this from `position` (a receiver facing away from that ball gets
    /// nothing from the cluster: the shader skips its lights and its visibility).
    pub spread: f32,
    pub _pad: [f32; 3],
}
const _: () = assert!(std::mem::size_of::<GpuCluster>() == 48);

pub struct LightCluster {
    pub params: LightClusterParams,
    clusterer: Clusterer,
    clustering: Clustering,
    cubes: CubeShadowRenderer,
    shade: ShadePass,
    lights_buffer: GrowableBuffer,
    clusters_buffer: GrowableBuffer,
    bind_group: Option<wgpu::BindGroup>,
    gpu_clusters: Vec<GpuCluster>,
    gpu_lights: Vec<GpuLight>,
    batch_size: usize,
    counts: TechniqueCounts,
    clustering_ms: f64,
    /// Per screen tile, the clusters whose `C_att` sphere reaches it (the renderer's tile-list service).
    cluster_tiles: TileLists,
    cluster_spheres: Vec<[f32; 4]>,
    /// The reference path, for the worst case.
    /// The per-light path of the worst case (every cluster holds one light): the reference's own service.
    fallback: PerLightShadows,
    using_reference: bool,
    /// What the cluster maps draw: the scene, or its simplified copy (`proxy` below 1).
    maps: MapGeometry,
    /// How far the copy's surface may lie from the scene's (world units; 0 without a copy): added to the
    /// lookups' bias, so a receiver behind a surface the collapse moved toward the light does not shadow itself.
    proxy_bias: f32,
    /// `centers=cover` gave way to the paper's selection this frame (lights too dense for its neighbour lists).
    cover_fallback: bool,
}

impl LightCluster {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts) -> LightCluster {
        let device = &gpu.device;
        let entries = [storage_entry(0), storage_entry(1), uniform_entry(2), depth_texture_entry(3)];
        let shade = ShadePass::new::<ClusterBatchUniform>(gpu, layouts, "lightcluster shade", &SHADE, &entries, true);
        LightCluster {
            params: LightClusterParams::default(),
            clusterer: Clusterer::default(),
            clustering: Clustering::default(),
            cubes: CubeShadowRenderer::new(gpu),
            shade,
            lights_buffer: GrowableBuffer::new(device, "lightcluster lights", 64 * 32),
            clusters_buffer: GrowableBuffer::new(device, "lightcluster clusters", 64 * 32),
            bind_group: None,
            gpu_clusters: Vec::new(),
            gpu_lights: Vec::new(),
            batch_size: 1,
            counts: TechniqueCounts::default(),
            clustering_ms: 0.0,
            cluster_tiles: TileLists::new(gpu, &layouts.screen, &layouts.light_tiles),
            cluster_spheres: Vec::new(),
            fallback: PerLightShadows::new(gpu, layouts, CubeShadowRenderer::new(gpu)),
            using_reference: false,
            maps: MapGeometry::default(),
            proxy_bias: 0.0,
            cover_fallback: false,
        }
    }

    /// The clustering of the last frame.
    pub fn clustering(&self) -> &Clustering {
        &self.clustering
    }

    /// Steps 2-4 (section 3.1) for the `visible` lights: the paper's centers, or with `centers=cover` those of
    /// greedy covering ([`cover`]; the paper's when the lights are too dense for it, `cover_fallback` set).
    fn cluster(&mut self, lights: &[PointLight], visible: &[usize], camera: &crate::scene::Camera) {
        let z_far = if self.params.z_far > 0.0 { self.params.z_far } else { camera.z_far };
        let cluster_params = ClusterParams { d_init: self.params.d_init, z_far, adaptive: self.params.adaptive };
        self.cover_fallback = false;
        if self.params.centers == Centers::Cover {
            if cover::cluster_cover(lights, visible, camera.position, &cluster_params, &mut self.clustering) {
                return;
            }
            self.cover_fallback = true;
        }
        self.clusterer.cluster_visible_into(lights, visible, camera.position, &cluster_params, &mut self.clustering);
    }
}

/// A distinct, stable colour per cluster index.
pub fn cluster_color(index: usize) -> [f32; 4] {
    super::index_color(index)
}

impl Technique for LightCluster {
    fn key(&self) -> &'static str {
        "lightcluster"
    }

    fn label(&self) -> &'static str {
        "LightCluster"
    }

    fn params(&self) -> Vec<Param> {
        self.params.describe()
    }

    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        check_param(self.key(), &self.params(), key, value)?;
        self.params.set(key, value);
        Ok(())
    }

    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        // Step 1: clustering on the CPU.
        let start = std::time::Instant::now();
        // Step 1 (frustum culling) is the renderer's light list, shared with every technique.
        self.cluster(ctx.lights, &ctx.visible_lights.indices, ctx.camera);
        self.clustering_ms = start.elapsed().as_secs_f64() * 1000.0;
        let visible = self.clustering.visible;
        let cluster_count = self.clustering.clusters.len();

        // Step 2: the worst case goes down the reference path.
        self.using_reference = self.params.fallback && cluster_count > 0 && cluster_count == visible;
        if self.using_reference {
            // The reference path draws the scene itself (and reports no copy or build of one).
            self.maps = MapGeometry::default();
            self.proxy_bias = 0.0;
            let steps = self.fallback.prepare(ctx, &self.params.cube);
            self.counts = TechniqueCounts {
                lights_visible: self.fallback.visible_lights(),
                batches: steps,
                clusters: Some(cluster_count),
                fell_back_to_reference: true,
                ..Default::default()
            };
            return Ok(steps);
        }

        // Lights in cluster order, each cluster a contiguous run.
        self.gpu_lights.clear();
        self.gpu_clusters.clear();
        for cluster in &self.clustering.clusters {
            let first_light = self.gpu_lights.len() as u32;
            self.gpu_lights.extend(cluster.members.iter().map(|&i| GpuLight::new(&ctx.lights[i])));
            let spread =
                cluster.members.iter().map(|&i| ctx.lights[i].position.distance(cluster.position)).fold(0.0, f32::max);
            self.gpu_clusters.push(GpuCluster {
                position: cluster.position.to_array(),
                radius: cluster.d_min.max(0.0),
                c_att: cluster.c_att,
                shadow_near: shadow_near(cluster.c_att),
                first_light,
                light_count: cluster.members.len() as u32,
                spread,
                _pad: [0.0; 3],
            });
        }
        let (res, budget) = self.params.cube.resolution_and_budget(ctx.gpu);
        self.batch_size = CubeShadowRenderer::batch_capacity(ctx.gpu, res, budget).min(ctx.max_lights_per_step);
        let batches = cluster_count.div_ceil(self.batch_size);
        self.counts =
            TechniqueCounts { lights_visible: visible, batches, clusters: Some(cluster_count), ..Default::default() };
        if self.params.centers == Centers::Cover {
            // 1: the lights were too dense for the covering, and the paper's centers were used.
            self.counts.figures.insert("cover_fallback".into(), f64::from(u8::from(self.cover_fallback)));
        }
        // The cluster maps' geometry: a cube map draws edges straight as they are, so nothing is cut (max_edge 0).
        let scene_size = ctx.scene.bounds.size().length();
        let geometry = ProxyParams {
            keep: self.params.proxy,
            max_error: self.params.proxy_error * if scene_size.is_finite() { scene_size } else { 0.0 },
            max_edge: 0.0,
        };
        self.maps.update(ctx.gpu, ctx.scene, geometry);
        self.proxy_bias = if self.maps.is_copy() { geometry.max_error } else { 0.0 };
        if let Some(t) = self.maps.copy_triangles() {
            self.counts.figures.insert("map_geometry_triangles".into(), t as f64);
        }
        if cluster_count == 0 {
            return Ok(0);
        }
        let mut rebind = self.bind_group.is_none();
        rebind |= self.lights_buffer.write(ctx.gpu, &self.gpu_lights);
        rebind |= self.clusters_buffer.write(ctx.gpu, &self.gpu_clusters);
        rebind |= self.cubes.ensure_atlas(ctx.gpu, res, self.batch_size.min(cluster_count));
        if rebind {
            let atlas = self.cubes.atlas().expect("atlas was just ensured");
            self.bind_group = Some(self.shade.bind_group(
                ctx.gpu,
                &[
                    wgpu::BindGroupEntry { binding: 0, resource: self.lights_buffer.buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: self.clusters_buffer.buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 2, resource: self.shade.batch_uniform().as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&atlas.view) },
                ],
            ));
        }
        Ok(batches)
    }

    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        if self.using_reference {
            let stats = self.fallback.encode_batch(ctx, step, encoder, ctx.scene.cube_geometry(), &self.params.cube);
            self.counts.add_cube_stats(&stats);
            return Ok(());
        }
        if step == 0 {
            // Bin the clusters' C_att spheres into screen tiles once per frame, for every batch's shading.
            self.cluster_spheres.clear();
            self.cluster_spheres.extend(self.gpu_clusters.iter().map(|c| {
                let [x, y, z] = c.position;
                [x, y, z, c.c_att]
            }));
            self.cluster_tiles.build(
                ctx.gpu,
                &ctx.layouts.light_tiles,
                ctx.screen_bind_group,
                ctx.timer,
                encoder,
                ctx.size,
                &self.cluster_spheres,
                ctx.light_tiles_enabled,
            );
        }
        // Step 3: this batch's cluster cube maps, then its shading.
        let first = step * self.batch_size;
        let last = (first + self.batch_size).min(self.gpu_clusters.len());
        let res = self.cubes.atlas().map_or(1, |a| a.resolution);
        let casters: Vec<CubeCaster> = self.gpu_clusters[first..last]
            .iter()
            .map(|c| {
                let p = &self.params.cube;
                let bias = p.bias_world + self.proxy_bias;
                let hard = CubeCaster::hard_lookup_radius(c.c_att, res, p.normal_offset_texels, bias);
                // PCF and PCSS tap within 4 d_min of the receiver (`shade.wgsl`: the filter radius is capped
                // there, the blocker search is d_min wide).
                CubeCaster {
                    position: Vec3::from_array(c.position),
                    near: c.shadow_near,
                    far: c.c_att,
                    lookup_radius: hard + 4.0 * c.radius,
                }
            })
            .collect();
        let geometry =
            CubeGeometry { cull: self.params.cube.cull, receivers: ctx.receivers, ..self.maps.geometry(ctx.scene) };
        let stats = self.cubes.render(ctx.gpu, geometry, ctx.timer, encoder, "shadow maps", &casters);
        self.counts.add_cube_stats(&stats);

        let atlas = self.cubes.atlas().expect("prepare sized the atlas");
        let uniform = ClusterBatchUniform {
            first_cluster: first as u32,
            cluster_count: (last - first) as u32,
            resolution: atlas.resolution as f32,
            bias_world: self.params.cube.bias_world + self.proxy_bias,
            normal_offset_texels: self.params.cube.normal_offset_texels,
            tiles_per_row: atlas.tiles_per_row,
            samples: self.params.samples,
            flags: if self.params.filter == Filter::Pcss { FLAG_PCSS } else { 0 }
                | if self.params.early_out { FLAG_EARLY_OUT } else { 0 },
            only_cluster: self.params.visibility_of.unwrap_or(u32::MAX),
            _pad: [0; 3],
        };
        self.shade.write_batch(ctx.gpu, &uniform);
        let group = self.bind_group.as_ref().expect("prepare created the bind group");
        self.shade.encode(ctx, encoder, "shading", group, Some(self.cluster_tiles.bind_group()));
        Ok(())
    }

    fn step_label(&self) -> &'static str {
        "shadow maps + shading"
    }

    fn counts(&self) -> TechniqueCounts {
        self.counts.clone()
    }

    fn uses_light_tiles(&self) -> bool {
        // The reference path reads the renderer's lists of lights; the cluster path bins its own clusters.
        self.using_reference
    }

    fn cpu_times(&self) -> Vec<PassTime> {
        let clustering = PassTime { name: "clustering".into(), ms: self.clustering_ms, count: 1 };
        std::iter::once(clustering).chain(self.maps.build_time()).collect()
    }

    /// Per pixel, the cluster whose center is nearest among those whose `C_att` reaches the pixel: the cluster
    /// whose shadow map shades it most.
    fn pixel_ids(&self, positions: &[Option<Vec3>]) -> Option<(&'static str, Vec<u32>)> {
        self.pixel_id_map(positions)
    }

    /// Step 1 again (about 0.1 ms for hundreds of lights), so the clusters follow a dragged light or camera.
    fn update_overlays(&mut self, ctx: &crate::technique::OverlayContext) -> crate::technique::OverlayUpdate {
        self.cluster(ctx.lights, ctx.visible, ctx.camera);
        crate::technique::OverlayUpdate::live()
    }

    fn overlays(&self, lights: &[PointLight]) -> Vec<OverlayLayer> {
        self.overlay_layers(lights)
    }

    fn explain(&self) -> Vec<super::ExplainStep> {
        self.explain_steps()
    }

    fn shadow_atlas(&self) -> Option<(&crate::services::cube_shadows::CubeAtlas, &'static str)> {
        if self.using_reference {
            return self
                .fallback
                .atlas()
                .map(|a| (a, "cube maps of the last batch, six faces per light (+x -x +y -y +z -z)"));
        }
        self.cubes.atlas().map(|a| (a, "cube maps of the last batch, six faces per cluster (+x -x +y -y +z -z)"))
    }

    fn light_details(&self, index: usize) -> Option<super::LightDetails> {
        self.cluster_details(index)
    }

    fn overlay_legend(&self, layer: &OverlayLayer) -> Vec<super::LegendEntry> {
        self.legend_of(layer)
    }
}
