//! The sweep's PNG plot: time and error against the first swept parameter, one line per combination of the
//! other parameters, the comparison target's time as a dashed line (a line of its own when the light count is
//! swept). Drawn with plotters on a bitmap, text with the font egui ships (no system fonts needed).

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{anyhow, Result};
use plotters::prelude::*;

/// One setting of a sweep, for plotting.
pub struct PlotRow {
    pub x: f64,
    /// The other swept parameters, e.g. "filter=pcss"; rows with the same series form one line.
    pub series: String,
    pub ms: f64,
    /// None for a time-only row (the comparison target's own time when the light count is swept).
    pub rmse: Option<f64>,
}

/// The font figures and plots draw with (egui's Ubuntu Light), for its metrics.
fn metrics_font() -> &'static ab_glyph::FontRef<'static> {
    static FONT: std::sync::OnceLock<ab_glyph::FontRef<'static>> = std::sync::OnceLock::new();
    FONT.get_or_init(|| {
        ab_glyph::FontRef::try_from_slice(epaint_default_fonts::UBUNTU_LIGHT).expect("egui's font parses")
    })
}

/// `text` with what the font has no glyph for replaced: arrows by ASCII ones, anything else by `?` (the font
/// would draw an empty box).
pub(crate) fn drawable(text: &str) -> String {
    use ab_glyph::Font;
    let font = metrics_font();
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_whitespace() || font.glyph_id(c).0 != 0 {
            out.push(c);
        } else {
            out.push_str(match c {
                '→' => "->",
                '←' => "<-",
                '↔' => "<->",
                _ => "?",
            });
        }
    }
    out
}

/// The width in pixels of `text` drawn at `size` pixels.
pub(crate) fn text_width(text: &str, size: f32) -> f32 {
    use ab_glyph::{Font, ScaleFont};
    let font = metrics_font().as_scaled(ab_glyph::PxScale::from(size));
    text.chars().map(|c| font.h_advance(font.glyph_id(c))).sum()
}

/// `text` (made [`drawable`]) broken at spaces into lines of at most `max_width` pixels at `size` (a word wider
/// than that stays whole on its line).
pub(crate) fn wrap(text: &str, size: f32, max_width: f32) -> Vec<String> {
    let text = drawable(text);
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split(' ') {
        let candidate = if line.is_empty() { word.to_string() } else { format!("{line} {word}") };
        if !line.is_empty() && text_width(&candidate, size) > max_width {
            lines.push(std::mem::take(&mut line));
            line = word.to_string();
        } else {
            line = candidate;
        }
    }
    lines.push(line);
    lines
}

/// `text` (made [`drawable`]) cut to at most `max_width` pixels at `size`, ending in "…" when cut.
pub(crate) fn truncate(text: &str, size: f32, max_width: f32) -> String {
    let text = drawable(text);
    if text_width(&text, size) <= max_width {
        return text;
    }
    let mut out = String::new();
    for c in text.chars() {
        let next = format!("{out}{c}…");
        if text_width(&next, size) > max_width {
            break;
        }
        out.push(c);
    }
    out.push('…');
    out
}

pub(crate) fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT);
    });
}

