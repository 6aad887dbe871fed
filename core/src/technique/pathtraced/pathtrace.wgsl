// One-bounce path tracing, the truth for one-bounce indirect light: per pixel and sample, a cosine-distributed
// bounce direction around the receiver's normal, the closest hit y through the BVH (raytrace_bvh.wgsl), and
// the direct light at y from one light picked in proportion to its power, with a shadow ray, plus every sun's
// with a shadow ray of its own. With the cosine pdf cos/pi the estimate of the reflected radiance is
// rho(x) * L(y -> x), and L(y -> x) = rho(y)/pi * (I * attenuation(d) * cos(theta_y) * V / p_light
// + sum over suns of E * cos(theta_y) * V). Hits reflect their material's mean
// albedo, carried in the triangle's w components (see core/src/accel/scene_bvh.rs). Random numbers: a PCG hash of the pixel, the sample
// index and the seed, so a frame is reproducible. Composed after common.wgsl, raytrace_bvh.wgsl and vpl_basis.wgsl.
// `PtStep` mirrors `PtStepUniform` in core/src/technique/pathtraced/mod.rs.

struct PtStep {
    first_sample: u32,
    sample_count: u32,
    total_samples: u32,
    light_count: u32,
    bias: f32,
    seed: u32,
    sun_count: u32,
    sun_ray_length: f32,
    // Per sun: the direction its light travels, and colour times illuminance.
    sun_direction: array<vec4<f32>, 4>,
    sun_radiance: array<vec4<f32>, 4>,
}

// `shadow_near` holds the cumulative light-selection probability (the last light's is 1).
@group(1) @binding(2) var<storage, read> lights: array<Light>;
@group(1) @binding(3) var<uniform> step: PtStep;
@group(2) @binding(0) var<storage, read_write> indirect_out: array<vec4<f32>>;

fn pt_hash(x: u32) -> u32 {
    let state = x * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn pt_unit(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

// Index of the light whose cumulative probability first exceeds u.
fn pt_pick_light(u: f32) -> u32 {
    var lo = 0u;
    var hi = step.light_count - 1u;
    loop {
        if lo >= hi {
            break;
        }
        let mid = (lo + hi) / 2u;
        if lights[mid].shadow_near <= u {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

@compute @workgroup_size(8, 8)
fn pathtrace_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let width = u32(frame.viewport.x);
    let height = u32(frame.viewport.y);
    if id.x >= width || id.y >= height || (step.light_count == 0u && step.sun_count == 0u) {
        return;
    }
    let s = load_surface(vec2<i32>(id.xy));
    if !s.is_geometry {
        return;
    }
    let eps = step.bias * max(1.0, length(frame.camera_position.xyz - s.position));
    let origin = s.position + s.normal * eps;
    let basis = vpl_basis(s.normal);
    let pixel_hash = pt_hash(id.x + pt_hash(id.y + pt_hash(step.seed)));
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < step.sample_count; k++) {
        let i = step.first_sample + k;
        let h0 = pt_hash(pixel_hash ^ (i * 0x9e3779b9u));
        let h1 = pt_hash(h0);
        let h2 = pt_hash(h1);
        // Cosine-distributed direction.
        let u = pt_unit(h0);
        let phi = 2.0 * PI * pt_unit(h1);
        let r = sqrt(u);
        let dir = normalize(basis * vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u, 0.0))));
        let hit = bvh_closest_hit(origin, dir, BVH_MISS);
        if hit.t >= BVH_MISS {
            continue;
        }
        let y = origin + dir * hit.t;
        let tri = bvh_triangles[hit.triangle];
        let albedo_y = vec3<f32>(tri.v0.w, tri.e1.w, tri.e2.w);
        var n_y = normalize(cross(tri.e1.xyz, tri.e2.xyz));
        if dot(n_y, dir) > 0.0 {
            n_y = -n_y;
        }
        let shadow_origin_y = y + n_y * eps;
        for (var k = 0u; k < step.sun_count; k++) {
            let l_sun = -step.sun_direction[k].xyz;
            let cos_sun = dot(n_y, l_sun);
            if cos_sun > 0.0 && !bvh_occluded(shadow_origin_y, l_sun, step.sun_ray_length) {
                sum += albedo_y / PI * step.sun_radiance[k].xyz * cos_sun;
            }
        }
        if step.light_count == 0u {
            continue;
        }
        let li = pt_pick_light(pt_unit(h2));
        let p_light = lights[li].shadow_near - select(0.0, lights[max(li, 1u) - 1u].shadow_near, li > 0u);
        if p_light <= 0.0 {
            continue;
        }
        let light = lights[li];
        let to_light = light.position - y;
        let d = length(to_light);
        if !(d > 0.0) || d >= light.range {
            continue;
        }
        let l = to_light / d;
        let cos_y = dot(n_y, l);
        if cos_y <= 0.0 {
            continue;
        }
        let y_eps = eps;
        let shadow_origin = y + n_y * y_eps;
        let shadow_distance = length(light.position - shadow_origin);
        if bvh_occluded(shadow_origin, (light.position - shadow_origin) / shadow_distance, shadow_distance - y_eps) {
            continue;
        }
        let irradiance = light.radiance * (attenuation(d, light.range) * cos_y * spot_factor(light, -l) / p_light);
        sum += albedo_y / PI * irradiance;
    }
    let index = id.y * width + id.x;
    count_work(vec2<i32>(id.xy), WORK_INDIRECT_CLOSEST_HIT_RAYS, bvh_closest_rays);
    count_work(vec2<i32>(id.xy), WORK_INDIRECT_SHADOW_RAYS, bvh_shadow_rays);
    indirect_out[index] += vec4<f32>(s.albedo * sum / f32(step.total_samples), 0.0);
}
