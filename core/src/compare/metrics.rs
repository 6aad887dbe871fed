//! The scalar metrics of one technique image against the reference (definitions in the module docs).

use serde::Serialize;

use super::flip;
use super::image::{check_len, check_param, check_same_size, in_mask, is_finite_rgb, luminance, CompareError, Image};

/// Luminance floor of the PSNR peak and of the relative threshold (radiance units).
const LUMINANCE_FLOOR: f64 = 1e-3;

/// Visibility factors of the technique and of the reference, from [`super::visibility::visibility_image`], one per pixel.
#[derive(Clone, Copy, Debug)]
pub struct Visibility<'a> {
    pub technique: &'a [f32],
    pub reference: &'a [f32],
}

/// What [`compare`] computes beyond the always-present radiance metrics.
#[derive(Clone, Copy, Debug)]
pub struct CompareOptions<'a> {
    /// Relative luminance error above which a pixel counts in `share_over_threshold` (0.05 = 5%).
    pub threshold: f32,
    /// Compute `flip_mean` (about 0.15 s for a 640x360 image, one core).
    pub flip: bool,
    /// Exposure applied before the ACES tone mapping of the FLIP inputs; use the render's exposure.
    pub exposure: f32,
    /// FLIP's observer model: pixels per degree of visual angle (67 ≈ a 0.7 m wide 4K monitor at 0.7 m).
    pub pixels_per_degree: f32,
    /// Visibility factors for `shadow_intensity_error`; `None` leaves it out.
    pub visibility: Option<Visibility<'a>>,
}

impl Default for CompareOptions<'_> {
    fn default() -> Self {
        CompareOptions {
            threshold: 0.05,
            flip: true,
            exposure: 1.0,
            pixels_per_degree: super::flip::DEFAULT_PIXELS_PER_DEGREE,
            visibility: None,
        }
    }
}

/// Error metrics of a technique image against the reference over the compared pixels (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Metrics {
    /// Compared pixels `N` (the mask's `true` entries).
    pub pixels: usize,
    /// Compared pixels with a NaN or infinite channel in either image, scored as maximal errors.
    pub non_finite: usize,
    pub mse: f64,
    pub rmse: f64,
    /// `None` (JSON `null`) when the images are identical over the compared pixels.
    pub psnr_db: Option<f64>,
    /// The PSNR peak: the brightest reference luminance, at least 1e-3.
    pub peak_luminance: f64,
    pub mean_abs: f64,
    /// INSM's average shadow intensity error, in `[0,1]`; `None` without visibility factors.
    pub shadow_intensity_error: Option<f64>,
    /// Mean signed visibility difference, in `[-1,1]`: > 0 light leaks, < 0 over-shadowing.
    pub shadow_intensity_bias: Option<f64>,
    /// Mean FLIP error in `[0,1]`; `None` when not asked for.
    pub flip_mean: Option<f64>,
    /// Share of compared pixels whose relative luminance error exceeds `threshold`, in `[0,1]`.
    pub share_over_threshold: f64,
    pub threshold: f64,
}

/// Compares `technique` with `reference` over the pixels where `mask` is `true` (all pixels when `None`).
pub fn compare(
    technique: &Image,
    reference: &Image,
    mask: Option<&[bool]>,
    options: &CompareOptions,
) -> Result<Metrics, CompareError> {
    check_same_size("technique image", technique, reference)?;
    let n = reference.len();
    check_len("mask", mask, n)?;
    check_param("threshold", options.threshold)?;
    check_param("exposure", options.exposure)?;
    if let Some(v) = &options.visibility {
        check_len("technique visibility", Some(v.technique), n)?;
        check_len("reference visibility", Some(v.reference), n)?;
    }

    let compared = || (0..n).filter(|&i| in_mask(mask, i));
    let peak = compared()
        .map(|i| reference.pixels[i])
        .filter(|&p| is_finite_rgb(p))
        .map(|p| luminance(p) as f64)
        .fold(LUMINANCE_FLOOR, f64::max);
    let threshold = options.threshold as f64;

    let (mut pixels, mut non_finite, mut over) = (0usize, 0usize, 0usize);
    let (mut sum_sq, mut sum_abs) = (0.0f64, 0.0f64);
    for i in compared() {
        let (t, r) = (technique.pixels[i], reference.pixels[i]);
        pixels += 1;
        if !(is_finite_rgb(t) && is_finite_rgb(r)) {
            non_finite += 1;
            over += 1;
            sum_sq += 3.0 * peak * peak;
            sum_abs += 3.0 * peak;
            continue;
        }
        for c in 0..3 {
            let d = t[c] as f64 - r[c] as f64;
            sum_sq += d * d;
            sum_abs += d.abs();
        }
        let (yt, yr) = (luminance(t) as f64, luminance(r) as f64);
        if (yt - yr).abs() > threshold * yr.max(LUMINANCE_FLOOR) {
            over += 1;
        }
    }
    let per = |sum: f64| if pixels == 0 { 0.0 } else { sum / (3 * pixels) as f64 };
    let mse = per(sum_sq);
    let psnr_db = (mse > 0.0).then(|| 10.0 * (peak * peak / mse).log10());

    let (shadow_intensity_error, shadow_intensity_bias) = match &options.visibility {
        Some(v) => {
            let (abs, signed) = visibility_errors(v, compared());
            (Some(abs), Some(signed))
        }
        None => (None, None),
    };

    let flip_mean = if options.flip {
        let mean = if pixels == 0 {
            0.0
        } else {
            let map = flip::flip_error_map(technique, reference, mask, options.exposure, options.pixels_per_degree)?;
            compared().map(|i| map[i] as f64).sum::<f64>() / pixels as f64
        };
        Some(mean)
    } else {
        None
    };

    Ok(Metrics {
        pixels,
        non_finite,
        mse,
        rmse: mse.sqrt(),
        psnr_db,
        peak_luminance: peak,
        mean_abs: per(sum_abs),
        shadow_intensity_error,
        shadow_intensity_bias,
        flip_mean,
        share_over_threshold: if pixels == 0 { 0.0 } else { over as f64 / pixels as f64 },
        threshold,
    })
}

/// Mean absolute and mean signed visibility difference over `pixels`; a NaN factor is an error of 1.
fn visibility_errors(v: &Visibility, pixels: impl Iterator<Item = usize>) -> (f64, f64) {
    let (mut count, mut abs, mut signed) = (0usize, 0.0f64, 0.0f64);
    for i in pixels {
        count += 1;
        let d = v.technique[i] as f64 - v.reference[i] as f64;
        if d.is_finite() {
            abs += d.abs();
            signed += d;
        } else {
            abs += 1.0;
        }
    }
    if count == 0 {
        (0.0, 0.0)
    } else {
        (abs / count as f64, signed / count as f64)
    }
}
