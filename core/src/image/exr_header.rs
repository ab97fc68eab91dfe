//! What the `exr` crate does not check in an OpenEXR header, and the format forbids (its own
//! library refuses each):
//! - a data or display window inverted: the crate takes a window's size as the distance
//!   between its corners, so a window whose maximum lies below its minimum read as a valid
//!   image of the mirrored size (or failed later, as damaged pixel data);
//! - an attribute given twice in one part's header: the last one won (a second data window
//!   changed the image's size);
//! - a channel named twice in a part's channel list: the crate reassigned the channels, and
//!   a comparison of such a file read the wrong colours without a word;
//! - a multi-part file cut short in a part other than the one read: the crate reads only the
//!   chunks of the part it decodes, so the file was read as whole ([`cut_short`], which
//!   needs the whole file; the rest is checked on the header alone, [`header_fault`]).
//!
//! The header is a list of attributes, each a name and a type name (both null-terminated),
//! a little-endian i32 size and that many bytes of value, ended by an empty name; a
//! multi-part file has one such list per part and an empty list after the last.

/// The version field's multi-part flag.
const MULTI_PART: u32 = 0x1000;

/// What the header holds that the format forbids (above), said for a user: `"an inverted
/// window, which OpenEXR does not allow (dataWindow: xMax 0 is less than xMin 3)"`; None when
/// there is nothing or the header cannot be walked (the crate's own reading then says what is
/// wrong: cut short, not an EXR). Only the header is read: `bytes` may be the file's first
/// bytes alone.
pub fn header_fault(bytes: &[u8]) -> Option<String> {
    let mut names = std::collections::HashSet::new();
    let mut part = 0;
    let visit = |p: usize, name: &[u8], kind: &[u8], value: &[u8]| {
        if p != part {
            (part, names) = (p, Default::default());
        }
        let named = String::from_utf8_lossy(name);
        if !names.insert(name.to_vec()) {
            return Some(format!(
                "attribute {named} given twice in one header, which OpenEXR does not allow"
            ));
        }
        value_fault(&named, kind, value)
    };
    walk(bytes, visit).err().flatten()
}

/// The headers' attributes, part by part: `visit(part, name, type name, value)` for each, up
/// to the first fault it says (`Err(Some)`); `Ok` with where the headers end (a multi-part
/// file's offset tables begin there), and whether the file is multi-part; `Err(None)` where
/// the bytes are not an EXR header or end inside it.
fn walk(
    bytes: &[u8],
    mut visit: impl FnMut(usize, &[u8], &[u8], &[u8]) -> Option<String>,
) -> Result<(usize, bool), Option<String>> {
    if !has_magic(bytes) {
        return Err(None);
    }
    let version = bytes.get(4..8).ok_or(None)?;
    let version = u32::from_le_bytes(version.try_into().expect("four bytes"));
    let multi_part = version & MULTI_PART != 0;
    let mut at = 8;
    for part in 0.. {
        let mut attributes = 0;
        loop {
            let name = c_string(bytes, &mut at).ok_or(None)?;
            if name.is_empty() {
                break;
            }
            let kind = c_string(bytes, &mut at).ok_or(None)?;
            let size = bytes.get(at..at + 4).ok_or(None)?;
            let size = i32::from_le_bytes(size.try_into().expect("four bytes"));
            at += 4;
            let end = usize::try_from(size).ok().and_then(|s| at.checked_add(s));
            let value = end.and_then(|end| bytes.get(at..end)).ok_or(None)?;
            at += value.len();
            attributes += 1;
            if let Some(why) = visit(part, name, kind, value) {
                return Err(Some(why));
            }
        }
        // A single-part header ends at its first empty name; a multi-part file's list of
        // headers ends with an empty one.
        if !multi_part || attributes == 0 {
            break;
        }
    }
    Ok((at, multi_part))
}

