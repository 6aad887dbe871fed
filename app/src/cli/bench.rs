//! `shadowlab bench`: the standard suite, every technique of the registries (direct, and indirect over the
//! preview) on the built-in scenes (and the shared real scenes), each at its defaults against its own comparison
//! target; a Markdown table. The suite is the registries': a technique added there is benched.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use shadowlab_core::vpl::VplSettings;

use shadowlab_core::renderer::{Component, Renderer};
use shadowlab_core::scene::{Camera, PointLight};
use shadowlab_core::technique::registry::{self, TechniqueEntry};

use super::args::{FrameArgs, SceneArgs};
use super::setup::setup;
use crate::files::{check_output_path, write_atomic};
use crate::measure::{IndirectChoice, Rendered};

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    #[arg(long, default_value_t = 360)]
    pub height: u32,
    #[arg(long, default_value_t = 512)]
    pub shadow_res: u32,
    #[arg(long, default_value_t = 1)]
    pub warmup: u32,
    #[arg(long, default_value_t = 3)]
    pub repeat: u32,
    /// VPLs of the indirect rows.
    #[arg(long, default_value_t = 256)]
    pub vpls: u32,
    /// Folder of the shared real scenes (dabrovic-sponza, conference); skipped when absent.
    #[arg(long, default_value = "../shared/scenes")]
    pub scenes: PathBuf,
    /// Only the built-in scenes.
    #[arg(long)]
    pub builtin_only: bool,
    /// Markdown table output.
    #[arg(long)]
    pub out: PathBuf,
}

/// One scene of the benchmark suite: name, scene arguments, camera.
struct BenchScene {
    name: &'static str,
    scene: SceneArgs,
    camera: Option<&'static str>,
    z_far: Option<f32>,
}

pub fn run(args: BenchArgs) -> Result<()> {
    check_output_path(&args.out, "md")?;
    let builtin = |name: &'static str| BenchScene {
        name,
        scene: SceneArgs { scene: name.into(), scale: 1.0, lights: "scene".into(), suns: Vec::new() },
        camera: None,
        z_far: None,
    };
    let mut suite = vec![builtin("cornell"), builtin("arcade"), builtin("restaurant")];
    let sponza = args.scenes.join("dabrovic-sponza/sponza.obj");
    let conference = args.scenes.join("conference/conference.obj");
    if !args.builtin_only {
        if sponza.is_file() {
            suite.push(BenchScene {
                name: "sponza",
                scene: SceneArgs {
                    scene: sponza.display().to_string(),
                    scale: 1.0,
                    lights: "paper".into(),
                    suns: Vec::new(),
                },
                camera: Some("-14,2.5,0,10,3,0"),
                z_far: Some(30.0),
            });
        } else {
            eprintln!("warning: {} not found: Sponza skipped", sponza.display());
        }
        if conference.is_file() {
            suite.push(BenchScene {
                name: "conference",
                scene: SceneArgs {
                    scene: conference.display().to_string(),
                    scale: 0.01,
                    lights: "random:64:3:1".into(),
                    suns: Vec::new(),
                },
                camera: None,
                z_far: None,
            });
        }
    }
    let mut md = String::from(
        "| scene | technique | against | shadow maps | median ms | min ms | clock | speedup | RMSE | shadow error | lookups/px | taps/px | shadow rays | depth triangles | shadow texels |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut adapter = String::new();
    for s in &suite {
        let frame = FrameArgs {
            width: args.width,
            height: args.height,
            shadow_res: Some(args.shadow_res),
            camera: s.camera.map(String::from),
            fov: None,
            z_far: s.z_far,
            exposure: 1.0,
            auto_exposure: false,
            tonemap: "aces".into(),
            specular: false,
            warmup: args.warmup,
            repeat: args.repeat,
            quiet: true,
            indirect: "none".into(),
            indirect_params: Vec::new(),
            vpls: args.vpls,
            vpl_source: "auto".into(),
            bounces: 1,
            vpl_clamp: VplSettings::default().clamp_world,
            vpl_seed: 0,
            component: "total".into(),
            indirect_gain: 1.0,
            no_light_tiles: false,
            no_receiver_culling: false,
        };
        eprintln!("{}: loading", s.name);
        let (gpu, mut renderer, _scene, lights, camera) = setup(&s.scene, &frame)?;
        adapter = gpu.adapter_description();
        let mut bench =
            SceneBench { renderer: &mut renderer, frame: &frame, camera: &camera, lights: &lights, name: s.name };
        // Direct light: every technique of the registry at its defaults, against its own comparison target.
        bench.rows(&mut md, registry::REGISTRY, false, |key| (key.to_string(), IndirectChoice::none()))?;
        // Indirect light alone: every indirect technique over the preview, against its own target, on the VPLs
        // it prefers (the target on the same ones).
        bench.rows(&mut md, registry::INDIRECT_REGISTRY, true, |key| {
            (registry::preview().key.to_string(), IndirectChoice { key: key.to_string(), params: Vec::new() })
        })?;
    }
    md += &format!(
        "\n{}x{}, {} texels per cube face, {} VPLs (indirect rows: the indirect component alone, over `{}`), median of {} \
         frames after {} warm-up, on {adapter}. Each technique at its defaults against its registry's comparison \
         target, both in the same clock.\n",
        args.width,
        args.height,
        args.shadow_res,
        args.vpls,
        registry::preview().key,
        args.repeat,
        args.warmup
    );
    write_atomic(&args.out, md.as_bytes())?;
    print!("{md}");
    Ok(())
}

