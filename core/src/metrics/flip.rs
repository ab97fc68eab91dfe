//! FLIP through `nv-flip`, computed in bands of rows, in parallel, and watched.
//!
//! `nv-flip` builds its C++ without OpenMP, so one call is one core for the whole image: an
//! 8192² comparison ran for about a minute without a word, could not be stopped, and held some
//! 8 GB of intermediate images. FLIP is local, though: a pixel's error reads only the pixels
//! within reach of its filters (the spatial filter and the feature filter, each applied as a
//! row pass then a column pass, clamped at the image's border). So each band of rows is
//! computed from itself and [`BAND_MARGIN`] rows on either side, and its own rows come out
//! exactly as from the whole image: the same sums over the same pixels in the same order
//! (tested bit for bit). The bands run on rayon's threads, a band's rows are reported to a
//! [`Watch`] as its band ends, and a stop is honoured before the next band.

use std::ops::Range;
use std::sync::OnceLock;

use rayon::prelude::*;

use super::FLIP_PIXELS_PER_DEGREE;
use crate::image::png::linear_to_srgb;
use crate::image::RgbaImage;
use crate::watch::{Stopped, Unwatched, Watch};

/// Rows read beyond a band on each side. At [`FLIP_PIXELS_PER_DEGREE`] = 67 the widest filter
/// reaches 10 rows (the spatial filter: ⌈3 · √(0.04 / 2π²) · 67⌉; the feature filter:
/// ⌈3 · 0.5 · 0.082 · 67⌉ = 9), and the two are applied side by side, not one after the other,
/// so 10 rows do (and 9 do not: the tests hold both); 12 leave room.
pub const BAND_MARGIN: u32 = 12;

/// About how many pixels a band holds: under a second of one core's work (0.67 s here), so a
/// stop waits no longer than that and the first estimate, said once a band has ended, comes
/// soon; the margin's rows add a fifth at most (8192 wide: 128 rows and 24 more read).
const BAND_PIXELS: u64 = 1 << 20;

/// The fewest rows a band holds, however wide the image: the margin's rows add at most 3/8.
const MIN_BAND_ROWS: u32 = 64;

/// Rows a band holds instead of [`band_rows`]'s choice, a whole number from 1: larger bands
/// read fewer margin rows, smaller ones stop sooner. The tests set it to hold long FLIP work
/// that no signal cuts short, as a band is.
pub const BAND_ROWS_VAR: &str = "SPECCHIO_FLIP_BAND_ROWS";

/// The per-pixel FLIP map (LDR FLIP, [`FLIP_PIXELS_PER_DEGREE`]) of two same-size linear
/// images, each first encoded to 8-bit sRGB exactly as the PNG previews are
/// ([`linear_to_srgb`], clamped to [0, 1], NaN as 0).
pub fn flip_map(test: &RgbaImage, reference: &RgbaImage) -> Vec<f32> {
    flip_map_watched(test, reference, &Unwatched).expect("an unwatched map is never stopped")
}

/// [`flip_map`], each band's rows reported to `watch` as it ends; [`Stopped`] when `watch`
/// said to stop before a band.
pub fn flip_map_watched(
    test: &RgbaImage,
    reference: &RgbaImage,
    watch: &dyn Watch,
) -> Result<Vec<f32>, Stopped> {
    let rows = chosen_band_rows().unwrap_or_else(|| band_rows(test.width));
    in_bands(
        &Srgb8::of(test),
        &Srgb8::of(reference),
        rows,
        BAND_MARGIN,
        watch,
    )
}

/// The rows [`BAND_ROWS_VAR`] asks for, if any; a value that is not a whole number from 1 is
/// said once and not used.
fn chosen_band_rows() -> Option<u32> {
    static ROWS: OnceLock<Option<u32>> = OnceLock::new();
    *ROWS.get_or_init(|| {
        let text = std::env::var_os(BAND_ROWS_VAR)?;
        let text = text.to_string_lossy();
        let rows = text.trim().parse().ok().filter(|&r: &u32| r > 0);
        if rows.is_none() {
            crate::warnings::warn(&format!(
                "{BAND_ROWS_VAR}={} is not a whole number from 1; FLIP's bands are chosen by \
                 the image's width",
                crate::text::quoted_text(&text)
            ));
        }
        rows
    })
}

/// How many rows a band of an image `width` pixels wide holds.
fn band_rows(width: u32) -> u32 {
    let rows = BAND_PIXELS / u64::from(width.max(1));
    (rows.min(u64::from(u32::MAX)) as u32).max(MIN_BAND_ROWS)
}

/// An image as FLIP reads it: 8-bit sRGB, three bytes a pixel, row after row.
struct Srgb8 {
    width: u32,
    height: u32,
    bytes: Vec<u8>,
}

impl Srgb8 {
    fn of(image: &RgbaImage) -> Self {
        let bytes = (image.pixels.par_iter())
            .flat_map_iter(|p| [p[0], p[1], p[2]])
            .map(|v| (linear_to_srgb(v) * 255.0).round() as u8)
            .collect();
        Self {
            width: image.width,
            height: image.height,
            bytes,
        }
    }

    /// Rows `rows` as an image of their own.
    fn rows(&self, rows: &Range<u32>) -> nv_flip::FlipImageRgb8 {
        let row = self.width as usize * 3;
        let bytes = &self.bytes[rows.start as usize * row..rows.end as usize * row];
        nv_flip::FlipImageRgb8::with_data(self.width, rows.len() as u32, bytes)
    }
}

