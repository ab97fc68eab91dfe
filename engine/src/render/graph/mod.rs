//! The frame's resources as declared uses: a pass says how it uses each image (and the
//! readback buffer), and the barriers between passes are derived here, never written by hand.
//!
//! Every resource a frame touches outlives the frame, so each is imported with its *resting*
//! use: how the last frame left it, which is also how this frame must leave it (the next one
//! imports it the same way). [`FrameGraph::uses`] gives the barriers that make a pass's uses
//! safe after everything declared before them; [`FrameGraph::finish`] the ones that put every
//! resource back at rest. A barrier is derived from the state the graph tracks per resource:
//! its layout, and every access since the last barrier (reads accumulate; a write, or a new
//! layout, needs a barrier after all of them).
//!
//! Which passes are declared this way: the view passes and the readback (`passes.rs`,
//! `readback.rs`). The lookup's pre-pass, the cube fill and the mips still place their own
//! (docs/renderer.md, "One frame's flow").

use ash::vk;

use super::draw::{barrier, Sync, COLOR_OUT, COPY_READ, COPY_WRITE, DEPTH_RW, SAMPLED};
use crate::vk::commands::{image_barriers, memory_barrier, ImageBarrier};
use crate::vk::device::Device;

/// How a pass uses a resource: a layout (for an image) and the stages and accesses of the use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Use {
    /// Drawn into as a colour attachment, cleared first: earlier contents are not kept.
    ColorTarget,
    /// Tested and written as a depth attachment, cleared first.
    DepthTarget,
    /// Sampled or fetched by fragment shaders.
    FragmentRead,
    /// Copied from.
    CopySource,
    /// Copied into (a buffer).
    CopyDestination,
    /// Read by the host after the frame's fence (a buffer).
    HostRead,
}

impl Use {
    /// The image layout of the use (buffers have none: `UNDEFINED`).
    fn layout(self) -> vk::ImageLayout {
        match self {
            Use::ColorTarget => vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            Use::DepthTarget => vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
            Use::FragmentRead => vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            Use::CopySource => vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            Use::CopyDestination | Use::HostRead => vk::ImageLayout::UNDEFINED,
        }
    }

    fn sync(self) -> Sync {
        match self {
            Use::ColorTarget => COLOR_OUT,
            Use::DepthTarget => DEPTH_RW,
            Use::FragmentRead => SAMPLED,
            Use::CopySource => COPY_READ,
            Use::CopyDestination => COPY_WRITE,
            Use::HostRead => (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
        }
    }

    fn writes(self) -> bool {
        matches!(
            self,
            Use::ColorTarget | Use::DepthTarget | Use::CopyDestination
        )
    }

    /// Whether the use overwrites every texel before reading any: the contents before it
    /// need not be kept (the barrier's old layout is `UNDEFINED`).
    fn discards(self) -> bool {
        matches!(self, Use::ColorTarget | Use::DepthTarget)
    }
}

/// A resource a frame uses: an image's subresources, or a buffer (whole).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Resource {
    Image(vk::Image, Subresources),
    Buffer(vk::Buffer),
}

impl Resource {
    /// The subresources `range` of `image`: a resource of its own, whatever else of the
    /// image is tracked (the graph does not split or merge ranges).
    pub fn image(image: vk::Image, range: vk::ImageSubresourceRange) -> Self {
        Resource::Image(
            image,
            Subresources {
                aspect: range.aspect_mask,
                mips: [range.base_mip_level, range.level_count],
                layers: [range.base_array_layer, range.layer_count],
            },
        )
    }
}

/// An image's subresource range as a value that compares (ash's range does not).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Subresources {
    aspect: vk::ImageAspectFlags,
    /// First level and count.
    mips: [u32; 2],
    /// First layer and count.
    layers: [u32; 2],
}

impl Subresources {
    fn range(self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: self.aspect,
            base_mip_level: self.mips[0],
            level_count: self.mips[1],
            base_array_layer: self.layers[0],
            layer_count: self.layers[1],
        }
    }
}

/// A derived barrier: an image's, with its layout transition (from, to: layout, stages and
/// accesses), or a memory barrier for a buffer (from, to: stages and accesses).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Barrier {
    Image {
        image: vk::Image,
        range: Subresources,
        from: (vk::ImageLayout, Sync),
        to: (vk::ImageLayout, Sync),
    },
    Memory(Sync, Sync),
}

