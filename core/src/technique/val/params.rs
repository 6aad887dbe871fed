//! VAL's parameters: what they are, their defaults, and how the UI and the CLI see and set them.

use crate::technique::{Param, ParamKind, ParamValue};

/// Most VALs per frame (the per-pixel visibility array of `val/gather.wgsl`).
pub const MAX_VALS: usize = 256;

/// Where a VAL's map stands (`centre`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Centre {
    /// The VAL's mean, moved off its surface along its normal (the paper's).
    Mean,
    /// The member VPL nearest the mean, moved off its own surface (beyond the paper,
    /// [`super::centre::map_centres`]).
    Member,
    /// `Member` for a VAL of at most `member_share` of the VPLs, `Mean` for a larger one (the default).
    Auto,
}

impl Centre {
    pub const NAMES: &'static [&'static str] = &["auto", "mean", "member"];

    pub fn name(self) -> &'static str {
        match self {
            Centre::Mean => "mean",
            Centre::Member => "member",
            Centre::Auto => "auto",
        }
    }

    pub fn from_name(name: &str) -> Option<Centre> {
        match name {
            "mean" => Some(Centre::Mean),
            "member" => Some(Centre::Member),
            "auto" => Some(Centre::Auto),
            _ => None,
        }
    }
}

/// `centre = auto`'s limit: a VAL of at most 1/32 of the frame's VPLs (32 of 1,024) has its map at a member VPL.
/// A small VAL (a patch, the VPLs around a column's foot or on both sides of an arch) is best seen from a point
/// on a surface it lies on: its mean floats in the open or sits in the column. A large one (several surfaces, a
/// large share of the light: the first bisections) is better seen from its mean in the open. Measured
/// (docs/techniques/val.md, FLIP against per-VPL maps at M = 2...256): every VAL at a member made Sponza's and the
/// conference room's error rise from M = 2 to 8 and fall lower from M = 30-96 up; with 16 VPLs Sponza fell at
/// every M and the conference room stayed flat from 2 to 4; with 32 both fall at every M.
pub const DEFAULT_MEMBER_SHARE: f32 = 1.0 / 32.0;

