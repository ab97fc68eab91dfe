//! Subresource ranges as the frame graph counts them: an image's levels and layers numbered
//! one by one (mip-major), and numbered subresources that need the same barrier merged back
//! into as few ranges as cover exactly them.

use std::collections::BTreeMap;

use ash::vk;

use super::Sync;

/// An image's subresource range as a value that compares (ash's range does not).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Subresources {
    aspect: vk::ImageAspectFlags,
    /// First level and count.
    mips: [u32; 2],
    /// First layer and count.
    layers: [u32; 2],
}

/// The source side of a barrier: old layout, stages and accesses.
type From = (vk::ImageLayout, Sync);

impl Subresources {
    pub fn of(range: vk::ImageSubresourceRange) -> Self {
        Self {
            aspect: range.aspect_mask,
            mips: [range.base_mip_level, range.level_count],
            layers: [range.base_array_layer, range.layer_count],
        }
    }

    pub fn range(self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: self.aspect,
            base_mip_level: self.mips[0],
            level_count: self.mips[1],
            base_array_layer: self.layers[0],
            layer_count: self.layers[1],
        }
    }

    /// How many subresources the range holds.
    pub fn count(self) -> usize {
        (self.mips[1] * self.layers[1]) as usize
    }

    /// The numbers, within `self` (a whole image), of the subresources of `part`.
    pub fn indices(self, part: Subresources) -> Vec<usize> {
        let inside = |[base, count]: [u32; 2], [all_base, all_count]: [u32; 2]| {
            base >= all_base && base + count <= all_base + all_count
        };
        assert!(
            part.aspect == self.aspect
                && inside(part.mips, self.mips)
                && inside(part.layers, self.layers),
            "{part:?} is not a part of {self:?}"
        );
        let mips = part.mips[0]..part.mips[0] + part.mips[1];
        (mips.flat_map(|m| {
            let layers = part.layers[0]..part.layers[0] + part.layers[1];
            layers.map(move |l| ((m - self.mips[0]) * self.layers[1] + l - self.layers[0]) as usize)
        }))
        .collect()
    }

    /// The numbered subresources of `self` (a whole image) in `needed`, each with the source
    /// side of its barrier, as ranges: per source, runs of adjacent layers, and a run over
    /// adjacent levels where each level has the same runs. Sorted by level, then layer.
    pub fn merge(self, needed: Vec<(usize, From)>) -> Vec<(Subresources, From)> {
        let layers = self.layers[1] as usize;
        let mut by_source: Vec<(From, BTreeMap<u32, Vec<u32>>)> = Vec::new();
        for (i, from) in needed {
            let at = match by_source.iter().position(|(f, _)| *f == from) {
                Some(at) => at,
                None => {
                    by_source.push((from, BTreeMap::new()));
                    by_source.len() - 1
                }
            };
            let (mip, layer) = ((i / layers) as u32, (i % layers) as u32);
            by_source[at].1.entry(mip).or_default().push(layer);
        }
        let mut merged: Vec<(Subresources, From)> = Vec::new();
        for (from, levels) in by_source {
            // Open blocks: a run of layers and the levels it spans so far.
            let mut open: Vec<([u32; 2], [u32; 2])> = Vec::new();
            let mut closed = Vec::new();
            for (&mip, layers) in &levels {
                let runs = runs(layers);
                let (continued, ended): (Vec<_>, Vec<_>) = open
                    .drain(..)
                    .partition(|(run, [m0, n])| m0 + n == mip && runs.contains(run));
                closed.extend(ended);
                open = (runs.iter())
                    .map(|run| match continued.iter().find(|(r, _)| r == run) {
                        Some(&(r, [m0, n])) => (r, [m0, n + 1]),
                        None => (*run, [mip, 1]),
                    })
                    .collect();
            }
            closed.extend(open);
            merged.extend(closed.into_iter().map(|([l0, ln], [m0, mn])| {
                let range = Subresources {
                    aspect: self.aspect,
                    mips: [self.mips[0] + m0, mn],
                    layers: [self.layers[0] + l0, ln],
                };
                (range, from)
            }));
        }
        merged.sort_by_key(|(r, _)| (r.mips[0], r.layers[0]));
        merged
    }
}

/// Adjacent numbers as runs (first, count).
fn runs(layers: &[u32]) -> Vec<[u32; 2]> {
    let mut sorted = layers.to_vec();
    sorted.sort_unstable();
    let mut runs: Vec<[u32; 2]> = Vec::new();
    for l in sorted {
        match runs.last_mut() {
            Some([first, count]) if *first + *count == l => *count += 1,
            _ => runs.push([l, 1]),
        }
    }
    runs
}
