//! Wavefront OBJ: positions, texture coordinates, normals and polygonal faces.
//!
//! A hand-written reader rather than a library, so that every refusal names its line and says
//! what the statement should look like, and so that the work is bounded before it is done.

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use super::{check_budget, Part};
use crate::scene::asset::AssetError;
use crate::text::quoted_text;
use crate::watch::Watch;

/// Statements that carry nothing a mesh of ours needs: object and group names, smoothing
/// groups, materials (the scene assigns the material), lines, points, parameter-space vertices.
const IGNORED: &[&str] = &["o", "g", "s", "mg", "usemtl", "mtllib", "l", "p", "vp"];

/// One face corner: indices (0-based) into positions, uvs, normals.
type Corner = (u32, Option<u32>, Option<u32>);

/// Everything read so far; vertices are shared between faces by their (v, vt, vn) triple.
#[derive(Default)]
struct Reader {
    positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    normals: Vec<Vec3>,
    corners: HashMap<Corner, u32>,
    part: Part,
    /// Whether every corner so far had a uv / a normal (else the part gets none of them).
    all_uvs: bool,
    all_normals: bool,
}

/// The most corners a face may have: its fan's indices reach the limit of one mesh file.
const MAX_FACE_CORNERS: usize = super::MAX_MESH_INDICES / 3 + 2;
/// The most numbers a `v`, `vt` or `vn` statement has (`v x y z r g b`).
const MAX_NUMBERS: usize = 7;

/// The lines of `bytes`, each ended by LF, CR LF or a CR alone (classic Mac OS files), without
/// its ending.
fn lines(bytes: &[u8]) -> impl Iterator<Item = &[u8]> {
    let mut rest = Some(bytes);
    std::iter::from_fn(move || {
        let text = rest?;
        match text.iter().position(|&b| b == b'\n' || b == b'\r') {
            None => {
                rest = None;
                Some(text)
            }
            Some(end) => {
                let crlf = text[end] == b'\r' && text.get(end + 1) == Some(&b'\n');
                rest = Some(&text[end + if crlf { 2 } else { 1 }..]);
                Some(&text[..end])
            }
        }
    })
}

/// Parses OBJ text into one part, its bytes reported to `watch` as they are read.
pub(super) fn parse(bytes: &[u8], watch: &dyn Watch) -> Result<Part, AssetError> {
    let mut r = Reader {
        all_uvs: true,
        all_normals: true,
        ..Reader::default()
    };
    // A byte-order mark is not part of the first statement (some editors write one).
    let bytes = bytes.strip_prefix("\u{feff}".as_bytes()).unwrap_or(bytes);
    let mut read = 0;
    for (i, raw) in lines(bytes).enumerate() {
        // A mesh of millions of lines takes seconds: said as it goes, and a signal stops it
        // between two blocks of lines.
        if i % (1 << 16) == 0 {
            let at = raw.as_ptr() as usize - bytes.as_ptr() as usize;
            watch.rows_done(u32::try_from(at - read).unwrap_or(u32::MAX));
            read = at;
            if crate::output::stop_asked() || watch.stop() {
                return Err(AssetError::Stopped);
            }
        }
        let line = i + 1;
        let at = |message: String| AssetError::Obj { line, message };
        // Comments run from '#' to the end of the line, in any encoding, and so may the
        // statements we ignore (an exporter's Latin-1 name in one is no reason to refuse the
        // mesh).
        let code = raw.split(|&b| b == b'#').next().unwrap_or(raw);
        let first = code.split(u8::is_ascii_whitespace).find(|w| !w.is_empty());
        if first.is_some_and(|w| IGNORED.iter().any(|k| k.as_bytes() == w)) {
            continue;
        }
        let text = std::str::from_utf8(code).map_err(|_| {
            at("not UTF-8 text (an OBJ file is text; is this a binary file?)".into())
        })?;
        let mut words = text.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        // The words a statement may have, and one more to tell a line of too many: a line of
        // 125 million words was collected whole (2.3 GB) before it was refused.
        let most = match keyword {
            "f" => MAX_FACE_CORNERS,
            "v" | "vt" | "vn" => MAX_NUMBERS,
            // Ignored, or unknown (refused by name, which needs none of the words).
            _ => 0,
        };
        let args: Vec<&str> = words.by_ref().take(most + 1).collect();
        if most > 0 && args.len() > most {
            return Err(at(format!(
                "`{keyword}` with more than {most} values on one line"
            )));
        }
        r.statement(keyword, &args).map_err(at)?;
    }
    Ok(r.finish())
}

