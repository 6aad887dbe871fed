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
        let root = root.titled(title, ("sans-serif", 22)).map_err(|e| err(&e))?;
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
