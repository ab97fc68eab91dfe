//! Host memory: the budget a command's memory estimate is checked against before it starts
//! any work, so that a user's numbers (view resolutions, sensor sizes, samples, queries, grid
//! spacing) are refused up front with the figures instead of growing until the machine runs
//! out of memory.
//!
//! The budget is `SPECCHIO_MEMORY_BUDGET` when set (a size such as `6GiB`, `512MiB` or a number
//! of bytes), else three quarters of the machine's physical memory (`MemTotal` of
//! `/proc/meminfo`), else 8 GiB where the OS does not say. Estimates are upper bounds of a
//! command's peak resident memory, made of parts per pixel measured on this project's own code
//! (each part's constant says where it comes from) and checked against measured peaks by the
//! tests (`tests/cli/memory.rs`); the estimates of each command are in [`estimates`].

pub mod estimates;

use std::fmt;

/// The variable that sets the budget.
pub const BUDGET_VARIABLE: &str = "SPECCHIO_MEMORY_BUDGET";
/// The budget where neither the variable nor the OS says anything (bytes).
pub const FALLBACK_BUDGET_BYTES: u64 = 8 << 30;

/// The memory a command may use, and where that figure came from (for messages).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Budget {
    pub bytes: u64,
    pub source: String,
}

impl Budget {
    /// The budget for this process: see the module's documentation.
    pub fn from_env() -> Result<Budget, MemoryError> {
        if let Some(text) = std::env::var_os(BUDGET_VARIABLE) {
            let text = text.to_string_lossy();
            let bytes = parse_size(&text).ok_or_else(|| MemoryError::BadBudget {
                text: text.clone().into_owned(),
            })?;
            return Ok(Budget {
                bytes,
                source: format!("{BUDGET_VARIABLE}={text}"),
            });
        }
        Ok(match physical_memory_bytes() {
            Some(total) => Budget {
                bytes: total / 4 * 3,
                source: format!(
                    "3/4 of this machine's {} (set {BUDGET_VARIABLE} to change it)",
                    Bytes(total)
                ),
            },
            None => Budget {
                bytes: FALLBACK_BUDGET_BYTES,
                source: format!("the default (set {BUDGET_VARIABLE} to change it)"),
            },
        })
    }
}

/// Why a command did not start.
#[derive(Debug, thiserror::Error)]
pub enum MemoryError {
    #[error(
        "this run would need about {} of memory ({}), more than the budget of {} ({}): {hint}",
        Bytes(*total), parts, Bytes(budget.bytes), budget.source
    )]
    OverBudget {
        total: u64,
        /// The parts, largest first, as text.
        parts: String,
        budget: Budget,
        hint: String,
    },
    #[error(
        "{BUDGET_VARIABLE}={text} is not a size: write bytes or a number with KiB, MiB or GiB \
         (e.g. 6GiB)"
    )]
    BadBudget { text: String },
}

/// A command's memory estimate: named parts, in bytes.
#[derive(Debug, Default, Clone)]
pub struct Estimate {
    parts: Vec<(String, u64)>,
}

impl Estimate {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds `bytes` for `what` (saturating: an absurd request stays absurd, never wraps).
    pub fn add(&mut self, what: impl Into<String>, bytes: u64) -> &mut Self {
        self.parts.push((what.into(), bytes));
        self
    }

    /// `count` items of `each` bytes (saturating).
    pub fn add_many(&mut self, what: impl Into<String>, count: u64, each: u64) -> &mut Self {
        self.add(what, count.saturating_mul(each))
    }

    pub fn total(&self) -> u64 {
        self.parts
            .iter()
            .fold(0u64, |t, (_, b)| t.saturating_add(*b))
    }

    /// Ok when the total fits `budget`; else the refusal, with the parts and `hint` (what to
    /// lower).
    pub fn check(&self, budget: &Budget, hint: &str) -> Result<(), MemoryError> {
        let total = self.total();
        if total <= budget.bytes {
            return Ok(());
        }
        let mut parts = self.parts.clone();
        parts.sort_by_key(|p| std::cmp::Reverse(p.1));
        // Resolutions cannot help when the textures are most of it, nor anything of the
        // scene's when the fixed part alone is over the budget.
        let base = (parts.iter()).find(|(what, _)| what == estimates::BASE_PART);
        let hint = match parts.first() {
            _ if base.is_some_and(|b| b.1 > budget.bytes) => {
                "the budget is below what any run takes (the driver and the program): raise it"
            }
            Some((what, _)) if what == estimates::TEXTURES_PART => {
                "the scene's textures are the largest part: use smaller images (materials' file)"
            }
            _ => hint,
        };
        let parts = parts
            .iter()
            .filter(|(_, b)| *b > 0)
            .map(|(what, b)| format!("{what}: {}", Bytes(*b)))
            .collect::<Vec<_>>()
            .join(", ");
        Err(MemoryError::OverBudget {
            total,
            parts,
            budget: budget.clone(),
            hint: hint.to_owned(),
        })
    }
}

