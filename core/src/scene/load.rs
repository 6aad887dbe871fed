//! Where a scene comes from: a file by its extension (OBJ, glTF) or a built-in by name. The entry points of
//! [`Scene`], kept apart from the model (`mod.rs`) so the model imports none of the loaders that build it.

use std::path::Path;

use super::{builtin, gltf_loader, obj_loader, Scene};
use crate::error::LoadError;

impl Scene {
    /// Load a scene file by extension (`.obj`, `.gltf`, `.glb`), multiplying positions by `unit_scale`
    /// (the conference room is in centimetres: 0.01 gives metres). The camera frames the scene; lights come
    /// from the file when it has any (glTF `KHR_lights_punctual`).
    pub fn load(path: &Path, unit_scale: f32) -> Result<Scene, LoadError> {
        if !(unit_scale.is_finite() && unit_scale > 0.0) {
            return Err(LoadError::InvalidScale { scale: unit_scale });
        }
        if !path.exists() {
            return Err(LoadError::NotFound { path: path.to_path_buf() });
        }
        let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("obj") => obj_loader::load_obj(path, unit_scale),
            Some("gltf") | Some("glb") => gltf_loader::load_gltf(path, unit_scale),
            _ => Err(LoadError::UnsupportedFormat { path: path.to_path_buf() }),
        }
    }

    /// A built-in scene by name (`cornell`, `arcade`, `restaurant`).
    pub fn builtin(name: &str) -> Result<Scene, LoadError> {
        builtin::build(name)
    }

    /// `name` is a built-in scene name or a path to a file.
    pub fn load_any(name_or_path: &str, unit_scale: f32) -> Result<Scene, LoadError> {
        if !(unit_scale.is_finite() && unit_scale > 0.0) {
            return Err(LoadError::InvalidScale { scale: unit_scale });
        }
        if builtin::NAMES.contains(&name_or_path) {
            if unit_scale != 1.0 {
                log::warn!("--scale is ignored for built-in scenes");
            }
            return Scene::builtin(name_or_path);
        }
        let path = Path::new(name_or_path);
        if !path.exists() && path.extension().is_none() {
            return Err(LoadError::UnknownBuiltin {
                name: name_or_path.to_string(),
                choices: builtin::NAMES.join(", "),
            });
        }
        Scene::load(path, unit_scale)
    }
}
