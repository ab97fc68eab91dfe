//! `specchio compare` as a user runs it: known answers in the JSON, exit codes, errors that
//! name the file, and a heatmap the size of the images (or no file at all on error).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use specchio::image::RgbaImage;
use specchio::output::write_exr;

#[path = "../common/mod.rs"]
mod common;

/// Runs `specchio ARGS`, its messages held to readable numbers.
fn specchio(args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_specchio"))
        .args(args)
        .output()
        .expect("the specchio binary runs");
    common::readable_numbers(args, &out);
    out
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("specchio-compare-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// 16x8, every channel `base + offset` with base in [0.2, 0.8].
fn image(offset: f32) -> RgbaImage {
    let (width, height) = (16, 8);
    let pixels = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let u = x as f32 / width as f32;
            let v = y as f32 / height as f32;
            [
                0.2 + 0.6 * u + offset,
                0.2 + 0.6 * v + offset,
                0.5 + offset,
                1.0,
            ]
        })
        .collect();
    RgbaImage {
        width,
        height,
        pixels,
    }
}

/// How closely a heatmap colour gives its FLIP value back: the colour map interpolates 9 stops
/// 1/8 apart and rounds each channel to a byte; every stretch between stops moves some channel
/// by at least 48 levels, so one byte triple covers at most 1/(8 * 48) of the value, and the
/// middle of that stretch is within half of it (0.0013) of the value drawn, plus the 1e-5 step
/// it is found with. A mean or p99 (1-Lipschitz in the values) inherits the bound.
const HEATMAP_FLIP_RESOLUTION: f64 = 1.0 / (8.0 * 48.0) / 2.0 + 1e-5;

/// The FLIP value each heatmap colour stands for: the middle of the values the colour map
/// (`specchio::metrics::colour_map`) draws in that colour, scanned in steps of 1e-5.
fn colour_values() -> std::collections::HashMap<[u8; 3], f64> {
    const STEPS: u32 = 100_000;
    let mut spans = std::collections::HashMap::<[u8; 3], (f64, f64)>::new();
    for i in 0..=STEPS {
        let v = f64::from(i) / f64::from(STEPS);
        let span = spans
            .entry(specchio::metrics::colour_map(v as f32))
            .or_insert((v, v));
        span.1 = v;
    }
    spans
        .into_iter()
        .map(|(colour, (lo, hi))| (colour, (lo + hi) / 2.0))
        .collect()
}

