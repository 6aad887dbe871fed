//! Fuzzy clustering of shading points and VPLs (Colom, Marques, Santos 2022): visibility is ray traced only
//! between the representatives of shading-point (SP) clusters and of VPL clusters, and every shading point
//! interpolates it from its `F` nearest SP clusters.
//!
//! Per frame (the paper's Fig. 2):
//! 1. VPLs: the renderer's shared set; the paper traces particles, which `--vpl-source auto` (the default)
//!    picks for this technique (`TechniqueEntry::vpl_source`); both sources work.
//! 2. VPL clustering: `K_vpl` clusters by Algorithm 1 over position and normal ([`kmeans`], on the GPU in
//!    [`gpu`]); each cluster becomes one light at its representative (the member nearest the centroid) with
//!    its members' mean normal and summed flux (`I_c` of equation 6).
//! 3. Shading points: the G-buffer's pixels (position, normal) of the current view (`fuzzy/points.wgsl`).
//! 4. SP clustering: `K_sp` clusters by Algorithm 1 over every `gamma`-th column and row, then Algorithm 2
//!    assigns every pixel to its `F` nearest clusters with inverse distances (`assign=neighbours`, the default:
//!    the pixels between samples from their four samples' lists, a deviation of [`kmeans`]). Both clusterings: initial
//!    centroids from the data, a regular grid over the centroids rebuilt every iteration and a search from the
//!    27 cells around a point, fixed-point atomic sums (64-bit, 2^-24 of the scene's bounds), `dist` of
//!    equation 7 with `n_t`.
//! 5. Visibility: one shadow ray through the scene BVH from every SP representative to every light (VPL
//!    cluster or VPL): `K_sp x K_vpl` bits (`fuzzy/visibility.wgsl`).
//! 6. Shading (equation 6, `fuzzy/shade.wgsl`): every shading point sums the lights with its own BRDF and
//!    geometry term toward the light and the visibility `V~`: `hard` (its nearest cluster's), `fuzzy`
//!    (equation 8, the mean over its `F` clusters) or `weighted` (equations 9-10, inverse-distance weights).
//!
//! Steps of a rendered frame: the first encodes steps 2-4 (the shading points and both clusterings, sized in
//! `prepare` from their settings, so nothing waits for them), then step 5 in blocks of rows, step 6 in batches
//! of lights, and a last step reads the clusters back for the counts (and, with `inspect`, the assignments for
//! the overlays and the probe) after the frame's GPU work. (The clustering was read back in `prepare`, a wait of
//! 170-200 ms in the middle of the frame on a 143k-triangle interior at 240x160.)
//!
//! Ablations (section 4): `cluster = sp` (every VPL is a light, SPs clustered: Fig. 7), `vpl` (VPLs clustered,
//! every pixel traces its own rays to the VPL clusters' representatives: Fig. 9, the shared VPL gather with
//! ray-traced visibility), `both` (the method, Fig. 10).
//!
//! Deviations, and why (besides those of [`kmeans`]):
//! - The representatives are members (the one nearest the centroid), not the centroids: a centroid is a mean
//!   of surface points and may lie inside geometry or in the air, where shadow rays would start blocked or
//!   unblocked wrongly. The paper speaks of "the representative VPL of cluster c" without saying how it is
//!   chosen.
//! - Both clusterings run in every frame whose inputs changed (the paper clusters VPLs once per static scene):
//!   lights and the camera move here. A frame reuses the VPL clusters of the same VPL set and the shading-point
//!   clusters of the same view (`reuse=all`; `vpls` and `none` cluster more, for timing).
//! - Ray ends are offset along their normals by `bias` times the camera distance, as `vpl-raytraced` does, so
//!   the two are comparable (with one cluster per VPL and per pixel the two images agree: tested).

pub mod gpu;
pub mod kmeans;
mod overlays;
pub mod params;

use std::sync::Arc;

use glam::Vec3;

