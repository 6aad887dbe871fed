//! `shadowlab animate`: the lights moved a step a frame, and the flicker measured; CSV rows.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;
use shadowlab_core::scene::PointLight;

use super::args::{check_technique, parse_step, FrameArgs, SceneArgs, TechniqueChoice};
use super::progress::Progress;
use super::setup::setup;
use crate::files::{check_output_path, write_atomic};

#[derive(Args, Debug)]
pub struct AnimateArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    #[command(flatten)]
    pub choice: TechniqueChoice,
    /// Frames rendered; the lights move by `--step` between frames.
    #[arg(long, default_value_t = 30)]
    pub frames: u32,
    /// The move of every light per frame, `DX,DY,DZ` in world units.
    #[arg(long, value_name = "DX,DY,DZ", default_value = "0.02,0,0")]
    pub step: String,
    /// One row per frame (CSV).
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(args: AnimateArgs) -> Result<()> {
    check_output_path(&args.out, "csv")?;
    check_technique(&args.choice.technique)?;
    if args.frames < 2 || args.frames > 1000 {
        bail!("--frames {}: between 2 and 1000", args.frames);
    }
    let step = parse_step(&args.step)?;
    let (_gpu, mut renderer, scene, lights, camera) = setup(&args.scene, &args.frame)?;
    let f = &args.frame;
    let mut technique = args.choice.create(&renderer, f.shadow_res)?;
    crate::measure::apply_indirect(&mut renderer, &f.indirect_choice())?;
    let mut previous: Option<Vec<[f32; 4]>> = None;
    // Per frame: index, change against the previous frame, mean radiance, figures.
    type FrameRow = (u32, Option<f64>, f64, std::collections::BTreeMap<String, f64>);
    let mut rows: Vec<FrameRow> = Vec::new();
    let mut progress = Progress::new(&format!("animate {}", args.choice.technique), f.quiet).with_unit("frame");
    for i in 0..args.frames {
        let moved: Vec<PointLight> =
            lights.iter().map(|l| PointLight { position: l.position + step * i as f32, ..*l }).collect();
        let report = renderer.render_frame(technique.as_mut(), &camera, &moved, &mut |_, _| {})?;
        let image = renderer.read_hdr()?;
        let mean = image.iter().map(|p| ((p[0] + p[1] + p[2]) / 3.0) as f64).sum::<f64>() / image.len() as f64;
        // Mean absolute change of luminance-like (mean RGB) radiance against the previous frame.
        let change = previous.as_ref().map(|prev| {
            prev.iter()
                .zip(&image)
                .map(|(a, b)| (((a[0] + a[1] + a[2]) - (b[0] + b[1] + b[2])) / 3.0).abs() as f64)
                .sum::<f64>()
                / image.len() as f64
        });
        let mut figures: std::collections::BTreeMap<String, f64> =
            report.counts.technique.figures.iter().map(|(k, v)| (format!("figure.{k}"), *v)).collect();
        if let Some(ind) = &report.indirect {
            figures.extend(ind.counts.figures.iter().map(|(k, v)| (format!("indirect.figure.{k}"), *v)));
        }
        rows.push((i, change, mean, figures));
        previous = Some(image);
        progress.update(i as usize + 1, args.frames as usize);
    }
    let keys: std::collections::BTreeSet<String> = rows.iter().flat_map(|r| r.3.keys().cloned()).collect();
    let mut csv = String::from("frame,mean_change,mean_radiance");
    for k in &keys {
        csv += &format!(",{k}");
    }
    csv += "\n";
    for (i, change, mean, figures) in &rows {
        csv += &format!("{i},{},{mean:.6}", change.map(|c| format!("{c:.6}")).unwrap_or_default());
        for k in &keys {
            csv += &format!(",{}", figures.get(k).map(|v| v.to_string()).unwrap_or_default());
        }
        csv += "\n";
    }
    write_atomic(&args.out, csv.as_bytes())?;
    let changes: Vec<f64> = rows.iter().filter_map(|r| r.1).collect();
    let mean_change = changes.iter().sum::<f64>() / changes.len().max(1) as f64;
    let mean_radiance = rows.iter().map(|r| r.2).sum::<f64>() / rows.len() as f64;
    if !f.quiet {
        eprintln!(
            "{} + {} on {}: mean frame-to-frame change {:.3e} ({:.2} % of the mean {} radiance {:.3e})",
            args.choice.technique,
            f.indirect,
            scene.name,
            mean_change,
            100.0 * mean_change / mean_radiance.max(1e-30),
            f.component,
            mean_radiance
        );
        eprintln!("wrote {}", args.out.display());
    }
    Ok(())
}
