//! Measurement shared by `shadowlab compare`, `sweep` and `bench`: render a technique (with warm-up and
//! repeated frames for trustworthy timings), render a comparison target, compute metrics and difference images.

use std::collections::BTreeMap;

use anyhow::{anyhow, Result};
use serde::Serialize;
use shadowlab_core::compare::{self, CompareOptions, DiffMode, Image, Metrics, Visibility};
use shadowlab_core::scene::{Camera, PointLight};
use shadowlab_core::technique::Technique;
use shadowlab_core::timing::{common_clock, PassTime, TimingSource};
use shadowlab_core::{FrameReport, Renderer};

/// Timings of repeated frames of one technique.
///
/// A frame's time is its GPU work in `clock` (every step: G-buffer, shadow maps, shading, tone mapping) plus its
/// CPU stages (clustering, VPL generation, readbacks a technique waits for), which run before its GPU steps.
#[derive(Clone, Debug, Serialize)]
pub struct TimingSummary {
    pub frames: usize,
    /// The clock of `median_ms`, `min_ms`, `best3_mean_ms` and `passes_median_ms`: GPU timestamps only when
    /// every frame used them.
    pub clock: TimingSource,
    /// Why the run left the timestamps, when it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clock_reason: Option<String>,
    pub median_ms: f64,
    pub min_ms: f64,
    /// Mean of the three fastest frames (the fuzzy-clustering paper's "mean of the 3 best of 10").
    pub best3_mean_ms: f64,
    /// Per pass (or step, in wall-clock steps), the median over frames.
    pub passes_median_ms: Vec<PassTime>,
    /// Median frame time in wall-clock steps (plus CPU stages), whatever `clock` is: every summary has it, so
    /// any two compare in it.
    pub steps_median_ms: f64,
    /// Median frame time in GPU timestamps (plus CPU stages), where the adapter has them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timestamps_median_ms: Option<f64>,
    /// Median wall-clock time of a frame, from its start to its last readback (CPU stages, culling, waits and
    /// all steps).
    pub wall_median_ms: f64,
    /// The fastest frame's wall-clock time (the least disturbed on a shared machine).
    pub wall_min_ms: f64,
    /// Per CPU stage of the techniques (e.g. clustering, readbacks), the median over frames.
    pub cpu_stages_median_ms: Vec<PassTime>,
}

impl TimingSummary {
    /// The median frame time in `clock` (the wall-clock steps where these frames lack timestamps).
    pub fn median_in(&self, clock: TimingSource) -> f64 {
        shadowlab_core::timing::in_clock(clock, self.steps_median_ms, self.timestamps_median_ms)
    }
}

/// How much faster one side is than the other, both measured in `clock`.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Speedup {
    /// `against` time over `technique` time (above 1: the technique is faster).
    pub ratio: f64,
    pub clock: TimingSource,
    /// The same ratio of the frames' wall clocks (start to last readback), for a check.
    pub wall_ratio: f64,
}

impl Speedup {
    /// `technique` against `against`, in the clock both have (timestamps only when both sides used them).
    pub fn of(technique: &TimingSummary, against: &TimingSummary) -> Speedup {
        let clock = common_clock(technique.clock, against.clock);
        Speedup {
            ratio: against.median_in(clock) / technique.median_in(clock).max(1e-9),
            clock,
            wall_ratio: against.wall_median_ms / technique.wall_median_ms.max(1e-9),
        }
    }

    /// "×2.31 (GPU timestamps; wall clock ×2.28)".
    pub fn text(&self) -> String {
        format!("x{:.2} ({}; frame wall clock x{:.2})", self.ratio, self.clock.name(), self.wall_ratio)
    }
}

/// A count as people read it: whole numbers whole, means with two decimals (work counts in the CLI and the app).
pub fn count_text(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.0}")
    } else {
        format!("{v:.2}")
    }
}

pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

