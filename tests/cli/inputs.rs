//! Every command reads its input files through the one reader (`specchio::files`): a FIFO is
//! refused before it is opened (opening one blocks until a writer comes), a device such as
//! `/dev/zero` is refused before it is read (it never ends); and no output, under any name,
//! replaces a file the command read.

use std::path::Path;
use std::process::{Command, Output};
use std::time::Duration;

#[path = "../common/mod.rs"]
mod common;

use common::{root, temp_dir};

/// `specchio ARGS`, with two minutes to end.
fn specchio_within(args: &[&str]) -> Output {
    common::specchio_within(args, Duration::from_secs(120))
}

fn mkfifo(p: &Path) {
    let ok = Command::new("mkfifo").arg(p).status().unwrap().success();
    assert!(ok, "mkfifo {}", p.display());
}

/// The inputs that were read without the checks before: `localise`'s scene and `--landmarks`,
/// `bench --baseline`. Each fails at once, naming the file and what it is, and writes nothing.
#[cfg(target_os = "linux")]
#[test]
fn fifos_and_devices_are_refused_by_every_command() {
    let dir = temp_dir("special-inputs");
    std::fs::create_dir_all(&dir).unwrap();
    let fifo = dir.join("pipe.json");
    mkfifo(&fifo);
    let scene_fifo = dir.join("scene.toml");
    mkfifo(&scene_fifo);
    let out = dir.join("out");
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let thesis = s(&root().join("scenes/thesis-room.toml"));
    let small = ["--grid", "4", "--queries", "2", "--sensor-size", "32"];
    let cases: Vec<(Vec<String>, String, &str)> = vec![
        (
            vec!["localise".into(), s(&scene_fifo), "--out".into(), s(&out)],
            s(&scene_fifo),
            "FIFO",
        ),
        (
            vec!["localise".into(), thesis.clone(), "--out".into(), s(&out)]
                .into_iter()
                .chain(small.iter().map(|a| a.to_string()))
                .chain(["--landmarks".into(), s(&fifo)])
                .collect(),
            s(&fifo),
            "FIFO",
        ),
        (
            vec!["localise".into(), thesis.clone(), "--out".into(), s(&out)]
                .into_iter()
                .chain(small.iter().map(|a| a.to_string()))
                .chain(["--landmarks".into(), "/dev/zero".into()])
                .collect(),
            "/dev/zero".into(),
            "a device",
        ),
        (
            vec![
                "bench".into(),
                "--quick".into(),
                "--baseline".into(),
                s(&fifo),
            ],
            s(&fifo),
            "FIFO",
        ),
        (
            vec![
                "bench".into(),
                "--quick".into(),
                "--baseline".into(),
                "/dev/zero".into(),
            ],
            "/dev/zero".into(),
            "a device",
        ),
    ];
    for (args, names, what) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let result = specchio_within(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(1), "{args:?}:\n{stderr}");
        assert!(
            stderr.contains(&names),
            "{args:?}: must name {names}:\n{stderr}"
        );
        assert!(
            stderr.contains(what),
            "{args:?}: must say {what}:\n{stderr}"
        );
        assert!(stderr.contains("not a regular file"), "{stderr}");
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
    std::fs::remove_dir_all(&*dir).unwrap();
}

