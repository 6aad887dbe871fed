//! glTF's bytes: buffers from files, data URIs or the `.glb` blob, accessor reads (strided, sparse,
//! normalized integers), image sources, and the URI decoding they need. The loader's structure is in
//! `gltf_loader.rs`; this is the part that touches raw bytes, so every bound is checked here.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};

use super::texture::{decode_texture_bytes, find_file_case_insensitive, load_texture};
use super::TextureImage;

/// An image to decode: a file or data URI, or bytes embedded in a buffer view (`.glb`).
pub(super) enum ImageSource {
    Uri { name: String, uri: String },
    Embedded { name: String, bytes: Result<Vec<u8>, String> },
}

impl ImageSource {
    pub(super) fn load(&self, dir: &Path) -> Result<TextureImage, String> {
        match self {
            ImageSource::Embedded { name, bytes } => decode_texture_bytes(name, bytes.as_ref().map_err(Clone::clone)?),
            ImageSource::Uri { name, uri } => match read_uri(dir, uri)? {
                UriData::Bytes(bytes) => decode_texture_bytes(name, &bytes),
                UriData::File(file) => load_texture(&file),
                UriData::Missing(wanted) => Err(format!("missing texture '{wanted}' (looked in {})", dir.display())),
            },
        }
    }
}

/// What a URI points at.
pub(super) enum UriData {
    /// Data decoded from a `data:` URI.
    Bytes(Vec<u8>),
    /// An existing file.
    File(PathBuf),
    /// A relative path with no file behind it (the decoded path).
    Missing(String),
}

pub(super) fn read_uri(dir: &Path, uri: &str) -> Result<UriData, String> {
    if let Some(data) = uri.strip_prefix("data:") {
        return decode_data_uri(data).map(UriData::Bytes);
    }
    let relative = if let Some(file) = uri.strip_prefix("file://").or_else(|| uri.strip_prefix("file:")) {
        file
    } else if uri.split('/').next().is_some_and(|first| first.contains(':')) {
        return Err(format!("unsupported URI '{}'", shorten(uri)));
    } else {
        uri
    };
    let relative = percent_decode(relative);
    Ok(match find_file_case_insensitive(dir, &relative) {
        Some(file) => UriData::File(file),
        None => UriData::Missing(relative),
    })
}

/// Load every buffer: the GLB binary chunk, data URIs or files next to the glTF. A missing or short buffer is
/// an error: the meshes cannot be read without it.
pub(super) fn load_buffers(
    document: &gltf::Document,
    dir: &Path,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<Vec<u8>>, String> {
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => {
                blob.take().ok_or_else(|| format!("buffer {i} refers to the GLB binary chunk, but there is none"))?
            }
            gltf::buffer::Source::Uri(uri) => match read_uri(dir, uri).map_err(|e| format!("buffer {i}: {e}"))? {
                UriData::Bytes(bytes) => bytes,
                UriData::File(file) => {
                    std::fs::read(&file).map_err(|e| format!("buffer {i}: cannot read {}: {e}", file.display()))?
                }
                UriData::Missing(wanted) => {
                    return Err(format!("buffer {i}: file '{wanted}' not found in {}", dir.display()));
                }
            },
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {i} is truncated: it has {} bytes, the file declares {}",
                data.len(),
                buffer.length()
            ));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// A binary glTF's 12-byte header and chunk headers, checked before the `gltf` crate reads them (it subtracts
/// the header size from the declared length without checking, and trusts chunk lengths).
pub(super) fn check_glb_header(bytes: &[u8]) -> Result<(), String> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let u32_at = |at: usize| bytes.get(at..at + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize);
    let length = u32_at(8).ok_or("the GLB header is cut short")?;
    if length < 12 || length > bytes.len() {
        return Err(format!("the GLB header declares {length} bytes; the file has {}", bytes.len()));
    }
    let mut at = 12;
    while at + 8 <= length {
        let chunk = u32_at(at).ok_or("a GLB chunk header is cut short")?;
        let end = (at + 8).checked_add(chunk).filter(|&e| e <= length);
        match end {
            Some(e) => at = e,
            None => return Err(format!("a GLB chunk at byte {at} declares {chunk} bytes past the end of the file")),
        }
    }
    Ok(())
}

