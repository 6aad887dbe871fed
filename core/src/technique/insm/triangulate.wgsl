// INSM step 3 (Wang et al. 2016, Algorithm 2): triangulate the intermediate shadow maps on the GPU.
//
// One workgroup per tile of TILE x TILE neighbourhoods of one image, one invocation per 2x2 neighbourhood whose
// top-left sample is (u, v) (u = x, v = y). The tile's samples and a halo are read from the depth atlas once into
// workgroup memory; the connectivity tests read them from there. The neighbourhood gives the triangles
//   [(u, v), (u, v+1), (u+1, v+1)] and [(u+1, v+1), (u+1, v), (u, v)],
// each kept when IsConnected holds for its three edges (`edge_connected`: both samples valid, not background,
// and the second-order differences at a and at b, |z(a - d) + z(b) - 2 z(a)| and |z(a) + z(b + d) - 2 z(b)|,
// do not show a step between a and b).
// z is the inverse view depth 1 / z_view, which is affine in image coordinates on any plane, so its second
// difference is exactly 0 for every plane whatever its orientation (the property the paper relies on; a depth
// buffer is affine in 1 / z_view too). Dividing by z of the middle sample makes eps dimensionless, so one
// value suits every scene scale (the paper's eps is in depth units and "depends on the scene"). A neighbour
// outside the image or on the background gives no information.
//
// Adaptive meshes (a deviation beyond the paper, `adaptive` on; its functions are in
// core/src/technique/insm/triangulate_adaptive.wgsl, appended to this file; the CPU twin is
// core/src/technique/insm/triangulate/adaptive.rs): a first pass (`classify`) asks of each tile a quadtree of blocks:
// the whole tile, its four 4x4 quadrants and its sixteen 2x2 blocks (those at least `min_block` a side). A
// block is planar when it is whole (its samples lie in the image), all its neighbourhoods keep both triangles,
// and its samples' inverse depths are all within merge_epsilon (relative) of the affine function through its
// corners z(0,0), z(s,0), z(0,s) (the second-difference test taken across the block: affine on a plane); the
// tile's `merged` mask holds a bit per planar block. In the second pass (`triangulate`) every neighbourhood
// belongs to a leaf, the largest planar block around it or itself alone (`leaf_of`). A sample is a vertex when
// it is a corner of the leaf of one of the neighbourhoods around it (`is_vertex`); a merged leaf is written as
// two triangles when its sides hold no vertex but its corners, else as a fan from its centre sample over every
// vertex of its boundary, so neighbouring leaves (in this tile or the next) share every vertex of a common
// side: no T-junctions, no cracks. The plane test uses merge_epsilon (tighter than eps). `classify` also writes
// every sample's vertex and, per tile, which of its neighbourhoods keep both triangles (`full_lo`, `full_hi`),
// so that `triangulate` can look at other maps.
//
// Covered triangles (a deviation beyond the paper, `drop_covered` on; see core/src/technique/insm/mod.rs): a
// sample of map j is covered when another map i reconstructs it more finely (it projects into a neighbourhood
// of i that keeps both triangles, lies on i's triangle there within eps, and that neighbourhood is smaller in
// world area than the sample's own, within FINER_SLACK: the lower-numbered map). `triangulate` drops a
// triangle whose three corners are covered, and a merged block whose samples all are.
//
// Outputs: one vertex per sample (world position, inverse depth; inverse depth 0 = background), the kept
// triangles of each tile compacted at the start of the tile's fixed slot of MAX_TRIS triangles, and per tile
// its triangle count and the bounds of its triangles, which the CPU reads back to cull tiles per light.
// Keep TILE and the `Tile` layout in sync with core/src/technique/insm/triangulate.rs.

