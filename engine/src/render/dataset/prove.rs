//! A frame rendered elsewhere (a Ray worker's `DatasetFrames`, or one a user made by hand)
//! proven to be this plan's before the output takes it: its index line the one the plan gives
//! its pose, its colour and labels made by the run's lookup and ground truth, and its files
//! made with the plan's choices (the geometry frame of its ray map and point cloud, the
//! panoramas' frame). The file names are `check_frame`'s; a frame
//! rendered for another scene, trajectory or choice would otherwise be placed without a word.

use super::Plan;
use crate::scene::Lookup;
use crate::sensor::dataset::{DatasetError, Frame, GeometryFrame};
use crate::sensor::layers::{Layer, CAMERA_FILE, POINTS_FILE};
use crate::sensor::GroundTruth;

/// How far a recorded panorama seam may be from the plan's (degrees): the record is the
/// plan's number printed, so only its last digit.
const SEAM_TOLERANCE_DEG: f64 = 1e-9;

impl Plan {
    /// Proves `frame` this plan's, rendered by `run` (the lookup and ground truth the
    /// dataset's summary will name); `index_of` gives the plan's index lines
    /// ([`Plan::index_lines`]).
    pub fn prove(
        &self,
        frame: &Frame,
        run: (Lookup, GroundTruth),
        index_of: &mut dyn FnMut(usize) -> String,
    ) -> Result<(), DatasetError> {
        let i = frame.frame;
        let refuse = |why: String| DatasetError::Invalid(format!("frame {i}: {why}"));
        if i >= self.poses.len() {
            let n = self.poses.len();
            return Err(refuse(format!("the dataset has {n} frames")));
        }
        if frame.index_line != index_of(i) {
            return Err(refuse(
                "its index line is not the one this dataset gives the pose: it was rendered \
                 for another scene, trajectory or pose"
                    .into(),
            ));
        }
        let file = |name: &str| {
            (frame.files.iter())
                .find(|(p, _)| p.file_name().is_some_and(|n| n == name))
                .map(|(_, bytes)| bytes.as_slice())
        };
        let camera: serde_json::Value = (file(CAMERA_FILE))
            .and_then(|b| serde_json::from_slice(b).ok())
            .ok_or_else(|| refuse(format!("{CAMERA_FILE} is missing or not JSON")))?;
        let made = |key: &str| camera.pointer(&format!("/ground_truth/{key}"))?.as_str();
        let (lookup, truth) = (run.0.to_string(), run.1.name());
        if made("colour") != Some(&lookup) || made("layers") != Some(truth) {
            return Err(refuse(format!(
                "it was rendered with the {} lookup and {} ground truth, not this run's {lookup} \
                 and {truth}",
                made("colour").unwrap_or("no"),
                made("layers").unwrap_or("no"),
            )));
        }
        if self.outputs.has(Layer::RAYS) {
            let said = camera.pointer("/files/ray_frame").and_then(|v| v.as_str());
            let want = (self.geometry != GeometryFrame::Scene).then(|| self.geometry.says());
            if said != want {
                return Err(refuse(format!(
                    "its ray map is not in the dataset's {} frame",
                    self.geometry
                )));
            }
        }
        if let Some(ply) = file(POINTS_FILE).filter(|_| self.outputs.has(Layer::POINTS)) {
            let header = String::from_utf8_lossy(&ply[..ply.len().min(4096)]);
            let said = (header.lines()).find_map(|l| l.strip_prefix("comment frame: "));
            if said.and_then(GeometryFrame::of_ply_comment) != Some(self.geometry) {
                return Err(refuse(format!(
                    "its point cloud is not in the dataset's {} frame",
                    self.geometry
                )));
            }
        }
        let heading = self.poses[i].heading_deg.to_radians();
        let want = self.panoramas.seam(heading).to_degrees();
        let seams = camera
            .pointer("/files/panoramas")
            .and_then(|v| v.as_array());
        for seam in seams.into_iter().flatten() {
            let said = seam.get("seam_azimuth_deg").and_then(|v| v.as_f64());
            if !said.is_some_and(|s| (s - want).abs() <= SEAM_TOLERANCE_DEG) {
                return Err(refuse(format!(
                    "its panoramas are not in the dataset's {} frame",
                    self.panoramas.name()
                )));
            }
        }
        Ok(())
    }
}
