// INSM step 3 (Wang et al. 2016, Algorithm 2): triangulate the intermediate shadow maps on the GPU.
//
// One workgroup per tile of TILE x TILE neighbourhoods of one image, one invocation per 2x2 neighbourhood whose
// top-left sample is (u, v) (u = x, v = y). The tile's samples and a halo are read from the depth atlas once into
// workgroup memory; the connectivity tests read them from there. The neighbourhood gives the triangles
//   [(u, v), (u, v+1), (u+1, v+1)] and [(u+1, v+1), (u+1, v), (u, v)],
// each kept when IsConnected holds for its three edges. Edge (a, b) with step d = b - a is connected when both
// samples are valid (not background) and the second-order differences at a and at b are below epsilon:
//   |z(a - d) + z(b) - 2 z(a)| < eps z(a)   and   |z(a) + z(b + d) - 2 z(b)| < eps z(b).
// z is the inverse view depth 1 / z_view, which is affine in image coordinates on any plane, so its second
// difference is exactly 0 for every plane whatever its orientation (the property the paper relies on; a depth
// buffer is affine in 1 / z_view too). Dividing by z of the middle sample makes eps dimensionless, so one
// value suits every scene scale (the paper's eps is in depth units and "depends on the scene"). A neighbour
// outside the image gives no information and passes; a background neighbour (z = 0) fails, as in the paper.
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
}

struct View {
    world_from_clip: mat4x4<f32>,
    near: f32,
    far: f32,
    _pad0: f32,
    _pad1: f32,
}

struct Tile {
    count: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
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

// The tile's samples with a halo (one before, two after: the second differences of the last neighbourhood's
// edges reach two samples past it), loaded once into workgroup memory: inverse depth and world position.
const HALO: u32 = 11u; // TILE + 3
var<workgroup> halo_z: array<f32, 121>; // HALO * HALO
var<workgroup> halo_p: array<vec3<f32>, 121>;
var<private> tile_origin: vec2<i32>;

var<workgroup> tri_count: atomic<u32>;
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

// Inverse depth of sample p from the tile's halo (p within one before and two after the tile).
fn z_at(p: vec2<i32>) -> f32 {
    let l = vec2<u32>(p - tile_origin + vec2<i32>(1));
    return halo_z[l.y * HALO + l.x];
}

fn p_at(p: vec2<i32>) -> vec3<f32> {
    let l = vec2<u32>(p - tile_origin + vec2<i32>(1));
    return halo_p[l.y * HALO + l.x];
}

fn second_difference_ok(prev: f32, mid: f32, next: f32) -> bool {
    if prev < 0.0 || next < 0.0 {
        return true;
    }
    return abs(prev + next - 2.0 * mid) < params.epsilon * mid;
}

// Edges go right, down or down-right, so a - d and b + d stay within the halo.
fn edge_connected(a: vec2<i32>, b: vec2<i32>) -> bool {
    let za = z_at(a);
    let zb = z_at(b);
    if za <= 0.0 || zb <= 0.0 {
        return false;
    }
    let d = b - a;
    return second_difference_ok(z_at(a - d), za, zb) && second_difference_ok(za, zb, z_at(b + d));
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

@compute @workgroup_size(8, 8, 1)
fn triangulate(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    let image = wg.z;
    tile_origin = vec2<i32>(wg.xy * TILE);
    for (var i = li; i < HALO * HALO; i += TILE * TILE) {
        let p = tile_origin + vec2<i32>(i32(i % HALO), i32(i / HALO)) - vec2<i32>(1);
        let z = inv_depth(p, image);
        halo_z[i] = z;
        halo_p[i] = select(vec3<f32>(0.0), world_position(p, image), z > 0.0);
    }
    if li == 0u {
        atomicStore(&tri_count, 0u);
        for (var i = 0u; i < 3u; i++) {
            atomicStore(&lo[i], 0xffffffffu);
            atomicStore(&hi[i], 0u);
        }
    }
    workgroupBarrier();

    let r = params.resolution;
    let uv = wg.xy * TILE + lid.xy;
    let tile = (image * params.tiles_per_side + wg.y) * params.tiles_per_side + wg.x;
    let base = image * r * r;
    let p00 = vec2<i32>(uv);

    // The vertex of sample (u, v): every sample belongs to exactly one invocation.
    if uv.x < r && uv.y < r {
        let z = z_at(p00);
        vertices[base + uv.y * r + uv.x] = select(vec4<f32>(0.0), vec4<f32>(p_at(p00), z), z > 0.0);
    }

    // The two triangles of the neighbourhood (Algorithm 2, lines 2-5).
    if uv.x + 1u < r && uv.y + 1u < r {
        let p01 = p00 + vec2<i32>(0, 1);
        let p11 = p00 + vec2<i32>(1, 1);
        let p10 = p00 + vec2<i32>(1, 0);
        let diagonal = edge_connected(p00, p11);
        let t1 = diagonal && edge_connected(p00, p01) && edge_connected(p01, p11);
        let t2 = diagonal && edge_connected(p10, p11) && edge_connected(p00, p10);
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
        t.bounds_min = vec4<f32>(unordered(atomicLoad(&lo[0])), unordered(atomicLoad(&lo[1])), unordered(atomicLoad(&lo[2])), 0.0);
        t.bounds_max = vec4<f32>(unordered(atomicLoad(&hi[0])), unordered(atomicLoad(&hi[1])), unordered(atomicLoad(&hi[2])), 0.0);
        tiles[tile] = t;
    }
}
