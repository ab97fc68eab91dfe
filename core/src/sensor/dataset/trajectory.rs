//! A robot's trajectory: when it is where, facing which way.
//!
//! - CSV: a header naming the columns `time,x,y,z,heading` (in any order, each once), then
//!   one pose per line; blank lines and lines starting with `#` are skipped.
//! - JSON: `[{"time": 0.0, "position": [x, y, z], "heading": 0.0}, ...]`.
//!
//! `time` in seconds (≥ 0, never decreasing: the scene's objects are where they are at that
//! time; equal times make a pose grid), the position of the mirror's viewpoint (the robot) in
//! the scene file's coordinates (metres, +Y up), `heading` in degrees about +Y, counter-
//! clockwise seen from above (the robot turned from the scene's own sensor: 0 is the file's).
//! Every mistake names the file, the line (CSV) or the entry (JSON) and the field.

use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::files::{read_regular_file, FileError};
use crate::text::num_text;

/// The most poses a trajectory may hold (each is a frame of images on disk).
pub const MAX_POSES: usize = 100_000;
/// The largest trajectory file read (about 40 bytes a pose, with room to spare).
pub const MAX_TRAJECTORY_BYTES: u64 = 64 << 20;

/// One pose of the robot.
#[derive(Debug, Clone, PartialEq)]
pub struct Pose {
    /// Where the file says it: a CSV line or a JSON entry.
    pub at: Place,
    pub time_s: f64,
    /// The mirror's viewpoint in the scene file's coordinates (metres).
    pub position: DVec3,
    pub heading_deg: f64,
}

/// Where in the file a pose is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Place {
    /// A CSV line (1-based).
    Line(usize),
    /// A JSON entry (0-based).
    Entry(usize),
}

/// A trajectory the dataset cannot use, named by file, place and field.
#[derive(Debug, thiserror::Error)]
pub enum TrajectoryError {
    /// The file could not be read (its message names no path: the path is said here).
    #[error("{}: cannot read the trajectory: {source}", path.display())]
    File { path: PathBuf, source: FileError },
    #[error("{}{}: {field}: {message}", file.display(), place_text(*place))]
    Invalid {
        file: PathBuf,
        place: Option<Place>,
        field: String,
        message: String,
    },
}

fn place_text(place: Option<Place>) -> String {
    match place {
        Some(Place::Line(n)) => format!(":{n}"),
        Some(Place::Entry(i)) => format!(": poses[{i}]"),
        None => String::new(),
    }
}

impl TrajectoryError {
    pub fn invalid(file: &Path, place: Option<Place>, field: &str, message: String) -> Self {
        TrajectoryError::Invalid {
            file: file.to_path_buf(),
            place,
            field: field.to_owned(),
            message,
        }
    }
}

/// The poses of the trajectory file `path`: JSON when its name ends in `.json` or its text
/// starts with `[` or `{` (which no CSV header does: a JSON file named `.txt` was read as CSV
/// and said "names no `time` column"), else CSV.
pub fn read(path: &Path) -> Result<Vec<Pose>, TrajectoryError> {
    let bytes =
        read_regular_file(path, MAX_TRAJECTORY_BYTES).map_err(|source| TrajectoryError::File {
            path: path.to_owned(),
            source,
        })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        TrajectoryError::invalid(path, None, "(file)", format!("not UTF-8 text (byte {at})"))
    })?;
    // A byte-order mark (spreadsheets write one) is not part of the first field.
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let json = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
        || text.trim_start().starts_with(['[', '{']);
    let mut poses = if json {
        parse_json(path, text)?
    } else {
        parse_csv(path, text)?
    };
    check(path, &poses)?;
    // One turn is enough: a heading of 1e6 degrees would lose its digits in single precision.
    // Adding +0 makes a file's -0 a 0, which the records would otherwise write as -0.0.
    for p in &mut poses {
        p.heading_deg = p.heading_deg.rem_euclid(360.0) + 0.0;
        p.time_s += 0.0;
        p.position += 0.0;
    }
    Ok(poses)
}

/// The columns a CSV header must name.
const COLUMNS: [&str; 5] = ["time", "x", "y", "z", "heading"];

