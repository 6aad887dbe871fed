//! The shadow-map inspector: the depth atlas the current technique (or the indirect technique) rendered in its
//! last step ([`Technique::shadow_atlas`]), read back once per completed frame while the panel is on screen, as
//! grey (near white, far dark, empty black); the whole atlas, or one cube map unfolded as a cross (faces
//! +x −x +y −y +z −z as the atlas stores them, each as rendered). Scroll to zoom, drag to pan; under the pointer
//! the tile, its cube and face, and the stored depth.
//!
//! Not yet: world distances in the readout (the atlas does not say which light a tile belongs to, nor its near
//! and far planes), linearised grey, INSM's intermediate maps, and selecting a light's map from the view.
//!
//! [`Technique::shadow_atlas`]: shadowlab_core::technique::Technique::shadow_atlas

use eframe::egui;
use shadowlab_core::renderer::cube_shadows::CubeAtlas;
use shadowlab_core::GpuContext;

/// Which technique's maps are shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapSource {
    Direct,
    Indirect,
}

/// A read-back depth atlas.
pub struct AtlasDepths {
    pub depths: Vec<f32>,
    pub width: u32,
    pub height: u32,
    pub resolution: u32,
    pub tiles_per_row: u32,
    pub tiles: usize,
    pub what: &'static str,
}

impl AtlasDepths {
    pub fn read(gpu: &GpuContext, atlas: &CubeAtlas, what: &'static str) -> anyhow::Result<AtlasDepths> {
        let size = atlas.texture.size();
        let bytes = shadowlab_core::renderer::readback::read_texture(gpu, &atlas.texture, size.width, size.height, 4)?;
        let depths = bytes.chunks_exact(4).map(|d| f32::from_le_bytes([d[0], d[1], d[2], d[3]])).collect();
        Ok(AtlasDepths {
            depths,
            width: size.width,
            height: size.height,
            resolution: atlas.resolution.max(1),
            tiles_per_row: atlas.tiles_per_row.max(1),
            tiles: atlas.tiles,
            what,
        })
    }

    /// The depth at atlas texel (x, y).
    pub fn depth(&self, x: u32, y: u32) -> Option<f32> {
        (x < self.width && y < self.height).then(|| self.depths[(y * self.width + x) as usize])
    }

    /// The atlas texel of texel (u, v) of tile `tile`.
    fn tile_texel(&self, tile: usize, u: u32, v: u32) -> (u32, u32) {
        let t = tile as u32;
        ((t % self.tiles_per_row) * self.resolution + u, (t / self.tiles_per_row) * self.resolution + v)
    }

    /// Cube maps in the atlas; 0 for paraboloid atlases (VPLs, VALs), whose tiles are single maps. The trait
    /// describes an atlas only in words, so this goes by its description.
    pub fn cubes(&self) -> usize {
        if self.what.contains("cube") {
            self.tiles / 6
        } else {
            0
        }
    }
}

/// Where each face of a cube goes in the cross, in tiles: +y on top, −x +z +x −z across, −y below.
const CROSS: [(u32, u32); 6] = [(2, 1), (0, 1), (1, 0), (1, 2), (1, 1), (3, 1)];
const FACES: [&str; 6] = ["+x", "-x", "+y", "-y", "+z", "-z"];

/// What the inspector shows: an image of depths (NaN where nothing is, outside the cross) and, per pixel, the
/// tile it came from.
pub struct Shown {
    pub width: u32,
    pub height: u32,
    pub depths: Vec<f32>,
    pub tiles: Vec<u32>,
}

impl Shown {
    /// The whole atlas, or cube `cube` unfolded as a cross (4 x 3 tiles).
    pub fn new(atlas: &AtlasDepths, cube: Option<usize>) -> Shown {
        match cube.filter(|&c| c < atlas.cubes()) {
            None => {
                let tiles = (0..atlas.height)
                    .flat_map(|y| {
                        (0..atlas.width)
                            .map(move |x| (y / atlas.resolution) * atlas.tiles_per_row + x / atlas.resolution)
                    })
                    .collect();
                Shown { width: atlas.width, height: atlas.height, depths: atlas.depths.clone(), tiles }
            }
            Some(c) => {
                let r = atlas.resolution;
                let (w, h) = (4 * r, 3 * r);
                let mut depths = vec![f32::NAN; (w * h) as usize];
                let mut tiles = vec![u32::MAX; (w * h) as usize];
                for (face, &(cx, cy)) in CROSS.iter().enumerate() {
                    let tile = c * 6 + face;
                    for v in 0..r {
                        for u in 0..r {
                            let (ax, ay) = atlas.tile_texel(tile, u, v);
                            let at = ((cy * r + v) * w + cx * r + u) as usize;
                            depths[at] = atlas.depth(ax, ay).unwrap_or(f32::NAN);
                            tiles[at] = tile as u32;
                        }
                    }
                }
                Shown { width: w, height: h, depths, tiles }
            }
        }
    }

