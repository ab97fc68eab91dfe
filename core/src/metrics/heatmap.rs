//! The FLIP error heatmap: each pixel's FLIP value through a magma-like colour map.

use std::path::Path;

use super::{Comparison, MetricsError};
use crate::output::write_png_rgb8;

/// Nine stops of matplotlib's magma (sRGB bytes at 0, 1/8, ..., 1): black through purple and
/// orange to pale yellow. Perceptually ordered: lightness rises at every stop, so a larger
/// error always reads brighter, also in greyscale.
const MAGMA_STOPS: [[u8; 3]; 9] = [
    [0, 0, 4],
    [28, 16, 68],
    [79, 18, 123],
    [129, 37, 129],
    [181, 54, 122],
    [229, 80, 100],
    [251, 135, 97],
    [254, 194, 135],
    [252, 253, 191],
];

/// Pixels outside the mask or non-finite in either image (not compared): mid grey, which the
/// colour map never produces with equal channels.
pub const NOT_COMPARED_RGB8: [u8; 3] = [128, 128, 128];

/// The colour of `value` in [0, 1] (clamped; NaN as 0), interpolated linearly between the
/// neighbouring stops in sRGB bytes.
pub fn colour_map(value: f32) -> [u8; 3] {
    let v = if value.is_nan() {
        0.0
    } else {
        value.clamp(0.0, 1.0)
    };
    let x = v * (MAGMA_STOPS.len() - 1) as f32;
    let i = (x.floor() as usize).min(MAGMA_STOPS.len() - 2);
    let t = x - i as f32;
    let (lo, hi) = (MAGMA_STOPS[i], MAGMA_STOPS[i + 1]);
    std::array::from_fn(|c| {
        (f32::from(lo[c]) + t * (f32::from(hi[c]) - f32::from(lo[c]))).round() as u8
    })
}

/// Writes the heatmap of `comparison` as an 8-bit PNG the size of the images, atomically
/// (nothing at `path` on error).
pub fn write_heatmap(path: &Path, comparison: &Comparison) -> Result<(), MetricsError> {
    write_png_rgb8(
        path,
        comparison.width,
        comparison.height,
        &heatmap_rgb8(comparison),
    )?;
    Ok(())
}

/// The heatmap's pixels, 8-bit RGB rows top to bottom (for a caller writing it through its own
/// output transaction).
pub fn heatmap_rgb8(comparison: &Comparison) -> Vec<u8> {
    comparison
        .flip_map
        .iter()
        .zip(&comparison.compared)
        .flat_map(|(&v, &compared)| {
            if compared {
                colour_map(v)
            } else {
                NOT_COMPARED_RGB8
            }
        })
        .collect()
}
