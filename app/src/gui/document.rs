//! What a user edits and saves: the scene source, lights, camera, technique and its parameters, view settings.
//! Saved as RON, atomically (temp file + rename); loading a broken file changes nothing and says why; fields
//! from a newer version are reported, not fatal. Light edits go through [`History`] for undo/redo.

use shadowlab_core::technique::registry;
use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use shadowlab_core::renderer::Component;
use shadowlab_core::scene::{Camera, DirectionalLight, PointLight, SceneSource};
use shadowlab_core::technique::ParamValue;
use shadowlab_core::vpl::VplSettings;

/// Version written into scene files (2: indirect light; files of version 1 load as "no indirect").
pub const FILE_VERSION: u32 = 2;

/// The indirect light of a document: the indirect technique (from `INDIRECT_REGISTRY`), its parameters, the
/// VPL settings every indirect technique shares, and which component of the light the views show.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct IndirectSettings {
    /// Key of the indirect technique; None = direct light only.
    pub technique: Option<String>,
    /// Parameters per indirect technique key, as set by the user.
    pub params: BTreeMap<String, BTreeMap<String, ParamValue>>,
    pub vpl: VplSettings,
    pub component: Component,
    /// Display gain of the indirect component, 1..1000.
    pub gain: f32,
}

impl Default for IndirectSettings {
    fn default() -> Self {
        IndirectSettings {
            technique: None,
            params: BTreeMap::new(),
            vpl: VplSettings::default(),
            component: Component::Total,
            gain: 1.0,
        }
    }
}

impl IndirectSettings {
    /// The smallest and largest display gain the app offers.
    pub const GAIN_RANGE: std::ops::RangeInclusive<f32> = 1.0..=1000.0;

