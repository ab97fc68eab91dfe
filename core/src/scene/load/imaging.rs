//! `[sensor.imaging]`: the camera's imaging chain, each number in its unit and range, the
//! default camera's value where the file gives none (`crate::scene::imaging`).

use super::numbers::Range;
use super::{Ctx, R};
use crate::scene::format::ImagingSpec;
use crate::scene::imaging::{Imaging, Response};

/// The longest exposure (s): a robot's camera exposes for milliseconds; 10 s bounds the
/// charge a pixel collects (and the work of drawing its shot noise).
const EXPOSURE_S: Range = Range::above(0.0, 10.0);
/// Analogue gain (dB): machine-vision cameras offer 0 to about 48 dB.
const GAIN_DB: Range = Range::closed(0.0, 48.0);
const UNIT_FLUX: Range = Range::above(0.0, 1e12);
const FULL_WELL_E: Range = Range::closed(1.0, 1e7);
const READ_NOISE_E: Range = Range::closed(0.0, 1e4);
const DARK_CURRENT: Range = Range::closed(0.0, 1e6);
const SYSTEM_GAIN: Range = Range::above(0.0, 1e4);
const GAMMA: Range = Range::closed(0.1, 10.0);
/// Non-uniformities: a PRNU of 50 % is a broken sensor; a DSNU of 10⁴ e⁻ one as bad.
const PRNU_PERCENT: Range = Range::closed(0.0, 50.0);
const DSNU_E: Range = Range::closed(0.0, 1e4);
const UNIT: Range = Range::closed(0.0, 1.0);
/// The lens blur's standard deviation (px): its kernel reaches 3σ, at most 60 pixels.
const BLUR_PX: Range = Range::closed(0.0, 20.0);
/// The most instants an exposure is integrated over: each is a render of the sensor's view.
const MOTION_SAMPLES: u32 = 64;
/// A rolling shutter's readout (s): a CMOS sensor reads out in milliseconds; 1 s bounds it.
const READOUT_S: Range = Range::closed(0.0, 1.0);
/// The most instants a frame's rows see in all, a rolling shutter's included.
const MAX_INSTANTS: u32 = 1024;
/// The ADC's bits: 8 (one byte per sample) to 16 (two).
const BIT_DEPTH: std::ops::RangeInclusive<i64> = 8..=16;
/// A measured response curve's points.
const TABLE_POINTS: std::ops::RangeInclusive<usize> = 2..=4096;