impl Reader {
    fn statement(&mut self, keyword: &str, args: &[&str]) -> Result<(), String> {
        match keyword {
            "v" => {
                let [x, y, z] = numbers::<3>("v", args, 3..=7, "v x y z (optionally w or r g b)")?;
                let far = [x, y, z]
                    .iter()
                    .position(|c| c.abs() > super::MAX_COORDINATE);
                if let Some(k) = far {
                    return Err(format!(
                        "`v` value {} {} is past the ±{:e} a vertex coordinate may hold",
                        k + 1,
                        quoted_text(args[k]),
                        super::MAX_COORDINATE
                    ));
                }
                self.positions.push(Vec3::new(x, y, z));
            }
            "vt" => {
                let [u, v] = numbers::<2>("vt", args, 1..=3, "vt u [v [w]]")?;
                let max = crate::scene::MAX_UV;
                if let Some(k) = [u, v].iter().position(|c| c.abs() > max) {
                    return Err(format!(
                        "`vt` value {} {} is past the ±{max:e} a texture coordinate may hold",
                        k + 1,
                        quoted_text(args[k]),
                    ));
                }
                // OBJ's v grows upwards; ours grows downwards (image row order).
                self.uvs.push(Vec2::new(u, 1.0 - v));
            }
            "vn" => {
                let [x, y, z] = numbers::<3>("vn", args, 3..=3, "vn x y z")?;
                self.normals.push(Vec3::new(x, y, z));
            }
            "f" => self.face(args)?,
            k if IGNORED.contains(&k) => {}
            other => {
                return Err(format!(
                    "unknown statement {}: expected v, vt, vn, f, or one of {} (ignored)",
                    quoted_text(other),
                    IGNORED.join(", ")
                ))
            }
        }
        Ok(())
    }

    /// A polygon, triangulated as a fan around its first corner.
    fn face(&mut self, args: &[&str]) -> Result<(), String> {
        if args.len() < 3 {
            return Err(format!(
                "a face needs at least 3 corners, got {} (f v1 v2 v3 ..., each v, v/vt, v//vn or v/vt/vn)",
                args.len()
            ));
        }
        let triangles = args.len() - 2;
        check_budget(
            self.part.indices.len(),
            triangles * 3,
            self.part.positions.len(),
            args.len(),
        )
        .map_err(|e| e.to_string())?;
        let mut ids = Vec::with_capacity(args.len());
        for (k, corner) in args.iter().enumerate() {
            let c = self
                .corner(corner)
                .map_err(|m| format!("face corner {} {}: {m}", k + 1, quoted_text(corner)))?;
            ids.push(self.vertex(c));
        }
        for t in 1..ids.len() - 1 {
            self.part
                .indices
                .extend_from_slice(&[ids[0], ids[t], ids[t + 1]]);
        }
        Ok(())
    }

    /// Parses `v`, `v/vt`, `v//vn` or `v/vt/vn`.
    fn corner(&self, text: &str) -> Result<Corner, String> {
        let mut fields = text.split('/');
        let v = fields.next().unwrap_or("");
        let vt = fields.next().filter(|s| !s.is_empty());
        let vn = fields.next().filter(|s| !s.is_empty());
        if fields.next().is_some() {
            return Err("too many `/`: expected v, v/vt, v//vn or v/vt/vn".into());
        }
        let v = resolve(v, self.positions.len(), "vertex (v)")?;
        let vt = vt
            .map(|s| resolve(s, self.uvs.len(), "texture coordinate (vt)"))
            .transpose()?;
        let vn = vn
            .map(|s| resolve(s, self.normals.len(), "normal (vn)"))
            .transpose()?;
        Ok((v, vt, vn))
    }

    /// The part's vertex for a corner, added on first use.
    fn vertex(&mut self, c: Corner) -> u32 {
        if let Some(&id) = self.corners.get(&c) {
            return id;
        }
        let (v, vt, vn) = c;
        let p = &mut self.part;
        p.positions.push(self.positions[v as usize]);
        self.all_uvs &= vt.is_some();
        self.all_normals &= vn.is_some();
        p.uvs.push(vt.map_or(Vec2::ZERO, |t| self.uvs[t as usize]));
        p.normals
            .push(vn.map_or(Vec3::ZERO, |n| self.normals[n as usize]));
        let id = (p.positions.len() - 1) as u32;
        self.corners.insert(c, id);
        id
    }

    fn finish(mut self) -> Part {
        // A part has uvs / normals for all its vertices or none (flat normals, zero uvs).
        if !self.all_uvs {
            self.part.uvs.clear();
        }
        if !self.all_normals {
            self.part.normals.clear();
        }
        self.part
    }
}

/// A 1-based (or negative, counting back from the latest) OBJ index into a list of `len`
/// items, as a 0-based index.
fn resolve(text: &str, len: usize, what: &str) -> Result<u32, String> {
    let n: i64 = text
        .parse()
        .map_err(|_| format!("{} is not an index (a whole number)", quoted_text(text)))?;
    let index = if n > 0 {
        n - 1
    } else if n < 0 {
        len as i64 + n
    } else {
        return Err(format!(
            "{what} index 0: OBJ indices start at 1 (or count back from -1)"
        ));
    };
    if index < 0 || index >= len as i64 {
        return Err(format!(
            "refers to {what} {n}, but {len} are defined above this line"
        ));
    }
    Ok(index as u32)
}

