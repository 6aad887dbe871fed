//! Painting the views into the 3D view: the technique's image alone, side by side or split with the
//! comparison target's (a draggable split line), or the difference image with its metrics and colour legend;
//! captions and the progress bar of the frame being refined.

use eframe::egui;

use super::Views;
use crate::gui::document::ViewMode;
use crate::gui::session::Session;
use crate::measure::technique_pair;

impl Views {
    /// Paint the images of the view mode into `rect`; dragging the split line's handle moves `view.split`.
    pub fn paint(&self, ui: &mut egui::Ui, painter: &egui::Painter, rect: egui::Rect, session: &mut Session) {
        let indirect = session.indirect.technique.as_deref();
        let against_indirect = session.against_indirect_key();
        let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
        if let Some(gpu) = &self.gpu {
            match session.view.mode {
                ViewMode::Single => {
                    painter.image(gpu.main.texture_id, rect, uv, egui::Color32::WHITE);
                }
                ViewMode::SideBySide => {
                    let (l, r) = rect.split_left_right_at_fraction(0.5);
                    painter.image(gpu.main.texture_id, l, uv, egui::Color32::WHITE);
                    painter.image(gpu.reference.texture_id, r, uv, egui::Color32::WHITE);
                    painter.line_segment([r.left_top(), r.left_bottom()], egui::Stroke::new(2.0, egui::Color32::BLACK));
                    label(painter, l.left_top(), &technique_pair(&session.technique, indirect));
                    label(painter, r.left_top(), &technique_pair(&session.view.compare_against, against_indirect));
                }
                ViewMode::Difference => match &self.difference {
                    Some(d) => {
                        painter.image(d.texture.id(), rect, uv, egui::Color32::WHITE);
                        let m = &d.metrics;
                        label(
                            painter,
                            rect.left_top(),
                            &format!(
                                "{} vs {}: RMSE {:.4}  PSNR {}  FLIP {}  shadow error {}",
                                technique_pair(&session.technique, indirect),
                                technique_pair(&session.view.compare_against, against_indirect),
                                m.rmse,
                                m.psnr_db.map(|p| format!("{p:.1} dB")).unwrap_or_else(|| "inf".into()),
                                m.flip_mean.map(|f| format!("{f:.3}")).unwrap_or_else(|| "-".into()),
                                m.shadow_intensity_error
                                    .map(|e| format!("{:.2}%", e * 100.0))
                                    .unwrap_or_else(|| "-".into()),
                            ),
                        );
                        legend(painter, rect, session.view.diff_signed, session.view.diff_gain);
                    }
                    None => {
                        painter.image(gpu.main.texture_id, rect, uv, egui::Color32::from_gray(90));
                        label(painter, rect.left_top(), "computing the difference when both images are complete…");
                    }
                },
                ViewMode::Split => {
                    let x = rect.left() + rect.width() * session.view.split.clamp(0.0, 1.0);
                    let s = session.view.split.clamp(0.0, 1.0);
                    let left = egui::Rect::from_min_max(rect.min, egui::pos2(x, rect.bottom()));
                    let right = egui::Rect::from_min_max(egui::pos2(x, rect.top()), rect.max);
                    painter.image(
                        gpu.main.texture_id,
                        left,
                        egui::Rect::from_min_max(uv.min, egui::pos2(s, 1.0)),
                        egui::Color32::WHITE,
                    );
                    painter.image(
                        gpu.reference.texture_id,
                        right,
                        egui::Rect::from_min_max(egui::pos2(s, 0.0), uv.max),
                        egui::Color32::WHITE,
                    );
                    painter.line_segment(
                        [egui::pos2(x, rect.top()), egui::pos2(x, rect.bottom())],
                        egui::Stroke::new(2.0, egui::Color32::WHITE),
                    );
                    label(painter, rect.left_top(), &technique_pair(&session.technique, indirect));
                    label(
                        painter,
                        egui::pos2(x, rect.top()),
                        &technique_pair(&session.view.compare_against, against_indirect),
                    );
                    // The split line is draggable from a handle at its middle.
                    let handle = egui::Rect::from_center_size(egui::pos2(x, rect.center().y), egui::vec2(14.0, 40.0));
                    let h = ui.interact(handle, ui.scope_id().with("split"), egui::Sense::drag());
                    painter.rect_filled(handle, 3.0, egui::Color32::from_white_alpha(200));
                    if h.dragged() {
                        session.view.split = ((x + h.drag_delta().x - rect.left()) / rect.width()).clamp(0.0, 1.0);
                    }
                }
            }
            // Progress of the frame being refined.
            let progress =
                gpu.main.progress.min(if session.view.mode == ViewMode::Single { 1.0 } else { gpu.reference.progress });
            if progress < 1.0 {
                let bar = egui::Rect::from_min_size(
                    rect.left_bottom() - egui::vec2(0.0, 4.0),
                    egui::vec2(rect.width() * progress, 4.0),
                );
                painter.rect_filled(bar, 0.0, egui::Color32::from_rgb(90, 170, 255));
                ui.ctx().request_repaint();
            }
        }
    }
}

fn label(painter: &egui::Painter, at: egui::Pos2, text: &str) {
    painter.text(
        at + egui::vec2(6.0, 4.0),
        egui::Align2::LEFT_TOP,
        text,
        egui::FontId::proportional(13.0),
        egui::Color32::WHITE,
    );
}

/// Colour legend of the difference view.
fn legend(painter: &egui::Painter, rect: egui::Rect, signed: bool, gain: f32) {
    let w = 160.0;
    let origin = rect.right_bottom() - egui::vec2(w + 16.0, 34.0);
    for i in 0..w as usize {
        let t = i as f32 / (w - 1.0);
        let color = if signed {
            let s = t * 2.0 - 1.0;
            let v = (s.abs() * 255.0) as u8;
            if s >= 0.0 {
                egui::Color32::from_rgb(v, 0, 0)
            } else {
                egui::Color32::from_rgb(0, v, 0)
            }
        } else {
            let [r, g, b] = shadowlab_core::compare::colormap(t);
            egui::Color32::from_rgb(r, g, b)
        };
        painter.rect_filled(
            egui::Rect::from_min_size(origin + egui::vec2(i as f32, 0.0), egui::vec2(1.0, 10.0)),
            0.0,
            color,
        );
    }
    let (lo, hi) = if signed {
        (format!("-{:.2}", 1.0 / gain), format!("+{:.2}", 1.0 / gain))
    } else {
        ("0".into(), format!("{:.2}", 1.0 / gain))
    };
    painter.text(
        origin + egui::vec2(0.0, 12.0),
        egui::Align2::LEFT_TOP,
        lo,
        egui::FontId::proportional(11.0),
        egui::Color32::WHITE,
    );
    painter.text(
        origin + egui::vec2(w, 12.0),
        egui::Align2::RIGHT_TOP,
        hi,
        egui::FontId::proportional(11.0),
        egui::Color32::WHITE,
    );
}
