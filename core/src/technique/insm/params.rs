//! INSM's parameters: what they are, their defaults, how the UI and the CLI see and set them, and the
//! per-light maps' parameters they give (the lookup's bias).

use super::triangulate::MeshSettings;
use super::viewpoints::{self, Placement, Viewpoint};
use crate::scene::Aabb;
use crate::services::cube_params::CubeMapParams;
use crate::technique::{Param, ParamKind, ParamValue};

/// Most intermediate shadow maps (the paper uses 6 to 14).
pub const MAX_VIEWPOINTS: usize = 16;
/// Largest intermediate shadow map side (the paper's Table 2 goes to 512).
pub const MAX_INSM_RESOLUTION: u32 = 512;

/// The connectivity test's default ε (relative second difference of inverse depth) at [`EPSILON_RESOLUTION`]²
/// samples for the `box` and `custom` placements ([`InsmParams::epsilon_at`] for other resolutions). A step
/// under about ε of the depth is bridged, and the lookup's bias and push absorb about a sample's footprint,
/// which shrinks as 1 / resolution: so ε does too, down to [`EPSILON_FLOOR`] (at 512², 0.005 cut real
/// surfaces: the conference room 2.85 -> 3.40 %). 0.02 at every resolution lowered the error at 128² on all
/// seven scenes measured but raised it at 512² (the tori 0.77 -> 2.55 %, the Dragon 0.21 -> 0.42 %); scaled as
/// √(128 / resolution) it put the Dragon at 1.23 % at 256² against 0.60 % with this rule (issue 23, measured in
/// docs/techniques/insm.md).
pub const DEFAULT_EPSILON: f32 = 0.02;

/// The same for the `inside` and `walls` placements, whose 100° views see surfaces from a metre to across the
/// room: 0.04 at 128² lowered the error on four of the five interiors against 0.02 (the conference room 6.40 ->
/// 5.74 %, Sponza 6.50 -> 6.23 %, the Cornell box 4.16 -> 4.00 %, the arcade 8.45 -> 8.41 %; the restaurant
/// 1.24 -> 1.28 %), and 0.03 / 0.05 less in all (docs/techniques/insm.md). The box placement's scenes went the
/// other way (the tori 2.81 -> 3.12 %, the Dragon 0.59 -> 0.71 % at 0.03).
pub const DEFAULT_EPSILON_INSIDE: f32 = 0.04;

/// The tolerance for a steep edge (beyond the paper, `triangulate::SampledImage::edge_connected`): an edge
/// across which the surface is seen at more than [`DEFAULT_STEEP_ANGLE`] from face-on is cut above this
/// (instead of ε), at 128² and scaled as ε is; it matters only below ε, i.e. for the inside placements, whose
/// larger ε keeps curved surfaces (chairs, curtains) whole but also joined the arcade's columns, seen down its
/// hall, to one another and to the walls behind them: a curtain that closed its arches under the scene's own
/// 80 lights (shadow error against the ray tracer 20.3 % with ε 0.04, 6.7 % with 0.02, 6.5 % with this;
/// docs/techniques/insm.md). The box placement's ε: steep edges are held to what the box views hold them to.
pub const DEFAULT_STEP_EPSILON: f32 = DEFAULT_EPSILON;

/// How far from face-on a surface is seen (degrees) before its edges are steep ([`DEFAULT_STEP_EPSILON`]).
/// Measured at 60 / 70 / 75 / 79 / 82 / 84.5° (160x90, 128², against the ray tracer): the arcade with its own
/// lights 6.6 / 6.5 / 6.5 / 6.5 / 16.7 / 20.3 %, the conference room (1,024 lights) 6.03 / 5.80 / 5.72 / 5.67 /
/// 5.66 / 5.65 % (5.74 % without the rule), Sponza 6.31 / 6.33 / 6.24 / 6.24 / 6.23 / 6.22 % (6.23 %): the
/// joins the arcade needed cut lie beyond 79°; 75° keeps a margin below that and costs the others nothing.
pub const DEFAULT_STEEP_ANGLE: f32 = 75.0;

/// The smallest ε the resolution scaling gives (a smaller `epsilon` is used as it is).
pub const EPSILON_FLOOR: f32 = 0.01;

