//! The app's state that its `impl` files act on (the view's input in `interact.rs`, the start options in
//! `start.rs`, a lost device's recovery in `recovery.rs`, a long run in `soak.rs`, the recent files in
//! `open.rs`), kept apart from them so that the app struct (`mod.rs`) imports only data and the files that add
//! its behaviour sit above it.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use eframe::egui;
use glam::Vec3;

use super::gizmo::Handle;
use super::session::DragTarget;

/// A drag of the gizmo in progress.
#[derive(Clone, Debug)]
pub(super) struct GizmoDrag {
    pub(super) handle: Handle,
    pub(super) target: DragTarget,
    /// Position at the start of the drag (the undo snapshot is taken then).
    pub(super) start: Vec3,
    pub(super) accumulated: egui::Vec2,
}

/// The 3D view's input state.
pub struct Interaction {
    /// A drag of the gizmo in progress.
    pub(super) drag: Option<GizmoDrag>,
    /// When the camera or the gizmo last moved: the preview renders until a moment after.
    pub(super) last_interaction: Option<Instant>,
    /// Orbit the camera continuously, as a user dragging would (UI frame-rate measurements).
    pub(super) orbit_demo: bool,
}

impl Interaction {
    pub fn new(orbit_demo: bool) -> Interaction {
        Interaction { drag: None, last_interaction: None, orbit_demo }
    }
}

/// What the start options set, beyond the scene: techniques, their parameters, the view, the target.
#[derive(Clone, Debug, Default)]
pub struct StartState {
    pub technique: Option<String>,
    /// `key=value` of the technique.
    pub params: Vec<String>,
    pub indirect: Option<String>,
    pub indirect_params: Vec<String>,
    /// single, side, split or difference.
    pub view: Option<String>,
    /// The comparison target (a reference or ground truth).
    pub against: Option<String>,
    pub against_params: Vec<String>,
    /// The target's indirect technique (`none`, or a key).
    pub against_indirect: Option<String>,
    /// The component of the light the views show: total, direct or indirect.
    pub component: Option<String>,
    /// An Explain step to open on: `N` (1-based) of the technique's steps, or `KEY:N` of technique `KEY` (the
    /// technique or the indirect technique).
    pub explain: Option<String>,
    /// Overlay layers to show (`LAYER`) or hide (`LAYER=off`) by the names the Overlays panel lists, applied
    /// after the Explain step.
    pub overlays: Vec<String>,
}

/// What the app did when its GPU device was lost.
#[derive(Clone, Debug)]
pub struct Recovery {
    /// Why wgpu says the device was lost.
    pub reason: String,
    /// The scene file the current state was saved to (None when saving failed, with the error in `message`).
    pub file: Option<PathBuf>,
    /// The command that starts a new ShadowLab on it (program, arguments), when it is relaunched.
    pub relaunch: Option<(PathBuf, Vec<String>)>,
    /// What the window says.
    pub message: String,
}

/// The state of a long run.
pub struct Soak {
    pub(super) started: Instant,
    pub(super) next_switch: f64,
    pub(super) next_report: f64,
    pub(super) switches: usize,
    /// The first report once every technique ran (after one cycle of switches: before it, creating the
    /// techniques' pipelines and pools is growth of no concern): (resident MiB, GPU allocated, GPU reserved).
    pub(super) first: Option<(f64, f64, f64)>,
    pub(super) first_t: f64,
}

impl Soak {
    pub fn new() -> Soak {
        Soak { started: Instant::now(), next_switch: 0.0, next_report: 0.0, switches: 0, first: None, first_t: 0.0 }
    }
}

impl Default for Soak {
    fn default() -> Self {
        Soak::new()
    }
}

fn recent_path(dir: &Path) -> PathBuf {
    dir.join("recent.ron")
}

pub(super) fn load_recent(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_to_string(recent_path(dir)).ok().and_then(|t| ron::from_str(&t).ok()).unwrap_or_default()
}

pub(super) fn save_recent(dir: &Path, recent: &[PathBuf]) {
    let write = || -> Result<()> {
        std::fs::create_dir_all(dir)?;
        crate::files::write_atomic(&recent_path(dir), ron::to_string(recent)?.as_bytes())
    };
    if let Err(e) = write() {
        log::warn!("cannot save the recent files list: {e:#}");
    }
}
