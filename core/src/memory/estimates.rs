//! Each command's host-memory estimate, checked against the budget ([`super::Budget`]) before
//! the command starts any work: a resolution, sensor size or cube size that would need more
//! than the machine has is refused with the figures, instead of growing until the OS kills
//! the run.
//!
//! The constants are measured peaks of this project's commands (release build, lavapipe,
//! whose device memory is host memory), rounded up by about a tenth, so that each estimate
//! is an upper bound: `/usr/bin/time -f %M` of `render`, `reference`, `calibrate` and
//! `localise` on thesis-room with both views (or the sensor) at 1024², 2048² and 4096², the
//! cube at 1024, 2048 and 4096, and on heavy for the per-triangle parts; every one grew
//! linearly. `tests/cli/memory.rs` checks the estimates against measured peaks.

use super::{Budget, Estimate, MemoryError};
use crate::scene::Scene;

const MIB: u64 = 1 << 20;

/// The driver, the device, the pipelines and the program itself (render at small sizes:
/// about 132 MiB besides its images; the validation layer adds some 25 MiB).
const RENDER_BASE_BYTES: u64 = 192 * MIB;
/// A view pixel (observer or sensor): its target, readback, EXR and PNG encoding (37.8
/// measured).
const RENDER_VIEW_PIXEL_BYTES: u64 = 42;
/// `--directions`: a view pixel's direction image, read back and encoded (52 measured).
const RENDER_DIRECTION_PIXEL_BYTES: u64 = 58;
/// A cube texel (6 a face² in all): colour, depth and mips on the device, the faces read back
/// and written (39 measured).
const RENDER_CUBE_TEXEL_BYTES: u64 = 44;
/// `--sensor-outputs`: a sensor pixel's ray map, range, ids, the id cube's share and the
/// panoramas (294 measured), and their fixed part.
const RENDER_SENSOR_OUTPUT_PIXEL_BYTES: u64 = 330;
const RENDER_SENSOR_OUTPUT_BASE_BYTES: u64 = 32 * MIB;
/// A sensor pixel's camera image (`[sensor.imaging]`), counted from the code rather than
/// measured: the light, three f32 (two copies while the blur runs), the codes, three u16,
/// and the PNG's samples and bytes, six each at most: 36 at the peak.
const CAMERA_IMAGE_PIXEL_BYTES: u64 = 36;
/// With motion blur, the exposure's sum (four f64) and the instant read back (four f32),
/// counted from the code: 48.
const MOTION_BLUR_PIXEL_BYTES: u64 = 48;
/// A triangle of one pass over the scene: vertex and index buffers, meshlets, per-object
/// data (heavy: about 188 measured).
const RENDER_TRIANGLE_BYTES: u64 = 210;

/// The program and the scene without its triangles (reference at 1024²: 144 MiB in all).
const REFERENCE_BASE_BYTES: u64 = 64 * MIB;
/// A traced pixel (observer or sensor): colour, direction, distance, ids, hidden layers and
/// their encoding (66–68 measured; samples per pixel do not change it).
const REFERENCE_PIXEL_BYTES: u64 = 75;
/// A triangle in world space with its BVH (heavy: about 310 measured).
const REFERENCE_TRIANGLE_BYTES: u64 = 340;
/// `--sensor-outputs` on the reference: a sensor pixel's layers and panoramas (30–57
/// measured), and their fixed part.
const REFERENCE_SENSOR_OUTPUT_PIXEL_BYTES: u64 = 66;
const REFERENCE_SENSOR_OUTPUT_BASE_BYTES: u64 = 128 * MIB;

/// `calibrate` without its pixels (no device, no BVH of note: 15 MB by the fit below).
const CALIBRATE_BASE_BYTES: u64 = 24 * MIB;
/// A sensor pixel of `calibrate`: its exact ray, residuals and images (77 measured, debug
/// build, thesis-room from 1024² to 4096²: 96 MB to 1.31 GB).
const CALIBRATE_PIXEL_BYTES: u64 = 88;
/// A pixel the models are fitted to (at most a 512² sensor's: `sensor::central`): its
/// samples and the fits' residual and Jacobian columns (512², every pixel fitted: 69.5 MB in
/// all, some 160 bytes a fitted pixel beyond the ray map).
const CALIBRATE_FIT_PIXEL_BYTES: u64 = 160;

