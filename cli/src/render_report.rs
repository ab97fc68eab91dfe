//! What `specchio render` says of a method's run: its lines (frames, the cube's updates, the
//! views' GPU times) and the files it wrote, said from the folder itself.

use std::path::Path;

use specchio::render::methods::Method;
use specchio::render::FrameReport;
use specchio::scene::Lookup;

use crate::records::RenderSummary;
use crate::render::Args;

/// The run's lines; `method` is None where no cube was made (a lookup that samples none).
pub(crate) fn print_summary(
    args: &Args,
    (method, lookup): (Option<Method>, Lookup),
    out: &Path,
    reports: &[FrameReport],
    summary: &RenderSummary,
) {
    let ms = |v: Option<f64>| v.map_or("n/a".to_owned(), |v| format!("{v:.2} ms"));
    let filled = match method {
        Some(method) => format!(" with {method},"),
        None => ",".to_owned(),
    };
    specchio::say!(
        "rendered {} frame(s) of {}{filled} lookup {lookup}, into {}",
        reports.len(),
        args.scene.display(),
        out.display()
    );
    if method.is_none() {
        specchio::say!("  cube map:           none made (the {lookup} lookup samples none)");
    } else {
        specchio::say!(
            "  cube updates:       {} of {} frames",
            summary.cube_updates,
            reports.len()
        );
        specchio::say!(
            "  cube update (GPU):  {} median",
            ms(summary.median_gpu_cube_update_ms)
        );
    }
    specchio::say!(
        "  observer (GPU):     {} median",
        ms(summary.median_gpu_observer_ms)
    );
    specchio::say!(
        "  sensor (GPU):       {} median",
        ms(summary.median_gpu_sensor_ms)
    );
}

/// The files a run wrote, said from the folder itself (a fixed list left out the sensor
/// outputs): an EXR and a PNG of one image as `name.exr/.png`; a sequence's frame folders
/// (`0000/`, ..., `10000/`, ...), which hold the same names, once, with their count. Linear
/// in the files (a 100 000-frame sequence has a million). `render.json` is written after this
/// is said, and named where it will be (`record_here`: in this folder, not above it as under
/// `--method all`), beside the frame folders rather than in each.
pub(crate) fn files_line(files: &[String], record_here: bool) -> String {
    fn frame(f: &str) -> Option<(&str, &str)> {
        f.split_once('/')
            .filter(|(d, _)| d.len() >= 4 && d.bytes().all(|b| b.is_ascii_digit()))
    }
    let folders: std::collections::BTreeSet<&str> = files
        .iter()
        .filter_map(|f| frame(f).map(|(d, _)| d))
        .collect();
    let first = folders.first().copied();
    let names: Vec<&str> = files
        .iter()
        .filter_map(|f| match frame(f) {
            Some((d, rest)) => (Some(d) == first).then_some(rest),
            None => Some(f.as_str()),
        })
        .collect();
    let set: std::collections::HashSet<&str> = names.iter().copied().collect();
    let mut said: Vec<String> = Vec::new();
    for name in &names {
        match name.strip_suffix(".png") {
            Some(stem) if set.contains(format!("{stem}.exr").as_str()) => continue,
            _ => {}
        }
        match name.strip_suffix(".exr") {
            Some(stem) if set.contains(format!("{stem}.png").as_str()) => {
                said.push(format!("{stem}.exr/.png"))
            }
            _ => said.push((*name).to_owned()),
        }
    }
    let line = said.join(", ");
    match (folders.len() > 1, record_here) {
        (true, true) => format!(
            "in each of {} frame folders (0000/ ...): {line}; render.json beside them",
            folders.len()
        ),
        (true, false) => format!(
            "in each of {} frame folders (0000/ ...): {line}",
            folders.len()
        ),
        (false, true) => line + ", render.json",
        (false, false) => line,
    }
}
