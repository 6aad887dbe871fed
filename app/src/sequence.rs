//! Image sequences (the camera orbiting its target, or the lights moving) saved as numbered PNGs and as one
//! looping animated GIF (the `image` crate's encoder: a NeuQuant palette per frame): shared by
//! `shadowlab sequence` and the app's File menu. Every frame is rendered completely by the caller.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use glam::{Quat, Vec3};
use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, Frame, RgbaImage};
use shadowlab_core::scene::{Aabb, Camera};

/// What moves between the frames of a sequence.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Motion {
    /// The camera turns once around its target (the `--camera` target, or the point of the view axis as far
    /// ahead as the scene's centre), 360°/frames a frame.
    Orbit,
    /// Every light moves by `--step` a frame (as in `animate`).
    Lights,
}

/// Most frames of one sequence (ten minutes at 6 frames a second).
pub const MAX_FRAMES: usize = 3600;

/// GIF palette speed, 1 (best, slowest) to 30: 10 quantises a 640x360 frame in a few tens of milliseconds.
const GIF_SPEED: i32 = 10;

/// The camera turned by `angle_rad` about the vertical axis through `target`: the same distance, pitch and
/// roll, looking at the same point when it did (one step of an orbit).
pub fn orbit_camera(camera: &Camera, target: Vec3, angle_rad: f32) -> Camera {
    let turn = Quat::from_rotation_y(angle_rad);
    Camera {
        position: target + turn * (camera.position - target),
        orientation: (turn * camera.orientation).normalize(),
        ..*camera
    }
}

/// The point an orbit turns around when none is given: on the view axis, as far ahead as the scene's centre
/// (at least the near plane's distance ten times), so a camera looking at the scene orbits what it sees.
pub fn orbit_target(camera: &Camera, bounds: &Aabb) -> Vec3 {
    let ahead = (bounds.center() - camera.position).dot(camera.forward());
    camera.position + camera.forward() * ahead.max(camera.near * 10.0)
}

/// `frame-0000.png` ... in `dir`.
pub fn frame_path(dir: &Path, index: usize) -> PathBuf {
    dir.join(format!("frame-{index:04}.png"))
}

/// Check a frame count before anything is rendered.
pub fn check_frames(frames: usize) -> Result<()> {
    if !(1..=MAX_FRAMES).contains(&frames) {
        bail!("a sequence has 1 to {MAX_FRAMES} frames, not {frames}");
    }
    Ok(())
}

/// A looping GIF written frame by frame, so a long sequence never holds its raw frames: only the encoded
/// bytes are kept (a GIF is small: 36 frames of 320x180 take about 180 KiB), written to the file by
/// [`GifWriter::finish`] (a temporary file, then a rename: a failure leaves no half GIF).
pub struct GifWriter {
    encoder: Option<GifEncoder<SharedBytes>>,
    bytes: SharedBytes,
    path: PathBuf,
    delay: Delay,
    size: Option<(u32, u32)>,
}

/// The encoder's output, shared so the bytes can be taken once the encoder is dropped (dropping it writes
/// the GIF trailer, which cannot fail into memory).
#[derive(Clone, Default)]
struct SharedBytes(std::rc::Rc<std::cell::RefCell<Vec<u8>>>);

impl std::io::Write for SharedBytes {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.borrow_mut().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl GifWriter {
    /// Each frame shown for `frame_ms` (GIF delays are in hundredths of a second: rounded down to 10 ms, at
    /// least 10).
    pub fn new(path: &Path, frame_ms: u32) -> Result<GifWriter> {
        let bytes = SharedBytes::default();
        let mut encoder = GifEncoder::new_with_speed(bytes.clone(), GIF_SPEED);
        encoder.set_repeat(Repeat::Infinite).context("cannot encode the GIF")?;
        let delay = Delay::from_numer_denom_ms(frame_ms.clamp(10, 655_350) / 10 * 10, 1);
        Ok(GifWriter { encoder: Some(encoder), bytes, path: path.to_path_buf(), delay, size: None })
    }

    /// Add a frame: all of one size, at most 65,535 pixels a side.
    pub fn add(&mut self, frame: &RgbaImage) -> Result<()> {
        let size = *self.size.get_or_insert(frame.dimensions());
        if frame.dimensions() != size {
            bail!("the frames of a GIF must all have one size");
        }
        if size.0 > u16::MAX as u32 || size.1 > u16::MAX as u32 {
            bail!("{}x{} is too large for a GIF (at most 65535 a side)", size.0, size.1);
        }
        let encoder = self.encoder.as_mut().expect("encoding until finished");
        encoder
            .encode_frame(Frame::from_parts(frame.clone(), 0, 0, self.delay))
            .context("cannot encode a frame of the GIF")
    }

    /// Write the file.
    pub fn finish(mut self) -> Result<()> {
        if self.size.is_none() {
            bail!("a GIF needs at least one frame");
        }
        drop(self.encoder.take());
        let bytes = std::mem::take(&mut *self.bytes.0.borrow_mut());
        crate::files::write_atomic(&self.path, &bytes)
    }
}

/// Write `frames` as a looping GIF (see [`GifWriter`]).
pub fn write_gif(path: &Path, frames: &[RgbaImage], frame_ms: u32) -> Result<()> {
    let mut gif = GifWriter::new(path, frame_ms)?;
    for f in frames {
        gif.add(f)?;
    }
    gif.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_orbit_step_keeps_distance_and_target_and_a_full_turn_comes_back() {
        let target = Vec3::new(1.0, 0.5, -2.0);
        let camera = Camera::look_at(Vec3::new(4.0, 2.0, 3.0), target, 1.0, 0.05, 50.0);
        let quarter = orbit_camera(&camera, target, std::f32::consts::FRAC_PI_2);
        assert!(((quarter.position - target).length() - (camera.position - target).length()).abs() < 1e-4);
        assert!((quarter.position.y - camera.position.y).abs() < 1e-5, "a turn about the vertical");
        assert!((quarter.position - camera.position).length() > 1.0, "it moved");
        let to_target = (target - quarter.position).normalize();
        assert!(quarter.forward().dot(to_target) > 0.9999, "still looking at the target");
        let full = orbit_camera(&camera, target, std::f32::consts::TAU);
        assert!((full.position - camera.position).length() < 1e-4);
    }

    #[test]
    fn a_gif_has_every_frame_at_its_size_and_bad_input_is_an_error() {
        use image::AnimationDecoder;
        let dir = std::env::temp_dir().join(format!("shadowlab-gif-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.gif");
        let frames: Vec<RgbaImage> =
            (0..3u8).map(|i| RgbaImage::from_pixel(8, 5, image::Rgba([i * 100, 50, 200 - i * 60, 255]))).collect();
        write_gif(&path, &frames, 120).unwrap();
        let file = std::io::BufReader::new(std::fs::File::open(&path).unwrap());
        let decoded = image::codecs::gif::GifDecoder::new(file).unwrap().into_frames().collect_frames().unwrap();
        assert_eq!(decoded.len(), 3);
        for (d, f) in decoded.iter().zip(&frames) {
            assert_eq!(d.buffer().dimensions(), (8, 5));
            assert_eq!(d.delay().numer_denom_ms(), (120, 1));
            let (a, b) = (d.buffer().get_pixel(3, 2).0, f.get_pixel(3, 2).0);
            assert!((0..3).all(|c| (a[c] as i32 - b[c] as i32).abs() <= 8), "{a:?} {b:?}");
        }
        assert!(write_gif(&path, &[], 100).is_err());
        assert!(write_gif(&path, &[RgbaImage::new(2, 2), RgbaImage::new(3, 2)], 100).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