/// A sensor pixel of `localise` (`--sensor-size` squared): the renderer's targets or the
/// reference's layers, the read back image and its panorama (66.7 measured with a cube
/// lookup; the reference's pixel is at most `REFERENCE_PIXEL_BYTES`).
const LOCALISE_PIXEL_BYTES: u64 = 80;

/// `bench`: a fill method's renderer per cube texel in the timing phase (14.4 measured), and
/// its fixed part (about 7 MiB).
const BENCH_METHOD_TEXEL_BYTES: u64 = 16;
const BENCH_METHOD_BASE_BYTES: u64 = 8 * MIB;
/// `bench`: a rung's renderer per cube texel (12.3 measured) and per view pixel (its views,
/// read back with their directions: about 50 measured).
const BENCH_RUNG_TEXEL_BYTES: u64 = 14;
const BENCH_RUNG_VIEW_PIXEL_BYTES: u64 = 55;
/// `bench`: the error measurement per view pixel: the reference's images and layers and each
/// lookup's read back images and directions (thesis-room: 336 MiB for 742,144 view pixels,
/// the same at 512² and 1024² faces).
const BENCH_ACCURACY_VIEW_PIXEL_BYTES: u64 = 500;

/// The estimate's part for the textures (its refusal then says to shrink them).
pub(crate) const TEXTURES_PART: &str = "the scene's textures";
/// What every run takes whatever its sizes: no setting of the scene's can lower it.
pub(crate) const BASE_PART: &str = "the driver and the program";
/// A decoded texel of the scene's textures: the decoded image, its upload and its mips.
pub(crate) const TEXEL_BYTES: u64 = 12;

/// What the scene itself costs a renderer or the reference: its triangles a pass (every
/// object's, walls included) at `triangle_bytes` each, and its textures.
fn scene_parts(e: &mut Estimate, scene: &Scene, triangle_bytes: u64) {
    let triangles: u64 = scene
        .objects
        .iter()
        .map(|o| scene.meshes[o.mesh].indices.len() as u64 / 3)
        .sum();
    e.add_many("the scene's triangles", triangles, triangle_bytes);
    let texels: u64 = scene
        .textures
        .iter()
        .map(|t| u64::from(t.width) * u64::from(t.height))
        .sum();
    e.add_many(TEXTURES_PART, texels, TEXEL_BYTES);
}

fn pixels([w, h]: [u32; 2]) -> u64 {
    u64::from(w) * u64::from(h)
}

/// `specchio render` (`directions`: `--directions`; `sensor_outputs`: `--sensor-outputs`).
pub fn render(
    scene: &Scene,
    face_size_px: u32,
    directions: bool,
    sensor_outputs: bool,
) -> Result<(), MemoryError> {
    let frames = u64::from(sensor_outputs);
    render_estimate(scene, face_size_px, directions, frames).check(&Budget::from_env()?, HINT)
}

/// `specchio dataset` and the Python package's datasets, with `frames_held` frames' outputs
/// in memory at once: the one rendering and those held by the encoders
/// (`render/dataset/frames.rs`; the H200 measured 315 MB with one encoder, 563 MB with four:
/// 83 MB a frame of a 512² sensor, which the sensor outputs' 330 bytes a pixel bound).
/// `face_size_px`: the cube's, 0 where the lookup makes none (a traced one, the default).
pub fn dataset(scene: &Scene, face_size_px: u32, frames_held: u64) -> Result<(), MemoryError> {
    render_estimate(scene, face_size_px, false, frames_held)
        .check(&Budget::from_env()?, DATASET_HINT)
}

const HINT: &str =
    "lower observer.resolution, sensor.resolution or the cube's face size (--cube-size)";
/// A dataset has no `--cube-size`: the scene's face size is the one to lower.
const DATASET_HINT: &str = "lower observer.resolution, sensor.resolution or cube.face_size";

