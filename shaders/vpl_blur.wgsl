// The geometry-aware blur that completes interleaved sampling (Dong et al. 2009 section 6, after Segovia et
// al. 2006 and Laine et al. 2007): with interleaving on, the pixel of class (x mod B, y mod B) gathered only
// every B^2-th VPL (scaled by B^2; B = `block`, the paper's 8). A B x B window holds each class once, so
// averaging it spreads every VPL over the window again. Only neighbours on the pixel's surface count; the irradiance (radiance / albedo) is
// averaged, then multiplied by the pixel's own albedo, so texture detail stays sharp.
//
// The surface test: a normal within BLUR_NORMAL (the paper's beta = 0.8, after Laine et al.), a position within
// BLUR_PLANE of the camera distance off the pixel's tangent plane and within BLUR_REACH of it. The paper's
// alpha is a distance (10 % of the scene's extent); the tangent plane is a deviation: a floor seen at a grazing
// angle has rows metres apart, which a distance drops, so the blur then ran along the rows alone.
//
// Beyond the papers, one sample per class: where a class's pixel in the B x B window lies on another surface (a
// column's edge, the far side of a crease), the same class's pixel one block over (B pixels across, down, or
// both) stands in for it, the nearest first; a class none of whose four candidates is on the surface is left
// out. Averaging the window's accepted pixels alone (the blur before) weighs the classes unevenly wherever
// neighbours drop out, and each class is a different share of the VPLs: stripes along a floor's rows and a
// pillar's columns. Measured in docs/techniques/vpl-gather.md ("Interleaved sampling's blur").
//
// The ratio estimator (`ratio`, beyond the paper; after Heitz et al. 2018's ratio of stochastic shadows): the
// gathers wrote each pixel's unshadowed light from every VPL (in the indirect buffer) and the luminance of its
// share of the VPLs with and without visibility (`ratio_in`); the window's accepted samples give a visibility
// share sum(shadowed) / sum(unshadowed), and the pixel's light is its own unshadowed light times that share. Only
// the visibility is blurred: the light's falloff, the pixel's normal and the VPLs near it stay per pixel. Where
// no sample of the window is lit by its VPLs the share is unknown and the pixel gets none (the plain blur's
// answer there too). Composed after common.wgsl.

struct BlurParams {
    // 1: the ratio estimator (the gathers ran with interleave 2), 0: the plain blur
    ratio: u32,
    // B, the interleaving block's side (2-8)
    block: u32,
    pad0: u32,
    pad1: u32,
}

@group(1) @binding(0) var<storage, read> blur_src: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> blur_dst: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read> ratio_in: array<vec2<f32>>;
@group(1) @binding(3) var<uniform> blur: BlurParams;

const BLUR_NORMAL: f32 = 0.8;
const BLUR_PLANE: f32 = 0.02;
const BLUR_REACH: f32 = 0.08;

// The nearer of a window offset in [-B/2, B - B/2) and the same class's offset one block over.
fn other_block(d: i32, b: i32) -> i32 {
    return select(d - b, d + b, d < 0);
}

@compute @workgroup_size(8, 8)
fn blur_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let width = u32(frame.viewport.x);
    let height = u32(frame.viewport.y);
    if id.x >= width || id.y >= height {
        return;
    }
    let index = id.y * width + id.x;
    let s = load_surface(vec2<i32>(id.xy));
    if !s.is_geometry {
        blur_dst[index] = blur_src[index];
        return;
    }
    let camera_distance = length(frame.camera_position.xyz - s.position);
    let plane = BLUR_PLANE * camera_distance;
    let reach = BLUR_REACH * camera_distance;
    var sum = vec3<f32>(0.0);
    var weight = 0.0;
    let b = i32(clamp(blur.block, 2u, 8u));
    let lo = -(b / 2);
    for (var dy = lo; dy < lo + b; dy++) {
        for (var dx = lo; dx < lo + b; dx++) {
            let near = vec2<i32>(dx, dy);
            let far = vec2<i32>(other_block(dx, b), other_block(dy, b));
            // The four offsets of this class, nearest first: the window's, one block across or down (the
            // nearer of the two first), both.
            var candidates = array<vec2<i32>, 4>(near, vec2<i32>(far.x, dy), vec2<i32>(dx, far.y), far);
            if dx * dx + far.y * far.y < far.x * far.x + dy * dy {
                candidates[1] = vec2<i32>(dx, far.y);
                candidates[2] = vec2<i32>(far.x, dy);
            }
            for (var k = 0; k < 4; k++) {
                let q = vec2<i32>(id.xy) + candidates[k];
                if q.x < 0 || q.y < 0 || q.x >= i32(width) || q.y >= i32(height) {
                    continue;
                }
                let n = load_surface(q);
                let offset = n.position - s.position;
                if !n.is_geometry || dot(n.normal, s.normal) < BLUR_NORMAL || abs(dot(offset, s.normal)) > plane
                    || length(offset) > reach {
                    continue;
                }
                let at = u32(q.y) * width + u32(q.x);
                if blur.ratio != 0u {
                    sum += vec3<f32>(ratio_in[at], 0.0);
                } else {
                    sum += blur_src[at].rgb / max(n.albedo, vec3<f32>(1e-3));
                }
                weight += 1.0;
                break;
            }
        }
    }
    if blur.ratio != 0u {
        // sum.x: the window's shadowed luminance, sum.y: its unshadowed one.
        var share = 0.0;
        if sum.y > 0.0 {
            share = clamp(sum.x / sum.y, 0.0, 1.0);
        }
        blur_dst[index] = vec4<f32>(blur_src[index].rgb * share, 0.0);
        return;
    }
    // The pixel itself always passes, so weight >= 1.
    blur_dst[index] = vec4<f32>(max(s.albedo, vec3<f32>(1e-3)) * sum / max(weight, 1.0), 0.0);
}
