//! The central approximation of the sensor, exported: the single-viewpoint models robotics
//! tools calibrate (Mei's unified model for OpenCV `omnidir` and Kalibr `omni`, Scaramuzza's
//! polynomial for OCamCalib), fitted to the exact, non-central ray map, each with its residual
//! per pixel: the angle between the model's ray and the ray the pixel really sees, which is
//! the price of pretending a spherical mirror has one viewpoint.
//!
//! **Frames.** The models' rays live in the sensor camera's frame (its axes from the sensor
//! pose: `right`, `down` and `forward`, the last pointing at the mirror), with the origin at
//! one fitted viewpoint. A mirror reverses handedness, and a calibration tool fits positive
//! focal lengths with the image centre on its +z (omnidir) or -z (OCamCalib) axis, so each
//! model's axes are those of the image and the frame is left-handed, as any calibration of a
//! one-mirror camera from real images would give (its planar targets hide the reflection):
//! - omnidir / Kalibr: x = right (image columns), y = down (rows), z = -forward;
//! - OCamCalib: x = down (rows), y = right (columns), z = forward.
//!
//! **Viewpoint.** The point nearest to all the pixels' rays in the least-squares sense (a
//! point on the sensor's axis inside the sphere); the residual angles do not depend on it,
//! only the pixels of points at a finite distance do (parallax).

pub mod export;
pub mod folder;
pub mod mei;
pub mod parts;
pub mod record;
pub mod ros;
pub mod scaramuzza;

use glam::{DVec2, DVec3};

pub use mei::MeiModel;
pub use parts::{Part, Unwatched, Watch};
pub use scaramuzza::OcamModel;

use super::RayMap;
use crate::metrics::percentile::percentile;
use crate::scene::camera::ViewBasis;
use crate::scene::state::SceneState;
use crate::scene::Scene;
use crate::sensor::solve::{self, LmReport};

/// One pixel's observation for a fit: its image point in the model's own pixel convention and
/// the unit direction it sees, in the model's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub pixel: DVec2,
    pub direction: DVec3,
}

/// Why a central model could not be fitted.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error("only {} the mirror; a central model needs at least 9 ({SEEN_BY})", pixels_seeing(*.0))]
    TooFewPixels(usize),
    #[error("no starting point for the fit: {0} ({SEEN_BY})")]
    NoStart(&'static str),
    #[error("the fitted polynomial's elevation does not grow with the radius, so it has no inverse (invpol); the models expect the mirror's image about its axis ({SEEN_BY})")]
    NotMonotonic,
    #[error("no invpol of degree up to {0} could be fitted (every basis was singular)")]
    Invpol(usize),
    #[error("the pixels' rays have no single nearest point (they are all parallel)")]
    NoViewpoint,
    #[error("the {shape} mirror shows nothing straight down its axis: the rays beside its apex leave at {lowest_deg:.1} degrees elevation, so its image has no centre ray, which every central model (Mei's, Scaramuzza's) is built about; calibrate a mirror that is smooth on its axis (sphere, hyperboloid, paraboloid)")]
    NoAxisRay {
        shape: &'static str,
        lowest_deg: f64,
    },
    #[error("stopped before {0}")]
    Stopped(&'static str),
}

/// What decides the pixels a fit sees, for a fit that fails on too few or too odd of them.
const SEEN_BY: &str = "what the fit sees is set by sensor.resolution and sensor.fov_y (a wide \
                       field of view leaves the mirror few pixels), and by sensor.tilt and \
                       sensor.shift, which turn or move the sensor off the mirror's axis";

/// "N pixels see", "1 pixel sees".
fn pixels_seeing(n: usize) -> String {
    match n {
        1 => "1 pixel sees".to_owned(),
        n => format!("{n} pixels see"),
    }
}

/// The sensor camera's axes in world space (unit, right-handed: right x down = forward).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorAxes {
    pub right: DVec3,
    pub down: DVec3,
    pub forward: DVec3,
}

impl SensorAxes {
    pub fn of_view(view: &ViewBasis) -> Self {
        Self {
            right: view.right.as_dvec3().normalize(),
            down: view.down.as_dvec3().normalize(),
            forward: view.forward.as_dvec3().normalize(),
        }
    }

    /// Rows of the world-to-omnidir rotation (a reflection: determinant -1).
    pub fn omnidir_rows(&self) -> [DVec3; 3] {
        [self.right, self.down, -self.forward]
    }

    /// Rows of the world-to-OCamCalib rotation (a reflection: determinant -1).
    pub fn ocamcalib_rows(&self) -> [DVec3; 3] {
        [self.down, self.right, self.forward]
    }
}

