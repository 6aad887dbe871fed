//! The argument groups several subcommands flatten into theirs: the scene and its lights, the frame (image
//! size, camera, shading, indirect light, timing), the technique and its comparison target; and the checks of
//! technique keys.

use anyhow::{anyhow, bail, Result};
use clap::Args;
use glam::Vec3;
use shadowlab_core::technique;

use crate::measure::IndirectChoice;

#[derive(Args, Debug, Clone)]
pub struct SceneArgs {
    /// A built-in scene (cornell, arcade, restaurant) or a .obj/.gltf/.glb file.
    #[arg(long, default_value = "arcade")]
    pub scene: String,
    /// Unit scale applied to a scene file's positions (the conference room is in centimetres: 0.01).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f32,
    /// Lights: `scene` (from the scene), `paper` (the scene's paper layout), `random:COUNT:L_ATT[:SEED]`,
    /// `above:COUNT:L_ATT[:SEED]` (over the scene, from its top to half its height higher),
    /// `circles:CIRCLES:PER_CIRCLE:L_ATT`, `grid:NXxNY:L_ATT`.
    #[arg(long, default_value = "scene")]
    pub lights: String,
    /// A sun (directional light) `AZIMUTH,ELEVATION,ILLUMINANCE[,R,G,B]`: degrees from -Z towards +X, degrees
    /// above the horizon, W/m², linear colour (white when absent). Repeatable, at most 4; replaces the scene's
    /// own suns.
    #[arg(long = "sun")]
    pub suns: Vec<String>,
}

/// Image size, camera and shading settings shared by `render`, `compare` and `sweep`.
#[derive(Args, Debug, Clone)]
pub struct FrameArgs {
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    #[arg(long, default_value_t = 360)]
    pub height: u32,
    /// Texels per cube-map face (the technique's `shadow_res` parameter).
    #[arg(long)]
    pub shadow_res: Option<u32>,
    /// Camera `EX,EY,EZ,TX,TY,TZ` (eye and target); the scene's camera when absent.
    #[arg(long, value_name = "EX,EY,EZ,TX,TY,TZ")]
    pub camera: Option<String>,
    /// Vertical field of view in degrees.
    #[arg(long)]
    pub fov: Option<f32>,
    /// Far plane (`z_far`).
    #[arg(long)]
    pub z_far: Option<f32>,
    /// Exposure (a compensation with --auto-exposure).
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// Scale the exposure so the image's log-average luminance lands on middle grey (the app's default; off
    /// here so renders of one scene stay comparable).
    #[arg(long)]
    pub auto_exposure: bool,
    /// Tone mapping: aces, reinhard or linear.
    #[arg(long, default_value = "aces")]
    pub tonemap: String,
    /// Blinn-Phong specular on top of Lambert.
    #[arg(long)]
    pub specular: bool,
    /// Frames rendered and thrown away before the measured ones (the first frame also compiles pipelines).
    #[arg(long, default_value_t = 1)]
    pub warmup: u32,
    /// Measured frames; timings report the median, the minimum and the mean of the 3 fastest.
    #[arg(long, default_value_t = 1)]
    pub repeat: u32,
    /// No progress output.
    #[arg(long)]
    pub quiet: bool,
    #[arg(long, default_value = "none", help = registry_help("Indirect technique added to the direct one, none or one of", true))]
    pub indirect: String,
    /// A parameter of the indirect technique, `key=value` (in `sweep`: `key=VALUES` like `--param`); repeatable.
    #[arg(long = "indirect-param", value_name = "KEY=VALUE")]
    pub indirect_params: Vec<String>,
    /// VPLs (RSM texels or traced particles) shared by every VPL technique; 0 = no indirect light.
    #[arg(long, default_value_t = 1024)]
    pub vpls: u32,
    /// Where VPLs come from: rsm (reflective shadow maps), traced (particles through the BVH) or auto (the
    /// indirect technique's paper's choice: traced for fuzzy, else rsm).
    #[arg(long, default_value = "auto")]
    pub vpl_source: String,
    /// Bounces of traced particles (the rsm source is one bounce).
    #[arg(long, default_value_t = 1)]
    pub bounces: u32,
    /// d_clamp of the VPL gathers in world units: 1/d^2 is clamped to 1/d_clamp^2.
    #[arg(long, default_value_t = 0.1)]
    pub vpl_clamp: f32,
    /// Seed of the VPLs' quasi-random sequence.
    #[arg(long, default_value_t = 0)]
    pub vpl_seed: u32,
    /// What images, metrics and difference images show: total, direct or indirect.
    #[arg(long, default_value = "total")]
    pub component: String,
    /// Display gain of the indirect component in saved images (metrics never use it).
    #[arg(long, default_value_t = 1.0)]
    pub indirect_gain: f32,
    /// Loop every shading pass over all the lights of its batch instead of its 16x16 tile's list (the image
    /// is the same; for measuring what the tiled light lists save).
    #[arg(long)]
    pub no_light_tiles: bool,
    /// Draw every chunk in a light's range into its cube map instead of only those between it and the view's
    /// surfaces (receiver-aware caster culling; the image is the same; for measuring what it saves).
    #[arg(long)]
    pub no_receiver_culling: bool,
}

impl FrameArgs {
    /// The indirect technique of the technique side.
    pub fn indirect_choice(&self) -> IndirectChoice {
        IndirectChoice { key: self.indirect.clone(), params: self.indirect_params.clone() }
    }
}