/// The lookup's depth bias in intermediate samples of the viewpoints' mean width, and the push of every mesh
/// vertex in widths of its own sample (a depth bias that follows how coarsely each surface was sampled: a wall
/// seen from across a room needs more than a chair seen from nearby). Half a mean sample plus 1.5 of its own
/// replaced one mean sample (issue 23): with ε 0.02 at 128², 160x90, 1,024 lights, against the ray tracer, the
/// conference room 6.78 % with one mean sample, 6.46 % with a push of 2 alone, 6.40 % with these
/// (docs/techniques/insm.md).
pub const DEFAULT_BIAS_SAMPLES: f32 = 0.5;
pub const DEFAULT_PUSH_SAMPLES: f32 = 1.5;

/// The resolution at which `epsilon` is given ([`InsmParams::epsilon_at`]).
pub const EPSILON_RESOLUTION: u32 = 128;

/// INSM's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct InsmParams {
    /// Number of intermediate shadow maps `k`.
    pub viewpoints: u32,
    /// Side `w` of each intermediate shadow map.
    pub insm_resolution: u32,
    /// Relative second-order difference above which an edge is a depth discontinuity.
    pub epsilon: f32,
    /// The same for the `inside` and `walls` placements.
    pub epsilon_inside: f32,
    /// The tolerance for a steep edge ([`DEFAULT_STEP_EPSILON`]), at 128².
    pub step_epsilon: f32,
    /// The angle from face-on beyond which an edge is steep, degrees (90: none is).
    pub steep_angle: f32,
    /// Merge planar blocks of neighbourhoods into a few triangles (the adaptive mesh, beyond the paper).
    pub adaptive: bool,
    /// The smallest block the adaptive mesh merges, neighbourhoods a side (2, 4 or 8: whole tiles only).
    pub merge_block: u32,
    /// Relative tolerance of the merge test (planes pass it to rounding; it bounds how far a merged block
    /// strays from its samples).
    pub merge_epsilon: f32,
    /// Drop the triangles of a map whose corners another map reconstructs more finely (beyond the paper).
    pub drop_covered: bool,
    /// The share of the reconstructed meshes' triangles the per-light maps draw (1: as triangulated; below 1
    /// simplified by edge collapse, beyond the paper).
    pub simplify: f32,
    /// How far the simplified surface may move from the triangulated one, as a share of the scene's diagonal.
    pub simplify_error: f32,
    /// Move every sample at a cut edge half a sample across it along its surface, undoing the half-sample
    /// erosion of the reconstruction (beyond the paper; on by default).
    pub dilate: bool,
    pub placement: Placement,
    /// How far the `box` placement's cameras stand from the box centre, in multiples of the paper's (on the box).
    pub box_distance: f32,
    /// The lookup's depth bias in intermediate samples (at least `bias`): the mesh stands for the surface only to
    /// within about a sample (beyond the paper).
    pub bias_samples: f32,
    /// Each mesh vertex drawn this many of its own samples' widths further from the light (beyond the paper).
    pub push_samples: f32,
    /// Also render the meshes from the viewpoints, for inspection beside the intermediate images (the image does
    /// not change; the frame takes k more views).
    pub mesh_views: bool,
    /// The per-light cube maps (`shadow_res` is the per-light resolution of the paper's Table 3).
    pub cube: CubeMapParams,
}

