// Tiled light lists (a renderer service, core/src/services/light_tiles.rs): one workgroup per 16x16-pixel
// screen tile. Composed after common.wgsl (frame uniform, G-buffer depth, position reconstruction).
// 1. Every invocation reconstructs its four pixels' world positions from the G-buffer depth; the tile's geometry
//    pixels are bounded by a world-space box (each invocation reduces four pixels in registers, then
//    order-preserving float bits in workgroup atomics).
// 2. The spheres (a light's range, a cluster's C_att) are tested against the box, and their range of distances
//    to the camera against the distances the tile's pixels occupy (32 bins), 64 at a time, one per
//    invocation; the hits of a chunk are a 64-bit mask, so each hit's slot is a prefix count and the list
//    stays in sphere order (a pixel sums its lights in the same order as without tiles: the same image).
// 3. A tile whose list does not fit `capacity` is marked TILE_OVERFLOW: its pixels loop over every sphere.
// The box test is conservative (a margin for the rounding of the two position reconstructions), so a list
// holds every sphere that reaches one of the tile's pixels. `TileBuild` mirrors `TileBuildUniform` in
// core/src/services/light_tiles.rs.

struct TileBuild {
    tiles_x: u32,
    tiles_y: u32,
    capacity: u32,
    sphere_count: u32,
}

const TILE_SIZE: u32 = 16u;
const TILE_OVERFLOW: u32 = 0xffffffffu;

@group(1) @binding(0) var<uniform> build: TileBuild;
// xyz: centre (world), w: radius
@group(1) @binding(1) var<storage, read> spheres: array<vec4<f32>>;
// Per tile its count (tiles_x * tiles_y of them), then per tile `capacity` item slots: one buffer, so a pass
// that reads it needs one storage binding (the downlevel limit is four per stage).
@group(1) @binding(2) var<storage, read_write> tile_lists: array<u32>;

// Workgroup: 16 x 4 invocations per 16x16-pixel tile, each reducing a column of four pixels in registers
// before touching the workgroup's atomics (a quarter of the atomics of one invocation per pixel: lavapipe
// runs workgroup atomics one lane at a time, and they were most of this pass).
const LANES: u32 = 64u;
const ROWS_PER_LANE: u32 = 4u;

var<workgroup> box_lo: array<atomic<u32>, 3>;
var<workgroup> box_hi: array<atomic<u32>, 3>;
var<workgroup> geometry_pixels: atomic<u32>;
var<workgroup> tile_has_geometry: u32;
var<workgroup> hit_mask: array<atomic<u32>, 2>;
// The tile's geometry pixels' distances to the camera: their range, and which of 32 bins of it they occupy
// (2.5D culling, Harada 2012): a sphere whose distance range [|c - camera| - r, + r] meets no occupied bin
// reaches no pixel of the tile even when it touches the box (a column in front of a far wall).
var<workgroup> distance_lo: atomic<u32>;
var<workgroup> distance_hi: atomic<u32>;
var<workgroup> distance_mask: atomic<u32>;

