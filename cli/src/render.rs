//! `specchio render`: one frame (or a sequence) of a scene, written as EXR + PNG + JSON.

use crate::image_files::ImageFiles;
use crate::render_report::{files_line, print_summary};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::{bail, Result};
use specchio::output::{OutputError, Sink, Transaction};
use specchio::process::progress::{self, Progress};
use specchio::render::lookups::{self, TraceIn, TraceOrder};
use specchio::render::methods::Method;
use specchio::render::{FrameImages, FrameReport, Readback, RenderOptions, Renderer};
use specchio::scene::camera::FACE_NAMES;
use specchio::scene::{
    CubeFormat, Lookup, RefreshPolicy, Scene, MAX_DISTANCE_STEPS, MAX_SECANT_STEPS,
};
use specchio::sensor::SensorOutputs;
use specchio::vk::device::{self, Device, DeviceInfo};

use crate::records::{
    CubeSettings, NotRun, RenderRecord, RenderRun, RenderSettings, RenderSummary,
};
use crate::render_input::{chosen_lookup, frame_times_are_in_range, load_scene, options_apply};
use specchio::process::args::{face_size, real, seconds, whole};
use specchio::process::probe;
use specchio::vk::instance::{Instance, InstanceDesc};

/// More frames than this is a mistake, not a render (about an hour of video at 30 fps).
pub const MAX_FRAMES: u32 = 100_000;

/// The largest `--frame` (a year of frames at 30 fps): frame numbers stay far from overflow.
pub const MAX_FRAME_INDEX: u64 = 1_000_000_000;

