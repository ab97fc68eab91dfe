//! Panoramas: the sensor image unwrapped onto a cylinder or a longitude–latitude grid, and the
//! same panoramas read straight from the cube map.
//!
//! Both kinds share the columns: column `j` (of `W`) is azimuth `(j + 0.5) / W * 360` degrees
//! (`optics` module: 0 along +X, 90 along +Z). Row `i` (of `H`, row 0 at the top) is, at its
//! centre,
//! - longitude–latitude: elevation `e_top - (i + 0.5) / H * (e_top - e_bottom)`, linear in
//!   the angle, over everything the mirror shows (`e_top` its highest elevation, for the
//!   sphere 90 degrees minus the rim angle; `e_bottom` its lowest: -90, or for a cone
//!   90 - 2 x its half-angle, what the rays beside its apex show);
//! - cylindrical: `tan(elevation) = tan(e_top) - (i + 0.5) / H * (tan(e_top) - tan(e_bottom))`,
//!   the projection onto a vertical cylinder around the axis, over
//!   [max(-45, lowest shown), min(45, highest shown)] degrees (a cone's band that lies wholly
//!   beyond 45 degrees: the band itself).
//!
//! Sizes: `W` is the disc's circumference in pixels rounded to a multiple of 4 (a column per
//! pixel at the rim), and `H` keeps the columns' angular scale (lon–lat: `W * (e_top -
//! e_bottom) / 360 degrees`; cylindrical: `W / (2 pi) * (tan e_top - tan e_bottom)`, the
//! cylinder of radius `W / (2 pi)`).
//!
//! From the sensor image, a panorama pixel takes the colour the image shows at the point
//! `SensorOptics::pixel_seeing` gives for its direction (bilinear). That direction is a ray's
//! direction, not a viewpoint: the mirror has none, and each column's rays leave different
//! points of the sphere. From the cube map, the same direction is looked up from the cube's
//! centre (bilinear within the face), as a central camera there would see (the mirror's
//! viewpoint, unless `cube.offset` moves the cube).

use std::f64::consts::{FRAC_PI_4, TAU};

use glam::{Vec2, Vec3};

use super::optics::{direction, SensorOptics};
use crate::image::RgbaImage;
use crate::scene::camera::CUBE_FACE_AXES;

/// Columns are capped here (a 16k-wide panorama is already finer than any sensor here).
const MAX_WIDTH: u32 = 16_384;

/// How rows map to elevation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PanoramaKind {
    Cylindrical,
    LonLat,
}

impl PanoramaKind {
    pub const ALL: [Self; 2] = [Self::Cylindrical, Self::LonLat];

    /// The name in file names: `sensor.panorama.NAME.exr`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Cylindrical => "cylindrical",
            Self::LonLat => "lonlat",
        }
    }
}

/// A panorama's size and the elevations of its top and bottom edges (radians).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PanoramaLayout {
    pub kind: PanoramaKind,
    pub width: u32,
    pub height: u32,
    pub top_elevation_rad: f64,
    pub bottom_elevation_rad: f64,
}

impl PanoramaLayout {
    /// The layout for the sensor `optics` (see the module documentation).
    pub fn for_sensor(optics: &SensorOptics, kind: PanoramaKind) -> Self {
        let rim = f64::from(optics.disc_radius_px());
        let width = ((TAU * rim / 4.0).round() as u32 * 4).clamp(4, MAX_WIDTH);
        let (top, lowest) = (optics.max_elevation(), optics.min_elevation());
        let (top, bottom) = match kind {
            PanoramaKind::LonLat => (top, lowest),
            PanoramaKind::Cylindrical => {
                let (high, low) = (top.min(FRAC_PI_4), lowest.max(-FRAC_PI_4));
                // A cone's band may lie wholly beyond 45 degrees: then the band itself.
                if high > low {
                    (high, low)
                } else {
                    (top, lowest)
                }
            }
        };
        let span = match kind {
            PanoramaKind::LonLat => (top - bottom) / TAU,
            PanoramaKind::Cylindrical => (top.tan() - bottom.tan()) / TAU,
        };
        Self {
            kind,
            width,
            height: ((f64::from(width) * span).round() as u32).max(1),
            top_elevation_rad: top,
            bottom_elevation_rad: bottom,
        }
    }

