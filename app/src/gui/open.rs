//! Opening and saving: built-in scenes, models, scene files (everything in a file is checked before anything
//! changes), files dropped on the window, and the recent-files list.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context, Result};
use eframe::egui;
use shadowlab_core::scene::{Scene, SceneSource};

use super::document::SceneFile;
use super::state::save_recent;
use super::ShadowLabApp;

impl ShadowLabApp {
    /// Replace the scene (and its lights and camera). The previous scene stays when `scene` failed to load.
    pub fn set_scene(&mut self, mut scene: Scene) {
        self.views.set_scene(&scene);
        // A model without a camera of its own starts inside when it is an interior (the framing camera would
        // see its roof), from its open side when it is a room open on one side, from outside otherwise.
        if scene.camera_is_framing() {
            if let Some(camera) = self.views.first_view(&scene.bounds, scene.camera.fov_y) {
                scene.camera = camera;
            }
        }
        for text in self.session.set_scene(scene) {
            self.chrome.toasts.note(text, 6);
        }
    }

    pub fn load_builtin(&mut self, name: &str) {
        match Scene::builtin(name) {
            Ok(s) => {
                self.set_scene(s);
                self.session.scene_file = None;
            }
            Err(e) => self.error(e.to_string()),
        }
    }

    /// Open a scene file (.ron) or a model; errors become a message and the current state stays.
    pub fn open_path(&mut self, path: &Path) {
        let is_ron = path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("ron"));
        let result = if is_ron { self.load_scene_file(path) } else { self.load_model(path, 1.0) };
        match result {
            Ok(()) => {
                self.remember_recent(path);
                self.toast(format!("opened {}", path.display()));
            }
            Err(e) => self.error(format!("{:#}", e)),
        }
    }

    fn load_model(&mut self, path: &Path, scale: f32) -> Result<()> {
        let scene = Scene::load(path, scale)?;
        self.set_scene(scene);
        self.session.scene_file = None;
        Ok(())
    }

    pub fn save_scene_file(&mut self, path: &Path) -> Result<()> {
        self.session.scene_file_data().save(path)?;
        self.session.scene_file = Some(path.to_path_buf());
        self.remember_recent(path);
        Ok(())
    }

    /// Load a scene file. Everything is checked before anything changes.
    pub fn load_scene_file(&mut self, path: &Path) -> Result<()> {
        let (file, warnings) = SceneFile::load(path)?;
        let scene = match &file.scene {
            SceneSource::Builtin(name) => Scene::builtin(name)?,
            SceneSource::File { path: model, unit_scale } => {
                // A relative model path is relative to the scene file.
                let model = if model.is_relative() {
                    path.parent().unwrap_or(Path::new(".")).join(model)
                } else {
                    model.clone()
                };
                Scene::load(&model, *unit_scale).with_context(|| "the scene file's model".to_string())?
            }
        };
        if shadowlab_core::technique::registry::REGISTRY.iter().all(|e| e.key != file.technique) {
            return Err(anyhow!("unknown technique '{}'", file.technique));
        }
        // Every saved parameter is checked against its technique's ranges before anything changes, so a bad
        // value (an edited file, a viewpoint at NaN) is an error here and the current state stays.
        if let Some(gpu) = &mut self.views.gpu {
            for (key, values) in &file.params {
                let technique = gpu.main.technique(key).with_context(|| "the scene file's parameters".to_string())?;
                let params = technique.params();
                for (name, value) in values {
                    shadowlab_core::technique::check_param(key, &params, name, value)
                        .map_err(|e| anyhow!("technique '{key}': {e}"))?;
                }
            }
            // The indirect technique's too (its key and the VPL settings were checked when the file was read).
            for (key, values) in &file.indirect.params {
                let technique = gpu.main.indirect_technique(key).context("the scene file's indirect parameters")?;
                let params = technique.borrow().params();
                for (name, value) in values {
                    shadowlab_core::technique::check_param(key, &params, name, value)
                        .map_err(|e| anyhow!("indirect technique '{key}': {e}"))?;
                }
            }
        }
        self.set_scene(scene);
        self.session.apply_file(file);
        self.session.scene_file = Some(path.to_path_buf());
        for w in warnings {
            self.toast(format!("{}: {w}", path.display()));
        }
        Ok(())
    }

    fn remember_recent(&mut self, path: &Path) {
        let path = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        self.chrome.recent.retain(|p| p != &path);
        self.chrome.recent.insert(0, path);
        self.chrome.recent.truncate(10);
        save_recent(&self.lifecycle.data_dir, &self.chrome.recent);
    }

    /// Open the first file dropped on the window.
    pub(super) fn handle_dropped_files(&mut self, ctx: &egui::Context) {
        let dropped: Vec<PathBuf> = ctx.input(|i| i.raw.dropped_files.iter().map(|f| f.path().to_path_buf()).collect());
        if let Some(path) = dropped.first() {
            self.open_path(path);
        }
    }
}
