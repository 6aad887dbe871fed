//! The panels around the 3D view: menu bar, technique and parameters (generated from the technique's parameter
//! list), the indirect technique with its parameters (the same generated panel), VPL settings and component,
//! render and camera settings, overlays, the light list and inspector, scene statistics, timings.

use eframe::egui;
use egui_plot::{Legend, Line, Plot, PlotPoints};
use glam::Vec3;
use std::collections::{BTreeMap, VecDeque};

use shadowlab_core::renderer::Component;
use shadowlab_core::technique::{CameraPose, ParamKind, ParamValue, Technique, INDIRECT_REGISTRY, REGISTRY};
use shadowlab_core::vpl::{VplSource, MAX_BOUNCES, MAX_VPLS};

use crate::gui::camera::CameraMode;
use crate::gui::chrome::{Chrome, Toasts};
use crate::gui::document::{IndirectSettings, ViewMode};
use crate::gui::inspector::Inspector;
use crate::gui::layout::Pane;
use crate::gui::session::{Animation, Session};
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
    for p in technique.params() {
        let changed = match (&p.kind, &p.value) {
            (ParamKind::Cameras { max, selected_by }, ParamValue::Cameras(list)) => {
                let in_use = technique.cameras_in_use(p.key);
                let edited = cameras_ui(ui, &p, *max, list, &in_use, view_camera, selected_camera);
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
        if let Some(v) = changed {
            if technique.set_param(p.key, &v).is_ok() {
                user.insert(p.key.to_string(), v);
            }
        }
    }
}

fn technique_ui(session: &mut Session, views: &mut Views, ui: &mut egui::Ui) {
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
fn indirect_ui(session: &mut Session, views: &mut Views, status: &mut String, ui: &mut egui::Ui) {
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
        if let Some(source) = choice.as_deref().and_then(shadowlab_core::technique::preferred_vpl_source) {
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

fn render_ui(session: &mut Session, views: &Views, ui: &mut egui::Ui) {
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
            session.camera =
                crate::gui::camera::CameraController::from_camera(&session.scene.camera, &session.scene.bounds);
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
        ui.selectable_value(&mut session.view.compare_against, "reference".to_string(), "reference");
        ui.selectable_value(&mut session.view.compare_against, "raytraced".to_string(), "ray traced");
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

fn overlays_ui(session: &mut Session, views: &mut Views, ui: &mut egui::Ui) {
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

fn lights_ui(session: &mut Session, toasts: &mut Toasts, ui: &mut egui::Ui) {
    ui.heading(format!("Lights ({})", session.lights.len()));
    ui.label("Click a light to select it; drag the gizmo to move it. Ctrl+click on a surface adds one.");
    thread_local! {
        static SPEC: std::cell::RefCell<String> = std::cell::RefCell::new("circles:10:8:7".to_string());
    }
    ui.horizontal(|ui| {
        let mut spec = SPEC.with(|s| s.borrow().clone());
        ui.add(egui::TextEdit::singleline(&mut spec).desired_width(140.0).hint_text("random:64:2:1"))
            .on_hover_text("random:COUNT:L_ATT[:SEED], circles:N:PER:L_ATT, grid:NXxNY:L_ATT, paper, scene");
        if ui.button("Apply layout").clicked() {
            match session.apply_layout(&spec) {
                Ok(n) => toasts.say(format!("{n} lights from '{spec}'")),
                Err(e) => toasts.error(e.to_string()),
            }
        }
        SPEC.with(|s| *s.borrow_mut() = spec);
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
}

fn stats_ui(session: &Session, ui: &mut egui::Ui) {
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
        ui.label("bounds");
        ui.label(format!("{:.1} × {:.1} × {:.1} (scene units, metres)", b.size().x, b.size().y, b.size().z));
        ui.end_row();
    });
}

/// Per-pass table of the last complete frame, a plot of recent frames, and the same-session comparison with
/// the reference.
pub fn timings_ui(views: &Views, ui_frame_ms: &VecDeque<f64>, status: &str, ui: &mut egui::Ui) {
    let Some(gpu) = &views.gpu else { return };
    let ui_ms = ui_frame_ms.iter().copied().sum::<f64>() / ui_frame_ms.len().max(1) as f64;
    ui.horizontal_wrapped(|ui| {
        ui.label(format!("adapter: {}", gpu.ctx.adapter_description()));
        ui.separator();
        ui.label(format!("UI {:.0} fps", 1000.0 / ui_ms.max(1e-3)));
        ui.separator();
        ui.label(format!("lights per step: {}", gpu.sizer.max_lights_per_step));
        if !status.is_empty() {
            ui.separator();
            ui.colored_label(egui::Color32::LIGHT_RED, status);
        }
    });
    let table = |ui: &mut egui::Ui| {
        // A scroll area, so more rows never resize the panel (and with it the 3D view, which would restart).
        egui::ScrollArea::vertical().id_salt("timings table").auto_shrink([false, false]).show(ui, |ui| {
            if let Some(r) = &gpu.main.last_report {
                egui::Grid::new("passes").striped(true).num_columns(3).show(ui, |ui| {
                    ui.strong("pass");
                    ui.strong("ms");
                    ui.strong("count");
                    ui.end_row();
                    for p in &r.passes {
                        ui.label(&p.name);
                        ui.label(format!("{:.2}", p.ms));
                        ui.label(format!("{}", p.count));
                        ui.end_row();
                    }
                    let indirect_stages = r.indirect.iter().flat_map(|i| &i.cpu_stages);
                    for (p, indirect) in
                        r.cpu_stages.iter().map(|p| (p, false)).chain(indirect_stages.map(|p| (p, true)))
                    {
                        ui.label(format!("{} (CPU{})", p.name, if indirect { ", indirect" } else { "" }));
                        ui.label(format!("{:.3}", p.ms));
                        ui.label("1");
                        ui.end_row();
                    }
                    ui.strong(format!("{} total", r.technique));
                    ui.strong(format!("{:.2}", r.gpu_total_ms));
                    ui.label(format!("{:?}", r.timing_source));
                    ui.end_row();
                });
                let c = &r.counts;
                ui.label(format!(
                    "{} of {} lights visible · {} shadow maps in {} steps{} · shadow triangles {} drawn, {} culled",
                    c.technique.lights_visible,
                    c.lights_total,
                    c.technique.shadow_maps,
                    c.technique.batches,
                    c.technique.clusters.map(|n| format!(" · {n} clusters")).unwrap_or_default(),
                    c.technique.shadow_triangles_submitted,
                    c.technique.shadow_triangles_culled,
                ));
                if !c.technique.figures.is_empty() {
                    ui.label(figures_text(&c.technique.figures));
                }
                if let Some(i) = &r.indirect {
                    let mut parts = vec![format!("indirect {}", i.technique)];
                    if !i.counts.figures.is_empty() {
                        parts.push(figures_text(&i.counts.figures));
                    }
                    parts.push(format!("{} steps", i.counts.batches));
                    if i.vpls > 0 {
                        parts.push(format!("VPLs from {}, {} samples missed", i.vpl_source.name(), i.vpl_misses));
                    }
                    if i.counts.shadow_maps > 0 {
                        parts.push(format!(
                            "{} shadow maps, {} triangles drawn",
                            i.counts.shadow_maps, i.counts.shadow_triangles_submitted
                        ));
                    }
                    ui.label(parts.join(" · "));
                }
                // Every technique seen this session against the reference, same session and adapter.
                let reference =
                    crate::gui::views::technique_pair("reference", r.indirect.as_ref().map(|i| i.technique.as_str()));
                if let Some((reference_ms, _)) = views.session_times.get(&reference) {
                    egui::Grid::new("session").striped(true).num_columns(4).show(ui, |ui| {
                        ui.strong("technique (this session)");
                        ui.strong("GPU ms");
                        ui.strong("speedup");
                        ui.strong("parameters");
                        ui.end_row();
                        for (name, (ms, params)) in &views.session_times {
                            ui.label(name);
                            ui.label(format!("{ms:.1}"));
                            ui.label(format!("×{:.2}", reference_ms / ms.max(1e-6)));
                            ui.label(params);
                            ui.end_row();
                        }
                    });
                }
            } else {
                ui.label("rendering the first frame…");
            }
        });
    };
    let plot = |ui: &mut egui::Ui| {
        let mut names: Vec<String> = Vec::new();
        for (_, _, passes) in &views.timings {
            for p in passes {
                if !names.contains(&p.name) {
                    names.push(p.name.clone());
                }
            }
        }
        Plot::new("timings").legend(Legend::default()).height(130.0).y_axis_label("ms").show(ui, |plot| {
            let total: PlotPoints = views.timings.iter().map(|(t, ms, _)| [*t, *ms]).collect();
            plot.line(Line::new("frame (GPU)", total));
            for name in names {
                let pts: PlotPoints = views
                    .timings
                    .iter()
                    .map(|(t, _, passes)| [*t, passes.iter().filter(|p| p.name == name).map(|p| p.ms).sum::<f64>()])
                    .collect();
                plot.line(Line::new(name, pts));
            }
        });
    };
    // Side by side when the panel is wide, the plot above the table when it is a narrow column.
    if ui.available_width() >= 560.0 {
        ui.columns(2, |cols| {
            table(&mut cols[0]);
            plot(&mut cols[1]);
        });
    } else {
        plot(ui);
        table(ui);
    }
}

/// A technique's named figures (`vpls 1024 · samples 16`), in key order, whatever the technique.
pub fn figures_text(figures: &BTreeMap<String, f64>) -> String {
    figures
        .iter()
        .map(|(k, v)| if v.fract() == 0.0 && v.abs() < 1e15 { format!("{k} {v:.0}") } else { format!("{k} {v:.3}") })
        .collect::<Vec<_>>()
        .join(" · ")
}

/// Sweep one numeric parameter of the current technique against the reference, plotted live.
fn sweep_ui(
    session: &Session,
    views: &mut Views,
    input: &mut (String, f64, f64, usize),
    toasts: &mut Toasts,
    ui: &mut egui::Ui,
) {
    ui.heading("Sweep");
    let key = session.technique.clone();
    let Some(gpu) = &mut views.gpu else { return };
    let Ok(technique) = gpu.main.technique(&key) else { return };
    let numeric: Vec<_> = technique
        .params()
        .into_iter()
        .filter(|p| matches!(p.kind, ParamKind::Float { .. } | ParamKind::Int { .. }))
        .collect();
    if numeric.is_empty() {
        ui.label("this technique has no numeric parameter");
        return;
    }
    let (param_key, start, end, count) = input;
    let before = param_key.clone();
    if !numeric.iter().any(|p| p.key == param_key.as_str()) {
        *param_key = numeric[0].key.to_string();
    }
    egui::ComboBox::from_label("parameter").selected_text(param_key.clone()).show_ui(ui, |ui| {
        for p in &numeric {
            ui.selectable_value(param_key, p.key.to_string(), p.label);
        }
    });
    // A new parameter gets a range around its current value, inside its limits.
    if *param_key != before {
        if let Some(p) = numeric.iter().find(|p| p.key == param_key.as_str()) {
            let (lo, hi, v) = match (&p.kind, &p.value) {
                (ParamKind::Float { min, max }, ParamValue::Float(v)) => (*min as f64, *max as f64, *v as f64),
                (ParamKind::Int { min, max }, ParamValue::Int(v)) => (*min as f64, *max as f64, *v as f64),
                _ => (0.0, 1.0, 0.5),
            };
            (*start, *end) = if v > 0.0 { ((v * 0.25).max(lo), (v * 2.0).min(hi)) } else { (lo, (lo + 1.0).min(hi)) };
        }
    }
    ui.horizontal(|ui| {
        ui.add(egui::DragValue::new(start).speed(0.01).prefix("from "));
        ui.add(egui::DragValue::new(end).speed(0.01).prefix("to "));
        ui.add(egui::DragValue::new(count).range(2..=64).prefix("values "));
    });
    let (param_key, start, end, count) = (param_key.clone(), *start, *end, *count);
    let running = views.sweep.as_mut().is_some_and(|s| s.poll());
    let (mut run, mut cancel) = (false, false);
    ui.horizontal(|ui| {
        run = !running && ui.button("Run sweep").clicked();
        cancel = running && ui.button("Cancel").clicked();
    });
    if run {
        if let Some(kind) = numeric.iter().find(|p| p.key == param_key.as_str()).map(|p| p.kind.clone()) {
            let values = crate::gui::sweep::values(&kind, start, end, count);
            if let Err(e) = views.start_sweep(session, &param_key, values) {
                toasts.error(format!("sweep: {e:#}"));
            }
        }
    }
    if cancel {
        if let Some(s) = &views.sweep {
            s.cancel();
        }
    }
    if let Some(s) = &views.sweep {
        if running {
            ui.add(egui::ProgressBar::new(s.rows.len() as f32 / s.total.max(1) as f32).show_percentage());
            ui.ctx().request_repaint_after(std::time::Duration::from_millis(200));
        }
        if let Some(e) = &s.error {
            ui.colored_label(egui::Color32::LIGHT_RED, e);
        }
        if !s.rows.is_empty() {
            let time: PlotPoints = s.rows.iter().map(|r| [r.value, r.ms]).collect();
            let reference: PlotPoints = s.rows.iter().map(|r| [r.value, r.reference_ms]).collect();
            Plot::new("sweep time").legend(Legend::default()).height(110.0).x_axis_label(s.key.clone()).show(
                ui,
                |plot| {
                    plot.line(Line::new("ms", time));
                    plot.line(Line::new("reference ms", reference));
                },
            );
            let error: PlotPoints = s.rows.iter().map(|r| [r.value, r.rmse]).collect();
            Plot::new("sweep error").legend(Legend::default()).height(110.0).x_axis_label(s.key.clone()).show(
                ui,
                |plot| {
                    plot.line(Line::new("RMSE", error));
                },
            );
        }
    }
}

/// The UI of one panel (a tile of the layout).
pub fn pane_ui(session: &mut Session, views: &mut Views, chrome: &mut Chrome, ui: &mut egui::Ui, pane: Pane) {
    match pane {
        // Drawn by the layout itself.
        Pane::View => {}
        Pane::Technique => {
            technique_ui(session, views, ui);
            ui.separator();
            indirect_ui(session, views, &mut chrome.status, ui);
        }
        Pane::Render => render_ui(session, views, ui),
        Pane::Overlays => overlays_ui(session, views, ui),
        Pane::Lights => lights_ui(session, &mut chrome.toasts, ui),
        Pane::Scene => stats_ui(session, ui),
        Pane::Sweep => sweep_ui(session, views, &mut chrome.sweep_input, &mut chrome.toasts, ui),
        Pane::Timings => timings_ui(views, &chrome.ui_frame_ms, &chrome.status, ui),
        Pane::Maps => maps_ui(session, views, &mut chrome.inspector, ui),
        Pane::Explain => explain_ui(session, views, chrome, ui),
    }
}

/// The steps of the current technique's paper, as the technique declares them; choosing one switches the
/// overlay layers (and the shadow-map panel) that show it.
fn explain_ui(session: &mut Session, views: &mut Views, chrome: &mut Chrome, ui: &mut egui::Ui) {
    ui.heading("Explain");
    // The direct technique's steps, then the indirect technique's (when one is chosen and describes any).
    let mut sections: Vec<(String, &'static str, Vec<shadowlab_core::technique::ExplainStep>)> = Vec::new();
    {
        let Some(gpu) = &mut views.gpu else { return };
        if let Ok(technique) = gpu.main.technique(&session.technique) {
            sections.push((session.technique.clone(), technique.label(), technique.explain()));
        }
        if let Some(key) = session.indirect.technique.clone() {
            if let Ok(shared) = gpu.main.indirect_technique(&key) {
                let technique = shared.borrow();
                let steps = technique.explain();
                if !steps.is_empty() {
                    sections.push((key, technique.label(), steps));
                }
            }
        }
    }
    for (key, label, steps) in sections {
        if steps.is_empty() {
            ui.label(format!("{label} describes no steps."));
            continue;
        }
        ui.label(format!("The steps of {label}, as in its paper; choose one to see it in the view."));
        let mut chosen = None;
        for (i, step) in steps.iter().enumerate() {
            let selected = chrome.explain.step.as_ref().is_some_and(|(k, j)| *k == key && *j == i);
            if ui.selectable_label(selected, step.title).clicked() {
                chosen = Some(i);
            }
        }
        if let Some(i) = chosen {
            show_explain_step(session, views, chrome, &key, &steps, i);
            chrome.explain.step = Some((key.clone(), i));
        }
        if let Some(step) = chrome.explain.step.as_ref().filter(|(k, _)| *k == key).and_then(|(_, i)| steps.get(*i)) {
            ui.separator();
            ui.label(step.text);
        }
        ui.separator();
    }
}

/// Show what step `index` of technique `key`'s Explain `steps` shows: its overlay layers on, the
/// technique's others off; the shadow-map panel in front with the step's maps when it is about them; the
/// parameter values it sets, and the values from before for parameters that only other steps set.
pub fn show_explain_step(
    session: &mut Session,
    views: &mut Views,
    chrome: &mut Chrome,
    key: &str,
    steps: &[shadowlab_core::technique::ExplainStep],
    index: usize,
) {
    let Some(step) = steps.get(index) else { return };
    for (name, _) in views.overlay_layers(session) {
        let on = step.layers.contains(&name.as_str());
        session.view.overlays.insert(name, on);
    }
    let indirect = key != session.technique;
    if step.shows_shadow_maps {
        chrome.inspector.source = crate::gui::inspector::MapSource { indirect, set: step.maps };
        chrome.layout.request_focus(Pane::Maps);
    }
    let named: std::collections::BTreeSet<&str> = steps.iter().flat_map(|s| s.params.iter().map(|(k, _)| *k)).collect();
    if named.is_empty() {
        return;
    }
    let Some(gpu) = &mut views.gpu else { return };
    let specs = if indirect {
        gpu.main.indirect_technique(key).map(|t| t.borrow().params())
    } else {
        gpu.main.technique(key).map(|t| t.params())
    };
    let Ok(specs) = specs else { return };
    let mut errors = Vec::new();
    for name in named {
        let Some(spec) = specs.iter().find(|p| p.key == name) else { continue };
        let saved = (key.to_string(), name.to_string());
        let value = match step.params.iter().find(|(k, _)| *k == name) {
            Some((_, text)) => match spec.kind.parse(name, text) {
                Ok(v) => {
                    chrome.explain.saved.entry(saved).or_insert_with(|| spec.value.clone());
                    v
                }
                Err(e) => {
                    errors.push(e.to_string());
                    continue;
                }
            },
            None => match chrome.explain.saved.remove(&saved) {
                Some(v) => v,
                None => continue,
            },
        };
        let params = if indirect { &mut session.indirect.params } else { &mut session.params };
        params.entry(key.to_string()).or_default().insert(name.to_string(), value);
    }
    for e in errors {
        chrome.toasts.error(e);
    }
}

/// The shadow-map inspector: reads the chosen maps back once per completed frame (not for the preview while
/// the camera moves), then shows them; a selected light shows its cube map.
pub fn maps_ui(session: &Session, views: &mut Views, inspector: &mut Inspector, ui: &mut egui::Ui) {
    use crate::gui::inspector::{AtlasDepths, MapSource};
    use shadowlab_core::technique::Technique;
    // Every map set of the direct and the indirect technique: shadow maps first, then depth images.
    fn sets(t: &dyn Technique) -> Vec<(&shadowlab_core::renderer::cube_shadows::CubeAtlas, &'static str)> {
        t.shadow_atlas().into_iter().chain(t.depth_images()).collect()
    }
    fn labelled(t: &dyn Technique, indirect: bool) -> Vec<(MapSource, String)> {
        let shadow = usize::from(t.shadow_atlas().is_none());
        let images = t.depth_images().into_iter().map(|(_, what)| what);
        let names = t.shadow_atlas().map(|_| "shadow maps").into_iter().chain(images);
        let who = if indirect { "indirect" } else { "direct" };
        names
            .enumerate()
            .map(|(i, name)| (MapSource { indirect, set: i + shadow }, format!("{} ({who}): {name}", t.label())))
            .collect()
    }
    let key = session.technique.clone();
    let indirect_key = session.indirect.technique.clone();
    let selected = session.selected;
    let mut sources = Vec::new();
    let mut follow: Option<(usize, Vec<Vec3>)> = None;
    if let Some(gpu) = &mut views.gpu {
        if let Ok(t) = gpu.main.technique(&key) {
            sources.extend(labelled(t.as_ref(), false));
        }
        if let Some(k) = &indirect_key {
            if let Ok(t) = gpu.main.indirect_technique(k) {
                sources.extend(labelled(t.borrow().as_ref(), true));
            }
        }
        if !sources.iter().any(|(s, _)| *s == inspector.source) {
            inspector.source = sources.first().map(|(s, _)| *s).unwrap_or(MapSource::DIRECT);
        }
        let complete = gpu.main.last_report.as_ref().is_some_and(|r| r.technique == key);
        let source = inspector.source;
        let from = (gpu.main.frame_key(), source);
        if gpu.main.is_converged() && complete && inspector.read_from != Some(from) {
            let ctx = gpu.ctx.clone();
            // `set` 0 is the shadow atlas; without one the depth images still start at 1.
            let read = |t: &dyn Technique| {
                let offset = usize::from(t.shadow_atlas().is_none());
                let all = sets(t);
                source
                    .set
                    .checked_sub(offset)
                    .and_then(|i| all.get(i))
                    .map(|(a, what)| AtlasDepths::read(&ctx, a, what))
                    .transpose()
            };
            let result = if source.indirect {
                match &indirect_key {
                    Some(k) => gpu.main.indirect_technique(k).and_then(|t| read(t.borrow().as_ref())),
                    None => Ok(None),
                }
            } else {
                gpu.main.technique(&key).and_then(|t| read(t.as_ref()))
            };
            inspector.set_atlas(result.map_err(|e| format!("{e:#}")), from);
        }
    }
    if let Some(i) = selected {
        let lights = session.animated_lights();
        if let Some(light) = lights.get(i) {
            let mut positions = vec![light.position];
            let group = views.light_details(session, i).map(|d| d.group).unwrap_or_default();
            positions.extend(group.iter().filter_map(|&m| lights.get(m)).map(|l| l.position));
            follow = Some((i, positions));
        }
    }
    if let Some((i, positions)) = follow {
        inspector.follow_light(i, &positions);
    }
    inspector.ui(ui, sources);
}
