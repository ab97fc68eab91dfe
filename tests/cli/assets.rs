//! Broken asset files (OBJ, glTF, GLB, PNG) as a user meets them through `specchio render`:
//! each fails with a non-zero exit and no panic, and its message names the scene file, the
//! line and field that referred to the asset, the asset, and what inside the asset is wrong.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Duration;

#[path = "../common/mod.rs"]
mod common;

use common::{root, specchio_within, temp_dir};

/// `specchio render SCENE --out OUT`, killed and reported if still running after `patience`.
fn render(scene: &Path, out: &Path, patience: Duration) -> Output {
    let (scene, out) = (scene.to_str().unwrap(), out.to_str().unwrap());
    specchio_within(&["render", scene, "--out", out], patience)
}

/// The expectations in a bad-asset scene's first line:
/// `# ...; the error must name FIELD, line N, and say: TEXT`.
fn expectation(text: &str) -> (String, u32, String) {
    let first = text.lines().next().unwrap_or("");
    let (names, say) = first
        .split_once(", and say: ")
        .expect("`, and say: ` in line 1");
    let names = names
        .split_once("must name ")
        .expect("`must name ` in line 1")
        .1;
    let (field, line) = names.split_once(", line ").expect("`, line N` in line 1");
    (
        field.to_string(),
        line.parse().expect("a line number"),
        say.to_string(),
    )
}

#[test]
fn every_bad_asset_fails_clearly_without_output() {
    let dir = root().join("tests/scenes/bad-assets");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(
        files.len() >= 30,
        "at least 30 bad-asset scenes, found {}",
        files.len()
    );
    let mut failures = Vec::new();
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        let (field, line, say) = expectation(&text);
        let asset = text
            .lines()
            .find_map(|l| l.strip_prefix("file = \"assets/"))
            .and_then(|l| l.strip_suffix('"'))
            .expect("a `file = \"assets/...\"` line");
        let out = temp_dir("bad");
        let result = render(&file, &out, Duration::from_secs(120));
        let stderr = String::from_utf8_lossy(&result.stderr);
        let name = file.file_name().unwrap().to_string_lossy();
        let wanted = [
            (format!("{name}:{line}:"), "the scene file and line"),
            (format!("{field}: cannot load "), "the field"),
            (asset.to_string(), "the asset"),
            (say.clone(), "what is wrong"),
        ];
        let missing: Vec<_> = wanted
            .iter()
            .filter(|(s, _)| !stderr.contains(s.as_str()))
            .map(|(s, what)| format!("{what} `{s}`"))
            .collect();
        if result.status.success()
            || stderr.contains("panicked")
            || out.exists()
            || !missing.is_empty()
        {
            failures.push(format!(
                "{name}: exit {:?}, output written: {}, missing {missing:?}:\n{stderr}",
                result.status.code(),
                out.exists()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A FIFO blocks a reader until a writer appears: as the scene or as a texture it must be
/// refused before it is opened, not waited on.
#[cfg(target_os = "linux")]
#[test]
fn fifos_are_refused_not_waited_on() {
    let dir = temp_dir("fifo");
    std::fs::create_dir_all(&dir).unwrap();
    let mkfifo = |p: &Path| {
        let ok = Command::new("mkfifo").arg(p).status().unwrap().success();
        assert!(ok, "mkfifo {}", p.display());
    };
    let scene_fifo = dir.join("scene.toml");
    mkfifo(&scene_fifo);
    let texture_fifo = dir.join("pipe.png");
    mkfifo(&texture_fifo);
    let textured = dir.join("textured.toml");
    std::fs::write(
        &textured,
        "[mirror]\ncenter = [0, 3, 0]\nradius = 1\n[room]\ncenter = [0, 3, 0]\nsize = [10, 6, 10]\n\
         walls = \"tex\"\n[[materials]]\nname = \"tex\"\ntype = \"texture\"\nfile = \"pipe.png\"\n",
    )
    .unwrap();
    for (scene, says) in [
        (
            &scene_fifo,
            "scene.toml: cannot read scene file: is a FIFO (named pipe)",
        ),
        (
            &textured,
            "textured.toml:11:8: materials[0].file: cannot load",
        ),
    ] {
        let out = dir.join("out");
        let result = render(scene, &out, Duration::from_secs(120));
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success(), "{}: must fail", scene.display());
        assert!(
            stderr.contains(says),
            "{}: must say `{says}`:\n{stderr}",
            scene.display()
        );
        assert!(stderr.contains("not a regular file"), "{stderr}");
        assert!(!out.exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}
