//! Appearance-based localisation: where is the robot, from its sensor image alone?
//!
//! The robot is the mirror and the sensor camera below it, moving together. A database holds
//! the sensor's *descriptor* at known poses (landmarks on a floor grid, [`poses`]); a query
//! image is described the same way and matched to its nearest landmark, and the heading is
//! recovered by comparing the two descriptors.
//!
//! Descriptors are plug-ins behind [`Descriptor`], each with one home (a module here) and a
//! name in [`DescriptorKind`], so that a second one can be compared with the first on the
//! same sweep. The first is the Fourier signature of the cylindrical panorama ([`fourier`]),
//! which forgets the heading; the second, a low-resolution panorama compared over every
//! column shift ([`shift`]), searches it.

pub mod fourier;
pub mod poses;
pub mod position;
pub mod shift;

use serde::{Deserialize, Serialize};

use crate::image::RgbaImage;

/// What localisation can refuse.
#[derive(Debug, thiserror::Error)]
pub enum LocaliseError {
    #[error(
        "no landmark fits: at spacing {} m no grid pose keeps the mirror (radius {} m) and \
         the sensor's line of sight inside the room and clear of objects",
        crate::text::num_text(*spacing_m),
        crate::text::num_text(*radius_m)
    )]
    NoLandmarks { spacing_m: f64, radius_m: f32 },
    #[error(
        "the sensor camera ({} m) is outside the room (floor {} m, ceiling {} m) at the \
         mirror's height",
        crate::text::num_text(*sensor_y_m),
        crate::text::num_text(*floor_m),
        crate::text::num_text(*ceiling_m)
    )]
    SensorOutsideRoom {
        sensor_y_m: f32,
        floor_m: f32,
        ceiling_m: f32,
    },
    #[error(
        "no free query pose found in {tries} random tries at time {} s: the room's free \
         floor is (almost) empty",
        crate::text::num_text(*time_s)
    )]
    NoFreePose { tries: u32, time_s: f64 },
    #[error(
        "a landmark grid of spacing {} m spans {} poses over this room's floor, more \
         than the {max} a sweep may render: choose a larger spacing",
        crate::text::num_text(*spacing_m),
        crate::text::count_text(*count)
    )]
    TooManyLandmarks {
        spacing_m: f64,
        count: u64,
        max: u64,
    },
}

/// The most grid poses a landmark sweep renders (half an hour at 10 sensor images/s), checked
/// before any pose is made: a tiny spacing must be refused, not run for days.
pub const MAX_LANDMARKS: u64 = 20_000;

/// A descriptor of one panorama, as numbers a [`Descriptor`] made and reads.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Signature {
    /// The signature's columns: a heading is a circular shift of this many (the panorama's
    /// width for the Fourier signature, its low-resolution width for the column shift).
    pub columns: u32,
    pub values: Vec<f32>,
}

/// A way to describe a panorama, compare two descriptions and recover the turn between them.
pub trait Descriptor: Sync {
    /// Its name in reports and on the command line.
    fn name(&self) -> &'static str;
    /// The descriptor of a panorama whose columns span 360 degrees of azimuth.
    fn describe(&self, panorama: &RgbaImage) -> Signature;
    /// Dissimilarity of two descriptors (0 for equal ones; smaller is more alike).
    fn distance(&self, a: &Signature, b: &Signature) -> f64;
    /// The turn (radians, in [0, 2 pi)) that maps `landmark`'s panorama onto `query`'s: the
    /// query's column at azimuth `a` shows what the landmark's shows at `a - turn`.
    fn turn(&self, landmark: &Signature, query: &Signature) -> f64;
    /// The shape of [`Descriptor::describe`]'s signature of a `width` x `height` panorama: its
    /// `columns` and its number of values. A saved signature of another shape was made with
    /// other settings (or is damaged) and cannot be compared with this run's.
    fn shape(&self, width: u32, height: u32) -> (u32, usize);
    /// The cells [`Descriptor::distance`] compares for one pair of signatures of a `width` x
    /// `height` panorama: the unit matching's work is counted in before a run commits to it.
    fn pair_cost(&self, width: u32, height: u32) -> u64;
}

/// The registered descriptors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DescriptorKind {
    Fourier,
    ColumnShift,
}

impl DescriptorKind {
    pub const ALL: [Self; 2] = [Self::Fourier, Self::ColumnShift];

