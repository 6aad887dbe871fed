// Fuzzy K-means of surface points on the GPU (Colom et al. 2022, Algorithms 1 and 2), the twin of
// core/src/technique/fuzzy/kmeans.rs: the same samples (every gamma-th column and row), initial centroids (the
// first valid sample at or after k S / K), equation 7 (|p1 - p2| when n1 . n2 > n_t), grid search grown shell
// by shell from the 27 cells until provably complete, ties to the lower index, fixed-point means and the F
// nearest with inverse distances. WGSL has no float atomics: members add their position as a fraction of the
// bounds and their normal as (n + 1) / 2, times 2^24, into 64-bit sums made of two atomic u32 (the carry is
// added to the high word when the low word wraps), so a mean keeps 2^-24 of the bounds whatever the count.
// Entry points, one dispatch each, in the order of gpu.rs `encode`: km_init (not in a warm start: the centroids
// are the last run's); grid_clear before the first grid (with the accumulators and the queue; km_update clears
// them for every later one); per iteration grid_count, grid_scan
// (with the fill; a real GPU: then grid_fill), km_assign (a real GPU: then queue_args and km_assign_wide over
// the samples it queued); km_update; then the grid again, km_final (over the samples with neighbour lists; a real
// GPU: queue_args, km_search_wide), km_blocks, km_fill, queue_args and km_search (a real GPU: km_search_wide),
// dispatched indirectly over the queue, rep_pick, rep_finish.
// `KmParams`, `KmPoint` mirror core/src/technique/fuzzy/gpu.rs. The grid (its levels and the passes that build
// it) is in kmeans_grid.wgsl, the search in kmeans_search.wgsl, Algorithm 2 (km_final, km_fill, km_search) in
// kmeans_final.wgsl; the four are one module.

const MAX_F: u32 = 8u;
// A real GPU's schedule (true: kmeans_search.wgsl `find_near` for every point and a workgroup per unfinished
// search, the grid's finer levels and its scan over many workgroups) or a CPU rasterizer's (gpu.rs `kernels`:
// set per pipeline, so each compiles without the other's code).
override GPU_SCHEDULE: bool = false;
// Count the searches' work into `search_counts` (gpu.rs `set_count_searches`; compiled out otherwise).
override COUNT_WORK: bool = false;
const NONE: u32 = 0xffffffffu;
const FIXED: f32 = 16777216.0;
// Words of `work` per cluster: position sums (lo, hi) x 3, normal sums (lo, hi) x 3, member count, best
// distance bits, representative, flux sums (lo, hi) x 3, 3 spare.
const ACC: u32 = 24u;
// The normal buckets: an octahedral map of NB_SIDE x NB_SIDE cells over the centroids' normals.
const NB_SIDE: u32 = 8u;
const NB: u32 = 64u;
// Radians added to a bucket's reach so that rounding never skips a bucket that holds a compatible centroid.
const NB_MARGIN: f32 = 1e-3;
const ACC_COUNT: u32 = 12u;
const ACC_BEST: u32 = 13u;
const ACC_REP: u32 = 14u;
const ACC_FLUX: u32 = 15u;

struct KmParams {
    point_count: u32,
    width: u32,
    height: u32,
    gamma: u32,
    sample_count: u32,
    cluster_count: u32,
    fuzziness: u32,
    // 1: the points carry flux (VPLs): the outputs get the members' flux and mean normal
    has_flux: u32,
    n_t: f32,
    min_distance: f32,
    cell: f32,
    cells: u32,
    // xyz: grid cells per axis, w: the largest ring searched once a compatible centroid is found (0: exact)
    dims: vec4<u32>,
    bounds_min: vec4<f32>,
    bounds_extent: vec4<f32>,
    // x: 1 / the largest flux component (has_flux), y: that component
    flux_scale: vec4<f32>,
    // The grid's finer levels (a real GPU's schedule and a CPU rasterizer's alike): x: how many (0: the coarse
    // level alone), y: the cells of each one's hash table, z: the most centroids a point's cell holds before its
    // searches use the next finer level
    fine: vec4<u32>,
    // A real GPU's schedule: x: the cells and centroids a point's search visits alone before it goes to a
    // workgroup's (0: no bound but the shells)
    sched: vec4<u32>,
    // x: 1: Algorithm 2 searches the grid for the samples only; km_fill gives the other points the F nearest of
    // their four neighbouring samples' lists (kmeans.rs `neighbour_lists`); y: the most centroids a search for F > 1
    // scans whole from the normal buckets instead of walking the grid (0: always the grid); z: 1: a warm start (the
    // last run's centroids): km_update moves a centroid left without members back to its initial sample
    options: vec4<u32>,
}

