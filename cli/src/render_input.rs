//! What `specchio render` takes from its arguments before any work: the scene with the
//! command line's settings (checked against the memory it would take), the frames' times,
//! the lookup, and the refusal of options that would change nothing.

use anyhow::{bail, Context, Result};
use specchio::render::lookups::{self, TraceOrder};
use specchio::scene::{Lookup, Scene};
use specchio::vk::device::DeviceInfo;

use crate::render::Args;

/// Refuses a run whose first or last frame falls at no finite time, or past the latest scene
/// time: each flag is in its own range, but --frame over a tiny --fps (1 / 4.9e-324) is
/// infinite, which the scene's motion cannot be evaluated at (an orbiting object silently
/// dropped out of the image), and a late one loses an orbit's phase.
pub(crate) fn frame_times_are_in_range(args: &Args, start_s: f64) -> Result<()> {
    let last_s = start_s + f64::from(args.frames - 1) / args.fps();
    let latest = specchio::scene::MAX_SCENE_TIME_S;
    if last_s.is_finite() && last_s > latest {
        bail!(
            "the last frame falls at {} s (--time or --frame, --frames, --fps), past the \
             latest scene time ({} s), where an animation's phase is lost: give an earlier \
             --time or --frame, fewer --frames or a larger --fps",
            specchio::text::approx_text(last_s),
            specchio::text::num_text(latest)
        );
    }
    if !(start_s.is_finite() && last_s.is_finite()) {
        bail!(
            "--fps {}: frames {}..{} fall at no finite time (frame / fps overflows); \
             give a larger --fps or --time",
            specchio::text::num_text(args.fps()),
            args.frame.unwrap_or(0),
            args.frame.unwrap_or(0) + u64::from(args.frames - 1)
        );
    }
    Ok(())
}

/// Refuses an option that would change nothing here, rather than take it without a word (and
/// record it in render.json as if it had): the fill's options and the cube's size where the
/// renderer makes no cube (a lookup that samples none, without an id cube),
/// the update options under a refresh policy that re-renders every face whole anyway, the
/// walks' and builds' options with another lookup, --fps for a single frame at a --time.
pub(crate) fn options_apply(args: &Args, scene: &Scene, lookup: Lookup) -> Result<()> {
    let plugin = lookups::plugin(lookup);
    if args.fps.is_some() && args.frame.is_none() && args.frames == 1 {
        bail!(
            "--fps: sets the times of --frame and of --frames beyond the first, and this run \
             renders one frame at --time {}; leave it out, or give --frame or --frames",
            specchio::text::num_text(args.time.unwrap_or(0.0))
        );
    }
    let cube = [
        ("--cube-size", args.cube_size.is_some()),
        ("--method", args.method.is_some()),
        ("--full-updates", args.full_updates),
        ("--whole-faces", args.whole_faces),
    ];
    if let Some((option, _)) = cube.iter().find(|(_, given)| *given) {
        if !needs_cube(args, lookup) {
            bail!(
                "{option}: the {lookup} lookup samples no cube map, so none is made{}; leave \
                 it out, or give a lookup that samples the cube (--lookup box, say)",
                chosen_for_outputs(args)
            );
        }
    }
    let search = [
        ("--distance-steps", args.distance_steps.is_some()),
        ("--secant-steps", args.secant_steps.is_some()),
    ];
    if let Some((option, _)) = search.iter().find(|(_, given)| *given) {
        // The ray map of a cube lookup's sensor outputs searches the cube's depth too.
        let ray_map_searches = args.sensor_outputs && !plugin.traces_ray_map();
        if !plugin.searches_depth() && !ray_map_searches {
            bail!(
                "{option}: only the distance lookups and a cube lookup's sensor outputs search \
                 the cube's depth, and this run's lookup is {lookup}{}; leave it out, or give \
                 --lookup distance",
                chosen_for_outputs(args)
            );
        }
    }
    let updates = [
        ("--full-updates", args.full_updates),
        ("--whole-faces", args.whole_faces),
    ];
    if let Some((option, _)) = updates.iter().find(|(_, given)| *given) {
        use specchio::scene::RefreshPolicy;
        let policy = match scene.refresh {
            RefreshPolicy::OnChange => None,
            RefreshPolicy::EveryFrame => Some("\"every-frame\"".to_owned()),
            RefreshPolicy::EveryN(n) => Some(format!("\"every-n\" (n = {n})")),
        };
        if let Some(policy) = policy {
            bail!(
                "{option}: changes only updates on change, and {} sets refresh.policy = \
                 {policy}: every update re-renders all six faces whole; leave it out, or set \
                 the policy to \"on-change\"",
                args.scene.display(),
            );
        }
    }
    let walks = [
        ("--trace-in", args.trace_in.is_some()),
        ("--bvh-layout", args.bvh_layout.is_some()),
    ];
    if let Some((option, _)) = walks.iter().find(|(_, given)| *given) {
        if lookup != Lookup::Bvh {
            bail!(
                "{option}: only the bvh lookup walks trees of its own, and this run's lookup \
                 is {lookup}; leave it out, or give --lookup bvh"
            );
        }
    }
    if args.footprint {
        footprint_applies(args, scene, lookup)?;
    }
    if args.trace_order.is_some() && !plugin.builds_scene_trace() {
        bail!(
            "--trace-order: only the ray-query and distance-exact lookups build acceleration \
             structures, and this run's lookup is {lookup}{}; leave it out, or give --lookup \
             ray-query",
            chosen_for_outputs(args)
        );
    }
    Ok(())
}

