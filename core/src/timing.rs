//! Per-pass timing in one clock that holds, chosen per run.
//!
//! Every step of a frame is timed both ways: GPU timestamps around each pass (wgpu-profiler, where the adapter
//! has `TIMESTAMP_QUERY`) and CPU wall time from submitting the step to its completion. `SHADOWLAB_TIMING`
//! picks the clock a report's `passes` use:
//! - `gpu`: the timestamps (the wall-clock steps where the adapter has none);
//! - `cpu`: the wall-clock steps;
//! - `auto` (the default): the timestamps, until a step's timestamps cover under [`AUTO_MIN_COVERAGE`] of its
//!   submit-to-done time (steps of at least [`AUTO_MIN_STEP_MS`], where submission overhead is small); from
//!   that frame on the run uses the wall-clock steps and says why (`FrameTiming::reason`), provided the time
//!   they miss is at least [`AUTO_MIN_MISSING_SHARE`] of the frame. Measured on
//!   lavapipe: the timestamps around fuzzy clustering's visibility dispatch read 0.03 ms of its 36.8 ms.
//!
//! Whatever the clock, a report also carries the sum of the wall-clock steps and, where the adapter has them,
//! the sum of the timestamps, so two reports are always comparable in one clock ([`common_clock`]).
//!
//! A step is waited for in one of two ways ([`StepWait`]): the CLI and the tests block on each step; the app
//! submits and goes on, and a thread of the timer's waits for the step and notes when it completed
//! ([`StepWait::Deferred`]), so the UI thread never waits for a progressive step.

use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use serde::Serialize;
use wgpu_profiler::{GpuProfiler, GpuProfilerSettings, GpuTimerQueryResult};

use crate::error::GpuError;
use crate::gpu::GpuContext;

mod step_wait;
pub use step_wait::StepWait;
use step_wait::{StepSlot, StepWaiter, Waiting};

/// A step must take at least this long from submit to completion before `auto` judges its timestamps.
pub const AUTO_MIN_STEP_MS: f64 = 2.0;
/// `auto` leaves the timestamps when a judged step's timestamps cover less than this share of its wall time...
/// (0.5 until the twenty-ninth session, which let ISM's step through at 60 %: lavapipe's timestamps around its
/// compute passes read 15-33 ms of a 70-100 ms step, its splat 0.0 ms, and a bench row read x1.01 over the
/// reference in them where the wall clocks said x0.61; the steps that hold cover 83-99 % of theirs.)
pub const AUTO_MIN_COVERAGE: f64 = 0.75;
/// ...and the time they miss is at least this share of the frame's wall-clock steps: a step whose missing time
/// is smaller cannot move a ratio of two frames by more than that, while a loaded machine delays small steps
/// (measured: a 6.7 ms tone-map step with 2.5 ms of timestamps while two test processes shared 2 cores).
pub const AUTO_MIN_MISSING_SHARE: f64 = 0.05;

/// What the user asked for (`SHADOWLAB_TIMING`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum TimingMode {
    #[default]
    Auto,
    Gpu,
    Cpu,
}

impl TimingMode {
    pub const CHOICES: &'static str = "auto, gpu or cpu";

    pub fn parse(text: &str) -> Result<TimingMode, GpuError> {
        match text.trim().to_ascii_lowercase().as_str() {
            "" | "auto" => Ok(TimingMode::Auto),
            "gpu" => Ok(TimingMode::Gpu),
            "cpu" => Ok(TimingMode::Cpu),
            other => Err(GpuError::InvalidSettings(format!(
                "SHADOWLAB_TIMING={other:?} is not a clock: choose {} (auto, the default, uses GPU timestamps \
                 unless they disagree with the wall clock)",
                TimingMode::CHOICES
            ))),
        }
    }

