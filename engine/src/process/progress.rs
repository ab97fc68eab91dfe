//! Long work said as it goes. A command whose work may run for minutes (a reference camera of
//! 67 M rays, 100 000 localisation queries) counts it here as it is done, from any thread:
//! once a first part has taken [`ESTIMATE_AFTER`](super::patience::ESTIMATE_AFTER), it says on stderr what the whole is, how
//! much is done and about how long the rest will take, so the user can stop it (Ctrl-C stops
//! it cleanly: [`Progress::stopped`] is checked between parts) before the bulk of it; after
//! that a line every [`REPEAT_EVERY`] keeps a log alive. Work that ends sooner says nothing,
//! so short commands print what they always printed.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use super::interrupt;
use super::patience::estimate_after;

/// How often a line follows the estimate while the work goes on.
pub const REPEAT_EVERY: Duration = Duration::from_secs(30);

/// A piece of long work: `total` units (rays, images) of something named `what`.
pub struct Progress {
    what: String,
    unit: &'static str,
    total: u64,
    done: AtomicU64,
    start: Instant,
    /// When the estimate is due ([`estimate_after`]).
    after: Duration,
    /// When a line was last said (None: not yet).
    said: Mutex<Option<Instant>>,
}

impl Progress {
    /// Work of `total` `unit`s, said as `what` ("reference: sensor camera, 8192x8192 at 1
    /// spp"); nothing is printed yet.
    pub fn new(what: impl Into<String>, total: u64, unit: &'static str) -> Self {
        Self {
            what: what.into(),
            unit,
            total,
            done: AtomicU64::new(0),
            start: Instant::now(),
            after: estimate_after(),
            said: Mutex::new(None),
        }
    }

    /// `n` more units done; says the estimate, or a line, when it is time.
    pub fn add(&self, n: u64) {
        let done = self.done.fetch_add(n, Ordering::Relaxed) + n;
        let elapsed = self.start.elapsed();
        // Nothing done yet (a part of no work: a layer with no files) gives no rate.
        if elapsed < self.after || done >= self.total || done == 0 {
            return;
        }
        let Ok(mut said) = self.said.try_lock() else {
            return; // another thread is saying it
        };
        if said.is_some_and(|at| at.elapsed() < REPEAT_EVERY) {
            return;
        }
        crate::say_err!("{}", self.line(done, elapsed, said.is_none()));
        *said = Some(Instant::now());
    }

    /// Whether a stopping signal came: the work should stop at its next part.
    pub fn stopped(&self) -> bool {
        interrupt::check("").is_err()
    }

    /// How many units are done.
    pub fn done(&self) -> u64 {
        self.done.load(Ordering::Relaxed)
    }

    /// The line said: the whole, the part done, the time left at the rate so far.
    fn line(&self, done: u64, elapsed: Duration, first: bool) -> String {
        let rate = done as f64 / elapsed.as_secs_f64();
        let left = Duration::from_secs_f64((self.total - done) as f64 / rate.max(1e-9));
        let stop = if first {
            "; Ctrl-C stops it cleanly"
        } else {
            ""
        };
        let part = match self.unit {
            PERCENT => format!("{} % done", done * 100 / self.total.max(1)),
            unit => format!("{done} of {} {unit}", self.total),
        };
        format!(
            "{}: {part} in {}, about {} left{stop}",
            self.what,
            duration_text(elapsed),
            duration_text(left)
        )
    }
}

/// The unit of work counted in shares of the whole: said as "40 % done", the part done of
/// [`Progress::new`]'s total in hundredths.
pub const PERCENT: &str = "%";

/// A calibration's progress, said as "`what`: sensor WxH: 40 % done in ...": its parts
/// counted by their shares, the files' among them where it writes them (`files`; a dataset's
/// bag fits the unified model and writes no calibration files).
pub fn calibration(what: &str, [w, h]: [u32; 2], files: bool) -> Progress {
    use crate::sensor::central::Part;
    let total = (Part::ALL.iter())
        .filter(|&&p| files || p != Part::Files)
        .map(|p| p.share())
        .sum();
    Progress::new(format!("{what}: sensor {w}x{h}"), total, PERCENT)
}

