//! Cube fill methods as plug-ins. Each fills the dirty faces of a [`CubePlan`] into the cube's
//! mip 0, and every one must give the same pixels as six-pass, bit for bit (tested on every
//! installed driver).
//!
//! A method is one module beside this file with a type implementing [`FillMethod`]: it states
//! what it needs from the device as data ([`Needs`]: device creation, `specchio info`, the
//! CLI's `--method` and the tests all read it), how it addresses the cube ([`CubeLayout`]),
//! and builds its per-renderer state ([`FillPass`]: its pipeline, its buffers), which records
//! through the narrow [`CubeRecorder`]. Adding a method is that module, its shaders, and one
//! line in [`REGISTRY`]; everything that lists methods iterates the registry.

mod geometry;
mod instanced;
mod mesh;
mod multiview;
mod plan;
mod recorder;
mod six_pass;

use crate::vk::device::{DeviceInfo, Limit, OptionalFeatures};
use crate::vk::GpuError;

pub use multiview::{view_mask_leak, ViewMaskLeak};
pub use plan::{CubePlan, Patch, Patching};
pub(in crate::render) use recorder::FillParts;
pub use recorder::{CubeRecorder, MethodContext, Prepare};

/// Every cube fill method, in the order the CLI, `specchio info`, the docs and the benchmark
/// list them. Six-pass comes first: it is the reference the others are compared with.
static REGISTRY: &[&dyn FillMethod] = &[
    &six_pass::SixPass,
    &multiview::Multiview,
    &geometry::Geometry,
    &geometry::GeometryInvocations,
    &instanced::Instanced,
    &mesh::MeshShader,
    &mesh::MeshShaderWide,
];

/// One cube fill method: what it is, what it needs, and how it makes its per-renderer pass.
pub trait FillMethod: Sync {
    /// The name on the command line and in every report (kebab-case).
    fn name(&self) -> &'static str;
    /// One line saying how a triangle reaches its face (CLI help, `info`, docs).
    fn summary(&self) -> &'static str;
    /// `Some(method)`: a variant of another method kept for measurement; it runs only when
    /// named (never in `--method all` or the benchmark's default set).
    fn variant_of(&self) -> Option<&'static str> {
        None
    }
    /// What the device must have.
    fn needs(&self) -> Needs;
    /// How the method's pass(es) address the cube's faces.
    fn layout(&self) -> CubeLayout;
    /// Builds the method's pipeline and state for one renderer.
    fn create(&self, ctx: &MethodContext<'_>) -> Result<Box<dyn FillPass>, GpuError>;
}

/// A method's per-renderer state: its pipeline(s) and buffers. `Send`: a renderer may move
/// to another thread (the Python package renders with the GIL released).
pub trait FillPass: Send {
    /// Before recording a cube update: per-update data of the method's own (indirect
    /// commands, say). Most methods need none.
    fn prepare(&mut self, _plan: &CubePlan, _ctx: &mut Prepare<'_>) -> Result<(), GpuError> {
        Ok(())
    }
    /// Records the fill of `plan`'s dirty faces into mip 0 (the caller set the layouts and
    /// rebuilds the mips afterwards).
    fn record(&self, rec: &CubeRecorder<'_>, plan: &CubePlan);
}

/// What a method needs from the device, as data.
#[derive(Debug, Clone, Copy, Default)]
pub struct Needs {
    /// Optional features device creation must enable.
    pub features: OptionalFeatures,
    /// Minimum values of device limits.
    pub limits: &'static [(Limit, u32)],
    /// The method must first render a small cube in a child process and match six-pass bit
    /// for bit (`specchio probe`): drivers have crashed or drawn wrongly with valid usage.
    pub probe: bool,
}

/// How a method's pass(es) address the cube.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CubeLayout {
    /// One rendering scope per dirty face, on a single-layer view of that face. Each face gets
    /// its own statistics query and timestamp.
    PerFace,
    /// One rendering scope over a six-layer view; the shaders pick each primitive's face
    /// (`gl_Layer`). A partial update clears only the dirty layers' dirty rectangles and
    /// draws under one scissor, their union over the faces.
    Layered,
    /// One multiview scope with view mask `0x3F`; the driver replays each draw per view. A
    /// pipeline's view mask is fixed and a clear reaches every view, so every update
    /// re-renders all six faces, whole or in the same rectangles.
    Multiview,
}

