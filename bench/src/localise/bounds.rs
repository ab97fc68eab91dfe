//! What one `specchio localise` run may take, checked before any query pose is made: the
//! images it renders, the cells its matching compares and the memory it holds; and a warning
//! when the landmark file it writes will be too large to read back.

use anyhow::{bail, Context, Result};

use super::{database, Args, Plan, Source};

/// The most sensor images one run renders or traces (landmarks and queries, every source):
/// each option is bounded, but their product must be too.
const MAX_IMAGES: u64 = 200_000;

/// The most cells one run's matching compares (every row's queries against its landmarks,
/// `Descriptor::pair_cost` each): about a day at the 4.8e9 cells/s measured on 2 cores (600
/// column-shift queries against 190 landmarks in 16 s).
const MAX_MATCH_CELLS: f64 = 4e14;

/// Refuses a run whose images (landmark sweeps plus queries at every time, per source)
/// exceed [`MAX_IMAGES`], or whose matching exceeds [`MAX_MATCH_CELLS`], before any query
/// pose is made.
pub(super) fn check_work(args: &Args, plan: &Plan) -> Result<()> {
    let sources = plan.sources.len() as u64;
    let sweeps = if plan.saved.is_some() {
        sources - 1
    } else {
        sources
    };
    let landmarks = plan.landmark_poses.len() as u64 * sweeps;
    let queries = u64::from(args.queries) * plan.times.len() as u64 * sources;
    let images = landmarks.saturating_add(queries);
    if images > MAX_IMAGES {
        bail!(
            "this run would render {images} sensor images ({} landmarks x {sweeps} sweeps, \
             {} queries x {} times x {sources} sources), more than the {MAX_IMAGES} one run may: \
             fewer --queries, --times or --sources",
            plan.landmark_poses.len(),
            args.queries,
            plan.times.len()
        );
    }
    // Rows per time: each source against itself, and each lookup against the reference.
    let cross = match plan.sources.contains(&Source::Reference) {
        true => sources - 1,
        false => 0,
    };
    let rows = (sources + cross) as f64 * plan.times.len() as f64;
    let (w, h) = (plan.body.layout.width, plan.body.layout.height);
    let cells = rows
        * f64::from(args.queries)
        * plan.landmark_poses.len() as f64
        * plan.descriptor.pair_cost(w, h) as f64;
    if cells > MAX_MATCH_CELLS {
        bail!(
            "matching this run's queries would compare {cells:.1e} cells ({rows} row(s) of {} \
             queries x {} landmarks, {} cells each with {} k={}), more than the {MAX_MATCH_CELLS:.0e} \
             (about a day on 2 cores) one run may: fewer --queries, a larger --grid or a smaller --k",
            args.queries,
            plan.landmark_poses.len(),
            plan.descriptor.pair_cost(w, h),
            plan.descriptor.name(),
            plan.k
        );
    }
    warn_if_unreadable(plan);
    Ok(())
}

/// Says before the sweep when the landmark file this run writes will be larger than
/// `--landmarks` reads back: the run is fine, but its database cannot be reused as it is.
fn warn_if_unreadable(plan: &Plan) {
    /// A signature value as the landmark file writes it: a shortest f32 in pretty JSON, on its
    /// own indented line (measured: about 22 bytes).
    const BYTES_PER_VALUE: u64 = 22;
    let (w, h) = (plan.body.layout.width, plan.body.layout.height);
    let values = plan.descriptor.shape(w, h).1 as u64;
    let bytes = (plan.landmark_poses.len() as u64)
        .saturating_mul(values)
        .saturating_mul(BYTES_PER_VALUE);
    if bytes > database::MAX_LANDMARKS_FILE_BYTES {
        specchio::say_err!(
            "localise: warning: landmarks.json will be about {} MiB ({} landmarks of {values} \
             values), more than the {} MiB --landmarks reads back; a larger --grid or a smaller \
             --k keeps the database reusable",
            bytes >> 20,
            plan.landmark_poses.len(),
            database::MAX_LANDMARKS_FILE_BYTES >> 20
        );
    }
}

/// The memory the run will hold at once (one renderer, the sensor, every source's landmark
/// signatures), against the budget.
pub(super) fn check_memory(args: &Args, plan: &Plan) -> Result<()> {
    // A signature is at most 16k values a panorama row (column-shift; fourier keeps 2k).
    let values = u64::from(plan.body.layout.height)
        * u64::from(specchio::sensor::localise::shift::COLUMNS_PER_K)
        * u64::from(plan.k);
    let landmarks = plan.landmark_poses.len() as u64 * plan.sources.len() as u64;
    // The cube `--cube-size` makes, where a source fills one (the scene's own size is not
    // used: the estimate once counted it whatever --cube-size said, and its hint failed).
    let fills_cube = plan.sources.iter().any(|&s| super::checks::samples_cube(s));
    let cube_px = fills_cube.then(|| args.cube_size_or_default());
    let scene = &plan.body.scene;
    specchio::memory::estimates::localise(scene, args.sensor_size, cube_px, landmarks, values)
        .with_context(|| args.scene.display().to_string())
}