/// One scene of the suite: its renderer, frame arguments, camera and lights (each call of [`SceneBench::rows`]
/// renders a target once per VPL source and reuses it for every technique that names it).
struct SceneBench<'a> {
    renderer: &'a mut Renderer,
    frame: &'a FrameArgs,
    camera: &'a Camera,
    lights: &'a [PointLight],
    name: &'static str,
}

impl SceneBench<'_> {
    /// The rows of `entries`: each technique `side(key)` makes (a direct key and an indirect choice) against its
    /// entry's target, made by the same `side`; direct entries shade the whole image, `indirect` ones the
    /// indirect component alone with the VPL source their entry prefers.
    fn rows(
        &mut self,
        md: &mut String,
        entries: &[TechniqueEntry],
        indirect: bool,
        side: impl Fn(&str) -> (String, IndirectChoice),
    ) -> Result<()> {
        type Source = Option<shadowlab_core::vpl::VplSource>;
        let mut done: Vec<(String, Source, Rendered)> = Vec::new();
        let mut inputs: Option<(Source, crate::measure::CompareInputs)> = None;
        for entry in entries {
            let mut settings = self.renderer.settings().clone();
            settings.component = if indirect { Component::Indirect } else { Component::Total };
            let source = indirect.then(|| registry::preferred_vpl_source(entry.key).unwrap_or_default());
            if let Some(source) = source {
                settings.vpl.source = source;
            }
            if settings != *self.renderer.settings() {
                self.renderer.set_settings(settings)?;
            }
            if inputs.as_ref().is_none_or(|(s, _)| *s != source) {
                inputs = Some((source, crate::measure::compare_inputs(self.renderer, self.camera, self.lights)?));
            }
            let inputs = &inputs.as_ref().expect("made above").1;
            for key in [entry.target, entry.key] {
                if done.iter().any(|(k, s, _)| k == key && *s == source) {
                    continue;
                }
                eprintln!("{}: {key}", self.name);
                let (direct, choice) = side(key);
                let r = crate::measure::render_technique(
                    self.renderer,
                    &direct,
                    self.frame.shadow_res,
                    &[],
                    self.camera,
                    self.lights,
                    &choice,
                    self.frame.warmup,
                    self.frame.repeat,
                    &mut |_| {},
                )?;
                done.push((key.to_string(), source, r));
            }
            let find = |key: &str| done.iter().find(|(k, s, _)| k == key && *s == source).map(|(_, _, r)| r);
            let (r, target) = (find(entry.key).expect("rendered above"), find(entry.target).expect("rendered above"));
            let (against, rmse, shadow, speedup) = if entry.target == entry.key {
                ("(itself: a ground truth)".to_string(), "-".to_string(), "-".to_string(), "-".to_string())
            } else {
                let (m, _) = crate::measure::compare_images(
                    &r.image,
                    &target.image,
                    inputs,
                    crate::measure::DiffKind::Absolute,
                    1.0,
                    false,
                    1.0,
                )?;
                let sp = crate::measure::Speedup::of(&r.timing, &target.timing);
                (
                    entry.target.to_string(),
                    format!("{:.5}", m.rmse),
                    m.shadow_intensity_error.map(|e| format!("{:.2}%", e * 100.0)).unwrap_or_else(|| "-".into()),
                    format!("x{:.2} ({}; wall x{:.2})", sp.ratio, sp.clock.name(), sp.wall_ratio),
                )
            };
            // The indirect technique's own counts and VPLs on indirect rows (the preview under it has none).
            let (c, name) = match (&r.report.indirect, indirect) {
                (Some(i), true) => {
                    let vpls =
                        if i.vpls > 0 { format!(", {} {} VPLs", i.vpls, i.vpl_source.name()) } else { String::new() };
                    (&i.counts, format!("{} + {}{vpls}", registry::preview().key, entry.key))
                }
                _ => (&r.report.counts.technique, entry.key.to_string()),
            };
            let work = r.report.total_work();
            md.push_str(&format!(
                "| {} | {name} | {against} | {}{} | {:.1} | {:.1} | {} | {speedup} | {rmse} | {shadow} | {:.2} | {:.2} | {:.0} | {:.0} | {:.0} |\n",
                self.name,
                c.shadow_maps,
                c.clusters.map(|n| format!(" ({n} clusters)")).unwrap_or_default(),
                r.timing.median_ms,
                r.timing.min_ms,
                r.timing.clock.name(),
                work["shadow_lookups_per_pixel"],
                work["filter_taps_per_pixel"],
                work["shadow_rays"],
                work["depth_triangles"],
                work["shadow_texels_written"],
            ));
        }
        Ok(())
    }
}