/// Write a two-panel PNG (time, RMSE) of `rows` against `x_label`, with the comparison target's time as a dashed
/// line when it is one number (`reference_ms`; None when it varies along x and comes as rows of its own).
pub fn sweep_plot(
    path: &Path,
    title: &str,
    x_label: &str,
    rows: &[PlotRow],
    against: &str,
    reference_ms: Option<f64>,
) -> Result<()> {
    if rows.is_empty() {
        return Err(anyhow!("nothing to plot"));
    }
    register_font();
    let mut series: BTreeMap<&str, Vec<&PlotRow>> = BTreeMap::new();
    for r in rows {
        series.entry(r.series.as_str()).or_default().push(r);
    }
    let (x0, x1) = rows.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| (a.min(r.x), b.max(r.x)));
    let (x0, x1) = if x1 > x0 { (x0, x1) } else { (x0 - 0.5, x0 + 0.5) };
    let max_ms = rows.iter().map(|r| r.ms).fold(reference_ms.unwrap_or(0.0), f64::max) * 1.1;
    let max_rmse = rows.iter().filter_map(|r| r.rmse).fold(0.0, f64::max).max(1e-6) * 1.1;
    let err = |e: &dyn std::fmt::Display| anyhow!("cannot draw the plot: {e}");

    const SIZE: (u32, u32) = (1200, 480);
    let mut rgb = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let root = root.titled(title, ("sans-serif", title_size(&root, title, 22.0))).map_err(|e| err(&e))?;
        let (left, right) = root.split_horizontally(600);
        let colors = [RGBColor(31, 119, 180), RGBColor(214, 39, 40), RGBColor(44, 160, 44), RGBColor(148, 103, 189)];

        let mut time = ChartBuilder::on(&left)
            .margin(12)
            .caption("GPU time per frame (ms)", ("sans-serif", 18))
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, 0.0..max_ms)
            .map_err(|e| err(&e))?;
        time.configure_mesh().x_desc(x_label).y_desc("ms").draw().map_err(|e| err(&e))?;
        if let Some(reference_ms) = reference_ms {
            time.draw_series(DashedLineSeries::new(
                vec![(x0, reference_ms), (x1, reference_ms)],
                8,
                5,
                BLACK.stroke_width(2),
            ))
            .map_err(|e| err(&e))?
            .label(against)
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
        }
        let mut error = ChartBuilder::on(&right)
            .margin(12)
            .caption(format!("RMSE against {against}"), ("sans-serif", 18))
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, 0.0..max_rmse)
            .map_err(|e| err(&e))?;
        error.configure_mesh().x_desc(x_label).y_desc("RMSE").draw().map_err(|e| err(&e))?;

        for (i, (name, points)) in series.iter().enumerate() {
            let color = colors[i % colors.len()];
            let label = if name.is_empty() { "technique".to_string() } else { name.to_string() };
            let t: Vec<(f64, f64)> = points.iter().map(|r| (r.x, r.ms)).collect();
            time.draw_series(LineSeries::new(t.clone(), color.stroke_width(2)))
                .map_err(|e| err(&e))?
                .label(label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
            time.draw_series(t.into_iter().map(|p| Circle::new(p, 3, color.filled()))).map_err(|e| err(&e))?;
            let e: Vec<(f64, f64)> = points.iter().filter_map(|r| r.rmse.map(|v| (r.x, v))).collect();
            if e.is_empty() {
                continue;
            }
            error
                .draw_series(LineSeries::new(e.clone(), color.stroke_width(2)))
                .map_err(|e| err(&e))?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
            error.draw_series(e.into_iter().map(|p| Circle::new(p, 3, color.filled()))).map_err(|e| err(&e))?;
        }
        time.configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| err(&e))?;
        error
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    let image = image::RgbImage::from_raw(SIZE.0, SIZE.1, rgb).ok_or_else(|| anyhow!("plot buffer size"))?;
    image.save_with_format(path, image::ImageFormat::Png).map_err(|e| anyhow!("cannot write {}: {e}", path.display()))
}

/// One configuration of a trade-off, for plotting.
pub struct TradeoffPoint {
    /// The try it belongs to (one colour each).
    pub series: String,
    pub ms: f64,
    pub error: f64,
    /// The work count of the second panel, when one was asked for.
    pub work: Option<f64>,
    pub pareto: bool,
    pub pick: bool,
}

/// The title's font size: `preferred`, or smaller so that the whole title fits the image's width (a long
/// technique name and scene used to run off both edges); never below 10.
fn title_size<DB: DrawingBackend>(area: &DrawingArea<DB, plotters::coord::Shift>, title: &str, preferred: f64) -> f64 {
    let width = area.dim_in_pixel().0 as f64 * 0.96;
    match area.estimate_text_size(title, &("sans-serif", preferred).into_text_style(area)) {
        Ok((w, _)) if w as f64 > width => (preferred * width / w as f64).max(10.0),
        _ => preferred,
    }
}