struct Params {
    resolution: u32,
    tiles_per_side: u32,
    epsilon: f32,
    // tiles per row of the depth atlas (image j is atlas tile j)
    atlas_tiles_per_row: u32,
    // 1: merge planar tiles (the adaptive mesh)
    adaptive: u32,
    // relative tolerance of the merge test (tighter than epsilon: planes pass it to rounding)
    merge_epsilon: f32,
    // 1: drop what another map reconstructs more finely
    drop_covered: u32,
    // 1: move every sample at a cut edge half a sample across it, along its surface (`dilated_position`)
    dilate: u32,
    // the tolerance for a steep edge (`edge_connected`), at most epsilon
    step_epsilon: f32,
    // the smallest block the adaptive mesh merges, neighbourhoods a side (2, 4 or TILE)
    min_block: u32,
    _pad1: u32,
    _pad2: u32,
}

struct View {
    world_from_clip: mat4x4<f32>,
    clip_from_world: mat4x4<f32>,
    near: f32,
    far: f32,
    // the relative inverse-depth change per sample above which an edge is steep (0: none is)
    steep: f32,
    _pad1: f32,
}

struct Tile {
    count: u32,
    // the planar mask (written by `classify`, kept by `triangulate`): bit 0 the whole tile, bits 1 + qy * 2 + qx
    // its 4x4 quadrants, bits 5 + by * 4 + bx its 2x2 blocks
    merged: u32,
    // bit y * TILE + x: neighbourhood (x, y) of the tile keeps both triangles (`classify`; kept by `triangulate`)
    full_lo: u32,
    full_hi: u32,
    bounds_min: vec4<f32>,
    bounds_max: vec4<f32>,
}

const TILE: u32 = 8u;
const MAX_TRIS: u32 = 128u; // 2 * TILE * TILE

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> views: array<View>;
@group(0) @binding(2) var depth_atlas: texture_2d<f32>;
@group(0) @binding(3) var<storage, read_write> vertices: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> indices: array<u32>;
@group(0) @binding(5) var<storage, read_write> tiles: array<Tile>;

// The tile's samples with a halo (two before, two after: the second differences of the last neighbourhood's
// edges reach two samples past it, and `dilated_position` tests the edges on both sides of every sample),
// loaded once into workgroup memory: inverse depth and world position.
const HALO: u32 = 12u; // TILE + 4
const HALO_BEFORE: i32 = 2;
var<workgroup> halo_z: array<f32, 144>; // HALO * HALO
var<workgroup> halo_p: array<vec3<f32>, 144>;
var<private> tile_origin: vec2<i32>;
// The steepness of the tile's map (`View::steep`), set with the halo.
var<private> map_steep: f32;

var<workgroup> tri_count: atomic<u32>;
var<workgroup> planar_mask: atomic<u32>;
var<workgroup> full_bits: array<atomic<u32>, 2>;
// Sample (x, y) of the tile (0..=TILE each): 1 when another map reconstructs it more finely.
const CORNERS: u32 = 9u; // TILE + 1
var<workgroup> covered: array<u32, 81>; // CORNERS * CORNERS
var<workgroup> lo: array<atomic<u32>, 3>;
var<workgroup> hi: array<atomic<u32>, 3>;

fn depth_at(p: vec2<i32>, image: u32) -> f32 {
    let r = i32(params.resolution);
    let origin = vec2<i32>(i32(image % params.atlas_tiles_per_row), i32(image / params.atlas_tiles_per_row)) * r;
    return textureLoad(depth_atlas, origin + p, 0).r;
}

// Inverse view depth of sample p: -1 outside the image, 0 background.
fn inv_depth(p: vec2<i32>, image: u32) -> f32 {
    let r = i32(params.resolution);
    if any(p < vec2<i32>(0)) || any(p >= vec2<i32>(r)) {
        return -1.0;
    }
    let d = depth_at(p, image);
    if d >= 1.0 {
        return 0.0;
    }
    let v = views[image];
    return (v.far - d * (v.far - v.near)) / (v.near * v.far);
}

