//! Fuzzy clustering's parameters (Colom 2022's `k_sp`, `k_vpl`, `f`, `gamma`, `n_t` and the section 4 ablations),
//! described for the UI and the CLI and set in one place.

use super::kmeans::{ShadeMode, MAX_F};
use crate::technique::params::{Param, ParamKind, ParamValue};

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
    /// Iterations of the shading points' k-means when it starts from the last view's centroids (same scene,
    /// image size and settings, the camera moved by a step, not a jump): the paper's section 6 proposal. 0:
    /// every view starts from Algorithm 1's initial samples.
    pub warm_iterations: u32,
    pub n_t: f32,
    /// `hard`, `fuzzy` or `weighted`.
    pub mode: String,
    /// `both`, `sp` or `vpl`.
    pub cluster: String,
    /// Ray offset along the normals, world units per metre of camera distance.
    pub ray_bias: f32,
    /// Read the clusters back every frame for the overlays (costs a readback of the per-pixel clusters).
    pub inspect: bool,
    /// Which of the last frame's clusters a frame reuses when their inputs did not change: `all` (the VPL
    /// clusters of the same VPL set and the shading-point clusters of the same view), `vpls` (the VPL clusters
    /// only: the view is clustered every frame, as when the camera moves) or `none` (both every frame).
    pub reuse: String,
    /// The pixel whose clusters and visibility rays the probe overlay shows (-1: none).
    pub probe_x: i32,
    pub probe_y: i32,
    /// Shadow rays one visibility step traces at most.
    pub rays_per_step: u32,
    /// `exact` (the search grows until it holds the F nearest) or `paper` (the 27 cells around a point).
    pub search: String,
    /// Algorithm 2 for the pixels between samples: `neighbours` (the F nearest among the four neighbouring
    /// samples' clusters, a grid search where fewer than F match) or `search` (every pixel searches the grid).
    pub assign: String,
    /// Lights one shading step sums.
    pub lights_per_step: u32,
    /// Time each clustering dispatch in a pass of its own (profiling) instead of one pass per stage.
    pub time_dispatches: bool,
    /// A real GPU's schedule: the grid shells a search walks before a workgroup finishes it (speed only).
    pub near_shells: u32,
    /// A real GPU's schedule: the cells and centroids a search visits alone (0: no bound; speed only).
    pub near_budget: u32,
    /// The grid's finer levels (0: none) and the crowd of a point's cell above which its searches use the next
    /// one (speed only).
    pub fine_levels: u32,
    pub fine_above: u32,
    /// The clustering's schedule: `auto` (from the adapter: a real GPU's or a CPU rasterizer's), `gpu` or `cpu`
    /// (speed only).
    pub schedule: String,
    /// Count the searches' work (cells, centroids, queued points per kernel) into the counts (slower).
    pub count_searches: bool,
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
            warm_iterations: 2,
            n_t: 3f32.sqrt() / 2.0,
            mode: "weighted".into(),
            cluster: "both".into(),
            ray_bias: 0.001,
            inspect: true,
            reuse: "all".into(),
            probe_x: -1,
            probe_y: -1,
            rays_per_step: 1 << 22,
            search: "exact".into(),
            time_dispatches: false,
            near_shells: super::gpu::NEAR_SHELLS,
            near_budget: super::gpu::NEAR_BUDGET,
            fine_levels: super::gpu::FINE_LEVELS,
            fine_above: super::gpu::FINE_ABOVE,
            schedule: "auto".into(),
            count_searches: false,
            assign: "neighbours".into(),
            lights_per_step: crate::technique::MAX_LIGHT_WORK_PER_PASS as u32,
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
const ASSIGN_CHOICES: &[&str] = &["neighbours", "search"];
const SCHEDULE_CHOICES: &[&str] = &["auto", "gpu", "cpu"];

/// The parameters that change how the clustering and the frame's steps are scheduled, timed or counted, never the
/// image (`Technique::tuning_params`; core/tests/fuzzy.rs renders the same image with each changed).
pub const TUNING: &[&str] = &[
    "rays_per_step",
    "lights_per_step",
    "schedule",
    "near_shells",
    "near_budget",
    "fine_levels",
    "fine_above",
    "time_dispatches",
    "count_searches",
];
const REUSE_CHOICES: &[&str] = &["all", "vpls", "none"];