    /// `SHADOWLAB_TIMING`, `auto` when unset; a value that is no choice is an error naming the choices.
    pub fn from_env() -> Result<TimingMode, GpuError> {
        match std::env::var("SHADOWLAB_TIMING") {
            Ok(v) => TimingMode::parse(&v),
            Err(std::env::VarError::NotPresent) => Ok(TimingMode::Auto),
            Err(std::env::VarError::NotUnicode(_)) => {
                Err(GpuError::InvalidSettings(format!("SHADOWLAB_TIMING is not text: choose {}", TimingMode::CHOICES)))
            }
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            TimingMode::Auto => "auto",
            TimingMode::Gpu => "gpu",
            TimingMode::Cpu => "cpu",
        }
    }
}

/// The clock of a report's milliseconds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TimingSource {
    /// GPU timestamp queries around each pass.
    GpuTimestamps,
    /// CPU wall time from submitting each step to its completion.
    WallClockSteps,
}

impl TimingSource {
    /// "GPU timestamps" / "wall-clock steps", for tables and captions.
    pub fn name(self) -> &'static str {
        match self {
            TimingSource::GpuTimestamps => "GPU timestamps",
            TimingSource::WallClockSteps => "wall-clock steps",
        }
    }
}

/// The clock two sets of figures can both be compared in: the timestamps when both have them, else the
/// wall-clock steps (which every report has).
pub fn common_clock(a: TimingSource, b: TimingSource) -> TimingSource {
    if a == TimingSource::GpuTimestamps && b == TimingSource::GpuTimestamps {
        TimingSource::GpuTimestamps
    } else {
        TimingSource::WallClockSteps
    }
}

/// The clock of one frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameTiming {
    pub mode: TimingMode,
    /// The clock of the report's `passes` and `total_ms`.
    pub source: TimingSource,
    /// Why `auto` left the timestamps (set from the frame where it did, for the rest of the run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// Sum of the GPU timestamps of the frame, where the adapter has them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timestamps_ms: Option<f64>,
    /// Sum of the frame's steps from submit to completion.
    pub steps_wall_ms: f64,
}

/// A time in `clock`, from its wall-clock-steps figure and its timestamps figure (when it has one; the
/// wall-clock steps where it has none). Every "ms in a clock" of reports, summaries and the app is this.
pub fn in_clock(clock: TimingSource, steps_ms: f64, timestamps_ms: Option<f64>) -> f64 {
    match clock {
        TimingSource::GpuTimestamps => timestamps_ms.unwrap_or(steps_ms),
        TimingSource::WallClockSteps => steps_ms,
    }
}

impl FrameTiming {
    /// The frame's GPU work in `clock` (the timestamps, or the wall-clock steps where they are missing).
    pub fn ms_in(&self, clock: TimingSource) -> f64 {
        in_clock(clock, self.steps_wall_ms, self.timestamps_ms)
    }

    /// The clock this frame's figures are comparable in (timestamps only when it has them and uses them).
    pub fn comparable_source(&self) -> TimingSource {
        if self.timestamps_ms.is_some() {
            self.source
        } else {
            TimingSource::WallClockSteps
        }
    }
}

/// Time spent in passes of one name during a frame (batches of the same pass are summed).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PassTime {
    pub name: String,
    pub ms: f64,
    /// How many passes of this name ran.
    pub count: u32,
}

/// One frame's timings as [`PassTimer::finish_frame`] returns them.
pub struct FrameTimes {
    /// In the clock of `timing.source`.
    pub passes: Vec<PassTime>,
    /// Wall-clock steps, by step label (always).
    pub steps: Vec<PassTime>,
    /// GPU timestamps of passes submitted in CPU stages (their time is in the stages').
    pub stage_passes: Vec<PassTime>,
    pub timing: FrameTiming,
}

/// The step index of a query recorded in a CPU stage.
const IN_STAGE: usize = usize::MAX;

struct Step {
    label: String,
    wall_ms: f64,
}