fn world_position(p: vec2<i32>, image: u32) -> vec3<f32> {
    let r = f32(params.resolution);
    let ndc = vec2<f32>((f32(p.x) + 0.5) / r * 2.0 - 1.0, 1.0 - (f32(p.y) + 0.5) / r * 2.0);
    let w = views[image].world_from_clip * vec4<f32>(ndc, depth_at(p, image), 1.0);
    return w.xyz / w.w;
}

// Inverse depth of sample p from the tile's halo (p within two before and two after the tile).
fn z_at(p: vec2<i32>) -> f32 {
    let l = vec2<u32>(p - tile_origin + vec2<i32>(HALO_BEFORE));
    return halo_z[l.y * HALO + l.x];
}

// World position of sample p from the tile's halo: in `classify` where the sample is, in `triangulate` its
// vertex as `classify` wrote it (dilated when `dilate` is on), so that the bounds and the covered test's
// footprints use the mesh's own vertices, as the CPU twin does.
fn p_at(p: vec2<i32>) -> vec3<f32> {
    let l = vec2<u32>(p - tile_origin + vec2<i32>(HALO_BEFORE));
    return halo_p[l.y * HALO + l.x];
}

// Edge (a, b) with step d = b - a, both samples valid: the paper's second differences at a and at b,
//   s_a = z(a - d) + z(b) - 2 z(a),   s_b = z(a) + z(b + d) - 2 z(b),
// each known when its outer sample (a - d, b + d) is valid. The edge is connected when
// 1. a known one is below eps (relative): the surface continues smoothly from one side into the edge; or
// 2. neither outer sample tells (background or outside the image) and one is outside the image, or
//    |z(a) - z(b)| < eps z (first order).
// Deviation: the paper requires both second differences below eps. That drops every edge *next to* a
// discontinuity too, eroding each surface by a sample and a half instead of the half sample the paper reports
// (section 4.1), and two edges more around every crease: a plate 3-4 samples wide vanished (the box placement
// on the test scene rendered the unshadowed image). With this rule a step cuts only the edge across it (both
// tests fail), so a surface keeps its last sample. A crease still cuts the one edge across it (both fail).
// Tried and not kept: also connecting an edge whose two second differences exceed eps with the same sign (the
// lines extrapolated from both sides meet between a and b: a crease, a ridge two samples wide). It halved the
// error on the outside-in tori (5.3 % to 2.9 %) but joined thin objects side by side at different depths with
// membranes (chair legs): the conference room went from 11.1 % to 18.3 % (13.4 % with the jump bounded by 4 eps).
fn edge_connected(a: vec2<i32>, b: vec2<i32>) -> bool {
    let za = z_at(a);
    let zb = z_at(b);
    // epsilon 0 connects nothing (as the paper's test does): the way to switch the reconstruction off.
    if za <= 0.0 || zb <= 0.0 || params.epsilon <= 0.0 {
        return false;
    }
    let d = b - a;
    let z_before = z_at(a - d);
    let z_after = z_at(b + d);
    let known_a = z_before > 0.0;
    let known_b = z_after > 0.0;
    let s_a = z_before + zb - 2.0 * za;
    let s_b = za + z_after - 2.0 * zb;
    // Deviation (beyond the paper): a steep edge, one whose inverse depth changes by more than map_steep
    // (relative) per sample (a surface seen at more than `steep_angle` from face-on), is held to step_epsilon,
    // tighter than the inside placements' epsilon. Their larger epsilon keeps curved surfaces whole (chairs,
    // curtains), and it also joined the arcade's columns, seen down its hall from a ring camera, to one another
    // and to the walls behind them, samples metres apart: a curtain along the hall that closed its arches.
    let steep = map_steep > 0.0 && abs(za - zb) > map_steep * length(vec2<f32>(d)) * max(za, zb);
    let eps = select(params.epsilon, params.step_epsilon, steep);
    let ok_a = known_a && abs(s_a) < eps * za;
    let ok_b = known_b && abs(s_b) < eps * zb;
    if ok_a || ok_b {
        return true;
    }
    if !known_a && !known_b {
        // Outside the image (z = -1) gives no information and does not object, as in the paper's test.
        return z_before < 0.0 || z_after < 0.0 || abs(za - zb) < params.epsilon * max(za, zb);
    }
    return false;
}

