//! Tooltips of the 3D view: a light's fields and what the technique made of it, a technique camera, what a
//! visible overlay layer draws under the pointer (a VAL, a VPL, a cluster's representative, a per-pixel ID).

use std::sync::Arc;

use eframe::egui;
use shadowlab_core::technique::Overlay;

use super::Views;
use crate::gui::document::ViewMode;
use crate::gui::gizmo::{self, Projection};
use crate::gui::session::Session;

impl Views {
    /// The tooltip of a light in the view: its fields, and what the technique made of it.
    pub fn light_tooltip(&mut self, session: &Session, index: usize) -> Vec<String> {
        let Some(l) = session.lights.get(index).copied() else { return Vec::new() };
        let mut lines = vec![
            format!("light {index}{}", if l.spot.is_some() { " (spot)" } else { "" }),
            format!("position ({:.2}, {:.2}, {:.2})", l.position.x, l.position.y, l.position.z),
            format!("intensity {:.2} · L_att {:.2}", l.intensity, l.range),
        ];
        if let Some(d) = self.light_details(session, index) {
            lines.extend(d.lines);
        }
        lines
    }

    /// The tooltip of a camera the technique used (a `Cameras` parameter's, e.g. an INSM viewpoint) under `pos`.
    pub fn camera_tooltip(&mut self, session: &Session, projection: &Projection, pos: egui::Pos2) -> Vec<String> {
        let Some(gpu) = &mut self.gpu else { return Vec::new() };
        let Ok(technique) = gpu.main.technique(&session.technique) else { return Vec::new() };
        for p in technique.params() {
            if let shadowlab_core::technique::ParamKind::Cameras { .. } = p.kind {
                let cameras = technique.cameras_in_use(p.key);
                if let Some(i) = gizmo::pick_point(projection, cameras.iter().map(|c| c.position), pos, 10.0) {
                    let c = cameras[i];
                    return vec![
                        format!("{} #{} of {}", p.label, i + 1, cameras.len()),
                        format!("position ({:.2}, {:.2}, {:.2})", c.position.x, c.position.y, c.position.z),
                        format!(
                            "looking at ({:.2}, {:.2}, {:.2}) · fov {:.0}°",
                            c.target.x, c.target.y, c.target.z, c.fov_y_deg
                        ),
                    ];
                }
            }
        }
        Vec::new()
    }

    /// The tooltip of what a visible overlay layer draws under `pos` (a VAL, a VPL, a cluster's
    /// representative), from the direct or the indirect technique's hover points
    /// ([`Technique::hover_points`](shadowlab_core::technique::Technique::hover_points)).
    pub fn overlay_tooltip(&mut self, session: &Session, projection: &Projection, pos: egui::Pos2) -> Vec<String> {
        use shadowlab_core::technique::Technique;
        let visible: Vec<String> =
            self.overlay_layers(session).into_iter().filter(|(_, on)| *on).map(|(n, _)| n).collect();
        let indirect_key = session.indirect.technique.clone();
        let Some(gpu) = &mut self.gpu else { return Vec::new() };
        let pick = |t: &dyn Technique| {
            let points: Vec<_> =
                t.hover_points().into_iter().filter(|p| visible.iter().any(|v| v == p.layer)).collect();
            let i = gizmo::pick_point(projection, points.iter().map(|p| p.position), pos, 8.0)?;
            Some(points[i]).map(|p| t.hover_details(p.layer, p.index)).filter(|lines| !lines.is_empty())
        };
        if let Some(lines) = gpu.main.technique(&session.technique).ok().and_then(|t| pick(t.as_ref())) {
            return lines;
        }
        let indirect = indirect_key.and_then(|k| gpu.main.indirect_technique(&k).ok());
        if let Some(lines) = indirect.as_ref().and_then(|t| pick(t.borrow().as_ref())) {
            return lines;
        }
        // A visible per-pixel ID map (a cluster per pixel) under the pointer: the ID there, and what the
        // technique says of that ID as a hover index of the map's layer. Only in the single view, which the
        // render target fills.
        let Some(rect) = self.last_viewport_rect.filter(|_| session.view.mode == ViewMode::Single) else {
            return Vec::new();
        };
        // (layer, size, ids, from the indirect technique)
        type IdMapLayer = (&'static str, (u32, u32), Arc<Vec<u32>>, bool);
        let mut maps: Vec<IdMapLayer> = Vec::new();
        if let Some((_, name, ids, size)) = &self.pixel_ids {
            maps.push((name, *size, ids.clone(), false));
        }
        if let Some(t) = &indirect {
            for layer in t.borrow().overlays(&[]) {
                for o in &layer.primitives {
                    if let Overlay::IdMap { width, height, ids, .. } = o {
                        maps.push((layer.name, (*width, *height), ids.clone(), true));
                    }
                }
            }
        }
        let uv = (pos - rect.min) / rect.size();
        for (name, (w, h), ids, from_indirect) in maps {
            if !visible.iter().any(|v| v == name) || !(0.0..1.0).contains(&uv.x) || !(0.0..1.0).contains(&uv.y) {
                continue;
            }
            let (x, y) = ((uv.x * w as f32) as u32, (uv.y * h as f32) as u32);
            let Some(&id) = ids.get((y * w + x) as usize).filter(|id| **id != u32::MAX) else { continue };
            let mut lines = vec![format!("{name}: {id} (pixel {x}, {y})")];
            let details = if from_indirect {
                indirect.as_ref().map(|t| t.borrow().hover_details(name, id as usize))
            } else {
                gpu.main.technique(&session.technique).ok().map(|t| t.hover_details(name, id as usize))
            };
            lines.extend(details.unwrap_or_default());
            return lines;
        }
        Vec::new()
    }
}
