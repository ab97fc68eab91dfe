//! The verdict of the Vulkan validation layer, the same for every command that creates an
//! instance (`bench`, `render`, `info`, `probe`): with validation on (`--validate` or
//! `SPECCHIO_VALIDATE=1`), any message the layer reported makes the command fail, exit 3, and
//! say how many messages there were (each is printed on stderr as it arrives).

use specchio::vk::instance::ValidationLog;

/// The exit status of a command whose work succeeded but whose validation did not.
pub const EXIT_VALIDATION: u8 = 3;

/// The layer reported messages: the command's result cannot be trusted.
#[derive(Debug)]
pub struct ValidationFailed {
    pub count: usize,
    pub first: String,
}

impl std::fmt::Display for ValidationFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the Vulkan validation layer reported {} message(s) (printed above; the first: {})",
            self.count, self.first
        )
    }
}

impl std::error::Error for ValidationFailed {}

/// Ok when the layer reported nothing.
pub fn verdict(messages: &[String]) -> Result<(), ValidationFailed> {
    match messages.first() {
        None => Ok(()),
        Some(first) => Err(ValidationFailed {
            count: messages.len(),
            first: first.clone(),
        }),
    }
}

/// `result` held to "no messages": call it once every Vulkan object is gone (the layer's
/// leak report arrives while the device is destroyed). An error of the work itself is kept,
/// with the validation failure as its context.
pub fn checked<T>(log: &ValidationLog, result: anyhow::Result<T>) -> anyhow::Result<T> {
    held_to(&log.messages(), result)
}

/// [`checked`] on the messages themselves.
fn held_to<T>(messages: &[String], result: anyhow::Result<T>) -> anyhow::Result<T> {
    match (result, verdict(messages)) {
        (result, Ok(())) => result,
        (Ok(_), Err(failed)) => Err(failed.into()),
        (Err(e), Err(failed)) => Err(e.context(failed)),
    }
}

/// The exit status for an error: [`EXIT_VALIDATION`] when validation failed, else 1.
pub fn exit_code(e: &anyhow::Error) -> std::process::ExitCode {
    if e.downcast_ref::<ValidationFailed>().is_some() {
        std::process::ExitCode::from(EXIT_VALIDATION)
    } else {
        std::process::ExitCode::FAILURE
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run_with(messages: &[&str], work: anyhow::Result<u32>) -> anyhow::Result<u32> {
        held_to(
            &messages.iter().map(|m| m.to_string()).collect::<Vec<_>>(),
            work,
        )
    }

    #[test]
    fn no_messages_pass_the_result_through() {
        assert_eq!(verdict(&[]).ok(), Some(()));
        assert_eq!(run_with(&[], Ok(7)).unwrap(), 7);
        assert!(checked(&ValidationLog::default(), Ok(7)).is_ok());
    }

    #[test]
    fn any_message_fails_with_exit_3_and_the_count() {
        let e = run_with(&["[vulkan ERROR] VUID-x", "[vulkan WARNING] y"], Ok(7)).unwrap_err();
        let text = format!("{e:#}");
        assert!(
            text.contains("2 message(s)") && text.contains("VUID-x"),
            "{text}"
        );
        assert_eq!(exit_code(&e), std::process::ExitCode::from(3));
    }

    #[test]
    fn a_failed_command_keeps_its_error_and_still_exits_3() {
        let e = run_with(&["m"], Err(anyhow::anyhow!("device lost"))).unwrap_err();
        let text = format!("{e:#}");
        assert!(
            text.contains("device lost") && text.contains("1 message(s)"),
            "{text}"
        );
        assert_eq!(exit_code(&e), std::process::ExitCode::from(3));
        let plain = anyhow::anyhow!("bad scene");
        assert_eq!(exit_code(&plain), std::process::ExitCode::FAILURE);
    }
}
