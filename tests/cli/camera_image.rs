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
    for (command, extra) in [
        ("render", &["--cube-size", "64"][..]),
        ("reference", &[][..]),
    ] {
        let out = dir.join(command);
        let o = out.to_str().unwrap();
        run_ok(&[&[command, s, "--out", o, "--sensor-outputs"], extra].concat());
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
