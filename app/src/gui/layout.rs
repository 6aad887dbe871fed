//! The window's layout: the 3D view and the panels as docked tiles (egui_tiles). Panels are tabs that can be
//! dragged to another place, resized, hidden (each tab bar's "hide" button, or the Panels menu) and shown again
//! (Panels menu); "Full view" (Tab or F11) hides every panel and the menu bar. The default gives the view about
//! 70 % of the window. The layout is saved in the app's data folder (`layout.ron`) when it changes and loaded
//! at start; a missing or broken file gives the default layout.

use std::path::{Path, PathBuf};

use anyhow::Result;
use eframe::egui;
use egui_tiles::{Container, Linear, LinearDir, Tile, TileId, Tiles, Tree};
use serde::{Deserialize, Serialize};

/// What a tile shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Pane {
    View,
    Technique,
    Render,
    Overlays,
    Lights,
    Scene,
    Sweep,
    Timings,
    Maps,
    Explain,
}

impl Pane {
    pub const ALL: [Pane; 10] = [
        Pane::View,
        Pane::Technique,
        Pane::Render,
        Pane::Overlays,
        Pane::Lights,
        Pane::Scene,
        Pane::Sweep,
        Pane::Timings,
        Pane::Maps,
        Pane::Explain,
    ];

    pub fn title(self) -> &'static str {
        match self {
            Pane::View => "3D view",
            Pane::Technique => "Shadows",
            Pane::Render => "Render",
            Pane::Overlays => "Overlays",
            Pane::Lights => "Lights",
            Pane::Scene => "Scene",
            Pane::Sweep => "Sweep",
            Pane::Timings => "Timings",
            Pane::Maps => "Shadow maps",
            Pane::Explain => "Explain",
        }
    }
}

/// Share of the window's width the left column of panels gets by default.
const LEFT_COLUMN_SHARE: f32 = 0.3;
/// Version 2 added the shadow-map inspector, 3 the Explain panel; older files give the default layout.
const LAYOUT_VERSION: u32 = 3;

#[derive(Serialize, Deserialize)]
struct LayoutFile {
    version: u32,
    tree: Tree<Pane>,
    full_view: bool,
}

/// The tiles, the full-view flag, and whether they changed since they were saved.
pub struct Layout {
    pub tree: Tree<Pane>,
    /// Every panel (and the menu bar) hidden: the view fills the window.
    pub full_view: bool,
    dirty: bool,
    /// A panel to bring forward once the tiles are drawn (a pane's UI cannot change the tree it is drawn in).
    pending_focus: Option<Pane>,
}

impl Layout {
    /// The default: a column of tabbed panels on the left (technique, render, overlays, lights, explain above; timings,
    /// shadow maps, sweep, scene below), the 3D view on the right.
    pub fn default_tree() -> Tree<Pane> {
        let mut tiles = Tiles::default();
        let view = tiles.insert_pane(Pane::View);
        let top: Vec<TileId> = [Pane::Technique, Pane::Render, Pane::Overlays, Pane::Lights, Pane::Explain]
            .into_iter()
            .map(|p| tiles.insert_pane(p))
            .collect();
        let bottom: Vec<TileId> =
            [Pane::Timings, Pane::Maps, Pane::Sweep, Pane::Scene].into_iter().map(|p| tiles.insert_pane(p)).collect();
        let top = tiles.insert_tab_tile(top);
        let bottom = tiles.insert_tab_tile(bottom);
        let left = tiles.insert_container(Linear::new_binary(LinearDir::Vertical, [top, bottom], 0.6));
        let root = tiles.insert_container(Linear::new_binary(LinearDir::Horizontal, [left, view], LEFT_COLUMN_SHARE));
        Tree::new(egui::Id::unique("shadowlab layout"), root, tiles)
    }

    pub fn new() -> Layout {
        Layout { tree: Self::default_tree(), full_view: false, dirty: false, pending_focus: None }
    }

    fn path(dir: &Path) -> PathBuf {
        dir.join("layout.ron")
    }

    /// The saved layout, or the default when there is none or it cannot be used (with a warning in the log).
    pub fn load(dir: &Path) -> Layout {
        let path = Self::path(dir);
        let Ok(text) = std::fs::read_to_string(&path) else { return Layout::new() };
        match ron::from_str::<LayoutFile>(&text) {
            Ok(file) if file.version == LAYOUT_VERSION && Self::is_complete(&file.tree) => {
                Layout { tree: file.tree, full_view: file.full_view, dirty: false, pending_focus: None }
            }
            Ok(_) => {
                log::warn!("{}: not a layout of this version; using the default", path.display());
                Layout::new()
            }
            Err(e) => {
                log::warn!("{}: {e}; using the default layout", path.display());
                Layout::new()
            }
        }
    }

    /// Every pane exactly once, reachable from the root, and the view shown.
    fn is_complete(tree: &Tree<Pane>) -> bool {
        let Some(root) = tree.root() else { return false };
        let mut found = Vec::new();
        let mut stack = vec![root];
        while let Some(id) = stack.pop() {
            match tree.tiles.get(id) {
                Some(Tile::Pane(p)) => found.push(*p),
                Some(Tile::Container(c)) => stack.extend(c.children().copied()),
                None => return false,
            }
        }
        let view_shown = tree.tiles.find_pane(&Pane::View).is_some_and(|id| tree.tiles.is_visible(id));
        view_shown && Pane::ALL.iter().all(|p| found.iter().filter(|f| *f == p).count() == 1)
    }

