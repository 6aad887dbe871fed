//! A light's reflective shadow map in the Shadow maps panel: what the `rsm` VPL source draws its VPLs from
//! (Dachsbacher & Stamminger 2005; Dong et al. 2009 section 6). The source never stores the map (it casts only
//! the `N` texels it draws, [`shadowlab_core::vpl`]), so the view casts every texel's central ray of the chosen
//! light's map on the CPU ([`rsm_image`]) at a resolution chosen here, and shows per texel its reflected flux
//! (colour), its normal (RGB) or its distance from the light (grey), a cube unfolded as a cross (as the
//! inspector unfolds cube maps), a narrow spot's one face, a sun's orthographic square. The texels the frame's
//! first-bounce VPLs of that light came from are ringed, with how many. The map is cast again when the light,
//! the resolution or the scene changes, once the frame has settled (not while a light is dragged).

use std::collections::BTreeMap;
use std::sync::Arc;

use eframe::egui;
use shadowlab_core::accel::gpu_scene::GpuScene;
use shadowlab_core::accel::scene_bvh::SceneBvh;
use shadowlab_core::scene::{DirectionalLight, PointLight};
use shadowlab_core::vpl::rsm::{rsm_image, RsmEmitter, RsmImage, RsmLayout};
use shadowlab_core::vpl::{emitter_name, VplSet, VplSource, RSM_RESOLUTION};

use crate::gui::image_view::{fit_texture, ImageView};
use crate::rsm_picture::{picture, picture_size, pixel_of, readout, RsmShow};

/// The resolutions offered (texels a face side).
pub const RESOLUTIONS: [u32; 4] = [32, 64, 128, 256];
/// Most rings drawn over the image (a frame of 65k VPLs would hide the map).
const MAX_MARKS: usize = 4096;

/// One of the scene's emitters, as the VPL set numbers them: point lights, then suns.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Emitter {
    Point(PointLight),
    Sun(DirectionalLight),
}

/// What an image was cast from. The scene is held, so that a new scene is never taken for the old one at the
/// same address.
#[derive(Clone)]
struct Cast {
    index: usize,
    emitter: Emitter,
    resolution: u32,
    scene: Arc<GpuScene>,
}

impl PartialEq for Cast {
    fn eq(&self, o: &Cast) -> bool {
        (self.index, self.emitter, self.resolution) == (o.index, o.emitter, o.resolution)
            && Arc::ptr_eq(&self.scene, &o.scene)
    }
}

/// What the view reads from the app each UI frame.
pub struct RsmInputs<'a> {
    /// The scene's BVH (built on first use).
    pub bvh: &'a dyn Fn() -> Arc<SceneBvh>,
    /// The scene's geometry: a new scene casts again.
    pub scene: Arc<GpuScene>,
    pub lights: &'a [PointLight],
    pub suns: &'a [DirectionalLight],
    /// The frame's VPLs (empty without an indirect technique).
    pub vpls: &'a Arc<VplSet>,
    /// The light selected in the view, followed once per selection.
    pub selected: Option<usize>,
    /// False while the frame is moving (a dragged light): the map waits.
    pub settled: bool,
}

/// The view's state.
pub struct RsmView {
    /// The emitter shown: a point light's index, or `lights + k` for sun `k`.
    pub emitter: usize,
    pub resolution: u32,
    pub show: RsmShow,
    /// Ring the texels the frame's VPLs came from.
    pub marks: bool,
    pub image: Option<RsmImage>,
    cast: Option<Cast>,
    /// CPU milliseconds of the last cast.
    pub cast_ms: f64,
    /// Texel (face, x, y) -> VPLs drawn from it; and the VPL set (held) and emitter they were counted for.
    pub drawn: BTreeMap<(u32, u32, u32), u32>,
    drawn_from: Option<(Arc<VplSet>, usize)>,
    /// VPLs in the frame, and how they were made.
    vpl_note: String,
    pub error: Option<String>,
    texture: Option<(egui::TextureHandle, RsmShow)>,
    view: ImageView,
    pub readout: Option<String>,
    followed: Option<usize>,
    emitters: usize,
    /// The map shown is not the chosen light's as it is now: it is cast once the frame settles.
    pub waiting: bool,
}

