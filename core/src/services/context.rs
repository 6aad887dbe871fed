//! What the renderer hands a technique each frame ([`FrameContext`]: the GPU, the scene, the targets, the
//! lights and VPLs, the services' outputs), how a technique's frame sees the suns ([`DirectionalVisibility`]),
//! and the full-screen pass that adds a technique's light into the HDR target ([`accumulate_pass`]). Here, with
//! the services, since the services that run a technique's passes take it (`per_light_shadows`, `vpl_gather`,
//! `shade_pass`, `directional`); the `Technique` trait that receives it is above, in `technique/mod.rs`.

use crate::accel::gpu_scene::GpuScene;
use crate::gpu::GpuContext;
use crate::math::Frustum;
use crate::scene::{Camera, PointLight};
use crate::timing::PassTimer;
use crate::vpl::{VplFrame, VplSettings};

use super::layouts::SharedLayouts;
use super::light_tiles::TileLists;
use super::lights::VisibleLights;

/// How a technique's frame sees the directional lights (drawn by the renderer's `directional.rs`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DirectionalVisibility {
    /// The orthographic shadow map (the default: the reference and the shadow-map techniques).
    #[default]
    ShadowMap,
    /// One shadow ray per pixel and light (the ground truths and the ray-traced techniques).
    Traced,
    /// No visibility (the unshadowed preview).
    None,
}

/// Everything a technique may read during a frame.
pub struct FrameContext<'a> {
    pub gpu: &'a GpuContext,
    pub scene: &'a GpuScene,
    pub layouts: &'a SharedLayouts,
    /// Group 0 of every full-screen pass: the frame uniform and the G-buffer (see `common.wgsl`).
    pub screen_bind_group: &'a wgpu::BindGroup,
    /// HDR radiance target (`SharedLayouts::hdr_format`); techniques add their lights' radiance into it.
    pub hdr_view: &'a wgpu::TextureView,
    pub camera: &'a Camera,
    pub aspect: f32,
    pub frustum: Frustum,
    pub lights: &'a [PointLight],
    /// The suns (at most [`crate::scene::MAX_DIRECTIONAL_LIGHTS`]). The renderer shades their direct light for
    /// every technique ([`super::directional`]) and makes VPLs of them; a technique reads them only
    /// for light it computes itself (the path tracer's bounce).
    pub directional_lights: &'a [crate::scene::DirectionalLight],
    pub timer: &'a PassTimer,
    /// Upper bound on the lights (or clusters, cube maps) one step may handle, so an interactive caller can keep
    /// each step short; `usize::MAX` when unlimited. Never changes the image, only how the work is split.
    pub max_lights_per_step: usize,
    /// Render target size in pixels.
    pub size: (u32, u32),
    /// Indirect radiance per pixel (`array<vec4<f32>>`, row-major), cleared at the start of every frame;
    /// indirect techniques add into it. A placeholder without an indirect technique.
    pub indirect_buffer: &'a wgpu::Buffer,
    /// The frame's VPLs (empty unless the indirect technique `Technique::uses_vpls`).
    pub vpls: &'a VplFrame,
    pub vpl_settings: &'a VplSettings,
    /// The lights whose range touches the view frustum, uploaded once for every technique.
    pub visible_lights: &'a VisibleLights,
    /// Per 16x16-pixel tile, the visible lights that reach it (group 2 of a shading pass, `light_tiles.wgsl`),
    /// built after `prepare` when the technique `Technique::uses_light_tiles`; encode steps read it.
    pub light_tiles: &'a TileLists,
    /// The render setting `light_tiles` (`RenderSettings::light_tiles`): techniques that bin their own spheres
    /// follow it too.
    pub light_tiles_enabled: bool,
    /// The bounds of the surfaces this frame shades (the view frustum within the scene's box), for receiver-aware
    /// caster culling in shadow maps ([`super::cube_shadows::CubeGeometry::receivers`]); None when
    /// the render setting is off.
    pub receivers: Option<crate::scene::Aabb>,
}

/// Most light evaluations (lights x shadow rays) one full-screen pass may do per pixel: a single pass over
/// 100,000 lights (or 4,096 lights x 256 rays) can run for seconds and lose a real GPU's device to its
/// watchdog, so passes are split to stay under this. The image does not change.
pub const MAX_LIGHT_WORK_PER_PASS: usize = 4096;

/// A full-screen pass that adds `pipeline`'s output into the HDR target: group 0 is the screen bind group,
/// groups 1.. are `groups` (the technique's, then the tile lists' when it reads them). The shading passes of all techniques go through here.
pub fn accumulate_pass(
    ctx: &FrameContext,
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::RenderPipeline,
    groups: &[&wgpu::BindGroup],
) {
    ctx.timer.render_pass(
        encoder,
        label,
        wgpu::RenderPassDescriptor {
            label: None,
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: ctx.hdr_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        },
        |pass| {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, ctx.screen_bind_group, &[]);
            for (i, group) in groups.iter().enumerate() {
                pass.set_bind_group(1 + i as u32, *group, &[]);
            }
            pass.draw(0..3, 0..1);
        },
    );
}
