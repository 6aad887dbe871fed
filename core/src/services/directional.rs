//! Directional lights (a glTF sun, [`crate::scene::DirectionalLight`]): a renderer service that adds them to
//! every direct technique's frame, after the G-buffer and the ambient pass, in one step of its own
//! ("directional lights"). The papers' techniques are about many point lights; a scene has at most
//! [`MAX_DIRECTIONAL_LIGHTS`] suns, so there is nothing to cluster, merge or resample: every technique gets the
//! same treatment, and only the visibility differs by what the technique is
//! (a technique's `directional_visibility`):
//!
//! 1. Fit (CPU, [`fit`]): per light an orthographic view along its direction whose x-y extent covers the part of
//!    the scene the camera sees (the view frustum's corners, clipped to the scene's bounds, in the light's
//!    frame: the shadow receivers) and whose depth covers the whole scene towards the light (every caster
//!    between the sun and a receiver).
//! 2. Depth ([`DirectionalLights::render_maps`]): the scene drawn into one tile per light of a depth atlas by
//!    the shared [`CubeShadowRenderer::render_views`] (chunk culling, alpha-tested cut-outs), [`RESOLUTION`]²
//!    texels.
//! 3. Shade ([`DirectionalLights::shade`], `shaders/directional_light.wgsl`): every geometry pixel adds each
//!    light's BRDF times its irradiance along the direction times the visibility:
//!    - `ShadowMap` (the reference and the shadow-map approximations: LightCluster, INSM, ISM): a 3x3 PCF of the
//!      orthographic map (`directional_shadowmap.wgsl`), depth bias and normal offset of a texel and a half;
//!    - `Traced` (the ray tracer, ReSTIR, whose visibility is ray traced): one shadow ray through the scene BVH
//!      (`directional_traced.wgsl`): exact, the truth the map is measured against;
//!    - `None` (the unshadowed preview): no visibility.
//!
//! The lights are the scene's (a glTF file's suns) until `Renderer::set_directional_lights` replaces them
//! (the app's Lights panel adds, turns and removes suns; scene files keep them).
//!
//! Indirect light: the suns make VPLs too ([`crate::vpl`]: an orthographic RSM or parallel particles), so every
//! indirect technique sees them, and the path tracer adds each sun with a shadow ray at every bounce point.

use glam::{Mat4, Vec3, Vec4};
use wgpu::util::DeviceExt;

use super::context::{DirectionalVisibility, FrameContext};
use crate::accel::gpu_scene::GpuScene;
use crate::accel::scene_bvh::SceneBvh;
use crate::error::GpuError;
use crate::gpu::bind::{depth_texture_entry, uniform_entry};
use crate::gpu::GpuContext;
use crate::scene::{Aabb, Camera, DirectionalLight, MAX_DIRECTIONAL_LIGHTS};
use crate::services::cube_shadows::CubeShadowRenderer;
use crate::services::layouts::SharedLayouts;
use crate::services::shade_pass::ShadePass;
use crate::shaders::{DIRECTIONAL_SHADOWMAP as MAPPED, DIRECTIONAL_TRACED as TRACED};
use crate::timing::PassTimer;

/// Texels per side of a directional light's shadow map.
pub const RESOLUTION: u32 = 2048;
/// Shadow rays' origin offset along the normal, world units per metre of camera distance (the ray tracer's
/// default `bias`).
const RAY_BIAS: f32 = 0.001;

/// Mirrors `DirectionalOne` in `shaders/directional_light.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuDirectional {
    clip_from_world: [[f32; 4]; 4],
    direction: [f32; 4],
    radiance: [f32; 4],
    tile: [f32; 4],
}

/// Mirrors `Directionals` in `shaders/directional_light.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct DirectionalUniform {
    count: u32,
    mode: u32,
    ray_bias: f32,
    ray_length: f32,
    lights: [GpuDirectional; MAX_DIRECTIONAL_LIGHTS],
}
const _: () = assert!(std::mem::size_of::<DirectionalUniform>() == 16 + 112 * MAX_DIRECTIONAL_LIGHTS);

