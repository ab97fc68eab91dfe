//! `specchio reference`: the exact mirror, ray traced on the CPU, for judging the cube map.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::{bail, Context, Result};
use specchio::output::{Sink, Transaction};
use specchio::reference::render::Watch;
use specchio::reference::{Reference, ReferenceImages, ReferenceStats, MAX_SPP};
use specchio::sensor::{imaging, SensorOutputs};

use crate::records::{ReferenceCameras, ReferenceRecord};
use specchio::process::args::{real, whole};
use specchio::process::progress::Progress;

#[derive(clap::Args)]
pub struct Args {
    /// The scene file (TOML; see docs/scene-format.md).
    scene: PathBuf,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Scene time in seconds (finite, >= 0).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true,
          value_parser = real(0.0, false, f64::INFINITY))]
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
    let scene = specchio::scene::load(&args.scene)?;
    if let Some(why) = specchio::reference::too_many_paths(&scene, args.spp) {
        bail!("{}: --{why}", args.scene.display());
    }
    specchio::memory::estimates::reference(&scene, args.sensor_outputs)
        .with_context(|| args.scene.display().to_string())?;
    // All or nothing: written into a hidden folder beside --out, renamed into place at the end.
    let mut out = Transaction::new();
    out.folder(&args.out, "reference.json")?;
    specchio::process::interrupt::catch();
    let reference = Reference::new(&scene, args.time);
    // Filled in the order traced: observer, sensor.
    let mut cameras: [ReferenceStats; 2] = Default::default();
    let ([ow, oh], [sw, sh]) = (scene.observer.resolution, scene.sensor.resolution);
    // One estimate for the whole command, both cameras, in pixels (their rows differ in
    // width): an estimate of the observer alone said "about a minute left" with the larger
    // sensor still to come.
    let whole = Progress::new(
        format!(
            "reference: observer {ow}x{oh} and sensor {sw}x{sh} cameras at {} spp",
            args.spp
        ),
        u64::from(ow) * u64::from(oh) + u64::from(sw) * u64::from(sh),
        "pixels",
    );
    for (slot, (name, view, [w, h])) in cameras.iter_mut().zip([
        ("observer", reference.observer_view(), [ow, oh]),
        ("sensor", reference.sensor_view(), [sw, sh]),
    ]) {
        specchio::process::interrupt::check(&format!("before tracing the {name} camera"))?;
        let rows = CameraRows::new(&whole, w);
        let Some((images, stats)) = reference.render_watched(&view, w, h, args.spp, &rows) else {
            let at = format!("after {} of {h} rows of the {name} camera", rows.done());
            return Err(specchio::process::interrupt::stopped(&at).into());
        };
        write_images(&out, &args.out, name, &images)?;
        if name == "sensor" && args.sensor_outputs {
            let mut outputs = SensorOutputs::from_reference(&scene, args.time, &images);
            let light = imaging::traced_exposure(&scene, args.time, args.spp, [w, h]);
            outputs.expose(&scene, 0, light.as_ref());
            outputs.write(&out, &args.out)?;
        }
        specchio::say!(
            "{name}: {w}x{h}, {} spp, {} rays in {:.0} ms ({:.2} M rays/s), {} mirror pixels, {} misses",
            stats.spp,
            stats.rays,
            stats.trace_ms,
            stats.rays_per_second / 1e6,
            stats.mirror_pixels,
            stats.misses
        );
        *slot = stats;
    }
    let geometry = &reference.geometry;
    specchio::say!(
        "BVH: {} object triangles, {} meshes' trees built in {:.1} ms, the top level over {} objects in {:.1} ms; the room's walls are an analytic box",
        geometry.triangle_count(),
        scene.meshes.len(),
        geometry.mesh_build.as_secs_f64() * 1e3,
        scene.objects.len(),
        geometry.top_build.as_secs_f64() * 1e3
    );
    let [observer, sensor] = cameras;
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
    specchio::process::interrupt::check("before placing the output")?;
    out.commit()?;
    Ok(ExitCode::SUCCESS)
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
}

fn write_images(out: &Transaction, dir: &Path, name: &str, images: &ReferenceImages) -> Result<()> {
    out.write_exr(&dir.join(format!("{name}.exr")), &images.color)?;
    out.write_png(&dir.join(format!("{name}.png")), &images.color)?;
    out.write_exr(
        &dir.join(format!("{name}.direction.exr")),
        &images.direction,
    )?;
    out.write_exr(&dir.join(format!("{name}.distance.exr")), &images.distance)?;
    out.write_exr(&dir.join(format!("{name}.object.exr")), &images.object)?;
    Ok(())
}

/// One camera's rows, counted into the command's whole progress as pixels and on their own
/// (for the message of a stop).
struct CameraRows<'a> {
    whole: &'a Progress,
    width: u64,
    rows: AtomicU64,
}

impl<'a> CameraRows<'a> {
    fn new(whole: &'a Progress, width: u32) -> Self {
        Self {
            whole,
            width: u64::from(width),
            rows: AtomicU64::new(0),
        }
    }

    fn done(&self) -> u64 {
        self.rows.load(Ordering::Relaxed)
    }
}

impl Watch for CameraRows<'_> {
    fn row_done(&self) {
        self.rows.fetch_add(1, Ordering::Relaxed);
        self.whole.add(self.width);
    }

    fn stop(&self) -> bool {
        self.whole.stopped()
    }
}
