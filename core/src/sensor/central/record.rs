//! `calibration.json` and `check_points.json`, as typed records (written by `specchio
//! calibrate`, read back by the tests and by `scripts/check-omnidir.py`).

use serde::{Deserialize, Serialize};

use super::{MeiModel, OcamModel};

/// Mean, p99 (nearest rank, `metrics::percentile`) and maximum of a per-pixel quantity.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub mean: f64,
    pub p99: f64,
    pub max: f64,
}

/// `calibration.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationRecord {
    pub scene: String,
    pub time_s: f64,
    /// Sensor image (width, height), pixels.
    pub image: [u32; 2],
    pub mirror_pixels: usize,
    /// The models were fitted to every `fit_stride`-th row and column of the mirror pixels
    /// (1 up to a 512² sensor's worth); the residuals are every pixel's.
    pub fit_stride: u32,
    pub fit_pixels: usize,
    pub frame: FrameRecord,
    /// The single viewpoint the models assume, world space (metres).
    pub viewpoint_world: [f64; 3],
    /// How far the exact rays pass from that viewpoint (metres).
    pub ray_distance_to_viewpoint_m: Summary,
    pub omnidir: ModelRecord<MeiModel>,
    pub ocamcalib: ModelRecord<OcamModel>,
    /// The models' frames as right-handed TF frames in ROS REP-103's `map`.
    pub ros: super::ros::RosCalibration,
    /// The files written beside this one.
    pub files: Vec<String>,
}

/// The models' axes, as rows of world-space unit vectors: a model-frame point is
/// `rows * (world - viewpoint_world)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    pub omnidir_rows: [[f64; 3]; 3],
    pub ocamcalib_rows: [[f64; 3]; 3],
    pub note: String,
}

/// One fitted model, its fit and its residual.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelRecord<M> {
    pub model: M,
    /// Angle between the model's ray and the exact ray over the mirror pixels it has a ray for
    /// (degrees).
    pub residual_deg: Summary,
    /// Mirror pixels the model has no ray for (left out of `residual_deg`).
    pub pixels_without_ray: usize,
    /// The EXR of the per-pixel residual.
    pub residual_image: String,
    pub fit_iterations: usize,
    /// Root mean square of the fit's own objective at the end (pixels for omnidir, the chord
    /// between unit directions, about radians, for OCamCalib).
    pub fit_rms: f64,
    /// OCamCalib's `invpol`: how far it is from its polynomial's exact inverse at worst over
    /// the image's radii (pixels; OCamCalib's own tolerance is 0.01). None for omnidir, whose
    /// projection is exact.
    pub inverse_error_px: Option<f64>,
}

/// A 3D point on an exact ray and what each exported model predicts for it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CheckPoint {
    /// The pixel whose exact ray the point lies on (x, y), 0-based: its true image point.
    pub pixel: [u32; 2],
    /// Distance from the mirror along that ray (metres).
    pub distance_m: f64,
    pub world: [f64; 3],
    /// The point in the omnidir frame (origin at the viewpoint).
    pub omnidir_point: [f64; 3],
    /// Its (x, y) pixel by our Mei model (None: behind the model's second centre).
    pub omnidir_pixel: Option<[f64; 2]>,
    /// The point in the OCamCalib frame (origin at the viewpoint).
    pub ocamcalib_point: [f64; 3],
    /// Its (row, col) by our port of OCamCalib's `world2cam`.
    pub ocamcalib_row_col: [f64; 2],
}

/// `check_points.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CheckPoints {
    pub points: Vec<CheckPoint>,
}
