//! The module arrows of docs/architecture.md, checked on the source as the compiler reads it:
//! every file of the engine and of the core it re-exports is parsed (`syn`), and every path it
//! names (`use` trees with their `{..}` groups, paths in code, `super::super::...`, and the
//! crates' exported macros, `say!` and `crate::say!`, as the module that defines them) is
//! resolved to the module it reaches. The two crates are read as one tree of modules, as the
//! engine's users see them (`specchio::scene` is the core's `scene`). The rules:
//!
//! - the Vulkan layer knows nothing of the renderer or the scene;
//! - no modules import each other round a loop of any length (a parent and its own child
//!   modules aside: a folder's `mod.rs` and its files are one module split up);
//! - [`crate::process`], what the programs on top share, is imported by nothing below it.
//!
//! That the CPU-only modules (the core: scene, image, files, memory, reference, metrics,
//! output, sensor, ...) reach no Vulkan is the compiler's to hold: the core depends on no
//! Vulkan crate and on no crate of the workspace above it, which `crate_arrows.rs` checks on
//! the manifests.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use syn::visit::Visit;

/// A module path below the crate root, as its names (`["render", "cube_fill"]`).
type Module = Vec<String>;

/// Every `.rs` file under `src` with the module it defines.
fn modules(src: &Path) -> Vec<(PathBuf, Module)> {
    let mut found = Vec::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("source folder") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let rel = path.strip_prefix(src).expect("under src");
            let mut names: Module = rel
                .iter()
                .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_owned())
                .collect();
            if matches!(
                names.last().map(String::as_str),
                Some("mod" | "lib" | "main")
            ) {
                names.pop();
            }
            found.push((path, names));
        }
    }
    found.sort();
    found
}

/// The modules a file's paths reach, resolved from `here` (the file's own module).
struct Paths<'a> {
    here: &'a Module,
    /// The crate's `#[macro_export]` macros by name, with the module defining each.
    macros: &'a BTreeMap<String, Module>,
    /// The inline modules (`mod tests { .. }`) being visited, inside `here`.
    inline: Vec<String>,
    reached: BTreeSet<Module>,
}

impl Paths<'_> {
    /// Resolves a path's leading segments: `crate::a::b`, `super::x`, `self::y`. Others
    /// (external crates, locals, prelude) are not modules of this crate.
    fn add(&mut self, segments: &[String]) {
        let mut at: Module = match segments.first().map(String::as_str) {
            Some("crate") => Vec::new(),
            Some("super") | Some("self") => {
                let mut at = self.here.clone();
                at.extend(self.inline.iter().cloned());
                at
            }
            _ => return,
        };
        for s in segments {
            match s.as_str() {
                "crate" | "self" => {}
                "super" => {
                    at.pop();
                }
                name => at.push(name.to_owned()),
            }
        }
        self.reached.insert(at);
    }

    fn tree(&mut self, prefix: &mut Vec<String>, tree: &syn::UseTree) {
        match tree {
            syn::UseTree::Path(p) => {
                prefix.push(p.ident.to_string());
                self.tree(prefix, &p.tree);
                prefix.pop();
            }
            syn::UseTree::Name(n) => {
                prefix.push(n.ident.to_string());
                self.add(prefix);
                prefix.pop();
            }
            syn::UseTree::Rename(r) => {
                prefix.push(r.ident.to_string());
                self.add(prefix);
                prefix.pop();
            }
            syn::UseTree::Glob(_) => self.add(prefix),
            syn::UseTree::Group(g) => {
                for t in &g.items {
                    self.tree(prefix, t);
                }
            }
        }
    }
}

