//! What a caller gives and gets per frame: the renderer's options, what to read back, the
//! pixels read back, and the frame's timings and counters.

use serde::Serialize;

use crate::image::RgbaImage;
use crate::scene::RefreshPolicy;
use crate::vk::queries::PipelineStats;

use super::methods;

/// Renderer settings that are not part of the scene.
#[derive(Debug, Clone, Default)]
pub struct RenderOptions {
    /// Overrides the scene's `cube.face_size` (`--cube-size`).
    pub cube_size: Option<u32>,
    /// The option that set `cube_size`, as messages name it: `--cube-size` unless said
    /// (the benchmark's is `--cube-sizes`).
    pub cube_size_option: Option<&'static str>,
    /// How the cube is filled (the device must support it: see `Method::missing_features`).
    pub method: methods::Method,
    /// Under `on-change`, re-render only the faces a moved object touches (old or new bounds).
    /// Off: any change re-renders all six (the reference the incremental update is tested
    /// against).
    pub full_updates: bool,
    /// A dirty face re-renders whole instead of only its dirty rectangles (the pixels a
    /// moved object's old or new bounds project to). Multiview always re-renders all six
    /// faces, in the rectangles of every dirty face together.
    pub whole_faces: bool,
    /// Fill only the tiles of the cube the drawn views may read (`footprint.rs`): marked by
    /// a pass over the views before the fill whenever they or the mirror move, the rest left
    /// unfilled. A frame that reads the cube otherwise (its read-back, the ray map through
    /// it, a lookup that searches its depth) fills it all. The views' pixels are a full
    /// fill's.
    pub footprint: bool,
    /// With `footprint`: clear the whole cube to a colour no scene makes before its first
    /// fill, so that a tile the footprint missed would show in the views (the tests).
    pub footprint_poison: bool,
    /// How six-pass draws a face's dirty rectangles: the cheaper way by default (the
    /// one-scope methods draw them under one box).
    pub patching: methods::Patching,
    /// Replaces the scene's refresh policy (benchmarks force `every-frame`).
    pub refresh: Option<RefreshPolicy>,
    /// Replaces the mirror's lookup mode (`--lookup`).
    pub lookup: Option<crate::scene::Lookup>,
    /// Make the id cube (an R32_UINT attachment every fill writes, `targets::IdCube`): the
    /// sensor's ray map (`Readback::rays`) reads range and id through it and refuses to run
    /// without it. Off by default, so the benchmark's fills do not pay for it.
    pub id_cube: bool,
    /// The order the tracing lookups hand their acceleration-structure builds (`--trace-order`;
    /// `given` reproduces the scene's order, to measure what the split order gains).
    pub trace_order: super::lookups::TraceOrder,
    /// Where a tracing lookup walks its rays: in the mirror's fragment shaders, or once a view
    /// in a compute pass (`--trace-in`; None: the device's default, `TraceIn::default_for`).
    pub trace_in: Option<super::lookups::TraceIn>,
    /// How the bvh lookup lays out and walks its trees (`--bvh-layout`; None: the device's
    /// default, `lookups::default_bvh_layout`).
    pub bvh_layout: Option<crate::bvh::BvhLayout>,
    /// The lookup stays as given for the renderer's life: no switch in place, as the viewer's
    /// keys and the benchmark's accuracy rungs make. A lookup that samples no cube, with no id
    /// cube asked for, then has no cube: a stand-in of one texel a face is made for the
    /// bindings, so that a scene's large `cube.face_size` neither takes memory nor stops the
    /// run at the device's limits (`--lookup bvh` on a scene of 8192² faces was refused for
    /// a cube it never reads). A frame that would fill it is refused.
    pub lookup_fixed: bool,
    /// Frames the renderer may have submitted and not finished (`Renderer::submit_frame`),
    /// 1 to `MAX_FRAMES_IN_FLIGHT`; 0 counts as 1. With 1, each frame waits for the one
    /// before; the live viewer keeps 2, so that it records a frame while the GPU runs the last.
    pub frames_in_flight: usize,
}

