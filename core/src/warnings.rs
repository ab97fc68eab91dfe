//! Warnings: what a user should know that is not an error (triangles a driver will leave out
//! of the images, files a killed run left behind). A command says each on standard error as it
//! comes. A host with a channel of its own takes them instead: the Python module shows them as
//! Python warnings, since a notebook never shows the process's standard error, where they would
//! be lost without a word.

use std::sync::Mutex;

/// `None`: said on standard error; `Some`: kept for the host (see [`hold`]).
static HELD: Mutex<Option<Vec<String>>> = Mutex::new(None);

fn held() -> std::sync::MutexGuard<'static, Option<Vec<String>>> {
    HELD.lock().unwrap_or_else(|e| e.into_inner())
}

/// Says `text` (no `warning:` prefix), bounded as every message is: `warning: TEXT` on
/// standard error, or kept until the host [`take`]s it.
pub fn warn(text: &str) {
    let text = crate::text::bounded_message(text);
    match held().as_mut() {
        Some(kept) => kept.push(text),
        None => crate::say_err!("warning: {text}"),
    }
}

/// From now on the process's warnings are kept for [`take`], not printed: for a host that
/// shows them its own way, after each call into the library. Process-wide, since a warning
/// may come from any thread the work runs on.
pub fn hold() {
    held().get_or_insert_with(Vec::new);
}

/// The warnings kept since the last call, oldest first (none unless [`hold`] was called).
pub fn take() -> Vec<String> {
    held().as_mut().map(std::mem::take).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Held warnings come back once each, in order, bounded; before `hold` nothing is kept.
    /// (One test: the holding is process-wide.)
    #[test]
    fn held_warnings_are_taken_once_in_order() {
        warn("said on standard error, not kept");
        assert!(take().is_empty());
        hold();
        warn("first");
        warn(&format!("second {}", "x".repeat(1000)));
        let taken = take();
        assert_eq!(taken.len(), 2);
        assert_eq!(taken[0], "first");
        assert!(taken[1].starts_with("second xxx") && taken[1].contains("more characters"));
        assert!(take().is_empty());
    }
}
