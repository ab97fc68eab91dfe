//! The sensor camera's image as a real camera reports it: the clean rendered image (linear,
//! relative units) through a lens (blur, vignetting) onto a pixel that collects charge with
//! shot noise, adds dark current and read noise, saturates at its full well, and is digitised
//! through a response curve at the ADC's bit depth (EMVA 1288's linear camera model, per
//! colour channel: a three-chip camera, no mosaic). The scene's `[sensor.imaging]` sets the
//! numbers ([`Imaging`]); the ground-truth layers stay clean.
//!
//! Every draw of a frame comes from the seed and the frame's number, one stream per row, so a
//! frame is the same bytes on any machine and with any number of threads.

use rayon::prelude::*;
use serde::Serialize;

use super::optics::SensorOptics;
use crate::image::RgbaImage;
use crate::random::SplitMix64;
use crate::reference::Reference;
pub use crate::scene::imaging::{Imaging, Response};
use crate::scene::Scene;
use crate::watch::{Stopped, Watch};
pub use exposure::{integrate, Schedule};

mod chain;
pub mod draw;
mod exposure;
mod lens;
#[cfg(test)]
mod tests;

/// The camera image's file: RGB PNG, 8-bit for a bit depth of 8, 16-bit above, each code
/// shifted to the top of its sample (`sBIT` says how many bits are significant).
pub const CAMERA_IMAGE_FILE: &str = "sensor.camera.png";

/// A frame's image as the camera reports it: digital numbers, RGB, rows top to bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraImage {
    pub width: u32,
    pub height: u32,
    /// 3 per pixel, each in 0..2^bit_depth.
    pub dn: Vec<u16>,
    /// The chain that made it.
    pub imaging: Imaging,
    /// The frame number its draws came from (with the seed).
    pub frame: u64,
}

/// What `camera.json` says of the camera image: its file, the chain's numbers and the draws.
#[derive(Debug, Clone, Serialize)]
pub struct ImagingRecord {
    pub file: &'static str,
    /// How a sample of the file becomes the camera's code.
    pub code: String,
    pub exposure_s: f32,
    pub gain_db: f32,
    pub unit_flux_e_per_s: f32,
    pub full_well_e: f32,
    pub read_noise_e: f32,
    pub dark_current_e_per_s: f32,
    pub system_gain_dn_per_e: f32,
    pub bit_depth: u32,
    pub black_level_dn: f32,
    pub response: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gamma: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub response_table: Option<Vec<f32>>,
    pub vignetting: f32,
    pub blur_px: f32,
    pub seed: u64,
    pub motion_blur_samples: u32,
    pub rolling_shutter_s: f32,
    pub prnu_percent: f32,
    pub dsnu_e: f32,
    pub frame: u64,
}

impl CameraImage {
    /// The PNG's samples: each code shifted to the top of its 8- or 16-bit sample.
    pub fn samples(&self) -> (Vec<u8>, u8) {
        let (sample_bits, shift) = match self.imaging.bit_depth {
            8 => (8, 0),
            b => (16, 16 - b),
        };
        let bytes = match sample_bits {
            8 => self.dn.iter().map(|&d| d as u8).collect(),
            _ => (self.dn.iter())
                .flat_map(|&d| (d << shift).to_be_bytes())
                .collect(),
        };
        (bytes, sample_bits)
    }

    /// The image as [`CAMERA_IMAGE_FILE`]'s PNG.
    pub fn png(&self) -> Result<Vec<u8>, crate::image::png::EncodingError> {
        let (samples, bits) = self.samples();
        let mut bytes = Vec::new();
        let size = (self.width, self.height);
        let depth = (bits, self.imaging.bit_depth as u8);
        crate::image::png::encode_rgb_samples(&mut bytes, size, &samples, depth)?;
        Ok(bytes)
    }

    pub fn record(&self) -> ImagingRecord {
        let imaging = &self.imaging;
        let shift = match imaging.bit_depth {
            8 => 0,
            b => 16 - b,
        };
        ImagingRecord {
            file: CAMERA_IMAGE_FILE,
            code: match shift {
                0 => "the sample itself".into(),
                s => format!("the 16-bit sample shifted right by {s} bits"),
            },
            exposure_s: imaging.exposure_s,
            gain_db: imaging.gain_db,
            unit_flux_e_per_s: imaging.unit_flux_e_per_s,
            full_well_e: imaging.full_well_e,
            read_noise_e: imaging.read_noise_e,
            dark_current_e_per_s: imaging.dark_current_e_per_s,
            system_gain_dn_per_e: imaging.system_gain_dn_per_e,
            bit_depth: imaging.bit_depth,
            black_level_dn: imaging.black_level_dn,
            response: imaging.response.name(),
            gamma: match imaging.response {
                Response::Gamma(g) => Some(g),
                _ => None,
            },
            response_table: match &imaging.response {
                Response::Table(t) => Some(t.clone()),
                _ => None,
            },
            vignetting: imaging.vignetting,
            blur_px: imaging.blur_px,
            seed: imaging.seed,
            motion_blur_samples: imaging.motion_blur_samples,
            rolling_shutter_s: imaging.rolling_shutter_s,
            prnu_percent: imaging.prnu_percent,
            dsnu_e: imaging.dsnu_e,
            frame: self.frame,
        }
    }
}

