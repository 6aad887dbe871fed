//! What a frame cost and did (the frame report, its counts, the indirect part), and a frame in progress.

use std::time::Instant;

use serde::Serialize;

use crate::scene::{Camera, PointLight};
use crate::technique::TechniqueCounts;
use crate::timing::{FrameTiming, PassTime, TimingSource};

/// Counts of a frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrameCounts {
    pub lights_total: usize,
    pub scene_triangles: u64,
    /// Triangles the G-buffer pass drew after view-frustum culling of chunks.
    pub gbuffer_triangles: u64,
    #[serde(flatten)]
    pub technique: TechniqueCounts,
}

/// What one frame cost and did.
#[derive(Clone, Debug, Serialize)]
pub struct FrameReport {
    pub technique: String,
    /// The technique's parameters in the frame (`key` -> value as text).
    pub parameters: std::collections::BTreeMap<String, String>,
    pub width: u32,
    pub height: u32,
    /// What the frame rendered besides the technique: a fingerprint of the camera, the lights, the renderer's
    /// settings that change the work ([`super::RenderSettings::work_fingerprint`]) and the scene's size. Two frames with the same fingerprint, technique
    /// and parameters measured the same configuration (the app keys its session times by it).
    pub view_fingerprint: u64,
    /// The clock of `passes` and `total_ms`, and the frame's GPU work in the other clock.
    pub timing: FrameTiming,
    /// Per pass (GPU timestamps) or per step (wall-clock steps), in the order they ran; passes of one name
    /// (batches) are summed.
    pub passes: Vec<PassTime>,
    /// Sum of the passes, in the clock `timing.source` names.
    pub total_ms: f64,
    /// Per step, its wall time from submit to completion (whatever the clock of `passes`).
    pub steps: Vec<PassTime>,
    /// GPU timestamps of passes a technique submitted and waited for in a CPU stage (e.g. a GPU k-means in
    /// `prepare`): their time is in `cpu_stages`, so they are in no clock's total.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub stage_passes: Vec<PassTime>,
    /// CPU stages of the technique (e.g. clustering), milliseconds.
    pub cpu_stages: Vec<PassTime>,
    /// CPU wall time from the start of the frame to its completion (includes culling and waiting).
    pub wall_ms: f64,
    pub counts: FrameCounts,
    /// Hardware-independent work counts of the direct part (the G-buffer's triangles included; keys and
    /// meanings in [`crate::technique::work`]).
    pub work: std::collections::BTreeMap<String, f64>,
    /// The indirect technique of the frame, when there is one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub indirect: Option<IndirectReport>,
}

impl FrameReport {
    /// The frame's CPU stages, direct and indirect (milliseconds).
    pub fn cpu_stages_ms(&self) -> f64 {
        let indirect = self.indirect.iter().flat_map(|i| &i.cpu_stages);
        self.cpu_stages.iter().chain(indirect).map(|p| p.ms).sum()
    }

    /// The frame's time in `clock`: its GPU work in that clock (every step's passes) plus its CPU stages
    /// (clustering, VPL generation, ...), which run before the GPU steps.
    pub fn frame_ms_in(&self, clock: TimingSource) -> f64 {
        self.timing.ms_in(clock) + self.cpu_stages_ms()
    }

    /// The frame's work counts, direct and indirect together (the per-pixel means over the same pixels).
    pub fn total_work(&self) -> std::collections::BTreeMap<String, f64> {
        let mut m = self.work.clone();
        if let Some(i) = &self.indirect {
            for (k, v) in &i.work {
                if k != "shaded_pixels" {
                    *m.entry(k.clone()).or_insert(0.0) += v;
                }
            }
        }
        let pixels = m.get("shaded_pixels").copied().unwrap_or(0.0);
        for (mean, total) in [("shadow_lookups_per_pixel", "shadow_lookups"), ("filter_taps_per_pixel", "filter_taps")]
        {
            let t = m.get(total).copied().unwrap_or(0.0);
            m.insert(mean.to_string(), if pixels > 0.0 { t / pixels } else { 0.0 });
        }
        m
    }

    /// [`FrameReport::frame_ms_in`] the report's own clock.
    pub fn frame_ms(&self) -> f64 {
        self.frame_ms_in(self.timing.source)
    }
}

/// What the indirect technique of a frame did.
#[derive(Clone, Debug, Serialize)]
pub struct IndirectReport {
    pub technique: String,
    pub parameters: std::collections::BTreeMap<String, String>,
    /// VPLs used (0 for techniques that use none, e.g. the path tracer).
    pub vpls: usize,
    pub vpl_source: crate::vpl::VplSource,
    /// VPL samples (texels or particles) that hit nothing.
    pub vpl_misses: u32,
    /// True when the frame reused the previous frame's VPLs (same lights, settings and scene), so the
    /// "vpl generation" stage timed only the check.
    pub vpls_reused: bool,
    pub counts: TechniqueCounts,
    /// Hardware-independent work counts of the indirect technique ([`crate::technique::work`]).
    pub work: std::collections::BTreeMap<String, f64>,
    /// CPU stages (VPL generation, the technique's own), milliseconds.
    pub cpu_stages: Vec<PassTime>,
    /// The frame's passes that the indirect technique ran (also in the frame's `passes`), and their sum.
    pub passes: Vec<PassTime>,
    pub gpu_ms: f64,
}

/// A frame in progress.
pub struct FrameJob {
    pub steps_total: usize,
    pub steps_done: usize,
    pub(super) started: Instant,
    pub(super) camera: Camera,
    pub(super) lights: Vec<PointLight>,
    pub(super) gbuffer_triangles: u64,
    /// Steps of the direct technique; the indirect technique's follow.
    pub(super) direct_steps: usize,
    pub(super) vpl_ms: f64,
    pub(super) vpls_reused: bool,
}

impl FrameJob {
    pub fn is_done(&self) -> bool {
        self.steps_done >= self.steps_total
    }
    /// 0..1
    pub fn progress(&self) -> f32 {
        if self.steps_total == 0 {
            1.0
        } else {
            self.steps_done as f32 / self.steps_total as f32
        }
    }
}
