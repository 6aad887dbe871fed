//! The Shadows panel: the technique and its parameters (a panel generated from the technique's parameter
//! list), the indirect technique with its parameters (the same generated panel), the VPL settings and the
//! component the views show.

use std::collections::BTreeMap;

use eframe::egui;
use shadowlab_core::renderer::Component;
use shadowlab_core::technique::registry::{INDIRECT_REGISTRY, REGISTRY};
use shadowlab_core::technique::{CameraPose, ParamKind, ParamValue, Technique};
use shadowlab_core::vpl::{VplSource, MAX_BOUNCES, MAX_VPLS};

use crate::gui::document::IndirectSettings;
use crate::gui::session::Session;
use crate::gui::views::Views;

/// A widget for one technique parameter; returns the new value when it changed.
fn param_ui(ui: &mut egui::Ui, kind: &ParamKind, value: &ParamValue, label: &str, help: &str) -> Option<ParamValue> {
    let mut out = None;
    ui.horizontal(|ui| match (kind, value) {
        (ParamKind::Float { min, max }, ParamValue::Float(v)) => {
            let mut x = *v;
            // egui's logarithmic sliders need a range that does not cross zero (a negative minimum panics).
            let logarithmic = *min >= 0.0 && *max / min.max(1e-6) > 1000.0;
            let r = ui.add(egui::Slider::new(&mut x, *min..=*max).logarithmic(logarithmic).text(label));
            if r.changed() {
                out = Some(ParamValue::Float(x));
            }
        }
        (ParamKind::Int { min, max }, ParamValue::Int(v)) => {
            let mut x = *v;
            let logarithmic = *min >= 0 && *max / (*min).max(1) > 100;
            if ui.add(egui::Slider::new(&mut x, *min..=*max).logarithmic(logarithmic).text(label)).changed() {
                out = Some(ParamValue::Int(x));
            }
        }
        (ParamKind::Bool, ParamValue::Bool(v)) => {
            let mut x = *v;
            if ui.checkbox(&mut x, label).changed() {
                out = Some(ParamValue::Bool(x));
            }
        }
        (ParamKind::Choice(options), ParamValue::Choice(v)) => {
            let mut x = v.clone();
            egui::ComboBox::from_label(label).selected_text(&x).show_ui(ui, |ui| {
                for o in options.iter() {
                    ui.selectable_value(&mut x, o.to_string(), *o);
                }
            });
            if &x != v {
                out = Some(ParamValue::Choice(x));
            }
        }
        _ => {
            ui.label(format!("{label}: {value}"));
        }
    })
    .response
    .on_hover_text(help);
    out
}

/// The list of a [`ParamKind::Cameras`] parameter: select (the gizmo moves it), delete, add from the view camera,
/// or start from the cameras the technique placed itself. Returns the new list when it changed.
fn cameras_ui(
    ui: &mut egui::Ui,
    p: &shadowlab_core::technique::Param,
    max: usize,
    list: &[CameraPose],
    in_use: &[CameraPose],
    view_camera: &shadowlab_core::scene::Camera,
    selected: &mut Option<(String, usize)>,
) -> Option<Vec<CameraPose>> {
    let mut out = None;
    ui.label(format!("{}: {} of at most {max}", p.label, list.len())).on_hover_text(p.help);
    let mut remove = None;
    for (i, c) in list.iter().enumerate() {
        ui.horizontal(|ui| {
            let is_selected = selected.as_ref().is_some_and(|(k, j)| k == p.key && *j == i);
            let text = format!("#{} at ({:.2}, {:.2}, {:.2})", i + 1, c.position.x, c.position.y, c.position.z);
            if ui.selectable_label(is_selected, text).on_hover_text("Select to move it with the gizmo").clicked() {
                *selected = Some((p.key.to_string(), i));
            }
            if ui.small_button("Remove").on_hover_text("Remove this camera").clicked() {
                remove = Some(i);
            }
        });
    }
    if let Some(i) = remove {
        let mut l = list.to_vec();
        l.remove(i);
        *selected = None;
        out = Some(l);
    }
    ui.horizontal(|ui| {
        let add = ui
            .add_enabled(list.len() < max, egui::Button::new("Add from view"))
            .on_hover_text("A new camera where the view camera is, looking where it looks");
        if add.clicked() {
            let mut l = list.to_vec();
            l.push(CameraPose {
                position: view_camera.position,
                target: view_camera.position + view_camera.forward(),
                fov_y_deg: view_camera.fov_y.to_degrees().clamp(10.0, 120.0),
            });
            *selected = Some((p.key.to_string(), l.len() - 1));
            out = Some(l);
        }
        let copy = ui
            .add_enabled(!in_use.is_empty() && in_use != list, egui::Button::new("Edit the placed ones"))
            .on_hover_text("Start from the cameras the technique placed in the last frame");
        if copy.clicked() {
            out = Some(in_use.iter().take(max).copied().collect());
        }
    });
    out
}