use super::{
    check_param, index_color, FrameContext, Overlay, OverlayLayer, Param, ParamError, ParamValue, Technique,
    TechniqueCounts,
};
use crate::accel::scene_bvh::SceneBvh;
use crate::error::GpuError;
use crate::gpu::bind::storage_rw_entry;
use crate::gpu::bind::{storage_entry, uniform_entry};
use crate::gpu::GpuContext;
use crate::renderer::layouts::compute_pipeline;
use crate::renderer::layouts::SharedLayouts;
use crate::renderer::vpl_gather::{vpl_overlays, GatherBatchUniform, VplGatherPass};
use crate::scene::PointLight;
use crate::shaders;
use crate::timing::PassTime;
use crate::vpl::{GpuVpl, VplSet};
use gpu::{GpuKMeans, GpuPoint};
use kmeans::{KMeansParams, MAX_F};
pub use params::{ClusterMode, FuzzyParams};

use crate::shaders::WgslModule;
/// This technique's own WGSL modules; its registry entry lists them and the naga test validates them.
pub const SHADERS: &[WgslModule] = &[POINTS, VISIBILITY, SHADE, KMEANS];
const POINTS: WgslModule =
    crate::wgsl!("fuzzy_points", ["shaders/common.wgsl", "core/src/technique/fuzzy/points.wgsl"]);
const VISIBILITY: WgslModule =
    crate::wgsl!("fuzzy_visibility", ["shaders/raytrace_bvh.wgsl", "core/src/technique/fuzzy/visibility.wgsl"]);
const SHADE: WgslModule = crate::wgsl!(
    "fuzzy_shade",
    ["shaders/common.wgsl", "shaders/vpl_common.wgsl", "core/src/technique/fuzzy/shade.wgsl"]
);
const KMEANS: WgslModule = crate::wgsl!(
    "fuzzy_kmeans",
    [
        "core/src/technique/fuzzy/kmeans.wgsl",
        "core/src/technique/fuzzy/kmeans_search.wgsl",
        "core/src/technique/fuzzy/kmeans_final.wgsl"
    ]
);

/// Mirrors `VisParams` in `fuzzy/visibility.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct VisParamsUniform {
    sp_count: u32,
    light_count: u32,
    words_per_row: u32,
    first_row: u32,
    row_count: u32,
    _pad: [u32; 3],
    camera_bias: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<VisParamsUniform>() == 48);

/// Mirrors `FuzzyShade` in `fuzzy/shade.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadeUniform {
    fuzziness: u32,
    mode: u32,
    words_per_row: u32,
    _pad: u32,
}

/// What the last frame's clusterings left on the CPU (for counts and overlays).
#[derive(Default)]
struct Inspection {
    size: (u32, u32),
    sp_clusters: Vec<GpuPoint>,
    sp_centroids: Vec<GpuPoint>,
    /// Per pixel, F entries (inspect only).
    sp_assignment: Vec<u32>,
    sp_inverse: Vec<f32>,
    vpl_clusters: Vec<GpuPoint>,
    /// Per VPL, its cluster (inspect only).
    vpl_assignment: Vec<u32>,
    probe: Vec<Overlay>,
    /// The per-pixel maps of the shading-point clusters (inspect only), made once per frame: the app asks for
    /// the overlays every UI frame.
    hard_map: Option<Arc<Vec<u32>>>,
    blend_map: Option<Arc<Vec<[u8; 4]>>>,
}

