// The search of fuzzy/kmeans.wgsl (concatenated after it): the F nearest compatible centroids of a point, by the
// grid walked shell by shell (kmeans.rs `Grid::nearest`) or, where they are few, by the normal buckets.

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
    consider_centroid(k, centroid(k), p, n, f_max);
}

fn consider_centroid(k: u32, c: KmPoint, p: vec3<f32>, n: vec3<f32>, f_max: u32) {
    if COUNT_WORK {
        counted_centroids += 1u;
    }
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
fn cell_distance(c: vec3<i32>, l: u32, p: vec3<f32>) -> f32 {
    let lo = km.bounds_min.xyz + vec3<f32>(c) * level_cell(l);
    let hi = lo + vec3<f32>(level_cell(l));
    let top = level_dims(l) - 1;
    let below = select(lo - p, vec3<f32>(0.0), c == vec3<i32>(0));
    let above = select(p - hi, vec3<f32>(0.0), c == top);
    return length(max(max(below, above), vec3<f32>(0.0)));
}

// A cell farther than the F-th centroid found cannot change the list once it is full.
fn visit_cell(c: vec3<i32>, l: u32, p: vec3<f32>, n: vec3<f32>, f_max: u32) {
    if best_n == f_max && cell_distance(c, l, p) > best_d(f_max - 1u) {
        return;
    }
    if COUNT_WORK {
        counted_cells += 1u;
    }
    let i = cell_index(c, l);
    let s = grid[starts_base() + i];
    let e = grid[starts_base() + i + 1u];
    if GPU_SCHEDULE {
        near_steps += 1u + e - s;
    }
    for (var j = s; j < e; j++) {
        let k = grid[items_base() + j];
        let ck = centroid(k);
        // A fine cell's hash slot may hold other cells' centroids: each is considered in its own cell only (a
        // walk can meet a slot more than once).
        if GPU_SCHEDULE && l > 0u && any(cell_of(ck.position.xyz, l) != c) {
            continue;
        }
        consider_centroid(k, ck, p, n, f_max);
    }
}

// How far every centroid outside the block of radius r around cell c is from p at least: the distance to the
// block's nearest face with cells beyond it (kmeans.rs `Grid::guarantee`).
fn guarantee(p: vec3<f32>, c: vec3<i32>, l: u32, r: i32) -> f32 {
    var g = 3.0e38;
    let cell = level_cell(l);
    let dims = level_dims(l);
    for (var a = 0; a < 3; a++) {
        if c[a] - r > 0 {
            g = min(g, p[a] - (km.bounds_min[a] + f32(c[a] - r) * cell));
        }
        if c[a] + r < dims[a] - 1 {
            g = min(g, km.bounds_min[a] + f32(c[a] + r + 1) * cell - p[a]);
        }
    }
    return g;
}

// Shell by shell (Chebyshev radius r) from the point's cell: at least the 27 cells of the paper, more until the
// F-th distance found is within the guarantee (every unvisited centroid is farther) or the grid is exhausted.
fn search(p: vec3<f32>, n: vec3<f32>, f_max: u32) {
    reset_best();
    search_shells(p, n, f_max, 0x7fffffff, 0u);
}

// The cells and centroids a bounded search has visited (a real GPU's schedule).
var<private> near_steps: u32;

// The shells around p in its level (`level_of`) until the search is finished (true) or, unfinished (false),
// after shell max_r, FINE_SHELLS more in a finer level, whose cells are smaller, or after a row of cells that
// brings the cells and centroids it visited past `budget` (0: none) (a real GPU's schedule, whose dispatch lasts
// as long as its longest search; `search` walks without the bounds; with its own copy of the loop instead,
// lavapipe's clustering measured the same).
const FINE_SHELLS: i32 = 2;

fn search_shells(p: vec3<f32>, n: vec3<f32>, f_max: u32, near_r: i32, budget: u32) -> bool {
    near_steps = 0u;
    let l = level_of(p);
    let max_r = select(near_r, near_r + FINE_SHELLS, GPU_SCHEDULE && l > 0u && near_r < 0x7fff0000);
    let c = cell_of(p, l);
    let dims = level_dims(l);
    let far = max(c, dims - 1 - c);
    let reach = max(far.x, max(far.y, far.z));
    var r = 0;
    var finished = false;
    loop {
        let lo = max(c - vec3<i32>(r), vec3<i32>(0));
        let hi = min(c + vec3<i32>(r), dims - 1);
        for (var z = lo.z; z <= hi.z; z++) {
            for (var y = lo.y; y <= hi.y; y++) {
                if abs(z - c.z) == r || abs(y - c.y) == r {
                    for (var x = lo.x; x <= hi.x; x++) {
                        visit_cell(vec3<i32>(x, y, z), l, p, n, f_max);
                    }
                } else {
                    if c.x - r >= 0 {
                        visit_cell(vec3<i32>(c.x - r, y, z), l, p, n, f_max);
                    }
                    if c.x + r < dims.x {
                        visit_cell(vec3<i32>(c.x + r, y, z), l, p, n, f_max);
                    }
                }
                if GPU_SCHEDULE && budget > 0u && near_steps > budget {
                    return false;
                }
            }
        }
        let complete = best_n == f_max && best_d(f_max - 1u) <= guarantee(p, c, l, r);
        // dims.w > 0: stop after that ring once a compatible centroid is found (1: the paper's 27 cells).
        let ring_done = km.dims.w > 0u && r >= i32(km.dims.w) && best_n > 0u;
        if (r >= 1 && (complete || ring_done)) || r >= reach {
            finished = true;
            break;
        }
        if r >= max_r {
            break;
        }
        r++;
    }
    return finished;
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

// The F nearest compatible centroids (the search state), exactly as `search` finds them (a CPU rasterizer's
// schedule; a real GPU's is `find_near` and the workgroup-wide `wide_find` below). Where the buckets that can
// hold a compatible centroid hold at most options.y centroids (a point on a crease or a narrow face, whose
// compatible centroids are few and may be far), a search for F > 1 scans them whole instead of walking the grid
// shell by shell until F are found, which can visit every cell. A compatible centroid lies within acos(n_t) of
// the point's normal and within its bucket's spread of the bucket's axis, so a bucket whose axis is farther than
// both (plus a margin for rounding) holds none. When none is compatible, the nearest by position is the grid's
// (F = 1, every centroid compatible), as the exhausted search would find it. The nearest alone (F = 1:
// Algorithm 1's assignment) walks the grid (its first shells hold it, and counting the buckets for every point
// took twice as long on lavapipe: sixteenth session), and so does a search whose buckets hold more than
// options.y centroids.
fn find(p: vec3<f32>, n: vec3<f32>, f_max: u32) {
    if !bucket_scan(n) || f_max == 1u {
        search(p, n, f_max);
        return;
    }
    reset_best();
    var mask_lo = 0u;
    var mask_hi = 0u;
    var total = 0u;
    for (var b = 0u; b < NB; b++) {
        if compatible_bucket(b, n) {
            let count = grid[nb_starts_base() + b + 1u] - grid[nb_starts_base() + b];
            total += count;
            if count > 0u && b < 32u {
                mask_lo |= 1u << b;
            } else if count > 0u {
                mask_hi |= 1u << (b - 32u);
            }
        }
    }
    if total > km.options.y {
        search(p, n, f_max);
        return;
    }
    for (var b = 0u; b < NB; b++) {
        let bit = select(mask_hi >> (b - 32u), mask_lo >> b, b < 32u) & 1u;
        if bit == 0u {
            continue;
        }
        let s = grid[nb_starts_base() + b];
        let e = grid[nb_starts_base() + b + 1u];
        for (var j = s; j < e; j++) {
            consider(grid[nb_items_base() + j], p, n, f_max);
        }
    }
    if best_n == 0u {
        nearest_by_position(p, n);
    }
}

// Whether the normal buckets may serve the search of a point of normal n (else only the grid does: the paper's
// ring-limited search, a bucket scan limit of 0, a normal that is not unit).
fn bucket_scan(n: vec3<f32>) -> bool {
    return km.options.y > 0u && km.dims.w == 0u && unit(n);
}

// Whether bucket b can hold a centroid compatible with normal n.
fn compatible_bucket(b: u32, n: vec3<f32>) -> bool {
    let limit = bitcast<f32>(grid[nb_limits_base() + b]);
    return !(limit > -1.5 && dot(n, bucket_axis(b)) < limit);
}

// No compatible centroid: the nearest by position (the grid's, F = 1, every centroid compatible) as `any`.
fn nearest_by_position(p: vec3<f32>, n: vec3<f32>) {
    all_compatible = true;
    search(p, n, 1u);
    all_compatible = false;
    let k = best_kl.x;
    let d = best_dl.x;
    reset_best();
    any_k = k;
    any_d = d;
}

// A real GPU's schedule (GPU_SCHEDULE true). A dispatch lasts as long as its slowest invocation, and a point whose
// compatible centroids are far (a crease, a chair's leg, a surface that came into view since a warm start's
// centroids were placed) walks far: on the H200 at 1024x720 such walks made the shading points' clustering 69-81 %
// of a moving camera's frame (docs/techniques/fuzzy.md, eighteenth and nineteenth sessions). So every point walks
// the grid's first options.w shells (`find_near`: finished there for most points, exactly as `search`), and a
// point they leave unfinished is queued for a workgroup of its own (`km_assign_wide`, `km_search_wide`), whose 64
// invocations scan the compatible buckets' centroids together (`wide_find`), as `find` would scan them alone.

// True when the search of p finished within the first options.w shells (or the buckets cannot serve it, and the
// grid search ran whole here); false: the point goes to the workgroup-wide search.
fn find_near(p: vec3<f32>, n: vec3<f32>, f_max: u32) -> bool {
    if !bucket_scan(n) {
        search(p, n, f_max);
        return true;
    }
    reset_best();
    return search_shells(p, n, f_max, i32(km.options.w), km.sched.x);
}

const WIDE: u32 = 64u;
var<workgroup> wide_ok: array<u32, NB>;
var<workgroup> wide_d: array<f32, 512>;
var<workgroup> wide_k: array<u32, 512>;
var<workgroup> wide_point: u32;
var<workgroup> wide_found: u32;

// The queued point of this workgroup (NONE past the queue's end), the same for all its invocations.
fn wide_item(wid: vec3<u32>, groups: vec3<u32>, t: u32) -> u32 {
    if t == 0u {
        let i = wid.x + wid.y * groups.x;
        var m = NONE;
        if i < atomicLoad(&work[queue_base()]) {
            m = atomicLoad(&work[queue_base() + 1u + i]);
        }
        wide_point = m;
    }
    return workgroupUniformLoad(&wide_point);
}

// The workgroup's queued point (NONE past the queue's end), searched by `wide_find` and counted as `kind`:
// invocation 0's search state holds its F nearest (km_assign_wide, km_search_wide).
fn wide_search(wid: vec3<u32>, groups: vec3<u32>, t: u32, f_max: u32, kind: u32) -> u32 {
    let m = wide_item(wid, groups, t);
    if m == NONE {
        return NONE;
    }
    let p = km_points[m];
    wide_find(p.position.xyz, p.normal.xyz, f_max, t);
    count_search(kind, t == 0u, false);
    return m;
}

// Invocation t's F nearest to the workgroup's memory; invocation 0 merges the WIDE lists into its search state
// (each centroid is in one list: no duplicates) and tells the workgroup how many it holds.
fn wide_merge(f_max: u32, t: u32) -> u32 {
    for (var f = 0u; f < MAX_F; f++) {
        wide_d[t * MAX_F + f] = best_d(f);
        wide_k[t * MAX_F + f] = best_k(f);
    }
    workgroupBarrier();
    if t == 0u {
        reset_best();
        for (var i = 0u; i < WIDE; i++) {
            for (var f = 0u; f < f_max; f++) {
                let k = wide_k[i * MAX_F + f];
                let d = wide_d[i * MAX_F + f];
                // Each list is sorted: the rest of it is farther.
                if k == NONE || (best_n == f_max && !less(d, k, best_d(f_max - 1u), best_k(f_max - 1u))) {
                    break;
                }
                insert_best(d, k, f_max);
            }
        }
        wide_found = best_n;
    }
    return workgroupUniformLoad(&wide_found);
}

// `find` by the workgroup: the compatible buckets' centroids scanned by all WIDE invocations, invocation 0's search
// state holding the F nearest (or, when none is compatible, the nearest by position as `any`, from every active
// centroid). (A walk of the grid by the workgroup, shell by shell, before the scan was tried: exact, but on the
// conference room at 1024x720 it did as much work as the scan, 6.7 million cells and 13.9 million centroids
// against 20.7 million centroids, and more in its longest invocation, 302 steps against 85: the points queued
// here have no F compatible centroids near them. Lists per normal bucket and cell 4 times coarser than the grid's,
// walked by the workgroup near the point first, were tried too: exact, 3.4 times fewer centroids considered on the
// conference room, 6.1 against 20.7 million, but a crowded cell made one invocation's work 10 times the scan's
// longest, 841 steps against 85, and a workgroup waits for it; not timed on a GPU, backed out.)
fn wide_find(p: vec3<f32>, n: vec3<f32>, f_max: u32, t: u32) {
    wide_ok[t] = u32(compatible_bucket(t, n));
    workgroupBarrier();
    reset_best();
    for (var b = 0u; b < NB; b++) {
        if wide_ok[b] == 0u {
            continue;
        }
        let s = grid[nb_starts_base() + b];
        let e = grid[nb_starts_base() + b + 1u];
        for (var j = s + t; j < e; j += WIDE) {
            consider(grid[nb_items_base() + j], p, n, f_max);
        }
    }
    if wide_merge(f_max, t) > 0u {
        return;
    }
    reset_best();
    all_compatible = true;
    for (var k = t; k < km.cluster_count; k += WIDE) {
        if centroid(k).position.w > 0.5 {
            consider(k, p, n, 1u);
        }
    }
    all_compatible = false;
    wide_merge(1u, t);
    if t == 0u {
        let k = best_kl.x;
        let d = best_dl.x;
        reset_best();
        any_k = k;
        any_d = d;
    }
}
