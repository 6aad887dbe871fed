//! The renderer's settings (not a technique's): size, tone mapping, exposure, which component to show, the
//! indirect light's gain and VPLs, and their validation.

use glam::Vec3;
use serde::Serialize;

use crate::error::GpuError;
use crate::vpl::VplSettings;

/// Largest render target side accepted.
pub const MAX_RENDER_SIZE: u32 = 8192;

/// How the HDR image becomes display colours.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ToneMap {
    Aces,
    Reinhard,
    /// Exposure then clamp: radiance 1 maps to white.
    Linear,
}

/// Settings of the renderer (not of a technique).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub exposure: f32,
    /// Multiply `exposure` by the scale that maps the image's log-average luminance to middle grey (metered on
    /// the GPU each complete frame, [`exposure`]); `exposure` is then a compensation. On in the app, off in
    /// the CLI (`--auto-exposure`), so renders of the same scene stay comparable.
    pub auto_exposure: AutoExposure,
    pub tonemap: ToneMap,
    /// Ambient radiance factor: ambient term = `ambient * albedo`.
    pub ambient: Vec3,
    pub background: Vec3,
    /// Blinn-Phong specular on top of Lambert.
    pub specular: bool,
    /// At most this many lights (cube maps) per step; 0 = as many as the technique's memory budget allows.
    /// The app lowers it on slow adapters so each UI frame does a bounded amount of work.
    pub max_lights_per_step: usize,
    /// The VPLs every indirect technique of a frame shares.
    pub vpl: VplSettings,
    /// Which part of the light the output, `read_hdr` and so every comparison show.
    pub component: Component,
    /// Display gain of the indirect part when [`Component::Indirect`] is shown (not applied to `read_hdr`).
    pub indirect_gain: f32,
    /// Tiled light lists ([`light_tiles`]): shading passes visit only the lights (clusters) that reach their
    /// pixel's 16x16 tile. The image is the same either way; off loops over every light of a batch.
    pub light_tiles: bool,
    /// Receiver-aware caster culling in the cube shadow maps ([`crate::services::cube_shadows::receiver_bounds`]):
    /// a chunk that cannot lie between a light and the view's surfaces in its range is not drawn. The image is
    /// the same either way; off is for measuring what it saves.
    pub receiver_culling: bool,
}

impl RenderSettings {
    /// The settings that change a frame's work (size, specular, steps, VPLs, component, tiles), for telling
    /// measured configurations apart; the display-only ones (exposure and its metering, tone map, ambient and
    /// background colours, indirect gain) are left out, so the app's two views compare.
    pub fn work_fingerprint(&self) -> u64 {
        crate::fingerprint::fingerprint(&(
            self.width,
            self.height,
            self.specular,
            self.max_lights_per_step,
            &self.vpl,
            self.component,
            self.light_tiles,
        ))
    }
}

/// Whether the tone mapping scales the exposure by a metered one ([`exposure`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum AutoExposure {
    /// The exposure as set.
    #[default]
    Off,
    /// Meter every complete frame (and a preview before the first), and scale by it.
    Meter,
    /// Scale by the last metered value without metering (the app's fast preview while the user drags, so the
    /// brightness does not jump between the preview and the full image).
    Hold,
}

/// A part of the image: everything, the ambient + direct part, or the indirect part alone.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Component {
    /// Ambient + emission + direct + indirect.
    #[default]
    Total,
    /// Ambient + emission + direct (the whole image without an indirect technique).
    Direct,
    /// Indirect light only (zero without an indirect technique).
    Indirect,
}

impl Component {
    pub const NAMES: &'static [&'static str] = &["total", "direct", "indirect"];
    pub fn parse(text: &str) -> Option<Component> {
        match text.trim() {
            "total" => Some(Component::Total),
            "direct" => Some(Component::Direct),
            "indirect" => Some(Component::Indirect),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        Component::NAMES[self as usize]
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 640,
            height: 360,
            exposure: 1.0,
            auto_exposure: AutoExposure::Off,
            tonemap: ToneMap::Aces,
            ambient: Vec3::splat(0.03),
            background: Vec3::new(0.05, 0.06, 0.08),
            specular: false,
            max_lights_per_step: 0,
            vpl: VplSettings::default(),
            component: Component::Total,
            indirect_gain: 1.0,
            light_tiles: true,
            receiver_culling: true,
        }
    }
}

impl RenderSettings {
    pub fn validate(&self) -> Result<(), GpuError> {
        if self.width == 0 || self.height == 0 || self.width > MAX_RENDER_SIZE || self.height > MAX_RENDER_SIZE {
            return Err(GpuError::InvalidSettings(format!(
                "image size {}x{} must be between 1x1 and {MAX_RENDER_SIZE}x{MAX_RENDER_SIZE}",
                self.width, self.height
            )));
        }
        if !(self.exposure.is_finite() && self.exposure > 0.0) {
            return Err(GpuError::InvalidSettings(format!("exposure {} must be > 0", self.exposure)));
        }
        if !(self.ambient.is_finite() && self.background.is_finite()) {
            return Err(GpuError::InvalidSettings("ambient and background must be finite".into()));
        }
        if !(self.indirect_gain.is_finite() && self.indirect_gain > 0.0 && self.indirect_gain <= 1e6) {
            return Err(GpuError::InvalidSettings(format!("indirect gain {} must be in (0, 1e6]", self.indirect_gain)));
        }
        self.vpl.validate().map_err(GpuError::InvalidSettings)?;
        Ok(())
    }
}
