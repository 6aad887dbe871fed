//! Comparing a technique's image with the reference: error metrics, difference images, visibility factors.
//!
//! Pure CPU functions over linear HDR radiance images ([`Image`], e.g. from `Renderer::read_hdr`); nothing here
//! touches the GPU. The role of Falcor's `ErrorMeasurePass`, plus the metrics of the many-light shadow papers
//! (INSM's shadow intensity error, LightCluster's difference images) and NVIDIA's FLIP.
//!
//! # Pixels that count
//!
//! Every metric is computed over the same set of pixels `P`: those whose entry in the caller's mask is `true`
//! (valid, i.e. geometry was drawn there), or every pixel when the mask is `None`. The mask is a row-major
//! `&[bool]` of `width * height` entries; the renderer's background colour can occur on geometry, so the
//! comparison never guesses it from colours. `N = |P|`. An empty `P` gives `pixels: 0` and zero errors.
//!
//! # Definitions
//!
//! `T` is the technique's image, `R` the reference, `c` one of the three colour channels (alpha is ignored),
//! `d_c(p) = T_c(p) − R_c(p)`, and `Y = 0.2126·r + 0.7152·g + 0.0722·b` (Rec. 709 luminance of linear RGB).
//!
//! - `mse` `= 1/(3N) · Σ_p Σ_c d_c(p)²`, in linear radiance (not tone mapped); `rmse = √mse`.
//! - `mean_abs` `= 1/(3N) · Σ_p Σ_c abs(d_c(p))`.
//! - `peak_luminance` `= max(max_p Y_R(p), 1e-3)` over the finite reference pixels of `P`.
//! - `psnr_db` `= 10 · log10(peak_luminance² / mse)`; `None` (JSON `null`) when `mse = 0` (identical images).
//! - `share_over_threshold` `= 1/N · #{p : abs(Y_T(p) − Y_R(p)) > threshold · max(Y_R(p), 1e-3)}`: a relative
//!   luminance error with a floor, so near-black reference pixels need an absolute difference of
//!   `threshold · 1e-3` radiance to count.
//! - `shadow_intensity_error` `= 1/N · Σ_p abs(V_T(p) − V_R(p))`, INSM's (Wang et al. 2016) "average shadow
//!   intensity error per valid image pixel", with `V` the visibility factor of [`visibility_image`]; only when
//!   [`CompareOptions::visibility`] is given. Like the paper's, it is a relaxed measure: errors of different
//!   lights at one pixel may cancel.
//! - `shadow_intensity_bias` `= 1/N · Σ_p (V_T(p) − V_R(p))`: > 0 when the technique leaks light (too bright),
//!   < 0 when it over-shadows (non-finite factors are left out of the sum, still counted in `N`).
//! - `flip_mean`: the mean over `P` of the per-pixel FLIP error (NVIDIA's ꟻLIP, LDR variant, in `[0,1]`,
//!   [`flip_error_map`]) between [`tonemap_for_flip`] of both images; only when [`CompareOptions::flip`].
//!
//! The visibility factor of a pixel is `V = (Y_shadowed − Y_ambient) / (Y_unshadowed − Y_ambient)` clamped to
//! `[0,1]`: the luminance-weighted share of the direct light that reaches the pixel. `Y_ambient` (ambient and
//! emission only) is subtracted because ambient light is never shadowed. Where the unshadowed direct light is
//! negligible (`≤ 1% of Y_unshadowed + 1e-6`, which covers `0/0`) `V = 1` (lit): shadowing cannot change such
//! a pixel noticeably, and the f16 HDR target cannot resolve the ratio there.
//!
//! FLIP sees what a viewer sees: both images go through the renderer's ACES tone mapping at
//! [`CompareOptions::exposure`] and sRGB encoding to 8 bits ([`tonemap_for_flip`]). Because FLIP filters over a
//! neighbourhood, the technique's pixels outside the mask are replaced by the reference's before it runs.
//!
//! # Difference images
//!
//! [`difference_image`] colours the per-pixel luminance difference `Y_T − Y_R` times a gain (1, 5, 10, ...):
//! [`DiffMode::Absolute`] maps `abs(difference) · gain` through [`colormap`] (dark blue = none, cyan, green,
//! yellow, red ≥ 1, as LightCluster's figures), [`DiffMode::Signed`] draws red where the technique is too
//! bright and green where it is too dark, black where equal (as INSM's figures). Pixels outside the mask are
//! dark grey. [`visibility_difference_image`] does the same for `V_T − V_R`.
//!
//! # Example
//!
//! ```
//! use shadowlab_core::compare::{compare, difference_image, CompareOptions, DiffMode, Image};
//!
//! let reference = Image::filled(16, 16, [0.5, 0.5, 0.5, 1.0]);
//! let mut technique = reference.clone();
//! technique.pixels[0] = [0.6, 0.6, 0.6, 1.0];
//! let mask = vec![true; 16 * 16]; // in the app: where geometry was drawn
//! let metrics = compare(&technique, &reference, Some(&mask), &CompareOptions::default())?;
//! assert_eq!(metrics.pixels, 256);
//! assert!(metrics.psnr_db.unwrap() > 30.0);
//! let picture = difference_image(&technique, &reference, Some(&mask), DiffMode::Signed, 5.0)?;
//! assert_eq!(picture.get_pixel(0, 0).0[0], 128); // red: too bright by 0.1, times 5
//! # Ok::<(), shadowlab_core::compare::CompareError>(())
//! ```
//!
//! # Broken pixels
//!
//! A pixel of `P` with a non-finite (NaN, ±inf) colour channel in `T` or `R` never panics and never poisons the
//! sums: it is counted in `non_finite` and scored as a maximal error — an absolute error of `peak_luminance`
//! in each channel for `mse`/`mean_abs` (so it costs as much as a pixel that is entirely wrong at the image's
//! brightest level), over the threshold, a FLIP error of 1, and a visibility error of 1 (`V` is NaN there).
//! Difference images draw such pixels magenta, a colour outside [`colormap`].

mod diff;
mod flip;
mod image;
mod metrics;
mod visibility;

pub use diff::{colormap, difference_image, visibility_difference_image, DiffMode};
pub use flip::{flip_error_map, tonemap_for_flip, DEFAULT_PIXELS_PER_DEGREE};
pub use image::{luminance, CompareError, Image};
pub use metrics::{compare, CompareOptions, Metrics, Visibility};
pub use visibility::visibility_image;
