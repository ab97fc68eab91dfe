//! Compiles every `shaders/NAME.STAGE.glsl` to SPIR-V with glslang and embeds the words.
//!
//! glslang is run as its own command-line compiler, `glslangValidator` (Debian's
//! `glslang-tools`, which `scripts/setup.sh` installs; `GLSLANG_VALIDATOR=PATH` names another):
//! the library crate compiled glslang's C++ from source in every fresh build, 68 s of a
//! 4-minute release build on 2 cores, for the same compiler.
//!
//! Generates `$OUT_DIR/shaders.rs` with one `pub const NAME_STAGE: &[u32]` per shader (or per
//! module its `// build:` line names, each compiled with its own define), and
//! `SPIRV_MEMBER_OFFSETS`: (struct, member, byte offset) read back from the SPIR-V, which a
//! test compares with the `#[repr(C)]` Rust mirrors of `shaders/include/shared.glsl`; and from
//! `shaders/include/quantities/` the ray map's include and `SENSOR_QUANTITIES`
//! (`build/quantities.rs`).
//! A compile error fails the build and prints glslang's message with file and line.
//!
//! Also sets `SPECCHIO_BUILD_ID`: a digest of everything the library's outputs are computed
//! from (its sources and the core's, the shaders, the dependencies' versions in Cargo.lock),
//! which a resumable dataset keeps in its key (`Plan::run_key`, src/render/dataset/mod.rs):
//! two builds that may write different bytes never finish one dataset together. The shaders are compiled again
//! only when they changed, since a change to any source now runs this script.

use std::collections::BTreeMap;
use std::ffi::OsString;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "build/quantities.rs"]
mod quantities;

/// The stage of `NAME.STAGE.glsl`, as glslang's `-S` names it.
fn stage_of(name: &str) -> Option<&str> {
    let stage = name.strip_suffix(".glsl")?.rsplit('.').next()?;
    ["vert", "frag", "geom", "comp", "mesh", "task"]
        .contains(&stage)
        .then_some(stage)
}

/// One module built from a source file: its name (None: the file's own) and its defines.
type Build = (Option<String>, Vec<String>);

/// What one source file is built into: its `// build: MODULE=DEFINE ...` line, where a shader
/// that is one technique with several outputs (a lookup's colour and its direction) names each
/// module it makes and the define that selects its output (`MODULE=A+B`: several defines, an
/// output and a variant of how it is found); the file itself (no define) without such a line. A module `mirror_direction` of `mirror.frag.glsl` becomes the
/// constant `MIRROR_DIRECTION_FRAG`.
fn variants(text: &str) -> Result<Vec<Build>, String> {
    let Some(line) = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("// build:"))
    else {
        return Ok(vec![(None, Vec::new())]);
    };
    let mut builds = Vec::new();
    for item in line.split_whitespace() {
        let (module, defines) = item
            .split_once('=')
            .ok_or_else(|| format!("`{item}` in its `// build:` line is not MODULE=DEFINE"))?;
        let word =
            |w: &str| !w.is_empty() && w.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        // MODULE=A+B: several defines (one technique's output and a variant of its inputs).
        let defines: Vec<&str> = defines.split('+').collect();
        if !word(module) || !defines.iter().all(|d| word(d)) {
            return Err(format!(
                "`{item}` in its `// build:` line: letters, digits and _ only"
            ));
        }
        let defines = defines.iter().map(|d| d.to_string()).collect();
        builds.push((Some(module.to_owned()), defines));
    }
    if builds.is_empty() {
        return Err("its `// build:` line names no module".into());
    }
    Ok(builds)
}