/// The technique's parameters; their keys, ranges and help are in [`ValParams::describe`].
#[derive(Clone, Debug, PartialEq)]
pub struct ValParams {
    /// `M`.
    pub vals: u32,
    pub iterations: u32,
    pub w_x: f32,
    pub w_a: f32,
    /// `L`, the length position distances are divided by, as a fraction of the scene's diagonal.
    pub length_fraction: f32,
    /// `pcss`, `cssm` or `hard`.
    pub visibility: String,
    /// `Delta`, each VAL's size in the penumbra estimate: `bounds`, the diagonal of its VPLs' bounding rectangle
    /// (section 6), or `spread`, the side of the square with its VPLs' flux-weighted second moment
    /// ([`super::kmeans::spread_sizes`], beyond the paper).
    pub size: String,
    pub shadow_resolution: u32,
    /// Side of the blocker-search and PCF grid.
    pub grid: u32,
    pub bias_world: f32,
    pub normal_offset_texels: f32,
    /// Bias of a filter sample per texel of its offset, in texel footprints at the receiver.
    pub slope_bias: f32,
    /// Interleaved sampling (section 6), its ratio estimator (not with `solo`: the ratio's sum takes every VPL,
    /// solo one VAL's) and block.
    pub interleave: crate::services::vpl_gather::Interleave,
    /// Start k-means from the previous frame's VALs (the variant the paper rejects, Fig. 8). With `split` on,
    /// k-means makes `ceil(kmeans_share * M)` VALs (one by default), so it changes little or nothing then.
    pub warm_start: bool,
    pub vpls_per_step: u32,
    /// Show one VAL's contribution alone (its VPLs with its soft visibility; -1 = all VALs).
    pub solo: i32,
    /// `gpu` (the paper's GPU k-means, `val/kmeans.wgsl`) or `cpu` (the twin, [`super::kmeans::cluster`]).
    pub clustering: String,
    /// CSSM: the receiver's normalised depth is moved toward the VAL by this share of the map's depth range.
    pub cssm_offset: f32,
    /// Without interleaving, a VAL carrying less than this share of a pixel's unshadowed indirect light gets one
    /// depth test there instead of soft visibility (beyond the paper; 0: every VAL soft).
    pub soft_share: f32,
    /// Without interleaving, walk the VALs and their member lists and skip a VAL none of whose VPLs can light
    /// the pixel ([`super::cull`], beyond the paper; the same sum, fewer VPL evaluations); off: every pixel
    /// evaluates every VPL, as the paper's shading does.
    pub skip_unlit: bool,
    /// Refine the k-means result by bisecting VALs across surfaces ([`super::split`]); off: the paper's k-means
    /// alone.
    pub split: bool,
    /// [`super::split`]: the share of `M` the k-means clusters into before bisection fills up to `M`.
    pub kmeans_share: f32,
    /// [`super::split`]: which VAL is bisected next, `light` (largest light-weighted distance), `flux`
    /// (largest flux-weighted error, the default before) or `rule` (rule breakers first).
    pub rank: String,
    /// [`super::split`]: while there are fewer VALs than this, the next bisection is the one that lowers the
    /// flux-weighted error most (then `rank` decides).
    pub gain_until: u32,
    /// [`super::split`]: ranked by light or flux, a VAL's key counts `1 + hidden_weight * h` times, `h` the
    /// share of its VPLs' luminance its map's centre does not see (a ray each, the scene's BVH; 0: off).
    pub hidden_weight: f32,
    /// Where a VAL's map stands ([`Centre`]).
    pub centre: Centre,
    /// With `centre = auto`: a VAL of at most this share of the frame's VPLs stands at a member.
    pub member_share: f32,
    /// A member centre with geometry right beside it moves to a clearer member nearby ([`super::centre`],
    /// beyond the paper; rays against the scene's BVH); off: always the member nearest the mean.
    pub clearance: bool,
    /// [`super::split`]: a VAL whose normal cone is wider than this (degrees) is bisected by normal.
    pub max_cone_degrees: f32,
    /// [`super::split`]: the largest spread of a VAL's VPLs along its normal, as a share of its size.
    pub max_depth: f32,
    /// The share of the scene's triangles the VAL maps draw ([`crate::scene::proxy`]; 1: the scene itself).
    pub proxy: f32,
    /// How far the proxy's surface may move from the scene's, as a share of the scene's diagonal.
    pub proxy_error: f32,
    /// The longest triangle edge the VAL maps draw, as a share of the scene's diagonal (0: as they are).
    pub max_edge: f32,
}

