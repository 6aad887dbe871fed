// The grid of fuzzy/kmeans.wgsl (concatenated after it): its levels (the coarse cells and finer hashed ones), and
// the passes that build it from the working centroids every iteration: grid_clear, grid_count, then on a CPU
// rasterizer grid_scan (which fills), on a real GPU grid_sums, grid_scan, grid_starts and grid_fill.

// The grid has levels, each holding every centroid, so that a search in any finds the same clusters: the coarse
// (level 0; kmeans.rs `grid_shape`, the twin's grid) and up to three finer ones, each 4 times finer along each
// axis than the one before, whose cells go to a hash table each (their count would be 64 times the coarser
// one's). A point whose cell holds more than fine.z centroids searches the next finer level: the centroids follow
// the pixels, so near the camera a coarse cell can hold hundreds of them (on the H200, Sponza's 2-shell walks
// alone took 1.3 ms per iteration: docs/techniques/fuzzy.md, nineteenth session). A hash cell holds its cell's
// centroids and maybe others': a search considers each centroid in its own cell only.
// The finer levels are a real GPU's only (gpu.rs `encode`): GPU_SCHEDULE, a pipeline constant, leaves a CPU
// rasterizer's kernels the coarse level's code alone (with the levels' code compiled in, lavapipe's clustering
// took 1-2 points more of the orbit's frame).
fn level_cell(l: u32) -> f32 {
    if !GPU_SCHEDULE || l == 0u {
        return km.cell;
    }
    // A power of two: every use of a level's cell is the same float.
    return km.cell / f32(1u << (2u * l));
}

fn level_dims(l: u32) -> vec3<i32> {
    if !GPU_SCHEDULE || l == 0u {
        return vec3<i32>(km.dims.xyz);
    }
    return vec3<i32>(km.dims.xyz * (1u << (2u * l)));
}

fn cell_of(p: vec3<f32>, l: u32) -> vec3<i32> {
    let c = floor((p - km.bounds_min.xyz) / level_cell(l));
    let top = vec3<f32>(level_dims(l)) - 1.0;
    return vec3<i32>(clamp(c, vec3<f32>(0.0), top));
}

// The cell's index into the counts and starts: the coarse level's cells, then each finer level's hash table.
fn cell_index(c: vec3<i32>, l: u32) -> u32 {
    let u = vec3<u32>(c);
    if GPU_SCHEDULE && l > 0u {
        let h = (u.x * 73856093u) ^ (u.y * 19349663u) ^ (u.z * 83492791u);
        return km.cells + (l - 1u) * km.fine.y + (h & (km.fine.y - 1u));
    }
    return u.x + km.dims.x * (u.y + km.dims.y * u.z);
}

// The cells of all levels (the counts and starts).
fn all_cells() -> u32 {
    return km.cells + km.fine.x * km.fine.y;
}

// The level a search around p uses: the first whose cell around p holds at most fine.z centroids, or the finest
// (always the coarse level for the paper's ring-limited search, whose rings are its cells).
fn level_of(p: vec3<f32>) -> u32 {
    if !GPU_SCHEDULE || km.dims.w > 0u {
        return 0u;
    }
    var l = 0u;
    loop {
        if l >= km.fine.x {
            break;
        }
        let i = cell_index(cell_of(p, l), l);
        if grid[starts_base() + i + 1u] - grid[starts_base() + i] <= km.fine.z {
            break;
        }
        l++;
    }
    return l;
}

// The grid's cell counts and the normal buckets cleared, and the clusters' accumulators (and the search queue)
// for the assignment that follows the grid: entry i of each, one dispatch over max(cells, NB, K). grid_clear runs
// before a run's first grid only: every later grid follows a km_update, which clears them as it goes (a grid's
// counts are read only by the grid's own passes, the accumulators only by km_update and the representatives'
// passes, the queue by the searches before it; one dispatch less per iteration).
fn clear_for_grid(i: u32) {
    if i < all_cells() {
        atomicStore(&work[counts_base() + i], 0u);
    }
    if i < NB {
        atomicStore(&work[nb_counts_base() + i], 0u);
        atomicStore(&work[nb_least_base() + i], NONE);
    }
    if i < km.cluster_count {
        for (var j = 0u; j < ACC; j++) {
            atomicStore(&work[i * ACC + j], 0u);
        }
        atomicStore(&work[i * ACC + ACC_BEST], NONE);
        atomicStore(&work[i * ACC + ACC_REP], NONE);
    }
    if i == 0u {
        atomicStore(&work[queue_base()], 0u);
    }
}

@compute @workgroup_size(64)
fn grid_clear(@builtin(global_invocation_id) id: vec3<u32>) {
    clear_for_grid(id.x);
}

@compute @workgroup_size(64)
fn grid_count(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= km.cluster_count {
        return;
    }
    let c = centroid(k);
    if c.position.w > 0.5 {
        for (var l = 0u; l <= km.fine.x; l++) {
            atomicAdd(&work[counts_base() + cell_index(cell_of(c.position.xyz, l), l)], 1u);
        }
        // The bucket's cone: the least cosine between its axis and a member's normal (order-preserving as the
        // bits of cos + 2); a normal that is not unit opens the cone whole, so its bucket is never skipped.
        let n = c.normal.xyz;
        let b = normal_bucket(n);
        atomicAdd(&work[nb_counts_base() + b], 1u);
        var cosine = -1.0;
        if unit(n) {
            cosine = clamp(dot(n, bucket_axis(b)), -1.0, 1.0);
        }
        atomicMin(&work[nb_least_base() + b], bitcast<u32>(cosine + 2.0));
    }
}

var<workgroup> scan_partial: array<u32, 256>;
var<workgroup> scan_buckets: array<u32, NB>;

