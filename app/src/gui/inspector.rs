//! The shadow-map inspector: a depth atlas the current technique (or the indirect technique) rendered in its
//! last frame, read back once per completed frame while the panel is on screen: its shadow maps
//! ([`Technique::shadow_atlas`]: the last batch of cube maps, VAL or VPL paraboloid maps) or another set of
//! depth images it declares ([`Technique::depth_images`]: INSM's intermediate images). Shown as grey (near
//! white, far dark, empty black), by stored depth or linearised (by world distance); the whole atlas, or one
//! cube map unfolded as a cross (faces +x −x +y −y +z −z as the atlas stores them, each as rendered). Scroll to
//! zoom, drag to pan; under the pointer the tile, its cube and face, the stored depth and the world distance
//! from the map's light (or camera) to what the texel saw, from the tile's projection the atlas records
//! ([`TileProjection`]). Selecting a light in the view shows its cube map (or its cluster's).
//!
//! [`Technique::shadow_atlas`]: shadowlab_core::technique::Technique::shadow_atlas
//! [`Technique::depth_images`]: shadowlab_core::technique::Technique::depth_images

use eframe::egui;
use glam::Vec3;
use shadowlab_core::services::cube_shadows::{CubeAtlas, TileProjection};
use shadowlab_core::GpuContext;

use crate::gui::image_view::{fit_texture, ImageView};
use crate::gui::rsm_view::RsmView;
use crate::rsm_picture::{CROSS, FACES};

/// The maps list's entry for [`RsmView`].
pub const RSM_LABEL: &str = "a light's reflective shadow map (VPL source)";

/// Which maps are shown: the direct or the indirect technique's, its shadow maps (`set` 0) or its depth
/// image set `set - 1` ([`Technique::depth_images`](shadowlab_core::technique::Technique::depth_images)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MapSource {
    pub indirect: bool,
    pub set: usize,
}

impl MapSource {
    pub const DIRECT: MapSource = MapSource { indirect: false, set: 0 };
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
    /// Per tile, how it was rendered (None: not this frame).
    pub projections: Vec<Option<TileProjection>>,
    /// Cube maps at the start of the atlas: groups of six perspective tiles seen from one point.
    cube_count: usize,
}

impl AtlasDepths {
    pub fn read(gpu: &GpuContext, atlas: &CubeAtlas, what: &'static str) -> anyhow::Result<AtlasDepths> {
        let size = atlas.texture.size();
        let depths = shadowlab_core::gpu::readback::read_depths(gpu, &atlas.texture)?;
        Ok(AtlasDepths::new(
            depths,
            (size.width, size.height),
            atlas.resolution,
            atlas.tiles_per_row,
            atlas.projections.clone(),
            what,
        ))
    }

    pub fn new(
        depths: Vec<f32>,
        (width, height): (u32, u32),
        resolution: u32,
        tiles_per_row: u32,
        mut projections: Vec<Option<TileProjection>>,
        what: &'static str,
    ) -> AtlasDepths {
        let (resolution, tiles_per_row) = (resolution.max(1), tiles_per_row.max(1));
        let tiles = ((width / resolution) * (height / resolution)) as usize;
        projections.resize(tiles, None);
        let eyes: Vec<Option<Vec3>> = projections
            .iter()
            .map(|p| p.filter(|p| matches!(p, TileProjection::Perspective { .. })).map(|p| p.eye()))
            .collect();
        let cube_count = eyes
            .chunks_exact(6)
            .take_while(|faces| {
                let first = faces[0];
                first.is_some_and(|e| {
                    faces.iter().all(|f| f.is_some_and(|f| f.distance(e) <= 1e-3 * (1.0 + e.length())))
                })
            })
            .count();
        AtlasDepths { depths, width, height, resolution, tiles_per_row, tiles, what, projections, cube_count }
    }

