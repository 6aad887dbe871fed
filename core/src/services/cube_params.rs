//! The parameters every cube-shadow-map technique has (the reference, LightCluster, ...), described and set
//! in one place: a shared parameter block, not a copy in each technique.

use crate::contract::params::{Param, ParamKind, ParamValue};
use crate::gpu::GpuContext;
use crate::services::cube_shadows::DEFAULT_ATLAS_BUDGET_BYTES;

/// The parameters every cube-shadow-map technique has (the reference, LightCluster, ...), described and set
/// in one place.
#[derive(Clone, Debug, PartialEq)]
pub struct CubeMapParams {
    /// Texels per cube face.
    pub shadow_resolution: u32,
    /// Constant depth bias in world units.
    pub bias_world: f32,
    /// Normal offset in shadow-map texels.
    pub normal_offset_texels: f32,
    /// Memory for one batch's atlas, in MiB.
    pub atlas_budget_mib: u32,
    /// Cull chunks per light and per cube face. Off draws every chunk into every face, which is the
    /// conventional shadow mapping the INSM paper compares with (`n N` triangles).
    pub cull: bool,
}

impl Default for CubeMapParams {
    fn default() -> Self {
        CubeMapParams {
            shadow_resolution: 1024,
            bias_world: 0.01,
            normal_offset_texels: 1.5,
            atlas_budget_mib: (DEFAULT_ATLAS_BUDGET_BYTES >> 20) as u32,
            cull: true,
        }
    }
}

impl CubeMapParams {
    pub fn params(&self) -> Vec<Param> {
        vec![
            Param {
                key: "shadow_res",
                label: "Cube resolution",
                help: "Texels per cube-map face",
                kind: ParamKind::Int { min: 16, max: 4096 },
                value: ParamValue::Int(self.shadow_resolution as i64),
            },
            Param {
                key: "bias",
                label: "Depth bias",
                help: "Constant bias in world units",
                kind: ParamKind::Float { min: 0.0, max: 1.0 },
                value: ParamValue::Float(self.bias_world),
            },
            Param {
                key: "normal_offset",
                label: "Normal offset",
                help: "Receiver offset along its normal, in shadow-map texels",
                kind: ParamKind::Float { min: 0.0, max: 16.0 },
                value: ParamValue::Float(self.normal_offset_texels),
            },
            Param {
                key: "atlas_mib",
                label: "Batch memory (MiB)",
                help: "Memory of one batch of cube maps; more per batch means fewer passes",
                kind: ParamKind::Int { min: 1, max: 4096 },
                value: ParamValue::Int(self.atlas_budget_mib as i64),
            },
            Param {
                key: "cull",
                label: "Cull per light and face",
                help: "Draw only the chunks within a light's range and a face's pyramid (off: every chunk into every \
                       face, conventional shadow mapping)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(self.cull),
            },
        ]
    }

    /// Set one of these parameters (already range-checked); false when `key` is not one of them.
    pub fn set(&mut self, key: &str, value: &ParamValue) -> bool {
        match (key, value) {
            ("shadow_res", ParamValue::Int(v)) => self.shadow_resolution = *v as u32,
            ("bias", ParamValue::Float(v)) => self.bias_world = *v,
            ("normal_offset", ParamValue::Float(v)) => self.normal_offset_texels = *v,
            ("atlas_mib", ParamValue::Int(v)) => self.atlas_budget_mib = *v as u32,
            ("cull", ParamValue::Bool(v)) => self.cull = *v,
            _ => return false,
        }
        true
    }

    /// Cube-map resolution the device allows, and the atlas budget in bytes.
    pub fn resolution_and_budget(&self, gpu: &GpuContext) -> (u32, u64) {
        let res = self.shadow_resolution.min(gpu.device.limits().max_texture_dimension_2d);
        (res, self.atlas_budget_mib as u64 * (1 << 20))
    }
}
