//! The landmark database file (`landmarks.json`): written by every run, read back by
//! `--landmarks FILE` to skip the sweep. One typed record for both directions; a file that does
//! not fit this run (another scene, descriptor, size, panorama or source settings) is refused
//! naming the file and the field, since its signatures would be compared with unlike ones.

use std::path::Path;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use specchio::files::read_regular_file;
use specchio::sensor::localise::{DescriptorKind, Signature};
use specchio::text::num_text;

/// Largest landmarks file read (bytes), so that reading one stays within memory. At the
/// default settings (a 256² sensor, column-shift k=8: 5,248 values of about 22 bytes each) it
/// holds about 2,300 landmarks; a run that would write a larger file says so before its sweep
/// (`warn_if_unreadable` in `mod.rs`).
pub const MAX_LANDMARKS_FILE_BYTES: u64 = 256 << 20;

/// The file's `format` value.
pub const FORMAT: &str = "specchio-landmarks";
/// Version 2 added the source, grid, scene hash and cube size (version 1 had none of them and
/// cannot be checked, so it is refused). Version 3: the column-shift descriptor keeps 16
/// columns per `k`, not 8, so the same settings now mean another signature; the version
/// says so in the refusal rather than a count of columns.
pub const VERSION: u32 = 3;

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Landmark {
    /// The mirror's centre, local (scene file minus `scene_origin_m`).
    pub position_m: [f32; 3],
    pub signature: Signature,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Database {
    pub format: String,
    pub version: u32,
    /// The scene file as given on the command line (for people; `scene_hash` is checked).
    pub scene: String,
    /// FNV-1a (64 bit) of the scene file's bytes, in hex: a changed scene is another scene.
    pub scene_hash: String,
    pub scene_origin_m: [f64; 3],
    /// Which images the signatures describe (`--sources`: a lookup or `reference`).
    pub source: String,
    pub descriptor: String,
    pub coefficients: u32,
    pub grid_m: f64,
    pub sensor_px: u32,
    /// Cube face size of a lookup's images; none for the reference, which has no cube.
    pub cube_px: Option<u32>,
    /// The cylindrical panorama the signatures were taken from (`PanoramaLayout`).
    pub panorama: serde_json::Value,
    pub landmarks: Vec<Landmark>,
}

/// FNV-1a, 64 bit: a cheap, stable fingerprint (not a defence against forgery).
pub fn fnv1a64(bytes: &[u8]) -> String {
    let hash = bytes.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    });
    format!("{hash:016x}")
}

/// Reads `path` and checks it against `expected_for(source)`: this run's settings for the
/// file's source (its landmarks empty), or why that source is not part of this run.
pub fn load(
    path: &Path,
    expected_for: &dyn Fn(&str) -> Result<Database, String>,
) -> Result<Database> {
    let name = path.display();
    let bytes = read_regular_file(path, MAX_LANDMARKS_FILE_BYTES)
        .with_context(|| format!("--landmarks {name}: reading"))?;
    parse(&bytes, &name.to_string(), expected_for)
}

/// [`load`] on the file's bytes; `name` is how errors name the file.
pub fn parse(
    bytes: &[u8],
    name: &str,
    expected_for: &dyn Fn(&str) -> Result<Database, String>,
) -> Result<Database> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| anyhow::anyhow!("--landmarks {name}: not UTF-8 text ({e})"))?;
    // Format and version first, so an old or foreign file says so rather than "missing field".
    let value = specchio::files::json::parse_unique_keys(text)
        .with_context(|| format!("--landmarks {name}: not a landmarks file (malformed JSON)"))?;
    // What a field holds, as the file spells it.
    let shown = |field: &str| match value.get(field) {
        Some(v) => format!("is {v}"),
        None => "is missing".to_owned(),
    };
    if value.get("format").and_then(|v| v.as_str()) != Some(FORMAT) {
        bail!(
            "--landmarks {name}: field `format` {}, expected \"{FORMAT}\"",
            shown("format")
        );
    }
    if value.get("version").and_then(|v| v.as_u64()) != Some(u64::from(VERSION)) {
        bail!(
            "--landmarks {name}: field `version` {}, this specchio reads {VERSION}",
            shown("version")
        );
    }
    let db: Database = serde_json::from_str(text)
        .with_context(|| format!("--landmarks {name}: not a version {VERSION} landmarks file"))?;
    let expected =
        expected_for(&db.source).map_err(|e| anyhow::anyhow!("--landmarks {name}: {e}"))?;
    check_matches(&db, &expected).map_err(|e| anyhow::anyhow!("--landmarks {name}: {e}"))?;
    check_signatures(&db, &expected).map_err(|e| anyhow::anyhow!("--landmarks {name}: {e}"))?;
    Ok(db)
}

