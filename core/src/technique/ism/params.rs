//! The parameters of the two ISM techniques: their defaults (the INSM paper's ISM setup where it gives them:
//! about 12,000 points per 128x128 map), ranges and descriptions. `ism` and `vpl-ism` share them; the VPL one
//! adds its gather's.

use super::pull_push::MAX_LEVELS;
use crate::technique::{check_param, Param, ParamError, ParamKind, ParamValue};

/// The most points one map splats (the splat dispatch's x dimension holds 4 M; more is not imperfect anymore).
pub const MAX_POINTS_PER_MAP: u32 = 1_000_000;
/// The largest map side: 1024² per map is as much as a per-light shadow map, past what ISM is for.
pub const MAX_RESOLUTION: u32 = 1024;

#[derive(Clone, Debug, PartialEq)]
pub struct IsmParams {
    /// Points each map splats (its subset of the scene's pool).
    pub points_per_map: u32,
    /// Side of each paraboloid map, texels (a point light's dual paraboloid is two of them).
    pub resolution: u32,
    /// Pull-push levels (0: the raw splats; clamped to the levels the resolution has, and said in the counts).
    pub levels: u32,
    /// Pull-push depth threshold: texels farther than the nearest of a neighbourhood by more than this fraction
    /// are not averaged with it.
    pub threshold: f32,
    /// Constant depth bias, in texel footprints at the receiver.
    pub bias: f32,
    /// Receiver offset along its normal, in texel footprints at the receiver.
    pub normal_offset: f32,
    pub seed: u32,
    /// Memory of one batch's maps (atlas and pyramid), MiB.
    pub atlas_mib: u32,
    /// The light (`ism`) or VPL (`vpl-ism`) whose map the inspector's second image and the point layer show.
    pub inspect: u32,
    /// `vpl-ism`: VPLs gathered per step (also at most one batch of maps).
    pub vpls_per_step: u32,
    /// `vpl-ism`: interleaved sampling and the geometry-aware blur (Dong section 6), its ratio estimator and
    /// block, as the other gathers.
    pub interleave: crate::services::vpl_gather::Interleave,
}

impl Default for IsmParams {
    fn default() -> Self {
        IsmParams {
            points_per_map: 12_000,
            resolution: 128,
            levels: 4,
            threshold: 1.0,
            bias: 1.0,
            normal_offset: 1.5,
            seed: 0,
            atlas_mib: 64,
            inspect: 0,
            vpls_per_step: 256,
            interleave: Default::default(),
        }
    }
}