// Float to an unsigned integer with the same order, for atomic min/max.
fn ordered(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn unordered(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u & 0x7fffffffu, (u & 0x80000000u) != 0u));
}

fn grow_bounds(p: vec3<f32>) {
    atomicMin(&lo[0], ordered(p.x));
    atomicMin(&lo[1], ordered(p.y));
    atomicMin(&lo[2], ordered(p.z));
    atomicMax(&hi[0], ordered(p.x));
    atomicMax(&hi[1], ordered(p.y));
    atomicMax(&hi[2], ordered(p.z));
}

// `from_vertices`: positions from the vertex buffer `classify` wrote, else from the depth atlas.
fn load_halo(wg: vec3<u32>, li: u32, from_vertices: bool) {
    let image = wg.z;
    tile_origin = vec2<i32>(wg.xy * TILE);
    map_steep = views[image].steep;
    for (var i = li; i < HALO * HALO; i += TILE * TILE) {
        let p = tile_origin + vec2<i32>(i32(i % HALO), i32(i / HALO)) - vec2<i32>(HALO_BEFORE);
        let z = inv_depth(p, image);
        halo_z[i] = z;
        var w = vec3<f32>(0.0);
        if z > 0.0 {
            if from_vertices {
                w = vertices[(image * params.resolution + u32(p.y)) * params.resolution + u32(p.x)].xyz;
            } else {
                w = world_position(p, image);
            }
        }
        halo_p[i] = w;
    }
    if li == 0u {
        atomicStore(&tri_count, 0u);
        atomicStore(&planar_mask, 0u);
        atomicStore(&full_bits[0], 0u);
        atomicStore(&full_bits[1], 0u);
        for (var i = 0u; i < 3u; i++) {
            atomicStore(&lo[i], 0xffffffffu);
            atomicStore(&hi[i], 0u);
        }
    }
}

// Both triangles of neighbourhood p00 kept (Algorithm 2, lines 2-5).
fn neighbourhood_triangles(p00: vec2<i32>) -> vec2<bool> {
    let p01 = p00 + vec2<i32>(0, 1);
    let p11 = p00 + vec2<i32>(1, 1);
    let p10 = p00 + vec2<i32>(1, 0);
    let diagonal = edge_connected(p00, p11);
    let t1 = diagonal && edge_connected(p00, p01) && edge_connected(p01, p11);
    let t2 = diagonal && edge_connected(p10, p11) && edge_connected(p00, p10);
    return vec2<bool>(t1, t2);
}

// Half the step from sample `behind` to sample s, when the edge from s to s + d is cut (a step, a crease, or
// the background) and the edge from s - d to s is kept: how far s moves along its surface across the cut.
fn half_step_across(s: vec2<i32>, d: vec2<i32>) -> vec3<f32> {
    let r = i32(params.resolution);
    let n = s + d;
    let behind = s - d;
    if any(n < vec2<i32>(0)) || any(n >= vec2<i32>(r)) || any(behind < vec2<i32>(0)) || any(behind >= vec2<i32>(r)) {
        return vec3<f32>(0.0);
    }
    if edge_connected(s, n) || !edge_connected(behind, s) {
        return vec3<f32>(0.0);
    }
    let step = p_at(s) - p_at(behind);
    // A surface seen at a grazing angle (its view depth changing faster than GRAZING_SLOPE times its lateral
    // spacing) is at a curved silhouette: the tangent would leave it by up to half a sample and shadow the
    // surface itself. It stays.
    let depth_change = abs(1.0 / z_at(s) - 1.0 / z_at(behind));
    let lateral_sq = max(dot(step, step) - depth_change * depth_change, 0.0);
    if depth_change * depth_change > GRAZING_SLOPE * GRAZING_SLOPE * lateral_sq {
        return vec3<f32>(0.0);
    }
    return 0.5 * step;
}

