//! What `localise` refuses before any work because it would mean nothing: a source or a time
//! twice, a fill method or a cube size where no source fills a cube.

use anyhow::{bail, Result};
use specchio::render::lookups;
use specchio::render::methods::Method;

use super::source::Source;

/// The cube's face size in texels where `--cube-size` is not given.
const DEFAULT_CUBE_PX: u32 = 128;
use super::{names, Args};

impl Args {
    /// `--method`, or six-pass where it is not given.
    pub(super) fn method_or_default(&self) -> Method {
        self.method.unwrap_or(Method::SIX_PASS)
    }

    /// `--cube-size`, or 128 texels where it is not given.
    pub(super) fn cube_size_or_default(&self) -> u32 {
        self.cube_size.unwrap_or(DEFAULT_CUBE_PX)
    }
}

/// Whether `source` samples a cube map, so that one is filled for it: a lookup that reads
/// the cube, not one that traces its rays, nor the reference.
pub(super) fn samples_cube(source: Source) -> bool {
    matches!(source, Source::Lookup(l) if lookups::plugin(l).uses_cube())
}

/// `--method` and `--cube-size` where some source fills a cube: with none they would change
/// nothing, and be recorded in localise.json as used.
pub(super) fn cube_options_apply(args: &Args, sources: &[Source]) -> Result<()> {
    let given = [
        ("--method", args.method.is_some()),
        ("--cube-size", args.cube_size.is_some()),
    ];
    let Some((option, _)) = given.into_iter().find(|(_, given)| *given) else {
        return Ok(());
    };
    if !sources.iter().any(|&s| samples_cube(s)) {
        bail!(
            "{option}: no source here samples a cube map ({}), so none is filled; leave it \
             out, or name a source that samples the cube in --sources (box, say)",
            names(sources)
        );
    }
    Ok(())
}

/// Each source and each time once: a time given twice rendered its queries twice into two
/// equal rows, a source given twice was merged without a word.
pub(super) fn once_each(sources: &[Source], times: &[f64]) -> Result<()> {
    if let Some((first, again)) = repeated(sources) {
        let name = sources[first - 1].name();
        bail!("--sources: {name} is given twice (items {first} and {again}); each source once");
    }
    if let Some((first, again)) = repeated(times) {
        let t = times[first - 1];
        bail!("--times: {t} is given twice (items {first} and {again}); each time once");
    }
    Ok(())
}

/// The first item given again, as the places (from 1) of its first and second mention.
fn repeated<T: PartialEq>(items: &[T]) -> Option<(usize, usize)> {
    (items.iter().enumerate()).find_map(|(i, x)| {
        let first = items[..i].iter().position(|y| y == x)?;
        Some((first + 1, i + 1))
    })
}