fn main() {
    // Read at run time: a build-script binary may be shared between checkouts of the crate.
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let root = Path::new(&manifest).join("../shaders");
    let include_dir = root.join("include");
    println!("cargo:rerun-if-changed={}", root.display());
    println!("cargo:rerun-if-env-changed=GLSLANG_VALIDATOR");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&root)
        .expect("shaders/ exists next to engine/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "glsl"))
        .collect();
    files.sort();
    let quantities_dir = include_dir.join("quantities");
    for dir in [&root, &include_dir, &quantities_dir] {
        for e in std::fs::read_dir(dir)
            .expect("shader folder readable")
            .flatten()
        {
            println!("cargo:rerun-if-changed={}", e.path().display());
        }
    }
    let manifest = Path::new(&manifest);
    // The core (`core/`) and the Vulkan layer (`vk/`) are part of what the library computes:
    // their sources count too.
    let sources = [
        manifest.join("src"),
        manifest.join("build.rs"),
        manifest.join("build"),
        manifest.join("Cargo.toml"),
        manifest.join("../core/src"),
        manifest.join("../core/Cargo.toml"),
        manifest.join("../vk/src"),
        manifest.join("../vk/Cargo.toml"),
        manifest.join("../Cargo.lock"),
    ];
    for path in &sources {
        println!("cargo:rerun-if-changed={}", path.display());
    }
    let mut all = sources.to_vec();
    all.push(root.clone());
    println!(
        "cargo:rustc-env=SPECCHIO_BUILD_ID={:08x}",
        digest(manifest, &all)
    );
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let glslang = Glslang::new(&root, &out_dir).unwrap_or_else(|why| panic!("{why}"));
    // The shaders, this script, which compiles them, and the compiler's version.
    let compiled_from = [
        root.clone(),
        manifest.join("build.rs"),
        manifest.join("build"),
    ];
    let shaders = format!(
        "{:08x} {}",
        digest(manifest, &compiled_from),
        glslang.version
    );
    let done = out_dir.join("shaders.digest");
    if out_dir.join("shaders.rs").is_file()
        && std::fs::read_to_string(&done).ok() == Some(shaders.clone())
    {
        return;
    }
    // A build stopped while compiling must not leave the digest of shaders it did not write.
    let _ = std::fs::remove_file(&done);
    let names = quantities::find(&quantities_dir).unwrap_or_else(|why| panic!("{why}"));
    let generated = glslang.generated.join("sensor_quantities.glsl");
    std::fs::write(&generated, quantities::glsl(&names)).expect("OUT_DIR writable");
    let mut rust = compile(&glslang, &files, &include_dir);
    rust.push_str(&quantities::rust(&names));
    std::fs::write(out_dir.join("shaders.rs"), rust).expect("OUT_DIR writable");
    std::fs::write(done, shaders).expect("OUT_DIR writable");
}

/// CRC-32 of the files under `paths` (folders walked), each by its path relative to
/// `manifest` and its bytes, in path order.
fn digest(manifest: &Path, paths: &[PathBuf]) -> u32 {
    let mut files = Vec::new();
    let mut stack = paths.to_vec();
    while let Some(p) = stack.pop() {
        match std::fs::read_dir(&p) {
            Ok(entries) => stack.extend(entries.flatten().map(|e| e.path())),
            Err(_) if p.is_file() => files.push(p),
            Err(_) => {}
        }
    }
    files.sort();
    let mut hasher = crc32fast::Hasher::new();
    for f in files {
        let rel = f.strip_prefix(manifest).unwrap_or(&f);
        hasher.update(rel.to_string_lossy().as_bytes());
        hasher.update(&std::fs::read(&f).unwrap_or_default());
    }
    hasher.finalize()
}

/// Compiles every shader of `files` into the Rust module's text.
fn compile(glslang: &Glslang, files: &[PathBuf], include_dir: &Path) -> String {
    let mut generated = Generated::new();
    for file in files {
        generated.compile_file(glslang, file);
    }
    generated.fail_if_any();
    let mut out = generated.out;
    out.push_str(&shared_constants(&include_dir.join("shared.glsl")));
    out.push_str(&member_offsets(&generated.offsets));
    out
}

/// glslang's command-line compiler, with the options every shader is compiled with: Vulkan 1.3
/// (SPIR-V 1.6), includes from `shaders/include/` and the generated ones, run in `shaders/` so
/// that its messages name the file as `NAME.STAGE.glsl:LINE`.
struct Glslang {
    program: OsString,
    /// Its `--version` line, kept with the compiled shaders: another glslang compiles them again.
    version: String,
    shaders: PathBuf,
    scratch: PathBuf,
    /// Where the generated includes are written (`sensor_quantities.glsl`).
    generated: PathBuf,
}

