//! The comparison core: metrics by hand, masks, broken pixels, difference images, visibility factors, FLIP.

use shadowlab_core::compare::{
    colormap, compare, difference_image, flip_error_map, tonemap_for_flip, visibility_difference_image,
    visibility_image, CompareError, CompareOptions, DiffMode, Image, Visibility,
};

const W: u32 = 32;
const H: u32 = 24;

/// A smooth, coloured test image with some structure (values up to ~1.2).
fn scene() -> Image {
    let mut pixels = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let u = x as f32 / W as f32;
            let v = y as f32 / H as f32;
            let stripe = if (x / 4 + y / 4) % 2 == 0 { 0.2 } else { 0.0 };
            pixels.push([0.2 + u + stripe, 0.3 + 0.5 * v, 0.4 + 0.3 * u * v, 1.0]);
        }
    }
    Image::new(W, H, pixels).unwrap()
}

fn map(image: &Image, f: impl Fn(usize, [f32; 4]) -> [f32; 4]) -> Image {
    Image { pixels: image.pixels.iter().enumerate().map(|(i, &p)| f(i, p)).collect(), ..image.clone() }
}

fn no_flip() -> CompareOptions<'static> {
    CompareOptions { flip: false, ..Default::default() }
}

fn luminance(p: [f32; 4]) -> f64 {
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

#[test]
fn identical_images_have_no_error() {
    let r = scene();
    let m = compare(&r, &r, None, &CompareOptions::default()).unwrap();
    assert_eq!(m.pixels, (W * H) as usize);
    assert_eq!(m.non_finite, 0);
    assert_eq!((m.mse, m.rmse, m.mean_abs, m.share_over_threshold), (0.0, 0.0, 0.0, 0.0));
    assert_eq!(m.psnr_db, None);
    assert!(m.flip_mean.unwrap() < 1e-6, "flip {:?}", m.flip_mean);
    assert_eq!(m.shadow_intensity_error, None);
    // PSNR of identical images is JSON null, every other number finite.
    let json = serde_json::to_value(&m).unwrap();
    assert!(json["psnr_db"].is_null());
    assert_eq!(json["pixels"], (W * H) as u64);
}

#[test]
fn constant_offset_gives_hand_computed_errors() {
    // Reference: grey 0.5 with one pixel at 2.0 (luminance 2.0 = the peak). Technique: +0.1 on every channel.
    let mut r = Image::filled(4, 2, [0.5, 0.5, 0.5, 1.0]);
    r.pixels[3] = [2.0, 2.0, 2.0, 1.0];
    let t = map(&r, |_, p| [p[0] + 0.1, p[1] + 0.1, p[2] + 0.1, p[3]]);
    let m = compare(&t, &r, None, &CompareOptions { threshold: 0.1, ..no_flip() }).unwrap();
    let d = 0.1f32 as f64; // the f32 offset as stored: 0.5 + 0.1 and 2.0 + 0.1 in f32
    let d0 = (0.5f32 + 0.1f32) as f64 - 0.5;
    let d1 = (2.0f32 + 0.1f32) as f64 - 2.0;
    let mse = (7.0 * d0 * d0 + d1 * d1) / 8.0;
    assert!((m.mse - mse).abs() < 1e-12, "{} vs {}", m.mse, mse);
    assert!((m.mse - d * d).abs() < 1e-7);
    assert!((m.rmse - mse.sqrt()).abs() < 1e-12);
    assert!((m.mean_abs - (7.0 * d0 + d1) / 8.0).abs() < 1e-12);
    assert!((m.peak_luminance - 2.0).abs() < 1e-6);
    let psnr = 10.0 * (m.peak_luminance * m.peak_luminance / mse).log10();
    assert!((m.psnr_db.unwrap() - psnr).abs() < 1e-9);
    // 10·log10(4 / 0.01) = 26.02 dB.
    assert!((m.psnr_db.unwrap() - 26.0206).abs() < 1e-3, "{:?}", m.psnr_db);
    // Relative luminance errors: 0.1/0.5 = 20% over the 10% threshold on grey, 0.1/2 = 5% under it on the peak.
    assert!((m.share_over_threshold - 7.0 / 8.0).abs() < 1e-12);
    assert_eq!(m.threshold, 0.1f32 as f64);
}

#[test]
fn masked_out_pixels_do_not_count() {
    let r = scene();
    let t = map(&r, |i, p| if i % 3 == 0 { [p[0] * 1.1, p[1], p[2] * 0.9, p[3]] } else { p });
    let mut mask = vec![true; r.len()];
    for y in 0..H as usize {
        for x in 0..6 {
            mask[y * W as usize + x] = false;
        }
    }
    let options = CompareOptions { threshold: 0.02, ..Default::default() };
    let before = compare(&t, &r, Some(&mask), &options).unwrap();
    assert_eq!(before.pixels, mask.iter().filter(|&&m| m).count());
    // Wreck masked-out pixels of the technique (NaN included): nothing changes, FLIP included.
    let t2 = map(&t, |i, p| if mask[i] { p } else { [f32::NAN, 100.0, -3.0, 0.0] });
    let after = compare(&t2, &r, Some(&mask), &options).unwrap();
    assert_eq!(before, after);
    assert!(before.mse > 0.0 && before.flip_mean.unwrap() > 0.0);
    // Masked-out reference pixels do not count either (FLIP aside: its filters see the neighbourhood).
    let r2 = map(&r, |i, p| if mask[i] { p } else { [0.0, 0.0, 0.0, 1.0] });
    let options = CompareOptions { flip: false, ..options };
    assert_eq!(compare(&t, &r, Some(&mask), &options).unwrap(), compare(&t2, &r2, Some(&mask), &options).unwrap());

    // The same pixels do count without the mask.
    let all = compare(&t2, &r2, None, &options).unwrap();
    assert_eq!(all.pixels, r.len());
    assert!(all.mse > before.mse);
}

#[test]
fn empty_mask_gives_zeros() {
    let r = scene();
    let t = map(&r, |_, p| [p[0] + 1.0, p[1], p[2], p[3]]);
    let mask = vec![false; r.len()];
    let v = vec![0.5; r.len()];
    let options =
        CompareOptions { visibility: Some(Visibility { technique: &v, reference: &v }), ..Default::default() };
    let m = compare(&t, &r, Some(&mask), &options).unwrap();
    assert_eq!(m.pixels, 0);
    assert_eq!((m.mse, m.rmse, m.mean_abs, m.share_over_threshold), (0.0, 0.0, 0.0, 0.0));
    assert_eq!((m.psnr_db, m.flip_mean, m.shadow_intensity_error), (None, Some(0.0), Some(0.0)));
    // And a 0x0 image.
    let e = Image::filled(0, 0, [0.0; 4]);
    assert_eq!(compare(&e, &e, None, &CompareOptions::default()).unwrap().pixels, 0);
}

#[test]
fn nan_and_inf_pixels_are_maximal_errors() {
    let r = Image::filled(4, 4, [0.5, 0.5, 0.5, 1.0]);
    let mut t = r.clone();
    t.pixels[5] = [f32::NAN, 0.5, 0.5, 1.0];
    t.pixels[6] = [0.5, f32::INFINITY, 0.5, 1.0];
    let m = compare(&t, &r, None, &CompareOptions::default()).unwrap();
    assert_eq!(m.non_finite, 2);
    // Each broken pixel costs the peak (0.5) in every channel.
    let peak = luminance([0.5, 0.5, 0.5, 1.0]);
    assert!((m.peak_luminance - peak).abs() < 1e-7);
    assert!((m.mse - 2.0 * peak * peak / 16.0).abs() < 1e-9);
    assert!((m.mean_abs - 2.0 * peak / 16.0).abs() < 1e-9);
    assert!((m.psnr_db.unwrap() - 10.0 * 8f64.log10()).abs() < 1e-6);
    assert_eq!(m.share_over_threshold, 2.0 / 16.0);
    let flip = m.flip_mean.unwrap();
    assert!(flip >= 2.0 / 16.0 && flip.is_finite(), "{flip}");
    serde_json::to_string(&m).unwrap();

    // A broken reference pixel too, and broken pixels in the difference images.
    let mut r2 = r.clone();
    r2.pixels[0] = [f32::NEG_INFINITY, 0.0, 0.0, 1.0];
    assert_eq!(compare(&t, &r2, None, &CompareOptions::default()).unwrap().non_finite, 3);
    for mode in [DiffMode::Absolute, DiffMode::Signed] {
        let d = difference_image(&t, &r2, None, mode, 5.0).unwrap();
        assert_eq!(d.get_pixel(1, 1).0, [255, 0, 255, 255]);
        assert_eq!(d.get_pixel(0, 0).0, [255, 0, 255, 255]);
    }
    // Tone mapping for FLIP: NaN is black, inf white.
    let ldr = tonemap_for_flip(&t, 1.0);
    assert_eq!(ldr.get_pixel(1, 1).0[0], 0);
    assert_eq!(ldr.get_pixel(2, 1).0[1], 255);
}

#[test]
fn size_mismatches_are_typed_errors() {
    let r = scene();
    let small = Image::filled(W - 1, H, [0.0; 4]);
    let err = compare(&small, &r, None, &no_flip()).unwrap_err();
    assert!(
        matches!(err, CompareError::SizeMismatch { found_w, expected_w, .. } if found_w == W - 1 && expected_w == W)
    );
    assert!(err.to_string().contains("31x24"), "{err}");
    assert!(matches!(
        difference_image(&small, &r, None, DiffMode::Absolute, 1.0),
        Err(CompareError::SizeMismatch { .. })
    ));
    assert!(matches!(visibility_image(&small, &r, None), Err(CompareError::SizeMismatch { .. })));
    assert!(matches!(flip_error_map(&small, &r, None, 1.0, 67.0), Err(CompareError::SizeMismatch { .. })));

    let short_mask = vec![true; 10];
    assert!(matches!(compare(&r, &r, Some(&short_mask), &no_flip()), Err(CompareError::Length { found: 10, .. })));
    let broken = Image { width: W, height: H, pixels: vec![[0.0; 4]; 5] };
    assert!(matches!(compare(&broken, &r, None, &no_flip()), Err(CompareError::PixelCount { found: 5, .. })));
    assert!(Image::new(2, 2, vec![[0.0; 4]; 3]).is_err());
    let v = vec![1.0; 7];
    let options = CompareOptions { visibility: Some(Visibility { technique: &v, reference: &v }), ..no_flip() };
    assert!(matches!(compare(&r, &r, None, &options), Err(CompareError::Length { .. })));
    assert!(matches!(
        visibility_difference_image(&v, &v, W, H, None, DiffMode::Signed, 1.0),
        Err(CompareError::Length { .. })
    ));
    let bad = CompareOptions { threshold: f32::NAN, ..no_flip() };
    assert!(matches!(compare(&r, &r, None, &bad), Err(CompareError::InvalidParameter { .. })));
    assert!(matches!(
        difference_image(&r, &r, None, DiffMode::Absolute, -1.0),
        Err(CompareError::InvalidParameter { .. })
    ));
}

/// Hue in degrees of an RGB colour (0 = red, 120 = green, 240 = blue).
fn hue(c: [u8; 3]) -> f32 {
    let [r, g, b] = c.map(|v| v as f32);
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    assert!(max > min, "grey has no hue: {c:?}");
    let h = if max == r {
        60.0 * ((g - b) / (max - min))
    } else if max == g {
        60.0 * ((b - r) / (max - min) + 2.0)
    } else {
        60.0 * ((r - g) / (max - min) + 4.0)
    };
    h.rem_euclid(360.0)
}

#[test]
fn colormap_runs_from_dark_blue_to_red() {
    assert_eq!(colormap(0.0), [0, 0, 128]);
    assert_eq!(colormap(1.0), [255, 0, 0]);
    assert_eq!(colormap(0.25), [0, 255, 255]);
    assert_eq!(colormap(0.5), [0, 255, 0]);
    assert_eq!(colormap(0.75), [255, 255, 0]);
    assert_eq!(colormap(-3.0), colormap(0.0));
    assert_eq!(colormap(7.0), colormap(1.0));
    assert_eq!(colormap(f32::NAN), colormap(1.0));
    let mut previous = 360.0;
    for i in 0..=1000 {
        let h = hue(colormap(i as f32 / 1000.0));
        assert!(h <= previous + 1e-3, "hue rises at t = {}: {previous} -> {h}", i as f32 / 1000.0);
        previous = h;
    }
    assert_eq!(previous, 0.0);
}

#[test]
fn absolute_difference_image_uses_the_colormap_and_grey_background() {
    let r = Image::filled(3, 1, [0.5, 0.5, 0.5, 1.0]);
    let mut t = r.clone();
    t.pixels[1] = [0.6, 0.6, 0.6, 1.0]; // luminance difference 0.1
    t.pixels[2] = [9.0, 9.0, 9.0, 1.0];
    let mask = [true, true, false];
    let d = difference_image(&t, &r, Some(&mask), DiffMode::Absolute, 5.0).unwrap();
    assert_eq!((d.width(), d.height()), (3, 1));
    assert_eq!(d.get_pixel(0, 0).0, [0, 0, 128, 255]);
    let [r5, g5, b5] = colormap((0.6f32 - 0.5) * 5.0);
    assert_eq!(d.get_pixel(1, 0).0, [r5, g5, b5, 255]);
    assert_eq!(d.get_pixel(2, 0).0, [40, 40, 40, 255]);
    // Gain 10 saturates it at red.
    let d = difference_image(&t, &r, None, DiffMode::Absolute, 10.0).unwrap();
    assert_eq!(d.get_pixel(1, 0).0, [255, 0, 0, 255]);
}

#[test]
fn signed_difference_image_is_red_when_brighter_green_when_darker() {
    let r = Image::filled(3, 1, [0.5, 0.5, 0.5, 1.0]);
    let t = Image::new(3, 1, vec![[0.6, 0.6, 0.6, 1.0], [0.4, 0.4, 0.4, 1.0], [0.5, 0.5, 0.5, 1.0]]).unwrap();
    let d = difference_image(&t, &r, None, DiffMode::Signed, 5.0).unwrap();
    let [too_bright, too_dark, equal] = [0, 1, 2].map(|x| d.get_pixel(x, 0).0);
    assert!(too_bright[0] > 120 && too_bright[1] == 0 && too_bright[2] == 0, "{too_bright:?}");
    assert!(too_dark[1] > 120 && too_dark[0] == 0 && too_dark[2] == 0, "{too_dark:?}");
    assert_eq!(equal, [0, 0, 0, 255]);
    // |0.1| · 5 = 0.5 of full scale.
    assert!((too_bright[0] as i32 - 128).abs() <= 1);
    // Gain 1 is dimmer than gain 10.
    let d1 = difference_image(&t, &r, None, DiffMode::Signed, 1.0).unwrap();
    let d10 = difference_image(&t, &r, None, DiffMode::Signed, 10.0).unwrap();
    assert!(d1.get_pixel(0, 0).0[0] < d10.get_pixel(0, 0).0[0]);
    assert_eq!(d10.get_pixel(1, 0).0, [0, 255, 0, 255]);
}

#[test]
fn visibility_ratio() {
    let unshadowed = Image::new(3, 1, vec![[0.8, 0.6, 0.4, 1.0], [0.0; 4], [1.0, 1.0, 1.0, 1.0]]).unwrap();
    let shadowed = map(&unshadowed, |_, p| [p[0] * 0.5, p[1] * 0.5, p[2] * 0.5, p[3]]);
    let v = visibility_image(&shadowed, &unshadowed, None).unwrap();
    assert!((v[0] - 0.5).abs() < 1e-6, "{v:?}");
    assert_eq!(v[1], 1.0, "0/0 is lit");
    assert!((v[2] - 0.5).abs() < 1e-6);

    // With an ambient term: shadowed = ambient + 0.25 · direct → 0.25.
    let ambient = Image::filled(3, 1, [0.1, 0.1, 0.1, 1.0]);
    let direct = [0.6, 0.4, 0.2];
    let u = Image::filled(3, 1, [0.1 + direct[0], 0.1 + direct[1], 0.1 + direct[2], 1.0]);
    let s = Image::filled(3, 1, [0.1 + 0.25 * direct[0], 0.1 + 0.25 * direct[1], 0.1 + 0.25 * direct[2], 1.0]);
    let v = visibility_image(&s, &u, Some(&ambient)).unwrap();
    assert!(v.iter().all(|x| (x - 0.25).abs() < 1e-5), "{v:?}");
    // Ambient-only pixels (no direct light) are lit; values are clamped to [0,1]; NaN input gives NaN.
    let v = visibility_image(&ambient, &ambient, Some(&ambient)).unwrap();
    assert_eq!(v, vec![1.0; 3]);
    let brighter = map(&u, |_, p| [p[0] * 2.0, p[1] * 2.0, p[2] * 2.0, p[3]]);
    let darker = Image::filled(3, 1, [0.0; 4]);
    assert_eq!(visibility_image(&brighter, &u, Some(&ambient)).unwrap(), vec![1.0; 3]);
    assert_eq!(visibility_image(&darker, &u, Some(&ambient)).unwrap(), vec![0.0; 3]);
    let mut broken = s.clone();
    broken.pixels[1][2] = f32::NAN;
    assert!(visibility_image(&broken, &u, Some(&ambient)).unwrap()[1].is_nan());
}

#[test]
fn shadow_intensity_error_of_half_shadowed_image() {
    // Fully lit reference; the technique shadows the left half completely and the right half not at all.
    let (w, h) = (8, 4);
    let unshadowed = Image::filled(w, h, [0.7, 0.7, 0.7, 1.0]);
    let reference = unshadowed.clone();
    let technique = Image {
        pixels: (0..w * h).map(|i| if i % w < w / 2 { [0.0, 0.0, 0.0, 1.0] } else { [0.7, 0.7, 0.7, 1.0] }).collect(),
        ..unshadowed.clone()
    };
    let v_t = visibility_image(&technique, &unshadowed, None).unwrap();
    let v_r = visibility_image(&reference, &unshadowed, None).unwrap();
    let options = CompareOptions { visibility: Some(Visibility { technique: &v_t, reference: &v_r }), ..no_flip() };
    let m = compare(&technique, &reference, None, &options).unwrap();
    assert!((m.shadow_intensity_error.unwrap() - 0.5).abs() < 1e-9, "{:?}", m.shadow_intensity_error);
    assert!((m.shadow_intensity_bias.unwrap() + 0.5).abs() < 1e-9, "too dark: negative bias");

    // Half shadowing (V = 0.5) everywhere against fully lit: 0.5 as well; a mask of the right half: 0.
    let half = map(&unshadowed, |_, p| [p[0] * 0.5, p[1] * 0.5, p[2] * 0.5, p[3]]);
    let v_half = visibility_image(&half, &unshadowed, None).unwrap();
    let options = CompareOptions { visibility: Some(Visibility { technique: &v_half, reference: &v_r }), ..no_flip() };
    let m = compare(&half, &reference, None, &options).unwrap();
    assert!((m.shadow_intensity_error.unwrap() - 0.5).abs() < 1e-6);
    let right: Vec<bool> = (0..w * h).map(|i| i % w >= w / 2).collect();
    let options = CompareOptions { visibility: Some(Visibility { technique: &v_t, reference: &v_r }), ..no_flip() };
    assert_eq!(compare(&technique, &reference, Some(&right), &options).unwrap().shadow_intensity_error, Some(0.0));

    // A NaN factor is an error of 1.
    let mut v_nan = v_r.clone();
    v_nan[0] = f32::NAN;
    let options = CompareOptions { visibility: Some(Visibility { technique: &v_nan, reference: &v_r }), ..no_flip() };
    let m = compare(&reference, &reference, None, &options).unwrap();
    assert!((m.shadow_intensity_error.unwrap() - 1.0 / (w * h) as f64).abs() < 1e-12);

    // Visibility difference images: too dark (technique shadows) is green in signed mode, red at gain 2 in
    // absolute mode (|−1| · 2 ≥ 1), dark blue where equal.
    let signed = visibility_difference_image(&v_t, &v_r, w, h, None, DiffMode::Signed, 1.0).unwrap();
    assert_eq!(signed.get_pixel(0, 0).0, [0, 255, 0, 255]);
    assert_eq!(signed.get_pixel(w - 1, 0).0, [0, 0, 0, 255]);
    let abs = visibility_difference_image(&v_t, &v_r, w, h, Some(&right), DiffMode::Absolute, 2.0).unwrap();
    assert_eq!(abs.get_pixel(0, 0).0, [40, 40, 40, 255]);
    assert_eq!(abs.get_pixel(w - 1, 0).0, [0, 0, 128, 255]);
    let abs = visibility_difference_image(&v_t, &v_r, w, h, None, DiffMode::Absolute, 2.0).unwrap();
    assert_eq!(abs.get_pixel(0, 0).0, [255, 0, 0, 255]);
    let nan = visibility_difference_image(&v_nan, &v_r, w, h, None, DiffMode::Signed, 1.0).unwrap();
    assert_eq!(nan.get_pixel(0, 0).0, [255, 0, 255, 255]);
}

#[test]
fn flip_grows_with_the_perturbation() {
    let r = scene();
    // Darken a block (a wrong shadow) a little and a lot.
    let shade = |k: f32| {
        map(&r, |i, p| {
            let (x, y) = (i as u32 % W, i as u32 / W);
            if (8..20).contains(&x) && (6..16).contains(&y) {
                [p[0] * k, p[1] * k, p[2] * k, p[3]]
            } else {
                p
            }
        })
    };
    let options = CompareOptions::default();
    let small = compare(&shade(0.9), &r, None, &options).unwrap();
    let large = compare(&shade(0.4), &r, None, &options).unwrap();
    let (fs, fl) = (small.flip_mean.unwrap(), large.flip_mean.unwrap());
    assert!(fs > 0.0 && fl > fs && fl <= 1.0, "small {fs}, large {fl}");
    assert!(large.mse > small.mse && large.psnr_db.unwrap() < small.psnr_db.unwrap());

    // The per-pixel map is in [0,1], near zero far from the change.
    let map = flip_error_map(&shade(0.4), &r, None, 1.0, 67.0).unwrap();
    assert_eq!(map.len(), r.len());
    assert!(map.iter().all(|e| (0.0..=1.0).contains(e)));
    // (FLIP's spatial filters leave a faint tail: 5e-5 at 8 pixels from the block.)
    assert!(map[0] < 1e-3 && map[(10 * W + 12) as usize] > 0.5, "{} {}", map[0], map[(10 * W + 12) as usize]);

    // Exposure changes what FLIP sees: the tone-mapped images match the ACES curve.
    let grey = Image::filled(1, 1, [0.18, 0.18, 0.18, 1.0]);
    let aces = |x: f32| (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    let srgb = |v: f32| if v <= 0.0031308 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    for exposure in [0.5f32, 1.0, 4.0] {
        let expected = (srgb(aces(0.18 * exposure)) * 255.0).round() as u8;
        assert_eq!(tonemap_for_flip(&grey, exposure).get_pixel(0, 0).0, [expected; 3]);
    }
}