/// Write a PNG of error against time per frame (and against a work count when `work_label` is given), one
/// colour per try, the Pareto front as a black line, the pick ringed, the target's time as a dashed line.
pub fn tradeoff_plot(
    path: &Path,
    title: &str,
    error_label: &str,
    points: &[TradeoffPoint],
    target: Option<(&str, f64)>,
    work_label: Option<&str>,
) -> Result<()> {
    if points.is_empty() {
        return Err(anyhow!("nothing to plot"));
    }
    register_font();
    let err = |e: &dyn std::fmt::Display| anyhow!("cannot draw the plot: {e}");
    let mut series: Vec<&str> = Vec::new();
    for p in points {
        if !series.contains(&p.series.as_str()) {
            series.push(&p.series);
        }
    }
    let max_err = points.iter().map(|p| p.error).filter(|e| e.is_finite()).fold(0.0, f64::max).max(1e-9) * 1.1;
    // The panels' x axes: time per frame, and the work count when one is asked for.
    let mut panels: Vec<(&str, bool)> = vec![("time per frame (ms)", true)];
    if let Some(label) = work_label {
        panels.push((label, false));
    }
    let x_of = |p: &TradeoffPoint, time: bool| if time { p.ms } else { p.work.unwrap_or(0.0) };
    let size: (u32, u32) = (720 * panels.len() as u32, 520);
    let mut rgb = vec![0u8; (size.0 * size.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let root = root.titled(title, ("sans-serif", title_size(&root, title, 20.0))).map_err(|e| err(&e))?;
        let areas = root.split_evenly((1, panels.len()));
        let colors = [
            RGBColor(31, 119, 180),
            RGBColor(214, 39, 40),
            RGBColor(44, 160, 44),
            RGBColor(148, 103, 189),
            RGBColor(255, 127, 14),
            RGBColor(23, 190, 207),
        ];
        for (area, &(x_label, time)) in areas.iter().zip(&panels) {
            // A log axis: times and work counts span orders of magnitude (an unshadowed frame and a ray-traced
            // one); a zero (no such work) is drawn at the axis' left end.
            let xs = points.iter().map(|p| x_of(p, time)).chain(target.filter(|_| time).map(|t| t.1));
            let (lo, hi) = xs
                .filter(|x| *x > 0.0 && x.is_finite())
                .fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
            let (lo, hi) = if hi > 0.0 { (lo / 1.5, hi * 1.5) } else { (0.1, 10.0) };
            let x_of = |p: &TradeoffPoint| x_of(p, time).max(lo);
            let mut chart = ChartBuilder::on(area)
                .margin(14)
                .x_label_area_size(44)
                .y_label_area_size(74)
                .build_cartesian_2d((lo..hi).log_scale(), 0.0..max_err)
                .map_err(|e| err(&e))?;
            let x_desc = format!("{x_label}, log scale");
            // Compact labels: a log axis of work counts otherwise runs "4000000.05000000.0" together.
            let compact = |v: &f64| {
                let (n, suffix) = match v.abs() {
                    a if a >= 1e9 => (format!("{:.2}", v / 1e9), "G"),
                    a if a >= 1e6 => (format!("{:.2}", v / 1e6), "M"),
                    a if a >= 1e4 => (format!("{:.0}", v / 1e3), "k"),
                    a if a >= 10.0 => (format!("{v:.0}"), ""),
                    _ => (format!("{v:.2}"), ""),
                };
                let n = if n.contains('.') { n.trim_end_matches('0').trim_end_matches('.') } else { &n };
                format!("{n}{suffix}")
            };
            chart
                .configure_mesh()
                .x_desc(x_desc)
                .y_desc(error_label)
                .x_labels(6)
                .x_label_formatter(&|v| compact(v))
                .draw()
                .map_err(|e| err(&e))?;
            if let Some((name, ms)) = target.filter(|_| time) {
                chart
                    .draw_series(DashedLineSeries::new(vec![(ms, 0.0), (ms, max_err)], 8, 5, BLACK.stroke_width(1)))
                    .map_err(|e| err(&e))?
                    .label(format!("{name} (target)"))
                    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
            }
            let mut front: Vec<(f64, f64)> = points.iter().filter(|p| p.pareto).map(|p| (x_of(p), p.error)).collect();
            front.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
            if time && front.len() > 1 {
                chart
                    .draw_series(LineSeries::new(front, BLACK.stroke_width(2)))
                    .map_err(|e| err(&e))?
                    .label("Pareto front")
                    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
            }
            for (i, name) in series.iter().enumerate() {
                let color = colors[i % colors.len()];
                let pts: Vec<(f64, f64)> =
                    points.iter().filter(|p| p.series == *name).map(|p| (x_of(p), p.error)).collect();
                chart
                    .draw_series(pts.into_iter().map(|p| Circle::new(p, 4, color.filled())))
                    .map_err(|e| err(&e))?
                    .label(name.to_string())
                    .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
            }
            let picks: Vec<(f64, f64)> = points.iter().filter(|p| p.pick).map(|p| (x_of(p), p.error)).collect();
            if !picks.is_empty() {
                chart
                    .draw_series(picks.into_iter().map(|p| Circle::new(p, 9, BLACK.stroke_width(2))))
                    .map_err(|e| err(&e))?
                    .label("pick")
                    .legend(|(x, y)| Circle::new((x + 10, y), 6, BLACK.stroke_width(2)));
            }
            // Upper right: on a trade-off the slow and wrong corner, where no configuration worth having lies.
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(|e| err(&e))?;
        }
        root.present().map_err(|e| err(&e))?;
    }
    let image = image::RgbImage::from_raw(size.0, size.1, rgb).ok_or_else(|| anyhow!("plot buffer size"))?;
    image.save_with_format(path, image::ImageFormat::Png).map_err(|e| anyhow!("cannot write {}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_title_gets_a_smaller_font_that_fits_and_a_short_one_keeps_its_own() {
        register_font();
        let (w, h) = (720u32, 520u32);
        let mut rgb = vec![0u8; (w * h * 3) as usize];
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        assert_eq!(title_size(&root, "FLIP", 20.0), 20.0);
        let long = "FLIP against unshadowed + vpl-raytraced on sponza (8 lights, 160x90), time in wall-clock steps \
                    of the whole frame";
        let size = title_size(&root, long, 20.0);
        assert!((10.0..20.0).contains(&size), "{size}");
        let (width, _) = root.estimate_text_size(long, &("sans-serif", size).into_text_style(&root)).unwrap();
        assert!(width as f64 <= w as f64 * 0.97, "{width} px at {size} pt in {w} px");
    }
}
