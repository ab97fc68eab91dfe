//! How long the window takes to answer a key that changes only the window (F1's menu, `h`'s
//! help): from the loop hearing the key to the return of the present of the first window
//! frame drawn after it. On a CPU driver a present returns once that frame has been drawn
//! (Mesa's software present waits for it); the copy into the window may follow on the
//! driver's own thread (lavapipe's X11 present has one). So this is the viewer's share of "a
//! key is answered within one display refresh": the X server's delivery of the key before
//! it and the driver's copy and the display's refresh after it are not in it.
//!
//! A key that changes the scene is answered by the scene's next view instead, rendered and
//! then shown by a window frame like this one. A key heard while the window is hidden or
//! minimised waits for the window to be shown again, and that wait counts: it is what the key
//! waited for.

use std::time::Instant;

/// The keys waiting for their window frame, and the times they waited.
#[derive(Debug, Default)]
pub struct Answers {
    /// The earliest key heard since the last window frame was handed to the present thread.
    waiting: Option<Instant>,
    /// The earliest key the present on its way answers, and when it was handed over.
    presenting: Option<(Instant, Instant)>,
    /// Milliseconds from each answered key to its present's return.
    ms: Vec<f64>,
}

impl Answers {
    /// A key that changes only the window was heard `at`.
    pub fn key(&mut self, at: Instant) {
        self.waiting.get_or_insert(at);
    }

    /// A window frame was handed to the present thread `at`: it answers the keys waiting. The
    /// one before it has returned (the loop draws only then), and was settled first.
    pub fn presented(&mut self, at: Instant) {
        debug_assert!(
            self.presenting.is_none(),
            "the last present was not settled"
        );
        if let Some(key) = self.waiting.take() {
            self.presenting = Some((key, at));
        }
    }

    /// The last present returned `at` (`None`: none has yet): the keys it answered are
    /// counted. A return from before the hand-over is the previous present's.
    pub fn settle(&mut self, returned: Option<Instant>) {
        match (self.presenting, returned) {
            (Some((key, handed)), Some(at)) if at >= handed => {
                self.ms.push(at.duration_since(key).as_secs_f64() * 1e3);
                self.presenting = None;
            }
            _ => {}
        }
    }

    /// The exit summary's line, when some key was answered.
    pub fn summary(&self) -> Option<String> {
        let mut ms = self.ms.clone();
        let median = specchio::metrics::percentile::median(&mut ms)?;
        let max = ms.iter().copied().fold(0.0, f64::max);
        Some(format!(
            "window keys (F1, h): {} answered, median {median:.1} ms, max {max:.1} ms \
             from the key to its frame's present",
            ms.len()
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_key_is_answered_by_the_first_present_after_it() {
        let t0 = Instant::now();
        let at = |ms: u64| t0 + Duration::from_millis(ms);
        let mut a = Answers::default();
        // A present handed over before the key answers nothing.
        a.presented(at(0));
        a.key(at(10));
        a.settle(Some(at(12)));
        assert!(a.summary().is_none());
        // Two keys before one frame: the earlier one's wait counts, once.
        a.key(at(15));
        a.presented(at(20));
        // The previous present's return (before the hand-over) is not this one's.
        a.settle(Some(at(12)));
        assert!(a.summary().is_none());
        a.settle(Some(at(24)));
        a.settle(Some(at(30)));
        assert_eq!(a.ms, [14.0]);
        let line = a.summary().unwrap();
        assert!(
            line.contains("1 answered, median 14.0 ms, max 14.0 ms"),
            "{line}"
        );
    }
}
