//! A zoomable, pannable image filling the rest of a panel (the shadow-map inspector's and the RSM view's):
//! fitted at zoom 1, scroll to zoom around the pointer (1 to 64), drag to pan; and an image shrunk to the GPU's
//! texture limit ([`fit_texture`]).

use eframe::egui;

/// Zoom and pan of one image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageView {
    /// Points per texel, relative to the fitted size.
    pub zoom: f32,
    /// The image's centre, from the panel's centre.
    pub offset: egui::Vec2,
}

impl Default for ImageView {
    fn default() -> Self {
        ImageView { zoom: 1.0, offset: egui::Vec2::ZERO }
    }
}

/// Where an image was drawn.
pub struct Placed {
    /// The image's rectangle (it may reach past the panel when zoomed).
    pub rect: egui::Rect,
    /// Points per texel.
    pub scale: f32,
    /// A painter clipped to the panel, for marks over the image.
    pub painter: egui::Painter,
    /// The texel under the pointer, if the pointer is over the image.
    pub hovered: Option<(u32, u32)>,
}

impl Placed {
    /// The panel point at the centre of texel `(x, y)`.
    pub fn point(&self, x: u32, y: u32) -> egui::Pos2 {
        self.rect.min + egui::vec2(x as f32 + 0.5, y as f32 + 0.5) * self.scale
    }
}

impl ImageView {
    /// Back to the fitted image.
    pub fn reset(&mut self) {
        *self = ImageView::default();
    }

    /// Draw `texture` (an image of `size` texels) into the panel's remaining space, less `reserve` points
    /// below it (for a readout line), zooming and panning by the pointer.
    pub fn show(&mut self, ui: &mut egui::Ui, texture: &egui::TextureHandle, size: [u32; 2], reserve: f32) -> Placed {
        let area = egui::vec2(ui.available_width(), (ui.available_height() - reserve).max(120.0));
        let (rect, response) = ui.allocate_exact_size(area, egui::Sense::click_and_drag());
        let image_size = egui::vec2(size[0].max(1) as f32, size[1].max(1) as f32);
        let fit = (rect.width() / image_size.x).min(rect.height() / image_size.y);
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                let before = self.zoom;
                self.zoom = (self.zoom * (scroll * 0.005).exp()).clamp(1.0, 64.0);
                if let Some(p) = response.hover_pos() {
                    // Keep the texel under the pointer where it is.
                    let from_center = p - rect.center() - self.offset;
                    self.offset -= from_center * (self.zoom / before - 1.0);
                }
            }
        }
        if response.dragged() {
            self.offset += response.drag_delta();
        }
        let scale = fit * self.zoom;
        let shown = egui::Rect::from_center_size(rect.center() + self.offset, image_size * scale);
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, egui::Color32::from_gray(30));
        let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
        painter.image(texture.id(), shown, uv, egui::Color32::WHITE);
        let hovered = response.hover_pos().and_then(|p| {
            let t = (p - shown.min) / scale;
            (t.x >= 0.0 && t.y >= 0.0 && t.x < image_size.x && t.y < image_size.y).then_some((t.x as u32, t.y as u32))
        });
        Placed { rect: shown, scale, painter, hovered }
    }
}

/// An image no larger than `max_side` on either side (the GPU's texture limit; a large atlas exceeds it):
/// shrunk by a whole factor, each pixel the brightest of its block, so thin near geometry stays visible. The
/// readout still reads the full-resolution depths.
pub fn fit_texture(image: egui::ColorImage, max_side: usize) -> egui::ColorImage {
    let [w, h] = image.size;
    let factor = w.max(h).div_ceil(max_side.max(1));
    if factor <= 1 {
        return image;
    }
    let (sw, sh) = (w.div_ceil(factor), h.div_ceil(factor));
    let brightness = |c: egui::Color32| c.r() as u32 + c.g() as u32 + c.b() as u32;
    let pixels = (0..sh)
        .flat_map(|y| (0..sw).map(move |x| (x, y)))
        .map(|(x, y)| {
            let block = (y * factor..((y + 1) * factor).min(h))
                .flat_map(|py| (x * factor..((x + 1) * factor).min(w)).map(move |px| py * w + px));
            block.map(|i| image.pixels[i]).max_by_key(|c| brightness(*c)).unwrap_or_default()
        })
        .collect();
    egui::ColorImage::new([sw, sh], pixels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_image_over_the_texture_limit_is_shrunk_keeping_its_bright_texels() {
        let (w, h) = (10usize, 5usize);
        let mut pixels = vec![egui::Color32::BLACK; w * h];
        pixels[3 * w + 7] = egui::Color32::WHITE;
        let image = egui::ColorImage::new([w, h], pixels);
        assert_eq!(fit_texture(image.clone(), 10).size, [10, 5], "within the limit: unchanged");
        let small = fit_texture(image, 4);
        assert_eq!(small.size, [4, 2], "shrunk by 3, rounded up");
        assert_eq!(small.pixels[4 + 2], egui::Color32::WHITE, "the white texel's block stays white");
        assert_eq!(small.pixels.iter().filter(|c| **c == egui::Color32::WHITE).count(), 1);
    }
}
