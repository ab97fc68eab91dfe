//! The calibration folder that `specchio calibrate` writes: the models in the tools' own
//! formats, each model's residual as an image, the check points and `calibration.json`, which
//! lists the others. The command decides when and where (its output transaction); this
//! module decides what the folder holds and what each file is called.

use std::path::Path;

use crate::image::RgbaImage;
use crate::output::{OutputError, Sink, Transaction};
use crate::sensor::RayMap;

use super::record::{CalibrationRecord, CheckPoints, FrameRecord, ModelRecord};
use super::{export, Calibration, Residual};

/// Every `CHECK_STRIDE`-th pixel in rows and columns gives check points...
pub const CHECK_STRIDE: u32 = 16;
/// ...at these distances from the mirror along its exact ray (metres): near, where the
/// viewpoint's offset from the true ray origins shows as parallax, to far, where only the
/// directional residual is left.
pub const CHECK_DISTANCES_M: [f64; 4] = [0.5, 2.0, 10.0, 1000.0];

pub const OPENCV: &str = "opencv_omnidir.yaml";
pub const KALIBR: &str = "kalibr_camchain.yaml";
pub const OCAMCALIB: &str = "ocamcalib_calib_results.txt";
pub const RESIDUAL_OMNIDIR: &str = "residual_omnidir.exr";
pub const RESIDUAL_OCAMCALIB: &str = "residual_ocamcalib.exr";
pub const CHECK_POINTS: &str = "check_points.json";
pub const RECORD: &str = "calibration.json";

/// Writes the folder's files into `dir` through `out`, `calibration.json` last; returns the
/// record written. The Kalibr camchain names `image_topic` (`sensor::bag::kalibr_image_topic`
/// of the scene).
pub fn write(
    out: &Transaction,
    dir: &Path,
    (cal, map): (&Calibration, &RayMap),
    (scene, image_topic): (&Path, &str),
    time_s: f64,
) -> Result<CalibrationRecord, OutputError> {
    let (w, h) = (cal.width, cal.height);
    out.write_bytes(
        &dir.join(OPENCV),
        export::opencv_yaml(&cal.mei, w, h).as_bytes(),
    )?;
    out.write_bytes(
        &dir.join(KALIBR),
        export::kalibr_yaml(&cal.mei, w, h, image_topic).as_bytes(),
    )?;
    out.write_bytes(
        &dir.join(OCAMCALIB),
        export::ocamcalib_txt(&cal.ocam).as_bytes(),
    )?;
    out.write_exr(
        &dir.join(RESIDUAL_OMNIDIR),
        &residual_image(&cal.mei_residual, w, h),
    )?;
    out.write_exr(
        &dir.join(RESIDUAL_OCAMCALIB),
        &residual_image(&cal.ocam_residual, w, h),
    )?;
    let points = CheckPoints {
        points: cal.check_points(map, CHECK_STRIDE, &CHECK_DISTANCES_M),
    };
    out.write_json(&dir.join(CHECK_POINTS), &points)?;
    let record = record(cal, scene, time_s);
    out.write_json(&dir.join(RECORD), &record)?;
    Ok(record)
}

/// The residual as an image: R = the angle in degrees where the model has a ray, G = 1 on
/// mirror pixels where it has none (R = 0 there), A = 1 on the mirror, 0 off it.
fn residual_image(residual: &Residual, width: u32, height: u32) -> RgbaImage {
    let pixels = residual
        .degrees
        .iter()
        .map(|d| match d {
            None => [0.0; 4],
            Some(d) if d.is_nan() => [0.0, 1.0, 0.0, 1.0],
            Some(d) => [*d as f32, 0.0, 0.0, 1.0],
        })
        .collect();
    RgbaImage {
        width,
        height,
        pixels,
    }
}

fn record(cal: &Calibration, scene: &Path, time_s: f64) -> CalibrationRecord {
    let rows = |r: [glam::DVec3; 3]| r.map(|v| v.to_array());
    let rms = |cost: f64, n: usize| (cost / n.max(1) as f64).sqrt();
    CalibrationRecord {
        scene: scene.display().to_string(),
        time_s,
        image: [cal.width, cal.height],
        mirror_pixels: cal.mirror_pixels,
        fit_stride: cal.fit_stride,
        fit_pixels: cal.fit_pixels,
        frame: FrameRecord {
            omnidir_rows: rows(cal.axes.omnidir_rows()),
            ocamcalib_rows: rows(cal.axes.ocamcalib_rows()),
            note: "model point = rows * (world - viewpoint_world); each frame is left-handed \
                   (the mirror reverses handedness): omnidir/Kalibr x = sensor right, y = \
                   sensor down, z = towards the camera; OCamCalib x = down (rows), y = right \
                   (columns), z = towards the mirror"
                .to_owned(),
        },
        viewpoint_world: (cal.origin + cal.viewpoint).to_array(),
        ray_distance_to_viewpoint_m: cal.ray_distance_m,
        omnidir: ModelRecord {
            model: cal.mei,
            residual_deg: cal.mei_residual.stats,
            pixels_without_ray: cal.mei_residual.without_ray,
            residual_image: RESIDUAL_OMNIDIR.to_owned(),
            fit_iterations: cal.mei_fit.iterations,
            // Two residuals (x, y) per pixel fitted.
            fit_rms: rms(cal.mei_fit.final_cost, 2 * cal.fit_pixels),
            inverse_error_px: None,
        },
        ocamcalib: ModelRecord {
            model: cal.ocam.clone(),
            residual_deg: cal.ocam_residual.stats,
            pixels_without_ray: cal.ocam_residual.without_ray,
            residual_image: RESIDUAL_OCAMCALIB.to_owned(),
            fit_iterations: cal.ocam_fit.iterations,
            // Three residuals (a unit vector's difference) per pixel fitted.
            fit_rms: rms(cal.ocam_fit.final_cost, 3 * cal.fit_pixels),
            inverse_error_px: Some(cal.ocam_invpol_error_px),
        },
        ros: super::ros::calibration(
            cal.axes.omnidir_rows(),
            cal.axes.ocamcalib_rows(),
            cal.origin + cal.viewpoint,
        ),
        files: [
            OPENCV,
            KALIBR,
            OCAMCALIB,
            RESIDUAL_OMNIDIR,
            RESIDUAL_OCAMCALIB,
            CHECK_POINTS,
        ]
        .map(str::to_owned)
        .to_vec(),
    }
}
