//! The JSON the other commands write, as typed structs (the benchmark's own record is
//! `bench::record`): `render.json`, `reference.json`, `compare --json`, `info --json` and the
//! probe's line. Keys are struct fields, so the writer and anything that reads a value back
//! (the render summary's printout) cannot disagree on a name. docs/outputs.md and
//! docs/accuracy.md list the keys.

use serde::Serialize;
use specchio::reference::ReferenceStats;
use specchio::render::methods::Method;
use specchio::render::{FrameReport, RefreshCounters};
use specchio::scene::Lookup;
use specchio::vk::device::DeviceInfo;

/// A method a command did not run, and why.
#[derive(Debug, Serialize)]
pub struct NotRun {
    pub method: Method,
    pub reason: String,
}

/// `render.json`.
#[derive(Debug, Serialize)]
pub struct RenderRecord {
    pub scene: String,
    pub description: String,
    /// World position of the mirror's centre at time 0: everything is rendered relative to it.
    pub origin: [f64; 3],
    pub settings: RenderSettings,
    pub device: DeviceInfo,
    pub methods_not_run: Vec<NotRun>,
    pub runs: Vec<RenderRun>,
    /// Messages the validation layer reported (any fails the command).
    pub validation_messages: usize,
}

#[derive(Debug, Serialize)]
pub struct RenderSettings {
    pub start_time_s: f64,
    pub fps: f64,
    pub frames: u32,
    /// The fill methods run: none where the renderer made no cube (a lookup that samples
    /// none).
    pub methods: Vec<Method>,
    pub full_updates: bool,
    pub whole_faces: bool,
    /// `--footprint`: only the tiles the views read were filled (each frame's
    /// `footprint_texels`, `cpu_footprint_ms`), and the cube was not written.
    pub footprint: bool,
    pub lookup: Lookup,
    /// The order the tracing lookups handed their acceleration-structure builds (`split` or
    /// `given`; only they read it).
    /// The order of the acceleration-structure builds; null for a lookup that builds none.
    pub trace_order: Option<&'static str>,
    /// `--trace-in` as given (each run says where it walked: `runs[].trace_in`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trace_in: Option<&'static str>,
    /// `--bvh-layout` as given (each run says which it walked: `runs[].bvh_layout`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bvh_layout: Option<&'static str>,
    /// The distance lookup's search steps (used only by it).
    pub distance_steps: u32,
    pub secant_steps: u32,
    /// The cube's settings; null where no cube was made.
    pub cube: Option<CubeSettings>,
    /// The cube's refresh policy; null where no cube was made.
    pub refresh: Option<String>,
    pub observer_resolution: [u32; 2],
    pub sensor_resolution: [u32; 2],
    pub validation: bool,
    pub lp_num_threads: Option<String>,
    pub malloc_trim_threshold_bytes: Option<i32>,
}

#[derive(Debug, Serialize)]
pub struct CubeSettings {
    pub face_size_px: u32,
    pub format: &'static str,
    /// Where the cube is rendered from, relative to the mirror's viewpoint (`cube.offset`).
    pub offset_m: [f32; 3],
    pub near_m: f32,
    pub far_m: f32,
    pub mipmaps: bool,
    pub anisotropy: u32,
}

/// One method's frames.
#[derive(Debug, Serialize)]
pub struct RenderRun {
    /// The method that filled the cube; null where no cube was made.
    pub method: Option<Method>,
    pub out: String,
    /// Where the bvh lookup walked its rays, as taken (`fragment` or `compute`: `--trace-in`,
    /// else the device's default); absent for the other lookups.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trace_in: Option<&'static str>,
    /// The bvh lookup's tree layout, as taken (`cwbvh` or `bvh4`: `--bvh-layout`, else the
    /// device's default); absent for the other lookups.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bvh_layout: Option<&'static str>,
    /// The cube's updates and skips; null where no cube was made.
    pub refresh_counters: Option<RefreshCounters>,
    pub summary: RenderSummary,
    pub frames: Vec<FrameReport>,
}

