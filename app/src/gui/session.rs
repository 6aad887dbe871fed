//! The session: what the user edits and what a scene file saves (the scene, its lights, the camera, the
//! technique and indirect technique with their parameters, the view settings), and with it what editing needs
//! but no file keeps: the undo history, the selection and the light animation.

use std::collections::BTreeMap;
use std::path::PathBuf;

use eframe::egui::Vec2;
use glam::Vec3;
use shadowlab_core::renderer::Component;
use shadowlab_core::scene::layout::{self as light_layout, LightLayout};
use shadowlab_core::scene::{DirectionalLight, PointLight, Scene};
use shadowlab_core::technique::{CameraPose, ParamValue};
use shadowlab_core::{AutoExposure, RenderSettings, ToneMap};

use super::camera::CameraController;
use super::document::{History, IndirectSettings, SceneFile, ViewSettings, FILE_VERSION};

/// Light animation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Animation {
    Off,
    Orbit,
    Bob,
}

impl Animation {
    const ORBIT_RAD_PER_SEC: f32 = 0.8;
    const BOB_RAD_PER_SEC: f32 = 1.5;

    /// Seconds after which every light is back where it started (none when off).
    pub fn period_secs(self) -> Option<f32> {
        match self {
            Animation::Off => None,
            Animation::Orbit => Some(std::f32::consts::TAU / Self::ORBIT_RAD_PER_SEC),
            Animation::Bob => Some(std::f32::consts::TAU / Self::BOB_RAD_PER_SEC),
        }
    }
}

/// What the gizmo moves.
#[derive(Clone, Debug, PartialEq)]
pub enum DragTarget {
    Light(usize),
    /// Camera `index` of the current technique's `ParamKind::Cameras` parameter `key` (INSM's viewpoints).
    Camera {
        key: String,
        index: usize,
    },
}

/// Pixels the preview renders while a light or the camera moves (about 400x240 at 16:10), whatever the view's
/// size: what it costs stays the same as the window grows.
pub const PREVIEW_PIXELS: f32 = 96_000.0;

/// What the user edits: the parts a scene file saves ([`Session::scene_file_data`]) and the editing state
/// around them.
pub struct Session {
    pub scene: Scene,
    pub lights: Vec<PointLight>,
    /// The directional lights (suns): the model's own, as the user edited them, or a scene file's.
    pub suns: Vec<DirectionalLight>,
    pub camera: CameraController,
    pub technique: String,
    /// Parameters the user set, per technique.
    pub params: BTreeMap<String, BTreeMap<String, ParamValue>>,
    /// The indirect technique, its parameters, the VPL settings and the component shown.
    pub indirect: IndirectSettings,
    pub view: ViewSettings,
    /// Undo/redo of the point lights and the suns together.
    pub history: History<(Vec<PointLight>, Vec<DirectionalLight>)>,
    /// The scene file the session was opened from or last saved to.
    pub scene_file: Option<PathBuf>,
    pub selected: Option<usize>,
    /// A selected technique camera (parameter key, index), e.g. an INSM viewpoint; exclusive with `selected`.
    pub selected_camera: Option<(String, usize)>,
    pub animation: Animation,
    pub animation_time: f32,
    /// The light layout the lights came from, as the Lights panel shows and edits it: `scene` for the scene's
    /// own lights, the layout placed for a scene without lights, the last applied one; empty for the lights of
    /// a scene file.
    pub layout_spec: String,
}

impl Session {
    /// The scene with its own lights and camera, the reference technique, default settings.
    pub fn new(scene: Scene) -> Session {
        Session {
            lights: scene.lights.clone(),
            suns: scene.directional.clone(),
            camera: CameraController::from_camera(&scene.camera, &scene.bounds),
            scene,
            technique: shadowlab_core::technique::registry::REFERENCE.into(),
            params: BTreeMap::new(),
            indirect: IndirectSettings::default(),
            view: ViewSettings::default(),
            history: History::default(),
            scene_file: None,
            selected: None,
            selected_camera: None,
            animation: Animation::Off,
            animation_time: 0.0,
            layout_spec: "scene".into(),
        }
    }

