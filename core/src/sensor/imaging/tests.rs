//! The camera model against its own definition: a flat field's mean and variance per level
//! (the photon transfer curve), the lens's fall-off and blur, saturation, the response
//! curves, and frames that are the same bytes however they are computed.

use super::chain::respond;
use super::lens::{blur, fall_off};
use super::*;
use crate::scene::Scene;

fn scene() -> Scene {
    crate::scene::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/test/six-colour-room.toml"
    )))
    .unwrap()
}

fn optics(scene: &Scene) -> SensorOptics {
    SensorOptics::at(scene, 0.0)
}

/// A flat field of linear value `v` the size of the scene's sensor image.
fn flat(scene: &Scene, v: f32) -> RgbaImage {
    let [width, height] = scene.sensor.resolution;
    RgbaImage {
        width,
        height,
        pixels: vec![[v, v, v, 1.0]; (width * height) as usize],
    }
}

/// The camera without its lens: no vignetting, no blur.
fn bare() -> Imaging {
    Imaging {
        vignetting: 0.0,
        ..Imaging::default()
    }
}

fn moments(dn: &[u16]) -> (f64, f64) {
    let n = dn.len() as f64;
    let mean = dn.iter().map(|&d| f64::from(d)).sum::<f64>() / n;
    let var = dn
        .iter()
        .map(|&d| (f64::from(d) - mean).powi(2))
        .sum::<f64>()
        / (n - 1.0);
    (mean, var)
}

#[test]
fn a_flat_fields_mean_and_variance_follow_the_photon_transfer_curve() {
    // EMVA 1288's linear model: mean μ = b + K (μe + μd), b the black level, variance
    // K² (μe + μd + σr²) + 1/12 (the quantisation's). Both within 5 standard errors of the
    // sample (the mean's σ/√n, the variance's σ²·√(2/n)), from no light to 45 % of the full
    // well, with dark current and a gain to make them count.
    let s = scene();
    let o = optics(&s);
    let imaging = Imaging {
        dark_current_e_per_s: 2000.0,
        gain_db: 6.0,
        ..bare()
    };
    let k = f64::from(imaging.system_gain_dn_per_e) * 10f64.powf(6.0 / 20.0);
    let t = f64::from(imaging.exposure_s);
    let sigma_r = f64::from(imaging.read_noise_e);
    let black = f64::from(imaging.black_level_dn);
    for (i, level) in [0.0, 0.02, 0.1, 0.25, 0.45].iter().enumerate() {
        let image = flat(&s, *level as f32);
        let got = expose(&imaging, &image, &o, i as u64);
        let charge = level * f64::from(imaging.unit_flux_e_per_s) * t + 2000.0 * t;
        let mean = black + k * charge;
        let var = k * k * (charge + sigma_r * sigma_r) + 1.0 / 12.0;
        let (m, v) = moments(&got.dn);
        let n = got.dn.len() as f64;
        assert!(
            (m - mean).abs() < 5.0 * (var / n).sqrt(),
            "level {level}: mean {m}, model {mean}"
        );
        assert!(
            (v - var).abs() < 5.0 * var * (2.0 / n).sqrt(),
            "level {level}: variance {v}, model {var}"
        );
    }
}

