//! A command's image files (its views, a reference's cameras), written one after another and
//! said as they go: a 4096² camera's EXRs and PNGs take seconds each, and a run used to write
//! them for 11 s without a word after its trace's estimate had said "about 2 s left".

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::Result;
use specchio::image::RgbaImage;
use specchio::output::{Sink, Transaction};
use specchio::process::progress::{Progress, PERCENT};
use specchio::watch::Watch;

/// How an image is written: linear RGBA in an EXR (4 samples a pixel), or an 8-bit sRGB
/// preview in a PNG (3).
#[derive(Clone, Copy)]
enum Kind {
    Exr,
    Png,
}

impl Kind {
    fn samples(self) -> u64 {
        match self {
            Kind::Exr => 4,
            Kind::Png => 3,
        }
    }
}

/// The image files to write, in order.
#[derive(Default)]
pub(crate) struct ImageFiles<'a> {
    files: Vec<(PathBuf, &'a RgbaImage, Kind)>,
}

impl<'a> ImageFiles<'a> {
    /// `image` as an EXR at `path`.
    pub(crate) fn exr(&mut self, path: PathBuf, image: &'a RgbaImage) {
        self.files.push((path, image, Kind::Exr));
    }

    /// `image` as an EXR and its PNG preview, at `stem` + `.exr` / `.png`.
    pub(crate) fn exr_and_png(&mut self, dir: &Path, stem: &str, image: &'a RgbaImage) {
        self.files
            .push((dir.join(format!("{stem}.exr")), image, Kind::Exr));
        self.files
            .push((dir.join(format!("{stem}.png")), image, Kind::Png));
    }

    /// `image` as a PNG at `path`.
    pub(crate) fn png(&mut self, path: PathBuf, image: &'a RgbaImage) {
        self.files.push((path, image, Kind::Png));
    }

    /// Writes them all into `out`; with `what` ("reference"), said as "`what`: writing 10
    /// image files: 40 % done in ..." once they have taken a moment, each file counted by
    /// its samples as it is written.
    pub(crate) fn write(self, out: &Transaction, what: Option<&str>) -> Result<()> {
        let samples = |(_, image, kind): &(PathBuf, &RgbaImage, Kind)| {
            u64::from(image.width) * u64::from(image.height) * kind.samples()
        };
        let total = self.files.iter().map(samples).sum();
        let n = self.files.len();
        let said =
            what.map(|w| Progress::new(format!("{w}: writing {n} image files"), total, PERCENT));
        for file in &self.files {
            let (path, image, kind) = file;
            // An EXR counted row by row as it encodes (an 8192² one takes seconds), the rest
            // of a file as it ends.
            let rows = Rows {
                said: said.as_ref(),
                samples_a_row: u64::from(image.width) * kind.samples(),
                counted: AtomicU64::new(0),
            };
            match kind {
                Kind::Exr => out.write_exr_watched(path, image, &rows)?,
                Kind::Png => out.write_png(path, image)?,
            }
            if let Some(said) = &said {
                said.add(samples(file) - rows.counted.load(Ordering::Relaxed));
            }
        }
        Ok(())
    }
}

/// One file's rows into the files' [`Progress`], in samples.
struct Rows<'a> {
    said: Option<&'a Progress>,
    samples_a_row: u64,
    counted: AtomicU64,
}

impl Watch for Rows<'_> {
    fn begin(&self, _rows: u64, _width: u32) {}

    fn rows_done(&self, rows: u32) {
        if let Some(said) = self.said {
            let samples = u64::from(rows) * self.samples_a_row;
            self.counted.fetch_add(samples, Ordering::Relaxed);
            said.add(samples);
        }
    }

    fn stop(&self) -> bool {
        false
    }
}
