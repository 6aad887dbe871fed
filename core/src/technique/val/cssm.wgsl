// Convolution soft shadow maps (Annen et al. 2008) for virtual area lights (Dong et al. 2009 sections 4.1-4.2,
// 6): the depth test f(d, z) = H(z - d) of a VAL's paraboloid map is expanded into a Fourier series of 4 terms,
//   f(d, z) ~ 1/2 + 2 sum_k (1/c_k) [cos(c_k d) sin(c_k z) - sin(c_k d) cos(c_k z)],  c_k = pi (2k - 1),
// over depths normalised to the map's [near, far] (what the atlas stores), so filtering f over a region is
// filtering the basis images cos(c_k z), sin(c_k z) (and, for the blocker search, z cos(c_k z), z sin(c_k z),
// z), which mip-mapping does once per map. cssm_basis writes level 0 of the basis textures from the depth
// atlas: `basis_a` = (cos, sin) of terms 1-2 and `basis_b` of terms 3-4, 8 bit as (v + 1) / 2 (the paper: "4
// term, 8 bit"); `basis_za` = z (cos, sin) of terms 1-2 and `basis_zb` = (z cos, z sin) of term 3 and z
// itself, 16-bit float (the paper: "4 term, 16 bit half float"; the fourth term of basis-z gives way to z,
// whose mean the blocker average needs, because a stage may write 4 storage textures at most). cssm_mip
// averages each level into the next. Tiles are powers of two, so no mip texel spans two VALs' maps.
// Composed alone; the lookups are in val/gather.wgsl.

@group(0) @binding(0) var cssm_depth: texture_2d<f32>;
@group(0) @binding(1) var out_a: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(2) var out_b: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(3) var out_za: texture_storage_2d<rgba16float, write>;
@group(0) @binding(4) var out_zb: texture_storage_2d<rgba16float, write>;

const CSSM_PI: f32 = 3.14159265358979;

fn c_k(k: u32) -> f32 {
    return CSSM_PI * f32(2u * k + 1u);
}

@compute @workgroup_size(8, 8)
fn cssm_basis(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(out_a);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let z = clamp(textureLoad(cssm_depth, vec2<i32>(id.xy), 0).r, 0.0, 1.0);
    // The series is a square wave of period 2 in z - d: with depths in [0, 1] a receiver near the VAL under an
    // empty texel (z = 1, d ~ 0) sits on the wave's next edge and comes out half lit, so the phase uses z / 2
    // (z - d in (-1/2, 1/2), half a period from either edge) at the cost of a twice wider step.
    let h = 0.5 * z;
    let t1 = vec2<f32>(cos(c_k(0u) * h), sin(c_k(0u) * h));
    let t2 = vec2<f32>(cos(c_k(1u) * h), sin(c_k(1u) * h));
    let t3 = vec2<f32>(cos(c_k(2u) * h), sin(c_k(2u) * h));
    let t4 = vec2<f32>(cos(c_k(3u) * h), sin(c_k(3u) * h));
    textureStore(out_a, vec2<i32>(id.xy), vec4<f32>(t1, t2) * 0.5 + 0.5);
    textureStore(out_b, vec2<i32>(id.xy), vec4<f32>(t3, t4) * 0.5 + 0.5);
    textureStore(out_za, vec2<i32>(id.xy), vec4<f32>(t1, t2) * z);
    textureStore(out_zb, vec2<i32>(id.xy), vec4<f32>(t3 * z, z, 0.0));
}

@group(0) @binding(5) var in_a: texture_2d<f32>;
@group(0) @binding(6) var in_b: texture_2d<f32>;
@group(0) @binding(7) var in_za: texture_2d<f32>;
@group(0) @binding(8) var in_zb: texture_2d<f32>;

fn average(t: texture_2d<f32>, p: vec2<i32>) -> vec4<f32> {
    return 0.25 * (textureLoad(t, p, 0) + textureLoad(t, p + vec2<i32>(1, 0), 0) + textureLoad(t, p + vec2<i32>(0, 1), 0)
        + textureLoad(t, p + vec2<i32>(1, 1), 0));
}

// Level L + 1 from level L (the `in_*` views are level L, the `out_*` views level L + 1).
@compute @workgroup_size(8, 8)
fn cssm_mip(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(out_a);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let p = vec2<i32>(id.xy) * 2;
    textureStore(out_a, vec2<i32>(id.xy), average(in_a, p));
    textureStore(out_b, vec2<i32>(id.xy), average(in_b, p));
    textureStore(out_za, vec2<i32>(id.xy), average(in_za, p));
    textureStore(out_zb, vec2<i32>(id.xy), average(in_zb, p));
}