#[test]
fn the_full_well_saturates_at_the_top_code_whatever_the_light() {
    let s = scene();
    // The full well is the top code less the black level: with the black level and the read
    // noise above it, the ADC's top code (a sample below it is a 5σ draw of the read noise).
    for v in [2.0, 1e6, f32::INFINITY] {
        let got = expose(&bare(), &flat(&s, v), &optics(&s), 0);
        let top = got.dn.iter().filter(|&&d| d == 4095).count();
        assert!(top as f64 > 0.9999 * got.dn.len() as f64, "{v}: {top}");
        assert!(got.dn.iter().all(|&d| d >= 4094), "{v}");
    }
    // Darkness, NaN included, is the black level and the read noise about it, both halves of
    // it kept: a mean of b + K μd and a variance of K² (μd + σr²) + 1/12.
    let imaging = bare();
    let got = expose(&imaging, &flat(&s, f32::NAN), &optics(&s), 0);
    let k = f64::from(imaging.system_gain_dn_per_e);
    let dark = f64::from(imaging.dark_current_e_per_s * imaging.exposure_s);
    let sigma_r = f64::from(imaging.read_noise_e);
    let (mean, var) = (
        f64::from(imaging.black_level_dn) + k * dark,
        k * k * (dark + sigma_r * sigma_r) + 1.0 / 12.0,
    );
    let (m, v) = moments(&got.dn);
    let n = got.dn.len() as f64;
    assert!(
        (m - mean).abs() < 5.0 * (var / n).sqrt(),
        "dark mean {m}, model {mean}"
    );
    assert!(
        (v - var).abs() < 5.0 * var * (2.0 / n).sqrt(),
        "dark variance {v}, model {var}"
    );
}

#[test]
fn a_frame_is_the_same_bytes_for_its_seed_and_number_and_differs_for_others() {
    let s = scene();
    let (image, o) = (flat(&s, 0.3), optics(&s));
    let a = expose(&bare(), &image, &o, 5);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let one_thread = pool.install(|| expose(&bare(), &image, &o, 5));
    assert_eq!(a, one_thread);
    assert_ne!(a.dn, expose(&bare(), &image, &o, 6).dn);
    let seeded = Imaging { seed: 1, ..bare() };
    assert_ne!(a.dn, expose(&seeded, &image, &o, 5).dn);
}

#[test]
fn natural_vignetting_is_cos4_of_the_pixels_angle() {
    let s = scene();
    let o = optics(&s);
    let (w, h) = (o.width as usize, o.height as usize);
    let f = fall_off(&o, 1.0);
    // The corner pixel's centre ray, from the field of view.
    let u = (1.0 - 1.0 / w as f64) * f64::from(o.view.tan_x);
    let t = (1.0 - 1.0 / h as f64) * f64::from(o.view.tan_y);
    let theta = (u * u + t * t).sqrt().atan();
    assert!((f(w - 1, h - 1) - theta.cos().powi(4)).abs() < 1e-12);
    assert!(f(w / 2, h / 2) > 0.9999);
    let half = fall_off(&o, 0.5);
    assert!((half(0, 0) - (1.0 - 0.5 * (1.0 - theta.cos().powi(4)))).abs() < 1e-12);
    assert_eq!(fall_off(&o, 0.0)(0, 0), 1.0);
}

#[test]
fn the_lens_blur_keeps_the_light_and_spreads_a_point_by_its_sigma() {
    let (w, h) = (41, 41);
    let mut v = vec![0.0f32; w * h * 3];
    v[(20 * w + 20) * 3 + 1] = 1.0;
    let out = blur(v.clone(), (w, h), 2.0);
    let green: Vec<f64> = (out.iter().skip(1).step_by(3))
        .map(|&g| f64::from(g))
        .collect();
    let total: f64 = green.iter().sum();
    assert!((total - 1.0).abs() < 1e-6);
    // The second moment along x of a Gaussian truncated at 3σ: σ² less 1.1 %.
    let var_x: f64 = (green.iter().enumerate())
        .map(|(i, g)| g * ((i % w) as f64 - 20.0).powi(2))
        .sum();
    assert!((var_x - 4.0).abs() < 0.05 * 4.0, "{var_x}");
    assert!(out.iter().step_by(3).all(|&r| r == 0.0));
    assert_eq!(blur(v.clone(), (w, h), 0.0), v);
}

