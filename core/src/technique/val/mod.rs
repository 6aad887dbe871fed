//! Virtual area lights (Dong, Grosch, Ritschel, Kautz, Seidel 2009): the frame's N VPLs clustered into M
//! VALs; one soft-shadowing paraboloid map per VAL; every pixel lit by all N VPLs, VPL `i` with the visibility
//! of its VAL `C(i)`: `L(x) ~ sum_i L_i(x) V~_C(i)(x)` (section 4).
//!
//! Per frame:
//! 1. VPLs: the renderer's shared set (either source).
//! 2. Clustering (section 5, [`kmeans`]): k-means over position and normal, `d = w_x dx / L + w_a da` (`L` a
//!    tenth of the scene's diagonal by default, parameter `length`), restarted
//!    every frame from VAL `k` = VPL `k N / M` (section 5.2); means of the members, the bounding rectangle of
//!    their projection on the plane perpendicular to the mean normal (section 6), and the map `C`.
//! 3. One paraboloid shadow map per VAL, all in one atlas and one render pass
//!    (`CubeShadowRenderer::render_paraboloids`), facing the VAL's normal.
//! 4. Soft visibility per VAL and pixel (`val/gather.wgsl`): `cssm` (the paper's, below), `pcss` (blocker search over the VAL's angular
//!    size, the paper's penumbra `p cos(beta) = (d - z_avg) Delta / z_avg`, `alpha = arctan(p cos(beta) / d)`,
//!    kernel width `alpha / pi` of the map, percentage-closer filtering) or `hard` (one test, for teaching).
//! 5. Shading (the shared VPL gather's terms): each pixel computes its M visibilities once, then sums all
//!    (or, interleaved, the 1/B² share of the) VPLs with the visibility of their VAL; a geometry-aware blur
//!    follows when interleaving. Receivers in a VAL's negative half-space see it fully (section 5.1).
//!
//! Deviations, and why:
//! - The clustering runs on the GPU (`clustering = gpu`, [`gpu_kmeans`], `val/kmeans.wgsl`: one dispatch per
//!   step, fixed-point atomic sums where the paper blends) and is read back (M VALs, and `C` for the
//!   overlays), because the VAL maps are culled per VAL on the CPU. `clustering = cpu` runs the twin
//!   [`kmeans::cluster`], which is also what the warm-start variant uses.
//! - Visibility `cssm` is the paper's convolution soft shadow maps ([`cssm`], `val/cssm.wgsl`: 4 Fourier terms,
//!   8-bit basis and 16-bit basis-z textures, mip-mapped, one trilinear lookup per texture for the blocker
//!   search and one for the kernel). Two deviations: the phase uses `z / 2` (the series is a square wave of
//!   period 2 in `z - d`; over [0, 1] a receiver near the VAL under an empty texel sits on the next edge and
//!   comes out half lit), and basis-z keeps 3 terms plus `z` itself (its mean is needed for `z_avg`; a stage
//!   may write 4 storage textures). With 4 terms the step rises over about a quarter of the map's depth range
//!   (the scene's diagonal), so a receiver is moved toward the VAL by `cssm_offset` (0.12 of the range) and
//!   contact shadows leak: measured on the plane-and-wall test scene, relative RMSE against exact visibility
//!   0.047 for CSSM against 0.053 for none at all, which is why `pcss` (explicit depth tests, `2 grid^2`
//!   texel reads per pixel and VAL) stays the default.
//! - Step 2 is refined ([`split`], issue 23): VALs are bisected, the one of largest light times distance
//!   `sum Y d` next (`rank = light`; `flux`, `sum Y d^2`, the key before), by normal when its normal cone
//!   exceeds `max_cone`, by depth when its VPLs spread along its normal by more than `max_depth` L, until
//!   there are M, starting from one VAL by default (`kmeans_share = 0`;
//!   the VALs for M + 1 are then those for M with one bisected, which is what makes the error fall with M
//!   on the real scenes, measured in docs/techniques/val.md). VALs across corners and layers were the leaks of
//!   the paper's Fig. 7. `split = off` is the paper's k-means alone.
//! - PCSS filter samples are compared with the receiver's plane along their own direction (a receiver-plane
//!   depth bias, `receiver_depth` in `val/gather.wgsl`) less `slope_bias` texels of depth per texel of offset
//!   for curvature. The earlier form, the receiver's own depth less `2` texels per texel of offset, also had
//!   to cover the plane's slope, so on flat receivers the wide kernels of large VALs let occluders through
//!   (Sponza, 30 VALs, bisection from k-means for M / 2 with a 30 degree cone rule: FLIP 0.25 -> 0.157); the closed-sphere test (a concave receiver) stays within
//!   3 % with `slope_bias = 1`.
//! - A VAL of at most `member_share` (1/32) of the frame's VPLs has its map at its member VPL nearest the mean,
//!   moved off that VPL's own surface (`centre = auto`, the default; `mean` is the paper's, `member` every VAL's;
//!   [`centre::map_centres`]): the mean of VPLs on both sides of an arch floats in the open or sits in a column.
//!   With it the error against per-VPL maps falls at every M on the three scenes measured and Sponza's is lower
//!   from M = 8 up (docs/techniques/val.md). A member with geometry right beside it (which its map would
//!   draw warped) gives way to the least crowded member nearby (`clearance`, the default; [`centre`]): the
//!   Cornell box with water's one rise in M.
//! - Δ in the penumbra estimate is the side of the square with the VPLs' flux-weighted second moment (`size =
//!   spread`, the default since the twenty-second session; [`kmeans::spread_sizes`]), not the diagonal of their
//!   bounding rectangle (`bounds`, the paper's, section 6): a faint VPL far off widens the rectangle as much as a
//!   bright one, and PCSS's penumbra is that of a square light of side Δ, not of its diagonal. Lower error at
//!   nearly every M on every scene measured, against per-VPL maps and exact VPL visibility alike.
//! - Step 5 without interleaving walks the VALs' member lists and skips a VAL none of whose VPLs can light the
//!   pixel (`skip_unlit`, the default; [`cull`]: its VPLs' sphere behind the pixel's tangent plane, or their
//!   normal cone facing away): the same sum with half the VPL evaluations on Sponza. The paper evaluates all N.
//! - VAL maps ignore geometry closer than a tenth of the VAL's size to its centre (the paper's Fig. 7: a
//!   cluster centre can lie inside geometry; "geometry located near the cluster center has to be ignored").
//!   The paper gives no amount; on Sponza with 30 VALs FLIP against per-VPL maps was 0.28 at a tenth, 0.37 at
//!   a quarter and 0.42 at a half (more ignored geometry leaks light; less shadows VALs that sit in geometry).
//! - The blocker search covers the VAL's half-size seen from the receiver and the PCF kernel is capped to it,
//!   as PCSS does (an uncapped `alpha / pi` kernel for large VALs averaged in texels that hide no part of the
//!   VAL: Sponza, 30 VALs, FLIP 0.42 uncapped against 0.37 capped, same near plane).
//! - The VAL maps draw the scene with every edge longer than `max_edge` cut (a paraboloid draws edges straight;
//!   the per-VPL reference draws the same copy), and with `proxy` below 1 a simplified copy
//!   ([`crate::scene::proxy`]): the paper's conclusion leaves "geometric simplifications ... on top of the
//!   visibility approximations" to future work, so it is off by default.

