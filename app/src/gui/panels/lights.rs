//! The Lights panel (layouts, and the inspector of the selected light) and the Scene panel (statistics).

use eframe::egui;
use glam::Vec3;

use crate::gui::session::Session;
use crate::gui::toasts::Toasts;

pub fn lights_ui(session: &mut Session, toasts: &mut Toasts, ui: &mut egui::Ui) {
    ui.heading(format!("Lights ({})", session.lights.len()));
    ui.label("Click a light to select it; drag the gizmo to move it. Ctrl+click on a surface adds one.");
    // The layout the lights came from (`scene`, the one placed for a scene without lights, the last applied),
    // edited in place and applied with the button.
    ui.horizontal(|ui| {
        let hint = if session.layout_spec.is_empty() { "the scene file's lights" } else { "random:64:2:1" };
        ui.add(egui::TextEdit::singleline(&mut session.layout_spec).desired_width(140.0).hint_text(hint))
            .on_hover_text(
            "random:COUNT:L_ATT[:SEED], above:COUNT:L_ATT[:SEED], circles:N:PER:L_ATT, grid:NXxNY:L_ATT, paper, scene",
        );
        if ui.button("Apply layout").clicked() {
            let spec = session.layout_spec.clone();
            match session.apply_layout(&spec) {
                Ok(n) => toasts.say(format!("{n} lights from '{spec}'")),
                Err(e) => toasts.error(e.to_string()),
            }
        }
    });
    ui.horizontal(|ui| {
        if ui.add_enabled(session.selected.is_some(), egui::Button::new("Duplicate")).clicked() {
            session.duplicate_selected();
        }
        if ui.add_enabled(session.selected.is_some(), egui::Button::new("Delete")).clicked() {
            session.delete_selected();
        }
    });
    if let Some(i) = session.selected.filter(|&i| i < session.lights.len()) {
        ui.separator();
        ui.label(format!("Light {i}"));
        let mut l = session.lights[i];
        let mut changed = false;
        let mut committed = false;
        let track = |r: egui::Response, changed: &mut bool, committed: &mut bool| {
            *changed |= r.changed();
            *committed |= r.drag_started() || r.gained_focus();
        };
        ui.horizontal(|ui| {
            for (axis, v) in ["x", "y", "z"].iter().zip([&mut l.position.x, &mut l.position.y, &mut l.position.z]) {
                let r = ui.add(egui::DragValue::new(v).speed(0.01).prefix(format!("{axis} ")));
                track(r, &mut changed, &mut committed);
            }
        });
        let mut rgb = l.color.to_array();
        let r = ui.horizontal(|ui| {
            ui.label("colour");
            ui.color_edit_button_rgb(&mut rgb)
        });
        track(r.inner, &mut changed, &mut committed);
        let r = ui.add(egui::Slider::new(&mut l.intensity, 0.0..=1000.0).logarithmic(true).text("intensity"));
        track(r, &mut changed, &mut committed);
        let r = ui.add(egui::Slider::new(&mut l.range, 0.01..=1000.0).logarithmic(true).text("L_att"));
        track(r, &mut changed, &mut committed);
        // Spot lights: a cone (glTF semantics) aimed by yaw and pitch.
        let mut is_spot = l.spot.is_some();
        let r = ui.checkbox(&mut is_spot, "spot light");
        if r.changed() {
            committed = true;
            changed = true;
            l.spot =
                is_spot.then(|| shadowlab_core::scene::Spot::aimed(Vec3::ZERO, Vec3::NEG_Y, 30f32.to_radians(), 0.2));
        }
        if let Some(spot) = &mut l.spot {
            let d = spot.direction;
            let mut yaw = d.x.atan2(-d.z).to_degrees();
            let mut pitch = d.y.clamp(-1.0, 1.0).asin().to_degrees();
            let mut cone = spot.outer_angle.to_degrees();
            let mut softness = if spot.outer_angle > 0.0 { 1.0 - spot.inner_angle / spot.outer_angle } else { 0.0 };
            ui.horizontal(|ui| {
                let r =
                    ui.add(egui::DragValue::new(&mut yaw).speed(0.5).range(-180.0..=180.0).prefix("yaw ").suffix("°"));
                track(r, &mut changed, &mut committed);
                let r = ui
                    .add(egui::DragValue::new(&mut pitch).speed(0.5).range(-90.0..=90.0).prefix("pitch ").suffix("°"));
                track(r, &mut changed, &mut committed);
            });
            let r = ui.add(egui::Slider::new(&mut cone, 0.0..=90.0).text("cone half-angle °"));
            track(r, &mut changed, &mut committed);
            let r = ui.add(egui::Slider::new(&mut softness, 0.0..=1.0).text("softness"));
            track(r, &mut changed, &mut committed);
            let (yaw, pitch) = (yaw.to_radians(), pitch.to_radians());
            let direction = Vec3::new(yaw.sin() * pitch.cos(), pitch.sin(), -yaw.cos() * pitch.cos());
            *spot = shadowlab_core::scene::Spot::aimed(Vec3::ZERO, direction, cone.to_radians(), softness);
        }
        l.color = Vec3::from_array(rgb);
        if committed {
            session.begin_edit();
        }
        if changed && l.is_valid() {
            session.lights[i] = l;
        }
    }
    ui.separator();
    suns_ui(session, ui);
}