#[derive(clap::Args)]
pub struct Args {
    /// The scene file (TOML; see docs/scene-format.md).
    pub(crate) scene: PathBuf,
    /// Output folder: created with everything in it at the end, or not at all; an earlier
    /// render there is replaced.
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// Scene time of the (first) frame in seconds (0 to 1e9).
    #[arg(long, conflicts_with = "frame", allow_negative_numbers = true,
          value_parser = seconds)]
    pub(crate) time: Option<f64>,
    /// Frame number of the (first) frame, 0..=1000000000; its time is N / fps.
    #[arg(long, allow_negative_numbers = true, value_parser = whole(0..=MAX_FRAME_INDEX))]
    pub(crate) frame: Option<u64>,
    /// Frames per second for --frame and --frames, in (0, 10000]. Default: 30.
    #[arg(long, allow_negative_numbers = true, value_parser = real(0.0, true, 10_000.0))]
    pub(crate) fps: Option<f64>,
    /// Render K consecutive frames (numbered outputs in DIR/NNNN/), 1..=100000.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1, value_parser = whole(1..=MAX_FRAMES))]
    pub(crate) frames: u32,
    /// Cube face size in texels (overrides the scene's cube.face_size).
    #[arg(long, allow_negative_numbers = true, value_parser = face_size)]
    pub(crate) cube_size: Option<u32>,
    /// Cube fill method (`specchio info` lists them, with what this device can run), or all
    /// (each usable one into DIR/<method>/; measurement variants only when named). Default:
    /// six-pass. Only a lookup that samples the cube fills one.
    #[arg(long, value_parser = specchio::process::args::method_or_all)]
    pub(crate) method: Option<String>,
    /// Mirror lookup (`specchio info` lists them, with what this device can run; see
    /// docs/accuracy.md). Default: the scene's `mirror.lookup`.
    #[arg(long, value_parser = specchio::process::args::lookup)]
    pub(crate) lookup: Option<Lookup>,
    /// The distance lookup's linear search steps, 1..=256 (overrides the scene's
    /// mirror.distance_steps; see docs/accuracy.md).
    #[arg(long, allow_negative_numbers = true, value_parser = whole(1..=MAX_DISTANCE_STEPS))]
    pub(crate) distance_steps: Option<u32>,
    /// The distance lookup's secant refinements, 0..=32 (overrides mirror.secant_steps).
    #[arg(long, allow_negative_numbers = true, value_parser = whole(0..=MAX_SECANT_STEPS))]
    pub(crate) secant_steps: Option<u32>,
    /// Also write, per mirror pixel, the direction looked up in the cube map
    /// (`observer.direction.exr`, `sensor.direction.exr`), to compare with `specchio reference`.
    #[arg(long)]
    pub(crate) directions: bool,
    /// Also write the sensor outputs: ray map, range and ids, the id map, panoramas from the
    /// sensor image (and from the cube where there is one), camera.json (docs/sensor.md).
    /// Without --lookup the colour, range and ids are all traced along one light path, on
    /// every device (bvh on CPU drivers, ray-query on a GPU with ray queries, bvh on any
    /// other); with a cube lookup range and ids come through the cube, with a warning and
    /// camera.json's `ground_truth` saying so.
    #[arg(long)]
    pub(crate) sensor_outputs: bool,
    /// Under `on-change`, re-render all six faces on any change instead of only the faces a
    /// moved object touches.
    #[arg(long)]
    pub(crate) full_updates: bool,
    /// Under `on-change`, re-render a dirty face whole instead of only its dirty rectangles
    /// (the pixels a moved object's old or new bounds project to; multiview re-renders all
    /// six faces, in the dirty faces' rectangles together).
    #[arg(long, conflicts_with = "full_updates")]
    pub(crate) whole_faces: bool,
    /// Fill only the tiles of the cube the views may read (marked by a pass over the views
    /// before the fill; docs/methods.md, "The footprint"); the cube is then not written, its
    /// other tiles being unfilled. Only the cube lookups (plain, box), without
    /// --sensor-outputs; refused on SwiftShader.
    #[arg(long)]
    pub(crate) footprint: bool,
    /// The order the tracing lookups (ray-query, distance-exact) hand their acceleration-
    /// structure builds: `split` (spatially coherent, the default) or `given` (the scene's own,
    /// to measure what the order is worth on a driver that keeps it: docs/accuracy.md). Only
    /// those lookups take it.
    #[arg(long, value_parser = specchio::process::args::trace_order)]
    pub(crate) trace_order: Option<TraceOrder>,
    /// Where the bvh lookup walks its rays: `fragment` (in the mirror's fragment shaders) or
    /// `compute` (once a view, in a compute pass before it is drawn). Default: the device's
    /// (compute on a GPU, fragment on a CPU driver; docs/accuracy.md).
    #[arg(long, value_parser = specchio::process::args::trace_in)]
    pub(crate) trace_in: Option<specchio::render::lookups::TraceIn>,
    /// How the bvh lookup lays out and walks its trees: `cwbvh` (eight children a node) or
    /// `bvh4` (four, nearest first). Default: the device's (bvh4 on SwiftShader, cwbvh
    /// elsewhere; docs/accuracy.md). The same pixels either way.
    #[arg(long, value_parser = specchio::process::args::bvh_layout)]
    pub(crate) bvh_layout: Option<specchio::bvh::BvhLayout>,
    /// Enable the Khronos validation layer; any message makes the command fail.
    #[arg(long)]
    pub(crate) validate: bool,
    /// Vulkan device: index or part of its name (see `specchio info`).
    #[arg(long)]
    pub(crate) device: Option<String>,
}

