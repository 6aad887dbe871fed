// LightCluster (Wiesenhuetter et al. 2013, section 3.2), shading of one batch of clusters. Each cluster is a
// disc area light of radius d_min at its center light, with one cube shadow map (far plane C_att). For every
// pixel, a cluster's visibility is computed once (PCF or PCSS over a Poisson disk) and modulates the summed
// radiance of all its member lights. With PCSS's early out, the first half of a loop's samples decide where
// they agree. Composed after common.wgsl, light_tiles.wgsl and cube_shadow.wgsl.
// `Batch` and `Cluster` mirror `ClusterBatchUniform` and `GpuCluster` in core/src/technique/lightcluster/mod.rs.

struct Batch {
    first_cluster: u32,
    cluster_count: u32,
    resolution: f32,
    bias_world: f32,
    normal_offset_texels: f32,
    tiles_per_row: u32,
    // Poisson-disk samples, 1..=64
    samples: u32,
    // bit 0: PCSS (else PCF); bit 1: PCSS's early out when the first half of a loop's samples agree
    flags: u32,
    // the one cluster whose visibility alone is drawn (grey), or 0xffffffff: every cluster shaded
    only_cluster: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

const FLAG_PCSS: u32 = 1u;
const FLAG_EARLY_OUT: u32 = 2u;

struct Cluster {
    position: vec3<f32>,
    // area-light radius: the cluster's d_min
    radius: f32,
    // C_att: no member light reaches farther from the center
    c_att: f32,
    shadow_near: f32,
    first_light: u32,
    light_count: u32,
    // no member light lies farther than this from `position`
    spread: f32,
}

@group(1) @binding(0) var<storage, read> lights: array<Light>;
@group(1) @binding(1) var<storage, read> clusters: array<Cluster>;
@group(1) @binding(2) var<uniform> batch: Batch;
@group(1) @binding(3) var shadow_atlas: texture_2d<f32>;

// Mitchell best-candidate points in the unit disc: every prefix is well spread, so the first N serve any N.
var<private> POISSON: array<vec2<f32>, 64> = array<vec2<f32>, 64>(
    vec2<f32>(-0.3523, -0.6983),
    vec2<f32>(0.6386, 0.7280),
    vec2<f32>(-0.8586, 0.4818),
    vec2<f32>(0.8402, -0.4860),
    vec2<f32>(-0.1599, 0.1652),
    vec2<f32>(-0.1793, 0.8959),
    vec2<f32>(-0.8760, -0.2242),
    vec2<f32>(0.9604, 0.1273),
    vec2<f32>(0.3131, -0.8999),
    vec2<f32>(0.3790, -0.1101),
    vec2<f32>(0.2796, 0.3824),
    vec2<f32>(-0.0341, -0.3252),
    vec2<f32>(-0.5879, 0.1097),
    vec2<f32>(0.2731, 0.9369),
    vec2<f32>(-0.4670, 0.5822),
    vec2<f32>(-0.4849, -0.2895),
    vec2<f32>(0.4350, -0.5125),
    vec2<f32>(-0.7774, -0.6001),
    vec2<f32>(-0.0853, -0.9735),
    vec2<f32>(0.6422, 0.3273),
    vec2<f32>(-0.9542, 0.1344),
    vec2<f32>(-0.0990, 0.5397),
    vec2<f32>(0.7488, -0.1360),
    vec2<f32>(0.6552, -0.7500),
    vec2<f32>(0.0921, -0.6386),
    vec2<f32>(0.1250, 0.0843),
    vec2<f32>(0.1782, 0.6642),
    vec2<f32>(-0.5085, 0.8599),
    vec2<f32>(0.8260, 0.5368),
    vec2<f32>(-0.2291, -0.1081),
    vec2<f32>(-0.4243, 0.3145),
    vec2<f32>(0.5177, 0.0990),
    vec2<f32>(0.2367, -0.3355),
    vec2<f32>(-0.7013, 0.6893),
    vec2<f32>(-0.5995, -0.7907),
    vec2<f32>(-0.1435, -0.5532),
    vec2<f32>(0.4223, 0.5865),
    vec2<f32>(-0.5319, -0.5314),
    vec2<f32>(0.0396, 0.3298),
    vec2<f32>(0.9581, -0.2676),
    vec2<f32>(0.5945, -0.3212),
    vec2<f32>(-0.6401, -0.1210),
    vec2<f32>(-0.6390, 0.4398),
    vec2<f32>(0.0439, 0.9901),
    vec2<f32>(-0.2543, -0.3451),
    vec2<f32>(-0.7081, -0.3723),
    vec2<f32>(-0.3055, -0.9210),
    vec2<f32>(0.9090, 0.3368),
    vec2<f32>(0.0969, -0.1444),
    vec2<f32>(-0.3636, 0.0807),
    vec2<f32>(-0.7797, 0.2681),
    vec2<f32>(-0.2808, 0.7045),
    vec2<f32>(0.0860, -0.8515),
    vec2<f32>(0.7343, 0.0973),
    vec2<f32>(-0.1552, -0.7785),
    vec2<f32>(0.4361, -0.7193),
    vec2<f32>(-0.0098, 0.7634),
    vec2<f32>(-0.2163, 0.3685),
    vec2<f32>(0.3163, 0.1743),
    vec2<f32>(0.4632, 0.8386),
    vec2<f32>(-0.8032, -0.0065),
    vec2<f32>(0.6438, -0.5208),
    vec2<f32>(0.9579, -0.0683),
    vec2<f32>(-0.8930, -0.4462)
);

struct ShadowSample {
    // 1 when the sample point is lit
    lit: f32,
    // distance from the light of the stored occluder along the tap's ray (when not lit)
    occluder: f32,
}

// Shadow-map texels this invocation read (blocker search and filter), for the work counters.
var<private> lc_taps: u32 = 0u;

fn shadow_sample(q: vec3<f32>, cluster: Cluster, cube_index: u32) -> ShadowSample {
    lc_taps += 1u;
    let look = cube_lookup(q - cluster.position, cube_index, batch.resolution, batch.tiles_per_row);
    let depth = textureLoad(shadow_atlas, look.texel, 0).r;
    var out: ShadowSample;
    let occluder_axis = cube_depth_to_distance(depth, cluster.shadow_near, cluster.c_att);
    // The occluder's distance from the light along the tap's ray, as the receiver's `d` in the penumbra estimate
    // is: the map stores distances along the face's axis, up to sqrt(3) times shorter toward a face's corner,
    // and a blocker distance in those units widened the penumbra w = r (d - d_b) / d_b several times there
    // (issue 23: the shadow error on Sponza, d_init 0.5, fell from 2.76 % to 0.95 % with this).
    out.occluder = occluder_axis * length(q - cluster.position) / max(look.axis_distance, 1e-20);
    out.lit = select(0.0, 1.0, depth >= 1.0 || look.axis_distance - batch.bias_world <= occluder_axis);
    return out;
}

// A point of the receiver plane (through p, normal n) seen from the light in direction `offset` away from p,
// `offset` being perpendicular to the light direction l: samples stay on the receiver plane, so filtering
// does not shadow the surface itself, while their footprint in the shadow map keeps the filter's size.
fn on_receiver_plane(p: vec3<f32>, n: vec3<f32>, l: vec3<f32>, offset: vec3<f32>) -> vec3<f32> {
    return p + offset - l * (dot(offset, n) / max(dot(l, n), 0.2));
}

fn cluster_visibility(s: Surface, cluster: Cluster, cube_index: u32) -> f32 {
    let to_light = cluster.position - s.position;
    let d = length(to_light);
    let l = to_light / d;
    let texel_world = 2.0 * d / batch.resolution;
    let p = s.position + s.normal * (texel_world * batch.normal_offset_texels);
    // Basis of the plane perpendicular to the light direction.
    let helper = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), abs(l.x) > 0.9);
    let t = normalize(cross(l, helper));
    let b = cross(l, t);
    let n = s.normal;
    let count = clamp(batch.samples, 1u, 64u);
    // PCSS's early out (`early_out=on`): in the blocker search and in the filter, the first `probe` samples
    // (a well-spread prefix of the Poisson disk) decide where they all agree, as in a lit or umbra region; only
    // where they disagree (penumbrae) are all taken. PCF keeps the paper's fixed samples.
    var probe = count;
    if (batch.flags & (FLAG_PCSS | FLAG_EARLY_OUT)) == (FLAG_PCSS | FLAG_EARLY_OUT) && count >= 4u {
        probe = count / 2u;
    }

    // Filter radius in world units at the receiver.
    var filter_radius = cluster.radius;
    if (batch.flags & FLAG_PCSS) != 0u {
        // PCSS step 1: blocker search over the region the disc light can see through.
        var blocker_sum = 0.0;
        var blockers = 0.0;
        for (var i = 0u; i < count; i++) {
            if i == probe && blockers == 0.0 {
                return 1.0; // the probe found no blocker: lit
            }
            let o = POISSON[i] * cluster.radius;
            let smp = shadow_sample(on_receiver_plane(p, n, l, t * o.x + b * o.y), cluster, cube_index);
            if smp.lit < 0.5 {
                blocker_sum += smp.occluder;
                blockers += 1.0;
            }
        }
        if blockers == 0.0 {
            return 1.0;
        }
        // Step 2: penumbra width from similar triangles, w = r (d_receiver - d_blocker) / d_blocker.
        let d_blocker = max(blocker_sum / blockers, cluster.shadow_near);
        let d_receiver = max(d - texel_world, d_blocker);
        // The wider the filter, the sparser its samples: limit it to a few light radii (see the module notes).
        filter_radius = min(cluster.radius * (d_receiver - d_blocker) / d_blocker, 4.0 * cluster.radius);
        // Every search sample blocked and the filter within the searched disc: the umbra, as production PCSS
        // takes it (skips the filter's samples; the search already found them all in shadow).
        if blockers == f32(count) && filter_radius <= cluster.radius {
            return 0.0;
        }
    }
    // PCF (PCSS step 3) over a disc of `filter_radius`.
    if filter_radius <= 0.0 {
        return shadow_sample(p, cluster, cube_index).lit;
    }
    var lit = 0.0;
    for (var i = 0u; i < count; i++) {
        if i == probe && (lit == 0.0 || lit == f32(probe)) {
            return lit / f32(probe); // the probe agrees: fully lit or fully shadowed
        }
        let o = POISSON[i] * filter_radius;
        lit += shadow_sample(on_receiver_plane(p, n, l, t * o.x + b * o.y), cluster, cube_index).lit;
    }
    return lit / f32(count);
}

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.position.xy);
    let s = load_surface(pixel);
    if !s.is_geometry {
        discard;
    }
    var sum = vec3<f32>(0.0);
    var evaluations = 0u;
    var lookups = 0u;
    // The batch's clusters whose C_att sphere reaches this pixel's tile (light_tiles.wgsl), in batch order.
    let span = tile_span(pixel, batch.first_cluster, batch.cluster_count);
    for (var j = span.start; j < span.end; j++) {
        let index = tile_item(span, j);
        let c = index - batch.first_cluster;
        let only = batch.only_cluster != 0xffffffffu;
        if only && index != batch.only_cluster {
            continue;
        }
        let cluster = clusters[index];
        // Pixels beyond C_att get nothing from the cluster (paper 3.2.2).
        let to_center = cluster.position - s.position;
        if length(to_center) > cluster.c_att {
            continue;
        }
        // A receiver facing away from the ball that holds every member light gets nothing from any of them
        // (n . (l - p) <= n . (c - p) + spread <= 0): skip their evaluations and the cluster's visibility.
        if dot(s.normal, to_center) <= -cluster.spread {
            continue;
        }
        var unshadowed = vec3<f32>(0.0);
        for (var i = 0u; i < cluster.light_count; i++) {
            unshadowed += shade_light(s, lights[cluster.first_light + i]);
        }
        evaluations += cluster.light_count;
        if any(unshadowed > vec3<f32>(0.0)) {
            let visibility = cluster_visibility(s, cluster, c);
            sum += select(unshadowed * visibility, vec3<f32>(visibility), only);
            lookups += 1u;
        }
    }
    count_work(pixel, WORK_LIGHT_EVALUATIONS, evaluations);
    // One lookup per cluster shadow map, its taps as PCF / PCSS took them (early outs included).
    count_work(pixel, WORK_SHADOW_LOOKUPS, lookups);
    count_work(pixel, WORK_FILTER_TAPS, lc_taps);
    return vec4<f32>(sum, 0.0);
}