/// Parses CSV text (see the module's comment).
pub fn parse_csv(file: &Path, text: &str) -> Result<Vec<Pose>, TrajectoryError> {
    let mut rows = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((header_line, header)) = rows.next() else {
        let why = format!(
            "no header; the first line names the columns {}",
            COLUMNS.join(",")
        );
        return Err(TrajectoryError::invalid(file, None, "(header)", why));
    };
    let at = Some(Place::Line(header_line));
    if let Some(sep) = [';', '\t', '|']
        .into_iter()
        .find(|&c| !header.contains(',') && header.contains(c))
    {
        let why = format!(
            "the columns are separated by {sep:?}; a trajectory's CSV separates them by commas \
             ({})",
            COLUMNS.join(",")
        );
        return Err(TrajectoryError::invalid(file, at, "(header)", why));
    }
    let names = cells(header).map_err(|why| TrajectoryError::invalid(file, at, "(header)", why))?;
    let mut index = [0usize; 5];
    for (k, column) in COLUMNS.iter().enumerate() {
        let found: Vec<usize> = (0..names.len()).filter(|&i| names[i] == *column).collect();
        match found[..] {
            [i] => index[k] = i,
            [] => {
                let why = format!(
                    "the header names no `{column}` column (it needs {})",
                    COLUMNS.join(",")
                );
                return Err(TrajectoryError::invalid(file, at, column, why));
            }
            _ => {
                let why = "the header names it more than once".to_owned();
                return Err(TrajectoryError::invalid(file, at, column, why));
            }
        }
    }
    if let Some(extra) = names.iter().find(|n| !COLUMNS.contains(n)) {
        let why = format!("unknown column (the columns are {})", COLUMNS.join(","));
        return Err(TrajectoryError::invalid(file, at, extra, why));
    }
    let mut poses = Vec::new();
    for (line, row) in rows {
        if poses.len() == MAX_POSES {
            let why = format!("more than {MAX_POSES} poses; split the trajectory");
            return Err(TrajectoryError::invalid(
                file,
                Some(Place::Line(line)),
                "(file)",
                why,
            ));
        }
        let at = Some(Place::Line(line));
        let cells = cells(row).map_err(|why| TrajectoryError::invalid(file, at, "(row)", why))?;
        if cells.len() != names.len() {
            let why = format!("{} values, the header names {}", cells.len(), names.len());
            return Err(TrajectoryError::invalid(file, at, "(row)", why));
        }
        let value = |k: usize| -> Result<f64, TrajectoryError> {
            let cell = cells[index[k]];
            cell.parse::<f64>().map_err(|_| {
                TrajectoryError::invalid(file, at, COLUMNS[k], format!("`{cell}` is not a number"))
            })
        };
        poses.push(Pose {
            at: Place::Line(line),
            time_s: value(0)?,
            position: DVec3::new(value(1)?, value(2)?, value(3)?),
            heading_deg: value(4)?,
        });
    }
    Ok(poses)
}

/// A CSV line's cells, trimmed, each unquoted where a spreadsheet quoted it (`"time"`); a
/// quote anywhere else is refused (no field here holds a comma or a quote).
fn cells(line: &str) -> Result<Vec<&str>, String> {
    line.split(',')
        .map(str::trim)
        .map(|cell| {
            let quoted = cell.len() >= 2 && cell.starts_with('"') && cell.ends_with('"');
            let inner = if quoted {
                &cell[1..cell.len() - 1]
            } else {
                cell
            };
            match inner.contains('"') {
                false => Ok(inner.trim()),
                true => Err(format!(
                    "`{cell}`: a stray quote (a cell is a name or a number, quoted or not)"
                )),
            }
        })
        .collect()
}

/// Parses JSON text (see the module's comment).
pub fn parse_json(file: &Path, text: &str) -> Result<Vec<Pose>, TrajectoryError> {
    // The array first, then each entry: a mistake in an entry names it, on one line or many.
    let parsed = crate::files::json::parse_unique_keys(text).map_err(|e| {
        let line = Some(Place::Line(e.line()));
        let why = format!("{e} (a trajectory is an array of poses)");
        TrajectoryError::invalid(file, line, "(json)", why)
    })?;
    let serde_json::Value::Array(entries) = parsed else {
        let why =
            "not an array: a trajectory is an array of poses [{time, position, heading}, ...]";
        return Err(TrajectoryError::invalid(file, None, "(json)", why.into()));
    };
    if entries.len() > MAX_POSES {
        let why = format!(
            "{} poses, more than {MAX_POSES}; split the trajectory",
            entries.len()
        );
        return Err(TrajectoryError::invalid(file, None, "(file)", why));
    }
    (entries.iter().enumerate())
        .map(|(i, entry)| json_pose(file, i, entry))
        .collect()
}

