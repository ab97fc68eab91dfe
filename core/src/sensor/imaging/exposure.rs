//! The exposure as a span of time: the instants a frame's camera image is integrated over
//! (motion blur), and, with a rolling shutter, which of them each row sees.
//!
//! The instants lie on one grid, a step of `exposure_s / motion_blur_samples` apart, each at
//! the middle of its step. With a global shutter every row sees the same N instants, centred
//! on the frame's time. With a rolling shutter row y's exposure is centred
//! `rolling_shutter_s × ((y + ½) / height − ½)` after the frame's time (the middle row's is
//! the frame's), and it sees the N consecutive instants of the grid within it: the grid
//! spans every row's exposure, N + ⌈readout / step⌉ instants in all.

use super::{Imaging, RgbaImage};

/// The instants of one frame's exposure.
#[derive(Debug, Clone, PartialEq)]
pub struct Schedule {
    /// Where the grid's first step starts (s).
    start: f64,
    step: f64,
    /// The instants each row sees.
    per_row: usize,
    /// The instants in all.
    instants: usize,
    /// The rolling shutter's readout (s): 0 for a global shutter.
    readout: f64,
}

impl Schedule {
    /// The schedule of a frame at `t_s`.
    pub fn of(imaging: &Imaging, t_s: f64) -> Schedule {
        let per_row = imaging.motion_blur_samples.max(1) as usize;
        let exposure = f64::from(imaging.exposure_s);
        let readout = f64::from(imaging.rolling_shutter_s);
        let step = exposure / per_row as f64;
        Schedule {
            start: t_s - 0.5 * (readout + exposure),
            step,
            per_row,
            instants: per_row + (readout / step).ceil() as usize,
            readout,
        }
    }

    /// Every instant, in time order.
    pub fn times(&self) -> Vec<f64> {
        (0..self.instants)
            .map(|k| self.start + (k as f64 + 0.5) * self.step)
            .collect()
    }

    /// The instants row `y` of `height` sees: `per_row` of them from the first returned.
    pub fn first_of_row(&self, y: usize, height: usize) -> usize {
        // Row y's exposure starts readout × (y + ½) / height after the grid's start.
        let at = self.readout * (y as f64 + 0.5) / height as f64 / self.step;
        ((at - 0.5).ceil().max(0.0) as usize).min(self.instants - self.per_row)
    }

    /// How many instants there are in all: each a render of the sensor's view where there are
    /// two or more ([`integrate`]).
    pub fn instants(&self) -> usize {
        self.instants
    }

    /// How many instants each row sees.
    pub fn per_row(&self) -> usize {
        self.per_row
    }
}

/// The light of the whole exposure of a frame at `t_s`: per row, the mean of the images
/// `render_at(t)` gives at the instants that row sees ([`Schedule`]); None (the frame's own
/// image is the light) where the exposure is one instant for every row.
pub fn integrate<E>(
    imaging: &Imaging,
    t_s: f64,
    mut render_at: impl FnMut(f64) -> Result<RgbaImage, E>,
) -> Result<Option<RgbaImage>, E> {
    let schedule = Schedule::of(imaging, t_s);
    let times = schedule.times();
    if times.len() < 2 {
        return Ok(None);
    }
    let mut sum: Vec<[f64; 4]> = Vec::new();
    let (mut width, mut height) = (0, 0);
    for (k, t) in times.iter().enumerate() {
        let image = render_at(*t)?;
        if sum.is_empty() {
            (width, height) = (image.width as usize, image.height as usize);
            sum = vec![[0.0; 4]; image.pixels.len()];
        }
        for y in 0..height {
            let first = schedule.first_of_row(y, height);
            if !(first..first + schedule.per_row()).contains(&k) {
                continue;
            }
            let row = y * width..(y + 1) * width;
            for (s, p) in sum[row.clone()].iter_mut().zip(&image.pixels[row]) {
                for c in 0..4 {
                    s[c] += f64::from(p[c]);
                }
            }
        }
    }
    let n = schedule.per_row() as f64;
    Ok(Some(RgbaImage {
        width: width as u32,
        height: height as u32,
        pixels: (sum.iter()).map(|s| s.map(|v| (v / n) as f32)).collect(),
    }))
}
