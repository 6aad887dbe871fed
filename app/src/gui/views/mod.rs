//! The views: the renderers of the 3D view and of its comparison target on eframe's device, and what is
//! derived from their frames: the overlays drawn over them and their legends, the technique's per-pixel ID
//! map, the difference image and its metrics, the metered exposure, frame timings, the hover tooltips; and
//! the parameter sweep run with their settings.

pub mod difference;
pub mod difference_data;
pub mod hover;
pub mod paint;
pub mod view;

use shadowlab_core::technique::registry::REFERENCE;
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{anyhow, Result};
use eframe::{egui, egui_wgpu};
use glam::Vec3;
use shadowlab_core::scene::PointLight;
use shadowlab_core::services::overlay::OverlayStyle;
use shadowlab_core::technique::{Glyph, LegendEntry, Overlay, OverlayLayer, OverlayUpdate, ParamValue, Technique};
use shadowlab_core::timing::{PassTime, StepWait};
use shadowlab_core::{AutoExposure, GpuContext, RenderSettings};

use super::document::ViewMode;
use super::session::Session;
use super::sweep;
use difference_data::{Difference, PendingDifference};
use view::{preview_technique, FrameInputs, StepSizer, View};

/// GPU state, created from eframe's render state.
pub struct Gpu {
    pub ctx: GpuContext,
    pub render_state: egui_wgpu::RenderState,
    pub main: View,
    pub reference: View,
    pub sizer: StepSizer,
}

