//! The VPL gather, a renderer service for every VPL technique: a compute pass in which every pixel sums the
//! radiance of a batch of the frame's VPLs times their visibility and adds it into the indirect buffer
//! (`vpl_gather.wgsl`). A technique brings its visibility as WGSL (`fn vpl_visibility(s, v, k) -> f32`,
//! composed before `vpl_gather.wgsl`) and its bind group 1 (what the visibility reads: the BVH, a shadow-map
//! atlas, nothing); group 0 is the screen group, group 2 the gather's own (VPLs, batch, output).
//!
//! Precision: each pixel's batch sum is an f32 register sum, added once per batch into an f32 buffer written by
//! that pixel's invocation only, so no atomics are needed and batching changes nothing beyond f32 rounding
//! (the HDR target's f16 blending would lose thousands of tiny terms).
//!
//! Also here: the VPL overlays every VPL technique shows ([`vpl_overlays`]).

use glam::Vec3;

use super::context::FrameContext;
use crate::contract::overlay::{index_color, Glyph, HoverPoint, LegendEntry, Overlay, OverlayLayer};
use crate::contract::params::{Param, ParamKind, ParamValue};
use crate::gpu::bind::storage_rw_entry;
use crate::gpu::GpuContext;
use crate::services::layouts::{compute_pipeline, SharedLayouts};
use crate::vpl::VplSet;

/// Mirrors `GatherBatch` in `vpl_common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GatherBatchUniform {
    pub first_vpl: u32,
    pub vpl_count: u32,
    pub clamp_sq: f32,
    pub bias: f32,
    pub first_tile: u32,
    pub tiles_per_row: u32,
    pub resolution: u32,
    pub normal_offset: f32,
    pub depth_near: f32,
    pub depth_far: f32,
    pub origin_offset: f32,
    /// 1: interleaved sampling (every B²-th VPL per pixel of a B x B block, times B²); 2: the same, writing
    /// the luminances the blur's ratio estimator needs ([`Interleave::mode`]).
    pub interleave: u32,
    /// B, the side of the interleaving block ([`Interleave::block`]); unused without interleaving.
    pub block: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<GatherBatchUniform>() == 64);

/// Interleaved sampling's parameters, the same for every gather that interleaves (`vpl-shadowmaps`,
/// `vpl-raytraced`, `vpl-unshadowed`, `vpl-ism`, `val`): each pixel of a `block` x `block` tile gathers every
/// `block`²-th VPL and [`InterleaveBlur`] completes it, with the ratio estimator or the paper's blur.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interleave {
    /// Interleaved sampling (Dong section 6); off for the references.
    pub on: bool,
    /// With interleaving, the ratio estimator (`vpl_blur.wgsl`): each pixel's unshadowed light from every VPL
    /// times its window's visibility share.
    pub ratio: bool,
    /// The block's side B: B² classes of VPLs, a B x B blur window (the paper's 8).
    pub block: u32,
}

impl Default for Interleave {
    fn default() -> Self {
        Interleave { on: false, ratio: true, block: 8 }
    }
}

/// The smallest and largest interleaving block.
pub const MIN_BLOCK: u32 = 2;
pub const MAX_BLOCK: u32 = 8;

impl Interleave {
    /// The parameters as the UI and the CLI see them.
    pub fn describe(&self) -> [Param; 3] {
        [
            Param {
                key: "interleave",
                label: "Interleaved sampling",
                help: "Each pixel of a B x B block (`block`, the paper's 8) gathers every B²-th VPL (times B²), then \
                       a geometry-aware blur over the block completes it (Dong section 6): B² times fewer visibility \
                       tests a pixel",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(self.on),
            },
            Param {
                key: "ratio",
                label: "Ratio estimator",
                help: "With interleaving: each pixel's unshadowed light from every VPL times the share of it its \
                       window saw unblocked, so only visibility is blurred (beyond the paper; the unshadowed sum \
                       costs every VPL per pixel again); off: the window's light averaged, as the paper",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(self.ratio),
            },
            Param {
                key: "block",
                label: "Interleaving block",
                help: "With interleaving: the block's side B, B² shares of the VPLs and a B x B blur (the paper's 8); \
                       smaller: sharper and B² times fewer VPLs saved",
                kind: ParamKind::Int { min: MIN_BLOCK as i64, max: MAX_BLOCK as i64 },
                value: ParamValue::Int(self.block as i64),
            },
        ]
    }

