//! The scene file's text: bytes decoded as UTF-8 (with a located message when they are not),
//! and TOML syntax errors turned into messages that say what is wrong, where, and what is
//! allowed.

use std::path::Path;

use crate::scene::error::{Location, SceneError};

/// How deep the scene format itself nests tables, arrays and dotted keys: `[[objects]]` ->
/// `animation` -> `positions` -> one position (messages quote it).
const FORMAT_DEPTH: usize = 4;

/// The scene text, or an error naming the line and column of the first byte that is not
/// UTF-8 and guessing the encoding the file is in.
pub(super) fn decode(path: &Path, bytes: Vec<u8>) -> Result<String, SceneError> {
    let e = match String::from_utf8(bytes) {
        Ok(text) => return Ok(text),
        Err(e) => e,
    };
    let bytes = e.as_bytes();
    let at = e.utf8_error().valid_up_to();
    // The valid prefix is text: count lines and characters in it.
    let prefix = String::from_utf8_lossy(&bytes[..at]);
    let location = Location::at_offset(path, &prefix, prefix.len());
    let utf16 = bytes.starts_with(&[0xFF, 0xFE])
        || bytes.starts_with(&[0xFE, 0xFF])
        || bytes.iter().take(64).filter(|&&b| b == 0).count() > 8;
    let message = if utf16 {
        "the file is UTF-16 (a byte-order mark or NUL bytes between characters); scene files must be UTF-8: save it as UTF-8".to_string()
    } else {
        format!(
            "byte 0x{:02X} is not UTF-8 (the file looks like Latin-1 or another 8-bit encoding); scene files must be UTF-8: save it as UTF-8",
            bytes[at]
        )
    };
    Err(SceneError::Encoding { location, message })
}

/// A TOML syntax error, located. The TOML reader's nesting limit gives "recursion limit" and
/// no position for a deeply dotted key or header: find the line ourselves and say what the
/// format allows.
pub(super) fn syntax_error(path: &Path, text: &str, e: &toml::de::Error) -> SceneError {
    let message = e.message().trim();
    let too_deep = message.contains("recursion") || message.contains("recurse");
    let location = match (e.span(), too_deep) {
        (Some(span), _) => Location::at_offset(path, text, span.start),
        (None, true) => match deepest_dotted_line(text) {
            Some(offset) => Location::at_offset(path, text, offset),
            None => Location::file_only(path),
        },
        (None, false) => Location::file_only(path),
    };
    let message = if too_deep {
        format!(
            "nesting too deep: this table header, dotted key, array or inline table nests deeper than the TOML reader allows ({message}); the scene format nests at most {FORMAT_DEPTH} levels (objects[0].animation.positions[0])"
        )
    } else {
        message.to_string()
    };
    SceneError::Syntax { location, message }
}

/// The byte offset of the first line whose key or table header has the most dots.
fn deepest_dotted_line(text: &str) -> Option<usize> {
    let mut best: Option<(usize, usize)> = None;
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        // Dots in comments and in values (`1.5`, "a.obj") do not nest anything.
        let code = line.split('#').next().unwrap_or(line);
        let key = code.split('=').next().unwrap_or(code);
        let dots = key.bytes().filter(|&b| b == b'.').count();
        if dots > 0 && best.is_none_or(|(most, _)| dots > most) {
            best = Some((dots, offset + (line.len() - line.trim_start().len())));
        }
        offset += line.len();
    }
    best.map(|(_, at)| at)
}
