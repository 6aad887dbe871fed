//! Paper-style figures: images side by side (the technique, its comparison target, their difference), each with
//! a caption under it, and a title line, as one PNG. Used by the app (File → Export figure) and by
//! `shadowlab compare --figure`. Text is drawn with plotters and the font egui ships.

use anyhow::{anyhow, Result};
use image::RgbaImage;
use plotters::prelude::*;
use shadowlab_core::compare::Metrics;

/// Space around and between the panes, in pixels.
pub const GAP: u32 = 8;
/// Height of the title line.
pub const TITLE_HEIGHT: u32 = 30;
/// Height of one caption line; every pane has [`CAPTION_LINES`] of them.
pub const LINE_HEIGHT: u32 = 18;
pub const CAPTION_LINES: u32 = 3;

/// One image of a figure and the lines of its caption (at most [`CAPTION_LINES`] are drawn).
pub struct FigurePane {
    pub image: RgbaImage,
    pub caption: Vec<String>,
}

/// The size of a figure of `panes` panes of `width` x `height`.
pub fn figure_size(width: u32, height: u32, panes: u32) -> (u32, u32) {
    (panes * width + (panes + 1) * GAP, TITLE_HEIGHT + height + GAP + CAPTION_LINES * LINE_HEIGHT + GAP)
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
    let (fw, fh) = figure_size(w, h, panes.len() as u32);
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
        let font = |size: u32| ("sans-serif", size).into_font().color(&BLACK);
        root.draw(&Text::new(title.to_string(), (GAP as i32, 6), font(18))).map_err(|e| err(&e))?;
        for (i, pane) in panes.iter().enumerate() {
            let x = (GAP + i as u32 * (w + GAP)) as i32;
            for (j, line) in pane.caption.iter().take(CAPTION_LINES as usize).enumerate() {
                let y = (TITLE_HEIGHT + h + GAP / 2 + j as u32 * LINE_HEIGHT) as i32;
                root.draw(&Text::new(line.clone(), (x, y), font(14))).map_err(|e| err(&e))?;
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
            image: RgbaImage::from_pixel(40, 30, image::Rgba([c, 0, 0, 255])),
            caption: vec![format!("pane {c}"), "second line".into()],
        };
        let fig = compose("title", &[pane(50), pane(150), pane(250)]).unwrap();
        assert_eq!(fig.dimensions(), figure_size(40, 30, 3));
        for (i, c) in [50u8, 150, 250].iter().enumerate() {
            let x = GAP + i as u32 * (40 + GAP) + 20;
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
}