impl<'ast> Visit<'ast> for Paths<'_> {
    fn visit_item_mod(&mut self, m: &'ast syn::ItemMod) {
        self.inline.push(m.ident.to_string());
        syn::visit::visit_item_mod(self, m);
        self.inline.pop();
    }

    fn visit_item_use(&mut self, u: &'ast syn::ItemUse) {
        self.tree(&mut Vec::new(), &u.tree);
    }

    /// A macro's own module: `say!(..)`, `crate::say!(..)` and `$crate::say!(..)` reach the
    /// module that defines `say` (an exported macro lives at the crate's root by name, so its
    /// path alone names no module). Its arguments are tokens, which are not read.
    fn visit_macro(&mut self, m: &'ast syn::Macro) {
        let segments: Vec<String> = m
            .path
            .segments
            .iter()
            .map(|s| s.ident.to_string())
            .collect();
        let name = match &segments[..] {
            [name] => Some(name),
            [root, name] if root == "crate" => Some(name),
            _ => None,
        };
        if let Some(module) = name.and_then(|n| self.macros.get(n)) {
            self.reached.insert(module.clone());
        }
        syn::visit::visit_macro(self, m);
    }

    fn visit_path(&mut self, p: &'ast syn::Path) {
        let segments: Vec<String> = p.segments.iter().map(|s| s.ident.to_string()).collect();
        self.add(&segments);
        syn::visit::visit_path(self, p);
    }
}

/// The crate's `#[macro_export]` macros by name, with the module that defines each.
fn exported_macros(parsed: &[(&Module, syn::File)]) -> BTreeMap<String, Module> {
    let mut found = BTreeMap::new();
    for (module, file) in parsed {
        for item in &file.items {
            let syn::Item::Macro(m) = item else { continue };
            let exported = m.attrs.iter().any(|a| a.path().is_ident("macro_export"));
            if let (true, Some(name)) = (exported, &m.ident) {
                found.insert(name.to_string(), (*module).clone());
            }
        }
    }
    found
}

/// The source folders read as one tree of modules, as the engine's users see them: the core's,
/// which the engine re-exports at its root under the same names, the Vulkan layer's, which it
/// re-exports as `vk`, and the engine's own.
fn source_folders() -> [(PathBuf, &'static str); 3] {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    [
        (manifest.join("../core/src"), ""),
        (manifest.join("../vk/src"), "vk"),
        (manifest.join("src"), ""),
    ]
}

