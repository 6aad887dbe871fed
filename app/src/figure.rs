//! Paper-style figures: images side by side (the technique, its comparison target, their difference), each with
//! a caption under it, and a title line, as one PNG. Used by the app (File → Export figure) and by
//! `shadowlab compare --figure`. Text is drawn with plotters and the font egui ships.

use anyhow::{anyhow, Result};
use image::RgbaImage;
use plotters::prelude::*;
use shadowlab_core::compare::Metrics;

/// Space around and between the panes, in pixels.
pub const GAP: u32 = 8;
/// Height of the title line (a title wider than the figure is cut with "…", so the panes always start here).
pub const TITLE_HEIGHT: u32 = 30;
/// Height of one caption line; every pane has room for at least [`CAPTION_LINES`] of them (more when a caption
/// wraps: lines wider than the pane break at spaces, and the figure grows).
pub const LINE_HEIGHT: u32 = 18;
pub const CAPTION_LINES: u32 = 3;
/// Text sizes in pixels.
const TITLE_SIZE: f32 = 18.0;
const CAPTION_SIZE: f32 = 14.0;

/// One image of a figure and the lines of its caption.
pub struct FigurePane {
    pub image: RgbaImage,
    pub caption: Vec<String>,
}

/// The size of a figure of `panes` panes of `width` x `height` whose captions take at most [`CAPTION_LINES`]
/// lines (a longer one makes the figure taller: [`figure_size_for`]).
pub fn figure_size(width: u32, height: u32, panes: u32) -> (u32, u32) {
    figure_size_for(width, height, panes, CAPTION_LINES)
}

/// The size of a figure whose longest caption takes `caption_lines` (at least [`CAPTION_LINES`] are reserved).
pub fn figure_size_for(width: u32, height: u32, panes: u32, caption_lines: u32) -> (u32, u32) {
    let captions = caption_lines.max(CAPTION_LINES) * LINE_HEIGHT;
    (panes * width + (panes + 1) * GAP, TITLE_HEIGHT + height + GAP + captions + GAP)
}

/// The metrics as two caption lines (short enough for panes of 320 pixels).
pub fn metrics_caption(m: &Metrics) -> [String; 2] {
    [
        format!(
            "RMSE {:.4} · PSNR {}",
            m.rmse,
            m.psnr_db.map(|p| format!("{p:.1} dB")).unwrap_or_else(|| "inf".into())
        ),
        format!(
            "FLIP {} · shadow err. {} · {:.1} % > {:.0} %",
            m.flip_mean.map(|f| format!("{f:.3}")).unwrap_or_else(|| "-".into()),
            m.shadow_intensity_error.map(|e| format!("{:.2} %", e * 100.0)).unwrap_or_else(|| "-".into()),
            m.share_over_threshold * 100.0,
            m.threshold * 100.0,
        ),
    ]
}

