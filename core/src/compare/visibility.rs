//! Per-pixel visibility (shadow) factors from a shadowed and an unshadowed render.

use super::image::{check_same_size, is_finite_rgb, luminance, CompareError, Image};

/// Unshadowed direct light below this share of the unshadowed luminance counts as none (`V = 1`).
const RELATIVE_EPSILON: f32 = 1e-2;
/// ... and below this absolute luminance, which covers `0/0`.
const ABSOLUTE_EPSILON: f32 = 1e-6;

/// The visibility factor of every pixel, row-major, in `[0,1]` (1 = fully lit):
/// `V = clamp((Y_shadowed − Y_ambient) / (Y_unshadowed − Y_ambient), 0, 1)` with `Y` the luminance.
///
/// `unshadowed` is the same frame rendered with every light's visibility forced to 1, `ambient` the frame with
/// no lights (ambient and emission only); without it the ambient term is taken as 0, which overestimates `V`
/// in shadows. Where the unshadowed direct light `Y_unshadowed − Y_ambient` is at most
/// `1% · Y_unshadowed + 1e-6` (no light reaches the pixel, `0/0` included), `V = 1`. A pixel with a non-finite
/// channel in any input gets `V = NaN`, which [`super::metrics::compare`] scores as a visibility error of 1.
pub fn visibility_image(
    shadowed: &Image,
    unshadowed: &Image,
    ambient: Option<&Image>,
) -> Result<Vec<f32>, CompareError> {
    check_same_size("shadowed image", shadowed, unshadowed)?;
    if let Some(a) = ambient {
        check_same_size("ambient image", a, unshadowed)?;
    }
    Ok((0..unshadowed.len())
        .map(|i| {
            let (s, u) = (shadowed.pixels[i], unshadowed.pixels[i]);
            let a = ambient.map_or([0.0; 4], |a| a.pixels[i]);
            if !(is_finite_rgb(s) && is_finite_rgb(u) && is_finite_rgb(a)) {
                return f32::NAN;
            }
            let (ys, yu, ya) = (luminance(s), luminance(u), luminance(a));
            let direct = yu - ya;
            if direct <= RELATIVE_EPSILON * yu.abs() + ABSOLUTE_EPSILON {
                return 1.0;
            }
            ((ys - ya) / direct).clamp(0.0, 1.0)
        })
        .collect())
}
