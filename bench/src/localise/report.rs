//! The experiment's answers: each query judged against the truth, summarised per row (one
//! landmark source, one query source, one query time), as JSON and a table.

use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;
use specchio::metrics::percentile::percentile;
use specchio::process::progress::Progress;
use specchio::render::methods::Method;
use specchio::sensor::localise::{self, position, Descriptor, Signature};

#[derive(Serialize)]
pub struct QueryResult {
    pub position_m: [f32; 3],
    pub heading_deg: f64,
    /// The landmark nearest to the true position (the right answer).
    pub nearest_landmark: usize,
    /// How far that landmark is from the true position.
    pub nearest_landmark_distance_m: f64,
    /// Whether the query stands on the map: within half a grid cell's diagonal of a landmark,
    /// as every pose inside a cell of four landmarks is. A query off the map stands where
    /// landmarks could not be taken (beside an object at time 0, or where one stood then and
    /// has moved since), so its right answer is a landmark farther than that.
    pub on_map: bool,
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
    /// The queries on the map and their recall (none when no query is on it): place
    /// recognition's usual measure, which counts a query only where the map has a landmark
    /// that could be its answer.
    pub on_map_queries: usize,
    pub recall_at_1_on_map: Option<f64>,
    pub recall_at_3_on_map: Option<f64>,
    /// The queries off the map, and their best match's median distance from the truth.
    pub off_map_queries: usize,
    pub median_position_error_off_map_m: Option<f64>,
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
    /// The cube's face size and fill method; null where no source fills a cube.
    pub cube_px: Option<u32>,
    pub method: Option<Method>,
    pub device: Option<String>,
    pub lp_num_threads: Option<String>,
    pub sources: Vec<SourceRun>,
    pub rows: Vec<Row>,
    pub validation_messages: usize,
}

