//! The Trade-off section of the Sweep panel: the ticked techniques, each over a range of one of its numeric
//! parameters, rendered on a worker against the view's comparison target; error against time per frame (one
//! colour per technique, the Pareto front, the target's time), a hovered point's configuration, a click loads
//! it into the view; with a budget, "Tune" sets the pick.

use std::collections::BTreeMap;

use eframe::egui;
use egui_plot::{Line, MarkerShape, Plot, PlotPoint, PlotPoints, Points, VLine};
use shadowlab_core::technique::registry::REGISTRY;
use shadowlab_core::technique::ParamKind;

use crate::gui::session::Session;
use crate::gui::toasts::Toasts;
use crate::gui::tradeoff_input::{ParamRange, TradeoffInput, TryInput};
use crate::gui::views::Views;
use crate::tradeoff::{self, Goal, Metric, TrySpec};

const COLORS: [egui::Color32; 6] = [
    egui::Color32::from_rgb(31, 119, 180),
    egui::Color32::from_rgb(214, 39, 40),
    egui::Color32::from_rgb(44, 160, 44),
    egui::Color32::from_rgb(148, 103, 189),
    egui::Color32::from_rgb(255, 127, 14),
    egui::Color32::from_rgb(23, 190, 207),
];

pub fn tradeoff_ui(
    session: &mut Session,
    views: &mut Views,
    input: &mut TradeoffInput,
    toasts: &mut Toasts,
    ui: &mut egui::Ui,
) {
    ui.heading("Trade-off");
    ui.label(format!(
        "Error against time per frame on this view, against {} (Compare sets it): the ticked techniques, each over \
         a range of one parameter.",
        crate::measure::technique_pair(&session.view.compare_against, session.against_indirect_key())
    ));
    let Some(gpu) = &mut views.gpu else { return };
    // The parameters of the ticked techniques only, from the main view's instances (asking every registered
    // technique would create each one's pipelines just to list them).
    let mut specs = BTreeMap::new();
    for entry in REGISTRY {
        let default_on = entry.key == session.technique;
        let t = input
            .tries
            .entry(entry.key.to_string())
            .or_insert_with(|| TryInput { on: default_on, ..Default::default() });
        if t.on {
            if let Ok(technique) = gpu.main.technique(entry.key) {
                specs.insert(entry.key, technique.params());
            }
        }
    }
    for entry in REGISTRY {
        let none = Vec::new();
        let params = specs.get(entry.key).unwrap_or(&none);
        let t = input.tries.get_mut(entry.key).expect("inserted above");
        ui.horizontal(|ui| {
            ui.checkbox(&mut t.on, entry.key).on_hover_text(format!("{} ({})", entry.label, entry.role.name()));
            if t.on && t.params.is_empty() {
                ui.weak("as set");
            }
        });
        if !t.on {
            continue;
        }
        let mut remove = None;
        for (i, range) in t.params.iter_mut().enumerate() {
            ui.horizontal(|ui| {
                ui.add_space(18.0);
                let before = range.key.clone();
                let label = params.iter().find(|p| p.key == range.key).map_or(range.key.as_str(), |p| p.label);
                egui::ComboBox::from_id_salt(("tradeoff param", entry.key, i)).selected_text(label).show_ui(ui, |ui| {
                    for p in params.iter().filter(|p| !matches!(p.kind, ParamKind::Cameras { .. })) {
                        ui.selectable_value(&mut range.key, p.key.to_string(), p.label);
                    }
                });
                let Some(p) = params.iter().find(|p| p.key == range.key) else { return };
                if range.key != before {
                    *range = ParamRange::of(p.key, &p.kind);
                }
                match &p.kind {
                    ParamKind::Float { .. } | ParamKind::Int { .. } => {
                        ui.add(egui::DragValue::new(&mut range.from).speed(0.01).prefix("from "));
                        ui.add(egui::DragValue::new(&mut range.to).speed(0.01).prefix("to "));
                        ui.add(egui::DragValue::new(&mut range.count).range(2..=32).prefix("values "));
                    }
                    ParamKind::Choice(options) => {
                        ui.weak(options.join(", "));
                    }
                    ParamKind::Bool => {
                        ui.weak("off, on");
                    }
                    ParamKind::Cameras { .. } => {}
                }
                if ui.small_button("x").on_hover_text("Try this technique without varying this parameter").clicked() {
                    remove = Some(i);
                }
            });
        }
        if let Some(i) = remove {
            t.params.remove(i);
        }
        let unused = params
            .iter()
            .find(|p| !matches!(p.kind, ParamKind::Cameras { .. }) && !t.params.iter().any(|r| r.key == p.key));
        if let Some(p) = unused {
            ui.horizontal(|ui| {
                ui.add_space(18.0);
                if ui
                    .small_button("+ parameter")
                    .on_hover_text("Vary one more parameter: every combination of the values is tried")
                    .clicked()
                {
                    t.params.push(ParamRange::of(p.key, &p.kind));
                }
            });
        }
    }
    ui.horizontal(|ui| {
        ui.label("error");
        for m in Metric::ALL {
            ui.selectable_value(&mut input.metric, m, m.name());
        }
    });
    ui.horizontal(|ui| {
        ui.checkbox(&mut input.use_budget, "budget").on_hover_text(
            "The lowest error within this time per frame: the swept parameter is bisected (time and error taken as \
             monotone in it) instead of rendering every value",
        );
        ui.add_enabled(input.use_budget, egui::DragValue::new(&mut input.budget_ms).range(0.01..=1e6).suffix(" ms"));
        if ui
            .checkbox(&mut input.use_max_error, "or within error")
            .on_hover_text("The fastest configuration whose error is at most this, by the same bisection")
            .changed()
            && input.use_max_error
        {
            input.use_budget = false;
        }
        ui.add_enabled(input.use_max_error, egui::DragValue::new(&mut input.max_error).range(0.0..=1e3).speed(0.001));
    });
    if input.use_budget {
        input.use_max_error = false;
    }
    let running = views.tradeoff.as_mut().is_some_and(|t| t.poll());
    let (mut run, mut cancel) = (false, false);
    ui.horizontal(|ui| {
        run = !running && ui.button("Run trade-off").clicked();
        cancel = running && ui.button("Cancel").clicked();
    });
    if run {
        let mut tries = Vec::new();
        for entry in REGISTRY {
            let Some(t) = input.tries.get(entry.key).filter(|t| t.on) else { continue };
            let known = specs.get(entry.key);
            let params: Vec<(String, Vec<String>)> = t
                .params
                .iter()
                .filter_map(|r| {
                    let p = known?.iter().find(|p| p.key == r.key)?;
                    Some((r.key.clone(), vec![r.values(&p.kind)]))
                })
                .collect();
            let text = std::iter::once(entry.key.to_string())
                .chain(params.iter().map(|(k, v)| format!("{k}={}", v[0])))
                .collect::<Vec<_>>()
                .join(" ");
            let indirect = session.indirect.technique.as_deref().unwrap_or("none");
            match TrySpec::parse(&text, entry.key, indirect) {
                Ok(mut spec) => {
                    // The view's indirect parameters, as the user set them.
                    if let Some(k) = &session.indirect.technique {
                        for (pk, v) in session.indirect.params.get(k).into_iter().flatten() {
                            spec.params.push((format!("{}{pk}", tradeoff::INDIRECT_PREFIX), vec![v.to_string()]));
                        }
                    }
                    tries.push(spec)
                }
                Err(e) => toasts.error(format!("trade-off: {e:#}")),
            }
        }
        if tries.is_empty() {
            toasts.error("trade-off: tick at least one technique");
        } else if let Err(e) = views.start_tradeoff(session, tries, input.metric, goal(input)) {
            toasts.error(format!("trade-off: {e:#}"));
        }
    }
    if cancel {
        if let Some(t) = &views.tradeoff {
            t.cancel();
        }
    }
    let Some(t) = &views.tradeoff else { return };
    if running {
        ui.add(egui::ProgressBar::new(t.rows.len() as f32 / t.expected.max(1) as f32).text(format!(
            "{} of about {} configurations",
            t.rows.len(),
            t.expected
        )));
        ui.ctx().request_repaint_after(std::time::Duration::from_millis(200));
    }
    if let Some(e) = &t.worker.error {
        ui.colored_label(egui::Color32::LIGHT_RED, e);
    }
    let points = t.points();
    let pick = if t.worker.finished { t.pick() } else { None };
    let clock = t.clock();
    // The x axis: the time per frame, or a work count of the rows (the front is drawn in the axes shown).
    let work_keys = t.work_keys();
    if input.x_axis.as_ref().is_some_and(|k| !work_keys.contains(k)) {
        input.x_axis = None;
    }
    let time_label = format!("ms per frame ({})", clock.name());
    ui.horizontal(|ui| {
        ui.label("x axis");
        egui::ComboBox::from_id_salt("tradeoff x axis")
            .selected_text(input.x_axis.clone().unwrap_or_else(|| time_label.clone()))
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut input.x_axis, None, time_label.as_str());
                for k in &work_keys {
                    ui.selectable_value(&mut input.x_axis, Some(k.clone()), k.as_str());
                }
            });
    });
    let shown: Vec<tradeoff::Point> = match &input.x_axis {
        None => points.clone(),
        Some(k) => t
            .rows
            .iter()
            .zip(&points)
            .map(|(r, p)| tradeoff::Point { ms: r.work.get(k).copied().unwrap_or(0.0), error: p.error })
            .collect(),
    };
    let front = tradeoff::pareto(&shown);
    let mut clicked = None;
    // As wide as the pane shows (a wide row above must not push the plot past its right edge).
    let width = (ui.clip_rect().right() - ui.cursor().left()).min(ui.available_width()).max(120.0);
    // One plot per x axis (each with its own bounds); the wheel scrolls the pane, not the plot (drag pans it).
    let response = Plot::new(("tradeoff", input.x_axis.clone()))
        .allow_scroll(false)
        .width(width)
        .height(180.0)
        .x_axis_label(input.x_axis.clone().unwrap_or(time_label))
        .y_axis_label(t.metric.name())
        .include_x(0.0)
        .include_y(0.0)
        .show(ui, |plot| {
            if let (Some(target), None) = (t.target, &input.x_axis) {
                plot.vline(VLine::new("target", target.ms_in(clock)).color(egui::Color32::GRAY));
            }
            let mut line: Vec<[f64; 2]> =
                shown.iter().zip(&front).filter(|(_, f)| **f).map(|(p, _)| [p.ms, p.error]).collect();
            line.sort_by(|a, b| a[0].total_cmp(&b[0]));
            if line.len() > 1 {
                plot.line(Line::new("Pareto front", PlotPoints::from(line)).color(egui::Color32::WHITE));
            }
            for (i, spec) in t.tries.iter().enumerate() {
                let pts: Vec<[f64; 2]> =
                    t.rows.iter().zip(&shown).filter(|(r, _)| r.try_index == i).map(|(_, p)| [p.ms, p.error]).collect();
                let color = COLORS[i % COLORS.len()];
                plot.points(Points::new(spec.label(), PlotPoints::from(pts)).radius(4.0).color(color));
            }
            if let Some(i) = pick {
                let p = [shown[i].ms, shown[i].error];
                let ring = Points::new("pick", PlotPoints::from(vec![p])).shape(MarkerShape::Circle).filled(false);
                plot.points(ring.radius(9.0).color(egui::Color32::YELLOW));
            }
            // The configuration nearest the pointer (in screen space), for the tooltip and a click.
            let pointer = plot.response().hover_pos();
            let nearest = pointer.and_then(|at| {
                shown
                    .iter()
                    .enumerate()
                    .map(|(i, p)| (i, plot.screen_from_plot(PlotPoint::new(p.ms, p.error)).distance(at)))
                    .filter(|(_, d)| *d < 12.0)
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .map(|(i, _)| i)
            });
            if plot.response().clicked() {
                clicked = nearest;
            }
            let drawn = shown.iter().map(|p| plot.screen_from_plot(PlotPoint::new(p.ms, p.error))).collect();
            (nearest, drawn)
        });
    let (nearest, drawn) = response.inner;
    input.drawn = drawn;
    if let Some(i) = nearest {
        let r = &t.rows[i];
        let work = input.x_axis.as_ref().map(|k| format!(", {k} {}", shown[i].ms)).unwrap_or_default();
        let text = format!(
            "{} {}\n{:.2} ms ({}){work}, {} {:.5}{}",
            t.tries[r.try_index].label(),
            tradeoff::setting_text(&r.setting),
            points[i].ms,
            clock.name(),
            t.metric.name(),
            r.error,
            if front[i] { "\non the Pareto front (in the axes shown)" } else { "" }
        );
        response.response.on_hover_text_at_pointer(format!("{text}\nclick: load this configuration"));
    }
    match (t.goal, t.worker.finished, pick) {
        (Goal::All, ..) | (_, false, _) => {}
        (_, true, Some(i)) => {
            let r = &t.rows[i];
            ui.label(format!(
                "pick: {} {} at {:.2} ms, {} {:.5} ({} configurations rendered)",
                t.tries[r.try_index].label(),
                tradeoff::setting_text(&r.setting),
                points[i].ms,
                t.metric.name(),
                r.error,
                t.rows.len()
            ));
            if ui.button("Tune: use the pick").clicked() {
                clicked = Some(i);
            }
        }
        (_, true, None) => {
            ui.label(match t.goal {
                Goal::MaxError(e) => format!("nothing is within {} {e}", t.metric.name()),
                _ => "nothing fits the budget".to_string(),
            });
        }
    }
    if let Some(i) = clicked {
        let (try_index, setting) = (t.rows[i].try_index, t.rows[i].setting.clone());
        let spec = t.tries[try_index].clone();
        load_configuration(session, views, &spec, &setting, toasts);
    }
}