pub mod centre;
pub mod cssm;
pub mod cull;
pub mod gpu_kmeans;
pub mod kmeans;
mod overlays;
mod params;
mod passes;
pub mod split;

pub use params::{Centre, ValParams, MAX_VALS};

use std::sync::Arc;

use glam::Vec3;

use super::{
    check_param, index_color, FrameContext, Overlay, OverlayLayer, Param, ParamError, ParamValue, Technique,
    TechniqueCounts,
};
use crate::error::GpuError;
use crate::gpu::bind::{depth_texture_entry, storage_entry, uniform_entry};
use crate::gpu::buffer::GrowableBuffer;
use crate::gpu::GpuContext;
use crate::scene::proxy::ProxyParams;
use crate::scene::PointLight;
use crate::services::cube_shadows::{CubeShadowRenderer, MapGeometry, ParaboloidCaster};
use crate::services::layouts::SharedLayouts;
use crate::services::vpl_gather::{InterleaveBlur, VplGatherPass};
use crate::timing::PassTime;
use crate::vpl::VplSet;
use kmeans::{Clustering, KMeansParams};

use crate::shaders::WgslModule;
/// This technique's own WGSL modules; its registry entry lists them and the naga test validates them.
pub const SHADERS: &[WgslModule] = &[GATHER, cssm::CSSM, gpu_kmeans::KMEANS];
const GATHER: WgslModule = crate::shaders::wgsl!(
    "val_gather",
    ["shaders/common.wgsl", "shaders/vpl_common.wgsl", "shaders/vpl_basis.wgsl", "core/src/technique/val/gather.wgsl"]
);

