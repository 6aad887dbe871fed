//! The image every comparison reads ([`Image`]), the errors of a comparison that cannot be made
//! ([`CompareError`]), luminance, and the checks and masks the metrics and difference images share.

/// A linear RGBA radiance image, row-major from the top left (the layout of `Renderer::read_hdr`).
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

impl Image {
    /// Wraps `pixels`; fails when there are not exactly `width * height` of them.
    pub fn new(width: u32, height: u32, pixels: Vec<[f32; 4]>) -> Result<Image, CompareError> {
        let image = Image { width, height, pixels };
        image.check("image")?;
        Ok(image)
    }

    /// An image of one colour.
    pub fn filled(width: u32, height: u32, rgba: [f32; 4]) -> Image {
        Image { width, height, pixels: vec![rgba; width as usize * height as usize] }
    }

    /// Number of pixels, `width * height`.
    pub fn len(&self) -> usize {
        self.width as usize * self.height as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The pixel at column `x`, row `y`.
    pub fn get(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Errors when the public fields disagree (the pixel count is not `width * height`).
    fn check(&self, what: &'static str) -> Result<(), CompareError> {
        if self.pixels.len() != self.len() {
            return Err(CompareError::PixelCount {
                what,
                width: self.width,
                height: self.height,
                found: self.pixels.len(),
            });
        }
        Ok(())
    }
}

/// Why a comparison could not be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CompareError {
    #[error("{what} is {found_w}x{found_h} but the reference is {expected_w}x{expected_h}")]
    SizeMismatch { what: &'static str, expected_w: u32, expected_h: u32, found_w: u32, found_h: u32 },
    #[error("{what} says {width}x{height} but holds {found} pixels")]
    PixelCount { what: &'static str, width: u32, height: u32, found: usize },
    #[error("{what} has {found} entries, expected one per pixel ({expected})")]
    Length { what: &'static str, expected: usize, found: usize },
    #[error("invalid {what} {value} (must be a finite number >= 0)")]
    InvalidParameter { what: &'static str, value: f32 },
}

/// Rec. 709 luminance of linear RGB (alpha ignored).
pub fn luminance(p: [f32; 4]) -> f32 {
    crate::math::luminance(glam::Vec3::new(p[0], p[1], p[2]))
}

pub(super) fn is_finite_rgb(p: [f32; 4]) -> bool {
    p[0].is_finite() && p[1].is_finite() && p[2].is_finite()
}

/// `image` must have the reference's size and a consistent pixel count.
pub(super) fn check_same_size(what: &'static str, image: &Image, reference: &Image) -> Result<(), CompareError> {
    reference.check("reference")?;
    if image.width != reference.width || image.height != reference.height {
        return Err(CompareError::SizeMismatch {
            what,
            expected_w: reference.width,
            expected_h: reference.height,
            found_w: image.width,
            found_h: image.height,
        });
    }
    image.check(what)
}

/// The mask, when given, must have one entry per pixel.
pub(super) fn check_len<T>(what: &'static str, values: Option<&[T]>, expected: usize) -> Result<(), CompareError> {
    match values {
        Some(v) if v.len() != expected => Err(CompareError::Length { what, expected, found: v.len() }),
        _ => Ok(()),
    }
}

pub(super) fn check_param(what: &'static str, value: f32) -> Result<(), CompareError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(CompareError::InvalidParameter { what, value })
    }
}

/// Whether pixel `i` is compared.
pub(super) fn in_mask(mask: Option<&[bool]>, i: usize) -> bool {
    mask.is_none_or(|m| m[i])
}
