//! `shadowlab tradeoff`: several techniques with ranges of their parameters on one view against one target;
//! error against time per frame (the trusted clock) and work counts, the Pareto front, and with a budget the
//! pick: the lowest error within `--budget-ms`, or the fastest frame within `--max-error`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use shadowlab_core::technique::{self, work::WORK_KEYS};
use shadowlab_core::timing::common_clock;

use super::args::{check_indirect, FrameArgs, SceneArgs};
use super::progress::Progress;
use super::setup::setup;
use crate::files::{check_output_path, write_atomic};
use crate::measure::{apply_indirect, apply_params, IndirectChoice, Rendered, TimingSummary};
use crate::tradeoff::{self, Goal, Metric, Point, TrySpec};

#[derive(Args, Debug)]
pub struct TradeoffArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// A technique and the values of its parameters to try: `"lightcluster d_init=0.2:1.6:0.2 filter=pcf,pcss"`,
    /// `"insm insm_res=64,128,256"`, `reference`, `"val vals=2,8,30"` (an indirect technique over `--direct`),
    /// `"unshadowed+val indirect.vals=8"`; values as `sweep --param` takes them; repeatable.
    #[arg(long = "try", value_name = "SPEC", required = true)]
    pub tries: Vec<String>,
    /// The direct technique of a try that names only an indirect technique.
    #[arg(long, default_value = technique::registry::REFERENCE)]
    pub direct: String,
    /// The comparison target, written like a try with one value per parameter: `reference`, `raytraced`,
    /// `"reference+vpl-shadowmaps"`, `"pathtraced samples=64"`. Its indirect technique is `--indirect`'s unless
    /// it names one (or `--against-indirect` does).
    #[arg(long, default_value = technique::registry::REFERENCE)]
    pub against: String,
    /// The comparison target's indirect technique.
    #[arg(long = "against-indirect", value_name = "KEY")]
    pub against_indirect: Option<String>,
    /// A parameter of the target's indirect technique, `key=value`; repeatable.
    #[arg(long = "against-indirect-param", value_name = "KEY=VALUE")]
    pub against_indirect_params: Vec<String>,
    /// The error: RMSE of the HDR image, FLIP (perceptual, of the display-referred image) or the shadow error
    /// (mean |visibility difference| over lit pixels).
    #[arg(long, value_enum, default_value = "rmse")]
    pub metric: Metric,
    /// The lowest error within this time per frame (ms, in the run's clock); bisects monotone numeric
    /// parameters instead of rendering every setting.
    #[arg(long, conflicts_with = "max_error")]
    pub budget_ms: Option<f64>,
    /// The fastest frame within this error (in `--metric`).
    #[arg(long)]
    pub max_error: Option<f64>,
    /// A work count for the plot's second panel (error against work): one of the work keys
    /// (`depth_triangles`, `shadow_lookups`, `shadow_rays`, ...), the direct and indirect techniques' summed.
    #[arg(long, value_name = "KEY")]
    pub work_axis: Option<String>,
    /// One row per rendered configuration (CSV), with a `pareto` column.
    #[arg(long)]
    pub out: PathBuf,
    /// A PNG plot of error against time (and work), one colour per try, the Pareto front drawn.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// One rendered configuration and what was measured of it.
struct Row {
    try_index: usize,
    setting: tradeoff::Setting,
    timing: TimingSummary,
    metrics: shadowlab_core::compare::Metrics,
    error: f64,
    work: BTreeMap<String, f64>,
}

fn goal(args: &TradeoffArgs) -> Result<Goal> {
    match (args.budget_ms, args.max_error) {
        (Some(t), _) if !(t.is_finite() && t > 0.0) => bail!("--budget-ms {t}: give a time above 0 ms"),
        (Some(t), _) => Ok(Goal::BudgetMs(t)),
        (_, Some(e)) if !(e.is_finite() && e >= 0.0) => bail!("--max-error {e}: give an error of 0 or more"),
        (_, Some(e)) => Ok(Goal::MaxError(e)),
        _ => Ok(Goal::All),
    }
}

