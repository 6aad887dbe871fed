//! Short messages over the view (saved, failed, a scene's warnings), each for a few seconds, also logged.

use std::time::{Duration, Instant};

use eframe::egui;

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
