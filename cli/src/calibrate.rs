//! `specchio calibrate`: the central models robotics tools calibrate (OpenCV omnidir, Kalibr
//! omni, OCamCalib), fitted to the sensor's exact ray map and exported in the tools' own
//! formats, each with its per-pixel residual (docs/sensor-models.md). Pure geometry: no GPU.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use specchio::output::Transaction;
use specchio::process::interrupt;
use specchio::process::progress;
use specchio::sensor::central::record::{CalibrationRecord, Summary};
use specchio::sensor::central::{folder, Calibration, FitError};

use specchio::process::args::seconds;

#[derive(clap::Args)]
pub struct Args {
    /// The scene file (TOML; see docs/scene-format.md).
    scene: PathBuf,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Scene time in seconds (0 to 1e9): where the mirror and sensor are.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true,
          value_parser = seconds)]
    time: f64,
}

pub fn run(args: &Args) -> Result<ExitCode> {
    interrupt::catch();
    let loaded = specchio::scene::load(&args.scene);
    let scene = crate::render_input::unless_stopped(loaded, "while loading the scene")?;
    if let Some(why) = Calibration::too_large(&scene) {
        bail!("{}: {why}", args.scene.display());
    }
    specchio::memory::estimates::calibrate(&scene)
        .with_context(|| args.scene.display().to_string())?;
    // All or nothing: written into a hidden folder beside --out, renamed into place at the end.
    let mut out = Transaction::new();
    out.folder(&args.out, folder::RECORD)?;
    // A 4096² sensor takes seconds: past the first parts the estimate is said.
    let progress = progress::calibration("calibrate", scene.sensor.resolution, true);
    let (cal, map) = match Calibration::of_scene_watched(&scene, args.time, &progress) {
        Err(FitError::Stopped(next)) => {
            return Err(interrupt::stopped(&format!("before {next}")).into())
        }
        fitted => fitted
            .with_context(|| format!("{}: cannot fit the central models", args.scene.display()))?,
    };
    let topic = specchio::sensor::bag::kalibr_image_topic(scene.sensor.imaging.is_some());
    let scene_and_topic = (args.scene.as_path(), topic);
    let record = folder::write(&out, &args.out, (&cal, &map), scene_and_topic, args.time)?;
    print_summary(&record, &cal);
    // A signal that came after the last check still stops the run: nothing is placed.
    interrupt::check("before placing the output")?;
    out.commit()?;
    Ok(ExitCode::SUCCESS)
}

fn print_summary(record: &CalibrationRecord, cal: &Calibration) {
    let line = |name: &str, s: &Summary, lost: usize| {
        specchio::say!(
            "{name}: residual mean {:.3}, p99 {:.3}, max {:.3} degrees; {lost} mirror pixels without a ray",
            s.mean, s.p99, s.max
        );
    };
    // To a tenth of a millimetre, as the distances beside it: `{:?}` printed a viewpoint at
    // the origin as [-1.2805146162418848e-22, -3.8157153800408385e-10, 2.1826031995858615e-30].
    let point = record.viewpoint_world.map(|v| match format!("{v:.4}") {
        t if t.trim_start_matches(['-', '0', '.']).is_empty() => "0.0000".to_owned(),
        t => t,
    });
    specchio::say!(
        "{} mirror pixels; viewpoint [{}] (world, m); rays pass it at mean {:.3}, p99 {:.3}, max {:.3} m",
        cal.mirror_pixels,
        point.join(", "),
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
    let tolerance = specchio::sensor::central::scaramuzza::INVPOL_TOLERANCE_PX;
    if cal.ocam_invpol_error_px >= tolerance {
        specchio::say_err!(
            "warning: OCamCalib's invpol (world2cam) is within {:.3} px of its polynomial's \
             inverse, not the {tolerance} px OCamCalib fits to: no degree up to 30 does better \
             over this {}x{} image's radii (calibration.json: ocamcalib.inverse_error_px); \
             cam2world and the omnidir model are not affected",
            cal.ocam_invpol_error_px,
            cal.width,
            cal.height
        );
    }
}