impl Default for RsmView {
    fn default() -> Self {
        RsmView {
            emitter: 0,
            resolution: 64,
            show: RsmShow::Flux,
            marks: true,
            image: None,
            cast: None,
            cast_ms: 0.0,
            drawn: BTreeMap::new(),
            drawn_from: None,
            vpl_note: String::new(),
            error: None,
            texture: None,
            view: ImageView::default(),
            readout: None,
            followed: None,
            emitters: 0,
            waiting: false,
        }
    }
}

impl RsmView {
    /// The picture on screen (its texture and size in texels) and what it is, for the 3D view.
    pub fn on_screen(&self, lights: usize) -> Option<(egui::TextureId, [u32; 2], String)> {
        let ((texture, _), image) = (self.texture.as_ref()?, self.image.as_ref()?);
        let name = emitter_name(self.emitter, lights);
        Some((texture.id(), picture_size(image), format!("{name}'s reflective shadow map")))
    }

    /// The picture's pixels to ring (the texels the frame's VPLs came from), when rings are on.
    pub fn marks(&self) -> Vec<(u32, u32)> {
        match (&self.image, self.marks) {
            (Some(image), true) => {
                self.drawn.keys().take(MAX_MARKS).map(|&(face, x, y)| pixel_of(image, face, x, y)).collect()
            }
            _ => Vec::new(),
        }
    }

    /// Cast the map again if its light, resolution or scene changed (once settled), and count the VPLs drawn
    /// from it when the frame's VPLs changed.
    pub fn update(&mut self, inputs: &RsmInputs) {
        let (lights, suns) = (inputs.lights, inputs.suns);
        self.emitters = lights.len() + suns.len();
        if inputs.selected != self.followed {
            self.followed = inputs.selected;
            if let Some(i) = inputs.selected.filter(|&i| i < lights.len()) {
                self.emitter = i;
            }
        }
        if self.emitters == 0 {
            self.error = Some("No lights: add a light (Ctrl+click a surface) or a sun to see its RSM.".into());
            (self.image, self.cast, self.texture) = (None, None, None);
            return;
        }
        self.emitter = self.emitter.min(self.emitters - 1);
        let emitter = match self.emitter.checked_sub(lights.len()) {
            Some(k) => Emitter::Sun(suns[k]),
            None => Emitter::Point(lights[self.emitter]),
        };
        let cast = Cast { index: self.emitter, emitter, resolution: self.resolution, scene: inputs.scene.clone() };
        self.waiting = self.cast.as_ref() != Some(&cast) && !inputs.settled;
        if self.cast.as_ref() != Some(&cast) && inputs.settled {
            let bvh = (inputs.bvh)();
            let started = std::time::Instant::now();
            let result = match &cast.emitter {
                Emitter::Point(l) => rsm_image(&bvh, RsmEmitter::Point(l), cast.resolution),
                Emitter::Sun(s) => rsm_image(&bvh, RsmEmitter::Sun(s), cast.resolution),
            };
            self.cast_ms = started.elapsed().as_secs_f64() * 1e3;
            match result {
                Ok(image) => (self.image, self.error) = (Some(image), None),
                Err(e) => {
                    let name = emitter_name(cast.index, lights.len());
                    (self.image, self.error) = (None, Some(format!("No RSM of {name}: {e}.")));
                }
            }
            self.cast = Some(cast);
            self.texture = None;
            self.drawn_from = None;
            self.view.reset();
        }
        let counted = |(set, emitter): &(Arc<VplSet>, usize)| Arc::ptr_eq(set, inputs.vpls) && *emitter == self.emitter;
        if !self.drawn_from.as_ref().is_some_and(counted) {
            self.drawn_from = Some((inputs.vpls.clone(), self.emitter));
            self.drawn = match &self.image {
                Some(image) => image.drawn_texels(inputs.vpls, self.emitter as u32),
                None => BTreeMap::new(),
            };
            let set = inputs.vpls;
            self.vpl_note = match set.settings {
                _ if set.vpls.is_empty() => {
                    "No VPLs this frame: choose an indirect technique to see the texels the VPL source draws.".into()
                }
                Some(s) => {
                    let from = self.drawn.values().sum::<u32>();
                    let how = match s.source {
                        VplSource::Rsm => {
                            format!("drawn from the light's {0}² faces: a ring may hold several", RSM_RESOLUTION)
                        }
                        VplSource::Traced => {
                            "traced particles (vpl_source traced): ringed where their first hits lie".to_string()
                        }
                    };
                    format!("{from} of the frame's {} VPLs came from here, first bounce ({how}).", set.vpls.len())
                }
                None => String::new(),
            };
        }
    }