    /// Azimuth (radians) at horizontal position `x` (pixels; a column's centre at `j + 0.5`).
    pub fn azimuth(&self, x: f64) -> f64 {
        x / f64::from(self.width) * TAU
    }

    /// The column (fractional pixels) of azimuth `azimuth`; inverse of [`Self::azimuth`].
    pub fn column(&self, azimuth: f64) -> f64 {
        azimuth.rem_euclid(TAU) / TAU * f64::from(self.width)
    }

    /// Elevation (radians) at vertical position `y` (pixels from the top edge).
    pub fn elevation(&self, y: f64) -> f64 {
        let f = y / f64::from(self.height);
        let (top, bottom) = (self.top_elevation_rad, self.bottom_elevation_rad);
        match self.kind {
            PanoramaKind::LonLat => top - f * (top - bottom),
            PanoramaKind::Cylindrical => (top.tan() - f * (top.tan() - bottom.tan())).atan(),
        }
    }

    /// The row (fractional pixels from the top) of elevation `elevation`.
    pub fn row(&self, elevation: f64) -> f64 {
        let (top, bottom) = (self.top_elevation_rad, self.bottom_elevation_rad);
        let f = match self.kind {
            PanoramaKind::LonLat => (top - elevation) / (top - bottom),
            PanoramaKind::Cylindrical => (top.tan() - elevation.tan()) / (top.tan() - bottom.tan()),
        };
        f * f64::from(self.height)
    }

    /// Elevation and azimuth of pixel (j, i)'s centre.
    fn pixel_angles(&self, j: u32, i: u32) -> (f64, f64) {
        (
            self.elevation(f64::from(i) + 0.5),
            self.azimuth(f64::from(j) + 0.5),
        )
    }

    /// A panorama whose pixel colours come from `colour(row, elevation, azimuth)`.
    fn fill(&self, colour: impl Fn(u32, f64, f64) -> [f32; 4] + Sync) -> RgbaImage {
        use rayon::prelude::*;
        let pixels = (0..self.height)
            .into_par_iter()
            .flat_map_iter(|i| {
                let colour = &colour;
                (0..self.width).map(move |j| {
                    let (e, a) = self.pixel_angles(j, i);
                    colour(i, e, a)
                })
            })
            .collect();
        RgbaImage {
            width: self.width,
            height: self.height,
            pixels,
        }
    }

    /// The sensor image `image` unwrapped (see the module documentation); a direction the
    /// mirror does not show is black with alpha 0.
    pub fn unwrap(&self, optics: &SensorOptics, image: &RgbaImage) -> RgbaImage {
        // A row is one elevation, so the camera-ray angle that sees it (a bisection) is found
        // once per row, not once per pixel: it was most of the localisation sweep's time.
        let thetas: Vec<Option<f64>> = (0..self.height)
            .map(|i| optics.theta_for_elevation(self.elevation(f64::from(i) + 0.5)))
            .collect();
        self.fill(
            |i, _, a| match thetas[i as usize].and_then(|theta| optics.pixel_at(theta, a)) {
                Some(p) => bilinear(image, p),
                None => [0.0; 4],
            },
        )
    }

    /// The same panorama looked up in the cube map `faces` (layer order +X, -X, +Y, -Y, +Z,
    /// -Z, Vulkan's face orientation) from its centre.
    pub fn from_cube(&self, faces: &[RgbaImage]) -> RgbaImage {
        self.fill(|_, e, a| sample_cube(faces, direction(e, a)))
    }
}

/// Bilinear sample of `image` at `p` (pixels; centres at +0.5), edges clamped.
pub fn bilinear(image: &RgbaImage, p: Vec2) -> [f32; 4] {
    let (w, h) = (image.width as i64, image.height as i64);
    let q = p - Vec2::splat(0.5);
    let (x0, y0) = (q.x.floor(), q.y.floor());
    let (fx, fy) = (q.x - x0, q.y - y0);
    let at = |x: i64, y: i64| image.pixel(x.clamp(0, w - 1) as u32, y.clamp(0, h - 1) as u32);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let (a, b, c, d) = (
        at(x0, y0),
        at(x0 + 1, y0),
        at(x0, y0 + 1),
        at(x0 + 1, y0 + 1),
    );
    std::array::from_fn(|k| {
        let top = a[k] + fx * (b[k] - a[k]);
        let bottom = c[k] + fx * (d[k] - c[k]);
        top + fy * (bottom - top)
    })
}

