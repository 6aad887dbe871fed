//! Captures: screenshots of the 3D view (at its render resolution) and of the window, a paper-style figure (the technique, its comparison target and their
//! difference side by side, with technique, parameters and metrics as captions) and image sequences (an orbit
//! around the camera's target, or one period of the light animation) as PNGs and a GIF. Both render every
//! image completely, now, in a renderer of their own on the view's device at the view's render resolution (the
//! window waits: seconds on a software rasterizer).

use std::path::PathBuf;

use anyhow::{anyhow, Context, Result};
use eframe::egui;
use shadowlab_core::technique::Overlay;
use shadowlab_core::Renderer;

use super::camera::CameraMode;
use super::ShadowLabApp;
use crate::figure::{self, FigurePane};
use crate::measure::{self, DiffKind, IndirectChoice};
use crate::sequence::{self, Motion};

impl ShadowLabApp {
    fn indirect_choice(&self) -> IndirectChoice {
        self.session.indirect_choice_of(self.session.indirect.technique.as_deref())
    }

    /// A renderer of its own at the view's full render resolution.
    fn capture_renderer(&self) -> Result<Renderer> {
        let settings = self.session.render_settings(self.views.last_view_pixels, false);
        let gpu = self.views.gpu.as_ref().ok_or_else(|| anyhow!("no GPU"))?;
        Ok(gpu.main.renderer.new_view(settings)?)
    }

    /// The figure as an image: three panes of the view's render size (see [`figure::figure_size`]).
    pub fn figure_image(&mut self) -> Result<image::RgbaImage> {
        let camera = self.session.camera.camera();
        let lights = self.session.animated_lights();
        let mut renderer = self.capture_renderer()?;
        let indirect = self.indirect_choice();
        let no_progress = &mut |_: &str| {};
        let params = self.session.param_strings(&self.session.technique);
        let tech = measure::render_technique(
            &mut renderer,
            &self.session.technique,
            None,
            &params,
            &camera,
            &lights,
            &indirect,
            0,
            1,
            no_progress,
        )?;
        let tech_image = renderer.read_output()?;
        // The target is shown at the technique's metered exposure, so equal radiance looks equal in the panes.
        if let Some((scale, average)) = renderer.auto_exposure()? {
            let held = shadowlab_core::RenderSettings {
                auto_exposure: shadowlab_core::AutoExposure::Hold,
                ..renderer.settings().clone()
            };
            renderer.set_settings(held)?;
            renderer.set_held_exposure(scale, average)?;
        }
        let against = self.session.view.compare_against.clone();
        let against_params = self.session.param_strings(&against);
        let against_indirect = self.session.indirect_choice_of(self.session.against_indirect_key());
        let target = measure::render_technique(
            &mut renderer,
            &against,
            None,
            &against_params,
            &camera,
            &lights,
            &against_indirect,
            0,
            1,
            no_progress,
        )?;
        let target_image = renderer.read_output()?;
        let inputs = measure::compare_inputs(&mut renderer, &camera, &lights)?;
        let gain = self.session.view.diff_gain;
        let (metrics, diff) = measure::compare_images(
            &tech.image,
            &target.image,
            &inputs,
            DiffKind::Absolute,
            gain,
            true,
            self.session.view.exposure,
        )?;
        let (w, h) = (renderer.settings().width, renderer.settings().height);
        let component = match renderer.settings().component {
            shadowlab_core::renderer::Component::Total => String::new(),
            other => format!(" · {} light", other.name()),
        };
        let title = format!(
            "{} · {} lights · {w}x{h}{component} · {}",
            self.session.scene.name,
            lights.len(),
            renderer.gpu().adapter_description()
        );
        let metrics_lines = figure::metrics_caption(&metrics);
        let speedup = measure::Speedup::of(&tech.timing, &target.timing);
        let panes = [
            FigurePane {
                image: tech_image,
                caption: vec![
                    indirect.name_with(&self.session.technique),
                    indirect.params_caption(&params),
                    format!("{:.1} ms, {}", tech.timing.median_in(speedup.clock), speedup.text()),
                ],
            },
            FigurePane {
                image: target_image,
                caption: vec![
                    against_indirect.name_with(&against),
                    against_indirect.params_caption(&against_params),
                    format!("{:.1} ms ({})", target.timing.median_in(speedup.clock), speedup.clock.name()),
                ],
            },
            FigurePane {
                image: diff,
                caption: vec![
                    format!("|difference| ×{gain} (dark blue 0 → red {:.2})", 1.0 / gain),
                    metrics_lines[0].clone(),
                    metrics_lines[1].clone(),
                ],
            },
        ];
        figure::compose(&title, &panes)
    }

