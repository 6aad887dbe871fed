//! Instant radiosity (Keller 1997): the frame's VPLs gathered at every pixel, with one of three visibilities.
//! They differ only in `vpl_visibility` (a WGSL file each), so they share this folder; a technique with its own
//! VPL processing (virtual area lights, fuzzy clustering) gets its own folder and uses the same
//! [`VplGatherPass`] and VPL set.
//!
//! - `vpl-shadowmaps`: one paraboloid shadow map per VPL, oriented along its normal (Dong et al. 2009
//!   section 4.2: the "IR solution with a hard shadow for each VPL"), rendered into a reused depth atlas in
//!   batches (memory bounded by `atlas_mib` whatever the VPL count), chunks culled per VPL hemisphere. Per step:
//!   1. render the batch's paraboloid maps (`paraboloid_depth.wgsl`),
//!   2. gather the batch's VPLs with a one-texel depth test (`vpl_vis_paraboloid.wgsl`).
//! - `vpl-raytraced`: the same VPLs, visibility by a shadow ray through the scene BVH (`vpl_vis_raytraced.wgsl`):
//!   exact, the ground truth of VPL visibility (Colom et al. 2022's reference image). Per step: gather a batch.
//! - `vpl-unshadowed`: no visibility (`vpl_vis_none.wgsl`), the denominator of indirect shadow factors.
//!
//! `interleave` (all three, off by default and for the references): Dong et al. section 6's interleaved
//! sampling, each pixel of a B x B block (`block`, the paper's 8) gathers every B²-th VPL (times B²), and a last
//! step blurs the indirect buffer over B x B windows on the same surface, with the ratio estimator (`ratio`) or
//! as the paper ([`Interleave`], [`InterleaveBlur`], `vpl_blur.wgsl`).
//!
//! The radiance of VPL `i` at `x` is `rho(x)/pi * Phi_i/pi * cos(theta_i) cos(theta_x) / max(d^2, d_clamp^2)`
//! (`vpl_common.wgsl`); `d_clamp` is the render setting `vpl.clamp_world`.

mod explain;

use std::sync::Arc;

use super::{
    check_param, FrameContext, OverlayLayer, Param, ParamError, ParamKind, ParamValue, Technique, TechniqueCounts,
};
use crate::accel::scene_bvh::SceneBvh;
use crate::error::GpuError;
use crate::gpu::bind::depth_texture_entry;
use crate::gpu::GpuContext;
use crate::scene::proxy::ProxyParams;
use crate::scene::PointLight;
use crate::services::cube_shadows::{CubeShadowRenderer, MapGeometry, ParaboloidCaster, MAX_CUBES_PER_BATCH};
use crate::services::layouts::SharedLayouts;
use crate::services::vpl_gather::{vpl_overlays, GatherBatchUniform, Interleave, InterleaveBlur, VplGatherPass};
use crate::shaders;
use crate::timing::PassTime;
use crate::vpl::VplSet;

/// How a VPL's visibility is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Visibility {
    /// A paraboloid shadow map per VPL.
    ShadowMaps,
    /// A shadow ray per pixel and VPL.
    RayTraced,
    /// None: every VPL reaches every receiver in its hemisphere.
    None,
}

/// The parameters of the three gathers (each shows the ones it uses).
#[derive(Clone, Debug, PartialEq)]
pub struct GatherParams {
    /// VPLs gathered in one step (shadow maps: also at most what one atlas holds).
    pub vpls_per_step: u32,
    /// Shadow rays: origin offset along the normal, world units per metre of camera distance.
    pub ray_bias: f32,
    /// Paraboloid map side in texels.
    pub shadow_resolution: u32,
    /// Shadow maps: constant depth bias, world units.
    pub depth_bias_world: f32,
    /// Shadow maps: receiver offset along its normal, in texels of the map at the receiver.
    pub normal_offset_texels: f32,
    /// Shadow maps: memory of one batch's atlas, MiB.
    pub atlas_budget_mib: u32,
    /// Shadow maps: draw only the chunks in a VPL's front half-space.
    pub cull: bool,
    /// Shadow maps: the longest triangle edge the maps draw, as a share of the scene's diagonal (longer ones are
    /// cut, [`crate::scene::proxy`]: a paraboloid draws edges straight); 0: the scene's triangles as they are.
    pub max_edge: f32,
    /// Interleaved sampling (Dong section 6), its ratio estimator and block ([`Interleave`]). Off for the
    /// references.
    pub interleave: Interleave,
    /// The light whose VPL paths the "vpl paths" overlay shows.
    pub path_light: u32,
}

