//! The sweep panel: renders the current technique for a range of one parameter's values on a worker thread
//! (its own renderer on the shared device), compares each image with the view's comparison target (its
//! technique and indirect technique), and plots time and error
//! against the parameter while it runs. Cancel stops it after the current setting.

use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{anyhow, Result};
use shadowlab_core::compare::{self, CompareOptions, Image};
use shadowlab_core::scene::{Camera, PointLight};
use shadowlab_core::technique::ParamValue;
use shadowlab_core::timing::{common_clock, TimingSource};
use shadowlab_core::{GpuContext, RenderSettings, Renderer};

use super::worker::Worker;

/// One finished setting.
#[derive(Clone, Debug)]
pub struct SweepRow {
    pub value: f64,
    pub ms: f64,
    pub rmse: f64,
    pub reference_ms: f64,
    /// The clock of `ms` and `reference_ms`.
    pub clock: TimingSource,
}

/// A sweep in progress or finished.
pub struct Sweep {
    pub key: String,
    pub rows: Vec<SweepRow>,
    pub total: usize,
    pub worker: Worker<SweepRow>,
}

/// What the worker renders.
pub struct SweepJob {
    pub gpu: GpuContext,
    /// The main view's scene on the GPU (shared, not uploaded again) and the layouts it was made with.
    pub scene: std::sync::Arc<shadowlab_core::accel::gpu_scene::GpuScene>,
    pub layouts: std::sync::Arc<shadowlab_core::services::layouts::SharedLayouts>,
    pub lights: Vec<PointLight>,
    /// The session's directional lights.
    pub suns: Vec<shadowlab_core::scene::DirectionalLight>,
    pub camera: Camera,
    pub settings: RenderSettings,
    pub technique: String,
    pub fixed: Vec<(String, ParamValue)>,
    /// The indirect technique the technique's frames add (key, parameters).
    pub indirect: Option<(String, Vec<(String, ParamValue)>)>,
    /// The comparison target: its key and parameters, and its indirect technique.
    pub against: String,
    pub against_params: Vec<(String, ParamValue)>,
    pub against_indirect: Option<(String, Vec<(String, ParamValue)>)>,
    pub key: String,
    pub values: Vec<ParamValue>,
}

fn number(v: &ParamValue) -> f64 {
    match v {
        ParamValue::Float(x) => *x as f64,
        ParamValue::Int(x) => *x as f64,
        ParamValue::Bool(b) => *b as i32 as f64,
        ParamValue::Choice(_) | ParamValue::Cameras(_) => 0.0,
    }
}

fn run(job: SweepJob, cancel: &AtomicBool, send: &dyn Fn(SweepRow)) -> Result<()> {
    let mut settings = job.settings.clone();
    settings.max_lights_per_step = 0;
    let mut renderer = Renderer::for_scene(&job.gpu, job.scene.clone(), job.layouts.clone(), settings)?;
    renderer.set_directional_lights(&job.suns)?;
    let set_indirect = |renderer: &mut Renderer, indirect: &Option<(String, Vec<(String, ParamValue)>)>| {
        let Some((key, params)) = indirect else { return renderer.set_indirect(None).map_err(anyhow::Error::from) };
        let mut t =
            renderer.create_indirect_technique(key).ok_or_else(|| anyhow!("unknown indirect technique '{key}'"))?;
        for (k, v) in params {
            t.set_param(k, v)?;
        }
        renderer.set_indirect(Some(t)).map_err(anyhow::Error::from)
    };
    let (w, h) = (renderer.settings().width, renderer.settings().height);
    let mut reference =
        renderer.create_technique(&job.against).ok_or_else(|| anyhow!("unknown technique '{}'", job.against))?;
    let mut technique = renderer.create_technique(&job.technique).ok_or_else(|| anyhow!("unknown technique"))?;
    for (k, v) in &job.fixed {
        let _ = technique.set_param(k, v);
    }
    for (k, v) in &job.against_params {
        let _ = reference.set_param(k, v);
    }
    set_indirect(&mut renderer, &job.against_indirect)?;
    let r = renderer.render_frame(reference.as_mut(), &job.camera, &job.lights, &mut |_, _| {})?;
    let reference_report = r;
    let reference_image = Image::new(w, h, renderer.read_hdr()?)?;
    let mask = renderer.read_geometry_mask()?;
    set_indirect(&mut renderer, &job.indirect)?;
    for value in &job.values {
        if cancel.load(Ordering::Relaxed) {
            break;
        }
        technique.set_param(&job.key, value)?;
        let report = renderer.render_frame(technique.as_mut(), &job.camera, &job.lights, &mut |_, _| {})?;
        let image = Image::new(w, h, renderer.read_hdr()?)?;
        let options = CompareOptions { flip: false, ..Default::default() };
        let m = compare::compare(&image, &reference_image, Some(&mask), &options)?;
        // Both sides in one clock: the timestamps only when both frames used them.
        let clock = common_clock(report.timing.comparable_source(), reference_report.timing.comparable_source());
        send(SweepRow {
            value: number(value),
            ms: report.frame_ms_in(clock),
            rmse: m.rmse,
            reference_ms: reference_report.frame_ms_in(clock),
            clock,
        });
    }
    Ok(())
}

impl Sweep {
    pub fn start(job: SweepJob) -> Sweep {
        let (key, total) = (job.key.clone(), job.values.len());
        Sweep { key, rows: Vec::new(), total, worker: Worker::start(move |cancel, send| run(job, cancel, send)) }
    }

    /// Collect what the worker sent; true while it runs.
    pub fn poll(&mut self) -> bool {
        self.rows.extend(self.worker.poll());
        !self.worker.finished
    }

    pub fn cancel(&self) {
        self.worker.cancel();
    }
}

/// `count` evenly spaced values from `start` to `end` for a numeric parameter kind.
pub fn values(kind: &shadowlab_core::technique::ParamKind, start: f64, end: f64, count: usize) -> Vec<ParamValue> {
    use shadowlab_core::technique::ParamKind;
    let count = count.clamp(2, 64);
    (0..count)
        .map(|i| start + (end - start) * i as f64 / (count - 1) as f64)
        .filter_map(|v| match kind {
            ParamKind::Float { min, max } => Some(ParamValue::Float((v as f32).clamp(*min, *max))),
            ParamKind::Int { min, max } => Some(ParamValue::Int((v.round() as i64).clamp(*min, *max))),
            _ => None,
        })
        .collect()
}
