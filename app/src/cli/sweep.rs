//! `shadowlab sweep`: a technique for every combination of parameter values against a comparison target;
//! CSV and Markdown rows, and a plot.

use std::path::PathBuf;

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use shadowlab_core::scene::layout::{self, LightLayout};
use shadowlab_core::scene::PointLight;
use shadowlab_core::Renderer;

use super::args::{FrameArgs, SceneArgs, TargetArgs};
use super::progress::Progress;
use super::setup::setup;
use crate::files::{check_output_path, write_atomic};
use crate::measure::apply_params;

#[derive(Args, Debug)]
pub struct SweepArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    #[command(flatten)]
    pub target: TargetArgs,
    /// A swept parameter: `key=START:END:STEP`, `key=v1,v2,...` or `key=value`; repeatable (all combinations).
    /// `lights=N1,N2,...` sweeps the number of lights of a `--lights random:...` layout (put it first to plot
    /// time against the light count, the comparison target's time included).
    #[arg(long = "param", value_name = "KEY=VALUES")]
    pub params: Vec<String>,
    /// Skip the FLIP metric.
    #[arg(long)]
    pub no_flip: bool,
    /// One row per setting (CSV).
    #[arg(long)]
    pub out: PathBuf,
    /// The same rows as a Markdown table.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    /// A PNG plot of time and RMSE against the first swept (numeric) parameter.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Measure the target and every setting this many times over, alternating (the target, every setting, the
    /// target, every setting, ...), and give each setting the median of its rounds' speedups, each against the
    /// target of its own round, with their range (`speedup_min`, `speedup_max`): on a shared machine a load
    /// that comes and goes during the sweep then falls on both sides. The images and metrics are the first
    /// round's.
    #[arg(long, default_value_t = 1)]
    pub rounds: u32,
}

/// The swept pseudo-parameter that changes the number of lights, not a technique parameter.
const LIGHTS_KEY: &str = "lights";

/// Prefix of swept indirect-technique parameters in a sweep setting (`--indirect-param key=VALUES`).
const INDIRECT_PREFIX: &str = "indirect.";

/// A sweep setting's technique parameters as `key=value` (without `lights` and the indirect ones).
fn technique_params(setting: &[(String, String)]) -> Vec<String> {
    setting
        .iter()
        .filter(|(k, _)| k != LIGHTS_KEY && !k.starts_with(INDIRECT_PREFIX))
        .map(|(k, v)| format!("{k}={v}"))
        .collect()
}

/// A sweep setting's indirect technique, its swept parameters included.
fn indirect_for(setting: &[(String, String)], key: &str) -> crate::measure::IndirectChoice {
    crate::measure::IndirectChoice {
        key: key.to_string(),
        params: setting
            .iter()
            .filter_map(|(k, v)| k.strip_prefix(INDIRECT_PREFIX).map(|k| format!("{k}={v}")))
            .collect(),
    }
}

