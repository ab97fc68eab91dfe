//! How closely the cube path's sensor range and ids agree with the exact reference's, from
//! the files the two commands wrote (docs/sensor.md, "Range and id through the cube"):
//!
//! ```sh
//! specchio render    SCENE --out G --sensor-outputs
//! specchio reference SCENE --out R --sensor-outputs --spp 1
//! cargo run --release -p specchio-bench --example sensor_agreement -- G R
//! ```
//!
//! Over the pixels both masks call mirror pixels: the fraction whose ids are equal, how many
//! of the others lie within 2 pixels of a silhouette (the reference's id changes there) or
//! the image's border, and the range error (metres, and relative to the reference's range)
//! as median, p99 and maximum over the pixels whose ids agree.

use std::path::Path;

use anyhow::{bail, Context, Result};
use specchio::sensor::files::{f32_channel, read_channels, read_u32_channel};

/// One folder's mask, range and ids.
struct Layers {
    width: usize,
    mask: Vec<bool>,
    range: Vec<f32>,
    ids: Vec<u32>,
}

fn read(dir: &Path) -> Result<Layers> {
    let open = |name: &str| {
        let path = dir.join(name);
        read_channels(&path).with_context(|| format!("{}", path.display()))
    };
    let (rays, range, ids) = (
        open("sensor.rays.exr")?,
        open("sensor.range.exr")?,
        open("sensor.id.exr")?,
    );
    let missing = |what: &str| anyhow::anyhow!("{}: no {what} channel", dir.display());
    let mask: Vec<bool> = f32_channel(&rays, "mask")
        .ok_or_else(|| missing("mask"))?
        .iter()
        .map(|&m| m == 1.0)
        .collect();
    let camera: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("camera.json"))?)?;
    let width = camera["sensor"]["image_size"][0]
        .as_u64()
        .ok_or_else(|| missing("camera.json sensor.image_size"))? as usize;
    Ok(Layers {
        width,
        mask,
        range: f32_channel(&range, "range")
            .ok_or_else(|| missing("range"))?
            .to_vec(),
        ids: read_u32_channel(&ids, "id")
            .ok_or_else(|| missing("id"))?
            .to_vec(),
    })
}

/// Whether the reference's id changes within 2 pixels of pixel `i`, or the image ends there.
fn near_an_edge(r: &Layers, i: usize) -> bool {
    let (w, h) = (r.width as i64, (r.ids.len() / r.width) as i64);
    let (x, y) = (i as i64 % w, i as i64 / w);
    (-2..=2).any(|dy| {
        (-2..=2).any(|dx| {
            let (u, v) = (x + dx, y + dy);
            !(0..w).contains(&u) || !(0..h).contains(&v) || r.ids[(v * w + u) as usize] != r.ids[i]
        })
    })
}

fn stats(mut v: Vec<f64>) -> String {
    if v.is_empty() {
        return "none".into();
    }
    v.sort_by(f64::total_cmp);
    let at = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    format!(
        "median {:.3e}, p99 {:.3e}, max {:.3e}",
        at(0.5),
        at(0.99),
        at(1.0)
    )
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [gpu, reference] = args.as_slice() else {
        bail!("usage: sensor_agreement GPU_FOLDER REFERENCE_FOLDER");
    };
    let (g, r) = (read(Path::new(gpu))?, read(Path::new(reference))?);
    if g.ids.len() != r.ids.len() || g.width != r.width {
        bail!("the two folders' sensor images differ in size");
    }
    let (mut both, mut equal, mut edge, mut interior) = (0u64, 0u64, 0u64, 0u64);
    let (mut metres, mut relative) = (Vec::new(), Vec::new());
    for i in 0..r.ids.len() {
        if !(g.mask[i] && r.mask[i]) {
            continue;
        }
        both += 1;
        if g.ids[i] == r.ids[i] {
            equal += 1;
            let d = f64::from((g.range[i] - r.range[i]).abs());
            metres.push(d);
            relative.push(d / f64::from(r.range[i]));
        } else if near_an_edge(&r, i) {
            edge += 1;
        } else {
            interior += 1;
        }
    }
    let pct = |n: u64| 100.0 * n as f64 / both.max(1) as f64;
    println!("mirror pixels in both masks: {both}");
    println!("ids equal: {equal} ({:.3} %)", pct(equal));
    println!(
        "ids differ within 2 px of a silhouette: {edge} ({:.3} %); elsewhere: {interior} ({:.3} %)",
        pct(edge),
        pct(interior)
    );
    println!("range error where ids agree (m): {}", stats(metres));
    println!(
        "range error where ids agree (relative): {}",
        stats(relative)
    );
    Ok(())
}
