//! The Shadow maps panel: the shadow-map inspector on the maps of the direct and the indirect technique.

use eframe::egui;
use glam::Vec3;

use crate::gui::inspector::Inspector;
use crate::gui::session::Session;
use crate::gui::views::Views;

/// The shadow-map inspector: reads the chosen maps back once per completed frame (not for the preview while
/// the camera moves), then shows them; a selected light shows its cube map.
pub fn maps_ui(session: &Session, views: &mut Views, inspector: &mut Inspector, ui: &mut egui::Ui) {
    use crate::gui::inspector::{AtlasDepths, MapSource};
    use crate::gui::rsm_view::RsmInputs;
    use shadowlab_core::technique::Technique;
    // Every map set of the direct and the indirect technique: shadow maps first, then depth images.
    fn sets(t: &dyn Technique) -> Vec<(&shadowlab_core::services::cube_shadows::CubeAtlas, &'static str)> {
        t.shadow_atlas().into_iter().chain(t.depth_images()).collect()
    }
    fn labelled(t: &dyn Technique, indirect: bool) -> Vec<(MapSource, String)> {
        let shadow = usize::from(t.shadow_atlas().is_none());
        let images = t.depth_images().into_iter().map(|(_, what)| what);
        let names = t.shadow_atlas().map(|_| "shadow maps").into_iter().chain(images);
        let who = if indirect { "indirect" } else { "direct" };
        names
            .enumerate()
            .map(|(i, name)| (MapSource { indirect, set: i + shadow }, format!("{} ({who}): {name}", t.label())))
            .collect()
    }
    let key = session.technique.clone();
    let indirect_key = session.indirect.technique.clone();
    let selected = session.selected;
    let mut sources = Vec::new();
    let mut follow: Option<(usize, Vec<Vec3>)> = None;
    if let Some(gpu) = &mut views.gpu {
        if let Ok(t) = gpu.main.technique(&key) {
            sources.extend(labelled(t.as_ref(), false));
        }
        if let Some(k) = &indirect_key {
            if let Ok(t) = gpu.main.indirect_technique(k) {
                sources.extend(labelled(t.borrow().as_ref(), true));
            }
        }
        let complete = gpu.main.last_report.as_ref().is_some_and(|r| r.technique == key);
        if let Some((wanted, asked_in)) = inspector.requested {
            if sources.iter().any(|(s, _)| *s == wanted) {
                (inspector.source, inspector.requested) = (wanted, None);
            } else if complete && gpu.main.is_converged() && gpu.main.frame_key() != asked_in {
                inspector.requested = None;
            }
        }
        if !sources.iter().any(|(s, _)| *s == inspector.source) {
            inspector.source = sources.first().map(|(s, _)| *s).unwrap_or(MapSource::DIRECT);
        }
        if inspector.rsm_shown {
            let lights = session.animated_lights();
            let renderer = &gpu.main.renderer;
            let ctx = gpu.ctx.clone();
            let bvh = || renderer.scene().bvh(&ctx).0;
            inspector.rsm.update(&RsmInputs {
                bvh: &bvh,
                scene: renderer.shared_scene(),
                lights: &lights,
                suns: renderer.directional_lights(),
                vpls: &renderer.shared_vpls(),
                selected,
                settled: gpu.main.is_converged(),
            });
            inspector.ui(ui, sources, lights.len());
            return;
        }
        let source = inspector.source;
        let from = (gpu.main.frame_key(), source);
        if gpu.main.is_converged() && complete && inspector.read_from != Some(from) {
            let ctx = gpu.ctx.clone();
            // `set` 0 is the shadow atlas; without one the depth images still start at 1.
            let read = |t: &dyn Technique| {
                let offset = usize::from(t.shadow_atlas().is_none());
                let all = sets(t);
                source
                    .set
                    .checked_sub(offset)
                    .and_then(|i| all.get(i))
                    .map(|(a, what)| AtlasDepths::read(&ctx, a, what))
                    .transpose()
            };
            let result = if source.indirect {
                match &indirect_key {
                    Some(k) => gpu.main.indirect_technique(k).and_then(|t| read(t.borrow().as_ref())),
                    None => Ok(None),
                }
            } else {
                gpu.main.technique(&key).and_then(|t| read(t.as_ref()))
            };
            inspector.set_atlas(result.map_err(|e| format!("{e:#}")), from);
        }
    }
    if let Some(i) = selected {
        let lights = session.animated_lights();
        if let Some(light) = lights.get(i) {
            let mut positions = vec![light.position];
            let group = views.light_details(session, i).map(|d| d.group).unwrap_or_default();
            positions.extend(group.iter().filter_map(|&m| lights.get(m)).map(|l| l.position));
            follow = Some((i, positions));
        }
    }
    if let Some((i, positions)) = follow {
        inspector.follow_light(i, &positions);
    }
    inspector.ui(ui, sources, session.lights.len());
}
