//! `specchio reference`: the exact mirror, ray traced on the CPU, for judging the cube map.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use specchio::output::{Sink, Transaction};
use specchio::process::traced::{self, StoppedAt};
use specchio::process::{interrupt, progress};
use specchio::reference::{ReferenceImages, MAX_SPP};
use specchio::sensor::SensorOutputs;

use crate::image_files::ImageFiles;
use crate::records::{ReferenceCameras, ReferenceRecord};
use specchio::process::args::{seconds, whole};

#[derive(clap::Args)]
pub struct Args {
    /// The scene file (TOML; see docs/scene-format.md).
    scene: PathBuf,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Scene time in seconds (0 to 1e9).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true,
          value_parser = seconds)]
    time: f64,
    /// Samples per pixel on a fixed stratified grid, 1..=4096; 1 traces pixel centres only.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1, value_parser = whole(1..=MAX_SPP))]
    spp: u32,
    /// Also write the sensor outputs: ray map, range, object ids, panoramas and camera.json
    /// (docs/sensor.md).
    #[arg(long)]
    sensor_outputs: bool,
}

pub fn run(args: &Args) -> Result<ExitCode> {
    // --time and --spp were range-checked by clap (`specchio::process::args`).
    interrupt::catch();
    let loaded = specchio::scene::load(&args.scene);
    let scene = crate::render_input::unless_stopped(loaded, "while loading the scene")?;
    let instants = match args.sensor_outputs {
        true => specchio::sensor::imaging::exposure_renders(&scene),
        false => 0,
    };
    if let Some(why) = specchio::reference::too_many_paths(&scene, args.spp, instants) {
        bail!("{}: --{why}", args.scene.display());
    }
    specchio::memory::estimates::reference(&scene, args.sensor_outputs)
        .with_context(|| args.scene.display().to_string())?;
    // All or nothing: written into a hidden folder beside --out, renamed into place at the end.
    let mut out = Transaction::new();
    out.folder(&args.out, "reference.json")?;
    let signalled = || interrupt::check("").is_err();
    let traced = traced::trace(
        (&scene, args.time, args.spp),
        args.sensor_outputs,
        "reference",
        &signalled,
    )
    .map_err(|StoppedAt(at)| interrupt::stopped(&at))?;
    let cameras = [("observer", &traced.observer), ("sensor", &traced.sensor)];
    let mut files = ImageFiles::default();
    for (name, (images, _)) in cameras {
        image_files(&mut files, &args.out, name, images);
    }
    files.write(&out, Some("reference"))?;
    for (name, (images, stats)) in cameras {
        specchio::say!(
            "{name}: {}x{}, {} spp, {} rays in {:.0} ms ({:.2} M rays/s), {} mirror pixels, {} misses",
            images.color.width,
            images.color.height,
            stats.spp,
            stats.rays,
            stats.trace_ms,
            stats.rays_per_second / 1e6,
            stats.mirror_pixels,
            stats.misses
        );
    }
    if args.sensor_outputs {
        let mut outputs = SensorOutputs::from_reference(&scene, args.time, &traced.sensor.0);
        outputs.expose(&scene, 0, traced.light.as_ref());
        let writing = progress::sensor_outputs("reference", &outputs);
        outputs.write(&out, &args.out, &|n| writing.add(n))?;
    }
    let geometry = &traced.reference.geometry;
    specchio::say!(
        "BVH: {} object triangles, {} meshes' trees built in {:.1} ms, the top level over {} objects in {:.1} ms; the room's walls are an analytic box",
        geometry.triangle_count(),
        scene.meshes.len(),
        geometry.mesh_build.as_secs_f64() * 1e3,
        scene.objects.len(),
        geometry.top_build.as_secs_f64() * 1e3
    );
    let [observer, sensor] = [traced.observer.1, traced.sensor.1];
    let record = ReferenceRecord {
        scene: args.scene.display().to_string(),
        time_s: args.time,
        spp: args.spp,
        origin: scene.origin.to_array(),
        triangles: geometry.triangle_count(),
        bvh_meshes_ms: geometry.mesh_build.as_secs_f64() * 1e3,
        bvh_top_level_ms: geometry.top_build.as_secs_f64() * 1e3,
        threads: rayon_threads(),
        cameras: ReferenceCameras { observer, sensor },
    };
    out.write_json(&args.out.join("reference.json"), &record)?;
    // A signal that came after the last check still stops the run: nothing is placed.
    interrupt::check("before placing the output")?;
    out.commit()?;
    Ok(ExitCode::SUCCESS)
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
}

/// A camera's image files: its colour (EXR and PNG), and its direction, distance and object
/// layers.
fn image_files<'a>(
    files: &mut ImageFiles<'a>,
    dir: &Path,
    name: &str,
    images: &'a ReferenceImages,
) {
    files.exr_and_png(dir, name, &images.color);
    files.exr(dir.join(format!("{name}.direction.exr")), &images.direction);
    files.exr(dir.join(format!("{name}.distance.exr")), &images.distance);
    files.exr(dir.join(format!("{name}.object.exr")), &images.object);
}
