//! Point clouds as PLY (binary little-endian): one vertex per mirror pixel, where the pixel's
//! reflected ray ends (its origin plus range times direction), with the id of what it met.

use std::io::Write;

use glam::Vec3;

/// The PLY file of `points` (position, id), with `comments` in its header (one line each).
pub fn ply(points: &[(Vec3, u32)], comments: &[String]) -> Vec<u8> {
    let mut out = Vec::with_capacity(256 + points.len() * 16);
    let mut header = String::from("ply\nformat binary_little_endian 1.0\n");
    for c in comments {
        // A comment is one header line: no line break may end it early.
        header.push_str(&format!("comment {}\n", c.replace(['\n', '\r'], " ")));
    }
    header.push_str(&format!(
        "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property uint id\nend_header\n",
        points.len()
    ));
    out.extend_from_slice(header.as_bytes());
    for (p, id) in points {
        for v in p.to_array() {
            out.write_all(&v.to_le_bytes()).expect("a Vec grows");
        }
        out.write_all(&id.to_le_bytes()).expect("a Vec grows");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_then_sixteen_bytes_a_point() {
        let bytes = ply(
            &[(Vec3::new(1.0, -2.0, 3.5), 7), (Vec3::ZERO, 0)],
            &["frame: scene\nsecond line".into()],
        );
        let text_end = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .unwrap()
            + 11;
        let header = std::str::from_utf8(&bytes[..text_end]).unwrap();
        assert!(
            header.contains("comment frame: scene second line\n"),
            "{header}"
        );
        assert!(header.contains("element vertex 2\n"));
        let body = &bytes[text_end..];
        assert_eq!(body.len(), 32);
        let f = |i: usize| f32::from_le_bytes(body[i..i + 4].try_into().unwrap());
        assert_eq!([f(0), f(4), f(8)], [1.0, -2.0, 3.5]);
        assert_eq!(u32::from_le_bytes(body[12..16].try_into().unwrap()), 7);
    }
}