impl Glslang {
    /// The compiler named by `GLSLANG_VALIDATOR`, else `glslangValidator` on the PATH; an
    /// error that says how to install it when it does not run.
    fn new(shaders: &Path, out_dir: &Path) -> Result<Self, String> {
        let program = std::env::var_os("GLSLANG_VALIDATOR").unwrap_or("glslangValidator".into());
        let output = Command::new(&program).arg("--version").output();
        let version = match output {
            Ok(o) if o.status.success() => String::from_utf8_lossy(&o.stdout)
                .lines()
                .next()
                .unwrap_or("")
                .trim()
                .to_owned(),
            Ok(o) => return Err(format!("{} --version failed: {}", program.to_string_lossy(), o.status)),
            Err(e) => {
                return Err(format!(
                    "cannot run glslang's compiler `{}` ({e}): the shaders are compiled with it; \
                     install it (Debian: `apt-get install glslang-tools`, which scripts/setup.sh does) \
                     or name it with GLSLANG_VALIDATOR=PATH",
                    program.to_string_lossy()
                ))
            }
        };
        let scratch = out_dir.join("spirv");
        let generated = out_dir.join("glsl");
        for dir in [&scratch, &generated] {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
        Ok(Self {
            program,
            version,
            shaders: shaders.to_owned(),
            scratch,
            generated,
        })
    }

    /// Compiles `shaders/NAME` as `stage` with `define` defined, into the SPIR-V words of
    /// `module`; glslang's messages when it fails.
    fn compile(
        &self,
        name: &str,
        stage: &str,
        define: &[String],
        module: &str,
    ) -> Result<Vec<u32>, String> {
        let spv = self.scratch.join(format!("{module}.{stage}.spv"));
        let output = Command::new(&self.program)
            .current_dir(&self.shaders)
            .args(["-V", "--target-env", "vulkan1.3", "-S", stage, "-Iinclude"])
            .arg(format!("-I{}", self.generated.display()))
            .args(define.iter().map(|d| format!("-D{d}")))
            .arg("-o")
            .arg(&spv)
            .arg(name)
            .output()
            .map_err(|e| format!("cannot run {}: {e}", self.program.to_string_lossy()))?;
        if !output.status.success() {
            return Err(format!(
                "{}{}",
                String::from_utf8_lossy(&output.stdout),
                String::from_utf8_lossy(&output.stderr)
            ));
        }
        let bytes = std::fs::read(&spv).map_err(|e| format!("{}: {e}", spv.display()))?;
        if bytes.len() % 4 != 0 || bytes.is_empty() {
            return Err(format!(
                "{}: {} bytes is no SPIR-V",
                spv.display(),
                bytes.len()
            ));
        }
        Ok(bytes
            .chunks_exact(4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
            .collect())
    }
}

/// What the compiled shaders add up to: the generated module so far, the member offsets
/// read back from every module, and every failure.
struct Generated {
    out: String,
    offsets: BTreeMap<(String, String), u32>,
    failures: Vec<String>,
}

impl Generated {
    /// The generated module's header, nothing compiled yet.
    fn new() -> Self {
        Self {
            out: String::from("// Generated by engine/build.rs from shaders/*.glsl.\n"),
            offsets: BTreeMap::new(),
            failures: Vec::new(),
        }
    }

    /// Compiles every module of the source file `file`.
    fn compile_file(&mut self, glslang: &Glslang, file: &Path) {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let Some(stage) = stage_of(&name) else {
            self.failures
                .push(format!("shaders/{name}: name must be NAME.STAGE.glsl"));
            return;
        };
        let text = std::fs::read_to_string(file).expect("shader readable");
        let builds = match variants(&text) {
            Ok(v) => v,
            Err(why) => {
                self.failures.push(format!("shaders/{name}: {why}"));
                return;
            }
        };
        for (module, define) in builds {
            let base = name.split('.').next().unwrap_or(&name);
            let module = module.unwrap_or_else(|| base.to_owned());
            let compiled = glslang.compile(&name, stage, &define, &module);
            let built = match define.is_empty() {
                false => format!("`shaders/{name}` with `{}` defined", define.join("`, `")),
                true => format!("`shaders/{name}`"),
            };
            match compiled {
                Ok(words) => self.add_module(&words, &module, stage, &built),
                // glslang names the file as it was given (run in shaders/): give its path and
                // the defines in front of the line number.
                Err(e) => {
                    let place = match define.is_empty() {
                        true => format!("shaders/{name}"),
                        false => format!("shaders/{name} (`{}` defined)", define.join("`, `")),
                    };
                    let named = e.replace(&format!("ERROR: {name}:"), &format!("ERROR: {place}:"));
                    self.failures.push(named)
                }
            }
        }
    }

    /// Adds the constant `MODULE_STAGE` holding `words`, and the member offsets they declare.
    fn add_module(&mut self, words: &[u32], module: &str, stage_name: &str, built: &str) {
        read_offsets(words, &mut self.offsets);
        let ident = format!("{module}_{stage_name}")
            .replace(['.', '-'], "_")
            .to_uppercase();
        let _ = writeln!(
            self.out,
            "/// SPIR-V of {built}.\npub const {ident}: &[u32] = &{words:?};"
        );
    }

    /// Fails the build with every failure, each one's first error line also as a warning.
    fn fail_if_any(&self) {
        if self.failures.is_empty() {
            return;
        }
        for f in &self.failures {
            println!(
                "cargo:warning={}",
                f.lines().find(|l| l.contains("ERROR")).unwrap_or(f)
            );
        }
        panic!("shader compilation failed:\n{}", self.failures.join("\n"));
    }
}

/// The constant `SPIRV_MEMBER_OFFSETS`: every (struct, member, byte offset) of `offsets`.
fn member_offsets(offsets: &BTreeMap<(String, String), u32>) -> String {
    let mut out = String::from("/// (struct, member, byte offset) as glslang laid them out.\npub const SPIRV_MEMBER_OFFSETS: &[(&str, &str, u32)] = &[\n");
    for ((s, m), o) in offsets {
        let _ = writeln!(out, "    ({s:?}, {m:?}, {o}),");
    }
    out.push_str("];\n");
    out
}

/// The integer `#define`s of shared.glsl as a Rust module `shared`: the constants the shaders
/// and the engine share are written once, in GLSL. Each gets the comment on its line or the
/// comment block right above it as its doc comment.
fn shared_constants(path: &Path) -> String {
    let text = std::fs::read_to_string(path).expect("shaders/include/shared.glsl readable");
    let mut out = String::from(
        "/// Integer constants `#define`d in `shaders/include/shared.glsl`, their one definition.\n\
         pub mod shared {\n",
    );
    let mut above: Vec<&str> = Vec::new();
    for line in text.lines().map(str::trim) {
        if let Some(comment) = line.strip_prefix("//") {
            above.push(comment.trim());
            continue;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        if let ["#define", name, value, rest @ ..] = words.as_slice() {
            let digits = value.trim_end_matches('u');
            if !digits.is_empty() && digits.chars().all(|c| c.is_ascii_digit()) {
                let trailing = rest.join(" ");
                let doc = match trailing.strip_prefix("//") {
                    Some(c) => c.trim().to_owned(),
                    None if !above.is_empty() => above.join(" "),
                    None => format!("`{name}` in shared.glsl."),
                };
                let _ = writeln!(out, "    /// {doc}\n    pub const {name}: u32 = {digits};");
                // A comment block above a run of defines describes each of them.
                continue;
            }
        }
        above.clear();
    }
    out.push_str("}\n");
    out
}

/// Collects struct member offsets (OpMemberDecorate Offset) by struct and member debug name.
fn read_offsets(words: &[u32], into: &mut BTreeMap<(String, String), u32>) {
    let mut names: BTreeMap<u32, String> = BTreeMap::new();
    let mut members: BTreeMap<(u32, u32), String> = BTreeMap::new();
    let mut decorated: Vec<(u32, u32, u32)> = Vec::new();
    let mut i = 5; // skip the header
    while i < words.len() {
        let count = (words[i] >> 16) as usize;
        let op = words[i] & 0xffff;
        if count == 0 || i + count > words.len() {
            break;
        }
        let ins = &words[i..i + count];
        match op {
            5 => {
                names.insert(ins[1], string(&ins[2..]));
            } // OpName
            6 => {
                members.insert((ins[1], ins[2]), string(&ins[3..]));
            } // OpMemberName
            72 if ins[3] == 35 => decorated.push((ins[1], ins[2], ins[4])), // MemberDecorate Offset
            _ => {}
        }
        i += count;
    }
    for (ty, member, offset) in decorated {
        if let (Some(s), Some(m)) = (names.get(&ty), members.get(&(ty, member))) {
            into.insert((s.clone(), m.clone()), offset);
        }
    }
}

fn string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .take_while(|&b| b != 0)
        .collect();
    String::from_utf8_lossy(&bytes).into_owned()
}