pub struct FuzzyClustering {
    pub params: FuzzyParams,
    sp_kmeans: GpuKMeans,
    vpl_kmeans: GpuKMeans,
    points_pipeline: wgpu::ComputePipeline,
    points_layout: wgpu::BindGroupLayout,
    sp_points: Option<wgpu::Buffer>,
    bvh_layout: wgpu::BindGroupLayout,
    bvh_group: Option<wgpu::BindGroup>,
    bvh: Option<Arc<SceneBvh>>,
    vis_pipeline: wgpu::ComputePipeline,
    vis_layout: wgpu::BindGroupLayout,
    vis_uniform: wgpu::Buffer,
    endpoints: Option<wgpu::Buffer>,
    bits: Option<wgpu::Buffer>,
    shade_pass: VplGatherPass,
    shade_layout: wgpu::BindGroupLayout,
    shade_uniform: wgpu::Buffer,
    ray_pass: VplGatherPass,
    vpls: Arc<VplSet>,
    // This frame's plan.
    mode: ClusterMode,
    light_count: usize,
    sp_count: usize,
    words_per_row: usize,
    rows_per_step: usize,
    vis_steps: usize,
    lights_per_step: usize,
    shade_steps: usize,
    scene_size: f32,
    inspection: Inspection,
    counts: TechniqueCounts,
    /// The clusterings this frame's first step encodes (steps 2-4): the VPLs' and the shading points'
    /// k-means settings.
    pending: (Option<KMeansParams>, Option<KMeansParams>),
    /// The VPL set and settings the VPL clusters on the GPU were made from: a frame with the same set (the
    /// renderer keeps its `Arc` while the lights and VPL settings do not change, as when only the camera moves)
    /// and settings reuses them instead of clustering again.
    clustered_vpls: Option<(Arc<VplSet>, KMeansParams)>,
    /// This frame reuses the last frame's VPL clusters.
    vpl_reused: bool,
    /// The view and settings the shading-point clusters on the GPU were made from (the scene's BVH, the
    /// camera, the image size, the k-means settings): a frame of the same view (only lights moved, or the same
    /// frame again) reuses them, since they depend on the G-buffer alone.
    clustered_view: Option<ClusteredView>,
    /// This frame reuses the last frame's shading-point clusters.
    sp_reused: bool,
    /// This frame's shading-point k-means starts from the last view's centroids (`warm_iterations`).
    sp_warm: bool,
    /// Wall time of the last step's readback of the clusters (and the inspection's maps).
    readback_ms: f64,
    /// The kind of the last encoded step (its label when steps are timed on the CPU).
    last_step: &'static str,
    /// The camera of the last frame: the shading-point clusters are of its view.
    frame_camera: Option<crate::scene::Camera>,
}

/// The largest turn (degrees) and move (share of the scene's diagonal) of the camera between two frames for
/// which the second starts its k-means from the first's centroids (`warm_iterations`); measured up to 8 degrees
/// a frame on the conference room (docs/techniques/fuzzy.md), where a step of the orbit moves the eye by about
/// 7 % of the diagonal.
const WARM_MAX_TURN_DEGREES: f32 = 15.0;
const WARM_MAX_MOVE: f32 = 0.1;

/// Whether `to` is a step of a camera motion from `from`: turned and moved a little, the same field of view.
fn camera_step(from: &crate::scene::Camera, to: &crate::scene::Camera, scene_size: f32) -> bool {
    let turn = from.orientation.normalize().angle_between(to.orientation.normalize()).to_degrees();
    let moved = from.position.distance(to.position) / scene_size.max(1e-6);
    let same_fov = (from.fov_y - to.fov_y).abs() <= 0.01 * from.fov_y.abs();
    turn <= WARM_MAX_TURN_DEGREES && moved <= WARM_MAX_MOVE && same_fov
}

/// What a run of the shading-point clustering was made from: the scene's BVH, the camera, the image size and
/// the k-means settings.
type ClusteredView = (Arc<SceneBvh>, crate::scene::Camera, (u32, u32), KMeansParams);

