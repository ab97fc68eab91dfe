//! Known answers for every metric.

use super::*;
use crate::scene::TextureData;
use crate::watch::Watch;

/// Bad and unusual EXR inputs.
mod exr_inputs;

fn image(width: u32, height: u32, f: impl Fn(u32, u32) -> [f32; 4]) -> RgbaImage {
    RgbaImage {
        width,
        height,
        pixels: (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| f(x, y))
            .collect(),
    }
}

/// A smooth gradient with every channel in [0.2, 0.8], so +-0.1 stays in range.
fn gradient(width: u32, height: u32) -> RgbaImage {
    image(width, height, |x, y| {
        let u = x as f32 / width as f32;
        let v = y as f32 / height as f32;
        [0.2 + 0.6 * u, 0.2 + 0.6 * v, 0.5, 1.0]
    })
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("specchio-metrics-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn identical_images_have_zero_error_and_infinite_psnr() {
    let a = gradient(16, 8);
    let c = compare(&a, &a, None).unwrap();
    assert_eq!(c.pixels_compared, 128);
    assert_eq!(c.pixels_in_mask, 128);
    assert_eq!(c.rmse, Some(0.0));
    assert_eq!(c.rel_mse, Some(0.0));
    assert_eq!(c.max_abs_error, Some(0.0));
    assert!(c.psnr_is_infinite());
    assert_eq!(c.flip_mean, Some(0.0));
    assert_eq!(c.flip_p99, Some(0.0));
}

#[test]
fn constant_offset_of_a_tenth_is_rmse_0_1_and_psnr_20_db() {
    let reference = gradient(16, 8);
    let test = image(16, 8, |x, y| {
        let p = reference.pixel(x, y);
        [p[0] + 0.1, p[1] - 0.1, p[2] + 0.1, 0.0]
    });
    let c = compare(&test, &reference, None).unwrap();
    // f32 rounding of p + 0.1 is below 1e-7 at these magnitudes.
    assert!((c.rmse.unwrap() - 0.1).abs() < 1e-6, "{:?}", c.rmse);
    // PSNR = 10 log10(1 / 0.01) = 20 dB.
    assert!((c.psnr_db.unwrap() - 20.0).abs() < 1e-4, "{:?}", c.psnr_db);
    assert!((c.max_abs_error.unwrap() - 0.1).abs() < 1e-6);
    assert!(!c.psnr_is_infinite());
}

#[test]
fn rel_mse_of_a_hand_computed_2x1_image() {
    // Pixel 0: reference (1, 0, 0.5), test (0, 0, 0.5): only R differs, by 1.
    //   (1)^2 / (1^2 + 0.01) = 1 / 1.01 = 0.990099010
    // Pixel 1: reference (0.5, 0.5, 0.5), test (0.75, 0.5, 0.25): R and B differ by 0.25.
    //   2 * 0.0625 / (0.25 + 0.01) = 0.480769231
    // Mean over 6 channel values: 1.470868241 / 6 = 0.245144707.
    let reference = RgbaImage {
        width: 2,
        height: 1,
        pixels: vec![[1.0, 0.0, 0.5, 1.0], [0.5, 0.5, 0.5, 1.0]],
    };
    let test = RgbaImage {
        width: 2,
        height: 1,
        pixels: vec![[0.0, 0.0, 0.5, 1.0], [0.75, 0.5, 0.25, 1.0]],
    };
    let c = compare(&test, &reference, None).unwrap();
    assert!(
        (c.rel_mse.unwrap() - 0.245_144_707).abs() < 1e-8,
        "{:?}",
        c.rel_mse
    );
    // MSE = (1 + 2 * 0.0625) / 6 = 0.1875.
    assert!((c.rmse.unwrap() - 0.1875f64.sqrt()).abs() < 1e-12);
    assert_eq!(c.max_abs_error, Some(1.0));
}

#[test]
fn only_masked_pixels_count() {
    // The left half differs by 0.5, the right half by 0.1; the mask keeps the right half.
    let reference = image(8, 4, |_, _| [0.5, 0.5, 0.5, 1.0]);
    let test = image(8, 4, |x, _| {
        let d = if x < 4 { 0.5 } else { 0.1 };
        [0.5 + d, 0.5 + d, 0.5 + d, 1.0]
    });
    let mask = Mask::from_red(&image(8, 4, |x, _| {
        [if x < 4 { 0.0 } else { 1.0 }, 0.0, 0.0, 1.0]
    }));
    let c = compare(&test, &reference, Some(&mask)).unwrap();
    assert_eq!(c.pixels_in_mask, 16);
    assert_eq!(c.pixels_compared, 16);
    assert!((c.rmse.unwrap() - 0.1).abs() < 1e-6);
    assert!((c.max_abs_error.unwrap() - 0.1).abs() < 1e-6);
    let unmasked = compare(&test, &reference, None).unwrap();
    assert!((unmasked.max_abs_error.unwrap() - 0.5).abs() < 1e-6);
    // An empty mask compares nothing: every metric is undefined, not zero.
    let empty = Mask {
        width: 8,
        height: 4,
        selected: vec![false; 32],
    };
    let c = compare(&test, &reference, Some(&empty)).unwrap();
    assert_eq!(c.pixels_compared, 0);
    assert_eq!((c.rmse, c.psnr_db, c.flip_mean), (None, None, None));
}

#[test]
fn nan_and_inf_pixels_are_counted_and_excluded() {
    let reference = image(4, 1, |_, _| [0.5, 0.5, 0.5, 1.0]);
    let mut test = image(4, 1, |_, _| [0.6, 0.6, 0.6, 1.0]);
    test.pixels[0] = [f32::NAN, 0.0, 0.0, 1.0];
    test.pixels[1] = [0.0, f32::INFINITY, 0.0, 1.0];
    // NaN in alpha is ignored: the pixel is finite.
    test.pixels[2] = [0.6, 0.6, 0.6, f32::NAN];
    let mut reference_bad = reference.clone();
    reference_bad.pixels[3] = [f32::NEG_INFINITY, f32::NAN, 0.0, 1.0];

    let c = compare(&test, &reference_bad, None).unwrap();
    let nf = |nan_pixels, inf_pixels| NonFinite {
        nan_pixels,
        inf_pixels,
    };
    assert_eq!(c.test_non_finite, nf(1, 1));
    // NaN wins over Inf within one pixel.
    assert_eq!(c.reference_non_finite, nf(1, 0));
    assert_eq!(c.pixels_compared, 1);
    assert!((c.rmse.unwrap() - 0.1).abs() < 1e-6);
    assert!(c.rmse.unwrap().is_finite() && c.flip_mean.unwrap().is_finite());
    assert_eq!(c.compared, [false, false, true, false]);
}

/// A NaN or Inf pixel is left out of FLIP as of every metric: where the pixels compared are
/// equal, FLIP is 0 however the left-out ones lie among them (black NaN pixels between white
/// ones measured 0.81 before, their edges spread by FLIP's filters).
#[test]
fn non_finite_pixels_leave_flip_as_they_leave_the_rest() {
    let white = image(16, 16, |_, _| [1.0, 1.0, 1.0, 1.0]);
    let holes = |bad: f32| {
        image(16, 16, move |x, y| match (x + y) % 2 {
            0 => [bad, 1.0, 1.0, 1.0],
            _ => [1.0, 1.0, 1.0, 1.0],
        })
    };
    for bad in [f32::NAN, f32::INFINITY] {
        for (test, reference) in [(holes(bad), white.clone()), (white.clone(), holes(bad))] {
            let c = compare(&test, &reference, None).unwrap();
            assert_eq!(c.pixels_compared, 128);
            assert_eq!(
                (c.rmse, c.flip_mean, c.flip_p99),
                (Some(0.0), Some(0.0), Some(0.0))
            );
        }
    }
}

/// FLIP of two uniform colours, from its definition (Andersson et al., "FLIP: A Difference
/// Evaluator for Alternating Images", HPG 2020, section 4), independently of the `nv-flip` code:
/// a uniform image has no edges or points, so the feature difference is 0 and FLIP is the
/// colour difference alone; the CSF filters are normalised, so they leave a uniform image as it
/// is. The colour pipeline: linear sRGB to CIELAB (D65 white), the Hunt adjustment (a and b
/// scaled by 0.01 L), the HyAB distance |dL| + |d(a, b)|, raised to q_c = 0.7, then mapped to
/// [0, 1]: linearly to p_t = 0.95 at the knee p_c = 0.4 of the largest distance (Hunt-adjusted
/// green to blue), linearly from there to 1 at that distance. `a` and `b` are linear RGB.
fn flip_of_uniform(a: [f64; 3], b: [f64; 3]) -> f64 {
    const Q_C: f64 = 0.7;
    const P_C: f64 = 0.4;
    const P_T: f64 = 0.95;
    // Linear sRGB to XYZ (IEC 61966-2-1); white (1, 1, 1) maps to the row sums, D65.
    const M: [[f64; 3]; 3] = [
        [0.412_456_4, 0.357_576_1, 0.180_437_5],
        [0.212_672_9, 0.715_152_2, 0.072_175_0],
        [0.019_333_9, 0.119_192_0, 0.950_304_1],
    ];
    let hunt_lab = |rgb: [f64; 3]| {
        let xyz: [f64; 3] = std::array::from_fn(|i| {
            (0..3).map(|j| M[i][j] * rgb[j]).sum::<f64>() / M[i].iter().sum::<f64>()
        });
        let delta: f64 = 6.0 / 29.0;
        let f = |t: f64| {
            if t > delta.powi(3) {
                t.cbrt()
            } else {
                t / (3.0 * delta * delta) + 4.0 / 29.0
            }
        };
        let [fx, fy, fz] = xyz.map(f);
        let l = 116.0 * fy - 16.0;
        [
            l,
            0.01 * l * 500.0 * (fx - fy),
            0.01 * l * 200.0 * (fy - fz),
        ]
    };
    let hyab = |p: [f64; 3], q: [f64; 3]| (p[0] - q[0]).abs() + (p[1] - q[1]).hypot(p[2] - q[2]);
    let cmax = hyab(hunt_lab([0.0, 1.0, 0.0]), hunt_lab([0.0, 0.0, 1.0])).powf(Q_C);
    let knee = P_C * cmax;
    let e = hyab(hunt_lab(a), hunt_lab(b)).powf(Q_C);
    if e < knee {
        e * P_T / knee
    } else {
        P_T + (e - knee) / (cmax - knee) * (1.0 - P_T)
    }
}

/// Uniform pairs whose FLIP the definition gives ([`flip_of_uniform`]): black against white
/// (HyAB 100, above the knee: 0.967), red against green (chroma too: 0.987) and black against
/// the dark grey of sRGB byte 64 (below the knee: 0.58). Every pixel, the mean and the p99 are
/// that value. Colours are 8-bit exact (0, 64 and 255 after the sRGB encoding `compare`
/// applies), so FLIP sees exactly the colours the definition is evaluated at.
/// Tolerance 2e-4: FLIP runs in f32 (~1e-6 from its colour conversions), and its feature
/// filters' weights cancel on a uniform image only to f32 rounding (a residue r ~ 1e-7 in the
/// edge and point responses); FLIP raises the colour term c to 1 - sqrt(r / sqrt 2) ~
/// 1 - 3e-4, which moves it by c |ln c| 3e-4: at most 1e-4 here (0.58 |ln 0.58| 3e-4). A
/// wrong constant moves them by more: q_c = 0.71 instead of 0.7 by 4e-4, p_t = 0.96 by 7e-3.
#[test]
fn flip_of_uniform_colours_is_their_colour_difference_and_of_an_image_against_itself_zero() {
    // The linear value of sRGB byte 64 (the sRGB decoding FLIP applies to its 8-bit input).
    let grey = ((64.0 / 255.0 + 0.055) / 1.055f64).powf(2.4);
    for (a, b) in [
        ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
        ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, 0.0], [grey, grey, grey]),
    ] {
        let expected = flip_of_uniform(a, b);
        let uniform =
            |c: [f64; 3]| image(32, 32, |_, _| [c[0] as f32, c[1] as f32, c[2] as f32, 1.0]);
        let c = compare(&uniform(a), &uniform(b), None).unwrap();
        let worst = c
            .flip_map
            .iter()
            .map(|&v| (f64::from(v) - expected).abs())
            .fold(0.0, f64::max);
        assert!(
            worst < 2e-4,
            "{a:?} vs {b:?}: a pixel off by {worst}, expected {expected}"
        );
        for (name, v) in [("mean", c.flip_mean), ("p99", c.flip_p99)] {
            let v = v.unwrap();
            assert!(
                (v - expected).abs() < 2e-4,
                "{a:?} vs {b:?}: {name} {v}, expected {expected}"
            );
        }
    }
    let g = gradient(32, 32);
    assert!(flip_map(&g, &g).iter().all(|&v| v == 0.0));
}