/// Lay out `panes` (all the size of the first; others are scaled to it) on white with their captions.
pub fn compose(title: &str, panes: &[FigurePane]) -> Result<RgbaImage> {
    let first = panes.first().ok_or_else(|| anyhow!("a figure needs at least one image"))?;
    let (w, h) = first.image.dimensions();
    if w == 0 || h == 0 {
        return Err(anyhow!("a figure's images must not be empty"));
    }
    // Captions wider than their pane wrap at spaces (the figure grows), a title wider than the figure is cut,
    // and what the font cannot draw is replaced.
    let fw = figure_size(w, h, panes.len() as u32).0;
    let title = crate::plot::truncate(title, TITLE_SIZE, (fw - 2 * GAP) as f32);
    let captions: Vec<Vec<String>> = panes
        .iter()
        .map(|p| p.caption.iter().flat_map(|line| crate::plot::wrap(line, CAPTION_SIZE, w as f32)).collect())
        .collect();
    let caption_lines = captions.iter().map(Vec::len).max().unwrap_or(0) as u32;
    let (fw, fh) = figure_size_for(w, h, panes.len() as u32, caption_lines);
    let mut rgb = vec![255u8; (fw * fh * 3) as usize];
    for (i, pane) in panes.iter().enumerate() {
        let scaled;
        let image = if pane.image.dimensions() == (w, h) {
            &pane.image
        } else {
            scaled = image::imageops::resize(&pane.image, w, h, image::imageops::FilterType::Triangle);
            &scaled
        };
        let x0 = GAP + i as u32 * (w + GAP);
        for (x, y, p) in image.enumerate_pixels() {
            let at = (((TITLE_HEIGHT + y) * fw + x0 + x) * 3) as usize;
            rgb[at..at + 3].copy_from_slice(&p.0[..3]);
        }
    }
    crate::plot::register_font();
    let err = |e: &dyn std::fmt::Display| anyhow!("cannot draw the figure's text: {e}");
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (fw, fh)).into_drawing_area();
        let font = |size: f32| ("sans-serif", size as u32).into_font().color(&BLACK);
        root.draw(&Text::new(title, (GAP as i32, 6), font(TITLE_SIZE))).map_err(|e| err(&e))?;
        for (i, caption) in captions.iter().enumerate() {
            let x = (GAP + i as u32 * (w + GAP)) as i32;
            for (j, line) in caption.iter().enumerate() {
                let y = (TITLE_HEIGHT + h + GAP / 2 + j as u32 * LINE_HEIGHT) as i32;
                root.draw(&Text::new(line.clone(), (x, y), font(CAPTION_SIZE))).map_err(|e| err(&e))?;
            }
        }
        root.present().map_err(|e| err(&e))?;
    }
    let rgba: Vec<u8> = rgb.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect();
    RgbaImage::from_raw(fw, fh, rgba).ok_or_else(|| anyhow!("figure buffer of the wrong size"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_figure_has_its_panes_side_by_side_under_the_title() {
        let pane = |c: u8| FigurePane {
            image: RgbaImage::from_pixel(120, 30, image::Rgba([c, 0, 0, 255])),
            caption: vec![format!("pane {c}"), "second line".into()],
        };
        let fig = compose("title", &[pane(50), pane(150), pane(250)]).unwrap();
        assert_eq!(fig.dimensions(), figure_size(120, 30, 3));
        for (i, c) in [50u8, 150, 250].iter().enumerate() {
            let x = GAP + i as u32 * (120 + GAP) + 20;
            assert_eq!(fig.get_pixel(x, TITLE_HEIGHT + 15).0, [*c, 0, 0, 255], "pane {i} in place");
        }
        // Some caption text is drawn (dark pixels under the images).
        let caption_dark = (0..fig.width())
            .flat_map(|x| (TITLE_HEIGHT + 30..fig.height()).map(move |y| (x, y)))
            .filter(|&(x, y)| fig.get_pixel(x, y).0[0] < 128)
            .count();
        assert!(caption_dark > 20, "{caption_dark} dark caption pixels");
        assert!(compose("empty", &[]).is_err());
    }

    #[test]
    fn long_captions_wrap_within_their_pane_and_missing_glyphs_are_replaced() {
        let long = "485.2 ms (median of 1, GPU timestamps), x1.71 against the reference's 830.1 ms".to_string();
        let pane = |c: u8| FigurePane {
            image: RgbaImage::from_pixel(120, 60, image::Rgba([c, c, c, 255])),
            caption: vec![long.clone(), "|difference| x4 (dark blue 0 → red 0.25)".into()],
        };
        let title = "cornell · 32 lights · 160x90 · llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Cpu) and more words";
        let fig = compose(title, &[pane(50), pane(150)]).unwrap();
        // The captions wrapped into more lines than reserved: the figure grew; the title was cut to fit.
        let (w, h) = figure_size(120, 60, 2);
        assert_eq!(fig.width(), w);
        assert!(fig.height() > h, "{} not above {h}", fig.height());
        let cut = crate::plot::truncate(title, TITLE_SIZE, (w - 2 * GAP) as f32);
        assert!(cut.ends_with('…') && crate::plot::text_width(&cut, TITLE_SIZE) <= (w - 2 * GAP) as f32, "{cut}");
        // No caption pixel of the first pane spills into the gap before the second.
        let gap_x = GAP + 120 + GAP / 2;
        let spilled = (TITLE_HEIGHT + 60..fig.height()).filter(|&y| fig.get_pixel(gap_x, y).0[0] < 200).count();
        assert_eq!(spilled, 0, "caption text in the gap between panes");
        for line in crate::plot::wrap(&long, CAPTION_SIZE, 120.0) {
            assert!(crate::plot::text_width(&line, CAPTION_SIZE) <= 120.0 || !line.contains(' '), "{line}");
        }
        // The arrow the font lacks is drawn as ASCII; what it has is kept.
        assert_eq!(crate::plot::drawable("0 → 1 · ×2 Δ"), "0 -> 1 · ×2 Δ");
    }
}