/// A renderer of `scene` with `frames` frames' sensor outputs in memory.
fn render_estimate(scene: &Scene, face_size_px: u32, directions: bool, frames: u64) -> Estimate {
    let views = pixels(scene.observer.resolution) + pixels(scene.sensor.resolution);
    let face = u64::from(face_size_px);
    let mut e = Estimate::new();
    e.add(BASE_PART, RENDER_BASE_BYTES);
    scene_parts(&mut e, scene, RENDER_TRIANGLE_BYTES);
    e.add_many("the two views", views, RENDER_VIEW_PIXEL_BYTES);
    // None where the renderer makes no cube (a lookup that samples none: face size 0).
    if face > 0 {
        e.add_many("the cube", 6 * face * face, RENDER_CUBE_TEXEL_BYTES);
    }
    if directions {
        e.add_many("the direction images", views, RENDER_DIRECTION_PIXEL_BYTES);
    }
    if frames > 0 {
        let sensor = pixels(scene.sensor.resolution);
        let what = match frames {
            1 => "the sensor outputs".to_owned(),
            n => format!("{n} frames' sensor outputs"),
        };
        e.add_many(what, frames * sensor, RENDER_SENSOR_OUTPUT_PIXEL_BYTES)
            .add(
                "the sensor outputs' fixed part",
                RENDER_SENSOR_OUTPUT_BASE_BYTES,
            );
        camera_image(&mut e, scene, frames);
    }
    e
}

/// `frames` frames' camera images, where the scene has an imaging chain.
fn camera_image(e: &mut Estimate, scene: &Scene, frames: u64) {
    if scene.sensor.imaging.is_some() {
        let sensor = pixels(scene.sensor.resolution);
        e.add_many(
            "the camera image",
            frames * sensor,
            CAMERA_IMAGE_PIXEL_BYTES,
        );
        // A rolling shutter alone spans instants too.
        if crate::sensor::imaging::exposure_renders(scene) > 0 {
            e.add_many("the exposure's sum", sensor, MOTION_BLUR_PIXEL_BYTES);
        }
    }
}

/// `specchio reference`.
pub fn reference(scene: &Scene, sensor_outputs: bool) -> Result<(), MemoryError> {
    let views = pixels(scene.observer.resolution) + pixels(scene.sensor.resolution);
    let mut e = Estimate::new();
    e.add("the program", REFERENCE_BASE_BYTES);
    scene_parts(&mut e, scene, REFERENCE_TRIANGLE_BYTES);
    e.add_many("the two traced views", views, REFERENCE_PIXEL_BYTES);
    if sensor_outputs {
        let sensor = pixels(scene.sensor.resolution);
        e.add_many(
            "the sensor outputs",
            sensor,
            REFERENCE_SENSOR_OUTPUT_PIXEL_BYTES,
        )
        .add(
            "the sensor outputs' fixed part",
            REFERENCE_SENSOR_OUTPUT_BASE_BYTES,
        );
        camera_image(&mut e, scene, 1);
    }
    e.check(
        &Budget::from_env()?,
        "lower observer.resolution or sensor.resolution",
    )
}

/// `specchio compare`'s program, without images (measured 81 MB with two 1024² images'
/// 48 MB taken out).
const COMPARE_BASE_BYTES: u64 = 96 * MIB;
/// A compared pixel: the two decoded images, each file's bytes while it decodes, FLIP's
/// bands and map, the heatmap (44.6 measured at 8192², 3.07 GB in all, 30 November 2026).
const COMPARE_PIXEL_BYTES: u64 = 48;
/// A mask's pixel: its decoded image while it is read, then one flag.
const COMPARE_MASK_PIXEL_BYTES: u64 = 20;

/// `specchio compare` of two `size` images (from their headers), with a mask or not: an
/// 8192² comparison holds 3 GB, one at the 16384² the metrics read about 13 GB.
pub fn compare(size: [u32; 2], mask: bool) -> Result<(), MemoryError> {
    let mut e = Estimate::new();
    e.add(BASE_PART, COMPARE_BASE_BYTES);
    e.add_many("the images", pixels(size), COMPARE_PIXEL_BYTES);
    if mask {
        e.add_many("the mask", pixels(size), COMPARE_MASK_PIXEL_BYTES);
    }
    e.check(&Budget::from_env()?, "compare smaller images")
}

