//! The journal of a resumable dataset's work folder: its lines (the run's key, then one line
//! per finished frame), read back bounded and checked as the run writes them.

use std::fs::{File, OpenOptions};
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::super::check::{check_frame_names, check_index_line};
use super::super::frame_files;
use crate::sensor::layers::Layers;

/// The journal's format; a journal of another format is refused.
pub(super) const FORMAT: u32 = 1;
/// Longest journal line read back: a frame's line is a few hundred bytes.
const MAX_LINE: u64 = 64 << 10;

/// What a dataset's bytes depend on: a run resumes only a work folder whose key is its own.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunKey {
    /// This program's version and build (a digest of the engine's sources, shaders and
    /// dependencies: engine/build.rs).
    pub specchio: String,
    /// The scene's files (the scene, its meshes and textures) and the trajectory file, by
    /// length and CRC-32 (`files::digest`), in the order they were read.
    pub inputs: Vec<String>,
    /// The poses as checked, by CRC-32 of their exact values (a grid has no file).
    pub poses: String,
    pub frames: usize,
    pub lookup: String,
    pub ground_truth: String,
    /// The device's name and driver: another device may round differently.
    pub device: String,
    /// Whose frame the panoramas are in (`robot`, `world`). A journal from before this field
    /// reads as `""`, which no run asks for.
    #[serde(default)]
    pub panoramas: String,
    /// The layers each frame holds (`image,range,...`: `Layers`' text). A journal from before
    /// this field reads as `""`, which no run asks for.
    #[serde(default)]
    pub outputs: String,
    /// The frame of the ray map and the point cloud (`scene`, `map`, `base_link`). A journal
    /// from before this field reads as `""`, which no run asks for.
    #[serde(default)]
    pub geometry: String,
}

/// One journal line.
#[derive(Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub(super) enum Line {
    Run { format: u32, key: RunKey },
    Frame(Journaled),
}

/// A finished frame: its files (name in its folder, size, CRC-32) and its index line.
#[derive(Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Journaled {
    pub frame: usize,
    pub files: Vec<(String, u64, u32)>,
    pub index: String,
}

/// A journaled frame as the run writes it: of this dataset, its names a frame folder's,
/// its index line its own.
pub(super) fn check_journaled(f: &Journaled, key: &RunKey) -> Result<(), String> {
    let frames = key.frames;
    if f.frame >= frames {
        return Err(format!(
            "frame {}: the dataset has {frames} frames",
            f.frame
        ));
    }
    let names: Vec<&str> = f.files.iter().map(|(n, _, _)| n.as_str()).collect();
    let layers: Layers = (key.outputs.parse()).map_err(|e| format!("the run's outputs: {e}"))?;
    check_frame_names(f.frame, &names, &frame_files(layers))?;
    check_index_line(f.frame, &f.index)
}

/// The journal's whole lines (numbered from 1) and their length; a last line without its
/// newline was cut short by a crash and is left out.
pub(super) struct Journal {
    pub lines: Vec<(usize, Line)>,
    pub complete: u64,
    /// The line cut short at the end, if any.
    pub tail: Vec<u8>,
}

/// Reads the journal line by line, each line and the line count bounded: a run of `frames`
/// frames writes its key and a line per frame done (again, where a frame was lost).
pub(super) fn read_journal(journal: &mut File, frames: usize) -> Result<Journal, JournalError> {
    let most = 1 + 4 * frames + 64;
    let mut reader = BufReader::new(journal);
    let mut read = Journal {
        lines: Vec::new(),
        complete: 0,
        tail: Vec::new(),
    };
    let mut line = Vec::new();
    for n in 1.. {
        line.clear();
        let got = (reader.by_ref().take(MAX_LINE + 1))
            .read_until(b'\n', &mut line)
            .map_err(JournalError::Io)?;
        if got == 0 {
            break;
        }
        if line.last() != Some(&b'\n') {
            if got as u64 > MAX_LINE {
                return Err(JournalError::Bad(format!(
                    "line {n}: longer than a journal line"
                )));
            }
            read.tail = line;
            break; // cut short at the end
        }
        if n > most {
            let why = format!("has more lines than a run of {frames} frames writes");
            return Err(JournalError::Bad(why));
        }
        let parsed = serde_json::from_slice(&line[..line.len() - 1])
            .map_err(|_| JournalError::Bad(format!("line {n}: not a journal line")))?;
        read.lines.push((n, parsed));
        read.complete += got as u64;
    }
    Ok(read)
}

/// The first field in which two keys differ, said for a person.
pub(super) fn differs(theirs: &RunKey, ours: &RunKey) -> Option<String> {
    let field = if theirs.specchio != ours.specchio {
        format!("specchio {} against {}", theirs.specchio, ours.specchio)
    } else if theirs.frames != ours.frames {
        format!(
            "other poses: {} frames against {}",
            theirs.frames, ours.frames
        )
    } else if theirs.inputs != ours.inputs || theirs.poses != ours.poses {
        "the scene, its assets or the poses changed since".to_owned()
    } else if theirs.lookup != ours.lookup || theirs.ground_truth != ours.ground_truth {
        format!(
            "the {} lookup with {} ground truth, against {} with {}",
            theirs.lookup, theirs.ground_truth, ours.lookup, ours.ground_truth
        )
    } else if theirs.device != ours.device {
        format!("device {} against {}", theirs.device, ours.device)
    } else if theirs.panoramas != ours.panoramas {
        format!(
            "panoramas in the {} frame against the {}",
            or_none(&theirs.panoramas),
            ours.panoramas
        )
    } else if theirs.outputs != ours.outputs {
        format!(
            "the outputs {} against {}",
            or_none(&theirs.outputs),
            ours.outputs
        )
    } else if theirs.geometry != ours.geometry {
        format!(
            "the ray map and cloud in the {} frame against the {}",
            or_none(&theirs.geometry),
            ours.geometry
        )
    } else if theirs != ours {
        // A field added to the key and not named above still refuses the journal.
        "another run key".to_owned()
    } else {
        return None;
    };
    Some(field)
}

/// A key field as the message says it: `(none)` for a journal from before the field.
fn or_none(field: &str) -> &str {
    match field {
        "" => "(none)",
        f => f,
    }
}

pub(super) fn open_journal(at: &Path) -> std::io::Result<File> {
    let mut options = OpenOptions::new();
    options.read(true).write(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NOFOLLOW);
    }
    let file = options.open(at)?;
    match file.metadata()?.is_file() {
        true => Ok(file),
        false => Err(std::io::Error::other("not a regular file")),
    }
}

/// Why a journal could not be read: its file, or a line that is not the run's.
pub(super) enum JournalError {
    Io(std::io::Error),
    Bad(String),
}