/// A world vector in the frame whose axes are `rows`.
pub fn to_frame(rows: &[DVec3; 3], v: DVec3) -> DVec3 {
    DVec3::new(rows[0].dot(v), rows[1].dot(v), rows[2].dot(v))
}

/// A per-pixel angle (degrees) and its summary.
#[derive(Debug, Clone, PartialEq)]
pub struct Residual {
    /// Per pixel, rows top to bottom; None off the mirror, NaN where the model has no ray for
    /// a mirror pixel (beyond the horizon of a model with xi > 1).
    pub degrees: Vec<Option<f64>>,
    /// Over the mirror pixels where the model has a ray.
    pub stats: record::Summary,
    /// Mirror pixels where the model has no ray.
    pub without_ray: usize,
}

impl Residual {
    fn new(degrees: Vec<Option<f64>>) -> Self {
        let all = degrees.iter().flatten().count();
        let mut values: Vec<f64> = degrees
            .iter()
            .flatten()
            .copied()
            .filter(|d| !d.is_nan())
            .collect();
        let without_ray = all - values.len();
        let mean = values.iter().sum::<f64>() / values.len().max(1) as f64;
        let p99 = percentile(&mut values, 0.99).unwrap_or(0.0);
        let max = values.last().copied().unwrap_or(0.0);
        Self {
            degrees,
            stats: record::Summary { mean, p99, max },
            without_ray,
        }
    }
}

/// The fitted central models of one sensor at one time.
#[derive(Debug, Clone)]
pub struct Calibration {
    pub width: u32,
    pub height: u32,
    pub axes: SensorAxes,
    /// World position of the scene's local origin (the ray map is in local coordinates:
    /// world = origin + local).
    pub origin: DVec3,
    /// The single viewpoint, local coordinates (metres).
    pub viewpoint: DVec3,
    /// Distance of each ray from the viewpoint (metres): how far from central the sensor is.
    pub ray_distance_m: record::Summary,
    pub mei: MeiModel,
    pub mei_fit: LmReport,
    pub mei_residual: Residual,
    pub ocam: OcamModel,
    pub ocam_fit: LmReport,
    /// How far `ocam.invpol` is from the exact inverse of its polynomial at worst (pixels):
    /// below OCamCalib's 0.01 px unless no degree up to 30 reaches it.
    pub ocam_invpol_error_px: f64,
    pub ocam_residual: Residual,
    pub mirror_pixels: usize,
    /// The fits took every `fit_stride`-th row and column ([`fit_stride`]): `fit_pixels`
    /// mirror pixels.
    pub fit_stride: u32,
    pub fit_pixels: usize,
}

/// The most sensor pixels a calibration takes (4096², 7.5 s and 1.3 GB here): the central
/// models need no more.
pub const MAX_CALIBRATION_PIXELS: u64 = 4096 * 4096;

impl Calibration {
    /// Why the scene's sensor is too large to calibrate (a sentence naming the field), if
    /// it is.
    pub fn too_large(scene: &Scene) -> Option<String> {
        let [w, h] = scene.sensor.resolution;
        (u64::from(w) * u64::from(h) > MAX_CALIBRATION_PIXELS).then(|| {
            format!(
                "sensor.resolution {w}x{h} is more than the {MAX_CALIBRATION_PIXELS} pixels \
                 (4096x4096) a calibration fits; the models do not need more"
            )
        })
    }

    /// Fits both models to the exact ray map of the scene's sensor at time `t_s`.
    pub fn of_scene(scene: &Scene, t_s: f64) -> Result<(Self, RayMap), FitError> {
        Self::of_scene_watched(scene, t_s, &Unwatched)
    }

    /// [`Self::of_scene`], each part said to `watch`, which can stop it between parts.
    pub fn of_scene_watched(
        scene: &Scene,
        t_s: f64,
        watch: &dyn Watch,
    ) -> Result<(Self, RayMap), FitError> {
        let lowest = crate::sensor::SensorOptics::at(scene, t_s).min_elevation();
        if lowest > -std::f64::consts::FRAC_PI_2 {
            return Err(FitError::NoAxisRay {
                shape: scene.mirror.shape.name(),
                lowest_deg: lowest.to_degrees(),
            });
        }
        let map = RayMap::exact(scene, t_s);
        let state = SceneState::at(scene, t_s);
        let view = state.sensor_view(scene, map.width as f32 / map.height as f32);
        let axes = SensorAxes::of_view(&view);
        let parts = Parts(watch);
        parts.done(Part::Rays, "finding the viewpoint")?;
        let stride = fit_stride(map.mirror_pixels());
        let mut calibration = Self::fit_strided(&map, axes, stride, &parts)?;
        calibration.origin = scene.origin;
        Ok((calibration, map))
    }