    pub fn save(&mut self, dir: &Path) -> Result<()> {
        let file = LayoutFile { version: LAYOUT_VERSION, tree: self.tree.clone(), full_view: self.full_view };
        std::fs::create_dir_all(dir)?;
        crate::files::write_atomic(&Self::path(dir), ron::to_string(&file)?.as_bytes())?;
        self.dirty = false;
        Ok(())
    }

    /// Save when something changed and no drag (of a tab or a divider) is in progress.
    pub fn save_if_changed(&mut self, dir: &Path, ctx: &egui::Context) {
        if self.dirty && !ctx.input(|i| i.pointer.any_down()) {
            if let Err(e) = self.save(dir) {
                log::warn!("cannot save the layout: {e:#}");
                self.dirty = false;
            }
        }
    }

    pub fn mark_changed(&mut self) {
        self.dirty = true;
    }

    pub fn reset(&mut self) {
        self.tree = Self::default_tree();
        self.full_view = false;
        self.dirty = true;
    }

    pub fn toggle_full_view(&mut self) {
        self.full_view = !self.full_view;
        self.dirty = true;
    }

    pub fn is_shown(&self, pane: Pane) -> bool {
        !self.full_view && self.tree.tiles.find_pane(&pane).is_some_and(|id| self.tree.is_visible(id))
    }

    /// Whether the pane is drawn this frame: shown, and the active tab of its tab group.
    pub fn is_on_screen(&self, pane: Pane) -> bool {
        if pane == Pane::View {
            return true;
        }
        !self.full_view
            && self.tree.tiles.find_pane(&pane).is_some_and(|id| {
                self.tree.is_visible(id)
                    && self.tree.tiles.parent_of(id).is_none_or(|parent| match self.tree.tiles.get(parent) {
                        Some(Tile::Container(Container::Tabs(tabs))) => tabs.is_active(id),
                        _ => true,
                    })
            })
    }

    /// Show or hide a panel (the view is always shown).
    pub fn set_shown(&mut self, pane: Pane, shown: bool) {
        if pane == Pane::View {
            return;
        }
        if let Some(id) = self.tree.tiles.find_pane(&pane) {
            self.tree.set_visible(id, shown);
            self.dirty = true;
        }
    }

    /// Show a panel and make it the active tab of its group (e.g. the light inspector when a light is picked).
    pub fn focus(&mut self, pane: Pane) {
        let Some(id) = self.tree.tiles.find_pane(&pane) else { return };
        if !self.tree.is_visible(id) {
            self.tree.set_visible(id, true);
        }
        if let Some(parent) = self.tree.tiles.parent_of(id) {
            if let Some(Tile::Container(Container::Tabs(tabs))) = self.tree.tiles.get_mut(parent) {
                if !tabs.is_active(id) {
                    tabs.set_active(id);
                    self.dirty = true;
                }
            }
        }
    }

    /// [`Layout::focus`] from inside a pane's UI: done when the tiles have been drawn.
    pub fn request_focus(&mut self, pane: Pane) {
        self.pending_focus = Some(pane);
    }

    /// Bring forward the panel [`Layout::request_focus`] asked for (once the tiles have been drawn).
    pub fn focus_pending(&mut self) {
        if let Some(pane) = self.pending_focus.take() {
            self.focus(pane);
        }
    }

    /// Where the pane was laid out last frame.
    pub fn rect(&self, pane: Pane) -> Option<egui::Rect> {
        self.tree.tiles.find_pane(&pane).and_then(|id| self.tree.tiles.rect(id))
    }
}

impl Default for Layout {
    fn default() -> Self {
        Layout::new()
    }
}

/// The Panels menu: show or hide each panel, full view, the default layout.
pub fn panels_menu(layout: &mut Layout, ui: &mut egui::Ui) {
    for pane in Pane::ALL.into_iter().filter(|p| *p != Pane::View) {
        let mut shown = layout.is_shown(pane);
        if ui.checkbox(&mut shown, pane.title()).changed() {
            if shown {
                // Shown again, and in front of its tab group.
                layout.focus(pane);
            } else {
                layout.set_shown(pane, false);
            }
            layout.mark_changed();
        }
    }
    ui.separator();
    if ui.button("Full view (Tab or F11)").clicked() {
        layout.toggle_full_view();
        ui.close();
    }
    if ui.button("Default layout").clicked() {
        layout.reset();
        ui.close();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_layout_is_complete_and_survives_a_round_trip() {
        let mut layout = Layout::new();
        assert!(Layout::is_complete(&layout.tree));
        layout.set_shown(Pane::Sweep, false);
        layout.set_shown(Pane::View, false);
        assert!(!layout.is_shown(Pane::Sweep) && layout.is_shown(Pane::View), "the view cannot be hidden");
        let dir = std::env::temp_dir().join(format!("shadowlab-layout-{}", std::process::id()));
        layout.save(&dir).unwrap();
        let loaded = Layout::load(&dir);
        assert!(!loaded.is_shown(Pane::Sweep) && loaded.is_shown(Pane::Lights));
        // A broken file, or a tree without the view, gives the default layout.
        std::fs::write(Layout::path(&dir), "(version: 1, tree: (").unwrap();
        assert!(Layout::load(&dir).is_shown(Pane::Sweep));
        let mut tree = Layout::default_tree();
        let view = tree.tiles.find_pane(&Pane::View).unwrap();
        tree.remove_recursively(view);
        assert!(!Layout::is_complete(&tree));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
