// ISM step 2, splatting (Ritschel et al. 2008, section 3.2): one invocation per point of a map's subset and map.
// The point's distance from the map's centre, normalised to [near, far], goes into the one texel its direction
// lands in with atomicMin: positive f32s order as their bits do, so the u32 minimum is the nearest point.
// Point lights (dual paraboloid): each point into the hemisphere on its side. VPLs (one hemisphere along the
// normal, Ritschel's): points behind the map's plane are dropped. Points nearer than `near` or past `far` (a
// light's range: nothing there is lit by it) are dropped. Composed after vpl_basis.wgsl and ism/paraboloid.wgsl.
// `SplatParams` mirrors `SplatUniform` in core/src/technique/ism/passes.rs.

struct SplatParams {
    views: u32,
    points_per_map: u32,
    pool: u32,
    resolution: u32,
}

@group(0) @binding(0) var<storage, read> pool_points: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> views: array<IsmView>;
@group(0) @binding(2) var<uniform> splat: SplatParams;
// Level 0 of every tile of the batch (f32 bits), then the coarser levels (ism/pull_push.wgsl).
@group(0) @binding(3) var<storage, read_write> depth_bits: array<atomic<u32>>;

@compute @workgroup_size(64)
fn splat_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let m = id.y;
    if m >= splat.views || id.x >= splat.points_per_map || splat.pool == 0u {
        return;
    }
    let view = views[m];
    if id.x >= view.subset.y {
        return;
    }
    let p = pool_points[(view.subset.x + id.x) % splat.pool].xyz;
    let rel = p - view.centre.xyz;
    var axis = view.axis.xyz;
    var tile = view.subset.z;
    if view.subset.w != 0u && dot(rel, axis) < 0.0 {
        axis = -axis;
        tile += 1u;
    }
    let look = ism_project(rel, axis, splat.resolution);
    let near = view.centre.w;
    let far = view.axis.w;
    if look.cos_axis < 0.0 || look.distance < near || look.distance >= far {
        return;
    }
    let z = (look.distance - near) / (far - near);
    let res = splat.resolution;
    let at = tile * res * res + look.texel.y * res + look.texel.x;
    atomicMin(&depth_bits[at], bitcast<u32>(z));
}
