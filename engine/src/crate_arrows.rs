//! The crates' arrows, read from their manifests (docs/architecture.md, "Where each part
//! lives"): the core depends on no workspace crate but `workspace-hack/` and on no Vulkan
//! crate, the engine on the core only, the benchmark and the viewer on the engine only, the
//! Python package on the engine and the benchmark (whose localisation experiment
//! `specchio.localise` runs), the CLI on the engine, the benchmark and the viewer; and the CLI's build and
//! the Python wheel's ask the same features of what they share, so the wheel reuses the
//! engine the main job compiled.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Crates that reach a GPU: none may be a dependency of the core.
const VULKAN_CRATES: [&str; 4] = ["ash", "ash-window", "gpu-allocator", "raw-window-handle"];

/// The core cannot name Vulkan: the compiler holds that, as long as its manifest lists no
/// Vulkan crate (and no workspace crate, which `crates_depend_one_way` checks).
#[test]
fn the_core_depends_on_no_vulkan_crate() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join("core/Cargo.toml")).expect("the core's manifest");
    let manifest: toml::Table = text.parse().expect("a well-formed manifest");
    assert!(
        manifest
            .get("dependencies")
            .is_some_and(|d| d.get("obvhs").is_some()),
        "the core's dependencies were not where this test reads them"
    );
    for table in ["dependencies", "dev-dependencies", "build-dependencies"] {
        let deps = manifest.get(table).and_then(|t| t.as_table());
        for name in deps.into_iter().flat_map(|d| d.keys()) {
            assert!(
                !VULKAN_CRATES.contains(&name.as_str()),
                "the core depends on {name} ({table}): it must stay GPU-free"
            );
        }
    }
}

/// The workspace's crates, by folder, with the workspace crates each may depend on.
const CRATE_ARROWS: [(&str, &[&str]); 8] = [
    ("workspace-hack", &[]),
    ("core", &["workspace-hack"]),
    ("vk", &[]),
    ("engine", &["core", "vk"]),
    ("bench", &["engine"]),
    ("viewer", &["engine"]),
    ("cli", &["engine", "bench", "viewer"]),
    // The benchmark for its localisation experiment (`specchio.localise`), run as the command
    // runs it.
    ("python", &["engine", "bench"]),
];

/// The workspace crates (by folder) that the manifest in `folder` depends on, in any of its
/// dependency tables.
fn workspace_dependencies(root: &Path, folder: &str) -> BTreeSet<String> {
    let path = root.join(folder).join("Cargo.toml");
    let text = std::fs::read_to_string(&path).expect("a crate manifest");
    let manifest: toml::Table = text.parse().expect("a well-formed manifest");
    let mut found = BTreeSet::new();
    for table in ["dependencies", "dev-dependencies", "build-dependencies"] {
        let Some(deps) = manifest.get(table).and_then(|t| t.as_table()) else {
            continue;
        };
        for dep in deps.values() {
            if let Some(p) = dep.get("path").and_then(|p| p.as_str()) {
                let target = Path::new(folder).join(p);
                let name = target.file_name().expect("a folder").to_string_lossy();
                found.insert(name.into_owned());
            }
        }
    }
    found
}

#[test]
fn crates_depend_one_way() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let workspace: toml::Table = std::fs::read_to_string(root.join("Cargo.toml"))
        .expect("the workspace manifest")
        .parse()
        .expect("a well-formed manifest");
    let members: BTreeSet<&str> = workspace["workspace"]["members"]
        .as_array()
        .expect("members")
        .iter()
        .map(|m| m.as_str().expect("a member folder"))
        .collect();
    let known: BTreeSet<&str> = CRATE_ARROWS.iter().map(|(c, _)| *c).collect();
    assert_eq!(
        members, known,
        "a crate was added or removed: give it its arrows here"
    );
    for (folder, allowed) in CRATE_ARROWS {
        for dep in workspace_dependencies(&root, folder) {
            assert!(
                allowed.contains(&dep.as_str()),
                "{folder} depends on {dep}: only on {allowed:?} (docs/architecture.md)"
            );
        }
    }
}

/// Every package the CLI's build and the Python wheel's build share, with the features each
/// compiles it with (`name version` to its feature lists, one per way it is built).
fn shared_features(package: &[&str]) -> BTreeMap<String, BTreeSet<String>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .current_dir(&root)
        .args(["tree", "--locked", "-e", "normal,build", "--prefix", "none"])
        .args(["-f", "{p}|{f}"])
        .args(package)
        .output()
        .expect("cargo tree runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut found: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        let line = line.trim_end_matches(" (*)");
        if let Some((package, features)) = line.split_once('|') {
            let id = package.split(" (").next().unwrap_or(package).to_owned();
            found.entry(id).or_default().insert(features.to_owned());
        }
    }
    found
}

/// The main job builds the CLI without the viewer; the wheel is built on its own. Cargo reuses
/// the engine between them only where every shared dependency has the same features in both:
/// `workspace-hack/` asks for the union. A dependency that adds a feature to one build alone
/// fails here, naming it.
#[test]
fn the_wheel_build_shares_the_engines_features() {
    let cli = shared_features(&["-p", "specchio-cli", "--no-default-features"]);
    let wheel = shared_features(&["-p", "specchio-python"]);
    assert!(cli.contains_key("specchio-core v0.1.0") && wheel.contains_key("specchio v0.1.0"));
    let differing: Vec<String> = (cli.iter())
        .filter_map(|(id, features)| {
            let other = wheel.get(id)?;
            (features != other).then(|| format!("{id}: {features:?} against {other:?}"))
        })
        .collect();
    assert!(
        differing.is_empty(),
        "features the CLI's build and the wheel's differ on (workspace-hack/Cargo.toml): \
         {differing:#?}"
    );
}
