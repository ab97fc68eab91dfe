//! `specchio compare TEST REFERENCE`: error metrics of one linear EXR against another (see
//! `docs/accuracy.md`, "Metrics"). Exits 0 whenever the images were compared, however much
//! they differ; bad input is an error naming the file, and writes nothing.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

use crate::records::{CompareRecord, CompareSettings};
use anyhow::{Context, Result};
use specchio::metrics::{
    self, Comparison, MetricsError, FLIP_PERCENTILE, FLIP_PIXELS_PER_DEGREE, MASK_THRESHOLD,
    PSNR_PEAK, REL_MSE_EPSILON,
};
use specchio::output::{Sink, Transaction};
use specchio::process::interrupt;
use specchio::process::progress::Progress;
use specchio::reference::angular;
use specchio::watch::Watch;

#[derive(clap::Args)]
pub struct Args {
    /// The image under test (linear OpenEXR, first RGBA layer).
    test: PathBuf,
    /// The reference image (linear OpenEXR), same size; relMSE divides by it.
    reference: PathBuf,
    /// Compare only the pixels whose red channel is above 0.5 (EXR, or PNG by its stored value).
    #[arg(long)]
    mask: Option<PathBuf>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// Write the per-pixel FLIP error as a colour-mapped PNG (magma; grey: not compared). A
    /// colour comparison's: not with --angular, which has no FLIP.
    #[arg(long, conflicts_with = "angular", value_parser = specchio::process::args::png_path)]
    heatmap: Option<PathBuf>,
    /// The two files are direction images (`render --directions` against the reference's
    /// `NAME.direction.exr`): report the mirror's angular lookup error instead, in degrees and
    /// in texels of a cube face of this size.
    #[arg(long, allow_negative_numbers = true, value_name = "FACE_SIZE", value_parser = specchio::process::args::face_size)]
    angular: Option<u32>,
}

pub fn run(args: &Args) -> Result<ExitCode> {
    // A signal stops the comparison at its next step with the staged heatmap removed (it
    // used to end the process and leave the staging folder behind): caught before staging.
    interrupt::catch();
    let out = stage_heatmap(args)?;
    if let Some(face_size) = args.angular {
        return angular(args, face_size);
    }
    // 1. Read and compare; any bad input stops here, before a file is written.
    let inputs = read_said(args)?;
    interrupt::check("after reading the images")?;
    let comparison = compare_said(&inputs)?;
    interrupt::check("after comparing")?;

    // 2. The heatmap, written atomically.
    if let Some(path) = &args.heatmap {
        let rgb8 = metrics::heatmap_rgb8(&comparison);
        let size = (comparison.width, comparison.height);
        let encoding =
            Said::new(|rows, w| format!("compare: writing the heatmap of {w}x{rows} pixels"));
        out.write_png_rgb8_watched(path, size, &rgb8, &encoding)?;
        interrupt::check("before placing the heatmap")?;
        out.commit()?;
    }

    // 3. Report.
    if args.json {
        specchio::say!(
            "{}",
            serde_json::to_string_pretty(&to_json(args, &comparison))?
        );
    } else {
        print_table(args, &comparison);
    }
    Ok(ExitCode::SUCCESS)
}

/// The comparison with its FLIP said as it goes (an 8192² comparison is about a minute of
/// FLIP): the estimate once it has run for a moment, and a stop between bands of rows.
fn compare_said(inputs: &metrics::Inputs) -> Result<Comparison> {
    let flip = Said::new(|rows, w| format!("compare: FLIP of {w}x{rows} pixels"));
    let (test, reference) = (&inputs.test, &inputs.reference);
    match metrics::compare_watched(test, reference, inputs.mask.as_ref(), &flip) {
        Err(MetricsError::Stopped) => {
            let at = format!("after {} of {} rows of FLIP", flip.done(), flip.rows());
            Err(interrupt::stopped(&at).into())
        }
        done => Ok(done?),
    }
}

/// The images read with their decoding said as it goes (two 8192² EXRs decode for seconds),
/// and stopped at the next chunk at a signal.
fn read_said(args: &Args) -> Result<metrics::Inputs> {
    let images = 2 + usize::from(args.mask.as_deref().is_some_and(metrics::is_exr_name));
    let reading = Said::new(move |rows, w| {
        let h = rows / images as u64;
        format!("compare: reading {images} images of {w}x{h} pixels")
    });
    let (test, reference) = (&args.test, &args.reference);
    match metrics::read_inputs_watched(test, reference, args.mask.as_deref(), &reading) {
        Err(MetricsError::Stopped) => {
            let at = format!(
                "while reading the images ({} of their {} rows decoded)",
                reading.done(),
                reading.rows()
            );
            Err(interrupt::stopped(&at).into())
        }
        read => Ok(read?),
    }
}