#[test]
fn flip_p99_is_the_nearest_rank() {
    assert_eq!(percentile::rank(100, 0.99), Some(98));
    assert_eq!(percentile::rank(101, 0.99), Some(99));
    assert_eq!(percentile::rank(1, 0.99), Some(0));
    assert_eq!(percentile::rank(0, 0.99), None);
    // The reported p99 is the ceil(0.99 n)-th smallest FLIP value of the compared pixels.
    let (a, mut b) = (gradient(16, 16), gradient(16, 16));
    for (i, p) in b.pixels.iter_mut().enumerate() {
        p[0] += 0.001 * (i % 97) as f32;
    }
    let c = compare(&a, &b, None).unwrap();
    let mut flips: Vec<f32> = c.flip_map.clone();
    flips.sort_by(f32::total_cmp);
    let n = flips.len();
    let expected = f64::from(flips[(0.99 * n as f64).ceil() as usize - 1]);
    assert_eq!(c.flip_p99, Some(expected));
}

#[test]
fn a_size_mismatch_names_both_sizes() {
    let e = compare(&gradient(4, 2), &gradient(3, 2), None).unwrap_err();
    let text = e.to_string();
    assert!(text.contains("4x2") && text.contains("3x2"), "{text}");
    let mask = Mask::from_red(&gradient(4, 3));
    let text = compare(&gradient(4, 2), &gradient(4, 2), Some(&mask))
        .unwrap_err()
        .to_string();
    assert!(
        text.contains("4x2") && text.contains("4x3") && text.contains("mask"),
        "{text}"
    );
}

