//! How a command's run ends: its error said on one line, the exit status it gives, and, for
//! a program that must not wait for its device, an end without teardown.
//!
//! A device does not drop a frame it has started. A program that quits while one runs (the
//! viewer, `q` during a frame a heavy lookup makes seconds long on a CPU driver) would wait
//! for it in its teardown, holding the terminal without a reason a person can see. It can
//! end instead, as [`end_without_teardown`] does: the kernel frees the process's memory and
//! its device work (a GPU's driver reclaims its queues; a CPU driver's threads are the
//! process's own). It must not end by `exit`: the exit handlers and C++ destructors of the
//! driver (llvmpipe's LLVM) would run while its threads still execute the frame.

use std::io::Write;
use std::process::ExitCode;

use super::validation::{ValidationFailed, EXIT_VALIDATION};

/// The error and its causes on one line, each cause once: many errors already say their
/// cause in their own message (`cannot read x: No such file`), and printing the chain as well
/// would repeat it.
pub fn error_text(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = e.to_string();
    for cause in chain(e).skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text = format!("{text}: {cause}");
        }
    }
    crate::text::bounded_message(&text)
}

/// The exit status for an error: [`EXIT_VALIDATION`] when the validation layer reported
/// messages (whether or not the work failed too), else 1.
pub fn exit_status(e: &(dyn std::error::Error + 'static)) -> u8 {
    match chain(e).any(|e| e.is::<ValidationFailed>()) {
        true => EXIT_VALIDATION,
        false => 1,
    }
}

/// The error and its causes, outermost first.
fn chain<'a>(
    e: &'a (dyn std::error::Error + 'static),
) -> impl Iterator<Item = &'a (dyn std::error::Error + 'static)> {
    std::iter::successors(Some(e), |e| e.source())
}

/// A command's result as its exit status, its error said on stderr (`error: ...`). A failed
/// write to stdout (not the reader leaving) is the command's failure too.
pub fn report<E>(result: Result<ExitCode, E>) -> ExitCode
where
    E: AsRef<dyn std::error::Error + Send + Sync + 'static>,
{
    match verdict(result) {
        Ok(code) => code,
        Err(status) => ExitCode::from(status),
    }
}

/// Ends the process now, as [`report`] would say `result`, without running destructors or
/// exit handlers: for a program that leaves work on its device (see the module's comment).
/// Its output is flushed first; it writes no file after this.
pub fn end_without_teardown<E>(result: Result<ExitCode, E>) -> !
where
    E: AsRef<dyn std::error::Error + Send + Sync + 'static>,
{
    let status = match verdict(result) {
        Ok(code) if code == ExitCode::SUCCESS => 0,
        Ok(_) => 1,
        Err(status) => status,
    };
    let _ = std::io::stdout().flush();
    let _ = std::io::stderr().flush();
    // SAFETY: ends the process at once, as documented above; nothing after it runs.
    unsafe { libc::_exit(i32::from(status)) }
}

/// The exit code of a success, or the status of an error once said on stderr.
fn verdict<E>(result: Result<ExitCode, E>) -> Result<ExitCode, u8>
where
    E: AsRef<dyn std::error::Error + Send + Sync + 'static>,
{
    let stdout = crate::stdout::verdict();
    let said = |e: &(dyn std::error::Error + 'static)| {
        crate::say_err!("error: {}", error_text(e));
        exit_status(e)
    };
    match (result, stdout) {
        (Err(e), _) => Err(said(e.as_ref())),
        (Ok(_), Err(e)) => Err(said(&e)),
        (Ok(code), Ok(())) => Ok(code),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::process::validation::checked;
    use crate::vk::instance::ValidationLog;

    fn failed(work: Option<&str>) -> ValidationFailed {
        ValidationFailed {
            count: 2,
            first: "[vulkan ERROR] VUID-x".into(),
            work: work.map(|w| w.into()),
        }
    }

    #[test]
    fn validation_messages_exit_3_and_keep_the_work_error() {
        let e = failed(None);
        assert_eq!(exit_status(&e), 3);
        assert!(
            error_text(&e).contains("2 message(s)"),
            "{}",
            error_text(&e)
        );
        let e = failed(Some("device lost"));
        assert_eq!(exit_status(&e), 3);
        let text = error_text(&e);
        assert!(
            text.contains("2 message(s)") && text.contains("device lost"),
            "{text}"
        );
        // No messages: the work's own error, exit 1.
        let work: Box<dyn std::error::Error + Send + Sync> = "bad scene".into();
        let plain: Result<(), _> = checked(&ValidationLog::default(), Err(work));
        assert_eq!(exit_status(plain.unwrap_err().as_ref()), 1);
    }

    /// An error that wraps another, as a context does.
    #[derive(Debug)]
    struct Wrapped(&'static str, std::io::Error);

    impl std::fmt::Display for Wrapped {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str(self.0)
        }
    }

    impl std::error::Error for Wrapped {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.1)
        }
    }

    #[test]
    fn each_cause_is_said_once() {
        let io = || std::io::Error::new(std::io::ErrorKind::NotFound, "No such file");
        // A cause that its error's message already includes is not repeated...
        let e = Wrapped("cannot read x.toml: No such file", io());
        assert_eq!(error_text(&e), "cannot read x.toml: No such file");
        // ...one it does not include is appended.
        let e = Wrapped("cannot write y", std::io::Error::other("disk full"));
        assert_eq!(error_text(&e), "cannot write y: disk full");
    }
}
