//! Difference images: what the error looks like, as RGBA8.

use image::{Rgba, RgbaImage};

use super::image::{check_len, check_param, check_same_size, in_mask, is_finite_rgb, luminance, CompareError, Image};

/// Pixels outside the mask (background).
const BACKGROUND: [u8; 3] = [40, 40, 40];
/// Pixels with a NaN or infinite value: not a colour of [`colormap`] or of the signed map.
const NON_FINITE: [u8; 3] = [255, 0, 255];

/// How a per-pixel difference becomes a colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DiffMode {
    /// `|difference| · gain` through [`colormap`]: dark blue (none) → cyan → green → yellow → red (≥ 1), as in
    /// LightCluster's difference images.
    Absolute,
    /// As in the INSM paper: red where the technique is too bright, green where too dark, black where equal;
    /// channel value `255 · min(1, |difference| · gain)`.
    Signed,
}

/// Colour stops of [`colormap`], evenly spaced over `[0,1]`.
const STOPS: [[f32; 3]; 5] = [
    [0.0, 0.0, 128.0],   // dark blue
    [0.0, 255.0, 255.0], // cyan
    [0.0, 255.0, 0.0],   // green
    [255.0, 255.0, 0.0], // yellow
    [255.0, 0.0, 0.0],   // red
];

/// The error colour map for `t` in `[0,1]` (clamped; NaN counts as 1): dark blue at 0, cyan at 0.25, green at
/// 0.5, yellow at 0.75, red at 1, linear in between; the hue falls monotonically from blue to red.
pub fn colormap(t: f32) -> [u8; 3] {
    let t = if t.is_nan() { 1.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (STOPS.len() - 1) as f32;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f32;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    [0, 1, 2].map(|c| (a[c] + (b[c] - a[c]) * f).round() as u8)
}

/// The colour of a signed difference `d` (already multiplied by the gain).
fn signed_colour(d: f32) -> [u8; 3] {
    let v = (d.abs().min(1.0) * 255.0).round() as u8;
    if d > 0.0 {
        [v, 0, 0]
    } else {
        [0, v, 0]
    }
}

/// Colours one difference value per pixel; `None` marks a non-finite pixel.
fn render(
    width: u32,
    height: u32,
    mask: Option<&[bool]>,
    mode: DiffMode,
    gain: f32,
    difference: impl Fn(usize) -> Option<f32>,
) -> RgbaImage {
    let mut out = RgbaImage::new(width, height);
    for (i, pixel) in out.pixels_mut().enumerate() {
        let rgb = if !in_mask(mask, i) {
            BACKGROUND
        } else {
            match difference(i) {
                Some(d) if d.is_finite() => match mode {
                    DiffMode::Absolute => colormap(d.abs() * gain),
                    DiffMode::Signed => signed_colour(d * gain),
                },
                _ => NON_FINITE,
            }
        };
        *pixel = Rgba([rgb[0], rgb[1], rgb[2], 255]);
    }
    out
}

/// The difference image of `technique` against `reference`: per pixel the luminance difference
/// `Y_T − Y_R` (linear radiance), scaled by `gain` (1, 5, 10, ...) and coloured by `mode`. Pixels outside
/// `mask` are dark grey, pixels with a non-finite channel magenta.
pub fn difference_image(
    technique: &Image,
    reference: &Image,
    mask: Option<&[bool]>,
    mode: DiffMode,
    gain: f32,
) -> Result<RgbaImage, CompareError> {
    check_same_size("technique image", technique, reference)?;
    check_len("mask", mask, reference.len())?;
    check_param("gain", gain)?;
    Ok(render(reference.width, reference.height, mask, mode, gain, |i| {
        let (t, r) = (technique.pixels[i], reference.pixels[i]);
        (is_finite_rgb(t) && is_finite_rgb(r)).then(|| luminance(t) - luminance(r))
    }))
}

/// The difference image of visibility factors (from [`super::visibility::visibility_image`]): per pixel `V_T − V_R`,
/// scaled by `gain` and coloured by `mode` as in [`difference_image`] (red = the technique lets more light
/// through in signed mode). NaN factors are magenta.
pub fn visibility_difference_image(
    v_technique: &[f32],
    v_reference: &[f32],
    width: u32,
    height: u32,
    mask: Option<&[bool]>,
    mode: DiffMode,
    gain: f32,
) -> Result<RgbaImage, CompareError> {
    let n = width as usize * height as usize;
    check_len("technique visibility", Some(v_technique), n)?;
    check_len("reference visibility", Some(v_reference), n)?;
    check_len("mask", mask, n)?;
    check_param("gain", gain)?;
    Ok(render(width, height, mask, mode, gain, |i| Some(v_technique[i] - v_reference[i])))
}
