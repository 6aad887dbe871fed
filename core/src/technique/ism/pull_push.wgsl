// ISM step 3, pull-push hole filling (Ritschel et al. 2008, section 3.3): clearing, the pull (each coarse texel
// the mean of its non-empty children within the depth threshold of the nearest), the push (each empty fine texel
// the bilinear mean of the coarse texels around it, over those within the threshold of the nearest) and the
// resolve of level 0 into the atlas. One dispatch per level; x: the texels of a tile's level, y: the tile.
// Mirrors core/src/technique/ism/pull_push.rs (the CPU twin) operation for operation. Composed after
// ism/paraboloid.wgsl. `PullPushLevel` mirrors `LevelUniform` in core/src/technique/ism/passes.rs.

struct PullPushLevel {
    fine_res: u32,
    coarse_res: u32,
    // offsets of the levels' first tiles in `pyramid`, in texels
    fine_offset: u32,
    coarse_offset: u32,
    tiles: u32,
    threshold: f32,
    tiles_per_row: u32,
    _pad: u32,
}

@group(0) @binding(0) var<storage, read_write> pyramid: array<f32>;
@group(0) @binding(1) var<uniform> level: PullPushLevel;
@group(1) @binding(0) var atlas_out: texture_storage_2d<r32float, write>;

fn pp_is_empty(z: f32) -> bool {
    return !(z < ISM_EMPTY);
}

// The mean of the non-empty `values` within the threshold of their nearest, weighted by `weights` (EMPTY when
// all are empty): `near_mean` of pull_push.rs.
fn pp_near_mean(values: array<f32, 4>, weights: array<f32, 4>) -> f32 {
    var z_min = ISM_EMPTY;
    for (var k = 0u; k < 4u; k++) {
        if !pp_is_empty(values[k]) && weights[k] > 0.0 {
            z_min = min(z_min, values[k]);
        }
    }
    if pp_is_empty(z_min) {
        return ISM_EMPTY;
    }
    let limit = z_min * (1.0 + level.threshold);
    var sum = 0.0;
    var weight = 0.0;
    for (var k = 0u; k < 4u; k++) {
        if !pp_is_empty(values[k]) && weights[k] > 0.0 && values[k] <= limit {
            sum += values[k] * weights[k];
            weight += weights[k];
        }
    }
    if weight > 0.0 {
        return sum / weight;
    }
    return ISM_EMPTY;
}

@compute @workgroup_size(64)
fn clear_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = level.fine_res * level.fine_res;
    if id.x >= n || id.y >= level.tiles {
        return;
    }
    pyramid[level.fine_offset + id.y * n + id.x] = ISM_EMPTY;
}

@compute @workgroup_size(64)
fn pull_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let cres = level.coarse_res;
    let fres = level.fine_res;
    if id.x >= cres * cres || id.y >= level.tiles {
        return;
    }
    let x = id.x % cres;
    let y = id.x / cres;
    let fine = level.fine_offset + id.y * fres * fres;
    var values = array<f32, 4>(ISM_EMPTY, ISM_EMPTY, ISM_EMPTY, ISM_EMPTY);
    var weights = array<f32, 4>(0.0, 0.0, 0.0, 0.0);
    for (var k = 0u; k < 4u; k++) {
        let fx = 2u * x + (k & 1u);
        let fy = 2u * y + (k >> 1u);
        if fx < fres && fy < fres {
            values[k] = pyramid[fine + fy * fres + fx];
            weights[k] = 1.0;
        }
    }
    pyramid[level.coarse_offset + id.y * cres * cres + id.x] = pp_near_mean(values, weights);
}

@compute @workgroup_size(64)
fn push_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let fres = level.fine_res;
    let cres = i32(level.coarse_res);
    if id.x >= fres * fres || id.y >= level.tiles {
        return;
    }
    let at = level.fine_offset + id.y * fres * fres + id.x;
    if !pp_is_empty(pyramid[at]) {
        return;
    }
    let x = id.x % fres;
    let y = id.x / fres;
    // The fine texel's centre in coarse texel units.
    let c = (vec2<f32>(f32(x), f32(y)) + 0.5) * 0.5 - 0.5;
    let c0 = floor(c);
    let f = c - c0;
    let i0 = vec2<i32>(c0);
    let coarse = level.coarse_offset + id.y * level.coarse_res * level.coarse_res;
    var values = array<f32, 4>(ISM_EMPTY, ISM_EMPTY, ISM_EMPTY, ISM_EMPTY);
    let weights = array<f32, 4>((1.0 - f.x) * (1.0 - f.y), f.x * (1.0 - f.y), (1.0 - f.x) * f.y, f.x * f.y);
    for (var k = 0u; k < 4u; k++) {
        let s = clamp(i0 + vec2<i32>(i32(k & 1u), i32(k >> 1u)), vec2<i32>(0), vec2<i32>(cres - 1));
        values[k] = pyramid[coarse + u32(s.y * cres + s.x)];
    }
    pyramid[at] = pp_near_mean(values, weights);
}

@compute @workgroup_size(64)
fn resolve_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let res = level.fine_res;
    if id.x >= res * res || id.y >= level.tiles {
        return;
    }
    let z = pyramid[level.fine_offset + id.y * res * res + id.x];
    let texel = ism_atlas_texel(id.y, vec2<u32>(id.x % res, id.x / res), level.tiles_per_row, res);
    textureStore(atlas_out, texel, vec4<f32>(z, 0.0, 0.0, 0.0));
}