pub fn run(args: &Args) -> Result<ExitCode> {
    // 1. Everything that can be wrong with the input is found before the output folder exists
    //    (the numbers' ranges by clap, `specchio::process::args`).
    // Signals are caught from here: a scene with a mesh of millions of triangles takes
    // seconds to load, and a Ctrl-C then stops it with a word, not without one.
    specchio::process::interrupt::catch_in_long_frames();
    let scene = crate::render_input::unless_stopped(load_scene(args), "while loading the scene")?;
    let start_s = (args.time).unwrap_or_else(|| args.frame.unwrap_or(0) as f64 / args.fps());
    frame_times_are_in_range(args, start_s)?;
    // Everything is written into a hidden folder beside --out, renamed into place at the end
    // (dropped, it is removed): a failure anywhere below leaves nothing behind.
    let mut out = Transaction::new();
    out.folder(&args.out, "render.json")?;

    // 2. The GPU, with the features of the methods that will run.
    let instance = Instance::create(&InstanceDesc::from_env(args.validate))?;
    let log = instance.validation_log();
    let validation = instance.validation;
    let chosen = device::choose(&instance, args.device.as_deref())?;
    let (methods, refused) = pick_methods(args.method_name(), &chosen)?;
    let lookup = chosen_lookup(args, &scene, &chosen);
    if let Some(why) = lookups::missing_features(lookup, &chosen) {
        bail!("lookup {lookup} cannot run on {}: {why}", chosen.name);
    }
    options_apply(args, &scene, lookup)?;
    let features = lookups::features(lookup);
    let device = probe::device_for(&instance, args.device.as_deref(), &methods, features)?;
    drop(instance);
    if let Some(why) = specchio::render::footprint_refusal(&device.info).filter(|_| args.footprint)
    {
        bail!("--footprint: {why}; leave it out, or give another --device (lavapipe)");
    }

    // 3. Frames, per method (`--method all`: each into DIR/<method>/), each method's frames
    //    said as they go and, with several methods, the whole run's too.
    let whole = (methods.len() > 1).then(|| {
        let what = format!("render {}: {} methods", args.out.display(), methods.len());
        Progress::new(
            what,
            methods.len() as u64 * u64::from(args.frames),
            "frames",
        )
    });
    let runs = (methods.iter())
        .map(|&method| {
            let at = (start_s, whole.as_ref());
            render_method(args, (&device, lookup), &scene, method, at, &out)
        })
        .collect::<Result<Vec<_>>>()?;

    // 4. The record, once the device is gone (the layer's leak report comes then).
    let info = device.info.clone();
    drop(device);
    let messages = log.messages();
    // A lookup that samples no cube has none made (`RenderOptions::lookup_fixed`): no method
    // ran, and the record says so rather than name six-pass.
    let methods = match crate::render_input::needs_cube(args, lookup) {
        true => methods,
        false => Vec::new(),
    };
    let mut record = render_record(
        (args, &scene, lookup),
        start_s,
        (methods, &refused),
        info,
        runs,
    );
    record.settings.validation = validation;
    // Counted once the device was dropped: its leak report is in.
    record.validation_messages = messages.len();
    out.write_json(&args.out.join("render.json"), &record)?;
    // A signal that came after the last check still stops the run: nothing is placed.
    specchio::process::interrupt::check("before placing the output")?;
    out.commit()?;
    if args.method_name() == "all" {
        specchio::say!("record: {}", args.out.join("render.json").display());
    }
    for (m, why) in &refused {
        specchio::say!("  {m}: not run: {why}");
    }
    specchio::process::validation::verdict(&messages)?;
    Ok(ExitCode::SUCCESS)
}

