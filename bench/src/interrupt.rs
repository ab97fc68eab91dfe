//! Ctrl-C (SIGINT) and SIGTERM during a command that writes outputs: the command stops at its
//! next check and returns an error, so its output transaction is dropped and removes what it
//! had written, instead of the process dying with a hidden half-written folder on disk. A
//! second signal ends the process at once (the handler is one-shot).

use std::sync::atomic::{AtomicBool, Ordering};

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_: libc::c_int) {
    // Only an atomic store: async-signal-safe.
    INTERRUPTED.store(true, Ordering::SeqCst);
}

/// Installs the handler for SIGINT and SIGTERM (once per process is enough; again is harmless).
pub fn catch() {
    for signal in [libc::SIGINT, libc::SIGTERM] {
        // SAFETY: a zeroed sigaction is valid (empty mask); the handler only stores an atomic.
        // SA_RESETHAND restores the default after the first signal, so a second one kills.
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
            action.sa_flags = libc::SA_RESETHAND | libc::SA_RESTART;
            libc::sigaction(signal, &action, std::ptr::null_mut());
        }
    }
}

/// An error once a signal has arrived; `progress` says how far the command got.
pub fn check(progress: &str) -> anyhow::Result<()> {
    if INTERRUPTED.load(Ordering::SeqCst) {
        anyhow::bail!("interrupted {progress}: nothing was written");
    }
    Ok(())
}
