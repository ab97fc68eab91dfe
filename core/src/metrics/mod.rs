//! Image-error metrics: a test image against a reference, both linear HDR RGB.
//!
//! [`compare`] computes, over the pixels selected by an optional [`Mask`]: RMSE, PSNR, relMSE,
//! the largest absolute error, the NaN / Inf pixel counts of each image, and FLIP (NVIDIA's
//! perceptual difference, through the `nv-flip` crate) on 8-bit sRGB versions of both. The
//! exact definitions, with units and constants, are in `docs/accuracy.md` ("Metrics").
//!
//! ```no_run
//! use std::path::Path;
//! // `specchio::metrics` is this module, re-exported by the engine.
//! use specchio_core::metrics;
//!
//! let test = metrics::read_exr(Path::new("a/observer.exr"))?;
//! let reference = metrics::read_exr(Path::new("b/observer.exr"))?;
//! let c = metrics::compare(&test, &reference, None)?;
//! println!("RMSE {:?}, FLIP mean {:?}", c.rmse, c.flip_mean);
//! metrics::write_heatmap(Path::new("flip.png"), &c)?;
//! # Ok::<(), metrics::MetricsError>(())
//! ```

mod flip;
mod heatmap;
pub mod percentile;
mod read;

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use crate::image::RgbaImage;
use crate::output::OutputError;
use crate::watch::{Stopped, Unwatched, Watch};

pub use flip::{flip_map, flip_map_watched, BAND_MARGIN as FLIP_BAND_MARGIN};
pub use heatmap::{colour_map, heatmap_rgb8, write_heatmap, NOT_COMPARED_RGB8};
pub use read::{
    is_exr_name, read_exr, read_exr_channels, read_inputs, read_inputs_watched, read_mask, Inputs,
    MAX_INPUT_SIDE_PX,
};

/// PSNR's peak signal: linear 1.0 (diffuse white). HDR values above it are not clipped, so an
/// error larger than 1 gives a negative PSNR.
pub const PSNR_PEAK: f64 = 1.0;

/// relMSE's epsilon in `(a - b)^2 / (b^2 + epsilon)`: keeps black reference pixels from
/// dividing by zero; an error of 0.1 on black then weighs 1.0.
pub const REL_MSE_EPSILON: f64 = 0.01;

/// FLIP's pixels per degree of visual angle: FLIP's default, a 0.7 m wide 4K monitor seen from
/// 0.7 m. Larger values hide finer detail.
pub const FLIP_PIXELS_PER_DEGREE: f32 = 67.0;

/// The FLIP percentile reported next to the mean (nearest rank, [`percentile`]).
pub const FLIP_PERCENTILE: f64 = 0.99;

/// A mask pixel selects its image pixel when its red channel is above this (EXR: the linear
/// value; PNG: the stored value scaled to [0, 1], so 128 and up in 8 bits).
pub const MASK_THRESHOLD: f32 = 0.5;

#[derive(Debug, thiserror::Error)]
pub enum MetricsError {
    #[error("{path}: no such file")]
    Missing { path: PathBuf },
    #[error("cannot read {path}: {message}")]
    Read { path: PathBuf, message: String },
    #[error("size mismatch: {a_name} is {}x{}, {b_name} is {}x{}", a_size.0, a_size.1, b_size.0, b_size.1)]
    SizeMismatch {
        a_name: String,
        a_size: (u32, u32),
        b_name: String,
        b_size: (u32, u32),
    },
    /// Two images of one size whose data windows start at different pixels: compared pixel
    /// for pixel, they would be compared shifted.
    #[error(
        "data window mismatch: {a_name} starts at ({}, {}), {b_name} at ({}, {}); the images \
         are compared pixel for pixel, so their windows must start at the same pixel",
        a_origin.0, a_origin.1, b_origin.0, b_origin.1
    )]
    OriginMismatch {
        a_name: String,
        a_origin: (i32, i32),
        b_name: String,
        b_origin: (i32, i32),
    },
    #[error(
        "{path}: the mask selects no pixel (every red value is at most {threshold}): there is \
         nothing to compare"
    )]
    EmptyMask { path: PathBuf, threshold: f32 },
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The comparison's memory estimate, from the headers, is over the budget.
    #[error(transparent)]
    Memory(#[from] crate::memory::MemoryError),
    /// The caller's watch stopped the reading or the comparison before it was done.
    #[error("stopped before the comparison was done")]
    Stopped,
}

/// Which pixels take part: `selected[y * width + x]`, rows top to bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct Mask {
    pub width: u32,
    pub height: u32,
    pub selected: Vec<bool>,
}

