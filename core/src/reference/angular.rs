//! The mirror's angular lookup error: per mirror pixel, the angle between the direction the
//! rasterizer looked up in the cube map and the exact direction from the cube's centre to the
//! surface the reflected ray really meets.

use glam::Vec3;
use serde::Serialize;

use crate::image::RgbaImage;

/// Summary of the angular error over the pixels both images mark as mirror pixels.
#[derive(Debug, Clone, Copy, Default, Serialize, serde::Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AngularError {
    /// Pixels compared (mirror pixels in both images).
    pub pixels: usize,
    pub mean_deg: f64,
    pub p99_deg: f64,
    pub max_deg: f64,
    /// The same in texels of a cube face of `face_size_px`: one texel spans 90 / face_size
    /// degrees at a face's centre (it is smaller towards the edges, so this is conservative).
    pub face_size_px: u32,
    pub mean_texels: f64,
    pub p99_texels: f64,
    pub max_texels: f64,
}

/// Angles (degrees) between two direction images, over the pixels where both alphas are 1
/// and `keep(x, y)` holds.
pub fn angles_deg(
    raster: &RgbaImage,
    exact: &RgbaImage,
    keep: impl Fn(u32, u32) -> bool,
) -> Vec<f64> {
    let w = raster.width;
    raster
        .pixels
        .iter()
        .zip(&exact.pixels)
        .enumerate()
        .filter(|(i, (a, b))| a[3] == 1.0 && b[3] == 1.0 && keep(*i as u32 % w, *i as u32 / w))
        .map(|(_, (a, b))| {
            let (a, b) = (
                Vec3::new(a[0], a[1], a[2]).as_dvec3(),
                Vec3::new(b[0], b[1], b[2]).as_dvec3(),
            );
            // atan2 of |a x b| and a . b stays accurate for tiny angles (acos does not).
            a.cross(b).length().atan2(a.dot(b)).to_degrees()
        })
        .collect()
}

/// Mean, 99th percentile (nearest rank, `metrics::percentile`) and maximum of `angles`.
pub fn summarize(mut angles: Vec<f64>, face_size_px: u32) -> AngularError {
    if angles.is_empty() {
        return AngularError {
            face_size_px,
            ..Default::default()
        };
    }
    angles.sort_by(f64::total_cmp);
    let n = angles.len();
    let mean = angles.iter().sum::<f64>() / n as f64;
    let p99 = crate::metrics::percentile::of_sorted(&angles, 0.99).unwrap_or(0.0);
    let max = angles[n - 1];
    let texel = 90.0 / f64::from(face_size_px.max(1));
    AngularError {
        pixels: n,
        mean_deg: mean,
        p99_deg: p99,
        max_deg: max,
        face_size_px,
        mean_texels: mean / texel,
        p99_texels: p99 / texel,
        max_texels: max / texel,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_angles() {
        let img = |d: [f32; 3]| RgbaImage {
            width: 1,
            height: 1,
            pixels: vec![[d[0], d[1], d[2], 1.0]],
        };
        let a = angles_deg(&img([1.0, 0.0, 0.0]), &img([0.0, 1.0, 0.0]), |_, _| true);
        assert!((a[0] - 90.0).abs() < 1e-9);
        let s = 1e-4f32.to_radians();
        let a = angles_deg(
            &img([1.0, 0.0, 0.0]),
            &img([s.cos(), s.sin(), 0.0]),
            |_, _| true,
        );
        assert!(
            (a[0] - 1e-4).abs() < 1e-6,
            "tiny angles stay accurate: {}",
            a[0]
        );
        let e = summarize(vec![0.0, 1.0, 2.0], 90);
        assert_eq!((e.pixels, e.max_deg, e.max_texels), (3, 2.0, 2.0));
        assert!((e.mean_deg - 1.0).abs() < 1e-12);
        // p99 by nearest rank: the ceil(0.99 n)-th smallest, here ceil(59.4) = the 60th of
        // 1..=60 (a rounded (n - 1) p would give the 59th).
        let e = summarize((1..=60).rev().map(f64::from).collect(), 90);
        assert_eq!(e.p99_deg, 60.0);
    }
}
