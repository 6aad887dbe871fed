//! The difference view's state that `Views` holds: the image and metrics of one pair of converged frames, and
//! the pair on its way from a worker thread; computed and drawn by `difference.rs`.

use anyhow::Result;
use eframe::egui;

/// The difference view's image and metrics, for one pair of converged frames.
pub struct Difference {
    pub texture: egui::TextureHandle,
    pub metrics: shadowlab_core::compare::Metrics,
    /// What it was computed from (both views' frame keys and the diff settings).
    pub(super) key: (u64, u64, bool, bool, u32),
}

/// A difference image and its metrics on their way from a worker thread.
pub(super) struct PendingDifference {
    pub(super) key: (u64, u64, bool, bool, u32),
    pub(super) size: (u32, u32),
    pub(super) result: std::sync::mpsc::Receiver<Result<(shadowlab_core::compare::Metrics, image::RgbaImage)>>,
}
