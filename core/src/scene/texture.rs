//! Texture files: case-insensitive lookup and decoding to RGBA8.
//!
//! Scene files written on Windows name their textures with any letter case and with backslashes
//! (`map_Kd Textures\Brick.JPG` for a file `textures/brick.jpg`), so lookups fall back to a per-component
//! case-insensitive match. Decoded textures are RGBA8, sRGB encoded as stored in the file, and at most
//! [`MAX_TEXTURE_SIZE`] on a side.

use std::io::Cursor;
use std::path::{Component, Path, PathBuf};

use image::imageops::FilterType;
use image::{DynamicImage, ImageReader};

use super::TextureImage;

/// Textures larger than this on a side are downscaled (aspect kept) when loaded.
pub const MAX_TEXTURE_SIZE: u32 = 2048;

/// Find `relative` (a path as written in a scene file) under `dir`.
///
/// The exact path is tried first; then each path component is matched case-insensitively against the
/// directory listing; then, as a last resort, the bare file name is looked up in `dir` (MTL files exported
/// with absolute paths such as `C:\work\tex\wood.jpg`). Backslashes count as separators and surrounding
/// quotes are ignored. Returns `None` when nothing matches or the match is not a file.
pub fn find_file_case_insensitive(dir: &Path, relative: &str) -> Option<PathBuf> {
    let name = relative.trim().trim_matches('"').replace('\\', "/");
    if name.is_empty() {
        return None;
    }
    let exact = dir.join(&name);
    if exact.is_file() {
        return Some(exact);
    }
    // Windows absolute paths ("C:/...") are not absolute on Unix: keep only the part after the drive.
    let without_drive = match name.as_bytes() {
        [d, b':', ..] if d.is_ascii_alphabetic() => &name[2..],
        _ => &name[..],
    };
    if let Some(found) = match_components(dir, without_drive.trim_start_matches('/')) {
        return Some(found);
    }
    let file_name = without_drive.rsplit('/').next().unwrap_or("");
    if file_name != without_drive {
        return match_components(dir, file_name);
    }
    None
}

/// Walk `relative` from `dir` one component at a time, matching each case-insensitively when the exact name
/// does not exist.
fn match_components(dir: &Path, relative: &str) -> Option<PathBuf> {
    let mut current = dir.to_path_buf();
    for component in Path::new(relative).components() {
        match component {
            Component::Normal(part) => {
                let exact = current.join(part);
                if exact.exists() {
                    current = exact;
                    continue;
                }
                let wanted = part.to_str()?.to_lowercase();
                // Sorted so that a directory holding both `a.PNG` and `A.png` resolves the same way every time.
                let mut matches: Vec<PathBuf> = std::fs::read_dir(&current)
                    .ok()?
                    .filter_map(Result::ok)
                    .filter(|entry| entry.file_name().to_str().is_some_and(|n| n.to_lowercase() == wanted))
                    .map(|entry| entry.path())
                    .collect();
                matches.sort();
                current = matches.into_iter().next()?;
            }
            Component::ParentDir => current = current.join(".."),
            Component::CurDir => {}
            Component::RootDir | Component::Prefix(_) => {}
        }
    }
    current.is_file().then_some(current)
}

/// Read and decode a PNG or JPEG file into RGBA8 (sRGB), downscaled to at most [`MAX_TEXTURE_SIZE`].
pub fn load_texture(path: &Path) -> Result<TextureImage, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read texture {}: {e}", path.display()))?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| path.display().to_string());
    decode_texture_bytes(&name, &bytes).map_err(|e| format!("{}: {e}", path.display()))
}

/// Decode an encoded PNG or JPEG image held in memory (a glTF embedded image, say) into RGBA8 (sRGB),
/// downscaled to at most [`MAX_TEXTURE_SIZE`]. The format is recognised from the bytes, not from `name`.
pub fn decode_texture_bytes(name: &str, bytes: &[u8]) -> Result<TextureImage, String> {
    let reader = ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot read image '{name}': {e}"))?;
    if reader.format().is_none() {
        return Err(format!("image '{name}' is not a PNG or JPEG file"));
    }
    let image = reader.decode().map_err(|e| format!("cannot decode image '{name}': {e}"))?;
    if image.width() == 0 || image.height() == 0 {
        return Err(format!("image '{name}' is empty (0 pixels)"));
    }
    let image = downscale(image);
    let rgba = image.into_rgba8();
    Ok(TextureImage { name: name.to_string(), width: rgba.width(), height: rgba.height(), rgba8: rgba.into_raw() })
}

/// Shrink images larger than [`MAX_TEXTURE_SIZE`] on a side, keeping the aspect ratio. The filter works on
/// the sRGB-encoded values directly, which slightly darkens high-contrast detail; fine for a preview-scale
/// reduction of oversized textures.
fn downscale(image: DynamicImage) -> DynamicImage {
    if image.width() <= MAX_TEXTURE_SIZE && image.height() <= MAX_TEXTURE_SIZE {
        return image;
    }
    // `resize` fits the image inside the box and keeps its aspect ratio.
    image.resize(MAX_TEXTURE_SIZE, MAX_TEXTURE_SIZE, FilterType::Triangle)
}

/// Run `decode` over `items` on a few threads (texture decoding dominates the load time of textured scenes),
/// returning the results in the order of `items`.
pub fn decode_parallel<T, F>(items: &[T], decode: F) -> Vec<Result<TextureImage, String>>
where
    T: Sync,
    F: Fn(&T) -> Result<TextureImage, String> + Sync,
{
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).clamp(1, 8).min(items.len());
    if threads <= 1 {
        return items.iter().map(&decode).collect();
    }
    let chunk = items.len().div_ceil(threads);
    std::thread::scope(|scope| {
        let handles: Vec<_> = items
            .chunks(chunk)
            .map(|part| {
                let decode = &decode;
                (part.len(), scope.spawn(move || part.iter().map(decode).collect::<Vec<_>>()))
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|(len, h)| {
                h.join().unwrap_or_else(|_| vec![Err("the texture decoder panicked".to_string()); len])
            })
            .collect()
    })
}