impl Default for GatherParams {
    fn default() -> Self {
        GatherParams {
            vpls_per_step: 256,
            ray_bias: 0.001,
            shadow_resolution: 128,
            depth_bias_world: 0.01,
            normal_offset_texels: 1.5,
            atlas_budget_mib: 64,
            cull: true,
            max_edge: crate::scene::proxy::DEFAULT_MAX_EDGE,
            interleave: Interleave::default(),
            path_light: 0,
        }
    }
}

pub struct VplGather {
    visibility: Visibility,
    pub params: GatherParams,
    pass: VplGatherPass,
    blur: InterleaveBlur,
    visibility_layout: wgpu::BindGroupLayout,
    visibility_group: Option<wgpu::BindGroup>,
    shadows: Option<CubeShadowRenderer>,
    /// The BVH the visibility group was made with (ray traced), to rebind when the scene changes.
    bvh: Option<Arc<SceneBvh>>,
    vpls: Arc<VplSet>,
    batch_size: usize,
    /// Gather steps of this frame (the blur, when interleaving, is one more).
    batches: usize,
    scene_size: f32,
    counts: TechniqueCounts,
    build_ms: Option<f64>,
    /// Shadow maps: what they draw, the scene with its long edges cut (`max_edge` 0: the scene as it is).
    maps: MapGeometry,
}

impl VplGather {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts, visibility: Visibility) -> VplGather {
        let device = &gpu.device;
        let entries: Vec<wgpu::BindGroupLayoutEntry> = match visibility {
            Visibility::ShadowMaps => vec![depth_texture_entry(0)],
            Visibility::RayTraced => crate::accel::scene_bvh::SceneBvh::layout_entries(),
            Visibility::None => vec![],
        };
        let visibility_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("vpl visibility"),
            entries: &entries,
        });
        let (label, source) = match visibility {
            Visibility::ShadowMaps => ("vpl_gather_paraboloid", shaders::VPL_GATHER_PARABOLOID.source),
            Visibility::RayTraced => ("vpl_gather_raytraced", shaders::VPL_GATHER_RAYTRACED.source),
            Visibility::None => ("vpl_gather_unshadowed", shaders::VPL_GATHER_UNSHADOWED.source),
        };
        let pass = VplGatherPass::new(gpu, layouts, label, source, &visibility_layout);
        VplGather {
            blur: InterleaveBlur::new(gpu, layouts),
            visibility,
            params: GatherParams::default(),
            pass,
            visibility_layout,
            visibility_group: None,
            shadows: (visibility == Visibility::ShadowMaps).then(|| CubeShadowRenderer::new(gpu)),
            bvh: None,
            vpls: Arc::default(),
            batch_size: 1,
            batches: 0,
            scene_size: 1.0,
            counts: TechniqueCounts::default(),
            build_ms: None,
            maps: MapGeometry::default(),
        }
    }

    /// Maps of the configured resolution one batch's atlas holds.
    fn maps_per_batch(&self, gpu: &GpuContext) -> (u32, usize) {
        let res = self.params.shadow_resolution.min(gpu.device.limits().max_texture_dimension_2d);
        let per_map = res as u64 * res as u64 * 4;
        let by_budget = (self.params.atlas_budget_mib as u64 * (1 << 20) / per_map.max(1)) as usize;
        let per_row = (gpu.device.limits().max_texture_dimension_2d / res.max(1)) as usize;
        (res, by_budget.min(per_row * per_row).clamp(1, MAX_CUBES_PER_BATCH * 6))
    }

    /// Where paraboloid maps are centred and their depth range. A VPL sits on a surface, so the map's centre is
    /// pushed off it along the normal by 0.2 % of the scene's diagonal: the triangles right around the VPL then
    /// lie behind the map's plane (and are discarded) instead of rising in front of it at grazing angles, where
    /// the paraboloid projection stretches a small triangle across the whole map (measured on the closed-sphere
    /// test: 0.07 % offset darkened the image by 16 %, 0.2 % matches the ray tracer within 3 %). The far plane is
    /// the scene's diagonal (VPLs have no range).
    fn depth_range(&self) -> (f32, f32, f32) {
        let offset = self.scene_size * 2e-3;
        (offset, self.scene_size * 1e-5, self.scene_size * 1.01)
    }
}

