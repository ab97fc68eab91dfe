//! An update on change gives, frame after frame, the bytes a full update gives, as the
//! command writes them: each re-rendered face's rectangles, each face whole, and all six.

#[path = "../common/mod.rs"]
mod common;

use common::render_scene;

/// orbit-near-seams (a small ball on a tilted orbit over the cube's seams, 64² faces) under
/// dirty rectangles and whole dirty faces writes every frame's sensor and observer views as
/// the full updates write them. On lavapipe its rectangles once differed by a half-float step
/// in five sensor pixels: the mips above them were blitted as a box of each level, and that
/// is not bit for bit the whole level's blit (docs/methods.md, "Mips").
#[test]
fn updates_on_change_write_the_full_updates_bytes() {
    let scene = "scenes/test/orbit-near-seams.toml";
    let frames = ["--frames", "6", "--fps", "4"];
    let run = |name: &str, how: Option<&str>| {
        let mut extra = frames.to_vec();
        extra.extend(how);
        let (out, json) = render_scene(name, scene, &extra);
        let faces: Vec<u64> = (json["runs"][0]["frames"].as_array().expect("frames").iter())
            .map(|f| f["faces_rendered"].as_u64().expect("faces_rendered"))
            .collect();
        (out, faces)
    };
    let (full, all_faces) = run("updates-full", Some("--full-updates"));
    assert!(all_faces[1..].iter().all(|&n| n == 6), "{all_faces:?}");
    for how in [None, Some("--whole-faces")] {
        let (out, faces) = run("updates-on-change", how);
        assert!(
            faces[1..].iter().any(|&n| n < 6),
            "{how:?}: the ball never left a face untouched: {faces:?}"
        );
        for frame in 0..6 {
            for view in ["sensor.exr", "observer.exr"] {
                let at = format!("{frame:04}/{view}");
                let (a, b) = (std::fs::read(full.join(&at)), std::fs::read(out.join(&at)));
                assert!(
                    a.expect("full update") == b.expect("on change"),
                    "{how:?}: {at} differs from the full updates'"
                );
            }
        }
    }
}

/// `--footprint` fills only the tiles the views read and writes every frame's views as a
/// whole cube's, byte for byte, records what it filled, and writes no cube. On the default
/// device: lavapipe here and in CI, or a GPU; never SwiftShader, which refuses the footprint
/// (the test below holds that refusal).
#[test]
fn the_footprint_writes_the_whole_cubes_views() {
    let scene = "scenes/test/orbit-near-seams.toml";
    let extra = ["--frames", "4", "--fps", "4", "--lookup", "box"];
    let (whole, plain) = render_scene("footprint-whole", scene, &extra);
    // Without a footprint: no footprint figures (not zeros, which say "already marked").
    for f in plain["runs"][0]["frames"].as_array().expect("frames") {
        assert!(
            f["footprint_texels"].is_null() && f["cpu_footprint_ms"].is_null(),
            "{f}"
        );
    }
    let mut cut_args = extra.to_vec();
    cut_args.push("--footprint");
    let (cut, json) = render_scene("footprint-cut", scene, &cut_args);
    assert_eq!(json["settings"]["footprint"], true);
    let frames = json["runs"][0]["frames"].as_array().expect("frames");
    let face = 64 * 64;
    for f in frames {
        let needed = f["footprint_texels"].as_u64().expect("footprint_texels");
        assert!(needed > 0 && needed <= 6 * face, "{f}");
        assert!(f["cpu_footprint_ms"].as_f64().is_some(), "{f}");
    }
    // Marked once: the views and the mirror stand still.
    let marked = frames
        .iter()
        .filter(|f| f["cpu_footprint_ms"].as_f64() > Some(0.0));
    assert_eq!(marked.count(), 1, "{frames:?}");
    for frame in 0..4 {
        for view in ["sensor.exr", "observer.exr", "views.png"] {
            let at = format!("{frame:04}/{view}");
            let (a, b) = (std::fs::read(whole.join(&at)), std::fs::read(cut.join(&at)));
            assert!(a.expect("whole") == b.expect("footprint"), "{at} differs");
        }
        assert!(whole.join(format!("{frame:04}/cube")).exists());
        assert!(
            !cut.join(format!("{frame:04}/cube")).exists(),
            "a cube was written"
        );
    }
}

/// On SwiftShader `--footprint` is refused before anything is written, naming the option, why
/// and what to do instead.
#[test]
fn the_footprint_is_refused_on_swiftshader_naming_it() {
    let root = common::root();
    if !root
        .join(".drivers/swiftshader/vk_swiftshader_icd.json")
        .exists()
    {
        common::skip(
            "--footprint on SwiftShader",
            "SwiftShader is not provided here",
        );
        return;
    }
    let out = common::temp_dir("footprint-swiftshader");
    let scene = root.join("scenes/test/six-colour-room.toml");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_specchio"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args([
            "--cube-size",
            "32",
            "--footprint",
            "--device",
            "swiftshader",
        ])
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{said}");
    assert!(
        said.contains(
            "--footprint: the footprint on SwiftShader: its cube sampler takes one level"
        ) && said.contains("leave it out, or give another --device (lavapipe)"),
        "{said}"
    );
    assert!(!out.exists() && common::staging_folders(&out).is_empty());
}