/// One method's frames, written into its folder, and its summary printed.
fn render_method(
    args: &Args,
    (device, lookup): (&Arc<Device>, Lookup),
    scene: &Scene,
    method: Method,
    (start_s, whole): (f64, Option<&Progress>),
    out: &Transaction,
) -> Result<RenderRun> {
    let dir = if args.method_name() == "all" {
        args.out.join(method.name())
    } else {
        args.out.clone()
    };
    let options = RenderOptions {
        cube_size: args.cube_size,
        method,
        full_updates: args.full_updates,
        whole_faces: args.whole_faces,
        footprint: args.footprint,
        lookup: Some(lookup),
        lookup_fixed: true,
        id_cube: crate::render_input::id_cube(args, lookup),
        trace_order: args.trace_order(),
        trace_in: args.trace_in,
        bvh_layout: args.bvh_layout,
        ..Default::default()
    };
    let mut renderer = Renderer::new(device, scene.clone(), &options)?;
    if let (true, Some(warning)) = (
        args.sensor_outputs,
        renderer.sensor_ground_truth().warning(&renderer.scene),
    ) {
        specchio::say_err!("warning: sensor outputs ({lookup} lookup): {warning}");
    }
    let reports = render_frames(args, &mut renderer, (start_s, whole), out, &dir)?;
    let summary = summarize(&reports);
    let lookup = renderer.scene.mirror.lookup;
    let method = crate::render_input::needs_cube(args, lookup).then_some(method);
    // Said from the folder; a listing that fails costs the line, never the render.
    let files = out.written(&dir);
    print_summary(args, (method, lookup), &dir, &reports, &summary);
    match files {
        // `--method all` writes render.json above the methods' folders: said once, there.
        Ok(files) => specchio::say!("  files: {}", files_line(&files, dir == args.out)),
        Err(e) => specchio::say!("  files: (cannot list them: {e})"),
    }
    let walks = lookup == specchio::scene::Lookup::Bvh;
    let taken = if renderer.pretraced() {
        TraceIn::Compute
    } else {
        TraceIn::Fragment
    };
    Ok(RenderRun {
        method,
        out: dir.display().to_string(),
        trace_in: walks.then(|| taken.name()),
        bvh_layout: renderer.bvh_layout().map(|l| l.name()),
        refresh_counters: method.is_some().then(|| renderer.counters()),
        summary,
        frames: reports,
    })
}

/// `render.json`: the settings the runs had, the device, what did not run, the runs (the
/// validation setting and the message count are the caller's to fill in).
fn render_record(
    (args, scene, lookup): (&Args, &Scene, Lookup),
    start_s: f64,
    (methods, refused): (Vec<Method>, &[(Method, String)]),
    device: DeviceInfo,
    runs: Vec<RenderRun>,
) -> RenderRecord {
    let cube = &scene.cube;
    let cube_made = !methods.is_empty();
    RenderRecord {
        scene: args.scene.display().to_string(),
        description: scene.description.clone(),
        origin: scene.origin.to_array(),
        settings: RenderSettings {
            start_time_s: start_s,
            fps: args.fps(),
            frames: args.frames,
            methods,
            full_updates: args.full_updates,
            whole_faces: args.whole_faces,
            footprint: args.footprint,
            // The lookup the frames used: `--sensor-outputs` without `--lookup` picks a traced
            // one by the device (the scene's was recorded, though not used).
            lookup,
            trace_order: lookups::plugin(lookup)
                .builds_scene_trace()
                .then(|| args.trace_order().name()),
            trace_in: args.trace_in.map(|t| t.name()),
            bvh_layout: args.bvh_layout.map(|l| l.name()),
            distance_steps: scene.mirror.distance_steps,
            secant_steps: scene.mirror.secant_steps,
            cube: cube_made.then(|| CubeSettings {
                face_size_px: args.cube_size.unwrap_or(cube.face_size_px),
                format: format_name(cube.format),
                offset_m: cube.offset_m.to_array(),
                near_m: cube.near_m,
                far_m: cube.far_m,
                mipmaps: cube.mipmaps,
                anisotropy: cube.anisotropy,
            }),
            refresh: cube_made.then(|| refresh_name(scene.refresh)),
            observer_resolution: scene.observer.resolution,
            sensor_resolution: scene.sensor.resolution,
            validation: false,
            lp_num_threads: std::env::var("LP_NUM_THREADS").ok(),
            malloc_trim_threshold_bytes: specchio::process::allocator::trim_threshold(),
        },
        device,
        methods_not_run: (refused.iter())
            .map(|(m, why)| NotRun {
                method: *m,
                reason: why.clone(),
            })
            .collect(),
        runs,
        validation_messages: 0,
    }
}

/// `--method NAME`: that method, refused with the reason when it cannot run here.
/// `--method all`: every usable method, and the others with their reasons.
/// Methods that run, and methods that do not with the reason.
type MethodChoice = (Vec<Method>, Vec<(Method, String)>);