    /// Set one of [`Interleave::describe`]'s parameters; false for another key.
    pub fn set(&mut self, key: &str, value: &ParamValue) -> bool {
        match (key, value) {
            ("interleave", ParamValue::Bool(v)) => self.on = *v,
            ("ratio", ParamValue::Bool(v)) => self.ratio = *v,
            ("block", ParamValue::Int(v)) => self.block = (*v).clamp(MIN_BLOCK as i64, MAX_BLOCK as i64) as u32,
            _ => return false,
        }
        true
    }

    /// `GatherBatchUniform::interleave`: 0 off, 1 the paper's blur, 2 the ratio estimator (when `ratio` and
    /// `allow_ratio`: a technique may refuse it for a frame, e.g. VAL's `solo`).
    pub fn mode(&self, allow_ratio: bool) -> u32 {
        match (self.on, self.ratio && allow_ratio) {
            (false, _) => 0,
            (true, false) => 1,
            (true, true) => 2,
        }
    }

    /// The batch fields for these parameters.
    pub fn apply(&self, batch: &mut GatherBatchUniform, allow_ratio: bool) {
        batch.interleave = self.mode(allow_ratio);
        // (The shaders clamp it to MIN_BLOCK..=MAX_BLOCK, as `set` does.)
        batch.block = self.block;
    }
}

/// Mirrors `BlurParams` in `vpl_blur.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct BlurUniform {
    ratio: u32,
    block: u32,
    pad: [u32; 2],
}

fn ratio_buffer(gpu: &GpuContext, size: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("vpl gather ratio"),
        size: size.max(RATIO_BYTES_PER_PIXEL),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A compute pipeline gathering VPLs with one visibility function.
pub struct VplGatherPass {
    pipeline: wgpu::ComputePipeline,
    gather_layout: wgpu::BindGroupLayout,
    uniform: wgpu::Buffer,
    /// The ratio estimator's per-pixel luminances (`ratio_out`, two f32 a pixel), made at the frame's size by
    /// the first batch that needs it; a placeholder of one pixel otherwise.
    ratio: wgpu::Buffer,
}

/// Bytes per pixel of the ratio estimator's buffer (`vec2<f32>`).
const RATIO_BYTES_PER_PIXEL: u64 = 8;

/// Workgroups of 8x8 covering the image.
pub fn pixel_workgroups(size: (u32, u32)) -> (u32, u32) {
    (size.0.div_ceil(8), size.1.div_ceil(8))
}

impl VplGatherPass {
    /// `source`: common.wgsl, the visibility's files, vpl_common.wgsl, vpl_gather.wgsl (see `shaders.rs`).
    pub fn new(
        gpu: &GpuContext,
        layouts: &SharedLayouts,
        label: &str,
        source: &str,
        visibility_layout: &wgpu::BindGroupLayout,
    ) -> VplGatherPass {
        Self::with_entry(gpu, layouts, label, source, "gather_main", visibility_layout)
    }

    /// A gather with its own entry point (a technique that computes visibility per cluster, not per VPL, and
    /// loops over the VPLs itself, with `vpl_common.wgsl`'s bindings and terms).
    pub fn with_entry(
        gpu: &GpuContext,
        layouts: &SharedLayouts,
        label: &str,
        source: &str,
        entry: &str,
        visibility_layout: &wgpu::BindGroupLayout,
    ) -> VplGatherPass {
        let device = &gpu.device;
        let gather_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("vpl gather"),
            entries: &[
                crate::gpu::bind::storage_entry(0),
                crate::gpu::bind::uniform_entry(1),
                storage_rw_entry(2),
                storage_rw_entry(3),
            ],
        });
        let pipeline = compute_pipeline(gpu, layouts, label, source, entry, &[visibility_layout, &gather_layout]);
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl gather batch"),
            size: std::mem::size_of::<GatherBatchUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let ratio = ratio_buffer(gpu, RATIO_BYTES_PER_PIXEL);
        VplGatherPass { pipeline, gather_layout, uniform, ratio }
    }

    /// The ratio estimator's buffer, for [`InterleaveBlur::encode`] after the frame's last batch.
    pub fn ratio_buffer(&self) -> &wgpu::Buffer {
        &self.ratio
    }

    /// Gather VPLs `batch.first_vpl .. + batch.vpl_count` of the frame into the indirect buffer, in a compute
    /// pass named `label`. One call per step: the batch uniform is written with `queue.write_buffer`.
    pub fn encode(
        &mut self,
        ctx: &FrameContext,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        visibility_group: &wgpu::BindGroup,
        batch: GatherBatchUniform,
    ) {
        self.encode_lights(ctx, encoder, label, visibility_group, batch, &ctx.vpls.buffer.buffer);
    }

    /// [`Self::encode`] over another set of lights in the `GpuVpl` layout (e.g. VPL clusters). With the ratio
    /// estimator (`batch.interleave` 2) the batch whose `first_vpl` is 0 starts the frame's ratio sums (clears
    /// [`Self::ratio_buffer`]), so a frame's batches go in order from its first VPL, as every technique's do.
    pub fn encode_lights(
        &mut self,
        ctx: &FrameContext,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        visibility_group: &wgpu::BindGroup,
        mut batch: GatherBatchUniform,
        lights: &wgpu::Buffer,
    ) {
        batch.clamp_sq = ctx.vpl_settings.clamp_world * ctx.vpl_settings.clamp_world;
        ctx.gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&batch));
        if batch.interleave == 2 {
            // The frame's first batch starts the sums (the renderer clears the indirect buffer itself).
            let size = ctx.size.0 as u64 * ctx.size.1 as u64 * RATIO_BYTES_PER_PIXEL;
            if self.ratio.size() != size.max(RATIO_BYTES_PER_PIXEL) {
                self.ratio = ratio_buffer(ctx.gpu, size);
            }
            if batch.first_vpl == 0 {
                encoder.clear_buffer(&self.ratio, 0, None);
            }
        }
        let group = ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vpl gather"),
            layout: &self.gather_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: lights.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: self.uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: ctx.indirect_buffer.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: self.ratio.as_entire_binding() },
            ],
        });
        let (x, y) = pixel_workgroups(ctx.size);
        ctx.timer.compute_pass(encoder, label, |pass| {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, ctx.screen_bind_group, &[]);
            pass.set_bind_group(1, visibility_group, &[]);
            pass.set_bind_group(2, &group, &[]);
            pass.dispatch_workgroups(x, y, 1);
        });
    }
}