/// `specchio calibrate`.
pub fn calibrate(scene: &Scene) -> Result<(), MemoryError> {
    let mut e = Estimate::new();
    e.add("the program", CALIBRATE_BASE_BYTES);
    scene_parts(&mut e, scene, REFERENCE_TRIANGLE_BYTES);
    let sensor = pixels(scene.sensor.resolution);
    e.add_many(
        "the sensor's ray map and residuals",
        sensor,
        CALIBRATE_PIXEL_BYTES,
    );
    let fitted = sensor.min(crate::sensor::central::MAX_FIT_PIXELS as u64);
    e.add_many("the models' fits", fitted, CALIBRATE_FIT_PIXEL_BYTES);
    e.check(&Budget::from_env()?, "lower sensor.resolution")
}

/// `specchio localise`: one renderer at a time, a `sensor_px`² sensor, its `cube_px`² cube
/// where a source fills one, and the landmarks' signatures (`signature_values` floats each,
/// for `landmarks` landmarks per source).
pub fn localise(
    scene: &Scene,
    sensor_px: u32,
    cube_px: Option<u32>,
    landmarks: u64,
    signature_values: u64,
) -> Result<(), MemoryError> {
    let mut e = Estimate::new();
    e.add(BASE_PART, RENDER_BASE_BYTES);
    scene_parts(
        &mut e,
        scene,
        RENDER_TRIANGLE_BYTES.max(REFERENCE_TRIANGLE_BYTES),
    );
    e.add_many("the sensor", pixels([sensor_px; 2]), LOCALISE_PIXEL_BYTES);
    if let Some(face) = cube_px.map(u64::from) {
        e.add_many("the cube", 6 * face * face, RENDER_CUBE_TEXEL_BYTES);
    }
    e.add_many(
        "the landmarks' signatures",
        landmarks.saturating_mul(signature_values),
        4,
    );
    let hint = match cube_px {
        Some(_) => "lower --sensor-size or --cube-size",
        None => "lower --sensor-size",
    };
    e.check(&Budget::from_env()?, hint)
}

/// `specchio bench`: scenes and face sizes are measured one after another, so the estimate is
/// that of the largest; within one, the fill methods' renderers (`methods`, the timing phase)
/// and the ladder's (`rungs`) are alive in turn, each renderer with the scene, and the error
/// measurement with the reference beside them. Measured phase by phase on thesis-room at 512²
/// and 1024² faces (the constants above).
pub fn bench(
    scenes: &[&Scene],
    face_sizes: &[u32],
    methods: usize,
    rungs: usize,
    accuracy: bool,
) -> Result<(), MemoryError> {
    let face = u64::from(face_sizes.iter().copied().max().unwrap_or(0));
    let texels = 6 * face * face;
    let mut worst = Estimate::new();
    for scene in scenes {
        let views = pixels(scene.observer.resolution) + pixels(scene.sensor.resolution);
        let mut one = Estimate::new();
        scene_parts(&mut one, scene, RENDER_TRIANGLE_BYTES);
        let per_scene = one.total();
        let method = texels * BENCH_METHOD_TEXEL_BYTES + BENCH_METHOD_BASE_BYTES + per_scene;
        let rung =
            texels * BENCH_RUNG_TEXEL_BYTES + views * BENCH_RUNG_VIEW_PIXEL_BYTES + per_scene;
        let mut e = Estimate::new();
        e.add(BASE_PART, RENDER_BASE_BYTES);
        let timing = (methods as u64).saturating_mul(method);
        let ladder = (rungs as u64).saturating_mul(rung);
        match timing >= ladder {
            true => e.add(format!("{methods} fill methods' renderers"), timing),
            false => e.add(format!("{rungs} rungs' renderers"), ladder),
        };
        if accuracy {
            e.add_many(
                "the error measurement",
                views,
                BENCH_ACCURACY_VIEW_PIXEL_BYTES,
            );
            scene_parts(&mut e, scene, REFERENCE_TRIANGLE_BYTES);
        }
        if e.total() > worst.total() {
            worst = e;
        }
    }
    worst.check(
        &Budget::from_env()?,
        "lower --cube-sizes, or measure fewer --methods or --rungs at once",
    )
}
