//! Every command that scales with a user's numbers checks a memory estimate before it starts
//! (`core/src/memory/estimates.rs`, `specchio::memory`): refused over the budget with the figures and
//! nothing written, and, where it runs, never using more than it estimated.
//!
//! The estimate is read from the refusal under a 1 MiB budget (`SPECCHIO_MEMORY_BUDGET=1MiB`,
//! below every command's estimate here and above the scene's textures, which are held to the
//! budget as they load), then the same command runs under the default budget and its peak
//! resident memory (from `wait4`, the child's own) must stay within it, and within twice what
//! it uses (an estimate too loose to mean anything fails too).

use std::path::Path;
use std::process::Command;

#[path = "../common/mod.rs"]
mod common;

use common::{root, run_measured, temp_dir};

/// "about 349.3 MiB" in `text`, as bytes.
fn estimate(text: &str) -> u64 {
    let at = text
        .find("would need about ")
        .unwrap_or_else(|| panic!("no estimate in:\n{text}"));
    let mut words = text[at + 17..].split_whitespace();
    let number: f64 = words.next().unwrap().parse().unwrap();
    let unit = match words.next().unwrap() {
        "bytes" => 1u64,
        "KiB" => 1 << 10,
        "MiB" => 1 << 20,
        "GiB" => 1 << 30,
        other => panic!("unit {other}"),
    };
    (number * unit as f64) as u64
}

/// Runs `specchio ARGS` with `budget` (None: the default); its exit code, stderr and peak
/// resident memory in bytes.
fn run(args: &[&str], budget: Option<&str>) -> (Option<i32>, String, u64) {
    let mut command = Command::new(env!("CARGO_BIN_EXE_specchio"));
    command.args(args).env_remove("SPECCHIO_MEMORY_BUDGET");
    if let Some(b) = budget {
        command.env("SPECCHIO_MEMORY_BUDGET", b);
    }
    let m = run_measured(command);
    (m.code, m.stderr, m.peak_bytes)
}

/// thesis-room with both views at `side`², in `dir` (with the textures it names).
fn thesis_at(dir: &Path, side: u32) -> String {
    let text = std::fs::read_to_string(root().join("scenes/thesis-room.toml")).unwrap();
    let text = text
        .replace(
            "resolution = [800, 600]",
            &format!("resolution = [{side}, {side}]"),
        )
        .replace(
            "resolution = [512, 512]",
            &format!("resolution = [{side}, {side}]"),
        );
    std::fs::create_dir_all(dir.join("textures")).unwrap();
    for entry in std::fs::read_dir(root().join("scenes/textures")).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), dir.join("textures").join(entry.file_name())).unwrap();
    }
    let path = dir.join("thesis.toml");
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_owned()
}