impl Mask {
    /// A mask read from `path` must select some pixel. A comparison of none reports every
    /// metric as n/a and would exit 0: a script that trusts the exit status would pass an
    /// all-black mask (an image written over the mask, say).
    pub fn check_selects(&self, path: &Path) -> Result<(), MetricsError> {
        if self.selected.contains(&true) {
            return Ok(());
        }
        Err(MetricsError::EmptyMask {
            path: path.to_owned(),
            threshold: MASK_THRESHOLD,
        })
    }

    /// Every pixel whose red channel is above [`MASK_THRESHOLD`].
    pub fn from_red(image: &RgbaImage) -> Mask {
        Mask {
            width: image.width,
            height: image.height,
            selected: image.pixels.iter().map(|p| p[0] > MASK_THRESHOLD).collect(),
        }
    }
}

/// NaN and Inf pixels of one image, among the masked pixels. A pixel is NaN when any of its
/// R, G, B is NaN, otherwise Inf when any is infinite; alpha is ignored.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NonFinite {
    pub nan_pixels: u64,
    pub inf_pixels: u64,
}

/// The result of [`compare`]. The error metrics are `None` when no pixel was compared (empty
/// mask, or every masked pixel non-finite in one of the images).
#[derive(Debug, Clone)]
pub struct Comparison {
    pub width: u32,
    pub height: u32,
    /// Pixels the mask selects (`width * height` without a mask).
    pub pixels_in_mask: u64,
    /// Masked pixels finite in both images: the ones every metric below is taken over.
    pub pixels_compared: u64,
    pub test_non_finite: NonFinite,
    pub reference_non_finite: NonFinite,
    /// `sqrt(mean((a - b)^2))` over R, G, B of the compared pixels (linear units).
    pub rmse: Option<f64>,
    /// `10 log10(PSNR_PEAK^2 / MSE)` in dB; `+inf` when the RMSE is 0.
    pub psnr_db: Option<f64>,
    /// `mean((a - b)^2 / (b^2 + REL_MSE_EPSILON))` over R, G, B, b the reference.
    pub rel_mse: Option<f64>,
    /// `max |a - b|` over R, G, B of the compared pixels (linear units).
    pub max_abs_error: Option<f64>,
    /// Mean of the FLIP map over the compared pixels, in [0, 1].
    pub flip_mean: Option<f64>,
    /// The 99th percentile of the FLIP map over the compared pixels, nearest rank: the
    /// `ceil(0.99 n)`-th smallest value.
    pub flip_p99: Option<f64>,
    /// The per-pixel FLIP value of every pixel (rows top to bottom), masked or not.
    pub flip_map: Vec<f32>,
    /// Which pixels were compared (in the mask and finite in both images).
    pub compared: Vec<bool>,
}

impl Comparison {
    /// Whether the images are identical on the compared pixels (PSNR is infinite).
    pub fn psnr_is_infinite(&self) -> bool {
        self.psnr_db.is_some_and(f64::is_infinite)
    }
}

/// Compares `test` with `reference` (same size) over the pixels `mask` selects (all without
/// one). See the fields of [`Comparison`] for the definitions.
pub fn compare(
    test: &RgbaImage,
    reference: &RgbaImage,
    mask: Option<&Mask>,
) -> Result<Comparison, MetricsError> {
    compare_watched(test, reference, mask, &Unwatched)
}

