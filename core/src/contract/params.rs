//! Parameters a technique describes for the UI and the CLI: their values, kinds and ranges, and the check
//! every `set_param` makes. No GPU code: the app, the CLI and the renderer services read these types.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// A camera a technique renders from (INSM's reference viewpoints): position, target, vertical field of view.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraPose {
    pub position: Vec3,
    pub target: Vec3,
    pub fov_y_deg: f32,
}

/// A parameter value.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ParamValue {
    Float(f32),
    Int(i64),
    Bool(bool),
    Choice(String),
    /// A list of cameras the user places (the app's gizmo moves their positions).
    Cameras(Vec<CameraPose>),
}

impl std::fmt::Display for ParamValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamValue::Float(v) => write!(f, "{v}"),
            ParamValue::Int(v) => write!(f, "{v}"),
            ParamValue::Bool(v) => write!(f, "{v}"),
            ParamValue::Choice(v) => write!(f, "{v}"),
            ParamValue::Cameras(v) => {
                let poses: Vec<String> = v
                    .iter()
                    .map(|c| {
                        let (p, t) = (c.position, c.target);
                        format!("{},{},{},{},{},{},{}", p.x, p.y, p.z, t.x, t.y, t.z, c.fov_y_deg)
                    })
                    .collect();
                write!(f, "{}", poses.join(";"))
            }
        }
    }
}

/// The kind and range of a parameter, enough for the UI to build a widget and for the CLI to parse text.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamKind {
    Float {
        min: f32,
        max: f32,
    },
    Int {
        min: i64,
        max: i64,
    },
    Bool,
    Choice(&'static [&'static str]),
    /// Up to `max` cameras. On the command line: `px,py,pz,tx,ty,tz,fov` per camera, separated by `;` (numbers may
    /// also be separated by spaces, which `sweep` needs: there commas separate swept values).
    Cameras {
        max: usize,
        /// A choice parameter and the value that makes the technique use these cameras (INSM: `placement` =
        /// `custom`); the app sets it when the user edits the list.
        selected_by: Option<(&'static str, &'static str)>,
    },
}

/// A technique parameter with its current value.
#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    pub key: &'static str,
    pub label: &'static str,
    pub help: &'static str,
    pub kind: ParamKind,
    pub value: ParamValue,
}

impl Param {
    /// The ray-origin offset every tracer has: along the normal, world units per metre of camera distance.
    pub fn ray_bias(value: f32) -> Param {
        Param {
            key: "bias",
            label: "Ray offset",
            help: "Ray origin offset along the normal, world units per metre of camera distance",
            kind: ParamKind::Float { min: 0.0, max: 0.1 },
            value: ParamValue::Float(value),
        }
    }

    /// The share of the scene's triangles a technique's shadow maps draw from a simplified copy of the scene
    /// ([`crate::scene::proxy`]; VALs and LightCluster, beyond their papers).
    pub fn map_proxy(keep: f32) -> Param {
        Param {
            key: "proxy",
            label: "Map geometry kept",
            help: "The share of the scene's triangles the shadow maps draw: below 1 a simplified copy of the scene \
                   (edge collapse of the opaque surfaces, cut-outs kept whole; beyond the technique's paper). The \
                   collapse also stops at 'Proxy error', and stopped there it is most reliable: set this low and \
                   the error bound decides. 1: the scene itself (the references never simplify)",
            kind: ParamKind::Float { min: 0.01, max: 1.0 },
            value: ParamValue::Float(keep),
        }
    }

    /// How far that copy's surface may move, as a share of the scene's diagonal; `help` says so, and what else
    /// follows from it in the technique.
    pub fn map_proxy_error(help: &'static str, value: f32) -> Param {
        Param {
            key: "proxy_error",
            label: "Proxy error",
            help,
            kind: ParamKind::Float { min: 0.0, max: 0.1 },
            value: ParamValue::Float(value),
        }
    }