/// VAL maps ignore geometry closer to the centre than this fraction of the VAL's size (paper, Fig. 7).
const NEAR_FRACTION: f32 = 0.1;

/// A VAL map's centre lies this share of the scene's diagonal in front of the VAL (off its surfaces).
const MAP_OFFSET: f32 = 2e-3;

/// Whether geometry lies between `a` and `b`: a segment stopped a ten-thousandth of the scene short of `b`'s
/// surface, against the scene's BVH (cut-outs let it through, as in every tracer).
fn segment_occluded(bvh: &crate::accel::scene_bvh::SceneBvh, a: Vec3, b: Vec3, scene_size: f32) -> bool {
    let eps = scene_size * 1e-4;
    let d = b - a;
    let len = d.length();
    len.is_finite() && len > 2.0 * eps && bvh.occluded(a, d / len, len - eps)
}

/// Mirrors `ValParams` in `val/gather.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ValParamsUniform {
    val_count: u32,
    mode: u32,
    grid: u32,
    tiles_per_row: u32,
    resolution: u32,
    bias: f32,
    normal_offset: f32,
    slope_bias: f32,
    solo: i32,
    levels: u32,
    cssm_offset: f32,
    soft_share: f32,
    batch_size: u32,
    skip_unlit: u32,
    members_offset: u32,
    _pad: u32,
}
const _: () = assert!(std::mem::size_of::<ValParamsUniform>() == 64);

pub struct VirtualAreaLights {
    pub params: ValParams,
    pass: VplGatherPass,
    blur: InterleaveBlur,
    layout: wgpu::BindGroupLayout,
    shadows: CubeShadowRenderer,
    gpu_kmeans: gpu_kmeans::GpuKMeans,
    cssm: cssm::Cssm,
    /// True when this frame's `C` is the GPU k-means' buffer (else `map_buffer`).
    gpu_map: bool,
    vals_buffer: GrowableBuffer,
    map_buffer: GrowableBuffer,
    /// [`cull::MemberLists`] in one buffer: the ranges (two words each), then the VPL indices.
    lists_buffer: GrowableBuffer,
    /// Where the VPL indices start in `lists_buffer`, in words.
    members_offset: u32,
    /// Whether this frame's member lists fit one storage binding (else every VPL is evaluated).
    lists_fit: bool,
    uniform: wgpu::Buffer,
    vpls: Arc<VplSet>,
    clustering: Clustering,
    previous_centres: Vec<(Vec3, Vec3)>,
    casters: Vec<ParaboloidCaster>,
    batch_size: usize,
    batches: usize,
    scene_size: f32,
    counts: TechniqueCounts,
    clustering_ms: f64,
    /// The scene BVH's build time when this frame built it (the first frame with a hidden weight or a clearance).
    bvh_build_ms: Option<f64>,
    /// What the VAL maps draw: the scene with its long edges cut, simplified with `proxy` below 1.
    maps: MapGeometry,
    /// The scene's BVH and bounds, from the last frame (the hidden members' weight in [`split`], the member
    /// centres' clearance in [`centre`]; a preview of another scene's VPLs goes without it).
    bvh: Option<(Arc<crate::accel::scene_bvh::SceneBvh>, crate::scene::Aabb)>,
}

