//! The bytes behind a glTF document: the GLB container, and each buffer's data from the GLB
//! binary chunk, a `data:` URI or a file beside the glTF file.
//!
//! A glTF file is often someone else's content, so its URIs may reach only inside its own
//! folder: no absolute paths, no schemes other than `data:`, no `..`, and no symbolic link
//! leading out. External files are read through the shared regular-file reader, all of a
//! document's external buffers together within [`MAX_GLTF_BUFFER_BYTES`].

use std::path::{Path, PathBuf};

use gltf::json::Root;

use crate::files::{read_regular_file, MAX_GLTF_BUFFER_BYTES};
use crate::scene::asset::AssetError;
use crate::text::quoted_text;

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// The two parts of a glTF asset: its JSON text and, for GLB, its binary chunk.
pub(super) struct Container<'a> {
    pub json: &'a [u8],
    pub bin: Option<&'a [u8]>,
}

/// Splits a GLB container, or takes the bytes as glTF JSON when they do not start with the
/// GLB magic.
pub(super) fn container(bytes: &[u8]) -> Result<Container<'_>, AssetError> {
    if !bytes.starts_with(GLB_MAGIC) {
        return Ok(Container {
            json: bytes,
            bin: None,
        });
    }
    let word = |at: usize| -> Option<u32> {
        let b = bytes.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let header = |m: String| AssetError::gltf("GLB header", m);
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(header(format!(
            "file is {} bytes, shorter than the 12-byte GLB header",
            bytes.len()
        )));
    };
    if version != 2 {
        return Err(header(format!("version {version}; only glTF 2 is read")));
    }
    if length as usize != bytes.len() {
        return Err(header(format!(
            "says the file is {length} bytes, but it is {} (truncated or padded?)",
            bytes.len()
        )));
    }
    let json = chunk(bytes, 12, CHUNK_JSON, "first chunk (JSON)")?;
    let json_end = 12 + 8 + json.len();
    let bin = if json_end < bytes.len() {
        Some(chunk(bytes, json_end, CHUNK_BIN, "second chunk (BIN)")?)
    } else {
        None
    };
    Ok(Container { json, bin })
}

/// The data of the chunk at byte `at`, which must be of type `kind` and fit in the file.
fn chunk<'a>(bytes: &'a [u8], at: usize, kind: u32, name: &str) -> Result<&'a [u8], AssetError> {
    let err = |m: String| AssetError::gltf(format!("GLB {name}"), m);
    let head = bytes
        .get(at..at + 8)
        .ok_or_else(|| err(format!("missing: the file ends at byte {}", bytes.len())))?;
    let length = u32::from_le_bytes([head[0], head[1], head[2], head[3]]) as usize;
    let found = u32::from_le_bytes([head[4], head[5], head[6], head[7]]);
    if found != kind {
        return Err(err(format!(
            "has type 0x{found:08X}, expected 0x{kind:08X}"
        )));
    }
    bytes
        .get(at + 8..(at + 8).saturating_add(length))
        .ok_or_else(|| {
            err(format!(
                "says it holds {length} bytes from byte {}, past the end of the file ({} bytes)",
                at + 8,
                bytes.len()
            ))
        })
}

/// Each buffer's bytes, exactly `byteLength` long.
pub(super) fn load(
    root: &Root,
    bin: Option<&[u8]>,
    folder: &Path,
) -> Result<Vec<Vec<u8>>, AssetError> {
    let mut external_bytes = 0u64;
    let mut out = Vec::with_capacity(root.buffers.len());
    for (i, buffer) in root.buffers.iter().enumerate() {
        let at = format!("buffers[{i}]");
        let data =
            match &buffer.uri {
                None if i == 0 && bin.is_some() => bin.unwrap_or_default().to_vec(),
                None => return Err(AssetError::gltf(
                    format!("{at}.uri"),
                    "missing: only buffer 0 of a GLB file may omit its uri (it is the BIN chunk)",
                )),
                Some(uri) if uri.starts_with("data:") => {
                    data_uri(uri).map_err(|m| AssetError::gltf(format!("{at}.uri"), m))?
                }
                Some(uri) => {
                    let path = resolve_uri(folder, uri)
                        .map_err(|m| AssetError::gltf(format!("{at}.uri"), m))?;
                    let budget = MAX_GLTF_BUFFER_BYTES - external_bytes;
                    let data = read_regular_file(&path, budget).map_err(|e| {
                        AssetError::gltf(
                            format!("{at}.uri"),
                            format!(
                                "{}: {e} (external buffers together may hold at most {} MiB)",
                                quoted_text(uri),
                                MAX_GLTF_BUFFER_BYTES >> 20
                            ),
                        )
                    })?;
                    external_bytes += data.len() as u64;
                    data
                }
            };
        let length = buffer.byte_length.0;
        if (data.len() as u64) < length {
            return Err(AssetError::gltf(
                format!("{at}.byteLength"),
                format!(
                    "is {length}, but the buffer's data holds only {} bytes",
                    data.len()
                ),
            ));
        }
        let mut data = data;
        data.truncate(length as usize);
        out.push(data);
    }
    Ok(out)
}