    /// Grey: the drawn depths stretched from white (nearest) to dark grey (farthest); empty texels (depth 1)
    /// black, outside the cross a dark blue.
    pub fn image(&self) -> egui::ColorImage {
        let drawn = self.depths.iter().copied().filter(|d| *d < 1.0);
        let (lo, hi) = drawn.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), d| (lo.min(d), hi.max(d)));
        let span = (hi - lo).max(1e-6);
        let pixels = self
            .depths
            .iter()
            .map(|&d| {
                if d.is_nan() {
                    egui::Color32::from_rgb(20, 24, 40)
                } else if d >= 1.0 {
                    egui::Color32::BLACK
                } else {
                    egui::Color32::from_gray((255.0 * (1.0 - 0.85 * (d - lo) / span)) as u8)
                }
            })
            .collect();
        egui::ColorImage::new([self.width as usize, self.height as usize], pixels)
    }

    /// The readout of texel (x, y): tile, cube, face, stored depth.
    pub fn readout(&self, x: u32, y: u32) -> Option<String> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = (y * self.width + x) as usize;
        let (tile, d) = (self.tiles[i], self.depths[i]);
        if tile == u32::MAX {
            return None;
        }
        let depth = if d >= 1.0 { "empty (1.0)".to_string() } else { format!("{d:.5}") };
        Some(format!(
            "texel ({x}, {y}) · tile {tile} · cube {} face {} · depth {depth}",
            tile / 6,
            FACES[(tile % 6) as usize]
        ))
    }
}

/// The panel's state.
pub struct Inspector {
    pub source: MapSource,
    /// None: the whole atlas; Some(c): cube c unfolded.
    pub cube: Option<usize>,
    pub atlas: Option<AtlasDepths>,
    pub shown: Option<Shown>,
    texture: Option<egui::TextureHandle>,
    /// The frame (view frame key, source) the atlas was read from.
    pub read_from: Option<(u64, MapSource)>,
    /// Texel of the shown image per point of the panel, and the image's offset (zoom and pan).
    zoom: f32,
    offset: egui::Vec2,
    pub error: Option<String>,
    /// The readout of the texel under the pointer in the last frame.
    pub readout: Option<String>,
}

impl Default for Inspector {
    fn default() -> Self {
        Inspector {
            source: MapSource::Direct,
            cube: Some(0),
            atlas: None,
            shown: None,
            texture: None,
            read_from: None,
            zoom: 1.0,
            offset: egui::Vec2::ZERO,
            error: None,
            readout: None,
        }
    }
}

impl Inspector {
    /// Take a new atlas (or none, with why).
    pub fn set_atlas(&mut self, atlas: Result<Option<AtlasDepths>, String>, from: (u64, MapSource)) {
        self.read_from = Some(from);
        self.texture = None;
        self.shown = None;
        match atlas {
            Ok(a) => {
                self.error = None;
                self.atlas = a;
            }
            Err(e) => {
                self.error = Some(e);
                self.atlas = None;
            }
        }
    }

    fn refresh(&mut self, ctx: &egui::Context) {
        if self.shown.is_none() {
            if let Some(a) = &self.atlas {
                let shown = Shown::new(a, self.cube);
                self.texture = Some(ctx.load_texture("shadow map", shown.image(), egui::TextureOptions::NEAREST));
                self.shown = Some(shown);
            }
        }
    }

