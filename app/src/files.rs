//! Output files: a path's checks before the (slow) work, atomic writes (a temporary file beside the target,
//! then a rename), PNG encoding. Shared by the command line, the measurement code and the app.

use std::path::Path;

use anyhow::{bail, Context, Result};

/// The file name ends in `.ext` (any case) and its folder exists: checked before anything is rendered.
pub fn check_output_path(path: &Path, ext: &str) -> Result<()> {
    let ok = path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case(ext));
    if !ok {
        bail!("{}: the file name must end in .{ext}", path.display());
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            bail!("{}: the folder {} does not exist", path.display(), dir.display());
        }
    }
    Ok(())
}

/// Write a file atomically: a temporary file beside it, then a rename, so a failure never leaves half a file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension(format!("{}.tmp", path.extension().and_then(|e| e.to_str()).unwrap_or("out")));
    std::fs::write(&tmp, bytes).with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// `image` as PNG bytes.
pub fn encode_png(image: &image::RgbaImage) -> Result<Vec<u8>> {
    let mut png = Vec::new();
    image.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).context("cannot encode the PNG")?;
    Ok(png)
}
