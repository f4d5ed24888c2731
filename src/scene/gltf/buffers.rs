//! Buffers and the bytes behind URIs: the GLB container, `data:` URIs (base64) and external
//! files next to the scene file.

use super::Loader;
use crate::scene::SceneError;
use std::path::Path;

/// Checks a GLB's 12-byte header and its chunks' lengths against the file (glTF 2.0 §4.4),
/// so that a truncated file is named as such.
pub fn check_glb_header(bytes: &[u8]) -> Result<(), String> {
    let word = |at: usize| -> Option<u32> {
        let b = bytes.get(at..at + 4)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(format!(
            "truncated GLB file: {} bytes, shorter than its 12-byte header",
            bytes.len()
        ));
    };
    if version != 2 {
        return Err(format!("GLB version {version}: mcrt reads version 2"));
    }
    if length < 20 {
        return Err(format!(
            "its GLB header says {length} bytes, too few for the header and a JSON chunk"
        ));
    }
    if length as usize > bytes.len() {
        return Err(format!(
            "truncated GLB file: its header says {length} bytes, the file has {}",
            bytes.len()
        ));
    }
    let mut at = 12usize;
    while at < length as usize {
        let (Some(chunk), Some(_)) = (word(at), word(at + 4)) else {
            return Err(format!(
                "truncated GLB file: a chunk header at byte {at} is cut off"
            ));
        };
        let end = (at as u64) + 8 + chunk as u64;
        if end > length as u64 {
            return Err(format!(
                "truncated GLB file: the chunk at byte {at} claims {chunk} bytes, past the \
                 end of the file ({length} bytes)"
            ));
        }
        at = end as usize;
    }
    Ok(())
}

/// Every buffer's bytes, each at least as long as its `byteLength`.
pub fn load(
    path: &Path,
    doc: &::gltf::Document,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let mut out = Vec::new();
    for b in doc.buffers() {
        let i = b.index();
        let data = match b.source() {
            ::gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                SceneError::new(
                    path,
                    None,
                    format!(
                        "buffers[{i}] has no uri, so it is the GLB's binary chunk, but the \
                         file has none (or another buffer took it)"
                    ),
                )
            })?,
            ::gltf::buffer::Source::Uri(uri) => read_uri(path, uri)
                .map_err(|e| SceneError::new(path, None, format!("buffers[{i}]: {e}")))?,
        };
        if data.len() < b.length() {
            return Err(SceneError::new(
                path,
                None,
                format!(
                    "buffers[{i}] declares byteLength {} but its data has {} bytes",
                    b.length(),
                    data.len()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The bytes a URI names: a base64 `data:` URI, or a file relative to the scene file
/// (percent-encoded, as URIs are). Other schemes are refused.
pub fn read_uri(scene: &Path, uri: &str) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((_, data)) = rest.split_once(";base64,") else {
            return Err("a data: URI that is not base64-encoded".into());
        };
        return decode_base64(data);
    }
    if uri.contains("://") {
        return Err(format!(
            "the URI '{}' is not a relative file path (mcrt reads no network resources)",
            crate::input::shorten(uri)
        ));
    }
    let rel = percent_decode(uri)?;
    let file = scene.parent().unwrap_or(Path::new(".")).join(&rel);
    crate::input::read(&file).map_err(|e| format!("cannot read '{}': {e}", file.display()))
}

/// `%XX` escapes to bytes; the result must be UTF-8.
fn percent_decode(s: &str) -> Result<String, String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = b
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| {
                    format!("a bad %-escape in the URI '{}'", crate::input::shorten(s))
                })?;
            out.push(hex);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| "a URI that is not UTF-8 once unescaped".into())
}

/// Standard base64 (RFC 4648 §4), padding optional; whitespace is not allowed in a URI.
pub fn decode_base64(s: &str) -> Result<Vec<u8>, String> {
    let s = s.trim_end_matches('=');
    let mut out = Vec::with_capacity(s.len() / 4 * 3 + 2);
    let (mut acc, mut bits) = (0u32, 0u32);
    for (i, c) in s.bytes().enumerate() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => {
                return Err(format!(
                    "a data: URI with a non-base64 character at offset {i}"
                ))
            }
        };
        acc = (acc << 6) | v as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    if bits >= 6 {
        return Err("a data: URI whose base64 length is impossible".into());
    }
    Ok(out)
}

impl Loader<'_> {
    /// The bytes of a buffer view, checked against its buffer.
    pub fn view_bytes(&self, view: &::gltf::buffer::View) -> Result<&[u8], SceneError> {
        let buf = &self.buffers[view.buffer().index()];
        let (start, len) = (view.offset(), view.length());
        start
            .checked_add(len)
            .and_then(|end| buf.get(start..end))
            .ok_or_else(|| {
                self.err(format!(
                    "bufferViews[{}] (bytes {start} to {start}+{len}) lies outside its buffer \
                     ({} bytes)",
                    view.index(),
                    buf.len()
                ))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(decode_base64("AAEC/w==").unwrap(), [0, 1, 2, 255]);
        assert_eq!(decode_base64("").unwrap(), b"");
        assert!(decode_base64("a").is_err());
        assert!(decode_base64("aGV*").is_err());
    }

    #[test]
    fn percent_escapes() {
        assert_eq!(percent_decode("my%20mesh.bin").unwrap(), "my mesh.bin");
        assert!(percent_decode("bad%2").is_err());
    }

    #[test]
    fn glb_header_checks() {
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(20u32.to_le_bytes());
        glb.extend(0u32.to_le_bytes());
        glb.extend(b"JSON");
        assert_eq!(check_glb_header(&glb), Ok(()));
        assert!(check_glb_header(&glb[..16])
            .unwrap_err()
            .contains("truncated"));
        let mut long = glb.clone();
        long[12..16].copy_from_slice(&8u32.to_le_bytes());
        assert!(check_glb_header(&long)
            .unwrap_err()
            .contains("past the end"));
        let mut short = glb.clone();
        short[8..12].copy_from_slice(&4u32.to_le_bytes());
        assert!(check_glb_header(&short).unwrap_err().contains("too few"));
    }
}