    /// Fits both models to `map`, whose sensor has the axes `axes` (local origin at the world's).
    pub fn fit(map: &RayMap, axes: SensorAxes) -> Result<Self, FitError> {
        Self::fit_strided(
            map,
            axes,
            fit_stride(map.mirror_pixels()),
            &Parts(&Unwatched),
        )
    }

    /// [`Self::fit`] on every `stride`-th row and column of the mirror pixels.
    fn fit_strided(
        map: &RayMap,
        axes: SensorAxes,
        stride: u32,
        parts: &Parts,
    ) -> Result<Self, FitError> {
        // Before the viewpoint's fit, which would call too few rays "parallel".
        if map.mirror_pixels() < 9 {
            return Err(FitError::TooFewPixels(map.mirror_pixels()));
        }
        let (viewpoint, ray_distance_m) = nearest_point(map)?;
        parts.done(Part::Viewpoint, "fitting the omnidir model")?;
        // Pixel centres: OpenCV's (x, y) and OCamCalib's (row, col) are both 0-based there.
        let pixels = mirror_pixels(map, stride);
        let mei_samples: Vec<Sample> = pixels
            .iter()
            .map(|&(px, d)| Sample {
                pixel: px,
                direction: to_frame(&axes.omnidir_rows(), d),
            })
            .collect();
        let ocam_samples: Vec<Sample> = pixels
            .iter()
            .map(|&(px, d)| Sample {
                pixel: DVec2::new(px.y, px.x),
                direction: to_frame(&axes.ocamcalib_rows(), d),
            })
            .collect();
        let (mei, mei_fit) = MeiModel::fit(&mei_samples, map.width, map.height)?;
        parts.done(Part::Omnidir, "fitting the OCamCalib model")?;
        // The largest radius of every mirror pixel, not only of the fit's samples.
        let rho_max = |m: &OcamModel| {
            use rayon::prelude::*;
            (0..map.height)
                .into_par_iter()
                .flat_map_iter(|y| (0..map.width).map(move |x| (x, y)))
                .filter(|&(x, y)| map.get(x, y).is_some())
                .map(|(x, y)| m.radius_of(DVec2::new(f64::from(y), f64::from(x))))
                .reduce(|| 0.0, f64::max)
        };
        let (ocam, ocam_fit, ocam_invpol_error_px) =
            OcamModel::fit(&ocam_samples, map.width, map.height, rho_max)?;
        parts.done(Part::Ocamcalib, "computing the residuals")?;
        let mei_residual = residual(map, |px, d| {
            let ray = mei.unproject(px)?;
            Some(angle_deg(ray, to_frame(&axes.omnidir_rows(), d)))
        });
        let ocam_residual = residual(map, |px, d| {
            let ray = ocam.cam2world(DVec2::new(px.y, px.x));
            Some(angle_deg(ray, to_frame(&axes.ocamcalib_rows(), d)))
        });
        parts.done(Part::Residuals, "writing the files")?;
        Ok(Self {
            width: map.width,
            height: map.height,
            axes,
            origin: DVec3::ZERO,
            viewpoint,
            ray_distance_m,
            mei,
            mei_fit,
            mei_residual,
            ocam,
            ocam_fit,
            ocam_invpol_error_px,
            ocam_residual,
            mirror_pixels: map.mirror_pixels(),
            fit_stride: stride,
            fit_pixels: pixels.len(),
        })
    }

    /// Points along the exact rays of every `stride`-th mirror pixel (in rows and columns), at
    /// each of `distances_m` from the mirror, with the pixels both models predict for them:
    /// what an external tool must reproduce from the exported files.
    pub fn check_points(
        &self,
        map: &RayMap,
        stride: u32,
        distances_m: &[f64],
    ) -> Vec<record::CheckPoint> {
        let mut points = Vec::new();
        for y in (stride / 2..map.height).step_by(stride as usize) {
            for x in (stride / 2..map.width).step_by(stride as usize) {
                let Some(ray) = map.get(x, y) else { continue };
                for &distance_m in distances_m {
                    let local = ray.origin.as_dvec3() + ray.direction.as_dvec3() * distance_m;
                    let rel = local - self.viewpoint;
                    let omnidir_point = to_frame(&self.axes.omnidir_rows(), rel);
                    let ocamcalib_point = to_frame(&self.axes.ocamcalib_rows(), rel);
                    points.push(record::CheckPoint {
                        pixel: [x, y],
                        distance_m,
                        world: (self.origin + local).to_array(),
                        omnidir_point: omnidir_point.to_array(),
                        omnidir_pixel: self.mei.project(omnidir_point).map(|p| p.to_array()),
                        ocamcalib_point: ocamcalib_point.to_array(),
                        ocamcalib_row_col: self.ocam.world2cam(ocamcalib_point).to_array(),
                    });
                }
            }
        }
        points
    }
}

