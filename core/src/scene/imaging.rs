//! `[sensor.imaging]`: the sensor camera's imaging chain as the scene file sets it, from the
//! light on a pixel to the number the camera reports. `crate::sensor::imaging` applies it;
//! docs/sensor.md says what each number does.
//!
//! The defaults are a machine-vision camera on a Sony IMX249 (5.86 µm global-shutter pixels,
//! a 12-bit ADC), as Matrix Vision's mvBlueFOX3-2024a table gives it measured to EMVA 1288:
//! a maximum SNR of 45.1 dB and a dynamic range of 73 dB. A shot-noise-limited pixel's best
//! SNR is √(full well), so the full well is 10^(45.1 / 10) = 32,359 e⁻, and the read noise
//! is that over 10^(73 / 20): 7.24 e⁻. The table gives no dark current; 1.5 e⁻/s is what an
//! IMX249 camera was measured at by its user at 20 °C, and is small beside the read noise at
//! any exposure a robot uses. The system gain maps the full well to the ADC's top code.

/// The full well of the default camera (e⁻): 10^(45.1 / 10).
pub const IMX249_FULL_WELL_E: f32 = 32_359.0;
/// Its read noise (e⁻ rms): the full well over 10^(73 / 20).
pub const IMX249_READ_NOISE_E: f32 = 7.24;
/// Its dark current (e⁻/s at 20 °C).
pub const IMX249_DARK_CURRENT_E_PER_S: f32 = 1.5;
/// Its ADC's bits.
pub const IMX249_BIT_DEPTH: u32 = 12;
/// The default black level (DN): the code of no light, above zero by four times the default
/// camera's dark noise (7.24 e⁻ × 4095 / 32,359 = 0.92 DN), so that the read noise's
/// negative half is kept rather than clipped at code 0, as a machine-vision camera's black
/// level (offset) setting is for; a dark frame's mean is then this plus the dark charge.
pub const DEFAULT_BLACK_LEVEL_DN: f32 = 4.0;
/// The default exposure time (s): 10 ms, short enough that a robot moving at 1 m/s moves
/// 1 cm in it.
pub const DEFAULT_EXPOSURE_S: f32 = 0.01;
/// Photo-electrons per second a pixel collects from a rendered linear value of 1 (the
/// renderer's light is in relative units; this sets the absolute scale): with the default
/// exposure a value of 1 fills 93 % of the full well, so a white wall under the default
/// light is bright without clipping.
pub const DEFAULT_UNIT_FLUX_E_PER_S: f32 = 3.0e6;

/// How the camera maps its linear signal (0 dark, 1 the ADC's top code) to the code it
/// reports, before quantisation.
#[derive(Debug, Clone, PartialEq)]
pub enum Response {
    /// The code is proportional to the collected charge (a machine-vision camera's raw mode).
    Linear,
    /// The sRGB transfer curve (IEC 61966-2-1).
    Srgb,
    /// `x^(1 / gamma)`.
    Gamma(f32),
    /// Output values at evenly spaced inputs 0..=1, interpolated linearly (a measured curve);
    /// at least two, each in [0, 1], never decreasing.
    Table(Vec<f32>),
}

impl Response {
    /// The name the scene file uses.
    pub fn name(&self) -> &'static str {
        match self {
            Response::Linear => "linear",
            Response::Srgb => "srgb",
            Response::Gamma(_) => "gamma",
            Response::Table(_) => "table",
        }
    }
}

/// The imaging chain of the sensor camera: exposure, noise, quantisation, response, lens.
#[derive(Debug, Clone, PartialEq)]
pub struct Imaging {
    /// Exposure time (s).
    pub exposure_s: f32,
    /// Analogue gain (dB) on top of `system_gain_dn_per_e`.
    pub gain_db: f32,
    /// Photo-electrons per second from a rendered linear value of 1.
    pub unit_flux_e_per_s: f32,
    /// Saturation capacity (e⁻): the charge is clipped here.
    pub full_well_e: f32,
    /// Temporal dark noise (e⁻ rms), Gaussian.
    pub read_noise_e: f32,
    /// Dark current (e⁻/s): its charge adds to the signal, with its own shot noise.
    pub dark_current_e_per_s: f32,
    /// Digital numbers per electron at 0 dB (EMVA 1288's K).
    pub system_gain_dn_per_e: f32,
    /// The ADC's bits (8 to 16).
    pub bit_depth: u32,
    /// The code of no light (DN), below the top code.
    pub black_level_dn: f32,
    pub response: Response,
    /// How much of the lens's natural cos⁴ fall-off the image shows: 0 none, 1 all of it.
    pub vignetting: f32,
    /// The lens's blur: a Gaussian's standard deviation in pixels (0: none).
    pub blur_px: f32,
    /// Every random draw of a frame comes from this and the frame's number.
    pub seed: u64,
    /// Instants the exposure is integrated over, evenly spread across it and centred on the
    /// frame's time: the robot's motion along its trajectory and the scene's animations blur
    /// the camera image. 1: the image of the frame's instant alone (no motion blur).
    pub motion_blur_samples: u32,
    /// A rolling shutter's readout (s): the last row's exposure starts this much after the
    /// first's; 0, a global shutter (the IMX249's), every row exposed at once.
    pub rolling_shutter_s: f32,
    /// Photo-response non-uniformity: the standard deviation of the pixels' sensitivities
    /// about their mean, percent (EMVA 1288's PRNU); a fixed pattern of the camera.
    pub prnu_percent: f32,
    /// Dark-signal non-uniformity: the standard deviation of the pixels' dark offsets (e⁻,
    /// EMVA 1288's DSNU); a fixed pattern of the camera.
    pub dsnu_e: f32,
}

impl Default for Imaging {
    /// The IMX249 camera of the module's notes, linear, with no lens blur (a lens is not in a
    /// sensor's datasheet), natural vignetting, seed 0, no motion blur (each instant
    /// integrated costs a render) and uniform pixels (the table gives no PRNU or DSNU).
    fn default() -> Self {
        let top = ((1u32 << IMX249_BIT_DEPTH) - 1) as f32;
        Self {
            exposure_s: DEFAULT_EXPOSURE_S,
            gain_db: 0.0,
            unit_flux_e_per_s: DEFAULT_UNIT_FLUX_E_PER_S,
            full_well_e: IMX249_FULL_WELL_E,
            read_noise_e: IMX249_READ_NOISE_E,
            dark_current_e_per_s: IMX249_DARK_CURRENT_E_PER_S,
            system_gain_dn_per_e: top / IMX249_FULL_WELL_E,
            bit_depth: IMX249_BIT_DEPTH,
            black_level_dn: DEFAULT_BLACK_LEVEL_DN,
            response: Response::Linear,
            vignetting: 1.0,
            blur_px: 0.0,
            seed: 0,
            motion_blur_samples: 1,
            rolling_shutter_s: 0.0,
            prnu_percent: 0.0,
            dsnu_e: 0.0,
        }
    }
}
