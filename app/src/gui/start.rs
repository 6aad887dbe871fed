//! Starting the app in a known state (`--app-technique`, `--app-param`, `--app-against`, ...), for a class or
//! a script, and the one line it prints at exit with `--quit-after`: the view, both configurations and the
//! last metrics.

use std::collections::BTreeMap;

use anyhow::{anyhow, bail, Result};
use shadowlab_core::technique::registry::{INDIRECT_REGISTRY, REGISTRY};
use shadowlab_core::technique::ParamValue;

use super::document::ViewMode;
use super::state::StartState;
use super::ShadowLabApp;

/// The view mode a `--app-view` names.
pub fn parse_view(text: &str) -> Result<ViewMode> {
    Ok(match text {
        "single" => ViewMode::Single,
        "side" => ViewMode::SideBySide,
        "split" => ViewMode::Split,
        "difference" => ViewMode::Difference,
        other => bail!("unknown view '{other}' (single, side, split, difference)"),
    })
}

fn view_name(mode: ViewMode) -> &'static str {
    match mode {
        ViewMode::Single => "single",
        ViewMode::SideBySide => "side",
        ViewMode::Split => "split",
        ViewMode::Difference => "difference",
    }
}

/// `key=value` pairs, parsed by the parameters' own kinds.
fn parse_params(
    owner: &str,
    specs: &[shadowlab_core::technique::Param],
    pairs: &[String],
) -> Result<BTreeMap<String, ParamValue>> {
    let mut out = BTreeMap::new();
    for pair in pairs {
        let (k, v) = pair.split_once('=').ok_or_else(|| anyhow!("'{pair}': expected KEY=VALUE"))?;
        let (k, v) = (k.trim(), v.trim());
        let spec = specs.iter().find(|s| s.key == k).ok_or_else(|| {
            anyhow!(
                "'{owner}' has no parameter '{k}' (it has: {})",
                specs.iter().map(|s| s.key).collect::<Vec<_>>().join(", ")
            )
        })?;
        out.insert(k.to_string(), spec.kind.parse(k, v)?);
    }
    Ok(out)
}

/// `LAYER` or `LAYER=on|off`: the layer's name and whether it is shown.
fn overlay_spec(spec: &str) -> (&str, bool) {
    let (name, shown) = match spec.rsplit_once('=').map(|(name, state)| (name, state.trim())) {
        Some((name, "on" | "true")) => (name, true),
        Some((name, "off" | "false")) => (name, false),
        _ => (spec, true),
    };
    (name.trim(), shown)
}

/// The layer named `name` (case aside) among the layers offered.
fn offered_layer(name: &str, layers: &[String]) -> Result<String> {
    match layers.iter().find(|l| l.eq_ignore_ascii_case(name)) {
        Some(layer) => Ok(layer.clone()),
        None if layers.is_empty() => bail!("the technique offers no overlay layers"),
        None => bail!("no such layer (the technique offers: {})", layers.join(", ")),
    }
}