/// One JSON entry: `{"time": s, "position": [x, y, z], "heading": deg}`, every field named
/// where it is wrong.
fn json_pose(file: &Path, i: usize, entry: &serde_json::Value) -> Result<Pose, TrajectoryError> {
    let at = Some(Place::Entry(i));
    let wrong = |field: &str, why: &str| TrajectoryError::invalid(file, at, field, why.into());
    let fields = entry
        .as_object()
        .ok_or_else(|| wrong("(entry)", "must be an object {time, position, heading}"))?;
    if let Some(extra) = fields
        .keys()
        .find(|k| !["time", "position", "heading"].contains(&k.as_str()))
    {
        return Err(wrong(
            extra,
            "unknown field (a pose has time, position, heading)",
        ));
    }
    let number = |key: &str| -> Result<f64, TrajectoryError> {
        match fields.get(key) {
            None => Err(wrong(key, "required field is missing")),
            Some(v) => v.as_f64().ok_or_else(|| wrong(key, "must be a number")),
        }
    };
    let position = match fields.get("position").and_then(|v| v.as_array()) {
        None if !fields.contains_key("position") => {
            Err(wrong("position", "required field is missing"))
        }
        Some(a) if a.len() == 3 && a.iter().all(|c| c.as_f64().is_some()) => Ok(DVec3::new(
            a[0].as_f64().unwrap(),
            a[1].as_f64().unwrap(),
            a[2].as_f64().unwrap(),
        )),
        _ => Err(wrong("position", "must be an array of 3 numbers [x, y, z]")),
    }?;
    Ok(Pose {
        at: Place::Entry(i),
        time_s: number("time")?,
        position,
        heading_deg: number("heading")?,
    })
}