    /// The cube map whose centre is within `tolerance_world` of `position` (a light's), if the atlas has one.
    pub fn cube_at(&self, position: Vec3, tolerance_world: f32) -> Option<usize> {
        (0..self.cube_count)
            .find(|&c| self.projections[c * 6].is_some_and(|p| p.eye().distance(position) <= tolerance_world))
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

    /// Cube maps in the atlas (groups of six perspective tiles seen from one point: not paraboloid maps, nor
    /// INSM's views).
    pub fn cubes(&self) -> usize {
        self.cube_count
    }
}

/// What the inspector shows: an image of depths (NaN where nothing is, outside the cross) and, per pixel, the
/// tile it came from (tiles are `resolution`-aligned in both layouts, so a pixel's texel in its tile is its
/// position modulo `resolution`).
pub struct Shown {
    pub width: u32,
    pub height: u32,
    pub depths: Vec<f32>,
    pub tiles: Vec<u32>,
    resolution: u32,
    cubes: usize,
    projections: Vec<Option<TileProjection>>,
}

impl Shown {
    /// The whole atlas, or cube `cube` unfolded as a cross (4 x 3 tiles).
    pub fn new(atlas: &AtlasDepths, cube: Option<usize>) -> Shown {
        let (resolution, cubes, projections) = (atlas.resolution, atlas.cubes(), atlas.projections.clone());
        match cube.filter(|&c| c < atlas.cubes()) {
            None => {
                let tiles = (0..atlas.height)
                    .flat_map(|y| {
                        (0..atlas.width)
                            .map(move |x| (y / atlas.resolution) * atlas.tiles_per_row + x / atlas.resolution)
                    })
                    .collect();
                let (width, height, depths) = (atlas.width, atlas.height, atlas.depths.clone());
                Shown { width, height, depths, tiles, resolution, cubes, projections }
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
                Shown { width: w, height: h, depths, tiles, resolution, cubes, projections }
            }
        }
    }

    /// The world distance from the map's eye (light, camera) to what pixel `i` shows; None where the tile's
    /// projection is not known or the texel is empty.
    fn distance_at(
        &self,
        i: usize,
        reader: Option<&shadowlab_core::services::cube_shadows::DistanceReader>,
    ) -> Option<f32> {
        let (x, y) = (i as u32 % self.width, i as u32 / self.width);
        reader?.distance(x % self.resolution, y % self.resolution, self.depths[i])
    }

    /// The world distance at pixel (x, y) (see [`Self::distance_at`]).
    pub fn distance(&self, x: u32, y: u32) -> Option<f32> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = (y * self.width + x) as usize;
        let projection = self.projections.get(self.tiles[i] as usize).copied().flatten()?;
        self.distance_at(i, Some(&projection.reader(self.resolution)))
    }

    /// Per pixel, the world distance (NaN where there is none).
    fn distances(&self) -> Vec<f32> {
        let readers: Vec<_> = self.projections.iter().map(|p| p.map(|p| p.reader(self.resolution))).collect();
        (0..self.depths.len())
            .map(|i| {
                let reader = readers.get(self.tiles[i] as usize).and_then(|r| r.as_ref());
                self.distance_at(i, reader).unwrap_or(f32::NAN)
            })
            .collect()
    }

    /// Grey: the drawn texels stretched from white (nearest) to dark grey (farthest), by stored depth or, with
    /// `linear`, by world distance (hardware depth crowds everything but the nearest texels near 1: linearised,
    /// equal steps of grey are equal steps of distance); empty texels (depth 1) black, outside the cross a dark
    /// blue. Texels whose distance is unknown (a tile not rendered this frame) are drawn by depth.
    pub fn image(&self, linear: bool) -> egui::ColorImage {
        let values = if linear {
            self.distances()
        } else {
            self.depths.iter().map(|&d| if d < 1.0 { d } else { f32::NAN }).collect()
        };
        let drawn = values.iter().copied().filter(|v| v.is_finite());
        let (lo, hi) = drawn.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), d| (lo.min(d), hi.max(d)));
        let span = (hi - lo).max(1e-6);
        let pixels = self
            .depths
            .iter()
            .zip(&values)
            .map(|(&d, &v)| {
                if d.is_nan() {
                    egui::Color32::from_rgb(20, 24, 40)
                } else if d >= 1.0 {
                    egui::Color32::BLACK
                } else {
                    let t = if v.is_finite() { (v - lo) / span } else { d };
                    egui::Color32::from_gray((255.0 * (1.0 - 0.85 * t.clamp(0.0, 1.0))) as u8)
                }
            })
            .collect();
        egui::ColorImage::new([self.width as usize, self.height as usize], pixels)
    }

    /// The readout of texel (x, y): tile, cube and face (of a cube map), stored depth, world distance.
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
        let map = if (tile as usize) < self.cubes * 6 {
            format!("cube {} face {}", tile / 6, FACES[(tile % 6) as usize])
        } else {
            match self.projections.get(tile as usize).copied().flatten() {
                Some(TileProjection::Paraboloid { .. }) => "paraboloid map".to_string(),
                Some(TileProjection::Perspective { .. }) => "view".to_string(),
                None => "not rendered this frame".to_string(),
            }
        };
        let distance = match self.distance(x, y) {
            Some(dist) => format!(" · distance {dist:.3}"),
            None => String::new(),
        };
        Some(format!("texel ({x}, {y}) · tile {tile} · {map} · depth {depth}{distance}"))
    }
}

