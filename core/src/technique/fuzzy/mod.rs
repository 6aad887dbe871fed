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
mod passes;
mod preview;

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
use crate::scene::PointLight;
use crate::services::layouts::compute_pipeline;
use crate::services::layouts::SharedLayouts;
use crate::services::vpl_gather::{vpl_overlays, GatherBatchUniform, VplGatherPass};
use crate::shaders;
use crate::timing::PassTime;
use crate::vpl::{GpuVpl, VplSet};
use gpu::{GpuKMeans, GpuPoint};
use kmeans::{KMeansParams, MAX_F};
pub use params::{ClusterMode, FuzzyParams};

use crate::shaders::WgslModule;
/// This technique's own WGSL modules; its registry entry lists them and the naga test validates them.
pub const SHADERS: &[WgslModule] = &[POINTS, VISIBILITY, SHADE, gpu::KMEANS];
const POINTS: WgslModule =
    crate::shaders::wgsl!("fuzzy_points", ["shaders/common.wgsl", "core/src/technique/fuzzy/points.wgsl"]);
const VISIBILITY: WgslModule = crate::shaders::wgsl!(
    "fuzzy_visibility",
    ["shaders/raytrace_bvh.wgsl", "core/src/technique/fuzzy/visibility.wgsl"]
);
const SHADE: WgslModule = crate::shaders::wgsl!(
    "fuzzy_shade",
    ["shaders/common.wgsl", "shaders/vpl_common.wgsl", "core/src/technique/fuzzy/shade.wgsl"]
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
    /// Their size: the frame's, or the preview's grid while the camera moves ([`preview`]).
    map_size: (u32, u32),
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
    /// The camera and VPL set (held) the preview last clustered the shading points for ([`preview`]).
    followed_view: Option<(crate::scene::Camera, Arc<VplSet>)>,
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
            followed_view: None,
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

    fn tuning_params(&self) -> &'static [&'static str] {
        params::TUNING
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
        self.followed_view = None;
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
            return self.visibility_step(ctx, step, encoder);
        }
        self.shading_step(ctx, step - self.vis_steps, encoder)
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
