//! The Explain panel: the steps of the technique's paper; choosing one shows it in the view.

use eframe::egui;

use crate::gui::chrome::Chrome;
use crate::gui::layout::Pane;
use crate::gui::session::Session;
use crate::gui::views::Views;

/// The steps of the current technique's paper, as the technique declares them; choosing one switches the
/// overlay layers (and the shadow-map panel) that show it.
pub fn explain_ui(session: &mut Session, views: &mut Views, chrome: &mut Chrome, ui: &mut egui::Ui) {
    ui.heading("Explain");
    ui.checkbox(&mut chrome.explain.maps_in_view, "a step's maps alone in the view")
        .on_hover_text("A step about maps shows them large in the 3D view; click the view or press Esc to return");
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
    chrome.explain.map_in_view = step.shows_shadow_maps && chrome.explain.maps_in_view;
    if step.shows_shadow_maps {
        chrome.inspector.rsm_shown = step.maps == shadowlab_core::technique::RSM_MAPS;
        if !chrome.inspector.rsm_shown {
            let source = crate::gui::inspector::MapSource { indirect, set: step.maps };
            // The step's parameters may make the set first in the next frame (INSM's meshes' views).
            let key = views.gpu.as_ref().map_or(0, |g| g.main.frame_key());
            (chrome.inspector.source, chrome.inspector.requested) = (source, Some((source, key)));
        }
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