/// The bytes of a buffer view, checked against its buffer.
pub(super) fn view_bytes<'b>(view: &gltf::buffer::View, buffers: &'b [Vec<u8>]) -> Result<&'b [u8], String> {
    let buffer =
        buffers.get(view.buffer().index()).ok_or_else(|| format!("buffer view {} has no buffer", view.index()))?;
    let start = view.offset();
    let end = start.saturating_add(view.length());
    buffer.get(start..end).ok_or_else(|| {
        format!(
            "buffer view {} (bytes {start}..{end}) lies outside buffer {} ({} bytes)",
            view.index(),
            view.buffer().index(),
            buffer.len()
        )
    })
}

/// The elements of an accessor packed tightly (`count * element size` bytes), sparse substitutions applied.
pub(super) fn accessor_bytes(accessor: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u8>, String> {
    let element = accessor.size();
    let count = accessor.count();
    let total = count.checked_mul(element).filter(|&t| t <= u32::MAX as usize).ok_or("the accessor is too large")?;
    let mut out = vec![0u8; total];
    if let Some(view) = accessor.view() {
        let data = view_bytes(&view, buffers)?;
        let stride = view.stride().unwrap_or(element);
        if stride < element {
            return Err(format!("byte stride {stride} is smaller than the element size {element}"));
        }
        let start = accessor.offset();
        if count > 0 {
            let end = (count - 1).checked_mul(stride).and_then(|e| e.checked_add(start.checked_add(element)?));
            if end.is_none_or(|end| end > data.len()) {
                return Err(format!(
                    "accessor {} reads past the end of buffer view {} ({} bytes)",
                    accessor.index(),
                    view.index(),
                    data.len()
                ));
            }
        }
        for (i, dst) in out.chunks_exact_mut(element).enumerate() {
            let src = start + i * stride;
            dst.copy_from_slice(&data[src..src + element]);
        }
    }
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        let index_size = match sparse.indices().index_type() {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        let range = |offset: usize, len: usize| offset..offset.saturating_add(len);
        let index_view = view_bytes(&sparse.indices().view(), buffers)?;
        let index_bytes = index_view
            .get(range(sparse.indices().offset(), n.saturating_mul(index_size)))
            .ok_or("sparse indices lie outside their buffer view")?;
        let value_view = view_bytes(&sparse.values().view(), buffers)?;
        let value_bytes = value_view
            .get(range(sparse.values().offset(), n.saturating_mul(element)))
            .ok_or("sparse values lie outside their buffer view")?;
        for (k, value) in value_bytes.chunks_exact(element.max(1)).enumerate().take(n) {
            let target = read_uint(&index_bytes[k * index_size..(k + 1) * index_size]) as usize;
            if target >= count {
                return Err(format!("sparse index {target} is out of range (count {count})"));
            }
            out[target * element..(target + 1) * element].copy_from_slice(value);
        }
    }
    Ok(out)
}

/// A little-endian unsigned integer of 1, 2 or 4 bytes.
pub(super) fn read_uint(bytes: &[u8]) -> u32 {
    bytes.iter().rev().fold(0u32, |acc, &b| (acc << 8) | b as u32)
}

/// Accessor components as f32, normalised integers mapped to [0, 1] or [-1, 1] as the glTF spec says.
pub(super) fn read_floats(
    accessor: &gltf::Accessor,
    buffers: &[Vec<u8>],
    dimensions: Dimensions,
) -> Result<Vec<f32>, String> {
    if accessor.dimensions() != dimensions {
        return Err(format!("expected a {dimensions:?} accessor, found {:?}", accessor.dimensions()));
    }
    let bytes = accessor_bytes(accessor, buffers)?;
    let normalized = accessor.normalized();
    let scale = |v: f32, max: f32| if normalized { (v / max).max(-1.0) } else { v };
    Ok(match accessor.data_type() {
        DataType::F32 => bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect(),
        DataType::U8 => bytes.iter().map(|&b| scale(b as f32, 255.0)).collect(),
        DataType::I8 => bytes.iter().map(|&b| scale(b as i8 as f32, 127.0)).collect(),
        DataType::U16 => {
            bytes.chunks_exact(2).map(|b| scale(u16::from_le_bytes([b[0], b[1]]) as f32, 65535.0)).collect()
        }
        DataType::I16 => {
            bytes.chunks_exact(2).map(|b| scale(i16::from_le_bytes([b[0], b[1]]) as f32, 32767.0)).collect()
        }
        DataType::U32 => bytes.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32).collect(),
    })
}