/// Refuses what no dataset can render: no pose, a number that is not finite, a negative
/// time, time running backwards.
fn check(file: &Path, poses: &[Pose]) -> Result<(), TrajectoryError> {
    if poses.is_empty() {
        return Err(TrajectoryError::invalid(
            file,
            None,
            "(file)",
            "no poses".into(),
        ));
    }
    let mut last = 0.0;
    for p in poses {
        let at = Some(p.at);
        let fields = [
            ("time", p.time_s),
            ("x", p.position.x),
            ("y", p.position.y),
            ("z", p.position.z),
            ("heading", p.heading_deg),
        ];
        for (field, v) in fields {
            if !v.is_finite() {
                return Err(TrajectoryError::invalid(
                    file,
                    at,
                    field,
                    format!("{} is not finite", num_text(v)),
                ));
            }
        }
        if p.time_s < 0.0 {
            let why = format!("{} s: must be >= 0", num_text(p.time_s));
            return Err(TrajectoryError::invalid(file, at, "time", why));
        }
        // Before the headings are brought into one turn (`read`), which makes 1e300 a 0.
        if !crate::scene::is_heading(p.heading_deg) {
            let why = format!(
                "{}: {}",
                num_text(p.heading_deg),
                crate::scene::HEADING_RULE
            );
            return Err(TrajectoryError::invalid(file, at, "heading", why));
        }
        if p.time_s < last {
            let why = format!(
                "{} s is before the pose above ({} s): time never runs backwards",
                num_text(p.time_s),
                num_text(last)
            );
            return Err(TrajectoryError::invalid(file, at, "time", why));
        }
        last = p.time_s;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn csv(text: &str) -> Result<Vec<Pose>, TrajectoryError> {
        let file = Path::new("t.csv");
        let poses = parse_csv(file, text)?;
        check(file, &poses)?;
        Ok(poses)
    }

    #[test]
    fn csv_columns_in_any_order_comments_and_blank_lines() {
        let poses = csv("# a robot\nheading, time, x, y, z\n\n0, 0, 1, 3, 2\n90, 0.5, 1.5, 3, 2\n")
            .unwrap();
        assert_eq!(poses.len(), 2);
        assert_eq!(poses[1].at, Place::Line(5));
        assert_eq!(poses[1].time_s, 0.5);
        assert_eq!(poses[1].position, DVec3::new(1.5, 3.0, 2.0));
        assert_eq!(poses[1].heading_deg, 90.0);
    }

    /// A byte-order mark before the header (spreadsheets write one) and headings of many
    /// turns, read as the same turn; a -0 as 0.
    #[test]
    fn a_bom_is_skipped_and_headings_are_one_turn() {
        let dir = std::env::temp_dir().join(format!("specchio-trajectory-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bom.csv");
        std::fs::write(
            &path,
            "\u{feff}time,x,y,z,heading\n-0,1,3,2,-90\n1,1,3,2,1e6\n2,-0,3,2,-0\n",
        )
        .unwrap();
        let poses = read(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(poses[0].heading_deg, 270.0);
        assert_eq!(poses[1].heading_deg, 1e6 % 360.0);
        // A -0 is read as 0: records would write it as -0.0.
        let p = &poses[2];
        let signs = [poses[0].time_s, p.position.x, p.heading_deg].map(|v| v.is_sign_negative());
        assert_eq!(signs, [false, false, false]);
    }

    /// A spreadsheet's quoted header and cells read as plain ones; a file whose text is JSON
    /// is read as JSON whatever its name.
    #[test]
    fn quoted_csv_and_json_by_content() {
        let quoted = csv("\"time\",\"x\",\"y\",\"z\",\"heading\"\n\"0.5\",1,3,2,\"90\"\n").unwrap();
        assert_eq!((quoted[0].time_s, quoted[0].heading_deg), (0.5, 90.0));
        let dir = std::env::temp_dir().join(format!("specchio-json-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("robot.txt");
        std::fs::write(
            &path,
            "\n [{\"time\": 0, \"position\": [1, 3, 2], \"heading\": 5}]",
        )
        .unwrap();
        let poses = read(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!((poses[0].at, poses[0].heading_deg), (Place::Entry(0), 5.0));
    }

    #[test]
    fn json_poses_keep_their_entries() {
        let text = r#"[{"time": 0, "position": [1, 3, 2], "heading": 45}, {"time": 1, "position": [2, 3, 2], "heading": 0}]"#;
        let poses = parse_json(Path::new("t.json"), text).unwrap();
        assert_eq!(poses[1].at, Place::Entry(1));
        assert_eq!(poses[0].heading_deg, 45.0);
    }

    #[test]
    fn every_mistake_names_file_place_and_field() {
        let cases = [
            ("", "t.csv: (header): no header"),
            (
                "time,x,y,heading\n",
                "t.csv:1: z: the header names no `z` column",
            ),
            (
                "time,x,y,z,heading,speed\n",
                "t.csv:1: speed: unknown column",
            ),
            (
                "time,x,y,z,heading,x\n",
                "t.csv:1: x: the header names it more than once",
            ),
            (
                "time;x;y;z;heading\n0;1;3;2;0\n",
                "t.csv:1: (header): the columns are separated by ';'; a trajectory's CSV separates them by commas",
            ),
            (
                "time\tx\ty\tz\theading\n",
                "t.csv:1: (header): the columns are separated by '\\t'",
            ),
            (
                "time,x,y,z,heading\n0,1,\"3,2,0\n",
                "t.csv:2: (row): `\"3`: a stray quote",
            ),
            ("time,x,y,z,heading\n", "t.csv: (file): no poses"),
            (
                "time,x,y,z,heading\n0,1,2,3\n",
                "t.csv:2: (row): 4 values, the header names 5",
            ),
            (
                "time,x,y,z,heading\n0,1,two,3,0\n",
                "t.csv:2: y: `two` is not a number",
            ),
            (
                "time,x,y,z,heading\n0,1,2,3,NaN\n",
                "t.csv:2: heading: NaN is not finite",
            ),
            // Refused before it is brought into one turn, which made it a 0.
            (
                "time,x,y,z,heading\n0,1,2,3,1e300\n",
                "t.csv:2: heading: 1e300: must be a finite number of degrees from -1e6 to 1e6",
            ),
            (
                "time,x,y,z,heading\n1,1,2,3,0\n0.5,1,2,3,0\n",
                "t.csv:3: time: 0.5 s is before the pose above",
            ),
            (
                "time,x,y,z,heading\n-1,1,2,3,0\n",
                "t.csv:2: time: -1 s: must be >= 0",
            ),
        ];
        for (text, want) in cases {
            let got = csv(text).unwrap_err().to_string();
            assert!(got.starts_with(want), "{text:?}: {got}");
        }
        let json = [
            ("{}", "t.json: (json): not an array"),
            ("[{\"time\": 0,\n \"time\": 5, \"position\": [1, 2, 3], \"heading\": 0}]", "t.json:2: (json): the key `time` is written twice"),
            ("[{\"time\": 0, \"position\": [1, 2], \"heading\": 0}]", "t.json: poses[0]: position: must be an array of 3 numbers"),
            ("[{\"time\": 0, \"position\": [1, 2, 3], \"heading\": 0, \"speed\": 1}]", "t.json: poses[0]: speed: unknown field"),
            ("[{\"time\": 0, \"position\": [1, 2, 3], \"heading\": 0}, {\"time\": 1, \"position\": [1, 2, 3]}]", "t.json: poses[1]: heading: required field is missing"),
            ("[{\"time\": \"0\", \"position\": [1, 2, 3], \"heading\": 0}]", "t.json: poses[0]: time: must be a number"),
        ];
        for (text, want) in json {
            let got = parse_json(Path::new("t.json"), text)
                .unwrap_err()
                .to_string();
            assert!(got.starts_with(want), "{text:?}: {got}");
        }
    }
}
