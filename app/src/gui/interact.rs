//! The 3D view's input: the gizmo (moving a light or a technique camera), picking (a click selects a light or
//! a technique camera, Ctrl+click adds a light on a surface, Alt+click probes a pixel), the context menu, the
//! camera's mouse and keyboard input, and the tooltips under the pointer; the views render and paint in the
//! middle of it.

use std::time::Instant;

use eframe::egui;
use glam::Vec3;

use super::camera::{CameraInput, CameraMode};
use super::document::ViewMode;
use super::gizmo::{self, Projection};
use super::legend;
use super::session::{Animation, DragTarget};
use super::state::GizmoDrag;
use super::ShadowLabApp;

impl ShadowLabApp {
    /// Camera input from the view's response and the keyboard.
    fn camera_input(&self, ctx: &egui::Context, response: &egui::Response, gizmo_active: bool) -> CameraInput {
        let dt = ctx.input(|i| i.stable_dt).min(0.1);
        let mut input = CameraInput { dt_secs: dt, ..Default::default() };
        if !gizmo_active && response.dragged_by(egui::PointerButton::Primary) {
            let d = response.drag_delta();
            input.rotate = glam::Vec2::new(d.x, d.y);
        }
        if response.dragged_by(egui::PointerButton::Middle) || response.dragged_by(egui::PointerButton::Secondary) {
            let d = response.drag_delta();
            input.pan = glam::Vec2::new(d.x, d.y);
        }
        if response.hovered() {
            input.zoom = ctx.input(|i| i.smooth_scroll_delta.y);
        }
        if self.session.camera.mode == CameraMode::Fly && !ctx.egui_wants_keyboard_input() {
            ctx.input(|i| {
                let axis = |pos: egui::Key, neg: egui::Key| (i.key_down(pos) as i32 - i.key_down(neg) as i32) as f32;
                input.movement = Vec3::new(
                    axis(egui::Key::W, egui::Key::S),
                    axis(egui::Key::D, egui::Key::A),
                    axis(egui::Key::E, egui::Key::Q),
                );
                input.fast = i.modifiers.shift;
            });
        }
        input
    }

