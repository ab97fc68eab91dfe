//! Mirror lookups as plug-ins: how the mirror's fragment shader turns the reflected pixel-centre
//! ray into a colour. Each states what it needs from the device as data ([`LookupNeeds`]:
//! device creation, `specchio info`, `--lookup` and the tests read it), whether it reads the
//! cube map (a lookup that does not skips the cube fill), and builds its per-renderer pass
//! ([`LookupPass`]: its mirror pipelines, the descriptor set they read at set 1, and any
//! per-frame work of its own).
//!
//! The scene file names a lookup ([`Lookup`]); everything else about it lives in its module
//! here: what it needs, the direction its shader starts from ([`Start`], the one choice the
//! shared shader code makes), its shaders, its pass and its rungs in the benchmark's ladder
//! ([`Rung`]). Adding a lookup is its module and shaders and one entry in the registry
//! ([`crate::lookup_registry`]), which makes both the scene's `Lookup` and [`REGISTRY`];
//! nothing in the scene, `shared.glsl`, the benchmark or the CLI.

mod bvh;
mod cube;
mod distance;
mod distance_exact;
mod pretrace;
mod ray_query;
mod tally;
mod tracing;

pub use crate::bvh::Work;
pub use bvh::default_layout as default_bvh_layout;
pub use pretrace::TraceIn;
pub use tally::{FrameTally, TracedRays};
pub use tracing::TraceOrder;

use std::sync::Arc;

use ash::vk;
use glam::Vec3;

use super::gpu::ObjectData;
use super::graph::{PassRecorder, Resource, Use};
use super::resources::SceneResources;
use super::targets::CubeTarget;
use crate::render::pipelines::mirror_pipeline;
use crate::render::targets::{DIRECTION_FORMAT, VIEW_FORMAT};
use crate::scene::Lookup;
use crate::vk::commands::Submitter;
use crate::vk::device::{Device, DeviceInfo, OptionalFeatures};
use crate::vk::pipeline::{Pipeline, PipelineLayout};
use crate::vk::uploads::FrameUploads;
use crate::vk::GpuError;

