// Auto-exposure: the log-average luminance of the displayed image (Reinhard et al. 2002, equation 1:
// L_avg = exp(mean(log(delta + L)))) over the pixels that show geometry (the background colour is the user's
// choice, not the scene's light), and the scale `key / L_avg` that maps it to middle grey. Two passes, both
// deterministic (no float atomics): `meter_main` sums each 16x16 tile in workgroup memory into `partials`,
// `meter_resolve` sums the tiles in one workgroup. The tone mapping reads the scale on the GPU, so no frame
// waits for a readback. Composed after common.wgsl and display.wgsl.

// Per 16x16 tile: (sum of log luminance, pixels metered).
@group(1) @binding(2) var<storage, read_write> partials: array<vec2<f32>>;
// [0]: x scale, y L_avg, z pixels metered, w 1 once metered.
@group(1) @binding(3) var<storage, read_write> result: array<vec4<f32>>;

// Middle grey.
const KEY: f32 = 0.18;
// Keeps black pixels finite in the log.
const DELTA: f32 = 1e-4;
// The scale stays within 2^-16..2^16: an all-black image keeps a finite exposure.
const MAX_SCALE: f32 = 65536.0;

var<workgroup> tile_sum: array<vec2<f32>, 256>;

// Sum `value` over the workgroup's 256 invocations into tile_sum[0] (a tree in workgroup memory; every
// invocation must call it).
fn reduce(local: u32, value: vec2<f32>) {
    tile_sum[local] = value;
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride /= 2u) {
        if local < stride {
            tile_sum[local] += tile_sum[local + stride];
        }
        workgroupBarrier();
    }
}

fn tiles_x() -> u32 {
    return (u32(frame.viewport.x) + 15u) / 16u;
}

@compute @workgroup_size(16, 16)
fn meter_main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) local: u32,
              @builtin(workgroup_id) group: vec3<u32>) {
    var value = vec2<f32>(0.0);
    if id.x < u32(frame.viewport.x) && id.y < u32(frame.viewport.y) {
        let pixel = vec2<i32>(id.xy);
        if textureLoad(gbuffer_depth, pixel, 0).r < 1.0 {
            let c = displayed_radiance(pixel);
            let y = luminance(max(c, vec3<f32>(0.0)));
            // A NaN or infinite pixel (a technique's bug) is not metered.
            if y == y && y < 3.0e38 {
                value = vec2<f32>(log(DELTA + y), 1.0);
            }
        }
    }
    reduce(local, value);
    if local == 0u {
        partials[group.y * tiles_x() + group.x] = tile_sum[0];
    }
}

@compute @workgroup_size(256)
fn meter_resolve(@builtin(local_invocation_index) local: u32) {
    let tiles = tiles_x() * ((u32(frame.viewport.y) + 15u) / 16u);
    var value = vec2<f32>(0.0);
    for (var i = local; i < tiles; i += 256u) {
        value += partials[i];
    }
    reduce(local, value);
    if local == 0u {
        let total = tile_sum[0];
        if total.y > 0.0 {
            let average = exp(total.x / total.y);
            let scale = clamp(KEY / average, 1.0 / MAX_SCALE, MAX_SCALE);
            result[0] = vec4<f32>(scale, average, total.y, 1.0);
        } else {
            result[0] = vec4<f32>(1.0, 0.0, 0.0, 1.0);
        }
    }
}
