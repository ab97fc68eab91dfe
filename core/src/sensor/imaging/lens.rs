//! What the lens does before the pixel counts: a Gaussian blur (the lens's spread of a point)
//! and natural vignetting, the cos⁴ fall-off of light reaching the image plane at angle θ
//! from the axis (the obliquity of the pupil and the pixel, and the distance; a telecentric,
//! orthographic camera has none). Then the exposure turns light into mean photo-charge.

use rayon::prelude::*;

use super::Imaging;
use crate::image::RgbaImage;
use crate::sensor::optics::SensorOptics;

/// The light on the sensor (RGB, rows top to bottom): the linear image blurred by the lens.
/// A negative or NaN value is no light; an infinite one is capped by the chain. In f32, as the
/// image is: three samples a pixel, so that a large sensor's camera image costs little memory.
pub fn light(imaging: &Imaging, image: &RgbaImage) -> Vec<f32> {
    let (w, h) = (image.width as usize, image.height as usize);
    let no_nan = |v: f32| if v.is_nan() { 0.0 } else { v.max(0.0) };
    let linear: Vec<f32> = (image.pixels.iter())
        .flat_map(|p| [no_nan(p[0]), no_nan(p[1]), no_nan(p[2])])
        .collect();
    blur(linear, (w, h), f64::from(imaging.blur_px))
}

/// Row `y`'s mean photo-electrons per sample, from its `light`: vignetted, times the flux and
/// the exposure.
pub fn mean_electrons<'a>(
    imaging: &Imaging,
    fall_off: &impl Fn(usize, usize) -> f64,
    y: usize,
    light: &'a [f32],
) -> impl Iterator<Item = f64> + 'a {
    let scale = f64::from(imaging.unit_flux_e_per_s) * f64::from(imaging.exposure_s);
    let fall_off: Vec<f64> = (0..light.len() / 3).map(|x| fall_off(x, y)).collect();
    (light.iter().enumerate()).map(move |(i, v)| f64::from(*v) * scale * fall_off[i / 3])
}

/// The share of light pixel (x, y) keeps: 1 - s (1 - cos⁴θ), θ the angle of its centre's
/// ray from the axis of a pinhole camera; 1 everywhere for an orthographic one.
pub fn fall_off(optics: &SensorOptics, strength: f64) -> impl Fn(usize, usize) -> f64 + '_ {
    let v = &optics.view;
    let (w, h) = (f64::from(optics.width), f64::from(optics.height));
    let pinhole = !v.is_orthographic();
    move |x, y| {
        if !pinhole || strength == 0.0 {
            return 1.0;
        }
        let u = ((x as f64 + 0.5) / w * 2.0 - 1.0) * f64::from(v.tan_x);
        let t = ((y as f64 + 0.5) / h * 2.0 - 1.0) * f64::from(v.tan_y);
        let cos2 = 1.0 / (1.0 + u * u + t * t);
        1.0 - strength * (1.0 - cos2 * cos2)
    }
}

/// A separable Gaussian of standard deviation `sigma` pixels over 3 interleaved channels,
/// reaching 3σ, the edge pixels repeated beyond the image (a flat field stays flat to the
/// border; a bright pixel within 3σ of it counts more than once, as if the scene went on
/// beyond the image as its edge shows it); `sigma` 0 leaves the image as it is.
pub fn blur(v: Vec<f32>, (w, h): (usize, usize), sigma: f64) -> Vec<f32> {
    if sigma <= 0.0 || v.is_empty() {
        return v;
    }
    let kernel = gaussian(sigma);
    let r = (kernel.len() / 2) as isize;
    // One output row at a time, on every core: each sample is the same sum in the same order
    // however the rows are shared out.
    let pass = |src: Vec<f32>, along_x: bool| -> Vec<f32> {
        let mut out = vec![0.0; src.len()];
        out.par_chunks_mut(w * 3).enumerate().for_each(|(y, row)| {
            for x in 0..w {
                for c in 0..3 {
                    let mut sum = 0.0;
                    for (k, weight) in kernel.iter().enumerate() {
                        let d = k as isize - r;
                        let (sx, sy) = match along_x {
                            true => ((x as isize + d).clamp(0, w as isize - 1) as usize, y),
                            false => (x, (y as isize + d).clamp(0, h as isize - 1) as usize),
                        };
                        sum += weight * f64::from(src[(sy * w + sx) * 3 + c]);
                    }
                    row[x * 3 + c] = sum as f32;
                }
            }
        });
        out
    };
    pass(pass(v, true), false)
}

/// The normalised Gaussian's weights at -⌈3σ⌉..=⌈3σ⌉.
fn gaussian(sigma: f64) -> Vec<f64> {
    let r = (3.0 * sigma).ceil() as isize;
    let raw: Vec<f64> = (-r..=r)
        .map(|d| libm::exp(-(d * d) as f64 / (2.0 * sigma * sigma)))
        .collect();
    let total: f64 = raw.iter().sum();
    raw.iter().map(|w| w / total).collect()
}
