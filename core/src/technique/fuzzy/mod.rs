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
//!    assigns every pixel to its `F` nearest clusters with inverse distances. Both clusterings: initial
//!    centroids from the data, a regular grid over the centroids rebuilt every iteration and a search from the
//!    27 cells around a point, fixed-point atomic sums (64-bit, 2^-24 of the scene's bounds), `dist` of
//!    equation 7 with `n_t`.
//! 5. Visibility: one shadow ray through the scene BVH from every SP representative to every light (VPL
//!    cluster or VPL): `K_sp x K_vpl` bits (`fuzzy/visibility.wgsl`).
//! 6. Shading (equation 6, `fuzzy/shade.wgsl`): every shading point sums the lights with its own BRDF and
//!    geometry term toward the light and the visibility `V~`: `hard` (its nearest cluster's), `fuzzy`
//!    (equation 8, the mean over its `F` clusters) or `weighted` (equations 9-10, inverse-distance weights).
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
//! - Both clusterings run every frame (the paper clusters VPLs once per static scene): lights move here.
//! - Ray ends are offset along their normals by `bias` times the camera distance, as `vpl-raytraced` does, so
//!   the two are comparable (with one cluster per VPL and per pixel the two images agree: tested).

pub mod gpu;
pub mod kmeans;

use std::sync::Arc;

use glam::Vec3;

use super::{
    check_param, index_color, FrameContext, Overlay, OverlayLayer, Param, ParamError, ParamKind, ParamValue, Technique,
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
use kmeans::{KMeansParams, ShadeMode, MAX_F};

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
const KMEANS: WgslModule = crate::wgsl!("fuzzy_kmeans", ["core/src/technique/fuzzy/kmeans.wgsl"]);

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

/// Which side is clustered (section 4's ablation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClusterMode {
    /// Shading points clustered, every VPL a light.
    ShadingPoints,
    /// VPLs clustered, every pixel its own rays.
    Vpls,
    Both,
}

#[derive(Clone, Debug, PartialEq)]
pub struct FuzzyParams {
    /// `K_sp`; 0: `k_sp_percent` of the pixels.
    pub k_sp: u32,
    pub k_sp_percent: f32,
    pub k_vpl: u32,
    /// `F`.
    pub fuzziness: u32,
    /// `gamma`.
    pub gamma: u32,
    pub iterations: u32,
    pub n_t: f32,
    /// `hard`, `fuzzy` or `weighted`.
    pub mode: String,
    /// `both`, `sp` or `vpl`.
    pub cluster: String,
    /// Ray offset along the normals, world units per metre of camera distance.
    pub ray_bias: f32,
    /// Read the clusters back every frame for the overlays (costs a readback of the per-pixel clusters).
    pub inspect: bool,
    /// The pixel whose clusters and visibility rays the probe overlay shows (-1: none).
    pub probe_x: i32,
    pub probe_y: i32,
    /// Shadow rays one visibility step traces at most.
    pub rays_per_step: u32,
    /// `exact` (the search grows until it holds the F nearest) or `paper` (the 27 cells around a point).
    pub search: String,
    /// Lights one shading step sums.
    pub lights_per_step: u32,
}

impl Default for FuzzyParams {
    fn default() -> Self {
        FuzzyParams {
            k_sp: 0,
            // The paper's sweet spot: "increasing the number of clusters to more than ~1 % of the total shading
            // points brings relatively small reductions in terms of MSE" (section 4.2).
            k_sp_percent: 1.0,
            k_vpl: 256,
            fuzziness: 6,
            gamma: 4,
            iterations: 8,
            n_t: 3f32.sqrt() / 2.0,
            mode: "weighted".into(),
            cluster: "both".into(),
            ray_bias: 0.001,
            inspect: true,
            probe_x: -1,
            probe_y: -1,
            rays_per_step: 1 << 22,
            search: "exact".into(),
            lights_per_step: super::MAX_LIGHT_WORK_PER_PASS as u32,
        }
    }
}

impl FuzzyParams {
    pub fn cluster_mode(&self) -> ClusterMode {
        match self.cluster.as_str() {
            "sp" => ClusterMode::ShadingPoints,
            "vpl" => ClusterMode::Vpls,
            _ => ClusterMode::Both,
        }
    }