impl FuzzyClustering {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts) -> FuzzyClustering {
        let device = &gpu.device;
        let points_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fuzzy shading points"),
            entries: &[storage_rw_entry(0)],
        });
        let points_pipeline =
            compute_pipeline(gpu, layouts, "fuzzy_points", POINTS.source, "sp_points_main", &[&points_layout]);
        let bvh_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fuzzy bvh"),
            entries: &crate::accel::scene_bvh::SceneBvh::layout_entries(),
        });
        let vis_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fuzzy visibility"),
            entries: &[uniform_entry(0), storage_entry(1), storage_rw_entry(2)],
        });
        let vis_module = crate::gpu::pipeline::create_module(device, "fuzzy_visibility", VISIBILITY.source);
        let vis_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("fuzzy visibility"),
            bind_group_layouts: &[Some(&vis_layout), Some(&bvh_layout)],
            immediate_size: 0,
        });
        let vis_pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("fuzzy visibility"),
            layout: Some(&vis_pipeline_layout),
            module: &vis_module,
            entry_point: Some("visibility_main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let shade_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fuzzy shading"),
            entries: &[uniform_entry(0), storage_entry(1), storage_entry(2)],
        });
        let shade_pass =
            VplGatherPass::with_entry(gpu, layouts, "fuzzy_shade", SHADE.source, "fuzzy_shade_main", &shade_layout);
        let ray_pass =
            VplGatherPass::new(gpu, layouts, "fuzzy vpl rays", shaders::VPL_GATHER_RAYTRACED.source, &bvh_layout);
        let uniform = |label, size| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        FuzzyClustering {
            params: FuzzyParams::default(),
            sp_kmeans: GpuKMeans::new(gpu, "shading points"),
            vpl_kmeans: GpuKMeans::new(gpu, "vpls"),
            points_pipeline,
            points_layout,
            sp_points: None,
            bvh_layout,
            bvh_group: None,
            bvh: None,
            vis_pipeline,
            vis_layout,
            vis_uniform: uniform("fuzzy visibility params", std::mem::size_of::<VisParamsUniform>() as u64),
            endpoints: None,
            bits: None,
            shade_pass,
            shade_layout,
            shade_uniform: uniform("fuzzy shading params", std::mem::size_of::<ShadeUniform>() as u64),
            ray_pass,
            vpls: Arc::default(),
            frame_camera: None,
            mode: ClusterMode::Both,
            light_count: 0,
            sp_count: 0,
            words_per_row: 0,
            rows_per_step: 1,
            vis_steps: 0,
            lights_per_step: 1,
            shade_steps: 0,
            scene_size: 1.0,
            inspection: Inspection::default(),
            counts: TechniqueCounts::default(),
            pending: (None, None),
            clustered_vpls: None,
            vpl_reused: false,
            clustered_view: None,
            sp_reused: false,
            sp_warm: false,
            readback_ms: 0.0,
            last_step: "fuzzy shading",
        }
    }

    fn kmeans_params(
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

    /// The buffer holding this frame's lights (`GpuVpl` layout): the VPL clusters or the VPLs.
    fn lights_buffer<'a>(&'a self, ctx: &'a FrameContext) -> &'a wgpu::Buffer {
        match self.mode {
            ClusterMode::ShadingPoints => &ctx.vpls.buffer.buffer,
            _ => self.vpl_kmeans.clusters.as_ref().expect("prepare clustered the VPLs"),
        }
    }

    /// The per-pixel maps of the read-back shading-point clusters: the nearest cluster's ID, and the F clusters'
    /// colours blended by the visibility mode's weights.
    /// Steps 2-4, the frame's first step: the shading points from the G-buffer, both clusterings.
    fn cluster_step(&mut self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) -> Result<(), GpuError> {
        let (vpl_kp, sp_kp) = self.pending;
        if let Some(kp) = vpl_kp.as_ref().filter(|_| !self.vpl_reused) {
            self.clustered_vpls = None;
            let max_flux = self.vpls.vpls.iter().map(|v| v.flux.max_element()).fold(0.0f32, f32::max);
            let vpls = &ctx.vpls.buffer.buffer;
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
            let (x, y) = crate::renderer::vpl_gather::pixel_workgroups(ctx.size);
            ctx.timer.compute_pass(encoder, "fuzzy shading points", |pass| {
                pass.set_pipeline(&self.points_pipeline);
                pass.set_bind_group(0, ctx.screen_bind_group, &[]);
                pass.set_bind_group(1, &group, &[]);
                pass.dispatch_workgroups(x, y, 1);
            });
            let points = self.sp_points.as_ref().expect("ensured");
            let run = KMeansParams { iterations: self.params.warm_iterations, ..*kp };
            let (kp_run, warm) = if self.sp_warm { (&run, true) } else { (kp, false) };
            self.sp_kmeans.encode(ctx.gpu, ctx.timer, encoder, points, kp_run, None, warm)?;
            self.clustered_view = self.bvh.clone().map(|bvh| (bvh, *ctx.camera, ctx.size, *kp));
        }
        Ok(())
    }

    /// The last step: the clusters read back for the counts (and, with `inspect`, the assignments for the
    /// overlays and the probe), after the frame's GPU work, so no step waits for the clustering.
    fn readback_step(&mut self, ctx: &FrameContext) -> Result<(), GpuError> {
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
                        ClusterMode::ShadingPoints => self
                            .vpls
                            .vpls
                            .iter()
                            .map(|v| GpuPoint {
                                position: v.position.extend(1.0).to_array(),
                                normal: v.normal.extend(1.0).to_array(),
                                flux: v.flux.extend(0.0).to_array(),
                            })
                            .collect(),
                        _ => self.inspection.vpl_clusters.clone(),
                    };
                    self.inspection.probe = self.probe_overlay(ctx, &lights);
                }
            }
        }
        self.readback_ms = start.elapsed().as_secs_f64() * 1000.0;
        Ok(())
    }
}