impl VirtualAreaLights {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts) -> VirtualAreaLights {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("val visibility"),
            entries: &[
                depth_texture_entry(0),
                storage_entry(1),
                storage_entry(2),
                uniform_entry(3),
                cssm::filterable_entry(4),
                cssm::filterable_entry(5),
                cssm::filterable_entry(6),
                cssm::filterable_entry(7),
                wgpu::BindGroupLayoutEntry {
                    binding: 8,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
                storage_entry(9),
            ],
        });
        let pass = VplGatherPass::with_entry(gpu, layouts, "val_gather", GATHER.source, "val_gather_main", &layout);
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("val params"),
            size: std::mem::size_of::<ValParamsUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        VirtualAreaLights {
            params: ValParams::default(),
            pass,
            blur: InterleaveBlur::new(gpu, layouts),
            layout,
            shadows: CubeShadowRenderer::new(gpu),
            gpu_kmeans: gpu_kmeans::GpuKMeans::new(gpu),
            cssm: cssm::Cssm::new(gpu),
            gpu_map: false,
            vals_buffer: GrowableBuffer::new(device, "vals", 64 * 64),
            map_buffer: GrowableBuffer::new(device, "vpl to val", 4 * 1024),
            lists_buffer: GrowableBuffer::new(device, "vpls by val", 4 * 1024),
            members_offset: 0,
            lists_fit: false,
            uniform,
            vpls: Arc::default(),
            clustering: Clustering::default(),
            previous_centres: Vec::new(),
            casters: Vec::new(),
            batch_size: 1,
            batches: 0,
            scene_size: 1.0,
            counts: TechniqueCounts::default(),
            clustering_ms: 0.0,
            bvh_build_ms: None,
            maps: MapGeometry::default(),
            bvh: None,
        }
    }
}

impl VirtualAreaLights {
    /// Whether this frame allows the interleaving's ratio estimator (when `ratio` asks for it): not with `solo`,
    /// whose gather takes one VAL's VPLs where the ratio's unshadowed sum takes every VPL.
    fn allow_ratio(&self) -> bool {
        self.params.solo < 0
    }

    /// Each VAL's `Delta` in the penumbra estimate (`size`): its rectangle's diagonal or its VPLs' spread.
    fn sizes(&self, vpls: &[crate::vpl::Vpl]) -> Vec<f32> {
        match self.params.size.as_str() {
            "spread" => kmeans::spread_sizes(&self.clustering, vpls),
            _ => self.clustering.vals.iter().map(|v| v.size()).collect(),
        }
    }

    /// Step 2's k-means settings for this frame's scene size.
    fn kmeans_params(&self) -> KMeansParams {
        let m = (self.params.vals as usize).min(MAX_VALS);
        KMeansParams {
            vals: if self.params.split {
                ((m as f32 * self.params.kmeans_share).ceil() as usize).clamp(1, m)
            } else {
                m
            },
            iterations: self.params.iterations,
            w_x: self.params.w_x,
            w_a: self.params.w_a,
            scene_length: self.scene_size * self.params.length_fraction,
        }
    }

    /// Step 2's refinement ([`split`]) of a k-means result, shared by the frame and the overlays' preview.
    fn refine(&self, vpls: &[crate::vpl::Vpl], scene_bounds: crate::scene::Aabb, base: Clustering) -> Clustering {
        if !self.params.split {
            return base;
        }
        let m = (self.params.vals as usize).min(MAX_VALS);
        let sp = split::SplitParams {
            vals: m,
            rank: match self.params.rank.as_str() {
                "rule" => split::Rank::Rule,
                "flux" => split::Rank::Flux,
                _ => split::Rank::Light,
            },
            gain_until: self.params.gain_until as usize,
            max_cone: self.params.max_cone_degrees.to_radians(),
            max_depth: self.params.max_depth * self.scene_size * self.params.length_fraction,
            iterations: 8,
            hidden_weight: self.params.hidden_weight,
        };
        // Whether a VAL's map centre sees a VPL: a segment between them, stopped a ten-thousandth of the scene
        // short of the VPL's surface, against the scene's BVH (cut-outs let it through, as in every tracer).
        let bvh = self.bvh.as_ref().filter(|(_, bounds)| *bounds == scene_bounds).map(|(b, _)| b);
        let occluded = |a: Vec3, b: Vec3| bvh.is_some_and(|bvh| segment_occluded(bvh, a, b, self.scene_size));
        let sight = split::Sight { occluded: &occluded, offset: self.scene_size * MAP_OFFSET };
        split::split(vpls, &self.kmeans_params(), &sp, bvh.map(|_| &sight), &base)
    }
}