/// Makes [`REGISTRY`] from the registry's entries: each lookup with its plug-in.
macro_rules! plugin_table {
    ($( $(#[$doc:meta])* $variant:ident = $name:literal => $plugin:path; )*) => {
        /// Every lookup's plug-in, in [`Lookup::ALL`]'s order.
        static REGISTRY: &[(Lookup, &dyn MirrorLookup)] = &[$((Lookup::$variant, &$plugin)),*];
    };
}

crate::lookup_registry::with_lookups!(plugin_table);

/// One mirror lookup: what it is, what it needs, and how it makes its per-renderer pass.
pub trait MirrorLookup: Sync {
    /// One line saying what the mirror shows and when it is exact (CLI help, `info`, docs).
    fn summary(&self) -> &'static str;
    /// What the device must have.
    fn needs(&self) -> LookupNeeds {
        LookupNeeds::default()
    }
    /// Whether the mirror samples the cube map. When not, the renderer skips the cube fill
    /// (unless the cube itself is read back).
    fn uses_cube(&self) -> bool;
    /// Whether every read of the cube is a sample of the footprint filter
    /// (`footprint_filter.glsl`) from `mirror.glsl`'s lookup, which the footprint pass runs
    /// to mark what the views read (`RenderOptions::footprint`): the cube lookups. A depth
    /// search reads wherever its search goes.
    fn marks_footprint(&self) -> bool {
        false
    }
    /// Whether it searches the cube's depth, so that `mirror.distance_steps` and
    /// `mirror.secant_steps` (`render --distance-steps`, `--secant-steps`) change it.
    fn searches_depth(&self) -> bool {
        false
    }
    /// Whether it builds acceleration structures over the scene (`tracing::SceneTrace`), so
    /// that `RenderOptions::trace_order` (`render --trace-order`) changes it.
    fn builds_scene_trace(&self) -> bool {
        false
    }
    /// Whether its pass traces the sensor's ray map through its own set
    /// ([`LookupPass::trace_set`]): the range and ids then follow the colour's own light path,
    /// and the renderer needs no id cube for them. The renderer checks that the pass agrees.
    fn traces_ray_map(&self) -> bool {
        false
    }
    /// For a lookup that traces the ray map: how it ranks as the ground truth's default on
    /// `device`, lower first ([`one_light_path`]). Each says why from its own measurements.
    fn ground_truth_rank(&self, _device: &DeviceInfo) -> u32 {
        u32::MAX
    }
    /// Why it cannot hold `scene` on `device`, where that is known before anything is built
    /// (None: nothing known against it). A default choice passes over such a lookup.
    fn cannot_hold(&self, _scene: &crate::scene::Scene, _device: &DeviceInfo) -> Option<String> {
        None
    }
    /// The cube-map direction its shader starts from (`FrameData.flags.y`).
    fn start(&self) -> Start;
    /// Its rungs in the benchmark's ladder: the settings it is measured at.
    fn rungs(&self) -> &'static [Rung];
    /// Builds the lookup's mirror pipelines and state for one renderer.
    fn create(&self, ctx: &LookupContext<'_>) -> Result<Box<dyn LookupPass>, GpuError>;
    /// The work its sensor frame's trace does at `t_s` with the trees laid out as `layout`,
    /// counted on the CPU (exact and the same on every device: the benchmark records it).
    /// None for a lookup with no count of its own.
    fn sensor_work(
        &self,
        _scene: &crate::scene::Scene,
        _t_s: f64,
        _layout: crate::bvh::BvhLayout,
    ) -> Option<Result<Work, String>> {
        None
    }
}

/// The cube-map direction a lookup starts from: what `mirror.glsl`'s `lookup_at` returns
/// for it. The only per-lookup choice the shared shader code makes; the rest of a lookup's
/// technique is its own shader.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Start {
    /// The reflected direction itself (the thesis's plain lookup; a lookup that reads no
    /// cube has this too, unused).
    Reflection,
    /// From the cube's centre to where the reflected ray leaves the room's box (the box
    /// lookup; the distance searches' footprint and their answer where they find nothing).
    RoomBox,
}

impl Start {
    /// Its `LOOKUP_FROM_*` code in `FrameData.flags.y`.
    pub fn code(self) -> u32 {
        match self {
            Start::Reflection => super::gpu::LOOKUP_FROM_REFLECTION,
            Start::RoomBox => super::gpu::LOOKUP_FROM_ROOM_BOX,
        }
    }
}

/// One rung of the benchmark's trade-off ladder (`specchio bench`): a lookup with the
/// settings it is measured at. Each lookup lists its own ([`MirrorLookup::rungs`]); the
/// ladder is all of them in their `order` ([`ladder`]).
pub struct Rung {
    /// Unique in the ladder; names the rung in `--rungs`, the table, the record and the plot.
    pub label: &'static str,
    pub lookup: Lookup,
    /// Its place in the ladder, from the thesis's lookup (0) towards the exact one.
    pub order: u8,
    /// Sets whatever else the rung needs in the scene (the lookup itself is set for it).
    pub configure: fn(&mut crate::scene::Scene),
    /// Fills only the cube's tiles its sensor reads (`RenderOptions::footprint`; the ladder's
    /// timed frames draw the sensor alone): its lookup's rung's images, at the footprint's
    /// cost.
    pub footprint: bool,
}

/// A rung that needs nothing beyond its lookup.
pub fn as_is(_: &mut crate::scene::Scene) {}

/// The ladder: every lookup's rungs, in their order.
pub fn ladder() -> Vec<&'static Rung> {
    let mut all: Vec<&'static Rung> = REGISTRY.iter().flat_map(|(_, l)| l.rungs()).collect();
    all.sort_by_key(|r| r.order);
    all
}

/// What a lookup needs from the device, as data.
#[derive(Debug, Clone, Copy, Default)]
pub struct LookupNeeds {
    /// Optional features (and their extensions) device creation must enable.
    pub features: OptionalFeatures,
}

/// What a lookup's pass is built from.
pub struct LookupContext<'a> {
    /// The lookup being built (for its messages).
    pub lookup: Lookup,
    /// The scene being rendered (its meshes and room, for a lookup that builds from them).
    pub scene: &'a crate::scene::Scene,
    pub device: &'a Arc<Device>,
    pub resources: &'a SceneResources,
    /// The cube map (colour and depth) the cube lookups read.
    pub cube: &'a CubeTarget,
    /// For the lookup's own one-off GPU work (building acceleration structures).
    pub submitter: &'a Submitter,
    /// Push-constant bytes of the mirror's shaders (`gpu::Push`).
    pub push_size: u32,
    /// The order the tracing lookups hand their builds (`RenderOptions::trace_order`).
    pub trace_order: TraceOrder,
    /// The renderer's frames in flight: what the host reads back per frame needs one copy
    /// per frame (`tally.rs`).
    pub frames_in_flight: usize,
    /// Where a tracing lookup walks its rays (`RenderOptions::trace_in`, else the device's
    /// default).
    pub trace_in: TraceIn,
    /// How the bvh lookup lays out and walks its trees (`RenderOptions::bvh_layout`, else the
    /// device's default).
    pub bvh_layout: crate::bvh::BvhLayout,
}

