//! Imperfect shadow maps (Ritschel, Grosch, Kim, Seidel, Dachsbacher, Kautz 2008): a low-resolution shadow map
//! per light, splatted from a coarse point approximation of the scene instead of rasterised from its triangles,
//! with the holes filled by pull-push. Two techniques share this folder: `ism` for the scene's lights (as the
//! INSM paper, Wang et al. 2016, compares against it in its Table 1 and Figs. 4-5: about 12,000 points per
//! 128x128 map, its target here is `reference`), and `vpl-ism` for VPLs (Ritschel's use, which Dong et al. 2009
//! name for VPL visibility; its target is `vpl-shadowmaps`), gathered through the shared VPL gather.
//!
//! Symbols: the scene's point pool `P` (`|P| = N`, [`points::pool_size`]), a map's subset of `n` points
//! (`points`), the map side `w` (`resolution`), the pull-push levels `L` (`levels`) and depth threshold `τ`
//! (`threshold`), a texel's footprint `f = d (2 / w)(1 + cos θ)` at a receiver at distance `d` and angle `θ` to
//! the map's axis, the bias `b f` and the normal offset `o f` (`bias`, `normal_offset`).
//!
//! Per frame:
//! 1. Points (section 3.1, [`points`]): `P` uniform by area over the scene's triangles, stratified and shuffled
//!    with `seed`, sampled on the CPU once per scene and kept (with the technique, until the scene, `seed` or
//!    `N` change); map `i` (light `i` of the frame, or VPL `i`) splats the `n` points from `i n mod N`.
//! 2. Splatting (section 3.2, [`IsmMaps::render`], `ism/splat.wgsl`): per batch of maps, one compute dispatch
//!    of `n` invocations per map; each point's normalised distance `z = (d - near)/(far - near)` goes into the
//!    one texel its direction lands in with `atomicMin` on the f32 bits (a u32 storage buffer). A point light's
//!    map is a dual paraboloid (Brabec et al. 2002: two hemispheres facing +y and -y, two tiles); a VPL's one
//!    hemispherical paraboloid along its normal, as Ritschel's, centred a little off its surface as
//!    `vpl-shadowmaps`'s maps.
//! 3. Pull-push (section 3.3, [`pull_push`], `ism/pull_push.wgsl`): `L` pull dispatches (a coarse texel the mean
//!    of its children within `τ` of the nearest), `L` push dispatches (an empty texel the bilinear mean of the
//!    coarser level within `τ`), a resolve of level 0 into the batch's atlas (`R32Float`, 1.0 empty).
//! 4. Shadow lookup (`ism/shade.wgsl` for lights, through the tiled light lists as the reference's shading;
//!    `ism/vpl_visibility.wgsl` for VPLs, in the shared gather `vpl_gather.wgsl`): the receiver moved `o f` along
//!    its normal, one texel, visible when `d - b f <= z_occluder`.
//!
//! Deviations from the paper, and why:
//! - Points are single-texel splats (Ritschel's points are pixels too) and pull-push fills only empty texels:
//!   a background point that lands in a gap of a nearer surface stays (the threshold only keeps it out of the
//!   averages), which is ISM's light leaking at low point counts.
//! - The pool holds [`points::POOL_SUBSETS`] subsets (at most [`points::MAX_POOL_POINTS`] points), not one per
//!   map (Ritschel's 8 M points for 1,024 VPLs): maps past the 32nd reuse subsets, for memory.
//! - Bias and normal offset are in texel footprints, not world units, so one value suits every scene scale and
//!   map resolution (a splat's depth error grows with the footprint).
//! - Cut-out (alpha-tested) materials drop their points on cut-out texels (nearest texel), as the depth passes
//!   alpha-test them.

mod overlays;
pub mod params;
pub mod passes;
pub mod points;
pub mod pull_push;

use std::sync::Arc;

use glam::Vec3;

