//! The experiment's answers: each query judged against the truth, summarised per row (one
//! landmark source, one query source, one query time), as JSON and a table.

use glam::Vec3;
use serde::Serialize;
use specchio::metrics::percentile::percentile;
use specchio::render::methods::Method;
use specchio::sensor::localise::{self, position, Descriptor, Signature};

#[derive(Serialize)]
pub struct QueryResult {
    pub position_m: [f32; 3],
    pub heading_deg: f64,
    /// The landmark nearest to the true position (the right answer).
    pub nearest_landmark: usize,
    /// The three best matches, best first.
    pub matches: Vec<usize>,
    /// The best match's distance from the true position.
    pub position_error_m: f64,
    /// The position fitted to the descriptor distances around the best match, within its
    /// grid cell (`specchio::sensor::localise::position`), and its distance from the truth.
    pub fitted_position_m: [f32; 3],
    pub fitted_position_error_m: f64,
    pub heading_estimate_deg: f64,
    pub heading_error_deg: f64,
}

#[derive(Serialize)]
pub struct Summary {
    pub landmarks: usize,
    pub queries: usize,
    pub recall_at_1: f64,
    pub recall_at_3: f64,
    pub median_position_error_m: f64,
    pub p90_position_error_m: f64,
    /// The fitted position's error.
    pub median_fitted_position_error_m: f64,
    pub p90_fitted_position_error_m: f64,
    pub median_heading_error_deg: f64,
    pub p90_heading_error_deg: f64,
    /// One panorama column in degrees: the heading's natural resolution.
    pub column_deg: f64,
}

/// One source's landmark sweep: sensor images per second (render or trace, read back,
/// unwrap, describe), none when its landmarks were loaded (`--landmarks`).
#[derive(Serialize)]
pub struct SourceRun {
    pub source: &'static str,
    pub landmarks_file: String,
    pub sweep_seconds: Option<f64>,
    pub sweep_images_per_s: Option<f64>,
}

/// One experiment: landmarks from one source, queries from one (the same, or the reference).
#[derive(Serialize)]
pub struct Row {
    pub landmarks_from: &'static str,
    pub queries_from: &'static str,
    pub query_time_s: f64,
    /// The landmark source's sweep speed (sensor images/s), none for loaded landmarks.
    pub landmark_images_per_s: Option<f64>,
    pub summary: Summary,
    pub per_query: Vec<QueryResult>,
}

#[derive(Serialize)]
pub struct Report {
    pub scene: String,
    pub descriptor: &'static str,
    pub coefficients: u32,
    pub grid_m: f64,
    pub seed: u64,
    pub queries_at_landmarks: bool,
    pub sensor_px: u32,
    pub cube_px: u32,
    pub method: Method,
    pub device: Option<String>,
    pub lp_num_threads: Option<String>,
    pub sources: Vec<SourceRun>,
    pub rows: Vec<Row>,
    pub validation_messages: usize,
}