    /// Replace the scene, its lights (a default layout when it has none) and the camera; clears the selection
    /// and the undo history. Returns what to tell the user: the scene's warnings, and the lights placed.
    pub fn set_scene(&mut self, scene: Scene) -> Vec<String> {
        let mut notes: Vec<String> = scene.warnings.iter().map(|w| format!("warning: {w}")).collect();
        self.lights = scene.lights.clone();
        self.suns = scene.directional.clone();
        self.layout_spec = "scene".into();
        if self.lights.is_empty() {
            // Most OBJ files and many glTF models come without lights: start lit, and say so.
            let layout = light_layout::default_for_unlit(&scene);
            if let Ok(lights) = light_layout::generate(&layout, &scene) {
                self.lights = lights;
                self.layout_spec = layout.to_string();
                notes.push(format!("{} has no lights: placed {layout} (Lights panel to change)", scene.name));
            }
        }
        self.camera = CameraController::from_camera(&scene.camera, &scene.bounds);
        self.selected = None;
        self.history.clear();
        self.scene = scene;
        notes
    }

    /// Take the lights, camera, techniques, parameters and view settings of a scene file (its scene is
    /// already loaded); everything in it was checked.
    pub fn apply_file(&mut self, file: SceneFile) {
        self.lights = file.lights;
        if let Some(suns) = file.directional {
            self.suns = suns;
        }
        self.layout_spec = String::new();
        self.camera = CameraController::from_camera(&file.camera, &self.scene.bounds);
        self.technique = file.technique;
        self.params = file.params;
        self.indirect = file.indirect;
        self.view = file.view;
    }

    /// What a scene file saves of the session.
    pub fn scene_file_data(&self) -> SceneFile {
        SceneFile {
            version: FILE_VERSION,
            scene: self.scene.source.clone(),
            lights: self.lights.clone(),
            camera: self.camera.camera(),
            technique: self.technique.clone(),
            params: self.params.clone(),
            view: self.view.clone(),
            indirect: self.indirect.clone(),
            directional: Some(self.suns.clone()),
        }
    }

    // ----- lights -----

    /// Record the current lights and suns for undo; call before every light edit.
    pub fn begin_edit(&mut self) {
        self.history.record((self.lights.clone(), self.suns.clone()));
    }

    pub fn undo(&mut self) {
        let mut now = (std::mem::take(&mut self.lights), std::mem::take(&mut self.suns));
        let undone = self.history.undo(&mut now);
        (self.lights, self.suns) = now;
        if undone {
            self.fix_selection();
        }
    }

    pub fn redo(&mut self) {
        let mut now = (std::mem::take(&mut self.lights), std::mem::take(&mut self.suns));
        let redone = self.history.redo(&mut now);
        (self.lights, self.suns) = now;
        if redone {
            self.fix_selection();
        }
    }

    fn fix_selection(&mut self) {
        if self.selected.is_some_and(|i| i >= self.lights.len()) {
            self.selected = None;
        }
    }

    pub fn delete_selected(&mut self) {
        if let Some(i) = self.selected.filter(|&i| i < self.lights.len()) {
            self.begin_edit();
            self.lights.remove(i);
            self.selected = None;
        }
    }

    pub fn duplicate_selected(&mut self) {
        if let Some(i) = self.selected.filter(|&i| i < self.lights.len()) {
            self.begin_edit();
            let mut l = self.lights[i];
            l.position += Vec3::new(0.1, 0.0, 0.1) * l.range.min(10.0);
            self.lights.push(l);
            self.selected = Some(self.lights.len() - 1);
        }
    }

    /// Add a light at a surface point (slightly off the surface along its normal).
    pub fn add_light_at(&mut self, point: Vec3, normal: Vec3) {
        let template = self.selected.and_then(|i| self.lights.get(i).copied()).unwrap_or_else(|| {
            let range = (self.scene.bounds.size().length() * 0.15).max(0.5);
            PointLight::new(
                Vec3::ZERO,
                Vec3::new(1.0, 0.9, 0.8),
                light_layout::default_intensity_for_range(range),
                range,
            )
        });
        self.begin_edit();
        let offset = (template.range * 0.05).clamp(0.02, 0.5);
        self.lights.push(PointLight { position: point + normal * offset, ..template });
        self.selected = Some(self.lights.len() - 1);
    }

    /// Replace the lights by a layout (`random:64:2:1`, ...); returns how many there are now.
    pub fn apply_layout(&mut self, spec: &str) -> anyhow::Result<usize> {
        let lights = light_layout::parse(spec).and_then(|l: LightLayout| light_layout::generate(&l, &self.scene))?;
        self.begin_edit();
        self.lights = lights;
        self.selected = None;
        self.layout_spec = spec.trim().to_string();
        Ok(self.lights.len())
    }