/// The target: a try with one value per parameter. On the indirect component alone, a target that names no
/// indirect technique (and no `--against-indirect`) takes the tries' indirect technique's own comparison target
/// (`vpl-shadowmaps` for `val`), said unless quiet: without it the tries' indirect light was compared with the
/// target's none, or with the same technique, which differs by nothing.
fn target(args: &TradeoffArgs, tries: &[TrySpec]) -> Result<(String, Vec<String>, IndirectChoice)> {
    let spec = TrySpec::parse(&args.against, &args.direct, &args.frame.indirect)
        .map_err(|e| anyhow!("{}", e.to_string().replace("--try", "--against")))?;
    if let Some((k, v)) = spec.params.iter().find(|(_, v)| v.len() != 1) {
        bail!("--against '{}': '{k}' has {} values; the target takes one", args.against, v.len());
    }
    let setting: tradeoff::Setting = spec.params.iter().map(|(k, v)| (k.clone(), v[0].clone())).collect();
    let named_indirect = spec.indirect != args.frame.indirect || args.against.contains('+');
    let mut indirect = tradeoff::indirect_choice(&spec.indirect, &setting);
    if let Some(k) = &args.against_indirect {
        check_indirect(k)?;
        indirect = IndirectChoice { key: k.clone(), params: args.against_indirect_params.clone() };
    } else if !args.against_indirect_params.is_empty() {
        bail!("--against-indirect-param needs --against-indirect");
    } else if !named_indirect {
        let own_target =
            tries.iter().find(|t| t.indirect != "none").filter(|_| args.frame.component == "indirect").and_then(|t| {
                technique::registry::own_indirect_target(&t.indirect).map(|target| (&t.indirect, target))
            });
        match own_target {
            Some((key, target)) => {
                if !args.frame.quiet {
                    eprintln!(
                        "note: the indirect component of {key} against its own target, {target} (--against \
                         KEY+INDIRECT or --against-indirect chooses another)"
                    );
                }
                indirect = IndirectChoice { key: target.to_string(), params: Vec::new() };
            }
            None => indirect.params.extend(args.frame.indirect_params.iter().cloned()),
        }
    }
    Ok((spec.technique, tradeoff::direct_params(&setting), indirect))
}

