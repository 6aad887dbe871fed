//! LightCluster's parameters: the paper's (`d_init`, `z_far`, the view-adaptive scaling, the filter and its
//! samples), the Explain panel's one-cluster view, the simplified copy beyond the paper and the cube maps'
//! shared settings, with their keys, ranges and help texts.

use crate::services::cube_params::CubeMapParams;
use crate::technique::{Param, ParamKind, ParamValue};

/// Soft-shadow filter of a cluster.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Pcf,
    Pcss,
}

/// How cluster centers are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Centers {
    /// The paper's: in order of `L_att`, a light no center covers yet becomes one.
    Paper,
    /// Greedy covering: the light covering the most uncovered lights next (beyond the paper; [`super::cover`]).
    Cover,
}

#[derive(Clone, Debug, PartialEq)]
pub struct LightClusterParams {
    pub d_init: f32,
    /// How step 3 picks the centers (the same covering relation either way).
    pub centers: Centers,
    /// `z_far` of the view-adaptive scaling; 0 uses the camera's far plane.
    pub z_far: f32,
    pub adaptive: bool,
    pub filter: Filter,
    pub samples: u32,
    /// PCSS: in the blocker search and the filter, decide from the first half of the samples where they agree
    /// (all lit or all shadowed), and take the rest only where they disagree (beyond the paper; PCF keeps its
    /// fixed samples).
    pub early_out: bool,
    /// Cube-map resolution, bias, normal offset, batch memory.
    pub cube: CubeMapParams,
    /// Render the reference path when clustering merges nothing (the paper's worst case).
    pub fallback: bool,
    /// Draw only this cluster's soft visibility, as grey (the Explain panel's step 5); None: shade them all.
    pub visibility_of: Option<u32>,
    /// The share of the scene's triangles the cluster maps draw ([`crate::scene::proxy`]; 1: the scene itself).
    pub proxy: f32,
    /// How far the simplified surface may move from the scene's, as a share of the scene's diagonal.
    pub proxy_error: f32,
}

impl Default for LightClusterParams {
    fn default() -> Self {
        LightClusterParams {
            d_init: 0.5,
            centers: Centers::Paper,
            z_far: 0.0,
            adaptive: true,
            filter: Filter::Pcss,
            samples: 8,
            early_out: true,
            cube: CubeMapParams::default(),
            fallback: true,
            visibility_of: None,
            proxy: 1.0,
            proxy_error: 0.0005,
        }
    }
}

impl LightClusterParams {
    /// The parameters with their keys, ranges, help texts and current values.
    pub fn describe(&self) -> Vec<Param> {
        let mut params = vec![
            Param {
                key: "d_init",
                label: "d_init",
                help: "Initial minimum distance between cluster centers (world units)",
                kind: ParamKind::Float { min: 0.0, max: 1000.0 },
                value: ParamValue::Float(self.d_init),
            },
            Param {
                key: "centers",
                label: "Cluster centers",
                help: "paper: in order of range, a light no center covers becomes one; cover: the light covering the \
                       most lights not yet covered (beyond the paper: fewer clusters, each within d_min as before)",
                kind: ParamKind::Choice(&["paper", "cover"]),
                value: ParamValue::Choice(if self.centers == Centers::Cover { "cover" } else { "paper" }.into()),
            },
            Param {
                key: "z_far",
                label: "z_far",
                help: "Distance at which d_min reaches 0 (0: the camera's far plane)",
                kind: ParamKind::Float { min: 0.0, max: 1.0e6 },
                value: ParamValue::Float(self.z_far),
            },
            Param {
                key: "adaptive",
                label: "View-adaptive d_min",
                help: "Scale d_min by the distance to the camera (off: constant d_init, no flicker)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(self.adaptive),
            },
            Param {
                key: "filter",
                label: "Filter",
                help: "PCF (fixed width) or PCSS (contact-hardening)",
                kind: ParamKind::Choice(&["pcf", "pcss"]),
                value: ParamValue::Choice(if self.filter == Filter::Pcf { "pcf" } else { "pcss" }.into()),
            },
            Param {
                key: "samples",
                label: "Samples",
                help: "Poisson-disk samples per cluster and pixel",
                kind: ParamKind::Int { min: 1, max: 64 },
                value: ParamValue::Int(self.samples as i64),
            },
            Param {
                key: "early_out",
                label: "PCSS early out",
                help: "PCSS: stop after the first half of the samples when they agree (all lit or all shadowed)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(self.early_out),
            },
            Param {
                key: "fallback",
                label: "Reference when nothing clusters",
                help: "Use the reference path when every visible light is its own cluster (the paper's worst case)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(self.fallback),
            },
            Param {
                key: "visibility_of",
                label: "Visibility of one cluster",
                help: "-1: shade every cluster; k: draw only cluster k's soft visibility, in grey over the ambient \
                       light (white: lit, black: in its shadow; nothing beyond its C_att)",
                kind: ParamKind::Int { min: -1, max: 1 << 20 },
                value: ParamValue::Int(self.visibility_of.map_or(-1, i64::from)),
            },
            Param::map_proxy(self.proxy),
            Param::map_proxy_error(
                "proxy: the farthest the simplified surface may move from the scene's, as a share of the scene's \
                 diagonal (the simplification stops there, above the share asked for if need be); the lookups' \
                 depth bias grows by as much",
                self.proxy_error,
            ),
        ];
        params.extend(self.cube.params());
        params
    }

    /// Set one parameter ([`crate::technique::check_param`] has checked its key and value); an unknown key is the
    /// cube maps' or nothing.
    pub fn set(&mut self, key: &str, value: &ParamValue) {
        match (key, value) {
            ("d_init", ParamValue::Float(v)) => self.d_init = *v,
            ("centers", ParamValue::Choice(v)) => {
                self.centers = if v == "cover" { Centers::Cover } else { Centers::Paper }
            }
            ("z_far", ParamValue::Float(v)) => self.z_far = *v,
            ("adaptive", ParamValue::Bool(v)) => self.adaptive = *v,
            ("filter", ParamValue::Choice(v)) => self.filter = if v == "pcf" { Filter::Pcf } else { Filter::Pcss },
            ("samples", ParamValue::Int(v)) => self.samples = *v as u32,
            ("early_out", ParamValue::Bool(v)) => self.early_out = *v,
            ("fallback", ParamValue::Bool(v)) => self.fallback = *v,
            ("visibility_of", ParamValue::Int(v)) => self.visibility_of = u32::try_from(*v).ok(),
            ("proxy", ParamValue::Float(v)) => self.proxy = *v,
            ("proxy_error", ParamValue::Float(v)) => self.proxy_error = *v,
            _ => {
                let known = self.cube.set(key, value);
                debug_assert!(known, "check_param accepted an unknown key");
            }
        }
    }
}