/// The writing of a single render's sensor outputs (`frame`'s), said as "`what`: the sensor
/// outputs of a 4096x4096 sensor: 40 % done in ...": each layer counted by its samples as it
/// ends. A 4096² sensor's take half a minute, after a trace of seconds.
pub fn sensor_outputs(what: &str, frame: &crate::sensor::SensorOutputs) -> Progress {
    let [w, h] = [frame.rays.width, frame.rays.height];
    let what = format!("{what}: the sensor outputs of a {w}x{h} sensor");
    Progress::new(what, frame.samples(), PERCENT)
}

/// A calibration counts its parts here by their shares of the whole ([`PERCENT`]), and stops
/// between parts at a signal.
impl crate::sensor::central::Watch for Progress {
    fn part_done(&self, part: crate::sensor::central::Part) {
        self.add(part.share());
    }

    fn stop(&self) -> bool {
        self.stopped()
    }
}

/// Long work below the commands ([`crate::watch::long_work`]: an OBJ file's parse) counted in
/// its own units and said as shares of the whole.
impl crate::watch::Watch for Progress {
    fn rows_done(&self, units: u32) {
        self.add(u64::from(units));
    }

    fn stop(&self) -> bool {
        self.stopped()
    }
}

/// The watcher [`crate::watch::long_work`] makes in a command: a [`Progress`] in shares.
fn long_work(what: String, total: u64) -> Box<dyn crate::watch::Watch> {
    Box::new(Progress::new(what, total, PERCENT))
}

/// Has work below the commands say itself as a command's long work does: an OBJ file's parse
/// by its bytes ([`crate::watch::long_work`]), a mesh's trees once they have taken the
/// process's patience ([`crate::watch::said_while`]). The command-line binary calls it first
/// thing; a library user's process (Python's) says nothing.
pub fn say_long_work() {
    crate::watch::watch_long_work_with(long_work);
    crate::watch::say_slow_work_after(estimate_after);
}

/// A duration for a person: "45 s", "3 min 20 s", "2 h 5 min".
pub fn duration_text(d: Duration) -> String {
    let s = d.as_secs_f64().round() as u64;
    match s {
        0..60 => format!("{s} s"),
        60..3600 => format!("{} min {} s", s / 60, s % 60),
        _ => format!("{} h {} min", s / 3600, (s % 3600) / 60),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_as_a_person_says_them() {
        assert_eq!(duration_text(Duration::from_millis(400)), "0 s");
        assert_eq!(duration_text(Duration::from_secs(59)), "59 s");
        assert_eq!(duration_text(Duration::from_secs(200)), "3 min 20 s");
        assert_eq!(duration_text(Duration::from_secs(7500)), "2 h 5 min");
    }

    /// The line names the whole and the part, and extrapolates the rate so far.
    #[test]
    fn the_estimate_extrapolates_the_rate_so_far() {
        let p = Progress::new("reference: sensor camera", 1000, "rows");
        let line = p.line(100, Duration::from_secs(10), true);
        assert_eq!(
            line,
            "reference: sensor camera: 100 of 1000 rows in 10 s, about 1 min 30 s left; \
             Ctrl-C stops it cleanly"
        );
        let line = p.line(500, Duration::from_secs(50), false);
        assert!(line.ends_with("about 50 s left"), "{line}");
    }

    /// Parts of no work give no rate, and no line: with none done, a first line said "about
    /// 185140906666666 h left" for the sensor outputs' first layer, one with no files.
    #[test]
    fn nothing_done_says_nothing() {
        let mut p = Progress::new("render: the sensor outputs", 1000, PERCENT);
        p.after = Duration::ZERO;
        p.add(0);
        assert!(p.said.lock().unwrap().is_none());
        p.add(10);
        assert!(p.said.lock().unwrap().is_some());
    }
}