use super::{FrameContext, OverlayLayer, Param, ParamError, ParamValue, Technique, TechniqueCounts};
use crate::error::GpuError;
use crate::gpu::bind::{depth_texture_entry, storage_entry, uniform_entry};
use crate::gpu::GpuContext;
use crate::scene::PointLight;
use crate::services::cube_shadows::CubeAtlas;
use crate::services::layouts::SharedLayouts;
use crate::services::shade_pass::ShadePass;
use crate::services::vpl_gather::{GatherBatchUniform, InterleaveBlur, VplGatherPass};
use crate::shaders::WgslModule;
use crate::timing::PassTime;
use crate::vpl::VplSet;
pub use params::IsmParams;
pub use passes::{GpuIsmView, IsmMaps, MapSettings};
use points::subset_offset;
use pull_push::usable_levels;

/// This technique's own WGSL modules; its registry entries list them and the naga test validates them.
pub const SHADERS: &[WgslModule] = &[passes::SPLAT, passes::PULL_PUSH, SHADE, VPL_GATHER];
const SHADE: WgslModule = crate::shaders::wgsl!(
    "ism_shade",
    [
        "shaders/common.wgsl",
        "shaders/light_tiles.wgsl",
        "shaders/vpl_basis.wgsl",
        "core/src/technique/ism/paraboloid.wgsl",
        "core/src/technique/ism/shade.wgsl",
        "shaders/per_light_main.wgsl"
    ]
);
const VPL_GATHER: WgslModule = crate::shaders::wgsl!(
    "ism_vpl_gather",
    [
        "shaders/common.wgsl",
        "shaders/vpl_common.wgsl",
        "shaders/vpl_basis.wgsl",
        "core/src/technique/ism/paraboloid.wgsl",
        "core/src/technique/ism/vpl_visibility.wgsl",
        "shaders/vpl_gather.wgsl"
    ]
);

/// Mirrors `IsmBatch` in `ism/shade.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadeUniform {
    first_light: u32,
    light_count: u32,
    resolution: u32,
    tiles_per_row: u32,
    bias: f32,
    normal_offset: f32,
    _pad: [f32; 2],
}
const _: () = assert!(std::mem::size_of::<ShadeUniform>() == 32);

/// A copy of the inspected map's tiles (a light's two, a VPL's one), which the inspector shows as the
/// technique's depth image whatever batch it was in.
struct Inspected {
    atlas: CubeAtlas,
}

/// Copy tiles `tiles` of `from` into tiles 0.. of a new atlas (with their projections).
fn copy_tiles(gpu: &GpuContext, encoder: &mut wgpu::CommandEncoder, from: &CubeAtlas, tiles: &[usize]) -> CubeAtlas {
    let res = from.resolution;
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("ism inspected map"),
        size: wgpu::Extent3d { width: res * tiles.len() as u32, height: res, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: passes::ATLAS_FORMAT,
        usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    for (i, &t) in tiles.iter().enumerate() {
        let origin =
            wgpu::Origin3d { x: (t as u32 % from.tiles_per_row) * res, y: (t as u32 / from.tiles_per_row) * res, z: 0 };
        encoder.copy_texture_to_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &from.texture,
                mip_level: 0,
                origin,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d { x: i as u32 * res, y: 0, z: 0 },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::Extent3d { width: res, height: res, depth_or_array_layers: 1 },
        );
    }
    let view = texture.create_view(&Default::default());
    let projections = tiles.iter().map(|&t| from.projections.get(t).copied().flatten()).collect();
    CubeAtlas {
        texture,
        view,
        resolution: res,
        tiles_per_row: tiles.len() as u32,
        capacity: 0,
        tiles: tiles.len(),
        projections,
    }
}

/// The figures both techniques report.
fn map_figures(counts: &mut TechniqueCounts, params: &IsmParams, settings: &MapSettings, pool: usize, maps: usize) {
    let f = &mut counts.figures;
    f.insert("ism maps".into(), maps as f64);
    f.insert("ism points per map".into(), settings.points_per_map as f64);
    f.insert("ism point splats".into(), maps as f64 * settings.points_per_map as f64);
    f.insert("ism pool points".into(), pool as f64);
    f.insert("ism resolution".into(), settings.resolution as f64);
    f.insert("ism pull-push levels".into(), settings.levels as f64);
    if settings.levels < params.levels {
        // Said: more levels than the resolution has were asked for.
        f.insert("ism pull-push levels asked".into(), params.levels as f64);
    }
}

