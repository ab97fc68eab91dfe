//! `[sensor.imaging]`: the datasheet camera by default, every number in its range, each
//! response word with the field it needs and no other; each error names its line and field.

use std::path::Path;

use super::MINIMAL;
use crate::scene::imaging::{Imaging, Response};
use crate::scene::load_str;

#[test]
fn no_table_no_camera_image_and_an_empty_one_is_the_datasheet_camera() {
    let plain = load_str(MINIMAL, Path::new("plain.toml")).unwrap();
    assert_eq!(plain.sensor.imaging, None);
    let text = format!("{MINIMAL}[sensor.imaging]\n");
    let s = load_str(&text, Path::new("camera.toml")).unwrap();
    let i = s.sensor.imaging.unwrap();
    assert_eq!(i, Imaging::default());
    // The IMX249's numbers: 45.1 dB of SNR is a 32,359 e- well, 73 dB of range a 7.24 e-
    // read noise, and the gain puts the well at the 12-bit ADC's top code.
    assert_eq!(i.full_well_e, 10f32.powf(4.51).round());
    assert!((i.read_noise_e - i.full_well_e / 10f32.powf(73.0 / 20.0)).abs() < 0.01);
    assert!((i.full_well_e * i.system_gain_dn_per_e - 4095.0).abs() < 1e-3);
}

#[test]
fn the_file_sets_every_number_and_the_gain_follows_the_well_and_the_bits() {
    let text = format!(
        "{MINIMAL}[sensor.imaging]\nexposure_s = 0.002\ngain_db = 12\nfull_well_e = 10000\n\
         bit_depth = 10\nresponse = \"gamma\"\ngamma = 2.2\nvignetting = 0.5\nblur_px = 1.5\n\
         seed = 42\ndark_current_e_per_s = 0\nread_noise_e = 2\nunit_flux_e_per_s = 1e6\n"
    );
    let i = load_str(&text, Path::new("camera.toml"))
        .unwrap()
        .sensor
        .imaging
        .unwrap();
    assert_eq!(i.system_gain_dn_per_e, 1023.0 / 10000.0);
    assert_eq!(i.response, Response::Gamma(2.2));
    assert_eq!((i.bit_depth, i.seed, i.exposure_s), (10, 42, 0.002));
    let table =
        format!("{MINIMAL}[sensor.imaging]\nresponse = \"table\"\nresponse_table = [0, 0.7, 1]\n");
    let i = load_str(&table, Path::new("t.toml"))
        .unwrap()
        .sensor
        .imaging
        .unwrap();
    assert_eq!(i.response, Response::Table(vec![0.0, 0.7, 1.0]));
}

#[test]
fn bad_numbers_and_words_name_their_field_and_line() {
    let cases: &[(&str, &str)] = &[
        ("exposure_s = 0\n", "sensor.imaging.exposure_s: must be in (0, 10], got 0"),
        ("exposure_s = 11\n", "sensor.imaging.exposure_s"),
        ("gain_db = -1\n", "sensor.imaging.gain_db: must be in [0, 48]"),
        ("full_well_e = 0.5\n", "sensor.imaging.full_well_e"),
        ("read_noise_e = nan\n", "sensor.imaging.read_noise_e: must be a finite number"),
        ("bit_depth = 7\n", "sensor.imaging.bit_depth: must be in 8..=16 bits, got 7"),
        ("bit_depth = 12.5\n", "sensor.imaging.bit_depth"),
        ("seed = -3\n", "sensor.imaging.seed: must be >= 0, got -3"),
        ("vignetting = 1.5\n", "sensor.imaging.vignetting: must be in [0, 1]"),
        ("blur_px = 21\n", "sensor.imaging.blur_px: must be in [0, 20]"),
        ("prnu_percent = -1\n", "sensor.imaging.prnu_percent: must be in [0, 50]"),
        ("rolling_shutter_s = 2\n", "sensor.imaging.rolling_shutter_s: must be in [0, 1]"),
        (
            "exposure_s = 0.0625\nmotion_blur_samples = 64\nrolling_shutter_s = 1\n",
            "sensor.imaging.rolling_shutter_s: asks for 1088 instants a frame",
        ),
        ("dsnu_e = inf\n", "sensor.imaging.dsnu_e: must be a finite number"),
        ("motion_blur_samples = 65\n", "sensor.imaging.motion_blur_samples: must be in 1..=64, got 65"),
        ("black_level_dn = 4095\n", "sensor.imaging.black_level_dn: must be in [0, 4095), got 4095"),
        ("bit_depth = 8\nblack_level_dn = 300\n", "sensor.imaging.black_level_dn: must be in [0, 255)"),
        ("response = \"log\"\n", "sensor.imaging.response: must be \"linear\", \"srgb\", \"gamma\" or \"table\", got \"log\""),
        ("response = \"gamma\"\n", "sensor.imaging.gamma: required field is missing (response = \"gamma\" needs it)"),
        ("gamma = 2.2\n", "sensor.imaging.gamma: not allowed here: response is \"linear\""),
        ("response = \"table\"\n", "sensor.imaging.response_table: required field is missing"),
        ("response = \"table\"\nresponse_table = [0.5]\n", "sensor.imaging.response_table: must have 2..=4096 values, got 1"),
        ("response = \"table\"\nresponse_table = [0, 0.6, 0.5]\n", "sensor.imaging.response_table[2]: must not decrease"),
        ("response = \"srgb\"\nresponse_table = [0, 1]\n", "sensor.imaging.response_table: not allowed here"),
        ("exposure = 0.01\n", "exposure"),
    ];
    for (extra, needle) in cases {
        let text = format!("{MINIMAL}[sensor.imaging]\n{extra}");
        let err = load_str(&text, Path::new("case.toml")).expect_err(extra);
        let msg = err.to_string();
        assert!(
            msg.contains(needle),
            "{extra:?}: expected {needle:?} in {msg}"
        );
        assert!(msg.starts_with("case.toml:"), "{msg}");
        assert!(err.line().is_some(), "{msg}");
    }
}

/// A `[sensor.imaging]` table alone (Python's `imaging=`) is checked as a scene file's is:
/// the same camera from the same keys, and a value out of range named by its field.
#[test]
fn an_imaging_table_alone_is_checked_as_in_a_scene() {
    let table = "[sensor.imaging]\nexposure_s = 0.002\ngain_db = 6\nseed = 9\n";
    let alone = crate::scene::imaging_str(table, Path::new("imaging=")).unwrap();
    let scene = load_str(&format!("{MINIMAL}{table}"), Path::new("s.toml")).unwrap();
    assert_eq!(Some(alone), scene.sensor.imaging);
    let e = crate::scene::imaging_str("[sensor.imaging]\nexposure_s = 20\n", Path::new("imaging="))
        .unwrap_err();
    assert_eq!(e.field(), Some("sensor.imaging.exposure_s"), "{e}");
    let e = crate::scene::imaging_str("[sensor.imaging]\nexposur = 1\n", Path::new("imaging="))
        .unwrap_err();
    assert!(e.to_string().contains("unknown field `exposur`"), "{e}");
}
