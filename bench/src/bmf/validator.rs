//! A validator of BMF written apart from the writer, from Bencher's documentation, and its
//! own tests.

use serde_json::Value;

/// Bencher's limits: a benchmark name is 1 to 1024 characters, a measure's slug or name 1 to 64
/// (https://bencher.dev/docs/how-to/track-custom-benchmarks/,
/// https://bencher.dev/docs/reference/bencher-metric-format/, "Order of Precedence").
const MAX_BENCHMARK_NAME: usize = 1024;
const MAX_MEASURE: usize = 64;

/// Every way `text` breaks BMF, each with where. Bencher's rules (its JSON schema,
/// https://bencher.dev/bmf.json, and the limits above): an object of benchmark names, each an
/// object of measures, each an object with a number `value` and optional number `lower_value`
/// and `upper_value`. Ours on top: no other key in a metric, every number finite and
/// lower_value <= value <= upper_value (Bencher checks neither), a measure key that is a slug
/// (so Bencher finds or creates the measure by that slug), no benchmark without measures.
pub(super) fn violations(text: &str) -> Vec<String> {
    let doc: Value = match serde_json::from_str(text) {
        Ok(v) => v,
        // NaN and Infinity are not JSON: they end here.
        Err(e) => return vec![format!("not JSON: {e}")],
    };
    let mut out = Vec::new();
    let Some(benchmarks) = doc.as_object() else {
        return vec!["the top level is not an object".into()];
    };
    for (name, measures) in benchmarks {
        if name.is_empty() || name.chars().count() > MAX_BENCHMARK_NAME {
            out.push(format!("benchmark name {name:?}: not 1 to 1024 characters"));
        }
        let Some(measures) = measures.as_object() else {
            out.push(format!("{name}: not an object"));
            continue;
        };
        if measures.is_empty() {
            out.push(format!("{name}: no measures"));
        }
        for (measure, metric) in measures {
            let at = format!("{name} / {measure}");
            if !is_slug(measure) {
                out.push(format!(
                    "{at}: the measure is not a slug of 1 to 64 characters"
                ));
            }
            out.extend(
                metric_violations(metric)
                    .into_iter()
                    .map(|v| format!("{at}: {v}")),
            );
        }
    }
    out
}

fn metric_violations(metric: &Value) -> Vec<String> {
    let Some(metric) = metric.as_object() else {
        return vec!["the metric is not an object".into()];
    };
    let mut out = Vec::new();
    for key in metric.keys() {
        if !["value", "lower_value", "upper_value"].contains(&key.as_str()) {
            out.push(format!("unknown key `{key}`"));
        }
    }
    let number = |key: &str, out: &mut Vec<String>| match metric.get(key) {
        None => None,
        Some(v) => match v.as_f64().filter(|x| x.is_finite()) {
            Some(x) => Some(x),
            None => {
                out.push(format!("`{key}` is {v}, not a finite number"));
                None
            }
        },
    };
    let value = number("value", &mut out);
    if !metric.contains_key("value") {
        out.push("`value` is missing".into());
    }
    let lower = number("lower_value", &mut out);
    let upper = number("upper_value", &mut out);
    if let (Some(l), Some(v)) = (lower, value) {
        if l > v {
            out.push(format!("lower_value {l} above value {v}"));
        }
    }
    if let (Some(v), Some(u)) = (value, upper) {
        if v > u {
            out.push(format!("value {v} above upper_value {u}"));
        }
    }
    out
}

/// Lower-case ASCII letters, digits and single inner hyphens, 1 to 64 characters (the form of
/// Bencher's slugs, `lib/bencher_valid/src/slug.rs`).
fn is_slug(s: &str) -> bool {
    let chars_ok = s
        .chars()
        .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-');
    chars_ok
        && (1..=MAX_MEASURE).contains(&s.len())
        && !s.starts_with('-')
        && !s.ends_with('-')
        && !s.contains("--")
}

#[test]
fn the_validator_accepts_a_document_like_benchers_own_example() {
    // The shape of the example on Bencher's BMF page: two measures with bounds, one without,
    // a benchmark name with spaces and slashes.
    let text = r#"{
        "parse/small": {
            "latency": { "value": 41.5, "lower_value": 40.0, "upper_value": 44.25 },
            "throughput": { "value": 2.5, "lower_value": 2.0, "upper_value": 3.0 }
        },
        "/bin/sh -c ./build.sh": { "build-time": { "value": 12.0 } }
    }"#;
    assert_eq!(violations(text), Vec::<String>::new());
}

/// Documents that break one rule each, and a word of the violation expected.
const BROKEN: &[(&str, &str)] = &[
    ("[]", "top level"),
    (r#"{"a": {"m": {"value": NaN}}}"#, "not JSON"),
    (r#"{"": {"m": {"value": 1}}}"#, "benchmark name"),
    (r#"{"a": []}"#, "not an object"),
    (r#"{"a": {}}"#, "no measures"),
    (r#"{"a": {"m": 1}}"#, "metric is not an object"),
    (r#"{"a": {"m": {}}}"#, "`value` is missing"),
    (r#"{"a": {"m": {"value": null}}}"#, "not a finite number"),
    (r#"{"a": {"m": {"value": "1"}}}"#, "not a finite number"),
    (
        r#"{"a": {"m": {"value": 1, "lower_value": true}}}"#,
        "not a finite",
    ),
    (r#"{"a": {"m": {"value": 1, "unit": "ms"}}}"#, "unknown key"),
    (
        r#"{"a": {"m": {"value": 1, "lower_value": 2}}}"#,
        "lower_value 2 above",
    ),
    (
        r#"{"a": {"m": {"value": 3, "upper_value": 2}}}"#,
        "above upper_value",
    ),
    (r#"{"a": {"Cube Update": {"value": 1}}}"#, "not a slug"),
    (r#"{"a": {"cube--update": {"value": 1}}}"#, "not a slug"),
];

#[test]
fn the_validator_catches_every_broken_rule() {
    let long_name = "x".repeat(MAX_BENCHMARK_NAME + 1);
    let long_measure = "m".repeat(MAX_MEASURE + 1);
    let too_long = [
        (
            format!(r#"{{"{long_name}": {{"m": {{"value": 1}}}}}}"#),
            "benchmark name",
        ),
        (
            format!(r#"{{"a": {{"{long_measure}": {{"value": 1}}}}}}"#),
            "not a slug",
        ),
    ];
    let broken = BROKEN.iter().map(|&(t, e)| (t.to_owned(), e));
    for (text, expected) in broken.chain(too_long) {
        let v = violations(&text);
        assert!(
            v.iter().any(|v| v.contains(expected)),
            "{text}: expected `{expected}`, got {v:?}"
        );
    }
}