fn settings_of(p: &IsmParams) -> MapSettings {
    MapSettings {
        resolution: p.resolution,
        points_per_map: p.points_per_map,
        levels: usable_levels(p.resolution, p.levels),
        threshold: p.threshold,
    }
}

/// `ism`: a dual-paraboloid imperfect shadow map per visible light, in batches.
pub struct Ism {
    pub params: IsmParams,
    maps: IsmMaps,
    shade: ShadePass,
    shade_group: Option<wgpu::BindGroup>,
    /// The light buffer generation and atlas generation the shading group was made with.
    shade_key: Option<(u64, u64)>,
    settings: MapSettings,
    batch_size: usize,
    visible: Vec<usize>,
    inspected: Option<Inspected>,
    counts: TechniqueCounts,
    sampling_ms: Option<f64>,
}

impl Ism {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts) -> Ism {
        let entries = [storage_entry(0), uniform_entry(1), depth_texture_entry(2)];
        let params = IsmParams::default();
        Ism {
            settings: settings_of(&params),
            params,
            maps: IsmMaps::new(gpu),
            shade: ShadePass::new::<ShadeUniform>(gpu, layouts, "ism shade", &SHADE, &entries, true),
            shade_group: None,
            shade_key: None,
            batch_size: 1,
            visible: Vec::new(),
            inspected: None,
            counts: TechniqueCounts::default(),
            sampling_ms: None,
        }
    }

    /// The scene's point pool of the last frame (empty before the first).
    pub fn pool(&self) -> Arc<Vec<Vec3>> {
        self.maps.pool().map(|p| p.points.clone()).unwrap_or_default()
    }
}

