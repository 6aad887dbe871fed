//! The GPU side of a frame, one function per pass (as every technique has it): where each VAL's map stands and
//! what the gather reads of it ([`GpuVal`], steps 2-3 of the paper), step 3's paraboloid maps (and CSSM's basis
//! textures), and steps 4-5's gather of a batch of VPLs.

use glam::Vec3;

use super::{centre, cull, segment_occluded, Centre, ValParamsUniform, VirtualAreaLights, MAP_OFFSET, NEAR_FRACTION};
use crate::error::GpuError;
use crate::scene::proxy::DEFAULT_MAX_EDGE;
use crate::services::context::FrameContext;
use crate::services::cube_shadows::ParaboloidCaster;
use crate::services::vpl_gather::GatherBatchUniform;

/// Mirrors `GpuVal` in `val/gather.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct GpuVal {
    centre: [f32; 4],
    normal: [f32; 4],
    depth: [f32; 4],
    cone: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<GpuVal>() == 64);

impl VirtualAreaLights {
    /// Each VAL's map (its centre, near and far planes, into `casters`) and what the gather reads of it: Δ, the
    /// VPL count, the depth range, its VPLs' bounding sphere and normal cone.
    pub(super) fn place_vals(&mut self, scene_bounds: crate::scene::Aabb) -> Vec<GpuVal> {
        let set = self.vpls.clone();
        let vpls = &set.vpls;
        let offset = self.scene_size * MAP_OFFSET;
        let far = self.scene_size * 1.01;
        self.casters.clear();
        // Each VAL's map centre: the paper's (its mean, moved off its surface along its normal) or its member VPL
        // nearest the mean, moved off its own surface ([`centre::map_centres`]), by `centre`.
        // A VAL of at most `member_share` of the VPLs (`centre = auto`, every VAL with `member`) stands at a member.
        let max_members = match self.params.centre {
            Centre::Mean => 0,
            Centre::Member => usize::MAX,
            Centre::Auto => (self.params.member_share.max(0.0) as f64 * vpls.len() as f64).floor() as usize,
        };
        // With the scene's BVH, a small VAL whose nearest member is crowded by nearby geometry (which its map
        // would draw warped) stands at a clearer member ([`centre`]); probes reach a tenth of the maps' longest edge.
        let bvh = self.bvh.as_ref().filter(|(_, b)| *b == scene_bounds).map(|(b, _)| b.clone());
        let occluded = |a: Vec3, b: Vec3| bvh.as_ref().is_some_and(|bvh| segment_occluded(bvh, a, b, self.scene_size));
        let max_edge = if self.params.max_edge > 0.0 { self.params.max_edge } else { DEFAULT_MAX_EDGE };
        let clearance = centre::Clearance { occluded: &occluded, reach: centre::REACH * max_edge * self.scene_size };
        let centres = centre::map_centres(
            vpls,
            &self.clustering.assignment,
            &self.clustering.vals,
            max_members,
            offset,
            bvh.as_ref().filter(|_| self.params.clearance).map(|_| &clearance),
        );
        // Delta of the penumbra estimate (the near plane stays a share of the rectangle's size).
        let sizes = self.sizes(vpls);
        // Each VAL's bounding sphere about its map's centre and its VPLs' normal cone ([`cull`]): a receiver that
        // none of its VPLs can light skips its VPLs (`may_light`) and its visibility (`val_visibility`). The
        // radius is widened by a millionth of the scene for rounding.
        let axes: Vec<Vec3> = self.clustering.vals.iter().map(|v| v.normal).collect();
        let bounds = cull::val_bounds(vpls, &self.clustering.assignment, &centres, &axes, self.scene_size * 1e-6);
        self.clustering
            .vals
            .iter()
            .zip(&centres)
            .zip(&bounds)
            .zip(&sizes)
            .map(|(((v, &centre), &(radius, cone)), &size)| {
                let near = (NEAR_FRACTION * v.size()).max(self.scene_size * 1e-5);
                self.casters.push(ParaboloidCaster { centre, normal: v.normal, near, far });
                GpuVal {
                    centre: centre.extend(size).to_array(),
                    normal: v.normal.extend(v.count as f32).to_array(),
                    depth: [near, far, radius, 0.0],
                    cone,
                }
            })
            .collect()
    }