impl FuzzyParams {
    /// The parameters as the UI and the CLI list them.
    pub fn describe(&self) -> Vec<Param> {
        let p = self;
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
                kind: ParamKind::Int { min: 0, max: super::gpu::MAX_CLUSTERS as i64 },
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
                kind: ParamKind::Int { min: 1, max: super::gpu::MAX_CLUSTERS as i64 },
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
                key: "warm_iterations",
                label: "Iterations after a camera move",
                help: "Shading-point k-means iterations when a view moved by a step (turned at most 15 degrees, \
                       moved at most a tenth of the scene) starts from the last view's centroids (a centroid left \
                       without members starts again from its initial sample; the paper's proposed future work); \
                       a jump, or 0 here: Algorithm 1 from the initial samples",
                kind: ParamKind::Int { min: 0, max: 100 },
                value: ParamValue::Int(p.warm_iterations as i64),
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
                key: "assign",
                label: "Pixels between samples",
                help: "neighbours: a pixel off the gamma grid takes its F nearest among the clusters of the four \
                       samples around it (a grid search where fewer than F match its normal; the samples search \
                       the grid); search: every pixel searches the grid, as the paper does (slower on a software \
                       rasterizer, no faster on an NVIDIA H200: docs/techniques/fuzzy.md)",
                kind: ParamKind::Choice(ASSIGN_CHOICES),
                value: ParamValue::Choice(p.assign.clone()),
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
                key: "reuse",
                label: "Reuse unchanged clusters",
                help: "all: keep the last frame's VPL clusters while the VPLs stay and its shading-point clusters \
                       while the view stays (as when only a light moves); vpls: the VPL clusters only (the view is \
                       clustered every frame, as when the camera moves); none: both every frame (for timing)",
                kind: ParamKind::Choice(REUSE_CHOICES),
                value: ParamValue::Choice(p.reuse.clone()),
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
            Param {
                key: "time_dispatches",
                label: "Time each clustering dispatch",
                help: "Time every dispatch of the clustering as a pass of its own (`fuzzy clustering (...): \
                       <stage>: <kernel>`) instead of one pass per stage: where the clustering's time goes, at the \
                       cost of a timestamp pair per dispatch (the image does not change)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(p.time_dispatches),
            },
            Param {
                key: "near_shells",
                label: "Shells before a workgroup search",
                help: "On a GPU (not a software rasterizer): the grid shells around a point that its search walks \
                       alone; a search they leave unfinished goes to a workgroup of its own whose 64 invocations \
                       scan the compatible centroids together. Speed only: the clusters do not change",
                kind: ParamKind::Int { min: 0, max: 16 },
                value: ParamValue::Int(p.near_shells as i64),
            },
            Param {
                key: "near_budget",
                label: "Steps before a workgroup search",
                help: "On a GPU (not a software rasterizer): the grid cells and centroids a point's search visits \
                       alone before a workgroup finishes it (0: the shells alone bound it). Speed only: the \
                       clusters do not change",
                kind: ParamKind::Int { min: 0, max: 1 << 20 },
                value: ParamValue::Int(p.near_budget as i64),
            },
            Param {
                key: "fine_levels",
                label: "Finer grid levels",
                help: "Levels of the cluster grid finer than its cells (each 4 x 4 x 4 cells per cell of the one \
                       before, hashed): near the camera the clusters are small and a cell holds hundreds of them; \
                       0: the cells alone. Speed only: the clusters do not change",
                kind: ParamKind::Int { min: 0, max: 3 },
                value: ParamValue::Int(p.fine_levels as i64),
            },
            Param {
                key: "fine_above",
                label: "Finer level above",
                help: "The centroids a point's grid cell may hold before its cluster searches use the next finer \
                       level. Speed only: the clusters do not change",
                kind: ParamKind::Int { min: 0, max: 65_536 },
                value: ParamValue::Int(p.fine_above as i64),
            },
            Param {
                key: "schedule",
                label: "Clustering schedule",
                help: "auto: from the adapter; gpu: a real GPU's (two grid shells per point, then a workgroup per \
                       unfinished search, finer grid levels, the grid's scan over many workgroups); cpu: a software \
                       rasterizer's (each search by one invocation). Speed only: the clusters do not change",
                kind: ParamKind::Choice(SCHEDULE_CHOICES),
                value: ParamValue::Choice(p.schedule.clone()),
            },
            Param {
                key: "count_searches",
                label: "Count the searches' work",
                help: "Count the grid cells visited, the centroids considered and the points queued by each kernel \
                       of the shading points' clustering, in the counts (`sp <kernel>: ...`; atomics: slower, the \
                       same clusters)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(p.count_searches),
            },
        ]
    }

    /// Set one parameter [`check_param`](crate::technique::check_param) accepted.
    pub fn set(&mut self, key: &str, value: &ParamValue) {
        let p = self;
        match (key, value) {
            ("cluster", ParamValue::Choice(v)) => p.cluster = v.clone(),
            ("mode", ParamValue::Choice(v)) => p.mode = v.clone(),
            ("k_sp", ParamValue::Int(v)) => p.k_sp = *v as u32,
            ("k_sp_percent", ParamValue::Float(v)) => p.k_sp_percent = *v,
            ("k_vpl", ParamValue::Int(v)) => p.k_vpl = *v as u32,
            ("f", ParamValue::Int(v)) => p.fuzziness = *v as u32,
            ("gamma", ParamValue::Int(v)) => p.gamma = *v as u32,
            ("iterations", ParamValue::Int(v)) => p.iterations = *v as u32,
            ("warm_iterations", ParamValue::Int(v)) => p.warm_iterations = *v as u32,
            ("n_t", ParamValue::Float(v)) => p.n_t = *v,
            ("bias", ParamValue::Float(v)) => p.ray_bias = *v,
            ("search", ParamValue::Choice(v)) => p.search = v.clone(),
            ("assign", ParamValue::Choice(v)) => p.assign = v.clone(),
            ("inspect", ParamValue::Bool(v)) => p.inspect = *v,
            ("reuse", ParamValue::Choice(v)) => p.reuse = v.clone(),
            ("probe_x", ParamValue::Int(v)) => p.probe_x = *v as i32,
            ("probe_y", ParamValue::Int(v)) => p.probe_y = *v as i32,
            ("rays_per_step", ParamValue::Int(v)) => p.rays_per_step = *v as u32,
            ("lights_per_step", ParamValue::Int(v)) => p.lights_per_step = *v as u32,
            ("time_dispatches", ParamValue::Bool(v)) => p.time_dispatches = *v,
            ("near_shells", ParamValue::Int(v)) => p.near_shells = *v as u32,
            ("near_budget", ParamValue::Int(v)) => p.near_budget = *v as u32,
            ("fine_levels", ParamValue::Int(v)) => p.fine_levels = *v as u32,
            ("fine_above", ParamValue::Int(v)) => p.fine_above = *v as u32,
            ("schedule", ParamValue::Choice(v)) => p.schedule = v.clone(),
            ("count_searches", ParamValue::Bool(v)) => p.count_searches = *v,
            _ => unreachable!("check_param accepted an unknown key"),
        }
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
