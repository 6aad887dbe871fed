//! The chrome around the views: the tiled layout of the panels, their inputs and state (the shadow-map
//! inspector, the Explain panel's step, the sweep panel's inputs, the File menu's recent files and sequence
//! settings), the status line, UI frame times, and the toasts over the view.

use std::collections::{BTreeMap, VecDeque};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use eframe::egui;
use shadowlab_core::technique::ParamValue;

use super::inspector::Inspector;
use super::layout::Layout;

/// The panels' and the window's own state (nothing a scene file saves).
pub struct Chrome {
    /// The tiles of the window (panels around the 3D view) and the full-view flag.
    pub layout: Layout,
    pub toasts: Toasts,
    /// The shadow-map inspector's state.
    pub inspector: Inspector,
    pub explain: Explain,
    /// Sweep panel inputs: parameter key, start, end, number of values.
    pub sweep_input: (String, f64, f64, usize),
    /// The Trade-off section's techniques, ranges, metric and budget.
    pub tradeoff_input: super::panels::tradeoff::TradeoffInput,
    /// Recently opened or saved scene files and models, newest first (File menu).
    pub recent: Vec<PathBuf>,
    /// Frames of an orbit image sequence (File menu).
    pub orbit_frames: usize,
    /// Draw the view's visible overlay layers over the frames of image sequences (File menu).
    pub sequence_overlays: bool,
    /// The last render or GPU error (or the probe's pixel), shown in the timings panel.
    pub status: String,
    /// Durations of the last UI frames, in ms.
    pub ui_frame_ms: VecDeque<f64>,
    /// The selection of the last UI frame: a new one brings the light inspector forward.
    pub last_selected: Option<usize>,
    /// False: every file dialog is answered with Cancel (tests driving the app; `Startup::no_file_dialogs`).
    pub file_dialogs: bool,
}

impl Chrome {
    pub fn new(layout: Layout, recent: Vec<PathBuf>) -> Chrome {
        Chrome {
            layout,
            toasts: Toasts::default(),
            inspector: Inspector::default(),
            explain: Explain::default(),
            sweep_input: ("d_init".into(), 0.1, 1.6, 6),
            tradeoff_input: Default::default(),
            recent,
            orbit_frames: 36,
            sequence_overlays: true,
            status: String::new(),
            ui_frame_ms: VecDeque::new(),
            last_selected: None,
            file_dialogs: true,
        }
    }
}

/// The Explain panel's state.
#[derive(Default)]
pub struct Explain {
    /// The chosen step: (technique key, step index).
    pub step: Option<(String, usize)>,
    /// Parameter values from before an Explain step set them, per (technique, parameter): restored when a step
    /// that does not set them is chosen.
    pub saved: BTreeMap<(String, String), ParamValue>,
}

/// A short message shown over the view.
struct Toast {
    text: String,
    error: bool,
    until: Instant,
}

/// The messages shown over the view, each for a few seconds.
#[derive(Default)]
pub struct Toasts(Vec<Toast>);

impl Toasts {
    /// A message for 4 s (and the log).
    pub fn say(&mut self, text: impl Into<String>) {
        let text = text.into();
        log::info!("{text}");
        self.0.push(Toast { text, error: false, until: Instant::now() + Duration::from_secs(4) });
    }

    /// An error for 8 s (and the log).
    pub fn error(&mut self, text: impl Into<String>) {
        let text = text.into();
        log::warn!("{text}");
        self.0.push(Toast { text, error: true, until: Instant::now() + Duration::from_secs(8) });
    }

    /// A note for `secs` seconds, not logged (a scene's warnings, say).
    pub fn note(&mut self, text: String, secs: u64) {
        self.0.push(Toast { text, error: false, until: Instant::now() + Duration::from_secs(secs) });
    }

    /// The messages not yet expired, in the window's bottom right corner.
    pub fn ui(&mut self, ctx: &egui::Context) {
        let now = Instant::now();
        self.0.retain(|t| t.until > now);
        if self.0.is_empty() {
            return;
        }
        egui::Area::new(egui::Id::unique("toasts")).anchor(egui::Align2::RIGHT_BOTTOM, egui::vec2(-12.0, -40.0)).show(
            ctx,
            |ui| {
                for t in &self.0 {
                    let color =
                        if t.error { egui::Color32::from_rgb(255, 120, 120) } else { egui::Color32::LIGHT_GREEN };
                    egui::Frame::popup(ui.style()).show(ui, |ui| {
                        ui.colored_label(color, &t.text);
                    });
                }
            },
        );
        ctx.request_repaint_after(Duration::from_millis(500));
    }
}
