//! The footprint (issue #46): the cube filled only where the views read it. Before a frame
//! fills the cube, a pass marks every tile of level 0 the drawn views' mirror pixels may sample
//! (`pass.rs`, `shaders/footprint_mark.comp.glsl`); the update then re-renders only those
//! tiles, through the dirty rectangles' path, which every method fills exactly
//! (`docs/methods.md`, "The footprint").
//!
//! What the cube holds is tracked by tile: `valid` tiles show the state the cube shows. An
//! update re-renders the needed tiles that are not valid (never filled, or changed while not
//! needed) whole, and within the valid ones only the update's own dirty rectangles; a tile
//! nobody reads is left as it is, valid or not. The marks are made again only when what they
//! are made from changes (the frame's constants, the marked views, the cube's levels): a
//! sensor fixed under its mirror is marked once, a moving observer every frame it moves.

mod in_frame;
mod pass;
pub mod tiles;

use std::sync::Arc;
use std::time::Instant;

use pass::MarkPass;
pub use tiles::Tiles;

use super::gpu::{FrameData, ViewData};
use super::refresh::Dirty;
use crate::scene::pixel_rect::PixelRect;
use crate::vk::commands::Submitter;
use crate::vk::device::Device;
use crate::vk::GpuError;

/// Above this many rectangles a face's update re-renders its changed tiles whole instead of
/// its dirty rectangles cut by the footprint's (the pieces of 32 dirty rectangles by a few
/// dozen of the footprint's grow as their product), and above it again their bounding box:
/// each rectangle costs the host a cull of the face's drawables.
const MAX_PIECES: usize = 64;

/// Why SwiftShader gets no footprint: its sampler reads what no pixel's own samples reach.
const SWIFTSHADER: &str = "the footprint on SwiftShader: its cube sampler takes one level \
    of detail for each 2 x 2 quad of pixels, from the quad's first pixel's gradients \
    (SamplerCore::computeLodCube), which along the mirror's rim may be a pixel off the mirror; \
    what a view reads there cannot be marked from its own pixels (docs/methods.md, \
    \"The footprint\")";

/// Why `device` cannot fill a footprint (None: it can).
pub fn refusal(device: &crate::vk::device::DeviceInfo) -> Option<&'static str> {
    (device.short_name == "swiftshader").then_some(SWIFTSHADER)
}

/// The footprint of a renderer's views and what its cube holds, by tile.
pub struct Footprint {
    pass: MarkPass,
    /// What `marked` was marked from (`None`: nothing yet).
    key: Option<Vec<u8>>,
    /// The tiles the marks said, kept while a frame needs every tile (its read-back, say), so
    /// that the next is not marked again.
    marked: Tiles,
    /// The tiles the drawn views may read.
    needed: Tiles,
    /// The tiles that show the state the cube shows.
    valid: Tiles,
    /// Clear the cube to a poison before its first fill (`RenderOptions::footprint_poison`).
    pub poison: bool,
}

impl Footprint {
    pub fn create(
        device: &Arc<Device>,
        (face_size, view_count): (u32, usize),
        poison: bool,
    ) -> Result<Self, GpuError> {
        if let Some(why) = refusal(&device.info) {
            return Err(GpuError::Unsupported(why.into()));
        }
        Ok(Self {
            pass: MarkPass::create(device, face_size, view_count)?,
            key: None,
            marked: Tiles::all(face_size),
            needed: Tiles::all(face_size),
            valid: Tiles::none(face_size),
            poison,
        })
    }

    /// Texels of level 0 the views may read.
    pub fn texels(&self) -> u64 {
        self.needed.texels()
    }

    /// The tiles the views `marked` read of a cube of `levels` levels in the frame of `frame`
    /// and `views`, marked again when any of these changed; the host time it took when marked
    /// (ms).
    pub fn mark(
        &mut self,
        submitter: &Submitter,
        (frame, views): (&FrameData, &[ViewData]),
        marked: &[u32],
        levels: u32,
    ) -> Result<Option<f64>, GpuError> {
        let mut key = bytemuck::bytes_of(frame).to_vec();
        key.extend(levels.to_le_bytes());
        for &v in marked {
            key.extend(v.to_le_bytes());
            key.extend(bytemuck::bytes_of(&views[v as usize]));
        }
        if self.key.as_ref() == Some(&key) {
            self.needed = self.marked.clone();
            return Ok(None);
        }
        let start = Instant::now();
        self.marked = self.pass.mark(submitter, (frame, views), marked, levels)?;
        self.needed = self.marked.clone();
        self.key = Some(key);
        Ok(Some(start.elapsed().as_secs_f64() * 1e3))
    }

