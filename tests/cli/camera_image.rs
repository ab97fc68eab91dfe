//! The camera image of a scene's `[sensor.imaging]` from the commands: the PNG holds the
//! codes the chain makes of the clean image beside it, `camera.json` says how it was made,
//! and a dataset's frames each draw their own noise.

#[path = "../common/mod.rs"]
mod common;

use std::path::{Path, PathBuf};

use common::{root, specchio, temp_dir};
use specchio::image::RgbaImage;
use specchio::sensor::imaging::{self, CAMERA_IMAGE_FILE};
use specchio::sensor::SensorOptics;

/// The six-colour room with a 12-bit sRGB camera, blurred and vignetted, written into `dir`.
fn scene_with_camera(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(root().join("scenes/test/six-colour-room.toml")).unwrap();
    let path = dir.join("camera-room.toml");
    let camera = "\n[sensor.imaging]\nexposure_s = 0.006\nresponse = \"srgb\"\nblur_px = 1.2\n\
                  gain_db = 3\nseed = 9\n";
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(&path, format!("{text}{camera}")).unwrap();
    path
}

fn run_ok(args: &[&str]) {
    let r = specchio(args);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
}

/// The camera image's codes (the 16-bit samples shifted back) and its sBIT.
fn codes(path: &Path) -> (Vec<u16>, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let sbit = reader.info().sbit.as_deref().unwrap().to_vec();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut buf).unwrap();
    let shift = 16 - u32::from(sbit[0]);
    let dn = (buf.chunks(2))
        .map(|b| u16::from_be_bytes([b[0], b[1]]) >> shift)
        .collect();
    (dn, sbit)
}

