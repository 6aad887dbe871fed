//! The Render panel (resolution, exposure, light animation, camera, comparison and difference settings with the
//! metrics) and the Overlays panel (the technique's overlay layers with their legends).

use eframe::egui;

use crate::gui::camera::{CameraController, CameraMode};
use crate::gui::document::ViewMode;
use crate::gui::session::{Animation, Session};
use crate::gui::views::Views;

pub fn render_ui(session: &mut Session, views: &Views, ui: &mut egui::Ui) {
    ui.heading("Render");
    ui.add(egui::Slider::new(&mut session.view.resolution_scale, 0.1..=2.0).text("resolution scale"));
    ui.horizontal(|ui| {
        ui.checkbox(&mut session.view.auto_exposure, "auto exposure").on_hover_text(
            "Scale the exposure so the image's log-average luminance (over the geometry) is middle grey; the \
             slider then compensates. Each view meters its own complete image; the preview while dragging keeps \
             the last one.",
        );
    });
    if let (true, Some((scale, average))) = (session.view.auto_exposure, views.metered_exposure) {
        ui.label(format!("metered: log-average luminance {average:.4}, scale ×{scale:.3}"));
    }
    let label = if session.view.auto_exposure { "compensation" } else { "exposure" };
    ui.add(egui::Slider::new(&mut session.view.exposure, 0.05..=8.0).logarithmic(true).text(label));
    ui.checkbox(&mut session.view.specular, "Blinn-Phong specular");
    ui.horizontal(|ui| {
        ui.label("Animate lights");
        ui.radio_value(&mut session.animation, Animation::Off, "off");
        ui.radio_value(&mut session.animation, Animation::Orbit, "orbit");
        ui.radio_value(&mut session.animation, Animation::Bob, "bob");
    });
    ui.heading("Camera");
    ui.horizontal(|ui| {
        let mut mode = session.camera.mode;
        ui.radio_value(&mut mode, CameraMode::Orbit, "orbit");
        ui.radio_value(&mut mode, CameraMode::Fly, "fly (WASD QE)");
        session.camera.set_mode(mode);
    });
    ui.horizontal(|ui| {
        if ui.button("Frame scene (F)").clicked() {
            let b = session.scene.bounds;
            session.camera.frame(&b);
        }
        if ui.button("Reset").clicked() {
            session.camera = CameraController::from_camera(&session.scene.camera, &session.scene.bounds);
        }
    });
    let near = session.camera.near;
    ui.add(egui::Slider::new(&mut session.camera.z_far, (near * 2.0)..=10_000.0).logarithmic(true).text("z_far"));
    ui.add(egui::Slider::new(&mut session.camera.fov_y, 0.2..=2.5).text("fov (rad)"));
    ui.heading("Compare");
    ui.horizontal(|ui| {
        ui.selectable_value(&mut session.view.mode, ViewMode::Single, "single");
        ui.selectable_value(&mut session.view.mode, ViewMode::SideBySide, "side by side");
        ui.selectable_value(&mut session.view.mode, ViewMode::Split, "split");
        ui.selectable_value(&mut session.view.mode, ViewMode::Difference, "difference");
    });
    ui.horizontal(|ui| {
        ui.label("against");
        // The registry's references and ground truths, in its order.
        for target in shadowlab_core::technique::registry::targets() {
            ui.selectable_value(&mut session.view.compare_against, target.key.to_string(), target.key)
                .on_hover_text(format!("{} ({})", target.label, target.role.name()));
        }
    });
    if session.view.mode == ViewMode::Difference {
        ui.horizontal(|ui| {
            ui.checkbox(&mut session.view.diff_signed, "signed");
            ui.checkbox(&mut session.view.diff_visibility, "shadow factors");
        });
        ui.horizontal(|ui| {
            ui.label("gain");
            for g in [1.0, 5.0, 10.0] {
                ui.selectable_value(&mut session.view.diff_gain, g, format!("×{g}"));
            }
        });
        if let Some(d) = &views.difference {
            let m = &d.metrics;
            egui::Grid::new("metrics").num_columns(2).show(ui, |ui| {
                ui.label("RMSE");
                ui.label(format!("{:.5}", m.rmse));
                ui.end_row();
                ui.label("MSE");
                ui.label(format!("{:.3e}", m.mse));
                ui.end_row();
                ui.label("PSNR");
                ui.label(m.psnr_db.map(|p| format!("{p:.2} dB")).unwrap_or_else(|| "inf".into()));
                ui.end_row();
                ui.label("FLIP mean");
                ui.label(m.flip_mean.map(|f| format!("{f:.4}")).unwrap_or_else(|| "-".into()));
                ui.end_row();
                ui.label("shadow error");
                ui.label(m.shadow_intensity_error.map(|e| format!("{:.2}%", e * 100.0)).unwrap_or_else(|| "-".into()));
                ui.end_row();
                ui.label(format!("pixels > {:.0}%", m.threshold * 100.0));
                ui.label(format!("{:.2}%", m.share_over_threshold * 100.0));
                ui.end_row();
            });
        }
    }
}

pub fn overlays_ui(session: &mut Session, views: &mut Views, ui: &mut egui::Ui) {
    ui.heading("Overlays");
    ui.checkbox(&mut session.view.x_ray, "X-ray (through geometry)")
        .on_hover_text("Off: the parts behind surfaces are drawn faded; on: everything is drawn in full on top");
    ui.checkbox(&mut session.view.legend, "Legend over the view");
    ui.label("Hover a light for its details; click it to select it (and its cluster, when it has one).");
    for (name, on) in views.overlay_layers(session) {
        let mut x = on;
        if ui.checkbox(&mut x, &name).changed() {
            session.view.overlays.insert(name.clone(), x);
        }
        // The legend of the layers drawn in the last frame.
        if let Some((_, entries)) = views.legends.iter().find(|(n, _)| *n == name).filter(|_| x) {
            for e in entries {
                crate::gui::legend::entry_ui(ui, e);
            }
        }
    }
}
