//! INSM's parameters: what they are, their defaults, how the UI and the CLI see and set them, and the
//! per-light maps' parameters they give (the lookup's bias).

use super::triangulate::MeshSettings;
use super::viewpoints::{self, Placement, Viewpoint};
use super::{MAX_INSM_RESOLUTION, MAX_VIEWPOINTS};
use crate::renderer::cube_params::CubeMapParams;
use crate::scene::Aabb;
use crate::technique::{Param, ParamKind, ParamValue};

/// The connectivity test's default ε (relative second difference of inverse depth). 0.02 was tried with the
/// lookup's sample bias and dilation (160x90, 1,024 lights, `--param epsilon=0.01,0.02`): at 128² it lowered
/// the error against the ray tracer on all seven scenes measured (the Dragon 0.57 / 0.57 %, the tori 3.50 /
/// 2.62 %, the conference room 7.49 / 6.78 %, the restaurant 1.37 / 1.27 %, the Cornell box 4.36 / 4.22 %,
/// Sponza 7.05 / 6.59 %, the arcade 9.25 / 8.34 %), but at 512² it was worse (the tori 0.77 / 2.55 %, the
/// Dragon 0.21 / 0.42 %), so that the error no longer fell with the resolution: a bridged step stands up to ε
/// of the depth from the surfaces it joins, which the one-sample bias absorbs at 128² and not once the samples
/// are four times finer. Not kept; an ε scaled to the sample's angular width would be the next thing to try.
pub const DEFAULT_EPSILON: f32 = 0.01;

/// INSM's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct InsmParams {
    /// Number of intermediate shadow maps `k`.
    pub viewpoints: u32,
    /// Side `w` of each intermediate shadow map.
    pub insm_resolution: u32,
    /// Relative second-order difference above which an edge is a depth discontinuity.
    pub epsilon: f32,
    /// Merge planar 8x8 tiles into a few triangles (the adaptive mesh, beyond the paper).
    pub adaptive: bool,
    /// Relative tolerance of the merge test (planes pass it to rounding; it bounds how far a merged tile
    /// strays from its samples).
    pub merge_epsilon: f32,
    /// Drop the triangles of a map whose corners another map reconstructs more finely (beyond the paper).
    pub drop_covered: bool,
    /// Move every sample at a cut edge half a sample across it along its surface, undoing the half-sample
    /// erosion of the reconstruction (beyond the paper; on by default).
    pub dilate: bool,
    pub placement: Placement,
    /// How far the `box` placement's cameras stand from the box centre, in multiples of the paper's (on the box).
    pub box_distance: f32,
    /// The lookup's depth bias in intermediate samples (at least `bias`): the mesh stands for the surface only to
    /// within about a sample (beyond the paper).
    pub bias_samples: f32,
    /// The per-light cube maps (`shadow_res` is the per-light resolution of the paper's Table 3).
    pub cube: CubeMapParams,
}

impl Default for InsmParams {
    fn default() -> Self {
        InsmParams {
            viewpoints: 10,
            insm_resolution: 128,
            epsilon: DEFAULT_EPSILON,
            adaptive: true,
            merge_epsilon: MeshSettings::default().merge_epsilon,
            drop_covered: true,
            dilate: true,
            placement: Placement::Box,
            box_distance: viewpoints::DEFAULT_BOX_DISTANCE,
            bias_samples: 1.0,
            cube: CubeMapParams { shadow_resolution: 512, ..CubeMapParams::default() },
        }
    }
}