pub(super) fn read_vec3(accessor: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<Vec3>, String> {
    Ok(read_floats(accessor, buffers, Dimensions::Vec3)?.chunks_exact(3).map(Vec3::from_slice).collect())
}

pub(super) fn read_vec2(accessor: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<Vec2>, String> {
    Ok(read_floats(accessor, buffers, Dimensions::Vec2)?.chunks_exact(2).map(Vec2::from_slice).collect())
}

pub(super) fn read_indices(accessor: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u32>, String> {
    if accessor.dimensions() != Dimensions::Scalar {
        return Err(format!("expected a scalar accessor, found {:?}", accessor.dimensions()));
    }
    let size = match accessor.data_type() {
        DataType::U8 => 1,
        DataType::U16 => 2,
        DataType::U32 => 4,
        other => return Err(format!("indices must be unsigned integers, found {other:?}")),
    };
    Ok(accessor_bytes(accessor, buffers)?.chunks_exact(size).map(read_uint).collect())
}

/// Decode the part after `data:`: `[<media type>][;base64],<data>`.
pub(super) fn decode_data_uri(data: &str) -> Result<Vec<u8>, String> {
    let (header, payload) = data.split_once(',').ok_or("malformed data URI (no ',')")?;
    if header.ends_with(";base64") {
        decode_base64(payload)
    } else {
        Ok(percent_decode_bytes(payload))
    }
}

/// Standard or URL-safe base64, padding optional, whitespace ignored.
pub(super) fn decode_base64(text: &str) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    let (mut acc, mut bits) = (0u32, 0u32);
    for (i, c) in text.bytes().enumerate() {
        let value = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' => break,
            b' ' | b'\t' | b'\r' | b'\n' => continue,
            _ => return Err(format!("invalid base64 data (character {i})")),
        };
        acc = (acc << 6) | value as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Ok(out)
}

pub(super) fn percent_decode_bytes(text: &str) -> Vec<u8> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    out
}

/// URIs are percent-encoded (`my%20texture.png`); invalid escapes are kept as written.
pub(super) fn percent_decode(text: &str) -> String {
    String::from_utf8_lossy(&percent_decode_bytes(text)).into_owned()
}

pub(super) fn shorten(text: &str) -> String {
    if text.chars().count() > 60 {
        format!("{}...", text.chars().take(60).collect::<String>())
    } else {
        text.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trip() {
        assert_eq!(decode_base64("aGVsbG8gd29ybGQ=").unwrap(), b"hello world");
        assert_eq!(decode_base64("aGVsbG8gd29ybGQ").unwrap(), b"hello world");
        assert_eq!(decode_base64("AAEC\n/w==").unwrap(), [0, 1, 2, 255]);
        assert!(decode_base64("a*b").is_err());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("my%20tex.png"), "my tex.png");
        assert_eq!(percent_decode("100%"), "100%");
        assert_eq!(percent_decode("%zz%4"), "%zz%4");
        assert_eq!(percent_decode("%FF"), "\u{FFFD}");
    }
}
