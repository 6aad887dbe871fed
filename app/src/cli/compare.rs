//! `shadowlab compare`: a technique against a comparison target: the difference image, the metrics, a figure.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;
use serde::Serialize;

use super::args::{FrameArgs, SceneArgs, TargetArgs};
use super::setup::setup;
use crate::files::{check_output_path, encode_png, write_atomic};

#[derive(Args, Debug)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    #[command(flatten)]
    pub target: TargetArgs,
    /// A technique parameter, `key=value`; repeatable.
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// Difference image mode.
    #[arg(long, value_enum, default_value = "absolute")]
    pub mode: crate::measure::DiffKind,
    /// Gain of the difference image (1, 5, 10, ...).
    #[arg(long, default_value_t = 1.0)]
    pub gain: f32,
    /// Skip the FLIP metric (the slowest one).
    #[arg(long)]
    pub no_flip: bool,
    /// Difference image (PNG).
    #[arg(long)]
    pub out: PathBuf,
    /// The technique's own image (PNG).
    #[arg(long)]
    pub image: Option<PathBuf>,
    /// A paper-style figure (PNG): the technique, the target and the difference side by side, with captions.
    #[arg(long)]
    pub figure: Option<PathBuf>,
    /// Metrics and timings as JSON.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Measure both sides this many times over, alternating (the target, the technique, the target, ...), and
    /// give the median of the rounds' speedups, each against the target of its own round, with their range: on
    /// a shared machine a load that comes and goes then falls on both sides. The images and metrics are the
    /// first round's.
    #[arg(long, default_value_t = 1)]
    pub rounds: u32,
}

#[derive(Serialize)]
struct CompareReport<'a> {
    adapter: String,
    scene: &'a str,
    lights: usize,
    width: u32,
    height: u32,
    technique: &'a str,
    technique_parameters: &'a std::collections::BTreeMap<String, String>,
    against: &'a str,
    against_parameters: &'a std::collections::BTreeMap<String, String>,
    metrics: &'a shadowlab_core::compare::Metrics,
    technique_timing: &'a crate::measure::TimingSummary,
    against_timing: &'a crate::measure::TimingSummary,
    /// Same-run speedup of the technique over the comparison target (median frame times, both in one clock).
    speedup: crate::measure::Speedup,
    technique_counts: &'a shadowlab_core::renderer::FrameCounts,
    /// Hardware-independent work of each side's last frame, direct and indirect together.
    technique_work: std::collections::BTreeMap<String, f64>,
    against_work: std::collections::BTreeMap<String, f64>,
    /// The component the metrics were computed on.
    component: &'a str,
    indirect: &'a crate::measure::IndirectChoice,
    against_indirect: &'a crate::measure::IndirectChoice,
    /// VPLs the technique side used (absent without an indirect technique).
    vpls: Option<usize>,
    technique_indirect: Option<&'a shadowlab_core::renderer::IndirectReport>,
    against_report_indirect: Option<&'a shadowlab_core::renderer::IndirectReport>,
    /// Set when the two sides' maps are not at one resolution (both named).
    resolution_note: Option<&'a str>,
    /// With `--rounds` above 1: each round's speedup and the medians `speedup` comes from.
    #[serde(skip_serializing_if = "Option::is_none")]
    rounds: Option<crate::rounds::Rounds>,
}

