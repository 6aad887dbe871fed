//! Legends of the overlay layers: the glyphs (dot, line, circle, frustum, rectangle, palette) in their colours,
//! next to what the layer's technique says they mean ([`Technique::overlay_legend`]); in the Overlays panel
//! (every entry) and over the 3D view (each visible layer's first entries).
//!
//! [`Technique::overlay_legend`]: shadowlab_core::technique::Technique::overlay_legend

use eframe::egui;
use shadowlab_core::technique::{index_color, Glyph, LegendEntry};

fn color32(c: [f32; 4]) -> egui::Color32 {
    let u = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    egui::Color32::from_rgb(u(c[0]), u(c[1]), u(c[2]))
}

/// Paint `glyph` in `color` inside `rect`.
pub fn paint_glyph(painter: &egui::Painter, rect: egui::Rect, glyph: Glyph, color: [f32; 4]) {
    let c = color32(color);
    let stroke = egui::Stroke::new(2.0, c);
    let center = rect.center();
    let r = rect.width().min(rect.height()) * 0.4;
    match glyph {
        Glyph::Dot => {
            painter.circle(center, r * 0.8, c, egui::Stroke::new(1.0, egui::Color32::BLACK));
        }
        Glyph::Line => {
            painter.line_segment([rect.left_center(), rect.right_center()], stroke);
        }
        Glyph::Circle => {
            painter.circle_stroke(center, r, stroke);
        }
        Glyph::Frustum => {
            let apex = rect.left_center() + egui::vec2(1.0, 0.0);
            let (top, bottom) = (rect.right_top() + egui::vec2(-1.0, 2.0), rect.right_bottom() - egui::vec2(1.0, 2.0));
            painter.line_segment([apex, top], stroke);
            painter.line_segment([apex, bottom], stroke);
            painter.line_segment([top, bottom], stroke);
        }
        Glyph::Rect => {
            painter.rect_stroke(rect.shrink(2.0), 0.0, stroke, egui::StrokeKind::Inside);
        }
        Glyph::Pixels | Glyph::Palette => {
            // Four colours of the index palette: "one colour per cluster".
            let w = rect.width() / 4.0;
            for i in 0..4 {
                let cell = egui::Rect::from_min_size(
                    rect.left_top() + egui::vec2(i as f32 * w, rect.height() * 0.2),
                    egui::vec2(w, rect.height() * 0.6),
                );
                painter.rect_filled(cell, 0.0, color32(index_color(i)));
            }
        }
    }
}

/// One legend line as widgets: the glyph, then the text.
pub fn entry_ui(ui: &mut egui::Ui, entry: &LegendEntry) {
    ui.horizontal(|ui| {
        ui.add_space(20.0);
        let (rect, _) = ui.allocate_exact_size(egui::vec2(18.0, 14.0), egui::Sense::hover());
        paint_glyph(ui.painter(), rect, entry.glyph, entry.color);
        ui.label(&entry.text);
    });
}

/// How many entries of each layer the legend over the view shows (the layer's own description comes first;
/// the counts follow in the Overlays panel).
const ENTRIES_IN_VIEW: usize = 1;

/// The legend of the visible layers in the view's lower left corner, on a translucent background.
pub fn paint_in_view(painter: &egui::Painter, view: egui::Rect, legends: &[(String, Vec<LegendEntry>)]) {
    if legends.is_empty() {
        return;
    }
    let font = egui::FontId::proportional(12.0);
    let line = 16.0;
    let lines: usize = legends.iter().map(|(_, e)| 1 + e.len().min(ENTRIES_IN_VIEW)).sum();
    let height = lines as f32 * line + 8.0;
    let width = (view.width() * 0.5).clamp(160.0, 420.0);
    let rect =
        egui::Rect::from_min_size(view.left_bottom() + egui::vec2(8.0, -height - 12.0), egui::vec2(width, height));
    let painter = painter.with_clip_rect(view);
    painter.rect_filled(rect, 4.0, egui::Color32::from_black_alpha(170));
    let mut y = rect.top() + 4.0;
    for (name, entries) in legends {
        painter.text(
            egui::pos2(rect.left() + 6.0, y),
            egui::Align2::LEFT_TOP,
            name,
            font.clone(),
            egui::Color32::WHITE,
        );
        y += line;
        for e in entries.iter().take(ENTRIES_IN_VIEW) {
            let glyph = egui::Rect::from_min_size(egui::pos2(rect.left() + 14.0, y + 1.0), egui::vec2(18.0, 12.0));
            paint_glyph(&painter, glyph, e.glyph, e.color);
            painter.text(
                egui::pos2(glyph.right() + 6.0, y),
                egui::Align2::LEFT_TOP,
                &e.text,
                font.clone(),
                egui::Color32::from_gray(220),
            );
            y += line;
        }
    }
}
