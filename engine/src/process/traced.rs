//! A reference run said as it goes: the observer and sensor cameras and, where asked, the
//! sensor's exposure (an exact render at each of its instants: motion blur, a rolling shutter)
//! counted as pixels under one estimate, and stopped before any pixel when the caller says.
//! `specchio reference` and Python's `specchio.reference` both trace through here, so both
//! say the same estimate and both stop within a pixel of a Ctrl-C.

use std::sync::atomic::{AtomicU64, Ordering};

use super::progress::Progress;
use crate::image::RgbaImage;
use crate::reference::{Reference, ReferenceImages, ReferenceStats};
use crate::scene::Scene;
use crate::sensor::imaging;
use crate::watch::{Stopped, Watch};

/// What a reference run traced: the reference it built (its trees, for what the caller says
/// of them), each camera's images and statistics, and the light of the sensor's whole
/// exposure where it was asked for and spans more than one instant.
pub struct Traced<'s> {
    pub reference: Reference<'s>,
    pub observer: (ReferenceImages, ReferenceStats),
    pub sensor: (ReferenceImages, ReferenceStats),
    pub light: Option<RgbaImage>,
}

/// Where a stopped run was, for its message: "after 12 of 600 rows of the observer camera".
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StoppedAt(pub String);

/// Traces `scene`'s two cameras at `time`, `spp` samples a pixel, and, with `exposure`, the
/// sensor's exposure, saying the estimate as `what` ("reference", the caller's name) once the
/// work has run for a moment; `stop` is asked before every pixel. One scene and one time for
/// all of it: the reference is built here.
pub fn trace<'s>(
    (scene, time, spp): (&'s Scene, f64, u32),
    exposure: bool,
    what: &str,
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<Traced<'s>, StoppedAt> {
    let reference = Reference::new(scene, time);
    let ([ow, oh], [sw, sh]) = (scene.observer.resolution, scene.sensor.resolution);
    let instants = match exposure {
        true => imaging::exposure_renders(scene),
        false => 0,
    };
    // One estimate for the whole run in pixels (the cameras' rows differ in width): an
    // estimate of the observer alone said "about a minute left" with the larger sensor and
    // its exposure still to come.
    let sensor_pixels = u64::from(sw) * u64::from(sh);
    let whole = Progress::new(
        whole_text(what, [[ow, oh], [sw, sh]], spp, instants),
        u64::from(ow) * u64::from(oh) + sensor_pixels * (1 + instants as u64),
        "pixels",
    );
    let camera = |name: &str, view, [w, h]: [u32; 2]| {
        let rows = Rows::new(&whole, w, stop);
        reference
            .render_watched(&view, w, h, spp, &rows)
            .map_err(|Stopped| {
                StoppedAt(format!(
                    "after {} of {h} rows of the {name} camera",
                    rows.done()
                ))
            })
    };
    let observer = camera("observer", reference.observer_view(), [ow, oh])?;
    let sensor = camera("sensor", reference.sensor_view(), [sw, sh])?;
    let light = match instants {
        0 => None,
        _ => {
            let rows = Rows::new(&whole, sw, stop);
            imaging::traced_exposure(scene, time, spp, [sw, sh], &rows).map_err(|Stopped| {
                let done = rows.done() / u64::from(sh.max(1));
                StoppedAt(format!(
                    "after {done} of the sensor exposure's {instants} instants"
                ))
            })?
        }
    };
    Ok(Traced {
        reference,
        observer,
        sensor,
        light,
    })
}

/// The estimate's subject: "reference: observer 800x600 and sensor 512x512 cameras at 1 spp,
/// and the sensor's exposure at 1024 instants".
fn whole_text(
    what: &str,
    [[ow, oh], [sw, sh]]: [[u32; 2]; 2],
    spp: u32,
    instants: usize,
) -> String {
    let exposure = match instants {
        0 => String::new(),
        n => format!(", and the sensor's exposure at {n} instants"),
    };
    format!("{what}: observer {ow}x{oh} and sensor {sw}x{sh} cameras at {spp} spp{exposure}")
}