    /// Check what does not need a device: the technique key is registered, the VPL settings and the gain are in
    /// range. (Parameters are checked against the technique's own ranges by the app, which creates it.)
    pub fn validate(&self) -> Result<()> {
        let registry = shadowlab_core::technique::registry::INDIRECT_REGISTRY;
        for key in self.technique.iter().chain(self.params.keys()) {
            if registry.iter().all(|e| e.key != key.as_str()) {
                bail!(
                    "unknown indirect technique '{key}' (choose one of: {})",
                    shadowlab_core::technique::registry::indirect_keys()
                );
            }
        }
        self.vpl.validate().map_err(|e| anyhow::anyhow!("indirect light: {e}"))?;
        if !(self.gain.is_finite() && Self::GAIN_RANGE.contains(&self.gain)) {
            bail!("indirect gain {} must be between 1 and 1000", self.gain);
        }
        Ok(())
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum ViewMode {
    #[default]
    Single,
    /// Technique on the left, reference on the right.
    SideBySide,
    /// One image, technique left of a draggable line, reference right of it.
    Split,
    /// The difference image of the technique against the reference, with its error metrics.
    Difference,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ViewSettings {
    pub mode: ViewMode,
    /// 0..1, position of the split line.
    pub split: f32,
    pub x_ray: bool,
    /// Overlay layers by name: shown or not. Layers not listed use their default.
    pub overlays: BTreeMap<String, bool>,
    /// Render resolution relative to the viewport size.
    pub resolution_scale: f32,
    pub exposure: f32,
    /// Exposure scaled so the image's log-average luminance is middle grey (then `exposure` compensates).
    pub auto_exposure: bool,
    pub specular: bool,
    /// Difference view: signed (red too bright, green too dark) instead of absolute.
    pub diff_signed: bool,
    /// Difference view: compare shadow factors (visibility) instead of final colour.
    pub diff_visibility: bool,
    /// Difference view gain (1, 5, 10, ...).
    pub diff_gain: f32,
    /// What side-by-side, split and difference views compare with: `reference` or `raytraced`.
    pub compare_against: String,
    /// The comparison target's indirect technique: None = the view's own (both sides the same indirect
    /// light), `none` = direct light only, or a key of the indirect registry (`val` against `vpl-shadowmaps`,
    /// `fuzzy` against `pathtraced`). Absent in older files (= the view's own).
    pub against_indirect: Option<String>,
    /// A legend of the visible overlay layers drawn over the 3D view.
    pub legend: bool,
}

impl ViewSettings {
    /// Every field in range, so a file never leaves a permanent render error (a NaN exposure, say).
    pub fn validate(&self) -> Result<()> {
        let in_range = |name: &str, v: f32, lo: f32, hi: f32| -> Result<()> {
            if !(v.is_finite() && (lo..=hi).contains(&v)) {
                bail!("view setting {name} = {v} must be between {lo} and {hi}");
            }
            Ok(())
        };
        in_range("split", self.split, 0.0, 1.0)?;
        in_range("resolution_scale", self.resolution_scale, 0.1, 2.0)?;
        in_range("exposure", self.exposure, 1e-3, 1e3)?;
        in_range("diff_gain", self.diff_gain, 0.01, 1e4)?;
        if !registry::targets().any(|e| e.key == self.compare_against) {
            let known = registry::targets().map(|e| e.key).collect::<Vec<_>>().join(", ");
            bail!("view setting compare_against = '{}' must be one of {known}", self.compare_against);
        }
        if let Some(k) = self.against_indirect.as_deref() {
            if k != "none" && shadowlab_core::technique::registry::INDIRECT_REGISTRY.iter().all(|e| e.key != k) {
                bail!(
                    "view setting against_indirect = '{k}' must be none or one of {}",
                    shadowlab_core::technique::registry::indirect_keys()
                );
            }
        }
        Ok(())
    }
}

impl Default for ViewSettings {
    fn default() -> Self {
        ViewSettings {
            mode: ViewMode::Single,
            split: 0.5,
            x_ray: false,
            overlays: BTreeMap::new(),
            resolution_scale: 1.0,
            exposure: 1.0,
            auto_exposure: true,
            specular: false,
            diff_signed: false,
            diff_visibility: false,
            diff_gain: 1.0,
            compare_against: registry::REFERENCE.into(),
            against_indirect: None,
            legend: true,
        }
    }
}

/// A scene file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneFile {
    pub version: u32,
    pub scene: SceneSource,
    pub lights: Vec<PointLight>,
    pub camera: Camera,
    pub technique: String,
    /// Parameters per technique key, as set by the user.
    #[serde(default)]
    pub params: BTreeMap<String, BTreeMap<String, ParamValue>>,
    #[serde(default)]
    pub view: ViewSettings,
    /// Indirect light; absent in files of version 1 (= none).
    #[serde(default)]
    pub indirect: IndirectSettings,
    /// The directional lights (suns) as the user left them; absent in older files (= the model's own).
    #[serde(default)]
    pub directional: Option<Vec<DirectionalLight>>,
}

const KNOWN_FIELDS: &[&str] =
    &["version", "scene", "lights", "camera", "technique", "params", "view", "indirect", "directional"];

impl SceneFile {
    pub fn to_ron(&self) -> Result<String> {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default()).context("cannot encode the scene file")
    }

    /// Parse a scene file. Returns the file and warnings (unknown fields from a newer version).
    pub fn from_ron(text: &str) -> Result<(SceneFile, Vec<String>)> {
        let value: ron::Value = ron::from_str(text).map_err(|e| anyhow::anyhow!("not a ShadowLab scene file: {e}"))?;
        let mut warnings = Vec::new();
        if let ron::Value::Map(map) = &value {
            for (k, _) in map.iter() {
                if let ron::Value::String(key) = k {
                    if !KNOWN_FIELDS.contains(&key.as_str()) {
                        warnings.push(format!("unknown field '{key}' ignored (written by a newer ShadowLab?)"));
                    }
                }
            }
        }
        let file: SceneFile = ron::from_str(text).map_err(|e| anyhow::anyhow!("broken scene file: {e}"))?;
        if file.version > FILE_VERSION {
            warnings.push(format!("file version {} is newer than this ShadowLab ({FILE_VERSION})", file.version));
        }
        if let Some(i) = file.lights.iter().position(|l| !l.is_valid()) {
            bail!("light {i} has a non-finite or negative value");
        }
        let max = shadowlab_core::scene::layout::MAX_LIGHTS;
        if file.lights.len() > max {
            bail!("the file has {} lights; the limit is {max}", file.lights.len());
        }
        if !file.camera.is_valid() {
            bail!("the camera has non-finite or degenerate values");
        }
        if let Some(suns) = &file.directional {
            if let Some(i) = suns.iter().position(|l| !l.is_valid()) {
                bail!("directional light {i} has a zero or non-finite direction, or a negative or non-finite value");
            }
            let max = shadowlab_core::scene::MAX_DIRECTIONAL_LIGHTS;
            if suns.len() > max {
                bail!("the file has {} directional lights; the limit is {max}", suns.len());
            }
        }
        file.indirect.validate()?;
        file.view.validate()?;
        Ok((file, warnings))
    }

    pub fn load(path: &Path) -> Result<(SceneFile, Vec<String>)> {
        let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
        SceneFile::from_ron(&text).with_context(|| path.display().to_string())
    }

    /// Write atomically: a temporary file beside the target, then a rename; the old file survives any failure.
    pub fn save(&self, path: &Path) -> Result<()> {
        let text = self.to_ron()?;
        crate::files::write_atomic(path, text.as_bytes())
    }
}

/// Undo/redo of light edits, as snapshots of what the edits change (the session's point lights and suns).
#[derive(Debug)]
pub struct History<T> {
    undo: Vec<T>,
    redo: Vec<T>,
}

impl<T> Default for History<T> {
    fn default() -> Self {
        History { undo: Vec::new(), redo: Vec::new() }
    }
}

/// Snapshots kept; older ones are dropped.
pub const HISTORY_LIMIT: usize = 200;

impl<T> History<T> {
    /// Call before an edit with the state as it is.
    pub fn record(&mut self, before: T) {
        self.undo.push(before);
        if self.undo.len() > HISTORY_LIMIT {
            self.undo.remove(0);
        }
        self.redo.clear();
    }
    pub fn undo(&mut self, current: &mut T) -> bool {
        match self.undo.pop() {
            Some(prev) => {
                self.redo.push(std::mem::replace(current, prev));
                true
            }
            None => false,
        }
    }
    pub fn redo(&mut self, current: &mut T) -> bool {
        match self.redo.pop() {
            Some(next) => {
                self.undo.push(std::mem::replace(current, next));
                true
            }
            None => false,
        }
    }
    /// How many edits can be undone.
    pub fn depth(&self) -> usize {
        self.undo.len()
    }
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }
    pub fn clear(&mut self) {
        self.undo.clear();
        self.redo.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn file() -> SceneFile {
        SceneFile {
            version: FILE_VERSION,
            scene: SceneSource::Builtin("cornell".into()),
            lights: vec![PointLight::new(Vec3::ONE, Vec3::ONE, 2.0, 3.0)],
            camera: Camera::look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO, 0.8, 0.05, 30.0),
            technique: registry::REFERENCE.into(),
            params: BTreeMap::from([(
                registry::REFERENCE.to_string(),
                BTreeMap::from([("shadow_res".to_string(), ParamValue::Int(256))]),
            )]),
            view: ViewSettings::default(),
            indirect: IndirectSettings::default(),
            directional: Some(vec![sun()]),
        }
    }