/// The geometry-aware B x B blur that completes interleaved sampling (`vpl_blur.wgsl`): blurs the indirect
/// buffer into a scratch buffer and copies it back. Run once per frame, after the last gather. With the ratio
/// estimator (the gathers ran with interleave mode 2) it blurs the visibility share alone and multiplies each
/// pixel's unshadowed light from every VPL (what the gathers left in the indirect buffer) by it.
pub struct InterleaveBlur {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    uniform: wgpu::Buffer,
    scratch: Option<wgpu::Buffer>,
}

impl InterleaveBlur {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts) -> InterleaveBlur {
        let layout = gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("vpl blur"),
            entries: &[
                crate::gpu::bind::storage_entry(0),
                storage_rw_entry(1),
                crate::gpu::bind::storage_entry(2),
                crate::gpu::bind::uniform_entry(3),
            ],
        });
        let pipeline =
            compute_pipeline(gpu, layouts, "vpl_blur", crate::shaders::VPL_BLUR.source, "blur_main", &[&layout]);
        let uniform = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl blur"),
            size: std::mem::size_of::<BlurUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        InterleaveBlur { pipeline, layout, uniform, scratch: None }
    }

    /// After the frame's last batch of `pass`, gathered with `interleave` (and the ratio estimator when
    /// `allow_ratio`, as [`Interleave::apply`] was told).
    pub fn encode(
        &mut self,
        ctx: &FrameContext,
        encoder: &mut wgpu::CommandEncoder,
        interleave: &Interleave,
        allow_ratio: bool,
        pass: &VplGatherPass,
    ) {
        let ratio = (interleave.mode(allow_ratio) == 2).then(|| pass.ratio_buffer());
        let block = interleave.block;
        let size = ctx.indirect_buffer.size();
        if self.scratch.as_ref().is_none_or(|b| b.size() != size) {
            self.scratch = Some(ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("vpl blur scratch"),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }));
        }
        let params = BlurUniform { ratio: ratio.is_some() as u32, block, pad: [0; 2] };
        ctx.gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&params));
        let scratch = self.scratch.as_ref().expect("made above");
        let group = ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("vpl blur"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: ctx.indirect_buffer.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: scratch.as_entire_binding() },
                // Without the ratio estimator the blur reads its source there, unused (one binding layout).
                wgpu::BindGroupEntry { binding: 2, resource: ratio.unwrap_or(ctx.indirect_buffer).as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: self.uniform.as_entire_binding() },
            ],
        });
        let (x, y) = pixel_workgroups(ctx.size);
        ctx.timer.compute_pass(encoder, "vpl blur", |pass| {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, ctx.screen_bind_group, &[]);
            pass.set_bind_group(1, &group, &[]);
            pass.dispatch_workgroups(x, y, 1);
        });
        encoder.copy_buffer_to_buffer(scratch, 0, ctx.indirect_buffer, 0, size);
    }
}

