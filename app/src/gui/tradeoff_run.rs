//! The app's trade-off: several techniques with ranges of their parameters rendered on a worker thread (its own
//! renderer on the shared device, like the sweep) against the view's comparison target, each configuration's
//! error and time per frame sent as it completes; the search, the Pareto front and the pick are
//! [`crate::tradeoff`]'s, the same as `shadowlab tradeoff`'s. Cancel stops it after the current configuration.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::{anyhow, Result};
use shadowlab_core::compare::{self, CompareOptions, Image};
use shadowlab_core::scene::{Camera, PointLight};
use shadowlab_core::technique::Technique;
use shadowlab_core::timing::{common_clock, TimingSource};
use shadowlab_core::{FrameReport, GpuContext, RenderSettings, Renderer};

use super::worker::Worker;
use crate::measure::IndirectChoice;
use crate::tradeoff::{self, Goal, Metric, Point, Setting, TrySpec};

/// A frame's time in both clocks, so rows are compared in the clock all of them (and the target) used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameTimes {
    /// The clock this frame's timestamps allow (timestamps, or the wall-clock steps).
    pub source: TimingSource,
    pub timestamps_ms: f64,
    pub wall_ms: f64,
}

impl FrameTimes {
    fn of(report: &FrameReport) -> FrameTimes {
        FrameTimes {
            source: report.timing.comparable_source(),
            timestamps_ms: report.frame_ms_in(TimingSource::GpuTimestamps),
            wall_ms: report.frame_ms_in(TimingSource::WallClockSteps),
        }
    }

    pub fn ms_in(&self, clock: TimingSource) -> f64 {
        match clock {
            TimingSource::GpuTimestamps => self.timestamps_ms,
            TimingSource::WallClockSteps => self.wall_ms,
        }
    }
}

/// One rendered configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct TradeoffRow {
    pub try_index: usize,
    pub setting: Setting,
    pub times: FrameTimes,
    pub error: f64,
    /// The frame's work counts, the direct and the indirect technique's summed per key (as `tradeoff --work-axis`
    /// plots them).
    pub work: std::collections::BTreeMap<String, f64>,
}

/// What the worker sends: the target's time, then each configuration.
pub enum TradeoffMessage {
    Target(FrameTimes),
    Row(TradeoffRow),
}

/// What the worker renders: the view as the sweep takes it, the tries and the target.
pub struct TradeoffJob {
    pub gpu: GpuContext,
    pub scene: Arc<shadowlab_core::accel::gpu_scene::GpuScene>,
    pub layouts: Arc<shadowlab_core::services::layouts::SharedLayouts>,
    pub lights: Vec<PointLight>,
    /// The session's directional lights.
    pub suns: Vec<shadowlab_core::scene::DirectionalLight>,
    pub camera: Camera,
    pub settings: RenderSettings,
    pub tries: Vec<TrySpec>,
    /// The parameters the user set for each try's technique (`key=value`), under the tried ones.
    pub base_params: HashMap<String, Vec<String>>,
    pub against: String,
    pub against_params: Vec<String>,
    pub against_indirect: IndirectChoice,
    pub metric: Metric,
    pub goal: Goal,
}

/// A trade-off in progress or finished.
pub struct Tradeoff {
    pub tries: Vec<TrySpec>,
    pub metric: Metric,
    pub goal: Goal,
    pub rows: Vec<TradeoffRow>,
    pub target: Option<FrameTimes>,
    /// About how many configurations it renders ([`tradeoff::expected_renders`]).
    pub expected: usize,
    pub worker: Worker<TradeoffMessage>,
}

fn render(
    renderer: &mut Renderer,
    technique: &mut dyn Technique,
    indirect: &IndirectChoice,
    camera: &Camera,
    lights: &[PointLight],
) -> Result<(Image, FrameReport)> {
    crate::measure::apply_indirect(renderer, indirect)?;
    let report = renderer.render_frame(technique, camera, lights, &mut |_, _| {})?;
    let (w, h) = (renderer.settings().width, renderer.settings().height);
    Ok((Image::new(w, h, renderer.read_hdr()?)?, report))
}

