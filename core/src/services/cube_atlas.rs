//! What a cube shadow map atlas holds, for the passes that read it and for the inspector: the atlas of the
//! current batch, how each tile maps world points to stored depth and back, and what a render call drew.
//! Written by [`super::cube_shadows::CubeShadowRenderer`].

use glam::Vec3;

/// How `tiles` square tiles of `resolution` texels are laid out in an atlas on `device`: as many columns as a
/// square needs, at most what the device's largest texture allows, and the rows that takes.
pub fn atlas_grid(device: &wgpu::Device, resolution: u32, tiles: usize) -> (u32, u32) {
    let max_per_row = (device.limits().max_texture_dimension_2d / resolution.max(1)).max(1);
    let tiles = tiles.max(1) as u32;
    let tiles_per_row = ((tiles as f32).sqrt().ceil() as u32).clamp(1, max_per_row);
    (tiles_per_row, tiles.div_ceil(tiles_per_row))
}

/// The atlas of the current batch, as the shading passes see it.
pub struct CubeAtlas {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    pub resolution: u32,
    pub tiles_per_row: u32,
    /// Cube maps it holds.
    pub capacity: usize,
    /// Square tiles it holds (6 per cube map).
    pub tiles: usize,
    /// How each tile was last rendered (None: not rendered since the atlas was cleared), so that its stored
    /// depths can be read back as world distances (the app's shadow-map inspector).
    pub projections: Vec<Option<TileProjection>>,
}

impl CubeAtlas {
    /// Forget every tile's projection when a pass clears the atlas; then record `projections` from `first_tile`.
    pub(super) fn record_projections(
        &mut self,
        clear: bool,
        first_tile: usize,
        projections: impl Iterator<Item = TileProjection>,
    ) {
        if clear {
            self.projections.clear();
        }
        self.projections.resize(self.tiles, None);
        for (i, p) in projections.enumerate() {
            if let Some(slot) = self.projections.get_mut(first_tile + i) {
                *slot = Some(p);
            }
        }
    }
}

/// How a tile of an atlas maps world points to stored depth, and back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TileProjection {
    /// A perspective view, `clip_from_world` (a cube map's face: 90°, near..far; INSM's intermediate images):
    /// hardware depth (`cube_depth_to_distance` in cube_shadow.wgsl inverts it along a cube face's axis).
    Perspective { clip_from_world: glam::Mat4 },
    /// A paraboloid map (paraboloid_depth.wgsl): depth `(d - near) / (far - near)` of the distance d from `centre`.
    Paraboloid { centre: Vec3, near: f32, far: f32 },
}

impl TileProjection {
    /// The point the map looks from (a cube map's light, a view's camera, a paraboloid's centre).
    pub fn eye(&self) -> Vec3 {
        match *self {
            // The eye is where clip x, y and w vanish: world_from_clip · (0, 0, 1, 0), dehomogenised.
            TileProjection::Perspective { clip_from_world } => {
                let e = clip_from_world.as_dmat4().inverse() * glam::DVec4::Z;
                (e.truncate() / e.w).as_vec3()
            }
            TileProjection::Paraboloid { centre, .. } => centre,
        }
    }

    /// The world distance from [`Self::eye`] to what texel (u, v) of a `resolution`-texel square tile saw,
    /// given the depth stored there; None for an empty texel (depth 1: nothing within the far plane).
    pub fn distance(&self, u: u32, v: u32, resolution: u32, depth: f32) -> Option<f32> {
        self.reader(resolution).distance(u, v, depth)
    }

    /// [`Self::distance`] for many texels of one tile (the inverse matrix computed once).
    pub fn reader(&self, resolution: u32) -> DistanceReader {
        let world_from_clip = match *self {
            TileProjection::Perspective { clip_from_world } => Some(clip_from_world.as_dmat4().inverse()),
            TileProjection::Paraboloid { .. } => None,
        };
        let eye = world_from_clip.map(|m| {
            let e = m * glam::DVec4::Z;
            e.truncate() / e.w
        });
        DistanceReader { projection: *self, world_from_clip, eye, resolution: resolution.max(1) as f64 }
    }
}

/// Reads one tile's depths as distances ([`TileProjection::reader`]).
pub struct DistanceReader {
    projection: TileProjection,
    world_from_clip: Option<glam::DMat4>,
    eye: Option<glam::DVec3>,
    resolution: f64,
}

impl DistanceReader {
    pub fn distance(&self, u: u32, v: u32, depth: f32) -> Option<f32> {
        if !(0.0..1.0).contains(&depth) {
            return None;
        }
        match (self.projection, self.world_from_clip, self.eye) {
            (TileProjection::Paraboloid { near, far, .. }, _, _) => Some(near + depth * (far - near)),
            (TileProjection::Perspective { .. }, Some(world_from_clip), Some(eye)) => {
                let ndc_x = (u as f64 + 0.5) / self.resolution * 2.0 - 1.0;
                let ndc_y = 1.0 - (v as f64 + 0.5) / self.resolution * 2.0;
                let p = world_from_clip * glam::DVec4::new(ndc_x, ndc_y, depth as f64, 1.0);
                Some((p.truncate() / p.w).distance(eye) as f32)
            }
            _ => None,
        }
    }
}

/// Triangles drawn and culled by one `render` call.
#[derive(Clone, Copy, Debug, Default)]
pub struct CubeStats {
    pub cubes: usize,
    /// Depth texels the maps cover (6 faces of resolution² per cube map, resolution² per paraboloid map).
    pub texels_written: u64,
    pub triangles_submitted: u64,
    pub triangles_culled: u64,
}