impl Technique for Ism {
    fn key(&self) -> &'static str {
        "ism"
    }

    fn label(&self) -> &'static str {
        "Imperfect shadow maps"
    }

    fn params(&self) -> Vec<Param> {
        self.params.list(false)
    }

    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        self.params.set("ism", false, key, value)
    }

    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        self.sampling_ms = self.maps.ensure_pool(ctx.gpu, ctx.scene, self.params.points_per_map, self.params.seed);
        self.visible = ctx.visible_lights.indices.clone();
        self.settings = settings_of(&self.params);
        self.counts = TechniqueCounts { lights_visible: self.visible.len(), ..Default::default() };
        if self.visible.is_empty() {
            self.inspected = None;
            return Ok(0);
        }
        let budget = self.params.atlas_mib as u64 * (1 << 20);
        let tiles = IsmMaps::tiles_per_batch(ctx.gpu, self.settings.resolution, self.settings.levels, budget, 2)?;
        self.batch_size = (tiles / 2).min(ctx.max_lights_per_step).max(1);
        let tiles = 2 * self.batch_size.min(self.visible.len());
        self.maps.ensure_batch(ctx.gpu, self.settings.resolution, tiles, self.settings.levels);
        let key = (ctx.visible_lights.generation, self.maps.atlas_generation());
        if self.shade_key != Some(key) || self.shade_group.is_none() {
            let atlas = self.maps.atlas().expect("ensure_batch made it");
            self.shade_group = Some(self.shade.bind_group(
                ctx.gpu,
                &[
                    wgpu::BindGroupEntry { binding: 0, resource: ctx.visible_lights.buffer.buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: self.shade.batch_uniform().as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&atlas.view) },
                ],
            ));
            self.shade_key = Some(key);
        }
        if !self.visible.contains(&(self.params.inspect as usize)) {
            self.inspected = None;
        }
        let batches = self.visible.len().div_ceil(self.batch_size);
        self.counts.batches = batches;
        self.counts.shadow_maps = self.visible.len();
        map_figures(&mut self.counts, &self.params, &self.settings, self.maps.pool_points(), self.visible.len());
        Ok(batches)
    }

    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        let first = step * self.batch_size;
        let last = (first + self.batch_size).min(self.visible.len());
        let (n, pool) = (self.settings.points_per_map, self.maps.pool_points());
        // Steps 2-3: the batch's dual paraboloids.
        let views: Vec<GpuIsmView> = (first..last)
            .map(|i| {
                let l = &ctx.visible_lights.gpu[i];
                let offset = subset_offset(self.visible[i], n as usize, pool);
                let tile = 2 * (i - first) as u32;
                GpuIsmView::new(Vec3::from(l.position), Vec3::Y, l.shadow_near, l.range, offset, n, tile, true)
            })
            .collect();
        self.maps.render(ctx.gpu, Some(ctx.timer), encoder, &views, self.settings);
        let res = self.settings.resolution as u64;
        self.counts.work.shadow_texels_written += 2 * views.len() as u64 * res * res;
        // Step 4: shading with the batch's lights.
        let atlas = self.maps.atlas().expect("prepare made the batch");
        let uniform = ShadeUniform {
            first_light: first as u32,
            light_count: (last - first) as u32,
            resolution: atlas.resolution,
            tiles_per_row: atlas.tiles_per_row,
            bias: self.params.bias,
            normal_offset: self.params.normal_offset,
            _pad: [0.0; 2],
        };
        self.shade.write_batch(ctx.gpu, &uniform);
        let group = self.shade_group.as_ref().expect("prepare made the shading group");
        self.shade.encode(ctx, encoder, "ism shading", group, None);
        let inspect = self.params.inspect as usize;
        if let Some(k) = (first..last).find(|&i| self.visible[i] == inspect) {
            let tiles = [2 * (k - first), 2 * (k - first) + 1];
            self.inspected = Some(Inspected { atlas: copy_tiles(ctx.gpu, encoder, atlas, &tiles) });
        }
        Ok(())
    }

    fn step_label(&self) -> &'static str {
        "ism maps + shading"
    }

    fn counts(&self) -> TechniqueCounts {
        self.counts.clone()
    }

    fn cpu_times(&self) -> Vec<PassTime> {
        self.sampling_ms.map(|ms| PassTime { name: "ism point sampling".into(), ms, count: 1 }).into_iter().collect()
    }

    fn uses_light_tiles(&self) -> bool {
        true
    }

    fn overlays(&self, lights: &[PointLight]) -> Vec<OverlayLayer> {
        let mut layers = super::light_overlays(lights);
        let pool = self.pool();
        let (inspect, n) = (self.params.inspect as usize, self.settings.points_per_map as usize);
        let start = (inspect < lights.len()).then(|| subset_offset(inspect, n, pool.len()) as usize);
        layers.extend(overlays::point_layers(&pool, start, n));
        layers
    }

    fn overlay_legend(&self, layer: &OverlayLayer) -> Vec<super::LegendEntry> {
        overlays::legend(layer)
    }

    fn explain(&self) -> Vec<super::ExplainStep> {
        overlays::explain_steps(false)
    }

    fn light_details(&self, index: usize) -> Option<super::LightDetails> {
        let (n, pool) = (self.settings.points_per_map as usize, self.maps.pool_points());
        let offset = subset_offset(index, n, pool);
        let visible = self.visible.contains(&index);
        let lines = vec![
            format!("ISM: pool points {offset}.. ({n} of {pool}, wrapping)"),
            if visible {
                format!("dual paraboloid, 2 x {}², {} pull-push levels", self.settings.resolution, self.settings.levels)
            } else {
                "no map: outside the view".to_string()
            },
        ];
        Some(super::LightDetails { lines, group: vec![index] })
    }

    fn shadow_atlas(&self) -> Option<(&CubeAtlas, &'static str)> {
        self.maps.atlas().map(|a| (a, "imperfect shadow maps of the last batch: two paraboloids per light (+y, -y)"))
    }

    fn depth_images(&self) -> Vec<(&CubeAtlas, &'static str)> {
        self.inspected
            .iter()
            .map(|i| (&i.atlas, "the inspected light's imperfect shadow map (`inspect`): upper (+y) and lower (-y)"))
            .collect()
    }
}