#[test]
fn files_are_named_in_errors() {
    let dir = temp_dir("files");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    crate::output::write_exr(&a, &gradient(4, 2)).unwrap();
    crate::output::write_exr(&b, &gradient(2, 2)).unwrap();
    let text = read_inputs(&a, &b, None).err().unwrap().to_string();
    assert!(text.contains("a.exr") && text.contains("b.exr"), "{text}");
    assert!(text.contains("4x2") && text.contains("2x2"), "{text}");

    let missing = dir.join("none.exr");
    let e = read_inputs(&a, &missing, None).err().unwrap();
    assert!(matches!(e, MetricsError::Missing { .. }));
    assert!(e.to_string().contains("none.exr"));

    let garbage = dir.join("garbage.exr");
    std::fs::write(&garbage, b"not an exr").unwrap();
    let e = read_exr(&garbage).unwrap_err();
    assert!(matches!(e, MetricsError::Read { .. }));
    assert!(e.to_string().contains("garbage.exr"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn masks_read_from_exr_and_png_agree() {
    let dir = temp_dir("masks");
    // Red 0, 0.25, 0.75, 1: the right two pixels are selected.
    let m = image(4, 1, |x, _| {
        [x as f32 / 4.0 + 0.25 * (x / 2) as f32, 1.0, 1.0, 1.0]
    });
    let exr = dir.join("m.exr");
    let png = dir.join("m.png");
    crate::output::write_exr(&exr, &m).unwrap();
    crate::output::write_png(&png, &m).unwrap();
    let from_exr = read_mask(&exr).unwrap();
    assert_eq!(from_exr.selected, [false, false, true, true]);
    // The PNG stores sRGB-encoded red, which is above half exactly where linear is above ~0.21;
    // the threshold applies to the stored value, so the 0.25 pixel is selected there.
    assert_eq!(read_mask(&png).unwrap().selected, [false, true, true, true]);
    // A mask that selects nothing is refused, naming the file, not compared as n/a.
    let black = dir.join("black.png");
    crate::output::write_png(&black, &image(4, 1, |_, _| [0.0, 1.0, 1.0, 1.0])).unwrap();
    let e = read_mask(&black)
        .unwrap()
        .check_selects(&black)
        .unwrap_err();
    assert!(matches!(e, MetricsError::EmptyMask { .. }), "{e}");
    assert!(
        e.to_string()
            .contains("black.png: the mask selects no pixel"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn colour_map_is_ordered_and_heatmap_has_the_image_size() {
    assert_eq!(colour_map(0.0), [0, 0, 4]);
    assert_eq!(colour_map(1.0), [252, 253, 191]);
    assert_eq!(colour_map(f32::NAN), colour_map(0.0));
    // Relative luminance of the sRGB bytes rises with the value.
    let luminance = |c: [u8; 3]| {
        let lin = |v: u8| {
            let v = f32::from(v) / 255.0;
            if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        };
        0.2126 * lin(c[0]) + 0.7152 * lin(c[1]) + 0.0722 * lin(c[2])
    };
    let mut last = -1.0;
    for i in 0..=64 {
        let c = colour_map(i as f32 / 64.0);
        assert_ne!(c, NOT_COMPARED_RGB8);
        let l = luminance(c);
        assert!(l > last, "luminance falls at {i}/64");
        last = l;
    }

    let dir = temp_dir("heatmap");
    let path = dir.join("flip.png");
    let c = compare(&gradient(5, 3), &gradient(5, 3), None).unwrap();
    write_heatmap(&path, &c).unwrap();
    let png = TextureData::from_png(&path).unwrap();
    assert_eq!((png.width, png.height), (5, 3));
    assert_eq!(&png.rgba8[..3], &[0, 0, 4]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A watch of reading: the rows said at `begin`, those decoded, and a stop after `stop_after`.
struct Reading {
    begun: std::sync::Mutex<Option<(u64, u32)>>,
    rows: std::sync::atomic::AtomicU64,
    stop_after: u64,
}

impl Reading {
    fn new(stop_after: u64) -> Self {
        Self {
            begun: std::sync::Mutex::new(None),
            rows: 0.into(),
            stop_after,
        }
    }

    fn rows(&self) -> u64 {
        self.rows.load(std::sync::atomic::Ordering::SeqCst)
    }
}

impl Watch for Reading {
    fn begin(&self, rows: u64, width: u32) {
        *self.begun.lock().unwrap() = Some((rows, width));
    }

    fn rows_done(&self, rows: u32) {
        (self.rows).fetch_add(u64::from(rows), std::sync::atomic::Ordering::SeqCst);
    }

    fn stop(&self) -> bool {
        self.rows() >= self.stop_after
    }
}

/// Reading says the rows it will decode (both images, and a mask), reports every one,
/// and stops at the watch's word with nothing read; a mask of another size is refused from
/// the headers, before any row is decoded.
#[test]
fn reading_is_reported_row_by_row_and_stopped_at_a_word() {
    let dir = temp_dir("reading");
    let (a, b, m) = (dir.join("a.exr"), dir.join("b.exr"), dir.join("m.exr"));
    crate::output::write_exr(&a, &gradient(64, 256)).unwrap();
    crate::output::write_exr(&b, &gradient(64, 256)).unwrap();
    crate::output::write_exr(&m, &image(64, 256, |_, _| [1.0; 4])).unwrap();
    let all = Reading::new(u64::MAX);
    let read = read_inputs_watched(&a, &b, Some(&m), &all).unwrap();
    assert_eq!(*all.begun.lock().unwrap(), Some((3 * 256, 64)));
    assert_eq!(all.rows(), 3 * 256);
    assert_eq!(read.test, gradient(64, 256));
    assert_eq!(
        read.mask.map(|m| m.selected.iter().filter(|&&s| s).count()),
        Some(64 * 256)
    );
    // A PNG mask's rows are counted too, once it is decoded (with the images, not before
    // the count begins).
    let png = dir.join("m.png");
    crate::output::write_png(&png, &image(64, 256, |_, _| [1.0; 4])).unwrap();
    let with_png = Reading::new(u64::MAX);
    read_inputs_watched(&a, &b, Some(&png), &with_png).unwrap();
    assert_eq!(*with_png.begun.lock().unwrap(), Some((3 * 256, 64)));
    assert_eq!(with_png.rows(), 3 * 256);
    // Stopped within the first image, after its first chunks of 16 rows.
    let stopped = Reading::new(32);
    let err = read_inputs_watched(&a, &b, None, &stopped).err().unwrap();
    assert!(matches!(err, MetricsError::Stopped), "{err}");
    assert!((32..256).contains(&stopped.rows()), "{}", stopped.rows());
    // Another size, found from the headers: nothing decoded, and the files named.
    // (A new file: what this process read, no output of it replaces.)
    let short = dir.join("short.exr");
    crate::output::write_exr(&short, &image(64, 255, |_, _| [1.0; 4])).unwrap();
    // Nor is any file read whole: their first bytes hold their headers.
    let early = Reading::new(u64::MAX);
    let (err, read_whole) = crate::files::digest::while_reading(|| {
        read_inputs_watched(&a, &b, Some(&short), &early)
            .err()
            .unwrap()
    });
    assert!(matches!(err, MetricsError::SizeMismatch { .. }), "{err}");
    assert!(err.to_string().contains("short.exr is 64x255"), "{err}");
    assert_eq!((early.rows(), *early.begun.lock().unwrap()), (0, None));
    assert_eq!(read_whole, []);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A header read from a file's first bytes gives the colour layer's size; one that reaches
/// past them gives none (the whole file is read for it), and bytes that are no EXR's are
/// refused from the first of them.
#[test]
fn a_size_is_read_from_the_first_bytes_where_they_hold_the_header() {
    let dir = temp_dir("heads");
    let a = dir.join("a.exr");
    crate::output::write_exr(&a, &gradient(64, 32)).unwrap();
    let bytes = std::fs::read(&a).unwrap();
    use super::read::size_from_head;
    assert_eq!(size_from_head(&a, &bytes, false).unwrap(), Some((64, 32)));
    assert_eq!(size_from_head(&a, &bytes[..40], true).unwrap(), None);
    let e = size_from_head(&a, b"P6 64 32", true).unwrap_err();
    assert!(e.to_string().contains("not an OpenEXR image"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