// A VPL (GpuVpl) or a shading point: position (w: 1 valid), normal, flux.
struct KmPoint {
    position: vec4<f32>,
    normal: vec4<f32>,
    flux: vec4<f32>,
}

@group(0) @binding(0) var<uniform> km: KmParams;
@group(0) @binding(1) var<storage, read> km_points: array<KmPoint>;
// [0, K): the clusters as lights / endpoints (representative's position, w: 1 when it has members; normal, w:
// members; flux). [K, 2K): the working centroids (position, w: 1 active; normal).
@group(0) @binding(2) var<storage, read_write> clusters: array<KmPoint>;
// K * ACC accumulators, then the grid's cell counts (all levels; the fill cursors while the centroids are filled), the normal
// buckets' counts (cursors) and least cosines (grid_count's atomicMin); then the search queue of km_fill: its
// length and the points (up to all).
@group(0) @binding(3) var<storage, read_write> work: array<atomic<u32>>;
// Per point, F entries of (cluster, bitcast inverse distance); NONE where empty. With neighbour lists, then the
// blocks' lists (km_blocks).
@group(0) @binding(4) var<storage, read_write> assignment: array<u32>;
// The workgroups of km_search (x, y, z), written by queue_args from the queue's length: an indirect dispatch,
// so that the points km_fill did not queue cost no workgroup.
@group(0) @binding(5) var<storage, read_write> search_args: array<u32>;
// The grid and the normal buckets as the searches read them, written by grid_scan and grid_fill only: the cells'
// starts (all levels' cells + 1), their items (K per level, the coarse level's first), the buckets' starts
// (NB + 1), their limits (NB, f32 bits), their items (K). Not
// in `work`: the searches read these words thousands of times a point, and an atomic load is not cached near
// the core on a real GPU (a relaxed load at device scope goes to the shared cache), a plain load is.
@group(0) @binding(6) var<storage, read_write> grid: array<u32>;
// With COUNT_WORK, per kind of search (SEARCH_KINDS, gpu.rs `SEARCH_KINDS`) 5 words: the points searched, the
// cells visited, the centroids considered, the points queued for a search of their own, the most cells and
// centroids one invocation visited.
@group(0) @binding(7) var<storage, read_write> search_counts: array<atomic<u32>>;

// The kinds of search counted: km_assign (0), km_assign_wide (1), km_final (2), km_fill (3), km_search and
// km_search_wide (4).
const COUNT_ASSIGN: u32 = 0u;
const COUNT_ASSIGN_WIDE: u32 = 1u;
const COUNT_FINAL: u32 = 2u;
const COUNT_FILL: u32 = 3u;
const COUNT_SEARCH: u32 = 4u;
var<private> counted_cells: u32;
var<private> counted_centroids: u32;

// One invocation's search work into its kind's counts (`point`: it counts a point searched; `queued`: the point
// went to a search of its own).
fn count_search(kind: u32, point: bool, queued: bool) {
    if COUNT_WORK {
        let b = kind * 5u;
        if point {
            atomicAdd(&search_counts[b], 1u);
        }
        atomicAdd(&search_counts[b + 1u], counted_cells);
        atomicAdd(&search_counts[b + 2u], counted_centroids);
        if queued {
            atomicAdd(&search_counts[b + 3u], 1u);
        }
        atomicMax(&search_counts[b + 4u], counted_cells + counted_centroids);
    }
}

fn global_index(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * 64u;
}

fn counts_base() -> u32 {
    return km.cluster_count * ACC;
}

fn nb_counts_base() -> u32 {
    return counts_base() + all_cells();
}

fn nb_least_base() -> u32 {
    return nb_counts_base() + NB;
}

fn queue_base() -> u32 {
    return nb_least_base() + NB;
}

// `grid`'s parts.
fn starts_base() -> u32 {
    return 0u;
}

fn items_base() -> u32 {
    return all_cells() + 1u;
}

fn nb_starts_base() -> u32 {
    return items_base() + (km.fine.x + 1u) * km.cluster_count;
}