// tan 60 degrees: the steepest surface (against the image plane) whose samples move across a cut edge. Keep in
// sync with GRAZING_SLOPE in core/src/technique/insm/triangulate.rs.
const GRAZING_SLOPE: f32 = 1.7320508;

// The vertex of sample s (beyond the paper, `dilate`): the reconstruction joins sample centres, so a surface
// ends at its last sample although its true edge lies anywhere up to the next one: the half-sample erosion the
// paper reports (section 4.1), which lets light leak past every silhouette and crease (a tube three samples wide
// keeps two samples' width). With `dilate` a sample at a cut edge moves half a sample across it, extrapolated
// along its own surface from the sample behind it (the expected position of the edge), in each of the four
// axis directions; a sample with no kept edge behind it (one sample wide along that axis) has no triangle there
// and does not move. The CPU twin is `SampledImage::dilated` in core/src/technique/insm/triangulate.rs.
fn dilated_position(s: vec2<i32>) -> vec3<f32> {
    var p = p_at(s);
    if params.dilate == 0u {
        return p;
    }
    p += half_step_across(s, vec2<i32>(1, 0));
    p += half_step_across(s, vec2<i32>(-1, 0));
    p += half_step_across(s, vec2<i32>(0, 1));
    p += half_step_across(s, vec2<i32>(0, -1));
    return p;
}

fn tile_index(image: u32, t: vec2<u32>) -> u32 {
    return (image * params.tiles_per_side + t.y) * params.tiles_per_side + t.x;
}

// Pass 1 of the adaptive mesh: which blocks of each tile are planar.
@compute @workgroup_size(8, 8, 1)
fn classify(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    load_halo(wg, li, false);
    workgroupBarrier();
    let r = params.resolution;
    let uv = wg.xy * TILE + lid.xy;
    // The vertex of sample (u, v): every sample belongs to exactly one invocation. Written here so that
    // `triangulate` reads every map's samples from the buffer.
    if uv.x < r && uv.y < r {
        let z = z_at(vec2<i32>(uv));
        vertices[wg.z * r * r + uv.y * r + uv.x] =
            select(vec4<f32>(0.0), vec4<f32>(dilated_position(vec2<i32>(uv)), z), z > 0.0);
    }
    if uv.x + 1u < r && uv.y + 1u < r {
        let p00 = vec2<i32>(uv);
        let kept = neighbourhood_triangles(p00);
        if kept.x && kept.y {
            atomicOr(&full_bits[li / 32u], 1u << (li % 32u));
        }
    }
    workgroupBarrier();
    // Invocation 0 asks of the whole tile, 1-4 of its quadrants, 5-20 of its 2x2 blocks.
    if params.adaptive != 0u && li < 21u {
        let b = mask_block(li);
        if b.z >= params.min_block && block_planar(b) {
            atomicOr(&planar_mask, 1u << li);
        }
    }
    workgroupBarrier();
    if li == 0u {
        let t = tile_index(wg.z, wg.xy);
        tiles[t].merged = atomicLoad(&planar_mask);
        tiles[t].full_lo = atomicLoad(&full_bits[0]);
        tiles[t].full_hi = atomicLoad(&full_bits[1]);
    }
}

// Neighbourhood n of `image` keeps both triangles (the bits `classify` wrote).
fn neighbourhood_full(image: u32, n: vec2<u32>) -> bool {
    let t = tile_index(image, n / TILE);
    let bit = (n.y % TILE) * TILE + n.x % TILE;
    let word = select(tiles[t].full_lo, tiles[t].full_hi, bit >= 32u);
    return ((word >> (bit % 32u)) & 1u) != 0u;
}