/// The first field that differs from this run's settings, with both values.
fn check_matches(db: &Database, run: &Database) -> Result<(), String> {
    // Said as a person reads them: no `Some(8)`, no 300 digits of a tiny spacing.
    let point = |p: [f64; 3]| format!("[{}]", p.map(num_text).join(", "));
    let cube = |c: Option<u32>| c.map_or("missing or null".to_owned(), |c| c.to_string());
    let fields: [(&str, String, String, &str); 8] = [
        (
            "scene_hash",
            db.scene_hash.clone(),
            run.scene_hash.clone(),
            "the scene file's contents",
        ),
        (
            "descriptor",
            db.descriptor.clone(),
            run.descriptor.clone(),
            "--descriptor",
        ),
        (
            "coefficients",
            db.coefficients.to_string(),
            run.coefficients.to_string(),
            "--k",
        ),
        (
            "grid_m",
            num_text(db.grid_m),
            num_text(run.grid_m),
            "--grid",
        ),
        (
            "sensor_px",
            db.sensor_px.to_string(),
            run.sensor_px.to_string(),
            "--sensor-size",
        ),
        (
            "panorama",
            db.panorama.to_string(),
            run.panorama.to_string(),
            "the sensor's panorama",
        ),
        (
            "scene_origin_m",
            point(db.scene_origin_m),
            point(run.scene_origin_m),
            "the scene's origin",
        ),
        (
            "cube_px",
            cube(db.cube_px),
            cube(run.cube_px),
            "--cube-size",
        ),
    ];
    // Before 1 December 2026 a k past what the panorama holds was cut silently and recorded
    // as asked: such a file's k cannot be asked for now, so say what to do instead.
    let kind = specchio::sensor::localise::DescriptorKind::parse(&run.descriptor);
    let width = run.panorama["width"]
        .as_u64()
        .and_then(|w| u32::try_from(w).ok());
    if let (Some(kind), Some(width)) = (kind, width) {
        if db.descriptor == run.descriptor && db.coefficients != run.coefficients {
            if let Some(why) = kind.k_fault(db.coefficients, width) {
                return Err(format!(
                    "field `coefficients` is {}: --k {0}: {why}; files written before 1 \
                     December 2026 recorded a k the panorama could not hold (their signatures \
                     were made with less): take the landmarks again",
                    db.coefficients
                ));
            }
        }
    }
    // A source that samples no cube does not read the field: files written before
    // 30 November 2026 recorded `--cube-size` for traced lookups too.
    let read = |field: &str| field != "cube_px" || run.cube_px.is_some();
    for (field, saved, now, from) in fields {
        if read(field) && saved != now {
            return Err(format!(
                "field `{field}` is {saved}, this run has {now} ({from}): the landmarks were \
                 taken with other settings"
            ));
        }
    }
    Ok(())
}