pub fn run(args: TradeoffArgs) -> Result<()> {
    check_output_path(&args.out, "csv")?;
    if let Some(p) = &args.plot {
        check_output_path(p, "png")?;
    }
    if let Some(k) = &args.work_axis {
        if !WORK_KEYS.contains(&k.as_str()) {
            bail!("--work-axis '{k}': choose one of {}", WORK_KEYS.join(", "));
        }
    }
    check_indirect(&args.frame.indirect)?;
    if args.frame.indirect == "none" && !args.frame.indirect_params.is_empty() {
        bail!("--indirect-param given without an --indirect technique");
    }
    let goal = goal(&args)?;
    let mut tries: Vec<TrySpec> =
        args.tries.iter().map(|t| TrySpec::parse(t, &args.direct, &args.frame.indirect)).collect::<Result<_>>()?;
    // A try over `--indirect`'s technique takes `--indirect-param`s too, under the values it names itself.
    for t in tries.iter_mut().filter(|t| t.indirect == args.frame.indirect && t.indirect != "none") {
        for pair in &args.frame.indirect_params {
            let (k, v) =
                pair.split_once('=').ok_or_else(|| anyhow!("--indirect-param '{pair}': expected KEY=VALUE"))?;
            let key = format!("{}{}", tradeoff::INDIRECT_PREFIX, k.trim());
            if t.params.iter().all(|(existing, _)| *existing != key) {
                t.params.push((key, vec![v.trim().to_string()]));
            }
        }
    }
    let grid: usize = tries.iter().map(TrySpec::setting_count).sum();
    for t in &tries {
        crate::measure::check_combinations(&t.params).with_context(|| format!("--try '{}'", t.label()))?;
    }
    if grid > crate::measure::MAX_SWEEP_SETTINGS {
        bail!("the tries make {grid} settings; at most {}", crate::measure::MAX_SWEEP_SETTINGS);
    }
    let (against, against_params, against_indirect) = target(&args, &tries)?;
    let f = &args.frame;
    let (_gpu, mut renderer, scene, lights, camera) = setup(&args.scene, f)?;
    // Every setting checked before the first (slow) render: each parameter's values applied once.
    for t in &tries {
        let mut probe = renderer.create_technique(&t.technique).ok_or_else(|| anyhow!("unknown technique"))?;
        for (key, values) in &t.params {
            for v in values {
                let one = vec![(key.clone(), v.clone())];
                apply_params(probe.as_mut(), f.shadow_res, &tradeoff::direct_params(&one))
                    .with_context(|| format!("--try '{}'", t.label()))?;
                let indirect = tradeoff::indirect_choice(&t.indirect, &one);
                apply_indirect(&mut renderer, &indirect).with_context(|| format!("--try '{}'", t.label()))?;
            }
        }
    }
    let quiet = f.quiet;
    let flip = args.metric == Metric::Flip;
    let render = |renderer: &mut shadowlab_core::Renderer,
                  technique: &str,
                  params: &[String],
                  indirect: &IndirectChoice|
     -> Result<Rendered> {
        crate::measure::render_technique(
            renderer,
            technique,
            f.shadow_res,
            params,
            &camera,
            &lights,
            indirect,
            f.warmup,
            f.repeat,
            &mut |_: &str| {},
        )
    };
    let target = render(&mut renderer, &against, &against_params, &against_indirect)?;
    let inputs = crate::measure::compare_inputs(&mut renderer, &camera, &lights)?;
    let mut rows: Vec<Row> = Vec::new();
    let mut progress = Progress::new("tradeoff", quiet).with_unit("frame");
    let expected = tradeoff::expected_renders(&tries, goal);
    progress.update(0, expected);
    let mut clock = target.timing.clock;
    let mut told_clock = false;
    let mut eval = |t: usize, setting: &tradeoff::Setting| -> Result<Point> {
        let spec = &tries[t];
        let r = render(
            &mut renderer,
            &spec.technique,
            &tradeoff::direct_params(setting),
            &tradeoff::indirect_choice(&spec.indirect, setting),
        )
        .with_context(|| format!("{} {}", spec.label(), tradeoff::setting_text(setting)))?;
        let (m, _) = crate::measure::compare_images(
            &r.image,
            &target.image,
            &inputs,
            crate::measure::DiffKind::Absolute,
            1.0,
            flip,
            f.exposure,
        )?;
        let error = args.metric.of(&m)?;
        if let Some(reason) = r.timing.clock_reason.as_ref().filter(|_| !told_clock && !quiet) {
            eprintln!("timing: {reason}");
            told_clock = true;
        }
        clock = common_clock(clock, r.timing.clock);
        let mut work: BTreeMap<String, f64> = r.report.work.iter().map(|(k, v)| (k.clone(), *v)).collect();
        if let Some(ind) = &r.report.indirect {
            work.extend(ind.work.iter().map(|(k, v)| (format!("indirect.{k}"), *v)));
        }
        let point = Point { ms: r.timing.median_in(clock), error };
        rows.push(Row { try_index: t, setting: setting.clone(), timing: r.timing, metrics: m, error, work });
        progress.update(rows.len(), expected.max(rows.len()));
        Ok(point)
    };
    let evaluated = tradeoff::search(&tries, goal, &mut eval, &|| false)?;
    debug_assert_eq!(evaluated.len(), rows.len());
    // Every row and the target in one clock, chosen once all are in; the front and the pick in it.
    // The target timed again after the tries: on a shared machine one of the two can be disturbed; the faster
    // median is its time, and a large difference is said.
    let again = render(&mut renderer, &against, &against_params, &against_indirect)?;
    let clock =
        rows.iter().fold(common_clock(target.timing.clock, again.timing.clock), |c, r| common_clock(c, r.timing.clock));
    let points: Vec<Point> = rows.iter().map(|r| Point { ms: r.timing.median_in(clock), error: r.error }).collect();
    let front = tradeoff::pareto(&points);
    let pick = tradeoff::pick(&points, goal);
    let (first_ms, again_ms) = (target.timing.median_in(clock), again.timing.median_in(clock));
    let target_ms = first_ms.min(again_ms);
    if !quiet && first_ms.max(again_ms) > 1.2 * target_ms {
        eprintln!(
            "note: the target took {first_ms:.2} ms before the tries and {again_ms:.2} ms after them ({}): the \
             machine was disturbed; its time is the faster",
            clock.name()
        );
    }

    let work_keys: BTreeSet<&String> =
        rows.iter().flat_map(|r| r.work.iter().filter(|(_, v)| **v != 0.0).map(|(k, _)| k)).collect();
    let mut csv = String::from(
        "try,technique,indirect,parameters,ms,clock,against_ms,speedup,error,metric,rmse,psnr_db,flip,shadow_error,\
         share_over_5pct,wall_ms,pareto,pick",
    );
    for k in &work_keys {
        csv += &format!(",work.{k}");
    }
    csv.push('\n');
    for (i, (r, p)) in rows.iter().zip(&points).enumerate() {
        let spec = &tries[r.try_index];
        let m = &r.metrics;
        let cells = [
            spec.label(),
            spec.technique.clone(),
            spec.indirect.clone(),
            tradeoff::setting_text(&r.setting),
            format!("{:.3}", p.ms),
            clock.name().to_string(),
            format!("{target_ms:.3}"),
            format!("{:.3}", target_ms / p.ms.max(1e-9)),
            format!("{:.6}", r.error),
            args.metric.name().to_string(),
            format!("{:.6}", m.rmse),
            m.psnr_db.map(|v| format!("{v:.2}")).unwrap_or_else(|| "inf".into()),
            m.flip_mean.map(|v| format!("{v:.4}")).unwrap_or_default(),
            m.shadow_intensity_error.map(|v| format!("{v:.5}")).unwrap_or_default(),
            format!("{:.4}", m.share_over_threshold),
            format!("{:.3}", r.timing.wall_median_ms),
            front[i].to_string(),
            (pick == Some(i)).to_string(),
        ];
        csv += &cells.map(|c| if c.contains(',') { format!("\"{c}\"") } else { c }).join(",");
        for k in &work_keys {
            csv += &format!(",{}", r.work.get(*k).map(|v| v.to_string()).unwrap_or_default());
        }
        csv.push('\n');
    }
    write_atomic(&args.out, csv.as_bytes())?;

    let target_name = tradeoff::label(&against, &against_indirect.key);
    if !quiet {
        eprintln!(
            "{} configurations of {} tries on {} ({} lights, {}x{}) against {target_name} at {target_ms:.2} ms \
             ({}); the Pareto front:",
            rows.len(),
            tries.len(),
            scene.name,
            lights.len(),
            f.width,
            f.height,
            clock.name()
        );
        for (i, r) in rows.iter().enumerate().filter(|(i, _)| front[*i]) {
            eprintln!(
                "  {:<24} {:<36} {:>9.2} ms  {} {:.5}",
                tries[r.try_index].label(),
                tradeoff::setting_text(&r.setting),
                points[i].ms,
                args.metric.name(),
                points[i].error
            );
        }
        eprintln!("wrote {}", args.out.display());
    }
    let frames_per_config = f.warmup + f.repeat.max(1);
    match goal {
        Goal::All => {}
        _ => {
            let limit = match goal {
                Goal::BudgetMs(t) => format!("within {t} ms per frame"),
                Goal::MaxError(e) => format!("within {} {e}", args.metric.name()),
                Goal::All => unreachable!(),
            };
            match pick {
                Some(i) => {
                    let r = &rows[i];
                    println!(
                        "pick: {} {} {:.3} ms {} {:.6}",
                        tries[r.try_index].label(),
                        tradeoff::setting_text(&r.setting),
                        points[i].ms,
                        args.metric.name(),
                        r.error
                    );
                }
                None => println!("pick: nothing fits {limit} (the fastest tried: {:.3} ms)", {
                    points.iter().map(|p| p.ms).fold(f64::INFINITY, f64::min)
                }),
            }
            println!(
                "searched {limit}: {} of the {grid} configurations rendered ({} frames, {frames_per_config} each), \
                 time in {}",
                rows.len(),
                rows.len() as u32 * frames_per_config,
                clock.name()
            );
        }
    }
    if let Some(path) = &args.plot {
        let names = crate::tradeoff::series_labels(&tries);
        let series: Vec<crate::plot::TradeoffPoint> = rows
            .iter()
            .zip(&points)
            .enumerate()
            .map(|(i, (r, p))| crate::plot::TradeoffPoint {
                series: names[r.try_index].clone(),
                ms: p.ms,
                error: p.error,
                // The frame's whole count: the direct technique's and the indirect one's.
                work: args.work_axis.as_ref().map(|k| {
                    r.work.get(k).copied().unwrap_or(0.0) + r.work.get(&format!("indirect.{k}")).copied().unwrap_or(0.0)
                }),
                pareto: front[i],
                pick: pick == Some(i),
            })
            .collect();
        let title = format!(
            "{} against {target_name} on {} ({} lights, {}x{}), time in {}",
            args.metric.name(),
            scene.name,
            lights.len(),
            f.width,
            f.height,
            clock.name()
        );
        let tmp = path.with_extension("png.tmp.png");
        crate::plot::tradeoff_plot(
            &tmp,
            &title,
            args.metric.name(),
            &series,
            Some((&target_name, target_ms)),
            args.work_axis.as_deref(),
        )?;
        std::fs::rename(&tmp, path).with_context(|| format!("cannot write {}", path.display()))?;
        if !quiet {
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
}
