// Fuzzy K-means of surface points on the GPU (Colom et al. 2022, Algorithms 1 and 2), the twin of
// core/src/technique/fuzzy/kmeans.rs: the same samples (every gamma-th column and row), initial centroids (the
// first valid sample at or after k S / K), equation 7 (|p1 - p2| when n1 . n2 > n_t), grid search grown shell
// by shell from the 27 cells until provably complete, ties to the lower index, fixed-point means and the F
// nearest with inverse distances. WGSL has no float atomics: members add their position as a fraction of the
// bounds and their normal as (n + 1) / 2, times 2^24, into 64-bit sums made of two atomic u32 (the carry is
// added to the high word when the low word wraps), so a mean keeps 2^-24 of the bounds whatever the count.
// Entry points, one dispatch each, in this order (see gpu.rs): km_init; per iteration grid_clear, grid_count,
// grid_scan, grid_fill, acc_clear, km_assign, km_update; then the grid again, acc_clear, km_final, rep_pick,
// rep_finish. `KmParams`, `KmPoint` mirror core/src/technique/fuzzy/gpu.rs.

const MAX_F: u32 = 8u;
const NONE: u32 = 0xffffffffu;
const FIXED: f32 = 16777216.0;
// Words of `work` per cluster: position sums (lo, hi) x 3, normal sums (lo, hi) x 3, member count, best
// distance bits, representative, flux sums (lo, hi) x 3, 3 spare.
const ACC: u32 = 24u;
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
// K * ACC accumulators, then the grid: counts (cells), starts (cells + 1), items (K).
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

// The search state of one invocation: the F nearest compatible centroids, and the nearest by position.
var<private> best_d: array<f32, MAX_F>;
var<private> best_k: array<u32, MAX_F>;
var<private> best_n: u32;
var<private> any_d: f32;
var<private> any_k: u32;

fn less(d: f32, k: u32, d2: f32, k2: u32) -> bool {
    return d < d2 || (d == d2 && k < k2);
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
    if dot(n, c.normal.xyz) > km.n_t {
        if best_n == f_max && !less(d, k, best_d[f_max - 1u], best_k[f_max - 1u]) {
            return;
        }
        var at = best_n;
        for (var i = 0u; i < best_n; i++) {
            if less(d, k, best_d[i], best_k[i]) {
                at = i;
                break;
            }
        }
        if at < f_max {
            var j = min(best_n, f_max - 1u);
            while j > at {
                best_d[j] = best_d[j - 1u];
                best_k[j] = best_k[j - 1u];
                j--;
            }
            best_d[at] = d;
            best_k[at] = k;
            best_n = min(best_n + 1u, f_max);
        }
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
    if best_n == f_max && cell_distance(c, p) > best_d[f_max - 1u] {
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
    best_n = 0u;
    any_k = NONE;
    any_d = 3.0e38;
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
        let complete = best_n == f_max && best_d[f_max - 1u] <= guarantee(p, c, r);
        // dims.w > 0: stop after that ring once a compatible centroid is found (1: the paper's 27 cells).
        let ring_done = km.dims.w > 0u && r >= i32(km.dims.w) && best_n > 0u;
        if (r >= 1 && (complete || ring_done)) || r >= reach {
            break;
        }
        r++;
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
}

// The nearest cluster of a point: entry 0 of the search, or the nearest by position when none is compatible.
fn nearest_cluster(p: KmPoint) -> u32 {
    search(p.position.xyz, p.normal.xyz, 1u);
    if best_n > 0u {
        return best_k[0];
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

// Algorithm 2: the F nearest clusters of every point and their inverse distances; entry 0's cluster counts the
// point as a member (count, normal and flux sums, and the least member distance for the representative).
@compute @workgroup_size(64)
fn km_final(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let m = global_index(id, groups);
    if m >= km.point_count {
        return;
    }
    let f_max = clamp(km.fuzziness, 1u, MAX_F);
    let base = m * f_max * 2u;
    for (var f = 0u; f < f_max; f++) {
        assignment[base + 2u * f] = NONE;
        assignment[base + 2u * f + 1u] = 0u;
    }
    let p = km_points[m];
    if !point_valid(p) {
        return;
    }
    search(p.position.xyz, p.normal.xyz, f_max);
    var first = NONE;
    var first_d = 0.0;
    if best_n == 0u {
        first = any_k;
        first_d = any_d;
        if first != NONE {
            assignment[base] = first;
        }
    } else {
        first = best_k[0];
        first_d = best_d[0];
        for (var f = 0u; f < best_n; f++) {
            assignment[base + 2u * f] = best_k[f];
            assignment[base + 2u * f + 1u] = bitcast<u32>(1.0 / max(best_d[f], km.min_distance));
        }
    }
    if first == NONE {
        return;
    }
    let acc = first * ACC;
    atomicAdd(&work[acc + ACC_COUNT], 1u);
    accumulate_normal(first, p);
    atomicMin(&work[acc + ACC_BEST], bitcast<u32>(first_d));
    if km.has_flux == 1u {
        let flux = p.flux.rgb * km.flux_scale.x;
        add64(acc + ACC_FLUX + 0u, quantize(flux.r));
        add64(acc + ACC_FLUX + 2u, quantize(flux.g));
        add64(acc + ACC_FLUX + 4u, quantize(flux.b));
    }
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
