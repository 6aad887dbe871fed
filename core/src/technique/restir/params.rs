//! ReSTIR's parameters: their defaults (the paper's where it gives them), ranges and descriptions.

use crate::technique::{check_param, Param, ParamError, ParamKind, ParamValue};

/// The source pdf `p` the candidates are drawn from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// Every visible light alike.
    Uniform,
    /// In proportion to a light's power (luminance of colour times intensity), through an alias table.
    Power,
    /// Every light of the pixel's 16x16 tile list alike (the renderer's tile lists: the lights whose range
    /// reaches the tile). Not the paper's: its lights have no range.
    Tiles,
}

/// How reservoirs of other pixels (and of the previous frame) are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BiasMode {
    /// Algorithm 4: `W = w_sum / (M p̂(y))`, every input's `M` counted.
    Biased,
    /// Algorithm 6: `W = w_sum / (Z p̂(y))`, `Z` the `M` of the inputs that could have drawn `y` (a shadow ray
    /// from each).
    Unbiased,
}

pub const SOURCES: &[&str] = &["uniform", "power", "tiles"];
pub const BIAS_MODES: &[&str] = &["biased", "unbiased"];
/// The most spatial neighbours per pixel (the shader keeps their pixels for the unbiased `Z`).
/// Keep in sync with `RESTIR_MAX_SPATIAL` in `restir/spatial.wgsl`.
pub const MAX_SPATIAL: u32 = 32;

#[derive(Clone, Debug, PartialEq)]
pub struct RestirParams {
    /// `M`: candidates per pixel and frame (Algorithm 3).
    pub candidates: u32,
    pub source: Source,
    /// The history's `M` is capped at `history` times `candidates` (0: no temporal reuse).
    pub history: u32,
    /// `k`: spatial neighbours per pixel (0: no spatial reuse).
    pub spatial: u32,
    /// Radius of the spatial neighbourhood, pixels.
    pub radius: f32,
    pub bias_mode: BiasMode,
    /// Neighbours (spatial and temporal) whose camera distance differs by more than this fraction are rejected.
    pub depth_threshold: f32,
    /// Neighbours whose normal differs by more than this many degrees are rejected.
    pub normal_threshold_deg: f32,
    /// ReSTIR frames per rendered frame, each a step, their images averaged (progressive).
    pub frames: u32,
    /// Ray origin offset along the normal, world units per metre of camera distance.
    pub bias: f32,
    pub seed: u32,
    /// Read the final reservoirs back after each frame for the per-pixel maps (off for timing).
    pub inspect: bool,
}

impl Default for RestirParams {
    fn default() -> Self {
        RestirParams {
            candidates: 32,
            source: Source::Power,
            history: 20,
            spatial: 5,
            radius: 30.0,
            bias_mode: BiasMode::Unbiased,
            depth_threshold: 0.1,
            normal_threshold_deg: 25.0,
            frames: 1,
            bias: 0.001,
            seed: 0,
            inspect: true,
        }
    }
}

impl RestirParams {
    pub fn list(&self) -> Vec<Param> {
        let int = |key: &'static str, label: &'static str, help: &'static str, min: i64, max: i64, v: u32| Param {
            key,
            label,
            help,
            kind: ParamKind::Int { min, max },
            value: ParamValue::Int(v as i64),
        };
        let choice =
            |key: &'static str, label: &'static str, help: &'static str, options: &'static [&'static str], v: &str| {
                Param { key, label, help, kind: ParamKind::Choice(options), value: ParamValue::Choice(v.to_string()) }
            };
        let float = |key: &'static str, label: &'static str, help: &'static str, min: f32, max: f32, v: f32| Param {
            key,
            label,
            help,
            kind: ParamKind::Float { min, max },
            value: ParamValue::Float(v),
        };
        vec![
            int(
                "candidates",
                "Candidates (M)",
                "Lights drawn from the source pdf per pixel and frame (RIS)",
                1,
                1024,
                self.candidates,
            ),
            choice(
                "source",
                "Source pdf",
                "What the candidates are drawn from: every visible light alike, by power (alias table), or the \
                 lights of the pixel's tile list alike",
                SOURCES,
                match self.source {
                    Source::Uniform => "uniform",
                    Source::Power => "power",
                    Source::Tiles => "tiles",
                },
            ),
            int(
                "history",
                "Temporal history",
                "The previous frame's M is capped at this many times the candidates (0: no temporal reuse)",
                0,
                1000,
                self.history,
            ),
            int(
                "spatial",
                "Spatial neighbours (k)",
                "Neighbours' reservoirs combined per pixel (0: no spatial reuse)",
                0,
                MAX_SPATIAL as i64,
                self.spatial,
            ),
            float("radius", "Spatial radius", "Radius of the spatial neighbourhood, pixels", 1.0, 512.0, self.radius),
            choice(
                "bias_mode",
                "Combination",
                "biased: W = w_sum/(M p̂); unbiased: W = w_sum/(Z p̂), Z counting only the inputs that could have \
                 drawn the sample (a shadow ray from each)",
                BIAS_MODES,
                match self.bias_mode {
                    BiasMode::Biased => "biased",
                    BiasMode::Unbiased => "unbiased",
                },
            ),
            float(
                "depth_threshold",
                "Reject depth",
                "Neighbours whose camera distance differs by more than this fraction are not reused",
                0.0,
                10.0,
                self.depth_threshold,
            ),
            float(
                "normal_threshold",
                "Reject normal (degrees)",
                "Neighbours whose normal differs by more than this angle are not reused",
                0.0,
                180.0,
                self.normal_threshold_deg,
            ),
            int(
                "frames",
                "Frames",
                "ReSTIR frames per rendered frame (one step each, with temporal reuse from the one before), averaged",
                1,
                4096,
                self.frames,
            ),
            Param::ray_bias(self.bias),
            Param::seed("Seed of the candidates and neighbours", self.seed),
            Param {
                key: "inspect",
                label: "Read reservoirs back",
                help: "Read the final reservoirs back every frame for the per-pixel maps (off for timing)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(self.inspect),
            },
        ]
    }

    /// Check `value` against `key`'s range and set it.
    pub fn set(&mut self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        check_param("restir", &self.list(), key, value)?;
        match (key, value) {
            ("candidates", ParamValue::Int(v)) => self.candidates = *v as u32,
            ("source", ParamValue::Choice(v)) => {
                self.source = match v.as_str() {
                    "uniform" => Source::Uniform,
                    "tiles" => Source::Tiles,
                    _ => Source::Power,
                }
            }
            ("history", ParamValue::Int(v)) => self.history = *v as u32,
            ("spatial", ParamValue::Int(v)) => self.spatial = *v as u32,
            ("radius", ParamValue::Float(v)) => self.radius = *v,
            ("bias_mode", ParamValue::Choice(v)) => {
                self.bias_mode = if v == "biased" { BiasMode::Biased } else { BiasMode::Unbiased }
            }
            ("depth_threshold", ParamValue::Float(v)) => self.depth_threshold = *v,
            ("normal_threshold", ParamValue::Float(v)) => self.normal_threshold_deg = *v,
            ("frames", ParamValue::Int(v)) => self.frames = *v as u32,
            ("bias", ParamValue::Float(v)) => self.bias = *v,
            ("seed", ParamValue::Int(v)) => self.seed = *v as u32,
            ("inspect", ParamValue::Bool(v)) => self.inspect = *v,
            _ => unreachable!("check_param accepted an unknown key"),
        }
        Ok(())
    }
}
