// Algorithm 2 of fuzzy/kmeans.wgsl (concatenated after it): every point's F nearest clusters with inverse
// distances and the members they make; with neighbour lists, the samples by the search (km_final), the four
// samples' lists merged per block of points between them (km_blocks), the points from their block's list
// (km_fill), the long searches in a dispatch of their own (km_search; on a real GPU km_search_wide, a workgroup
// per point, also for the samples km_final left unfinished, before km_blocks reads their lists).

// Algorithm 2's output for point m: its F entries (the search state), and entry 0's cluster counts the point
// as a member (count, the least member distance for the representative; with flux, normal and flux sums).
// Every one of the point's F entries is written (NONE and 0 past the clusters found), so no pass clears them.
fn record(m: u32, p: KmPoint, f_max: u32) {
    let base = m * f_max * 2u;
    var first = NONE;
    var first_d = 0.0;
    if best_n == 0u {
        first = any_k;
        first_d = any_d;
        assignment[base] = first;
        assignment[base + 1u] = 0u;
        for (var f = 1u; f < f_max; f++) {
            assignment[base + 2u * f] = NONE;
            assignment[base + 2u * f + 1u] = 0u;
        }
    } else {
        first = best_kl.x;
        first_d = best_dl.x;
        for (var f = 0u; f < f_max; f++) {
            var k = NONE;
            var w = 0u;
            if f < best_n {
                k = best_k(f);
                w = bitcast<u32>(1.0 / max(best_d(f), km.min_distance));
            }
            assignment[base + 2u * f] = k;
            assignment[base + 2u * f + 1u] = w;
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
    let p = km_points[m];
    if !point_valid(p) {
        clear_entries(m, f_max);
        return;
    }
    if GPU_SCHEDULE {
        if !find_near(p.position.xyz, p.normal.xyz, f_max) {
            enqueue(m);
            count_search(COUNT_FINAL, true, true);
            return;
        }
    } else {
        find(p.position.xyz, p.normal.xyz, f_max);
    }
    count_search(COUNT_FINAL, true, false);
    record(m, p, f_max);
}

// The lists of the blocks (with neighbour lists): after the points' F entries in `assignment`, per sample s
// the block of pixels it is the top left corner of, the clusters of its four samples' lists, each once: a count,
// then up to 4 F clusters.
fn block_base(s: u32, f_max: u32) -> u32 {
    return km.point_count * f_max * 2u + s * (1u + 4u * f_max);
}

// The samples (columns, rows) at the four corners of the block whose top left sample is (sx, sy): the next
// column and row, clamped to the last (the image's last pixels lie after the last sample).
fn block_corners(sx: u32, sy: u32) -> array<u32, 4> {
    let g = max(km.gamma, 1u);
    let w = max(km.width, 1u);
    let h = max(km.height, 1u);
    let sx1 = min(sx + 1u, (w - 1u) / g);
    let sy1 = min(sy + 1u, (h - 1u) / g);
    return array<u32, 4>(sy * g * w + sx * g, sy * g * w + sx1 * g, sy1 * g * w + sx * g, sy1 * g * w + sx1 * g);
}

// One invocation per block (after km_final over the samples): its four samples' lists in one, each cluster
// once, in the order a point of the block would consider them (sample by sample, each list nearest first). The
// gamma^2 - 1 points of the block read this list instead of merging the four themselves (kmeans.rs
// `sample_corners`; docs/techniques/fuzzy.md, seventeenth session).
@compute @workgroup_size(64)
fn km_blocks(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let s = global_index(id, groups);
    if s == 0u {
        // The queue of km_final's samples has been searched (a real GPU's schedule): km_fill's starts empty.
        atomicStore(&work[queue_base()], 0u);
    }
    if s >= km.sample_count {
        return;
    }
    let g = max(km.gamma, 1u);
    let per_row = (km.width + g - 1u) / g;
    let f_max = clamp(km.fuzziness, 1u, MAX_F);
    let corners = block_corners(s % per_row, s / per_row);
    let base = block_base(s, f_max);
    // The list so far in eight vectors of four (NONE where empty): a cluster is looked up with eight vector
    // comparisons and appended with eight selects, in registers (a CPU rasterizer's SIMD lanes diverge less
    // than with a loop over the list).
    var list = array<vec4<u32>, 8>(
        vec4<u32>(NONE), vec4<u32>(NONE), vec4<u32>(NONE), vec4<u32>(NONE),
        vec4<u32>(NONE), vec4<u32>(NONE), vec4<u32>(NONE), vec4<u32>(NONE)
    );
    var n = 0u;
    for (var c = 0u; c < 4u; c++) {
        let sample = corners[c];
        if sample >= km.point_count {
            continue;
        }
        for (var f = 0u; f < f_max; f++) {
            let k = assignment[sample * f_max * 2u + 2u * f];
            if k == NONE {
                break;
            }
            let kv = vec4<u32>(k);
            var seen = false;
            for (var v = 0u; v < 8u; v++) {
                seen = seen || any(list[v] == kv);
            }
            if !seen {
                assignment[base + 1u + n] = k;
                for (var v = 0u; v < 8u; v++) {
                    list[v] = select(list[v], kv, vec4<u32>(v * 4u) + vec4<u32>(0u, 1u, 2u, 3u) == vec4<u32>(n));
                }
                n++;
            }
        }
    }
    assignment[base] = n;
}

// Algorithm 2 for the points off the sample grid (after km_blocks): the F nearest among the clusters the four
// samples around the point list (its block's list), by equation 7; the grid search where fewer than F of them
// are compatible (kmeans.rs `sample_corners`, `neighbour_lists`).
@compute @workgroup_size(64)
fn km_fill(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let m = global_index(id, groups);
    if m >= km.point_count {
        return;
    }
    let g = km.gamma;
    let w = max(km.width, 1u);
    let x = m % w;
    let y = m / w;
    if x % g == 0u && y % g == 0u {
        return;
    }
    let f_max = clamp(km.fuzziness, 1u, MAX_F);
    let p = km_points[m];
    if !point_valid(p) {
        clear_entries(m, f_max);
        return;
    }
    reset_best();
    let base = block_base((y / g) * ((w + g - 1u) / g) + x / g, f_max);
    let n = assignment[base];
    for (var i = 0u; i < n; i++) {
        consider(assignment[base + 1u + i], p.position.xyz, p.normal.xyz, f_max);
    }
    if best_n < f_max && GPU_SCHEDULE {
        // A real GPU's schedule: the grid's first shells here, the workgroup-wide search where they do not finish.
        if !find_near(p.position.xyz, p.normal.xyz, f_max) {
            enqueue(m);
            count_search(COUNT_FILL, true, true);
            return;
        }
    } else if best_n < f_max {
        // The grid search is long where it is needed (few compatible clusters near a crease): on a CPU
        // rasterizer it goes to a queue of its own (km_search) so that the invocations beside it do not wait.
        enqueue(m);
        count_search(COUNT_FILL, true, true);
        return;
    }
    count_search(COUNT_FILL, true, false);
    record(m, p, f_max);
}

// One invocation: the workgroups of the search over the queue from its length (x at most 32,768, as
// `global_index` and `wide_item` expect; none when the queue is empty): km_search's 64 points a workgroup, or
// on a real GPU km_assign_wide's and km_search_wide's one.
@compute @workgroup_size(1)
fn queue_args() {
    let queued = atomicLoad(&work[queue_base()]);
    var g = (queued + 63u) / 64u;
    if GPU_SCHEDULE {
        g = queued;
    }
    search_args[0] = min(g, 32768u);
    search_args[1] = max((g + 32767u) / 32768u, 1u);
    search_args[2] = 1u;
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
    count_search(COUNT_SEARCH, true, false);
    record(m, p, f_max);
}

// A real GPU's schedule: the points (or samples) the grid's first shells left unfinished, a workgroup each.
@compute @workgroup_size(64)
fn km_search_wide(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                  @builtin(local_invocation_id) lid: vec3<u32>) {
    let f_max = clamp(km.fuzziness, 1u, MAX_F);
    let m = wide_search(wid, groups, lid.x, f_max, COUNT_SEARCH);
    if m != NONE && lid.x == 0u {
        record(m, km_points[m], f_max);
    }
}