/// The clean linear `image` of a sensor with `optics`, exposed, as frame `frame` reports it.
pub fn expose(
    imaging: &Imaging,
    image: &RgbaImage,
    optics: &SensorOptics,
    frame: u64,
) -> CameraImage {
    let light = lens::light(imaging, image);
    let fall_off = lens::fall_off(optics, f64::from(imaging.vignetting));
    let w = image.width as usize;
    let chain = chain::Chain::new(imaging);
    let (prnu, dsnu) = (
        f64::from(imaging.prnu_percent) / 100.0,
        f64::from(imaging.dsnu_e),
    );
    let mut dn = vec![0u16; light.len()];
    (dn.par_chunks_mut(w * 3).enumerate()).for_each(|(y, row)| {
        let mut rng = row_stream(imaging.seed, frame, y as u64);
        // The camera's fixed pattern: the same for every frame, drawn only where it has one.
        let mut pattern = pattern_stream(imaging.seed, y as u64);
        let uniform = prnu == 0.0 && dsnu == 0.0;
        let light = &light[y * w * 3..(y + 1) * w * 3];
        let means = lens::mean_electrons(imaging, &fall_off, y, light);
        for (out, mean) in row.iter_mut().zip(means) {
            let pixel = match uniform {
                true => chain::Pixel::UNIFORM,
                false => chain::Pixel::drawn(&mut pattern, prnu, dsnu),
            };
            *out = chain.digitise(&mut rng, mean, pixel);
        }
    });
    CameraImage {
        width: image.width,
        height: image.height,
        dn,
        imaging: imaging.clone(),
        frame,
    }
}

/// How many renders of the sensor's view a frame's exposure takes beyond the frame's own: its
/// [`Schedule`]'s instants, or 0 for an exposure of one instant or no imaging chain.
pub fn exposure_renders(scene: &Scene) -> usize {
    (scene.sensor.imaging.as_ref())
        .map(|imaging| Schedule::of(imaging, 0.0).instants())
        .filter(|&n| n >= 2)
        .unwrap_or(0)
}

/// The light of the sensor camera's whole exposure at `t_s` from the exact reference: the
/// scene traced at each instant of its [`Schedule`], `spp` samples a pixel, `w`x`h`, every
/// row reported to `watch` (which may stop it); None for an exposure of one instant or a
/// scene without an imaging chain.
pub fn traced_exposure(
    scene: &Scene,
    t_s: f64,
    spp: u32,
    [w, h]: [u32; 2],
    watch: &dyn Watch,
) -> Result<Option<RgbaImage>, Stopped> {
    let Some(imaging) = scene.sensor.imaging.as_ref() else {
        return Ok(None);
    };
    // The meshes' trees are the same at every instant (only the objects' places move):
    // built once, not once an instant.
    let meshes = std::sync::Arc::new(crate::reference::objects::MeshTrees::build(&scene.meshes));
    integrate(imaging, t_s, |t| {
        let reference = Reference::with_meshes(scene, t, meshes.clone());
        let (images, _) = reference.render_watched(&reference.sensor_view(), w, h, spp, watch)?;
        Ok(images.color)
    })
}

/// Row `row`'s stream of the camera's fixed pattern (PRNU, DSNU): of the seed, not of a frame
/// (the salt keeps it apart from every frame's stream).
fn pattern_stream(seed: u64, row: u64) -> SplitMix64 {
    const SALT: u64 = 0x5EED_F1CE_D0FF_5E75;
    let h = SplitMix64::new(SplitMix64::new(seed ^ SALT).next_u64() ^ row).next_u64();
    SplitMix64::new(h)
}

/// Row `row`'s random stream of frame `frame`: the three numbers hashed in turn, so no two
/// (seed, frame, row) share a stream start.
fn row_stream(seed: u64, frame: u64, row: u64) -> SplitMix64 {
    let mut h = SplitMix64::new(seed).next_u64();
    h = SplitMix64::new(h ^ frame).next_u64();
    h = SplitMix64::new(h ^ row).next_u64();
    SplitMix64::new(h)
}
