//! Panoramas: the sensor image unwrapped onto a cylinder or a longitude–latitude grid, and the
//! same panoramas read straight from the cube map.
//!
//! Both kinds share the columns: column `j` (of `W`) is azimuth `seam + (j + 0.5) / W * 360`
//! degrees (`optics` module: 0 along the scene's +X, 90 along +Z), where `seam`, the azimuth
//! of the left edge, is 0 in the scene's frame and, in a robot's own frame ([`PanoramaFrame`]),
//! the azimuth its forward axis points along: its panoramas turn with it, as a real robot's
//! do, and say nothing of its heading. Row `i` (of `H`, row 0 at the top) is, at its
//! centre,
//! - longitude–latitude: elevation `e_top - (i + 0.5) / H * (e_top - e_bottom)`, linear in
//!   the angle, over everything the mirror shows (`e_top` its highest elevation, for the
//!   sphere 90 degrees minus the rim angle; `e_bottom` its lowest: -90, or for a cone
//!   90 - 2 x its half-angle, what the rays beside its apex show);
//! - cylindrical: `tan(elevation) = tan(e_top) - (i + 0.5) / H * (tan(e_top) - tan(e_bottom))`,
//!   the projection onto a vertical cylinder around the axis, over
//!   [max(-45, lowest shown), min(45, highest shown)] degrees; a band that lies wholly beyond
//!   45 degrees (a cone's; a paraboloid's or hyperboloid's whose rim is seen more than 45
//!   degrees below the horizon) gives its part nearest the horizon whose tangents span 2, as
//!   the ±45-degree band's do (the band itself, reaching the nadir, has no finite cylinder).
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

/// Whose frame a panorama's columns are in: where its seam (the left edge) points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PanoramaFrame {
    /// The robot's: its forward axis (the scene's +X turned by its heading) at the seam, the
    /// azimuth growing as the scene's does (towards its right). What a robot that does not
    /// know its heading unwraps; what `localise` matches.
    Robot,
    /// The scene's: azimuth 0 (+X) at the seam whatever the heading. It needs the true
    /// heading to make, which a real robot does not have.
    World,
}

impl PanoramaFrame {
    pub const ALL: [Self; 2] = [Self::Robot, Self::World];

    pub fn name(self) -> &'static str {
        match self {
            Self::Robot => "robot",
            Self::World => "world",
        }
    }

    /// The seam's azimuth (radians, in [0, 2 pi)) for a robot at `heading_rad` (counter-
    /// clockwise about +Y seen from above, 0 facing +X): its forward axis is at azimuth
    /// `-heading`, since azimuth grows from +X towards +Z, clockwise seen from above.
    pub fn seam(self, heading_rad: f64) -> f64 {
        match self {
            // Not `-heading`: heading 0 would make the seam -0, written "-0.0".
            Self::Robot => (TAU - heading_rad.rem_euclid(TAU)).rem_euclid(TAU),
            Self::World => 0.0,
        }
    }
}

impl std::str::FromStr for PanoramaFrame {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        (Self::ALL.into_iter())
            .find(|f| f.name() == s)
            .ok_or_else(|| format!("`{s}` is not a panorama frame: robot or world"))
    }
}

/// A panorama's size, the elevations of its top and bottom edges and the azimuth of its left
/// edge (radians).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PanoramaLayout {
    pub kind: PanoramaKind,
    pub width: u32,
    pub height: u32,
    pub top_elevation_rad: f64,
    pub bottom_elevation_rad: f64,
    /// The scene azimuth of the left edge (see the module documentation).
    pub seam_azimuth_rad: f64,
}

impl PanoramaLayout {
    /// The layout for the sensor `optics` (see the module documentation).
    pub fn for_sensor(optics: &SensorOptics, kind: PanoramaKind) -> Self {
        let rim = f64::from(optics.disc_radius_px());
        let width = ((TAU * rim / 4.0).round() as u32 * 4).clamp(4, MAX_WIDTH);
        let (top, lowest) = (optics.max_elevation(), optics.min_elevation());
        let (top, bottom) = match kind {
            PanoramaKind::LonLat => (top, lowest),
            PanoramaKind::Cylindrical => cylinder_band(top, lowest),
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
            seam_azimuth_rad: 0.0,
        }
    }

    /// The same layout with its left edge at azimuth `seam` (radians).
    pub fn with_seam(self, seam: f64) -> Self {
        Self {
            seam_azimuth_rad: seam,
            ..self
        }
    }

    /// Azimuth (radians) at horizontal position `x` (pixels; a column's centre at `j + 0.5`).
    pub fn azimuth(&self, x: f64) -> f64 {
        self.seam_azimuth_rad + x / f64::from(self.width) * TAU
    }