pub fn summarize(reports: &[FrameReport]) -> TimingSummary {
    let clock = if reports.iter().all(|r| r.timing.comparable_source() == TimingSource::GpuTimestamps) {
        TimingSource::GpuTimestamps
    } else {
        TimingSource::WallClockSteps
    };
    let totals: Vec<f64> = reports.iter().map(|r| r.frame_ms_in(clock)).collect();
    let mut sorted = totals.clone();
    sorted.sort_by(f64::total_cmp);
    let best = &sorted[..sorted.len().min(3)];
    // The passes in `clock`: a frame that used timestamps where the others did not contributes its steps.
    fn in_clock(r: &FrameReport, clock: TimingSource) -> &[PassTime] {
        if r.timing.source == clock {
            &r.passes
        } else {
            &r.steps
        }
    }
    let passes = |r| in_clock(r, clock);
    let mut names: Vec<String> = Vec::new();
    for r in reports {
        for p in passes(r) {
            if !names.contains(&p.name) {
                names.push(p.name.clone());
            }
        }
    }
    let passes_median_ms = names
        .into_iter()
        .map(|name| {
            let v: Vec<f64> =
                reports.iter().map(|r| passes(r).iter().filter(|p| p.name == name).map(|p| p.ms).sum()).collect();
            let count =
                reports.last().map(|r| passes(r).iter().filter(|p| p.name == name).map(|p| p.count).sum()).unwrap_or(0);
            PassTime { name, ms: median(v), count }
        })
        .collect();
    let mut stage_names: Vec<String> = Vec::new();
    let stages = |r: &FrameReport| -> Vec<PassTime> {
        let mut all = r.cpu_stages.clone();
        if let Some(i) = &r.indirect {
            all.extend(i.cpu_stages.iter().cloned());
        }
        all
    };
    for r in reports {
        for p in stages(r) {
            if !stage_names.contains(&p.name) {
                stage_names.push(p.name.clone());
            }
        }
    }
    let cpu_stages_median_ms = stage_names
        .into_iter()
        .map(|name| {
            let v: Vec<f64> =
                reports.iter().map(|r| stages(r).iter().filter(|p| p.name == name).map(|p| p.ms).sum()).collect();
            PassTime { name, ms: median(v), count: 1 }
        })
        .collect();
    let has_timestamps = reports.iter().all(|r| r.timing.timestamps_ms.is_some());
    TimingSummary {
        clock,
        clock_reason: reports.iter().rev().find_map(|r| r.timing.reason.clone()),
        steps_median_ms: median(reports.iter().map(|r| r.frame_ms_in(TimingSource::WallClockSteps)).collect()),
        timestamps_median_ms: has_timestamps
            .then(|| median(reports.iter().map(|r| r.frame_ms_in(TimingSource::GpuTimestamps)).collect())),
        wall_median_ms: median(reports.iter().map(|r| r.wall_ms).collect()),
        wall_min_ms: reports.iter().map(|r| r.wall_ms).reduce(f64::min).unwrap_or(0.0),
        cpu_stages_median_ms,
        frames: reports.len(),
        median_ms: median(totals),
        min_ms: sorted.first().copied().unwrap_or(0.0),
        best3_mean_ms: if best.is_empty() { 0.0 } else { best.iter().sum::<f64>() / best.len() as f64 },
        passes_median_ms,
    }
}

/// One rendered technique: its HDR image, the last frame's report and the timing summary.
pub struct Rendered {
    pub image: Image,
    pub report: FrameReport,
    pub timing: TimingSummary,
    pub parameters: BTreeMap<String, String>,
}

/// The indirect technique of one side of a comparison: `none` or a key, and its `key=value` parameters.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IndirectChoice {
    pub key: String,
    pub params: Vec<String>,
}

impl IndirectChoice {
    pub fn none() -> IndirectChoice {
        IndirectChoice { key: "none".into(), params: Vec::new() }
    }

    /// A side's name in captions and titles: `direct`, or `direct + indirect` with an indirect technique.
    pub fn name_with(&self, direct: &str) -> String {
        technique_pair(direct, (self.key != "none").then_some(self.key.as_str()))
    }

    /// A side's parameters for a caption: the direct technique's, then the indirect technique's after its key
    /// (`shadow_res=256 · val: vals=12`), "default parameters" when neither has any set.
    pub fn params_caption(&self, direct: &[String]) -> String {
        let mut parts = Vec::new();
        if !direct.is_empty() {
            parts.push(direct.join(" "));
        }
        if self.key != "none" && !self.params.is_empty() {
            parts.push(format!("{}: {}", self.key, self.params.join(" ")));
        }
        if parts.is_empty() {
            "default parameters".to_string()
        } else {
            parts.join(" · ")
        }
    }
}

/// `direct`, or `direct + indirect`: how a frame's techniques are named everywhere (views, tables, figures).
pub fn technique_pair(direct: &str, indirect: Option<&str>) -> String {
    match indirect {
        Some(i) => format!("{direct} + {i}"),
        None => direct.to_string(),
    }
}