/// Above this many VPLs the disc and normal layers draw every n-th VPL only (and say so in their names).
const OVERLAY_MAX_VPLS: usize = 4096;

/// The overlays of a VPL set: oriented discs (squares in the VPL's tangent plane) coloured by flux or by light,
/// their normals, and the paths (RSM texel rays or particle bounces) of up to 48 VPLs of light `path_light`.
/// `scene_size` scales the glyphs.
pub fn vpl_overlays(set: &VplSet, scene_size: f32, path_light: u32) -> Vec<OverlayLayer> {
    let vpls = &set.vpls;
    let stride = vpls.len().div_ceil(OVERLAY_MAX_VPLS).max(1);
    let max_flux = vpls.iter().map(|v| v.flux.max_element()).fold(0.0f32, f32::max).max(1e-20);
    let half = scene_size * 0.004;
    let disc = |v: &crate::vpl::Vpl, color: [f32; 4]| {
        let (t, b) = v.normal.any_orthonormal_pair();
        Overlay::Rect { center: v.position, half_u: t * half, half_v: b * half, color }
    };
    let flux_color = |f: Vec3| {
        // Hue from the flux's colour, brightness from its magnitude (square root, so dim VPLs stay visible).
        let c = f / f.max_element().max(1e-20);
        let k = 0.35 + 0.65 * (f.max_element() / max_flux).sqrt();
        [c.x * k, c.y * k, c.z * k, 1.0]
    };
    let thin = if stride > 1 { " (every n-th)" } else { "" };
    let name = |base: &'static str, thinned: &'static str| if thin.is_empty() { base } else { thinned };
    let [by_flux, by_light] = vpl_layer_names(vpls.len());
    vec![
        OverlayLayer {
            name: by_flux,
            visible_by_default: true,
            primitives: vpls.iter().step_by(stride).map(|v| disc(v, flux_color(v.flux))).collect(),
        },
        OverlayLayer {
            name: by_light,
            visible_by_default: false,
            primitives: vpls.iter().step_by(stride).map(|v| disc(v, index_color(v.light as usize))).collect(),
        },
        OverlayLayer {
            name: name("vpl normals", "vpl normals (every n-th)"),
            visible_by_default: false,
            primitives: vpls
                .iter()
                .step_by(stride)
                .map(|v| Overlay::Line {
                    from: v.position,
                    to: v.position + v.normal * (half * 6.0),
                    color: [0.4, 0.9, 1.0, 1.0],
                })
                .collect(),
        },
        OverlayLayer {
            name: "vpl paths (48 of the chosen light)",
            visible_by_default: false,
            primitives: vpls
                .iter()
                .filter(|v| v.light == path_light)
                .take(48)
                .map(|v| Overlay::Line { from: v.from, to: v.position, color: [1.0, 0.85, 0.3, 0.8] })
                .collect(),
        },
    ]
}

/// The names of [`vpl_overlays`]' layers that draw each VPL (by flux, by light), for a set of `count` VPLs.
fn vpl_layer_names(count: usize) -> [&'static str; 2] {
    if count.div_ceil(OVERLAY_MAX_VPLS) > 1 {
        ["vpls (flux, every n-th)", "vpls (by light, every n-th)"]
    } else {
        ["vpls (flux)", "vpls (by light)"]
    }
}