fn nb_limits_base() -> u32 {
    return nb_starts_base() + NB + 1u;
}

fn nb_items_base() -> u32 {
    return nb_limits_base() + NB;
}

// A real GPU's schedule: the cells' counts summed per block of 256 (grid_sums), then those sums' starts (grid_scan).
fn scan_blocks_base() -> u32 {
    return nb_items_base() + km.cluster_count;
}

fn scan_blocks() -> u32 {
    return (all_cells() + 255u) / 256u;
}

fn point_valid(p: KmPoint) -> bool {
    let finite = all(abs(p.position.xyz) < vec3<f32>(3.0e38)) && all(abs(p.normal.xyz) < vec3<f32>(3.0e38));
    return p.position.w > 0.5 && finite;
}

fn sample_point(s: u32) -> u32 {
    let g = max(km.gamma, 1u);
    let per_row = (km.width + g - 1u) / g;
    return (s / per_row) * g * km.width + (s % per_row) * g;
}

fn centroid(k: u32) -> KmPoint {
    return clusters[km.cluster_count + k];
}

fn add64(word: u32, v: u32) {
    let old = atomicAdd(&work[word], v);
    if old + v < old {
        atomicAdd(&work[word + 1u], 1u);
    }
}

fn read64(word: u32) -> f32 {
    return f32(atomicLoad(&work[word + 1u])) * 4294967296.0 + f32(atomicLoad(&work[word]));
}

fn quantize(v: f32) -> u32 {
    return u32(clamp(v, 0.0, 1.0) * FIXED);
}

fn accumulate_position(k: u32, p: KmPoint) {
    let f = (p.position.xyz - km.bounds_min.xyz) / km.bounds_extent.xyz;
    let base = k * ACC;
    add64(base + 0u, quantize(f.x));
    add64(base + 2u, quantize(f.y));
    add64(base + 4u, quantize(f.z));
}

fn accumulate_normal(k: u32, p: KmPoint) {
    let n = p.normal.xyz * 0.5 + 0.5;
    let base = k * ACC;
    add64(base + 6u, quantize(n.x));
    add64(base + 8u, quantize(n.y));
    add64(base + 10u, quantize(n.z));
}

// The renormalised mean normal of cluster k's sums, or `fallback` when it vanishes.
fn mean_normal(k: u32, count: u32, fallback: vec3<f32>) -> vec3<f32> {
    let base = k * ACC;
    let c = f32(count) * FIXED;
    let n = vec3<f32>(read64(base + 6u) / c, read64(base + 8u) / c, read64(base + 10u) / c) * 2.0 - 1.0;
    if dot(n, n) > 1e-12 {
        return normalize(n);
    }
    return fallback;
}

@compute @workgroup_size(64)
fn km_init(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < km.cluster_count {
        seed(id.x);
    }
}

// Centroid k's initial position: the first valid sample at or after k S / K (inactive when its share has none).
fn seed(k: u32) {
    let kc = km.cluster_count;
    let s = km.sample_count;
    // k S / K without overflowing u32 (K <= 65,536).
    let a = k * (s / kc) + (k * (s % kc)) / kc;
    let b = (k + 1u) * (s / kc) + ((k + 1u) * (s % kc)) / kc;
    clusters[kc + k] = KmPoint(vec4<f32>(0.0), vec4<f32>(0.0, 0.0, 1.0, 0.0), vec4<f32>(0.0));
    for (var i = a; i < b; i++) {
        let p = km_points[sample_point(i)];
        if point_valid(p) {
            clusters[kc + k] = KmPoint(vec4<f32>(p.position.xyz, 1.0), vec4<f32>(p.normal.xyz, 0.0), vec4<f32>(0.0));
            break;
        }
    }
}

// The nearest cluster of a point: entry 0 of the search, or the nearest by position when none is compatible.
fn nearest_cluster(p: KmPoint) -> u32 {
    find(p.position.xyz, p.normal.xyz, 1u);
    return nearest_found();
}

fn nearest_found() -> u32 {
    if best_n > 0u {
        return best_kl.x;
    }
    return any_k;
}

// Point m (a sample, a pixel) into the queue of the workgroup-wide searches (a real GPU's schedule).
fn enqueue(m: u32) {
    let q = atomicAdd(&work[queue_base()], 1u);
    atomicStore(&work[queue_base() + 1u + q], m);
}