/// Apply `--shadow-res` and `--param key=value` to a technique.
pub fn apply_params(technique: &mut dyn Technique, shadow_res: Option<u32>, params: &[String]) -> Result<()> {
    let mut all: Vec<(String, String)> = Vec::new();
    // `--shadow-res` applies to the techniques that have cube maps (not to the ray-traced truth, say).
    if let Some(r) = shadow_res.filter(|_| technique.params().iter().any(|p| p.key == "shadow_res")) {
        all.push(("shadow_res".into(), r.to_string()));
    }
    for p in params {
        let (k, v) = p.split_once('=').ok_or_else(|| anyhow!("--param '{p}': expected KEY=VALUE"))?;
        all.push((k.trim().to_string(), v.trim().to_string()));
    }
    let specs = technique.params();
    for (key, text) in all {
        let spec = specs.iter().find(|s| s.key == key).ok_or_else(|| {
            anyhow!(
                "technique '{}' has no parameter '{key}' (it has: {})",
                technique.key(),
                specs.iter().map(|s| s.key).collect::<Vec<_>>().join(", ")
            )
        })?;
        let value = spec.kind.parse(&key, &text)?;
        technique.set_param(&key, &value)?;
    }
    Ok(())
}

/// Give `renderer` the indirect technique of `choice` (or none).
pub fn apply_indirect(renderer: &mut Renderer, choice: &IndirectChoice) -> Result<()> {
    if choice.key == "none" {
        if !choice.params.is_empty() {
            return Err(anyhow!("--indirect-param given without an --indirect technique"));
        }
        renderer.set_indirect(None)?;
        return Ok(());
    }
    let mut t = renderer.create_indirect_technique(&choice.key).ok_or_else(|| {
        anyhow!(
            "unknown indirect technique '{}' (choose none or one of: {})",
            choice.key,
            shadowlab_core::technique::registry::indirect_keys()
        )
    })?;
    apply_params(t.as_mut(), None, &choice.params)?;
    renderer.set_indirect(Some(t))?;
    Ok(())
}

/// Render `technique` with `params` (`key=value`) `warmup` + `repeat` times.
#[allow(clippy::too_many_arguments)]
pub fn render_technique(
    renderer: &mut Renderer,
    technique: &str,
    shadow_res: Option<u32>,
    params: &[String],
    camera: &Camera,
    lights: &[PointLight],
    indirect: &IndirectChoice,
    warmup: u32,
    repeat: u32,
    progress: &mut dyn FnMut(&str),
) -> Result<Rendered> {
    let no_after = &mut |_: &mut Renderer, _: &dyn shadowlab_core::technique::Technique| Ok(());
    render_technique_then(
        renderer, technique, shadow_res, params, camera, lights, indirect, warmup, repeat, progress, no_after,
    )
}

/// [`render_technique`], then `after` with the renderer and the technique of the last frame (e.g. to draw the
/// technique's overlays over the output).
#[allow(clippy::too_many_arguments)]
pub fn render_technique_then(
    renderer: &mut Renderer,
    technique: &str,
    shadow_res: Option<u32>,
    params: &[String],
    camera: &Camera,
    lights: &[PointLight],
    indirect: &IndirectChoice,
    warmup: u32,
    repeat: u32,
    progress: &mut dyn FnMut(&str),
    after: &mut dyn FnMut(&mut Renderer, &dyn shadowlab_core::technique::Technique) -> Result<()>,
) -> Result<Rendered> {
    apply_indirect(renderer, indirect)?;
    let mut t = renderer.create_technique(technique).ok_or_else(|| {
        anyhow!("unknown technique '{technique}' (choose one of: {})", shadowlab_core::technique::registry::keys())
    })?;
    apply_params(t.as_mut(), shadow_res, params)?;
    let mut reports = Vec::new();
    for i in 0..warmup + repeat.max(1) {
        progress(&format!("{technique}: frame {}/{}", i + 1, warmup + repeat.max(1)));
        let r = renderer.render_frame(t.as_mut(), camera, lights, &mut |_, _| {})?;
        if i >= warmup {
            reports.push(r);
        }
    }
    let (w, h) = (renderer.settings().width, renderer.settings().height);
    let image = Image::new(w, h, renderer.read_hdr()?)?;
    after(renderer, t.as_ref())?;
    let mut parameters: BTreeMap<String, String> =
        t.params().into_iter().map(|p| (p.key.to_string(), p.value.to_string())).collect();
    if let Some(i) = renderer.indirect() {
        parameters.insert("indirect".into(), i.key().to_string());
        parameters.extend(i.params().into_iter().map(|p| (format!("indirect.{}", p.key), p.value.to_string())));
    }
    Ok(Rendered { image, timing: summarize(&reports), report: reports.pop().expect("at least one frame"), parameters })
}

