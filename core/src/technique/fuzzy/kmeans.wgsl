// Fuzzy K-means of surface points on the GPU (Colom et al. 2022, Algorithms 1 and 2), the twin of
// core/src/technique/fuzzy/kmeans.rs: the same samples (every gamma-th column and row), initial centroids (the
// first valid sample at or after k S / K), equation 7 (|p1 - p2| when n1 . n2 > n_t), grid search grown shell
// by shell from the 27 cells until provably complete, ties to the lower index, fixed-point means and the F
// nearest with inverse distances. WGSL has no float atomics: members add their position as a fraction of the
// bounds and their normal as (n + 1) / 2, times 2^24, into 64-bit sums made of two atomic u32 (the carry is
// added to the high word when the low word wraps), so a mean keeps 2^-24 of the bounds whatever the count.
// Entry points, one dispatch each, in this order (see gpu.rs): km_init; per iteration grid_clear, grid_count,
// grid_scan, grid_fill, acc_clear, km_assign, km_update; then the grid again, acc_clear, km_final (over the
// samples with neighbour lists, then km_fill over the other points), rep_pick, rep_finish. `KmParams`, `KmPoint` mirror core/src/technique/fuzzy/gpu.rs.

const MAX_F: u32 = 8u;
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
    // x: 1: Algorithm 2 searches the grid for the samples only; km_fill gives the other points the F nearest of
    // their four neighbouring samples' lists (kmeans.rs `neighbour_lists`); y: the most centroids a search scans
    // whole from the normal buckets instead of walking the grid (0: always the grid)
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
// K * ACC accumulators, then the grid: counts (cells), starts (cells + 1), items (K); then the normal buckets:
// counts (NB), starts (NB + 1), limits (NB), items (K); then the search queue of km_fill: its length and the
// points (up to all).
@group(0) @binding(3) var<storage, read_write> work: array<atomic<u32>>;
// Per point, F entries of (cluster, bitcast inverse distance); NONE where empty.
@group(0) @binding(4) var<storage, read_write> assignment: array<u32>;

fn global_index(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * 64u;
}

fn counts_base() -> u32 {
    return km.cluster_count * ACC;
}

fn starts_base() -> u32 {
    return counts_base() + km.cells;
}

fn items_base() -> u32 {
    return starts_base() + km.cells + 1u;
}

fn nb_counts_base() -> u32 {
    return items_base() + km.cluster_count;
}

fn nb_starts_base() -> u32 {
    return nb_counts_base() + NB;
}

fn nb_limits_base() -> u32 {
    return nb_starts_base() + NB + 1u;
}

fn nb_items_base() -> u32 {
    return nb_limits_base() + NB;
}

