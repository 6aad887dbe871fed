//! The difference view: the difference image of the technique against its comparison target and the error
//! metrics, for one pair of converged frames; the metrics (FLIP is slow) on a worker thread.

use anyhow::{anyhow, Result};
use eframe::egui;
use shadowlab_core::renderer::Component;
use shadowlab_core::RenderSettings;

use super::difference_data::{Difference, PendingDifference};
use super::Views;
use crate::gui::session::Session;

impl Views {
    /// Whether the shown difference is of the views' current frames (false while a newer one is computed or
    /// the views are still rendering new frames).
    pub fn difference_is_current(&self) -> bool {
        let (Some(d), Some(gpu)) = (&self.difference, &self.gpu) else { return false };
        gpu.main.is_converged()
            && gpu.reference.is_converged()
            && (d.key.0, d.key.1) == (gpu.main.frame_key(), gpu.reference.frame_key())
    }

    /// Recompute the difference image when both views have converged on new frames.
    pub fn update_difference(&mut self, session: &Session, ctx: &egui::Context) -> Result<()> {
        let camera = session.camera.camera();
        let lights = session.animated_lights();
        let Some(gpu) = &mut self.gpu else { return Ok(()) };
        if !(gpu.main.is_converged() && gpu.reference.is_converged()) {
            return Ok(());
        }
        let key = (
            gpu.main.frame_key(),
            gpu.reference.frame_key(),
            session.view.diff_signed,
            session.view.diff_visibility,
            session.view.diff_gain.to_bits(),
        );
        if self.difference.as_ref().is_some_and(|d| d.key == key) {
            return Ok(());
        }
        // A worker is on it: show its result when it arrives (an older key's result is dropped).
        if let Some(p) = &self.pending_difference {
            match p.result.try_recv() {
                Ok(result) => {
                    let (pkey, (w, h)) = (p.key, p.size);
                    self.pending_difference = None;
                    let (metrics, image) = result?;
                    let color = egui::ColorImage::from_rgba_unmultiplied([w as usize, h as usize], image.as_raw());
                    let texture = ctx.load_texture("difference", color, egui::TextureOptions::NEAREST);
                    self.difference = Some(Difference { texture, metrics, key: pkey });
                    if pkey == key {
                        return Ok(());
                    }
                }
                Err(std::sync::mpsc::TryRecvError::Empty) if p.key == key => {
                    ctx.request_repaint_after(std::time::Duration::from_millis(50));
                    return Ok(());
                }
                Err(_) => self.pending_difference = None,
            }
        }
        use shadowlab_core::compare::{self, CompareOptions, DiffMode, Image, Visibility};
        let (w, h) = gpu.main.size;
        // Shadow factors are those of the direct light, whatever component the views show; otherwise the
        // component shown is compared.
        let read = |renderer: &shadowlab_core::Renderer| {
            if session.view.diff_visibility {
                renderer.read_component(Component::Direct)
            } else {
                renderer.read_hdr()
            }
        };
        let technique = Image::new(w, h, read(&gpu.main.renderer)?)?;
        let reference = Image::new(w, h, read(&gpu.reference.renderer)?)?;
        let mask = gpu.main.renderer.read_geometry_mask()?;
        let mode = if session.view.diff_signed { DiffMode::Signed } else { DiffMode::Absolute };
        let gain = session.view.diff_gain;
        // The GPU part (readbacks, and for shadow factors the unshadowed and ambient-only images of the same
        // view) here; the CPU part (metrics with FLIP, the colour map) on a worker thread unless synchronous.
        let lit_ambient = if session.view.diff_visibility {
            let settings = RenderSettings { component: Component::Direct, ..gpu.main.renderer.settings().clone() };
            let mut aux = gpu.main.renderer.new_view(settings)?;
            let mut unshadowed = aux
                .create_technique(shadowlab_core::technique::registry::preview().key)
                .ok_or_else(|| anyhow!("no preview technique"))?;
            aux.render_frame(unshadowed.as_mut(), &camera, &lights, &mut |_, _| {})?;
            let lit = Image::new(w, h, aux.read_hdr()?)?;
            aux.render_frame(unshadowed.as_mut(), &camera, &[], &mut |_, _| {})?;
            let ambient = Image::new(w, h, aux.read_hdr()?)?;
            Some((lit, ambient))
        } else {
            None
        };
        let work = move || -> Result<(shadowlab_core::compare::Metrics, image::RgbaImage)> {
            Ok(match &lit_ambient {
                Some((lit, ambient)) => {
                    let v_t = compare::visibility_image(&technique, lit, Some(ambient))?;
                    let v_r = compare::visibility_image(&reference, lit, Some(ambient))?;
                    let options = CompareOptions {
                        visibility: Some(Visibility { technique: &v_t, reference: &v_r }),
                        ..Default::default()
                    };
                    let m = compare::compare(&technique, &reference, Some(&mask), &options)?;
                    (m, compare::visibility_difference_image(&v_t, &v_r, w, h, Some(&mask), mode, gain)?)
                }
                None => {
                    let m = compare::compare(&technique, &reference, Some(&mask), &CompareOptions::default())?;
                    (m, compare::difference_image(&technique, &reference, Some(&mask), mode, gain)?)
                }
            })
        };
        if self.background_work {
            let (tx, rx) = std::sync::mpsc::channel();
            let repaint = ctx.clone();
            std::thread::Builder::new().name("difference".into()).spawn(move || {
                let _ = tx.send(work());
                repaint.request_repaint();
            })?;
            self.pending_difference = Some(PendingDifference { key, size: (w, h), result: rx });
            return Ok(());
        }
        let (metrics, image) = work()?;
        let color = egui::ColorImage::from_rgba_unmultiplied([w as usize, h as usize], image.as_raw());
        let texture = ctx.load_texture("difference", color, egui::TextureOptions::NEAREST);
        self.difference = Some(Difference { texture, metrics, key });
        Ok(())
    }
}
