// One VPL's layout and the radiance it sends to a receiver, for the gathers (through vpl_common.wgsl, which
// adds the batch's bindings) and for the interleaving blur's ratio estimator (vpl_blur.wgsl). Composed after
// common.wgsl. `Vpl` mirrors `GpuVpl` in core/src/vpl/mod.rs.

struct Vpl {
    // xyz: position
    position: vec4<f32>,
    // xyz: unit normal
    normal: vec4<f32>,
    // rgb: reflected flux
    flux: vec4<f32>,
}

// Irradiance-like term of one VPL at a receiver, before visibility and the receiver's rho/pi:
// Phi/pi * cos(theta_i) cos(theta_x) / max(d^2, d_clamp^2). Zero (never NaN) when the receiver lies on the VPL,
// behind it, or faces away.
fn vpl_radiance(s: Surface, v: Vpl, clamp_sq: f32) -> vec3<f32> {
    let to_x = s.position - v.position.xyz;
    let d2 = dot(to_x, to_x);
    if !(d2 > 1e-12) {
        return vec3<f32>(0.0);
    }
    let w = to_x * inverseSqrt(d2);
    let cos_i = dot(v.normal.xyz, w);
    let cos_x = -dot(s.normal, w);
    if cos_i <= 0.0 || cos_x <= 0.0 {
        return vec3<f32>(0.0);
    }
    return v.flux.rgb * (cos_i * cos_x / (PI * max(d2, clamp_sq)));
}