fn queue_base() -> u32 {
    return nb_items_base() + km.cluster_count;
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

fn cell_of(p: vec3<f32>) -> vec3<i32> {
    let c = floor((p - km.bounds_min.xyz) / km.cell);
    let top = vec3<f32>(km.dims.xyz) - 1.0;
    return vec3<i32>(clamp(c, vec3<f32>(0.0), top));
}

fn cell_index(c: vec3<i32>) -> u32 {
    let u = vec3<u32>(c);
    return u.x + km.dims.x * (u.y + km.dims.y * u.z);
}

// The search state of one invocation: the F nearest compatible centroids (up to 8, sorted, in two vec4 halves:
// entries 0-3 and 4-7, FAR / NONE where empty), how many there are, and the nearest by position. Vectors with
// constant lanes instead of arrays with per-invocation indices: a CPU rasterizer (lavapipe) keeps them in
// registers and inserts without branches; the array version made the final assignment several times slower.
const FAR: f32 = 3.0e38;
var<private> best_dl: vec4<f32>;
var<private> best_dh: vec4<f32>;
var<private> best_kl: vec4<u32>;
var<private> best_kh: vec4<u32>;
var<private> best_n: u32;
var<private> any_d: f32;
var<private> any_k: u32;
// Every centroid counts as compatible (find's nearest by position).
var<private> all_compatible: bool;

fn best_d(i: u32) -> f32 {
    if i < 4u {
        return best_dl[i];
    }
    return best_dh[i - 4u];
}

fn best_k(i: u32) -> u32 {
    if i < 4u {
        return best_kl[i];
    }
    return best_kh[i - 4u];
}

fn reset_best() {
    best_dl = vec4<f32>(FAR);
    best_dh = vec4<f32>(FAR);
    best_kl = vec4<u32>(NONE);
    best_kh = vec4<u32>(NONE);
    best_n = 0u;
    any_k = NONE;
    any_d = FAR;
}

fn less(d: f32, k: u32, d2: f32, k2: u32) -> bool {
    return d < d2 || (d == d2 && k < k2);
}

fn listed(k: u32) -> bool {
    return any(best_kl == vec4<u32>(k)) || any(best_kh == vec4<u32>(k));
}

// Insert (d, k) into the sorted list: the entries it precedes move one place down (the last one drops out).
fn insert_best(d: f32, k: u32, f_max: u32) {
    let dv = vec4<f32>(d);
    let kv = vec4<u32>(k);
    let lt_l = (dv < best_dl) | ((dv == best_dl) & (kv < best_kl));
    let lt_h = (dv < best_dh) | ((dv == best_dh) & (kv < best_kh));
    // Each entry's predecessor (the new item before entry 0).
    let pd_l = vec4<f32>(d, best_dl.xyz);
    let pk_l = vec4<u32>(k, best_kl.xyz);
    let plt_l = vec4<bool>(false, lt_l.xyz);
    let pd_h = vec4<f32>(best_dl.w, best_dh.xyz);
    let pk_h = vec4<u32>(best_kl.w, best_kh.xyz);
    let plt_h = vec4<bool>(lt_l.w, lt_h.xyz);
    best_dl = select(best_dl, select(dv, pd_l, plt_l), lt_l);
    best_kl = select(best_kl, select(kv, pk_l, plt_l), lt_l);
    best_dh = select(best_dh, select(dv, pd_h, plt_h), lt_h);
    best_kh = select(best_kh, select(kv, pk_h, plt_h), lt_h);
    best_n = min(best_n + 1u, f_max);
}

// The nearest by position is only used when no compatible centroid is found, so it is kept only while none is.
// A full list rejects a farther candidate with one comparison.
fn consider(k: u32, p: vec3<f32>, n: vec3<f32>, f_max: u32) {
    let c = centroid(k);
    let d = length(p - c.position.xyz);
    if best_n == 0u && (any_k == NONE || less(d, k, any_d, any_k)) {
        any_d = d;
        any_k = k;
    }
    if all_compatible || dot(n, c.normal.xyz) > km.n_t {
        if best_n == f_max && !less(d, k, best_d(f_max - 1u), best_k(f_max - 1u)) {
            return;
        }
        insert_best(d, k, f_max);
    }
}

// The distance from p to the box of cell c; a border cell's box reaches to infinity outwards (centroids beyond
// the bounds are binned into it).
fn cell_distance(c: vec3<i32>, p: vec3<f32>) -> f32 {
    let lo = km.bounds_min.xyz + vec3<f32>(c) * km.cell;
    let hi = lo + vec3<f32>(km.cell);
    let top = vec3<i32>(km.dims.xyz) - 1;
    let below = select(lo - p, vec3<f32>(0.0), c == vec3<i32>(0));
    let above = select(p - hi, vec3<f32>(0.0), c == top);
    return length(max(max(below, above), vec3<f32>(0.0)));
}

// A cell farther than the F-th centroid found cannot change the list once it is full.
fn visit_cell(c: vec3<i32>, p: vec3<f32>, n: vec3<f32>, f_max: u32) {
    if best_n == f_max && cell_distance(c, p) > best_d(f_max - 1u) {
        return;
    }
    let i = cell_index(c);
    let s = atomicLoad(&work[starts_base() + i]);
    let e = atomicLoad(&work[starts_base() + i + 1u]);
    for (var j = s; j < e; j++) {
        consider(atomicLoad(&work[items_base() + j]), p, n, f_max);
    }
}

// How far every centroid outside the block of radius r around cell c is from p at least: the distance to the
// block's nearest face with cells beyond it (kmeans.rs `Grid::guarantee`).
fn guarantee(p: vec3<f32>, c: vec3<i32>, r: i32) -> f32 {
    var g = 3.0e38;
    for (var a = 0; a < 3; a++) {
        if c[a] - r > 0 {
            g = min(g, p[a] - (km.bounds_min[a] + f32(c[a] - r) * km.cell));
        }
        if c[a] + r < i32(km.dims[a]) - 1 {
            g = min(g, km.bounds_min[a] + f32(c[a] + r + 1) * km.cell - p[a]);
        }
    }
    return g;
}

// Shell by shell (Chebyshev radius r) from the point's cell: at least the 27 cells of the paper, more until the
// F-th distance found is within the guarantee (every unvisited centroid is farther) or the grid is exhausted.
fn search(p: vec3<f32>, n: vec3<f32>, f_max: u32) {
    reset_best();
    let c = cell_of(p);
    let dims = vec3<i32>(km.dims.xyz);
    let far = max(c, dims - 1 - c);
    let reach = max(far.x, max(far.y, far.z));
    var r = 0;
    loop {
        let lo = max(c - vec3<i32>(r), vec3<i32>(0));
        let hi = min(c + vec3<i32>(r), dims - 1);
        for (var z = lo.z; z <= hi.z; z++) {
            for (var y = lo.y; y <= hi.y; y++) {
                if abs(z - c.z) == r || abs(y - c.y) == r {
                    for (var x = lo.x; x <= hi.x; x++) {
                        visit_cell(vec3<i32>(x, y, z), p, n, f_max);
                    }
                } else {
                    if c.x - r >= 0 {
                        visit_cell(vec3<i32>(c.x - r, y, z), p, n, f_max);
                    }
                    if c.x + r < dims.x {
                        visit_cell(vec3<i32>(c.x + r, y, z), p, n, f_max);
                    }
                }
            }
        }
        let complete = best_n == f_max && best_d(f_max - 1u) <= guarantee(p, c, r);
        // dims.w > 0: stop after that ring once a compatible centroid is found (1: the paper's 27 cells).
        let ring_done = km.dims.w > 0u && r >= i32(km.dims.w) && best_n > 0u;
        if (r >= 1 && (complete || ring_done)) || r >= reach {
            break;
        }
        r++;
    }
}

// The normal buckets: the octahedral cell of a normal, the direction of a cell's centre.
fn normal_bucket(n: vec3<f32>) -> u32 {
    let a = abs(n.x) + abs(n.y) + abs(n.z);
    if !(a > 1e-20) || !(a < 3.0e38) {
        return 0u;
    }
    var uv = n.xy / a;
    if n.z < 0.0 {
        uv = (1.0 - abs(uv.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), uv >= vec2<f32>(0.0));
    }
    let cell = vec2<u32>(clamp((uv * 0.5 + 0.5) * f32(NB_SIDE), vec2<f32>(0.0), vec2<f32>(f32(NB_SIDE) - 1.0)));
    return cell.x + cell.y * NB_SIDE;
}

fn bucket_axis(b: u32) -> vec3<f32> {
    let uv = (vec2<f32>(f32(b % NB_SIDE), f32(b / NB_SIDE)) + 0.5) / f32(NB_SIDE) * 2.0 - 1.0;
    var n = vec3<f32>(uv, 1.0 - abs(uv.x) - abs(uv.y));
    if n.z < 0.0 {
        n = vec3<f32>((1.0 - abs(n.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), n.xy >= vec2<f32>(0.0)), n.z);
    }
    return normalize(n);
}

fn unit(n: vec3<f32>) -> bool {
    return abs(dot(n, n) - 1.0) < 1e-3;
}

// The F nearest compatible centroids (the search state), exactly as `search` finds them. Where the buckets that
// can hold a compatible centroid hold at most options.y centroids (a point on a crease or a narrow face, whose
// compatible centroids are few and may be far), they are scanned whole instead of walking the grid shell by
// shell until F are found, which can visit every cell. A compatible centroid lies within acos(n_t) of the point's
// normal and within its bucket's spread of the bucket's axis, so a bucket whose axis is farther than both (plus
// a margin for rounding) holds none. When none is compatible, the nearest by position is the grid's (F = 1, every
// centroid compatible), as the exhausted search would find it.
fn find(p: vec3<f32>, n: vec3<f32>, f_max: u32) {
    if km.options.y == 0u || km.dims.w > 0u || !unit(n) {
        search(p, n, f_max);
        return;
    }
    var mask_lo = 0u;
    var mask_hi = 0u;
    var total = 0u;
    for (var b = 0u; b < NB; b++) {
        let limit = bitcast<f32>(atomicLoad(&work[nb_limits_base() + b]));
        if limit > -1.5 && dot(n, bucket_axis(b)) < limit {
            continue;
        }
        let count = atomicLoad(&work[nb_starts_base() + b + 1u]) - atomicLoad(&work[nb_starts_base() + b]);
        if count == 0u {
            continue;
        }
        total += count;
        if b < 32u {
            mask_lo |= 1u << b;
        } else {
            mask_hi |= 1u << (b - 32u);
        }
    }
    if total > km.options.y {
        search(p, n, f_max);
        return;
    }
    reset_best();
    for (var b = 0u; b < NB; b++) {
        let bit = select(mask_hi >> (b - 32u), mask_lo >> b, b < 32u) & 1u;
        if bit == 0u {
            continue;
        }
        let s = atomicLoad(&work[nb_starts_base() + b]);
        let e = atomicLoad(&work[nb_starts_base() + b + 1u]);
        for (var j = s; j < e; j++) {
            consider(atomicLoad(&work[nb_items_base() + j]), p, n, f_max);
        }
    }
    if best_n == 0u {
        all_compatible = true;
        search(p, n, 1u);
        all_compatible = false;
        let k = best_kl.x;
        let d = best_dl.x;
        reset_best();
        any_k = k;
        any_d = d;
    }
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
    let k = id.x;
    let kc = km.cluster_count;
    if k >= kc {
        return;
    }
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

@compute @workgroup_size(64)
fn grid_clear(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < km.cells {
        atomicStore(&work[counts_base() + id.x], 0u);
    }
    if id.x < NB {
        atomicStore(&work[nb_counts_base() + id.x], 0u);
        atomicStore(&work[nb_limits_base() + id.x], NONE);
    }
}

@compute @workgroup_size(64)
fn grid_count(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= km.cluster_count {
        return;
    }
    let c = centroid(k);
    if c.position.w > 0.5 {
        atomicAdd(&work[counts_base() + cell_index(cell_of(c.position.xyz))], 1u);
        // The bucket's cone: the least cosine between its axis and a member's normal (order-preserving as the
        // bits of cos + 2); a normal that is not unit opens the cone whole, so its bucket is never skipped.
        let n = c.normal.xyz;
        let b = normal_bucket(n);
        atomicAdd(&work[nb_counts_base() + b], 1u);
        var cosine = -1.0;
        if unit(n) {
            cosine = clamp(dot(n, bucket_axis(b)), -1.0, 1.0);
        }
        atomicMin(&work[nb_limits_base() + b], bitcast<u32>(cosine + 2.0));
    }
}

var<workgroup> scan_partial: array<u32, 256>;

// One workgroup: exclusive prefix sum of the cell counts into the starts; the counts become the fill cursors.
@compute @workgroup_size(256)
fn grid_scan(@builtin(local_invocation_id) lid: vec3<u32>) {
    let t = lid.x;
    let cells = km.cells;
    let chunk = (cells + 255u) / 256u;
    let first = min(t * chunk, cells);
    let last = min(first + chunk, cells);
    var sum = 0u;
    for (var c = first; c < last; c++) {
        sum += atomicLoad(&work[counts_base() + c]);
    }
    scan_partial[t] = sum;
    workgroupBarrier();
    if t == 0u {
        var running = 0u;
        for (var i = 0u; i < 256u; i++) {
            let v = scan_partial[i];
            scan_partial[i] = running;
            running += v;
        }
        atomicStore(&work[starts_base() + cells], running);
        // The normal buckets (64, one invocation is enough): starts, fill cursors, and each bucket's limit: the
        // least cosine between a point's normal and the axis for which a member can be within acos(n_t).
        var nb_running = 0u;
        let theta = acos(clamp(km.n_t, -1.0, 1.0));
        for (var b = 0u; b < NB; b++) {
            let n = atomicLoad(&work[nb_counts_base() + b]);
            atomicStore(&work[nb_starts_base() + b], nb_running);
            atomicStore(&work[nb_counts_base() + b], 0u);
            nb_running += n;
            var limit = -2.0;
            if n > 0u {
                let spread = acos(clamp(bitcast<f32>(atomicLoad(&work[nb_limits_base() + b])) - 2.0, -1.0, 1.0));
                let reach = theta + spread + NB_MARGIN;
                if reach < 3.14159 {
                    limit = cos(reach);
                }
            }
            atomicStore(&work[nb_limits_base() + b], bitcast<u32>(limit));
        }
        atomicStore(&work[nb_starts_base() + NB], nb_running);
    }
    workgroupBarrier();
    var running = scan_partial[t];
    for (var c = first; c < last; c++) {
        let n = atomicLoad(&work[counts_base() + c]);
        atomicStore(&work[starts_base() + c], running);
        atomicStore(&work[counts_base() + c], 0u);
        running += n;
    }
}

@compute @workgroup_size(64)
fn grid_fill(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= km.cluster_count {
        return;
    }
    let c = centroid(k);
    if c.position.w > 0.5 {
        let cell = cell_index(cell_of(c.position.xyz));
        let slot = atomicLoad(&work[starts_base() + cell]) + atomicAdd(&work[counts_base() + cell], 1u);
        atomicStore(&work[items_base() + slot], k);
        let b = normal_bucket(c.normal.xyz);
        let nb_slot = atomicLoad(&work[nb_starts_base() + b]) + atomicAdd(&work[nb_counts_base() + b], 1u);
        atomicStore(&work[nb_items_base() + nb_slot], k);
    }
}

@compute @workgroup_size(64)
fn acc_clear(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= km.cluster_count {
        return;
    }
    for (var j = 0u; j < ACC; j++) {
        atomicStore(&work[k * ACC + j], 0u);
    }
    atomicStore(&work[k * ACC + ACC_BEST], NONE);
    atomicStore(&work[k * ACC + ACC_REP], NONE);
    if k == 0u {
        atomicStore(&work[queue_base()], 0u);
    }
}

// The nearest cluster of a point: entry 0 of the search, or the nearest by position when none is compatible.
fn nearest_cluster(p: KmPoint) -> u32 {
    find(p.position.xyz, p.normal.xyz, 1u);
    if best_n > 0u {
        return best_kl.x;
    }
    return any_k;
}

@compute @workgroup_size(64)
fn km_assign(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let s = global_index(id, groups);
    if s >= km.sample_count {
        return;
    }
    let p = km_points[sample_point(s)];
    if !point_valid(p) {
        return;
    }
    let k = nearest_cluster(p);
    if k == NONE {
        return;
    }
    accumulate_position(k, p);
    accumulate_normal(k, p);
    atomicAdd(&work[k * ACC + ACC_COUNT], 1u);
}

@compute @workgroup_size(64)
fn km_update(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= km.cluster_count {
        return;
    }
    let count = atomicLoad(&work[k * ACC + ACC_COUNT]);
    let c = centroid(k);
    if c.position.w < 0.5 || count == 0u {
        return;
    }
    let base = k * ACC;
    let n = f32(count) * FIXED;
    let f = vec3<f32>(read64(base + 0u) / n, read64(base + 2u) / n, read64(base + 4u) / n);
    let position = km.bounds_min.xyz + f * km.bounds_extent.xyz;
    clusters[km.cluster_count + k] =
        KmPoint(vec4<f32>(position, 1.0), vec4<f32>(mean_normal(k, count, c.normal.xyz), 0.0), vec4<f32>(0.0));
}

// Algorithm 2's output for point m: its F entries (the search state), and entry 0's cluster counts the point
// as a member (count, the least member distance for the representative; with flux, normal and flux sums).
fn record(m: u32, p: KmPoint, f_max: u32) {
    let base = m * f_max * 2u;
    var first = NONE;
    var first_d = 0.0;
    if best_n == 0u {
        first = any_k;
        first_d = any_d;
        if first != NONE {
            assignment[base] = first;
        }
    } else {
        first = best_kl.x;
        first_d = best_dl.x;
        for (var f = 0u; f < best_n; f++) {
            assignment[base + 2u * f] = best_k(f);
            assignment[base + 2u * f + 1u] = bitcast<u32>(1.0 / max(best_d(f), km.min_distance));
        }
    }
    if first == NONE {
        return;
    }
    let acc = first * ACC;
    atomicAdd(&work[acc + ACC_COUNT], 1u);
    atomicMin(&work[acc + ACC_BEST], bitcast<u32>(first_d));
    // The mean normal and the flux are only used for clusters of VPLs (rep_finish).
    if km.has_flux == 1u {
        accumulate_normal(first, p);
        let flux = p.flux.rgb * km.flux_scale.x;
        add64(acc + ACC_FLUX + 0u, quantize(flux.r));
        add64(acc + ACC_FLUX + 2u, quantize(flux.g));
        add64(acc + ACC_FLUX + 4u, quantize(flux.b));
    }
}

fn clear_entries(m: u32, f_max: u32) {
    let base = m * f_max * 2u;
    for (var f = 0u; f < f_max; f++) {
        assignment[base + 2u * f] = NONE;
        assignment[base + 2u * f + 1u] = 0u;
    }
}

fn neighbour_lists() -> bool {
    return km.options.x == 1u && km.gamma > 1u;
}

// Algorithm 2: the F nearest clusters of every point and their inverse distances, by the grid search; with
// neighbour lists, of the samples only (one invocation per sample).
@compute @workgroup_size(64)
fn km_final(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    var m = global_index(id, groups);
    if neighbour_lists() {
        if m >= km.sample_count {
            return;
        }
        m = sample_point(m);
    }
    if m >= km.point_count {
        return;
    }
    let f_max = clamp(km.fuzziness, 1u, MAX_F);
    clear_entries(m, f_max);
    let p = km_points[m];
    if !point_valid(p) {
        return;
    }
    find(p.position.xyz, p.normal.xyz, f_max);
    record(m, p, f_max);
}

// A candidate from a neighbouring sample's list, once.
fn consider_once(k: u32, p: vec3<f32>, n: vec3<f32>, f_max: u32) {
    if !listed(k) {
        consider(k, p, n, f_max);
    }
}

// Algorithm 2 for the points off the sample grid (after km_final over the samples): the F nearest among the
// clusters the four samples around the point list, by equation 7; the grid search where fewer than F of them
// are compatible (kmeans.rs `sample_corners`, `neighbour_lists`).
@compute @workgroup_size(64)
fn km_fill(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let m = global_index(id, groups);
    if m >= km.point_count {
        return;
    }
    let g = km.gamma;
    let w = max(km.width, 1u);
    let h = max(km.height, 1u);
    let x = m % w;
    let y = m / w;
    if x % g == 0u && y % g == 0u {
        return;
    }
    let f_max = clamp(km.fuzziness, 1u, MAX_F);
    clear_entries(m, f_max);
    let p = km_points[m];
    if !point_valid(p) {
        return;
    }
    reset_best();
    let x0 = x / g * g;
    let y0 = y / g * g;
    let x1 = min(x0 + g, (w - 1u) / g * g);
    let y1 = min(y0 + g, (h - 1u) / g * g);
    let corners = array<u32, 4>(y0 * w + x0, y0 * w + x1, y1 * w + x0, y1 * w + x1);
    for (var c = 0u; c < 4u; c++) {
        let s = corners[c];
        if s >= km.point_count {
            continue;
        }
        for (var f = 0u; f < f_max; f++) {
            let k = assignment[s * f_max * 2u + 2u * f];
            if k == NONE {
                break;
            }
            consider_once(k, p.position.xyz, p.normal.xyz, f_max);
        }
    }
    if best_n < f_max {
        // The grid search is long where it is needed (few compatible clusters near a crease): it goes to a
        // queue of its own (km_search) so that the invocations beside it do not wait for it.
        let q = atomicAdd(&work[queue_base()], 1u);
        atomicStore(&work[queue_base() + 1u + q], m);
        return;
    }
    record(m, p, f_max);
}

// The points km_fill queued: the grid search.
@compute @workgroup_size(64)
fn km_search(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = global_index(id, groups);
    if i >= atomicLoad(&work[queue_base()]) {
        return;
    }
    let m = atomicLoad(&work[queue_base() + 1u + i]);
    let f_max = clamp(km.fuzziness, 1u, MAX_F);
    let p = km_points[m];
    find(p.position.xyz, p.normal.xyz, f_max);
    record(m, p, f_max);
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