    /// Lights as rendered this frame (animated when animation is on).
    pub fn animated_lights(&self) -> Vec<PointLight> {
        self.lights_at(self.animation_time)
    }

    /// Lights at time `t_secs` of the light animation (as they are when it is off).
    pub fn lights_at(&self, t_secs: f32) -> Vec<PointLight> {
        let t = t_secs;
        match self.animation {
            Animation::Off => self.lights.clone(),
            Animation::Orbit => self
                .lights
                .iter()
                .enumerate()
                .map(|(i, l)| {
                    let r = (l.range * 0.1).min(1.0);
                    let a = t * Animation::ORBIT_RAD_PER_SEC + i as f32 * 0.7;
                    PointLight { position: l.position + Vec3::new(a.cos() * r, 0.0, a.sin() * r), ..*l }
                })
                .collect(),
            Animation::Bob => self
                .lights
                .iter()
                .enumerate()
                .map(|(i, l)| {
                    let h = (l.range * 0.05).min(0.5);
                    PointLight {
                        position: l.position + Vec3::Y * (t * Animation::BOB_RAD_PER_SEC + i as f32).sin() * h,
                        ..*l
                    }
                })
                .collect(),
        }
    }

    // ----- rendering -----

    pub fn render_settings(&self, size: Vec2, preview: bool) -> RenderSettings {
        let mut scale = self.view.resolution_scale.clamp(0.1, 2.0);
        if preview {
            // A fixed pixel budget, whatever the view's size: a large window previews as fast as a small one.
            let pixels = (size.x * size.y).max(1.0);
            scale = scale.min((PREVIEW_PIXELS / pixels).sqrt());
        }
        RenderSettings {
            width: ((size.x * scale) as u32).clamp(16, 4096),
            height: ((size.y * scale) as u32).clamp(16, 4096),
            exposure: self.view.exposure,
            // The preview holds the full image's metered exposure, so dragging does not change the brightness.
            auto_exposure: match (self.view.auto_exposure, preview) {
                (false, _) => AutoExposure::Off,
                (true, false) => AutoExposure::Meter,
                (true, true) => AutoExposure::Hold,
            },
            tonemap: ToneMap::Aces,
            specular: self.view.specular,
            vpl: self.indirect.vpl,
            // The preview has no indirect light: show all of what it has.
            component: if preview { Component::Total } else { self.indirect.component },
            indirect_gain: self
                .indirect
                .gain
                .clamp(*IndirectSettings::GAIN_RANGE.start(), *IndirectSettings::GAIN_RANGE.end()),
            ..Default::default()
        }
    }

    /// The indirect technique of the views (None while the preview renders) and the parameters the user set.
    pub fn indirect_inputs(&self, preview: bool) -> (Option<String>, BTreeMap<String, ParamValue>) {
        match self.indirect.technique.clone().filter(|_| !preview) {
            Some(key) => {
                let params = self.indirect.params.get(&key).cloned().unwrap_or_default();
                (Some(key), params)
            }
            None => (None, BTreeMap::new()),
        }
    }

    /// The parameters the user set for technique `key`, as `key=value` (what the CLI's `--param` takes).
    pub fn param_strings(&self, key: &str) -> Vec<String> {
        pairs(self.params.get(key))
    }

    /// Indirect technique `key` (None: none) with the parameters the user set for it.
    pub fn indirect_choice_of(&self, key: Option<&str>) -> crate::measure::IndirectChoice {
        match key {
            Some(k) => {
                crate::measure::IndirectChoice { key: k.to_string(), params: pairs(self.indirect.params.get(k)) }
            }
            None => crate::measure::IndirectChoice::none(),
        }
    }

    /// The comparison target's indirect technique key (None: direct light only): the view's own unless the
    /// user chose another for the target ([`ViewSettings::against_indirect`]); with the indirect component
    /// alone shown, the own technique's comparison target
    /// ([`shadowlab_core::technique::registry::own_indirect_target`]).
    pub fn against_indirect_key(&self) -> Option<&str> {
        match self.view.against_indirect.as_deref() {
            None if self.indirect.component == Component::Indirect => self
                .indirect
                .technique
                .as_deref()
                .map(|k| shadowlab_core::technique::registry::own_indirect_target(k).unwrap_or(k)),
            None => self.indirect.technique.as_deref(),
            Some("none") => None,
            Some(k) => Some(k),
        }
    }