fn run(job: TradeoffJob, cancel: &AtomicBool, send: &dyn Fn(TradeoffMessage)) -> Result<()> {
    let mut settings = job.settings.clone();
    settings.max_lights_per_step = 0;
    let mut renderer = Renderer::for_scene(&job.gpu, job.scene.clone(), job.layouts.clone(), settings)?;
    renderer.set_directional_lights(&job.suns)?;
    let mut target =
        renderer.create_technique(&job.against).ok_or_else(|| anyhow!("unknown technique '{}'", job.against))?;
    crate::measure::apply_params(target.as_mut(), None, &job.against_params)?;
    let (target_image, target_report) =
        render(&mut renderer, target.as_mut(), &job.against_indirect, &job.camera, &job.lights)?;
    send(TradeoffMessage::Target(FrameTimes::of(&target_report)));
    let mask = renderer.read_geometry_mask()?;
    // The shadow error needs the view's unshadowed and ambient-only images.
    let inputs = if job.metric == Metric::Shadow {
        Some(crate::measure::compare_inputs(&mut renderer, &job.camera, &job.lights)?)
    } else {
        None
    };
    let mut techniques: HashMap<String, Box<dyn Technique>> = HashMap::new();
    let mut eval = |t: usize, setting: &Setting| -> Result<Point> {
        let spec = &job.tries[t];
        if !techniques.contains_key(&spec.technique) {
            let created = renderer
                .create_technique(&spec.technique)
                .ok_or_else(|| anyhow!("unknown technique '{}'", spec.technique))?;
            techniques.insert(spec.technique.clone(), created);
        }
        let technique = techniques.get_mut(&spec.technique).expect("inserted above");
        let mut params = job.base_params.get(&spec.technique).cloned().unwrap_or_default();
        params.extend(tradeoff::direct_params(setting));
        crate::measure::apply_params(technique.as_mut(), None, &params)?;
        let indirect = tradeoff::indirect_choice(&spec.indirect, setting);
        let (image, report) = render(&mut renderer, technique.as_mut(), &indirect, &job.camera, &job.lights)?;
        let m = match &inputs {
            // The shadow error needs the visibility factors of both images.
            Some(inputs) => {
                let kind = crate::measure::DiffKind::Absolute;
                crate::measure::compare_images(&image, &target_image, inputs, kind, 1.0, false, 1.0)?.0
            }
            None => {
                let options = CompareOptions { flip: job.metric == Metric::Flip, ..Default::default() };
                compare::compare(&image, &target_image, Some(&mask), &options)?
            }
        };
        let error = job.metric.of(&m)?;
        let times = FrameTimes::of(&report);
        let clock = common_clock(times.source, target_report.timing.comparable_source());
        let mut work = report.work.clone();
        for (k, v) in report.indirect.iter().flat_map(|i| &i.work) {
            *work.entry(k.clone()).or_default() += v;
        }
        send(TradeoffMessage::Row(TradeoffRow { try_index: t, setting: setting.clone(), times, error, work }));
        Ok(Point { ms: times.ms_in(clock), error })
    };
    tradeoff::search(&job.tries, job.goal, &mut eval, &|| cancel.load(Ordering::Relaxed))?;
    Ok(())
}

impl Tradeoff {
    pub fn start(job: TradeoffJob) -> Tradeoff {
        let (tries, metric, goal) = (job.tries.clone(), job.metric, job.goal);
        let expected = tradeoff::expected_renders(&tries, goal);
        let worker = Worker::start(move |cancel, send| run(job, cancel, send));
        Tradeoff { tries, metric, goal, rows: Vec::new(), target: None, expected, worker }
    }

    /// Collect what the worker sent; true while it runs.
    pub fn poll(&mut self) -> bool {
        for m in self.worker.poll() {
            match m {
                TradeoffMessage::Target(t) => self.target = Some(t),
                TradeoffMessage::Row(r) => self.rows.push(r),
            }
        }
        !self.worker.finished
    }

    pub fn cancel(&self) {
        self.worker.cancel();
    }

    /// The clock every row and the target used (timestamps only when all did).
    pub fn clock(&self) -> TimingSource {
        let first = self.target.map(|t| t.source).unwrap_or(TimingSource::GpuTimestamps);
        self.rows.iter().fold(first, |c, r| common_clock(c, r.times.source))
    }

    /// Every row's point in [`Tradeoff::clock`].
    pub fn points(&self) -> Vec<Point> {
        let clock = self.clock();
        self.rows.iter().map(|r| Point { ms: r.times.ms_in(clock), error: r.error }).collect()
    }

    /// The work counts some row has a non-zero value of (the plot's other x axes).
    pub fn work_keys(&self) -> Vec<String> {
        let keys: std::collections::BTreeSet<&String> =
            self.rows.iter().flat_map(|r| r.work.iter().filter(|(_, v)| **v != 0.0).map(|(k, _)| k)).collect();
        keys.into_iter().cloned().collect()
    }

    /// The row the goal picks (a budget's lowest error, a maximum error's fastest), once finished.
    pub fn pick(&self) -> Option<usize> {
        tradeoff::pick(&self.points(), self.goal)
    }
}
