// The paraboloid projection of every imperfect shadow map (Brabec et al. 2002, as Ritschel et al. 2008 use it),
// shared by the splat and the lookups so that a map and its lookup agree. Composed after shaders/vpl_basis.wgsl:
// the basis, the texel convention and the linear depth (d - near) / (far - near) of the paraboloid shadow maps
// (paraboloid_depth.wgsl, vpl_vis_paraboloid.wgsl). A direction `dir` in the map's frame lands at
// dir.xy / (1 + dir.z); a point light's map is a dual paraboloid: the upper hemisphere faces +y, the lower -y.
// Keep `IsmView` in sync with `GpuIsmView` in core/src/technique/ism/passes.rs.

struct IsmView {
    // xyz: centre, w: near (world units)
    centre: vec4<f32>,
    // xyz: unit axis of the (upper) hemisphere, w: far (world units)
    axis: vec4<f32>,
    // x: first point of the map's subset in the pool, y: its points, z: the map's (first) tile, w: 1 for a dual
    // paraboloid (two tiles, z and z + 1), 0 for a hemisphere
    subset: vec4<u32>,
}

const ISM_UP: vec3<f32> = vec3<f32>(0.0, 1.0, 0.0);
// The depth of an empty texel (nothing within the far plane). Keep in sync with `pull_push::EMPTY`.
const ISM_EMPTY: f32 = 1.0;

struct IsmTexel {
    // the texel within its tile
    texel: vec2<u32>,
    // distance from the map's centre
    distance: f32,
    // cosine between the direction and the hemisphere's axis (negative behind the map's plane)
    cos_axis: f32,
}

fn ism_project(rel: vec3<f32>, axis: vec3<f32>, resolution: u32) -> IsmTexel {
    let basis = vpl_basis(axis);
    let local = vec3<f32>(dot(rel, basis[0]), dot(rel, basis[1]), dot(rel, basis[2]));
    var out: IsmTexel;
    out.distance = length(local);
    let dir = local / max(out.distance, 1e-30);
    out.cos_axis = dir.z;
    let uv = dir.xy / max(1.0 + dir.z, 1e-6);
    let t = vec2<f32>(uv.x * 0.5 + 0.5, 0.5 - uv.y * 0.5) * f32(resolution);
    out.texel = min(vec2<u32>(max(t, vec2<f32>(0.0))), vec2<u32>(resolution - 1u));
    return out;
}

// The atlas texel of `texel` of tile `tile` (tiles in rows of `tiles_per_row`).
fn ism_atlas_texel(tile: u32, texel: vec2<u32>, tiles_per_row: u32, resolution: u32) -> vec2<i32> {
    let origin = vec2<u32>(tile % tiles_per_row, tile / tiles_per_row) * resolution;
    return vec2<i32>(origin + texel);
}

// The angle one texel spans in the direction of cosine `cos_axis` to the axis, times the distance `d`: the
// texel's footprint at a receiver, which the normal offset and the bias are measured in. (The paraboloid's
// texels span (2 / resolution)(1 + cos) radians: twice as much at the centre as at the rim.)
fn ism_footprint(d: f32, cos_axis: f32, resolution: u32) -> f32 {
    return d * 2.0 / f32(resolution) * (1.0 + max(cos_axis, 0.0));
}
