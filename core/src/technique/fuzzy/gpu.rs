//! Algorithms 1 and 2 on the GPU (`fuzzy/kmeans.wgsl`), the twin of [`super::kmeans::cluster`]: one dispatch
//! per step over a buffer of points in the `GpuVpl` layout (the frame's VPLs as they are, or the shading points
//! written from the G-buffer by `fuzzy/points.wgsl`). Its outputs stay on the GPU for the visibility and
//! shading passes: `clusters` (the first `K` entries: each cluster as a light / ray endpoint, its
//! representative's position, normal and the members' flux) and `assignment` (per point, `F` clusters with
//! inverse distances). [`GpuKMeans::read_clusters`] and [`GpuKMeans::read_assignment`] read them back for the
//! counts and overlays.
//!
//! Things only the GPU does, for speed, without changing what is found (the tests compare each with the twin):
//! with neighbour lists, the four samples' lists are merged once per block of pixels between them
//! (`km_blocks`) instead of by each of the block's points; an exact search whose compatible centroids are few
//! scans them whole from an octahedral map of the centroids' normals (`find` in the shader) instead of walking
//! the grid shell by shell until `F` are found, which for a point on a crease or a narrow face can visit every
//! cell; and long searches are queued for a dispatch of their own, so that the points beside them do not wait.
//! That last one has two schedules (`GPU_SCHEDULE`): a CPU rasterizer's queues `km_fill`'s points short of `F`
//! compatible clusters for `km_search`, one invocation each; a real GPU's walks the first `near_shells` shells
//! of every search and queues the unfinished ones for `km_assign_wide` / `km_search_wide`, a workgroup of 64
//! each scanning the compatible buckets together, searches finer hashed grid levels where a cell is crowded,
//! and spreads the grid's prefix sum over the GPU (docs/techniques/fuzzy.md, nineteenth session).

use glam::Vec3;

use super::kmeans::{grid_shape, KMeansParams, MAX_F};
use crate::error::GpuError;
use crate::gpu::kernels::Kernels;
use crate::gpu::GpuContext;
use crate::timing::PassTimer;

/// Its WGSL module (listed by the technique's `SHADERS`).
pub const KMEANS: crate::shaders::WgslModule = crate::shaders::wgsl!(
    "fuzzy_kmeans",
    [
        "core/src/technique/fuzzy/kmeans.wgsl",
        "core/src/technique/fuzzy/kmeans_grid.wgsl",
        "core/src/technique/fuzzy/kmeans_search.wgsl",
        "core/src/technique/fuzzy/kmeans_final.wgsl"
    ]
);

mod read;
pub use read::{SearchCounts, SEARCH_KINDS};

/// Mirrors `KmParams` in `fuzzy/kmeans.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct KmParamsUniform {
    point_count: u32,
    width: u32,
    height: u32,
    gamma: u32,
    sample_count: u32,
    cluster_count: u32,
    fuzziness: u32,
    has_flux: u32,
    n_t: f32,
    min_distance: f32,
    cell: f32,
    cells: u32,
    dims: [u32; 4],
    bounds_min: [f32; 4],
    bounds_extent: [f32; 4],
    flux_scale: [f32; 4],
    fine: [u32; 4],
    sched: [u32; 4],
    options: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<KmParamsUniform>() == 160);

/// A point, cluster or light as the shaders store it (`KmPoint`, `Vpl`, `Endpoint`: the `GpuVpl` layout).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuPoint {
    /// xyz, w: 1 when it exists (a valid point; a cluster with members).
    pub position: [f32; 4],
    /// xyz, w: members (clusters).
    pub normal: [f32; 4],
    pub flux: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<GpuPoint>() == 48);

impl GpuPoint {
    /// A VPL as a light of the shading (every VPL its own, `cluster=sp`).
    pub fn of_vpl(v: &crate::vpl::Vpl) -> GpuPoint {
        GpuPoint {
            position: v.position.extend(1.0).to_array(),
            normal: v.normal.extend(1.0).to_array(),
            flux: v.flux.extend(0.0).to_array(),
        }
    }

    pub fn exists(&self) -> bool {
        self.position[3] > 0.5
    }
    pub fn position(&self) -> Vec3 {
        Vec3::from_slice(&self.position[..3])
    }
    pub fn normal(&self) -> Vec3 {
        Vec3::from_slice(&self.normal[..3])
    }
    pub fn members(&self) -> u32 {
        self.normal[3] as u32
    }
}

