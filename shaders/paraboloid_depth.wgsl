// Depth-only rendering of one paraboloid shadow map (a VPL's hemisphere, Brabec et al. 2002). The view comes
// per tile through a dynamic offset; composed after vpl_basis.wgsl (the lookup uses the same basis). Clip space is
// (dir.x, dir.y, depth * w, w) with w = 1 + dir.z, so x/w, y/w = dir.xy / (1 + dir.z) and clipping against
// |x|, |y| <= w cuts most of the back hemisphere; the fragment stage cuts the rest. Keep `ParaboloidView` in sync with core/src/services/cube_shadows.rs.

struct ParaboloidView {
    // xyz: centre, w: near
    centre: vec4<f32>,
    // xyz: unit normal, w: far
    normal: vec4<f32>,
}

@group(0) @binding(0) var<uniform> view: ParaboloidView;

struct ParaboloidOut {
    @builtin(position) clip: vec4<f32>,
    // signed height above the map's plane (affine in world space)
    @location(0) height: f32,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> ParaboloidOut {
    return paraboloid_project(position);
}

fn paraboloid_project(position: vec3<f32>) -> ParaboloidOut {
    let basis = vpl_basis(view.normal.xyz);
    let rel = position - view.centre.xyz;
    let local = vec3<f32>(dot(rel, basis[0]), dot(rel, basis[1]), dot(rel, basis[2]));
    let d = max(length(local), 1e-20);
    let dir = local / d;
    let depth = (d - view.centre.w) / (view.normal.w - view.centre.w);
    let w = 1.0 + dir.z;
    var out: ParaboloidOut;
    out.clip = vec4<f32>(dir.x, dir.y, depth * w, w);
    out.height = local.z;
    return out;
}

// The projection is not linear: a triangle behind the plane whose corners land around the rim (the one the VPL
// sits on, say) would be interpolated straight across the map's centre. Its interpolated height is negative
// there, so such fragments are dropped; so is the part of a triangle that crosses the plane.
@fragment
fn fs_main(in: ParaboloidOut) {
    if in.height < 0.0 {
        discard;
    }
}

// Alpha-tested casters (cut-out materials), as in shadow_depth.wgsl (material.wgsl's cutoff test).

struct ParaboloidMaskedOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) height: f32,
    @location(1) uv: vec2<f32>,
}

@vertex
fn vs_masked(@location(0) position: vec3<f32>, @location(2) uv: vec2<f32>) -> ParaboloidMaskedOut {
    let p = paraboloid_project(position);
    var out: ParaboloidMaskedOut;
    out.clip = p.clip;
    out.height = p.height;
    out.uv = uv;
    return out;
}

@fragment
fn fs_masked(in: ParaboloidMaskedOut) {
    if in.height < 0.0 || material_cut_out(in.uv) {
        discard;
    }
}