/// Difference-image mode of `compare`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DiffKind {
    /// |luminance difference|, dark blue (none) to red (high).
    Absolute,
    /// Red where the technique is too bright, green where too dark.
    Signed,
    /// Difference of shadow factors (visibility) instead of final colour.
    Visibility,
}

/// What a comparison needs besides the two images: the geometry mask and, for shadow factors, the
/// unshadowed and ambient-only images (None when the images are the indirect component alone: the direct
/// lights' shadow factors are not in them, and the shadow error would read 0 whatever the images).
pub struct CompareInputs {
    pub mask: Vec<bool>,
    pub unshadowed: Image,
    pub ambient: Image,
    pub shadow_factors: bool,
}

pub fn compare_inputs(renderer: &mut Renderer, camera: &Camera, lights: &[PointLight]) -> Result<CompareInputs> {
    let no_progress = &mut |_: &str| {};
    let none = IndirectChoice::none();
    let unshadowed = render_technique(
        renderer,
        shadowlab_core::technique::registry::preview().key,
        None,
        &[],
        camera,
        lights,
        &none,
        0,
        1,
        no_progress,
    )?
    .image;
    let ambient = render_technique(
        renderer,
        shadowlab_core::technique::registry::preview().key,
        None,
        &[],
        camera,
        &[],
        &none,
        0,
        1,
        no_progress,
    )?
    .image;
    let shadow_factors = renderer.settings().component != shadowlab_core::renderer::Component::Indirect;
    Ok(CompareInputs { mask: renderer.read_geometry_mask()?, unshadowed, ambient, shadow_factors })
}

/// Metrics of `technique` against `target` and the difference image.
pub fn compare_images(
    technique: &Image,
    target: &Image,
    inputs: &CompareInputs,
    kind: DiffKind,
    gain: f32,
    flip: bool,
    exposure: f32,
) -> Result<(Metrics, image::RgbaImage)> {
    let v_t = compare::visibility_image(technique, &inputs.unshadowed, Some(&inputs.ambient))?;
    let v_r = compare::visibility_image(target, &inputs.unshadowed, Some(&inputs.ambient))?;
    let options = CompareOptions {
        flip,
        exposure,
        visibility: inputs.shadow_factors.then_some(Visibility { technique: &v_t, reference: &v_r }),
        ..Default::default()
    };
    let metrics = compare::compare(technique, target, Some(&inputs.mask), &options)?;
    let diff = match kind {
        DiffKind::Absolute => {
            compare::difference_image(technique, target, Some(&inputs.mask), DiffMode::Absolute, gain)?
        }
        DiffKind::Signed => compare::difference_image(technique, target, Some(&inputs.mask), DiffMode::Signed, gain)?,
        DiffKind::Visibility => compare::visibility_difference_image(
            &v_t,
            &v_r,
            technique.width,
            technique.height,
            Some(&inputs.mask),
            DiffMode::Absolute,
            gain,
        )?,
    };
    Ok((metrics, diff))
}

/// Values of a sweep parameter: `a:b:step` (inclusive numeric range), `v1,v2,...` or a single value.
pub fn sweep_values(spec: &str) -> Result<(String, Vec<String>)> {
    let (key, values) = spec.split_once('=').ok_or_else(|| anyhow!("--param '{spec}': expected KEY=VALUES"))?;
    let key = key.trim().to_string();
    let parts: Vec<&str> = values.split(':').collect();
    if parts.len() == 3 {
        let nums: Vec<f64> = parts
            .iter()
            .map(|p| p.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| anyhow!("--param '{spec}': a range is START:END:STEP with numbers"))?;
        let (a, b, step) = (nums[0], nums[1], nums[2]);
        if !(a.is_finite() && b.is_finite() && step.is_finite() && step > 0.0 && b >= a) {
            bail_range(spec)?;
        }
        // Counted in f64 first: `0:1e30:1` must be refused, not overflow.
        let count_f = ((b - a) / step + 1e-9).floor() + 1.0;
        if count_f.is_nan() || count_f > 1000.0 {
            return Err(anyhow!("--param '{spec}': {count_f:.0} values; at most 1000"));
        }
        let count = count_f as usize;
        let decimals = format!("{step}").split('.').nth(1).map(|d| d.len()).unwrap_or(0);
        let integers = [a, step].iter().all(|v| v.fract() == 0.0);
        let values = (0..count)
            .map(|i| {
                let v = a + step * i as f64;
                if integers {
                    format!("{}", v as i64)
                } else {
                    format!("{v:.decimals$}")
                }
            })
            .collect();
        return Ok((key, values));
    }
    let values: Vec<String> = values.split(',').map(|v| v.trim().to_string()).filter(|v| !v.is_empty()).collect();
    if values.is_empty() {
        return Err(anyhow!("--param '{spec}': no values"));
    }
    Ok((key, values))
}