/// Words of the accumulators per cluster (`ACC` in the shader).
const ACC: u64 = 24;
/// Normal buckets (kmeans.wgsl `NB`).
const NB: u64 = 64;
/// Most clusters (the initial-centroid arithmetic of the shader stays within u32).
pub const MAX_CLUSTERS: usize = 65_536;

/// What one clustering run was sized for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunShape {
    /// Points in the dataset (M).
    pub points: usize,
    /// Clusters used (K clamped to the samples).
    pub clusters: usize,
    /// F.
    pub fuzziness: usize,
}

impl RunShape {
    /// What a run of `params` is sized for (known before it is encoded, so a frame can be planned).
    pub fn of(params: &KMeansParams) -> RunShape {
        let points = params.width as usize * params.height as usize;
        let g = params.gamma.max(1) as usize;
        let samples = (params.width as usize).div_ceil(g) * (params.height as usize).div_ceil(g);
        let clusters = params.clusters.min(samples).min(MAX_CLUSTERS);
        RunShape { points, clusters, fuzziness: params.fuzziness.clamp(1, MAX_F) }
    }
}

pub struct GpuKMeans {
    label: &'static str,
    kernels: Kernels,
    /// `2 K` points: the clusters as lights / endpoints, then the working centroids.
    pub clusters: Option<wgpu::Buffer>,
    work: Option<wgpu::Buffer>,
    /// The grid and the normal buckets as the searches read them (`grid` in the shader: plain words, not atomics).
    grid: Option<wgpu::Buffer>,
    /// Per point `F` entries of (cluster, inverse-distance bits).
    pub assignment: Option<wgpu::Buffer>,
    /// The workgroups of `km_search` (an indirect dispatch sized by the queue).
    search_args: wgpu::Buffer,
    search_args_stand_in: wgpu::Buffer,
    /// The searches' work counts (`search_counts` in the shader), written with `count_searches` only.
    search_counts: wgpu::Buffer,
    count_searches: bool,
    pub shape: RunShape,
    /// `K` of the last encoded run (its working centroids are what a warm start begins from).
    encoded_clusters: Option<usize>,
    /// The most centroids a search for `F` > 1 scans whole from the normal buckets instead of walking the grid
    /// (0: always the grid). Speed only: both find the same clusters.
    bucket_scan_limit: u32,
    /// The schedule for a real GPU (true) or a CPU rasterizer (false). Speed only: the same clusters either way
    /// (docs/techniques/fuzzy.md, eighteenth and nineteenth sessions). On a GPU a dispatch lasts as long as its
    /// slowest invocation, so every search walks `near_shells` shells alone and the unfinished ones go to a
    /// workgroup each (`km_assign_wide`, `km_search_wide`), crowded cells are searched in finer grid levels, and
    /// the grid's scan is spread over the GPU; on the H200 at 1024x720 the clustering took 2.9 instead of 10.5 ms
    /// on the conference room. On a CPU rasterizer a long search holds only its own lane: the nearest walks the
    /// grid to its end and the short lists are queued for `km_search` (the GPU schedule's code, run or only
    /// compiled in behind a uniform switch, made lavapipe's clustering about 50 % slower).
    gpu_schedule: bool,
    /// A real GPU's schedule: the grid shells every point walks, and the cells and centroids it visits (0: no
    /// bound), before an unfinished search goes to a workgroup.
    near_shells: u32,
    near_budget: u32,
    /// The grid's finer levels (0: the coarse one alone) and the crowd of a point's cell above which its searches
    /// use the next one.
    fine_levels: u32,
    fine_above: u32,
    /// Each dispatch in a timed pass of its own (`fuzzy clustering (<label>): <stage>: <entry>`), for profiling;
    /// off: one timed pass per stage.
    time_dispatches: bool,
}

/// [`GpuKMeans`]'s default bucket scan limit (searches for `F` > 1; the nearest alone walks the grid): measured
/// per dispatch on the three real scenes, 256 and 512 were fastest, 64 and 128 slower (docs/techniques/fuzzy.md).
pub const BUCKET_SCAN_LIMIT: u32 = 256;

/// [`GpuKMeans`]'s default finer levels of the grid (each 4 x 4 x 4 cells per cell of the one before;
/// kmeans.wgsl `level_cell`): most levels a search may descend to.
pub const FINE_LEVELS: u32 = 1;