fn pick_methods(arg: &str, info: &DeviceInfo) -> Result<MethodChoice> {
    if arg == "all" {
        return Ok(probe::partition(
            &Method::listed().collect::<Vec<_>>(),
            info,
        ));
    }
    let Some(m) = Method::parse(arg) else {
        bail!("--method {arg}: unknown; one of {}, all", Method::names());
    };
    if let Err(why) = probe::usable(m, info) {
        bail!("--method {arg}: cannot be used on this device: {why}");
    }
    Ok((vec![m], vec![]))
}

fn render_frames(
    args: &Args,
    renderer: &mut Renderer,
    (start_s, whole): (f64, Option<&Progress>),
    out: &Transaction,
    dir: &Path,
) -> Result<Vec<FrameReport>> {
    let progress = (args.frames > 1).then(|| indicatif::ProgressBar::new(u64::from(args.frames)));
    let estimate = Progress::new(
        format!("render {}", dir.display()),
        args.frames.into(),
        "frames",
    );
    let mut reports = Vec::new();
    for i in 0..args.frames {
        if i > 0 {
            estimate.add(1);
        }
        specchio::process::interrupt::check(&format!("after {i} of {} frame(s)", args.frames))?;
        let t = start_s + f64::from(i) / args.fps();
        // Frame numbers continue from --frame, so `every-n` counts scene frames, not run frames.
        let frame_index = args.frame.unwrap_or(0) + u64::from(i);
        let (report, images) = renderer.render_frame(
            frame_index,
            t,
            Readback {
                // A lookup that reads no cube (ray-query) leaves it unfilled, and a footprint
                // all but the tiles the views read: nothing to write.
                cube: lookups::plugin(renderer.scene.mirror.lookup).uses_cube() && !args.footprint,
                views: true,
                directions: args.directions,
                rays: args.sensor_outputs,
                ..Default::default()
            },
        )?;
        let frame_dir = if args.frames > 1 {
            dir.join(format!("{i:04}"))
        } else {
            dir.to_owned()
        };
        let wrote =
            write_frame(out, &frame_dir, &images, args.frames == 1).and_then(|()| {
                match args.sensor_outputs {
                    true => {
                        write_sensor_outputs(out, &frame_dir, renderer, (frame_index, t), images)
                    }
                    false => Ok(()),
                }
            });
        // A signal stops a frame's files between two (the transaction checks before each):
        // said, as between two frames, by how many frames were done.
        if let Err(e) = wrote {
            let stop = |c: &(dyn std::error::Error + 'static)| {
                matches!(c.downcast_ref(), Some(OutputError::Stopped { .. }))
            };
            if e.chain().any(stop) {
                let done = format!("after {i} of {} frame(s)", args.frames);
                return Err(specchio::process::interrupt::stopped(&done).into());
            }
            return Err(e);
        }
        reports.push(report);
        if let Some(p) = &progress {
            p.inc(1);
        }
        whole.inspect(|w| w.add(1));
    }
    if let Some(p) = progress {
        p.finish_and_clear();
    }
    Ok(reports)
}

/// The cube format as the scene file spells it.
fn format_name(f: CubeFormat) -> &'static str {
    match f {
        CubeFormat::Rgba16Float => "rgba16f",
        CubeFormat::Rgba8Unorm => "rgba8",
    }
}

/// The refresh policy as the scene file spells it (`every-n` with its n).
fn refresh_name(p: RefreshPolicy) -> String {
    match p {
        RefreshPolicy::EveryFrame => "every-frame".into(),
        RefreshPolicy::OnChange => "on-change".into(),
        RefreshPolicy::EveryN(n) => format!("every-n ({n})"),
    }
}