fn bail_range(spec: &str) -> Result<()> {
    Err(anyhow!("--param '{spec}': a range needs finite START <= END and STEP > 0"))
}

/// Every combination of the swept values, in order (the last parameter varies fastest).
/// Most settings one sweep renders (the product of the swept lists).
pub const MAX_SWEEP_SETTINGS: usize = 10_000;

/// The number of combinations of `params`, or an error above [`MAX_SWEEP_SETTINGS`] (checked before they are
/// built: three 1,000-value lists would be a billion).
pub fn check_combinations(params: &[(String, Vec<String>)]) -> Result<usize> {
    let mut n: usize = 1;
    for (_, values) in params {
        n = n.saturating_mul(values.len());
    }
    if n > MAX_SWEEP_SETTINGS {
        let sizes: Vec<String> = params.iter().map(|(k, v)| format!("{k}: {}", v.len())).collect();
        return Err(anyhow!(
            "the swept values make {} settings ({}); at most {MAX_SWEEP_SETTINGS}",
            if n == usize::MAX { "too many".to_string() } else { n.to_string() },
            sizes.join(", ")
        ));
    }
    Ok(n)
}

pub fn combinations(params: &[(String, Vec<String>)]) -> Vec<Vec<(String, String)>> {
    let mut out: Vec<Vec<(String, String)>> = vec![Vec::new()];
    for (key, values) in params {
        out = out
            .into_iter()
            .flat_map(|prefix| {
                values.iter().map(move |v| {
                    let mut c = prefix.clone();
                    c.push((key.clone(), v.clone()));
                    c
                })
            })
            .collect();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_side_with_an_indirect_technique_is_named_and_captioned_with_both_parts() {
        let val = IndirectChoice { key: "val".into(), params: vec!["vals=12".into()] };
        assert_eq!(val.name_with("unshadowed"), "unshadowed + val");
        assert_eq!(val.params_caption(&[]), "val: vals=12");
        assert_eq!(val.params_caption(&["shadow_res=256".into()]), "shadow_res=256 · val: vals=12");
        let none = IndirectChoice::none();
        assert_eq!(none.name_with("reference"), "reference");
        assert_eq!(none.params_caption(&[]), "default parameters");
        let bare = IndirectChoice { key: "val".into(), params: Vec::new() };
        assert_eq!(bare.params_caption(&[]), "default parameters");
    }

    #[test]
    fn ranges_lists_and_single_values() {
        assert_eq!(sweep_values("d_init=0.1:0.5:0.2").unwrap().1, vec!["0.1", "0.3", "0.5"]);
        assert_eq!(sweep_values("d_init=0.1:1.6:0.1").unwrap().1.len(), 16);
        assert_eq!(sweep_values("samples=8:32:8").unwrap().1, vec!["8", "16", "24", "32"]);
        assert_eq!(sweep_values("filter=pcf,pcss").unwrap(), ("filter".into(), vec!["pcf".into(), "pcss".into()]));
        assert_eq!(sweep_values("adaptive=on").unwrap().1, vec!["on"]);
        assert!(sweep_values("d_init=1:0:0.1").is_err());
        assert!(sweep_values("d_init=0:1:0").is_err());
        assert!(sweep_values("d_init=0:1e9:1").is_err());
        assert!(sweep_values("nokey").is_err());
    }

    #[test]
    fn combinations_are_the_cartesian_product() {
        let c = combinations(&[("a".into(), vec!["1".into(), "2".into()]), ("b".into(), vec!["x".into(), "y".into()])]);
        assert_eq!(c.len(), 4);
        assert_eq!(c[1], vec![("a".to_string(), "1".to_string()), ("b".to_string(), "y".to_string())]);
    }

    #[test]
    fn timing_summary_takes_median_min_and_best_three() {
        let r = |ms: f64| FrameReport {
            technique: "t".into(),
            parameters: Default::default(),
            view_fingerprint: 0,
            width: 1,
            height: 1,
            timing: shadowlab_core::timing::FrameTiming {
                mode: shadowlab_core::timing::TimingMode::Auto,
                source: TimingSource::GpuTimestamps,
                reason: None,
                timestamps_ms: Some(ms),
                steps_wall_ms: 2.0 * ms,
            },
            passes: vec![PassTime { name: "shading".into(), ms, count: 1 }],
            total_ms: ms,
            steps: vec![PassTime { name: "shading".into(), ms: 2.0 * ms, count: 1 }],
            stage_passes: Vec::new(),
            work: Default::default(),
            cpu_stages: vec![],
            wall_ms: ms,
            counts: Default::default(),
            indirect: None,
        };
        let s = summarize(&[r(5.0), r(1.0), r(3.0), r(9.0), r(2.0)]);
        assert_eq!(s.median_ms, 3.0);
        assert_eq!(s.min_ms, 1.0);
        assert_eq!(s.best3_mean_ms, 2.0);
        assert_eq!(s.passes_median_ms[0].ms, 3.0);
        assert_eq!(s.clock, TimingSource::GpuTimestamps);
        assert_eq!(s.steps_median_ms, 6.0);
    }

    fn report(ms: f64, source: TimingSource, steps_ms: f64) -> FrameReport {
        FrameReport {
            technique: "t".into(),
            parameters: Default::default(),
            view_fingerprint: 0,
            width: 1,
            height: 1,
            timing: shadowlab_core::timing::FrameTiming {
                mode: shadowlab_core::timing::TimingMode::Auto,
                source,
                reason: None,
                timestamps_ms: Some(ms),
                steps_wall_ms: steps_ms,
            },
            passes: match source {
                TimingSource::GpuTimestamps => vec![PassTime { name: "shading".into(), ms, count: 1 }],
                TimingSource::WallClockSteps => vec![PassTime { name: "shade step".into(), ms: steps_ms, count: 1 }],
            },
            total_ms: ms,
            steps: vec![PassTime { name: "shade step".into(), ms: steps_ms, count: 1 }],
            stage_passes: Vec::new(),
            work: Default::default(),
            cpu_stages: vec![PassTime { name: "clustering".into(), ms: 1.0, count: 1 }],
            wall_ms: steps_ms + 1.0,
            counts: Default::default(),
            indirect: None,
        }
    }

    #[test]
    fn a_speedup_compares_both_sides_in_one_clock() {
        // Both in timestamps: the timestamps (plus the CPU stage) on both sides.
        let fast = summarize(&[report(1.0, TimingSource::GpuTimestamps, 3.0)]);
        let slow = summarize(&[report(9.0, TimingSource::GpuTimestamps, 11.0)]);
        let s = Speedup::of(&fast, &slow);
        assert_eq!(s.clock, TimingSource::GpuTimestamps);
        assert!((s.ratio - 10.0 / 2.0).abs() < 1e-9, "{s:?}");
        // One side in wall-clock steps: both sides in wall-clock steps, never timestamps against steps.
        let slow_wall = summarize(&[report(9.0, TimingSource::WallClockSteps, 11.0)]);
        assert_eq!(slow_wall.clock, TimingSource::WallClockSteps);
        assert_eq!(slow_wall.passes_median_ms[0].name, "shade step");
        let s = Speedup::of(&fast, &slow_wall);
        assert_eq!(s.clock, TimingSource::WallClockSteps);
        assert!((s.ratio - 12.0 / 4.0).abs() < 1e-9, "{s:?}");
        assert!((s.wall_ratio - 12.0 / 4.0).abs() < 1e-9, "{s:?}");
        // A run that changed clock between frames is summarized in wall-clock steps throughout.
        let mixed =
            summarize(&[report(1.0, TimingSource::GpuTimestamps, 3.0), report(1.0, TimingSource::WallClockSteps, 3.0)]);
        assert_eq!(mixed.clock, TimingSource::WallClockSteps);
        assert_eq!(mixed.median_ms, 4.0);
        assert_eq!(mixed.passes_median_ms[0].name, "shade step");
    }
}