// Algorithm 1's assignment step: the sample's centroid takes it into its sums.
fn assign_to(k: u32, p: KmPoint) {
    if k == NONE {
        return;
    }
    accumulate_position(k, p);
    accumulate_normal(k, p);
    atomicAdd(&work[k * ACC + ACC_COUNT], 1u);
}

@compute @workgroup_size(64)
fn km_assign(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let s = global_index(id, groups);
    if s >= km.sample_count {
        return;
    }
    let m = sample_point(s);
    let p = km_points[m];
    if !point_valid(p) {
        return;
    }
    if GPU_SCHEDULE {
        if !find_near(p.position.xyz, p.normal.xyz, 1u) {
            enqueue(m);
            count_search(COUNT_ASSIGN, true, true);
            return;
        }
        assign_to(nearest_found(), p);
    } else {
        assign_to(nearest_cluster(p), p);
    }
    count_search(COUNT_ASSIGN, true, false);
}

// A real GPU's schedule: the samples km_assign queued, a workgroup each (its workgroups from queue_args).
@compute @workgroup_size(64)
fn km_assign_wide(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                  @builtin(local_invocation_id) lid: vec3<u32>) {
    let m = wide_search(wid, groups, lid.x, 1u, COUNT_ASSIGN_WIDE);
    if m != NONE && lid.x == 0u {
        assign_to(nearest_found(), km_points[m]);
    }
}

@compute @workgroup_size(64)
fn km_update(@builtin(global_invocation_id) id: vec3<u32>) {
    // Centroid k moved to its members' mean, then its accumulators (and entry k of the grid's counts) cleared
    // for the next grid (kmeans_grid.wgsl `clear_for_grid`). Dispatched over max(cells, NB, K).
    let k = id.x;
    if k < km.cluster_count {
        update_centroid(k);
    }
    clear_for_grid(k);
}

fn update_centroid(k: u32) {
    let count = atomicLoad(&work[k * ACC + ACC_COUNT]);
    let c = centroid(k);
    if c.position.w < 0.5 || count == 0u {
        // A warm start's centroid without members (its surface left the view or is hidden now) starts again
        // from its initial sample, as Algorithm 1 would have placed it in this view.
        if km.options.z == 1u {
            seed(k);
        }
        return;
    }
    let base = k * ACC;
    let n = f32(count) * FIXED;
    let f = vec3<f32>(read64(base + 0u) / n, read64(base + 2u) / n, read64(base + 4u) / n);
    let position = km.bounds_min.xyz + f * km.bounds_extent.xyz;
    clusters[km.cluster_count + k] =
        KmPoint(vec4<f32>(position, 1.0), vec4<f32>(mean_normal(k, count, c.normal.xyz), 0.0), vec4<f32>(0.0));
}

// The representative: the member at the least distance from its centroid, the lowest index on ties.
@compute @workgroup_size(64)
fn rep_pick(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let m = global_index(id, groups);
    if m >= km.point_count {
        return;
    }
    let f_max = clamp(km.fuzziness, 1u, MAX_F);
    let k = assignment[m * f_max * 2u];
    if k == NONE {
        return;
    }
    let d = length(km_points[m].position.xyz - centroid(k).position.xyz);
    if bitcast<u32>(d) == atomicLoad(&work[k * ACC + ACC_BEST]) {
        atomicMin(&work[k * ACC + ACC_REP], m);
    }
}

@compute @workgroup_size(64)
fn rep_finish(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= km.cluster_count {
        return;
    }
    let count = atomicLoad(&work[k * ACC + ACC_COUNT]);
    let rep = atomicLoad(&work[k * ACC + ACC_REP]);
    if count == 0u || rep == NONE {
        clusters[k] = KmPoint(vec4<f32>(0.0), vec4<f32>(0.0, 0.0, 1.0, 0.0), vec4<f32>(0.0));
        return;
    }
    let r = km_points[rep];
    var normal = r.normal.xyz;
    var flux = vec3<f32>(0.0);
    if km.has_flux == 1u {
        normal = mean_normal(k, count, centroid(k).normal.xyz);
        let base = k * ACC + ACC_FLUX;
        flux = vec3<f32>(read64(base), read64(base + 2u), read64(base + 4u)) / FIXED * km.flux_scale.y;
    }
    clusters[k] = KmPoint(vec4<f32>(r.position.xyz, 1.0), vec4<f32>(normal, f32(count)), vec4<f32>(flux, 0.0));
}