pub struct PassTimer {
    profiler: GpuProfiler,
    timestamps: bool,
    mode: TimingMode,
    /// Set when `auto` left the timestamps; the rest of the run uses the wall-clock steps.
    reason: Option<String>,
    steps: Vec<Step>,
    /// For every timestamp query of the frame, in the order they were opened, the step it belongs to.
    query_steps: std::cell::RefCell<Vec<usize>>,
    /// While set, recorded passes belong to a technique's CPU stage (GPU work it submits and waits for in
    /// `prepare`, such as a GPU k-means): the stage's wall time holds them, so they stay out of the frame's
    /// GPU clock (else they would count twice).
    in_stage: std::cell::Cell<bool>,
    /// While set, the labels of recorded passes are the indirect technique's.
    indirect: std::cell::Cell<bool>,
    indirect_labels: std::cell::RefCell<std::collections::BTreeSet<String>>,
    wait: StepWait,
    /// Started by the first deferred step.
    waiter: Option<StepWaiter>,
    /// The frame's deferred steps (index into `steps`) and their wall times to come.
    deferred: Vec<(usize, StepSlot)>,
}

impl PassTimer {
    /// A timer in the clock `SHADOWLAB_TIMING` names (an error for a value that is no choice).
    pub fn new(gpu: &GpuContext) -> Result<PassTimer, GpuError> {
        let mode = TimingMode::from_env()?;
        let settings = GpuProfilerSettings {
            enable_timer_queries: gpu.timestamps,
            enable_debug_groups: true,
            max_num_pending_frames: 4,
        };
        let profiler = GpuProfiler::new(&gpu.device, settings).map_err(|e| GpuError::Validation(e.to_string()))?;
        Ok(PassTimer {
            profiler,
            timestamps: gpu.timestamps,
            mode,
            reason: None,
            steps: Vec::new(),
            query_steps: Default::default(),
            in_stage: std::cell::Cell::new(false),
            indirect: std::cell::Cell::new(false),
            indirect_labels: Default::default(),
            wait: StepWait::Blocking,
            waiter: None,
            deferred: Vec::new(),
        })
    }

    /// Choose how steps are waited for from the next one on; returns the way chosen (always
    /// [`StepWait::Blocking`] on the GL backend, see [`StepWait::Deferred`]).
    pub fn set_step_wait(&mut self, gpu: &GpuContext, wait: StepWait) -> StepWait {
        self.wait = if gpu.adapter_info.backend == wgpu::Backend::Gl { StepWait::Blocking } else { wait };
        self.wait
    }

    pub fn step_wait(&self) -> StepWait {
        self.wait
    }

    /// Deferred steps submitted and not yet seen to complete (0 when steps block).
    pub fn steps_in_flight(&self) -> usize {
        self.waiter.as_ref().map_or(0, StepWaiter::in_flight)
    }

    /// How many steps the current frame has submitted.
    pub fn frame_steps(&self) -> usize {
        self.steps.len()
    }

    /// The wall time of the current frame's step `i` once it has completed (a deferred step in flight has none
    /// yet): what a caller sizing its next steps can go by.
    pub fn frame_step_ms(&self, i: usize) -> Option<f64> {
        match self.deferred.iter().find(|(j, _)| *j == i) {
            Some((_, slot)) => slot.get().and_then(|r| r.as_ref().ok().copied()),
            None => self.steps.get(i).map(|s| s.wall_ms),
        }
    }

    /// Choose the clock for the rest of the run (forgets an earlier `auto` decision).
    pub fn set_mode(&mut self, mode: TimingMode) {
        self.mode = mode;
        self.reason = None;
    }

    /// The clock the next frame's passes will use.
    pub fn source(&self) -> TimingSource {
        match self.mode {
            _ if !self.timestamps => TimingSource::WallClockSteps,
            TimingMode::Cpu => TimingSource::WallClockSteps,
            TimingMode::Gpu => TimingSource::GpuTimestamps,
            TimingMode::Auto if self.reason.is_some() => TimingSource::WallClockSteps,
            TimingMode::Auto => TimingSource::GpuTimestamps,
        }
    }

    /// Mark the passes recorded from now on as a CPU stage's (or not): see `in_stage`.
    pub fn set_stage(&self, on: bool) {
        self.in_stage.set(on);
    }

    /// Mark the passes recorded from now on as the indirect technique's (or not).
    pub fn set_indirect(&self, on: bool) {
        self.indirect.set(on);
    }