/// `--footprint` marks what the mirror's footprint filter reads of the cube: with a cube
/// lookup alone, and with nothing else reading the cube.
fn footprint_applies(args: &Args, scene: &Scene, lookup: Lookup) -> Result<()> {
    if let specchio::scene::RefreshPolicy::EveryN(n @ 2..) = scene.refresh {
        bail!(
            "--footprint: {} sets refresh.policy = \"every-n\" (n = {n}), whose cube shows an \
             older state between its updates, where a tile the views come to need could be \
             filled only with the newer one: every tile is filled; leave it out, or set the \
             policy to \"on-change\" or \"every-frame\"",
            args.scene.display()
        );
    }
    if args.sensor_outputs {
        bail!(
            "--footprint: --sensor-outputs reads the cube's ids and depth for the ray map, all \
             of them; leave one of the two out"
        );
    }
    if !lookups::plugin(lookup).marks_footprint() {
        bail!(
            "--footprint: only the cube lookups' reads of the cube (plain, box) can be \
             marked, and this run's lookup is {lookup}{}: {}; leave it out, or give --lookup box",
            chosen_for_outputs(args),
            match lookups::plugin(lookup).uses_cube() {
                true => "its search reads the cube's depth wherever it goes",
                false => "it samples no cube",
            }
        );
    }
    Ok(())
}

/// `result`, unless a signal came while it was made: then the stop, said as `at` (work a
/// signal cut short reports the signal, not the error it stopped with).
pub(crate) fn unless_stopped<T, E>(result: Result<T, E>, at: &str) -> Result<T>
where
    E: Into<anyhow::Error>,
{
    specchio::process::interrupt::check(at)?;
    result.map_err(Into::into)
}

/// The scene with the command line's search settings, checked against what the command was
/// asked to write and against the memory it would take.
pub(crate) fn load_scene(args: &Args) -> Result<Scene> {
    let mut scene = specchio::scene::load(&args.scene)?;
    if let Some(n) = args.distance_steps {
        scene.mirror.distance_steps = n;
    }
    if let Some(n) = args.secant_steps {
        scene.mirror.secant_steps = n;
    }
    // No cube where the lookup needs none (`RenderOptions::lookup_fixed`): one given, or the
    // traced one --sensor-outputs picks by the device without --lookup.
    let face_size_px = match known_lookup(args, &scene) {
        Some(lookup) if !needs_cube(args, lookup) => 0,
        None => 0,
        Some(_) => args.cube_size.unwrap_or(scene.cube.face_size_px),
    };
    specchio::memory::estimates::render(&scene, face_size_px, args.directions, args.sensor_outputs)
        .with_context(|| args.scene.display().to_string())?;
    Ok(scene)
}

/// The lookup the frames use where it is known before a device is chosen: `--lookup`, else the
/// scene's unless `--sensor-outputs` picks one by the device ([`chosen_lookup`]: a traced one,
/// which samples no cube).
fn known_lookup(args: &Args, scene: &Scene) -> Option<Lookup> {
    match (args.lookup, args.sensor_outputs) {
        (Some(lookup), _) => Some(lookup),
        (None, false) => Some(scene.mirror.lookup),
        (None, true) => None,
    }
}

/// Whether this run's renderer of `lookup` makes a cube: the lookup samples one, or the sensor
/// outputs' ray map reads range and ids through the id cube.
pub(crate) fn needs_cube(args: &Args, lookup: Lookup) -> bool {
    lookups::needs_cube(lookup, id_cube(args, lookup))
}

/// Whether the renderer makes the id cube: range and ids through the cube only when asked for,
/// so timings never pay (a lookup that traces the ray map needs none).
pub(crate) fn id_cube(args: &Args, lookup: Lookup) -> bool {
    args.sensor_outputs && !lookups::traces_ray_map(lookup)
}

/// The lookup the frames use: `--lookup`; else, for `--sensor-outputs`, the first that traces
/// and that the device runs, the faster there (`bvh` on CPU drivers, `ray-query` on a GPU with
/// ray queries, `bvh` on any other: each lookup's `ground_truth_rank`), so that
/// the colour, the range and the ids are traced along one light path; else the scene's.
pub(crate) fn chosen_lookup(args: &Args, scene: &Scene, device: &DeviceInfo) -> Lookup {
    let traced = || lookups::one_light_path(device, scene).filter(|_| args.sensor_outputs);
    args.lookup.or_else(traced).unwrap_or(scene.mirror.lookup)
}

/// ", chosen for the sensor outputs" where `--sensor-outputs` chose the lookup (no
/// `--lookup`): the user named none.
fn chosen_for_outputs(args: &Args) -> &'static str {
    match (args.lookup, args.sensor_outputs) {
        (None, true) => " (the lookup --sensor-outputs traces with, given no --lookup)",
        _ => "",
    }
}

impl Args {
    /// `--method`, or six-pass where it is not given.
    pub(crate) fn method_name(&self) -> &str {
        self.method.as_deref().unwrap_or("six-pass")
    }

    /// `--fps`, or 30 where it is not given.
    pub(crate) fn fps(&self) -> f64 {
        self.fps.unwrap_or(30.0)
    }

    /// `--trace-order`, or split where it is not given.
    pub(crate) fn trace_order(&self) -> TraceOrder {
        self.trace_order.unwrap_or(TraceOrder::Split)
    }
}
