//! Unshadowed: all visible lights, visibility 1, no shadow maps. The app's cheap preview while the camera or a
//! light moves, and the "no shadows" image that turns radiance into shadow factors for visibility comparisons.
//!
//! 1. Cull range spheres against the view frustum.
//! 2. Per step, shade a batch of lights in one full-screen pass (the batch is bounded only by
//!    `max_lights_per_step`; the whole frame is one step when unlimited); a pixel loops over the batch's lights
//!    in its tile's list (the renderer's tiled light lists).

use super::{check_param, FrameContext, OverlayLayer, Param, ParamError, ParamValue, Technique, TechniqueCounts};
use crate::error::GpuError;
use crate::gpu::bind::{storage_entry, uniform_entry};
use crate::gpu::GpuContext;
use crate::scene::PointLight;
use crate::services::layouts::SharedLayouts;
use crate::services::shade_pass::ShadePass;

use crate::shaders::WgslModule;
/// This technique's own WGSL modules; its registry entry lists them and the naga test validates them.
pub const SHADERS: &[WgslModule] = &[SHADE];
const SHADE: WgslModule = crate::shaders::wgsl!(
    "unshadowed_shade",
    ["shaders/common.wgsl", "shaders/light_tiles.wgsl", "core/src/technique/unshadowed/shade.wgsl"]
);

/// Mirrors `Batch` in `unshadowed/shade.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct UnshadowedBatchUniform {
    first_light: u32,
    light_count: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<UnshadowedBatchUniform>() == 16);

pub struct Unshadowed {
    shade: ShadePass,
    bind_group: Option<wgpu::BindGroup>,
    /// The generation of the renderer's light buffer the bind group was made with.
    lights_generation: Option<u64>,
    visible_count: usize,
    batch_size: usize,
    counts: TechniqueCounts,
}

impl Unshadowed {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts) -> Unshadowed {
        let entries = [storage_entry(0), uniform_entry(1)];
        Unshadowed {
            shade: ShadePass::new::<UnshadowedBatchUniform>(gpu, layouts, "unshadowed shade", &SHADE, &entries, true),
            bind_group: None,
            lights_generation: None,
            visible_count: 0,
            batch_size: 1,
            counts: TechniqueCounts::default(),
        }
    }
}

impl Technique for Unshadowed {
    fn key(&self) -> &'static str {
        "unshadowed"
    }

    fn label(&self) -> &'static str {
        "Unshadowed"
    }

    fn params(&self) -> Vec<Param> {
        Vec::new()
    }

    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        check_param(self.key(), &self.params(), key, value)
    }

    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        // The renderer culled and uploaded the lights (`ctx.visible_lights`).
        self.visible_count = ctx.visible_lights.indices.len();
        self.batch_size = self.visible_count.clamp(1, ctx.max_lights_per_step.min(super::MAX_LIGHT_WORK_PER_PASS));
        let batches = self.visible_count.div_ceil(self.batch_size);
        self.counts = TechniqueCounts { lights_visible: self.visible_count, batches, ..Default::default() };
        if self.visible_count == 0 {
            return Ok(0);
        }
        let generation = Some(ctx.visible_lights.generation);
        if self.lights_generation != generation || self.bind_group.is_none() {
            self.lights_generation = generation;
            self.bind_group = Some(self.shade.bind_group(
                ctx.gpu,
                &[
                    wgpu::BindGroupEntry { binding: 0, resource: ctx.visible_lights.buffer.buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: self.shade.batch_uniform().as_entire_binding() },
                ],
            ));
        }
        Ok(batches)
    }

    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        let first = step * self.batch_size;
        let last = (first + self.batch_size).min(self.visible_count);
        let uniform =
            UnshadowedBatchUniform { first_light: first as u32, light_count: (last - first) as u32, _pad: [0; 2] };
        self.shade.write_batch(ctx.gpu, &uniform);
        let group = self.bind_group.as_ref().expect("prepare created the bind group");
        self.shade.encode(ctx, encoder, "shading", group, None);
        Ok(())
    }

    /// Directional lights: the preview: no visibility, as for its point lights.
    fn directional_visibility(&self) -> super::DirectionalVisibility {
        super::DirectionalVisibility::None
    }

    fn step_label(&self) -> &'static str {
        "shading"
    }

    fn counts(&self) -> TechniqueCounts {
        self.counts.clone()
    }

    fn uses_light_tiles(&self) -> bool {
        true
    }

    /// The lights every technique shows (without them a user who chose the preview could not see the lights
    /// they place).
    fn overlays(&self, lights: &[PointLight]) -> Vec<OverlayLayer> {
        super::light_overlays(lights)
    }
}