#[test]
fn response_curves_map_their_ends_and_their_middle() {
    let table = Response::Table(vec![0.0, 0.8, 1.0]);
    // Halfway between the first two points (0.8 as stored, in f32).
    assert_eq!(respond(&table, 0.25), 0.5 * f64::from(0.8f32));
    assert_eq!(respond(&table, 1.0), 1.0);
    assert!((respond(&Response::Gamma(2.0), 0.25) - 0.5).abs() < 1e-12);
    assert!((respond(&Response::Srgb, 0.5) - 0.735_356_9).abs() < 1e-6);
    assert_eq!(respond(&Response::Linear, 0.3), 0.3);
}

#[test]
fn the_png_samples_carry_the_code_at_the_top_of_their_bits() {
    let image = CameraImage {
        width: 1,
        height: 1,
        dn: vec![4095, 1, 0],
        imaging: Imaging::default(),
        frame: 0,
    };
    let (bytes, bits) = image.samples();
    assert_eq!(bits, 16);
    assert_eq!(bytes, [0xFF, 0xF0, 0x00, 0x10, 0x00, 0x00]);
    let eight = CameraImage {
        imaging: Imaging {
            bit_depth: 8,
            ..Imaging::default()
        },
        dn: vec![255, 1, 0],
        ..image
    };
    assert_eq!(eight.samples(), (vec![255, 1, 0], 8));
}

#[test]
fn the_png_holds_the_codes_and_says_how_many_bits_count() {
    let image = CameraImage {
        width: 2,
        height: 1,
        dn: vec![4095, 1, 0, 7, 8, 2048],
        imaging: Imaging::default(),
        frame: 0,
    };
    let bytes = image.png().unwrap();
    let decoder = ::png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().unwrap();
    assert_eq!(reader.info().sbit.as_deref(), Some(&[12u8, 12, 12][..]));
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut buf).unwrap();
    let codes: Vec<u16> = (buf.chunks(2))
        .map(|b| u16::from_be_bytes([b[0], b[1]]) >> 4)
        .collect();
    assert_eq!(codes, image.dn);
}

#[test]
fn the_exposure_is_centred_on_the_frame_and_its_instants_share_it_evenly() {
    let imaging = Imaging {
        exposure_s: 0.1,
        motion_blur_samples: 4,
        ..Imaging::default()
    };
    let times = Schedule::of(&imaging, 2.0).times();
    let want = [1.9625, 1.9875, 2.0125, 2.0375];
    // To the f32 exposure's rounding (0.1 is 0.10000000149 in f32).
    assert!(
        times.iter().zip(want).all(|(t, w)| (t - w).abs() < 1e-8),
        "{times:?}"
    );
    assert_eq!(Schedule::of(&Imaging::default(), 2.0).times(), [2.0]);
    // The mean of the images at those instants; one instant is no integration at all.
    let image_at = |t: f64| -> Result<RgbaImage, ()> {
        Ok(RgbaImage {
            width: 1,
            height: 1,
            pixels: vec![[t as f32, 1.0, 0.0, 1.0]],
        })
    };
    let light = integrate(&imaging, 2.0, image_at).unwrap().unwrap();
    assert!((light.pixels[0][0] - 2.0).abs() < 1e-6 && light.pixels[0][1] == 1.0);
    assert_eq!(integrate(&Imaging::default(), 2.0, image_at), Ok(None));
}

#[test]
fn a_rolling_shutters_rows_see_their_own_stretch_of_the_exposure() {
    // 4 rows read out over 0.08 s, each exposed 0.02 s in 2 instants (a step of 0.01 s): row
    // y's exposure is centred 0.08 (y + 1/2) / 4 - 0.04 s after the frame's time, so each row
    // sees the mean time of its own centre, the middle rows' straddling the frame's.
    let imaging = Imaging {
        exposure_s: 0.02,
        motion_blur_samples: 2,
        rolling_shutter_s: 0.08,
        ..Imaging::default()
    };
    let schedule = Schedule::of(&imaging, 1.0);
    assert_eq!(schedule.times().len(), 2 + 8);
    let image_at = |t: f64| -> Result<RgbaImage, ()> {
        Ok(RgbaImage {
            width: 2,
            height: 4,
            pixels: vec![[t as f32, 0.0, 0.0, 1.0]; 8],
        })
    };
    let light = integrate(&imaging, 1.0, image_at).unwrap().unwrap();
    for y in 0..4 {
        let centre = 1.0 + 0.08 * ((y as f64 + 0.5) / 4.0 - 0.5);
        let seen = f64::from(light.pixels[y * 2][0]);
        assert!(
            (seen - centre).abs() < 1e-6,
            "row {y}: {seen} against {centre}"
        );
        assert_eq!(light.pixels[y * 2], light.pixels[y * 2 + 1]);
    }
}