/// A size in bytes, shown in the largest binary unit that keeps it at or above 1.
pub struct Bytes(pub u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const UNITS: [&str; 5] = ["bytes", "KiB", "MiB", "GiB", "TiB"];
        let mut value = self.0 as f64;
        let mut unit = 0;
        while value >= 1024.0 && unit + 1 < UNITS.len() {
            value /= 1024.0;
            unit += 1;
        }
        match unit {
            0 => write!(f, "{} bytes", self.0),
            _ => write!(f, "{value:.1} {}", UNITS[unit]),
        }
    }
}

/// `6GiB`, `512 MiB`, `1.5GiB`, `1000000`: bytes (None when it is none of those, or not above 0).
pub fn parse_size(text: &str) -> Option<u64> {
    let text = text.trim();
    let split = text
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(text.len());
    let (number, unit) = text.split_at(split);
    let number: f64 = number.parse().ok()?;
    let scale = match unit.trim() {
        "" | "B" => 1u64,
        "KiB" | "K" | "k" => 1 << 10,
        "MiB" | "M" => 1 << 20,
        "GiB" | "G" => 1 << 30,
        "TiB" | "T" => 1 << 40,
        _ => return None,
    };
    let bytes = number * scale as f64;
    (bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64).then_some(bytes as u64)
}

/// `MemTotal` of `/proc/meminfo` (Linux), in bytes.
fn physical_memory_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_in_binary_units() {
        assert_eq!(parse_size("1000"), Some(1000));
        assert_eq!(parse_size("6GiB"), Some(6 << 30));
        assert_eq!(parse_size(" 512 MiB "), Some(512 << 20));
        assert_eq!(parse_size("1.5G"), Some(3 << 29));
        for bad in ["", "GiB", "-1", "0", "1e9", "6 GB", "nan", "1.2.3"] {
            assert_eq!(parse_size(bad), None, "{bad}");
        }
    }

    /// A known over-budget estimate: the message names the total, each part largest first,
    /// the budget and its source, and the hint; an estimate that fits passes.
    #[test]
    fn an_estimate_over_the_budget_names_its_parts() {
        let budget = Budget {
            bytes: 1 << 30,
            source: "a test".into(),
        };
        let mut e = Estimate::new();
        e.add_many("images", 4096 * 4096, 16).add("tree", 1 << 20);
        assert!(e.check(&budget, "").is_ok(), "257 MiB fits 1 GiB");
        e.add_many("layers", 8192 * 8192, 64);
        let text = e
            .check(&budget, "lower the resolution")
            .unwrap_err()
            .to_string();
        assert_eq!(
            text,
            "this run would need about 4.3 GiB of memory (layers: 4.0 GiB, images: 256.0 MiB, \
             tree: 1.0 MiB), more than the budget of 1.0 GiB (a test): lower the resolution"
        );
        // Where the textures are the largest part, the hint is to shrink them.
        e.add_many(estimates::TEXTURES_PART, 8192 * 8192, 128);
        let text = e
            .check(&budget, "lower the resolution")
            .unwrap_err()
            .to_string();
        assert!(
            text.ends_with(
                ": the scene's textures are the largest part: use smaller images (materials' file)"
            ),
            "{text}"
        );
        // A budget below the fixed part alone: nothing of the scene's can help.
        let mut base = Estimate::new();
        base.add(estimates::BASE_PART, 2 << 30)
            .add("images", 1 << 20);
        let text = base.check(&budget, "lower the resolution").unwrap_err();
        let text = text.to_string();
        assert!(
            text.ends_with("(the driver and the program): raise it"),
            "{text}"
        );
        let mut huge = Estimate::new();
        huge.add_many("absurd", u64::MAX, 2).add("more", 1);
        assert_eq!(huge.total(), u64::MAX, "saturates, never wraps");
    }
}