/// A lookup's per-renderer state: the pipelines that draw the mirror. `Send`: a renderer may
/// move to another thread (the Python package renders with the GIL released).
pub trait LookupPass: Send {
    /// The lookup's two mirror pipelines and their layout.
    fn pipelines(&self) -> &MirrorPipelines;
    /// The colour pipeline (`directions` false) or the one writing the direction each mirror
    /// pixel sees (the angular error's input).
    fn pipeline(&self, directions: bool) -> &Pipeline {
        let p = self.pipelines();
        if directions {
            &p.directions
        } else {
            &p.colour
        }
    }
    /// Their layout: the scene set at 0, [`LookupPass::set`] at 1.
    fn layout(&self) -> &PipelineLayout {
        &self.pipelines().layout
    }
    /// The descriptor set the pipelines read at set 1.
    fn set(&self) -> vk::DescriptorSet;
    /// A lookup that traces the scene with nothing else at set 1: that set and the ray-map
    /// shaders that trace through it, so that the sensor's range and ids come from the
    /// colour's own light path.
    fn trace_set(&self) -> Option<TraceSet> {
        None
    }
    /// Before the frame is recorded: per-frame data of the lookup's own, from this frame's
    /// drawables, written to its device buffers through the frame's `uploads`. Most lookups
    /// have none. Its host time is the frame's `cpu_lookup_ms`.
    fn prepare(
        &mut self,
        _uploads: &mut FrameUploads,
        _frame: &FrameObjects<'_>,
    ) -> Result<(), GpuError> {
        Ok(())
    }
    /// The buffers the lookup's own passes use ([`LookupPass::record`],
    /// [`LookupPass::record_after_views`]) when frame slot `slot` is recorded, and how each
    /// rests between frames: the frame graph tracks them from the frame's start.
    fn resources(&self, _slot: usize) -> Vec<(Resource, Use)> {
        Vec::new()
    }
    /// Records the lookup's per-frame GPU work before the views, each command after the
    /// uses it needs are declared to `pass` (the graph makes it visible to the fragment
    /// shaders that declare nothing: declare the shaders' use last). Most lookups have none.
    /// A frame that records this records [`LookupPass::record_after_views`] too (both are
    /// skipped together, in a floor's frame): what the views' shaders wrote is declared read
    /// there, and the next frame's barriers start from that.
    fn record(&self, _pass: &mut PassRecorder<'_>) {}
    /// Whether the views' mirror passes read records a compute pass traced
    /// ([`LookupPass::pretrace`]) rather than tracing themselves.
    fn pretraces(&self) -> bool {
        false
    }
    /// How the lookup's trees are laid out, for a lookup that walks trees of its own (bvh).
    fn bvh_layout(&self) -> Option<crate::bvh::BvhLayout> {
        None
    }
    /// A pretraced lookup's walk of camera view `view` into its records, before the first
    /// pass that draws the view; the scene set is set 0. Lookups that do not pretrace record
    /// nothing.
    fn pretrace(&self, _pass: &mut PassRecorder<'_>, _scene_set: vk::DescriptorSet, _view: u32) {}
    /// Records what follows the frame's views: results copied for the host into the copy of
    /// frame slot `slot` (one of `LookupContext::frames_in_flight`).
    fn record_after_views(&self, _pass: &mut PassRecorder<'_>, _slot: usize) {}
    /// After the fence of slot `slot`'s frame: how many mirror rays the lookup traced (None:
    /// it traces all or none, so there is nothing to count).
    fn tally(&self, _slot: usize) -> Result<Option<FrameTally>, GpuError> {
        Ok(None)
    }
}

/// A frame's drawables as a lookup's [`LookupPass::prepare`] reads them.
pub struct FrameObjects<'a> {
    /// Their transforms and materials at the frame's time, walls first.
    pub objects: &'a [ObjectData],
    /// Their render-space bounds.
    pub bounds: &'a [(Vec3, Vec3)],
    /// The scene's refresh policy renews everything every frame (`every-frame`, as the
    /// benchmark's ladder measures a frame in which something moved): a lookup that keeps
    /// per-frame work for frames where something moved does it now too.
    pub every_frame: bool,
}

/// A tracing lookup's set 1, which the sensor's ray-map pass binds too, and that pass's
/// shaders (`mirror_ray.frag.glsl` built with `TRACED` and the lookup's tracer).
#[derive(Debug, Clone, Copy)]
pub struct TraceSet {
    pub layout: vk::DescriptorSetLayout,
    pub set: vk::DescriptorSet,
    /// The ray map's pass, which writes every quantity from one trace.
    pub ray_map: &'static [u32],
}

/// The two pipelines every lookup draws the mirror with: one writing colour, one writing the
/// direction each mirror pixel sees. Both read the scene set at 0 and the lookup's own set at
/// 1. Field order is drop order: pipelines before their layout.
pub struct MirrorPipelines {
    colour: Pipeline,
    directions: Pipeline,
    layout: PipelineLayout,
}

/// A lookup's two fragment shaders (`shaders/mirror_*.frag.glsl`).
pub(super) struct MirrorShaders {
    pub colour: &'static [u32],
    pub directions: &'static [u32],
}

impl MirrorPipelines {
    /// The layout over the scene set and `set_layout`, and both pipelines on it; `name`
    /// prefixes their debug names.
    fn create(
        ctx: &LookupContext<'_>,
        set_layout: vk::DescriptorSetLayout,
        shaders: MirrorShaders,
        name: &str,
    ) -> Result<Self, GpuError> {
        let device = ctx.device;
        let layout = PipelineLayout::create(
            device,
            &[ctx.resources.scene_set_layout.raw, set_layout],
            ctx.push_size,
            &format!("{name} layout"),
        )?;
        let colour = mirror_pipeline(
            device,
            &layout,
            shaders.colour,
            &[VIEW_FORMAT],
            &format!("{name} pipeline"),
        )?;
        let directions = mirror_pipeline(
            device,
            &layout,
            shaders.directions,
            &[DIRECTION_FORMAT],
            &format!("{name} direction pipeline"),
        )?;
        Ok(Self {
            colour,
            directions,
            layout,
        })
    }
}

/// The plug-in of `lookup`.
pub fn plugin(lookup: Lookup) -> &'static dyn MirrorLookup {
    // The registry makes both, in one order.
    REGISTRY[lookup as usize].1
}

/// Whether `lookup` traces the sensor's ray map itself ([`MirrorLookup::traces_ray_map`]):
/// a renderer for it needs no id cube.
pub fn traces_ray_map(lookup: Lookup) -> bool {
    plugin(lookup).traces_ray_map()
}

/// Whether a renderer of `lookup` needs a cube map: the lookup samples one, or the sensor's
/// ray map reads range and ids through the id cube (`id_cube`). Else a renderer whose lookup
/// stays fixed (`RenderOptions::lookup_fixed`) makes none.
pub fn needs_cube(lookup: Lookup, id_cube: bool) -> bool {
    plugin(lookup).uses_cube() || id_cube
}

/// The lookup that traces colour, range and ids along one light path on the device, the
/// sensor outputs' and datasets' default: of those it runs, the best ranked
/// ([`MirrorLookup::ground_truth_rank`]): `bvh` on a CPU driver, where it measured cheaper
/// than lavapipe's ray queries on every benchmark scene, and wherever there are no ray
/// queries; `ray-query` on a GPU that has them (ray-tracing hardware, presumably faster:
/// not measured here).
pub fn one_light_path(info: &DeviceInfo, scene: &crate::scene::Scene) -> Option<Lookup> {
    let runs = |&l: &Lookup| traces_ray_map(l) && missing_features(l, info).is_none();
    let ranked = |l: &Lookup| plugin(*l).ground_truth_rank(info);
    // Of those that can hold the scene (bvh's trees fit one storage buffer of a bounded
    // range: about 2.8 M triangles on the CPU drivers), else the best anyway, to say why not.
    let holds = |&l: &Lookup| plugin(l).cannot_hold(scene, info).is_none();
    let candidates = || Lookup::ALL.into_iter().filter(runs);
    candidates()
        .filter(holds)
        .min_by_key(ranked)
        .or_else(|| candidates().min_by_key(ranked))
}

/// Why the device cannot run `lookup` (None: it can).
pub fn missing_features(lookup: Lookup, info: &DeviceInfo) -> Option<String> {
    let lacks = plugin(lookup).needs().features.missing(&info.features);
    (!lacks.is_empty()).then(|| format!("the device lacks {}", lacks.join(", ")))
}

/// The optional device features `lookup` needs enabled.
pub fn features(lookup: Lookup) -> OptionalFeatures {
    plugin(lookup).needs().features
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact default by device: bvh on a CPU driver with or without ray queries (lavapipe,
    /// SwiftShader) and on a GPU without them (the H200 of docs/gpu.md), ray-query on a GPU
    /// with them. The devices are lavapipe's record in the committed baseline, retyped.
    #[test]
    fn the_exact_default_is_bvh_but_on_a_gpu_with_ray_queries() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let scene = crate::scene::load(&root.join("scenes/thesis-room.toml")).unwrap();
        let baseline = include_str!("../../../../bench/baselines/quick.json");
        let record: serde_json::Value = serde_json::from_str(baseline).unwrap();
        let device = |device_type: &str, ray_query: bool| -> DeviceInfo {
            let mut d = record["device"].clone();
            d["device_type"] = device_type.into();
            d["features"]["ray_query"] = ray_query.into();
            let mut info: DeviceInfo = serde_json::from_value(d).unwrap();
            // The record leaves it out; the specification's least, lavapipe's and SwiftShader's.
            info.limits.max_storage_buffer_range = 1 << 27;
            info
        };
        for (kind, ray_query, want) in [
            ("CPU", true, Lookup::Bvh),
            ("CPU", false, Lookup::Bvh),
            ("DISCRETE_GPU", false, Lookup::Bvh),
            ("DISCRETE_GPU", true, Lookup::RayQuery),
            ("INTEGRATED_GPU", true, Lookup::RayQuery),
        ] {
            let got = one_light_path(&device(kind, ray_query), &scene);
            assert_eq!(got, Some(want), "{kind}, ray queries {ray_query}");
        }
        // A device whose storage buffers hold fewer triangles than the scene's: bvh is passed
        // over for ray-query where the device has ray queries, and kept (to say why) where not.
        let mut small = device("CPU", true);
        small.limits.max_storage_buffer_range = 48;
        assert!(plugin(Lookup::Bvh).cannot_hold(&scene, &small).is_some());
        assert_eq!(one_light_path(&small, &scene), Some(Lookup::RayQuery));
        small.features.ray_query = false;
        assert_eq!(one_light_path(&small, &scene), Some(Lookup::Bvh));
    }

    #[test]
    fn the_registry_makes_one_lookup_per_plugin_in_order() {
        assert_eq!(REGISTRY.len(), Lookup::ALL.len());
        for (i, ((l, _), all)) in REGISTRY.iter().zip(Lookup::ALL).enumerate() {
            assert_eq!(*l, all);
            assert_eq!(*l as usize, i, "plugin() indexes the table by the variant");
            assert_eq!(Lookup::parse(l.name()), Some(*l));
            assert!(l
                .name()
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-'));
            // Reports write the lookup through serde: the same name, and it reads back.
            assert_eq!(serde_json::to_value(l).unwrap(), l.name());
            let back: Lookup = serde_json::from_value(serde_json::json!(l.name())).unwrap();
            assert_eq!(back, *l);
        }
        assert_eq!(
            Lookup::default(),
            Lookup::Plain,
            "the thesis's lookup is the default"
        );
    }

    /// Every registered lookup is accepted by the scene format under its own name.
    #[test]
    fn scene_files_accept_every_registered_lookup() {
        let base = include_str!("../../../../scenes/test/six-colour-room.toml");
        for l in Lookup::ALL {
            let text = with_lookup(base, l.name());
            let scene = crate::scene::load_str(&text, std::path::Path::new("lookup.toml"))
                .unwrap_or_else(|e| panic!("lookup = \"{l}\": {e}"));
            assert_eq!(scene.mirror.lookup, l);
        }
    }

    /// `text` with `lookup = "name"` in its `[mirror]` table (replacing any lookup there).
    fn with_lookup(text: &str, name: &str) -> String {
        let mut out = String::new();
        for line in text.lines() {
            if line.trim_start().starts_with("lookup") {
                continue;
            }
            out.push_str(line);
            out.push('\n');
            if line.trim() == "[mirror]" {
                out.push_str(&format!("lookup = \"{name}\"\n"));
            }
        }
        out
    }

    /// docs/accuracy.md has a row for every lookup and README names each.
    #[test]
    fn the_docs_cover_the_registry() {
        let accuracy = include_str!("../../../../docs/accuracy.md");
        let readme = include_str!("../../../../README.md");
        let format = include_str!("../../../../docs/scene-format.md");
        for l in Lookup::ALL {
            let row = format!("| `{}` |", l.name());
            assert!(
                accuracy.contains(&row),
                "docs/accuracy.md has no row for {l}"
            );
            let named = format!("`{}`", l.name());
            assert!(readme.contains(&named), "README never names `{l}`");
            assert!(
                format.contains(&named) || format.contains(&format!("\"{}\"", l.name())),
                "docs/scene-format.md never names {l}"
            );
        }
    }
}