/// The map in bands of `rows` rows, each computed with `margin` rows more on either side.
fn in_bands(
    test: &Srgb8,
    reference: &Srgb8,
    rows: u32,
    margin: u32,
    watch: &dyn Watch,
) -> Result<Vec<f32>, Stopped> {
    let (w, h) = (reference.width as usize, reference.height);
    watch.begin(u64::from(h), reference.width);
    let rows = rows.max(1);
    // Each band writes its rows into the one map (bands of `rows` rows, the last shorter).
    let mut map = vec![0.0f32; w * h as usize];
    (map.par_chunks_mut((rows as usize * w).max(1)).enumerate()).try_for_each(|(i, out)| {
        if watch.stop() {
            return Err(Stopped);
        }
        let start = i as u32 * rows;
        let band = start..start.saturating_add(rows).min(h);
        out.copy_from_slice(&band_map(test, reference, &band, margin));
        watch.rows_done(band.len() as u32);
        Ok(())
    })?;
    Ok(map)
}

/// Band `band`'s rows of the map, computed from the band and `margin` rows either side of it.
fn band_map(test: &Srgb8, reference: &Srgb8, band: &Range<u32>, margin: u32) -> Vec<f32> {
    let read = band.start.saturating_sub(margin)..band.end.saturating_add(margin).min(test.height);
    let map = nv_flip::flip(
        reference.rows(&read),
        test.rows(&read),
        FLIP_PIXELS_PER_DEGREE,
    )
    .to_vec();
    let w = test.width as usize;
    let skip = (band.start - read.start) as usize * w;
    map[skip..skip + band.len() * w].to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::SplitMix64;
    use std::sync::atomic::{AtomicU32, Ordering};

    /// An image with detail at every scale: noise over gradients, with a sharp-edged disc.
    fn detailed(w: u32, h: u32, seed: u64) -> RgbaImage {
        let mut random = SplitMix64::new(seed);
        let mut image = RgbaImage {
            width: w,
            height: h,
            pixels: vec![[0.0; 4]; (w * h) as usize],
        };
        for y in 0..h {
            for x in 0..w {
                let (u, v) = (x as f32 / w as f32, y as f32 / h as f32);
                let disc = ((u - 0.5).powi(2) + (v - 0.4).powi(2) < 0.06) as u8 as f32;
                let mut noise = || random.unit() as f32 * 0.3;
                let p = [u + noise(), v * disc + noise(), 0.5 * disc + noise(), 1.0];
                image.pixels[(y * w + x) as usize] = p;
            }
        }
        image
    }

    fn whole(test: &RgbaImage, reference: &RgbaImage) -> Vec<f32> {
        let (t, r) = (Srgb8::of(test), Srgb8::of(reference));
        let all = 0..t.height;
        nv_flip::flip(r.rows(&all), t.rows(&all), FLIP_PIXELS_PER_DEGREE).to_vec()
    }

    /// Banded, the map is the whole image's bit for bit, whatever the band height (bands of
    /// one row, of fewer rows than the margin, of several, and one band); with a margin one
    /// row short of the filters' reach it is not.
    #[test]
    fn bands_give_the_whole_images_map_bit_for_bit() {
        let (test, reference) = (detailed(96, 75, 1), detailed(96, 75, 2));
        let expected = whole(&test, &reference);
        let (t, r) = (Srgb8::of(&test), Srgb8::of(&reference));
        for rows in [1, 7, 16, 33, 75, 200] {
            let banded = in_bands(&t, &r, rows, BAND_MARGIN, &Unwatched).unwrap();
            assert!(
                banded
                    .iter()
                    .map(|v| v.to_bits())
                    .eq(expected.iter().map(|v| v.to_bits())),
                "bands of {rows} rows"
            );
        }
        // The filters' reach, worked out above: 10 rows of margin do, 9 do not.
        let reach = in_bands(&t, &r, 16, 10, &Unwatched).unwrap();
        assert!(reach
            .iter()
            .map(|v| v.to_bits())
            .eq(expected.iter().map(|v| v.to_bits())));
        let short = in_bands(&t, &r, 16, 9, &Unwatched).unwrap();
        assert_ne!(short, expected, "9 rows of margin are too few");
        assert_eq!(flip_map(&test, &reference), expected);
    }

    /// Every row is reported once; a stop asked for ends the map before its next band.
    #[test]
    fn every_row_is_reported_and_a_stop_is_honoured() {
        struct Count(AtomicU32, u32);
        impl Watch for Count {
            fn rows_done(&self, rows: u32) {
                self.0.fetch_add(rows, Ordering::SeqCst);
            }
            fn stop(&self) -> bool {
                self.0.load(Ordering::SeqCst) >= self.1
            }
        }
        let (t, r) = (
            Srgb8::of(&detailed(40, 50, 3)),
            Srgb8::of(&detailed(40, 50, 4)),
        );
        let all = Count(AtomicU32::new(0), u32::MAX);
        assert!(in_bands(&t, &r, 8, BAND_MARGIN, &all).is_ok());
        assert_eq!(all.0.into_inner(), 50);
        let stopped = Count(AtomicU32::new(0), 0);
        assert_eq!(in_bands(&t, &r, 8, BAND_MARGIN, &stopped), Err(Stopped));
        assert_eq!(stopped.0.into_inner(), 0, "no band begun after the stop");
    }

    /// Wide images take fewer rows a band, down to a floor; narrow ones many.
    #[test]
    fn a_band_holds_about_a_million_pixels() {
        assert_eq!(band_rows(8192), 128);
        assert_eq!(band_rows(512), 2048);
        assert_eq!(band_rows(1 << 20), MIN_BAND_ROWS);
        assert_eq!(band_rows(0), 1 << 20);
    }
}