fn quad_area(p00: vec3<f32>, p10: vec3<f32>, p01: vec3<f32>, p11: vec3<f32>) -> f32 {
    return 0.5 * length(cross(p11 - p00, p01 - p10));
}

// Slack of the finer-sampling comparison (FINER_SLACK in the CPU twin).
const FINER_SLACK: f32 = 0.95;

// Map i reconstructs world point w (a sample of map j, whose neighbourhood there spans area_j) more finely: w
// projects into a neighbourhood of i that keeps both triangles, lies on its triangle there (inverse depth within
// epsilon, relative), and that neighbourhood is smaller (or, within FINER_SLACK, i is the lower-numbered map).
fn reconstructs_better(i: u32, j: u32, w: vec3<f32>, area_j: f32) -> bool {
    let v = views[i];
    let c = v.clip_from_world * vec4<f32>(w, 1.0);
    if c.w <= 0.0 {
        return false;
    }
    let ndc = c.xyz / c.w;
    // Written so that NaN fails.
    if !(abs(ndc.x) <= 1.0 && abs(ndc.y) <= 1.0 && ndc.z >= 0.0 && ndc.z <= 1.0) {
        return false;
    }
    let r = f32(params.resolution);
    let f = vec2<f32>((ndc.x + 1.0) * 0.5 * r - 0.5, (1.0 - ndc.y) * 0.5 * r - 0.5);
    let n = floor(f);
    if n.x < 0.0 || n.y < 0.0 || n.x + 1.0 >= r || n.y + 1.0 >= r {
        return false;
    }
    let ni = vec2<u32>(n);
    if !neighbourhood_full(i, ni) {
        return false;
    }
    // Map i's samples as `classify` wrote them (world position, inverse depth).
    let ru = params.resolution;
    let o = i * ru * ru + ni.y * ru + ni.x;
    let s00 = vertices[o];
    let s10 = vertices[o + 1u];
    let s01 = vertices[o + ru];
    let s11 = vertices[o + ru + 1u];
    let z00 = s00.w;
    let z10 = s10.w;
    let z01 = s01.w;
    let z11 = s11.w;
    let a = f - n;
    // The neighbourhood's triangles [(0,0), (0,1), (1,1)] (a.x <= a.y) and [(1,1), (1,0), (0,0)].
    var fit: f32;
    if a.x <= a.y {
        fit = z00 + a.x * (z11 - z01) + a.y * (z01 - z00);
    } else {
        fit = z00 + a.x * (z10 - z00) + a.y * (z11 - z10);
    }
    let zp = (v.far - ndc.z * (v.far - v.near)) / (v.near * v.far);
    if !(abs(zp - fit) < params.epsilon * zp) {
        return false;
    }
    let area_i = quad_area(s00.xyz, s10.xyz, s01.xyz, s11.xyz);
    return area_i < area_j * FINER_SLACK || (i < j && area_i * FINER_SLACK <= area_j);
}

// Sample p of map j (in the tile's halo) is reconstructed more finely by another of the k maps. Its own
// footprint is the area of the neighbourhood it is the top-left corner of (the last one of its row or column
// at the image's edge); one with a background corner is unbounded.
fn sample_covered(p: vec2<i32>, j: u32, k: u32) -> bool {
    let z = z_at(p);
    let r = i32(params.resolution);
    if z <= 0.0 || r < 2 {
        return false;
    }
    let q = min(p, vec2<i32>(r - 2));
    let z4 = vec4<f32>(z_at(q), z_at(q + vec2<i32>(1, 0)), z_at(q + vec2<i32>(0, 1)), z_at(q + vec2<i32>(1, 1)));
    var area_j = 3.4028235e38;
    if all(z4 > vec4<f32>(0.0)) {
        area_j = quad_area(p_at(q), p_at(q + vec2<i32>(1, 0)), p_at(q + vec2<i32>(0, 1)), p_at(q + vec2<i32>(1, 1)));
    }
    // The surface point the sample saw, not its vertex: a vertex dilation moved lies off the other maps'
    // triangles and would never be found covered (the footprints compared are the mesh's own quads).
    let w = world_position(p, j);
    for (var i = 0u; i < k; i++) {
        if i != j && reconstructs_better(i, j, w, area_j) {
            return true;
        }
    }
    return false;
}