/// [`GpuKMeans`]'s default crowd of a point's cell above which its searches use the next finer level.
pub const FINE_ABOVE: u32 = 128;

/// The cells of each finer level's hash table for `k` centroids (a power of two, one to two per centroid: the
/// single-workgroup scan of `grid_scan` runs over them every iteration; with two to four per centroid the H200's
/// scan took 0.09 instead of 0.06 ms).
fn fine_table(k: usize) -> u64 {
    (k as u64).next_power_of_two().max(64)
}

/// [`GpuKMeans`]'s default bound on the cells and centroids a search visits alone (a real GPU's schedule; 0: none).
pub const NEAR_BUDGET: u32 = 0;

/// [`GpuKMeans`]'s default grid shells before a workgroup-wide search (a real GPU's schedule): the two shells
/// (125 cells) that the eighteenth session's bounded nearest search walked (1 and 3 were no faster on the H200).
pub const NEAR_SHELLS: u32 = 2;

/// Grow `slot` to a storage buffer (copyable both ways) of at least `size` bytes, rounded up to a power of two
/// so a frame that grows a little does not reallocate; true when it was (re)created.
pub(super) fn ensure_storage(slot: &mut Option<wgpu::Buffer>, gpu: &GpuContext, label: &str, size: u64) -> bool {
    if slot.as_ref().is_some_and(|b| b.size() >= size) {
        return false;
    }
    *slot = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(64).next_power_of_two(),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    }));
    true
}

/// One dispatch of a k-means run: its timed stage, its kernel and its workgroups (None: over the search queue,
/// as `queue_args` wrote them, an indirect dispatch).
type Step = (&'static str, &'static str, Option<(u32, u32)>);

/// Workgroups of 64 for `n` invocations, as `(x, y)` (x at most 32,768: `global_index` in the shader).
pub(super) fn groups(n: usize) -> (u32, u32) {
    let g = n.div_ceil(64).max(1) as u32;
    if g <= 65_535 {
        (g, 1)
    } else {
        (32_768, g.div_ceil(32_768))
    }
}

const ENTRIES: &[&str] = &[
    "km_init",
    "grid_clear",
    "grid_count",
    "grid_scan",
    "km_assign",
    "km_update",
    "km_final",
    "km_blocks",
    "km_fill",
    "queue_args",
    "km_search",
    "rep_pick",
    "rep_finish",
    "grid_fill",
    "grid_sums",
    "grid_starts",
    "km_assign_wide",
    "km_search_wide",
];

/// The k-means kernels for a real GPU's schedule or a CPU rasterizer's: the WGSL's `GPU_SCHEDULE`, a
/// pipeline-overridable constant, so each compiles without the other's code (a uniform switch instead made
/// lavapipe's clustering about 50 % slower in its own schedule); `COUNT_WORK` the same for the searches' work
/// counts.
fn kernels(gpu: &GpuContext, gpu_schedule: bool, count_work: bool) -> Kernels {
    // Binding 1: the points (read); 2-4: the clusters, the working centroids, the assignment; 5: the
    // workgroups of the queued searches; 6: the grid and the normal buckets; 7: the searches' work counts.
    let flag = |on: bool| if on { 1.0 } else { 0.0 };
    Kernels::new(
        gpu,
        "fuzzy kmeans",
        KMEANS.source,
        ENTRIES,
        std::mem::size_of::<KmParamsUniform>() as u64,
        &[true, false, false, false, false, false, false],
        &[("GPU_SCHEDULE", flag(gpu_schedule)), ("COUNT_WORK", flag(count_work))],
    )
}