    fn sun() -> DirectionalLight {
        DirectionalLight { direction: Vec3::new(0.3, -1.0, 0.2).normalize(), color: Vec3::ONE, illuminance: 3.0 }
    }

    #[test]
    fn suns_round_trip_older_files_keep_the_models_and_bad_ones_are_refused() {
        let (back, _) = SceneFile::from_ron(&file().to_ron().unwrap()).unwrap();
        assert_eq!(back.directional, Some(vec![sun()]));
        let older = SceneFile { directional: None, ..file() }.to_ron().unwrap().replace("directional: None,", "");
        assert!(!older.contains("directional"), "{older}");
        assert_eq!(SceneFile::from_ron(&older).unwrap().0.directional, None, "no field: the model's own suns");
        let bad = |d: DirectionalLight| SceneFile { directional: Some(vec![sun(), d]), ..file() }.to_ron().unwrap();
        for d in [
            DirectionalLight { direction: Vec3::ZERO, ..sun() },
            DirectionalLight { illuminance: -1.0, ..sun() },
            DirectionalLight { color: Vec3::new(f32::INFINITY, 1.0, 1.0), ..sun() },
        ] {
            let e = SceneFile::from_ron(&bad(d)).map(|_| ()).unwrap_err().to_string();
            assert!(e.contains("directional light 1"), "{e}");
        }
        let many = SceneFile { directional: Some(vec![sun(); 5]), ..file() }.to_ron().unwrap();
        let e = SceneFile::from_ron(&many).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("5 directional lights"), "{e}");
    }

    #[test]
    fn round_trips_through_ron() {
        let f = file();
        let (back, warnings) = SceneFile::from_ron(&f.to_ron().unwrap()).unwrap();
        assert_eq!(back, f);
        assert!(warnings.is_empty());
    }

    #[test]
    fn unknown_fields_are_reported_not_fatal() {
        let text = f_with_extra(&file().to_ron().unwrap());
        let (back, warnings) = SceneFile::from_ron(&text).unwrap();
        assert_eq!(back, file());
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].contains("future_feature"));
    }

    fn f_with_extra(ron_text: &str) -> String {
        let i = ron_text.rfind(')').unwrap();
        format!("{}    future_feature: 42,\n)", &ron_text[..i])
    }

    #[test]
    fn mutated_scene_files_load_or_fail_without_panicking() {
        let original = file().to_ron().unwrap().into_bytes();
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move |n: usize| {
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            (state.wrapping_mul(0x9e37_79b9_7f4a_7c15) % n.max(1) as u64) as usize
        };
        let (mut ok, mut refused) = (0, 0);
        for _ in 0..3000 {
            let mut b = original.clone();
            match next(3) {
                0 => b.truncate(next(b.len() + 1)),
                1 => {
                    let i = next(b.len());
                    b[i] ^= 1 << next(8);
                }
                _ => {
                    let (from, to) = (next(b.len()), next(b.len()));
                    let len = next((b.len() - from.max(to)).max(1));
                    let chunk = b[from..from + len].to_vec();
                    b[to..to + len].copy_from_slice(&chunk);
                }
            }
            let text = String::from_utf8_lossy(&b);
            match std::panic::catch_unwind(|| SceneFile::from_ron(&text)) {
                Ok(Ok(_)) => ok += 1,
                Ok(Err(_)) => refused += 1,
                Err(_) => panic!("a mutated scene file panicked the parser:\n{text}"),
            }
        }
        assert!(ok > 0 && refused > 0, "{ok} loaded, {refused} refused");
    }

    #[test]
    fn view_settings_out_of_range_are_refused() {
        for bad in [
            ViewSettings { exposure: f32::NAN, ..Default::default() },
            ViewSettings { exposure: 0.0, ..Default::default() },
            ViewSettings { resolution_scale: 50.0, ..Default::default() },
            ViewSettings { split: -1.0, ..Default::default() },
            ViewSettings { diff_gain: f32::INFINITY, ..Default::default() },
            ViewSettings { compare_against: "nope".into(), ..Default::default() },
        ] {
            let f = SceneFile { view: bad.clone(), ..file() };
            let text = f.to_ron().unwrap();
            let err = SceneFile::from_ron(&text).expect_err(&format!("{bad:?} was accepted"));
            assert!(err.to_string().contains("view setting"), "{err}");
        }
        assert!(SceneFile::from_ron(&file().to_ron().unwrap()).is_ok());
    }

    #[test]
    fn broken_files_are_errors() {
        assert!(SceneFile::from_ron("").is_err());
        assert!(SceneFile::from_ron("(version: 1, scene: Builtin(\"x\")").is_err());
        let mut f = file();
        f.lights[0].range = f32::NAN;
        let text = f.to_ron().unwrap();
        assert!(SceneFile::from_ron(&text).is_err(), "NaN light must be rejected");
    }

    #[test]
    fn indirect_settings_round_trip_and_old_files_load_without_them() {
        let key = shadowlab_core::technique::registry::INDIRECT_REGISTRY[0].key.to_string();
        let mut f = file();
        f.indirect.technique = Some(key.clone());
        f.indirect.params.insert(key.clone(), BTreeMap::from([("vpls_per_step".to_string(), ParamValue::Int(64))]));
        f.indirect.vpl.count = 77;
        f.indirect.vpl.source = shadowlab_core::vpl::VplSource::Traced;
        f.indirect.vpl.bounces = 3;
        f.indirect.component = Component::Indirect;
        f.indirect.gain = 20.0;
        let (back, warnings) = SceneFile::from_ron(&f.to_ron().unwrap()).unwrap();
        assert_eq!(back, f);
        assert!(warnings.is_empty(), "{warnings:?}");

        // A version-1 file has no `indirect`: it loads as "no indirect light".
        let mut old = file();
        old.version = 1;
        let text = old.to_ron().unwrap();
        let i = text.find("    indirect:").expect("the field is written");
        let j = i + text[i..].find("\n    ),\n").expect("the field ends") + "\n    ),\n".len();
        let text = format!("{}{}", &text[..i], &text[j..]);
        assert!(!text.contains("\n    indirect:"), "{text}");
        // Nor has an older file the view's `against_indirect` (the target's indirect technique): the view's own.
        let text = text.replace("        against_indirect: None,\n", "");
        assert!(!text.contains("against_indirect"), "{text}");
        let (back, warnings) = SceneFile::from_ron(&text).unwrap();
        assert_eq!(back.indirect, IndirectSettings::default());
        assert_eq!(back.view.against_indirect, None);
        assert!(warnings.is_empty(), "{warnings:?}");
    }

    #[test]
    fn bad_indirect_settings_are_refused_with_a_message() {
        let mut f = file();
        f.indirect.technique = Some("no-such-technique".into());
        let err = SceneFile::from_ron(&f.to_ron().unwrap()).unwrap_err();
        assert!(format!("{err:#}").contains("unknown indirect technique 'no-such-technique'"), "{err:#}");
        let mut f = file();
        f.indirect.vpl.bounces = 0;
        let err = SceneFile::from_ron(&f.to_ron().unwrap()).unwrap_err();
        assert!(format!("{err:#}").contains("bounces"), "{err:#}");
        let mut f = file();
        f.indirect.vpl.count = shadowlab_core::vpl::MAX_VPLS + 1;
        assert!(SceneFile::from_ron(&f.to_ron().unwrap()).is_err());
        let mut f = file();
        f.indirect.gain = 0.0;
        let err = SceneFile::from_ron(&f.to_ron().unwrap()).unwrap_err();
        assert!(format!("{err:#}").contains("gain"), "{err:#}");
    }

    #[test]
    fn a_failed_save_keeps_the_old_file() {
        let dir = std::env::temp_dir().join(format!("shadowlab-doc-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("scene.ron");
        file().save(&path).unwrap();
        let before = std::fs::read_to_string(&path).unwrap();
        // Saving into a path whose temp file cannot be created fails and leaves the original alone.
        let blocker = dir.join("scene.ron.tmp");
        std::fs::create_dir_all(&blocker).unwrap();
        let mut changed = file();
        changed.technique = "lightcluster".into();
        assert!(changed.save(&path).is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), before);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn undo_redo_restore_lights() {
        let mut h = History::default();
        let mut lights = vec![PointLight::new(Vec3::ZERO, Vec3::ONE, 1.0, 1.0)];
        h.record(lights.clone());
        lights[0].position = Vec3::X;
        assert!(h.undo(&mut lights));
        assert_eq!(lights[0].position, Vec3::ZERO);
        assert!(h.redo(&mut lights));
        assert_eq!(lights[0].position, Vec3::X);
        assert!(!h.redo(&mut lights));
    }
}