/// The cube map's colour in direction `d`: the face of the largest component, its (s, t) by
/// Vulkan's face table ([`CUBE_FACE_AXES`]), bilinear within that face.
pub fn sample_cube(faces: &[RgbaImage], d: Vec3) -> [f32; 4] {
    let (face, (major, s_axis, t_axis)) = CUBE_FACE_AXES
        .iter()
        .enumerate()
        .max_by(|(_, a), (_, b)| d.dot(a.0).total_cmp(&d.dot(b.0)))
        .expect("six faces");
    let m = d.dot(*major);
    let st = Vec2::new(d.dot(*s_axis), d.dot(*t_axis)) / m;
    let img = &faces[face];
    let size = Vec2::new(img.width as f32, img.height as f32);
    bilinear(img, (st + Vec2::ONE) * 0.5 * size)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cones whose band lies wholly above or below 45 degrees (half-angles 20 and 80: from
    /// 50 degrees up, and from -70 to -48): both panoramas span the band, every row of them
    /// inside it, so every row shows something.
    #[test]
    fn a_cones_band_beyond_45_degrees_is_the_cylinders_span() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let path = root.join("scenes/test/six-colour-room.toml");
        let text = std::fs::read_to_string(&path).unwrap();
        for alpha in [20, 80] {
            let cone = format!("shape = \"cone\"\nhalf_angle = {alpha}\nrim_radius = 1");
            let text = text.replace("radius = 1.0", &cone);
            let scene = crate::scene::load_str(&text, &path).unwrap();
            let optics = SensorOptics::at(&scene, 0.0);
            let (low, high) = (optics.min_elevation(), optics.max_elevation());
            assert!(
                low > FRAC_PI_4 || high < -FRAC_PI_4,
                "α {alpha}: the band is beyond 45"
            );
            for kind in PanoramaKind::ALL {
                let l = PanoramaLayout::for_sensor(&optics, kind);
                assert!(l.height > 1, "α {alpha}, {kind:?}: {l:?}");
                for row in 0..l.height {
                    let e = l.elevation(f64::from(row) + 0.5);
                    assert!(
                        (low..=high).contains(&e) && optics.theta_for_elevation(e).is_some(),
                        "α {alpha}, {kind:?}: row {row} at {} degrees",
                        e.to_degrees()
                    );
                }
            }
        }
    }

    /// A cube whose faces are each one flat colour returns that colour in the direction of
    /// the face's centre (the orientation comes from the face table, checked elsewhere).
    #[test]
    fn cube_sampling_picks_the_face_of_the_largest_component() {
        let faces: Vec<RgbaImage> = (0..6)
            .map(|f| RgbaImage {
                width: 4,
                height: 4,
                pixels: vec![[f as f32, 0.0, 0.0, 1.0]; 16],
            })
            .collect();
        for (f, (major, _, _)) in CUBE_FACE_AXES.iter().enumerate() {
            let d = (*major + 0.3 * Vec3::ONE.cross(*major)).normalize();
            assert_eq!(sample_cube(&faces, d)[0], f as f32);
        }
    }

    /// Rows and columns invert to the angles they were made from, for both kinds.
    #[test]
    fn rows_and_columns_round_trip() {
        for kind in PanoramaKind::ALL {
            let l = PanoramaLayout {
                kind,
                width: 720,
                height: 200,
                top_elevation_rad: 0.7,
                bottom_elevation_rad: -0.6,
            };
            for y in [0.0, 13.5, 100.0, 199.5] {
                assert!((l.row(l.elevation(y)) - y).abs() < 1e-9, "{kind:?} {y}");
            }
            assert!((l.elevation(0.0) - 0.7).abs() < 1e-12);
            assert!((l.elevation(200.0) + 0.6).abs() < 1e-12);
            assert!((l.column(std::f64::consts::FRAC_PI_2) - 180.0).abs() < 1e-9);
            assert!((l.azimuth(l.column(5.0)) - 5.0).abs() < 1e-9);
        }
    }
}