/// Every query of one row matched against one landmark database.
pub fn row(
    descriptor: &dyn Descriptor,
    (landmarks_from, database, positions): (&'static str, &[Signature], &[Vec3]),
    (queries_from, queries, truth): (&'static str, &[Signature], &[(Vec3, f64)]),
    query_time_s: f64,
    (column_deg, grid_m): (f64, f64),
) -> Row {
    let per_query: Vec<QueryResult> = queries
        .iter()
        .zip(truth)
        .map(|(q, &t)| judge(descriptor, (database, positions, grid_m), q, t))
        .collect();
    Row {
        landmarks_from,
        queries_from,
        query_time_s,
        landmark_images_per_s: None,
        summary: summarize(&per_query, database.len(), column_deg),
        per_query,
    }
}

/// One query's answer against the truth.
fn judge(
    descriptor: &dyn Descriptor,
    (database, positions, grid_m): (&[Signature], &[Vec3], f64),
    query: &Signature,
    (truth, heading): (Vec3, f64),
) -> QueryResult {
    let distances = localise::distances(descriptor, database, query);
    let order = localise::rank(&distances);
    let best = order[0];
    let nearest = (0..positions.len())
        .min_by(|&a, &b| {
            positions[a]
                .distance(truth)
                .total_cmp(&positions[b].distance(truth))
        })
        .expect("at least one landmark");
    let fitted = position::fit_position(positions, &distances, best, grid_m);
    let estimate = descriptor.turn(&database[best], query).to_degrees();
    let true_deg = heading.to_degrees();
    QueryResult {
        position_m: truth.to_array(),
        heading_deg: true_deg,
        nearest_landmark: nearest,
        matches: order.into_iter().take(3).collect(),
        position_error_m: f64::from(positions[best].distance(truth)),
        fitted_position_m: fitted.to_array(),
        fitted_position_error_m: f64::from(fitted.distance(truth)),
        heading_estimate_deg: estimate,
        heading_error_deg: ((estimate - true_deg + 180.0).rem_euclid(360.0) - 180.0).abs(),
    }
}

fn summarize(results: &[QueryResult], landmarks: usize, column_deg: f64) -> Summary {
    let n = results.len() as f64;
    let share =
        |f: &dyn Fn(&QueryResult) -> bool| results.iter().filter(|r| f(r)).count() as f64 / n;
    let mut pos: Vec<f64> = results.iter().map(|r| r.position_error_m).collect();
    let mut fitted: Vec<f64> = results.iter().map(|r| r.fitted_position_error_m).collect();
    let mut head: Vec<f64> = results.iter().map(|r| r.heading_error_deg).collect();
    let p = |v: &mut [f64], q| percentile(v, q).unwrap_or(f64::NAN);
    Summary {
        landmarks,
        queries: results.len(),
        recall_at_1: share(&|r| r.matches[0] == r.nearest_landmark),
        recall_at_3: share(&|r| r.matches.contains(&r.nearest_landmark)),
        median_position_error_m: p(&mut pos, 0.5),
        p90_position_error_m: p(&mut pos, 0.9),
        median_fitted_position_error_m: p(&mut fitted, 0.5),
        p90_fitted_position_error_m: p(&mut fitted, 0.9),
        median_heading_error_deg: p(&mut head, 0.5),
        p90_heading_error_deg: p(&mut head, 0.9),
        column_deg,
    }
}

/// The printed table: one line per row, then the sweeps.
pub fn print_table(r: &Report, out: &std::path::Path) {
    print_title(r);
    print_column_heads();
    for row in &r.rows {
        print_row(row);
    }
    for s in &r.sources {
        print_sweep(s);
    }
    specchio::say!(
        "  files: localise.json, localise.svg and the landmark files in {}",
        out.display()
    );
}

/// The table's title line: the scene and the experiment's settings.
fn print_title(r: &Report) {
    specchio::say!(
        "localisation in {} (grid {} m, {} k={}, {}² sensor, {}² cube, a panorama column {:.3}°)",
        r.scene,
        r.grid_m,
        r.descriptor,
        r.coefficients,
        r.sensor_px,
        r.cube_px,
        r.rows
            .first()
            .map_or(f64::NAN, |row| row.summary.column_deg)
    );
}

/// The table's two heading lines: the columns' names, then their units.
fn print_column_heads() {
    specchio::say!(
        "  {:<14} {:<14} {:>6} {:>9} {:>8} {:>8} {:>12} {:>10} {:>12} {:>10} {:>10} {:>9}",
        "landmarks",
        "queries",
        "time",
        "landmarks",
        "recall@1",
        "recall@3",
        "position m",
        "",
        "fitted m",
        "",
        "heading °",
        "sweep"
    );
    specchio::say!(
        "  {:<14} {:<14} {:>6} {:>9} {:>8} {:>8} {:>12} {:>10} {:>12} {:>10} {:>10} {:>9}",
        "from",
        "from",
        "s",
        "",
        "%",
        "%",
        "median",
        "p90",
        "median",
        "p90",
        "median",
        "images/s"
    );
}

/// One row's line of the table: its sources, query time and summary.
fn print_row(row: &Row) {
    let s = &row.summary;
    specchio::say!(
        "  {:<14} {:<14} {:>6} {:>9} {:>8.1} {:>8.1} {:>12.3} {:>10.3} {:>12.3} {:>10.3} {:>10.2} {:>9}",
        row.landmarks_from,
        row.queries_from,
        row.query_time_s,
        s.landmarks,
        100.0 * s.recall_at_1,
        100.0 * s.recall_at_3,
        s.median_position_error_m,
        s.p90_position_error_m,
        s.median_fitted_position_error_m,
        s.p90_fitted_position_error_m,
        s.median_heading_error_deg,
        row.landmark_images_per_s
            .map_or("loaded".to_owned(), |r| format!("{r:.2}"))
    );
}

/// One source's landmark sweep line: its speed, or that its landmarks were loaded.
fn print_sweep(s: &SourceRun) {
    match s.sweep_images_per_s {
        Some(rate) => specchio::say!(
            "  {} landmark sweep: {rate:.2} sensor images/s ({:.2} s) -> {}",
            s.source,
            s.sweep_seconds.unwrap_or(f64::NAN),
            s.landmarks_file
        ),
        None => specchio::say!(
            "  {} landmarks loaded (no sweep) -> {}",
            s.source,
            s.landmarks_file
        ),
    }
}
