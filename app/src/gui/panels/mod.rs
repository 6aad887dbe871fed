//! The panels around the 3D view, by group: the Shadows panel (technique, indirect technique, their generated
//! parameter panels, VPL settings), Render and Overlays, Lights and Scene, Timings and Sweep, Explain, Shadow
//! maps. Each takes the parts of the app it shows and edits.

pub mod explain;
pub mod lights;
pub mod maps;
pub mod render;
pub mod technique;
pub mod timings;
pub mod tradeoff;

use eframe::egui;

use super::chrome::Chrome;
use super::layout::Pane;
use super::session::Session;
use super::views::Views;

/// The UI of one panel (a tile of the layout).
pub fn pane_ui(session: &mut Session, views: &mut Views, chrome: &mut Chrome, ui: &mut egui::Ui, pane: Pane) {
    match pane {
        // Drawn by the layout itself.
        Pane::View => {}
        Pane::Technique => {
            technique::technique_ui(session, views, ui);
            ui.separator();
            technique::indirect_ui(session, views, &mut chrome.status, ui);
        }
        Pane::Render => render::render_ui(session, views, ui),
        Pane::Overlays => render::overlays_ui(session, views, ui),
        Pane::Lights => lights::lights_ui(session, &mut chrome.toasts, ui),
        Pane::Scene => lights::stats_ui(session, ui),
        Pane::Sweep => {
            timings::sweep_ui(session, views, &mut chrome.sweep_input, &mut chrome.toasts, ui);
            ui.separator();
            tradeoff::tradeoff_ui(session, views, &mut chrome.tradeoff_input, &mut chrome.toasts, ui);
        }
        Pane::Timings => timings::timings_ui(views, &session.scene.name, &chrome.ui_frame_ms, &chrome.status, ui),
        Pane::Maps => maps::maps_ui(session, views, &mut chrome.inspector, ui),
        Pane::Explain => explain::explain_ui(session, views, chrome, ui),
    }
}
