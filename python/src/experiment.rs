//! `specchio localise` from Python: the localisation experiment (landmarks on a floor grid,
//! random queries matched to them, the report) run in this process with the command's own
//! options and checks, stopped by Ctrl-C (docs/python.md, docs/sensor.md "Localisation").

use std::path::PathBuf;
use std::sync::Mutex;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use crate::errors;
use crate::said;

/// Runs `specchio localise SCENE --out OUT` with `options` as its options: each keyword is
/// the option of the same name (`queries=600` is `--queries 600`, `cube_size=128` is
/// `--cube-size 128`), a list or tuple its comma list (`times=[0, 3]`, `sources=["bvh",
/// "reference"]`), `True` a flag (`validate=True`), and `None` or `False` leaves it out; they
/// are checked as the command checks them. The output folder appears whole or not at all;
/// progress goes to stderr as the command's. Ctrl-C stops the run with nothing written:
/// between images at once, while the queries are matched when the matching ends. Returns the
/// report (`localise.json`) as a dict.
#[pyfunction]
#[pyo3(signature = (scene, out, **options))]
pub fn localise(
    py: Python<'_>,
    scene: crate::args::Given<PathBuf>,
    out: crate::args::Given<PathBuf>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    let (scene, out) = (scene.named("scene")?, out.named("out")?);
    let mut argv: Vec<String> = vec!["localise".into(), path_text(&scene)?];
    argv.extend(["--out".into(), path_text(&out)?]);
    for (key, value) in options.into_iter().flat_map(|d| d.iter()) {
        argv.extend(option(&key.extract::<String>()?, &value)?);
    }
    let args = specchio_bench::localise::parse(&argv)
        .map_err(|e| errors::command_error(clap_message(&e)))?;
    let stopped: Mutex<Option<PyErr>> = Mutex::new(None);
    // Python's pending signals (Ctrl-C), seen on the thread that called only: Python runs
    // its signal handlers there, so a check on a worker (the matching's) would find none,
    // and only contend for the GIL.
    let caller = std::thread::current().id();
    let stop = |at: &str| -> anyhow::Result<()> {
        if std::thread::current().id() != caller {
            return Ok(());
        }
        Python::attach(|py| py.check_signals()).map_err(|e| {
            *stopped.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
            anyhow::anyhow!("stopped {at}: nothing was written")
        })
    };
    let run = said::unsaid(py, || {
        // What this call may not replace is what it reads (docs/python.md).
        specchio::files::identity::forget();
        let (report, messages) = specchio_bench::localise::localise(&args, &stop)?;
        specchio::process::validation::verdict(&messages)?;
        anyhow::Ok(report)
    });
    // The report is placed (or nothing is): said, never raised.
    said::say_unraised(py);
    if let Some(e) = stopped.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(e);
    }
    let report =
        run.map_err(|e| errors::command_error(specchio::text::bounded_message(&format!("{e:#}"))))?;
    errors::json_to_py(py, &report)
}

/// A path as the command line would take it (not UTF-8: refused, naming it).
fn path_text(path: &std::path::Path) -> PyResult<String> {
    (path.to_str().map(str::to_owned))
        .ok_or_else(|| errors::error(format!("{}: not a UTF-8 path", path.display())))
}

/// The command-line word of keyword `key` = `value`: `--key=value`, one word, so that a
/// value beginning with `-` is read as the option's value, not as an option.
fn option(key: &str, value: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    let flag = format!("--{}", key.replace('_', "-"));
    if value.is_none() {
        return Ok(vec![]);
    }
    // Python's and numpy's booleans (`np.True_` is no `bool`: its type is numpy's `bool`, or
    // `bool_` before numpy 2; it extracts as one).
    if crate::args::is_bool(value) {
        // A bool is a switch: given to an option that takes a value, clap said only "a
        // value is required for '--queries'".
        if takes_value(&flag) {
            return Err(errors::error(format!(
                "{key}: {} (a bool); {flag} takes a value ({key}=600, say), not a switch",
                value.str()?
            )));
        }
        return Ok(match value.is_truthy()? {
            true => vec![flag],
            false => vec![],
        });
    }
    if value.is_instance_of::<PyDict>() {
        // Iterated, a dict gives its keys: `seed={"a": 1}` became `--seed=a`.
        return Err(errors::error(format!(
            "{key}: a dict; give the option's value, or a list for a comma list"
        )));
    }
    let listed = !value.is_instance_of::<PyString>() && value.try_iter().is_ok();
    let text = if listed {
        // A list, tuple, numpy array or any iterable but a string: the comma list.
        let items: PyResult<Vec<String>> = (value.try_iter()?)
            .map(|item| Ok(item?.str()?.to_string()))
            .collect();
        items?.join(",")
    } else {
        value.str()?.to_string()
    };
    Ok(vec![format!("{flag}={text}")])
}

/// Whether the command's option `flag` (`--queries`) takes a value; false for a switch or an
/// option the command does not have (clap names that one).
fn takes_value(flag: &str) -> bool {
    use clap::Args as _;
    let command = specchio_bench::localise::Args::augment_args(clap::Command::new("localise"));
    let long = flag.trim_start_matches("--");
    let found = (command.get_arguments())
        .find(|a| a.get_long() == Some(long))
        .is_some_and(|a| a.get_action().takes_values());
    found
}

/// Clap's error without its usage lines, the option named as the command names it.
fn clap_message(e: &clap::Error) -> String {
    let text = e.to_string();
    let first = text.split("\n\n").next().unwrap_or(&text);
    let first = first.trim().trim_start_matches("error: ");
    format!("localise: {first} (keyword arguments are the command's options: queries=600 is --queries 600)")
}