/// A watch as the fit uses it: a part done, then a stop before the next one said.
struct Parts<'w>(&'w dyn Watch);

impl Parts<'_> {
    /// `part` said done; stopped (`Stopped(next)`) if the watch says so.
    fn done(&self, part: Part, next: &'static str) -> Result<(), FitError> {
        self.0.part_done(part);
        match self.0.stop() {
            true => Err(FitError::Stopped(next)),
            false => Ok(()),
        }
    }
}

/// The most mirror pixels a model is fitted to (those of a 512² sensor): nine parameters of
/// smooth models are pinned down long before that, and every pixel of a 2048² sensor took the
/// two fits most of a minute. Beyond it the fits take every `stride`-th row and column
/// ([`fit_stride`]); the residuals are still every pixel's.
pub const MAX_FIT_PIXELS: usize = 512 * 512;

/// The stride in rows and columns that keeps `mirror_pixels` within [`MAX_FIT_PIXELS`].
pub fn fit_stride(mirror_pixels: usize) -> u32 {
    let mut stride = 1u32;
    while mirror_pixels.div_ceil((stride * stride) as usize) > MAX_FIT_PIXELS {
        stride += 1;
    }
    stride
}

/// The centre (0-based, OpenCV's convention) and exact direction (world) of each mirror pixel
/// in every `stride`-th row and column.
fn mirror_pixels(map: &RayMap, stride: u32) -> Vec<(DVec2, DVec3)> {
    (0..map.height)
        .step_by(stride as usize)
        .flat_map(|y| (0..map.width).step_by(stride as usize).map(move |x| (x, y)))
        .filter_map(|(x, y)| {
            let ray = map.get(x, y)?;
            Some((
                DVec2::new(x as f64, y as f64),
                ray.direction.as_dvec3().normalize(),
            ))
        })
        .collect()
}

/// The residual of a model whose ray for pixel (OpenCV coordinates) and exact world
/// direction `angle` gives, in degrees (None: the model has no ray there).
fn residual(map: &RayMap, angle: impl Fn(DVec2, DVec3) -> Option<f64> + Sync) -> Residual {
    use rayon::prelude::*;
    let degrees = (0..map.height)
        .into_par_iter()
        .flat_map_iter(|y| (0..map.width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let ray = map.get(x, y)?;
            let px = DVec2::new(x as f64, y as f64);
            Some(angle(px, ray.direction.as_dvec3().normalize()).unwrap_or(f64::NAN))
        })
        .collect();
    Residual::new(degrees)
}

/// The angle between two unit vectors in degrees, accurate for small angles too (atan2 of
/// the cross and dot products, where acos would lose half the digits near 0).
pub fn angle_deg(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b)).to_degrees()
}

/// The point nearest to all the rays (least squares of the perpendicular distances), and the
/// rays' distances from it.
fn nearest_point(map: &RayMap) -> Result<(DVec3, record::Summary), FitError> {
    let rays: Vec<(DVec3, DVec3)> = map
        .rays
        .iter()
        .flatten()
        .map(|r| (r.origin.as_dvec3(), r.direction.as_dvec3().normalize()))
        .collect();
    // Sum over rays of (I - d d^T) c = sum of (I - d d^T) o.
    let mut m = [0.0; 9];
    let mut v = [0.0; 3];
    for (o, d) in &rays {
        let (da, oa) = (d.to_array(), o.to_array());
        for i in 0..3 {
            for j in 0..3 {
                let p = f64::from(i == j) - da[i] * da[j];
                m[i * 3 + j] += p;
                v[i] += p * oa[j];
            }
        }
    }
    let c = solve::solve_square(&m, &v).ok_or(FitError::NoViewpoint)?;
    let c = DVec3::from_slice(&c);
    let mut distances: Vec<f64> = rays
        .iter()
        .map(|(o, d)| (c - *o).cross(*d).length())
        .collect();
    let residual = Residual::new(distances.drain(..).map(Some).collect());
    Ok((c, residual.stats))
}

#[cfg(test)]
mod stride_tests;
#[cfg(test)]
mod tests;