/// The file a relative URI names inside `folder`, or why it may not be read.
fn resolve_uri(folder: &Path, uri: &str) -> Result<PathBuf, String> {
    let allowed = "allowed: a data: URI, or a relative path inside the glTF file's folder";
    let decoded = percent_decode(uri).ok_or_else(|| {
        format!(
            "{} has a malformed %-escape or is not UTF-8",
            quoted_text(uri)
        )
    })?;
    let first = decoded.split('/').next().unwrap_or("");
    if decoded.is_empty() {
        return Err(format!("is empty; {allowed}"));
    }
    if decoded.starts_with('/') || decoded.contains('\\') || first.contains(':') {
        return Err(format!(
            "{} is absolute, has a scheme or a backslash; {allowed}",
            quoted_text(uri)
        ));
    }
    if decoded.split('/').any(|s| s == "..") {
        return Err(format!("{} uses `..`; {allowed}", quoted_text(uri)));
    }
    let path = folder.join(&decoded);
    // A symbolic link inside the folder must not lead out of it either. A path that does not
    // resolve is left for the reader, which reports it as missing (or as a link loop).
    if let (Ok(inside), Ok(target)) = (folder.canonicalize(), path.canonicalize()) {
        if !target.starts_with(&inside) {
            return Err(format!(
                "{} is a symbolic link to {}, outside the glTF file's folder; {allowed}",
                quoted_text(uri),
                target.display()
            ));
        }
    }
    Ok(path)
}

/// `%XX` escapes decoded; `None` for a bad escape or non-UTF-8 result.
fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// The bytes of a base64 `data:` URI (glTF allows no other encoding).
fn data_uri(uri: &str) -> Result<Vec<u8>, String> {
    let Some((header, payload)) = uri.split_once(',') else {
        return Err("data: URI without a `,` before its data".into());
    };
    if !header.ends_with(";base64") {
        return Err(format!(
            "data: URI {} is not base64; glTF buffers use `data:<type>;base64,<data>`",
            quoted_text(header)
        ));
    }
    base64(payload).map_err(|m| format!("data: URI: {m}"))
}

/// Standard base64 (`+`, `/`, optional `=` padding) decoded.
fn base64(text: &str) -> Result<Vec<u8>, String> {
    let digits = text.trim_end_matches('=');
    if text.len() - digits.len() > 2 {
        return Err("more than two `=` at the end of the base64 data".into());
    }
    let mut out = Vec::with_capacity(digits.len() / 4 * 3 + 2);
    let (mut acc, mut bits) = (0u32, 0u32);
    for (i, c) in digits.bytes().enumerate() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => {
                return Err(format!(
                    "byte {i} of the base64 data is {:?}, not a base64 digit",
                    c as char
                ))
            }
        };
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    if bits >= 6 {
        return Err("base64 data ends in the middle of a byte".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_known_answers() {
        assert_eq!(base64("").unwrap(), b"");
        assert_eq!(base64("Zg==").unwrap(), b"f");
        assert_eq!(base64("Zm8=").unwrap(), b"fo");
        assert_eq!(base64("Zm9vYmFy").unwrap(), b"foobar");
        assert!(base64("Zm9v!").is_err());
        assert!(base64("Z").is_err());
    }

    #[test]
    fn uris_stay_inside_the_folder() {
        let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/meshes");
        assert_eq!(
            resolve_uri(&folder, "sub%20dir/a.bin").unwrap(),
            folder.join("sub dir/a.bin")
        );
        for bad in [
            "../secret.bin",
            "a/../../x",
            "/etc/passwd",
            "file:///etc/passwd",
            "C:\\x",
            "%2e%2e/x",
            "%zz",
        ] {
            assert!(resolve_uri(&folder, bad).is_err(), "{bad} must be refused");
        }
    }

    #[test]
    fn glb_lengths_are_checked() {
        let mut glb = Vec::new();
        glb.extend_from_slice(b"glTF");
        glb.extend_from_slice(&2u32.to_le_bytes());
        glb.extend_from_slice(&24u32.to_le_bytes());
        glb.extend_from_slice(&4u32.to_le_bytes());
        glb.extend_from_slice(&CHUNK_JSON.to_le_bytes());
        glb.extend_from_slice(b"{}  ");
        let c = container(&glb).unwrap();
        assert_eq!((c.json, c.bin), (&b"{}  "[..], None));
        let e = container(&glb[..20]).err().unwrap().to_string();
        assert!(
            e.starts_with("GLB header: says the file is 24 bytes, but it is 20"),
            "{e}"
        );
        glb[12] = 200;
        let e = container(&glb).err().unwrap().to_string();
        assert!(e.contains("past the end of the file"), "{e}");
    }
}