/// Work counted in rows into a [`Progress`] of pixels that is made as the work begins
/// (`Watch::begin`), so its clock starts then: what came before (the reading, the sRGB
/// conversions before FLIP) would count as its time (a 4096² comparison's first estimate
/// said 25 s for 5 s of FLIP). `what` names the work from its rows and their width.
struct Said<F: Fn(u64, u32) -> String + Sync> {
    what: F,
    whole: OnceLock<(Progress, u64, u64)>,
    done: AtomicU64,
}

impl<F: Fn(u64, u32) -> String + Sync> Said<F> {
    fn new(what: F) -> Self {
        Self {
            what,
            whole: OnceLock::new(),
            done: AtomicU64::new(0),
        }
    }

    /// Rows done so far, and in all (0 before the work began).
    fn done(&self) -> u64 {
        self.done.load(Ordering::Relaxed)
    }

    fn rows(&self) -> u64 {
        self.whole.get().map_or(0, |(_, rows, _)| *rows)
    }
}

impl<F: Fn(u64, u32) -> String + Sync> Watch for Said<F> {
    fn begin(&self, rows: u64, width: u32) {
        let w = u64::from(width);
        let progress = Progress::new((self.what)(rows, width), rows * w, "pixels");
        let _ = self.whole.set((progress, rows, w));
    }

    fn rows_done(&self, rows: u32) {
        self.done.fetch_add(u64::from(rows), Ordering::Relaxed);
        if let Some((progress, _, width)) = self.whole.get() {
            progress.add(u64::from(rows) * width);
        }
    }

    fn stop(&self) -> bool {
        interrupt::check("").is_err()
    }
}

/// Stages `--heatmap` before anything is read. A heatmap written over an input would destroy
/// the user's image: the transaction refuses an output that is one of its inputs.
fn stage_heatmap(args: &Args) -> Result<Transaction> {
    let mut out = Transaction::new();
    if let Some(heatmap) = &args.heatmap {
        for input in [Some(&args.test), Some(&args.reference), args.mask.as_ref()]
            .into_iter()
            .flatten()
        {
            out.input(input)?;
        }
        out.file(heatmap)
            .with_context(|| format!("--heatmap {}", heatmap.display()))?;
    }
    Ok(out)
}