    /// A random seed; `help` says what it seeds.
    pub fn seed(help: &'static str, value: u32) -> Param {
        Param {
            key: "seed",
            label: "Seed",
            help,
            kind: ParamKind::Int { min: 0, max: u32::MAX as i64 },
            value: ParamValue::Int(value as i64),
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ParamError {
    #[error("technique '{technique}' has no parameter '{key}' (it has: {known})")]
    Unknown { technique: String, key: String, known: String },
    #[error("parameter '{key}': {reason}")]
    Invalid { key: String, reason: String },
}

impl ParamKind {
    /// Parse and range-check text for this kind (`--param key=value` on the command line).
    pub fn parse(&self, key: &str, text: &str) -> Result<ParamValue, ParamError> {
        let invalid = |reason: String| ParamError::Invalid { key: key.to_string(), reason };
        match self {
            ParamKind::Float { .. } => {
                let v: f32 = text.trim().parse().map_err(|_| invalid(format!("'{text}' is not a number")))?;
                self.check(key, &ParamValue::Float(v))?;
                Ok(ParamValue::Float(v))
            }
            ParamKind::Int { .. } => {
                let v: i64 = text.trim().parse().map_err(|_| invalid(format!("'{text}' is not an integer")))?;
                self.check(key, &ParamValue::Int(v))?;
                Ok(ParamValue::Int(v))
            }
            ParamKind::Bool => match text.trim() {
                "true" | "on" | "1" | "yes" => Ok(ParamValue::Bool(true)),
                "false" | "off" | "0" | "no" => Ok(ParamValue::Bool(false)),
                _ => Err(invalid(format!("'{text}' is not on/off"))),
            },
            ParamKind::Choice(_) => {
                let v = ParamValue::Choice(text.trim().to_string());
                self.check(key, &v)?;
                Ok(v)
            }
            ParamKind::Cameras { .. } => {
                let mut cameras = Vec::new();
                for (i, item) in text.split(';').map(str::trim).filter(|s| !s.is_empty()).enumerate() {
                    let numbers: Result<Vec<f32>, _> = item
                        .split(|c: char| c == ',' || c.is_whitespace())
                        .filter(|n| !n.is_empty())
                        .map(|n| n.parse::<f32>())
                        .collect();
                    match numbers.as_deref() {
                        Ok([px, py, pz, tx, ty, tz, fov]) => cameras.push(CameraPose {
                            position: Vec3::new(*px, *py, *pz),
                            target: Vec3::new(*tx, *ty, *tz),
                            fov_y_deg: *fov,
                        }),
                        _ => {
                            return Err(invalid(format!(
                                "camera {} '{item}' is not px,py,pz,tx,ty,tz,fov (7 numbers)",
                                i + 1
                            )))
                        }
                    }
                }
                let v = ParamValue::Cameras(cameras);
                self.check(key, &v)?;
                Ok(v)
            }
        }
    }

    /// Check a value against this kind's type and range.
    pub fn check(&self, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        let invalid = |reason: String| Err(ParamError::Invalid { key: key.to_string(), reason });
        match (self, value) {
            (ParamKind::Float { min, max }, ParamValue::Float(v)) => {
                if !v.is_finite() || v < min || v > max {
                    return invalid(format!("{v} is outside {min}..={max}"));
                }
            }
            (ParamKind::Int { min, max }, ParamValue::Int(v)) => {
                if v < min || v > max {
                    return invalid(format!("{v} is outside {min}..={max}"));
                }
            }
            (ParamKind::Bool, ParamValue::Bool(_)) => {}
            (ParamKind::Cameras { max, .. }, ParamValue::Cameras(v)) => {
                if v.len() > *max {
                    return invalid(format!("{} cameras, at most {max}", v.len()));
                }
                for (i, c) in v.iter().enumerate() {
                    let ok = c.position.is_finite()
                        && c.target.is_finite()
                        && c.position.distance_squared(c.target) > 1e-12
                        && c.fov_y_deg.is_finite()
                        && c.fov_y_deg > 1.0
                        && c.fov_y_deg < 170.0;
                    if !ok {
                        return invalid(format!(
                            "camera {}: position and target must be finite and distinct, fov in 1..170 degrees",
                            i + 1
                        ));
                    }
                }
            }
            (ParamKind::Choice(options), ParamValue::Choice(v)) => {
                if !options.contains(&v.as_str()) {
                    return invalid(format!("'{v}' is not one of {}", options.join(", ")));
                }
            }
            _ => return invalid(format!("wrong type of value {value}")),
        }
        Ok(())
    }
}

/// Helper for `set_param`: find the parameter, check the value's range, or say what exists.
pub fn check_param(technique: &str, params: &[Param], key: &str, value: &ParamValue) -> Result<(), ParamError> {
    match params.iter().find(|p| p.key == key) {
        Some(p) => p.kind.check(key, value),
        None => Err(ParamError::Unknown {
            technique: technique.to_string(),
            key: key.to_string(),
            known: params.iter().map(|p| p.key).collect::<Vec<_>>().join(", "),
        }),
    }
}
