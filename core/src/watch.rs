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

/// Has [`long_work`] make its watchers with `make` (set once a process): the command-line
/// binary installs one (`process::progress::say_long_work`); a library user sees nothing.
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
/// (unset: nothing is said, as in a library user's process). A function, asked at the first
/// such work: a malformed `SPECCHIO_ESTIMATE_AFTER_S` is then said by the run it concerns.
static PATIENCE: std::sync::OnceLock<fn() -> std::time::Duration> = std::sync::OnceLock::new();

/// How often [`said_while`] repeats its line after the first.
pub const STILL_GOING_EVERY: std::time::Duration = std::time::Duration::from_secs(30);

/// The least time [`said_while`] waits, whatever the patience: the tests' runs (patience 0)
/// build trees of milliseconds, which would otherwise be said or not by a race.
pub const STILL_GOING_AFTER_AT_LEAST: std::time::Duration = std::time::Duration::from_secs(1);

/// Has [`said_while`] say its work once it has run `after()` (set once a process:
/// `process::progress::say_long_work`, which the binary's `main` calls).
pub fn say_slow_work_after(after: fn() -> std::time::Duration) {
    let _ = PATIENCE.set(after);
}

/// `work`'s result; and where it runs past the process's patience ([`say_slow_work_after`],
/// at least [`STILL_GOING_AFTER_AT_LEAST`]), a line on stderr saying `what` is still going,
/// then one every [`STILL_GOING_EVERY`]. For work of one piece that has no parts to count (a
/// tree over millions of triangles): the user learns what the wait is, not how long it will
/// be.
pub fn said_while<T>(what: impl FnOnce() -> String, work: impl FnOnce() -> T) -> T {
    match PATIENCE.get() {
        Some(after) => {
            let after = after().max(STILL_GOING_AFTER_AT_LEAST);
            said_while_to(after, what(), |line| crate::say_err!("{line}"), work)
        }
        None => work(),
    }
}

/// [`said_while`] after `after`, each line given to `say` by a thread of its own, not joined:
/// a stderr that blocks holds that thread while the work runs, and its caller only if a line
/// is being said as the work ends (the price of no line after the work: the flag is set under
/// the lock each line is said under). The flag is set however the work ends, a panic too.
fn said_while_to<T>(
    after: std::time::Duration,
    what: String,
    say: impl Fn(String) + Send + 'static,
    work: impl FnOnce() -> T,
) -> T {
    use std::sync::{Arc, Condvar, Mutex};
    let ended = Arc::new((Mutex::new(false), Condvar::new()));
    let watching = Arc::clone(&ended);
    let timer = std::thread::Builder::new()
        .name("still going".into())
        .spawn(move || {
            let (lock, wake) = &*watching;
            let start = std::time::Instant::now();
            let mut due = start + after;
            let mut done = lock.lock().unwrap_or_else(|e| e.into_inner());
            while !*done {
                let now = std::time::Instant::now();
                if now < due {
                    done = (wake.wait_timeout(done, due - now))
                        .unwrap_or_else(|e| e.into_inner())
                        .0;
                    continue;
                }
                let secs = start.elapsed().as_secs_f64();
                say(format!("{what}: still going after {secs:.0} s"));
                due = now + STILL_GOING_EVERY;
            }
        });
    // No thread (the system refused one): the work, unsaid.
    let _ended = timer.is_ok().then_some(Ended(ended));
    work()
}

/// Sets the flag [`said_while_to`]'s thread watches, when the work returns or unwinds.
struct Ended(std::sync::Arc<(std::sync::Mutex<bool>, std::sync::Condvar)>);

impl Drop for Ended {
    fn drop(&mut self) {
        let (lock, wake) = &*self.0;
        *lock.lock().unwrap_or_else(|e| e.into_inner()) = true;
        wake.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::{Arc, Mutex};
    use std::time::Duration;

    /// Work past the patience is said while it runs (the work here waits for the line, so the
    /// test holds on a machine of any speed), and nothing after it ended; work that ends first
    /// says nothing; the result comes back either way.
    #[test]
    fn slow_work_is_said_while_it_runs_and_quick_work_is_not() {
        let lines = Arc::new(Mutex::new(Vec::new()));
        let (heard, hear) = std::sync::mpsc::channel();
        let say = {
            let lines = Arc::clone(&lines);
            let heard = Mutex::new(heard);
            move |line: String| {
                lines.lock().unwrap().push(line);
                let _ = heard.lock().unwrap().send(());
            }
        };
        let what = "building the trees of 3 triangles".to_owned();
        let out = said_while_to(Duration::ZERO, what.clone(), say, || {
            hear.recv_timeout(Duration::from_secs(60)).is_ok()
        });
        assert!(out, "no line within a minute");
        std::thread::sleep(Duration::from_millis(50));
        let said = lines.lock().unwrap().clone();
        assert_eq!(said.len(), 1, "{said:?}");
        assert!(
            said[0].starts_with("building the trees of 3 triangles: still going after "),
            "{said:?}"
        );
        lines.lock().unwrap().clear();
        let quiet = Arc::clone(&lines);
        let say = move |line: String| quiet.lock().unwrap().push(line);
        let out = said_while_to(Duration::from_secs(600), what, say, || 7);
        assert_eq!(out, 7);
        assert!(lines.lock().unwrap().is_empty());
    }
}