/// The generated parameter panel of a technique, direct or indirect: a widget per parameter of `params()`; a
/// change goes through `set_param` and is remembered in `user` (the values the views render with).
fn params_panel(
    ui: &mut egui::Ui,
    technique: &mut dyn Technique,
    user: &mut BTreeMap<String, ParamValue>,
    view_camera: &shadowlab_core::scene::Camera,
    selected_camera: &mut Option<(String, usize)>,
    selected_light: &mut Option<usize>,
) {
    // Apply the user's values first, so the widgets show them.
    for (k, v) in user.iter() {
        let _ = technique.set_param(k, v);
    }
    // The parameters that only schedule, time or count the work go last, folded ("Tuning").
    let tuning = technique.tuning_params();
    let (params, tuned): (Vec<_>, Vec<_>) = technique.params().into_iter().partition(|p| !tuning.contains(&p.key));
    let mut edits = Vec::new();
    for p in &params {
        let changed = match (&p.kind, &p.value) {
            (ParamKind::Cameras { max, selected_by }, ParamValue::Cameras(list)) => {
                let in_use = technique.cameras_in_use(p.key);
                let edited = cameras_ui(ui, p, *max, list, &in_use, view_camera, selected_camera);
                if edited.is_some() {
                    // Edited cameras are the ones the technique should use: select them.
                    if let Some((key, value)) = selected_by {
                        let value = ParamValue::Choice(value.to_string());
                        if technique.set_param(key, &value).is_ok() {
                            user.insert(key.to_string(), value);
                        }
                    }
                    *selected_light = None;
                }
                edited.map(ParamValue::Cameras)
            }
            _ => param_ui(ui, &p.kind, &p.value, p.label, p.help),
        };
        edits.extend(changed.map(|v| (p.key, v)));
    }
    if !tuned.is_empty() {
        egui::CollapsingHeader::new("Tuning (speed only: the image does not change)")
            .id_salt(("tuning", technique.key()))
            .show(ui, |ui| {
                for p in &tuned {
                    edits.extend(param_ui(ui, &p.kind, &p.value, p.label, p.help).map(|v| (p.key, v)));
                }
            });
    }
    for (key, v) in edits {
        if technique.set_param(key, &v).is_ok() {
            user.insert(key.to_string(), v);
        }
    }
}

pub fn technique_ui(session: &mut Session, views: &mut Views, ui: &mut egui::Ui) {
    ui.heading("Shadows");
    egui::ComboBox::from_label("Technique").selected_text(session.technique.clone()).width(150.0).truncate().show_ui(
        ui,
        |ui| {
            for e in REGISTRY {
                ui.selectable_value(&mut session.technique, e.key.to_string(), e.label);
            }
        },
    );
    let key = session.technique.clone();
    let view_camera = session.camera.camera();
    let Some(gpu) = &mut views.gpu else { return };
    let Ok(technique) = gpu.main.technique(&key) else { return };
    let user = session.params.entry(key.clone()).or_default();
    params_panel(ui, technique.as_mut(), user, &view_camera, &mut session.selected_camera, &mut session.selected);
    if ui.button("Reset parameters").clicked() {
        session.params.remove(&key);
        gpu.main.reset_technique(&key);
    }
}