    /// The labels of the passes recorded while [`PassTimer::set_indirect`] was on since the last call.
    pub fn take_indirect_labels(&self) -> std::collections::BTreeSet<String> {
        std::mem::take(&mut *self.indirect_labels.borrow_mut())
    }

    fn note(&self, label: &str) {
        if self.indirect.get() {
            self.indirect_labels.borrow_mut().insert(label.to_string());
        }
        if self.timestamps {
            let step = if self.in_stage.get() { IN_STAGE } else { self.steps.len() };
            self.query_steps.borrow_mut().push(step);
        }
    }

    /// Record a render pass named `label`; `record` fills it. The descriptor's timestamp writes are replaced.
    pub fn render_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        desc: wgpu::RenderPassDescriptor<'_>,
        record: impl FnOnce(&mut wgpu::RenderPass<'_>),
    ) {
        self.note(label);
        let query = self.profiler.begin_pass_query(label, encoder);
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(label),
                timestamp_writes: query.render_pass_timestamp_writes(),
                ..desc
            });
            record(&mut pass);
        }
        self.profiler.end_query(encoder, query);
    }

    /// Record a compute pass named `label`.
    pub fn compute_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        record: impl FnOnce(&mut wgpu::ComputePass<'_>),
    ) {
        self.note(label);
        let query = self.profiler.begin_pass_query(label, encoder);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: query.compute_pass_timestamp_writes(),
            });
            record(&mut pass);
        }
        self.profiler.end_query(encoder, query);
    }

    /// Submit one step of a frame, wait for it and record its wall time under `step_label`.
    pub fn submit(
        &mut self,
        gpu: &GpuContext,
        encoder: wgpu::CommandEncoder,
        step_label: &str,
    ) -> Result<(), GpuError> {
        if self.indirect.get() {
            self.indirect_labels.borrow_mut().insert(step_label.to_string());
        }
        let command_buffer = encoder.finish();
        if self.wait == StepWait::Deferred {
            let waiter = self.waiter.get_or_insert_with(|| StepWaiter::new(gpu.device.clone()));
            // An empty submission marks the end of what was queued before the step (the app's painting).
            let before = gpu.queue.submit([]);
            let submitted = Instant::now();
            let step = gpu.queue.submit([command_buffer]);
            let slot: StepSlot = Arc::new(OnceLock::new());
            self.steps.push(Step { label: step_label.to_string(), wall_ms: f64::NAN });
            self.deferred.push((self.steps.len() - 1, slot.clone()));
            if !waiter.send(Waiting { before, step, submitted, slot: slot.clone() }) {
                // The thread is gone (it cannot be, short of a panic in wgpu): wait here instead.
                gpu.wait_idle()?;
                let _ = slot.set(Ok(submitted.elapsed().as_secs_f64() * 1000.0));
            }
            return Ok(());
        }
        // Drain whatever else is queued first (the app's own UI painting shares the queue), so the step's wall
        // time is its own.
        gpu.wait_idle()?;
        let start = Instant::now();
        gpu.queue.submit([command_buffer]);
        gpu.wait_idle()?;
        self.steps.push(Step { label: step_label.to_string(), wall_ms: start.elapsed().as_secs_f64() * 1000.0 });
        Ok(())
    }

    /// Close the frame: resolve the queries, wait for the GPU, judge the timestamps (`auto`) and return the
    /// frame's times (passes in first-seen order for GPU timestamps).
    pub fn finish_frame(&mut self, gpu: &GpuContext) -> Result<FrameTimes, GpuError> {
        let mut encoder = gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("resolve") });
        self.profiler.resolve_queries(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
        self.profiler.end_frame().map_err(|e| GpuError::Validation(format!("timer: {e}")))?;
        gpu.wait_idle()?;
        if let Err(e) = self.collect_deferred() {
            self.steps.clear();
            self.query_steps.borrow_mut().clear();
            let _ = self.profiler.process_finished_frame(gpu.queue.get_timestamp_period());
            return Err(e);
        }
        let results = self.profiler.process_finished_frame(gpu.queue.get_timestamp_period());
        let steps = std::mem::take(&mut self.steps);
        let query_steps = std::mem::take(&mut *self.query_steps.borrow_mut());
        let mut timestamp_passes: Vec<PassTime> = Vec::new();
        let mut stage_passes: Vec<PassTime> = Vec::new();
        let mut all: Vec<(String, f64)> = Vec::new();
        if let Some(results) = &results {
            flatten(results, &mut all);
        }
        // Without one step per query (a query the adapter did not time), every query counts as a step's.
        let aligned = all.len() == query_steps.len();
        // The queries of steps, with their step, for `auto`'s judgement (only made when aligned).
        let mut flat: Vec<(String, f64)> = Vec::new();
        let mut flat_steps: Vec<usize> = Vec::new();
        for (i, (name, ms)) in all.iter().enumerate() {
            let in_stage = aligned && query_steps[i] == IN_STAGE;
            let list = if in_stage { &mut stage_passes } else { &mut timestamp_passes };
            match list.iter_mut().find(|p| &p.name == name) {
                Some(p) => {
                    p.ms += ms;
                    p.count += 1;
                }
                None => list.push(PassTime { name: name.clone(), ms: *ms, count: 1 }),
            }
            if !in_stage {
                flat.push((name.clone(), *ms));
                if aligned {
                    flat_steps.push(query_steps[i]);
                }
            }
        }
        if self.mode == TimingMode::Auto && self.timestamps && self.reason.is_none() && aligned {
            self.reason = judge(&steps, &flat, &flat_steps);
        }
        let mut step_times: Vec<PassTime> = Vec::new();
        for s in &steps {
            match step_times.iter_mut().find(|p| p.name == s.label) {
                Some(p) => {
                    p.ms += s.wall_ms;
                    p.count += 1;
                }
                None => step_times.push(PassTime { name: s.label.clone(), ms: s.wall_ms, count: 1 }),
            }
        }
        let source = self.source();
        let timing = FrameTiming {
            mode: self.mode,
            source,
            reason: self.reason.clone(),
            timestamps_ms: (self.timestamps && results.is_some()).then(|| flat.iter().map(|(_, ms)| ms).sum()),
            steps_wall_ms: steps.iter().map(|s| s.wall_ms).sum(),
        };
        let passes = match source {
            TimingSource::GpuTimestamps => timestamp_passes,
            TimingSource::WallClockSteps => step_times.clone(),
        };
        Ok(FrameTimes { passes, steps: step_times, stage_passes, timing })
    }
}