impl GpuKMeans {
    pub fn new(gpu: &GpuContext, label: &'static str) -> GpuKMeans {
        let gpu_schedule = gpu.adapter_info.device_type != wgpu::DeviceType::Cpu;
        let kernels = kernels(gpu, gpu_schedule, false);
        let search_args = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fuzzy search workgroups"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        // Bound at binding 5 while `km_search` runs: a dispatch may not read a buffer as its indirect arguments
        // while a bound group holds it writable.
        let search_args_stand_in = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fuzzy search workgroups (stand-in)"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let search_counts = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fuzzy search counts"),
            size: (SEARCH_KINDS.len() * 5 * 4) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        GpuKMeans {
            label,
            kernels,
            search_counts,
            count_searches: false,
            clusters: None,
            work: None,
            grid: None,
            assignment: None,
            search_args,
            search_args_stand_in,
            shape: RunShape::default(),
            encoded_clusters: None,
            bucket_scan_limit: BUCKET_SCAN_LIMIT,
            gpu_schedule,
            time_dispatches: false,
            near_shells: NEAR_SHELLS,
            near_budget: NEAR_BUDGET,
            fine_levels: FINE_LEVELS,
            fine_above: FINE_ABOVE,
        }
    }

    /// Sets the grid shells a real GPU's schedule walks before an unfinished search goes to a workgroup of its
    /// own (0: nearly every search does, which the tests use to check that path against the CPU twin). Speed
    /// only: the clusters found do not change.
    pub fn set_near_shells(&mut self, shells: u32) {
        self.near_shells = shells;
    }

    /// Sets the cells and centroids a real GPU's schedule lets a search visit alone before a workgroup finishes
    /// it (0: only the shells bound it). Speed only: the clusters found do not change.
    pub fn set_near_budget(&mut self, budget: u32) {
        self.near_budget = budget;
    }

    /// Sets the grid's finer levels (at most 3; 0: the coarse level alone) and the crowd of a point's cell above
    /// which its searches use the next one, in a real GPU's schedule (a CPU rasterizer's grid is the coarse level
    /// alone). Speed only: the clusters found do not change.
    pub fn set_fine_levels(&mut self, levels: u32, crowd: u32) {
        self.fine_levels = levels.min(3);
        self.fine_above = crowd;
    }

    /// Times each dispatch in a pass of its own (profiling: the report then names every kernel; the passes'
    /// timestamps cost a little) instead of one pass per stage.
    pub fn set_time_dispatches(&mut self, on: bool) {
        self.time_dispatches = on;
    }

    /// Sets the bucket scan limit (0: every search walks the grid; `u32::MAX`: every exact search for `F` > 1
    /// scans the buckets; the nearest alone always walks the grid). The clusters found do not change; the tests check both paths against the CPU twin.
    pub fn set_bucket_scan_limit(&mut self, limit: u32) {
        self.bucket_scan_limit = limit;
    }

    /// Sets the schedule: a real GPU's (two shells per point, then a workgroup per unfinished search) or a CPU
    /// rasterizer's (the default follows the adapter's device type). The clusters found do not change; the tests
    /// check both.
    pub fn set_gpu_schedule(&mut self, gpu: &GpuContext, gpu_schedule: bool) {
        if gpu_schedule != self.gpu_schedule {
            self.kernels = kernels(gpu, gpu_schedule, self.count_searches);
            self.gpu_schedule = gpu_schedule;
        }
    }

    /// Counts the searches' work (cells visited, centroids considered, points queued per kind of search; read
    /// with [`GpuKMeans::read_search_counts`]). The kernels count with atomics: slower, the same clusters.
    pub fn set_count_searches(&mut self, gpu: &GpuContext, on: bool) {
        if on != self.count_searches {
            self.kernels = kernels(gpu, self.gpu_schedule, on);
            self.count_searches = on;
        }
    }

    fn pipeline(&self, entry: &str) -> &wgpu::ComputePipeline {
        self.kernels.pipeline(entry)
    }

    /// Encode Algorithm 1 (and 2 as its last line) over the `params.width x params.height` points of `points`.
    /// `max_flux`: the largest flux component of the points when they are VPLs (the clusters then carry their
    /// members' flux and mean normal), None for shading points. `warm`: start from the last run's centroids
    /// instead of the initial samples (the twin's [`super::kmeans::cluster_from`]; only when the last run had
    /// the same `K`, else it starts cold), a centroid left without members moving back to its initial sample.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &mut self,
        gpu: &GpuContext,
        timer: &PassTimer,
        encoder: &mut wgpu::CommandEncoder,
        points: &wgpu::Buffer,
        params: &KMeansParams,
        max_flux: Option<f32>,
        warm: bool,
    ) -> Result<RunShape, GpuError> {
        // The working centroids must be a run's of the same `K` (`shape` is set by the technique before it
        // encodes, so it cannot tell).
        let warm = warm && self.encoded_clusters == Some(RunShape::of(params).clusters);
        let RunShape { points: m, clusters: k, fuzziness: f } = RunShape::of(params);
        let g = params.gamma.max(1) as usize;
        let samples = (params.width as usize).div_ceil(g) * (params.height as usize).div_ceil(g);
        let (cell, dims) = grid_shape(params.bounds_extent, k);
        let cells = (dims[0] * dims[1] * dims[2]) as u64;
        // The finer levels are a real GPU's: on lavapipe their grids cost more than they saved (at 240x160 few
        // cells are crowded).
        let fine_levels = if self.gpu_schedule { self.fine_levels } else { 0 };
        let fine = fine_levels as u64 * fine_table(k);
        let levels = fine_levels as u64 + 1;
        let neighbours = params.neighbour_lists && g > 1;
        // Per point F (cluster, inverse distance); with neighbour lists, then per block of pixels between four
        // samples a count and up to 4 F clusters (km_blocks).
        let block_words = if neighbours { samples as u64 * (1 + 4 * f as u64) } else { 0 };
        let assignment_bytes = m as u64 * f as u64 * 8 + block_words * 4;
        let limit = gpu.device.limits().max_storage_buffer_binding_size;
        if assignment_bytes > limit {
            return Err(GpuError::InvalidSettings(format!(
                "{}: {m} points x F = {f} need {} MiB of cluster assignments, above the adapter's {} MiB per \
                 buffer (lower F or the image size)",
                self.label,
                assignment_bytes >> 20,
                limit >> 20
            )));
        }
        let warm = !ensure_storage(&mut self.clusters, gpu, "fuzzy clusters", (2 * k.max(1) * 48) as u64) && warm;
        ensure_storage(
            &mut self.work,
            gpu,
            "fuzzy kmeans work",
            (k as u64 * ACC + cells + fine + 2 * NB + 1 + m as u64) * 4,
        );
        let scan_blocks = (cells + fine).div_ceil(256);
        let grid_words = cells + fine + 1 + (levels + 1) * k as u64 + 2 * NB + 1 + scan_blocks;
        ensure_storage(&mut self.grid, gpu, "fuzzy kmeans grid", grid_words * 4);
        ensure_storage(&mut self.assignment, gpu, "fuzzy assignment", assignment_bytes);
        self.shape = RunShape { points: m, clusters: k, fuzziness: f };
        self.encoded_clusters = Some(k);
        let (clusters, work, grid, assignment) = (
            self.clusters.as_ref().expect("grown"),
            self.work.as_ref().expect("grown"),
            self.grid.as_ref().expect("grown"),
            self.assignment.as_ref().expect("grown"),
        );
        if self.count_searches {
            encoder.clear_buffer(&self.search_counts, 0, None);
        }
        if k == 0 || m == 0 {
            // Nothing to cluster: no cluster exists and every point is unassigned.
            encoder.clear_buffer(clusters, 0, None);
            encoder.clear_buffer(assignment, 0, None);
            return Ok(self.shape);
        }
        let max_flux = max_flux.filter(|v| v.is_finite() && *v > 0.0);
        let uniform = KmParamsUniform {
            point_count: m as u32,
            width: params.width,
            height: params.height,
            gamma: g as u32,
            sample_count: samples as u32,
            cluster_count: k as u32,
            fuzziness: f as u32,
            has_flux: max_flux.is_some() as u32,
            n_t: params.n_t,
            min_distance: params.min_distance,
            cell,
            cells: cells as u32,
            dims: [dims[0], dims[1], dims[2], params.max_ring],
            bounds_min: params.bounds_min.extend(0.0).to_array(),
            bounds_extent: params.bounds_extent.max(Vec3::splat(1e-12)).extend(0.0).to_array(),
            flux_scale: [1.0 / max_flux.unwrap_or(1.0), max_flux.unwrap_or(1.0), 0.0, 0.0],
            fine: [fine_levels, fine_table(k) as u32, self.fine_above, 0],
            sched: [self.near_budget, 0, 0, 0],
            options: [neighbours as u32, self.bucket_scan_limit, warm as u32, self.near_shells],
        };
        self.kernels.write_uniform(gpu, &uniform);
        let counts = &self.search_counts;
        let group =
            self.kernels.bind_group(gpu, &[points, clusters, work, assignment, &self.search_args, grid, counts]);
        let search_group = self
            .kernels
            .bind_group(gpu, &[points, clusters, work, assignment, &self.search_args_stand_in, grid, counts]);
        let over_k = groups(k);
        // grid_clear also clears the clusters' accumulators.
        let over_cells = groups(((cells + fine) as usize).max(NB as usize).max(k));
        let over_samples = groups(samples);
        let over_points = groups(m);
        // The dispatches in order, each with its stage: Algorithm 1's iterations; the grid of the final centroids
        // and Algorithm 2's assignment (the samples' searches, the blocks' lists, the fill from them); the
        // searches of the points the fill queued and the representatives. Timed as one pass per stage (the
        // report's per-pass times; one pass for all cost the same) or, for profiling, one pass per dispatch.
        let mut plan: Vec<Step> = Vec::new();
        let gpu_schedule = self.gpu_schedule;
        // `clear`: the run's first grid; every later one follows a km_update, which clears as it goes.
        let grid_build = |plan: &mut Vec<_>, stage, clear: bool| {
            if clear {
                plan.push((stage, "grid_clear", Some(over_cells)));
            }
            plan.push((stage, "grid_count", Some(over_k)));
            if gpu_schedule {
                plan.push((stage, "grid_sums", Some((scan_blocks as u32, 1))));
                plan.push((stage, "grid_scan", Some((1, 1))));
                plan.push((stage, "grid_starts", Some((scan_blocks as u32, 1))));
                plan.push((stage, "grid_fill", Some(over_k)));
            } else {
                plan.push((stage, "grid_scan", Some((1, 1))));
            }
        };
        // The search over the queue: on a real GPU a workgroup per queued point (`km_assign_wide`,
        // `km_search_wide`), on a CPU rasterizer `km_search`, 64 points a workgroup.
        let over_queue = |plan: &mut Vec<_>, stage, entry| {
            plan.push((stage, "queue_args", Some((1, 1))));
            plan.push((stage, entry, None));
        };
        if !warm {
            plan.push(("iterations", "km_init", Some(over_k)));
        }
        for i in 0..params.iterations {
            grid_build(&mut plan, "iterations", i == 0);
            plan.push(("iterations", "km_assign", Some(over_samples)));
            if gpu_schedule {
                over_queue(&mut plan, "iterations", "km_assign_wide");
            }
            plan.push(("iterations", "km_update", Some(over_cells)));
        }
        grid_build(&mut plan, "assignment", params.iterations == 0);
        let search = if gpu_schedule { "km_search_wide" } else { "km_search" };
        if neighbours {
            plan.push(("assignment", "km_final", Some(over_samples)));
            if gpu_schedule {
                // The samples' lists complete before the blocks merge them.
                over_queue(&mut plan, "assignment", "km_search_wide");
            }
            plan.push(("assignment", "km_blocks", Some(over_samples)));
            plan.push(("assignment", "km_fill", Some(over_points)));
            plan.push(("assignment", "queue_args", Some((1, 1))));
            plan.push(("search", search, None));
        } else {
            plan.push(("assignment", "km_final", Some(over_points)));
            if gpu_schedule {
                over_queue(&mut plan, "search", "km_search_wide");
            }
        }
        plan.push(("search", "rep_pick", Some(over_points)));
        plan.push(("search", "rep_finish", Some(over_k)));
        let dispatch = |pass: &mut wgpu::ComputePass<'_>, entry: &str, size: Option<(u32, u32)>| {
            pass.set_pipeline(self.pipeline(entry));
            match size {
                Some((x, y)) => {
                    pass.set_bind_group(0, &group, &[]);
                    pass.dispatch_workgroups(x, y, 1);
                }
                None => {
                    pass.set_bind_group(0, &search_group, &[]);
                    pass.dispatch_workgroups_indirect(&self.search_args, 0);
                }
            }
        };
        let label = self.label;
        if self.time_dispatches {
            for &(stage, entry, size) in &plan {
                let name = format!("fuzzy clustering ({label}): {stage}: {entry}");
                timer.compute_pass(encoder, &name, |pass| dispatch(pass, entry, size));
            }
        } else {
            for stage in ["iterations", "assignment", "search"] {
                timer.compute_pass(encoder, &format!("fuzzy clustering ({label}): {stage}"), |pass| {
                    for &(_, entry, size) in plan.iter().filter(|d| d.0 == stage) {
                        dispatch(pass, entry, size);
                    }
                });
            }
        }
        Ok(self.shape)
    }
}