/// What to copy back to the CPU after a frame.
#[derive(Debug, Clone, Copy, Default)]
pub struct Readback {
    pub cube: bool,
    /// Observer, sensor and the side-by-side pair, each drawn and read back.
    pub views: bool,
    /// The sensor's view alone (implied by `views`): a dataset's frame, where drawing the
    /// observer and the pair only to drop them cost a third of the frame's GPU work.
    pub sensor: bool,
    /// The lookup direction of every observer and sensor mirror pixel (for the angular
    /// error against the exact reference).
    pub directions: bool,
    /// The sensor's ray map: every per-pixel quantity, traced where the lookup traces, else
    /// through the cube (`sensor_rays.rs`; which needs `RenderOptions::id_cube`).
    pub rays: bool,
}

/// Pixels of one frame (those asked for by [`Readback`]).
#[derive(Debug, Clone, Default)]
pub struct FrameImages {
    /// Mip 0 of the six faces in layer order +X, -X, +Y, -Y, +Z, -Z.
    pub cube: Option<Vec<RgbaImage>>,
    pub observer: Option<RgbaImage>,
    pub sensor: Option<RgbaImage>,
    pub pair: Option<RgbaImage>,
    /// Per mirror pixel the unit direction looked up in the cube map (rgb) and alpha 1;
    /// all zero elsewhere.
    pub observer_direction: Option<RgbaImage>,
    pub sensor_direction: Option<RgbaImage>,
    /// The sensor's ray map: every per-pixel quantity (`sensor::quantities`, `sensor_rays.rs`),
    /// of which `SensorOutputs::from_gpu` makes the ray map, range and ids.
    pub sensor_quantities: Option<crate::sensor::quantities::QuantityImages>,
    /// A window's view as drawn, texel for texel (a display frame's, `display.rs`).
    pub display: Option<super::display::DisplayPixels>,
}

/// Timings (milliseconds) and counters of one frame.
#[derive(Debug, Clone, Default, Serialize)]
pub struct FrameReport {
    pub frame: u64,
    pub time_s: f64,
    pub cube_updated: bool,
    pub faces_rendered: u32,
    /// Bit f set: face f was re-rendered this frame.
    pub face_mask: u8,
    /// Texels re-rendered: the dirty faces' area, or their dirty rectangles' where the update
    /// had them.
    pub texels_rendered: u64,
    /// Texels of level 0 the footprint holds the views may read (`RenderOptions::footprint`;
    /// None without it).
    pub footprint_texels: Option<u64>,
    /// Host time of the footprint's marking pass, submitted and waited for before the frame
    /// is recorded (ms; 0 for a frame whose footprint was already marked; None without a
    /// footprint).
    pub cpu_footprint_ms: Option<f64>,
    /// Objects (walls included) drawn into each face; 0 for a face not re-rendered.
    pub draws_per_face: [u32; 6],
    pub cpu_record_ms: f64,
    /// Host time of the lookup's own per-frame work before recording (the bvh lookup's
    /// top-level rebuild; part of `cpu_record_ms`).
    pub cpu_lookup_ms: f64,
    /// Submit to fence signalled (the whole frame's GPU work, readback copies included).
    pub submit_wait_ms: f64,
    /// GPU time per cube face (six-pass only), the fill, the fill plus mips, the mips, and
    /// each view (None without timestamps).
    pub gpu_face_ms: Option<[f64; 6]>,
    pub gpu_fill_ms: Option<f64>,
    pub gpu_cube_ms: Option<f64>,
    pub gpu_mips_ms: Option<f64>,
    pub gpu_observer_ms: Option<f64>,
    pub gpu_sensor_ms: Option<f64>,
    pub gpu_pair_ms: Option<f64>,
    /// Pipeline statistics of the whole fill, and per face for six-pass (None without the
    /// feature or when the cube was not updated).
    pub fill_stats: Option<PipelineStats>,
    pub face_stats: Option<[PipelineStats; 6]>,
    /// Observer, sensor, pair: each view's where it was drawn (a frame that draws the sensor
    /// alone has only the sensor's).
    pub view_stats: Option<[Option<PipelineStats>; 3]>,
    /// The lookup's traced rays among the observer's and sensor's mirror fragments (only
    /// `distance-exact`, which traces the rays its search cannot resolve).
    pub traced_rays: Option<crate::render::lookups::FrameTally>,
}

/// Running totals for the refresh policy (tested: `on-change` skips static frames).
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct RefreshCounters {
    pub frames: u64,
    pub cube_updates: u64,
    pub cube_skips: u64,
    /// Faces re-rendered over all frames (6 per full update).
    pub faces_rendered: u64,
}
