//! No output replaces an input under another spelling, on a case-folding file system whose
//! inodes differ per spelling: vfat mounted through FUSE (`fusefat`), where `t.EXR` and
//! `T.exr` are one file with two inode numbers, so the identity guard alone let
//! `compare T.exr r.exr --heatmap t.EXR`, `bench s.toml --json S.TOML` and `view s.toml
//! --screenshot S.TOML` replace their input and exit 0. (A heatmap or a screenshot now takes
//! only a `.png` name, so here it folds onto a PNG input: a mask, a scene named `s.png`.) Needs root, /dev/fuse, `fusefat` and `mkfs.vfat` (dosfstools; `scripts/setup.sh`
//! installs both); where they are missing the check is skipped, which CI refuses.

#[path = "../common/mod.rs"]
mod common;
mod viewer_support;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{render_six_colour, root, temp_dir};

/// A vfat image mounted through FUSE at `mnt`, unmounted when dropped.
struct Mount {
    mnt: PathBuf,
    /// Removed after the unmount (fields drop after `Drop::drop`).
    _dir: common::Scratch,
}

impl Mount {
    /// A fresh 32 MiB vfat mounted read-write, or why it cannot be.
    fn vfat(name: &str) -> Result<Mount, String> {
        for tool in ["fusefat", "mkfs.vfat", "fusermount"] {
            let found = Command::new("sh")
                .args(["-c", &format!("command -v {tool}")])
                .output()
                .map_err(|e| e.to_string())?;
            if !found.status.success() {
                return Err(format!("no `{tool}` (apt: fusefat, dosfstools, fuse)"));
            }
        }
        if !Path::new("/dev/fuse").exists() {
            return Err("no /dev/fuse".into());
        }
        let dir = temp_dir(name);
        std::fs::create_dir_all(&dir).unwrap();
        let (image, mnt) = (dir.join("vfat.img"), dir.join("mnt"));
        std::fs::write(&image, vec![0u8; 32 << 20]).unwrap();
        std::fs::create_dir(&mnt).unwrap();
        let run = |cmd: &mut Command| {
            let out = cmd.output().map_err(|e| e.to_string())?;
            match out.status.success() {
                true => Ok(()),
                false => Err(String::from_utf8_lossy(&out.stderr).into_owned()),
            }
        };
        run(Command::new("mkfs.vfat").arg(&image))?;
        run(Command::new("fusefat")
            .args(["-o", "rw+"])
            .arg(&image)
            .arg(&mnt))?;
        Ok(Mount { mnt, _dir: dir })
    }
}

impl Drop for Mount {
    fn drop(&mut self) {
        let _ = Command::new("fusermount").arg("-u").arg(&self.mnt).status();
    }
}

/// Runs `args` in `dir`; the exit code and stderr.
fn run_in(dir: &Path, args: &[&str]) -> (Option<i32>, String) {
    let out = common::output_of(
        Command::new(env!("CARGO_BIN_EXE_specchio"))
            .args(args)
            .current_dir(dir)
            .env("SPECCHIO_VALIDATE", "1"),
    );
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn an_output_never_replaces_its_input_through_a_case_fold_on_fuse_vfat() {
    let mount = match Mount::vfat("case-folding") {
        Ok(m) => m,
        Err(why) => return common::skip("a FUSE vfat mount", &why),
    };
    let mnt = &mount.mnt;
    // The fold is real here, and identities cannot see it.
    std::fs::write(mnt.join("Probe.txt"), b"x").unwrap();
    let ino =
        |p: &str| std::os::unix::fs::MetadataExt::ino(&std::fs::metadata(mnt.join(p)).unwrap());
    assert!(mnt.join("pROBE.TXT").exists(), "vfat folds case");
    assert_ne!(
        ino("Probe.txt"),
        ino("pROBE.TXT"),
        "FUSE gives each spelling its inode"
    );

    let (render, _) = render_six_colour("case-folding-render", &["--cube-size", "8"]);
    std::fs::write(
        mnt.join("T.exr"),
        std::fs::read(render.join("sensor.exr")).unwrap(),
    )
    .unwrap();
    std::fs::write(
        mnt.join("r.exr"),
        std::fs::read(render.join("sensor.exr")).unwrap(),
    )
    .unwrap();
    // The heatmap is a PNG (`--heatmap` takes only a .png name): the input it would fold onto
    // is the mask, a PNG (the render's sensor image, whose red walls select pixels).
    std::fs::write(
        mnt.join("M.png"),
        std::fs::read(render.join("sensor.png")).unwrap(),
    )
    .unwrap();
    let scene = root().join("scenes/test/six-colour-room.toml");
    std::fs::write(mnt.join("s.toml"), std::fs::read(&scene).unwrap()).unwrap();
    // The same scene under a PNG's name: the one input a screenshot can fold onto.
    std::fs::write(mnt.join("s.png"), std::fs::read(&scene).unwrap()).unwrap();
    let before = |p: &str| std::fs::read(mnt.join(p)).unwrap();
    let (mask, toml) = (before("M.png"), before("s.toml"));

    std::fs::create_dir(mnt.join("Sub")).unwrap();
    std::fs::write(mnt.join("Sub/M.png"), &mask).unwrap();
    let cases: [&[&str]; 4] = [
        &[
            "compare",
            "T.exr",
            "r.exr",
            "--mask",
            "M.png",
            "--heatmap",
            "m.PNG",
        ],
        // The input named by a spelling its folder does not list, the target by the listed one.
        &[
            "compare",
            "T.exr",
            "r.exr",
            "--mask",
            "m.png",
            "--heatmap",
            "M.png",
        ],
        // A parent folder spelled in another case.
        &[
            "compare",
            "T.exr",
            "r.exr",
            "--mask",
            "sub/M.png",
            "--heatmap",
            "SUB/m.png",
        ],
        &[
            "bench",
            "s.toml",
            "--quick",
            "--no-accuracy",
            "--no-floors",
            "--no-dynamic",
            "--no-tradeoff",
            "--json",
            "S.TOML",
        ],
    ];
    for args in cases {
        let (code, stderr) = run_in(mnt, args);
        assert_eq!(code, Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains("it is the input"), "{args:?}: {stderr}");
    }
    // The viewer's screenshot goes through the same guard (under Xvfb, run in the mount).
    if let Some(x) = viewer_support::Xvfb::start() {
        use viewer_support::Display;
        let out = common::output_of(
            x.command(&["s.png", "--frames", "2", "--screenshot", "S.PNG"])
                .current_dir(mnt),
        );
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(
            out.status.code(),
            Some(1),
            "view s.png --screenshot S.PNG: {stderr}"
        );
        assert!(stderr.contains("it is the input"), "{stderr}");
    }
    assert_eq!(before("M.png"), mask, "the input is untouched");
    assert_eq!(before("Sub/M.png"), mask, "the input is untouched");
    assert_eq!(before("s.toml"), toml, "the input is untouched");
    assert_eq!(before("s.png"), toml, "the input is untouched");
    // Another name is an output as usual.
    let (code, stderr) = run_in(mnt, &["compare", "T.exr", "r.exr", "--heatmap", "h.png"]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(mnt.join("h.png").exists());
    drop(mount);
    drop(render);
}
