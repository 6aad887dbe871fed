// Step 3 of Colom et al. 2022: the shading points are the G-buffer's pixels (position, normal), written as
// k-means points (`KmPoint` of fuzzy/kmeans.wgsl: position w = 1 for geometry, 0 for the sky). A normal that
// is not a unit vector (a zero or NaN G-buffer normal) is stored as zero: such a point matches no cluster by
// equation 7 and joins the nearest by position. Composed after common.wgsl.

struct SpPoint {
    position: vec4<f32>,
    normal: vec4<f32>,
    flux: vec4<f32>,
}

@group(1) @binding(0) var<storage, read_write> sp_points: array<SpPoint>;

@compute @workgroup_size(8, 8)
fn sp_points_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let width = u32(frame.viewport.x);
    let height = u32(frame.viewport.y);
    if id.x >= width || id.y >= height {
        return;
    }
    let s = load_surface(vec2<i32>(id.xy));
    var n = s.normal;
    if !(abs(dot(n, n) - 1.0) < 1e-3) {
        n = vec3<f32>(0.0);
    }
    let valid = s.is_geometry && all(abs(s.position) < vec3<f32>(3.0e38));
    sp_points[id.y * width + id.x] =
        SpPoint(vec4<f32>(s.position, select(0.0, 1.0, valid)), vec4<f32>(n, 0.0), vec4<f32>(0.0));
}
