//! Uniform and storage layouts shared between Rust and WGSL. Each struct names the WGSL struct it mirrors;
//! size asserts catch a field added on one side only.

use glam::{Mat4, Vec3};

use crate::scene::PointLight;

/// Mirrors `Frame` in `common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniform {
    pub clip_from_world: [[f32; 4]; 4],
    pub world_from_clip: [[f32; 4]; 4],
    pub camera_position: [f32; 4],
    pub viewport: [f32; 4],
    pub ambient: [f32; 4],
    pub background: [f32; 4],
    pub tonemap: [f32; 4],
    /// x: component shown (0 total, 1 direct, 2 indirect), y: indirect display gain, z: 1 when an indirect
    /// technique runs.
    pub indirect: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<FrameUniform>() == 224);

/// Mirrors `Camera` in `gbuffer.wgsl` and `Face` in `shadow_depth.wgsl`: one matrix, padded to the 256-byte
/// dynamic-offset alignment so an array of them can be indexed per draw.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MatrixUniform {
    pub clip_from_world: [[f32; 4]; 4],
    /// A cube face's centre (xyz) and how far a pushed vertex moves away from it per unit of its view depth (w;
    /// `Face` in `shadow_depth.wgsl`, [`crate::services::cube_shadows::CubeGeometry::push_per_depth`]).
    pub eye_push: [f32; 4],
    pub _pad: [[f32; 4]; 11],
}
const _: () = assert!(std::mem::size_of::<MatrixUniform>() == 256);

impl MatrixUniform {
    pub fn new(m: Mat4) -> Self {
        MatrixUniform { clip_from_world: m.to_cols_array_2d(), eye_push: [0.0; 4], _pad: [[0.0; 4]; 11] }
    }
}

/// Mirrors `Light` in `common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuLight {
    pub position: [f32; 3],
    pub range: f32,
    pub radiance: [f32; 3],
    pub shadow_near: f32,
    /// Spot direction (zero for omnidirectional lights).
    pub spot_direction: [f32; 3],
    /// Cone falloff: factor = saturate(cos * scale + offset)^2; 0 and 1 for omnidirectional lights.
    pub spot_scale: f32,
    pub spot_offset: f32,
    pub _pad: [f32; 3],
}
const _: () = assert!(std::mem::size_of::<GpuLight>() == 64);

impl GpuLight {
    pub fn new(light: &PointLight) -> Self {
        let (direction, (scale, offset)) = match light.spot {
            Some(s) => (s.direction, s.scale_offset()),
            None => (Vec3::ZERO, (0.0, 1.0)),
        };
        GpuLight {
            position: light.position.to_array(),
            range: light.range,
            radiance: (light.color * light.intensity).to_array(),
            shadow_near: shadow_near(light.range),
            spot_direction: direction.to_array(),
            spot_scale: scale,
            spot_offset: offset,
            _pad: [0.0; 3],
        }
    }
}

/// Near plane of a light's cube shadow map: small against its range, so close occluders still cast shadows,
/// large enough to keep 32-bit depth precise at the range.
pub fn shadow_near(range: f32) -> f32 {
    (range * 0.002).clamp(1e-4, 0.05)
}
