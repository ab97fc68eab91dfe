//! A command's image files (its views, a reference's cameras), written one after another and
//! said as they go: a 4096² camera's EXRs and PNGs take seconds each, and a run used to write
//! them for 11 s without a word after its trace's estimate had said "about 2 s left".

use std::path::{Path, PathBuf};

use anyhow::Result;
use specchio::image::RgbaImage;
use specchio::output::{Sink, Transaction};
use specchio::process::progress::{Progress, PERCENT};

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
            match kind {
                Kind::Exr => out.write_exr(path, image)?,
                Kind::Png => out.write_png(path, image)?,
            }
            if let Some(said) = &said {
                said.add(samples(file));
            }
        }
        Ok(())
    }
}