#[test]
fn the_fixed_pattern_stays_from_frame_to_frame_and_spreads_as_its_prnu_and_dsnu_say() {
    // EMVA 1288's split of a flat field's noise: over L frames, each pixel's mean keeps the
    // fixed pattern, whose spatial variance is K² ((μe PRNU)² + DSNU²), plus the temporal
    // variance over L; the temporal variance is each pixel's spread across the frames. Within
    // 5 standard errors (the variance's σ²·√(2/n)).
    let s = scene();
    let o = optics(&s);
    let imaging = Imaging {
        prnu_percent: 2.0,
        dsnu_e: 30.0,
        ..bare()
    };
    let (w, h, frames) = (64usize, 64usize, 16usize);
    let image = RgbaImage {
        width: w as u32,
        height: h as u32,
        pixels: vec![[0.3, 0.3, 0.3, 1.0]; w * h],
    };
    let shots: Vec<Vec<u16>> = (0..frames)
        .map(|f| expose(&imaging, &image, &o, f as u64).dn)
        .collect();
    let samples = w * h * 3;
    let per_pixel = |i: usize| shots.iter().map(|s| f64::from(s[i])).collect::<Vec<f64>>();
    let (mut means, mut temporal) = (Vec::with_capacity(samples), 0.0);
    for i in 0..samples {
        let v = per_pixel(i);
        let m = v.iter().sum::<f64>() / frames as f64;
        temporal += v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (frames - 1) as f64;
        means.push(m);
    }
    temporal /= samples as f64;
    let k = f64::from(imaging.system_gain_dn_per_e);
    let mu_e = 0.3 * f64::from(imaging.unit_flux_e_per_s * imaging.exposure_s);
    let dark = f64::from(imaging.dark_current_e_per_s * imaging.exposure_s);
    let sigma_r = f64::from(imaging.read_noise_e);
    let want_temporal = k * k * (mu_e + dark + sigma_r * sigma_r) + 1.0 / 12.0;
    let n = samples as f64;
    let se = want_temporal * (2.0 / (n * (frames - 1) as f64)).sqrt();
    assert!(
        (temporal - want_temporal).abs() < 5.0 * se,
        "temporal {temporal}, model {want_temporal}"
    );
    let mean = means.iter().sum::<f64>() / n;
    let spatial = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let pattern = k * k * ((mu_e * 0.02).powi(2) + 30.0 * 30.0);
    let want_spatial = pattern + want_temporal / frames as f64;
    assert!(
        (spatial - want_spatial).abs() < 5.0 * want_spatial * (2.0 / n).sqrt(),
        "spatial {spatial}, model {want_spatial}"
    );
    // Without a pattern, the frames' means spread only by the temporal noise over L.
    let uniform: Vec<Vec<u16>> = (0..frames)
        .map(|f| expose(&bare(), &image, &o, f as u64).dn)
        .collect();
    let means: Vec<f64> = (0..samples)
        .map(|i| uniform.iter().map(|s| f64::from(s[i])).sum::<f64>() / frames as f64)
        .collect();
    let mean = means.iter().sum::<f64>() / n;
    let spatial = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let want = want_temporal / frames as f64;
    assert!(
        (spatial - want).abs() < 5.0 * want * (2.0 / n).sqrt(),
        "uniform {spatial}, {want}"
    );
}
