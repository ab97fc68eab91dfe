//! Ctrl-C (SIGINT), SIGTERM and the other signals that would end the process (SIGHUP when
//! the terminal closes, SIGQUIT, SIGUSR1/2, SIGALRM) during a command that writes outputs:
//! the command stops at its next check (and always before it places its output) and returns
//! an error, so its output transaction is dropped and removes what it
//! had written, instead of the process dying with a hidden half-written folder on disk. A
//! second signal ends the process at once, but only half a second or more after the first:
//! `timeout` sends its SIGTERM to the process and then to its process group, and that second
//! copy must not cut the clean stop short. Before it ends, the process removes its staging
//! folders (`output::remove_staging_folders`), on a thread of its own, since a signal handler may
//! not touch the file system; a third signal ends it without waiting for that.

use std::sync::atomic::{AtomicBool, AtomicI32, AtomicI64, Ordering};

static INTERRUPTED: AtomicBool = AtomicBool::new(false);
/// When the first signal came, in monotonic-clock milliseconds.
static FIRST_MS: AtomicI64 = AtomicI64::new(0);
/// Whether a second signal has asked the cleaning thread to end the process.
static ENDING: AtomicBool = AtomicBool::new(false);
/// The write end of the pipe that wakes the cleaning thread; -1 without one.
static WAKE: AtomicI32 = AtomicI32::new(-1);

/// Signals closer than this to the first are taken for copies of it.
const REPEAT_MS: i64 = 500;

/// The monotonic clock in milliseconds (`clock_gettime` is async-signal-safe).
fn now_ms() -> i64 {
    // SAFETY: clock_gettime writes the timespec it is given; CLOCK_MONOTONIC always exists.
    let mut t: libc::timespec = unsafe { std::mem::zeroed() };
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut t) };
    t.tv_sec * 1000 + t.tv_nsec / 1_000_000
}

/// What a stopping signal does: the first one raises the flag; one that comes half a second
/// or more after it wakes the cleaning thread, which removes the staging folders and ends the
/// process; one after that (or one with no such thread) ends it at once. Runs in the signal
/// handler: atomics, the clock, `write` and `_exit` only, all async-signal-safe.
fn on_signal(signal: libc::c_int) {
    if !INTERRUPTED.swap(true, Ordering::SeqCst) {
        FIRST_MS.store(now_ms(), Ordering::SeqCst);
    } else if now_ms() - FIRST_MS.load(Ordering::SeqCst) >= REPEAT_MS {
        let wake = WAKE.load(Ordering::SeqCst);
        if wake < 0 || ENDING.swap(true, Ordering::SeqCst) {
            signal_hook::low_level::exit(128 + signal);
        }
        let byte = signal as u8;
        // SAFETY: writes one byte from a live local to the pipe's write end, which stays open
        // for the life of the process.
        if unsafe { libc::write(wake, (&byte as *const u8).cast(), 1) } != 1 {
            signal_hook::low_level::exit(128 + signal);
        }
    }
}

/// The thread a second signal wakes: it removes this process's staging folders and ends it
/// with the signal's status, as the handler would have without it.
fn start_cleaner() -> std::io::Result<()> {
    let mut ends = [0 as libc::c_int; 2];
    // SAFETY: `pipe2` fills the two descriptors it is given.
    if unsafe { libc::pipe2(ends.as_mut_ptr(), libc::O_CLOEXEC) } != 0 {
        return Err(std::io::Error::last_os_error());
    }
    let [read_end, write_end] = ends;
    // Before the thread starts: a thread that gave up at once must find it to take it back.
    WAKE.store(write_end, Ordering::SeqCst);
    let started = std::thread::Builder::new()
        .name("specchio-signals".into())
        .spawn(move || {
            let mut byte = 0u8;
            loop {
                // SAFETY: reads one byte into a live local from the pipe's read end, ours.
                let n = unsafe { libc::read(read_end, (&mut byte as *mut u8).cast(), 1) };
                if n == 1 {
                    crate::output::remove_staging_folders();
                    signal_hook::low_level::exit(128 + libc::c_int::from(byte));
                }
                let interrupted =
                    std::io::Error::last_os_error().raw_os_error() == Some(libc::EINTR);
                if n != -1 || !interrupted {
                    // No cleaner any more: a second signal ends the process at once.
                    WAKE.store(-1, Ordering::SeqCst);
                    return;
                }
            }
        });
    if started.is_err() {
        WAKE.store(-1, Ordering::SeqCst);
    }
    started.map(drop)
}