/// `vpl-ism`: one hemispherical imperfect shadow map per VPL, gathered by the shared VPL gather.
pub struct VplIsm {
    pub params: IsmParams,
    maps: IsmMaps,
    pass: VplGatherPass,
    blur: InterleaveBlur,
    visibility_layout: wgpu::BindGroupLayout,
    visibility_group: Option<wgpu::BindGroup>,
    atlas_generation: u64,
    settings: MapSettings,
    vpls: Arc<VplSet>,
    batch_size: usize,
    batches: usize,
    scene_size: f32,
    inspected: Option<Inspected>,
    counts: TechniqueCounts,
    sampling_ms: Option<f64>,
}

impl VplIsm {
    pub fn new(gpu: &GpuContext, layouts: &SharedLayouts) -> VplIsm {
        let visibility_layout = gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("vpl-ism atlas"),
            entries: &[depth_texture_entry(0)],
        });
        let pass = VplGatherPass::new(gpu, layouts, VPL_GATHER.name, VPL_GATHER.source, &visibility_layout);
        let params = IsmParams::default();
        VplIsm {
            settings: settings_of(&params),
            params,
            maps: IsmMaps::new(gpu),
            pass,
            blur: InterleaveBlur::new(gpu, layouts),
            visibility_layout,
            visibility_group: None,
            atlas_generation: 0,
            vpls: Arc::default(),
            batch_size: 1,
            batches: 0,
            scene_size: 1.0,
            inspected: None,
            counts: TechniqueCounts::default(),
            sampling_ms: None,
        }
    }

    /// Where a VPL's map is centred (off its surface along the normal), and its depth range: those of
    /// `vpl-shadowmaps`'s paraboloid maps (0.2 % of the scene's diagonal off, the diagonal as far plane).
    fn depth_range(&self) -> (f32, f32, f32) {
        (self.scene_size * 2e-3, self.scene_size * 1e-5, self.scene_size * 1.01)
    }
}