/// A technique's per-pixel ID map: (frame key, layer name, ids, render size).
pub type PixelIds = (u64, &'static str, Arc<Vec<u32>>, (u32, u32));

/// The two renderers (the technique's view and its comparison target) and what the app derived from their
/// last frames.
pub struct Views {
    /// None until eframe's device is there, and again once it was lost.
    pub gpu: Option<Gpu>,
    /// Timings of completed frames: (seconds since start, frame ms in the report's clock, passes).
    pub timings: VecDeque<(f64, f64, Vec<PassTime>)>,
    /// When the app started: the time axis of `timings`.
    started: Instant,
    /// Where the 3D view was laid out last UI frame.
    pub last_viewport_rect: Option<egui::Rect>,
    pub difference: Option<Difference>,
    /// The difference being computed on a worker thread (metrics with FLIP cost seconds on large images).
    pending_difference: Option<PendingDifference>,
    /// False in tests (`Startup::synchronous`): the difference is then computed on the UI thread.
    background_work: bool,
    pub sweep: Option<sweep::Sweep>,
    /// The trade-off of the Sweep panel, in progress or finished.
    pub tradeoff: Option<super::tradeoff_run::Tradeoff>,
    /// The last complete frame of every configuration measured this session, for the speedup table.
    pub session_times: super::session_times::SessionTimes,
    /// The technique's per-pixel ID map for a converged frame.
    pub pixel_ids: Option<PixelIds>,
    /// The legends of the overlay layers drawn in the last UI frame: (layer name, entries).
    pub legends: Vec<(String, Vec<LegendEntry>)>,
    /// The 3D view's size in physical pixels (captures render at its render resolution).
    pub last_view_pixels: egui::Vec2,
    /// The last complete frame's auto-exposure: (scale, log-average luminance), shown in the Render panel.
    pub metered_exposure: Option<(f32, f32)>,
    /// Milliseconds of this UI frame spent in [`Views::render`] (our rendering: the steps submitted and waited
    /// for, readbacks), for the UI frame's breakdown (the app's `FrameBreakdown`, `gui/mod.rs`).
    pub ui_frame_render_ms: f64,
}

impl Views {
    /// No GPU yet; `background_work` false computes the difference on the UI thread (deterministic tests).
    pub fn new(started: Instant, background_work: bool) -> Views {
        Views {
            gpu: None,
            timings: VecDeque::new(),
            started,
            last_viewport_rect: None,
            difference: None,
            pending_difference: None,
            background_work,
            sweep: None,
            tradeoff: None,
            session_times: Default::default(),
            pixel_ids: None,
            legends: Vec::new(),
            last_view_pixels: egui::vec2(640.0, 360.0),
            metered_exposure: None,
            ui_frame_render_ms: 0.0,
        }
    }

    /// Both renderers on a new scene (the comparison view shares the main view's scene buffers).
    pub fn set_scene(&mut self, scene: &shadowlab_core::scene::Scene) {
        if let Some(gpu) = &mut self.gpu {
            gpu.main.set_scene(scene);
            gpu.reference.share_scene_of(&gpu.main);
        }
    }

    /// Start a trade-off of `tries` on the current view against its comparison target (technique, parameters,
    /// indirect technique), with the user's parameters under the tried ones.
    pub fn start_tradeoff(
        &mut self,
        session: &Session,
        tries: Vec<crate::tradeoff::TrySpec>,
        metric: crate::tradeoff::Metric,
        goal: crate::tradeoff::Goal,
    ) -> Result<()> {
        let gpu = self.gpu.as_ref().ok_or_else(|| anyhow!("no GPU"))?;
        let base_params = tries.iter().map(|t| (t.technique.clone(), session.param_strings(&t.technique))).collect();
        let against = session.view.compare_against.clone();
        let against_indirect = session.indirect_choice_of(session.against_indirect_key());
        self.tradeoff = Some(super::tradeoff_run::Tradeoff::start(super::tradeoff_run::TradeoffJob {
            gpu: gpu.ctx.clone(),
            scene: gpu.main.renderer.shared_scene(),
            layouts: gpu.main.renderer.shared_layouts(),
            lights: session.animated_lights(),
            suns: session.suns.clone(),
            camera: session.camera.camera(),
            settings: gpu.main.renderer.settings().clone(),
            tries,
            base_params,
            against_params: session.param_strings(&against),
            against,
            against_indirect,
            metric,
            goal,
        }));
        Ok(())
    }

    /// The first view of a model without a camera (`first_view::first_view`, through the scene's BVH, built
    /// once and shared with the tracers): inside an enclosed interior, from the open side of a room open on one
    /// side; None for an object (keep the framing) or without a GPU.
    pub fn first_view(&self, bounds: &shadowlab_core::math::Aabb, fov_y: f32) -> Option<shadowlab_core::scene::Camera> {
        let gpu = self.gpu.as_ref()?;
        let (bvh, _) = gpu.main.renderer.shared_scene().bvh(&gpu.ctx);
        shadowlab_core::accel::first_view::first_view(&bvh.cpu, bounds, fov_y)
    }

    /// "Frame scene": the model's first view ([`Views::first_view`]: inside an enclosed interior, from the open
    /// side of a room open on one side), else the bounds framed from outside.
    pub fn frame_scene(&self, session: &mut Session) {
        let bounds = session.scene.bounds;
        match self.first_view(&bounds, session.camera.fov_y) {
            Some(camera) => {
                session.camera = super::camera::CameraController::from_camera(&camera, &bounds);
            }
            None => session.camera.frame(&bounds),
        }
    }

    /// Alt+click: hand the clicked pixel to the indirect technique's probe (the parameters it names), so its
    /// probe overlay shows that pixel; the app knows no technique, only `probe_params`. Returns the status line.
    pub fn probe_at(&mut self, session: &mut Session, pos: egui::Pos2, rect: egui::Rect) -> Option<String> {
        let (Some(key), Some(gpu)) = (session.indirect.technique.clone(), &mut self.gpu) else { return None };
        let size = gpu.main.size;
        let Ok(technique) = gpu.main.indirect_technique(&key) else { return None };
        let (px, py) = technique.borrow().probe_params()?;
        let u = ((pos.x - rect.min.x) / rect.width().max(1.0)).clamp(0.0, 1.0);
        let v = ((pos.y - rect.min.y) / rect.height().max(1.0)).clamp(0.0, 1.0);
        let x = ((u * size.0 as f32) as i64).min(size.0 as i64 - 1);
        let y = ((v * size.1 as f32) as i64).min(size.1 as i64 - 1);
        let params = session.indirect.params.entry(key).or_default();
        params.insert(px.to_string(), ParamValue::Int(x));
        params.insert(py.to_string(), ParamValue::Int(y));
        Some(format!("probe at pixel ({x}, {y})"))
    }

    /// The overlay layers of the indirect technique, from the instance the main view renders with.
    fn indirect_overlay_layers(
        &mut self,
        session: &Session,
        lights: &[PointLight],
    ) -> Vec<shadowlab_core::technique::OverlayLayer> {
        let (Some(key), Some(gpu)) = (session.indirect.technique.clone(), &mut self.gpu) else { return Vec::new() };
        match gpu.main.indirect_technique(&key) {
            Ok(t) => t.borrow().overlays(lights),
            Err(_) => Vec::new(),
        }
    }

    /// The overlay primitives of the current technique that the user has switched on, plus the selection, and
    /// the legend of each of those layers (as the layers describe themselves through their technique).
    /// `updates` (direct, indirect): what the preview's overlay stages made of each technique's layers while
    /// dragging; a layer that still shows the last complete frame, or was made at the preview's size, says so
    /// in its legend.
    fn overlay_primitives(
        &mut self,
        session: &Session,
        lights: &[PointLight],
        updates: &(OverlayUpdate, OverlayUpdate),
    ) -> (Vec<Overlay>, Vec<(String, Vec<LegendEntry>)>) {
        let mut out = Vec::new();
        let mut legends = Vec::new();
        let overlays = &session.view.overlays;
        let is_on = |layer: &OverlayLayer| *overlays.get(layer.name).unwrap_or(&layer.visible_by_default);
        let mut take =
            |technique: &dyn Technique, layers: Vec<OverlayLayer>, out: &mut Vec<Overlay>, update: &OverlayUpdate| {
                for layer in layers.into_iter().filter(|l| is_on(l)) {
                    let mut legend = technique.overlay_legend(&layer);
                    if update.is_stale(layer.name) {
                        legend.push(LegendEntry::new(Glyph::Rect, [0.7, 0.7, 0.7, 1.0], STALE_NOTE));
                    } else if let Some(note) = update.note(layer.name) {
                        legend.push(LegendEntry::new(Glyph::Rect, [0.7, 0.7, 0.7, 1.0], note));
                    }
                    legends.push((layer.name.to_string(), legend));
                    out.extend(layer.primitives);
                }
            };
        let shown = |name: &str, default: bool| *overlays.get(name).unwrap_or(&default);
        let Some(gpu) = &mut self.gpu else { return (out, Vec::new()) };
        if let Ok(technique) = gpu.main.technique(&session.technique) {
            // Only the shown layers are built (INSM's meshes cost a readback).
            let layers = technique.overlays_shown(lights, &shown);
            take(technique.as_ref(), layers, &mut out, &updates.0);
        }
        // The reference's light ranges over any technique that has no such layer of its own.
        let own_ranges = gpu
            .main
            .technique(&session.technique)
            .is_ok_and(|t| t.overlays_shown(&[], &|_, _| false).iter().any(|l| l.name == "light ranges"));
        if session.technique != REFERENCE && !own_ranges {
            if let Ok(reference) = gpu.main.technique(REFERENCE) {
                let layers = reference.overlays(lights).into_iter().filter(|l| l.name == "light ranges").collect();
                // Drawn from the lights themselves: always live.
                take(reference.as_ref(), layers, &mut out, &OverlayUpdate::live());
            }
        }
        if let Some(key) = session.indirect.technique.clone() {
            if let Ok(t) = gpu.main.indirect_technique(&key) {
                let t = t.borrow();
                let layers = t.overlays_shown(lights, &shown);
                take(t.as_ref(), layers, &mut out, &updates.1);
            }
        }
        // A selected light's group (its cluster): the primitives at its members stay, the rest is dimmed.
        if let Some(group) =
            session.selected.and_then(|i| self.light_details(session, i)).map(|d| d.group).filter(|g| g.len() > 1)
        {
            let at: Vec<Vec3> = group.iter().filter_map(|&m| lights.get(m)).map(|l| l.position).collect();
            let member = |p: &Vec3| at.contains(p);
            for o in &mut out {
                let keep = match o {
                    Overlay::Point { position, .. } => member(position),
                    Overlay::Line { from, to, .. } => member(from) || member(to),
                    Overlay::Sphere { center, .. } => member(center),
                    _ => true,
                };
                if !keep {
                    if let Overlay::Point { color, .. } | Overlay::Line { color, .. } | Overlay::Sphere { color, .. } =
                        o
                    {
                        color[3] *= 0.2;
                    }
                }
            }
        }
        // The suns (after the dimming: no light's group holds them): the renderer's service shades them for
        // every technique, so the layer is the app's.
        if !session.suns.is_empty() {
            let layer = shadowlab_core::technique::sun_overlays(&session.suns, &session.scene.bounds);
            if is_on(&layer) {
                let legend = shadowlab_core::technique::light_layer_legend(&layer).unwrap_or_default();
                legends.push((layer.name.to_string(), legend));
                out.extend(layer.primitives);
            }
        }
        if let Some(l) = session.selected.and_then(|i| lights.get(i)) {
            out.push(Overlay::Sphere { center: l.position, radius: l.range, color: [1.0, 1.0, 0.3, 0.6] });
            out.push(Overlay::Point { position: l.position, color: [1.0, 1.0, 0.2, 1.0], radius_px: 8.0 });
        }
        (out, legends)
    }

    /// What the current technique made of light `index` in its last frame (its cluster, say).
    pub fn light_details(
        &mut self,
        session: &Session,
        index: usize,
    ) -> Option<shadowlab_core::technique::LightDetails> {
        let gpu = self.gpu.as_mut()?;
        gpu.main.technique(&session.technique).ok()?.light_details(index)
    }

    /// The per-light map resolutions of the technique and its comparison target when both have maps and they
    /// differ (each technique has its own default): (technique's, target's). The user's value where set, else
    /// the technique's own.
    pub fn unequal_map_resolutions(&mut self, session: &Session) -> Option<(i64, i64)> {
        let gpu = self.gpu.as_mut()?;
        let resolution = |view: &mut View, key: &str| -> Option<i64> {
            let user = session.params.get(key).and_then(|p| p.get("shadow_res")).cloned();
            let own = view.technique(key).ok()?.params().into_iter().find(|p| p.key == "shadow_res")?.value;
            match user.unwrap_or(own) {
                ParamValue::Int(r) => Some(r),
                _ => None,
            }
        };
        let technique = resolution(&mut gpu.main, &session.technique)?;
        let target = resolution(&mut gpu.reference, &session.view.compare_against)?;
        (technique != target).then_some((technique, target))
    }

    /// Names of the overlay layers the current technique offers, with their state.
    pub fn overlay_layers(&mut self, session: &Session) -> Vec<(String, bool)> {
        let Some(gpu) = &mut self.gpu else { return Vec::new() };
        let mut names: Vec<(String, bool)> = Vec::new();
        // Only the names are needed: asking with no lights builds (almost) no primitives, every UI frame; one spot
        // light, when the scene has one, brings the layers that only spot lights have.
        let probe: Vec<PointLight> = session.lights.iter().find(|l| l.spot.is_some()).copied().into_iter().collect();
        if let Ok(t) = gpu.main.technique(&session.technique) {
            let layers = t.overlays_shown(&probe, &|_, _| false);
            names.extend(layers.into_iter().map(|l| (l.name.to_string(), l.visible_by_default)));
        }
        // The reference's light ranges, offered over a technique that has no such layer of its own (listed once).
        if session.technique != REFERENCE && names.iter().all(|(n, _)| n != "light ranges") {
            names.push(("light ranges".into(), false));
        }
        if !session.suns.is_empty() {
            names.push((shadowlab_core::technique::SUNS_LAYER.into(), true));
        }
        if let Ok(t) = gpu.main.technique(&session.technique) {
            if let Some((name, _)) = t.pixel_ids(&[]) {
                names.push((name.to_string(), false));
            }
        }
        names.extend(
            self.indirect_overlay_layers(session, &[]).into_iter().map(|l| (l.name.to_string(), l.visible_by_default)),
        );
        names.into_iter().map(|(n, d)| (n.clone(), *session.view.overlays.get(&n).unwrap_or(&d))).collect()
    }

    pub fn render(
        &mut self,
        session: &Session,
        size: egui::Vec2,
        pixels_per_point: f32,
        interacting: bool,
    ) -> Result<()> {
        let lights = session.animated_lights();
        let camera = session.camera.camera();
        // While the user drags, the preview renders the image, and the technique's overlay stages run again
        // for the new lights and camera (LightCluster's clustering), so its overlays follow in this UI frame.
        let updates = match (&mut self.gpu, interacting) {
            (Some(gpu), true) => {
                let indirect = session.indirect.technique.as_deref();
                gpu.main.update_overlays(&session.technique, indirect, &camera, &lights)?
            }
            _ => (OverlayUpdate::live(), OverlayUpdate::live()),
        };
        let (mut overlays, legends) = self.overlay_primitives(session, &lights, &updates);
        self.legends = legends;
        let technique = if interacting { preview_technique().to_string() } else { session.technique.clone() };
        let two = session.view.mode != ViewMode::Single;
        let per_view = if session.view.mode == ViewMode::SideBySide { egui::vec2(size.x * 0.5, size.y) } else { size };
        let settings = session.render_settings(per_view, interacting);
        // Dot sizes are in screen points; the render target may be smaller or larger than the view.
        let render_pixels_per_point = pixels_per_point * settings.width as f32 / per_view.x.max(1.0);
        for o in &mut overlays {
            if let Overlay::Point { radius_px, .. } = o {
                *radius_px *= render_pixels_per_point;
            }
        }
        // Lines about 2 points wide on screen, whatever the render resolution; occluded parts faded.
        let style = OverlayStyle { line_width_px: (2.0 * render_pixels_per_point).max(1.0), occluded_alpha: 0.25 };
        let params = session.params.get(&technique).cloned().unwrap_or_default();
        // The comparison view gets the target's indirect technique: the view's own (the same light on both
        // sides) unless the user chose another (VALs against one map per VPL, say).
        let (indirect, indirect_params) = session.indirect_inputs(interacting);
        let (against_indirect, against_indirect_params) = session.against_indirect_inputs(interacting);
        let x_ray = session.view.x_ray;
        let Some(gpu) = &mut self.gpu else { return Ok(()) };
        let main_inputs = FrameInputs {
            camera,
            lights: lights.clone(),
            technique,
            params,
            indirect,
            indirect_params,
            settings: settings.clone(),
            suns: session.suns.clone(),
        };
        // While the user drags, keep the UI fluid: the preview gets a third of the budget.
        let budget = if interacting { gpu.sizer.budget_ms() / 3.0 } else { gpu.sizer.budget_ms() };
        // Progressive steps are polled, never waited for; the moving preview's and a synchronous run's are
        // waited for, so their image is whole in the UI frame that asked for it.
        let wait = if interacting || !budget.is_finite() || !deferred_steps_allowed() {
            StepWait::Blocking
        } else {
            StepWait::Deferred
        };
        gpu.main.set_step_wait(wait);
        gpu.reference.set_step_wait(wait);
        let (spent, steps) = gpu.main.update(&gpu.render_state, &main_inputs, budget, gpu.sizer.max_lights_per_step)?;
        // The comparison view shows the technique's exposure (held, never metered itself), so the same radiance
        // looks the same on both sides of a split or side-by-side view.
        if gpu.main.new_report && settings.auto_exposure == AutoExposure::Meter {
            if let Some((scale, average)) = gpu.main.renderer.auto_exposure()? {
                gpu.reference.renderer.set_held_exposure(scale, average)?;
                self.metered_exposure = Some((scale, average));
            }
        }
        // The technique's per-pixel ID map, once per converged frame, when its layer is on.
        if gpu.main.is_converged() {
            let key = gpu.main.frame_key();
            let technique_key = main_inputs.technique.clone();
            let view_overlays = &session.view.overlays;
            let technique = gpu.main.technique(&technique_key)?;
            let layer = technique.pixel_ids(&[]).map(|(name, _)| name);
            let wanted = layer.is_some_and(|name| *view_overlays.get(name).unwrap_or(&false));
            if wanted && self.pixel_ids.as_ref().is_none_or(|(k, ..)| *k != key) {
                let positions = gpu.main.renderer.read_world_positions(&camera)?;
                let technique = gpu.main.technique(&technique_key)?;
                if let Some((name, ids)) = technique.pixel_ids(&positions) {
                    self.pixel_ids = Some((key, name, Arc::new(ids), gpu.main.size));
                }
            }
            if let Some((k, name, ids, (w, h))) = &self.pixel_ids {
                if *k == key && wanted && layer == Some(*name) {
                    overlays.insert(0, Overlay::IdMap { width: *w, height: *h, ids: ids.clone(), alpha: 0.45 });
                }
            }
        }
        gpu.main.renderer.set_overlay_style(style);
        gpu.reference.renderer.set_overlay_style(style);
        gpu.main.overlays(&camera, &overlays, x_ray)?;
        let mut total_spent = spent;
        let mut total_steps = steps;
        if two {
            let against = session.view.compare_against.clone();
            let reference_technique = if interacting { preview_technique() } else { against.as_str() };
            let reference_inputs = FrameInputs {
                camera,
                lights,
                technique: reference_technique.into(),
                params: session.params.get(reference_technique).cloned().unwrap_or_default(),
                indirect: against_indirect,
                indirect_params: against_indirect_params,
                suns: session.suns.clone(),
                settings: RenderSettings {
                    auto_exposure: match settings.auto_exposure {
                        AutoExposure::Off => AutoExposure::Off,
                        _ => AutoExposure::Hold,
                    },
                    ..settings
                },
            };
            // The reference gets what is left of the budget once the technique's image is complete.
            let left = if gpu.main.is_converged() { budget - spent } else { budget * 0.25 };
            let (s, n) = gpu.reference.update(
                &gpu.render_state,
                &reference_inputs,
                left.max(1.0),
                gpu.sizer.max_lights_per_step,
            )?;
            gpu.reference.overlays(&camera, &overlays, x_ray)?;
            total_spent += s;
            total_steps += n;
        }
        gpu.sizer.observe(total_spent, total_steps);
        let scene_name = &session.scene.name;
        if std::mem::take(&mut gpu.reference.new_report) {
            if let Some(r) = gpu.reference.last_report.as_ref().filter(|r| r.technique != preview_technique()) {
                self.session_times.record(scene_name, r);
            }
        }
        if std::mem::take(&mut gpu.main.new_report) {
            if let Some(r) = gpu.main.last_report.as_ref().filter(|r| r.technique != preview_technique()) {
                self.session_times.record(scene_name, r);
            }
            if let Some(r) = &gpu.main.last_report {
                let t = self.started.elapsed().as_secs_f64();
                if r.technique != preview_technique() {
                    self.timings.push_back((t, r.frame_ms(), r.passes.clone()));
                    while self.timings.front().is_some_and(|(t0, _, _)| t - t0 > 60.0) {
                        self.timings.pop_front();
                    }
                }
            }
        }
        Ok(())
    }

    /// Start a sweep of `key` over `values` for the current technique, view and lights.
    pub fn start_sweep(&mut self, session: &Session, key: &str, values: Vec<ParamValue>) -> Result<()> {
        let gpu = self.gpu.as_ref().ok_or_else(|| anyhow!("no GPU"))?;
        let settings = gpu.main.renderer.settings().clone();
        let fixed: Vec<(String, ParamValue)> = session
            .params
            .get(&session.technique)
            .map(|p| p.iter().filter(|(k, _)| k.as_str() != key).map(|(k, v)| (k.clone(), v.clone())).collect())
            .unwrap_or_default();
        self.sweep = Some(sweep::Sweep::start(sweep::SweepJob {
            gpu: gpu.ctx.clone(),
            scene: gpu.main.renderer.shared_scene(),
            layouts: gpu.main.renderer.shared_layouts(),
            lights: session.animated_lights(),
            suns: session.suns.clone(),
            camera: session.camera.camera(),
            settings,
            technique: session.technique.clone(),
            fixed,
            indirect: session.indirect.technique.clone().map(|k| {
                let params = session.indirect.params.get(&k).cloned().unwrap_or_default().into_iter().collect();
                (k, params)
            }),
            against: session.view.compare_against.clone(),
            against_params: session
                .params
                .get(&session.view.compare_against)
                .map(|p| p.iter().map(|(k, v)| (k.clone(), v.clone())).collect())
                .unwrap_or_default(),
            against_indirect: match session.against_indirect_inputs(false) {
                (Some(k), params) => Some((k, params.into_iter().collect())),
                (None, _) => None,
            },
            key: key.to_string(),
            values,
        }));
        Ok(())
    }
}

/// The legend line of a layer whose technique's overlays do not follow a moving light or camera.
pub const STALE_NOTE: &str = "while moving: as of the last complete frame (follows on release)";

/// False when `SHADOWLAB_STEP_WAIT=blocking`: every progressive step is waited for, as before steps were
/// polled (for A/B measurements of the UI's frame rate while a frame renders).
fn deferred_steps_allowed() -> bool {
    static ALLOWED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ALLOWED.get_or_init(|| std::env::var("SHADOWLAB_STEP_WAIT").map_or(true, |v| v.trim() != "blocking"))
}