/// Step 1: the orthographic clip-from-world of a light travelling along `direction` (unit) that covers the
/// scene's part of `camera`'s view (at `aspect`) in x-y and all of `scene` in depth (0 nearest the light).
/// None when the view holds nothing of the scene.
pub fn fit(direction: Vec3, camera: &Camera, aspect: f32, scene: &Aabb) -> Option<Mat4> {
    // The receivers: the view frustum's box within the scene's (the shadow maps' receiver-aware culling uses
    // the same bound).
    let receivers = crate::services::cube_shadows::receiver_bounds(camera, aspect, scene)?;
    let (right, up) = direction.any_orthonormal_pair();
    let to_light = |p: Vec3| Vec3::new(p.dot(right), p.dot(up), p.dot(direction));
    let light_box = |b: &Aabb| Aabb::from_points(b.corners().map(to_light));
    // x-y: the receivers; depth: the whole scene towards the light (every caster between it and them).
    let (xy, depth) = (light_box(&receivers), light_box(scene));
    let (x0, x1, y0, y1) = (xy.min.x, xy.max.x, xy.min.y, xy.max.y);
    if !(x1 > x0 && y1 > y0) {
        return None;
    }
    // A little margin, so the PCF's neighbours of a border receiver are inside the map.
    let pad = 2.0 / RESOLUTION as f32;
    let (cx, cy, hx, hy) = ((x0 + x1) * 0.5, (y0 + y1) * 0.5, (x1 - x0) * (0.5 + pad), (y1 - y0) * (0.5 + pad));
    let depth_pad = 1e-3 * scene.size().length().max(1e-6);
    let (z0, z1) = (depth.min.z - depth_pad, depth.max.z + depth_pad);
    // clip = ((x - cx) / hx, (y - cy) / hy, (z - z0) / (z1 - z0), 1), x, y, z the light-frame coordinates.
    let row = |axis: Vec3, scale: f32, offset: f32| (axis * scale).extend(-offset * scale);
    let rx = row(right, 1.0 / hx, cx);
    let ry = row(up, 1.0 / hy, cy);
    let rz = row(direction, 1.0 / (z1 - z0), z0);
    Some(Mat4::from_cols(rx, ry, rz, Vec4::W).transpose())
}

/// The service: the depth atlas, the two shading passes and their uniform.
pub struct DirectionalLights {
    maps: CubeShadowRenderer,
    mapped: ShadePass,
    traced: ShadePass,
    uniform: wgpu::Buffer,
    /// The BVH the traced group was made for.
    bvh: Option<std::sync::Arc<SceneBvh>>,
    traced_group: Option<wgpu::BindGroup>,
    /// The mode and light count of the frame's uniform (0 lights: nothing to shade).
    mode: DirectionalVisibility,
    count: usize,
    /// The lights shaded: the scene's, unless `Renderer::set_directional_lights` replaced them.
    lights: Vec<DirectionalLight>,
}

impl DirectionalLights {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts, lights: &[DirectionalLight]) -> DirectionalLights {
        let mapped = ShadePass::new::<[u32; 4]>(
            gpu,
            layouts,
            "directional lights",
            &MAPPED,
            &[uniform_entry(2), depth_texture_entry(3)],
            false,
        );
        let traced_entries = [SceneBvh::layout_entries(), vec![uniform_entry(2)]].concat();
        let traced = ShadePass::new::<[u32; 4]>(gpu, layouts, "directional lights", &TRACED, &traced_entries, false);
        let uniform = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("directional lights"),
            contents: bytemuck::bytes_of(&<DirectionalUniform as bytemuck::Zeroable>::zeroed()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        DirectionalLights {
            maps: CubeShadowRenderer::new(gpu),
            mapped,
            traced,
            uniform,
            bvh: None,
            traced_group: None,
            mode: DirectionalVisibility::None,
            count: 0,
            lights: lights.to_vec(),
        }
    }

    /// Steps 1-2 for `scene`'s directional lights seen by `camera`: the uniform, and for `ShadowMap` the depth
    /// maps. False when there is nothing to shade (no directional light, or none whose map covers the view).
    #[allow(clippy::too_many_arguments)]
    pub fn render_maps(
        &mut self,
        gpu: &GpuContext,
        scene: &GpuScene,
        camera: &Camera,
        aspect: f32,
        mode: DirectionalVisibility,
        timer: &PassTimer,
        encoder: &mut wgpu::CommandEncoder,
    ) -> bool {
        let fitted: Vec<(DirectionalLight, Mat4)> = self
            .lights
            .iter()
            .filter_map(|d| fit(d.direction, camera, aspect, &scene.bounds).map(|m| (*d, m)))
            .collect();
        self.count = fitted.len();
        self.mode = mode;
        if fitted.is_empty() {
            return false;
        }
        let resolution = RESOLUTION.min(gpu.device.limits().max_texture_dimension_2d);
        let mut uniform = DirectionalUniform {
            count: fitted.len() as u32,
            mode: match mode {
                DirectionalVisibility::None => 0,
                DirectionalVisibility::ShadowMap => 1,
                DirectionalVisibility::Traced => 2,
            },
            ray_bias: RAY_BIAS,
            ray_length: 2.0 * scene.bounds.size().length().max(1e-6),
            lights: Default::default(),
        };
        if mode == DirectionalVisibility::ShadowMap {
            self.maps.ensure_tiles(gpu, resolution, fitted.len());
        }
        let tiles_per_row = self.maps.atlas().map_or(1, |a| a.tiles_per_row) as usize;
        for (i, (d, m)) in fitted.iter().enumerate() {
            // A texel's footprint on the receivers: the map's width over its texels.
            let width = 2.0 / m.row(0).truncate().length().max(1e-12);
            let texel = width / resolution as f32;
            let depth_range = 1.0 / m.row(2).truncate().length().max(1e-12);
            uniform.lights[i] = GpuDirectional {
                clip_from_world: m.to_cols_array_2d(),
                direction: d.direction.extend(1.5 * texel / depth_range).to_array(),
                radiance: (d.color * d.illuminance).extend(1.5 * texel).to_array(),
                tile: [
                    ((i % tiles_per_row) as u32 * resolution) as f32,
                    ((i / tiles_per_row) as u32 * resolution) as f32,
                    resolution as f32,
                    0.0,
                ],
            };
        }
        gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        if mode == DirectionalVisibility::Traced {
            let (bvh, _) = scene.bvh(gpu);
            if self.bvh.as_ref().is_none_or(|b| !std::sync::Arc::ptr_eq(b, &bvh)) || self.traced_group.is_none() {
                let entries = [
                    bvh.bind_entries(),
                    vec![wgpu::BindGroupEntry { binding: 2, resource: self.uniform.as_entire_binding() }],
                ]
                .concat();
                self.traced_group = Some(self.traced.bind_group(gpu, &entries));
                self.bvh = Some(bvh);
            }
        }
        // The preview and the traced pass bind an atlas too (one texel, when no map was ever rendered).
        if self.maps.atlas().is_none() {
            self.maps.ensure_tiles(gpu, 1, 1);
        }
        if mode == DirectionalVisibility::ShadowMap {
            let views: Vec<Mat4> = fitted.iter().map(|(_, m)| *m).collect();
            self.maps.render_views(
                gpu,
                scene.cube_geometry(),
                timer,
                encoder,
                "directional shadow maps",
                &views,
                0,
                true,
            );
        }
        true
    }