/// `--angular`: the angle between the looked-up and the exact direction per mirror pixel.
fn angular(args: &Args, face_size: u32) -> Result<ExitCode> {
    // Read as a colour comparison's images are: said, stopped at a signal, the sizes and the
    // mask checked (two 8192² direction images read for 10 s, silently, through a Ctrl-C).
    let metrics::Inputs {
        test,
        reference,
        mask,
    } = read_said(args)?;
    interrupt::check("after reading the images")?;
    holds_directions(&args.test, &test)?;
    holds_directions(&args.reference, &reference)?;
    let keep = |x: u32, y: u32| {
        mask.as_ref()
            .is_none_or(|m| m.selected[(y * m.width + x) as usize])
    };
    let angles = angular::angles_deg(&test, &reference, keep);
    let e = angular::summarize(angles, face_size);
    if args.json {
        let mut value = serde_json::to_value(e)?;
        if e.pixels == 0 {
            // Nothing compared: the metrics are undefined, null as in the colour report.
            for (key, v) in value.as_object_mut().into_iter().flatten() {
                if key.ends_with("_deg") || key.ends_with("_texels") {
                    *v = serde_json::Value::Null;
                }
            }
        }
        specchio::say!("{}", serde_json::to_string_pretty(&value)?);
    } else if e.pixels == 0 {
        specchio::say!(
            "mirror pixels compared: 0 (no pixel has alpha 1 in both images inside the mask)"
        );
        specchio::say!("angular error (deg):    n/a");
    } else {
        specchio::say!("mirror pixels compared: {}", e.pixels);
        specchio::say!(
            "angular error (deg):    mean {:.4}  p99 {:.4}  max {:.4}",
            e.mean_deg,
            e.p99_deg,
            e.max_deg
        );
        specchio::say!(
            "in texels of {face_size}²:    mean {:.4}  p99 {:.4}  max {:.4}",
            e.mean_texels,
            e.p99_texels,
            e.max_texels
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The JSON report; every key is documented in docs/accuracy.md. Undefined metrics (nothing
/// compared) and an infinite PSNR are null, never a non-number.
fn to_json(args: &Args, c: &Comparison) -> CompareRecord {
    let path = |p: &Option<PathBuf>| p.as_ref().map(|p| p.display().to_string());
    let finite = |v: Option<f64>| v.filter(|v| v.is_finite());
    CompareRecord {
        test: args.test.display().to_string(),
        reference: args.reference.display().to_string(),
        mask: path(&args.mask),
        heatmap: path(&args.heatmap),
        width: c.width,
        height: c.height,
        pixels_in_mask: c.pixels_in_mask,
        pixels_compared: c.pixels_compared,
        test_nan_pixels: c.test_non_finite.nan_pixels,
        test_inf_pixels: c.test_non_finite.inf_pixels,
        reference_nan_pixels: c.reference_non_finite.nan_pixels,
        reference_inf_pixels: c.reference_non_finite.inf_pixels,
        rmse: c.rmse,
        psnr_db: finite(c.psnr_db),
        psnr_infinite: c.psnr_is_infinite(),
        rel_mse: c.rel_mse,
        max_abs_error: c.max_abs_error,
        flip_mean: c.flip_mean,
        flip_p99: c.flip_p99,
        settings: CompareSettings {
            psnr_peak: PSNR_PEAK,
            rel_mse_epsilon: REL_MSE_EPSILON,
            mask_threshold: MASK_THRESHOLD,
            flip_pixels_per_degree: FLIP_PIXELS_PER_DEGREE,
            flip_percentile: FLIP_PERCENTILE,
        },
    }
}

/// A metric for the table: six decimals where that reads (an image's errors are mostly between
/// 1e-4 and 1e3), else six significant digits with an exponent, so that an HDR image's 3e38
/// is not printed as 39 digits.
fn metric_text(v: f64) -> String {
    match v == 0.0 || (1e-4..1e6).contains(&v.abs()) {
        true => format!("{v:.6}"),
        false => format!("{v:.5e}"),
    }
}

fn print_table(args: &Args, c: &Comparison) {
    let num = |v: Option<f64>| v.map_or("n/a".to_owned(), metric_text);
    let psnr = match c.psnr_db {
        None => "n/a".to_owned(),
        Some(v) if v.is_infinite() => "inf (identical)".to_owned(),
        Some(v) if v.abs() >= 1e6 => format!("{v:.2e} dB"),
        Some(v) => format!("{v:.2} dB"),
    };
    specchio::say!(
        "compared {} against {} ({}x{})",
        args.test.display(),
        args.reference.display(),
        c.width,
        c.height
    );
    if let Some(mask) = &args.mask {
        specchio::say!("  mask:            {}", mask.display());
    }
    specchio::say!(
        "  pixels:          {} compared of {} in the mask",
        c.pixels_compared,
        c.pixels_in_mask
    );
    specchio::say!(
        "  NaN / Inf:       test {} / {}, reference {} / {} (excluded)",
        c.test_non_finite.nan_pixels,
        c.test_non_finite.inf_pixels,
        c.reference_non_finite.nan_pixels,
        c.reference_non_finite.inf_pixels
    );
    specchio::say!("  RMSE:            {}", num(c.rmse));
    specchio::say!("  {:<17}{psnr}", format!("PSNR (peak {PSNR_PEAK}):"));
    specchio::say!(
        "  {:<17}{}",
        format!("relMSE (e {REL_MSE_EPSILON}):"),
        num(c.rel_mse)
    );
    specchio::say!("  max |error|:     {}", num(c.max_abs_error));
    specchio::say!("  FLIP mean:       {}", num(c.flip_mean));
    specchio::say!("  FLIP 99th pct:   {}", num(c.flip_p99));
    if let Some(path) = &args.heatmap {
        specchio::say!("  heatmap:         {}", path.display());
    }
}

/// Refuses an image that is not a direction image: on every pixel it marks as the mirror's
/// (alpha 1) one holds a unit vector, or the zero vector of a ray that meets nothing, as
/// `render --directions` and `reference` write them.
/// A colour image has alpha 1 everywhere and colours of any length: compared as directions,
/// it gave angles that mean nothing, with success.
fn holds_directions(path: &std::path::Path, image: &specchio::image::RgbaImage) -> Result<()> {
    // The files are f32; a half-float copy still holds lengths within 1e-3 of 1.
    const TOLERANCE: f32 = 1e-2;
    let marked = image.pixels.iter().filter(|p| p[3] == 1.0);
    let (mut seen, mut wrong) = (0usize, None);
    for p in marked {
        seen += 1;
        let length = glam::Vec3::new(p[0], p[1], p[2]).length();
        if length == 0.0 {
            continue; // a ray that meets nothing
        }
        // NaN lengths count as wrong too.
        if (length - 1.0).abs() > TOLERANCE || length.is_nan() {
            wrong.get_or_insert(length);
        }
    }
    if let Some(length) = wrong {
        anyhow::bail!(
            "{}: not a direction image: a pixel marked as the mirror's (alpha 1) holds a vector \
             of length {}, not a unit direction (of {seen} marked); --angular compares the \
             direction files of `render --directions` and `reference` \
             (observer.direction.exr, sensor.direction.exr)",
            path.display(),
            specchio::text::num_text(length)
        );
    }
    Ok(())
}
