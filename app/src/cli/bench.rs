//! `shadowlab bench`: the standard suite, every technique on the built-in scenes (and the shared real scenes),
//! compared with the reference; a Markdown table.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use shadowlab_core::vpl::VplSettings;

use super::args::{FrameArgs, SceneArgs};
use super::setup::setup;
use crate::files::{check_output_path, write_atomic};

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
    // (technique, parameters) in the order of the table; the reference comes first: the others are compared
    // with it.
    let techniques: [(&str, &[&str]); 5] = [
        ("reference", &[]),
        ("unshadowed", &[]),
        ("lightcluster", &["d_init=0.5", "filter=pcss"]),
        ("lightcluster", &["d_init=0.5", "filter=pcf"]),
        ("raytraced", &[]),
    ];
    let mut md = String::from(
        "| scene | technique | parameters | shadow maps | median ms | min ms | clock | speedup vs reference | RMSE | shadow error | lookups/px | taps/px | shadow rays | depth triangles | shadow texels |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
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
            vpls: VplSettings::default().count,
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
        let inputs = crate::measure::compare_inputs(&mut renderer, &camera, &lights)?;
        let mut reference: Option<crate::measure::Rendered> = None;
        for (key, params) in techniques {
            eprintln!("{}: {key} {}", s.name, params.join(" "));
            let params: Vec<String> = params.iter().map(|p| p.to_string()).collect();
            let r = crate::measure::render_technique(
                &mut renderer,
                key,
                frame.shadow_res,
                &params,
                &camera,
                &lights,
                &crate::measure::IndirectChoice::none(),
                frame.warmup,
                frame.repeat,
                &mut |_| {},
            )?;
            let (rmse, shadow, speedup) = match &reference {
                Some(reference) => {
                    let (m, _) = crate::measure::compare_images(
                        &r.image,
                        &reference.image,
                        &inputs,
                        crate::measure::DiffKind::Absolute,
                        1.0,
                        false,
                        1.0,
                    )?;
                    (
                        format!("{:.5}", m.rmse),
                        m.shadow_intensity_error.map(|e| format!("{:.2}%", e * 100.0)).unwrap_or_default(),
                        {
                            let sp = crate::measure::Speedup::of(&r.timing, &reference.timing);
                            format!("{:.2} ({}; wall x{:.2})", sp.ratio, sp.clock.name(), sp.wall_ratio)
                        },
                    )
                }
                None => ("0".into(), "0%".into(), "1.00".into()),
            };
            let c = &r.report.counts.technique;
            let work = r.report.total_work();
            md += &format!(
                "| {} | {} | {} | {}{} | {:.1} | {:.1} | {} | {} | {} | {} | {:.2} | {:.2} | {:.0} | {:.0} | {:.0} |\n",
                s.name,
                key,
                params.join(" "),
                c.shadow_maps,
                c.clusters.map(|n| format!(" ({n} clusters)")).unwrap_or_default(),
                r.timing.median_ms,
                r.timing.min_ms,
                r.timing.clock.name(),
                speedup,
                rmse,
                shadow,
                work["shadow_lookups_per_pixel"],
                work["filter_taps_per_pixel"],
                work["shadow_rays"],
                work["depth_triangles"],
                work["shadow_texels_written"],
            );
            if reference.is_none() {
                reference = Some(r);
            }
        }
    }
    md += &format!(
        "\n{}x{}, {} texels per cube face, median of {} frames after {} warm-up, on {adapter}.\n",
        args.width, args.height, args.shadow_res, args.repeat, args.warmup
    );
    write_atomic(&args.out, md.as_bytes())?;
    print!("{md}");
    Ok(())
}
