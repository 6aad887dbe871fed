//! Reference: one cube shadow map per light, binary visibility. This is the oracle every other technique is
//! compared with, and the test oracle of the image tests.
//!
//! Per frame:
//! 1. Cull each light's range sphere (radius `L_att`) against the view frustum; the others contribute nothing.
//! 2. Split the visible lights into batches of as many cube maps as fit the atlas budget.
//! 3. Per batch (one step): render the batch's cube maps into the reused atlas (chunk-culled per light and
//!    per face), then shade every pixel with the batch's lights that its tile's list holds (the renderer's
//!    tiled light lists: the others cannot reach it) and add the result into the HDR target.
//!
//! Memory is the atlas of one batch plus the renderer's 64 bytes per visible light, whatever the number of lights.

use super::{check_param, FrameContext, OverlayLayer, Param, ParamError, ParamValue, Technique, TechniqueCounts};
use crate::error::GpuError;
use crate::gpu::GpuContext;
use crate::scene::PointLight;
use crate::services::cube_params::CubeMapParams;
use crate::services::cube_shadows::{CubeAtlas, CubeShadowRenderer};
use crate::services::layouts::SharedLayouts;
use crate::services::per_light_shadows::PerLightShadows;

/// The reference's parameters: those of every cube-map technique.
pub type ReferenceParams = CubeMapParams;

pub struct Reference {
    pub params: ReferenceParams,
    shadows: PerLightShadows,
    counts: TechniqueCounts,
}

impl Reference {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts) -> Reference {
        Reference {
            params: ReferenceParams::default(),
            shadows: PerLightShadows::new(gpu, layouts, CubeShadowRenderer::new(gpu)),
            counts: TechniqueCounts::default(),
        }
    }
}

impl Technique for Reference {
    fn key(&self) -> &'static str {
        "reference"
    }

    fn label(&self) -> &'static str {
        "Reference"
    }

    fn params(&self) -> Vec<Param> {
        self.params.params()
    }

    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        check_param(self.key(), &self.params(), key, value)?;
        let known = self.params.set(key, value);
        debug_assert!(known, "check_param accepted an unknown key");
        Ok(())
    }

    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        let batches = self.shadows.prepare(ctx, &self.params);
        self.counts = TechniqueCounts { lights_visible: self.shadows.visible_lights(), batches, ..Default::default() };
        Ok(batches)
    }

    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        let stats = self.shadows.encode_batch(ctx, step, encoder, ctx.scene.cube_geometry(), &self.params);
        self.counts.add_cube_stats(&stats);
        Ok(())
    }

    fn step_label(&self) -> &'static str {
        "shadow maps + shading"
    }

    fn shadow_atlas(&self) -> Option<(&CubeAtlas, &'static str)> {
        self.shadows.atlas().map(|a| (a, "cube maps of the last batch, six faces per light (+x -x +y -y +z -z)"))
    }

    fn counts(&self) -> TechniqueCounts {
        self.counts.clone()
    }

    fn uses_light_tiles(&self) -> bool {
        true
    }

    fn overlays(&self, lights: &[PointLight]) -> Vec<OverlayLayer> {
        super::light_overlays(lights)
    }
}
