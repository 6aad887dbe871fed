//! The chrome around the views: the tiled layout of the panels, their inputs and state (the shadow-map
//! inspector, the Explain panel's step, the sweep panel's inputs, the File menu's recent files and sequence
//! settings), the status line, UI frame times, and the toasts over the view (`toasts.rs`).

use std::collections::{BTreeMap, VecDeque};
use std::path::PathBuf;

use shadowlab_core::technique::ParamValue;

use super::inspector::Inspector;
use super::layout::Layout;
use super::toasts::Toasts;

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
    pub tradeoff_input: super::tradeoff_input::TradeoffInput,
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
pub struct Explain {
    /// The chosen step: (technique key, step index).
    pub step: Option<(String, usize)>,
    /// Parameter values from before an Explain step set them, per (technique, parameter): restored when a step
    /// that does not set them is chosen.
    pub saved: BTreeMap<(String, String), ParamValue>,
    /// A step about maps shows them alone in the 3D view (the Shadow maps panel's image, large), until the view
    /// is clicked, Esc is pressed or a step without maps is chosen.
    pub maps_in_view: bool,
    /// The chosen step's maps are in the view now.
    pub map_in_view: bool,
}

impl Default for Explain {
    fn default() -> Self {
        Explain { step: None, saved: BTreeMap::new(), maps_in_view: true, map_in_view: false }
    }
}