impl Default for ValParams {
    fn default() -> Self {
        ValParams {
            vals: 30,
            iterations: 10,
            w_x: 0.7,
            w_a: 0.3,
            // The paper weighs raw distances in its scenes' units (metres); a tenth of the diagonal is a room's
            // size in Sponza and a third of a metre in the Cornell box. Measured against per-VPL maps (FLIP,
            // 30 VALs, 160x90): Cornell 0.0087 -> 0.0024, Sponza 0.28 -> 0.20, conference 0.19 -> 0.17 from
            // L = the diagonal to L = a tenth of it.
            length_fraction: 0.1,
            visibility: "pcss".into(),
            // Measured (docs/techniques/val.md, twenty-second session): with the light rank `spread` lowers the
            // error at nearly every M on Sponza, the conference room and the Cornell box, on two other views of
            // each real scene and on the arcade and the restaurant, and against exact VPL visibility too; `bounds`
            // is the paper's.
            size: "spread".into(),
            shadow_resolution: 256,
            grid: 5,
            bias_world: 0.01,
            normal_offset_texels: 1.5,
            slope_bias: 1.0,
            interleave: Default::default(),
            warm_start: false,
            vpls_per_step: crate::vpl::MAX_VPLS,
            clustering: "gpu".into(),
            solo: -1,
            cssm_offset: 0.12,
            // Measured (docs/techniques/val.md, twenty-second session): 0.02 lowers FLIP against per-VPL maps at
            // nearly every M on the three scenes (and against exact VPL visibility on the real ones) with a fifth
            // of the filter taps; 0.05 about the same.
            soft_share: 0.02,
            skip_unlit: true,
            split: true,
            kmeans_share: 0.0,
            // Measured with `rank = flux` (docs/techniques/val.md): 40 degrees splits a room corner into its
            // walls; 30-35 also split the curved chairs' VALs by normal (a step up at M = 16-30 on the
            // conference room), 45 left Sponza 0.03 higher at M = 128-160, 180 (off) leaves the Cornell box's
            // corner VALs cut across by depth (not monotone at M = 4-16).
            // Measured (docs/techniques/val.md, twenty-second session): `light` lowers the error at nearly every M
            // from 30 up on Sponza and the conference room (and on two other views of each) and keeps it falling.
            rank: "light".into(),
            // Measured (docs/techniques/val.md): 16 makes Sponza's error fall at every M and leaves every M from
            // 64 up as `flux` alone has it on the three scenes; 32 moves M = 64.
            gain_until: 16,
            // Measured (docs/techniques/val.md, twentieth session) at 0, 1, 2, 3, 4 and 8: 2 lowers Sponza's error
            // at every M from 96 up (0.0781 at M = 192 against 0.0830) and keeps it falling at every M; the
            // conference room's rises 2-5 % at M = 30-96 and 224, falls at 128-192 and 256; the Cornell box's is
            // unchanged.
            hidden_weight: 2.0,
            centre: Centre::Auto,
            clearance: true,
            member_share: DEFAULT_MEMBER_SHARE,
            max_cone_degrees: 40.0,
            max_depth: 0.1,
            proxy: 1.0,
            proxy_error: 0.0005,
            max_edge: crate::scene::proxy::DEFAULT_MAX_EDGE,
        }
    }
}

const VISIBILITY_CHOICES: &[&str] = &["pcss", "cssm", "hard"];
const SIZE_CHOICES: &[&str] = &["bounds", "spread"];
const CLUSTERING_CHOICES: &[&str] = &["gpu", "cpu"];
const RANK_CHOICES: &[&str] = &["light", "flux", "rule"];