impl CubeLayout {
    /// Multiview view mask of the method's pipeline and rendering scope (0: none).
    pub fn view_mask(self) -> u32 {
        match self {
            CubeLayout::Multiview => 0x3F,
            CubeLayout::PerFace | CubeLayout::Layered => 0,
        }
    }
}

/// A cube fill method: a cheap, copyable handle to its registry entry (compared, hashed and
/// written by name).
#[derive(Clone, Copy)]
pub struct Method(&'static dyn FillMethod);

impl Method {
    /// The thesis's method and the reference every other method must match.
    pub const SIX_PASS: Method = Method(&six_pass::SixPass);

    /// Every registered method, variants included.
    pub fn all() -> impl Iterator<Item = Method> {
        REGISTRY.iter().map(|&m| Method(m))
    }

    /// The methods `--method all` and the benchmark run by default (variants left out).
    pub fn listed() -> impl Iterator<Item = Method> {
        Self::all().filter(|m| m.0.variant_of().is_none())
    }

    pub fn parse(name: &str) -> Option<Method> {
        Self::all().find(|m| m.name() == name)
    }

    /// Every registered name, comma-separated (for error messages and help).
    pub fn names() -> String {
        Self::all().map(Method::name).collect::<Vec<_>>().join(", ")
    }

    pub fn name(self) -> &'static str {
        self.0.name()
    }

    pub fn summary(self) -> &'static str {
        self.0.summary()
    }

    pub fn variant_of(self) -> Option<&'static str> {
        self.0.variant_of()
    }

    pub fn needs(self) -> Needs {
        self.0.needs()
    }

    pub fn layout(self) -> CubeLayout {
        self.0.layout()
    }

    pub(crate) fn create(self, ctx: &MethodContext<'_>) -> Result<Box<dyn FillPass>, GpuError> {
        self.0.create(ctx)
    }

    /// Why the device cannot run this method by its features and limits (None: it can, as
    /// far as those go; a method that `needs().probe` must also pass its probe).
    pub fn missing_features(self, info: &DeviceInfo) -> Option<String> {
        let needs = self.needs();
        let lacks = needs.features.missing(&info.features);
        if !lacks.is_empty() {
            return Some(format!("the device lacks {}", lacks.join(", ")));
        }
        needs.limits.iter().find_map(|&(limit, min)| {
            let have = limit.value(&info.limits);
            (have < min).then(|| format!("{} is {have}, {min} are needed", limit.name()))
        })
    }

    /// The optional device features this method needs enabled.
    pub fn features(self) -> OptionalFeatures {
        self.needs().features
    }
}

impl Default for Method {
    fn default() -> Self {
        Method::SIX_PASS
    }
}

impl PartialEq for Method {
    fn eq(&self, other: &Self) -> bool {
        self.name() == other.name()
    }
}

impl Eq for Method {}

impl std::hash::Hash for Method {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.name().hash(state);
    }
}

impl std::fmt::Debug for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl serde::Serialize for Method {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// Read back by name (benchmark records); an unknown name is an error listing the known ones.
impl<'de> serde::Deserialize<'de> for Method {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        Method::parse(&name).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "unknown method `{name}`, expected one of {}",
                Method::names()
            ))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_names_are_unique_kebab_case_and_six_pass_is_first() {
        let names: Vec<&str> = Method::all().map(Method::name).collect();
        assert_eq!(names[0], "six-pass");
        for (i, n) in names.iter().enumerate() {
            assert!(!names[..i].contains(n), "{n} registered twice");
            assert!(
                n.chars()
                    .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-'),
                "{n} is not kebab-case"
            );
        }
        for m in Method::all() {
            if let Some(of) = m.variant_of() {
                assert!(
                    Method::parse(of).is_some(),
                    "{m} is a variant of unknown {of}"
                );
            }
            assert_eq!(Method::parse(m.name()), Some(m));
        }
    }

    /// docs/methods.md documents every registered method: a table row for each listed one,
    /// and each variant by name.
    #[test]
    fn the_methods_doc_covers_the_registry() {
        let doc = include_str!("../../../../docs/methods.md");
        for m in Method::all() {
            let row = format!("| `{}` |", m.name());
            let named = format!("`{}`", m.name());
            match m.variant_of() {
                None => assert!(doc.contains(&row), "docs/methods.md has no row for {m}"),
                Some(_) => assert!(doc.contains(&named), "docs/methods.md never names {m}"),
            }
        }
    }
}
