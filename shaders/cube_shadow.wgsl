// Cube shadow map lookup. The cube maps of a batch of lights live as square tiles in one depth atlas: tile
// `6 * cube + face`, `tiles_per_row` tiles per row, each rendered with the face table of `cube_lookup` (keep in
// sync with `CUBE_FACES` and `cube_face_of` in core/src/math.rs). A tile holds hardware depth of a 90 degree perspective view;
// `cube_depth_to_distance` turns it back into the world-space distance along the face axis, so bias and
// comparisons are in world units. One atlas instead of a texture array lets a batch render in a single
// render pass (one viewport per face), which matters on lavapipe where each pass has a fixed cost.

struct CubeLookup {
    // texel in the atlas, clamped to the face's tile
    texel: vec2<i32>,
    // distance of the point along the face's axis
    axis_distance: f32,
}

// Where direction `v` (from the light) lands in cube map `cube_index` of an atlas with `resolution` texels per
// face and `tiles_per_row` tiles per row. The face table (forward, up) is written out per major axis: this runs
// per pixel per light, and selects are much cheaper than switches on lavapipe. `right = cross(forward, up)`
// gives the signs below.
fn cube_lookup(v: vec3<f32>, cube_index: u32, resolution: f32, tiles_per_row: u32) -> CubeLookup {
    let a = abs(v);
    var face: u32;
    var z: f32;
    var xy: vec2<f32>;
    if a.x >= a.y && a.x >= a.z {
        z = a.x;
        face = select(1u, 0u, v.x >= 0.0);
        xy = vec2<f32>(select(-v.z, v.z, v.x >= 0.0), v.y);
    } else if a.y >= a.z {
        z = a.y;
        face = select(3u, 2u, v.y >= 0.0);
        xy = vec2<f32>(v.x, select(-v.z, v.z, v.y >= 0.0));
    } else {
        z = a.z;
        face = select(5u, 4u, v.z >= 0.0);
        xy = vec2<f32>(select(v.x, -v.x, v.z >= 0.0), v.y);
    }
    let ndc = xy / z;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    var out: CubeLookup;
    let tile = cube_index * 6u + face;
    let origin = vec2<i32>(i32(tile % tiles_per_row), i32(tile / tiles_per_row)) * i32(resolution);
    out.texel = origin + clamp(vec2<i32>(uv * resolution), vec2<i32>(0), vec2<i32>(i32(resolution) - 1));
    out.axis_distance = z;
    return out;
}

// Hardware depth of a 90 degree perspective (near..far) back to the distance along the face axis.
fn cube_depth_to_distance(depth: f32, near: f32, far: f32) -> f32 {
    return near * far / (far - depth * (far - near));
}