/// The hover points of [`vpl_overlays`]: the VPLs its layers draw, indexed by VPL.
pub fn vpl_hover_points(set: &VplSet) -> Vec<HoverPoint> {
    let stride = set.vpls.len().div_ceil(OVERLAY_MAX_VPLS).max(1);
    let layers = vpl_layer_names(set.vpls.len());
    let points = set.vpls.iter().enumerate().step_by(stride);
    points.flat_map(|(index, v)| layers.map(|layer| HoverPoint { layer, position: v.position, index })).collect()
}

/// The tooltip of VPL `index` of the set: where its light came from, its flux and normal.
pub fn vpl_details(set: &VplSet, index: usize) -> Vec<String> {
    let Some(v) = set.vpls.get(index) else { return Vec::new() };
    let f = v.flux;
    vec![
        format!("VPL {index} of {}", set.vpls.len()),
        format!("from {}", set.light_name(v.light)),
        format!("flux ({:.3}, {:.3}, {:.3})", f.x, f.y, f.z),
        format!("normal ({:.2}, {:.2}, {:.2})", v.normal.x, v.normal.y, v.normal.z),
    ]
}

/// True for the names of [`vpl_overlays`]' layers that draw VPLs.
pub fn is_vpl_layer(set: &VplSet, layer: &str) -> bool {
    vpl_layer_names(set.vpls.len()).contains(&layer)
}

/// The legend of the layers of [`vpl_overlays`]; None for other layers.
pub fn vpl_layer_legend(layer: &OverlayLayer) -> Option<Vec<LegendEntry>> {
    let thinned = if layer.name.contains("every n-th") { " (every n-th VPL, past 4,096)" } else { "" };
    let name = layer.name;
    let entry = match () {
        _ if name.starts_with("vpls (flux") => LegendEntry::new(
            Glyph::Rect,
            [1.0, 0.9, 0.6, 1.0],
            format!("a VPL in its surface's plane, hue of its flux, brighter with more flux{thinned}"),
        ),
        _ if name.starts_with("vpls (by light") => LegendEntry::new(
            Glyph::Palette,
            index_color(0),
            format!("a VPL in the colour of the light it came from{thinned}"),
        ),
        _ if name.starts_with("vpl normals") => {
            LegendEntry::new(Glyph::Line, [0.4, 0.9, 1.0, 1.0], format!("a VPL's normal{thinned}"))
        }
        _ if name.starts_with("vpl paths") => LegendEntry::new(
            Glyph::Line,
            [1.0, 0.85, 0.3, 0.8],
            "where the light reaching a VPL left from (the light, or the previous bounce)",
        ),
        _ => return None,
    };
    Some(vec![entry])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vpl::Vpl;

    fn set(n: usize, lights: u32) -> VplSet {
        let vpls = (0..n)
            .map(|i| Vpl {
                position: Vec3::new(i as f32, 0.0, 0.0),
                normal: Vec3::Y,
                flux: Vec3::new(1.0 + i as f32, 0.5, 0.0),
                light: i as u32 % lights,
                from: Vec3::Y,
            })
            .collect();
        VplSet { vpls, ..Default::default() }
    }

    #[test]
    fn layers_show_every_vpl_and_the_chosen_lights_paths() {
        let layers = vpl_overlays(&set(100, 3), 10.0, 2);
        let by = |name: &str| layers.iter().find(|l| l.name.starts_with(name)).unwrap();
        assert_eq!(by("vpls (flux)").primitives.len(), 100);
        assert_eq!(by("vpl normals").primitives.len(), 100);
        let paths = &by("vpl paths").primitives;
        assert_eq!(paths.len(), 33);
        // Light 2's VPLs are 2, 5, 8, ...: each path ends at its VPL.
        assert!(matches!(paths[0], Overlay::Line { to, .. } if to == Vec3::new(2.0, 0.0, 0.0)));
        // The brightest VPL is drawn at full brightness, hue from its flux.
        match by("vpls (flux)").primitives[99] {
            Overlay::Rect { color, .. } => assert!((color[0] - 1.0).abs() < 1e-5 && color[2] == 0.0),
            _ => panic!("discs are rectangles"),
        }
    }

    #[test]
    fn many_vpls_are_thinned_and_say_so() {
        let layers = vpl_overlays(&set(10_000, 1), 10.0, 0);
        let flux = layers.iter().find(|l| l.name.starts_with("vpls (flux")).unwrap();
        assert!(flux.name.contains("every n-th") && flux.primitives.len() <= OVERLAY_MAX_VPLS);
    }
}
