//! `specchio calibrate`: the central models robotics tools calibrate (OpenCV omnidir, Kalibr
//! omni, OCamCalib), fitted to the sensor's exact ray map and exported in the tools' own
//! formats, each with its per-pixel residual (docs/sensor-models.md). Pure geometry: no GPU.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use specchio::image::RgbaImage;
use specchio::output::Transaction;
use specchio::sensor::central::record::{
    CalibrationRecord, CheckPoints, FrameRecord, ModelRecord, Summary,
};
use specchio::sensor::central::{export, Calibration, Residual};

use specchio::process::args::real;

#[derive(clap::Args)]
pub struct Args {
    /// The scene file (TOML; see docs/scene-format.md).
    scene: PathBuf,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Scene time in seconds (finite, >= 0): where the mirror and sensor are.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true,
          value_parser = real(0.0, false, f64::INFINITY))]
    time: f64,
}

/// Every `CHECK_STRIDE`-th pixel in rows and columns gives check points...
const CHECK_STRIDE: u32 = 16;
/// ...at these distances from the mirror along its exact ray (metres): near, where the
/// viewpoint's offset from the true ray origins shows as parallax, to far, where only the
/// directional residual is left.
const CHECK_DISTANCES_M: [f64; 4] = [0.5, 2.0, 10.0, 1000.0];

const OPENCV: &str = "opencv_omnidir.yaml";
const KALIBR: &str = "kalibr_camchain.yaml";
const OCAMCALIB: &str = "ocamcalib_calib_results.txt";
const RESIDUAL_OMNIDIR: &str = "residual_omnidir.exr";
const RESIDUAL_OCAMCALIB: &str = "residual_ocamcalib.exr";
const CHECK_POINTS: &str = "check_points.json";
const RECORD: &str = "calibration.json";

/// The most sensor pixels a calibration fits (4096²): the fits hold about 200 bytes per
/// pixel, so 8192² would need some 14 GB.
const MAX_PIXELS: u64 = 4096 * 4096;

pub fn run(args: &Args) -> Result<ExitCode> {
    let scene = specchio::scene::load(&args.scene)?;
    let [w, h] = scene.sensor.resolution;
    if u64::from(w) * u64::from(h) > MAX_PIXELS {
        bail!(
            "{}: sensor.resolution {w}x{h} is more than the {MAX_PIXELS} pixels (4096x4096) a \
             calibration fits; the models do not need more",
            args.scene.display()
        );
    }
    specchio::memory::estimates::calibrate(&scene)
        .with_context(|| args.scene.display().to_string())?;
    // All or nothing: written into a hidden folder beside --out, renamed into place at the end.
    let mut out = Transaction::new();
    out.folder(&args.out, RECORD)?;
    specchio::process::interrupt::catch();
    let (cal, map) = Calibration::of_scene(&scene, args.time)
        .with_context(|| format!("{}: cannot fit the central models", args.scene.display()))?;
    specchio::process::interrupt::check("after fitting the models")?;
    let dir = &args.out;
    let (w, h) = (cal.width, cal.height);
    out.write_bytes(
        &dir.join(OPENCV),
        export::opencv_yaml(&cal.mei, w, h).as_bytes(),
    )?;
    out.write_bytes(
        &dir.join(KALIBR),
        export::kalibr_yaml(&cal.mei, w, h).as_bytes(),
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
        points: cal.check_points(&map, CHECK_STRIDE, &CHECK_DISTANCES_M),
    };
    out.write_json(&dir.join(CHECK_POINTS), &points)?;
    let record = record(&cal, &args.scene, args.time);
    print_summary(&record, &cal);
    out.write_json(&dir.join(RECORD), &record)?;
    // A signal that came after the last check still stops the run: nothing is placed.
    specchio::process::interrupt::check("before placing the output")?;
    out.commit()?;
    Ok(ExitCode::SUCCESS)
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
            // Two residuals (x, y) per pixel.
            fit_rms: rms(cal.mei_fit.final_cost, 2 * cal.mirror_pixels),
        },
        ocamcalib: ModelRecord {
            model: cal.ocam.clone(),
            residual_deg: cal.ocam_residual.stats,
            pixels_without_ray: cal.ocam_residual.without_ray,
            residual_image: RESIDUAL_OCAMCALIB.to_owned(),
            fit_iterations: cal.ocam_fit.iterations,
            // Three residuals (a unit vector's difference) per pixel.
            fit_rms: rms(cal.ocam_fit.final_cost, 3 * cal.mirror_pixels),
        },
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

fn print_summary(record: &CalibrationRecord, cal: &Calibration) {
    let line = |name: &str, s: &Summary, lost: usize| {
        specchio::say!(
            "{name}: residual mean {:.3}, p99 {:.3}, max {:.3} degrees; {lost} mirror pixels without a ray",
            s.mean, s.p99, s.max
        );
    };
    specchio::say!(
        "{} mirror pixels; viewpoint {:?} (world, m); rays pass it at mean {:.3}, p99 {:.3}, max {:.3} m",
        cal.mirror_pixels,
        record.viewpoint_world,
        cal.ray_distance_m.mean,
        cal.ray_distance_m.p99,
        cal.ray_distance_m.max
    );
    line(
        "omnidir/Kalibr (Mei)",
        &cal.mei_residual.stats,
        cal.mei_residual.without_ray,
    );
    line(
        "OCamCalib (Scaramuzza)",
        &cal.ocam_residual.stats,
        cal.ocam_residual.without_ray,
    );
}