fn s(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

fn json_of(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is one JSON object")
}

#[test]
fn json_reports_known_answers_and_the_heatmap_has_the_image_size() {
    let dir = temp_dir("json");
    let (a, b, heat) = (dir.join("a.exr"), dir.join("b.exr"), dir.join("flip.png"));
    write_exr(&a, &image(0.1)).unwrap();
    write_exr(&b, &image(0.0)).unwrap();

    let json = json_of(&specchio(&[
        "compare",
        s(&a),
        s(&b),
        "--json",
        "--heatmap",
        s(&heat),
    ]));
    assert_eq!(json["width"], 16);
    assert_eq!(json["height"], 8);
    assert_eq!(json["pixels_compared"], 128);
    assert_eq!(json["pixels_in_mask"], 128);
    assert_eq!(json["test_nan_pixels"], 0);
    assert_eq!(json["reference_inf_pixels"], 0);
    assert!((json["rmse"].as_f64().unwrap() - 0.1).abs() < 1e-6);
    assert!((json["psnr_db"].as_f64().unwrap() - 20.0).abs() < 1e-4);
    assert_eq!(json["psnr_infinite"], false);
    assert_eq!(json["settings"]["flip_pixels_per_degree"], 67.0);
    assert_eq!(json["settings"]["rel_mse_epsilon"], 0.01);
    assert_eq!(json["heatmap"], s(&heat));

    // The heatmap: a PNG of the image's size, and no temporary left beside it.
    let png = specchio::scene::TextureData::from_png(&heat).unwrap();
    assert_eq!((png.width, png.height), (16, 8));
    // The FLIP mean and p99 recomputed from the heatmap, by the other route the command
    // offers: each pixel's colour read back through the colour map to its FLIP value.
    let values = colour_values();
    let mut flip: Vec<f64> = png
        .rgba8
        .chunks(4)
        .map(|p| values[&[p[0], p[1], p[2]]])
        .collect();
    flip.sort_by(f64::total_cmp);
    let mean = flip.iter().sum::<f64>() / flip.len() as f64;
    let p99 = flip[(0.99 * flip.len() as f64).ceil() as usize - 1];
    for (key, from_heatmap) in [("flip_mean", mean), ("flip_p99", p99)] {
        let reported = json[key].as_f64().unwrap();
        assert!(
            (reported - from_heatmap).abs() <= HEATMAP_FLIP_RESOLUTION,
            "{key} {reported}, the heatmap says {from_heatmap}"
        );
    }
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        names.iter().all(|n| !common::names_a_staging_folder(n)),
        "{names:?}"
    );

    // Identical images: PSNR is null in JSON (never inf) and flagged infinite.
    let json = json_of(&specchio(&["compare", s(&b), s(&b), "--json"]));
    assert_eq!(json["rmse"], 0.0);
    assert_eq!(json["psnr_db"], serde_json::Value::Null);
    assert_eq!(json["psnr_infinite"], true);
    assert_eq!(json["flip_mean"], 0.0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_table_is_the_default_and_a_mask_restricts_the_pixels() {
    let dir = temp_dir("table");
    let (a, b, m) = (dir.join("a.exr"), dir.join("b.exr"), dir.join("m.exr"));
    write_exr(&a, &image(0.1)).unwrap();
    write_exr(&b, &image(0.0)).unwrap();
    // The mask keeps the left 4 columns: 4 x 8 = 32 pixels.
    let mut mask = image(0.0);
    for (i, p) in mask.pixels.iter_mut().enumerate() {
        p[0] = if i % 16 < 4 { 1.0 } else { 0.0 };
    }
    write_exr(&m, &mask).unwrap();

    let out = specchio(&["compare", s(&a), s(&b)]);
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("RMSE") && stdout.contains("FLIP mean"),
        "{stdout}"
    );
    assert!(stdout.contains("20.00 dB"), "{stdout}");

    let json = json_of(&specchio(&[
        "compare",
        s(&a),
        s(&b),
        "--mask",
        s(&m),
        "--json",
    ]));
    assert_eq!(json["pixels_in_mask"], 32);
    assert_eq!(json["pixels_compared"], 32);
    assert_eq!(json["mask"], s(&m));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_input_fails_naming_the_file_and_writes_no_heatmap() {
    let dir = temp_dir("bad");
    let (a, small, heat) = (
        dir.join("a.exr"),
        dir.join("small.exr"),
        dir.join("flip.png"),
    );
    write_exr(&a, &image(0.0)).unwrap();
    write_exr(
        &small,
        &RgbaImage {
            width: 3,
            height: 2,
            pixels: vec![[0.0; 4]; 6],
        },
    )
    .unwrap();
    let missing = dir.join("missing.exr");
    let garbage = dir.join("garbage.exr");
    std::fs::write(&garbage, b"not an exr").unwrap();

    for (args, must_name) in [
        (vec![s(&a), s(&missing)], vec!["missing.exr"]),
        (vec![s(&garbage), s(&a)], vec!["garbage.exr"]),
        (
            vec![s(&a), s(&small)],
            vec!["a.exr", "small.exr", "16x8", "3x2"],
        ),
        (
            vec![s(&a), s(&a), "--mask", s(&small)],
            vec!["small.exr", "16x8", "3x2"],
        ),
    ] {
        let mut all = vec!["compare"];
        all.extend(&args);
        all.extend(["--heatmap", s(&heat)]);
        let out = specchio(&all);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} must fail");
        assert!(!stderr.contains("panicked"), "{args:?} panicked:\n{stderr}");
        for name in must_name {
            assert!(
                stderr.contains(name),
                "{args:?}: must name {name}:\n{stderr}"
            );
        }
        assert!(!heat.exists(), "{args:?}: no heatmap on error");
        assert!(out.stdout.is_empty(), "{args:?}: no report on error");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A heatmap that cannot be written (its folder missing, a file where its folder must be, a
/// folder in its place) fails naming the path the user gave, never the hidden temporary one,
/// and leaves nothing.
#[test]
fn an_unwritable_heatmap_is_named_as_the_user_gave_it() {
    let dir = temp_dir("heatmap");
    let a = dir.join("a.exr");
    write_exr(&a, &image(0.0)).unwrap();
    let folder = dir.join("folder");
    std::fs::create_dir(&folder).unwrap();
    for heat in [dir.join("nodir/h.png"), a.join("h.png"), folder.clone()] {
        let out = specchio(&["compare", s(&a), s(&a), "--heatmap", s(&heat)]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{heat:?} must fail");
        assert!(stderr.contains(s(&heat)), "must name {heat:?}:\n{stderr}");
        assert!(
            !common::names_a_staging_folder(&stderr),
            "names a temporary:\n{stderr}"
        );
        assert!(out.stdout.is_empty(), "no report on error");
        let mut names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["a.exr", "folder"]);
        assert_eq!(std::fs::read_dir(&folder).unwrap().count(), 0);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A heatmap path that names an input (under any spelling) is refused before anything is
/// written: the input survives byte for byte. (The heatmap takes only a .png name: the input
/// here is the mask, a PNG.)
#[test]
fn a_heatmap_over_an_input_is_refused_and_the_input_kept() {
    let dir = temp_dir("heatmap-over-input");
    let (test, reference) = (dir.join("test.exr"), dir.join("reference.exr"));
    write_exr(&test, &image(0.1)).unwrap();
    write_exr(&reference, &image(0.0)).unwrap();
    let mask = dir.join("mask.png");
    specchio::output::write_png(&mask, &image(0.9)).unwrap();
    let before = std::fs::read(&mask).unwrap();
    let respelled = dir.join(".").join("mask.png");
    let out = specchio(&[
        "compare",
        s(&test),
        s(&reference),
        "--mask",
        s(&mask),
        "--heatmap",
        s(&respelled),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("--heatmap") && stderr.contains("is the input"),
        "{stderr}"
    );
    assert_eq!(std::fs::read(&mask).unwrap(), before);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--angular` over images with no pixel to compare (alpha 0 everywhere: no mirror) reports
/// the metrics as undefined, null in JSON, never as a perfect 0.
#[test]
fn angular_with_nothing_compared_is_undefined_not_zero() {
    let dir = temp_dir("angular-none");
    let mut empty = image(0.0);
    for p in &mut empty.pixels {
        p[3] = 0.0;
    }
    // The other: unit directions everywhere (+Z), marked as the mirror's.
    let mut up = image(0.0);
    up.pixels.iter_mut().for_each(|p| *p = [0.0, 0.0, 1.0, 1.0]);
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    write_exr(&a, &empty).unwrap();
    write_exr(&b, &up).unwrap();
    let json = json_of(&specchio(&[
        "compare",
        s(&a),
        s(&b),
        "--angular",
        "16",
        "--json",
    ]));
    assert_eq!(json["pixels"], 0);
    for key in ["mean_deg", "p99_deg", "max_deg", "mean_texels"] {
        assert!(json[key].is_null(), "{key}: {json}");
    }
    let text = specchio(&["compare", s(&a), s(&b), "--angular", "16"]);
    assert!(String::from_utf8_lossy(&text.stdout).contains("n/a"));
    // Its reading is said as a colour comparison's is (two 8192² direction images read for
    // 10 s, silently, through a Ctrl-C).
    let said = common::specchio_with(
        &["compare", s(&a), s(&b), "--angular", "16"],
        &[common::ESTIMATE_AT_ONCE],
    );
    let stderr = String::from_utf8_lossy(&said.stderr);
    common::estimate_line(
        &stderr,
        "compare: reading 2 images of 16x8 pixels",
        256,
        "pixels",
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--angular` refuses a colour image: its pixels are marked (alpha 1) but hold no unit
/// directions, and compared as directions they gave angles that mean nothing.
#[test]
fn angular_refuses_what_is_not_a_direction_image() {
    let dir = temp_dir("angular-colour");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    write_exr(&a, &image(0.0)).unwrap();
    write_exr(&b, &image(0.1)).unwrap();
    let out = specchio(&["compare", s(&a), s(&b), "--angular", "16"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("a.exr: not a direction image: a pixel marked as the mirror's"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An HDR image's extreme values read in the table: an RMSE of 2.1e38 prints with its
/// exponent, not as 39 digits (the `specchio` helper holds every line to readable numbers).
#[test]
fn extreme_errors_print_readably() {
    let dir = temp_dir("extreme");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    let mut huge = image(0.0);
    huge.pixels
        .iter_mut()
        .for_each(|p| *p = [3e38, 3e38, 3e38, 1.0]);
    write_exr(&a, &huge).unwrap();
    write_exr(&b, &image(0.0)).unwrap();
    let out = specchio(&["compare", s(&a), s(&b)]);
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    let rmse = stdout.lines().find(|l| l.contains("RMSE:")).unwrap();
    assert!(
        rmse.trim().starts_with("RMSE:") && rmse.contains("e38"),
        "{stdout}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A comparison of two `side`² images (2048²: seconds of FLIP) with a heatmap, started with
/// `env` and its stderr in a file (so that a test may watch it as it runs): the child, the
/// heatmap's path and the stderr file's.
fn long_comparison(
    dir: &Path,
    side: u32,
    env: &[(&str, &str)],
) -> (std::process::Child, PathBuf, PathBuf) {
    let big = |offset: f32| RgbaImage {
        width: side,
        height: side,
        pixels: (0..side * side)
            .map(|i| {
                let v = 0.2 + 0.6 * (i % 97) as f32 / 97.0 + offset;
                [v, 1.0 - v, 0.5, 1.0]
            })
            .collect(),
    };
    let (a, b, heatmap) = (dir.join("a.exr"), dir.join("b.exr"), dir.join("h.png"));
    write_exr(&a, &big(0.0)).unwrap();
    write_exr(&b, &big(0.05)).unwrap();
    let stderr = dir.join("stderr.txt");
    let child = Command::new(env!("CARGO_BIN_EXE_specchio"))
        .args(["compare", s(&a), s(&b), "--heatmap", s(&heatmap)])
        .envs(env.iter().copied())
        .stdout(std::process::Stdio::null())
        .stderr(std::fs::File::create(&stderr).unwrap())
        .spawn()
        .unwrap();
    (child, heatmap, stderr)
}

/// What the run said on stderr so far.
fn said(stderr: &Path) -> String {
    std::fs::read_to_string(stderr).unwrap_or_default()
}

/// Ctrl-C during a comparison stops it with exit 1, saying so, and leaves neither the heatmap
/// nor its staging folder; it used to end the process at once and leave `.NAME.specchio-*`
/// behind.
#[test]
fn a_stopped_comparison_leaves_nothing() {
    let dir = temp_dir("stopped");
    let (child, heatmap, stderr) = long_comparison(&dir, 2048, &[]);
    // Once the heatmap is staged the comparison is under way, and the signal is caught.
    let staged = || !common::staging_folders(&heatmap).is_empty();
    let out = common::signal_when(child, libc::SIGINT, "the staged heatmap", staged);
    let stderr = said(&stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("interrupted") && stderr.contains("nothing was written"),
        "{stderr}"
    );
    assert!(!heatmap.exists());
    assert!(common::staging_folders(&heatmap).is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A heatmap's encoding is said as its rows go, in bands of 256 (an 8192² heatmap of a noisy
/// comparison encodes for some seconds, silently until 30 November 2026).
#[test]
fn writing_a_heatmap_says_its_estimate() {
    let dir = temp_dir("heatmap-said");
    let (a, heat) = (dir.join("a.exr"), dir.join("h.png"));
    let pixels = vec![[0.5, 0.25, 0.125, 1.0]; 4 * 600];
    let (width, height) = (4, 600);
    write_exr(
        &a,
        &RgbaImage {
            width,
            height,
            pixels,
        },
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_specchio"))
        .args(["compare", s(&a), s(&a), "--heatmap", s(&heat)])
        .env(common::ESTIMATE_AT_ONCE.0, common::ESTIMATE_AT_ONCE.1)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let what = "compare: writing the heatmap of 4x600 pixels";
    let line = common::estimate_line(&stderr, what, 2400, "pixels");
    assert!(line.contains(": 1024 of 2400 pixels"), "{line}");
    assert!(heat.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A long comparison says its estimates as it reads its images and once FLIP has begun, and a
/// Ctrl-C then stops it between bands of FLIP's rows, saying how far it got: FLIP used to be
/// one call of a minute at 8192², silent, that no signal could cut short, after seconds of
/// silent reading.
#[test]
fn a_long_comparison_says_its_estimate_and_stops_within_flip() {
    let dir = temp_dir("estimate");
    // 3072² in bands of 32 rows on one thread: 96 bands, seconds of work after the first has
    // ended on a machine of any number of cores.
    let env = [
        ("SPECCHIO_ESTIMATE_AFTER_S", "0"),
        ("SPECCHIO_FLIP_BAND_ROWS", "32"),
        ("RAYON_NUM_THREADS", "1"),
    ];
    let (child, heatmap, stderr) = long_comparison(&dir, 3072, &env);
    let estimate = "compare: FLIP of 3072x3072 pixels: ";
    let out = common::signal_when(child, libc::SIGINT, "the estimate", || {
        said(&stderr).contains(estimate)
    });
    let stderr = said(&stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let line = stderr.lines().find(|l| l.starts_with(estimate)).unwrap();
    assert!(
        line.contains(" of 9437184 pixels in ") && line.contains("left; Ctrl-C stops it"),
        "{line}"
    );
    // The reading before it says its own (two 8192² images decode for seconds).
    common::estimate_line(
        &stderr,
        "compare: reading 2 images of 3072x3072 pixels",
        2 * 3072 * 3072,
        "pixels",
    );
    let stop = stderr
        .lines()
        .find(|l| l.contains("interrupted after "))
        .unwrap();
    let rows: u32 = stop
        .split("interrupted after ")
        .nth(1)
        .and_then(|rest| rest.split(" of 3072 rows of FLIP").next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{stop}"));
    assert!(rows % 32 == 0 && rows < 3072, "{stop}");
    assert!(!heatmap.exists());
    assert!(common::staging_folders(&heatmap).is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A second Ctrl-C, 0.7 s after the first and while a band of FLIP still runs, ends the
/// process at once (exit 130), and it removes its staging folder first: that folder used to
/// stay, hidden, until a later run into the same output swept it.
#[test]
fn a_second_ctrl_c_ends_the_run_at_once_and_leaves_nothing() {
    let dir = temp_dir("stopped-twice");
    // 3072² in two bands of FLIP on one thread: the second band begins as the first one's
    // estimate is said, and no signal cuts a band short: seconds on this 2-core machine, far
    // beyond the second signal's 0.7 s on a machine several times faster.
    let env = [
        ("SPECCHIO_ESTIMATE_AFTER_S", "0"),
        ("SPECCHIO_FLIP_BAND_ROWS", "1536"),
        ("RAYON_NUM_THREADS", "1"),
    ];
    let (mut child, heatmap, stderr) = long_comparison(&dir, 3072, &env);
    let started = std::time::Instant::now();
    while !said(&stderr).contains("compare: FLIP of 3072x3072 pixels: ") {
        assert!(
            child.try_wait().unwrap().is_none(),
            "ended before its estimate"
        );
        assert!(started.elapsed().as_secs() < 300, "no estimate after 300 s");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    for pause_ms in [0, 700] {
        std::thread::sleep(std::time::Duration::from_millis(pause_ms));
        // SAFETY: signals our own child process.
        unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    }
    let out = child.wait_with_output().unwrap();
    let stderr = said(&stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(!heatmap.exists());
    assert!(common::staging_folders(&heatmap).is_empty(), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A band height that is not a whole number from 1 is said, and the bands are chosen as
/// usual: the comparison's figures are the same.
#[test]
fn a_bad_band_height_is_said_and_not_used() {
    let dir = temp_dir("band-rows");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    write_exr(&a, &image(0.0)).unwrap();
    write_exr(&b, &image(0.1)).unwrap();
    let plain = specchio(&["compare", s(&a), s(&b), "--json"]);
    for bad in ["0", "-3", "many"] {
        let out = Command::new(env!("CARGO_BIN_EXE_specchio"))
            .args(["compare", s(&a), s(&b), "--json"])
            .env("SPECCHIO_FLIP_BAND_ROWS", bad)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stderr}");
        assert!(
            stderr.contains(&format!(
                "SPECCHIO_FLIP_BAND_ROWS=\"{bad}\" is not a whole number"
            )),
            "{stderr}"
        );
        assert_eq!(out.stdout, plain.stdout, "{bad}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