/// `text` as it fits in `width` points in the button font, cut with "…" where it does not.
fn fit_text(ui: &egui::Ui, text: &str, width: f32) -> String {
    let font = egui::TextStyle::Button.resolve(ui.style());
    let wide = |t: String| ui.ctx().fonts_mut(|f| f.layout_no_wrap(t, font.clone(), egui::Color32::WHITE).size().x);
    if wide(text.to_string()) <= width {
        return text.to_string();
    }
    let chars: Vec<char> = text.chars().collect();
    let fits = |n: usize| wide(chars[..n].iter().collect::<String>() + "…") <= width;
    // The longest prefix that fits (the width grows with the prefix).
    let (mut lo, mut hi) = (0, chars.len());
    while lo < hi {
        let mid = (lo + hi).div_ceil(2);
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    chars[..lo].iter().collect::<String>() + "…"
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
    /// Zoom and pan.
    view: ImageView,
    pub error: Option<String>,
    /// The readout of the texel under the pointer in the last frame.
    pub readout: Option<String>,
    /// Grey by world distance instead of stored depth.
    pub linear: bool,
    /// The selected light and the read the cube was last chosen for, so a new selection (or a new frame's
    /// atlas) shows the selected light's cube once, and the user may choose another afterwards.
    pub followed: Option<(usize, (u64, MapSource))>,
    /// What following the selected light found (its cube, or why none).
    pub note: Option<String>,
    /// The map sets the techniques offered in the last UI frame, with their labels.
    pub sources: Vec<(MapSource, String)>,
    /// A set asked for (by an Explain step) that the technique offers only from its next frame, with the frame
    /// key it was asked in: shown once offered, forgotten once a later frame completed without it.
    pub requested: Option<(MapSource, u64)>,
    /// Show a light's reflective shadow map ([`RsmView`]) instead of a technique's maps.
    pub rsm_shown: bool,
    pub rsm: RsmView,
}

impl Default for Inspector {
    fn default() -> Self {
        Inspector {
            source: MapSource::DIRECT,
            cube: Some(0),
            atlas: None,
            shown: None,
            texture: None,
            read_from: None,
            view: ImageView::default(),
            error: None,
            readout: None,
            linear: false,
            followed: None,
            note: None,
            sources: Vec::new(),
            requested: None,
            rsm_shown: false,
            rsm: RsmView::default(),
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

    /// Show the cube map of light `light`, found among `positions` (the light's, then its group's: a cluster's
    /// cube map is rendered from one of its members), once per selection and read atlas.
    pub fn follow_light(&mut self, light: usize, positions: &[Vec3]) {
        let Some(read) = self.read_from else { return };
        if self.followed == Some((light, read)) {
            return;
        }
        let Some(atlas) = &self.atlas else { return };
        if atlas.cubes() == 0 {
            return;
        }
        self.followed = Some((light, read));
        match positions.iter().find_map(|p| atlas.cube_at(*p, 1e-4 * (1.0 + p.length()))) {
            Some(c) => {
                self.note = Some(format!("light {light}: cube {c}"));
                if self.cube != Some(c) {
                    self.cube = Some(c);
                    self.shown = None;
                    self.view.reset();
                }
            }
            None => self.note = Some(format!("light {light} has no cube map in the last batch")),
        }
    }

    fn refresh(&mut self, ctx: &egui::Context) {
        if self.shown.is_none() {
            if let Some(a) = &self.atlas {
                let shown = Shown::new(a, self.cube);
                let image = fit_texture(shown.image(self.linear), ctx.input(|i| i.max_texture_side));
                self.texture = Some(ctx.load_texture("shadow map", image, egui::TextureOptions::NEAREST));
                self.shown = Some(shown);
            }
        }
    }

    /// The image the panel shows (its texture, its size in texels) and what it is: the chosen maps (a cube map
    /// as a cross, or the whole atlas) or a light's RSM; None before one was read back.
    pub fn on_screen(&self, lights: usize) -> Option<(egui::TextureId, [u32; 2], String)> {
        if self.rsm_shown {
            return self.rsm.on_screen(lights);
        }
        let (shown, texture, atlas) = (self.shown.as_ref()?, self.texture.as_ref()?, self.atlas.as_ref()?);
        let what = match self.cube.filter(|&c| c < atlas.cubes()) {
            Some(c) => format!("{}: cube {c} as a cross", atlas.what),
            None => atlas.what.to_string(),
        };
        Some((texture.id(), [shown.width, shown.height], what))
    }

    /// The panel's controls and image; `sources` are the map sets the techniques offer this frame, `lights` the
    /// point lights (the RSM view numbers suns after them).
    pub fn ui(&mut self, ui: &mut egui::Ui, sources: Vec<(MapSource, String)>, lights: usize) {
        self.sources = sources;
        let sources = &self.sources;
        let current = match self.rsm_shown {
            true => RSM_LABEL,
            false => sources.iter().find(|(s, _)| *s == self.source).map(|(_, l)| l.as_str()).unwrap_or("none"),
        };
        // Labelled (the label also names it for accessibility), and narrow enough to leave the label room.
        // The chosen set's name cut to the room the label "maps" leaves (egui would wrap the label instead).
        let room = (ui.available_width() - 80.0).max(60.0);
        let current = fit_text(ui, current, room);
        let combo = egui::ComboBox::from_label("maps").width(room);
        let (mut source, mut rsm_shown) = (self.source, self.rsm_shown);
        combo.selected_text(current).show_ui(ui, |ui| {
            for (s, label) in sources {
                if ui.selectable_label(!rsm_shown && source == *s, label).clicked() {
                    (source, rsm_shown) = (*s, false);
                }
            }
            if ui.selectable_label(rsm_shown, RSM_LABEL).clicked() {
                rsm_shown = true;
            }
        });
        if (source, rsm_shown) != (self.source, self.rsm_shown) {
            self.requested = None;
        }
        (self.source, self.rsm_shown) = (source, rsm_shown);
        if self.rsm_shown {
            self.rsm.ui(ui, lights);
            return;
        }
        if let Some(e) = &self.error {
            ui.colored_label(egui::Color32::LIGHT_RED, e);
        }
        let Some(atlas) = &self.atlas else {
            ui.label("No shadow maps: the technique renders none, or its frame is not complete yet.");
            return;
        };
        let rendered = atlas.projections.iter().flatten().count();
        ui.label(format!(
            "{}: {} tiles of {}² texels, {rendered} rendered in the last pass",
            atlas.what, atlas.tiles, atlas.resolution
        ));
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
        ui.horizontal(|ui| {
            let linear = ui
                .checkbox(&mut self.linear, "linearised grey")
                .on_hover_text("Grey by world distance from the light (or camera), not by stored depth");
            if linear.changed() {
                self.shown = None;
            }
            if let Some(note) = &self.note {
                ui.label(note);
            }
        });
        if cube != self.cube {
            self.cube = cube;
            self.shown = None;
            self.view.reset();
        }
        self.refresh(ui.ctx());
        let (Some(shown), Some(texture)) = (&self.shown, &self.texture) else { return };
        let placed = self.view.show(ui, texture, [shown.width, shown.height], 24.0);
        self.readout = placed.hovered.and_then(|(x, y)| shown.readout(x, y));
        ui.label(self.readout.clone().unwrap_or_else(|| "scroll to zoom, drag to pan".into()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowlab_core::math::CUBE_FACES;

    #[test]
    fn a_cube_unfolds_into_a_cross_of_its_six_tiles() {
        // Two cubes of 2x2 tiles, 4 tiles per row: each texel's depth encodes its tile.
        let (r, per_row) = (2u32, 4u32);
        let (w, h) = (r * per_row, r * 3);
        let depths: Vec<f32> =
            (0..h).flat_map(|y| (0..w).map(move |x| ((y / r) * per_row + x / r) as f32 / 100.0)).collect();
        let cube_faces = |at: Vec3| {
            CUBE_FACES
                .iter()
                .map(move |f| Some(TileProjection::Perspective { clip_from_world: f.clip_from_world(at, 0.1, 5.0) }))
        };
        let (a, b) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(-1.0, 0.5, 0.0));
        let projections: Vec<_> = cube_faces(a).chain(cube_faces(b)).collect();
        let atlas = AtlasDepths::new(depths.clone(), (w, h), r, per_row, projections, "cube maps");
        assert_eq!(atlas.cubes(), 2);
        assert_eq!(
            (atlas.cube_at(b, 1e-4), atlas.cube_at(a, 1e-4), atlas.cube_at(Vec3::ZERO, 1e-4)),
            (Some(1), Some(0), None)
        );
        let cross = Shown::new(&atlas, Some(1));
        assert_eq!((cross.width, cross.height), (4 * r, 3 * r));
        // +y (tile 8) on top in the second column, -z (tile 11) at the right end of the middle row.
        assert_eq!(cross.depths[(r + 1) as usize], 8.0 / 100.0);
        assert_eq!(cross.tiles[((r + 1) * cross.width + 3 * r) as usize], 11);
        assert!(cross.depths[0].is_nan(), "outside the cross");
        assert!(cross.readout(0, 0).is_none());
        let readout = cross.readout(3 * r, r).unwrap();
        assert!(readout.contains("cube 1 face -z") && readout.contains("distance "), "{readout}");
        // Paraboloid maps are no cubes: no cross, the whole atlas; their distance is linear in depth.
        let paraboloids = vec![Some(TileProjection::Paraboloid { centre: a, near: 0.0, far: 10.0 }); 12];
        let atlas = AtlasDepths::new(depths.clone(), (w, h), r, per_row, paraboloids, "paraboloid maps");
        assert_eq!(atlas.cubes(), 0);
        let whole = Shown::new(&atlas, Some(1));
        assert_eq!((whole.width, whole.height), (w, h), "no cross of paraboloid maps: the whole atlas");
        assert_eq!(whole.image(false).size, [w as usize, h as usize]);
        let readout = whole.readout(3 * r, r).unwrap();
        // Tile 7 (second row, fourth column) stores depth 0.07: 0.7 of the 10 from its centre.
        assert!(readout.contains("tile 7 · paraboloid map") && readout.contains("distance 0.700"), "{readout}");
        // Tiles without a projection (not rendered this frame) have no distance.
        let unknown = AtlasDepths::new(depths, (w, h), r, per_row, Vec::new(), "images");
        assert!(!Shown::new(&unknown, None).readout(0, 0).unwrap().contains("distance"));
    }

    #[test]
    fn linearised_grey_steps_evenly_with_distance_and_depth_grey_does_not() {
        // One cube face; texels along its centre row at distances 1, 2, 3, 4 from the light.
        let r = 4u32;
        let face = CUBE_FACES[0];
        let clip_from_world = face.clip_from_world(Vec3::ZERO, 0.1, 10.0);
        // The depth the face stores at texel (u, 1) for a point at distance `d` along the texel's ray.
        let world_from_clip = clip_from_world.inverse();
        let depth_at = |u: u32, d: f32| {
            let ndc = glam::Vec2::new((u as f32 + 0.5) / r as f32 * 2.0 - 1.0, 1.0 - 1.5 / r as f32 * 2.0);
            let on_ray = world_from_clip.project_point3(ndc.extend(0.5));
            let c = clip_from_world * (on_ray.normalize() * d).extend(1.0);
            c.z / c.w
        };
        let mut depths = vec![1.0; (r * r * 6) as usize];
        for (u, d) in [1.0, 2.0, 3.0, 4.0].into_iter().enumerate() {
            depths[(r * 6) as usize + u] = depth_at(u as u32, d);
        }
        let projections = vec![Some(TileProjection::Perspective { clip_from_world }); 6];
        let atlas = AtlasDepths::new(depths, (r * 6, r), r, 6, projections, "cube maps");
        let whole = Shown::new(&atlas, None);
        let grey = |img: &egui::ColorImage, u: usize| img.pixels[r as usize * 6 + u].r() as i32;
        let (linear, by_depth) = (whole.image(true), whole.image(false));
        let steps = |img: &egui::ColorImage| {
            [grey(img, 0) - grey(img, 1), grey(img, 1) - grey(img, 2), grey(img, 2) - grey(img, 3)]
        };
        let l = steps(&linear);
        assert!(l.iter().all(|s| (s - l[0]).abs() <= 1 && *s > 50), "linear steps {l:?}");
        let d = steps(&by_depth);
        assert!(d[0] > 2 * d[2], "hardware depth crowds the far texels: {d:?}");
        let dist = whole.distance(1, 1).unwrap();
        assert!((dist - 2.0).abs() < 1e-3, "texel (1, 1) sees a point 2 from the light, not {dist}");
    }
}