    /// Step 3: every VAL's paraboloid map, one pass; with CSSM, the Fourier basis textures of every map and
    /// their mip levels.
    pub(super) fn encode_maps(
        &mut self,
        ctx: &FrameContext,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        // Step 3: every VAL's paraboloid map, one pass.
        let stats = self.shadows.render_paraboloids(
            ctx.gpu,
            self.maps.geometry(ctx.scene),
            ctx.timer,
            encoder,
            "val shadow maps",
            &self.casters,
            0,
        );
        self.counts.add_cube_stats(&stats);
        if self.params.visibility == "cssm" {
            // The Fourier basis textures of every VAL's map and their mip levels.
            let atlas = self.shadows.atlas().expect("prepare sized the atlas");
            self.cssm.encode(ctx.gpu, ctx.timer, encoder, atlas)?;
        }
        Ok(())
    }

    /// Steps 4-5 for the batch of VPLs `step`: each pixel's light per VAL, each VAL's visibility once.
    pub(super) fn encode_gather(&mut self, ctx: &FrameContext, step: usize, encoder: &mut wgpu::CommandEncoder) {
        let atlas = self.shadows.atlas().expect("prepare sized the atlas");
        let uniform = ValParamsUniform {
            val_count: self.clustering.vals.len() as u32,
            mode: match self.params.visibility.as_str() {
                "hard" => 0,
                "pcss" => 1,
                _ => 2,
            },
            grid: self.params.grid,
            tiles_per_row: atlas.tiles_per_row,
            resolution: atlas.resolution,
            bias: self.params.bias_world,
            normal_offset: self.params.normal_offset_texels,
            slope_bias: self.params.slope_bias,
            solo: self.params.solo,
            levels: self.cssm.levels(),
            cssm_offset: self.params.cssm_offset,
            soft_share: self.params.soft_share.max(0.0),
            batch_size: self.batch_size as u32,
            skip_unlit: (self.params.skip_unlit && self.lists_fit) as u32,
            members_offset: self.members_offset,
            _pad: 0,
        };
        ctx.gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        let views = self.cssm.views(self.params.visibility == "cssm");
        let group = ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("val visibility"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&atlas.view) },
                wgpu::BindGroupEntry { binding: 1, resource: self.vals_buffer.buffer.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: match (&self.gpu_kmeans.assignment, self.gpu_map) {
                        (Some(b), true) => b.as_entire_binding(),
                        _ => self.map_buffer.buffer.as_entire_binding(),
                    },
                },
                wgpu::BindGroupEntry { binding: 3, resource: self.uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(&views[0]) },
                wgpu::BindGroupEntry { binding: 5, resource: wgpu::BindingResource::TextureView(&views[1]) },
                wgpu::BindGroupEntry { binding: 6, resource: wgpu::BindingResource::TextureView(&views[2]) },
                wgpu::BindGroupEntry { binding: 7, resource: wgpu::BindingResource::TextureView(&views[3]) },
                wgpu::BindGroupEntry { binding: 8, resource: wgpu::BindingResource::Sampler(&self.cssm.sampler) },
                wgpu::BindGroupEntry { binding: 9, resource: self.lists_buffer.buffer.as_entire_binding() },
            ],
        });
        let first = step * self.batch_size;
        let last = (first + self.batch_size).min(self.vpls.vpls.len());
        let mut batch =
            GatherBatchUniform { first_vpl: first as u32, vpl_count: (last - first) as u32, ..Default::default() };
        self.params.interleave.apply(&mut batch, self.allow_ratio());
        self.pass.encode(ctx, encoder, "val soft visibility + indirect", &group, batch);
    }
}
