// Step 6 of Colom et al. 2022, equation 6: every shading point sums the batch's lights (VPL clusters, or every
// VPL when VPLs are not clustered) with its own BRDF and geometry term (vpl_term of vpl_common.wgsl) and the
// approximated visibility V~ of its shading-point clusters' representatives (fuzzy/visibility.wgsl's bits):
// - hard (mode 0): its nearest cluster's visibility;
// - fuzzy (mode 1, equation 8): the mean over its F nearest clusters;
// - weighted (mode 2, equations 9-10): the mean weighted by the inverse distances w_f = (1 / R_f) / W.
// A point that matched no cluster by normal (inverse distances all 0) uses its by-position cluster alone.
// Composed after common.wgsl and vpl_common.wgsl (group 2: lights, batch, indirect output).
// `FuzzyShade` mirrors core/src/technique/fuzzy/mod.rs.

const FUZZY_MAX_F: u32 = 8u;
const FUZZY_NONE: u32 = 0xffffffffu;

struct FuzzyShade {
    fuzziness: u32,
    mode: u32,
    words_per_row: u32,
    _pad: u32,
}

@group(1) @binding(0) var<uniform> shade: FuzzyShade;
// Per pixel, F entries of (cluster, bitcast inverse distance), from fuzzy/kmeans_final.wgsl.
@group(1) @binding(1) var<storage, read> sp_assignment: array<u32>;
@group(1) @binding(2) var<storage, read> vis_bits: array<u32>;

@compute @workgroup_size(8, 8)
fn fuzzy_shade_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let width = u32(frame.viewport.x);
    let height = u32(frame.viewport.y);
    if id.x >= width || id.y >= height {
        return;
    }
    let s = load_surface(vec2<i32>(id.xy));
    if !s.is_geometry {
        return;
    }
    let index = id.y * width + id.x;
    let f_max = clamp(shade.fuzziness, 1u, FUZZY_MAX_F);
    var rows: array<u32, FUZZY_MAX_F>;
    var w: array<f32, FUZZY_MAX_F>;
    var used = 0u;
    var total = 0.0;
    for (var f = 0u; f < f_max; f++) {
        let k = sp_assignment[(index * f_max + f) * 2u];
        if k == FUZZY_NONE {
            break;
        }
        rows[f] = k * shade.words_per_row;
        w[f] = bitcast<f32>(sp_assignment[(index * f_max + f) * 2u + 1u]);
        total += w[f];
        used++;
    }
    if used == 0u {
        return;
    }
    if shade.mode == 0u || total <= 0.0 {
        used = 1u;
        w[0] = 1.0;
    } else if shade.mode == 1u {
        for (var f = 0u; f < used; f++) {
            w[f] = 1.0 / f32(used);
        }
    } else {
        for (var f = 0u; f < used; f++) {
            w[f] = w[f] / total;
        }
    }
    var sum = vec3<f32>(0.0);
    var bits_read = 0u;
    for (var k = 0u; k < gather.vpl_count; k++) {
        let j = gather.first_vpl + k;
        let term = vpl_term(s, vpls[j]);
        if max(term.x, max(term.y, term.z)) > 0.0 {
            bits_read += used;
            let word = j >> 5u;
            let bit = j & 31u;
            var v = 0.0;
            for (var f = 0u; f < used; f++) {
                v += w[f] * f32((vis_bits[rows[f] + word] >> bit) & 1u);
            }
            sum += term * v;
        }
    }
    count_work(vec2<i32>(id.xy), WORK_VPL_EVALUATIONS, gather.vpl_count);
    // A lookup of the visibility V~ is one bit of a shading-point cluster's row (one "tap" each).
    count_work(vec2<i32>(id.xy), WORK_INDIRECT_SHADOW_LOOKUPS, bits_read);
    count_work(vec2<i32>(id.xy), WORK_INDIRECT_FILTER_TAPS, bits_read);
    indirect_out[index] += vec4<f32>(s.albedo / PI * sum, 0.0);
}