/// One resource's state: its layout, every access since its last barrier, and whether one of
/// them wrote.
#[derive(Debug, Clone, Copy)]
struct State {
    layout: vk::ImageLayout,
    since: Sync,
    written: bool,
}

impl State {
    fn resting(rest: Use) -> Self {
        Self {
            layout: rest.layout(),
            since: rest.sync(),
            written: rest.writes(),
        }
    }
}

struct Tracked {
    resource: Resource,
    rest: Use,
    state: State,
}

/// The resources of one frame's declared passes and their states.
#[derive(Default)]
pub(super) struct FrameGraph {
    tracked: Vec<Tracked>,
}

impl FrameGraph {
    /// Tracks `resource`, which rests as `rest` leaves it between frames.
    pub fn import(&mut self, resource: Resource, rest: Use) {
        debug_assert!(
            self.tracked.iter().all(|t| t.resource != resource),
            "{resource:?} imported twice"
        );
        self.tracked.push(Tracked {
            resource,
            rest,
            state: State::resting(rest),
        });
    }

    /// The barriers that make `uses` safe after every use declared before them; the
    /// resources are then in these uses' states. A resource never imported is a bug in the
    /// pass that names it.
    pub fn uses(&mut self, uses: &[(Resource, Use)]) -> Vec<Barrier> {
        (uses.iter())
            .filter_map(|&(resource, to)| {
                let at = (self.tracked.iter()).position(|t| t.resource == resource);
                let tracked = &mut self.tracked[at.expect("a declared resource is imported")];
                transition(tracked, to)
            })
            .collect()
    }

    /// The barriers that put every resource back at rest, for the next frame: none for one
    /// whose layout and accesses since its last barrier are its resting use's already (the
    /// next frame's first barrier waits for exactly those).
    pub fn finish(&mut self) -> Vec<Barrier> {
        (self.tracked.iter_mut())
            .filter_map(|t| {
                let rest = t.rest;
                let at_rest = t.state.layout == rest.layout() && t.state.since == rest.sync();
                let back = (!at_rest).then(|| transition(t, rest)).flatten();
                t.state = State::resting(rest);
                back
            })
            .collect()
    }
}

/// Records `barriers` (the images' in one call).
pub(super) fn record(device: &Device, cmd: vk::CommandBuffer, barriers: &[Barrier]) {
    let images: Vec<ImageBarrier> = (barriers.iter())
        .filter_map(|b| match *b {
            Barrier::Image {
                image,
                range,
                from,
                to,
            } => Some(barrier(image, range.range(), from, to)),
            Barrier::Memory(..) => None,
        })
        .collect();
    if !images.is_empty() {
        image_barriers(device, cmd, &images);
    }
    for b in barriers {
        if let Barrier::Memory(from, to) = *b {
            memory_barrier(device, cmd, from, to);
        }
    }
}

/// The barrier (if any) before `to` on `t`, and `t`'s state after it. Reads in the layout
/// they need after no write need none; after the host's own use none either (the host used
/// it before the frame's submission, which orders everything the host did before it);
/// anything else waits for every access since the last barrier.
fn transition(t: &mut Tracked, to: Use) -> Option<Barrier> {
    let state = &mut t.state;
    let same_layout = state.layout == to.layout();
    if same_layout && !state.written && !to.writes() {
        state.since = (state.since.0 | to.sync().0, state.since.1 | to.sync().1);
        return None;
    }
    let by_host = state.since.0 == vk::PipelineStageFlags2::HOST;
    if by_host && matches!(t.resource, Resource::Buffer(_)) {
        *state = State::resting(to);
        return None;
    }
    let from = state.since;
    let old = match to.discards() {
        true => vk::ImageLayout::UNDEFINED,
        false => state.layout,
    };
    *state = State {
        layout: to.layout(),
        since: to.sync(),
        written: to.writes(),
    };
    Some(match t.resource {
        Resource::Image(image, range) => Barrier::Image {
            image,
            range,
            from: (old, from),
            to: (to.layout(), to.sync()),
        },
        Resource::Buffer(_) => Barrier::Memory(from, to.sync()),
    })
}

#[cfg(test)]
mod tests;