// What grid_scan sums: on a CPU rasterizer the cells' counts, on a real GPU their sums per block of 256.
fn scan_value(i: u32) -> u32 {
    if GPU_SCHEDULE {
        return grid[scan_blocks_base() + i];
    }
    return atomicLoad(&work[counts_base() + i]);
}

// One workgroup: exclusive prefix sum of the cell counts into the starts, the counts becoming the fill cursors,
// and the normal buckets' starts and limits (an invocation each); then, on a CPU rasterizer, the centroids into
// their cells and normal buckets (one dispatch instead of two: there a dispatch costs about as much as filling a
// few thousand centroids). A real GPU's schedule spreads the work over the GPU (on the H200 the single
// workgroup's scan over every cell took 0.06-0.09 ms of each iteration): grid_sums sums the counts per block of
// 256 cells, this workgroup scans those sums, grid_starts scans each block from its sum's start, and grid_fill
// fills the centroids, an invocation each.
@compute @workgroup_size(256)
fn grid_scan(@builtin(local_invocation_id) lid: vec3<u32>) {
    let t = lid.x;
    let cells = all_cells();
    let values = select(cells, scan_blocks(), GPU_SCHEDULE);
    let chunk = (values + 255u) / 256u;
    let first = min(t * chunk, values);
    let last = min(first + chunk, values);
    var sum = 0u;
    for (var c = first; c < last; c++) {
        sum += scan_value(c);
    }
    scan_partial[t] = sum;
    if t < NB {
        scan_buckets[t] = atomicLoad(&work[nb_counts_base() + t]);
    }
    workgroupBarrier();
    if t == 0u {
        var running = 0u;
        for (var i = 0u; i < 256u; i++) {
            let v = scan_partial[i];
            scan_partial[i] = running;
            running += v;
        }
        grid[starts_base() + cells] = running;
    }
    if t < NB {
        // Bucket t: its start, fill cursor, and limit: the least cosine between a point's normal and the axis for
        // which a member can be within acos(n_t).
        var start = 0u;
        for (var b = 0u; b < t; b++) {
            start += scan_buckets[b];
        }
        let n = scan_buckets[t];
        grid[nb_starts_base() + t] = start;
        atomicStore(&work[nb_counts_base() + t], 0u);
        if t == NB - 1u {
            grid[nb_starts_base() + NB] = start + n;
        }
        var limit = -2.0;
        if n > 0u {
            let theta = acos(clamp(km.n_t, -1.0, 1.0));
            let spread = acos(clamp(bitcast<f32>(atomicLoad(&work[nb_least_base() + t])) - 2.0, -1.0, 1.0));
            let reach = theta + spread + NB_MARGIN;
            if reach < 3.14159 {
                limit = cos(reach);
            }
        }
        grid[nb_limits_base() + t] = bitcast<u32>(limit);
    }
    workgroupBarrier();
    var running = scan_partial[t];
    for (var c = first; c < last; c++) {
        let n = scan_value(c);
        if GPU_SCHEDULE {
            grid[scan_blocks_base() + c] = running;
        } else {
            grid[starts_base() + c] = running;
            atomicStore(&work[counts_base() + c], 0u);
        }
        running += n;
    }
    if !GPU_SCHEDULE {
        storageBarrier();
        for (var k = t; k < km.cluster_count; k += 256u) {
            fill_cell(k);
        }
    }
}

var<workgroup> block_scan: array<u32, 256>;

// Block `wid`'s 256 cell counts: their inclusive prefix sums in `block_scan` (Hillis-Steele), the count of cell
// `i` returned.
fn scan_block(i: u32, t: u32) -> u32 {
    var v = 0u;
    if i < all_cells() {
        v = atomicLoad(&work[counts_base() + i]);
    }
    block_scan[t] = v;
    workgroupBarrier();
    for (var o = 1u; o < 256u; o <<= 1u) {
        var add = 0u;
        if t >= o {
            add = block_scan[t - o];
        }
        workgroupBarrier();
        block_scan[t] += add;
        workgroupBarrier();
    }
    return v;
}

// A real GPU's schedule: each block of 256 cells' total count (before grid_scan).
@compute @workgroup_size(256)
fn grid_sums(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    scan_block(wid.x * 256u + lid.x, lid.x);
    if lid.x == 255u {
        grid[scan_blocks_base() + wid.x] = block_scan[255];
    }
}

// A real GPU's schedule: each cell's start from its block's (grid_scan) and the counts before it in the block;
// the counts become the fill cursors (after grid_scan).
@compute @workgroup_size(256)
fn grid_starts(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let i = wid.x * 256u + lid.x;
    let v = scan_block(i, lid.x);
    if i < all_cells() {
        grid[starts_base() + i] = grid[scan_blocks_base() + wid.x] + block_scan[lid.x] - v;
        atomicStore(&work[counts_base() + i], 0u);
    }
}

// A real GPU's schedule: the centroids into their cells and buckets, one invocation each (after grid_starts).
@compute @workgroup_size(64)
fn grid_fill(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < km.cluster_count {
        fill_cell(id.x);
    }
}

// Centroid k into its cell's and its normal bucket's lists (the starts scanned, the cursors at zero).
fn fill_cell(k: u32) {
    let c = centroid(k);
    if c.position.w > 0.5 {
        for (var l = 0u; l <= km.fine.x; l++) {
            let cell = cell_index(cell_of(c.position.xyz, l), l);
            let slot = grid[starts_base() + cell] + atomicAdd(&work[counts_base() + cell], 1u);
            grid[items_base() + slot] = k;
        }
        let b = normal_bucket(c.normal.xyz);
        let nb_slot = grid[nb_starts_base() + b] + atomicAdd(&work[nb_counts_base() + b], 1u);
        grid[nb_items_base() + nb_slot] = k;
    }
}