/// The sun's angles (the core's convention, shared with the CLI's `--sun`).
pub use shadowlab_core::scene::{sun_angles, sun_direction};

/// The directional lights: add, aim, colour and remove (undoable, saved in scene files).
fn suns_ui(session: &mut Session, ui: &mut egui::Ui) {
    let max = shadowlab_core::scene::MAX_DIRECTIONAL_LIGHTS;
    ui.horizontal(|ui| {
        ui.label(format!("Suns ({})", session.suns.len())).on_hover_text(
            "Directional lights: shaded for every direct technique with an orthographic shadow map fitted to the \
             view (the ray tracer and ReSTIR: shadow rays; the preview: none). Their light also makes VPLs \
             (an orthographic RSM or parallel particles), and the path tracer sees them at every bounce.",
        );
        let add = ui.add_enabled(session.suns.len() < max, egui::Button::new("+ sun"));
        if add.on_disabled_hover_text(format!("at most {max} suns")).clicked() {
            // From behind the viewer, 30 degrees to the side and 50 above the horizon: it lights what is seen.
            let (behind, _) = sun_angles(session.camera.camera().forward());
            let azimuth = (behind + 30.0 + 180.0).rem_euclid(360.0) - 180.0;
            session.begin_edit();
            session.suns.push(shadowlab_core::scene::DirectionalLight {
                direction: sun_direction(azimuth, 50.0),
                color: Vec3::ONE,
                illuminance: 1.0,
            });
        }
    });
    let mut remove = None;
    let mut committed = false;
    let mut edited = session.suns.clone();
    for (i, d) in edited.iter_mut().enumerate() {
        ui.push_id(("sun", i), |ui| {
            let (mut azimuth, mut elevation) = sun_angles(d.direction);
            let mut rgb = d.color.to_array();
            let mut track = |r: egui::Response| committed |= r.drag_started() || r.gained_focus();
            ui.horizontal(|ui| {
                ui.label(format!("{i}"));
                let r = ui.add(
                    egui::DragValue::new(&mut azimuth).speed(0.5).range(-180.0..=180.0).prefix("azimuth ").suffix("°"),
                );
                track(r);
                let r = ui.add(
                    egui::DragValue::new(&mut elevation)
                        .speed(0.5)
                        .range(-89.0..=89.0)
                        .prefix("elevation ")
                        .suffix("°"),
                );
                track(r);
                let r = ui.color_edit_button_rgb(&mut rgb);
                track(r);
                if ui.small_button("remove").on_hover_text("remove this sun").clicked() {
                    remove = Some(i);
                }
            });
            let r = ui.add(
                egui::Slider::new(&mut d.illuminance, 0.0..=1000.0)
                    .logarithmic(true)
                    .text("W/m²")
                    .clamping(egui::SliderClamping::Always),
            );
            track(r);
            d.direction = sun_direction(azimuth, elevation);
            d.color = Vec3::from_array(rgb).max(Vec3::ZERO);
        });
    }
    if committed {
        session.begin_edit();
    }
    if let Some(i) = remove {
        session.begin_edit();
        edited.remove(i);
    }
    if edited != session.suns && edited.iter().all(|d| d.is_valid()) {
        session.suns = edited;
    }
}

pub fn stats_ui(session: &Session, ui: &mut egui::Ui) {
    ui.heading("Scene");
    let b = session.scene.bounds;
    egui::Grid::new("stats").num_columns(2).show(ui, |ui| {
        ui.label("name");
        ui.label(&session.scene.name);
        ui.end_row();
        ui.label("triangles");
        ui.label(format!("{}", session.scene.triangle_count()));
        ui.end_row();
        ui.label("materials");
        ui.label(format!("{}", session.scene.materials.len()));
        ui.end_row();
        ui.label("lights");
        ui.label(format!("{}", session.lights.len()));
        ui.end_row();
        if !session.suns.is_empty() {
            ui.label("directional lights").on_hover_text(
                "The model file's suns (a glTF file's directional lights) as edited in the Lights panel: shaded for \
                 every technique, with the orthographic shadow map (the ray tracer and ReSTIR: shadow rays; the \
                 preview: none), and a share of the VPLs",
            );
            ui.vertical(|ui| {
                for d in &session.suns {
                    let v = d.direction;
                    ui.label(format!("towards ({:.2}, {:.2}, {:.2}), {:.3} W/m²", v.x, v.y, v.z, d.illuminance));
                }
            });
            ui.end_row();
        }
        ui.label("bounds");
        ui.label(format!("{:.1} × {:.1} × {:.1} (scene units, metres)", b.size().x, b.size().y, b.size().z));
        ui.end_row();
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_suns_angles_and_direction_round_trip() {
        for (az, el) in [(0.0, 45.0), (30.0, 50.0), (-150.0, 10.0), (179.0, 89.0), (-90.0, -20.0)] {
            let d = sun_direction(az, el);
            assert!((d.length() - 1.0).abs() < 1e-5);
            let (a, e) = sun_angles(d);
            assert!((a - az).abs() < 1e-3 && (e - el).abs() < 1e-3, "({az}, {el}) -> ({a}, {e})");
        }
        // A sun high in the sky shines down; azimuth 0 is towards -Z, so its light travels towards +Z.
        let d = sun_direction(0.0, 60.0);
        assert!(d.y < -0.8 && d.z > 0.4, "{d}");
    }
}