#[test]
fn each_command_stays_within_its_estimate_and_is_refused_above_the_budget() {
    let dir = temp_dir("memory");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = thesis_at(&dir, 1024);
    let out = dir.join("out");
    let o = out.to_str().unwrap();
    let six = root().join("scenes/test/six-colour-room.toml");
    let six = six.to_str().unwrap();
    let json = dir.join("bench.json");
    // Two 1024² images for compare (its estimate is from their headers).
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    let gradient = |v: f32| specchio::image::RgbaImage {
        width: 1024,
        height: 1024,
        pixels: (0..1024 * 1024)
            .map(|i| [v, (i % 1024) as f32 / 1024.0, 0.5, 1.0])
            .collect(),
    };
    specchio::output::write_exr(&a, &gradient(0.25)).unwrap();
    specchio::output::write_exr(&b, &gradient(0.5)).unwrap();
    let cases: [Vec<&str>; 7] = [
        // The whole benchmark (every method, the floors, the ladder and its errors) on a
        // small scene; `--json` is its output, removed below like the folders.
        vec![
            "bench",
            six,
            "--quick",
            "--cube-sizes",
            "256",
            "--json",
            json.to_str().unwrap(),
        ],
        vec!["render", &scene, "--out", o],
        vec![
            "render",
            &scene,
            "--out",
            o,
            "--sensor-outputs",
            "--directions",
        ],
        vec!["reference", &scene, "--out", o, "--sensor-outputs"],
        vec!["calibrate", &scene, "--out", o],
        vec![
            "compare",
            a.to_str().unwrap(),
            b.to_str().unwrap(),
            "--json",
        ],
        vec![
            "localise",
            &scene,
            "--out",
            o,
            "--sensor-size",
            "1024",
            "--grid",
            "4",
            "--queries",
            "2",
        ],
    ];
    let mut failures = Vec::new();
    for args in &cases {
        let (code, refusal, _) = run(args, Some("1MiB"));
        assert_eq!(code, Some(1), "{args:?} under a 1 MiB budget:\n{refusal}");
        assert!(refusal.contains("SPECCHIO_MEMORY_BUDGET=1MiB"), "{refusal}");
        assert!(
            !out.exists() && !json.exists(),
            "{args:?}: refused, yet wrote its output"
        );
        let estimated = estimate(&refusal);
        let (code, stderr, peak) = run(args, None);
        assert_eq!(code, Some(0), "{args:?}:\n{stderr}");
        let _ = std::fs::remove_dir_all(&out);
        let _ = std::fs::remove_file(&json);
        eprintln!("{}: estimate {estimated}, peak {peak}", args[0]);
        if peak > estimated || estimated > 2 * peak {
            failures.push(format!(
                "{args:?}: estimate {estimated} bytes, measured peak {peak} bytes"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The budget's own variable is checked: a value that is not a size is an error that says
/// how to write one, before any work.
#[test]
fn a_budget_that_is_not_a_size_is_refused() {
    let scene = root().join("scenes/test/six-colour-room.toml");
    let out = temp_dir("memory-bad");
    let (code, stderr, _) = run(
        &[
            "reference",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        Some("lots"),
    );
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("SPECCHIO_MEMORY_BUDGET=lots is not a size"),
        "{stderr}"
    );
    assert!(!out.exists());
    // A scene with textures reads the budget while loading them: the variable is named with
    // the file, not blamed on a texture's field.
    let textured = root().join("scenes/thesis-room.toml");
    let args = ["reference", textured.to_str().unwrap(), "--out"];
    let (code, stderr, _) = run(
        &[&args[..], &[out.to_str().unwrap()]].concat(),
        Some("lots"),
    );
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("thesis-room.toml: SPECCHIO_MEMORY_BUDGET=lots is not a size"),
        "{stderr}"
    );
    assert!(!stderr.contains("materials["), "{stderr}");
    assert!(!out.exists());
}

/// A texture is held to the budget from its header, before its pixels are decoded: a small
/// file can hold a large image (here 4096² in a few hundred KB: 192 MiB in a renderer). The
/// refusal names the texture's field, and the process never takes the decoded image's memory
/// (a peak of 534 MB for an 8192² file before, under a 100 MiB budget).
#[test]
fn a_texture_over_the_budget_is_refused_from_its_header() {
    let dir = temp_dir("memory-texture");
    std::fs::create_dir_all(&dir).unwrap();
    let side = 4096;
    let file = std::fs::File::create(dir.join("big.png")).unwrap();
    let mut png = png::Encoder::new(std::io::BufWriter::new(file), side, side);
    png.set_color(png::ColorType::Rgba);
    // Row by row: a child's peak (wait4's) counts what the parent held when it forked.
    let mut writer = png.write_header().unwrap();
    let mut rows = writer.stream_writer().unwrap();
    let row = vec![128u8; (side * 4) as usize];
    for _ in 0..side {
        std::io::Write::write_all(&mut rows, &row).unwrap();
    }
    rows.finish().unwrap();
    let text = std::fs::read_to_string(root().join("scenes/test/six-colour-room.toml")).unwrap();
    let scene = dir.join("big.toml");
    let material = "\n[[materials]]\nname = \"big\"\ntype = \"texture\"\nfile = \"big.png\"\n";
    let text = text.replacen("[room]", &format!("{material}\n[room]"), 1);
    let walls = text.find("walls").expect("the room names its walls");
    let end = walls + text[walls..].find('\n').unwrap();
    let text = format!("{}walls = \"big\"{}", &text[..walls], &text[end..]);
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let args = [
        "reference",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    let (code, stderr, peak) = run(&args, Some("64MiB"));
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("materials[") && stderr.contains(".file: this texture (4096 x 4096)"),
        "{stderr}"
    );
    assert!(
        stderr.contains("more than the memory budget of 64.0 MiB"),
        "{stderr}"
    );
    assert!(peak < 48 << 20, "peak {} MiB", peak >> 20);
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A run whose lookup makes no cube is not charged for one (a scene's 8192² faces were 16.5
/// GiB of a refusal whose hint, `--cube-size`, was itself refused with that lookup); one whose
/// lookup makes the cube is, with a hint the command takes (`cube.face_size` for a dataset,
/// which has no `--cube-size`), and localise's cube is the one its `--cube-size` makes.
#[test]
fn only_a_cube_that_is_made_is_counted() {
    let dir = temp_dir("memory-cube");
    let scene = thesis_at(&dir, 64);
    let text = std::fs::read_to_string(&scene).unwrap();
    let big = text.replace("face_size = 512", "face_size = 4096");
    assert_ne!(big, text, "the cube's face size line");
    std::fs::write(&scene, big).unwrap();
    // 6 x 4096² texels at 44 bytes: 4.1 GiB, against a budget of 2 GiB.
    let budget = Some("2GiB");
    let out = |name: &str| dir.join(name).to_str().unwrap().to_owned();
    let traced = [
        vec!["render", &scene, "--lookup", "bvh"],
        vec!["render", &scene, "--sensor-outputs"],
        vec!["dataset", &scene, "--grid", "5"],
    ];
    for (i, args) in traced.iter().enumerate() {
        let o = out(&format!("traced-{i}"));
        let (code, stderr, _) = run(&[&args[..], &["--out", &o]].concat(), budget);
        assert_eq!(code, Some(0), "{args:?}: {stderr}");
    }
    let (code, stderr, _) = run(
        &["render", &scene, "--lookup", "plain", "--out", &out("p")],
        budget,
    );
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("(the cube: ") && stderr.contains("(--cube-size)"),
        "{stderr}"
    );
    let dataset = ["dataset", &scene, "--grid", "5", "--lookup", "plain"];
    let (code, stderr, _) = run(&[&dataset[..], &["--out", &out("d")]].concat(), budget);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("(the cube: ") && stderr.ends_with("cube.face_size\n"),
        "{stderr}"
    );
    // localise fills the cube --cube-size makes (128² by default), not the scene's: it was
    // charged 4096² faces whatever --cube-size said, and its hint could not help.
    let localise = ["localise", &scene, "--sensor-size", "64", "--grid", "4"];
    let (l, l2) = (out("l"), out("l2"));
    let small = [&localise[..], &["--queries", "2", "--out", &l]].concat();
    let (code, stderr, _) = run(&small, budget);
    assert_eq!(code, Some(0), "{stderr}");
    let large = [&localise[..], &["--cube-size", "4096", "--out", &l2]].concat();
    let (code, stderr, _) = run(&large, budget);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("(the cube: ") && stderr.ends_with("--cube-size\n"),
        "{stderr}"
    );
}