impl Technique for FuzzyClustering {
    fn key(&self) -> &'static str {
        "fuzzy"
    }

    fn label(&self) -> &'static str {
        "Fuzzy clustering of shading points and VPLs (Colom 2022)"
    }

    fn params(&self) -> Vec<Param> {
        self.params.describe()
    }

    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        check_param(self.key(), &self.params(), key, value)?;
        self.params.set(key, value);
        Ok(())
    }

    fn uses_vpls(&self) -> bool {
        true
    }

    fn probe_params(&self) -> Option<(&'static str, &'static str)> {
        Some(("probe_x", "probe_y"))
    }

    fn explain(&self) -> Vec<super::ExplainStep> {
        self.explain_steps()
    }

    fn overlay_legend(&self, layer: &OverlayLayer) -> Vec<super::LegendEntry> {
        self.legend_of(layer)
    }

    fn hover_points(&self) -> Vec<super::HoverPoint> {
        self.hover_list()
    }

    fn hover_details(&self, layer: &str, index: usize) -> Vec<String> {
        self.hover_text(layer, index)
    }

    fn overlays(&self, lights: &[PointLight]) -> Vec<OverlayLayer> {
        self.overlay_layers(lights)
    }

    fn update_overlays(&mut self, ctx: &crate::technique::OverlayContext) -> crate::technique::OverlayUpdate {
        self.follow(ctx)
    }

    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        self.vpls = ctx.vpls.set.clone();
        self.frame_camera = Some(*ctx.camera);
        self.scene_size = ctx.scene.bounds.size().length().max(1e-6);
        self.mode = self.params.cluster_mode();
        let (w, h) = ctx.size;
        let pixels = w as usize * h as usize;
        let n = self.vpls.vpls.len();
        let sp_clustered = self.mode != ClusterMode::Vpls;
        let vpl_clustered = self.mode != ClusterMode::ShadingPoints;
        self.counts = TechniqueCounts { lights_visible: ctx.lights.len(), ..Default::default() };
        self.counts.figures.insert("vpls".into(), n as f64);
        self.inspection = Inspection { size: ctx.size, ..Default::default() };
        self.vis_steps = 0;
        self.shade_steps = 0;
        if n == 0 || pixels == 0 {
            return Ok(0);
        }
        let (bvh, _) = ctx.scene.bvh(ctx.gpu);
        if self.bvh.as_ref().is_none_or(|b| !Arc::ptr_eq(b, &bvh)) || self.bvh_group.is_none() {
            self.bvh_group = Some(ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("fuzzy bvh"),
                layout: &self.bvh_layout,
                entries: &bvh.bind_entries(),
            }));
        }
        self.bvh = Some(bvh);

        // Steps 2-4 are the frame's first step ([`FuzzyClustering::cluster_step`]); their sizes are known now, so
        // the frame is planned without waiting for them (the clusters are read back in its last step).
        let vpl_kp =
            vpl_clustered.then(|| self.kmeans_params(ctx.scene.bounds, self.params.k_vpl as usize, n as u32, 1, 1, 1));
        let sp_kp = sp_clustered.then(|| {
            let f = (self.params.fuzziness as usize).clamp(1, MAX_F);
            self.kmeans_params(ctx.scene.bounds, self.params.sp_clusters(pixels), w, h, self.params.gamma, f)
        });
        let (reuse_vpls, reuse_view) = (self.params.reuse != "none", self.params.reuse == "all");
        self.vpl_reused = reuse_vpls
            && vpl_kp.as_ref().is_some_and(|kp| {
                self.clustered_vpls.as_ref().is_some_and(|(set, done)| Arc::ptr_eq(set, &self.vpls) && done == kp)
            });
        self.sp_reused = reuse_view
            && sp_kp.as_ref().is_some_and(|kp| {
                self.clustered_view.as_ref().is_some_and(|(bvh, camera, size, done)| {
                    self.bvh.as_ref().is_some_and(|b| Arc::ptr_eq(b, bvh))
                        && camera == ctx.camera
                        && *size == ctx.size
                        && done == kp
                })
            });
        // A view moved by a step (same scene, image size and settings; the camera turned and moved a little, as
        // from one frame of a camera motion to the next) starts its k-means from the last view's centroids. A
        // jump (a released drag across the room, another viewpoint) starts from the samples, so that the image
        // a user stops on is clustered as fully as a first frame.
        let scene_size = self.scene_size;
        self.sp_warm = !self.sp_reused
            && self.params.warm_iterations > 0
            && sp_kp.as_ref().is_some_and(|kp| {
                self.clustered_view.as_ref().is_some_and(|(bvh, camera, size, done)| {
                    self.bvh.as_ref().is_some_and(|b| Arc::ptr_eq(b, bvh))
                        && *size == ctx.size
                        && done == kp
                        && camera_step(camera, ctx.camera, scene_size)
                })
            });
        self.counts.figures.insert("sp clusters warm-started".into(), if self.sp_warm { 1.0 } else { 0.0 });
        self.counts.figures.insert("vpl clusters reused".into(), if self.vpl_reused { 1.0 } else { 0.0 });
        self.counts.figures.insert("sp clusters reused".into(), if self.sp_reused { 1.0 } else { 0.0 });
        if let Some(kp) = &vpl_kp {
            self.vpl_kmeans.shape = gpu::RunShape::of(kp);
        }
        if let Some(kp) = &sp_kp {
            self.sp_kmeans.shape = gpu::RunShape::of(kp);
        }
        self.pending = (vpl_kp, sp_kp);

        // The plan: visibility steps (rows of SP clusters), then shading steps (batches of lights).
        self.light_count = if vpl_clustered { self.vpl_kmeans.shape.clusters } else { n };
        self.lights_per_step = (self.params.lights_per_step as usize).min(ctx.max_lights_per_step).max(1);
        self.shade_steps = self.light_count.div_ceil(self.lights_per_step);
        self.counts.figures.insert("lights shaded".into(), self.light_count as f64);
        if sp_clustered {
            self.sp_count = self.sp_kmeans.shape.clusters;
            self.words_per_row = self.light_count.div_ceil(32).max(1);
            let bits_bytes = (self.sp_count * self.words_per_row * 4) as u64;
            let limit = ctx.gpu.device.limits().max_storage_buffer_binding_size;
            if bits_bytes > limit {
                return Err(GpuError::InvalidSettings(format!(
                    "fuzzy: K_sp = {} x {} lights need {} MiB of visibility bits, above the adapter's {} MiB per \
                     buffer (lower k_sp / k_sp_percent or k_vpl)",
                    self.sp_count,
                    self.light_count,
                    bits_bytes >> 20,
                    limit >> 20
                )));
            }
            gpu::ensure_storage(&mut self.bits, ctx.gpu, "fuzzy visibility bits", bits_bytes);
            gpu::ensure_storage(
                &mut self.endpoints,
                ctx.gpu,
                "fuzzy ray ends",
                ((self.sp_count + self.light_count) * 48) as u64,
            );
            let rays_per_row = self.words_per_row * 32;
            self.rows_per_step = ((self.params.rays_per_step as usize) / rays_per_row).max(1);
            self.vis_steps = self.sp_count.div_ceil(self.rows_per_step);
            if self.mode == ClusterMode::ShadingPoints {
                // The lights are the VPLs: upload them behind the representatives.
                let gpu_vpls: Vec<GpuVpl> = self.vpls.vpls.iter().map(GpuVpl::new).collect();
                let at = (self.sp_count * 48) as u64;
                ctx.gpu.queue.write_buffer(
                    self.endpoints.as_ref().expect("ensured"),
                    at,
                    bytemuck::cast_slice(&gpu_vpls),
                );
            }
        } else {
            self.counts.figures.insert("shadow rays (at most)".into(), (pixels * self.light_count) as f64);
        }
        self.counts.batches = self.shade_steps;
        // The clustering step, visibility and shading, and the readback.
        Ok(1 + self.vis_steps + self.shade_steps + 1)
    }

    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        if step == 0 {
            self.last_step = "fuzzy clustering";
            return self.cluster_step(ctx, encoder);
        }
        let step = step - 1;
        if step == self.vis_steps + self.shade_steps {
            self.last_step = "fuzzy readback";
            return self.readback_step(ctx);
        }
        self.last_step = if step < self.vis_steps { "fuzzy visibility" } else { "fuzzy shading" };
        if step < self.vis_steps {
            // Step 5: a block of SP clusters' rows of visibility bits.
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
            let words = rows * self.words_per_row;
            let g = words.div_ceil(64).max(1) as u32;
            let (x, y) = if g <= 65_535 { (g, 1) } else { (32_768, g.div_ceil(32_768)) };
            let bvh = self.bvh_group.as_ref().expect("prepare bound the BVH");
            ctx.timer.compute_pass(encoder, "fuzzy visibility", |pass| {
                pass.set_pipeline(&self.vis_pipeline);
                pass.set_bind_group(0, &group, &[]);
                pass.set_bind_group(1, bvh, &[]);
                pass.dispatch_workgroups(x, y, 1);
            });
            return Ok(());
        }
        // Step 6: a batch of lights.
        let batch_index = step - self.vis_steps;
        let first = batch_index * self.lights_per_step;
        let last = (first + self.lights_per_step).min(self.light_count);
        let mut batch =
            GatherBatchUniform { first_vpl: first as u32, vpl_count: (last - first) as u32, ..Default::default() };
        let lights = self.lights_buffer(ctx);
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

    fn step_label(&self) -> &'static str {
        self.last_step
    }

    fn counts(&self) -> TechniqueCounts {
        self.counts.clone()
    }

    fn cpu_times(&self) -> Vec<PassTime> {
        vec![PassTime { name: "fuzzy readback".into(), ms: self.readback_ms, count: 1 }]
    }
}
