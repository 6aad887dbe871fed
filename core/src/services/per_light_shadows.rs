//! Per-light shadows: one cube shadow map per light, rendered batch by batch into a reused atlas, and hard-shadow
//! shading of each batch's lights (`shaders/per_light_shade.wgsl`). The reference technique is this service over
//! the scene's triangles; INSM runs it over its reconstructed meshes with the same batches and the same shading
//! (which is what makes the two comparable); LightCluster falls back to it when no two lights cluster.

use glam::Vec3;

use super::context::FrameContext;
use crate::gpu::bind::{depth_texture_entry, storage_entry, uniform_entry};
use crate::gpu::GpuContext;
use crate::services::cube_params::CubeMapParams;
use crate::services::cube_shadows::{CubeAtlas, CubeCaster, CubeGeometry, CubeShadowRenderer, CubeStats};
use crate::services::layouts::SharedLayouts;
use crate::services::shade_pass::ShadePass;
use crate::shaders;

/// Mirrors `Batch` in `per_light_shade.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct PerLightBatchUniform {
    first_light: u32,
    light_count: u32,
    resolution: f32,
    bias_world: f32,
    normal_offset_texels: f32,
    tiles_per_row: u32,
    _pad: [f32; 2],
}
const _: () = assert!(std::mem::size_of::<PerLightBatchUniform>() == 32);

/// One cube shadow map per light, rendered batch by batch into a reused atlas, and the reference's hard-shadow
/// shading. The reference draws the scene into the cube maps; INSM draws its reconstructed meshes with the same
/// batches and the same shading, which is what makes the two comparable.
pub struct PerLightShadows {
    cubes: CubeShadowRenderer,
    shade: ShadePass,
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
        let entries = [storage_entry(0), uniform_entry(1), depth_texture_entry(2)];
        let shade = ShadePass::new::<PerLightBatchUniform>(
            gpu,
            layouts,
            "per-light shade",
            &shaders::PER_LIGHT_SHADE,
            &entries,
            true,
        );
        PerLightShadows { cubes, shade, bind_group: None, lights_generation: None, visible_count: 0, batch_size: 1 }
    }

    /// The atlas of the last batch.
    pub fn atlas(&self) -> Option<&CubeAtlas> {
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
            self.bind_group = Some(self.shade.bind_group(
                ctx.gpu,
                &[
                    wgpu::BindGroupEntry { binding: 0, resource: ctx.visible_lights.buffer.buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: self.shade.batch_uniform().as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&atlas.view) },
                ],
            ));
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
        let res = self.cubes.atlas().map_or(1, |a| a.resolution);
        let casters: Vec<CubeCaster> = ctx.visible_lights.gpu[first..last]
            .iter()
            .map(|l| CubeCaster {
                position: Vec3::from_array(l.position),
                near: l.shadow_near,
                far: l.range,
                lookup_radius: CubeCaster::hard_lookup_radius(
                    l.range,
                    res,
                    params.normal_offset_texels,
                    params.bias_world,
                ),
            })
            .collect();
        let geometry = CubeGeometry { cull: params.cull, receivers: ctx.receivers, ..geometry };
        let stats = self.cubes.render(ctx.gpu, geometry, ctx.timer, encoder, "shadow maps", &casters);

        let atlas = self.cubes.atlas().expect("prepare sized the atlas");
        let uniform = PerLightBatchUniform {
            first_light: first as u32,
            light_count: (last - first) as u32,
            resolution: atlas.resolution as f32,
            bias_world: params.bias_world,
            normal_offset_texels: params.normal_offset_texels,
            tiles_per_row: atlas.tiles_per_row,
            _pad: [0.0; 2],
        };
        self.shade.write_batch(ctx.gpu, &uniform);
        let group = self.bind_group.as_ref().expect("prepare created the bind group");
        self.shade.encode(ctx, encoder, "shading", group, None);
        stats
    }
}