// Float bits whose unsigned order is the float order.
fn ordered_bits(v: f32) -> u32 {
    let b = bitcast<u32>(v);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn from_ordered_bits(b: u32) -> f32 {
    return bitcast<f32>(select(~b, b & 0x7fffffffu, (b & 0x80000000u) != 0u));
}

// Bin of distance d in [lo, hi], monotonic in d, clamped to 0..=31.
fn distance_bin(d: f32, lo: f32, hi: f32) -> u32 {
    let t = (d - lo) / max(hi - lo, 1e-30) * 32.0;
    return u32(clamp(t, 0.0, 31.0));
}

// The bit of a pixel's distance bin, 0 for a pixel without geometry (distance < 0).
fn distance_bit(d: f32, lo: f32, hi: f32) -> u32 {
    return select(0u, 1u << distance_bin(d, lo, hi), d >= 0.0);
}

@compute @workgroup_size(16, 4)
fn build_main(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    if lid < 3u {
        atomicStore(&box_lo[lid], 0xffffffffu);
        atomicStore(&box_hi[lid], 0u);
    }
    if lid < 2u {
        atomicStore(&hit_mask[lid], 0u);
    }
    if lid == 0u {
        atomicStore(&geometry_pixels, 0u);
        atomicStore(&distance_lo, 0xffffffffu);
        atomicStore(&distance_hi, 0u);
        atomicStore(&distance_mask, 0u);
    }
    workgroupBarrier();

    // Step 1: the world box of the tile's geometry pixels, this lane's four pixels first.
    var p_lo = vec3<f32>(3.4e38);
    var p_hi = vec3<f32>(-3.4e38);
    var count = 0u;
    var d_min = 3.4e38;
    var d_max = 0.0;
    // Each of the lane's pixels' distance to the camera, -1 without geometry (a vec4, not an array: lavapipe
    // keeps arrays indexed in a loop in memory).
    var distances = vec4<f32>(-1.0);
    for (var r = 0u; r < ROWS_PER_LANE; r++) {
        let pixel = group.xy * TILE_SIZE + vec2<u32>(local.x, local.y * ROWS_PER_LANE + r);
        if pixel.x < u32(frame.viewport.x) && pixel.y < u32(frame.viewport.y) {
            let depth = textureLoad(gbuffer_depth, vec2<i32>(pixel), 0).r;
            if depth < 1.0 {
                let uv = (vec2<f32>(pixel) + 0.5) * frame.viewport.zw;
                let ndc = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, depth, 1.0);
                let world = frame.world_from_clip * ndc;
                let p = world.xyz / world.w;
                p_lo = min(p_lo, p);
                p_hi = max(p_hi, p);
                count += 1u;
                let d = distance(p, frame.camera_position.xyz);
                d_min = min(d_min, d);
                d_max = max(d_max, d);
                distances[r] = d;
            }
        }
    }
    if count > 0u {
        for (var c = 0u; c < 3u; c++) {
            atomicMin(&box_lo[c], ordered_bits(p_lo[c]));
            atomicMax(&box_hi[c], ordered_bits(p_hi[c]));
        }
        atomicAdd(&geometry_pixels, count);
        atomicMin(&distance_lo, bitcast<u32>(d_min));
        atomicMax(&distance_hi, bitcast<u32>(d_max));
    }
    workgroupBarrier();
    let d_lo = bitcast<f32>(atomicLoad(&distance_lo));
    let d_hi = bitcast<f32>(atomicLoad(&distance_hi));
    if count > 0u {
        let bits = distance_bit(distances.x, d_lo, d_hi) | distance_bit(distances.y, d_lo, d_hi)
            | distance_bit(distances.z, d_lo, d_hi) | distance_bit(distances.w, d_lo, d_hi);
        atomicOr(&distance_mask, bits);
    }
    workgroupBarrier();
    if lid == 0u {
        tile_has_geometry = select(0u, 1u, atomicLoad(&geometry_pixels) > 0u);
    }
    let tile = group.y * build.tiles_x + group.x;
    if workgroupUniformLoad(&tile_has_geometry) == 0u {
        if lid == 0u {
            tile_lists[tile] = 0u;
        }
        return;
    }
    let lo = vec3<f32>(
        from_ordered_bits(atomicLoad(&box_lo[0])),
        from_ordered_bits(atomicLoad(&box_lo[1])),
        from_ordered_bits(atomicLoad(&box_lo[2])),
    );
    let hi = vec3<f32>(
        from_ordered_bits(atomicLoad(&box_hi[0])),
        from_ordered_bits(atomicLoad(&box_hi[1])),
        from_ordered_bits(atomicLoad(&box_hi[2])),
    );
    let box_scale = max(max(abs(lo.x), abs(lo.y)), max(max(abs(lo.z), abs(hi.x)), max(abs(hi.y), abs(hi.z))));
    let occupied = atomicLoad(&distance_mask);

    // Step 2: the spheres, LANES at a time, in order.
    let base = build.tiles_x * build.tiles_y + tile * build.capacity;
    var listed = 0u;
    for (var first = 0u; first < build.sphere_count; first += LANES) {
        let index = first + lid;
        var hit = false;
        if index < build.sphere_count {
            let sphere = spheres[index];
            let nearest = clamp(sphere.xyz, lo, hi);
            // Conservative: the pixels' positions here and in the shading pass may differ by rounding.
            let scale = max(box_scale, max(abs(sphere.x), max(abs(sphere.y), abs(sphere.z))));
            let reach = sphere.w * 1.001 + 2e-4 * scale;
            hit = dot(sphere.xyz - nearest, sphere.xyz - nearest) <= reach * reach;
            // A pixel within `reach` of the centre is within `reach` of its distance to the camera.
            let d = distance(sphere.xyz, frame.camera_position.xyz);
            let reach_d = reach + 1e-5 * scale;
            if hit && d + reach_d >= d_lo && d - reach_d <= d_hi {
                let first_bin = distance_bin(d - reach_d, d_lo, d_hi);
                let last_bin = distance_bin(d + reach_d, d_lo, d_hi);
                let bins = (0xffffffffu >> (31u - last_bin)) & (0xffffffffu << first_bin);
                hit = (bins & occupied) != 0u;
            } else {
                hit = false;
            }
        }
        if hit {
            atomicOr(&hit_mask[lid / 32u], 1u << (lid % 32u));
        }
        workgroupBarrier();
        var before = 0u;
        var chunk_hits = 0u;
        for (var w = 0u; w < LANES / 32u; w++) {
            let bits = countOneBits(atomicLoad(&hit_mask[w]));
            before += select(0u, bits, w < lid / 32u);
            chunk_hits += bits;
        }
        if hit {
            let word = atomicLoad(&hit_mask[lid / 32u]);
            let slot = listed + before + countOneBits(word & ((1u << (lid % 32u)) - 1u));
            if slot < build.capacity {
                tile_lists[base + slot] = index;
            }
        }
        listed += chunk_hits;
        workgroupBarrier();
        if lid < LANES / 32u {
            atomicStore(&hit_mask[lid], 0u);
        }
        workgroupBarrier();
    }

    // Step 3.
    if lid == 0u {
        tile_lists[tile] = select(listed, TILE_OVERFLOW, listed > build.capacity);
    }
}