impl IsmParams {
    /// The parameters of `ism` (`indirect` false) or `vpl-ism`.
    pub fn list(&self, indirect: bool) -> Vec<Param> {
        let int = |key: &'static str, label: &'static str, help: &'static str, min: i64, max: i64, v: u32| Param {
            key,
            label,
            help,
            kind: ParamKind::Int { min, max },
            value: ParamValue::Int(v as i64),
        };
        let float = |key: &'static str, label: &'static str, help: &'static str, min: f32, max: f32, v: f32| Param {
            key,
            label,
            help,
            kind: ParamKind::Float { min, max },
            value: ParamValue::Float(v),
        };
        let mut list = vec![
            int(
                "points",
                "Points per map",
                "Scene points each map splats, its own subset of the scene's pool (0 is refused: a map needs points)",
                1,
                MAX_POINTS_PER_MAP as i64,
                self.points_per_map,
            ),
            int(
                "resolution",
                "Map resolution",
                "Texels per side of each paraboloid map (a point light has two: a dual paraboloid)",
                8,
                MAX_RESOLUTION as i64,
                self.resolution,
            ),
            int(
                "levels",
                "Pull-push levels",
                "Levels of hole filling (0: the raw splats); more than the resolution has are clamped to its",
                0,
                MAX_LEVELS as i64,
                self.levels,
            ),
            float(
                "threshold",
                "Pull-push depth threshold",
                "Texels farther than the nearest of their neighbourhood by more than this fraction are not averaged \
                 with it",
                0.0,
                10.0,
                self.threshold,
            ),
            float(
                "bias",
                "Depth bias",
                "Constant depth bias, in texel footprints at the receiver",
                0.0,
                16.0,
                self.bias,
            ),
            float(
                "normal_offset",
                "Normal offset",
                "Receiver offset along its normal, in texel footprints at the receiver",
                0.0,
                16.0,
                self.normal_offset,
            ),
            Param::seed("Seed of the scene's point pool (its positions and their order)", self.seed),
            int(
                "atlas_mib",
                "Batch memory (MiB)",
                "Memory of one batch of maps (atlas and pull-push pyramid); more per batch means fewer steps",
                1,
                2048,
                self.atlas_mib,
            ),
        ];
        if indirect {
            list.push(int(
                "inspect",
                "Inspected VPL",
                "The VPL whose map the inspector's second image and the 'ism points of the inspected map' layer show",
                0,
                crate::vpl::MAX_VPLS as i64,
                self.inspect,
            ));
            list.push(int(
                "vpls_per_step",
                "VPLs per step",
                "VPLs mapped and gathered in one step; fewer means shorter steps (the image does not change)",
                1,
                crate::vpl::MAX_VPLS as i64,
                self.vpls_per_step,
            ));
            list.extend(self.interleave.describe());
        } else {
            list.push(int(
                "inspect",
                "Inspected light",
                "The light whose dual paraboloid the inspector's second image and the 'ism points of the inspected \
                 map' layer show",
                0,
                crate::scene::layout::MAX_LIGHTS as i64,
                self.inspect,
            ));
        }
        list
    }

    /// Check `value` against `key`'s range for technique `technique` and set it.
    pub fn set(&mut self, technique: &str, indirect: bool, key: &str, value: &ParamValue) -> Result<(), ParamError> {
        check_param(technique, &self.list(indirect), key, value)?;
        match (key, value) {
            ("points", ParamValue::Int(v)) => self.points_per_map = *v as u32,
            ("resolution", ParamValue::Int(v)) => self.resolution = *v as u32,
            ("levels", ParamValue::Int(v)) => self.levels = *v as u32,
            ("threshold", ParamValue::Float(v)) => self.threshold = *v,
            ("bias", ParamValue::Float(v)) => self.bias = *v,
            ("normal_offset", ParamValue::Float(v)) => self.normal_offset = *v,
            ("seed", ParamValue::Int(v)) => self.seed = *v as u32,
            ("atlas_mib", ParamValue::Int(v)) => self.atlas_mib = *v as u32,
            ("inspect", ParamValue::Int(v)) => self.inspect = *v as u32,
            ("vpls_per_step", ParamValue::Int(v)) => self.vpls_per_step = *v as u32,
            (k, v) => {
                // Interleaving's parameters, or none ([`Interleave::set`]).
                if !self.interleave.set(k, v) {
                    unreachable!("check_param accepted an unknown key")
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_values_are_refused_with_the_range() {
        let mut p = IsmParams::default();
        for (key, value) in [
            ("points", ParamValue::Int(0)),
            ("resolution", ParamValue::Int(0)),
            ("resolution", ParamValue::Int(1 << 20)),
            ("levels", ParamValue::Int(-1)),
            ("bias", ParamValue::Float(f32::NAN)),
        ] {
            let e = p.set("ism", false, key, &value).unwrap_err();
            assert!(e.to_string().contains("outside"), "{key} = {value}: {e}");
        }
        assert!(matches!(p.set("ism", false, "vpls_per_step", &ParamValue::Int(4)), Err(ParamError::Unknown { .. })));
        assert_eq!(p, IsmParams::default(), "a refused value changes nothing");
        p.set("vpl-ism", true, "vpls_per_step", &ParamValue::Int(4)).unwrap();
        assert_eq!(p.vpls_per_step, 4);
    }
}