/// Every signature must have the shape this run's descriptor gives the saved panorama
/// (columns and values), be finite and describe an image; and there must be one. The run's
/// settings are already known to equal the file's (`check_matches`).
fn check_signatures(db: &Database, run: &Database) -> Result<(), String> {
    if db.landmarks.is_empty() {
        return Err("field `landmarks` is empty".to_owned());
    }
    let (columns, values) = expected_shape(run)?;
    let mut seen = std::collections::HashMap::new();
    for (i, l) in db.landmarks.iter().enumerate() {
        if let Some(first) = seen.insert(l.position_m.map(f32::to_bits), i) {
            return Err(format!(
                "field `landmarks[{i}]`: the position of `landmarks[{first}]` again (a \
                 database holds one landmark a place; an edited or damaged file)"
            ));
        }
        let s = &l.signature;
        let problem = if s.values.len() != values {
            format!(
                "{} signature values, where {} k={} makes {values} of this panorama",
                s.values.len(),
                run.descriptor,
                run.coefficients
            )
        } else if s.columns != columns {
            format!(
                "{} columns, where {} k={} makes {columns} of this panorama",
                s.columns, run.descriptor, run.coefficients
            )
        } else if !s.values.iter().all(|v| v.is_finite()) {
            "a non-finite signature value".to_owned()
        } else if !l.position_m.iter().all(|v| v.is_finite()) {
            // 1e308 reads as an f32 infinity: say what is wrong with the number written.
            "a position that is not a number of metres within single precision (|x| <= 3.4e38)"
                .to_owned()
        } else if s.values.iter().all(|&v| v == 0.0) {
            // Every distance to it is the query's own norm: it would match arbitrarily.
            "a signature of zeros, which describes no image (a damaged file)".to_owned()
        } else {
            continue;
        };
        return Err(format!("field `landmarks[{i}]`: {problem}"));
    }
    Ok(())
}

/// The signature shape (columns, values) `run`'s descriptor makes of its panorama.
fn expected_shape(run: &Database) -> Result<(u32, usize), String> {
    let size = |field: &str| {
        run.panorama
            .get(field)
            .and_then(|v| v.as_u64())
            .and_then(|v| u32::try_from(v).ok())
            .ok_or_else(|| format!("field `panorama.{field}` is not a panorama size"))
    };
    let kind = DescriptorKind::parse(&run.descriptor)
        .ok_or_else(|| format!("field `descriptor` {} is not a descriptor", run.descriptor))?;
    Ok(kind
        .build(run.coefficients)
        .shape(size("width")?, size("height")?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a64_known_answers() {
        // The published FNV-1a 64 test vectors.
        assert_eq!(fnv1a64(b""), "cbf29ce484222325");
        assert_eq!(fnv1a64(b"a"), "af63dc4c8601ec8c");
        assert_eq!(fnv1a64(b"foobar"), "85944171f73967e8");
    }

    /// A box source's database at settings of no consequence.
    fn saved_box() -> Database {
        Database {
            format: "specchio-landmarks".into(),
            version: VERSION,
            scene: "s.toml".into(),
            scene_hash: fnv1a64(b""),
            scene_origin_m: [0.0; 3],
            source: "box".into(),
            descriptor: "fourier".into(),
            coefficients: 8,
            grid_m: 1e-300,
            sensor_px: 16,
            cube_px: Some(8),
            panorama: serde_json::Value::Null,
            landmarks: Vec::new(),
        }
    }

    /// A setting that differs is said as a person reads it: no `Some(8)`, no 300 digits.
    #[test]
    fn a_differing_setting_is_said_plainly() {
        let db = saved_box();
        let run = Database {
            cube_px: Some(16),
            ..db.clone()
        };
        let e = check_matches(&db, &run).unwrap_err();
        assert!(
            e.starts_with("field `cube_px` is 8, this run has 16 (--cube-size)"),
            "{e}"
        );
        let run = Database {
            cube_px: None,
            grid_m: 2e-300,
            ..db.clone()
        };
        let e = check_matches(&db, &run).unwrap_err();
        assert!(
            e.starts_with("field `grid_m` is 1e-300, this run has 2e-300"),
            "{e}"
        );
        let saved = Database {
            cube_px: None,
            ..db.clone()
        };
        let e = check_matches(&saved, &run_with(Some(16))).unwrap_err();
        assert!(
            e.contains("field `cube_px` is missing or null, this run has 16 (--cube-size)"),
            "{e}"
        );
        // A traced source reads no cube: the size an older file recorded for it is not asked.
        check_matches(&db, &run_with(None)).unwrap();
    }

    /// This run's settings: `saved_box`'s, with a source that fills a cube of `cube_px` or none.
    fn run_with(cube_px: Option<u32>) -> Database {
        Database {
            cube_px,
            ..saved_box()
        }
    }
}