/// Each module's reached modules, cut to the depth of modules that exist (a path to an item
/// `render::floors::Floor` reaches the module `render::floors`).
fn graph() -> BTreeMap<Module, BTreeSet<Module>> {
    let files: Vec<(PathBuf, Module)> = (source_folders().iter())
        .flat_map(|(src, under)| {
            modules(src).into_iter().map(move |(path, mut module)| {
                if !under.is_empty() {
                    module.insert(0, (*under).to_owned());
                }
                (path, module)
            })
        })
        .collect();
    let known: BTreeSet<Module> = files.iter().map(|(_, m)| m.clone()).collect();
    let parsed: Vec<(&Module, syn::File)> = (files.iter())
        .map(|(path, module)| {
            let text = std::fs::read_to_string(path).expect("source file");
            let file = syn::parse_file(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            (module, file)
        })
        .collect();
    let macros = exported_macros(&parsed);
    let mut graph: BTreeMap<Module, BTreeSet<Module>> = BTreeMap::new();
    for (module, file) in &parsed {
        let mut paths = Paths {
            here: module,
            macros: &macros,
            inline: Vec::new(),
            reached: BTreeSet::new(),
        };
        paths.visit_file(file);
        let edges = graph.entry((*module).clone()).or_default();
        for mut target in paths.reached {
            while !target.is_empty() && !known.contains(&target) {
                target.pop();
            }
            if !target.is_empty() && target != **module {
                edges.insert(target);
            }
        }
    }
    graph
}

fn starts_with(m: &Module, prefix: &[&str]) -> bool {
    m.len() >= prefix.len() && m.iter().zip(prefix).all(|(a, b)| a == b)
}

/// Every edge from a module under `from` to one under any of `to`.
fn edges_between(
    graph: &BTreeMap<Module, BTreeSet<Module>>,
    from: &str,
    to: &[&str],
) -> Vec<String> {
    graph
        .iter()
        .filter(|(m, _)| starts_with(m, &[from]))
        .flat_map(|(m, reached)| {
            reached
                .iter()
                .filter(|t| to.iter().any(|p| starts_with(t, &[p])))
                .map(move |t| format!("{} -> {}", m.join("::"), t.join("::")))
        })
        .collect()
}

#[test]
fn vulkan_layer_imports_neither_renderer_nor_scene() {
    let bad = edges_between(&graph(), "vk", &["render", "scene", "reference", "metrics"]);
    assert!(bad.is_empty(), "the Vulkan layer reaches up: {bad:#?}");
}

/// A module and its own descendants are one unit split over files; the other pairs must
/// keep their arrows one way.
fn related(a: &Module, b: &Module) -> bool {
    starts_with(a, &b.iter().map(String::as_str).collect::<Vec<_>>())
        || starts_with(b, &a.iter().map(String::as_str).collect::<Vec<_>>())
}

/// The modules `from` reaches along the graph's arrows, not counting arrows between a module
/// and its own descendants.
fn reachable(graph: &BTreeMap<Module, BTreeSet<Module>>, from: &Module) -> BTreeSet<Module> {
    let mut seen = BTreeSet::new();
    let mut stack = vec![from.clone()];
    while let Some(m) = stack.pop() {
        for next in graph.get(&m).into_iter().flatten() {
            if !related(&m, next) && seen.insert(next.clone()) {
                stack.push(next.clone());
            }
        }
    }
    seen
}

/// The loops of the graph: each set of two or more modules that all reach each other (its
/// strongly connected components), as `a -> b -> ...` names, sorted.
fn loops(graph: &BTreeMap<Module, BTreeSet<Module>>) -> Vec<Vec<String>> {
    let reach: BTreeMap<&Module, BTreeSet<Module>> =
        graph.keys().map(|m| (m, reachable(graph, m))).collect();
    let mut found: BTreeSet<Vec<String>> = BTreeSet::new();
    for (m, from_m) in &reach {
        let together: Vec<String> = (from_m.iter())
            .filter(|o| *o != *m && reach.get(o).is_some_and(|r| r.contains(*m)))
            .chain([*m])
            .map(|o| o.join("::"))
            .collect();
        if together.len() > 1 {
            let mut together = together;
            together.sort();
            found.insert(together);
        }
    }
    found.into_iter().collect()
}

#[test]
fn no_modules_import_each_other_round_a_loop() {
    let cycles = loops(&graph());
    assert!(cycles.is_empty(), "import loops: {cycles:#?}");
}

/// The loop search finds a loop of three, and not a parent with its own child.
#[test]
fn the_loop_search_finds_longer_loops() {
    let m = |s: &str| -> Module { s.split("::").map(str::to_owned).collect() };
    let graph: BTreeMap<Module, BTreeSet<Module>> = [
        ("output::stage", vec!["output::replace"]),
        ("output::replace", vec!["output::staged"]),
        ("output::staged", vec!["output::stage"]),
        ("render", vec!["render::floors"]),
        ("render::floors", vec!["render"]),
    ]
    .into_iter()
    .map(|(a, to)| (m(a), to.into_iter().map(m).collect()))
    .collect();
    assert_eq!(
        loops(&graph),
        [vec!["output::replace", "output::stage", "output::staged"]]
    );
}

/// The guard sees what the old text search missed: a `{..}` group, `super::super` and an
/// exported macro.
#[test]
fn the_guard_reads_groups_and_super_paths() {
    let here: Module = vec!["render".into(), "lookups".into()];
    let file = syn::parse_file(
        "use crate::{scene::camera, vk::{device::Device}};\n\
         fn f() { super::super::metrics::compare(); crate::say!(\"x\"); }",
    )
    .unwrap();
    let mut paths = Paths {
        here: &here,
        macros: &BTreeMap::from([("say".to_owned(), vec!["stdout".to_owned()])]),
        inline: Vec::new(),
        reached: BTreeSet::new(),
    };
    paths.visit_file(&file);
    let reached: Vec<String> = paths.reached.iter().map(|m| m.join("::")).collect();
    for expected in [
        "scene::camera",
        "vk::device::Device",
        "metrics::compare",
        "stdout",
    ] {
        assert!(reached.contains(&expected.to_owned()), "{reached:?}");
    }
}

#[test]
fn nothing_below_imports_the_process_module() {
    let graph = graph();
    let bad: Vec<String> = graph
        .iter()
        .filter(|(m, _)| !starts_with(m, &["process"]))
        .flat_map(|(m, reached)| {
            reached
                .iter()
                .filter(|t| starts_with(t, &["process"]))
                .map(move |t| format!("{} -> {}", m.join("::"), t.join("::")))
        })
        .collect();
    assert!(
        bad.is_empty(),
        "the engine reaches up into process: {bad:#?}"
    );
}

/// Whether `doc` names `name` as a whole word: not as the end of a longer name
/// (`draw.rs` inside `scene_draw.rs`).
fn names(doc: &str, name: &str) -> bool {
    doc.match_indices(name).any(|(at, _)| {
        let before = doc[..at].chars().next_back();
        !before.is_some_and(|c| c.is_alphanumeric() || c == '_')
    })
}

/// The `.rs` files at or under `path` (a folder, or one file).
fn rust_files(path: &Path) -> Vec<PathBuf> {
    if !path.is_dir() {
        return vec![path.to_path_buf()];
    }
    let mut found = Vec::new();
    for entry in std::fs::read_dir(path).expect("a source folder") {
        let p = entry.expect("an entry").path();
        match p.is_dir() {
            true => found.extend(rust_files(&p)),
            false if p.extension().is_some_and(|e| e == "rs") => found.push(p),
            false => {}
        }
    }
    found
}

/// How the module map must name `path`: its file name (`stage.rs`) or bare name in
/// backticks (`` `objects` ``, the scene loader's sections); for a folder's `mod.rs` the
/// folder (`load/`), for a crate's `lib.rs` or `main.rs` the crate's folder (`cli/`).
fn named_in(doc: &str, path: &Path) -> bool {
    let name = |p: &Path| {
        p.file_name()
            .expect("a name")
            .to_string_lossy()
            .into_owned()
    };
    let file = name(path);
    let stem = file.trim_end_matches(".rs");
    let parent = path.parent().expect("a folder");
    match stem {
        "mod" | "lib" | "main" => {
            // A crate's `src/` names nothing: its folder does.
            let folder = match name(parent).as_str() {
                "src" => name(parent.parent().expect("a crate folder")),
                other => other.to_owned(),
            };
            names(doc, &format!("{folder}/"))
        }
        _ => names(doc, &file) || doc.contains(&format!("`{stem}`")),
    }
}

/// docs/modules.md and docs/testing.md are the index the map (docs/architecture.md) points
/// into: every source file of the workspace is on it, by a whole word ([`named_in`]). A file
/// added without its line fails here, naming it.
#[test]
fn the_module_map_names_every_source_file() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    // The source files in modules.md, the test files (and the unit tests' own) in testing.md.
    let doc = ["docs/modules.md", "docs/testing.md"]
        .map(|p| std::fs::read_to_string(root.join(p)).expect("the doc"))
        .concat();
    let places = [
        "workspace-hack/src",
        "core/src",
        "vk/src",
        "engine/src",
        "engine/build.rs",
        "bench/src",
        "bench/examples",
        "viewer/src",
        "cli/src",
        "python/src",
        "tests/engine",
        "tests/cli",
        "tests/common",
        "tests/bench",
    ];
    let mut missing: Vec<String> = (places.iter())
        .flat_map(|p| rust_files(&root.join(p)))
        .filter(|path| !named_in(&doc, path))
        .map(|path| {
            path.strip_prefix(&root)
                .unwrap_or(&path)
                .display()
                .to_string()
        })
        .collect();
    missing.sort();
    assert!(
        missing.is_empty(),
        "docs/modules.md and docs/testing.md do not name: {missing:#?}"
    );
}