impl Technique for VplGather {
    fn key(&self) -> &'static str {
        match self.visibility {
            Visibility::ShadowMaps => "vpl-shadowmaps",
            Visibility::RayTraced => "vpl-raytraced",
            Visibility::None => "vpl-unshadowed",
        }
    }

    fn label(&self) -> &'static str {
        match self.visibility {
            Visibility::ShadowMaps => "VPLs, a shadow map each",
            Visibility::RayTraced => "VPLs, ray-traced visibility",
            Visibility::None => "VPLs, no visibility",
        }
    }

    fn params(&self) -> Vec<Param> {
        let p = &self.params;
        let mut list = vec![Param {
            key: "vpls_per_step",
            label: "VPLs per step",
            help: "VPLs gathered in one pass; fewer means shorter steps (the image does not change)",
            kind: ParamKind::Int { min: 1, max: crate::vpl::MAX_VPLS as i64 },
            value: ParamValue::Int(p.vpls_per_step as i64),
        }];
        list.extend(p.interleave.describe());
        list.push(Param {
            key: "path_light",
            label: "Paths of light",
            help: "The light whose VPL paths (RSM texel rays, particle bounces) the 'vpl paths' overlay shows",
            kind: ParamKind::Int { min: 0, max: crate::scene::layout::MAX_LIGHTS as i64 },
            value: ParamValue::Int(p.path_light as i64),
        });
        match self.visibility {
            Visibility::RayTraced => list.push(Param {
                key: "bias",
                label: "Ray offset",
                help: "Ray origin offset along the normal, world units per metre of camera distance",
                kind: ParamKind::Float { min: 0.0, max: 0.1 },
                value: ParamValue::Float(p.ray_bias),
            }),
            Visibility::ShadowMaps => list.extend([
                Param {
                    key: "shadow_res",
                    label: "Map resolution",
                    help: "Texels per side of each VPL's paraboloid shadow map",
                    kind: ParamKind::Int { min: 8, max: 2048 },
                    value: ParamValue::Int(p.shadow_resolution as i64),
                },
                Param {
                    key: "bias",
                    label: "Depth bias",
                    help: "Constant depth bias in world units",
                    kind: ParamKind::Float { min: 0.0, max: 10.0 },
                    value: ParamValue::Float(p.depth_bias_world),
                },
                Param {
                    key: "normal_offset",
                    label: "Normal offset",
                    help: "Receiver offset along its normal, in shadow-map texels at the receiver",
                    kind: ParamKind::Float { min: 0.0, max: 16.0 },
                    value: ParamValue::Float(p.normal_offset_texels),
                },
                Param {
                    key: "atlas_mib",
                    label: "Batch memory (MiB)",
                    help: "Memory of one batch of paraboloid maps; more per batch means fewer passes",
                    kind: ParamKind::Int { min: 1, max: 2048 },
                    value: ParamValue::Int(p.atlas_budget_mib as i64),
                },
                Param {
                    key: "cull",
                    label: "Cull per VPL",
                    help: "Draw only the chunks in front of a VPL (off: every chunk into every map)",
                    kind: ParamKind::Bool,
                    value: ParamValue::Bool(p.cull),
                },
                Param {
                    key: "max_edge",
                    label: "Longest edge",
                    help: "The longest triangle edge the maps draw, as a share of the scene's diagonal: longer ones \
                           are cut, since a paraboloid map draws a triangle's edges straight (a wall of two triangles \
                           beside a VPL lands in the wrong place). 0: the scene's triangles as they are",
                    kind: ParamKind::Float { min: 0.0, max: 1.0 },
                    value: ParamValue::Float(p.max_edge),
                },
            ]),
            Visibility::None => {}
        }
        list
    }

    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        check_param(self.key(), &self.params(), key, value)?;
        let p = &mut self.params;
        match (key, value) {
            ("vpls_per_step", ParamValue::Int(v)) => p.vpls_per_step = *v as u32,
            ("bias", ParamValue::Float(v)) if self.visibility == Visibility::RayTraced => p.ray_bias = *v,
            ("bias", ParamValue::Float(v)) => p.depth_bias_world = *v,
            ("shadow_res", ParamValue::Int(v)) => p.shadow_resolution = *v as u32,
            ("normal_offset", ParamValue::Float(v)) => p.normal_offset_texels = *v,
            ("atlas_mib", ParamValue::Int(v)) => p.atlas_budget_mib = *v as u32,
            ("cull", ParamValue::Bool(v)) => p.cull = *v,
            ("max_edge", ParamValue::Float(v)) => p.max_edge = *v,
            ("path_light", ParamValue::Int(v)) => p.path_light = *v as u32,
            (k, v) => {
                // Interleaving's parameters, or none ([`Interleave::set`]).
                if !p.interleave.set(k, v) {
                    unreachable!("check_param accepted an unknown key")
                }
            }
        }
        Ok(())
    }

    fn uses_vpls(&self) -> bool {
        true
    }

    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        self.build_ms = None;
        self.vpls = ctx.vpls.set.clone();
        self.scene_size = ctx.scene.bounds.size().length().max(1e-6);
        let n = self.vpls.vpls.len();
        self.batch_size = (self.params.vpls_per_step as usize).min(ctx.max_lights_per_step).max(1);
        if self.visibility == Visibility::ShadowMaps {
            let (res, per_batch) = self.maps_per_batch(ctx.gpu);
            self.batch_size = self.batch_size.min(per_batch);
            let cut = ProxyParams { keep: 1.0, max_error: 0.0, max_edge: self.params.max_edge * self.scene_size };
            self.maps.update(ctx.gpu, ctx.scene, cut);
            let shadows = self.shadows.as_mut().expect("shadow maps own a shadow renderer");
            let grew = shadows.ensure_tiles(ctx.gpu, res, self.batch_size.min(n.max(1)));
            if grew || self.visibility_group.is_none() {
                let atlas = shadows.atlas().expect("ensure_tiles made it");
                self.visibility_group = Some(ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("vpl paraboloid atlas"),
                    layout: &self.visibility_layout,
                    entries: &[wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&atlas.view),
                    }],
                }));
            }
        } else if self.visibility == Visibility::RayTraced {
            let (bvh, build_ms) = ctx.scene.bvh(ctx.gpu);
            self.build_ms = build_ms;
            if self.bvh.as_ref().is_none_or(|b| !Arc::ptr_eq(b, &bvh)) || self.visibility_group.is_none() {
                self.visibility_group = Some(ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("vpl ray-traced visibility"),
                    layout: &self.visibility_layout,
                    entries: &bvh.bind_entries(),
                }));
            }
            self.bvh = Some(bvh);
        } else if self.visibility_group.is_none() {
            self.visibility_group = Some(ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("vpl no visibility"),
                layout: &self.visibility_layout,
                entries: &[],
            }));
        }
        let batches = n.div_ceil(self.batch_size);
        self.counts = TechniqueCounts { lights_visible: ctx.lights.len(), batches, ..Default::default() };
        self.counts.figures.insert("vpls".into(), n as f64);
        if let Some(t) = self.maps.copy_triangles() {
            self.counts.figures.insert("map_geometry_triangles".into(), t as f64);
        }
        self.batches = batches;
        // With interleaving, one more step: the blur.
        Ok(if self.params.interleave.on && batches > 0 { batches + 1 } else { batches })
    }

    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        if step == self.batches {
            self.blur.encode(ctx, encoder, &self.params.interleave, true, &self.pass);
            return Ok(());
        }
        let first = step * self.batch_size;
        let last = (first + self.batch_size).min(self.vpls.vpls.len());
        let mut batch =
            GatherBatchUniform { first_vpl: first as u32, vpl_count: (last - first) as u32, ..Default::default() };
        self.params.interleave.apply(&mut batch, true);
        match self.visibility {
            Visibility::ShadowMaps => {
                // Step 1: this batch's paraboloid maps.
                let (origin_offset, near, far) = self.depth_range();
                let casters: Vec<ParaboloidCaster> = self.vpls.vpls[first..last]
                    .iter()
                    .map(|v| ParaboloidCaster {
                        centre: v.position + v.normal * origin_offset,
                        normal: v.normal,
                        near,
                        far,
                    })
                    .collect();
                let mut geometry = self.maps.geometry(ctx.scene);
                geometry.cull = self.params.cull;
                let shadows = self.shadows.as_mut().expect("shadow maps own a shadow renderer");
                let stats =
                    shadows.render_paraboloids(ctx.gpu, geometry, ctx.timer, encoder, "vpl shadow maps", &casters, 0);
                self.counts.add_cube_stats(&stats);
                let atlas = shadows.atlas().expect("rendered into it");
                batch.first_tile = 0;
                batch.tiles_per_row = atlas.tiles_per_row;
                batch.resolution = atlas.resolution;
                batch.bias = self.params.depth_bias_world;
                batch.normal_offset = self.params.normal_offset_texels;
                batch.depth_near = near;
                batch.depth_far = far;
                batch.origin_offset = origin_offset;
            }
            Visibility::RayTraced => batch.bias = self.params.ray_bias,
            Visibility::None => {}
        }
        // Step 2: gather.
        let group = self.visibility_group.as_ref().expect("prepare made the visibility group");
        self.pass.encode(ctx, encoder, "vpl gather", group, batch);
        Ok(())
    }

    fn step_label(&self) -> &'static str {
        match self.visibility {
            Visibility::ShadowMaps => "vpl shadow maps + gather",
            _ => "vpl gather",
        }
    }

    fn explain(&self) -> Vec<super::ExplainStep> {
        explain::explain_steps(self.visibility)
    }

    fn shadow_atlas(&self) -> Option<(&crate::services::cube_shadows::CubeAtlas, &'static str)> {
        self.shadows.as_ref().and_then(|s| s.atlas()).map(|a| (a, "paraboloid maps of the last batch, one per VPL"))
    }

    fn counts(&self) -> TechniqueCounts {
        self.counts.clone()
    }

    fn cpu_times(&self) -> Vec<PassTime> {
        let bvh = self.build_ms.map(|ms| PassTime { name: "bvh build".into(), ms, count: 1 });
        bvh.into_iter().chain(self.maps.build_time()).collect()
    }

    fn overlays(&self, _lights: &[PointLight]) -> Vec<OverlayLayer> {
        vpl_overlays(&self.vpls, self.scene_size, self.params.path_light)
    }

    fn hover_points(&self) -> Vec<super::HoverPoint> {
        crate::services::vpl_gather::vpl_hover_points(&self.vpls)
    }

    fn hover_details(&self, _layer: &str, index: usize) -> Vec<String> {
        crate::services::vpl_gather::vpl_details(&self.vpls, index)
    }

    fn overlay_legend(&self, layer: &OverlayLayer) -> Vec<super::LegendEntry> {
        let mut legend = crate::services::vpl_gather::vpl_layer_legend(layer)
            .or_else(|| super::light_layer_legend(layer))
            .unwrap_or_default();
        legend.extend(layer.summary());
        legend
    }
}