/// The first `N` of `args` as finite numbers, after checking the argument count.
fn numbers<const N: usize>(
    keyword: &str,
    args: &[&str],
    count: std::ops::RangeInclusive<usize>,
    form: &str,
) -> Result<[f32; N], String> {
    if !count.contains(&args.len()) {
        return Err(format!(
            "`{keyword}` with {} numbers: expected `{form}`",
            args.len()
        ));
    }
    let mut out = [0.0; N];
    for (k, text) in args.iter().enumerate() {
        let x: f32 = text.parse().map_err(|_| {
            format!(
                "`{keyword}` value {} {} is not a number",
                k + 1,
                quoted_text(text)
            )
        })?;
        if !x.is_finite() {
            return Err(format!(
                "`{keyword}` value {} is {}: must be finite (and within f32 range)",
                k + 1,
                quoted_text(text)
            ));
        }
        if k < N {
            out[k] = x;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unwatched, as a mesh parsed from bytes is.
    fn parse(bytes: &[u8]) -> Result<Part, AssetError> {
        super::parse(bytes, &crate::watch::Unwatched)
    }

    fn err(text: &str) -> String {
        match parse(text.as_bytes()) {
            Ok(_) => panic!("{text:?} must be refused"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn faces_share_corners_and_fan_triangulate() {
        let p = parse(b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1 -1/1\n").unwrap();
        assert_eq!(p.positions.len(), 4);
        assert_eq!(p.indices, vec![0, 1, 2, 0, 2, 3]);
        // v flipped to top-down; no normals anywhere: none kept.
        assert_eq!(p.uvs[0], Vec2::new(0.0, 1.0));
        assert!(p.normals.is_empty());
        // A byte-order mark and CRLF line ends are accepted.
        let p = parse("\u{feff}v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n".as_bytes()).unwrap();
        assert_eq!(p.indices, vec![0, 1, 2]);
        // So are lines ended by a CR alone (classic Mac OS), and ends mixed in one file; a
        // comment need not be UTF-8 (an exporter's Latin-1 "café").
        let p = parse(b"v 0 0 0\rv 1 0 0\r\nv 0 1 0 # caf\xe9\ng caf\xe9\nf 1 2 3\r").unwrap();
        assert_eq!((p.positions.len(), p.indices.len()), (3, 3));
        // And the lines are counted across them.
        assert!(err("v 0 0 0\rv 1 0 0\r\n\rf 1 2 9\n").starts_with("line 4: face corner 3"));
    }

    /// A line of more words than its statement may have is refused at the first word past
    /// them, not collected whole first.
    #[test]
    fn a_line_of_too_many_values_is_refused_by_its_count() {
        let e = err(&format!("v{}\n", " 1".repeat(1000)));
        assert_eq!(e, "line 1: `v` with more than 7 values on one line");
        let corners = MAX_FACE_CORNERS + 1;
        let e = err(&format!("v 0 0 0\nf{}\n", " 1".repeat(corners)));
        assert!(
            e.starts_with(&format!(
                "line 2: `f` with more than {MAX_FACE_CORNERS} values"
            )),
            "{e}"
        );
        // A statement ignored may have any number of words; an unknown one is named.
        assert!(parse(format!("g{}\n", " a".repeat(1000)).as_bytes()).is_ok());
        let e = err(&format!("curv2{}\n", " 1".repeat(10)));
        assert!(e.starts_with("line 1: unknown statement \"curv2\""), "{e}");
    }

    #[test]
    fn bad_statements_name_their_line_and_form() {
        let e = err("v 0 0 0\nv 1 0 0\nf 1 2 3\n");
        assert!(
            e.starts_with("line 3: face corner 3 \"3\": refers to vertex (v) 3, but 2"),
            "{e}"
        );
        assert!(err("v 0 0\n").starts_with("line 1: `v` with 2 numbers: expected `v x y z"));
        assert!(
            err("\n\nv 0 nan 0\n").starts_with("line 3: `v` value 2 is \"nan\": must be finite")
        );
        let far = err("v 0 0 0\nv -1e30 0 0\n");
        assert!(
            far.starts_with("line 2: `v` value 1 \"-1e30\" is past the ±1e15"),
            "{far}"
        );
        let uv = err("vt 0 3e38\n");
        assert!(
            uv.starts_with("line 1: `vt` value 2 \"3e38\" is past the ±1e15"),
            "{uv}"
        );
        assert!(err("v 0 0 0\nf 1 1\n").contains("at least 3 corners"));
        assert!(err("v 0 0 0\nf 0 1 1\n").contains("index 0: OBJ indices start at 1"));
        assert!(err("v 0 0 0\nf 1/2 1 1\n").contains("texture coordinate (vt) 2, but 0"));
        assert!(err("v 0 0 0\nf 1/1/1/1 1 1\n").contains("too many `/`"));
        assert!(err("PK\u{3}\u{4} zip").starts_with("line 1: unknown statement \"PK"));
        let e = parse(b"v 0 0 0\n\xff\xfe\n").err().unwrap().to_string();
        assert!(e.starts_with("line 2: not UTF-8"), "{e}");
    }
}