pub fn run(args: SweepArgs) -> Result<()> {
    check_output_path(&args.out, "csv")?;
    if let Some(m) = &args.markdown {
        check_output_path(m, "md")?;
    }
    let mut args = args;
    args.target.resolve(args.frame.component == "indirect", args.frame.quiet);
    args.target.check()?;
    if let Some(p) = &args.plot {
        check_output_path(p, "png")?;
    }
    let mut swept: Vec<(String, Vec<String>)> =
        args.params.iter().map(|p| crate::measure::sweep_values(p)).collect::<Result<_>>()?;
    for p in &args.frame.indirect_params {
        let (k, v) = crate::measure::sweep_values(p)?;
        swept.push((format!("{INDIRECT_PREFIX}{k}"), v));
    }
    if args.frame.indirect == "none" && !args.frame.indirect_params.is_empty() {
        bail!("--indirect-param given without an --indirect technique");
    }
    if swept.is_empty() {
        bail!("sweep needs at least one --param KEY=VALUES (or --indirect-param) to sweep");
    }
    crate::measure::check_combinations(&swept)?;
    let settings = crate::measure::combinations(&swept);
    let (_gpu, mut renderer, scene, lights, camera) = setup(&args.scene, &args.frame)?;
    let f = &args.frame;
    let quiet = f.quiet;
    // Check every setting before the first (slow) render.
    {
        let mut probe =
            renderer.create_technique(&args.target.technique).ok_or_else(|| anyhow!("unknown technique"))?;
        for setting in &settings {
            apply_params(probe.as_mut(), f.shadow_res, &technique_params(setting))?;
            crate::measure::apply_indirect(&mut renderer, &indirect_for(setting, &f.indirect))?;
        }
    }
    let same_indirect = f.indirect_choice();
    let target_indirect = args.target.against_indirect(&same_indirect, f.component == "indirect", quiet)?;
    // `--param lights=N1,N2,...` sweeps the light count of a `random:` layout: the comparison target is rendered
    // again for each count.
    let layout: LightLayout = layout::parse(&args.scene.lights)?;
    let lights_for = |setting: &[(String, String)]| -> Result<Option<Vec<PointLight>>> {
        let Some((_, n)) = setting.iter().find(|(k, _)| k == LIGHTS_KEY) else { return Ok(None) };
        let count: usize = n.parse().map_err(|_| anyhow!("--param lights: '{n}' is not a light count"))?;
        let Some(counted) = layout.with_count(count) else {
            bail!(
                "--param lights needs a random or above layout (--lights random:COUNT:L_ATT:SEED or \
                 above:COUNT:L_ATT:SEED)"
            )
        };
        Ok(Some(layout::generate(&counted, &scene)?))
    };
    for setting in &settings {
        lights_for(setting)?;
    }
    crate::rounds::check(args.rounds)?;
    if args.rounds > 1 && swept.iter().any(|(k, _)| k == LIGHTS_KEY) {
        bail!("--rounds needs one light count: it cannot be combined with --param lights=...");
    }
    // The target alone (a later round's times), and with the inputs the metrics compare against.
    let time_target = |renderer: &mut Renderer, lights: &[PointLight]| {
        crate::measure::render_technique(
            renderer,
            &args.target.against,
            f.shadow_res,
            &args.target.against_params,
            &camera,
            lights,
            &target_indirect,
            f.warmup,
            f.repeat,
            &mut |_: &str| {},
        )
    };
    let render_target = |renderer: &mut Renderer, lights: &[PointLight]| -> Result<_> {
        let target = time_target(renderer, lights)?;
        let inputs = crate::measure::compare_inputs(renderer, &camera, lights)?;
        Ok((target, inputs))
    };
    // One setting, with the frame's lights.
    let render_setting = |renderer: &mut Renderer, setting: &[(String, String)], lights: &[PointLight]| {
        crate::measure::render_technique(
            renderer,
            &args.target.technique,
            f.shadow_res,
            &technique_params(setting),
            &camera,
            lights,
            &indirect_for(setting, &f.indirect),
            f.warmup,
            f.repeat,
            &mut |_: &str| {},
        )
    };
    let mut lights = lights;
    let mut light_count = None;
    if let Some(l) = settings.first().map(|s| lights_for(s)).transpose()?.flatten() {
        light_count = Some(l.len());
        lights = l;
    }
    let (mut target, mut inputs) = render_target(&mut renderer, &lights)?;
    let keys: Vec<&str> = swept.iter().map(|(k, _)| k.as_str()).collect();
    let mut header: Vec<String> = keys.iter().map(|k| k.to_string()).collect();
    header.extend(
        [
            "clusters",
            "visible_lights",
            "shadow_maps",
            "batches",
            "shadow_maps_ms",
            "shading_ms",
            "total_ms",
            "min_ms",
            "against_ms",
            "speedup",
            "clock",
            "rmse",
            "psnr_db",
            "flip",
            "shadow_error",
            "share_over_5pct",
            "fallback",
            "vpls",
            "indirect_ms",
            "wall_ms",
            "against_wall_ms",
            "wall_min_ms",
            "against_wall_min_ms",
            "wall_speedup",
            "maps_res",
            "against_maps_res",
            "indirect_maps_res",
            "against_indirect_maps_res",
            "rounds",
            "speedup_min",
            "speedup_max",
        ]
        .map(String::from),
    );
    if args.plot.is_some() && swept.first().is_none_or(|(_, v)| v.iter().any(|x| x.parse::<f64>().is_err())) {
        bail!("--plot needs a numeric first --param (the x axis)");
    }
    let mut rows: Vec<Vec<String>> = Vec::new();
    // Named figures the techniques report (`vpls`, `samples`, ...), one column each after the fixed ones.
    let mut row_figures: Vec<std::collections::BTreeMap<String, f64>> = Vec::new();
    let mut plot_rows: Vec<crate::plot::PlotRow> = Vec::new();
    let mut progress = Progress::new(&format!("sweep {}", args.target.technique), quiet).with_unit("setting");
    let renders = settings.len() * args.rounds as usize;
    progress.update(0, renders);
    // Per setting, the first round's times in its clock (later rounds add to them).
    let mut rounds_of: Vec<Vec<crate::rounds::Round>> = Vec::new();
    let mut clocks: Vec<shadowlab_core::timing::TimingSource> = Vec::new();
    let mut plotted_counts: Vec<usize> = Vec::new();
    let mut told_clock = false;
    let mut told_resolution = false;
    // The timings behind `plot_rows`: the plot shows all of them in one clock, chosen once every row is in.
    let mut plot_timings: Vec<crate::measure::TimingSummary> = Vec::new();
    for (i, setting) in settings.iter().enumerate() {
        if let Some(l) = lights_for(setting)? {
            if light_count != Some(l.len()) {
                light_count = Some(l.len());
                lights = l;
                (target, inputs) = render_target(&mut renderer, &lights)?;
            }
            // The comparison target's time is a curve of its own when the light count is the x axis.
            if setting[0].0 == LIGHTS_KEY && !plotted_counts.contains(&lights.len()) {
                plotted_counts.push(lights.len());
                plot_rows.push(crate::plot::PlotRow {
                    x: lights.len() as f64,
                    series: format!("{} (against)", args.target.against),
                    ms: 0.0,
                    rmse: None,
                });
                plot_timings.push(target.timing.clone());
            }
        }
        let r = render_setting(&mut renderer, setting, &lights)?;
        let (m, _) = crate::measure::compare_images(
            &r.image,
            &target.image,
            &inputs,
            crate::measure::DiffKind::Absolute,
            1.0,
            !args.no_flip,
            f.exposure,
        )?;
        plot_rows.push(crate::plot::PlotRow {
            x: setting[0].1.parse().unwrap_or(0.0),
            series: setting[1..].iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(" "),
            ms: 0.0,
            rmse: Some(m.rmse),
        });
        plot_timings.push(r.timing.clone());
        let speedup = crate::measure::Speedup::of(&r.timing, &target.timing);
        if let Some(reason) = r.timing.clock_reason.as_ref().or(target.timing.clock_reason.as_ref()) {
            if !told_clock && !quiet {
                eprintln!("timing: {reason}");
            }
            told_clock = true;
        }
        let c = &r.report.counts.technique;
        let pass =
            |name: &str| 0.0 + r.timing.passes_median_ms.iter().filter(|p| p.name == name).map(|p| p.ms).sum::<f64>();
        let mut row: Vec<String> = setting.iter().map(|(_, v)| v.clone()).collect();
        row.extend([
            c.clusters.map(|n| n.to_string()).unwrap_or_default(),
            c.lights_visible.to_string(),
            c.shadow_maps.to_string(),
            c.batches.to_string(),
            format!("{:.2}", pass("shadow maps")),
            format!("{:.2}", pass("shading")),
            format!("{:.2}", r.timing.median_in(speedup.clock)),
            format!("{:.2}", r.timing.min_ms),
            format!("{:.2}", target.timing.median_in(speedup.clock)),
            format!("{:.2}", speedup.ratio),
            speedup.clock.name().to_string(),
            format!("{:.5}", m.rmse),
            m.psnr_db.map(|p| format!("{p:.2}")).unwrap_or_else(|| "inf".into()),
            m.flip_mean.map(|v| format!("{v:.4}")).unwrap_or_default(),
            m.shadow_intensity_error.map(|v| format!("{:.4}", v)).unwrap_or_default(),
            format!("{:.4}", m.share_over_threshold),
            c.fell_back_to_reference.to_string(),
            r.report.indirect.as_ref().map(|i| i.vpls.to_string()).unwrap_or_default(),
            // The indirect technique's passes, by the renderer's account (whatever their names).
            r.report
                .indirect
                .as_ref()
                .map(|i| format!("{:.2}", i.passes.iter().map(|p| pass(&p.name)).sum::<f64>()))
                .unwrap_or_default(),
            format!("{:.2}", r.timing.wall_median_ms),
            format!("{:.2}", target.timing.wall_median_ms),
            format!("{:.2}", r.timing.wall_min_ms),
            format!("{:.2}", target.timing.wall_min_ms),
            // Of the fastest frames: on a shared machine the least disturbed ones.
            format!("{:.2}", target.timing.wall_min_ms / r.timing.wall_min_ms.max(1e-9)),
        ]);
        // Each side's map resolutions as rendered (the techniques' defaults differ), and a note when unequal.
        let [res, indirect_res] = crate::equal_terms::resolutions(&r.parameters);
        let [against_res, against_indirect_res] = crate::equal_terms::resolutions(&target.parameters);
        row.extend([res, against_res, indirect_res, against_indirect_res]);
        row.extend(["1".to_string(), format!("{:.2}", speedup.ratio), format!("{:.2}", speedup.ratio)]);
        rounds_of.push(vec![crate::rounds::Round::of(&r.timing, &target.timing, speedup.clock)]);
        clocks.push(speedup.clock);
        if !told_resolution && !quiet {
            let technique_name = f.indirect_choice().name_with(&args.target.technique);
            let against_name = target_indirect.name_with(&args.target.against);
            if let Some(note) =
                crate::equal_terms::resolution_note(&technique_name, &r.parameters, &against_name, &target.parameters)
            {
                eprintln!("note: {note}");
                told_resolution = true;
            }
        }
        rows.push(row);
        let mut figures: std::collections::BTreeMap<String, f64> =
            c.figures.iter().map(|(k, v)| (format!("figure.{k}"), *v)).collect();
        if let Some(ind) = &r.report.indirect {
            figures.extend(ind.counts.figures.iter().map(|(k, v)| (format!("indirect.figure.{k}"), *v)));
            // The indirect technique's own passes and CPU stages, one column each (medians over frames).
            for p in &ind.passes {
                figures.insert(format!("indirect.pass.{}_ms", p.name), pass(&p.name));
            }
        }
        for st in &r.timing.cpu_stages_median_ms {
            figures.insert(format!("cpu.{}_ms", st.name), st.ms);
        }
        // Work counts (hardware-independent), a column each where the technique does such work.
        figures.extend(r.report.work.iter().filter(|(_, v)| **v != 0.0).map(|(k, v)| (format!("work.{k}"), *v)));
        if let Some(ind) = &r.report.indirect {
            let nonzero = ind.work.iter().filter(|(k, v)| **v != 0.0 && k.as_str() != "shaded_pixels");
            figures.extend(nonzero.map(|(k, v)| (format!("indirect.work.{k}"), *v)));
        }
        row_figures.push(figures);
        progress.update(i + 1, renders);
    }
    // Later rounds: the target, then every setting again, times only.
    let mut target_rounds = vec![target.timing.clone()];
    let mut setting_rounds: Vec<Vec<crate::measure::TimingSummary>> =
        plot_timings.iter().map(|t| vec![t.clone()]).collect();
    for round in 1..args.rounds as usize {
        let t = time_target(&mut renderer, &lights)?;
        for (i, setting) in settings.iter().enumerate() {
            let r = render_setting(&mut renderer, setting, &lights)?;
            rounds_of[i].push(crate::rounds::Round::of(&r.timing, &t.timing, clocks[i]));
            setting_rounds[i].push(r.timing);
            progress.update(round * settings.len() + i + 1, renders);
        }
        target_rounds.push(t.timing);
    }
    if args.rounds > 1 {
        let column = |name: &str| header.iter().position(|h| h == name).expect("a fixed column");
        for (row, times) in rows.iter_mut().zip(&rounds_of) {
            let r = crate::rounds::Rounds::of(times);
            for (name, value) in [
                ("total_ms", r.technique_ms),
                ("against_ms", r.against_ms),
                ("speedup", r.ratio),
                ("wall_ms", r.wall_ms),
                ("against_wall_ms", r.against_wall_ms),
                ("wall_min_ms", r.wall_min_ms),
                ("against_wall_min_ms", r.against_wall_min_ms),
                ("wall_speedup", r.against_wall_min_ms / r.wall_min_ms.max(1e-9)),
                ("speedup_min", r.ratio_min),
                ("speedup_max", r.ratio_max),
            ] {
                row[column(name)] = format!("{value:.2}");
            }
            row[column("rounds")] = r.count.to_string();
        }
    }
    let figure_keys: std::collections::BTreeSet<&String> = row_figures.iter().flat_map(|f| f.keys()).collect();
    header.extend(figure_keys.iter().map(|k| k.to_string()));
    for (row, figures) in rows.iter_mut().zip(&row_figures) {
        row.extend(figure_keys.iter().map(|k| figures.get(*k).map(|v| v.to_string()).unwrap_or_default()));
    }
    let mut csv = header.join(",") + "\n";
    for row in &rows {
        csv += &(row.join(",") + "\n");
    }
    write_atomic(&args.out, csv.as_bytes())?;
    let mut md = format!("| {} |\n|{}\n", header.join(" | "), "---|".repeat(header.len()));
    for row in &rows {
        md += &format!("| {} |\n", row.join(" | "));
    }
    if !quiet {
        eprintln!(
            "{} on {} ({} lights, {}x{}), against {} at {:.2} ms:",
            args.target.technique,
            scene.name,
            lights.len(),
            f.width,
            f.height,
            args.target.against,
            target.timing.median_in(target.timing.clock)
        );
        eprint!("{md}");
        eprintln!("wrote {}", args.out.display());
    }
    if let Some(path) = &args.markdown {
        write_atomic(path, md.as_bytes())?;
    }
    if let Some(path) = &args.plot {
        // Drawn to a temporary file, then renamed, like every output.
        let tmp = path.with_extension("png.tmp.png");
        let lights_swept = swept[0].0 == LIGHTS_KEY;
        // With indirect techniques the names say both parts (`unshadowed + val`).
        let technique_name = f.indirect_choice().name_with(&args.target.technique);
        let against_name = target_indirect.name_with(&args.target.against);
        let component = if f.component == "total" { String::new() } else { format!(", {} light", f.component) };
        let title = if lights_swept {
            format!("{technique_name} and {against_name} on {} ({}x{}{component})", scene.name, f.width, f.height)
        } else {
            format!("{technique_name} on {} ({} lights, {}x{}{component})", scene.name, lights.len(), f.width, f.height)
        };
        let clock =
            plot_timings.iter().fold(target.timing.clock, |c, t| shadowlab_core::timing::common_clock(c, t.clock));
        let over_rounds = |timings: &[crate::measure::TimingSummary]| {
            crate::measure::median(timings.iter().map(|t| t.median_in(clock)).collect())
        };
        for (row, timing) in plot_rows.iter_mut().zip(&plot_timings) {
            row.ms = timing.median_in(clock);
        }
        if args.rounds > 1 {
            // One plot row per setting (no light-count curve with rounds): the median over the rounds.
            for (row, timings) in plot_rows.iter_mut().zip(&setting_rounds) {
                row.ms = over_rounds(timings);
            }
        }
        let reference_ms = (!lights_swept).then_some(over_rounds(&target_rounds));
        let title = format!("{title}, time in {}", clock.name());
        crate::plot::sweep_plot(&tmp, &title, &swept[0].0, &plot_rows, &against_name, reference_ms)?;
        std::fs::rename(&tmp, path).with_context(|| format!("cannot write {}", path.display()))?;
        if !quiet {
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
}