impl PassTimer {
    /// Fill in the wall times of the frame's deferred steps (call once the GPU is idle).
    fn collect_deferred(&mut self) -> Result<(), GpuError> {
        if self.deferred.is_empty() {
            return Ok(());
        }
        if let Some(waiter) = &self.waiter {
            waiter.drain(Duration::from_secs(10))?;
        }
        for (i, slot) in std::mem::take(&mut self.deferred) {
            let wall = match slot.get() {
                Some(Ok(ms)) => *ms,
                Some(Err(e)) => return Err(GpuError::Validation(e.clone())),
                None => return Err(GpuError::Validation("a deferred step's completion was not seen".into())),
            };
            if let Some(step) = self.steps.get_mut(i) {
                step.wall_ms = wall;
            }
        }
        Ok(())
    }
}

/// `auto`'s judgement of one frame: the reason to leave the timestamps, or None when they hold.
fn judge(steps: &[Step], queries: &[(String, f64)], query_steps: &[usize]) -> Option<String> {
    let mut covered = vec![0.0; steps.len()];
    for ((_, ms), &step) in queries.iter().zip(query_steps) {
        if let Some(c) = covered.get_mut(step) {
            *c += ms;
        }
    }
    let frame_ms: f64 = steps.iter().map(|s| s.wall_ms).sum();
    let misses = |s: &Step, c: f64| {
        s.wall_ms >= AUTO_MIN_STEP_MS
            && c < AUTO_MIN_COVERAGE * s.wall_ms
            && s.wall_ms - c >= AUTO_MIN_MISSING_SHARE * frame_ms
    };
    steps.iter().zip(&covered).find(|(s, &c)| misses(s, c)).map(|(s, c)| {
        format!(
            "the GPU timestamps of step '{}' covered {c:.2} ms of its {:.1} ms from submit to completion \
                 (under {:.0} %), so this run reports wall-clock steps (SHADOWLAB_TIMING=gpu keeps the timestamps)",
            s.label,
            s.wall_ms,
            AUTO_MIN_COVERAGE * 100.0
        )
    })
}