impl Technique for VirtualAreaLights {
    fn key(&self) -> &'static str {
        "val"
    }

    fn label(&self) -> &'static str {
        "Virtual area lights (Dong 2009)"
    }

    fn params(&self) -> Vec<Param> {
        self.params.describe()
    }

    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        check_param(self.key(), &self.params(), key, value)?;
        self.params.set(key, value);
        Ok(())
    }

    fn uses_vpls(&self) -> bool {
        true
    }

    /// Step 2 again on the CPU twin (no warm start, so the next frame is not changed by it) for the preview's
    /// VPLs: the VALs follow a dragged light in the same UI frame (1,024 VPLs into 30 VALs: about a millisecond).
    fn update_overlays(&mut self, ctx: &crate::technique::OverlayContext) -> crate::technique::OverlayUpdate {
        if Arc::ptr_eq(&self.vpls, ctx.vpls) {
            // The VALs were made from this very set (the last frame's, the lights unmoved): nothing to redo.
            return crate::technique::OverlayUpdate::Live { note: ctx.vpl_note(), stale_layers: Vec::new() };
        }
        self.vpls = ctx.vpls.clone();
        self.scene_size = ctx.scene_bounds.size().length().max(1e-6);
        let base = kmeans::cluster(&self.vpls.vpls, &self.kmeans_params(), None);
        self.clustering = self.refine(&self.vpls.vpls, ctx.scene_bounds, base);
        crate::technique::OverlayUpdate::Live { note: ctx.vpl_note(), stale_layers: Vec::new() }
    }

    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        self.vpls = ctx.vpls.set.clone();
        self.bvh_build_ms = None;
        // The BVH serves the hidden members' weight and the member centres' clearance.
        if (self.params.split && self.params.hidden_weight > 0.0)
            || (self.params.clearance && self.params.centre != Centre::Mean)
        {
            let (bvh, build_ms) = ctx.scene.bvh(ctx.gpu);
            self.bvh = Some((bvh, ctx.scene.bounds));
            self.bvh_build_ms = build_ms;
        }
        let bounds = ctx.scene.bounds;
        self.scene_size = bounds.size().length().max(1e-6);
        let vpls = &self.vpls.vpls;
        let n = vpls.len();
        // Step 2: clustering.
        let start = std::time::Instant::now();
        let kp = self.kmeans_params();
        let warm = (self.params.warm_start && !self.previous_centres.is_empty()).then_some(&self.previous_centres[..]);
        // The GPU k-means restarts from the initial assignment only; warm starts run on the CPU.
        self.gpu_map = self.params.clustering == "gpu" && warm.is_none() && !vpls.is_empty();
        let base = if self.gpu_map {
            self.gpu_kmeans.run(ctx.gpu, ctx.timer, &ctx.vpls.buffer.buffer, vpls, &kp, bounds.min, bounds.size())?
        } else {
            kmeans::cluster(vpls, &kp, warm)
        };
        let k_means_vals = base.vals.len();
        self.clustering = self.refine(vpls, bounds, base);
        // A refined `C` is the CPU's: the GPU k-means' buffer holds the unrefined one.
        self.gpu_map &= !self.params.split;
        self.previous_centres = self.clustering.vals.iter().map(|v| (v.position, v.normal)).collect();
        self.clustering_ms = start.elapsed().as_secs_f64() * 1000.0;
        let m = self.clustering.vals.len();
        if (self.params.vals as usize) > n && n > 0 {
            log::info!("val: {} VALs asked for, {n} VPLs: using {m}", self.params.vals);
        }
        self.counts = TechniqueCounts { lights_visible: ctx.lights.len(), ..Default::default() };
        // Steps 2 and 4 of the k-means (CPU and GPU alike): every VPL against every centre, `iterations` times
        // and once more for the final map.
        self.counts.work.kmeans_distance_evaluations =
            (kp.iterations as u64 + 1) * n as u64 * kp.vals.min(n) as u64 * u64::from(!vpls.is_empty());
        self.counts.figures.insert("vpls".into(), n as f64);
        self.counts.figures.insert("vals".into(), self.clustering.non_empty as f64);
        self.counts.figures.insert("iterations".into(), self.params.iterations as f64);
        self.counts.figures.insert("kmeans_vals".into(), k_means_vals as f64);
        if n == 0 || m == 0 {
            self.batches = 0;
            return Ok(0);
        }
        // The GPU side of steps 2-3: VALs (map centre, size, depth range, bounds) and the casters of their maps.
        let gpu_vals = self.place_vals(bounds);
        let geometry = ProxyParams {
            keep: self.params.proxy,
            max_error: self.params.proxy_error * self.scene_size,
            max_edge: self.params.max_edge * self.scene_size,
        };
        self.maps.update(ctx.gpu, ctx.scene, geometry);
        if let Some(t) = self.maps.copy_triangles() {
            self.counts.figures.insert("map_geometry_triangles".into(), t as f64);
        }
        let res = self.params.shadow_resolution.min(ctx.gpu.device.limits().max_texture_dimension_2d);
        self.shadows.ensure_tiles(ctx.gpu, res, m);
        self.vals_buffer.write(ctx.gpu, &gpu_vals);
        if !self.gpu_map {
            self.map_buffer.write(ctx.gpu, &self.clustering.assignment);
        }
        // Not bounded by `max_lights_per_step`: every batch recomputes the pixel's M VAL visibilities, which is
        // most of a step's cost, so small batches would multiply the work instead of splitting it.
        self.batch_size = (self.params.vpls_per_step as usize).max(1);
        self.batches = n.div_ceil(self.batch_size);
        // Step 5 VAL by VAL: each batch's VPLs listed by VAL, the ranges first. Two words per batch and VAL: with
        // tiny batches of many VPLs (`vpls_per_step = 1`, 65,536 VPLs) more than a storage binding holds, so
        // this frame evaluates every VPL instead (the same image).
        let words_needed = (self.batches * m * 2 + n) as u64;
        // (The buffer grows to the next power of two of bytes: half the largest buffer at most.)
        let limits = ctx.gpu.device.limits();
        let limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size / 2) / 4;
        self.lists_fit = words_needed <= limit;
        if self.lists_fit {
            let lists = cull::member_lists(&self.clustering.assignment, m, self.batch_size);
            self.members_offset = (lists.ranges.len() * 2) as u32;
            let words: Vec<u32> = lists.ranges.iter().flatten().chain(&lists.order).copied().collect();
            self.lists_buffer.write(ctx.gpu, &words);
        } else if self.params.skip_unlit {
            log::info!("val: {words_needed} words of member lists exceed a storage binding; every VPL evaluated");
        }
        self.counts.batches = self.batches;
        Ok(if self.params.interleave.on { self.batches + 1 } else { self.batches })
    }

    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        if step == self.batches {
            self.blur.encode(ctx, encoder, &self.params.interleave, self.allow_ratio(), &self.pass);
            return Ok(());
        }
        if step == 0 {
            self.encode_maps(ctx, encoder)?;
        }
        self.encode_gather(ctx, step, encoder);
        Ok(())
    }

    fn step_label(&self) -> &'static str {
        "val"
    }

    fn explain(&self) -> Vec<super::ExplainStep> {
        self.explain_steps()
    }

    fn overlay_legend(&self, layer: &OverlayLayer) -> Vec<super::LegendEntry> {
        self.legend_of(layer)
    }

    fn shadow_atlas(&self) -> Option<(&crate::services::cube_shadows::CubeAtlas, &'static str)> {
        self.shadows.atlas().map(|a| (a, "one paraboloid map per VAL, facing its normal"))
    }

    fn counts(&self) -> TechniqueCounts {
        self.counts.clone()
    }

    fn cpu_times(&self) -> Vec<PassTime> {
        let clustering = PassTime { name: "val clustering".into(), ms: self.clustering_ms, count: 1 };
        let bvh = self.bvh_build_ms.map(|ms| PassTime { name: "bvh build".into(), ms, count: 1 });
        std::iter::once(clustering).chain(bvh).chain(self.maps.build_time()).collect()
    }

    fn hover_points(&self) -> Vec<super::HoverPoint> {
        self.hover_list()
    }

    fn hover_details(&self, layer: &str, index: usize) -> Vec<String> {
        self.hover_text(layer, index)
    }

    fn overlays(&self, lights: &[PointLight]) -> Vec<OverlayLayer> {
        self.overlay_layers(lights)
    }
}
