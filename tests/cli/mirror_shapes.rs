//! The commands on the central mirrors (issue 23): the benchmark's ladder and localisation
//! run on a hyperboloid and a paraboloid as on the sphere, and what they report follows from
//! the geometry.

#[path = "../common/mod.rs"]
mod common;

use common::{specchio, temp_dir};

const CENTRAL: [&str; 2] = ["scenes/hyperbolic-room.toml", "scenes/parabolic-room.toml"];

/// The benchmark measures each lookup's error against the reference: on a central mirror the
/// plain lookup is exact up to texel sampling (measured p99 9e-5 texel at 64² on lavapipe),
/// and the benchmark says so.
#[test]
fn the_benchmark_finds_the_plain_lookup_exact_on_central_mirrors() {
    let json = temp_dir("shapes-bench.json");
    let scenes: Vec<String> = CENTRAL
        .iter()
        .map(|s| common::root().join(s).display().to_string())
        .collect();
    let mut args = vec!["bench"];
    args.extend(scenes.iter().map(String::as_str));
    args.extend([
        "--quick",
        "--lookups",
        "plain,box",
        "--methods",
        "six-pass",
        "--no-dynamic",
        "--no-floors",
        "--no-tradeoff",
        "--json",
        json.to_str().unwrap(),
    ]);
    let run = specchio(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = record["accuracy"].as_array().expect("accuracy rows");
    for scene in CENTRAL {
        let plain = rows
            .iter()
            .find(|r| {
                r["scene"].as_str().is_some_and(|s| s.ends_with(scene))
                    && r["lookup"] == "plain"
                    && r["camera"] == "sensor"
            })
            .unwrap_or_else(|| panic!("{scene}: a plain sensor row"));
        let p99 = plain["angular"]["p99_texels"].as_f64().unwrap();
        assert!(p99 <= 0.02, "{scene}: plain lookup p99 {p99} texels");
        assert_eq!(plain["non_finite_pixels"], 0);
    }
}

/// Localisation with the queries at landmark poses is a check whose every match must be
/// exact, whatever the mirror: recall@1 of 100 % on both central mirrors and on the cone,
/// whose panorama spans only the band its flank shows.
#[test]
fn localisation_at_the_landmarks_matches_every_query_on_every_mirror_shape() {
    for scene in CENTRAL.into_iter().chain(["scenes/conical-room.toml"]) {
        let out = temp_dir("shapes-localise");
        let path = common::root().join(scene);
        let run = specchio(&[
            "localise",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--grid",
            "2",
            "--queries",
            "10",
            "--sensor-size",
            "64",
            "--queries-at-landmarks",
        ]);
        assert!(
            run.status.success(),
            "{scene}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let record: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("localise.json")).unwrap())
                .unwrap();
        let summary = &record["rows"][0]["summary"];
        assert_eq!(summary["recall_at_1"], 1.0, "{scene}: {summary}");
        assert_eq!(
            summary["median_position_error_m"], 0.0,
            "{scene}: {summary}"
        );
    }
}