pub fn run(args: CompareArgs) -> Result<()> {
    check_output_path(&args.out, "png")?;
    if let Some(r) = &args.report {
        check_output_path(r, "json")?;
    }
    if let Some(r) = &args.image {
        check_output_path(r, "png")?;
    }
    if let Some(r) = &args.figure {
        check_output_path(r, "png")?;
    }
    let mut args = args;
    args.target.resolve(args.frame.component == "indirect", args.frame.quiet);
    args.target.check()?;
    if !(args.gain.is_finite() && args.gain > 0.0) {
        bail!("--gain {}: must be a number > 0", args.gain);
    }
    crate::rounds::check(args.rounds)?;
    let (gpu, mut renderer, scene, lights, camera) = setup(&args.scene, &args.frame)?;
    let f = &args.frame;
    let quiet = f.quiet;
    let mut say = |m: &str| {
        if !quiet {
            eprintln!("{m}");
        }
    };
    let indirect = f.indirect_choice();
    let against_indirect = args.target.against_indirect(&indirect, f.component == "indirect", quiet)?;
    // Each side as one measurement (every round renders both the same way).
    let render_target = |renderer: &mut shadowlab_core::Renderer, progress: &mut dyn FnMut(&str)| {
        crate::measure::render_technique(
            renderer,
            &args.target.against,
            f.shadow_res,
            &args.target.against_params,
            &camera,
            &lights,
            &against_indirect,
            f.warmup,
            f.repeat,
            progress,
        )
    };
    let render_tech = |renderer: &mut shadowlab_core::Renderer, progress: &mut dyn FnMut(&str)| {
        crate::measure::render_technique(
            renderer,
            &args.target.technique,
            f.shadow_res,
            &args.params,
            &camera,
            &lights,
            &indirect,
            f.warmup,
            f.repeat,
            progress,
        )
    };
    let target = render_target(&mut renderer, &mut say)?;
    let target_image = args.figure.as_ref().map(|_| renderer.read_output()).transpose()?;
    let tech = render_tech(&mut renderer, &mut say)?;
    let tech_image = renderer.read_output()?;
    if let Some(path) = &args.image {
        write_atomic(path, &encode_png(&tech_image)?)?;
    }
    let inputs = crate::measure::compare_inputs(&mut renderer, &camera, &lights)?;
    let (metrics, diff) = crate::measure::compare_images(
        &tech.image,
        &target.image,
        &inputs,
        args.mode,
        args.gain,
        !args.no_flip,
        f.exposure,
    )?;
    let mut speedup = crate::measure::Speedup::of(&tech.timing, &target.timing);
    let clock = speedup.clock;
    // Later rounds: both sides again, times only; the speedup becomes the median of the rounds'.
    let (mut tech_ms, mut against_ms) = (tech.timing.median_in(clock), target.timing.median_in(clock));
    let mut rounds = None;
    if args.rounds > 1 {
        let mut times = vec![crate::rounds::Round::of(&tech.timing, &target.timing, clock)];
        for _ in 1..args.rounds {
            let t = render_target(&mut renderer, &mut |_: &str| {})?;
            let r = render_tech(&mut renderer, &mut |_: &str| {})?;
            times.push(crate::rounds::Round::of(&r.timing, &t.timing, clock));
        }
        let summary = crate::rounds::Rounds::of(&times);
        (tech_ms, against_ms) = (summary.technique_ms, summary.against_ms);
        speedup.ratio = summary.ratio;
        speedup.wall_ratio = crate::rounds::Rounds::wall_ratio(&times);
        rounds = Some(summary);
    }
    let resolution_note = crate::equal_terms::resolution_note(
        &indirect.name_with(&args.target.technique),
        &tech.parameters,
        &against_indirect.name_with(&args.target.against),
        &target.parameters,
    );
    // "median of 3", or with rounds "median of 3, over 4 rounds".
    let medians = |frames: usize| match &rounds {
        Some(r) => format!("median of {frames}, over {} rounds", r.count),
        None => format!("median of {frames}"),
    };
    if let (Some(path), Some(target_image)) = (&args.figure, target_image) {
        use crate::figure::{compose, metrics_caption, FigurePane};
        let metrics_lines = metrics_caption(&metrics);
        // Unequal map resolutions are named under each pane (the defaults differ between techniques).
        let maps_caption = |p: &std::collections::BTreeMap<String, String>| -> String {
            if resolution_note.is_none() {
                return String::new();
            }
            let [direct, indirect] = crate::equal_terms::resolutions(p);
            [(direct, "maps"), (indirect, "indirect maps")]
                .iter()
                .filter(|(r, _)| !r.is_empty())
                .map(|(r, what)| format!(" · {what} {r}²"))
                .collect()
        };
        let component = if f.component == "total" { String::new() } else { format!(" · {} light", f.component) };
        let title = format!(
            "{} · {} lights · {}x{}{component} · {}",
            scene.name,
            lights.len(),
            f.width,
            f.height,
            gpu.adapter_description()
        );
        let figure = compose(
            &title,
            &[
                FigurePane {
                    image: tech_image,
                    caption: vec![
                        indirect.name_with(&args.target.technique),
                        indirect.params_caption(&args.params) + &maps_caption(&tech.parameters),
                        format!(
                            "{:.1} ms ({}, {}), ×{:.2}",
                            tech_ms,
                            medians(tech.timing.frames),
                            clock.name(),
                            speedup.ratio
                        ),
                    ],
                },
                FigurePane {
                    image: target_image,
                    caption: vec![
                        against_indirect.name_with(&args.target.against),
                        against_indirect.params_caption(&args.target.against_params)
                            + &maps_caption(&target.parameters),
                        format!("{:.1} ms ({})", against_ms, medians(target.timing.frames)),
                    ],
                },
                FigurePane {
                    image: diff.clone(),
                    caption: vec![
                        format!("{:?} difference ×{}", args.mode, args.gain).to_lowercase(),
                        metrics_lines[0].clone(),
                        metrics_lines[1].clone(),
                    ],
                },
            ],
        )?;
        write_atomic(path, &encode_png(&figure)?)?;
    }
    write_atomic(&args.out, &encode_png(&diff)?)?;
    if !quiet {
        eprintln!(
            "{} vs {} on {} ({}x{}, {} light): RMSE {:.5}, PSNR {}, FLIP {}, shadow error {}, {:.2}% of pixels over \
             {:.0}%",
            indirect.name_with(&args.target.technique),
            against_indirect.name_with(&args.target.against),
            scene.name,
            f.width,
            f.height,
            f.component,
            metrics.rmse,
            metrics.psnr_db.map(|p| format!("{p:.2} dB")).unwrap_or_else(|| "inf".into()),
            metrics.flip_mean.map(|v| format!("{v:.4}")).unwrap_or_else(|| "-".into()),
            metrics.shadow_intensity_error.map(|v| format!("{:.2}%", v * 100.0)).unwrap_or_else(|| "-".into()),
            metrics.share_over_threshold * 100.0,
            metrics.threshold * 100.0,
        );
        if let Some(reason) = tech.timing.clock_reason.as_ref().or(target.timing.clock_reason.as_ref()) {
            eprintln!("timing: {reason}");
        }
        if let Some(note) = &resolution_note {
            eprintln!("note: {note}");
        }
        eprintln!(
            "time ({}, {}): {} {:.2} ms, {} {:.2} ms, speedup {}",
            medians(tech.timing.frames),
            clock.name(),
            indirect.name_with(&args.target.technique),
            tech_ms,
            against_indirect.name_with(&args.target.against),
            against_ms,
            speedup.text()
        );
        if let Some(r) = &rounds {
            eprintln!(
                "rounds: {} alternated, each against its own target; the median above, the rounds x{:.2} to x{:.2}",
                r.count, r.ratio_min, r.ratio_max
            );
        }
        eprintln!("wrote {}", args.out.display());
    }
    if let Some(path) = &args.report {
        let r = CompareReport {
            adapter: gpu.adapter_description(),
            scene: &args.scene.scene,
            lights: lights.len(),
            width: f.width,
            height: f.height,
            technique: &args.target.technique,
            technique_parameters: &tech.parameters,
            against: &args.target.against,
            against_parameters: &target.parameters,
            metrics: &metrics,
            technique_timing: &tech.timing,
            against_timing: &target.timing,
            speedup,
            technique_counts: &tech.report.counts,
            technique_work: tech.report.total_work(),
            against_work: target.report.total_work(),
            component: &f.component,
            indirect: &indirect,
            against_indirect: &against_indirect,
            vpls: tech.report.indirect.as_ref().map(|i| i.vpls),
            technique_indirect: tech.report.indirect.as_ref(),
            against_report_indirect: target.report.indirect.as_ref(),
            resolution_note: resolution_note.as_deref(),
            rounds,
        };
        write_atomic(path, serde_json::to_string_pretty(&r)?.as_bytes())?;
    }
    Ok(())
}