impl ShadowLabApp {
    /// Apply the start options; each bad one is reported (on stderr and in the window) and skipped.
    pub fn apply_start(&mut self, start: StartState) {
        let report = |app: &mut ShadowLabApp, e: anyhow::Error| {
            eprintln!("error: {e:#}");
            app.error(format!("{e:#}"));
        };
        if let Some(t) = &start.technique {
            match REGISTRY.iter().find(|e| e.key == t) {
                Some(e) => self.session.technique = e.key.to_string(),
                None => report(
                    self,
                    anyhow!("unknown technique '{t}' (choose one of: {})", shadowlab_core::technique::registry::keys()),
                ),
            }
        }
        if let Some(k) = &start.indirect {
            if INDIRECT_REGISTRY.iter().any(|e| e.key == k) {
                if let Some(source) = shadowlab_core::technique::registry::preferred_vpl_source(k) {
                    self.session.indirect.vpl.source = source;
                }
                self.session.indirect.technique = Some(k.clone());
            } else {
                report(
                    self,
                    anyhow!(
                        "unknown indirect technique '{k}' (choose one of: {})",
                        shadowlab_core::technique::registry::indirect_keys()
                    ),
                );
            }
        }
        if let Some(v) = &start.view {
            match parse_view(v) {
                Ok(mode) => self.session.view.mode = mode,
                Err(e) => report(self, e),
            }
        }
        if let Some(a) = &start.against {
            if shadowlab_core::technique::registry::targets().any(|e| e.key == a) {
                self.session.view.compare_against = a.clone();
            } else {
                let known: Vec<&str> = shadowlab_core::technique::registry::targets().map(|e| e.key).collect();
                report(self, anyhow!("--app-against '{a}': choose one of {}", known.join(", ")));
            }
        }
        if let Some(k) = &start.against_indirect {
            if k == "none" || INDIRECT_REGISTRY.iter().any(|e| e.key == k) {
                self.session.view.against_indirect = Some(k.clone());
            } else {
                report(
                    self,
                    anyhow!(
                        "--app-against-indirect '{k}': choose none or one of {}",
                        shadowlab_core::technique::registry::indirect_keys()
                    ),
                );
            }
        }
        if let Some(c) = &start.component {
            match shadowlab_core::renderer::Component::parse(c) {
                Some(component) => self.session.indirect.component = component,
                None => report(
                    self,
                    anyhow!("--app-component '{c}': choose {}", shadowlab_core::renderer::Component::NAMES.join(", ")),
                ),
            }
        }
        let direct = [
            (self.session.technique.clone(), &start.params, "--app-param"),
            (self.session.view.compare_against.clone(), &start.against_params, "--app-against-param"),
        ];
        for (key, pairs, option) in direct {
            if pairs.is_empty() {
                continue;
            }
            let specs = match self.views.gpu.as_mut().map(|g| g.main.technique(&key)) {
                Some(Ok(t)) => t.params(),
                _ => continue,
            };
            match parse_params(&key, &specs, pairs) {
                Ok(values) => self.session.params.entry(key).or_default().extend(values),
                Err(e) => report(self, anyhow!("{option}: {e:#}")),
            }
        }
        if !start.indirect_params.is_empty() {
            let key = self.session.indirect.technique.clone();
            let specs = match (&key, self.views.gpu.as_mut()) {
                (Some(k), Some(g)) => g.main.indirect_technique(k).map(|t| t.borrow().params()).ok(),
                _ => None,
            };
            match (key, specs) {
                (Some(key), Some(specs)) => match parse_params(&key, &specs, &start.indirect_params) {
                    Ok(values) => self.session.indirect.params.entry(key).or_default().extend(values),
                    Err(e) => report(self, anyhow!("--app-indirect-param: {e:#}")),
                },
                _ => report(self, anyhow!("--app-indirect-param needs --app-indirect")),
            }
        }
        if let Some(spec) = &start.explain {
            if let Err(e) = self.open_explain_step(spec) {
                report(self, anyhow!("--app-explain '{spec}': {e:#}"));
            }
        }
        // Shown at once; checked against the layers offered once a frame has completed (INSM offers its mesh
        // layers only when it has a mesh).
        for spec in &start.overlays {
            let (name, shown) = overlay_spec(spec);
            self.session.view.overlays.insert(name.to_string(), shown);
            self.lifecycle.start_overlays.push((spec.clone(), name.to_string()));
        }
    }

    /// Once the view has completed a frame: each `--app-overlay` layer not offered is a message, and one named in
    /// another case takes the offered layer's name.
    pub(super) fn check_start_overlays(&mut self) {
        let framed = self.views.gpu.as_ref().is_some_and(|g| g.main.last_report.is_some());
        if self.lifecycle.start_overlays.is_empty() || !framed {
            return;
        }
        let layers: Vec<String> = self.overlay_layers().into_iter().map(|(name, _)| name).collect();
        for (spec, name) in std::mem::take(&mut self.lifecycle.start_overlays) {
            match offered_layer(&name, &layers) {
                Ok(layer) if layer == name => {}
                Ok(layer) => {
                    let shown = self.session.view.overlays.remove(&name).unwrap_or(true);
                    self.session.view.overlays.insert(layer, shown);
                }
                Err(e) => {
                    self.session.view.overlays.remove(&name);
                    eprintln!("error: --app-overlay '{spec}': {e:#}");
                    self.error(format!("--app-overlay '{spec}': {e:#}"));
                }
            }
        }
    }