    /// Every tile is needed this frame: something other than the marked views reads the cube
    /// (its read-back, the ray map through it, a lookup the pass cannot mark), or a policy
    /// that updates every n frames could not fill a tile newly needed between its updates.
    pub fn need_all(&mut self, face_size: u32) {
        self.needed = Tiles::all(face_size);
    }

    /// What an update that `dirty` asks for re-renders within the footprint, and what the
    /// cube then holds. `first_fill`: the cube holds nothing yet. A first fill that would fill
    /// nothing (no view sees the mirror) fills every tile: the cube's images must leave the
    /// layout they were made in before a view binds them.
    pub fn restrict(&mut self, dirty: Dirty, first_fill: bool, size: u32) -> Dirty {
        if first_fill {
            self.valid = Tiles::none(size);
        }
        let (mut fill, mut valid) = fill_within(&self.needed, &self.valid, &dirty, size);
        if first_fill && fill.mask == 0 {
            (fill, valid) = (Dirty::faces(0x3F), Tiles::all(size));
        }
        self.valid = valid;
        fill
    }
}

/// The tiles `dirty` changes: its faces whole, or the tiles under its rectangles.
fn changed_tiles(dirty: &Dirty, size: u32) -> Tiles {
    let mut changed = Tiles::none(size);
    for f in (0..6).filter(|f| dirty.mask & (1 << f) != 0) {
        match &dirty.rects[f][..] {
            [] => changed.set_under(f, &PixelRect::whole(size)),
            rects => rects.iter().for_each(|r| changed.set_under(f, r)),
        }
    }
    changed
}

/// The pixels both rectangles hold, if any.
fn intersection(a: &PixelRect, b: &PixelRect) -> Option<PixelRect> {
    let r = PixelRect {
        x0: a.x0.max(b.x0),
        y0: a.y0.max(b.y0),
        x1: a.x1.min(b.x1),
        y1: a.y1.min(b.y1),
    };
    (r.x0 < r.x1 && r.y0 < r.y1).then_some(r)
}

/// What to re-render of faces of `size` texels, given the tiles the views need, those valid
/// and what `dirty` changed, and the tiles valid afterwards. Re-rendered: each needed tile
/// not valid, whole, and in each needed valid tile the pixels of `dirty` (whole faces or
/// rectangles), as disjoint rectangles. Valid afterwards: every needed tile, and each valid
/// one `dirty` does not reach. Exact as dirty rectangles are: a rectangle re-renders
/// everything that meets it, the rest of a valid tile keeps what it holds.
pub fn fill_within(needed: &Tiles, valid: &Tiles, dirty: &Dirty, size: u32) -> (Dirty, Tiles) {
    let changed = changed_tiles(dirty, size);
    let stale = needed.without(valid);
    let kept = needed.intersection(valid);
    let mut fill = Dirty::default();
    for f in 0..6 {
        let mut rects = stale.rects(f);
        if dirty.mask & (1 << f) != 0 {
            let pieces: Vec<PixelRect> = match &dirty.rects[f][..] {
                [] => kept.rects(f),
                dirty_rects => (dirty_rects.iter())
                    .flat_map(|d| {
                        kept.rects(f)
                            .into_iter()
                            .filter_map(|k| intersection(d, &k))
                    })
                    .collect(),
            };
            if pieces.len() > MAX_PIECES {
                rects = stale.union(&kept.intersection(&changed)).rects(f);
            } else {
                rects.extend(pieces);
            }
        }
        if rects.is_empty() {
            continue;
        }
        if rects.len() > MAX_PIECES {
            // Their bounding box: more is re-rendered, all of it exactly.
            rects = vec![rects.iter().fold(rects[0], |a, b| a.union(b))];
        }
        fill.mask |= 1 << f;
        let area: u64 = rects.iter().map(PixelRect::area).sum();
        if area < PixelRect::whole(size).area() {
            fill.rects[f] = rects;
        }
    }
    (fill, needed.union(&valid.without(&changed)))
}

#[cfg(test)]
mod tests;
