//! Standard output that never panics and never kills the process. `println!` panics when a
//! write fails (`specchio ... > /dev/full`), and with SIGPIPE at its default a reader that
//! goes away (`specchio ... | head -1`) kills the process mid-run, its staging folder left on
//! disk. Here SIGPIPE is ignored (by the binary's `main`), a failed write is recorded and later lines are
//! skipped, and the command runs to its end: its files are written as if stdout were fine.
//! The binary then ends with the failure, unless it was the reader going away (EPIPE), which, as
//! for other command-line tools, is not an error of ours.

use std::fmt;
use std::io::{self, Write};
use std::sync::Mutex;

/// The first failed write, if any.
static FAILED: Mutex<Option<io::Error>> = Mutex::new(None);

/// Writes `args` to stdout as they are (no newline added); see [`say!`](crate::say).
pub fn write(args: fmt::Arguments) {
    let mut failed = FAILED.lock().unwrap_or_else(|e| e.into_inner());
    if failed.is_some() {
        return;
    }
    let mut out = io::stdout().lock();
    if let Err(e) = out.write_fmt(args).and_then(|()| out.flush()) {
        *failed = Some(e);
    }
}

/// Writes `args` to stderr, never panicking: a closed or full stderr (`2>&1 | head -1`, a
/// full disk) loses the line, never the run. `eprintln!` panics there: a dataset piped to
/// `head` died at its first progress line, exit 101, nothing written. See [`say_err!`](crate::say_err).
pub fn write_err(args: fmt::Arguments) {
    let mut err = io::stderr().lock();
    let _ = err.write_fmt(args).and_then(|()| err.flush());
}

/// Ok unless a write to stdout failed for another reason than the reader going away.
pub fn verdict() -> Result<(), StdoutFailed> {
    match FAILED.lock().unwrap_or_else(|e| e.into_inner()).take() {
        Some(e) if e.kind() != io::ErrorKind::BrokenPipe => Err(StdoutFailed(e)),
        _ => Ok(()),
    }
}

/// A write to standard output failed (not because its reader went away).
#[derive(Debug, thiserror::Error)]
#[error("cannot write to standard output: {0}")]
pub struct StdoutFailed(#[source] io::Error);

/// `println!` for the commands: a line on stdout through [`write`].
#[macro_export]
macro_rules! say {
    () => {
        $crate::stdout::write(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::stdout::write(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `eprintln!` for the commands and the library: a line on stderr through [`write_err`].
#[macro_export]
macro_rules! say_err {
    ($($arg:tt)*) => {
        $crate::stdout::write_err(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` for the commands.
#[macro_export]
macro_rules! say_part {
    ($($arg:tt)*) => {
        $crate::stdout::write(format_args!($($arg)*))
    };
}