    /// Export the figure next to the screenshots. Returns the path.
    pub fn save_figure(&mut self) -> Result<PathBuf> {
        let image = self.figure_image()?;
        let path = self.screenshot_name("figure");
        std::fs::create_dir_all(path.parent().expect("has a parent"))?;
        image.save(&path).with_context(|| format!("cannot write {}", path.display()))?;
        Ok(path)
    }

    /// Render `frames` images, each complete, into a new folder next to the screenshots, and a looping GIF of
    /// them (`sequence.gif` in the same folder): a full orbit (yaw steps of 360°/frames around the orbit
    /// target, 80 ms a frame), or one period of the light animation (played in real time).
    pub fn save_sequence(&mut self, motion: Motion, frames: usize) -> Result<SavedSequence> {
        sequence::check_frames(frames)?;
        let period_secs = match motion {
            Motion::Orbit => None,
            Motion::Lights => Some(
                self.session
                    .animation
                    .period_secs()
                    .ok_or_else(|| anyhow!("the light animation is off: choose one in the Lights panel"))?,
            ),
        };
        let mut renderer = self.capture_renderer()?;
        let indirect = self.indirect_choice();
        let params = self.session.param_strings(&self.session.technique);
        let name = self.screenshot_name(match motion {
            Motion::Orbit => "orbit",
            Motion::Lights => "lights",
        });
        let dir = name.with_extension("");
        std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
        let mut orbit = self.session.camera.clone();
        orbit.set_mode(CameraMode::Orbit);
        let start_yaw = orbit.yaw;
        let mut paths = Vec::with_capacity(frames);
        let frame_ms = period_secs.map_or(80, |p| (p * 1000.0 / frames as f32).round() as u32);
        let gif_path = dir.join("sequence.gif");
        let mut gif = sequence::GifWriter::new(&gif_path, frame_ms)?;
        // The overlay layers the view shows, drawn as the view draws them (dots and lines in screen points).
        let layers: Vec<String> = if self.chrome.sequence_overlays {
            self.overlay_layers().into_iter().filter(|(_, on)| *on).map(|(name, _)| name).collect()
        } else {
            Vec::new()
        };
        let view_points = self.views.last_viewport_rect.map_or(1.0, |r| r.width().max(1.0));
        let render_pixels_per_point = renderer.settings().width as f32 / view_points;
        renderer.set_overlay_style(shadowlab_core::services::overlay::OverlayStyle {
            line_width_px: (2.0 * render_pixels_per_point).max(1.0),
            occluded_alpha: 0.25,
        });
        let x_ray = self.session.view.x_ray;
        for i in 0..frames {
            let share = i as f32 / frames as f32;
            let lights = match period_secs {
                Some(p) => self.session.lights_at(self.session.animation_time + p * share),
                None => {
                    orbit.yaw = start_yaw + std::f32::consts::TAU * share;
                    self.session.animated_lights()
                }
            };
            let camera = orbit.camera();
            let draw_overlays = &mut |r: &mut Renderer, t: &dyn shadowlab_core::technique::Technique| {
                if layers.is_empty() {
                    return Ok(());
                }
                let mut all = t.overlays(&lights);
                if let Some(i) = r.indirect() {
                    all.extend(i.overlays(&lights));
                }
                let mut primitives: Vec<Overlay> =
                    all.into_iter().filter(|l| layers.iter().any(|n| n == l.name)).flat_map(|l| l.primitives).collect();
                for o in &mut primitives {
                    if let Overlay::Point { radius_px, .. } = o {
                        *radius_px *= render_pixels_per_point;
                    }
                }
                Ok(r.draw_overlays(&camera, &primitives, x_ray)?)
            };
            measure::render_technique_then(
                &mut renderer,
                &self.session.technique,
                None,
                &params,
                &camera,
                &lights,
                &indirect,
                0,
                1,
                &mut |_| {},
                draw_overlays,
            )?;
            let path = sequence::frame_path(&dir, i);
            let image = renderer.read_output()?;
            image.save(&path).with_context(|| format!("cannot write {}", path.display()))?;
            paths.push(path);
            gif.add(&image)?;
        }
        gif.finish()?;
        Ok(SavedSequence { frames: paths, gif: gif_path })
    }
}