    /// The column (fractional pixels) of azimuth `azimuth`; inverse of [`Self::azimuth`].
    pub fn column(&self, azimuth: f64) -> f64 {
        (azimuth - self.seam_azimuth_rad).rem_euclid(TAU) / TAU * f64::from(self.width)
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
    pub fn pixel_angles(&self, j: u32, i: u32) -> (f64, f64) {
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
    /// mirror does not show is black with alpha 0. Only the image's mirror pixels are
    /// interpolated: at the rim a bilinear tap falls beside the mirror, on the camera's direct
    /// view of the room, which mixed into the top row colours up to 14 degrees away.
    pub fn unwrap(&self, optics: &SensorOptics, image: &RgbaImage) -> RgbaImage {
        self.unwrap_within(optics, image, &mirror_mask(optics, image))
    }

    /// [`Self::unwrap`] with the image's [`mirror_mask`] made already (every panorama of one
    /// image shares it: at 4096² it is 16 M pixels to decide).
    pub fn unwrap_within(
        &self,
        optics: &SensorOptics,
        image: &RgbaImage,
        mirror: &[bool],
    ) -> RgbaImage {
        // A row is one elevation, so the camera-ray angle that sees it (a bisection) is found
        // once per row, not once per pixel: it was most of the localisation sweep's time.
        let thetas: Vec<Option<f64>> = (0..self.height)
            .map(|i| optics.theta_for_elevation(self.elevation(f64::from(i) + 0.5)))
            .collect();
        self.fill(
            |i, _, a| match thetas[i as usize].and_then(|theta| optics.pixel_at(theta, a)) {
                Some(p) => bilinear_within(image, p, mirror),
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

/// Per pixel of `image` (the sensor's), whether it shows the mirror: the pixels a panorama's
/// taps may read. Rows in parallel.
pub fn mirror_mask(optics: &SensorOptics, image: &RgbaImage) -> Vec<bool> {
    use rayon::prelude::*;
    (0..image.height)
        .into_par_iter()
        .flat_map_iter(|y| {
            let centre = move |x: u32| Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            (0..image.width).map(move |x| optics.shows_mirror(centre(x)))
        })
        .collect()
}

/// The elevations (top, bottom) the cylindrical panorama spans, of the band [`lowest`, `top`]
/// the mirror shows: its part within 45 degrees of the horizon; where the band lies wholly
/// beyond (a cone's, or a paraboloid's or hyperboloid's whose rim is seen more than 45 degrees
/// below the horizon), its part nearest the horizon whose tangents span 2, as the ±45-degree
/// band's do. A cylinder reaches the poles only at infinity, so the band itself would have
/// made a panorama of unbounded height (the nadir's tangent: 10¹⁶ rows): the height is at
/// most the cylinder's diameter, `W / pi`, either way.
fn cylinder_band(top: f64, lowest: f64) -> (f64, f64) {
    let (high, low) = (top.min(FRAC_PI_4), lowest.max(-FRAC_PI_4));
    if high > low {
        (high, low)
    } else if top <= 0.0 {
        // Wholly below the horizon's ±45° band (its top at -45° exactly included).
        (top, (top.tan() - 2.0).atan().max(lowest))
    } else {
        ((lowest.tan() + 2.0).atan().min(top), lowest)
    }
}

/// Bilinear sample of `image` at `p` over the pixels `keep` selects (`keep[y * width + x]`),
/// their weights renormalised; black with alpha 0 where none of the four is kept. Where all
/// four are, exactly [`bilinear`]'s value.
fn bilinear_within(image: &RgbaImage, p: Vec2, keep: &[bool]) -> [f32; 4] {
    let (w, h) = (image.width as i64, image.height as i64);
    let q = p - Vec2::splat(0.5);
    let (x0, y0) = (q.x.floor(), q.y.floor());
    let (fx, fy) = (q.x - x0, q.y - y0);
    let at = |x: i64, y: i64| (x.clamp(0, w - 1) as u32, y.clamp(0, h - 1) as u32);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let taps = [
        (at(x0, y0), (1.0 - fx) * (1.0 - fy)),
        (at(x0 + 1, y0), fx * (1.0 - fy)),
        (at(x0, y0 + 1), (1.0 - fx) * fy),
        (at(x0 + 1, y0 + 1), fx * fy),
    ];
    let kept = |(x, y): (u32, u32)| keep[(y * image.width + x) as usize];
    if taps.iter().all(|&(xy, _)| kept(xy)) {
        return bilinear(image, p);
    }
    let total: f32 = taps.iter().filter(|&&(xy, _)| kept(xy)).map(|t| t.1).sum();
    if total <= 0.0 {
        return [0.0; 4];
    }
    let mut sum = [0.0f32; 4];
    for &((x, y), weight) in taps.iter().filter(|&&(xy, _)| kept(xy)) {
        let c = image.pixel(x, y);
        for k in 0..4 {
            sum[k] += weight / total * c[k];
        }
    }
    sum
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

    /// Paraboloids whose rim is seen from just above 45 degrees below the horizon to nearly
    /// straight down (rims 0.21 to 0.001 m at p = 0.25 m: −44.4 to −89.8 degrees; the band
    /// reaches the nadir, whose tangent is infinite): the cylindrical panorama is at most the
    /// cylinder's diameter tall (the lon–lat one at most half its width), every row inside the
    /// band, and the unwrap runs (at −53 degrees it asked for 64 GiB and aborted).
    #[test]
    fn a_band_reaching_the_nadir_keeps_the_cylinder_bounded() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let path = root.join("scenes/test/six-colour-room.toml");
        let text = std::fs::read_to_string(&path).unwrap();
        for rim in ["0.21", "0.15", "0.05", "0.001"] {
            let shape = format!("shape = \"paraboloid\"\nlatus_rectum = 1\nrim_radius = {rim}");
            let scene = crate::scene::load_str(&text.replace("radius = 1.0", &shape), &path);
            let optics = SensorOptics::at(&scene.unwrap(), 0.0);
            let (low, high) = (optics.min_elevation(), optics.max_elevation());
            for kind in PanoramaKind::ALL {
                let l = PanoramaLayout::for_sensor(&optics, kind);
                let top = l.elevation(0.5).to_degrees();
                eprintln!(
                    "rim {rim}: {kind:?} {}x{}, top row {top:.1}",
                    l.width, l.height
                );
                let tallest = match kind {
                    PanoramaKind::Cylindrical => f64::from(l.width) / std::f64::consts::PI,
                    PanoramaKind::LonLat => f64::from(l.width) / 2.0,
                };
                assert!(
                    f64::from(l.height) <= tallest + 1.0,
                    "rim {rim}, {kind:?}: {l:?}"
                );
                for row in [0, l.height / 2, l.height - 1] {
                    let e = l.elevation(f64::from(row) + 0.5);
                    assert!((low..=high).contains(&e), "rim {rim}, {kind:?}: row {row}");
                }
                let image = RgbaImage {
                    width: 64,
                    height: 64,
                    pixels: vec![[1.0; 4]; 64 * 64],
                };
                let unwrapped = l.unwrap(&optics, &image);
                assert_eq!(unwrapped.pixels.len() as u32, l.width * l.height);
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

    /// Rows and columns invert to the angles they were made from, for both kinds and any
    /// seam: a quarter turn past the seam is a quarter of the columns.
    #[test]
    fn rows_and_columns_round_trip() {
        for (kind, seam) in PanoramaKind::ALL
            .into_iter()
            .flat_map(|k| [(k, 0.0), (k, 5.5)])
        {
            let l = PanoramaLayout {
                kind,
                width: 720,
                height: 200,
                top_elevation_rad: 0.7,
                bottom_elevation_rad: -0.6,
                seam_azimuth_rad: seam,
            };
            for y in [0.0, 13.5, 100.0, 199.5] {
                assert!((l.row(l.elevation(y)) - y).abs() < 1e-9, "{kind:?} {y}");
            }
            assert!((l.elevation(0.0) - 0.7).abs() < 1e-12);
            assert!((l.elevation(200.0) + 0.6).abs() < 1e-12);
            let quarter = l.column(seam + std::f64::consts::FRAC_PI_2);
            assert!((quarter - 180.0).abs() < 1e-9, "{kind:?} {seam}: {quarter}");
            let a = l.azimuth(l.column(5.0));
            assert!((a - 5.0).rem_euclid(TAU).min((5.0 - a).rem_euclid(TAU)) < 1e-9);
        }
    }

    /// A robot's seam is its forward axis: the scene's +X turned by its heading
    /// (counter-clockwise about +Y seen from above) has azimuth `-heading`; the world's is 0.
    #[test]
    fn a_robots_seam_is_its_forward_axis() {
        for deg in [0.0, 30.0, 90.0, -120.0, 400.0] {
            let heading = f64::to_radians(deg);
            let forward = glam::DMat3::from_rotation_y(heading) * glam::DVec3::X;
            let azimuth = forward.z.atan2(forward.x).rem_euclid(TAU);
            let seam = PanoramaFrame::Robot.seam(heading);
            let off = (seam - azimuth).rem_euclid(TAU);
            assert!(
                off.min(TAU - off) < 1e-12,
                "{deg}: seam {seam}, forward {azimuth}"
            );
            assert_eq!(PanoramaFrame::World.seam(heading), 0.0);
        }
        // Facing +X, the seam is +0, not -0 (the records write the sign).
        assert!(PanoramaFrame::Robot.seam(0.0).is_sign_positive());
    }
}
