//! `shadowlab animate`: the lights moved a step a frame (and the camera turned a step about its target), the
//! flicker measured, each frame's time and passes (all frames in one clock, named in the `clock` column) and, with
//! `--against-indirect`, its error against a target rendered from the same camera and lights; CSV rows.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;
use shadowlab_core::compare::{self, CompareOptions, Image};
use shadowlab_core::scene::PointLight;

use super::args::{check_technique, parse_step, FrameArgs, SceneArgs, TechniqueChoice};
use super::progress::Progress;
use super::setup::{parse_vec3s, setup};
use crate::files::{check_output_path, write_atomic};
use crate::measure::IndirectChoice;

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
    /// The camera's turn about its target per frame, in degrees (the target: `--camera`'s, else the point
    /// `sequence` orbits); 0 keeps the camera still.
    #[arg(long, default_value_t = 0.0)]
    pub orbit: f32,
    /// Render every frame also with this indirect technique (the same direct technique, camera and lights, in
    /// a renderer of its own so the animated technique keeps its state) and report the frame's error against
    /// it (`rmse`, `psnr_db`, `share_over_5pct` of the chosen component).
    #[arg(long = "against-indirect", value_name = "KEY")]
    pub against_indirect: Option<String>,
    /// A parameter of the target's indirect technique, `key=value`; repeatable.
    #[arg(long = "against-indirect-param", value_name = "KEY=VALUE")]
    pub against_indirect_params: Vec<String>,
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
    if !args.orbit.is_finite() || args.orbit.abs() > 360.0 {
        bail!("--orbit {}: degrees per frame, between -360 and 360", args.orbit);
    }
    if args.against_indirect.is_none() && !args.against_indirect_params.is_empty() {
        bail!("--against-indirect-param needs --against-indirect");
    }
    let (_gpu, mut renderer, scene, lights, camera) = setup(&args.scene, &args.frame)?;
    let f = &args.frame;
    let mut technique = args.choice.create(&renderer, f.shadow_res)?;
    crate::measure::apply_indirect(&mut renderer, &f.indirect_choice())?;
    // The target: a renderer of its own (the animated technique's state, such as clusters kept from the last
    // frame, must not be replaced by the target's).
    let mut target = match &args.against_indirect {
        Some(key) => {
            let (gpu, mut r, ..) = setup(&args.scene, &args.frame)?;
            let t = args.choice.create(&r, f.shadow_res)?;
            let choice = IndirectChoice { key: key.clone(), params: args.against_indirect_params.clone() };
            crate::measure::apply_indirect(&mut r, &choice)?;
            Some((gpu, r, t))
        }
        None => None,
    };
    let orbit_target = match &f.camera {
        Some(text) => parse_vec3s(text)?.1,
        None => crate::sequence::orbit_target(&camera, &scene.bounds),
    };
    let mut previous: Option<Vec<[f32; 4]>> = None;
    // Per frame: index, change against the previous frame, mean radiance, figures (times and errors too).
    type FrameRow = (u32, Option<f64>, f64, std::collections::BTreeMap<String, f64>);
    let mut rows: Vec<FrameRow> = Vec::new();
    let mut reports = Vec::new();
    let mut progress = Progress::new(&format!("animate {}", args.choice.technique), f.quiet).with_unit("frame");
    for i in 0..args.frames {
        let moved: Vec<PointLight> =
            lights.iter().map(|l| PointLight { position: l.position + step * i as f32, ..*l }).collect();
        let camera = if args.orbit != 0.0 {
            crate::sequence::orbit_camera(&camera, orbit_target, (args.orbit * i as f32).to_radians())
        } else {
            camera
        };
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
        figures.extend(report.work.iter().map(|(k, v)| (format!("work.{k}"), *v)));
        if let Some(ind) = &report.indirect {
            figures.extend(ind.counts.figures.iter().map(|(k, v)| (format!("indirect.figure.{k}"), *v)));
            figures.extend(ind.work.iter().map(|(k, v)| (format!("indirect.work.{k}"), *v)));
        }
        if let Some((_, r, t)) = &mut target {
            r.render_frame(t.as_mut(), &camera, &moved, &mut |_, _| {})?;
            let (w, h) = (r.settings().width, r.settings().height);
            let reference = Image::new(w, h, r.read_hdr()?)?;
            let mask = r.read_geometry_mask()?;
            let options = CompareOptions { flip: false, ..Default::default() };
            let m = compare::compare(&Image::new(w, h, image.clone())?, &reference, Some(&mask), &options)?;
            figures.insert("rmse".into(), m.rmse);
            figures.insert("psnr_db".into(), m.psnr_db.unwrap_or(f64::INFINITY));
            figures.insert("share_over_5pct".into(), m.share_over_threshold);
        }
        rows.push((i, change, mean, figures));
        reports.push(report);
        previous = Some(image);
        progress.update(i as usize + 1, args.frames as usize);
    }
    // Every frame's time in one clock: the GPU timestamps where every frame has trustworthy ones, else the
    // wall-clock steps (`SHADOWLAB_TIMING=auto` may leave the timestamps in any frame), as `sweep` does.
    let clock = crate::measure::summarize(&reports).clock;
    for (row, report) in rows.iter_mut().zip(&reports) {
        row.3.insert("ms".into(), report.frame_ms_in(clock));
        let passes = if report.timing.source == clock { &report.passes } else { &report.steps };
        for p in passes {
            // A pass name is a column's name: no commas in a CSV header.
            *row.3.entry(format!("pass.{}_ms", p.name.replace(',', ";"))).or_default() += p.ms;
        }
    }
    let keys: std::collections::BTreeSet<String> = rows.iter().flat_map(|r| r.3.keys().cloned()).collect();
    let clock = clock.name();
    let mut csv = String::from("frame,mean_change,mean_radiance,clock");
    for k in &keys {
        csv += &format!(",{k}");
    }
    csv += "\n";
    for (i, change, mean, figures) in &rows {
        csv += &format!("{i},{},{mean:.6},{clock}", change.map(|c| format!("{c:.6}")).unwrap_or_default());
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