    pub fn lights(&self) -> &[DirectionalLight] {
        &self.lights
    }

    /// Replace the lights (checked by the caller).
    pub(crate) fn set_lights(&mut self, lights: &[DirectionalLight]) {
        self.lights = lights.to_vec();
    }

    /// Step 3: the frame's directional light into the HDR target (after [`Self::render_maps`] said there is
    /// some).
    pub fn shade(&self, ctx: &FrameContext, encoder: &mut wgpu::CommandEncoder) -> Result<(), GpuError> {
        if self.count == 0 {
            return Ok(());
        }
        match (self.mode, &self.traced_group) {
            (DirectionalVisibility::Traced, Some(group)) => {
                self.traced.encode(ctx, encoder, "directional lights", group, None);
            }
            (DirectionalVisibility::Traced, None) => {
                return Err(GpuError::InvalidSettings("directional lights: no BVH bound for the shadow rays".into()));
            }
            (DirectionalVisibility::ShadowMap | DirectionalVisibility::None, _) => {
                let atlas = self
                    .maps
                    .atlas()
                    .ok_or_else(|| GpuError::InvalidSettings("directional lights: render_maps before shade".into()))?;
                let group = self.mapped.bind_group(
                    ctx.gpu,
                    &[
                        wgpu::BindGroupEntry { binding: 2, resource: self.uniform.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&atlas.view) },
                    ],
                );
                self.mapped.encode(ctx, encoder, "directional lights", &group, None);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fitted_map_covers_the_visible_scene_and_orders_depth_from_the_light() {
        let scene = Aabb { min: Vec3::new(-5.0, 0.0, -5.0), max: Vec3::new(5.0, 4.0, 5.0) };
        let camera = Camera::look_at(Vec3::new(0.0, 2.0, 4.5), Vec3::new(0.0, 1.0, 0.0), 1.0, 0.05, 100.0);
        let direction = Vec3::new(0.3, -1.0, 0.2).normalize();
        let m = fit(direction, &camera, 16.0 / 9.0, &scene).expect("the view holds the scene");
        // A point the camera sees maps into the map; depth grows along the light's direction.
        let seen = Vec3::new(0.0, 0.0, 0.0);
        let c = m.project_point3(seen);
        assert!(c.x.abs() < 1.0 && c.y.abs() < 1.0 && (0.0..=1.0).contains(&c.z), "{c}");
        let below = m.project_point3(seen + direction);
        assert!(below.z > c.z, "further along the light is deeper");
        // Every corner of the scene lies within the depth range (every caster is drawn).
        for i in 0..8 {
            let p = Vec3::new(
                if i & 1 == 0 { -5.0 } else { 5.0 },
                if i & 2 == 0 { 0.0 } else { 4.0 },
                if i & 4 == 0 { -5.0 } else { 5.0 },
            );
            let z = m.project_point3(p).z;
            assert!((0.0..=1.0).contains(&z), "corner {p}: depth {z}");
        }
        // Nothing of the scene in view: no map.
        let away = Camera::look_at(Vec3::new(0.0, 2.0, 40.0), Vec3::new(0.0, 2.0, 80.0), 1.0, 0.05, 10.0);
        assert!(fit(direction, &away, 1.0, &scene).is_none());
        let empty = Aabb::EMPTY;
        assert!(fit(direction, &camera, 1.0, &empty).is_none());
    }
}