/// No report replaces a file the command read, however it is named: the benchmarked scene by
/// a hard link to it (as `S.TOML` names `s.toml` on a case-insensitive file system), the
/// scene's mesh, which only the scene names, and a compared image by a link. Each is refused
/// before any work, the file untouched.
#[cfg(unix)]
#[test]
fn no_output_replaces_an_input_under_another_name() {
    let dir = temp_dir("input-identity");
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = dir.join("m.obj");
    std::fs::write(&mesh, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let scene = dir.join("s.toml");
    std::fs::write(
        &scene,
        "[room]\ncenter = [0, 0, 0]\nsize = [10, 10, 10]\nwalls = \"red\"\n\
         [mirror]\ncenter = [0, 0, 0]\nradius = 1.0\n\
         [[materials]]\nname = \"red\"\ntype = \"color\"\ncolor = [1, 0, 0]\n\
         [[objects]]\nname = \"tri\"\nshape = \"mesh\"\nfile = \"m.obj\"\n\
         position = [2, 1, 2]\nmaterial = \"red\"\n",
    )
    .unwrap();
    std::fs::hard_link(&scene, dir.join("S.TOML")).unwrap();
    std::fs::hard_link(&mesh, dir.join("M.OBJ")).unwrap();
    let image = dir.join("a.exr");
    let grey = specchio::image::RgbaImage {
        width: 4,
        height: 4,
        pixels: vec![[0.5; 4]; 16],
    };
    specchio::output::write_exr(&image, &grey).unwrap();
    // A link under a PNG's name (the heatmap takes only a .png name) to the compared EXR.
    std::os::unix::fs::symlink(&image, dir.join("A.png")).unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let quick = ["--quick", "--no-accuracy", "--no-floors", "--no-dynamic"];
    let bench = |json: &Path| -> Vec<String> {
        let mut a = vec!["bench".to_owned(), s(&scene)];
        a.extend(quick.iter().map(|q| q.to_string()));
        a.extend(["--json".to_owned(), s(json)]);
        a
    };
    let cases = [
        (bench(&dir.join("S.TOML")), &scene),
        (bench(&dir.join("M.OBJ")), &mesh),
        (
            vec![
                "compare".to_owned(),
                s(&image),
                s(&image),
                "--heatmap".to_owned(),
                s(&dir.join("A.png")),
            ],
            &image,
        ),
    ];
    for (args, input) in cases {
        let before = std::fs::read(input).unwrap();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let result = specchio_within(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(1), "{args:?}:\n{stderr}");
        assert!(stderr.contains("is the input"), "{args:?}:\n{stderr}");
        assert_eq!(std::fs::read(input).unwrap(), before, "{args:?}");
    }
    std::fs::remove_dir_all(&*dir).unwrap();
}

/// A value of 100,000 characters in a scene, or in a baseline, is refused with a message a
/// terminal can hold: the value's start and how much was left out (the whole value was
/// repeated before, a 100 KB line).
#[test]
fn a_huge_value_is_refused_in_a_short_message() {
    let dir = temp_dir("huge-value");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(root().join("scenes/test/six-colour-room.toml")).unwrap();
    let huge = "x".repeat(100_000);
    let scene = dir.join("scene.toml");
    let lookup = format!("[mirror]\nlookup = \"{huge}\"\n");
    std::fs::write(&scene, text.replacen("[mirror]\n", &lookup, 1)).unwrap();
    let baseline = dir.join("baseline.json");
    let quick = std::fs::read_to_string(root().join("bench/baselines/quick.json")).unwrap();
    let mut record: serde_json::Value = serde_json::from_str(&quick).unwrap();
    record["settings"]["bvh_layout"] = serde_json::Value::String(huge.clone());
    std::fs::write(&baseline, record.to_string()).unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let out = s(&dir.join("out"));
    for args in [
        vec!["render".to_owned(), s(&scene), "--out".into(), out.clone()],
        vec![
            "bench".to_owned(),
            "--quick".into(),
            "--baseline".into(),
            s(&baseline),
        ],
    ] {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let run = specchio_within(&args);
        let said = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{args:?}: {said}");
        assert!(said.len() < 1000, "{args:?}: {} bytes", said.len());
        assert!(
            said.contains(&"x".repeat(50)) && said.contains(" more characters)"),
            "{said}"
        );
    }
    assert!(!dir.join("out").exists());
}

/// An option that would change nothing here is refused, naming it and why, rather than taken
/// without a word and recorded in render.json as if it had been applied; nothing is written.
#[test]
fn options_that_would_change_nothing_are_refused() {
    let dir = temp_dir("options-that-change-nothing");
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("out");
    let (out_s, base) = (out.to_str().unwrap(), dir.join("base.json"));
    let scene = |name: &str| root().join("scenes").join(name);
    let thesis = scene("thesis-room.toml");
    let (moving, still) = (
        scene("moving-objects.toml"),
        scene("test/six-colour-room.toml"),
    );
    let (thesis, moving) = (thesis.to_str().unwrap(), moving.to_str().unwrap());
    let still = still.to_str().unwrap();
    // One file under two names: a hard link, which a canonical path would miss (a copy of
    // the scene: the check comes before any scene is read).
    let (copy, linked) = (dir.join("scene.toml"), dir.join("scene-link.toml"));
    std::fs::copy(thesis, &copy).unwrap();
    std::fs::hard_link(&copy, &linked).unwrap();
    let (copy, thesis_again) = (copy.to_str().unwrap(), linked.to_str().unwrap());
    // A room refreshed every 2 frames (no file of its own to find beside it).
    let every_n = dir.join("every-n.toml");
    let room = std::fs::read_to_string(still).unwrap();
    let room_every_n = room.replace("policy = \"every-frame\"", "policy = \"every-n\"\nn = 2");
    assert_ne!(room, room_every_n);
    std::fs::write(&every_n, room_every_n).unwrap();
    let every_n = every_n.to_str().unwrap();
    let b = base.to_str().unwrap();
    // No --cube-size: it is refused itself where no cube is made (a row below).
    let small = ["--frames", "1"];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["render", thesis, "--out", out_s, "--whole-faces", "--full-updates"],
            "'--whole-faces' cannot be used with '--full-updates'",
        ),
        (
            vec!["render", moving, "--out", out_s, "--whole-faces"],
            "--whole-faces: changes only updates on change, and ",
        ),
        (
            vec!["render", moving, "--out", out_s, "--full-updates"],
            "sets refresh.policy = \"every-frame\": every update re-renders all six faces whole",
        ),
        (
            vec!["render", thesis, "--out", out_s, "--lookup", "plain", "--trace-in", "compute"],
            "--trace-in: only the bvh lookup walks trees of its own, and this run's lookup is plain",
        ),
        (
            vec!["render", thesis, "--out", out_s, "--lookup", "box", "--bvh-layout", "bvh4"],
            "--bvh-layout: only the bvh lookup walks trees of its own",
        ),
        (
            vec!["render", thesis, "--out", out_s, "--lookup", "bvh", "--method", "mesh"],
            "--method: the bvh lookup samples no cube map, so none is made; leave it out",
        ),
        (
            vec!["render", thesis, "--out", out_s, "--lookup", "bvh", "--cube-size", "64"],
            "--cube-size: the bvh lookup samples no cube map, so none is made; leave it out",
        ),
        (
            vec!["render", thesis, "--out", out_s, "--sensor-outputs", "--full-updates"],
            // bvh on a CPU driver, ray-query on a GPU that has ray queries: either fills none.
            " lookup samples no cube map, so none is made (the lookup --sensor-outputs traces \
             with, given no --lookup)",
        ),
        (
            vec!["render", thesis, "--out", out_s, "--lookup", "plain", "--distance-steps", "5"],
            "--distance-steps: only the distance lookups and a cube lookup's sensor outputs \
             search the cube's depth, and this run's lookup is plain",
        ),
        (
            vec!["render", thesis, "--out", out_s, "--lookup", "box", "--secant-steps", "3"],
            "--secant-steps: only the distance lookups and a cube lookup's sensor outputs",
        ),
        (
            vec!["render", thesis, "--out", out_s, "--lookup", "box", "--trace-order", "given"],
            "--trace-order: only the ray-query and distance-exact lookups build acceleration \
             structures, and this run's lookup is box",
        ),
        (
            vec!["render", thesis, "--out", out_s, "--lookup", "distance", "--footprint"],
            "--footprint: only the cube lookups' reads of the cube (plain, box) can be marked, \
             and this run's lookup is distance: its search reads the cube's depth",
        ),
        (
            vec!["render", thesis, "--out", out_s, "--lookup", "box", "--footprint", "--sensor-outputs"],
            "--footprint: --sensor-outputs reads the cube's ids and depth for the ray map",
        ),
        (
            vec!["render", every_n, "--out", out_s, "--lookup", "box", "--footprint"],
            "sets refresh.policy = \"every-n\" (n = 2), whose cube shows an older state between \
             its updates",
        ),
        (
            vec!["render", thesis, "--out", out_s, "--time", "2", "--fps", "60"],
            "--fps: sets the times of --frame and of --frames beyond the first, and this run \
             renders one frame at --time 2",
        ),
        (
            vec!["dataset", thesis, "--out", out_s, "--grid", "4", "--panorama-frame", "world", "--outputs", "image,range"],
            "panorama frame \"world\": only the panoramas layer is written in it, and this run \
             keeps none (outputs: image,range; format: files)",
        ),
        (
            vec!["dataset", thesis, "--out", out_s, "--grid", "4", "--geometry-frame", "map", "--outputs", "panoramas"],
            "geometry frame \"map\": only the rays and points layers are written in it",
        ),
        (
            vec!["bench", still, "--dynamic-from", "3", "--json", b],
            "--dynamic-from: sets where the dynamic measurement starts, and no scene here moves",
        ),
        (
            vec!["compare", thesis, thesis, "--angular", "64", "--heatmap", "h.png"],
            "'--angular <FACE_SIZE>' cannot be used with '--heatmap <HEATMAP>'",
        ),
        // The heatmap is a PNG: under an EXR's name it wrote PNG bytes, and `h.png/` (a
        // folder's name) wrote a file `h.png`.
        (
            vec!["compare", thesis, thesis, "--heatmap", "h.exr"],
            "`h.exr` is not a PNG file's name: the file is a PNG; name it .png",
        ),
        (
            vec!["compare", thesis, thesis, "--heatmap", "h.png/"],
            "`h.png/` is not a PNG file's name",
        ),
        (
            vec!["bench", thesis, "--no-accuracy", "--no-tradeoff", "--csv", "c.csv"],
            "--csv: holds the methods' speed against their error and the trade-off ladder's \
             rungs, and --no-accuracy --no-tradeoff leave out both",
        ),
        (
            vec!["bench", thesis, "--json", "b.json/"],
            "b.json/: a name that ends in `/`, `.` or `..` is a folder's; a file name is needed",
        ),
        (
            vec!["bench", thesis, "--rungs", "plain", "--trace-in", "compute", "--json", b],
            "--trace-in: changes only the bvh rung, and --rungs plain leaves it out",
        ),
        (
            vec!["bench", thesis, "--no-tradeoff", "--bvh-layout", "bvh4", "--json", b],
            "'--no-tradeoff' cannot be used with '--bvh-layout <BVH_LAYOUT>'",
        ),
        (
            vec!["bench", thesis, "--no-dynamic", "--dynamic-from", "3", "--json", b],
            "'--no-dynamic' cannot be used with '--dynamic-from <DYNAMIC_FROM>'",
        ),
        (
            vec!["bench", thesis, "--no-accuracy", "--lookups", "box", "--json", b],
            "'--no-accuracy' cannot be used with '--lookups <LOOKUPS>'",
        ),
        (
            vec!["bench", copy, thesis_again, "--json", b],
            "are one scene: each scene once",
        ),
        (
            vec!["localise", thesis, "--out", out_s, "--times", "0,3,0"],
            "--times: 0 is given twice (items 1 and 3); each time once",
        ),
        (
            vec!["localise", thesis, "--out", out_s, "--sources", "plain,box,plain"],
            "--sources: plain is given twice (items 1 and 3); each source once",
        ),
        (
            vec!["localise", thesis, "--out", out_s, "--sources", "bvh", "--method", "mesh"],
            "--method: no source here samples a cube map (bvh), so none is filled",
        ),
        (
            vec!["localise", thesis, "--out", out_s, "--sources", "reference,bvh", "--cube-size", "64"],
            "--cube-size: no source here samples a cube map (reference, bvh), so none is filled",
        ),
        (
            vec!["bench", thesis, "--max-regression", "5", "--json", base.to_str().unwrap()],
            "the following required arguments were not provided:\n  --baseline <BASELINE>",
        ),
    ];
    for (mut args, says) in cases {
        if args[0] == "render" {
            args.extend(small);
        }
        let run = specchio_within(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{args:?} succeeded");
        assert!(
            stderr.contains(says),
            "{args:?}: expected {says:?} in {stderr}"
        );
        assert!(!out.exists() && !base.exists(), "{args:?} wrote its output");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