impl InsmParams {
    /// The parameters as the UI and the CLI see them; `custom` is the custom viewpoints' list.
    pub fn describe(&self, custom: &[Viewpoint]) -> Vec<Param> {
        let mut params = vec![
            Param {
                key: "k",
                label: "Intermediate maps k",
                help: "Number of intermediate shadow maps (reference viewpoints)",
                kind: ParamKind::Int { min: 1, max: MAX_VIEWPOINTS as i64 },
                value: ParamValue::Int(self.viewpoints as i64),
            },
            Param {
                key: "insm_res",
                label: "INSM resolution",
                help: "Side of each intermediate shadow map in samples",
                kind: ParamKind::Int { min: 8, max: MAX_INSM_RESOLUTION as i64 },
                value: ParamValue::Int(self.insm_resolution as i64),
            },
            Param {
                key: "epsilon",
                label: "Discontinuity ε",
                help: "Relative second-order depth difference above which an edge is not triangulated",
                kind: ParamKind::Float { min: 0.0, max: 10.0 },
                value: ParamValue::Float(self.epsilon),
            },
            Param {
                key: "adaptive",
                label: "Adaptive mesh",
                help: "Merge planar 8x8 tiles of the depth images into a few triangles (beyond the paper; off: \
                       Algorithm 2's two triangles per 2x2 samples)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(self.adaptive),
            },
            Param {
                key: "merge_epsilon",
                label: "Merge tolerance",
                help: "Relative inverse-depth tolerance within which a tile's samples must lie on its plane to be \
                       merged (the adaptive mesh)",
                kind: ParamKind::Float { min: 0.0, max: 1.0 },
                value: ParamValue::Float(self.merge_epsilon),
            },
            Param {
                key: "drop_covered",
                label: "Drop covered triangles",
                help: "Drop the triangles of a map whose corners another map reconstructs more finely (beyond the \
                       paper; off: every map keeps all its triangles)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(self.drop_covered),
            },
            Param {
                key: "dilate",
                label: "Undo the erosion",
                help: "Move every sample at a depth discontinuity half a sample across it, along its surface: the \
                       reconstruction joins sample centres, so each surface ends half a sample short of its true \
                       edge and light leaks past it (beyond the paper; off: the paper's half-sample erosion)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(self.dilate),
            },
            Param {
                key: "placement",
                label: "Viewpoints",
                help: "box: the paper's bounding-box placement; inside: a ring inside the scene (rooms); custom: \
                       the viewpoints you placed",
                kind: ParamKind::Choice(Placement::NAMES),
                value: ParamValue::Choice(self.placement.name().to_string()),
            },
            Param {
                key: "box_distance",
                label: "Box cameras' distance",
                help: "How far the box placement's cameras stand from the scene's centre, in multiples of the \
                       paper's (1: on the bounding box, with a ~120° view that spends its samples on the image's \
                       borders; 4, the default: the same directions from four times as far, the box sampled \
                       almost uniformly)",
                kind: ParamKind::Float { min: 1.0, max: 16.0 },
                value: ParamValue::Float(self.box_distance),
            },
            Param {
                key: "bias_samples",
                label: "Mesh bias (samples)",
                help: "Depth bias of the shadow lookup in intermediate samples (the width of one at the viewpoints' \
                       mean distance to the scene's centre), when larger than the depth bias in metres: the mesh \
                       stands for the surface only to within about a sample (chords across curves and folds) and \
                       would shadow the surface it stands for (beyond the paper; 0: the depth bias alone)",
                kind: ParamKind::Float { min: 0.0, max: 8.0 },
                value: ParamValue::Float(self.bias_samples),
            },
            Param {
                key: "viewpoints",
                label: "Custom viewpoints",
                help: "The viewpoints of placement = custom: add them from the camera, move them with the gizmo",
                kind: ParamKind::Cameras { max: MAX_VIEWPOINTS, selected_by: Some(("placement", "custom")) },
                value: ParamValue::Cameras(custom.to_vec()),
            },
        ];
        let mut cube = self.cube.params();
        if let Some(p) = cube.iter_mut().find(|p| p.key == "shadow_res") {
            p.label = "Per-light resolution";
        }
        params.extend(cube);
        params
    }

    /// Set one parameter, already checked against [`InsmParams::describe`]; `custom` is the custom viewpoints.
    pub fn set(&mut self, custom: &mut Vec<Viewpoint>, key: &str, value: &ParamValue) {
        match (key, value) {
            ("k", ParamValue::Int(v)) => self.viewpoints = *v as u32,
            ("insm_res", ParamValue::Int(v)) => self.insm_resolution = *v as u32,
            ("epsilon", ParamValue::Float(v)) => self.epsilon = *v,
            ("adaptive", ParamValue::Bool(v)) => self.adaptive = *v,
            ("merge_epsilon", ParamValue::Float(v)) => self.merge_epsilon = *v,
            ("drop_covered", ParamValue::Bool(v)) => self.drop_covered = *v,
            ("dilate", ParamValue::Bool(v)) => self.dilate = *v,
            ("box_distance", ParamValue::Float(v)) => self.box_distance = *v,
            ("bias_samples", ParamValue::Float(v)) => self.bias_samples = *v,
            ("placement", ParamValue::Choice(v)) => {
                self.placement = Placement::from_name(v).expect("check_param checked the choice")
            }
            ("viewpoints", ParamValue::Cameras(v)) => *custom = v.clone(),
            _ => {
                let known = self.cube.set(key, value);
                debug_assert!(known, "check_param accepted an unknown key");
            }
        }
    }

    /// The per-light maps' parameters with the lookup's depth bias: the larger of `bias` and `bias_samples`
    /// intermediate samples ([`viewpoints::mean_sample_width`] of `views` at `resolution`).
    pub fn lookup_params(&self, views: &[Viewpoint], bounds: &Aabb, resolution: u32) -> CubeMapParams {
        let mesh_bias = self.bias_samples * viewpoints::mean_sample_width(views, bounds, resolution);
        let bias_world = if mesh_bias.is_finite() { self.cube.bias_world.max(mesh_bias) } else { self.cube.bias_world };
        CubeMapParams { bias_world, ..self.cube.clone() }
    }
}