/// One camera's rows, counted into the run's whole progress as pixels and on their own (for
/// the message of a stop).
struct Rows<'a> {
    whole: &'a Progress,
    width: u64,
    rows: AtomicU64,
    stop: &'a (dyn Fn() -> bool + Sync),
}

impl<'a> Rows<'a> {
    fn new(whole: &'a Progress, width: u32, stop: &'a (dyn Fn() -> bool + Sync)) -> Self {
        Self {
            whole,
            width: u64::from(width),
            rows: AtomicU64::new(0),
            stop,
        }
    }

    fn done(&self) -> u64 {
        self.rows.load(Ordering::Relaxed)
    }
}

impl Watch for Rows<'_> {
    fn rows_done(&self, rows: u32) {
        self.rows.fetch_add(u64::from(rows), Ordering::Relaxed);
        self.whole.add(self.width * u64::from(rows));
    }

    fn stop(&self) -> bool {
        (self.stop)()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small_scene(imaging: &str) -> Scene {
        let text = format!(
            "[room]\ncenter = [0, 3, 0]\nsize = [10, 6, 10]\nwalls = \"w\"\n\
             [mirror]\ncenter = [0, 3, 0]\nradius = 1\n\
             [[materials]]\nname = \"w\"\ntype = \"color\"\ncolor = [0.5, 0.5, 0.5]\n\
             [observer]\nresolution = [24, 16]\n[sensor]\nresolution = [20, 20]\n{imaging}"
        );
        crate::scene::load_str(&text, std::path::Path::new("traced.toml")).expect("scene")
    }

    /// Unstopped, the run is the two cameras the reference traces on its own, and the
    /// exposure's light where one is asked for and spans instants.
    #[test]
    fn a_run_traces_what_the_reference_traces() {
        let blur = "[sensor.imaging]\nexposure_s = 0.01\nmotion_blur_samples = 4\n";
        let scene = small_scene(blur);
        let run = trace((&scene, 0.0, 1), true, "t", &|| false).expect("run");
        let reference = Reference::new(&scene, 0.0);
        let (alone, _) = reference.render(&reference.sensor_view(), 20, 20, 1);
        assert_eq!(run.sensor.0.color.pixels, alone.color.pixels);
        assert_eq!(run.observer.0.color.width, 24);
        let light = run.light.expect("four instants give the exposure's light");
        assert_eq!((light.width, light.height), (20, 20));
        let without = trace((&scene, 0.0, 1), false, "t", &|| false).expect("run");
        assert!(without.light.is_none());
    }

    /// A stop asked for is honoured before the next pixel, and the message says where: in
    /// the first camera, in the second, or in the exposure.
    #[test]
    fn a_stop_is_honoured_and_placed() {
        let blur = "[sensor.imaging]\nexposure_s = 0.01\nmotion_blur_samples = 3\n";
        let scene = small_scene(blur);
        let stopped = trace((&scene, 0.0, 1), true, "t", &|| true);
        assert_eq!(
            stopped.err(),
            Some(StoppedAt(
                "after 0 of 16 rows of the observer camera".into()
            ))
        );
        // Stops once the observer's 24 x 16 and the sensor's 20 x 20 pixels are asked about.
        let asked = AtomicU64::new(0);
        let after_both = || asked.fetch_add(1, Ordering::SeqCst) >= 24 * 16 + 20 * 20;
        let in_exposure = trace((&scene, 0.0, 1), true, "t", &after_both);
        let message = in_exposure.err().expect("stopped").0;
        assert_eq!(message, "after 0 of the sensor exposure's 3 instants");
    }

    #[test]
    fn the_whole_is_named_with_its_exposure() {
        let cameras = [[800, 600], [512, 512]];
        assert_eq!(
            whole_text("reference", cameras, 4, 0),
            "reference: observer 800x600 and sensor 512x512 cameras at 4 spp"
        );
        assert!(whole_text("reference", cameras, 1, 1024)
            .ends_with("at 1 spp, and the sensor's exposure at 1024 instants"));
    }
}