fn goal(input: &TradeoffInput) -> Goal {
    if input.use_budget {
        Goal::BudgetMs(input.budget_ms)
    } else if input.use_max_error {
        Goal::MaxError(input.max_error)
    } else {
        Goal::All
    }
}

/// Make `spec` with `setting` the view's technique and parameters.
pub fn load_configuration(
    session: &mut Session,
    views: &mut Views,
    spec: &TrySpec,
    setting: &tradeoff::Setting,
    toasts: &mut Toasts,
) {
    let Some(gpu) = &mut views.gpu else { return };
    let Ok(technique) = gpu.main.technique(&spec.technique) else { return };
    let params = technique.params();
    session.technique = spec.technique.clone();
    for (key, text) in setting.iter().filter(|(k, _)| !k.starts_with(tradeoff::INDIRECT_PREFIX)) {
        match params.iter().find(|p| p.key == key.as_str()).map(|p| p.kind.parse(key, text)) {
            Some(Ok(value)) => {
                session.params.entry(spec.technique.clone()).or_default().insert(key.clone(), value);
            }
            Some(Err(e)) => toasts.error(format!("{e}")),
            None => toasts.error(format!("'{}' has no parameter '{key}'", spec.technique)),
        }
    }
    toasts.say(format!("loaded {} {}", spec.label(), tradeoff::setting_text(setting)));
}
