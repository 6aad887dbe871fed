// ReSTIR step 4, spatial reuse (Algorithm 5, lines 14-19), and in unbiased mode the final sample's
// visibility: the pixel's reservoir (after temporal reuse, reservoirs_in) combined with those of `spatial` random
// neighbours within `radius` pixels whose surfaces are alike (depth, normal), into reservoirs_out. Biased: Algorithm 4.
// Unbiased: Algorithm 6's 1/Z, Z counting the M of the inputs that could have drawn y (p̂ > 0 at their surface
// and y visible from it: a shadow ray from each input but the one y came from, whose W > 0 says so).
// Unbiased mode then keeps y's visibility from the pixel in W (W = 0 when blocked; the ray is also the centre's
// Z test, and none is needed when y is the pixel's own sample, which its W > 0 says it sees): every reservoir's
// W is then 0 where its pixel cannot see its sample, which the Z tests rely on. Biased mode leaves W as the
// paper does (the shading traces the ray). Composed after common.wgsl, raytrace_bvh.wgsl,
// restir/reservoir.wgsl and restir/trace.wgsl.

// = MAX_SPATIAL in core/src/technique/restir/params.rs.
const RESTIR_MAX_SPATIAL: u32 = 32u;

@compute @workgroup_size(8, 8)
fn spatial_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = restir_size();
    if any(id.xy >= size) {
        return;
    }
    let pixel = vec2<i32>(id.xy);
    let index = restir_index(id.xy);
    let center = reservoirs_in[index];
    let s = load_surface(pixel);
    if !s.is_geometry {
        reservoirs_out[index] = center;
        return;
    }
    restir_seed(id.xy, 2u);
    let camera = frame.camera_position.xyz;
    let depth = distance(camera, s.position);
    var r = restir_empty();
    var p_hat_y = 0.0;
    // The input y came from: 0 the pixel itself, i + 1 neighbour i.
    var taken = 0u;
    let p_center = restir_target(s, center.light);
    if restir_update(&r, center.light, p_center * center.w * center.m, center.m) {
        p_hat_y = p_center;
    }
    var evaluations = 1u;
    var neighbours: array<vec2<i32>, RESTIR_MAX_SPATIAL>;
    var count = 0u;
    let k = min(restir.spatial, RESTIR_MAX_SPATIAL);
    for (var i = 0u; i < k; i++) {
        // Uniform in the disc of `radius` pixels.
        let angle = 2.0 * PI * restir_random();
        let offset = restir.radius * sqrt(restir_random()) * vec2<f32>(cos(angle), sin(angle));
        let q = pixel + vec2<i32>(round(offset));
        if all(q == pixel) || any(q < vec2<i32>(0)) || any(q >= vec2<i32>(size)) {
            continue;
        }
        let n = load_surface(q);
        if !n.is_geometry || !restir_similar(depth, s.normal, distance(camera, n.position), n.normal) {
            continue;
        }
        let neighbour = reservoirs_in[restir_index(vec2<u32>(q))];
        let p_neighbour = restir_target(s, neighbour.light);
        evaluations += 1u;
        if restir_update(&r, neighbour.light, p_neighbour * neighbour.w * neighbour.m, neighbour.m) {
            p_hat_y = p_neighbour;
            taken = count + 1u;
        }
        neighbours[count] = q;
        count += 1u;
    }

    if restir.unbiased != 0u {
        // The final sample's visibility from the pixel.
        var visible = r.light != RESTIR_NONE && p_hat_y > 0.0;
        if visible && taken != 0u {
            visible = !restir_occluded(s.position, s.normal, r.light);
        }
        var z = 0.0;
        if visible {
            z += center.m;
        }
        for (var i = 0u; i < count; i++) {
            let q = neighbours[i];
            let neighbour = reservoirs_in[restir_index(vec2<u32>(q))];
            if taken == i + 1u {
                z += neighbour.m;
                continue;
            }
            if r.light == RESTIR_NONE {
                continue;
            }
            let n = load_surface(q);
            evaluations += 1u;
            if restir_target(n, r.light) > 0.0 && !restir_occluded(n.position, n.normal, r.light) {
                z += neighbour.m;
            }
        }
        r.w = restir_contribution_weight(r.w_sum, z, p_hat_y);
        if !visible {
            r.w = 0.0;
        }
    } else {
        r.w = restir_contribution_weight(r.w_sum, r.m, p_hat_y);
    }
    count_work(pixel, WORK_LIGHT_EVALUATIONS, evaluations);
    count_work(pixel, WORK_SHADOW_RAYS, bvh_shadow_rays);
    reservoirs_out[index] = restir_stamp(r, s);
}
