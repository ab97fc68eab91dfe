//! The verdict of the Vulkan validation layer, the same for every command that creates an
//! instance (`bench`, `render`, `info`, `probe`): with validation on (`--validate` or
//! `SPECCHIO_VALIDATE=1`), any message the layer reported makes the command fail, exit 3, and
//! say how many messages there were (each is printed on stderr as it arrives).
//! The exit status itself is the binary's to set.

use crate::vk::instance::ValidationLog;

/// The exit status of a command the validation layer reported messages for, whether its work
/// succeeded or failed too (the work's error is then the failure's cause).
pub const EXIT_VALIDATION: u8 = 3;

/// The work's own error, kept as the cause of a validation failure.
pub type WorkError = Box<dyn std::error::Error + Send + Sync>;

/// The layer reported messages: the command's result cannot be trusted.
#[derive(Debug)]
pub struct ValidationFailed {
    pub count: usize,
    pub first: String,
    /// The error the work failed with as well, if it did.
    pub work: Option<WorkError>,
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

impl std::error::Error for ValidationFailed {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.work.as_deref().map(|e| e as _)
    }
}

/// Ok when the layer reported nothing.
pub fn verdict(messages: &[String]) -> Result<(), ValidationFailed> {
    match messages.first() {
        None => Ok(()),
        Some(first) => Err(ValidationFailed {
            count: messages.len(),
            first: first.clone(),
            work: None,
        }),
    }
}

/// `result` held to "no messages": call it once every Vulkan object is gone (the layer's
/// leak report arrives while the device is destroyed). An error of the work itself is kept
/// as the validation failure's cause, so that the command still exits with
/// [`EXIT_VALIDATION`] and says both.
pub fn checked<T, E>(log: &ValidationLog, result: Result<T, E>) -> Result<T, E>
where
    E: From<ValidationFailed> + Into<WorkError>,
{
    held_to(&log.messages(), result)
}

/// [`checked`] on the messages themselves.
fn held_to<T, E>(messages: &[String], result: Result<T, E>) -> Result<T, E>
where
    E: From<ValidationFailed> + Into<WorkError>,
{
    match (result, verdict(messages)) {
        (result, Ok(())) => result,
        (Ok(_), Err(failed)) => Err(failed.into()),
        (Err(e), Err(failed)) => Err(ValidationFailed {
            work: Some(e.into()),
            ..failed
        }
        .into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The error a command's work fails with, in these tests.
    #[derive(Debug, thiserror::Error)]
    enum Failure {
        #[error("{0}")]
        Work(String),
        #[error(transparent)]
        Validation(#[from] ValidationFailed),
    }

    fn run_with(messages: &[&str], work: Result<u32, Failure>) -> Result<u32, Failure> {
        held_to(
            &messages.iter().map(|m| m.to_string()).collect::<Vec<_>>(),
            work,
        )
    }

    #[test]
    fn no_messages_pass_the_result_through() {
        assert!(verdict(&[]).is_ok());
        assert_eq!(run_with(&[], Ok(7)).unwrap(), 7);
        assert!(checked::<_, Failure>(&ValidationLog::default(), Ok(7)).is_ok());
        let work = run_with(&[], Err(Failure::Work("bad scene".into()))).unwrap_err();
        assert!(matches!(work, Failure::Work(_)), "{work}");
    }

    #[test]
    fn any_message_fails_with_the_count_and_the_first() {
        let e = run_with(&["[vulkan ERROR] VUID-x", "[vulkan WARNING] y"], Ok(7)).unwrap_err();
        let Failure::Validation(failed) = e else {
            panic!("not a validation failure: {e}")
        };
        assert_eq!(
            (failed.count, failed.first.as_str()),
            (2, "[vulkan ERROR] VUID-x")
        );
        assert!(failed.to_string().contains("2 message(s)"), "{failed}");
    }

    #[test]
    fn a_failed_command_keeps_its_error_as_the_cause() {
        let e = run_with(&["m"], Err(Failure::Work("device lost".into()))).unwrap_err();
        let Failure::Validation(failed) = e else {
            panic!("not a validation failure: {e}")
        };
        let cause = std::error::Error::source(&failed).map(|c| c.to_string());
        assert_eq!(cause.as_deref(), Some("device lost"));
    }
}