impl Default for InsmParams {
    fn default() -> Self {
        InsmParams {
            viewpoints: 10,
            insm_resolution: 128,
            epsilon: DEFAULT_EPSILON,
            epsilon_inside: DEFAULT_EPSILON_INSIDE,
            step_epsilon: DEFAULT_STEP_EPSILON,
            steep_angle: DEFAULT_STEEP_ANGLE,
            adaptive: true,
            merge_block: 2,
            merge_epsilon: MeshSettings::default().merge_epsilon,
            drop_covered: true,
            simplify: 1.0,
            simplify_error: 0.0005,
            dilate: true,
            placement: Placement::Auto,
            box_distance: viewpoints::DEFAULT_BOX_DISTANCE,
            bias_samples: DEFAULT_BIAS_SAMPLES,
            push_samples: DEFAULT_PUSH_SAMPLES,
            mesh_views: false,
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
                help: "Relative second-order depth difference above which an edge is not triangulated, at 128² \
                       samples, for the box and custom placements (scaled as 128 / resolution for other \
                       resolutions, down to 0.01)",
                kind: ParamKind::Float { min: 0.0, max: 10.0 },
                value: ParamValue::Float(self.epsilon),
            },
            Param {
                key: "epsilon_inside",
                label: "Discontinuity ε (inside)",
                help: "The same for the inside and walls placements, whose wide views see surfaces from a metre to \
                       across the room",
                kind: ParamKind::Float { min: 0.0, max: 10.0 },
                value: ParamValue::Float(self.epsilon_inside),
            },
            Param {
                key: "step_epsilon",
                label: "Steep-edge ε",
                help: "The discontinuity ε of a steep edge (a surface seen at more than the steep angle from \
                       face-on), at 128² samples, scaled as ε; it matters only below ε (beyond the paper; the inside \
                       placements: curved surfaces keep their larger ε)",
                kind: ParamKind::Float { min: 0.0, max: 10.0 },
                value: ParamValue::Float(self.step_epsilon),
            },
            Param {
                key: "steep_angle",
                label: "Steep angle (°)",
                help: "How far from face-on (degrees) the surface across an edge is seen before the edge is steep \
                       and held to the steep-edge ε (90: no edge is)",
                kind: ParamKind::Float { min: 0.0, max: 90.0 },
                value: ParamValue::Float(self.steep_angle),
            },
            Param {
                key: "adaptive",
                label: "Adaptive mesh",
                help: "Merge planar blocks of the depth images (a quadtree in each 8x8 tile) into a few triangles \
                       (beyond the paper; off: Algorithm 2's two triangles per 2x2 samples)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(self.adaptive),
            },
            Param {
                key: "merge_block",
                label: "Smallest merged block",
                help: "The smallest planar block of neighbourhoods the adaptive mesh merges: 2x2, 4x4, or 8x8 \
                       (whole tiles only, as before the quadtree)",
                kind: ParamKind::Choice(MERGE_BLOCKS),
                value: ParamValue::Choice(format!("{0}x{0}", self.merge_block)),
            },
            Param {
                key: "merge_epsilon",
                label: "Merge tolerance",
                help: "Relative inverse-depth tolerance within which a block's samples must lie on its plane to \
                       be merged (the adaptive mesh)",
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
                key: "simplify",
                label: "Mesh kept",
                help: "The share of the reconstructed meshes' triangles the per-light maps draw: below 1 the meshes \
                       are simplified by edge collapse (a border only along itself; beyond the paper), the collapse stopping \
                       at 'Simplify error' too: set this low and let the error bound decide. 1: as triangulated \
                       (the wireframe overlay always shows the triangulation). The simplification is CPU work in \
                       every frame: it pays where drawing triangles is the cost (a software rasterizer), and on \
                       a real GPU, where the maps' texels are, it can cost more than it saves",
                kind: ParamKind::Float { min: 0.01, max: 1.0 },
                value: ParamValue::Float(self.simplify),
            },
            Param {
                key: "simplify_error",
                label: "Simplify error",
                help: "simplify: the farthest the simplified surface may move from the triangulated one, as a \
                       share of the scene's diagonal",
                kind: ParamKind::Float { min: 0.0, max: 0.1 },
                value: ParamValue::Float(self.simplify_error),
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
                key: "mesh_views",
                label: "Meshes from the viewpoints",
                help: "Also draw the meshes seen from each viewpoint, beside the intermediate depth images in the \
                       Shadow maps panel, to see what the triangulation kept, bridged or lost (inspection: the \
                       image does not change; the frame's time includes k more views)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(self.mesh_views),
            },
            Param {
                key: "placement",
                label: "Viewpoints",
                help: "auto: inside for an enclosed interior, box for an object (the scene decides); box: the \
                       paper's bounding-box placement; inside: a ring inside the scene (rooms); walls: inside, with \
                       the cameras that stand behind a wall moved in front of it (rooms that do not fill their box: \
                       aisles, galleries); custom: the viewpoints you placed",
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
                key: "push_samples",
                label: "Mesh push (own samples)",
                help: "Each vertex of the meshes drawn into the per-light maps this many widths of its own sample \
                       further from the light: a depth bias that follows how coarsely each surface was sampled \
                       (beyond the paper; 0: off)",
                kind: ParamKind::Float { min: 0.0, max: 8.0 },
                value: ParamValue::Float(self.push_samples),
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
            ("epsilon_inside", ParamValue::Float(v)) => self.epsilon_inside = *v,
            ("step_epsilon", ParamValue::Float(v)) => self.step_epsilon = *v,
            ("steep_angle", ParamValue::Float(v)) => self.steep_angle = *v,
            ("adaptive", ParamValue::Bool(v)) => self.adaptive = *v,
            ("merge_block", ParamValue::Choice(v)) => {
                self.merge_block = 1 << (1 + MERGE_BLOCKS.iter().position(|b| b == v).expect("check_param checked it"))
            }
            ("merge_epsilon", ParamValue::Float(v)) => self.merge_epsilon = *v,
            ("drop_covered", ParamValue::Bool(v)) => self.drop_covered = *v,
            ("simplify", ParamValue::Float(v)) => self.simplify = *v,
            ("simplify_error", ParamValue::Float(v)) => self.simplify_error = *v,
            ("dilate", ParamValue::Bool(v)) => self.dilate = *v,
            ("mesh_views", ParamValue::Bool(v)) => self.mesh_views = *v,
            ("box_distance", ParamValue::Float(v)) => self.box_distance = *v,
            ("bias_samples", ParamValue::Float(v)) => self.bias_samples = *v,
            ("push_samples", ParamValue::Float(v)) => self.push_samples = *v,
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
        let width = viewpoints::mean_sample_width(views, bounds, resolution);
        let mesh_bias = self.bias_samples * width;
        let bias_world = if mesh_bias.is_finite() { self.cube.bias_world.max(mesh_bias) } else { self.cube.bias_world };
        CubeMapParams { bias_world, ..self.cube.clone() }
    }

    /// How far a mesh vertex moves away from a light per unit of its view depth: `push_samples` widths of a
    /// sample of `resolution`² over the viewpoints' mean field of view.
    pub fn push_per_depth(&self, views: &[Viewpoint], resolution: u32) -> f32 {
        if views.is_empty() || resolution == 0 {
            return 0.0;
        }
        let span: f32 =
            views.iter().map(|v| 2.0 * (0.5 * v.fov_y_deg.to_radians()).tan()).sum::<f32>() / views.len() as f32;
        let push = self.push_samples * span / resolution as f32;
        if push.is_finite() {
            push.max(0.0)
        } else {
            0.0
        }
    }

    /// The connectivity test's ε for `resolution`² maps: `epsilon` (`epsilon_inside` for the inside and walls
    /// placements) is given at 128² (`EPSILON_RESOLUTION`) and scales as 128 / resolution, down to
    /// `EPSILON_FLOOR` (0.02 at 128², 0.04 at 64², 0.01 from 256² up; inside 0.04, 0.08, 0.02 at 256², 0.01
    /// at 512²).
    pub fn epsilon_at(&self, resolution: u32) -> f32 {
        // `Auto` is resolved before the meshes are built (`Insm::prepare`); unresolved it is the box placement.
        let e = match self.placement {
            Placement::Inside | Placement::Walls => self.epsilon_inside,
            Placement::Box | Placement::Custom | Placement::Auto => self.epsilon,
        };
        scaled_epsilon(e, resolution)
    }

    /// The step tolerance for `resolution`² maps: `step_epsilon` scaled as [`Self::epsilon_at`] scales ε, and
    /// never above it (0.02 at 128², 0.01 from 256² up).
    pub fn step_epsilon_at(&self, resolution: u32) -> f32 {
        scaled_epsilon(self.step_epsilon, resolution).min(self.epsilon_at(resolution))
    }

    /// The steepness of a map of `fov_y_deg` and `resolution`² ([`triangulate::steep_slope`] at `steep_angle`).
    pub fn steep_slope(&self, fov_y_deg: f32, resolution: u32) -> f32 {
        super::triangulate::steep_slope(self.steep_angle, fov_y_deg, resolution)
    }

    /// The connectivity test's tolerances and the mesh's other settings for `resolution`² maps.
    pub fn mesh_settings(&self, resolution: u32) -> MeshSettings {
        MeshSettings {
            epsilon: self.epsilon_at(resolution),
            step_epsilon: self.step_epsilon_at(resolution),
            adaptive: self.adaptive,
            merge_epsilon: self.merge_epsilon,
            min_block: self.merge_block,
            drop_covered: self.drop_covered,
        }
    }
}

/// The choices of `merge_block`: 2, 4 and 8 neighbourhoods a side.
const MERGE_BLOCKS: &[&str] = &["2x2", "4x4", "8x8"];

/// A tolerance `e` given at 128² for `resolution`² maps: scaled as 128 / resolution, down to `EPSILON_FLOOR`
/// (a smaller `e` as it is).
fn scaled_epsilon(e: f32, resolution: u32) -> f32 {
    let scaled = e * EPSILON_RESOLUTION as f32 / resolution.max(1) as f32;
    scaled.max(e.min(EPSILON_FLOOR))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn epsilon_is_given_at_128_per_placement_and_scales_with_the_sample_width_down_to_a_floor() {
        let p = InsmParams { epsilon: 0.02, epsilon_inside: 0.04, placement: Placement::Box, ..InsmParams::default() };
        assert_eq!(InsmParams::default().placement, Placement::Auto, "the scene decides by default");
        assert_eq!(InsmParams { placement: Placement::Auto, ..p.clone() }.epsilon_at(128), 0.02, "unresolved: box");
        assert_eq!(p.epsilon_at(EPSILON_RESOLUTION), 0.02);
        assert!((p.epsilon_at(64) - 0.04).abs() < 1e-7);
        assert!((p.epsilon_at(32) - 0.08).abs() < 1e-7);
        assert!((p.epsilon_at(256) - 0.01).abs() < 1e-7);
        assert!((p.epsilon_at(512) - 0.01).abs() < 1e-7);
        assert!((p.epsilon_at(192) - 0.02 * 128.0 / 192.0).abs() < 1e-7);
        for placement in [Placement::Inside, Placement::Walls] {
            let q = InsmParams { placement, ..p.clone() };
            assert_eq!(q.epsilon_at(128), 0.04);
            assert!((q.epsilon_at(256) - 0.02).abs() < 1e-7);
            assert!((q.epsilon_at(512) - 0.01).abs() < 1e-7);
            assert!((q.epsilon_at(1024) - 0.01).abs() < 1e-7);
        }
        assert_eq!(InsmParams { placement: Placement::Custom, ..p.clone() }.epsilon_at(128), 0.02);
        // A value under the floor is used as it is; zero stays zero (the reconstruction off); a zero
        // resolution does not divide by zero.
        assert!((InsmParams { epsilon: 0.004, ..p.clone() }.epsilon_at(512) - 0.004).abs() < 1e-9);
        assert_eq!(InsmParams { epsilon: 0.0, ..p.clone() }.epsilon_at(256), 0.0);
        assert!(p.epsilon_at(0).is_finite());
    }

    #[test]
    fn the_step_tolerance_scales_as_epsilon_and_never_exceeds_it() {
        let p = InsmParams {
            epsilon: 0.02,
            epsilon_inside: 0.04,
            step_epsilon: 0.02,
            placement: Placement::Box,
            ..InsmParams::default()
        };
        // The box placement: the step tolerance is its ε at every resolution (no change to its meshes).
        for r in [64, 128, 256, 512] {
            assert_eq!(p.step_epsilon_at(r), p.epsilon_at(r), "{r}");
        }
        // The inside placements: half their ε at 128², the floor from 256² up, as ε is at 512².
        let q = InsmParams { placement: Placement::Inside, ..p.clone() };
        assert_eq!((q.epsilon_at(128), q.step_epsilon_at(128)), (0.04, 0.02));
        assert!((q.step_epsilon_at(64) - 0.04).abs() < 1e-7);
        assert!((q.step_epsilon_at(256) - 0.01).abs() < 1e-7 && (q.step_epsilon_at(512) - 0.01).abs() < 1e-7);
        // Above ε it is ε (the paper's test alone); the settings carry both.
        let loose = InsmParams { step_epsilon: 1.0, ..q.clone() };
        assert_eq!(loose.step_epsilon_at(128), loose.epsilon_at(128));
        let m = q.mesh_settings(128);
        assert_eq!((m.epsilon, m.step_epsilon, m.connectivity().step), (0.04, 0.02, 0.02));
    }

    #[test]
    fn the_lookup_offsets_and_the_push_follow_the_sample_width() {
        let bounds = Aabb { min: glam::Vec3::splat(-5.0), max: glam::Vec3::splat(5.0) };
        let views = viewpoints::select(Placement::Inside, &bounds, &[], 10, 4.0, None);
        let width = viewpoints::mean_sample_width(&views, &bounds, 128);
        assert!(width > 0.0 && width.is_finite());
        let p = InsmParams { bias_samples: 0.0, push_samples: 3.0, ..InsmParams::default() };
        assert_eq!(p.lookup_params(&views, &bounds, 128).bias_world, p.cube.bias_world);
        // The inside placement's views are 100°: a sample at depth z is z * 2 tan 50° / 128 wide.
        let push = p.push_per_depth(&views, 128);
        let expected = 3.0 * 2.0 * 50f32.to_radians().tan() / 128.0;
        assert!((push - expected).abs() < 1e-6 * expected, "{push} vs {expected}");
        assert_eq!(p.push_per_depth(&[], 128), 0.0);
        assert_eq!(InsmParams { push_samples: 0.0, ..p }.push_per_depth(&views, 128), 0.0);
    }
}
