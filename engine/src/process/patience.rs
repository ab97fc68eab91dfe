//! How long work runs before it is said: an estimate (`progress`) and a long GPU frame
//! (`interrupt`) both wait [`ESTIMATE_AFTER`], or what `SPECCHIO_ESTIMATE_AFTER_S` says.

use std::sync::OnceLock;
use std::time::Duration;

/// How long the work runs before its estimate is said: long enough to measure a rate, short
/// enough that the user has not yet waited.
pub const ESTIMATE_AFTER: Duration = Duration::from_millis(1500);
/// Seconds to say the estimate after instead ([`ESTIMATE_AFTER`] when unset): `0` makes every
/// command say it after its first part, which is how the tests see the line on a machine of
/// any speed.
pub const ESTIMATE_AFTER_VAR: &str = "SPECCHIO_ESTIMATE_AFTER_S";

/// [`ESTIMATE_AFTER`], or what [`ESTIMATE_AFTER_VAR`] says; a value that is not a number of
/// seconds from 0 to a day is said once and not used.
pub(crate) fn estimate_after() -> Duration {
    static AFTER: OnceLock<Duration> = OnceLock::new();
    *AFTER.get_or_init(|| {
        let Some(text) = std::env::var_os(ESTIMATE_AFTER_VAR) else {
            return ESTIMATE_AFTER;
        };
        let text = text.to_string_lossy();
        match parse_after(&text) {
            Some(after) => after,
            None => {
                crate::say_err!(
                    "warning: {ESTIMATE_AFTER_VAR}={text:?} is not a number of seconds from 0 \
                     to 86400; estimates come after {} s",
                    ESTIMATE_AFTER.as_secs_f64()
                );
                ESTIMATE_AFTER
            }
        }
    })
}

/// Seconds from 0 to a day, as [`ESTIMATE_AFTER_VAR`] takes them.
fn parse_after(text: &str) -> Option<Duration> {
    let s: f64 = text.trim().parse().ok()?;
    (0.0..=86_400.0)
        .contains(&s)
        .then(|| Duration::from_secs_f64(s))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The variable takes seconds from 0 to a day; anything else is no value (said, and the
    /// default kept).
    #[test]
    fn the_estimate_delay_is_seconds_from_zero_to_a_day() {
        assert_eq!(parse_after("0"), Some(Duration::ZERO));
        assert_eq!(parse_after(" 2.5 "), Some(Duration::from_millis(2500)));
        assert_eq!(parse_after("86400"), Some(Duration::from_secs(86_400)));
        for bad in ["", "-1", "nan", "inf", "1e300", "86401", "soon"] {
            assert_eq!(parse_after(bad), None, "{bad:?}");
        }
    }
}