    /// The central 3D view: image(s), gizmo, picking, camera.
    pub(super) fn viewport_ui(&mut self, ui: &mut egui::Ui) {
        if let Some(recovery) = &self.recovery {
            // No device to render with: the view says why and where the state went, until the window closes.
            let message = recovery.message.clone();
            ui.centered_and_justified(|ui| {
                ui.label(egui::RichText::new(message).color(ui.visuals().error_fg_color).size(16.0));
            });
            return;
        }
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
        self.views.last_viewport_rect = Some(rect);
        let projection_rect = if self.session.view.mode == ViewMode::SideBySide {
            egui::Rect::from_min_size(rect.min, egui::vec2(rect.width() * 0.5, rect.height()))
        } else {
            rect
        };
        let camera = self.session.camera.camera();
        let projection = Projection::new(&camera, projection_rect);

        // Gizmo and picking: a light, or a camera of the technique (INSM's viewpoints).
        let pointer = response.interact_pointer_pos().or(response.hover_pos());
        let selected_target = self.session.gizmo_target();
        let selected_pos = selected_target.as_ref().and_then(|t| self.session.target_position(t));
        if response.drag_started_by(egui::PointerButton::Primary) {
            if let (Some(pos), Some(at), Some(target)) = (pointer, selected_pos, selected_target.clone()) {
                if let Some(handle) = gizmo::hit_handle(&projection, at, pos) {
                    if matches!(target, DragTarget::Light(_)) {
                        self.session.begin_edit();
                    }
                    self.interaction.drag =
                        Some(GizmoDrag { handle, target, start: at, accumulated: egui::Vec2::ZERO });
                }
            }
        }
        if let Some(drag) = self.interaction.drag.clone() {
            if response.dragged_by(egui::PointerButton::Primary) {
                let accumulated = drag.accumulated + response.drag_delta();
                let delta = gizmo::drag_delta(&projection, drag.start, drag.handle, accumulated);
                self.session.set_target_position(&drag.target, drag.start + delta);
                if let Some(d) = &mut self.interaction.drag {
                    d.accumulated = accumulated;
                }
                self.interaction.last_interaction = Some(Instant::now());
            }
            if response.drag_stopped() || !ui.input(|i| i.pointer.primary_down()) {
                self.interaction.drag = None;
            }
        }
        let gizmo_active = self.interaction.drag.is_some();
        // An Explain step's maps fill the view: a click or Esc returns to the image (and does nothing else).
        let map_in_view = self.chrome.explain.map_in_view;
        if map_in_view && (response.clicked() || ui.input(|i| i.key_pressed(egui::Key::Escape))) {
            self.chrome.explain.map_in_view = false;
        } else if response.clicked() {
            if let Some(pos) = response.interact_pointer_pos() {
                let ctrl = ui.input(|i| i.modifiers.command);
                let alt = ui.input(|i| i.modifiers.alt);
                if alt {
                    if let Some(status) = self.views.probe_at(&mut self.session, pos, projection.rect) {
                        self.chrome.status = status;
                    }
                } else if ctrl {
                    let (o, d) = projection.ray(pos);
                    if let Some((t, n)) = gizmo::pick_surface(&self.session.scene, o, d) {
                        self.session.add_light_at(o + d * t, n);
                    }
                } else if selected_pos.and_then(|at| gizmo::hit_handle(&projection, at, pos)).is_none() {
                    self.session.selected = gizmo::pick_light(&projection, &self.session.animated_lights(), pos, 12.0);
                    self.session.selected_camera = None;
                    if self.session.selected.is_none() {
                        self.session.selected_camera = self.session.technique_cameras().and_then(|(key, cameras)| {
                            gizmo::pick_point(&projection, cameras.iter().map(|c| c.position), pos, 12.0)
                                .map(|i| (key, i))
                        });
                    }
                }
            }
        }
        response.context_menu(|ui| {
            if ui.button("Add light here").clicked() {
                if let Some(pos) = ui.ctx().input(|i| i.pointer.interact_pos()) {
                    let (o, d) = projection.ray(pos);
                    if let Some((t, n)) = gizmo::pick_surface(&self.session.scene, o, d) {
                        self.session.add_light_at(o + d * t, n);
                    }
                }
                ui.close();
            }
        });

        let mut input = self.camera_input(ui.ctx(), &response, gizmo_active);
        if self.interaction.orbit_demo {
            // About 40 points of drag per second, like a slow orbit by hand.
            input.rotate.x += 40.0 * input.dt_secs;
            ui.ctx().request_repaint();
        }
        if self.session.camera.update(&input) {
            self.interaction.last_interaction = Some(Instant::now());
        }
        let interacting = gizmo_active
            || input.is_active()
            || self.interaction.last_interaction.is_some_and(|t| t.elapsed().as_secs_f32() < 0.25);

        let ppp = ui.ctx().pixels_per_point();
        self.views.last_view_pixels = rect.size() * ppp;
        // Frames an Explain step set up (its parameter values) are not the user's configurations: the session
        // table leaves them out.
        self.views.session_times.recording = self.chrome.explain.step.is_none();
        let render_start = Instant::now();
        if let Err(e) = self.views.render(&self.session, rect.size() * ppp, ppp, interacting) {
            self.chrome.status = format!("render error: {e:#}");
        }
        self.views.ui_frame_render_ms += render_start.elapsed().as_secs_f64() * 1000.0;
        if self.session.view.mode == ViewMode::Difference {
            if let Err(e) = self.views.update_difference(&self.session, ui.ctx()) {
                self.chrome.status = format!("difference: {e:#}");
            }
        }

        // Show the images.
        let painter = ui.painter_at(rect);
        self.views.paint(ui, &painter, rect, &mut self.session);
        if let Some(at) = self.session.gizmo_target().and_then(|t| self.session.target_position(&t)) {
            let hover = pointer.and_then(|p| gizmo::hit_handle(&projection, at, p));
            gizmo::paint(&painter, &projection, at, self.interaction.drag.as_ref().map(|d| d.handle).or(hover));
        }
        if self.session.view.legend {
            legend::paint_in_view(&painter, rect, &self.views.legends);
        }
        if self.chrome.explain.map_in_view {
            self.paint_map_in_view(&painter, rect);
        }
        // A light under the pointer: its details in a tooltip (not over an Explain step's maps).
        if self.interaction.drag.is_none() && !interacting && !self.chrome.explain.map_in_view {
            if let Some(pos) = response.hover_pos() {
                let lines = match gizmo::pick_light(&projection, &self.session.animated_lights(), pos, 10.0) {
                    Some(i) => self.light_tooltip(i),
                    None => {
                        let camera = self.camera_tooltip(&projection, pos);
                        if camera.is_empty() {
                            self.overlay_tooltip(&projection, pos)
                        } else {
                            camera
                        }
                    }
                };
                if !lines.is_empty() {
                    response.clone().on_hover_ui_at_pointer(|ui| {
                        for l in &lines {
                            ui.label(l);
                        }
                    });
                }
            }
        }
        if interacting || self.session.animation != Animation::Off {
            ui.ctx().request_repaint();
        }
    }

    /// The Explain step's maps alone over the 3D view: the Shadow maps panel's image, fitted, with what it is.
    fn paint_map_in_view(&self, painter: &egui::Painter, rect: egui::Rect) {
        painter.rect_filled(rect, 0.0, egui::Color32::from_rgb(16, 18, 28));
        let caption = match self.chrome.inspector.on_screen(self.session.lights.len()) {
            Some((texture, [w, h], what)) => {
                let area = rect.shrink(24.0);
                let scale = (area.width() / w.max(1) as f32).min(area.height() / h.max(1) as f32);
                let image = egui::Rect::from_center_size(area.center(), egui::vec2(w as f32, h as f32) * scale);
                let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
                painter.image(texture, image, uv, egui::Color32::WHITE);
                if self.chrome.inspector.rsm_shown {
                    let marks = self.chrome.inspector.rsm.marks();
                    let point = |x: u32, y: u32| image.min + egui::vec2(x as f32 + 0.5, y as f32 + 0.5) * scale;
                    super::rsm_view::ring(painter, &marks, point, scale);
                }
                format!("{what} (the Shadow maps panel's image; click the view or press Esc for the scene)")
            }
            None => "the step's maps appear here once the frame has rendered them (click the view or Esc)".into(),
        };
        let font = egui::FontId::proportional(14.0);
        painter.text(
            rect.left_top() + egui::vec2(8.0, 4.0),
            egui::Align2::LEFT_TOP,
            caption,
            font,
            egui::Color32::WHITE,
        );
    }
}