/// The technique and its comparison target, shared by `compare` and `sweep`.
#[derive(Args, Debug)]
pub struct TargetArgs {
    #[arg(long, default_value = "lightcluster", help = registry_help("Technique", false))]
    pub technique: String,
    /// What to compare against: `reference` (cube map per light) or another technique such as `raytraced`
    /// (default: `reference`; with `--component indirect`, the technique itself, so that both sides differ only
    /// in their indirect light).
    #[arg(long = "against", value_name = "AGAINST")]
    pub against_given: Option<String>,
    /// The target's direct technique: `--against`, or its default ([`TargetArgs::resolve`]).
    #[arg(skip)]
    pub against: String,
    /// A parameter of the comparison target, `key=value`; repeatable.
    #[arg(long = "against-param", value_name = "KEY=VALUE")]
    pub against_params: Vec<String>,
    /// The comparison target's indirect technique (default: the same as `--indirect`; with `--component indirect`,
    /// the indirect technique's own comparison target, e.g. `vpl-shadowmaps` for `val`).
    #[arg(long = "against-indirect", value_name = "KEY")]
    pub against_indirect: Option<String>,
    /// A parameter of the target's indirect technique, `key=value`; repeatable.
    #[arg(long = "against-indirect-param", value_name = "KEY=VALUE")]
    pub against_indirect_params: Vec<String>,
}

impl TargetArgs {
    /// Settle the target's direct technique: `--against` when given; else the reference, or, when only the
    /// indirect component is compared (`indirect_only`), the technique itself: its direct light is not in the
    /// images, and a reference under the target's indirect light cost that side time the other did not pay
    /// (`compare --technique unshadowed --indirect val --component indirect` read x3.79 where the indirect
    /// techniques alone differ far less). Said on stderr unless `quiet`.
    pub fn resolve(&mut self, indirect_only: bool, quiet: bool) {
        self.against = match &self.against_given {
            Some(k) => k.clone(),
            None if indirect_only => {
                if !quiet && self.technique != technique::registry::REFERENCE {
                    eprintln!(
                        "note: the indirect component alone: the target's direct technique is {} too (--against \
                         chooses another)",
                        self.technique
                    );
                }
                self.technique.clone()
            }
            None => technique::registry::REFERENCE.to_string(),
        };
    }

    /// Both technique keys are registered.
    pub fn check(&self) -> Result<()> {
        check_technique(&self.technique)?;
        check_technique(&self.against)
    }

    /// The target's indirect technique: `--against-indirect` (with its parameters), else the technique side's,
    /// except when only the indirect component is compared (`indirect_only`): the same indirect technique on
    /// both sides then differs by nothing (an error of 0 whatever the technique), so the target is that
    /// technique's own comparison target in the registry (`val` against `vpl-shadowmaps`, `fuzzy` against
    /// `vpl-raytraced`; a ground truth against itself), said on stderr unless `quiet`.
    pub fn against_indirect(&self, same: &IndirectChoice, indirect_only: bool, quiet: bool) -> Result<IndirectChoice> {
        match &self.against_indirect {
            Some(k) => {
                check_indirect(k)?;
                Ok(IndirectChoice { key: k.clone(), params: self.against_indirect_params.to_vec() })
            }
            None if !self.against_indirect_params.is_empty() => {
                bail!("--against-indirect-param needs --against-indirect")
            }
            None => match technique::registry::own_indirect_target(&same.key).filter(|_| indirect_only) {
                Some(target) => {
                    if !quiet {
                        eprintln!(
                            "note: the indirect component of {} against its own target, {target} \
                                 (--against-indirect chooses another)",
                            same.key
                        );
                    }
                    Ok(IndirectChoice { key: target.to_string(), params: Vec::new() })
                }
                None => Ok(same.clone()),
            },
        }
    }
}

/// `none` or a key of the indirect registry.
pub fn check_indirect(key: &str) -> Result<()> {
    if key != "none" && technique::registry::INDIRECT_REGISTRY.iter().all(|e| e.key != key) {
        bail!("unknown indirect technique '{key}' (choose none or one of: {})", technique::registry::indirect_keys());
    }
    Ok(())
}

/// The direct technique of `render`, `animate` and `sequence`: its key and its parameters.
#[derive(Args, Debug)]
pub struct TechniqueChoice {
    #[arg(long, default_value = technique::registry::REFERENCE, help = registry_help("Technique", false))]
    pub technique: String,
    /// A technique parameter, `key=value`; repeatable.
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
}

impl TechniqueChoice {
    /// The technique on `renderer` with its parameters set (`shadow_res` from `--shadow-res` first). The key was
    /// checked with [`check_technique`] before the GPU was set up.
    pub fn create(
        &self,
        renderer: &shadowlab_core::Renderer,
        shadow_res: Option<u32>,
    ) -> Result<Box<dyn technique::Technique>> {
        let mut created = renderer
            .create_technique(&self.technique)
            .ok_or_else(|| anyhow!("unknown technique '{}'", self.technique))?;
        crate::measure::apply_params(created.as_mut(), shadow_res, &self.params)?;
        Ok(created)
    }
}

pub fn check_technique(key: &str) -> Result<()> {
    if technique::registry::REGISTRY.iter().all(|e| e.key != key) {
        bail!("unknown technique '{key}' (choose one of: {})", technique::registry::keys());
    }
    Ok(())
}

/// `--step DX,DY,DZ`.
pub fn parse_step(text: &str) -> Result<Vec3> {
    let step: Vec<f32> = text
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow!("--step '{text}': expected DX,DY,DZ"))?;
    match step.as_slice() {
        [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => Ok(Vec3::new(*x, *y, *z)),
        _ => bail!("--step '{text}': expected three finite numbers DX,DY,DZ"),
    }
}

/// `what: key, key, ...` with the registry's keys (direct or indirect), for `--help`.
pub(super) fn registry_help(what: &str, indirect: bool) -> String {
    format!("{what}: {}", if indirect { technique::registry::indirect_keys() } else { technique::registry::keys() })
}
