//! The Timings panel (per-pass times of the last complete frame, a plot of recent frames, the same-session
//! comparison with the reference) and the Sweep panel (one parameter swept against the reference, plotted live).

use std::collections::{BTreeMap, VecDeque};

use eframe::egui;
use egui_plot::{Legend, Line, Plot, PlotPoints};
use shadowlab_core::technique::{ParamKind, ParamValue};

use crate::gui::session::Session;
use crate::gui::toasts::Toasts;
use crate::gui::views::Views;
use shadowlab_core::timing::TimingSource;

/// Per-pass table of the last complete frame, a plot of recent frames, and the same-session comparison with
/// the reference.
pub fn timings_ui(views: &Views, scene: &str, ui_frame_ms: &VecDeque<f64>, status: &str, ui: &mut egui::Ui) {
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
                    ui.strong(format!("{} frame", r.technique));
                    ui.strong(format!("{:.2}", r.frame_ms()));
                    ui.label(r.timing.source.name());
                    ui.end_row();
                });
                clock_ui(r, ui);
                work_ui(r, ui);
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
                session_ui(views, scene, r, ui);
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
        // Colours chosen here and named under the plot: a legend inside a 130-point plot covered its lines.
        let color = |i: usize| {
            if i == 0 {
                egui::Color32::WHITE
            } else {
                egui::ecolor::Hsva::new((i as f32 * 0.618_034).fract(), 0.7, 0.95, 1.0).into()
            }
        };
        Plot::new("timings").height(130.0).y_axis_label("ms").show(ui, |plot| {
            let total: PlotPoints = views.timings.iter().map(|(t, ms, _)| [*t, *ms]).collect();
            plot.line(Line::new("frame", total).color(color(0)));
            for (i, name) in names.iter().enumerate() {
                let pts: PlotPoints = views
                    .timings
                    .iter()
                    .map(|(t, _, passes)| [*t, passes.iter().filter(|p| p.name == *name).map(|p| p.ms).sum::<f64>()])
                    .collect();
                plot.line(Line::new(name.clone(), pts).color(color(i + 1)));
            }
        });
        ui.horizontal_wrapped(|ui| {
            ui.spacing_mut().item_spacing.x = 10.0;
            for (i, name) in std::iter::once("frame").chain(names.iter().map(String::as_str)).enumerate() {
                ui.horizontal(|ui| {
                    ui.spacing_mut().item_spacing.x = 3.0;
                    let (swatch, _) = ui.allocate_exact_size(egui::vec2(9.0, 9.0), egui::Sense::hover());
                    ui.painter().rect_filled(swatch, 1.0, color(i));
                    ui.label(egui::RichText::new(name).small());
                });
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

/// Which clock the milliseconds come from, and the frame in the other clock.
fn clock_ui(r: &shadowlab_core::FrameReport, ui: &mut egui::Ui) {
    let t = &r.timing;
    let other = match (t.source, t.timestamps_ms) {
        (TimingSource::GpuTimestamps, _) => format!("wall-clock steps {:.2} ms", t.steps_wall_ms),
        (TimingSource::WallClockSteps, Some(ts)) => format!("GPU timestamps {ts:.2} ms"),
        (TimingSource::WallClockSteps, None) => "the adapter has no GPU timestamps".to_string(),
    };
    ui.label(format!(
        "clock: {} (SHADOWLAB_TIMING={}); frame = GPU work + CPU stages; {other}; frame wall clock {:.1} ms",
        t.source.name(),
        t.mode.name(),
        r.wall_ms
    ))
    .on_hover_text(
        "Every step is timed both ways: GPU timestamps around each pass and the wall time from submitting the \
         step to its completion. auto uses the timestamps until they cover under half of a step's wall time.",
    );
    if let Some(reason) = &t.reason {
        ui.colored_label(egui::Color32::from_rgb(230, 180, 80), format!("auto chose the wall clock: {reason}"));
    }
}

/// The frame's work counts (hardware-independent), direct and indirect, where the technique did such work.
fn work_ui(r: &shadowlab_core::FrameReport, ui: &mut egui::Ui) {
    let indirect = r.indirect.as_ref().map(|i| &i.work);
    let keys: Vec<&str> = shadowlab_core::technique::work::WORK_KEYS
        .iter()
        .copied()
        .filter(|k| {
            r.work.get(*k).is_some_and(|v| *v != 0.0) || indirect.and_then(|w| w.get(*k)).is_some_and(|v| *v != 0.0)
        })
        .collect();
    if keys.is_empty() {
        return;
    }
    let number = |v: Option<&f64>| v.map_or("-".to_string(), |v| crate::measure::count_text(*v));
    ui.collapsing("work counts (hardware-independent)", |ui| {
        egui::Grid::new("work").striped(true).num_columns(3).show(ui, |ui| {
            ui.strong("work");
            ui.strong(&r.technique);
            ui.strong(r.indirect.as_ref().map_or("", |i| i.technique.as_str()));
            ui.end_row();
            for k in keys {
                ui.label(k.replace('_', " "));
                ui.label(number(r.work.get(k)));
                ui.label(if indirect.is_some() && k != "shaded_pixels" {
                    number(indirect.and_then(|w| w.get(k)))
                } else {
                    String::new()
                });
                ui.end_row();
            }
        });
    })
    .header_response
    .on_hover_text("Counted where the work is decided: on the CPU (triangles, texels, k-means) or by the shaders");
}

/// The configurations of this view measured this session, with their speedup over the reference of the same
/// view in one clock.
fn session_ui(views: &Views, scene: &str, r: &shadowlab_core::FrameReport, ui: &mut egui::Ui) {
    let times = &views.session_times;
    if times.is_empty() {
        return;
    }
    let view = crate::gui::session_times::view_of(scene, r);
    let reference = shadowlab_core::technique::registry::REFERENCE;
    let rows = times.rows(view, reference);
    if rows.is_empty() {
        return;
    }
    match times.reference(view, reference) {
        Some(base) => ui.label(format!(
            "speedup = the {reference} frame ({}) over each frame, both of this view ({}, this camera and settings), \
             in the clock both used",
            if base.parameters.is_empty() { "default parameters" } else { base.parameters.as_str() },
            base.view_text
        )),
        None => ui.label(format!(
            "no {reference} frame of this view yet (same scene, lights, camera, size and settings): no speedup shown"
        )),
    };
    egui::Grid::new("session").striped(true).num_columns(4).show(ui, |ui| {
        ui.strong("technique (this view)");
        ui.strong("frame ms");
        ui.strong("speedup");
        ui.strong("parameters");
        ui.end_row();
        for row in rows {
            let e = &row.entry;
            ui.label(&e.technique);
            let clock = row.speedup.map(|(_, c)| c).unwrap_or(e.clock());
            ui.label(format!("{:.1}", e.ms_in(clock))).on_hover_text(clock.name());
            match row.speedup {
                Some((ratio, clock)) => ui.label(format!("×{ratio:.2}")).on_hover_text(format!("in {}", clock.name())),
                None => ui.label("-").on_hover_text("the reference itself, or no reference frame of this view"),
            };
            ui.label(&e.parameters);
            ui.end_row();
        }
    });
    let others = times.other_views(view);
    if others > 0 {
        ui.weak(format!("{others} frame(s) of other views (camera, lights, size or settings) are not compared"));
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
pub fn sweep_ui(
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
        if let Some(e) = &s.worker.error {
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
