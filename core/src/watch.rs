//! Long CPU work row by row, watched: each row done is reported, and the watcher may stop the
//! work before its next part. The reference's cameras and the FLIP of a large comparison are
//! such work; `process::Progress` (in the engine) is the watcher that says an estimate and
//! honours Ctrl-C, and this module is below both, so neither imports the other.

/// What long work reports to: rows done (as each part ends, all its rows at once, so that a
/// rate is the rate of the work), and whether to stop before the next part.
pub trait Watch: Sync {
    /// The work is `rows` rows of `width` pixels, said as it begins where it is known only
    /// then (the images a comparison reads, from their headers).
    fn begin(&self, _rows: u64, _width: u32) {}
    fn rows_done(&self, rows: u32);
    fn stop(&self) -> bool;
}

/// A progress callback for work that says the fraction of it done (0 to 1: the EXR codec's),
/// telling `watch` the rows of `rows` it has passed, each once.
pub fn rows_of_fraction(watch: &dyn Watch, rows: u64) -> impl FnMut(f64) + '_ {
    let mut said = 0;
    move |done: f64| {
        let now = ((done.clamp(0.0, 1.0) * rows as f64) as u64).min(rows);
        if now > said {
            watch.rows_done((now - said) as u32);
            said = now;
        }
    }
}

/// Watched work that its [`Watch`] stopped: nothing of it is kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stopped;

/// No one watching: every row is done.
pub struct Unwatched;

impl Watch for Unwatched {
    fn rows_done(&self, _: u32) {}

    fn stop(&self) -> bool {
        false
    }
}

/// Makes the watcher of long work named `what`, `total` units long (see [`long_work`]).
pub type LongWork = fn(what: String, total: u64) -> Box<dyn Watch>;

static LONG_WORK: std::sync::OnceLock<LongWork> = std::sync::OnceLock::new();

/// Has [`long_work`] make its watchers with `make` (set once a process): a command that says
/// its progress installs one (`process::interrupt::catch`); a library user sees nothing.
pub fn watch_long_work_with(make: LongWork) {
    let _ = LONG_WORK.set(make);
}

/// A watcher for work below the commands that may take seconds (a mesh file of millions of
/// lines): the process's ([`watch_long_work_with`]), or [`Unwatched`].
pub fn long_work(what: String, total: u64) -> Box<dyn Watch> {
    match LONG_WORK.get() {
        Some(make) => make(what, total),
        None => Box::new(Unwatched),
    }
}

/// How long work that cannot count its parts runs before [`said_while`] says it is still going
/// (unset: nothing is said, as in a library user's process).
static PATIENCE: std::sync::OnceLock<std::time::Duration> = std::sync::OnceLock::new();

/// How often [`said_while`] repeats its line after the first.
pub const STILL_GOING_EVERY: std::time::Duration = std::time::Duration::from_secs(30);

/// Has [`said_while`] say its work once it has run `after` (set once a process, by a command
/// that says its progress: `process::interrupt::catch`).
pub fn say_slow_work_after(after: std::time::Duration) {
    let _ = PATIENCE.set(after);
}

/// `work`'s result; and where it runs past the process's patience ([`say_slow_work_after`]),
/// a line on stderr saying `what` is still going, then one every [`STILL_GOING_EVERY`]. For
/// work of one piece that has no parts to count (a tree over millions of triangles): the
/// user learns what the wait is, not how long it will be.
pub fn said_while<T>(what: impl Fn() -> String + Sync, work: impl FnOnce() -> T) -> T {
    match PATIENCE.get() {
        Some(&after) => said_while_to(after, &what, &|line| crate::say_err!("{line}"), work),
        None => work(),
    }
}

/// [`said_while`] after `after`, each line given to `say`.
fn said_while_to<T>(
    after: std::time::Duration,
    what: &(dyn Fn() -> String + Sync),
    say: &(dyn Fn(String) + Sync),
    work: impl FnOnce() -> T,
) -> T {
    let (done, finished) = std::sync::mpsc::channel::<()>();
    std::thread::scope(|s| {
        s.spawn(move || {
            let start = std::time::Instant::now();
            let mut wait = after;
            let timed_out = std::sync::mpsc::RecvTimeoutError::Timeout;
            // Woken by the timeout, or by the sender's drop when the work ends.
            while finished.recv_timeout(wait) == Err(timed_out) {
                let secs = start.elapsed().as_secs_f64();
                say(format!("{}: still going after {secs:.0} s", what()));
                wait = STILL_GOING_EVERY;
            }
        });
        let out = work();
        drop(done);
        out
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;
    use std::time::Duration;

    /// Work past the patience is said while it runs (the work here waits for the line, so the
    /// test holds on a machine of any speed); work that ends first says nothing; the result
    /// comes back either way.
    #[test]
    fn slow_work_is_said_while_it_runs_and_quick_work_is_not() {
        let lines = Mutex::new(Vec::new());
        let (heard, hear) = std::sync::mpsc::channel();
        let heard = Mutex::new(heard);
        let say = |line: String| {
            lines.lock().unwrap().push(line);
            let _ = heard.lock().unwrap().send(());
        };
        let what = || "building the trees of 3 triangles".to_owned();
        let out = said_while_to(Duration::ZERO, &what, &say, || {
            hear.recv_timeout(Duration::from_secs(60)).is_ok()
        });
        assert!(out, "no line within a minute");
        assert_eq!(
            lines.lock().unwrap().as_slice(),
            ["building the trees of 3 triangles: still going after 0 s"]
        );
        lines.lock().unwrap().clear();
        let out = said_while_to(Duration::from_secs(600), &what, &say, || 7);
        assert_eq!(out, 7);
        assert!(lines.lock().unwrap().is_empty());
    }
}
