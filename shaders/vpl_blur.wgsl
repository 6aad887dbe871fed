// The geometry-aware blur that completes interleaved sampling (Dong et al. 2009 section 6, after Segovia et
// al. 2006 and Laine et al. 2007): with interleaving on, the pixel of class (x mod 8, y mod 8) gathered only
// every 64th VPL (scaled by 64). An 8x8 window holds each class once, so averaging it spreads every VPL over
// the window again. Only neighbours on the same surface count (normal within ~25 degrees, position within 3 %
// of the camera distance), and the irradiance (radiance / albedo) is averaged, then multiplied by the pixel's
// own albedo, so texture detail stays sharp. Composed after common.wgsl.

@group(1) @binding(0) var<storage, read> blur_src: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> blur_dst: array<vec4<f32>>;

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
    let tolerance = 0.03 * length(frame.camera_position.xyz - s.position);
    var sum = vec3<f32>(0.0);
    var weight = 0.0;
    for (var dy = -4; dy < 4; dy++) {
        for (var dx = -4; dx < 4; dx++) {
            let q = vec2<i32>(id.xy) + vec2<i32>(dx, dy);
            if q.x < 0 || q.y < 0 || q.x >= i32(width) || q.y >= i32(height) {
                continue;
            }
            let n = load_surface(q);
            if !n.is_geometry || dot(n.normal, s.normal) < 0.9 || distance(n.position, s.position) > tolerance {
                continue;
            }
            let albedo = max(n.albedo, vec3<f32>(1e-3));
            sum += blur_src[u32(q.y) * width + u32(q.x)].rgb / albedo;
            weight += 1.0;
        }
    }
    // The pixel itself always passes, so weight >= 1.
    blur_dst[index] = vec4<f32>(max(s.albedo, vec3<f32>(1e-3)) * sum / max(weight, 1.0), 0.0);
}
