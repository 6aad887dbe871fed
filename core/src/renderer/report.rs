//! What a frame cost and did (the frame report, its counts, the indirect part), and a frame in progress.

use std::time::Instant;

use serde::Serialize;

use crate::scene::{Camera, PointLight};
use crate::technique::TechniqueCounts;
use crate::timing::{PassTime, TimingSource};

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
    pub width: u32,
    pub height: u32,
    pub timing_source: TimingSource,
    /// Per pass, in the order they ran; passes of one name (batches) are summed.
    pub passes: Vec<PassTime>,
    /// Sum of the passes.
    pub gpu_total_ms: f64,
    /// CPU stages of the technique (e.g. clustering), milliseconds.
    pub cpu_stages: Vec<PassTime>,
    /// CPU wall time from the start of the frame to its completion (includes culling and waiting).
    pub wall_ms: f64,
    pub counts: FrameCounts,
    /// The indirect technique of the frame, when there is one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub indirect: Option<IndirectReport>,
}

/// What the indirect technique of a frame did.
#[derive(Clone, Debug, Serialize)]
pub struct IndirectReport {
    pub technique: String,
    /// VPLs used (0 for techniques that use none, e.g. the path tracer).
    pub vpls: usize,
    pub vpl_source: crate::vpl::VplSource,
    /// VPL samples (texels or particles) that hit nothing.
    pub vpl_misses: u32,
    /// True when the frame reused the previous frame's VPLs (same lights, settings and scene), so the
    /// "vpl generation" stage timed only the check.
    pub vpls_reused: bool,
    pub counts: TechniqueCounts,
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