/// Medians over frames (nearest rank); None where nothing was measured.
#[derive(Debug, Serialize)]
pub struct RenderSummary {
    pub frames: usize,
    /// Frames that updated the cube (the cube's median is over these only).
    pub cube_updates: usize,
    pub median_gpu_cube_update_ms: Option<f64>,
    pub median_gpu_observer_ms: Option<f64>,
    pub median_gpu_sensor_ms: Option<f64>,
    pub median_gpu_views_ms: Option<f64>,
    pub median_submit_wait_ms: Option<f64>,
    pub median_cpu_record_ms: Option<f64>,
}

/// `reference.json`.
#[derive(Debug, Serialize)]
pub struct ReferenceRecord {
    pub scene: String,
    pub time_s: f64,
    pub spp: u32,
    pub origin: [f64; 3],
    pub triangles: usize,
    /// The meshes' trees and the top level over the objects, in ms.
    pub bvh_meshes_ms: f64,
    pub bvh_top_level_ms: f64,
    pub threads: usize,
    pub cameras: ReferenceCameras,
}

#[derive(Debug, Serialize)]
pub struct ReferenceCameras {
    pub observer: ReferenceStats,
    pub sensor: ReferenceStats,
}

/// `compare --json` (every key is documented in docs/accuracy.md). Undefined metrics and an
/// infinite PSNR are null, never a non-number.
#[derive(Debug, Serialize)]
pub struct CompareRecord {
    pub test: String,
    pub reference: String,
    pub mask: Option<String>,
    pub heatmap: Option<String>,
    pub width: u32,
    pub height: u32,
    pub pixels_in_mask: u64,
    pub pixels_compared: u64,
    pub test_nan_pixels: u64,
    pub test_inf_pixels: u64,
    pub reference_nan_pixels: u64,
    pub reference_inf_pixels: u64,
    pub rmse: Option<f64>,
    pub psnr_db: Option<f64>,
    pub psnr_infinite: bool,
    pub rel_mse: Option<f64>,
    pub max_abs_error: Option<f64>,
    pub flip_mean: Option<f64>,
    pub flip_p99: Option<f64>,
    pub settings: CompareSettings,
}

#[derive(Debug, Serialize)]
pub struct CompareSettings {
    pub psnr_peak: f64,
    pub rel_mse_epsilon: f64,
    pub mask_threshold: f32,
    pub flip_pixels_per_degree: f32,
    pub flip_percentile: f64,
}

/// `info --json`.
#[derive(Debug, Serialize)]
pub struct InfoRecord {
    pub devices: Vec<InfoDevice>,
}

/// One device: what it is, whether it is usable and the default, and its methods.
#[derive(Debug, Serialize)]
pub struct InfoDevice {
    #[serde(flatten)]
    pub info: DeviceInfo,
    pub usable: bool,
    pub default: bool,
    pub rejected_because: Option<String>,
    pub mesa_too_old: bool,
    pub methods: Vec<InfoMethod>,
    pub lookups: Vec<InfoLookup>,
}

/// Whether a device can run one mirror lookup, and why not.
#[derive(Debug, Serialize)]
pub struct InfoLookup {
    pub lookup: specchio::scene::Lookup,
    pub usable: bool,
    pub reason: Option<String>,
}

#[derive(Debug, Serialize)]
pub struct InfoMethod {
    pub method: Method,
    pub usable: bool,
    pub reason: Option<String>,
}

/// `probe view-mask-leak`'s line.
#[derive(Debug, Serialize)]
pub struct ViewMaskLeakLine {
    #[serde(flatten)]
    pub leak: specchio::render::methods::ViewMaskLeak,
    pub device: String,
    pub driver_info: String,
    pub mesa_version: Option<String>,
}