impl ValParams {
    /// The parameters as the UI and the CLI see them.
    pub fn describe(&self) -> Vec<Param> {
        let p = self;
        let mut list = vec![
            Param {
                key: "vals",
                label: "VALs (M)",
                help: "Clusters of VPLs, each a soft-shadowing area light (clamped to the VPL count)",
                kind: ParamKind::Int { min: 1, max: MAX_VALS as i64 },
                value: ParamValue::Int(p.vals as i64),
            },
            Param {
                key: "clustering",
                label: "k-means on",
                help: "gpu: the paper's scatter passes (fixed-point atomic sums); cpu: the twin (also with warm start)",
                kind: ParamKind::Choice(CLUSTERING_CHOICES),
                value: ParamValue::Choice(p.clustering.clone()),
            },
            Param {
                key: "iterations",
                label: "k-means iterations",
                help: "Assignment and update rounds, restarted every frame from VAL k = VPL k N / M",
                kind: ParamKind::Int { min: 0, max: 100 },
                value: ParamValue::Int(p.iterations as i64),
            },
            Param {
                key: "w_x",
                label: "w_x (position)",
                help: "Weight of the position distance (divided by the scene's diagonal)",
                kind: ParamKind::Float { min: 0.0, max: 10.0 },
                value: ParamValue::Float(p.w_x),
            },
            Param {
                key: "w_a",
                label: "w_a (normal angle)",
                help: "Weight of the angle between normals, radians",
                kind: ParamKind::Float { min: 0.0, max: 10.0 },
                value: ParamValue::Float(p.w_a),
            },
            Param {
                key: "length",
                label: "L (share of the diagonal)",
                help: "The length position distances are divided by, as a share of the scene's diagonal: smaller \
                       weighs position more against the normals' angle",
                kind: ParamKind::Float { min: 1e-3, max: 10.0 },
                value: ParamValue::Float(p.length_fraction),
            },
            Param {
                key: "split",
                label: "Split VALs across surfaces",
                help: "Bisect VALs whose normals or depths spread too far (corners, columns) until there are M; off: \
                       the paper's k-means alone",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(p.split),
            },
            Param {
                key: "kmeans_share",
                label: "k-means share of M",
                help: "split: k-means clusters into this share of M VALs, bisection fills up to M",
                kind: ParamKind::Float { min: 0.0, max: 1.0 },
                value: ParamValue::Float(p.kmeans_share),
            },
            Param {
                key: "rank",
                label: "Bisect first",
                help: "split: light: the VAL of largest sum of its VPLs' luminance times their distance to its centre \
                       is bisected next; flux: the same with the distance squared (the default before); rule: every \
                       VAL breaking the cone or depth rule first (the first version)",
                kind: ParamKind::Choice(RANK_CHOICES),
                value: ParamValue::Choice(p.rank.clone()),
            },
            Param {
                key: "gain_until",
                label: "Bisect by gain below",
                help: "split: while there are fewer VALs than this, bisect the VAL whose bisection lowers the \
                       flux-weighted error most (so the first, coarse VALs improve at every step); then by rank",
                kind: ParamKind::Int { min: 0, max: 4096 },
                value: ParamValue::Int(p.gain_until as i64),
            },
            Param {
                key: "hidden_weight",
                label: "Hidden VPL weight",
                help: "split, rank light or flux: a VAL's key counts 1 + this x the share of its VPLs' light its \
                       map's centre cannot see (a ray per VPL); 0: the rank alone",
                kind: ParamKind::Float { min: 0.0, max: 100.0 },
                value: ParamValue::Float(p.hidden_weight),
            },
            Param {
                key: "centre",
                label: "Map centre",
                help: "mean: each VAL's map at its VPLs' mean, off its surface (the paper's); member: at the VPL \
                       nearest the mean, off its own surface (never in the open space across an arch); auto: member \
                       for a VAL of at most member_share of the VPLs, mean for a larger one",
                kind: ParamKind::Choice(Centre::NAMES),
                value: ParamValue::Choice(p.centre.name().to_string()),
            },
            Param {
                key: "member_share",
                label: "Member centre up to",
                help: "centre = auto: a VAL of at most this share of the frame's VPLs has its map at a member VPL",
                kind: ParamKind::Float { min: 0.0, max: 1.0 },
                value: ParamValue::Float(p.member_share),
            },
            Param {
                key: "clearance",
                label: "Clear member centre",
                help: "A VAL's map standing at a member with geometry right beside it (nearer than a tenth of the \
                       maps' longest edge, which its map would draw warped) moves to the least crowded member \
                       nearby; off: always the member nearest the mean",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(p.clearance),
            },
            Param {
                key: "max_cone",
                label: "Max normal cone (deg)",
                help: "split: a VAL whose VPL normals are farther than this from its normal is bisected by normal",
                kind: ParamKind::Float { min: 0.0, max: 180.0 },
                value: ParamValue::Float(p.max_cone_degrees),
            },
            Param {
                key: "max_depth",
                label: "Max depth spread",
                help:
                    "split: a VAL whose VPLs spread along its normal by more than this share of its size is bisected \
                       by depth",
                kind: ParamKind::Float { min: 0.0, max: 100.0 },
                value: ParamValue::Float(p.max_depth),
            },
            Param {
                key: "visibility",
                label: "Visibility",
                help: "pcss: soft shadow from the VAL's area (blocker search, penumbra, PCF); cssm: the paper's \
                       convolution soft shadow maps (4 Fourier terms, mip-mapped); hard: one test",
                kind: ParamKind::Choice(VISIBILITY_CHOICES),
                value: ParamValue::Choice(p.visibility.clone()),
            },
            Param {
                key: "size",
                label: "VAL size (Δ)",
                help: "The size in the penumbra estimate: bounds: the diagonal of the VPLs' bounding rectangle (the \
                       paper); spread (the default): the side of the square with the VPLs' flux-weighted second \
                       moment (a faint VPL far off does not widen it)",
                kind: ParamKind::Choice(SIZE_CHOICES),
                value: ParamValue::Choice(p.size.clone()),
            },
            Param {
                key: "shadow_res",
                label: "Map resolution",
                help: "Texels per side of each VAL's paraboloid map",
                kind: ParamKind::Int { min: 16, max: 2048 },
                value: ParamValue::Int(p.shadow_resolution as i64),
            },
            Param::map_proxy(p.proxy),
            Param::map_proxy_error(
                "proxy: the farthest the simplified surface may move from the scene's, as a share of the scene's \
                 diagonal (the simplification stops there, above the share asked for if need be)",
                p.proxy_error,
            ),
            Param {
                key: "max_edge",
                label: "Longest edge",
                help: "The longest triangle edge the VAL maps draw, as a share of the scene's diagonal: longer ones \
                       are cut, since a paraboloid map draws a triangle's edges straight. 0: the triangles as they are",
                kind: ParamKind::Float { min: 0.0, max: 1.0 },
                value: ParamValue::Float(p.max_edge),
            },
            Param {
                key: "grid",
                label: "PCF grid",
                help: "Side of the blocker-search and filter grid (grid^2 texels each)",
                kind: ParamKind::Int { min: 2, max: 16 },
                value: ParamValue::Int(p.grid as i64),
            },
            Param {
                key: "bias",
                label: "Depth bias",
                help: "Constant depth bias in world units",
                kind: ParamKind::Float { min: 0.0, max: 10.0 },
                value: ParamValue::Float(p.bias_world),
            },
            Param {
                key: "normal_offset",
                label: "Normal offset",
                help: "Receiver offset along its normal, in map texels at the receiver",
                kind: ParamKind::Float { min: 0.0, max: 16.0 },
                value: ParamValue::Float(p.normal_offset_texels),
            },
            Param {
                key: "slope_bias",
                label: "Slope bias",
                help: "Bias of a filter sample below the receiver's plane per texel of offset, in texel \
                       footprints (curved receivers otherwise shadow themselves in a wide kernel)",
                kind: ParamKind::Float { min: 0.0, max: 16.0 },
                value: ParamValue::Float(p.slope_bias),
            },
            Param {
                key: "cssm_offset",
                label: "CSSM offset",
                help: "cssm: the receiver moved toward the VAL by this share of the map's depth range (4 Fourier \
                       terms at half phase rise over about 1/4 of it: smaller darkens lit surfaces, larger leaks \
                       light)",
                kind: ParamKind::Float { min: 0.0, max: 0.5 },
                value: ParamValue::Float(p.cssm_offset),
            },
            Param {
                key: "soft_share",
                label: "Soft above share",
                help: "pcss/cssm without interleaving: a VAL carrying less than this share of a pixel's \
                       unshadowed indirect light gets one depth test there instead of soft visibility (its \
                       penumbra is worth less than its taps); 0: every VAL soft (the paper)",
                kind: ParamKind::Float { min: 0.0, max: 1.0 },
                value: ParamValue::Float(p.soft_share),
            },
            Param {
                key: "skip_unlit",
                label: "Skip VALs that cannot light",
                help: "Without interleaving: a pixel walks the VALs and skips one whose VPLs all lie behind its \
                       tangent plane or face away from it (bounds of the VAL's sphere and normal cone), never \
                       evaluating their VPLs; off: every VPL at every pixel, as the paper (the image does not change)",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(p.skip_unlit),
            },
            Param {
                key: "warm_start",
                label: "Warm start",
                help:
                    "Start k-means from last frame's VALs (the variant the paper rejects: VALs get lost); with split \
                       on, k-means makes only kmeans_share of M VALs (one by default), so it changes little or nothing",
                kind: ParamKind::Bool,
                value: ParamValue::Bool(p.warm_start),
            },
            Param {
                key: "solo",
                label: "Show one VAL",
                help: "The contribution of one VAL alone: its VPLs with its soft shadow (-1: all VALs)",
                kind: ParamKind::Int { min: -1, max: MAX_VALS as i64 - 1 },
                value: ParamValue::Int(p.solo as i64),
            },
            Param {
                key: "vpls_per_step",
                label: "VPLs per step",
                help: "VPLs gathered in one pass (the image does not change)",
                kind: ParamKind::Int { min: 1, max: crate::vpl::MAX_VPLS as i64 },
                value: ParamValue::Int(p.vpls_per_step as i64),
            },
        ];
        // Interleaving's two parameters, shared with the other gathers, before the warm start (as the paper's
        // section 6 before its ablation).
        let at = list.iter().position(|q| q.key == "warm_start").unwrap_or(list.len());
        list.splice(at..at, p.interleave.describe());
        list
    }