    /// The comparison target's indirect technique (None while the preview renders) with the parameters the
    /// user set for it.
    pub fn against_indirect_inputs(&self, preview: bool) -> (Option<String>, BTreeMap<String, ParamValue>) {
        match self.against_indirect_key().filter(|_| !preview) {
            Some(key) => (Some(key.to_string()), self.indirect.params.get(key).cloned().unwrap_or_default()),
            None => (None, BTreeMap::new()),
        }
    }

    // ----- the gizmo's targets -----

    /// The current technique's first camera-list parameter as the user set it: (key, cameras).
    pub fn technique_cameras(&self) -> Option<(String, Vec<CameraPose>)> {
        self.params.get(&self.technique)?.iter().find_map(|(k, v)| match v {
            ParamValue::Cameras(c) => Some((k.clone(), c.clone())),
            _ => None,
        })
    }

    /// What the gizmo is attached to: the selected light, else the selected technique camera.
    pub fn gizmo_target(&self) -> Option<DragTarget> {
        if let Some(i) = self.selected.filter(|&i| i < self.lights.len()) {
            return Some(DragTarget::Light(i));
        }
        let (key, index) = self.selected_camera.clone()?;
        let (k, cameras) = self.technique_cameras()?;
        (k == key && index < cameras.len()).then_some(DragTarget::Camera { key, index })
    }

    pub fn target_position(&self, target: &DragTarget) -> Option<Vec3> {
        match target {
            DragTarget::Light(i) => self.lights.get(*i).map(|l| l.position),
            DragTarget::Camera { key, index } => match self.params.get(&self.technique)?.get(key)? {
                ParamValue::Cameras(c) => c.get(*index).map(|c| c.position),
                _ => None,
            },
        }
    }

    /// Move a light, or a technique camera (its target moves along, so it keeps looking the same way).
    pub fn set_target_position(&mut self, target: &DragTarget, position: Vec3) {
        match target {
            DragTarget::Light(i) => {
                if let Some(l) = self.lights.get_mut(*i) {
                    l.position = position;
                }
            }
            DragTarget::Camera { key, index } => {
                let Some(ParamValue::Cameras(c)) = self.params.get_mut(&self.technique).and_then(|p| p.get_mut(key))
                else {
                    return;
                };
                if let Some(c) = c.get_mut(*index) {
                    let offset = c.target - c.position;
                    c.position = position;
                    c.target = position + offset;
                }
            }
        }
    }
}

/// Parameter values as `key=value`.
fn pairs(params: Option<&BTreeMap<String, ParamValue>>) -> Vec<String> {
    params.map(|p| p.iter().map(|(k, v)| format!("{k}={v}")).collect()).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_indirect_component_alone_is_compared_with_the_indirect_techniques_own_target() {
        let mut session = Session::new(Scene::builtin("cornell").unwrap());
        session.indirect.technique = Some("val".into());
        assert_eq!(session.against_indirect_key(), Some("val"), "the whole image: the same indirect light");
        session.indirect.component = Component::Indirect;
        assert_eq!(session.against_indirect_key(), Some("vpl-shadowmaps"), "the indirect light alone: its target");
        session.view.against_indirect = Some("vpl-raytraced".into());
        assert_eq!(session.against_indirect_key(), Some("vpl-raytraced"), "the user's choice stands");
        session.view.against_indirect = None;
        session.indirect.technique = Some("pathtraced".into());
        assert_eq!(session.against_indirect_key(), Some("pathtraced"), "a ground truth against itself");
    }

    #[test]
    fn the_moving_preview_renders_a_fixed_pixel_budget_whatever_the_view_size() {
        let session = Session::new(Scene::builtin("cornell").unwrap());
        let pixels = |s: &RenderSettings| (s.width * s.height) as f32;
        for (w, h) in [(1400.0, 860.0), (1024.0, 640.0), (2560.0, 1440.0)] {
            let preview = session.render_settings(Vec2::new(w, h), true);
            let full = session.render_settings(Vec2::new(w, h), false);
            assert!((pixels(&preview) - PREVIEW_PIXELS).abs() < 0.02 * PREVIEW_PIXELS, "{w}x{h}: {preview:?}");
            let aspect = |s: &RenderSettings| s.width as f32 / s.height as f32;
            assert!((aspect(&preview) - w / h).abs() < 0.02, "{w}x{h}: the preview keeps the view's shape");
            assert_eq!((full.width, full.height), (w as u32, h as u32));
        }
        // A view smaller than the budget previews at its own size.
        let small = session.render_settings(Vec2::new(200.0, 150.0), true);
        assert_eq!((small.width, small.height), (200, 150));
    }
}