fn clean(dir: &Path) -> RgbaImage {
    specchio::image::exr::decode_rgba(&std::fs::read(dir.join("sensor.exr")).unwrap()).unwrap()
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn render_and_reference_write_the_chains_codes_of_their_clean_image() {
    let dir = temp_dir("camera-image");
    let scene_path = scene_with_camera(&dir);
    let scene = specchio::scene::load(&scene_path).unwrap();
    let chain = scene.sensor.imaging.clone().unwrap();
    let optics = SensorOptics::at(&scene, 0.0);
    let s = scene_path.to_str().unwrap();
    for command in ["render", "reference"] {
        let out = dir.join(command);
        let o = out.to_str().unwrap();
        run_ok(&[command, s, "--out", o, "--sensor-outputs"]);
        let (dn, sbit) = codes(&out.join(CAMERA_IMAGE_FILE));
        assert_eq!(sbit, [12, 12, 12], "{command}");
        let expected = imaging::expose(&chain, &clean(&out), &optics, 0);
        assert_eq!(
            dn, expected.dn,
            "{command}: the codes of its own sensor.exr"
        );
        // Noise and exposure: not the clean image's codes, and most of the range used.
        assert!(
            dn.iter().any(|&d| d > 3000) && dn.iter().any(|&d| d < 1000),
            "{command}"
        );
        let record = &json(&out.join("camera.json"))["imaging"];
        assert_eq!(record["file"], CAMERA_IMAGE_FILE);
        assert_eq!(record["code"], "the 16-bit sample shifted right by 4 bits");
        assert_eq!(
            (record["response"].clone(), record["seed"].clone()),
            ("srgb".into(), 9.into())
        );
    }
    // A render's frame number is its scene frame's (`--frame`): its draws are that frame's.
    let out = dir.join("frame-3");
    let o = out.to_str().unwrap();
    run_ok(&["render", s, "--out", o, "--sensor-outputs", "--frame", "3"]);
    assert_eq!(json(&out.join("camera.json"))["imaging"]["frame"], 3);
    let expected = imaging::expose(&chain, &clean(&out), &optics, 3);
    assert_eq!(codes(&out.join(CAMERA_IMAGE_FILE)).0, expected.dn);
}

#[test]
fn a_datasets_frames_each_draw_their_own_noise() {
    let dir = temp_dir("camera-dataset");
    let scene_path = scene_with_camera(&dir);
    // Twice the same pose: the clean images are the same, the noise is not.
    let trajectory = dir.join("still.csv");
    std::fs::write(&trajectory, "time,x,y,z,heading\n0,0,0,0,0\n0,0,0,0,0\n").unwrap();
    let out = dir.join("set");
    let (s, t, o) = (
        scene_path.to_str().unwrap(),
        trajectory.to_str().unwrap(),
        out.to_str().unwrap(),
    );
    run_ok(&["dataset", s, "--trajectory", t, "--out", o]);
    let frame = |i: usize| out.join(format!("frames/{i:06}"));
    assert_eq!(
        std::fs::read(frame(0).join("sensor.exr")).unwrap(),
        std::fs::read(frame(1).join("sensor.exr")).unwrap()
    );
    let (a, b) = (
        codes(&frame(0).join(CAMERA_IMAGE_FILE)).0,
        codes(&frame(1).join(CAMERA_IMAGE_FILE)).0,
    );
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert!(differ > a.len() / 2, "{differ} of {} codes differ", a.len());
    let files = json(&out.join("dataset.json"))["frame_files"].clone();
    assert!(
        files
            .as_array()
            .unwrap()
            .contains(&CAMERA_IMAGE_FILE.into()),
        "{files}"
    );
    assert_eq!(json(&frame(1).join("camera.json"))["imaging"]["frame"], 1);
}

/// The robot turning at 90°/s through a 0.1 s exposure sweeps the image 9° about the disc's
/// centre (the camera looks up the turning axis): the red/blue wall corner, a radial line in
/// the image, becomes a ramp 9° wide, less the last of the 16 instants' share: 9° (1 − 1/16²).
/// The width is measured as 6 ∫ x (1 − x) dφ of the red share x = R / (R + B) along the
/// azimuth, which is the width of a linear ramp (and of this staircase, exactly so).
#[test]
fn the_robots_turn_during_the_exposure_blurs_an_edge_by_its_analytic_sweep() {
    let turned = turning_frame(
        "motion-blur",
        "exposure_s = 0.1\nunit_flux_e_per_s = 9e7\nmotion_blur_samples = 16\n",
    );
    let (blurred, sharp, centre) = (&turned.camera, &turned.clean, turned.centre);
    let w = turned.width;
    let (swept, swept_at) = edge_deg(blurred, w, centre);
    let (edge, edge_at) = edge_deg(sharp, w, centre);
    let expected = 9.0 * (1.0 - 1.0 / 256.0);
    assert!(edge < 1.5, "the clean edge is {edge}° wide");
    assert!(
        (swept - expected).abs() < edge + 0.3,
        "the swept edge is {swept}° wide, the sweep {expected}° (the clean edge {edge}°)"
    );
    // The exposure is centred on the frame's time: the swept edge's middle is where the
    // clean image, taken at that time, has the edge.
    assert!(
        (swept_at - edge_at).abs() < 0.2,
        "{swept_at}° against {edge_at}°"
    );
}

/// The red/blue edge's width and middle (degrees of azimuth about `centre`), from the red
/// share x of the pixels that see only the red and the blue walls (green dark, red + blue one
/// colour's worth), in 0.25° bins within 15° of where x crosses a half: the width
/// 6 ∫ x (1 − x) dφ, the middle where ∫ x dφ from the window's red end puts it.
fn edge_deg(rgb: &[[f64; 3]], width: usize, centre: [f64; 2]) -> (f64, f64) {
    const BIN: f64 = 0.25;
    let mut bins = vec![(0.0, 0usize); (360.0 / BIN) as usize];
    let full = rgb.iter().map(|p| p[0].max(p[2])).fold(0.0, f64::max);
    for (i, p) in rgb.iter().enumerate() {
        let sum = p[0] + p[2];
        if p[1] > 0.02 * full || (sum - full).abs() > 0.05 * full {
            continue;
        }
        let (x, y) = (
            (i % width) as f64 + 0.5 - centre[0],
            (i / width) as f64 + 0.5 - centre[1],
        );
        let phi = y.atan2(x).to_degrees().rem_euclid(360.0);
        let last = bins.len() - 1;
        let bin = &mut bins[((phi / BIN) as usize).min(last)];
        bin.0 += p[0] / sum;
        bin.1 += 1;
    }
    let share: Vec<Option<f64>> = (bins.iter())
        .map(|&(s, n)| (n > 0).then(|| s / n as f64))
        .collect();
    // The red-to-blue crossing: a bin at or above a half next to one below.
    let n = share.len();
    let cross = (0..n)
        .find(|&b| matches!((share[b], share[(b + 1) % n]), (Some(a), Some(c)) if (a - 0.5) * (c - 0.5) <= 0.0))
        .expect("no red/blue edge in the image");
    let reach = (15.0 / BIN) as isize;
    let window: Vec<f64> = (-reach..=reach)
        .map(|d| share[(cross as isize + d).rem_euclid(n as isize) as usize].unwrap_or(f64::NAN))
        .collect();
    assert!(
        window.iter().all(|x| x.is_finite()),
        "an empty bin near the edge"
    );
    let width = window.iter().map(|x| 6.0 * x * (1.0 - x) * BIN).sum();
    // How far the red reaches into the window from its red end (before the crossing or after).
    let red_first = window[0] > 0.5;
    let red: f64 = window.iter().sum::<f64>() * BIN;
    let start = (cross as f64 - reach as f64) * BIN;
    let middle = match red_first {
        true => start + red,
        false => start + window.len() as f64 * BIN - red,
    };
    (width, middle)
}

/// A rolling shutter reads row after row while the robot turns at 90°/s: row y is seen
/// R ((y + ½)/h − ½) after the frame's time (R = 0.1 s), turned by 90°/s times that, so the
/// radial red/blue corner, a vertical line below the disc's centre at the frame's heading,
/// leans over by (y − cy) tan Δ(y) pixels at row y. The exposure (4 ms, one instant) spaces
/// the rows' instants 4 ms apart, which moves a row by at most ±0.18° from its own time: the
/// bound below allows a pixel.
#[test]
fn a_rolling_shutter_leans_a_radial_edge_as_the_rows_turn() {
    let turned = turning_frame(
        "rolling-shutter",
        "exposure_s = 0.004\nunit_flux_e_per_s = 2.25e9\nrolling_shutter_s = 0.1\n",
    );
    let (rolled, sharp, [cx, cy]) = (&turned.camera, &turned.clean, turned.centre);
    let (w, h) = (turned.width, turned.clean.len() / turned.width);
    let mut rows = 0;
    let mut signs = std::collections::BTreeSet::new();
    for y in (cy as usize + 40)..h {
        let (Some(at), Some(sharp_at)) = (edge_x(rolled, w, y, cx), edge_x(sharp, w, y, cx)) else {
            continue;
        };
        let turn = (90.0 * 0.1 * ((y as f64 + 0.5) / h as f64 - 0.5)).to_radians();
        let lean = (y as f64 + 0.5 - cy) * turn.tan();
        let moved = at - sharp_at;
        assert!(
            (moved.abs() - lean.abs()).abs() < 1.0,
            "row {y}: the edge moved {moved} px, the rows' turn leans it {lean} px"
        );
        signs.insert(moved > 0.0);
        rows += 1;
    }
    assert!(rows > 50, "{rows} rows with the edge");
    assert_eq!(signs.len(), 1, "the edge leans one way");
}

/// Where along row `y` the red wall gives way to the blue one within 20 pixels of `cx`:
/// the window's left edge plus its red share (red on the left) or its right edge less it;
/// None where the window is not all red or blue (green dark, red + blue one colour's worth)
/// or holds no edge.
fn edge_x(rgb: &[[f64; 3]], width: usize, y: usize, cx: f64) -> Option<f64> {
    let (left, right) = (cx as usize - 20, cx as usize + 20);
    let full = rgb.iter().map(|p| p[0].max(p[2])).fold(0.0, f64::max);
    let mut red = Vec::new();
    for x in left..right {
        let p = rgb[y * width + x];
        let sum = p[0] + p[2];
        if p[1] > 0.02 * full || (sum - full).abs() > 0.05 * full {
            return None;
        }
        red.push(p[0] / sum);
    }
    let (first, last) = (red[0], red[red.len() - 1]);
    if (first - last).abs() < 0.9 {
        return None;
    }
    let share: f64 = red.iter().sum();
    Some(match first > last {
        true => left as f64 + share,
        false => right as f64 - share,
    })
}

/// Frame 1 of a dataset of the six-colour room with a camera of `imaging` (TOML lines) bright
/// and clean enough that noise does not move an edge (a 10⁷ e⁻ well, no read noise or dark
/// current, 16 bits, no vignetting), the robot turning at 90°/s through heading 45° at its
/// time, 0.5 s: its camera image and clean image (RGB, each in 0..1) and the disc's centre.
struct Turned {
    camera: Vec<[f64; 3]>,
    clean: Vec<[f64; 3]>,
    width: usize,
    centre: [f64; 2],
}

fn turning_frame(name: &str, imaging: &str) -> Turned {
    let dir = temp_dir(name);
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(root().join("scenes/test/six-colour-room.toml")).unwrap();
    let camera = format!(
        "\n[sensor.imaging]\nfull_well_e = 1e7\nread_noise_e = 0\ndark_current_e_per_s = 0\n\
         bit_depth = 16\nvignetting = 0\n{imaging}"
    );
    let scene_path = dir.join("turning.toml");
    std::fs::write(&scene_path, format!("{text}{camera}")).unwrap();
    let trajectory = dir.join("turn.csv");
    let turn = "time,x,y,z,heading\n0,0,0,0,0\n0.5,0,0,0,45\n1,0,0,0,90\n";
    std::fs::write(&trajectory, turn).unwrap();
    let out = dir.join("set");
    let [s, t, o] = [&scene_path, &trajectory, &out].map(|p| p.to_str().unwrap());
    run_ok(&[
        "dataset",
        s,
        "--trajectory",
        t,
        "--out",
        o,
        "--outputs",
        "image,camera",
    ]);
    let frame = out.join("frames/000001");
    let c = &json(&frame.join("camera.json"))["disc"]["centre_px"];
    let (dn, sbit) = codes(&frame.join(CAMERA_IMAGE_FILE));
    assert_eq!(sbit, [16, 16, 16]);
    let clean = clean(&frame);
    Turned {
        camera: (dn.chunks(3))
            .map(|c| [0, 1, 2].map(|k| f64::from(c[k]) / 65535.0))
            .collect(),
        clean: (clean.pixels.iter())
            .map(|p| [0, 1, 2].map(|k| f64::from(p[k])))
            .collect(),
        width: clean.width as usize,
        centre: [c[0].as_f64().unwrap(), c[1].as_f64().unwrap()],
    }
}

/// A frame's exposure of several instants (each a render of the sensor's view, up to 1024
/// a frame) is said as it goes: it was silent.
#[test]
fn an_exposure_of_many_instants_says_its_estimate() {
    let dir = temp_dir("exposure-estimate");
    let scene = scene_with_camera(&dir);
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, format!("{text}motion_blur_samples = 4\n")).unwrap();
    let out = dir.join("out");
    let args = [
        "render",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--sensor-outputs",
    ];
    let run = common::specchio_with(&args, &[common::ESTIMATE_AT_ONCE]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    common::estimate_line(
        &stderr,
        "render: frame 0's exposure at 4 instants",
        4,
        "renders",
    );
}