/// [`compare`], its FLIP reported row by row to `watch`, which may stop it between bands of
/// rows ([`MetricsError::Stopped`]): FLIP is nearly all of a comparison's time.
pub fn compare_watched(
    test: &RgbaImage,
    reference: &RgbaImage,
    mask: Option<&Mask>,
    watch: &dyn Watch,
) -> Result<Comparison, MetricsError> {
    same_size(("the test image", test), ("the reference image", reference))?;
    if let Some(mask) = mask {
        same_size_as_mask(("the reference image", reference), ("the mask", mask))?;
    }

    // 1. Which pixels count: in the mask, and finite in both images.
    let n = reference.pixels.len();
    let in_mask = |i: usize| mask.is_none_or(|m| m.selected[i]);
    let (mut test_non_finite, mut reference_non_finite) =
        (NonFinite::default(), NonFinite::default());
    let mut compared = vec![false; n];
    for (i, c) in compared.iter_mut().enumerate() {
        if !in_mask(i) {
            continue;
        }
        let a = count_non_finite(&test.pixels[i], &mut test_non_finite);
        let b = count_non_finite(&reference.pixels[i], &mut reference_non_finite);
        *c = a && b;
    }

    // 2. Linear metrics, accumulated in f64.
    let (mut sum_sq, mut sum_rel, mut max_abs, mut count) = (0.0f64, 0.0f64, 0.0f64, 0u64);
    for i in (0..n).filter(|&i| compared[i]) {
        for ch in 0..3 {
            let a = f64::from(test.pixels[i][ch]);
            let b = f64::from(reference.pixels[i][ch]);
            let d = a - b;
            sum_sq += d * d;
            sum_rel += d * d / (b * b + REL_MSE_EPSILON);
            max_abs = max_abs.max(d.abs());
        }
        count += 1;
    }
    let channels = (count * 3) as f64;
    let some = |v: f64| (count > 0).then_some(v);
    let mse = sum_sq / channels;
    let rmse = some(mse.sqrt());
    let psnr_db = some(if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (PSNR_PEAK * PSNR_PEAK / mse).log10()
    });

    // 3. FLIP on 8-bit sRGB, the whole image (its filters are spatial; `flip` computes it in
    //    bands with their filters' reach), pooled over the
    //    compared pixels. A pixel NaN or Inf in either image is left out here too: it takes
    //    the same finite value in both (the finite one's, else black), so it differs nowhere
    //    and makes no edge for its neighbours' filters to see.
    let (test, reference) = finite_alike(test, reference);
    let flip_map =
        flip_map_watched(&test, &reference, watch).map_err(|Stopped| MetricsError::Stopped)?;
    let mut flip: Vec<f32> = (0..n)
        .filter(|&i| compared[i])
        .map(|i| flip_map[i])
        .collect();
    flip.sort_by(f32::total_cmp);
    let flip_mean = some(flip.iter().map(|&v| f64::from(v)).sum::<f64>() / flip.len() as f64);
    let flip_p99 = percentile::of_sorted(&flip, FLIP_PERCENTILE).map(f64::from);

    Ok(Comparison {
        width: reference.width,
        height: reference.height,
        pixels_in_mask: (0..n).filter(|&i| in_mask(i)).count() as u64,
        pixels_compared: count,
        test_non_finite,
        reference_non_finite,
        rmse,
        psnr_db,
        rel_mse: some(sum_rel / channels),
        max_abs_error: some(max_abs),
        flip_mean,
        flip_p99,
        flip_map,
        compared,
    })
}

/// Both images with every pixel that is NaN or Inf in either made the same finite value in
/// both: the reference's where it is finite, else the test's, else black. Copied only where
/// there is such a pixel (the images may be large).
fn finite_alike<'i>(
    test: &'i RgbaImage,
    reference: &'i RgbaImage,
) -> (Cow<'i, RgbaImage>, Cow<'i, RgbaImage>) {
    let finite = |p: &[f32; 4]| p[..3].iter().all(|v| v.is_finite());
    let all_finite = |img: &RgbaImage| img.pixels.iter().all(finite);
    if all_finite(test) && all_finite(reference) {
        return (Cow::Borrowed(test), Cow::Borrowed(reference));
    }
    let (mut test, mut reference) = (test.clone(), reference.clone());
    for (t, r) in test.pixels.iter_mut().zip(&mut reference.pixels) {
        if finite(t) && finite(r) {
            continue;
        }
        let value = match (finite(r), finite(t)) {
            (true, _) => *r,
            (false, true) => *t,
            (false, false) => [0.0, 0.0, 0.0, 1.0],
        };
        (*t, *r) = (value, value);
    }
    (Cow::Owned(test), Cow::Owned(reference))
}

/// Counts a NaN or Inf pixel; returns whether the pixel is finite.
fn count_non_finite(p: &[f32; 4], counts: &mut NonFinite) -> bool {
    let rgb = &p[..3];
    if rgb.iter().any(|v| v.is_nan()) {
        counts.nan_pixels += 1;
        false
    } else if rgb.iter().any(|v| v.is_infinite()) {
        counts.inf_pixels += 1;
        false
    } else {
        true
    }
}

fn same_size(a: (&str, &RgbaImage), b: (&str, &RgbaImage)) -> Result<(), MetricsError> {
    check_size(a.0, (a.1.width, a.1.height), b.0, (b.1.width, b.1.height))
}

fn same_size_as_mask(a: (&str, &RgbaImage), mask: (&str, &Mask)) -> Result<(), MetricsError> {
    check_size(
        a.0,
        (a.1.width, a.1.height),
        mask.0,
        (mask.1.width, mask.1.height),
    )
}

fn check_size(
    a_name: &str,
    a_size: (u32, u32),
    b_name: &str,
    b_size: (u32, u32),
) -> Result<(), MetricsError> {
    if a_size == b_size {
        return Ok(());
    }
    Err(MetricsError::SizeMismatch {
        a_name: a_name.to_owned(),
        a_size,
        b_name: b_name.to_owned(),
        b_size,
    })
}

#[cfg(test)]
mod tests;