impl Technique for VplIsm {
    fn key(&self) -> &'static str {
        "vpl-ism"
    }

    fn label(&self) -> &'static str {
        "VPLs, an imperfect shadow map each"
    }

    fn params(&self) -> Vec<Param> {
        self.params.list(true)
    }

    fn set_param(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        self.params.set("vpl-ism", true, key, value)
    }

    fn uses_vpls(&self) -> bool {
        true
    }

    fn prepare(&mut self, ctx: &FrameContext) -> Result<usize, GpuError> {
        self.sampling_ms = self.maps.ensure_pool(ctx.gpu, ctx.scene, self.params.points_per_map, self.params.seed);
        self.vpls = ctx.vpls.set.clone();
        self.scene_size = ctx.scene.bounds.size().length().max(1e-6);
        self.settings = settings_of(&self.params);
        let n = self.vpls.vpls.len();
        self.counts = TechniqueCounts { lights_visible: ctx.lights.len(), ..Default::default() };
        if n == 0 {
            self.batches = 0;
            self.inspected = None;
            return Ok(0);
        }
        let budget = self.params.atlas_mib as u64 * (1 << 20);
        let tiles = IsmMaps::tiles_per_batch(ctx.gpu, self.settings.resolution, self.settings.levels, budget, 1)?;
        self.batch_size = (self.params.vpls_per_step as usize).min(ctx.max_lights_per_step).min(tiles).max(1);
        self.maps.ensure_batch(ctx.gpu, self.settings.resolution, self.batch_size.min(n), self.settings.levels);
        if self.visibility_group.is_none() || self.atlas_generation != self.maps.atlas_generation() {
            let atlas = self.maps.atlas().expect("ensure_batch made it");
            self.visibility_group = Some(ctx.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("vpl-ism atlas"),
                layout: &self.visibility_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&atlas.view),
                }],
            }));
            self.atlas_generation = self.maps.atlas_generation();
        }
        if self.params.inspect as usize >= n {
            self.inspected = None;
        }
        self.batches = n.div_ceil(self.batch_size);
        self.counts.batches = self.batches;
        self.counts.shadow_maps = n;
        self.counts.figures.insert("vpls".into(), n as f64);
        map_figures(&mut self.counts, &self.params, &self.settings, self.maps.pool_points(), n);
        Ok(if self.params.interleave.on { self.batches + 1 } else { self.batches })
    }

    fn encode_step(
        &mut self,
        ctx: &FrameContext,
        step: usize,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        if step >= self.batches {
            self.blur.encode(ctx, encoder, &self.params.interleave, true, &self.pass);
            return Ok(());
        }
        let first = step * self.batch_size;
        let last = (first + self.batch_size).min(self.vpls.vpls.len());
        let (n, pool) = (self.settings.points_per_map, self.maps.pool_points());
        let (origin_offset, near, far) = self.depth_range();
        // Steps 2-3: the batch's hemispheres.
        let views: Vec<GpuIsmView> = self.vpls.vpls[first..last]
            .iter()
            .enumerate()
            .map(|(k, v)| {
                let offset = subset_offset(first + k, n as usize, pool);
                GpuIsmView::new(v.position + v.normal * origin_offset, v.normal, near, far, offset, n, k as u32, false)
            })
            .collect();
        self.maps.render(ctx.gpu, Some(ctx.timer), encoder, &views, self.settings);
        let res = self.settings.resolution as u64;
        self.counts.work.shadow_texels_written += views.len() as u64 * res * res;
        // Step 4: the shared gather with the ISM lookup.
        let atlas = self.maps.atlas().expect("prepare made the batch");
        let mut batch = GatherBatchUniform {
            first_vpl: first as u32,
            vpl_count: (last - first) as u32,
            first_tile: 0,
            tiles_per_row: atlas.tiles_per_row,
            resolution: atlas.resolution,
            bias: self.params.bias,
            normal_offset: self.params.normal_offset,
            depth_near: near,
            depth_far: far,
            origin_offset,
            ..Default::default()
        };
        self.params.interleave.apply(&mut batch, true);
        let group = self.visibility_group.as_ref().expect("prepare made the visibility group");
        self.pass.encode(ctx, encoder, "vpl-ism gather", group, batch);
        let inspect = self.params.inspect as usize;
        if (first..last).contains(&inspect) {
            self.inspected = Some(Inspected { atlas: copy_tiles(ctx.gpu, encoder, atlas, &[inspect - first]) });
        }
        Ok(())
    }

    fn step_label(&self) -> &'static str {
        "vpl ism maps + gather"
    }

    fn counts(&self) -> TechniqueCounts {
        self.counts.clone()
    }

    fn cpu_times(&self) -> Vec<PassTime> {
        self.sampling_ms.map(|ms| PassTime { name: "ism point sampling".into(), ms, count: 1 }).into_iter().collect()
    }

    fn overlays(&self, _lights: &[PointLight]) -> Vec<OverlayLayer> {
        let mut layers = crate::services::vpl_gather::vpl_overlays(&self.vpls, self.scene_size, 0);
        let pool = self.maps.pool().map(|p| p.points.clone()).unwrap_or_default();
        let n = self.settings.points_per_map as usize;
        let start = ((self.params.inspect as usize) < self.vpls.vpls.len())
            .then(|| subset_offset(self.params.inspect as usize, n, pool.len()) as usize);
        layers.extend(overlays::point_layers(&pool, start, n));
        layers
    }

    fn overlay_legend(&self, layer: &OverlayLayer) -> Vec<super::LegendEntry> {
        match crate::services::vpl_gather::vpl_layer_legend(layer) {
            Some(mut legend) => {
                legend.extend(layer.summary());
                legend
            }
            None => overlays::legend(layer),
        }
    }

    fn hover_points(&self) -> Vec<super::HoverPoint> {
        crate::services::vpl_gather::vpl_hover_points(&self.vpls)
    }

    fn hover_details(&self, _layer: &str, index: usize) -> Vec<String> {
        crate::services::vpl_gather::vpl_details(&self.vpls, index)
    }

    fn explain(&self) -> Vec<super::ExplainStep> {
        overlays::explain_steps(true)
    }

    fn shadow_atlas(&self) -> Option<(&CubeAtlas, &'static str)> {
        self.maps.atlas().map(|a| (a, "imperfect shadow maps of the last batch, one hemisphere per VPL"))
    }

    fn depth_images(&self) -> Vec<(&CubeAtlas, &'static str)> {
        self.inspected.iter().map(|i| (&i.atlas, "the inspected VPL's imperfect shadow map (`inspect`)")).collect()
    }
}