/// A frame's image files: its views, their direction images and the cube's faces, said as
/// they are written where `said` (a single frame: a sequence says its frames).
fn write_frame(out: &Transaction, dir: &Path, images: &FrameImages, said: bool) -> Result<()> {
    let mut files = ImageFiles::default();
    if let Some(img) = &images.observer {
        files.exr_and_png(dir, "observer", img);
    }
    if let Some(img) = &images.sensor {
        files.exr_and_png(dir, "sensor", img);
    }
    if let Some(img) = &images.pair {
        files.png(dir.join("views.png"), img);
    }
    if let Some(img) = &images.observer_direction {
        files.exr(dir.join("observer.direction.exr"), img);
    }
    if let Some(img) = &images.sensor_direction {
        files.exr(dir.join("sensor.direction.exr"), img);
    }
    if let Some(faces) = &images.cube {
        for (face, img) in FACE_NAMES.iter().zip(faces) {
            files.exr(dir.join("cube").join(format!("{face}.exr")), img);
        }
    }
    files.write(out, said.then_some("render"))
}

/// The sensor outputs of one frame from its ray-map images (`Readback::rays`).
fn write_sensor_outputs(
    out: &Transaction,
    dir: &Path,
    renderer: &mut Renderer,
    (frame, t_s): (u64, f64),
    images: FrameImages,
) -> Result<()> {
    let missing = || anyhow::anyhow!("the frame's sensor ray map was not read back (a bug)");
    let quantities = images.sensor_quantities.ok_or_else(missing)?;
    let sensor = images.sensor.clone().ok_or_else(missing)?;
    let lookup = renderer.scene.mirror.lookup.to_string();
    let mut outputs = SensorOutputs::from_gpu(
        &renderer.scene,
        t_s,
        (&lookup, renderer.sensor_ground_truth()),
        sensor,
        quantities,
        images.cube,
    );
    // The camera image of the whole exposure: the sensor's view at each of its instants (the
    // scene's animations, the mirror's included, at each).
    // Up to 1024 renders a frame, said as they go (they were silent).
    let renders = specchio::sensor::imaging::exposure_renders(&renderer.scene) as u64;
    let what = format!("render: frame {frame}'s exposure at {renders} instants");
    let exposure = Progress::new(what, renders, "renders");
    let light = match renderer.scene.sensor.imaging.clone() {
        Some(imaging) => specchio::sensor::imaging::integrate(&imaging, t_s, |t| {
            // A signal stops them between two.
            specchio::process::interrupt::check(&format!("in frame {frame}'s exposure"))?;
            let readback = Readback {
                sensor: true,
                ..Default::default()
            };
            let (_, images) = renderer.render_frame(frame, t, readback)?;
            exposure.add(1);
            (images.sensor)
                .ok_or_else(|| anyhow::anyhow!("the sensor's view was not read back (a bug)"))
        })?,
        None => None,
    };
    outputs.expose(&renderer.scene, frame, light.as_ref());
    let writing = progress::sensor_outputs("render", &outputs);
    outputs.write(out, dir, &|n| writing.add(n))?;
    Ok(())
}

/// The project's one median (nearest rank: the lower middle of an even count).
fn median(mut v: Vec<f64>) -> Option<f64> {
    specchio::metrics::percentile::median(&mut v)
}

/// Medians over frames: cube update (only frames that updated it) and each view.
fn summarize(reports: &[FrameReport]) -> RenderSummary {
    let updated: Vec<&FrameReport> = reports.iter().filter(|r| r.cube_updated).collect();
    let m = |f: &dyn Fn(&FrameReport) -> Option<f64>, rs: &[&FrameReport]| {
        median(rs.iter().filter_map(|r| f(r)).collect())
    };
    let all: Vec<&FrameReport> = reports.iter().collect();
    RenderSummary {
        frames: reports.len(),
        cube_updates: updated.len(),
        median_gpu_cube_update_ms: m(&|r| r.gpu_cube_ms, &updated),
        median_gpu_observer_ms: m(&|r| r.gpu_observer_ms, &all),
        median_gpu_sensor_ms: m(&|r| r.gpu_sensor_ms, &all),
        median_gpu_views_ms: m(&|r| r.gpu_pair_ms, &all),
        median_submit_wait_ms: m(&|r| Some(r.submit_wait_ms), &all),
        median_cpu_record_ms: m(&|r| Some(r.cpu_record_ms), &all),
    }
}