    pub fn name(self) -> &'static str {
        match self {
            Self::Fourier => "fourier",
            Self::ColumnShift => "column-shift",
        }
    }

    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|d| d.name() == name)
    }

    pub fn names() -> String {
        Self::ALL.map(Self::name).join(", ")
    }

    /// The largest `k` whose descriptor a panorama `width` columns wide holds: a row's
    /// spectrum has `width / 2 + 1` distinct Fourier coefficients, and column shift takes
    /// `16 k` of the panorama's own columns, all of them from the `k` whose `16 k` first
    /// reaches `width`. Past it a descriptor keeps what the panorama has, so every larger `k`
    /// would describe alike under another name.
    pub fn largest_k(self, width: u32) -> u32 {
        match self {
            Self::Fourier => width / 2 + 1,
            Self::ColumnShift => width.div_ceil(shift::COLUMNS_PER_K).max(1),
        }
    }

    /// Why `k` is past [`Self::largest_k`] of a panorama `width` columns wide, said for a
    /// user after the option's name: `"fourier takes at most 49 for a panorama 96 columns
    /// wide (its rows have 49 distinct Fourier coefficients)"`.
    pub fn k_fault(self, k: u32, width: u32) -> Option<String> {
        let most = self.largest_k(width);
        let why = match self {
            Self::Fourier => format!("its rows have {most} distinct Fourier coefficients"),
            Self::ColumnShift => format!(
                "it takes {} k of the panorama's columns, all of them at k = {most}",
                shift::COLUMNS_PER_K
            ),
        };
        (k > most).then(|| {
            format!(
                "{} takes at most {most} for a panorama {width} columns wide ({why})",
                self.name()
            )
        })
    }

    /// The descriptor, with `coefficients` its size parameter `k` (Fourier: coefficients per
    /// row; column shift: `16 k` columns).
    pub fn build(self, coefficients: u32) -> Box<dyn Descriptor> {
        match self {
            Self::Fourier => Box::new(fourier::FourierSignature { coefficients }),
            Self::ColumnShift => Box::new(shift::ColumnShift::for_k(coefficients)),
        }
    }
}

/// Grey level of a linear RGB pixel (Rec. 709 luminance): descriptors compare brightness,
/// which also keeps them cheap.
pub fn luminance(p: [f32; 4]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

/// The `descriptor` distance of every landmark in `database` to `query`.
pub fn distances(
    descriptor: &dyn Descriptor,
    database: &[Signature],
    query: &Signature,
) -> Vec<f64> {
    database
        .iter()
        .map(|s| descriptor.distance(s, query))
        .collect()
}

/// Indices of landmarks by increasing distance `d` (from [`distances`]; ties by index).
pub fn rank(d: &[f64]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..d.len()).collect();
    order.sort_by(|&a, &b| d[a].total_cmp(&d[b]).then(a.cmp(&b)));
    order
}

/// A test panorama whose pixel (j, r) is `f(r, azimuth of column j)`, grey: the descriptors'
/// tests build their known answers on it.
#[cfg(test)]
pub(crate) fn test_panorama(width: u32, rows: u32, f: impl Fn(u32, f64) -> f32) -> RgbaImage {
    use std::f64::consts::TAU;
    let pixels = (0..rows)
        .flat_map(|r| {
            let f = &f;
            (0..width).map(move |j| {
                let v = f(r, (f64::from(j) + 0.5) / f64::from(width) * TAU);
                [v, v, v, 1.0]
            })
        })
        .collect();
    RgbaImage {
        width,
        height: rows,
        pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shape a saved signature is checked against is the one `describe` makes, for every
    /// descriptor, for narrow, wide, tall and flat panoramas and for k below and beyond what
    /// they hold; and comparing two costs at least one cell per value.
    #[test]
    fn shape_is_what_describe_makes() {
        for kind in DescriptorKind::ALL {
            for (w, h) in [(3u32, 2u32), (76, 24), (152, 49), (608, 194), (1000, 3)] {
                for k in [1u32, 4, 8, 40, 256] {
                    let d = kind.build(k);
                    let s = d.describe(&test_panorama(w, h, |r, az| {
                        (az + f64::from(r)).sin() as f32
                    }));
                    let what = format!("{} {w}x{h} k={k}", kind.name());
                    assert_eq!(d.shape(w, h), (s.columns, s.values.len()), "{what}");
                    assert!(d.pair_cost(w, h) as usize * 2 >= s.values.len(), "{what}");
                }
            }
        }
    }
}
