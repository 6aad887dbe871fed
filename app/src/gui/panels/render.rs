//! The Render panel (resolution, exposure, light animation, camera, comparison and difference settings with the
//! metrics) and the Overlays panel (the technique's overlay layers with their legends).

use eframe::egui;

use crate::gui::camera::{CameraController, CameraMode};
use crate::gui::document::ViewMode;
use crate::gui::session::{Animation, Session};
use crate::gui::views::Views;

pub fn render_ui(session: &mut Session, views: &mut Views, ui: &mut egui::Ui) {
    ui.heading("Render");
    ui.add(egui::Slider::new(&mut session.view.resolution_scale, 0.1..=2.0).text("resolution scale"));
    ui.horizontal(|ui| {
        ui.checkbox(&mut session.view.auto_exposure, "auto exposure").on_hover_text(
            "Scale the exposure so the image's log-average luminance (over the geometry) is middle grey; the \
             slider then compensates. Each view meters its own complete image; the preview while dragging keeps \
             the last one.",
        );
    });
    // The line is there before the first metering too, so nothing below it moves when the value arrives.
    if session.view.auto_exposure {
        match views.metered_exposure {
            Some((scale, average)) => {
                ui.label(format!("metered: log-average luminance {average:.4}, scale ×{scale:.3}"))
            }
            None => ui.label("metered: when the first frame is complete"),
        };
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
        if ui
            .button("Frame scene (F)")
            .on_hover_text("Inside an enclosed interior, from outside for an object")
            .clicked()
        {
            views.frame_scene(session);
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
    target_indirect_ui(session, ui);
    if session.view.mode != ViewMode::Single {
        map_resolution_ui(session, views, ui);
    }
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
            // While a new comparison is on its way the numbers are the previous frames': greyed and said so.
            let stale = !views.difference_is_current();
            if stale {
                ui.label(egui::RichText::new("previous frames' metrics: the new comparison is being computed").weak());
            }
            let text = |s: String| if stale { egui::RichText::new(s).weak() } else { egui::RichText::new(s) };
            egui::Grid::new("metrics").num_columns(2).show(ui, |ui| {
                ui.label("RMSE");
                ui.label(text(format!("{:.5}", m.rmse)));
                ui.end_row();
                ui.label("MSE");
                ui.label(text(format!("{:.3e}", m.mse)));
                ui.end_row();
                ui.label("PSNR").on_hover_text(
                    "10·log10(peak² / MSE) over the HDR images, the peak being the target's brightest luminance \
                     over the compared pixels (not 1: HDR radiance has no fixed maximum)",
                );
                ui.label(text(match m.psnr_db {
                    Some(p) => format!("{p:.2} dB (peak {:.3})", m.peak_luminance),
                    None => "inf (identical images)".into(),
                }));
                ui.end_row();
                ui.label("FLIP mean");
                ui.label(text(m.flip_mean.map(|f| format!("{f:.4}")).unwrap_or_else(|| "- (not computed)".into())));
                ui.end_row();
                ui.label("shadow error");
                ui.label(text(match m.shadow_intensity_error {
                    Some(e) => format!("{:.2}%", e * 100.0),
                    None if !session.view.diff_visibility => "- (needs \"shadow factors\" on)".into(),
                    None => "- (no lit pixel to compare)".into(),
                }));
                ui.end_row();
                ui.label(format!("pixels > {:.0}%", m.threshold * 100.0));
                ui.label(text(format!("{:.2}%", m.share_over_threshold * 100.0)));
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

/// The comparison target's indirect technique: the view's own (the default: the same indirect light on both
/// sides), none, or one of the indirect registry's references and ground truths, the view's declared target
/// marked (VALs against one shadow map per VPL, fuzzy clustering against exact VPL visibility).
fn target_indirect_ui(session: &mut Session, ui: &mut egui::Ui) {
    use shadowlab_core::technique::registry::INDIRECT_REGISTRY;
    let own = session.indirect.technique.clone();
    if own.is_none() && session.view.against_indirect.is_none() {
        return;
    }
    // The view's declared target, where it is not the view's own technique (a ground truth's is itself).
    let declared = own.as_deref().and_then(shadowlab_core::technique::registry::own_indirect_target);
    let indirect_only = session.indirect.component == shadowlab_core::renderer::Component::Indirect;
    let own_name = own.as_deref().unwrap_or("none");
    let name = |choice: &Option<String>| -> String {
        match (choice.as_deref(), declared) {
            (None, Some(target)) if indirect_only => {
                format!("{own_name}'s target ({target}; the indirect light alone)")
            }
            (None, _) => format!("same ({own_name})"),
            (Some("none"), _) => "none".to_string(),
            (Some(k), Some(target)) if k == target => format!("{k} ({own_name}'s target)"),
            (Some(k), _) => k.to_string(),
        }
    };
    let current = session.view.against_indirect.clone();
    ui.horizontal(|ui| {
        ui.label("target's indirect");
        egui::ComboBox::from_id_salt("against indirect")
            .selected_text(name(&current))
            .show_ui(ui, |ui| {
                let mut choices: Vec<Option<String>> = vec![None, Some("none".into())];
                choices
                    .extend(INDIRECT_REGISTRY.iter().filter(|e| e.role.is_target()).map(|e| Some(e.key.to_string())));
                for choice in choices {
                    let text = name(&choice);
                    ui.selectable_value(&mut session.view.against_indirect, choice, text);
                }
            })
            .response
            .on_hover_text(
                "The indirect technique of the comparison view (side by side, split, difference, figures, sweeps): \
             the view's own compares the direct techniques under the same indirect light (with the indirect \
             light alone shown, the indirect technique's own target instead: the same one would differ by \
             nothing); a reference or ground truth compares the indirect technique itself",
            );
    });
}

/// Says when the technique and its comparison target draw their maps at different resolutions (each technique
/// has its own default), with a button that gives the target the technique's.
fn map_resolution_ui(session: &mut Session, views: &mut Views, ui: &mut egui::Ui) {
    let Some((technique, target)) = views.unequal_map_resolutions(session) else { return };
    ui.horizontal_wrapped(|ui| {
        ui.label(
            egui::RichText::new(format!(
                "maps not at one resolution: {} {technique}², {} {target}²",
                session.technique, session.view.compare_against
            ))
            .color(ui.visuals().warn_fg_color),
        );
        if ui
            .button("match")
            .on_hover_text("Give the comparison target the technique's map resolution (its shadow_res parameter)")
            .clicked()
        {
            let against = session.view.compare_against.clone();
            session
                .params
                .entry(against)
                .or_default()
                .insert("shadow_res".into(), shadowlab_core::technique::ParamValue::Int(technique));
        }
    });
}