/// The indirect technique selector with its generated parameter panel, the VPL settings, and the component
/// the views show.
pub fn indirect_ui(session: &mut Session, views: &mut Views, status: &mut String, ui: &mut egui::Ui) {
    ui.heading("Indirect light");
    let mut choice = session.indirect.technique.clone();
    egui::ComboBox::from_label("Indirect")
        .selected_text(choice.clone().unwrap_or_else(|| "none".into()))
        .width(150.0)
        .truncate()
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut choice, None, "None (direct light only)");
            for e in INDIRECT_REGISTRY {
                ui.selectable_value(&mut choice, Some(e.key.to_string()), e.label);
            }
        });
    // A change restarts the views' frames: the indirect key is part of what a frame depends on. A technique
    // whose paper uses another VPL source switches to it (the user can switch back below).
    if choice != session.indirect.technique {
        if let Some(source) = choice.as_deref().and_then(shadowlab_core::technique::registry::preferred_vpl_source) {
            session.indirect.vpl.source = source;
        }
    }
    session.indirect.technique = choice;
    let mut uses_vpls = false;
    if let (Some(key), Some(gpu)) = (session.indirect.technique.clone(), &mut views.gpu) {
        match gpu.main.indirect_technique(&key) {
            Ok(shared) => {
                let mut technique = shared.borrow_mut();
                uses_vpls = technique.uses_vpls();
                let user = session.indirect.params.entry(key.clone()).or_default();
                let view_camera = session.camera.camera();
                ui.push_id("indirect parameters", |ui| {
                    params_panel(
                        ui,
                        technique.as_mut(),
                        user,
                        &view_camera,
                        &mut session.selected_camera,
                        &mut session.selected,
                    );
                });
                drop(technique);
                if ui.button("Reset indirect parameters").clicked() {
                    session.indirect.params.remove(&key);
                    // Both views, so a comparison keeps comparing the same indirect light.
                    for view in [&mut gpu.main, &mut gpu.reference] {
                        if let Err(e) = view.reset_indirect(&key) {
                            *status = format!("indirect: {e:#}");
                        }
                    }
                }
            }
            Err(e) => {
                ui.colored_label(egui::Color32::LIGHT_RED, format!("{e:#}"));
            }
        }
    }
    ui.add_enabled_ui(uses_vpls, |ui| vpl_ui(&mut session.indirect, ui));
    ui.horizontal(|ui| {
        ui.label("show");
        for c in [Component::Total, Component::Direct, Component::Indirect] {
            ui.selectable_value(&mut session.indirect.component, c, c.name());
        }
    })
    .response
    .on_hover_text("The part of the light the views, the difference and the screenshots show");
    ui.add_enabled_ui(session.indirect.component == Component::Indirect, |ui| {
        ui.add(
            egui::Slider::new(&mut session.indirect.gain, IndirectSettings::GAIN_RANGE)
                .logarithmic(true)
                .text("indirect gain"),
        )
        .on_hover_text("Display gain of the indirect component (not applied to measurements)");
    });
}

/// The VPL settings every indirect technique of a frame shares.
fn vpl_ui(indirect: &mut IndirectSettings, ui: &mut egui::Ui) {
    let v = &mut indirect.vpl;
    ui.add(egui::Slider::new(&mut v.count, 0..=MAX_VPLS).logarithmic(true).text("VPLs"))
        .on_hover_text("VPL samples drawn (RSM texels or particles); 0 = no indirect light");
    ui.horizontal(|ui| {
        ui.label("VPL source");
        for source in [VplSource::Rsm, VplSource::Traced] {
            ui.selectable_value(&mut v.source, source, source.name());
        }
    })
    .response
    .on_hover_text("rsm: reflective shadow maps (one bounce); traced: particles traced from the lights");
    ui.add_enabled_ui(v.source == VplSource::Traced, |ui| {
        ui.add(egui::Slider::new(&mut v.bounces, 1..=MAX_BOUNCES).text("bounces"))
            .on_hover_text("Bounces of a traced particle (the RSM source is always one bounce)");
    });
    ui.horizontal(|ui| {
        ui.add(
            egui::DragValue::new(&mut v.clamp_world)
                .range(0.0..=1000.0)
                .speed(0.002)
                .max_decimals(3)
                .prefix("clamp distance "),
        )
        .on_hover_text("1/d² is clamped to 1/d_clamp² (world units): fewer splotches, darker corners");
        ui.add(egui::DragValue::new(&mut v.seed).speed(1.0).prefix("seed "))
            .on_hover_text("Offset of the VPLs' quasi-random sequence: another, equally good, VPL set");
    });
}
