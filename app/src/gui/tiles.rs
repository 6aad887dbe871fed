//! The window's tiles (egui_tiles): the 3D view and each panel drawn in its tile, tab titles, a hide button on
//! each tab bar; edits of the tiles mark the layout for saving.

use eframe::egui;
use egui_tiles::{TileId, Tiles, Tree};

use super::layout::Pane;
use super::panels;
use super::ShadowLabApp;

/// egui_tiles' view of the app: each pane's UI, tab titles, a hide button on each tab bar.
struct Panes<'a> {
    app: &'a mut ShadowLabApp,
    edited: bool,
    hide: Option<TileId>,
}

impl egui_tiles::Behavior<Pane> for Panes<'_> {
    fn tab_title_for_pane(&mut self, pane: &Pane) -> egui::WidgetText {
        pane.title().into()
    }

    fn pane_ui(&mut self, ui: &mut egui::Ui, _tile_id: TileId, pane: &mut Pane) -> egui_tiles::UiResponse {
        if *pane == Pane::View {
            self.app.viewport_ui(ui);
            return egui_tiles::UiResponse::None;
        }
        egui::Frame::NONE.inner_margin(egui::Margin::same(6)).fill(ui.visuals().panel_fill).show(ui, |ui| {
            ui.set_min_size(ui.available_size());
            if matches!(*pane, Pane::Timings | Pane::Maps) {
                // They fill the panel themselves (the timings' table scrolls, the maps zoom and pan).
                panels::pane_ui(&mut self.app.session, &mut self.app.views, &mut self.app.chrome, ui, *pane);
            } else {
                egui::ScrollArea::vertical().id_salt(pane.title()).auto_shrink([false, false]).show(ui, |ui| {
                    panels::pane_ui(&mut self.app.session, &mut self.app.views, &mut self.app.chrome, ui, *pane);
                });
            }
        });
        egui_tiles::UiResponse::None
    }

    fn top_bar_right_ui(
        &mut self,
        _tiles: &Tiles<Pane>,
        ui: &mut egui::Ui,
        _tile_id: TileId,
        tabs: &egui_tiles::Tabs,
        _scroll_offset: &mut f32,
    ) {
        if let Some(active) = tabs.active {
            if ui.small_button("hide").on_hover_text("Hide this panel (Panels menu shows it again)").clicked() {
                self.hide = Some(active);
            }
        }
    }

    fn simplification_options(&self) -> egui_tiles::SimplificationOptions {
        // The view has no tab bar of its own; panels keep theirs (they are dragged by their tabs).
        egui_tiles::SimplificationOptions { all_panes_must_have_tabs: false, ..Default::default() }
    }

    fn is_tab_bar_visible(&self, _tile_id: TileId, _tabs: &egui_tiles::Tabs) -> bool {
        true
    }

    fn gap_width(&self, _style: &egui::Style) -> f32 {
        3.0
    }

    fn min_size(&self) -> f32 {
        60.0
    }

    fn on_edit(&mut self, _edit_action: egui_tiles::EditAction) {
        self.edited = true;
    }
}

/// The tiles with the app's panes in them.
impl ShadowLabApp {
    pub(super) fn tiles_ui(&mut self, ui: &mut egui::Ui) {
        let mut tree = std::mem::replace(
            &mut self.chrome.layout.tree,
            Tree::empty(egui::Id::unique("shadowlab layout (drawing)")),
        );
        let mut panes = Panes { app: self, edited: false, hide: None };
        tree.ui(&mut panes, ui);
        let (edited, hide) = (panes.edited, panes.hide);
        if let Some(id) = hide {
            tree.set_visible(id, false);
        }
        self.chrome.layout.tree = tree;
        if edited || hide.is_some() {
            self.chrome.layout.mark_changed();
        }
        self.chrome.layout.focus_pending();
    }
}