/// An image sequence the app saved.
pub struct SavedSequence {
    pub frames: Vec<PathBuf>,
    /// The frames as one looping animated GIF.
    pub gif: PathBuf,
}

impl ShadowLabApp {
    pub(super) fn screenshot_name(&self, what: &str) -> PathBuf {
        let params: String = self
            .session
            .params
            .get(&self.session.technique)
            .map(|p| p.iter().map(|(k, v)| format!("-{k}{v}")).collect())
            .unwrap_or_default();
        let stamp = chrono_like_stamp();
        let indirect = self.session.indirect.technique.as_ref().map(|k| format!("+{k}")).unwrap_or_default();
        let name = format!(
            "shadowlab-{}-{}{}{}-{}-{}.png",
            self.session.scene.name, self.session.technique, params, indirect, what, stamp
        )
        .replace(['/', '\\', ' ', ':'], "_");
        self.lifecycle.data_dir.join("screenshots").join(name)
    }

    /// Export a figure and say where it went (or why not).
    pub fn export_figure(&mut self) {
        match self.save_figure() {
            Ok(p) => self.toast(format!("saved {}", p.display())),
            Err(e) => self.error(format!("figure export failed: {e:#}")),
        }
    }

    /// Save the 3D view at its render resolution (no UI). Returns the path.
    pub fn save_view_screenshot(&mut self) -> Result<PathBuf> {
        let path = self.screenshot_name("view");
        let gpu = self.views.gpu.as_ref().ok_or_else(|| anyhow!("no GPU"))?;
        let image = gpu.main.renderer.read_output()?;
        std::fs::create_dir_all(path.parent().expect("has a parent"))?;
        image.save(&path).with_context(|| format!("cannot write {}", path.display()))?;
        Ok(path)
    }

    fn save_window_screenshot(&mut self, image: &egui::ColorImage) -> Result<PathBuf> {
        let path = self.screenshot_name("window");
        let [w, h] = image.size;
        let bytes: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
        let img = image::RgbaImage::from_raw(w as u32, h as u32, bytes).ok_or_else(|| anyhow!("bad screenshot"))?;
        std::fs::create_dir_all(path.parent().expect("has a parent"))?;
        img.save(&path).with_context(|| format!("cannot write {}", path.display()))?;
        Ok(path)
    }

    /// Ask the integration for a picture of the whole window; it arrives a frame or two later.
    pub fn request_window_screenshot(&mut self, ctx: &egui::Context) {
        let slot = self.lifecycle.window_shot.clone();
        let repaint = ctx.clone();
        ctx.request_screenshot(move |image| {
            if let Ok(mut s) = slot.lock() {
                *s = Some(image);
            }
            repaint.request_repaint();
        });
    }

    /// Save a window screenshot that arrived: the exit screenshot (then close), or one the user asked for.
    pub(super) fn receive_screenshots(&mut self, ctx: &egui::Context) {
        let shot = self.lifecycle.window_shot.lock().ok().and_then(|mut s| s.take());
        if let Some(image) = shot {
            if let (true, Some(path)) = (self.lifecycle.quitting, self.lifecycle.exit_screenshot.take()) {
                let [w, h] = image.size;
                let bytes: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
                match image::RgbaImage::from_raw(w as u32, h as u32, bytes).map(|img| img.save(&path)) {
                    Some(Ok(())) => eprintln!("saved {}", path.display()),
                    _ => eprintln!("error: cannot save {}", path.display()),
                }
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                return;
            }
            match self.save_window_screenshot(&image) {
                Ok(p) => self.toast(format!("saved {}", p.display())),
                Err(e) => self.error(format!("screenshot failed: {e:#}")),
            }
        }
    }
}

fn chrono_like_stamp() -> String {
    let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_millis()).unwrap_or(0);
    format!("{secs}")
}
