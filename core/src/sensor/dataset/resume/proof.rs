//! A resumed run proves what its journal says rather than trust it: each frame's files
//! against their journaled sizes and CRC-32s, its index line against the one its plan gives,
//! and its `pose.json` against that line.

use std::fs::File;
use std::io::Read;

/// Whether `file` is a regular file of `size` bytes whose CRC-32 is `crc`.
pub(super) fn file_is(mut file: File, size: u64, crc: u32) -> bool {
    if !file
        .metadata()
        .is_ok_and(|m| m.is_file() && m.len() == size)
    {
        return false;
    }
    let mut hasher = crc32fast::Hasher::new();
    let mut buf = vec![0u8; 1 << 20];
    loop {
        match file.read(&mut buf) {
            Ok(0) => break hasher.finalize() == crc,
            Ok(n) => hasher.update(&buf[..n]),
            Err(_) => break false,
        }
    }
}

/// Whether two JSON texts say the same: the same structure and strings, numbers equal to a
/// millionth (relative; absolute below 1). An index line is the plan's pose through f32
/// trigonometry, which another machine's libm (a Ray worker elsewhere) may round a last digit
/// apart; a forged pose is metres apart.
pub(super) fn same_json(a: &str, b: &str) -> bool {
    match (serde_json::from_str(a), serde_json::from_str(b)) {
        (Ok(a), Ok(b)) => same_value(&a, &b),
        _ => false,
    }
}

/// Whether a frame's `pose.json` (its bytes) is its index line without the folder.
pub(super) fn pose_is_index(pose: &[u8], index: &str) -> bool {
    let mut index: serde_json::Value = serde_json::from_str(index).unwrap_or_default();
    if let Some(line) = index.as_object_mut() {
        line.remove("folder");
    }
    serde_json::from_slice::<serde_json::Value>(pose).is_ok_and(|pose| same_value(&pose, &index))
}

/// [`same_json`] on parsed values.
fn same_value(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => match (x.as_f64(), y.as_f64()) {
            (Some(x), Some(y)) => (x - y).abs() <= 1e-6 * x.abs().max(y.abs()).max(1.0),
            _ => x == y,
        },
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(x, y)| same_value(x, y))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len()
                && x.iter()
                    .all(|(k, v)| y.get(k).is_some_and(|w| same_value(v, w)))
        }
        _ => a == b,
    }
}
