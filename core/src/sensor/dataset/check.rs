//! What a frame folder holds, checked wherever frames come in: from a renderer, from a Ray
//! worker through the Python driver, from a resumed run's journal.

use super::{any_frame_files, Frame};
use crate::sensor::dataset::frame_folder;

/// A frame as a frame folder of a run whose frames hold `files` holds it: every file in its
/// own folder, one of `files`, none twice, every fixed one there; its index line its own.
pub fn check_frame(frame: &Frame, files: &[&str]) -> Result<(), String> {
    let folder = frame_folder(frame.frame);
    let mut names = Vec::with_capacity(frame.files.len());
    for (path, _) in &frame.files {
        let name = (path.strip_prefix(&folder).ok())
            .filter(|rest| rest.components().count() == 1)
            .and_then(|rest| rest.to_str())
            .ok_or_else(|| {
                format!(
                    "{}: not a file of frame {}'s folder",
                    path.display(),
                    frame.frame
                )
            })?;
        names.push(name);
    }
    check_frame_names(frame.frame, &names, files)?;
    check_index_line(frame.frame, &frame.index_line)
}

/// Frame `frame`'s file names: each one of `files` (`*` standing for any plain suffix), none
/// twice, every one of `files` there (a `*` name by at least one file: a layer chosen is a
/// layer written).
pub fn check_frame_names(frame: usize, names: &[&str], files: &[&str]) -> Result<(), String> {
    if let Some(odd) = names.iter().find(|n| !named_in(files, n)) {
        return Err(format!(
            "frame {frame}: {odd} is not a file of this run's frames ({})",
            files.join(", ")
        ));
    }
    let mut sorted = names.to_vec();
    sorted.sort_unstable();
    if let Some(twice) = sorted.windows(2).find(|w| w[0] == w[1]) {
        return Err(format!("frame {frame}: {} twice", twice[0]));
    }
    match (files.iter()).find(|f| !names.iter().any(|n| named_in(&[**f], n))) {
        Some(missing) => Err(format!("frame {frame}: no {missing}")),
        None => Ok(()),
    }
}

/// A frame file's name, of any run: one a frame of every layer holds.
pub fn is_frame_file(name: &str) -> bool {
    named_in(&any_frame_files(), name)
}

/// Whether `name` is one of `files` (`*` standing for any plain suffix).
fn named_in(files: &[&str], name: &str) -> bool {
    files.iter().any(|f| match f.split_once('*') {
        None => *f == name,
        Some((head, _)) => {
            name.len() > head.len()
                && name.starts_with(head)
                && !name.contains(['/', '\\'])
                && name != "."
                && name != ".."
        }
    })
}

/// Frame `frame`'s index line: one JSON object on one line, naming the frame and its folder.
pub fn check_index_line(frame: usize, line: &str) -> Result<(), String> {
    let value: serde_json::Value = (!line.contains(['\n', '\r']))
        .then(|| serde_json::from_str(line).ok())
        .flatten()
        .unwrap_or_default();
    let folder = frame_folder(frame);
    match value["frame"] == frame && value["folder"] == folder.as_str() {
        true => Ok(()),
        false => Err(format!(
            "index line {frame}: not frame {frame}'s line (one JSON object with \"frame\": \
             {frame} and \"folder\": \"{folder}\")"
        )),
    }
}