    pub fn shade_mode(&self) -> ShadeMode {
        match self.mode.as_str() {
            "hard" => ShadeMode::Hard,
            "fuzzy" => ShadeMode::Fuzzy,
            _ => ShadeMode::Weighted,
        }
    }

    /// `K_sp` for an image of `pixels`.
    pub fn sp_clusters(&self, pixels: usize) -> usize {
        if self.k_sp > 0 {
            self.k_sp as usize
        } else {
            ((pixels as f64 * self.k_sp_percent as f64 / 100.0).round() as usize).max(1)
        }
    }
}

const MODE_CHOICES: &[&str] = &["weighted", "fuzzy", "hard"];
const CLUSTER_CHOICES: &[&str] = &["both", "sp", "vpl"];
const SEARCH_CHOICES: &[&str] = &["exact", "paper"];

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
    /// Wall time of the clusterings, from their submission to the clusters read back.
    readback_ms: f64,
    /// The kind of the last encoded step (its label when steps are timed on the CPU).
    last_step: &'static str,
}

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
            readback_ms: 0.0,
            last_step: "fuzzy shading",
        }
    }

    fn kmeans_params(
        &self,
        ctx: &FrameContext,
        clusters: usize,
        width: u32,
        height: u32,
        gamma: u32,
        f: usize,
    ) -> KMeansParams {
        let bounds = ctx.scene.bounds;
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
    fn build_pixel_maps(&mut self) {
        let ins = &mut self.inspection;
        let (w, h) = ins.size;
        let f = self.sp_kmeans.shape.fuzziness.max(1);
        let pixels = w as usize * h as usize;
        if ins.sp_assignment.is_empty() || ins.sp_assignment.len() != pixels * f {
            return;
        }
        ins.hard_map = Some(Arc::new(ins.sp_assignment.iter().step_by(f).copied().collect()));
        let mode = self.params.shade_mode();
        let blend: Vec<[u8; 4]> = (0..pixels)
            .map(|m| {
                let e = &ins.sp_assignment[m * f..m * f + f];
                if e[0] == u32::MAX {
                    return [0, 0, 0, 0];
                }
                let weights = kmeans::weights(mode, e, &ins.sp_inverse[m * f..m * f + f]);
                let mut c = [0.0f32; 3];
                for (&k, &wt) in e.iter().zip(&weights) {
                    if k != u32::MAX && wt > 0.0 {
                        let col = index_color(k as usize);
                        for i in 0..3 {
                            c[i] += wt * col[i];
                        }
                    }
                }
                [(c[0] * 255.0) as u8, (c[1] * 255.0) as u8, (c[2] * 255.0) as u8, 140]
            })
            .collect();
        ins.blend_map = Some(Arc::new(blend));
    }

    /// The probe overlay: the chosen pixel's F clusters (their representatives) and a shadow ray from each to
    /// every light (at most 4,096 lines), green when visible, red when blocked, traced on the CPU through the
    /// BVH with the same offsets as the GPU.
    fn probe_overlay(&self, ctx: &FrameContext, lights: &[GpuPoint]) -> Vec<Overlay> {
        let (w, h) = self.inspection.size;
        let (x, y) = (self.params.probe_x, self.params.probe_y);
        let f = self.sp_kmeans.shape.fuzziness;
        if x < 0 || y < 0 || x as u32 >= w || y as u32 >= h || self.inspection.sp_assignment.is_empty() {
            return Vec::new();
        }
        let Some(bvh) = &self.bvh else { return Vec::new() };
        let pixel = (y as usize) * w as usize + x as usize;
        let entries = &self.inspection.sp_assignment[pixel * f..pixel * f + f];
        let live: Vec<&GpuPoint> = lights.iter().filter(|l| l.exists()).collect();
        let used = entries.iter().take_while(|&&k| k != u32::MAX).count().max(1);
        let stride = (used * live.len()).div_ceil(4096).max(1);
        let mut out = Vec::new();
        for &k in entries.iter().take_while(|&&k| k != u32::MAX) {
            let Some(rep) = self.inspection.sp_clusters.get(k as usize).filter(|r| r.exists()) else { continue };
            out.push(Overlay::Point { position: rep.position(), color: index_color(k as usize), radius_px: 7.0 });
            let eps = self.params.ray_bias * (ctx.camera.position - rep.position()).length().max(1.0);
            let origin = rep.position() + rep.normal() * eps;
            for light in live.iter().step_by(stride) {
                let target = light.position() + light.normal() * eps;
                let to = target - origin;
                let d = to.length();
                let visible = d <= 2.0 * eps || bvh.closest_hit(origin, to / d, d - eps).is_none();
                let color = if visible { [0.2, 1.0, 0.3, 0.8] } else { [1.0, 0.2, 0.2, 0.8] };
                out.push(Overlay::Line { from: rep.position(), to: light.position(), color });
            }
        }
        out
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
        let p = &self.params;
        vec![
            Param {
                key: "cluster",
                label: "Clustered",
                help: "both: shading points and VPLs (the method); sp: shading points only, every VPL a light; \
                       vpl: VPLs only, every pixel traces its own rays (section 4's ablations)",
                kind: ParamKind::Choice(CLUSTER_CHOICES),
                value: ParamValue::Choice(p.cluster.clone()),
            },
            Param {
                key: "mode",
                label: "Visibility",
                help: "weighted: inverse-distance mean over the F nearest clusters (eq. 9-10); fuzzy: plain mean \
                       (eq. 8); hard: the nearest cluster's only",
                kind: ParamKind::Choice(MODE_CHOICES),
                value: ParamValue::Choice(p.mode.clone()),
            },
            Param {
                key: "k_sp",
                label: "K_sp (0: share)",
                help: "Shading-point clusters; 0 uses 'K_sp share' of the pixels",
                kind: ParamKind::Int { min: 0, max: gpu::MAX_CLUSTERS as i64 },
                value: ParamValue::Int(p.k_sp as i64),
            },
            Param {
                key: "k_sp_percent",
                label: "K_sp share (% of pixels)",
                help: "Shading-point clusters as a share of the pixels, when K_sp is 0 (the paper: 0.3 to 4 %)",
                kind: ParamKind::Float { min: 0.001, max: 100.0 },
                value: ParamValue::Float(p.k_sp_percent),
            },
            Param {
                key: "k_vpl",
                label: "K_vpl",
                help: "VPL clusters (clamped to the VPL count)",
                kind: ParamKind::Int { min: 1, max: gpu::MAX_CLUSTERS as i64 },
                value: ParamValue::Int(p.k_vpl as i64),
            },
            Param {
                key: "f",
                label: "F (clusters per point)",
                help: "The nearest shading-point clusters each pixel interpolates visibility from (paper: 6)",
                kind: ParamKind::Int { min: 1, max: MAX_F as i64 },
                value: ParamValue::Int(p.fuzziness as i64),
            },
            Param {
                key: "gamma",
                label: "gamma (downsampling)",
                help: "Every gamma-th column and row of the image takes part in the k-means iterations",
                kind: ParamKind::Int { min: 1, max: 64 },
                value: ParamValue::Int(p.gamma as i64),
            },
            Param {
                key: "iterations",
                label: "k-means iterations",
                help: "Assignment and update rounds of both clusterings",
                kind: ParamKind::Int { min: 0, max: 100 },
                value: ParamValue::Int(p.iterations as i64),
            },
            Param {
                key: "n_t",
                label: "n_t (normal threshold)",
                help: "Points whose normals' cosine is at most n_t never share a cluster (eq. 7; paper: sqrt(3)/2)",
                kind: ParamKind::Float { min: -1.0, max: 1.0 },
                value: ParamValue::Float(p.n_t),
            },
            Param {
                key: "search",
                label: "Cluster search",
                help: "exact: the grid search grows until it holds the F nearest clusters; paper: the 27 cells \
                       around a point only (faster; a far cluster can be missed)",
                kind: ParamKind::Choice(SEARCH_CHOICES),
                value: ParamValue::Choice(p.search.clone()),
            },
            Param {
                key: "bias",
                label: "Ray offset",
                help: "Ray ends offset along their normals, world units per metre of camera distance",
                kind: ParamKind::Float { min: 0.0, max: 0.1 },
                value: ParamValue::Float(p.ray_bias),
            },
            Param {
                key: "inspect",
                label: "Read clusters back",
                help: "Read the per-pixel clusters back every frame for the overlays (off for timing)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(p.inspect),
            },
            Param {
                key: "probe_x",
                label: "Probe pixel x",
                help: "The pixel whose F clusters and visibility rays the probe overlay shows (-1: none; in the app, \
                       Alt+click a pixel)",
                kind: ParamKind::Int { min: -1, max: 16_384 },
                value: ParamValue::Int(p.probe_x as i64),
            },
            Param {
                key: "probe_y",
                label: "Probe pixel y",
                help: "The probe's row (-1: none)",
                kind: ParamKind::Int { min: -1, max: 16_384 },
                value: ParamValue::Int(p.probe_y as i64),
            },
            Param {
                key: "rays_per_step",
                label: "Rays per step",
                help: "Shadow rays one visibility step traces at most (the image does not change)",
                kind: ParamKind::Int { min: 1024, max: 1 << 28 },
                value: ParamValue::Int(p.rays_per_step as i64),
            },
            Param {
                key: "lights_per_step",
                label: "Lights per step",
                help: "Lights one shading step sums (the image does not change)",
                kind: ParamKind::Int { min: 1, max: crate::vpl::MAX_VPLS as i64 },
                value: ParamValue::Int(p.lights_per_step as i64),
            },
        ]
    }

    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        check_param(self.key(), &self.params(), key, value)?;
        let p = &mut self.params;
        match (key, value) {
            ("cluster", ParamValue::Choice(v)) => p.cluster = v.clone(),
            ("mode", ParamValue::Choice(v)) => p.mode = v.clone(),
            ("k_sp", ParamValue::Int(v)) => p.k_sp = *v as u32,
            ("k_sp_percent", ParamValue::Float(v)) => p.k_sp_percent = *v,
            ("k_vpl", ParamValue::Int(v)) => p.k_vpl = *v as u32,
            ("f", ParamValue::Int(v)) => p.fuzziness = *v as u32,
            ("gamma", ParamValue::Int(v)) => p.gamma = *v as u32,
            ("iterations", ParamValue::Int(v)) => p.iterations = *v as u32,
            ("n_t", ParamValue::Float(v)) => p.n_t = *v,
            ("bias", ParamValue::Float(v)) => p.ray_bias = *v,
            ("search", ParamValue::Choice(v)) => p.search = v.clone(),
            ("inspect", ParamValue::Bool(v)) => p.inspect = *v,
            ("probe_x", ParamValue::Int(v)) => p.probe_x = *v as i32,
            ("probe_y", ParamValue::Int(v)) => p.probe_y = *v as i32,
            ("rays_per_step", ParamValue::Int(v)) => p.rays_per_step = *v as u32,
            ("lights_per_step", ParamValue::Int(v)) => p.lights_per_step = *v as u32,
            _ => unreachable!("check_param accepted an unknown key"),
        }
        Ok(())
    }

    fn uses_vpls(&self) -> bool {
        true
    }

    fn probe_params(&self) -> Option<(&'static str, &'static str)> {
        Some(("probe_x", "probe_y"))
    }

    fn explain(&self) -> Vec<super::ExplainStep> {
        use super::ExplainStep;
        vec![
            ExplainStep {
                title: "1. VPLs",
                text:
                    "Particles traced from the lights leave virtual point lights where they land (the shared VPL set).",
                layers: &["vpls (flux)", "vpls (flux, every n-th)"],
                shows_shadow_maps: false,
                ..Default::default()
            },
            ExplainStep {
                title: "2. VPL clusters",
                text: "K_vpl clusters by k-means over position and normal (equation 7: no two normals more than 30 \
                       degrees apart); each becomes one light at its representative with its members' flux.",
                layers: &["vpls by cluster", "vpls by cluster (every n-th)", "vpl cluster representatives"],
                shows_shadow_maps: false,
                ..Default::default()
            },
            ExplainStep {
                title: "3-4. Shading-point clusters",
                text: "The pixels' positions and normals clustered the same way (every gamma-th pixel in the \
                       iterations), then every pixel assigned to its F nearest clusters.",
                layers: &["shading-point clusters", "shading-point centroids"],
                shows_shadow_maps: false,
                ..Default::default()
            },
            ExplainStep {
                title: "5. Visibility between representatives",
                text: "One shadow ray from each shading-point cluster's representative to each light: K_sp x K_vpl \
                       rays instead of one per pixel and VPL. Alt+click a pixel to see its clusters' rays (green \
                       visible, red blocked).",
                layers: &[
                    "probe: clusters and visibility rays (green visible, red blocked)",
                    "vpl cluster representatives",
                ],
                shows_shadow_maps: false,
                ..Default::default()
            },
            ExplainStep {
                title: "6. Weighted visibility",
                text: "Each pixel shades every light with its own BRDF and geometry term and the visibility of its F \
                       clusters, weighted by inverse distance (weighted), equally (fuzzy) or its nearest only (hard).",
                layers: &["shading-point clusters (blended as the visibility mode weighs them)"],
                shows_shadow_maps: false,
                ..Default::default()
            },
        ]
    }

    fn overlay_legend(&self, layer: &OverlayLayer) -> Vec<super::LegendEntry> {
        use super::{Glyph, LegendEntry};
        let palette = index_color(0);
        let mut legend = match layer.name {
            "vpls by cluster" | "vpls by cluster (every n-th)" => {
                vec![LegendEntry::new(Glyph::Palette, palette, "a VPL, in its cluster's colour")]
            }
            "vpl cluster representatives" => vec![LegendEntry::new(
                Glyph::Palette,
                palette,
                "a VPL cluster's representative: the light it becomes (members' flux, mean normal)",
            )],
            "shading-point clusters" => {
                vec![LegendEntry::new(
                    Glyph::Pixels,
                    palette,
                    "each pixel in its nearest shading-point cluster's colour",
                )]
            }
            "shading-point clusters (blended as the visibility mode weighs them)" => vec![LegendEntry::new(
                Glyph::Pixels,
                palette,
                "each pixel: its F clusters' colours blended by the visibility weights",
            )],
            "shading-point centroids" => {
                vec![LegendEntry::new(Glyph::Palette, palette, "a shading-point cluster's centroid")]
            }
            "probe: clusters and visibility rays (green visible, red blocked)" => vec![
                LegendEntry::new(Glyph::Dot, palette, "the probed pixel's F clusters' representatives"),
                LegendEntry::new(Glyph::Line, [0.2, 1.0, 0.3, 0.8], "a shadow ray that reaches its light"),
                LegendEntry::new(Glyph::Line, [1.0, 0.2, 0.2, 0.8], "a shadow ray that is blocked"),
            ],
            _ => crate::renderer::vpl_gather::vpl_layer_legend(layer)
                .or_else(|| super::light_layer_legend(layer))
                .unwrap_or_default(),
        };
        legend.extend(layer.summary());
        legend
    }

    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        self.vpls = ctx.vpls.set.clone();
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

        // Steps 2-4: both clusterings in one submission.
        let mut encoder = ctx.gpu.device.create_command_encoder(&Default::default());
        if vpl_clustered {
            let kp = self.kmeans_params(ctx, self.params.k_vpl as usize, n as u32, 1, 1, 1);
            let max_flux = self.vpls.vpls.iter().map(|v| v.flux.max_element()).fold(0.0f32, f32::max);
            self.vpl_kmeans.encode(ctx.gpu, ctx.timer, &mut encoder, &ctx.vpls.buffer.buffer, &kp, Some(max_flux))?;
        }
        if sp_clustered {
            let f = (self.params.fuzziness as usize).clamp(1, MAX_F);
            gpu::ensure_storage(&mut self.sp_points, ctx.gpu, "fuzzy shading points", pixels as u64 * 48);
            let points = self.sp_points.as_ref().expect("ensured");
            let group = ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("fuzzy shading points"),
                layout: &self.points_layout,
                entries: &[wgpu::BindGroupEntry { binding: 0, resource: points.as_entire_binding() }],
            });
            let (x, y) = crate::renderer::vpl_gather::pixel_workgroups(ctx.size);
            ctx.timer.compute_pass(&mut encoder, "fuzzy shading points", |pass| {
                pass.set_pipeline(&self.points_pipeline);
                pass.set_bind_group(0, ctx.screen_bind_group, &[]);
                pass.set_bind_group(1, &group, &[]);
                pass.dispatch_workgroups(x, y, 1);
            });
            let kp = self.kmeans_params(ctx, self.params.sp_clusters(pixels), w, h, self.params.gamma, f);
            let points = self.sp_points.as_ref().expect("ensured");
            self.sp_kmeans.encode(ctx.gpu, ctx.timer, &mut encoder, points, &kp, None)?;
        }
        // Timed from the submission to the clusters read back: the clustering's GPU work and the readback (the
        // GPU timestamps of lavapipe are unreliable; this wall time is not). The work submitted before (the
        // G-buffer, the direct technique's steps) is waited for first, so it is not counted here; the readback
        // below waits for the queue anyway.
        ctx.gpu.wait_idle()?;
        let start = std::time::Instant::now();
        ctx.gpu.queue.submit([encoder.finish()]);

        // Read back what the counts and overlays need.
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
        self.readback_ms = start.elapsed().as_secs_f64() * 1000.0;
        let live = |c: &[GpuPoint]| c.iter().filter(|p| p.exists()).count();

        // The plan: visibility steps (rows of SP clusters), then shading steps (batches of lights).
        self.light_count = if vpl_clustered { self.vpl_kmeans.shape.clusters } else { n };
        self.lights_per_step = (self.params.lights_per_step as usize).min(ctx.max_lights_per_step).max(1);
        self.shade_steps = self.light_count.div_ceil(self.lights_per_step);
        self.counts.figures.insert("lights shaded".into(), self.light_count as f64);
        if vpl_clustered {
            self.counts.figures.insert("k_vpl".into(), live(&self.inspection.vpl_clusters) as f64);
        }
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
            let sp_live = live(&self.inspection.sp_clusters);
            let members: u32 = self.inspection.sp_clusters.iter().map(|c| c.members()).sum();
            self.counts.figures.insert("shading points".into(), members as f64);
            self.counts.figures.insert("k_sp".into(), sp_live as f64);
            self.counts.figures.insert("shadow rays".into(), (sp_live * self.light_count) as f64);
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
        if inspect && sp_clustered {
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
        Ok(self.vis_steps + self.shade_steps)
    }

    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
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
        vec![PassTime { name: "fuzzy clustering + readback".into(), ms: self.readback_ms, count: 1 }]
    }

    fn hover_points(&self) -> Vec<super::HoverPoint> {
        let ins = &self.inspection;
        let clusters = |layer: &'static str, points: &[GpuPoint]| -> Vec<super::HoverPoint> {
            let live = points.iter().enumerate().filter(|(_, c)| c.exists());
            live.map(|(index, c)| super::HoverPoint { layer, position: c.position(), index }).collect()
        };
        let mut points = clusters("vpl cluster representatives", &ins.vpl_clusters);
        points.extend(clusters("shading-point centroids", &ins.sp_centroids));
        // The VPLs of the "vpls by cluster" layer (every n-th past 4,096, as it draws them), then the shared layers'.
        let vpls = &self.vpls.vpls;
        let stride = vpls.len().div_ceil(4096).max(1);
        let layer = if stride > 1 { "vpls by cluster (every n-th)" } else { "vpls by cluster" };
        let assigned =
            vpls.iter().zip(&ins.vpl_assignment).enumerate().step_by(stride).filter(|(_, (_, &k))| k != u32::MAX);
        points.extend(assigned.map(|(index, (v, _))| super::HoverPoint { layer, position: v.position, index }));
        points.extend(crate::renderer::vpl_gather::vpl_hover_points(&self.vpls));
        points
    }

    fn hover_details(&self, layer: &str, index: usize) -> Vec<String> {
        let ins = &self.inspection;
        let cluster = |what: &str, points: &[GpuPoint]| -> Vec<String> {
            let Some(c) = points.get(index).filter(|c| c.exists()) else { return Vec::new() };
            let live = points.iter().filter(|c| c.exists()).count();
            let n = c.normal();
            vec![
                format!("{what} {index} ({live} with members)"),
                format!("{} members", c.members()),
                format!("normal ({:.2}, {:.2}, {:.2})", n.x, n.y, n.z),
            ]
        };
        match layer {
            "vpl cluster representatives" => cluster("VPL cluster", &ins.vpl_clusters),
            "shading-point centroids" => cluster("shading-point cluster", &ins.sp_centroids),
            // A pixel's cluster in the per-pixel map: the cluster's representative.
            "shading-point clusters" => cluster("shading-point cluster", &ins.sp_clusters),
            l if l.starts_with("vpls by cluster") || crate::renderer::vpl_gather::is_vpl_layer(&self.vpls, l) => {
                let mut lines = crate::renderer::vpl_gather::vpl_details(&self.vpls, index);
                if let Some(k) = ins.vpl_assignment.get(index).filter(|k| **k != u32::MAX) {
                    lines.push(format!("in VPL cluster {k}"));
                }
                lines
            }
            _ => Vec::new(),
        }
    }

    fn overlays(&self, _lights: &[PointLight]) -> Vec<OverlayLayer> {
        let ins = &self.inspection;
        let half = self.scene_size * 0.004;
        let vpls = &self.vpls.vpls;
        let stride = vpls.len().div_ceil(4096).max(1);
        let mut layers = Vec::new();
        if !ins.vpl_assignment.is_empty() {
            layers.push(OverlayLayer {
                name: if stride > 1 { "vpls by cluster (every n-th)" } else { "vpls by cluster" },
                visible_by_default: true,
                primitives: vpls
                    .iter()
                    .zip(&ins.vpl_assignment)
                    .step_by(stride)
                    .filter(|(_, &k)| k != u32::MAX)
                    .map(|(v, &k)| {
                        let (t, b) = v.normal.any_orthonormal_pair();
                        Overlay::Rect {
                            center: v.position,
                            half_u: t * half,
                            half_v: b * half,
                            color: index_color(k as usize),
                        }
                    })
                    .collect(),
            });
        }
        if !ins.vpl_clusters.is_empty() {
            layers.push(OverlayLayer {
                name: "vpl cluster representatives",
                visible_by_default: true,
                primitives: ins
                    .vpl_clusters
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| c.exists())
                    .map(|(k, c)| Overlay::Point { position: c.position(), color: index_color(k), radius_px: 5.0 })
                    .collect(),
            });
        }
        let (w, h) = ins.size;
        if let Some(ids) = &ins.hard_map {
            layers.push(OverlayLayer {
                name: "shading-point clusters",
                visible_by_default: false,
                primitives: vec![Overlay::IdMap { width: w, height: h, ids: ids.clone(), alpha: 0.5 }],
            });
        }
        if let Some(rgba) = &ins.blend_map {
            layers.push(OverlayLayer {
                name: "shading-point clusters (blended as the visibility mode weighs them)",
                visible_by_default: false,
                primitives: vec![Overlay::ColorMap { width: w, height: h, rgba: rgba.clone() }],
            });
        }
        if !ins.sp_centroids.is_empty() {
            layers.push(OverlayLayer {
                name: "shading-point centroids",
                visible_by_default: false,
                primitives: ins
                    .sp_centroids
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| c.exists())
                    .map(|(k, c)| Overlay::Point { position: c.position(), color: index_color(k), radius_px: 3.0 })
                    .collect(),
            });
        }
        layers.push(OverlayLayer {
            name: "probe: clusters and visibility rays (green visible, red blocked)",
            visible_by_default: true,
            primitives: ins.probe.clone(),
        });
        layers.extend(vpl_overlays(&self.vpls, self.scene_size, 0).into_iter().map(|mut l| {
            l.visible_by_default = false;
            l
        }));
        layers
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn k_sp_share_and_modes() {
        let p = FuzzyParams::default();
        assert_eq!(p.sp_clusters(100_000), 1000);
        assert_eq!(FuzzyParams { k_sp: 77, ..p.clone() }.sp_clusters(100_000), 77);
        assert_eq!(FuzzyParams { k_sp_percent: 0.001, ..p.clone() }.sp_clusters(10), 1);
        assert_eq!(p.shade_mode(), ShadeMode::Weighted);
        assert_eq!(p.cluster_mode(), ClusterMode::Both);
    }
}