/// A chunk of a multi-part file's part that starts or ends past the file's end, said for a
/// user; None when none does, the file is single-part (the crate reads every chunk of its one
/// part) or the offset tables cannot be read (the crate says so). `parts` are the crate's
/// reading of the headers, in order: each part's chunk count and the bytes from a chunk's
/// start to its data size field after the part number (a scan line's y, 4; a tile's four
/// coordinates, 16; None for deep data, whose chunks are left to the crate). `bytes` must be
/// the whole file: the crate reads only the chunks of the part it decodes, so a file cut
/// short in another part read as whole.
pub fn cut_short(bytes: &[u8], parts: &[(usize, Option<usize>)]) -> Option<String> {
    let (at, multi_part) = walk(bytes, |_, _, _, _| None).ok()?;
    if !multi_part {
        return None;
    }
    let tables_end = (parts.iter()).try_fold(at, |a, &(c, _)| a.checked_add(c.checked_mul(8)?))?;
    let mut tables = bytes.get(at..tables_end)?.chunks_exact(8);
    let end = bytes.len() as u64;
    for (p, &(chunks, size_field)) in parts.iter().enumerate() {
        for k in 0..chunks {
            let start = u64::from_le_bytes(tables.next()?.try_into().ok()?);
            // An offset into the headers or the tables is not a chunk's: the crate, not
            // asked to be pedantic, does not check it either.
            if start < tables_end as u64 {
                continue;
            }
            if start >= end || size_field.is_some_and(|f| !chunk_fits(bytes, start, f)) {
                return Some(format!(
                    "truncated: part {} of {}, chunk {} of {chunks}, at byte {start}, ends past \
                     the file's end ({end} bytes)",
                    p + 1,
                    parts.len(),
                    k + 1
                ));
            }
        }
    }
    None
}

/// Whether the chunk at `start`, whose data size field lies `field` bytes past its part
/// number, ends within `bytes` (a negative size is left to the crate, which says so).
fn chunk_fits(bytes: &[u8], start: u64, field: usize) -> bool {
    let size_at = usize::try_from(start)
        .ok()
        .and_then(|s| s.checked_add(4 + field));
    let Some(size) = size_at.and_then(|at| bytes.get(at..at.checked_add(4)?)) else {
        return false;
    };
    let size = i32::from_le_bytes(size.try_into().expect("four bytes"));
    let after_size = size_at.expect("read above") as u64 + 4;
    u64::try_from(size).map_or(true, |size| after_size + size <= bytes.len() as u64)
}

/// Whether `bytes` start as an OpenEXR file does (its four-byte magic number).
pub fn has_magic(bytes: &[u8]) -> bool {
    bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01])
}

/// What an attribute's value holds that the format forbids: an inverted window, a channel
/// named twice.
fn value_fault(name: &str, kind: &[u8], value: &[u8]) -> Option<String> {
    match kind {
        // Only the two windows the format requires: an optional box (a tool's own, say) may
        // be an empty one, min above max, as Imath writes it.
        b"box2i" if value.len() == 16 && matches!(name, "dataWindow" | "displayWindow") => {
            inverted(value).map(|why| {
                format!("an inverted window, which OpenEXR does not allow ({name}: {why})")
            })
        }
        b"chlist" => twice_named(value).map(|channel| {
            format!("channel {channel} named twice in {name}, which OpenEXR does not allow")
        }),
        _ => None,
    }
}

/// A name given twice in a channel list: entries of a null-terminated name and 16 bytes
/// (pixel type, linearity and reserved bytes, x and y sampling), ended by an empty name.
fn twice_named(list: &[u8]) -> Option<String> {
    let mut seen = std::collections::HashSet::new();
    let mut at = 0;
    loop {
        let name = c_string(list, &mut at)?;
        if name.is_empty() {
            return None;
        }
        if !seen.insert(name) {
            return Some(String::from_utf8_lossy(name).into_owned());
        }
        at += 16;
    }
}

/// `"xMax 0 is less than xMin 3"` for a box2i (xMin, yMin, xMax, yMax) inverted on an axis.
fn inverted(value: &[u8]) -> Option<String> {
    let corner = |i: usize| i32::from_le_bytes(value[4 * i..4 * i + 4].try_into().unwrap());
    let (x_min, y_min, x_max, y_max) = (corner(0), corner(1), corner(2), corner(3));
    if x_max < x_min {
        return Some(format!("xMax {x_max} is less than xMin {x_min}"));
    }
    (y_max < y_min).then(|| format!("yMax {y_max} is less than yMin {y_min}"))
}

