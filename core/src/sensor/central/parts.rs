//! A calibration's parts, for a command to say how far it is: the ray map, the viewpoint, the
//! two fits, the residuals and the files. A 4096² sensor takes some 15 s on two cores, most
//! of it after the first second, so the command says its estimate and can stop between parts.

/// One part of a calibration, in the order they run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// The exact ray of every sensor pixel.
    Rays,
    /// The point nearest to every pixel's ray.
    Viewpoint,
    /// Mei's model (OpenCV omnidir, Kalibr omni) fitted.
    Omnidir,
    /// Scaramuzza's polynomial (OCamCalib) and its inverse fitted.
    Ocamcalib,
    /// Both models' residual at every mirror pixel.
    Residuals,
    /// The exports, the residual images and the record written.
    Files,
}

impl Part {
    /// Every part, in order.
    pub const ALL: [Part; 6] = [
        Part::Rays,
        Part::Viewpoint,
        Part::Omnidir,
        Part::Ocamcalib,
        Part::Residuals,
        Part::Files,
    ];

    /// Its share of a calibration's time, in hundredths: each part's time in a release build
    /// at 4096² (thesis-room's sphere, 30 November 2026, two cores: 1.0, 0.7, 2.0, 1.1, 2.0
    /// and 3.6 s): the largest sensor's, where an estimate matters. A smaller one spends
    /// more of its time in the fits, which take a bounded sample of its pixels.
    pub fn share(self) -> u64 {
        match self {
            Part::Rays => 10,
            Part::Viewpoint => 7,
            Part::Omnidir => 19,
            Part::Ocamcalib => 11,
            Part::Residuals => 19,
            Part::Files => 34,
        }
    }
}

/// What a calibration reports to (`process::progress::Progress` for the commands): each part
/// done, and whether to stop before the next one.
pub trait Watch {
    fn part_done(&self, part: Part);
    fn stop(&self) -> bool;
}

/// No one watching: every part runs.
pub struct Unwatched;

impl Watch for Unwatched {
    fn part_done(&self, _: Part) {}

    fn stop(&self) -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shares are the whole: a finished calibration is 100 % done, never more.
    #[test]
    fn the_shares_make_a_whole() {
        assert_eq!(Part::ALL.iter().map(|p| p.share()).sum::<u64>(), 100);
    }
}
