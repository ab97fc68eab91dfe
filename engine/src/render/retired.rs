//! Deferred destruction: what the renderer lets go of while frames in flight may still use it
//! (a lookup's pass switched in place, the ray map's pass made for it) is kept until the last
//! frame submitted before it was let go has finished, then dropped, as Granite's per-frame
//! deletion queues do. Nothing waits for the GPU to replace a part.
//!
//! Frames are numbered in submission order (1, 2, ...) and finish in that order, so "the last
//! frame that may use it" is one number, and finishing frame n releases everything kept for
//! frames up to n.

/// Objects kept for the frames that may still use them.
pub(super) struct Retired<T> {
    /// Each object and the number of the last frame that may use it, in the order let go.
    kept: Vec<(u64, T)>,
}

impl<T> Default for Retired<T> {
    fn default() -> Self {
        Self { kept: Vec::new() }
    }
}

impl<T> Retired<T> {
    /// Keeps `object` until frame `last` has finished; with no frame in flight (`None`) it is
    /// dropped now.
    pub fn keep(&mut self, last: Option<u64>, object: T) {
        if let Some(last) = last {
            self.kept.push((last, object));
        }
    }

    /// The object frame `frame` used, if it was let go since: the first kept for a frame at
    /// or after it (objects let go earlier served earlier frames).
    pub fn used_by(&self, frame: u64) -> Option<&T> {
        (self.kept.iter())
            .find(|(last, _)| *last >= frame)
            .map(|(_, object)| object)
    }

    /// Frame `frame` has finished: drops what no later frame may use.
    pub fn release_through(&mut self, frame: u64) {
        self.kept.retain(|(last, _)| *last > frame);
    }

    /// How many objects are kept.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.kept.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two switches while frames run: frame 3 used what was let go after it, frame 5 what was
    /// let go after 5, frame 6 the current one; each is dropped once its last frame finished,
    /// and nothing is kept when no frame runs.
    #[test]
    fn each_object_lives_until_its_last_frame_finished() {
        let mut retired = Retired::default();
        retired.keep(Some(3), "first");
        retired.keep(Some(5), "second");
        retired.keep(None, "never kept");
        assert_eq!(retired.len(), 2);
        assert_eq!(retired.used_by(2), Some(&"first"));
        assert_eq!(retired.used_by(3), Some(&"first"));
        assert_eq!(retired.used_by(4), Some(&"second"));
        assert_eq!(retired.used_by(6), None);
        retired.release_through(2);
        assert_eq!(retired.len(), 2);
        retired.release_through(3);
        assert_eq!((retired.len(), retired.used_by(4)), (1, Some(&"second")));
        retired.release_through(5);
        assert_eq!(retired.len(), 0);
    }
}