    /// Set one parameter; `key` and `value` were checked against [`ValParams::describe`].
    pub fn set(&mut self, key: &str, value: &ParamValue) {
        let p = self;
        match (key, value) {
            ("vals", ParamValue::Int(v)) => p.vals = *v as u32,
            ("iterations", ParamValue::Int(v)) => p.iterations = *v as u32,
            ("w_x", ParamValue::Float(v)) => p.w_x = *v,
            ("w_a", ParamValue::Float(v)) => p.w_a = *v,
            ("length", ParamValue::Float(v)) => p.length_fraction = *v,
            ("visibility", ParamValue::Choice(v)) => p.visibility = v.clone(),
            ("size", ParamValue::Choice(v)) => p.size = v.clone(),
            ("shadow_res", ParamValue::Int(v)) => p.shadow_resolution = *v as u32,
            ("grid", ParamValue::Int(v)) => p.grid = *v as u32,
            ("bias", ParamValue::Float(v)) => p.bias_world = *v,
            ("normal_offset", ParamValue::Float(v)) => p.normal_offset_texels = *v,
            ("slope_bias", ParamValue::Float(v)) => p.slope_bias = *v,

            ("skip_unlit", ParamValue::Bool(v)) => p.skip_unlit = *v,
            ("clearance", ParamValue::Bool(v)) => p.clearance = *v,
            ("warm_start", ParamValue::Bool(v)) => p.warm_start = *v,
            ("vpls_per_step", ParamValue::Int(v)) => p.vpls_per_step = *v as u32,
            ("clustering", ParamValue::Choice(v)) => p.clustering = v.clone(),
            ("solo", ParamValue::Int(v)) => p.solo = *v as i32,
            ("cssm_offset", ParamValue::Float(v)) => p.cssm_offset = *v,
            ("soft_share", ParamValue::Float(v)) => p.soft_share = *v,
            ("split", ParamValue::Bool(v)) => p.split = *v,
            ("kmeans_share", ParamValue::Float(v)) => p.kmeans_share = *v,
            ("rank", ParamValue::Choice(v)) => p.rank = v.clone(),
            ("gain_until", ParamValue::Int(v)) => p.gain_until = *v as u32,
            ("hidden_weight", ParamValue::Float(v)) => p.hidden_weight = *v,
            ("centre", ParamValue::Choice(v)) => p.centre = Centre::from_name(v).unwrap_or(Centre::Auto),
            ("member_share", ParamValue::Float(v)) => p.member_share = *v,
            ("max_cone", ParamValue::Float(v)) => p.max_cone_degrees = *v,
            ("max_depth", ParamValue::Float(v)) => p.max_depth = *v,
            ("proxy", ParamValue::Float(v)) => p.proxy = *v,
            ("proxy_error", ParamValue::Float(v)) => p.proxy_error = *v,
            ("max_edge", ParamValue::Float(v)) => p.max_edge = *v,
            (k, v) => {
                // Interleaving's parameters, or none ([`Interleave::set`](crate::services::vpl_gather::Interleave::set)).
                if !p.interleave.set(k, v) {
                    unreachable!("check_param accepted an unknown key")
                }
            }
        }
    }
}