/// The signals whose default action would end the process with its staging folder on disk:
/// each stops the run cleanly instead (SIGPIPE is ignored in `main`; SIGKILL and SIGSTOP
/// cannot be caught).
const STOPPING: [libc::c_int; 7] = [
    libc::SIGINT,
    libc::SIGTERM,
    libc::SIGHUP,
    libc::SIGQUIT,
    libc::SIGUSR1,
    libc::SIGUSR2,
    libc::SIGALRM,
];

/// Installs the handler for the [`STOPPING`] signals, once per process (`signal-hook` keeps
/// any handler installed before ours and runs it too).
pub fn catch() {
    static INSTALLED: std::sync::Once = std::sync::Once::new();
    INSTALLED.call_once(|| {
        crate::output::stop_between_files(|| INTERRUPTED.load(Ordering::SeqCst));
        if let Err(e) = start_cleaner() {
            // A second signal then ends the process at once, its staging folders left to the
            // next run's sweep.
            crate::warnings::warn(&format!("cannot start the signal thread: {e}"));
        }
        for signal in STOPPING {
            // SAFETY: `on_signal` is async-signal-safe (see there); none of these signals is
            // one signal-hook forbids (SIGKILL, SIGSTOP, the fault signals).
            let installed =
                unsafe { signal_hook::low_level::register(signal, move || on_signal(signal)) };
            if let Err(e) = installed {
                // The run still works; only a signal would then end it the default way.
                crate::warnings::warn(&format!("cannot catch signal {signal}: {e}"));
            }
        }
    });
}

/// How long a frame's wait must have lasted before a signal ends the process from it (the
/// wait's own time, from when the frame is waited for: with frames in flight it may have been
/// submitted earlier): a shorter wait ends soon, and the command's own check then says where
/// it stopped.
pub const LONG_FRAME: std::time::Duration = std::time::Duration::from_secs(1);

/// [`catch`], and a signal may end the process from a frame's wait of [`LONG_FRAME`] or more: for a command that keeps nothing of a stopped run (not a dataset that resumes,
/// whose stop says which frames it kept).
pub fn catch_in_long_frames() {
    catch();
    crate::vk::commands::set_long_wait_hook(during_a_frame);
}

/// Asked every 100 ms while a frame runs on the GPU (`Submitter::wait_watched`): at a signal,
/// once the frame has run [`LONG_FRAME`], the process ends there, as a second signal's does,
/// with the staging folders removed and the usual message and status, rather than wait out
/// the frame (an 8192² localisation image is one frame of 13 s on lavapipe, and no GPU work
/// can be cut short). Nothing is torn down: the GPU still uses the frame's objects, and the
/// kernel and the driver reclaim them.
fn during_a_frame(waited: std::time::Duration) {
    if !INTERRUPTED.load(Ordering::SeqCst) {
        say_a_long_frame(waited);
        return;
    }
    if waited < LONG_FRAME {
        return;
    }
    crate::output::remove_staging_folders();
    let stopped: Box<dyn std::error::Error + Send + Sync> =
        Box::new(Interrupted("during a GPU frame".to_owned()));
    super::ending::end_without_teardown::<Box<dyn std::error::Error + Send + Sync>>(Err(stopped))
}

/// The first frame the GPU has worked on for as long as an estimate waits
/// ([`super::patience`]) is said, once a process: one 8192² frame is seconds on a CPU driver,
/// and a GPU frame cannot say how far it has got (later ones are counted by the command's own
/// estimate, and a line a frame would repeat it).
fn say_a_long_frame(waited: std::time::Duration) {
    static SAID: AtomicBool = AtomicBool::new(false);
    if waited >= super::patience::estimate_after() && !SAID.swap(true, Ordering::SeqCst) {
        crate::say_err!(
            "waiting for the GPU: one frame has run for {} s so far (a frame says nothing of its \
             progress); Ctrl-C stops it cleanly",
            format!("{:.1}", waited.as_secs_f64())
        );
    }
}

/// An error once a signal has arrived; `progress` says how far the command got.
pub fn check(progress: &str) -> Result<(), Interrupted> {
    if INTERRUPTED.load(Ordering::SeqCst) {
        return Err(Interrupted(progress.to_owned()));
    }
    Ok(())
}

/// The error of a command that a signal stopped `progress` (work that saw the signal at its
/// own check: [`super::progress::Progress::stopped`], a reference run's `stop`).
pub fn stopped(progress: &str) -> Interrupted {
    Interrupted(progress.to_owned())
}

/// A signal stopped the command; the text says how far it got.
#[derive(Debug, thiserror::Error)]
#[error("interrupted {0}: nothing was written")]
pub struct Interrupted(String);