impl Ctx<'_> {
    pub(super) fn imaging(&self, s: &ImagingSpec) -> R<Imaging> {
        let d = Imaging::default();
        let f = |name: &str, v: Option<f64>, default: f32, range: Range| match v {
            Some(v) => self.ranged(&format!("sensor.imaging.{name}"), v, range),
            None => Ok(default),
        };
        Ok(Imaging {
            exposure_s: f("exposure_s", s.exposure_s, d.exposure_s, EXPOSURE_S)?,
            gain_db: f("gain_db", s.gain_db, d.gain_db, GAIN_DB)?,
            unit_flux_e_per_s: f(
                "unit_flux_e_per_s",
                s.unit_flux_e_per_s,
                d.unit_flux_e_per_s,
                UNIT_FLUX,
            )?,
            full_well_e: f("full_well_e", s.full_well_e, d.full_well_e, FULL_WELL_E)?,
            read_noise_e: f("read_noise_e", s.read_noise_e, d.read_noise_e, READ_NOISE_E)?,
            dark_current_e_per_s: f(
                "dark_current_e_per_s",
                s.dark_current_e_per_s,
                d.dark_current_e_per_s,
                DARK_CURRENT,
            )?,
            system_gain_dn_per_e: self.system_gain(s)?,
            bit_depth: self.bit_depth(s)?,
            black_level_dn: self.black_level(s)?,
            response: self.response(s)?,
            vignetting: f("vignetting", s.vignetting, d.vignetting, UNIT)?,
            blur_px: f("blur_px", s.blur_px, d.blur_px, BLUR_PX)?,
            seed: self.seed(s)?,
            motion_blur_samples: match s.motion_blur_samples {
                None => d.motion_blur_samples,
                Some(n) => self.count("sensor.imaging.motion_blur_samples", n, MOTION_SAMPLES)?,
            },
            rolling_shutter_s: self.rolling_shutter(s)?,
            prnu_percent: f("prnu_percent", s.prnu_percent, d.prnu_percent, PRNU_PERCENT)?,
            dsnu_e: f("dsnu_e", s.dsnu_e, d.dsnu_e, DSNU_E)?,
        })
    }

    /// K: given, or the one that maps the full well to the ADC's top code.
    fn system_gain(&self, s: &ImagingSpec) -> R<f32> {
        if let Some(k) = s.system_gain_dn_per_e {
            return self.ranged("sensor.imaging.system_gain_dn_per_e", k, SYSTEM_GAIN);
        }
        let bits = self.bit_depth(s)?;
        let full_well = match s.full_well_e {
            Some(v) => self.ranged("sensor.imaging.full_well_e", v, FULL_WELL_E)?,
            None => Imaging::default().full_well_e,
        };
        Ok(((1u32 << bits) - 1) as f32 / full_well)
    }

    fn bit_depth(&self, s: &ImagingSpec) -> R<u32> {
        match s.bit_depth {
            None => Ok(Imaging::default().bit_depth),
            Some(b) if BIT_DEPTH.contains(&b) => Ok(b as u32),
            Some(b) => Err(self.invalid(
                "sensor.imaging.bit_depth",
                format!(
                    "must be in {}..={} bits, got {b}",
                    BIT_DEPTH.start(),
                    BIT_DEPTH.end()
                ),
            )),
        }
    }

    /// A rolling shutter's readout, whose exposure's instants (a render each) stay bounded.
    fn rolling_shutter(&self, s: &ImagingSpec) -> R<f32> {
        let field = "sensor.imaging.rolling_shutter_s";
        let Some(v) = s.rolling_shutter_s else {
            return Ok(0.0);
        };
        let readout = self.ranged(field, v, READOUT_S)?;
        let exposure = match s.exposure_s {
            Some(e) => self.ranged("sensor.imaging.exposure_s", e, EXPOSURE_S)?,
            None => Imaging::default().exposure_s,
        };
        let samples = match s.motion_blur_samples {
            Some(n) => self.count("sensor.imaging.motion_blur_samples", n, MOTION_SAMPLES)?,
            None => 1,
        };
        let instants = f64::from(samples) * (1.0 + f64::from(readout) / f64::from(exposure));
        if instants.ceil() > f64::from(MAX_INSTANTS) {
            return Err(self.invalid(
                field,
                format!(
                    "asks for {} instants a frame (motion_blur_samples × (1 + \
                     rolling_shutter_s / exposure_s), a render each); at most {MAX_INSTANTS}: \
                     a shorter readout, a longer exposure or fewer samples",
                    instants.ceil()
                ),
            ));
        }
        Ok(readout)
    }

    /// The black level: a code below the top one.
    fn black_level(&self, s: &ImagingSpec) -> R<f32> {
        let Some(v) = s.black_level_dn else {
            return Ok(Imaging::default().black_level_dn);
        };
        let top = ((1u32 << self.bit_depth(s)?) - 1) as f32;
        let range = Range {
            hi_open: true,
            ..Range::closed(0.0, top)
        };
        self.ranged("sensor.imaging.black_level_dn", v, range)
    }

    fn seed(&self, s: &ImagingSpec) -> R<u64> {
        match s.seed {
            None => Ok(0),
            Some(v) if v >= 0 => Ok(v as u64),
            Some(v) => Err(self.invalid("sensor.imaging.seed", format!("must be >= 0, got {v}"))),
        }
    }

    /// `response` and the field its word needs (`gamma`, `response_table`), none other.
    fn response(&self, s: &ImagingSpec) -> R<Response> {
        let word = s.response.as_deref().unwrap_or("linear");
        let needs = |field: &str, word: &str| {
            self.missing(
                &format!("sensor.imaging.{field}"),
                &format!("response = \"{word}\" needs it"),
            )
        };
        let unused = |field: &str| {
            self.unused(
                &format!("sensor.imaging.{field}"),
                &format!("response is \"{word}\""),
            )
        };
        if word != "gamma" && s.gamma.is_some() {
            return Err(unused("gamma"));
        }
        if word != "table" && s.response_table.is_some() {
            return Err(unused("response_table"));
        }
        match word {
            "linear" => Ok(Response::Linear),
            "srgb" => Ok(Response::Srgb),
            "gamma" => {
                let g = s.gamma.ok_or_else(|| needs("gamma", word))?;
                Ok(Response::Gamma(self.ranged(
                    "sensor.imaging.gamma",
                    g,
                    GAMMA,
                )?))
            }
            "table" => {
                let t = (s.response_table.as_ref()).ok_or_else(|| needs("response_table", word))?;
                self.response_table(t).map(Response::Table)
            }
            other => Err(self.invalid(
                "sensor.imaging.response",
                format!("must be \"linear\", \"srgb\", \"gamma\" or \"table\", got \"{other}\""),
            )),
        }
    }

    fn response_table(&self, t: &[f64]) -> R<Vec<f32>> {
        let field = "sensor.imaging.response_table";
        if !TABLE_POINTS.contains(&t.len()) {
            return Err(self.invalid(
                field,
                format!(
                    "must have {}..={} values, got {}",
                    TABLE_POINTS.start(),
                    TABLE_POINTS.end(),
                    t.len()
                ),
            ));
        }
        let mut out: Vec<f32> = Vec::with_capacity(t.len());
        for (i, v) in t.iter().enumerate() {
            let v = self.ranged(&format!("{field}[{i}]"), *v, UNIT)?;
            if let Some(&last) = out.last() {
                if v < last {
                    return Err(self.invalid(
                        &format!("{field}[{i}]"),
                        format!("must not decrease: {v} after {last}"),
                    ));
                }
            }
            out.push(v);
        }
        Ok(out)
    }
}