/// Every query of one row matched against one landmark database, on every core. Matching
/// grows with landmarks times queries, so it is said as it goes and stops at a signal.
pub fn row(
    descriptor: &dyn Descriptor,
    (landmarks_from, database, positions): (&'static str, &[Signature], &[Vec3]),
    (queries_from, queries, truth): (&'static str, &[Signature], &[(Vec3, f64)]),
    query_time_s: f64,
    (column_deg, grid_m): (f64, f64),
    stop: super::Stop,
) -> anyhow::Result<Row> {
    let progress = Progress::new(
        format!(
            "localise: matching {queries_from} queries at {} s against {} {landmarks_from} \
             landmarks",
            specchio::text::num_text(query_time_s),
            database.len()
        ),
        queries.len() as u64,
        "queries",
    );
    let per_query = queries
        .par_iter()
        .zip(truth)
        .map(|(q, &t)| {
            stop("while matching queries")?;
            let judged = judge(descriptor, (database, positions, grid_m), q, t);
            progress.add(1);
            Ok(judged)
        })
        .collect::<anyhow::Result<Vec<QueryResult>>>()?;
    Ok(Row {
        landmarks_from,
        queries_from,
        query_time_s,
        landmark_images_per_s: None,
        summary: summarize(&per_query, database.len(), column_deg),
        per_query,
    })
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
    let nearest_m = f64::from(positions[nearest].distance(truth));
    let fitted = position::fit_position(positions, &distances, best, grid_m);
    let estimate = descriptor.turn(&database[best], query).to_degrees();
    let true_deg = heading.to_degrees();
    QueryResult {
        position_m: truth.to_array(),
        heading_deg: true_deg,
        nearest_landmark: nearest,
        nearest_landmark_distance_m: nearest_m,
        on_map: nearest_m <= on_map_reach_m(grid_m),
        matches: order.into_iter().take(3).collect(),
        position_error_m: f64::from(positions[best].distance(truth)),
        fitted_position_m: fitted.to_array(),
        fitted_position_error_m: f64::from(fitted.distance(truth)),
        heading_estimate_deg: estimate,
        heading_error_deg: ((estimate - true_deg + 180.0).rem_euclid(360.0) - 180.0).abs(),
    }
}

/// The farthest a query on the map can be from every landmark: half a grid cell's diagonal,
/// with room for positions written as decimal text and read back as `f32`.
fn on_map_reach_m(grid_m: f64) -> f64 {
    grid_m * std::f64::consts::FRAC_1_SQRT_2 + 1e-3
}

fn summarize(results: &[QueryResult], landmarks: usize, column_deg: f64) -> Summary {
    let share = |of: &[&QueryResult], f: &dyn Fn(&QueryResult) -> bool| {
        (!of.is_empty()).then(|| of.iter().filter(|r| f(r)).count() as f64 / of.len() as f64)
    };
    let found = |r: &QueryResult| r.matches[0] == r.nearest_landmark;
    let in_three = |r: &QueryResult| r.matches.contains(&r.nearest_landmark);
    let all: Vec<&QueryResult> = results.iter().collect();
    let (on, off): (Vec<&QueryResult>, Vec<&QueryResult>) = all.iter().partition(|r| r.on_map);
    let mut pos: Vec<f64> = results.iter().map(|r| r.position_error_m).collect();
    let mut fitted: Vec<f64> = results.iter().map(|r| r.fitted_position_error_m).collect();
    let mut head: Vec<f64> = results.iter().map(|r| r.heading_error_deg).collect();
    let mut off_pos: Vec<f64> = off.iter().map(|r| r.position_error_m).collect();
    let p = |v: &mut [f64], q| percentile(v, q).unwrap_or(f64::NAN);
    Summary {
        landmarks,
        queries: results.len(),
        recall_at_1: share(&all, &found).unwrap_or(f64::NAN),
        recall_at_3: share(&all, &in_three).unwrap_or(f64::NAN),
        on_map_queries: on.len(),
        recall_at_1_on_map: share(&on, &found),
        recall_at_3_on_map: share(&on, &in_three),
        off_map_queries: off.len(),
        median_position_error_off_map_m: percentile(&mut off_pos, 0.5),
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
    let cube = match (r.cube_px, r.method) {
        (Some(px), Some(m)) => format!("{px}² cube by {m}, "),
        _ => String::new(),
    };
    specchio::say!(
        "localisation in {} (grid {} m, {} k={}, {}² sensor, {}a panorama column {:.3}°)",
        r.scene,
        r.grid_m,
        r.descriptor,
        r.coefficients,
        r.sensor_px,
        cube,
        r.rows
            .first()
            .map_or(f64::NAN, |row| row.summary.column_deg)
    );
}

/// The table's two heading lines: the columns' names, then their units.
fn print_column_heads() {
    specchio::say!(
        "  {:<14} {:<14} {:>6} {:>9} {:>8} {:>8} {:>7} {:>8} {:>12} {:>10} {:>12} {:>10} {:>10} {:>9}",
        "landmarks",
        "queries",
        "time",
        "landmarks",
        "recall@1",
        "recall@3",
        "on map",
        "recall@1",
        "position m",
        "",
        "fitted m",
        "",
        "heading °",
        "sweep"
    );
    specchio::say!(
        "  {:<14} {:<14} {:>6} {:>9} {:>8} {:>8} {:>7} {:>8} {:>12} {:>10} {:>12} {:>10} {:>10} {:>9}",
        "from",
        "from",
        "s",
        "",
        "%",
        "%",
        "queries",
        "on map %",
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
        "  {:<14} {:<14} {:>6} {:>9} {:>8.1} {:>8.1} {:>7} {:>8} {:>12.3} {:>10.3} {:>12.3} {:>10.3} {:>10.2} {:>9}",
        row.landmarks_from,
        row.queries_from,
        row.query_time_s,
        s.landmarks,
        100.0 * s.recall_at_1,
        100.0 * s.recall_at_3,
        s.on_map_queries,
        s.recall_at_1_on_map
            .map_or("-".to_owned(), |r| format!("{:.1}", 100.0 * r)),
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A query whose right answer is landmark `nearest`, `distance_m` from it, answered with
    /// `matches` (best first).
    fn query(nearest: usize, distance_m: f64, matches: [usize; 3], error_m: f64) -> QueryResult {
        QueryResult {
            position_m: [0.0; 3],
            heading_deg: 0.0,
            nearest_landmark: nearest,
            nearest_landmark_distance_m: distance_m,
            on_map: distance_m <= on_map_reach_m(0.5),
            matches: matches.to_vec(),
            position_error_m: error_m,
            fitted_position_m: [0.0; 3],
            fitted_position_error_m: error_m,
            heading_estimate_deg: 0.0,
            heading_error_deg: 0.0,
        }
    }

    /// On a 0.5 m grid every pose inside a cell is within half its diagonal (0.354 m) of a
    /// corner: the cell's centre is on the map, a pose just beyond that reach is not.
    #[test]
    fn the_map_reaches_half_a_cell_diagonal() {
        let centre = (2.0f64 * 0.25 * 0.25).sqrt();
        assert!(centre <= on_map_reach_m(0.5));
        assert!(0.36 > on_map_reach_m(0.5));
    }

    /// Four queries on the map (three found, one in the top three) and two off it (one found):
    /// the recalls over all, over the map, and the off-map error are those counts.
    #[test]
    fn queries_off_the_map_are_counted_apart() {
        let results = [
            query(0, 0.1, [0, 1, 2], 0.1),
            query(1, 0.2, [1, 0, 2], 0.2),
            query(2, 0.3, [2, 0, 1], 0.3),
            query(3, 0.35, [0, 3, 1], 0.6),
            query(4, 0.9, [4, 1, 2], 0.9),
            query(5, 1.5, [0, 1, 2], 4.0),
        ];
        let s = summarize(&results, 6, 0.5);
        assert_eq!((s.queries, s.on_map_queries, s.off_map_queries), (6, 4, 2));
        assert_eq!(s.recall_at_1, 4.0 / 6.0);
        assert_eq!(s.recall_at_3, 5.0 / 6.0);
        assert_eq!(s.recall_at_1_on_map, Some(0.75));
        assert_eq!(s.recall_at_3_on_map, Some(1.0));
        // The lower middle of 0.9 and 4.0, as every median here.
        assert_eq!(s.median_position_error_off_map_m, Some(0.9));
    }

    /// With every query off the map there is no on-map recall to state, not a 0 % or NaN.
    #[test]
    fn no_query_on_the_map_gives_no_on_map_recall() {
        let s = summarize(&[query(0, 2.0, [1, 2, 3], 2.0)], 4, 0.5);
        assert_eq!((s.on_map_queries, s.recall_at_1_on_map), (0, None));
        assert_eq!(s.recall_at_1, 0.0);
    }
}
