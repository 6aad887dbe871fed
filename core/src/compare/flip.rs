//! FLIP (NVIDIA's ꟻLIP, LDR) on tone-mapped versions of the HDR images, through the `nv-flip` crate.

use super::image::{check_len, check_param, check_same_size, in_mask, is_finite_rgb, CompareError, Image};

/// FLIP's default observer: 67 pixels per degree (a 0.7 m wide 4K monitor seen from 0.7 m).
pub const DEFAULT_PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// Largest radiance fed to the tone curve (f16 max); keeps `inf` from turning into `inf/inf`.
const MAX_RADIANCE: f32 = 65504.0;

/// Narkowicz's ACES fit, as in `shaders/tonemap.wgsl`.
fn aces(x: f32) -> f32 {
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// The sRGB transfer function (what the `Rgba8UnormSrgb` output target applies on store).
fn srgb_encode(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

fn to_display(radiance: f32, exposure: f32) -> u8 {
    let x = radiance * exposure;
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, MAX_RADIANCE) };
    (srgb_encode(aces(x)) * 255.0 + 0.5) as u8
}

/// The image as the renderer's ACES tone mapping would display it: `radiance · exposure`, Narkowicz's ACES fit
/// `x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)` clamped to `[0,1]`, sRGB encoded, rounded to 8 bits. NaN maps
/// to black and `+inf` to white. Alpha is dropped.
pub fn tonemap_for_flip(image: &Image, exposure: f32) -> image::RgbImage {
    let data = image.pixels.iter().flat_map(|p| [0, 1, 2].map(|c| to_display(p[c], exposure))).collect();
    image::RgbImage::from_raw(image.width, image.height, data).unwrap_or_else(|| image::RgbImage::new(0, 0))
}

/// The per-pixel FLIP error in `[0,1]` of `technique` against `reference`, both tone mapped with
/// [`tonemap_for_flip`], row-major, one value per pixel.
///
/// FLIP filters over a neighbourhood, so pixels outside `mask` are first set to the reference's tone-mapped
/// value in the technique's image: differences outside the mask then cannot leak into compared pixels. Pixels
/// where either image has a non-finite channel get an error of 1.
pub fn flip_error_map(
    technique: &Image,
    reference: &Image,
    mask: Option<&[bool]>,
    exposure: f32,
    pixels_per_degree: f32,
) -> Result<Vec<f32>, CompareError> {
    check_same_size("technique image", technique, reference)?;
    check_len("mask", mask, reference.len())?;
    check_param("exposure", exposure)?;
    if !(pixels_per_degree.is_finite() && pixels_per_degree > 0.0) {
        return Err(CompareError::InvalidParameter { what: "pixels per degree", value: pixels_per_degree });
    }
    if reference.is_empty() {
        return Ok(Vec::new());
    }
    let reference_ldr = tonemap_for_flip(reference, exposure);
    let mut technique_ldr = tonemap_for_flip(technique, exposure);
    for (i, (t, r)) in technique_ldr.chunks_exact_mut(3).zip(reference_ldr.chunks_exact(3)).enumerate() {
        if !in_mask(mask, i) {
            t.copy_from_slice(r);
        }
    }
    let (w, h) = (reference.width, reference.height);
    let error = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(w, h, &reference_ldr),
        nv_flip::FlipImageRgb8::with_data(w, h, &technique_ldr),
        pixels_per_degree,
    );
    let mut map = error.to_vec();
    for (i, e) in map.iter_mut().enumerate() {
        if !(e.is_finite() && is_finite_rgb(technique.pixels[i]) && is_finite_rgb(reference.pixels[i])) {
            *e = 1.0;
        }
    }
    Ok(map)
}
