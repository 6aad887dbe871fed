//! Per-pass timing. With `TIMESTAMP_QUERY` every pass gets GPU timestamps (wgpu-profiler); without it, each
//! submitted step is timed on the CPU from submit to completion, and the report says so.

use std::collections::BTreeMap;
use std::time::Instant;

use serde::Serialize;
use wgpu_profiler::{GpuProfiler, GpuProfilerSettings, GpuTimerQueryResult};

use crate::error::GpuError;
use crate::gpu::GpuContext;

/// Where the milliseconds of a report come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TimingSource {
    /// GPU timestamp queries around each pass.
    GpuTimestamps,
    /// CPU wall time from submitting a step to its completion (no timestamp support).
    CpuFallback,
}

/// Time spent in passes of one name during a frame (batches of the same pass are summed).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PassTime {
    pub name: String,
    pub ms: f64,
    /// How many passes of this name ran.
    pub count: u32,
}

pub struct PassTimer {
    profiler: GpuProfiler,
    source: TimingSource,
    cpu: BTreeMap<String, (f64, u32)>,
    /// While set, the labels of recorded passes are the indirect technique's.
    indirect: std::cell::Cell<bool>,
    indirect_labels: std::cell::RefCell<std::collections::BTreeSet<String>>,
}

impl PassTimer {
    pub fn new(gpu: &GpuContext) -> Result<PassTimer, GpuError> {
        let settings = GpuProfilerSettings {
            enable_timer_queries: gpu.timestamps,
            enable_debug_groups: true,
            max_num_pending_frames: 4,
        };
        let profiler = GpuProfiler::new(&gpu.device, settings).map_err(|e| GpuError::Validation(e.to_string()))?;
        let source = if gpu.timestamps { TimingSource::GpuTimestamps } else { TimingSource::CpuFallback };
        Ok(PassTimer {
            profiler,
            source,
            cpu: BTreeMap::new(),
            indirect: std::cell::Cell::new(false),
            indirect_labels: Default::default(),
        })
    }

    pub fn source(&self) -> TimingSource {
        self.source
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

    /// Submit one step of a frame. In CPU-fallback mode the step is waited for and its wall time recorded
    /// under `cpu_label`.
    pub fn submit(&mut self, gpu: &GpuContext, encoder: wgpu::CommandEncoder, cpu_label: &str) -> Result<(), GpuError> {
        let start = Instant::now();
        self.note(cpu_label);
        gpu.queue.submit([encoder.finish()]);
        if self.source == TimingSource::CpuFallback {
            gpu.wait_idle()?;
            let e = self.cpu.entry(cpu_label.to_string()).or_insert((0.0, 0));
            e.0 += start.elapsed().as_secs_f64() * 1000.0;
            e.1 += 1;
        }
        Ok(())
    }

    /// Close the frame: resolve the queries, wait for the GPU and return the per-pass times (in first-seen
    /// order for GPU timestamps).
    pub fn finish_frame(&mut self, gpu: &GpuContext) -> Result<Vec<PassTime>, GpuError> {
        let mut encoder = gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("resolve") });
        self.profiler.resolve_queries(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
        self.profiler.end_frame().map_err(|e| GpuError::Validation(format!("timer: {e}")))?;
        gpu.wait_idle()?;
        let results = self.profiler.process_finished_frame(gpu.queue.get_timestamp_period());
        let mut out: Vec<PassTime> = Vec::new();
        match self.source {
            TimingSource::GpuTimestamps => {
                if let Some(results) = results {
                    collect(&results, &mut out);
                }
            }
            TimingSource::CpuFallback => {
                out.extend(std::mem::take(&mut self.cpu).into_iter().map(|(name, (ms, count))| PassTime {
                    name,
                    ms,
                    count,
                }));
            }
        }
        Ok(out)
    }
}

fn collect(results: &[GpuTimerQueryResult], out: &mut Vec<PassTime>) {
    for r in results {
        if let Some(t) = &r.time {
            let ms = (t.end - t.start) * 1000.0;
            match out.iter_mut().find(|p| p.name == r.label) {
                Some(p) => {
                    p.ms += ms;
                    p.count += 1;
                }
                None => out.push(PassTime { name: r.label.clone(), ms, count: 1 }),
            }
        }
        collect(&r.nested_queries, out);
    }
}