    /// Choose Explain step `[KEY:]N` as the panel does (its layers, maps and parameters), with the panel in front.
    fn open_explain_step(&mut self, spec: &str) -> Result<()> {
        let (key, n) = match spec.rsplit_once(':') {
            Some((k, n)) => (k.trim().to_string(), n),
            None => (self.session.technique.clone(), spec),
        };
        let n: usize = n.trim().parse().map_err(|_| anyhow!("the step is a number from 1"))?;
        let indirect = self.session.indirect.technique.as_deref() == Some(key.as_str());
        if key != self.session.technique && !indirect {
            let within = match &self.session.indirect.technique {
                Some(k) => format!("'{}' or '{k}'", self.session.technique),
                None => format!("'{}'", self.session.technique),
            };
            bail!("'{key}' is not the technique or the indirect technique (choose {within})");
        }
        let gpu = self.views.gpu.as_mut().ok_or_else(|| anyhow!("no GPU"))?;
        let steps = if indirect {
            gpu.main.indirect_technique(&key)?.borrow().explain()
        } else {
            gpu.main.technique(&key)?.explain()
        };
        if n == 0 || n > steps.len() {
            bail!("'{key}' has {} Explain steps (1 to {})", steps.len(), steps.len());
        }
        super::panels::explain::show_explain_step(
            &mut self.session,
            &mut self.views,
            &mut self.chrome,
            &key,
            &steps,
            n - 1,
        );
        self.chrome.explain.step = Some((key, n - 1));
        // The Explain panel in front now; a step about maps asked for the Shadow maps panel too (another group).
        self.chrome.layout.focus(super::layout::Pane::Explain);
        Ok(())
    }

    /// The line printed at exit (`--quit-after`): the scene and view, both configurations as they rendered
    /// last, and the last difference's metrics (or why there are none).
    pub fn exit_line(&self) -> String {
        let s = &self.session;
        let params = |p: Option<&BTreeMap<String, ParamValue>>| -> String {
            p.map(|p| p.iter().map(|(k, v)| format!(" {k}={v}")).collect::<String>()).unwrap_or_default()
        };
        let indirect = |key: Option<&str>| match key {
            Some(k) => format!(" indirect={k}{}", params(s.indirect.params.get(k))),
            None => String::new(),
        };
        let component = match s.indirect.component {
            shadowlab_core::renderer::Component::Total => String::new(),
            c => format!(" component={}", c.name()),
        };
        let mut line = format!(
            "shadowlab: scene={} view={}{component} | technique={}{}{} | against={}{}{}",
            s.scene.name,
            view_name(s.view.mode),
            s.technique,
            params(s.params.get(&s.technique)),
            indirect(s.indirect.technique.as_deref()),
            s.view.compare_against,
            params(s.params.get(&s.view.compare_against)),
            indirect(s.against_indirect_key()),
        );
        let last_ms = self.views.gpu.as_ref().and_then(|g| g.main.last_report.as_ref()).map(|r| r.frame_ms());
        if let Some(ms) = last_ms {
            line += &format!(" | frame_ms={ms:.2}");
        }
        match (&self.views.difference, s.view.mode) {
            (Some(d), ViewMode::Difference) => {
                let m = &d.metrics;
                line += &format!(" | rmse={:.6} mse={:.3e}", m.rmse, m.mse);
                if let Some(p) = m.psnr_db {
                    line += &format!(" psnr_db={p:.2} peak={:.3}", m.peak_luminance);
                }
                if let Some(f) = m.flip_mean {
                    line += &format!(" flip={f:.4}");
                }
                if let Some(e) = m.shadow_intensity_error {
                    line += &format!(" shadow_error={e:.5}");
                }
            }
            (None, ViewMode::Difference) => line += " | metrics: none yet (the difference was not complete)",
            _ => line += " | metrics: none (only the difference view computes them: --app-view difference)",
        }
        line
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_overlay_is_named_as_offered_with_an_optional_state() {
        assert_eq!(overlay_spec("INSM mesh (wireframe)"), ("INSM mesh (wireframe)", true));
        assert_eq!(overlay_spec("light ranges=off"), ("light ranges", false));
        assert_eq!(overlay_spec("lights = on"), ("lights", true));
        assert_eq!(overlay_spec("a=b"), ("a=b", true), "a state other than on/off is part of the name");
        let layers = vec!["INSM mesh (wireframe)".to_string(), "light ranges".to_string()];
        assert_eq!(offered_layer("insm MESH (wireframe)", &layers).unwrap(), "INSM mesh (wireframe)");
        let e = offered_layer("INSM mesh", &layers).unwrap_err().to_string();
        assert!(e.contains("no such layer") && e.contains("INSM mesh (wireframe), light ranges"), "{e}");
        assert!(offered_layer("x", &[]).unwrap_err().to_string().contains("offers no overlay layers"));
    }
}