fn corner_covered(p: vec2<i32>) -> bool {
    let l = vec2<u32>(p - tile_origin);
    return covered[l.y * CORNERS + l.x] != 0u;
}

@compute @workgroup_size(8, 8, 1)
fn triangulate(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let image = wg.z;
    load_halo(wg, li, true);
    workgroupBarrier();

    let r = params.resolution;
    // The tile's samples (its neighbourhoods' corners) that another map reconstructs more finely.
    for (var c = li; c < CORNERS * CORNERS; c += TILE * TILE) {
        let p = tile_origin + vec2<i32>(i32(c % CORNERS), i32(c / CORNERS));
        let inside = all(p < vec2<i32>(i32(r)));
        let cov = params.drop_covered != 0u && inside && sample_covered(p, image, groups.z);
        covered[c] = select(0u, 1u, cov);
    }
    workgroupBarrier();
    let uv = wg.xy * TILE + lid.xy;
    let tile = (image * params.tiles_per_side + wg.y) * params.tiles_per_side + wg.x;
    let base = image * r * r;
    let p00 = vec2<i32>(uv);
    let mask = tiles[tile].merged;

    let leaf = leaf_of(image, p00);
    // A merged leaf is written by the invocation of its first neighbourhood.
    if leaf.z > 1 && all(leaf.xy == p00) {
        emit_leaf(image, tile, leaf);
    }

    // The two triangles of the neighbourhood (Algorithm 2, lines 2-5).
    if leaf.z == 1 {
        let kept = neighbourhood_triangles(p00);
        let p01 = p00 + vec2<i32>(0, 1);
        let p11 = p00 + vec2<i32>(1, 1);
        let p10 = p00 + vec2<i32>(1, 0);
        // A triangle whose three corners another map reconstructs more finely is dropped.
        let shared_covered = corner_covered(p00) && corner_covered(p11);
        let t1 = kept.x && !(shared_covered && corner_covered(p01));
        let t2 = kept.y && !(shared_covered && corner_covered(p10));
        let n = u32(t1) + u32(t2);
        if n > 0u {
            let slot = atomicAdd(&tri_count, n);
            var o = (tile * MAX_TRIS + slot) * 3u;
            let i00 = base + uv.y * r + uv.x;
            let i01 = i00 + r;
            let i11 = i00 + r + 1u;
            let i10 = i00 + 1u;
            grow_bounds(p_at(p00));
            grow_bounds(p_at(p11));
            if t1 {
                indices[o] = i00;
                indices[o + 1u] = i01;
                indices[o + 2u] = i11;
                o += 3u;
                grow_bounds(p_at(p01));
            }
            if t2 {
                indices[o] = i11;
                indices[o + 1u] = i10;
                indices[o + 2u] = i00;
                grow_bounds(p_at(p10));
            }
        }
    }
    workgroupBarrier();

    if li == 0u {
        var t: Tile;
        t.count = atomicLoad(&tri_count);
        // Neighbours may read these flags meanwhile: they are written with the values they had.
        t.merged = mask;
        t.full_lo = tiles[tile].full_lo;
        t.full_hi = tiles[tile].full_hi;
        t.bounds_min = vec4<f32>(unordered(atomicLoad(&lo[0])), unordered(atomicLoad(&lo[1])), unordered(atomicLoad(&lo[2])), 0.0);
        t.bounds_max = vec4<f32>(unordered(atomicLoad(&hi[0])), unordered(atomicLoad(&hi[1])), unordered(atomicLoad(&hi[2])), 0.0);
        tiles[tile] = t;
    }
}