fn flatten(results: &[GpuTimerQueryResult], out: &mut Vec<(String, f64)>) {
    for r in results {
        if let Some(t) = &r.time {
            out.push((r.label.clone(), (t.end - t.start) * 1000.0));
        }
        flatten(&r.nested_queries, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bad_clock_is_an_error_naming_the_choices() {
        assert_eq!(TimingMode::parse("CPU").unwrap(), TimingMode::Cpu);
        assert_eq!(TimingMode::parse(" gpu ").unwrap(), TimingMode::Gpu);
        assert_eq!(TimingMode::parse("").unwrap(), TimingMode::Auto);
        let e = TimingMode::parse("fast").unwrap_err().to_string();
        assert!(e.contains("\"fast\"") && e.contains("auto, gpu or cpu"), "{e}");
    }

    fn step(label: &str, wall_ms: f64) -> Step {
        Step { label: label.into(), wall_ms }
    }

    #[test]
    fn auto_judges_each_long_step_by_its_own_timestamps() {
        let steps = [step("gbuffer", 5.0), step("gather", 1000.0), step("tiny", 1.0)];
        // Timestamps that hold (the tiny step's overhead is not judged).
        let good = [("gbuffer".to_string(), 4.5), ("gather".to_string(), 990.0), ("tiny".to_string(), 0.01)];
        assert_eq!(judge(&steps, &good, &[0, 1, 2]), None);
        // A gather whose timestamps read 0.06 ms of its second: the run leaves them, naming the step.
        let bad = [("gbuffer".to_string(), 4.5), ("gather".to_string(), 0.06), ("tiny".to_string(), 0.01)];
        let reason = judge(&steps, &bad, &[0, 1, 2]).expect("the gather's timestamps miss the work");
        assert!(reason.contains("'gather'") && reason.contains("0.06 ms"), "{reason}");
        // A small step's missing time, under 5 % of the frame, is no reason (a loaded machine delays them).
        let busy = [step("tonemap", 6.7), step("shadows", 400.0)];
        let loaded = [("tonemap".to_string(), 2.5), ("shadows".to_string(), 399.0)];
        assert_eq!(judge(&busy, &loaded, &[0, 1]), None);
        // A step whose timestamps cover 60 % of it (ISM's on lavapipe, in a loaded run) leaves them too.
        let ism = [step("gbuffer", 5.0), step("ism maps + shading", 290.0)];
        let partial = [("gbuffer".to_string(), 4.5), ("ism maps + shading".to_string(), 174.0)];
        assert!(judge(&ism, &partial, &[0, 1]).is_some_and(|r| r.contains("under 75 %")));
        // Two passes of one step add up.
        let split = [("a".to_string(), 2.4), ("b".to_string(), 2.4)];
        assert_eq!(judge(&[step("both", 5.0)], &split, &[0, 0]), None);
    }

    #[test]
    fn one_clock_for_two_sides() {
        use TimingSource::*;
        assert_eq!(common_clock(GpuTimestamps, GpuTimestamps), GpuTimestamps);
        assert_eq!(common_clock(GpuTimestamps, WallClockSteps), WallClockSteps);
        assert_eq!(common_clock(WallClockSteps, GpuTimestamps), WallClockSteps);
        let t = FrameTiming {
            mode: TimingMode::Auto,
            source: GpuTimestamps,
            reason: None,
            timestamps_ms: None,
            steps_wall_ms: 3.0,
        };
        assert_eq!(t.comparable_source(), WallClockSteps, "no timestamps: only the wall clock compares");
        assert_eq!(t.ms_in(GpuTimestamps), 3.0);
    }
}