    /// The panel's controls and image.
    pub fn ui(&mut self, ui: &mut egui::Ui, has_indirect: bool) {
        ui.horizontal(|ui| {
            ui.selectable_value(&mut self.source, MapSource::Direct, "direct technique");
            ui.add_enabled_ui(has_indirect, |ui| {
                ui.selectable_value(&mut self.source, MapSource::Indirect, "indirect")
            });
        });
        if let Some(e) = &self.error {
            ui.colored_label(egui::Color32::LIGHT_RED, e);
        }
        let Some(atlas) = &self.atlas else {
            ui.label("No shadow maps: the technique renders none, or its frame is not complete yet.");
            return;
        };
        ui.label(format!("{}: {} tiles of {}² texels", atlas.what, atlas.tiles, atlas.resolution));
        let cubes = atlas.cubes();
        let mut cube = self.cube;
        ui.horizontal(|ui| {
            ui.radio_value(&mut cube, None, "whole atlas");
            let mut c = cube.unwrap_or(0);
            let unfolded = ui.radio(cube.is_some(), "cube map as a cross").clicked();
            let label = ui.label("number");
            let changed = ui
                .add_enabled(cubes > 0, egui::DragValue::new(&mut c).range(0..=cubes.saturating_sub(1)))
                .labelled_by(label.id);
            if unfolded || (changed.changed() && cube.is_some()) {
                cube = Some(c.min(cubes.saturating_sub(1)));
            }
        });
        if cubes == 0 && cube.is_some() {
            cube = None;
        }
        if cube != self.cube {
            self.cube = cube;
            self.shown = None;
            self.zoom = 1.0;
            self.offset = egui::Vec2::ZERO;
        }
        self.refresh(ui.ctx());
        let (Some(shown), Some(texture)) = (&self.shown, &self.texture) else { return };
        let size = egui::vec2(ui.available_width(), (ui.available_height() - 24.0).max(120.0));
        let (rect, response) = ui.allocate_exact_size(size, egui::Sense::click_and_drag());
        // Fit the image into the rect at zoom 1, then zoom around the pointer and pan by dragging.
        let image_size = egui::vec2(shown.width as f32, shown.height as f32);
        let fit = (rect.width() / image_size.x).min(rect.height() / image_size.y);
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                let before = self.zoom;
                self.zoom = (self.zoom * (scroll * 0.005).exp()).clamp(1.0, 64.0);
                if let Some(p) = response.hover_pos() {
                    // Keep the texel under the pointer where it is.
                    let from_center = p - rect.center() - self.offset;
                    self.offset -= from_center * (self.zoom / before - 1.0);
                }
            }
        }
        if response.dragged() {
            self.offset += response.drag_delta();
        }
        let scale = fit * self.zoom;
        let shown_rect = egui::Rect::from_center_size(rect.center() + self.offset, image_size * scale);
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, egui::Color32::from_gray(30));
        painter.image(
            texture.id(),
            shown_rect,
            egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
            egui::Color32::WHITE,
        );
        self.readout = response.hover_pos().and_then(|p| {
            let t = (p - shown_rect.min) / scale;
            (t.x >= 0.0 && t.y >= 0.0).then(|| shown.readout(t.x as u32, t.y as u32)).flatten()
        });
        ui.label(self.readout.clone().unwrap_or_else(|| "scroll to zoom, drag to pan".into()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cube_unfolds_into_a_cross_of_its_six_tiles() {
        // Two cubes of 2x2 tiles, 4 tiles per row: each texel's depth encodes its tile.
        let (r, per_row, tiles) = (2u32, 4u32, 12usize);
        let (w, h) = (r * per_row, r * 3);
        let depths = (0..h).flat_map(|y| (0..w).map(move |x| ((y / r) * per_row + x / r) as f32 / 100.0)).collect();
        let atlas = AtlasDepths {
            depths,
            width: w,
            height: h,
            resolution: r,
            tiles_per_row: per_row,
            tiles,
            what: "cube maps",
        };
        assert_eq!(atlas.cubes(), 2);
        let cross = Shown::new(&atlas, Some(1));
        assert_eq!((cross.width, cross.height), (4 * r, 3 * r));
        // +y (tile 8) on top in the second column, -z (tile 11) at the right end of the middle row.
        assert_eq!(cross.depths[(r + 1) as usize], 8.0 / 100.0);
        assert_eq!(cross.tiles[((r + 1) * cross.width + 3 * r) as usize], 11);
        assert!(cross.depths[0].is_nan(), "outside the cross");
        assert!(cross.readout(0, 0).is_none());
        assert!(cross.readout(3 * r, r).unwrap().contains("cube 1 face -z"));
        let paraboloids = AtlasDepths { what: "paraboloid maps", depths: atlas.depths.clone(), ..atlas };
        assert_eq!(paraboloids.cubes(), 0);
        assert_eq!(Shown::new(&paraboloids, Some(1)).width, w, "no cross of paraboloid maps: the whole atlas");
        let atlas = paraboloids;
        let whole = Shown::new(&atlas, None);
        assert_eq!((whole.width, whole.height), (w, h));
        assert_eq!(whole.image().size, [w as usize, h as usize]);
    }
}