/// The null-terminated bytes at `at` (without the null), `at` moved past the null.
fn c_string<'a>(bytes: &'a [u8], at: &mut usize) -> Option<&'a [u8]> {
    let rest = bytes.get(*at..)?;
    let len = rest.iter().position(|&b| b == 0)?;
    *at += len + 1;
    Some(&rest[..len])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One attribute: name, type name, value.
    type Attribute = (&'static str, &'static str, Vec<u8>);

    /// A header of each part's attributes, each part's list ended by a null; multi-part when
    /// there are several (then an empty list closes them).
    fn header(parts: &[Vec<Attribute>]) -> Vec<u8> {
        let mut out = vec![0x76, 0x2f, 0x31, 0x01];
        let flags = if parts.len() > 1 { MULTI_PART } else { 0 };
        out.extend((2 | flags).to_le_bytes());
        for attributes in parts {
            for (name, kind, value) in attributes {
                out.extend(name.as_bytes());
                out.push(0);
                out.extend(kind.as_bytes());
                out.push(0);
                out.extend((value.len() as i32).to_le_bytes());
                out.extend(value);
            }
            out.push(0);
        }
        if parts.len() > 1 {
            out.push(0);
        }
        out
    }

    fn window(c: [i32; 4]) -> Vec<u8> {
        c.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    #[test]
    fn inverted_windows_are_named_and_good_ones_pass() {
        let good = window([0, 0, 3, 2]);
        let one_pixel = window([5, 5, 5, 5]);
        let x = window([3, 0, 0, 2]);
        let y = window([0, 2, 3, 0]);
        let part = |data: &Vec<u8>, display: &Vec<u8>| -> Vec<Attribute> {
            vec![
                ("compression", "compression", vec![3u8]),
                ("dataWindow", "box2i", data.clone()),
                ("displayWindow", "box2i", display.clone()),
            ]
        };
        let case =
            |data: &Vec<u8>, display: &Vec<u8>| header_fault(&header(&[part(data, display)]));
        assert_eq!(case(&good, &good), None);
        assert_eq!(case(&one_pixel, &good), None);
        // A box of a tool's own may be empty (Imath's: min INT_MAX, max INT_MIN).
        let mut own = part(&good, &good);
        own.push((
            "originalDataWindow",
            "box2i",
            window([i32::MAX, i32::MAX, i32::MIN, i32::MIN]),
        ));
        assert_eq!(header_fault(&header(&[own])), None);
        assert_eq!(
            case(&x, &good).as_deref(),
            Some(
                "an inverted window, which OpenEXR does not allow (dataWindow: xMax 0 is less \
                 than xMin 3)"
            )
        );
        assert_eq!(
            case(&good, &y).as_deref(),
            Some(
                "an inverted window, which OpenEXR does not allow (displayWindow: yMax 0 is \
                 less than yMin 2)"
            )
        );
        // Every part of a multi-part file is walked: the third's window is found.
        let good_part = part(&good, &good);
        let parts = [good_part.clone(), good_part.clone(), good_part.clone()];
        assert_eq!(header_fault(&header(&parts)), None);
        let parts = [good_part.clone(), good_part, part(&good, &y)];
        assert!(header_fault(&header(&parts)).is_some_and(|w| w.contains("displayWindow: yMax")));
        // An attribute given twice in a part, and a channel named twice in its list.
        let mut twice = part(&good, &good);
        twice.push(("dataWindow", "box2i", good.clone()));
        assert_eq!(
            header_fault(&header(&[twice])).as_deref(),
            Some("attribute dataWindow given twice in one header, which OpenEXR does not allow")
        );
        let channel = |name: &str| {
            let mut entry = name.as_bytes().to_vec();
            entry.push(0);
            entry.extend([0u8; 16]);
            entry
        };
        let list = |names: &[&str]| -> Vec<u8> {
            let mut out: Vec<u8> = names.iter().flat_map(|n| channel(n)).collect();
            out.push(0);
            out
        };
        let with_channels = |names: &[&str]| {
            let mut p = part(&good, &good);
            p.push(("channels", "chlist", list(names)));
            header_fault(&header(&[p]))
        };
        assert_eq!(with_channels(&["A", "B", "G", "R"]), None);
        assert_eq!(
            with_channels(&["B", "G", "R", "R"]).as_deref(),
            Some("channel R named twice in channels, which OpenEXR does not allow")
        );
        // Without the magic number it is not an EXR header: left to the crate to say so.
        let mut not_exr = header(&[part(&x, &good)]);
        not_exr[0] = b'P';
        assert_eq!(header_fault(&not_exr), None);
        // A header cut short, or with a size past the end, is left to the crate.
        let cut = header(&[vec![("dataWindow", "box2i", x.clone())]]);
        assert_eq!(header_fault(&cut[..cut.len() - 6]), None);
        let mut lying = header(&[vec![("dataWindow", "box2i", x)]]);
        let size_at = 8 + "dataWindow\0box2i\0".len();
        lying[size_at..size_at + 4].copy_from_slice(&i32::MAX.to_le_bytes());
        assert_eq!(header_fault(&lying), None);
        assert_eq!(header_fault(b"v/1"), None);
    }
}