    /// The panel: controls, the map and the readout of the texel under the pointer.
    pub fn ui(&mut self, ui: &mut egui::Ui, lights: usize) {
        ui.horizontal(|ui| {
            let label = ui.label("light");
            let mut e = self.emitter;
            let max = self.emitters.saturating_sub(1);
            ui.add_enabled(
                self.emitters > 0,
                egui::DragValue::new(&mut e).range(0..=max).custom_formatter(|v, _| emitter_name(v as usize, lights)),
            )
            .labelled_by(label.id)
            .on_hover_text("Point lights, then suns; selecting a light in the view shows its RSM");
            self.emitter = e;
            egui::ComboBox::from_label("texels a face").selected_text(format!("{0}²", self.resolution)).show_ui(
                ui,
                |ui| {
                    for r in RESOLUTIONS {
                        ui.selectable_value(&mut self.resolution, r, format!("{r}²"));
                    }
                },
            );
        });
        ui.horizontal(|ui| {
            let before = self.show;
            ui.radio_value(&mut self.show, RsmShow::Flux, "flux");
            ui.radio_value(&mut self.show, RsmShow::Normal, "normal");
            ui.radio_value(&mut self.show, RsmShow::Distance, "distance");
            if before != self.show {
                self.texture = None;
            }
            ui.checkbox(&mut self.marks, "VPLs drawn").on_hover_text("Ring the texels the frame's VPLs came from");
        });
        if let Some(e) = &self.error {
            ui.colored_label(egui::Color32::LIGHT_RED, e);
        }
        if self.waiting {
            ui.label("The map is cast once the frame settles (a light or the camera is moving).");
        }
        let Some(image) = &self.image else { return };
        let what = match image.layout {
            RsmLayout::Cube { .. } => format!("a cube of 6 x {0}² texels", image.resolution),
            RsmLayout::Spot { .. } => format!("a spot's face of {0}² texels", image.resolution),
            RsmLayout::Sun { .. } => format!("a sun's square of {0}² texels", image.resolution),
        };
        let total = image.total_flux();
        ui.label(format!(
            "{}: {what}, cast on the CPU in {:.0} ms; reflected flux ({:.3}, {:.3}, {:.3})",
            emitter_name(self.emitter, lights),
            self.cast_ms,
            total.x,
            total.y,
            total.z
        ));
        ui.label(&self.vpl_note);
        if self.texture.as_ref().is_none_or(|(_, show)| *show != self.show) {
            let rgba = picture(image, self.show);
            let size = [rgba.width() as usize, rgba.height() as usize];
            let picture = egui::ColorImage::from_rgba_unmultiplied(size, rgba.as_raw());
            let picture = fit_texture(picture, ui.ctx().input(|i| i.max_texture_side));
            let texture = ui.ctx().load_texture("rsm", picture, egui::TextureOptions::NEAREST);
            self.texture = Some((texture, self.show));
        }
        let Some((texture, _)) = &self.texture else { return };
        let size = picture_size(image);
        let placed = self.view.show(ui, texture, size, 24.0);
        ring(&placed.painter, &self.marks(), |x, y| placed.point(x, y), placed.scale);
        self.readout = placed.hovered.and_then(|(px, py)| readout(image, &self.drawn, px, py));
        ui.label(self.readout.clone().unwrap_or_else(|| "scroll to zoom, drag to pan".into()));
    }
}

/// Ring the picture pixels `marks` (the texels VPLs came from), drawn at `point(x, y)` with `scale` points a
/// texel: in the panel and over the 3D view alike.
pub fn ring(painter: &egui::Painter, marks: &[(u32, u32)], point: impl Fn(u32, u32) -> egui::Pos2, scale: f32) {
    let radius = (scale * 0.5).max(2.0);
    let stroke = egui::Stroke::new(1.5, egui::Color32::from_rgb(255, 60, 200));
    for &(x, y) in marks {
        painter.circle_stroke(point(x, y), radius, stroke);
    }
}
