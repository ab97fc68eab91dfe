//! A dataset's output folder as a run fills it: staged, all or nothing, like every output;
//! the frames placed straight into it, or, in a resumable run, kept in its work folder
//! (`resume.rs`) until the last one is done. The CLI, the Python package and its Ray driver
//! all fill it through here, so the folders they make are the same.

use std::path::{Path, PathBuf};

use super::check::check_frame;
use super::frame_folder;
use super::resume::{RunKey, WorkFolder};
use super::{DatasetError, Frame, INDEX_FILE, SUMMARY_FILE};
use crate::output::{OutputError, Sink, Transaction};
use crate::sensor::bag::{self, BagError, Omni};
use crate::sensor::dataset::DatasetRecord;

/// The output folder of a dataset of `index.len()` frames, being filled.
pub struct Folder {
    staged: Transaction,
    root: PathBuf,
    work: Option<WorkFolder>,
    /// Each frame's index line, once it is placed.
    index: Vec<Option<String>>,
    /// The files each frame holds (`super::frame_files` of the run's layers).
    files: Vec<&'static str>,
}

/// The folder every frame folder is in.
const FRAMES: &str = "frames";

impl Folder {
    /// Stages the folder `root` for `frames` frames, each of which holds `files`; fails now,
    /// before any work, where `root` cannot become this output (docs/outputs.md).
    pub fn stage(
        root: &Path,
        frames: usize,
        files: Vec<&'static str>,
    ) -> Result<Folder, DatasetError> {
        let mut staged = Transaction::new();
        staged.folder(root, SUMMARY_FILE)?;
        Ok(Folder {
            staged,
            root: root.to_owned(),
            work: None,
            index: vec![None; frames],
            files,
        })
    }

    /// Makes the run resumable: frames are kept in the work folder as they finish, and the
    /// frames it holds from an earlier run with the same `key` are done, each proven against
    /// `index_of`, the index lines this run writes (the engine's `Plan::index_lines`). Returns
    /// how many.
    pub fn resume(
        &mut self,
        key: &RunKey,
        index_of: &mut dyn FnMut(usize) -> String,
    ) -> Result<usize, DatasetError> {
        let work = WorkFolder::open(&self.root, key, index_of)?;
        for (i, line) in work.done() {
            self.index[i] = Some(line.to_owned());
        }
        self.work = Some(work);
        Ok(self.done())
    }

    /// The frames still to render, in order.
    pub fn todo(&self) -> Vec<usize> {
        (self.index.iter().enumerate())
            .filter_map(|(i, line)| line.is_none().then_some(i))
            .collect()
    }

    /// How many frames are placed.
    pub fn done(&self) -> usize {
        self.index.iter().filter(|l| l.is_some()).count()
    }

    /// Frame `i`'s index line, once placed.
    pub fn index_line(&self, i: usize) -> Option<&str> {
        self.index.get(i).and_then(|l| l.as_deref())
    }

    /// The work folder, in a resumable run.
    pub fn work_folder(&self) -> Option<&Path> {
        self.work.as_ref().map(|w| w.path())
    }

    /// Places one frame; each frame once.
    pub fn place(&mut self, frame: &Frame) -> Result<(), DatasetError> {
        let n = self.index.len();
        let slot = self.index.get(frame.frame).ok_or_else(|| {
            DatasetError::Invalid(format!("frame {}: the dataset has {n} frames", frame.frame))
        })?;
        if slot.is_some() {
            let why = format!("frame {} was placed already", frame.frame);
            return Err(DatasetError::Invalid(why));
        }
        check_frame(frame, &self.files).map_err(DatasetError::Invalid)?;
        match &mut self.work {
            Some(work) => work.write(frame)?,
            None => {
                for (path, bytes) in &frame.files {
                    self.staged.write_bytes(&self.root.join(path), bytes)?;
                }
            }
        }
        self.index[frame.frame] = Some(frame.index_line.clone());
        Ok(())
    }

    /// With every frame placed: the frames (from the work folder, in a resumable run), the
    /// index and the summary `record`, staged; [`Ready::commit`] places them.
    /// A bag (`record.format`) carries `omni`, a central mirror's unified model.
    pub fn finish(
        self,
        record: &DatasetRecord,
        omni: Option<&Omni>,
    ) -> Result<Ready, DatasetError> {
        if let Some(missing) = self.index.iter().position(|l| l.is_none()) {
            return Err(DatasetError::Invalid(format!(
                "frame {missing} was never placed"
            )));
        }
        if let Some(work) = &self.work {
            work.link_into(&self.staged, &self.root)?;
        }
        let staged = self.staged;
        let format = record.format;
        if format.mcap {
            let extras = bag::Extras {
                scene_origin: glam::DVec3::from_array(record.scene_origin_m),
                geometry: record.geometry_frame,
                omni,
            };
            write_bag(&staged, &self.root, self.index.len(), &extras)?;
        }
        if format.files {
            let mut index = String::new();
            for line in self.index.iter().flatten() {
                index.push_str(line);
                index.push('\n');
            }
            staged.write_bytes(&self.root.join(INDEX_FILE), index.as_bytes())?;
        } else {
            // The bag holds them: rendered only to make it.
            let frames = staged.path_for(&self.root.join(FRAMES))?;
            std::fs::remove_dir_all(&frames).map_err(|source| OutputError::Io {
                path: self.root.join(FRAMES),
                source,
            })?;
        }
        staged.write_json(&self.root.join(SUMMARY_FILE), record)?;
        Ok(Ready {
            staged,
            work: self.work,
        })
    }
}

/// The ROS 2 bag of the `frames` frames staged in `root`'s transaction, in `root/bag/`.
fn write_bag(
    staged: &Transaction,
    root: &Path,
    frames: usize,
    extras: &bag::Extras,
) -> Result<(), DatasetError> {
    let dir = root.join(bag::BAG_FOLDER);
    let mcap = dir.join(bag::BAG_FILE);
    let read = |i: usize, name: &str| -> Result<Option<Vec<u8>>, BagError> {
        let path = root.join(frame_folder(i)).join(name);
        match std::fs::read(staged.path_for(&path)?) {
            Ok(bytes) => Ok(Some(bytes)),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(source) => Err(BagError::Io { path, source }),
        }
    };
    let metadata = bag::write(staged.create(&mcap)?, &mcap, frames, &read, extras)?;
    staged.write_bytes(&dir.join(bag::METADATA_FILE), metadata.as_bytes())?;
    Ok(())
}

/// A finished dataset, staged.
pub struct Ready {
    staged: Transaction,
    work: Option<WorkFolder>,
}

impl Ready {
    /// Places the dataset folder, then removes the work folder of a resumable run. Returns
    /// what of the work folder could not be removed (the dataset is in place all the same).
    pub fn commit(self) -> Result<Vec<String>, OutputError> {
        match self.staged.commit() {
            Ok(()) => Ok(self.work.map(WorkFolder::remove).unwrap_or_default()),
            // Placed, but the earlier output held something its manifest did not list, kept
            // aside: the dataset is in place all the same, and its work folder done with.
            Err(e @ OutputError::KeptAside { .. }) => {
                for left in self.work.map(WorkFolder::remove).unwrap_or_default() {
                    crate::warnings::warn(&format!(
                        "the work folder is not removed entirely: {left}"
                    ));
                }
                Err(e)
            }
            Err(e) => Err(e),
        }
    }
}
