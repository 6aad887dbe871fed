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

use glam::Vec3;
use wgpu::util::DeviceExt;

use super::{
    accumulate_pass, check_param, depth_texture_entry, storage_entry, uniform_entry, CubeMapParams, FrameContext,
    OverlayLayer, Param, ParamError, ParamValue, Technique, TechniqueCounts,
};
use crate::error::GpuError;
use crate::gpu::GpuContext;
use crate::renderer::cube_shadows::{CubeCaster, CubeGeometry, CubeShadowRenderer, CubeStats};
use crate::renderer::SharedLayouts;
use crate::scene::PointLight;
use crate::shaders;

/// Mirrors `Batch` in `reference_shade.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ReferenceBatchUniform {
    first_light: u32,
    light_count: u32,
    resolution: f32,
    bias_world: f32,
    normal_offset_texels: f32,
    tiles_per_row: u32,
    _pad: [f32; 2],
}
const _: () = assert!(std::mem::size_of::<ReferenceBatchUniform>() == 32);

/// The reference's parameters: those of every cube-map technique.
pub type ReferenceParams = super::CubeMapParams;

/// One cube shadow map per light, rendered batch by batch into a reused atlas, and the reference's hard-shadow
/// shading. The reference draws the scene into the cube maps; INSM draws its reconstructed meshes with the same
/// batches and the same shading, which is what makes the two comparable.
pub struct PerLightShadows {
    cubes: CubeShadowRenderer,
    pipeline: wgpu::RenderPipeline,
    group_layout: wgpu::BindGroupLayout,
    batch_uniform: wgpu::Buffer,
    bind_group: Option<wgpu::BindGroup>,
    /// The generation of the renderer's light buffer the bind group was made with.
    lights_generation: Option<u64>,
    /// Visible lights of this frame (the renderer's culling), in batch order.
    visible_count: usize,
    batch_size: usize,
}

impl PerLightShadows {
    /// `cubes` draws the geometry `encode_batch` will be given (the scene's, or another vertex layout).
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts, cubes: CubeShadowRenderer) -> PerLightShadows {
        let device = &gpu.device;
        let group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("reference shade"),
            entries: &[storage_entry(0), uniform_entry(1), depth_texture_entry(2)],
        });
        let module = shaders::create_module(device, "reference_shade", shaders::REFERENCE_SHADE);
        let pipeline = layouts.fullscreen_pipeline(
            device,
            "reference shade",
            &module,
            &[&group_layout, &layouts.light_tiles],
            SharedLayouts::HDR_FORMAT,
            true,
        );
        let batch_uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("reference batch"),
            contents: bytemuck::bytes_of(&ReferenceBatchUniform::zeroed_default()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        PerLightShadows {
            cubes,
            pipeline,
            group_layout,
            batch_uniform,
            bind_group: None,
            lights_generation: None,
            visible_count: 0,
            batch_size: 1,
        }
    }

    /// The atlas of the last batch.
    pub fn atlas(&self) -> Option<&crate::renderer::cube_shadows::CubeAtlas> {
        self.cubes.atlas()
    }

    /// Lights that passed the frustum culling of the last `prepare`.
    pub fn visible_lights(&self) -> usize {
        self.visible_count
    }

    /// Steps 1-2: cull lights against the view frustum, split them into batches; returns the batch count.
    pub fn prepare(&mut self, ctx: &FrameContext, params: &CubeMapParams) -> usize {
        // Step 1 is the renderer's light culling (`ctx.visible_lights`).
        self.visible_count = ctx.visible_lights.indices.len();
        if self.visible_count == 0 {
            return 0;
        }
        let (res, budget) = params.resolution_and_budget(ctx.gpu);
        self.batch_size = CubeShadowRenderer::batch_capacity(ctx.gpu, res, budget).min(ctx.max_lights_per_step).max(1);
        let batches = self.visible_count.div_ceil(self.batch_size);

        let mut rebind = self.bind_group.is_none();
        rebind |= self.lights_generation != Some(ctx.visible_lights.generation);
        self.lights_generation = Some(ctx.visible_lights.generation);
        rebind |= self.cubes.ensure_atlas(ctx.gpu, res, self.batch_size.min(self.visible_count));
        if rebind {
            let atlas = self.cubes.atlas().expect("atlas was just ensured");
            self.bind_group = Some(ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("reference shade"),
                layout: &self.group_layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: ctx.visible_lights.buffer.buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: self.batch_uniform.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&atlas.view) },
                ],
            }));
        }
        batches
    }

    /// Step 3 for batch `batch`: its cube maps drawn from `geometry`, then its shading added to the HDR target.
    pub fn encode_batch(
        &mut self,
        ctx: &FrameContext,
        batch: usize,
        encoder: &mut wgpu::CommandEncoder,
        geometry: CubeGeometry<'_>,
        params: &CubeMapParams,
    ) -> CubeStats {
        let first = batch * self.batch_size;
        let last = (first + self.batch_size).min(self.visible_count);
        let casters: Vec<CubeCaster> = ctx.visible_lights.gpu[first..last]
            .iter()
            .map(|l| CubeCaster { position: Vec3::from_array(l.position), near: l.shadow_near, far: l.range })
            .collect();
        let geometry = CubeGeometry { cull: params.cull, ..geometry };
        let stats = self.cubes.render(ctx.gpu, geometry, ctx.timer, encoder, "shadow maps", &casters);

        let atlas = self.cubes.atlas().expect("prepare sized the atlas");
        let uniform = ReferenceBatchUniform {
            first_light: first as u32,
            light_count: (last - first) as u32,
            resolution: atlas.resolution as f32,
            bias_world: params.bias_world,
            normal_offset_texels: params.normal_offset_texels,
            tiles_per_row: atlas.tiles_per_row,
            _pad: [0.0; 2],
        };
        ctx.gpu.queue.write_buffer(&self.batch_uniform, 0, bytemuck::bytes_of(&uniform));
        let group = self.bind_group.as_ref().expect("prepare created the bind group");
        accumulate_pass(ctx, encoder, "shading", &self.pipeline, &[group, ctx.light_tiles.bind_group()]);
        stats
    }
}

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

impl ReferenceBatchUniform {
    fn zeroed_default() -> Self {
        bytemuck::Zeroable::zeroed()
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

    fn shadow_atlas(&self) -> Option<(&crate::renderer::cube_shadows::CubeAtlas, &'static str)> {
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
