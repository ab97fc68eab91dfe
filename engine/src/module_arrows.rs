//! The module arrows of docs/architecture.md, checked on the source: the Vulkan layer knows
//! nothing of the renderer or the scene, and the CPU-only modules (scene, image, reference,
//! metrics, output) reach no Vulkan through their imports.
use std::path::Path;

/// Every `crate::NAME` path in the `.rs` files under `dir`, as (file, NAME).
fn crate_paths(dir: &Path) -> Vec<(String, String)> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).expect("source folder") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            let text = std::fs::read_to_string(&path).expect("source file");
            for piece in text.split("crate::").skip(1) {
                let name: String = piece
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                found.push((path.display().to_string(), name));
            }
        }
    }
    found
}

fn assert_no_imports(module: &str, forbidden: &[&str]) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let dir = src.join(module);
    let paths = if dir.is_dir() {
        crate_paths(&dir)
    } else {
        let file = src.join(format!("{module}.rs"));
        let text = std::fs::read_to_string(&file).expect("module file");
        text.split("crate::")
            .skip(1)
            .map(|p| {
                let name = p
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                (file.display().to_string(), name)
            })
            .collect()
    };
    let bad: Vec<_> = paths
        .iter()
        .filter(|(_, name)| forbidden.contains(&name.as_str()))
        .collect();
    assert!(
        bad.is_empty(),
        "{module} must not use {forbidden:?}: {bad:?}"
    );
}

#[test]
fn vulkan_layer_imports_neither_renderer_nor_scene() {
    assert_no_imports("vk", &["render", "scene", "reference", "metrics"]);
}

#[test]
fn cpu_modules_reach_no_vulkan() {
    for module in ["scene", "image", "reference", "metrics", "output", "sensor"] {
        assert_no_imports(module, &["vk", "render", "shaders"]);
    }
    // Nor the Vulkan bindings directly.
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut stack: Vec<_> = ["scene", "reference", "metrics", "sensor"]
        .iter()
        .map(|m| src.join(m))
        .chain(["image.rs", "output"].iter().map(|f| src.join(f)))
        .collect();
    while let Some(p) = stack.pop() {
        if p.is_dir() {
            stack.extend(std::fs::read_dir(&p).unwrap().map(|e| e.unwrap().path()));
        } else {
            let text = std::fs::read_to_string(&p).unwrap();
            assert!(!text.contains("ash::"), "{} uses ash", p.display());
        }
    }
}
