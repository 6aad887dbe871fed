//! The menu bar: File (open, recent, save, screenshots, the figure, image sequences), Scene, Edit (undo, redo,
//! duplicate, delete), View (the view mode, X-ray overlays), Panels.

use eframe::egui;

use super::document::ViewMode;
use super::ShadowLabApp;
use crate::sequence::Motion;

impl ShadowLabApp {
    pub(super) fn menu_bar(&mut self, ui: &mut egui::Ui) {
        egui::Panel::top("menu").show(ui, |ui| {
            egui::MenuBar::new().ui(ui, |ui| {
                ui.menu_button("File", |ui| {
                    if ui.button("Open scene or model…").clicked() {
                        let dialogs = self.chrome.file_dialogs;
                        if let Some(path) = dialogs
                            .then(|| {
                                rfd::FileDialog::new()
                                    .add_filter("ShadowLab scenes and models", &["ron", "obj", "gltf", "glb"])
                                    .pick_file()
                            })
                            .flatten()
                        {
                            self.open_path(&path);
                        }
                        ui.close();
                    }
                    ui.menu_button("Open recent", |ui| {
                        if self.chrome.recent.is_empty() {
                            ui.label("(none)");
                        }
                        for path in self.chrome.recent.clone() {
                            if ui.button(path.display().to_string()).clicked() {
                                self.open_path(&path);
                                ui.close();
                            }
                        }
                    });
                    ui.separator();
                    if ui.button("Save scene file…").clicked() {
                        let dialogs = self.chrome.file_dialogs;
                        let path = dialogs
                            .then(|| rfd::FileDialog::new().add_filter("ShadowLab scene", &["ron"]).save_file())
                            .flatten();
                        if let Some(path) = path {
                            match self.save_scene_file(&path) {
                                Ok(()) => self.toast(format!("saved {}", path.display())),
                                Err(e) => self.error(format!("save failed, nothing was overwritten: {e:#}")),
                            }
                        }
                        ui.close();
                    }
                    if let Some(path) = self.session.scene_file.clone() {
                        if ui
                            .button(format!("Save to {}", path.file_name().unwrap_or_default().to_string_lossy()))
                            .clicked()
                        {
                            match self.save_scene_file(&path) {
                                Ok(()) => self.toast(format!("saved {}", path.display())),
                                Err(e) => self.error(format!("save failed, nothing was overwritten: {e:#}")),
                            }
                            ui.close();
                        }
                    }
                    ui.separator();
                    if ui.button("Screenshot of the 3D view (F12)").clicked() {
                        match self.save_view_screenshot() {
                            Ok(p) => self.toast(format!("saved {}", p.display())),
                            Err(e) => self.error(format!("screenshot failed: {e:#}")),
                        }
                        ui.close();
                    }
                    if ui.button("Screenshot of the window (Shift+F12)").clicked() {
                        self.request_window_screenshot(ui.ctx());
                        ui.close();
                    }
                    if ui
                        .button("Export figure: view, reference, difference (Ctrl+F12)")
                        .on_hover_text("One PNG with captions; both images are rendered completely first")
                        .clicked()
                    {
                        self.export_figure();
                        ui.close();
                    }
                    let animated = self.session.animation.period_secs().is_some();
                    let sequences = [
                        (
                            Motion::Orbit,
                            "Orbit sequence (PNGs + GIF)",
                            "A full orbit around the target, each frame complete",
                            true,
                        ),
                        (
                            Motion::Lights,
                            "Light animation sequence (PNGs + GIF)",
                            "One period of the light animation (Lights panel), each frame complete",
                            animated,
                        ),
                    ];
                    for (motion, text, hover, enabled) in sequences {
                        let button = ui
                            .add_enabled(enabled, egui::Button::new(text))
                            .on_hover_text(hover)
                            .on_disabled_hover_text("Switch a light animation on in the Lights panel first");
                        if button.clicked() {
                            match self.save_sequence(motion, self.chrome.orbit_frames) {
                                Ok(s) => self.toast(format!("saved {} frames and {}", s.frames.len(), s.gif.display())),
                                Err(e) => self.error(format!("image sequence failed: {e:#}")),
                            }
                            ui.close();
                        }
                    }
                    ui.horizontal(|ui| {
                        let label = ui.label("frames per sequence");
                        ui.add(egui::DragValue::new(&mut self.chrome.orbit_frames).range(2..=720))
                            .labelled_by(label.id);
                        ui.checkbox(&mut self.chrome.sequence_overlays, "with the overlays");
                    });
                });
                ui.menu_button("Scene", |ui| {
                    for name in shadowlab_core::scene::builtin::NAMES {
                        if ui.button(*name).clicked() {
                            self.load_builtin(name);
                            ui.close();
                        }
                    }
                });
                ui.menu_button("Edit", |ui| {
                    if ui.add_enabled(self.session.history.can_undo(), egui::Button::new("Undo (Ctrl+Z)")).clicked() {
                        self.session.undo();
                    }
                    if ui
                        .add_enabled(self.session.history.can_redo(), egui::Button::new("Redo (Ctrl+Shift+Z)"))
                        .clicked()
                    {
                        self.session.redo();
                    }
                    ui.separator();
                    if ui
                        .add_enabled(self.session.selected.is_some(), egui::Button::new("Duplicate light (Ctrl+D)"))
                        .clicked()
                    {
                        self.session.duplicate_selected();
                    }
                    if ui
                        .add_enabled(self.session.selected.is_some(), egui::Button::new("Delete light (Del)"))
                        .clicked()
                    {
                        self.session.delete_selected();
                    }
                });
                ui.menu_button("View", |ui| {
                    ui.radio_value(&mut self.session.view.mode, ViewMode::Single, "Single view");
                    ui.radio_value(
                        &mut self.session.view.mode,
                        ViewMode::SideBySide,
                        "Side by side with the reference",
                    );
                    ui.radio_value(&mut self.session.view.mode, ViewMode::Split, "Split view with the reference");
                    ui.radio_value(
                        &mut self.session.view.mode,
                        ViewMode::Difference,
                        "Difference against the reference",
                    );
                    ui.separator();
                    ui.checkbox(&mut self.session.view.x_ray, "X-ray overlays");
                });
                ui.menu_button("Panels", |ui| super::layout::panels_menu(&mut self.chrome.layout, ui));
            });
        });
    }
}
