//! One sample's way from its mean charge to its code (EMVA 1288's linear camera, then the
//! response curve): shot noise on the photo and dark charge, the well's capacity, read noise,
//! the gain, the black level and the ADC. The transcendental functions are `libm`'s, written
//! in Rust, so that a seed gives the same codes whatever maths library the machine has.

use super::draw;
use super::{Imaging, Response};
use crate::random::SplitMix64;

/// The charge a pixel's mean is capped at before its shot noise is drawn (e⁻): a hundred
/// times the largest full well the loader accepts, so a capped pixel saturates whatever it
/// draws, and an unbounded rendered value (an HDR highlight) costs no more than any other.
const MEAN_CAP_E: f64 = 1e9;

/// The chain's constants, worked out once.
pub(super) struct Chain<'a> {
    dark_e: f64,
    read_noise_e: f64,
    full_well_e: f64,
    /// Digital numbers per electron, the analogue gain included.
    gain: f64,
    black: f64,
    top: f64,
    response: &'a Response,
}

impl<'a> Chain<'a> {
    pub(super) fn new(i: &'a Imaging) -> Self {
        Self {
            dark_e: f64::from(i.dark_current_e_per_s) * f64::from(i.exposure_s),
            read_noise_e: f64::from(i.read_noise_e),
            full_well_e: f64::from(i.full_well_e),
            gain: f64::from(i.system_gain_dn_per_e) * libm::pow(10.0, f64::from(i.gain_db) / 20.0),
            black: f64::from(i.black_level_dn),
            top: f64::from((1u32 << i.bit_depth) - 1),
            response: &i.response,
        }
    }

    /// One sample: the photo and dark charge drawn (shot noise) and held to the well, the
    /// read noise added (it may take the signal below zero, which the black level keeps in
    /// range), times the gain; then the response over the codes above the black level, the
    /// black level, and the nearest code the ADC has.
    /// `pixel` is the pixel's own sensitivity and dark offset (e⁻): its fixed pattern.
    pub(super) fn digitise(&self, rng: &mut SplitMix64, photo_e: f64, pixel: Pixel) -> u16 {
        let mean = (photo_e * pixel.sensitivity + self.dark_e).min(MEAN_CAP_E);
        let charge = draw::poisson(rng, mean).min(self.full_well_e) + pixel.dark_offset_e;
        let signal = (charge + self.read_noise_e * draw::normal(rng)) * self.gain;
        let span = self.top - self.black;
        let code = match self.response {
            // The signal as it is, negative noise included.
            Response::Linear => self.black + signal,
            curve => self.black + span * respond(curve, (signal / span).clamp(0.0, 1.0)),
        };
        code.round().clamp(0.0, self.top) as u16
    }
}

/// A pixel's fixed pattern: its sensitivity relative to the mean pixel's and its dark offset.
#[derive(Debug, Clone, Copy)]
pub(super) struct Pixel {
    pub sensitivity: f64,
    pub dark_offset_e: f64,
}

impl Pixel {
    pub const UNIFORM: Pixel = Pixel {
        sensitivity: 1.0,
        dark_offset_e: 0.0,
    };

    /// A pixel of a camera whose sensitivities spread by `prnu` (a fraction) and dark offsets
    /// by `dsnu_e` (e⁻), both normal, drawn from `rng` (never below no sensitivity).
    pub fn drawn(rng: &mut SplitMix64, prnu: f64, dsnu_e: f64) -> Pixel {
        Pixel {
            sensitivity: (1.0 + prnu * draw::normal(rng)).max(0.0),
            dark_offset_e: dsnu_e * draw::normal(rng),
        }
    }
}

/// The response curve at `x` in [0, 1].
pub(super) fn respond(response: &Response, x: f64) -> f64 {
    match response {
        Response::Linear => x,
        // IEC 61966-2-1.
        Response::Srgb if x <= 0.003_130_8 => 12.92 * x,
        Response::Srgb => 1.055 * libm::pow(x, 1.0 / 2.4) - 0.055,
        Response::Gamma(g) => libm::pow(x, 1.0 / f64::from(*g)),
        Response::Table(t) => {
            let at = x * (t.len() - 1) as f64;
            let i = (at.floor() as usize).min(t.len() - 2);
            let f = at - i as f64;
            f64::from(t[i]) * (1.0 - f) + f64::from(t[i + 1]) * f
        }
    }
}
