//! The frame's resources as declared uses: a pass says how it uses each image's subresources
//! and each buffer, and the barriers between passes are derived here, never written by hand.
//!
//! Every resource a frame touches outlives the frame, so each is imported with its *resting*
//! use: how the last frame left it, which is also how this frame must leave it (the next one
//! imports it the same way); an image nothing has used yet is imported *fresh* (its contents
//! undefined). [`FrameGraph::uses`] gives the barriers that make a pass's uses safe after
//! everything declared before them; [`FrameGraph::finish`] the ones that put every resource
//! back at rest. A barrier is derived from the state the graph tracks per subresource (each mip
//! level of each layer): its layout, and every access since its last barrier (reads
//! accumulate; a write, or a new layout, needs a barrier after all of them). Subresources that
//! need the same barrier are given one, over their range (`ranges.rs`).
//!
//! Every pass of a frame is declared this way: the uploads, the lookups' own passes (the
//! top-level acceleration structure's build, the traced rays' tally, through
//! [`PassRecorder`]), the cube fill and its mip chain, the views, the readback and the copy of
//! the queries' results (docs/renderer.md, "One frame's flow"). Only one-off work outside the
//! frames (uploads at creation, bottom-level builds, the material check's results) places
//! its own.

mod ranges;

use ash::vk;

use super::draw::{barrier, Sync, COLOR_OUT, COPY_READ, COPY_WRITE, DEPTH_RW, NOTHING, SAMPLED};
use crate::vk::commands::{image_barriers, memory_barrier, ImageBarrier};
use crate::vk::device::Device;
pub use ranges::Subresources;

/// How a pass uses a resource: a layout (for an image) and the stages and accesses of the use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Use {
    /// Drawn into as a colour attachment, cleared first: earlier contents are not kept.
    ColorTarget,
    /// Drawn into as a colour attachment, the texels it does not draw kept (a cube's clean
    /// faces).
    ColorKept,
    /// Tested and written as a depth attachment, cleared first.
    DepthTarget,
    /// Tested and written as a depth attachment, the rest kept.
    DepthKept,
    /// Sampled or fetched by fragment shaders.
    FragmentRead,
    /// Cleared whole by a transfer command (`vkCmdClearColorImage`: the footprint's poison).
    Cleared,
    /// Blitted from.
    BlitSource,
    /// Blitted into, whole: earlier contents are not kept.
    BlitDestination,
    /// Copied from.
    CopySource,
    /// Copied into (a buffer).
    CopyDestination,
    /// Read by the host after the frame's fence (a buffer).
    HostRead,
    /// Filled by a transfer command (`vkCmdFillBuffer`: a counter zeroed).
    Filled,
    /// Read by any later command, whatever its stage: what the frame's uploads fill
    /// (uniforms, storage, indirect commands, acceleration-structure instances).
    ReadAnywhere,
    /// Read and written by fragment shaders' storage accesses (atomic counters).
    FragmentStorage,
    /// Built into: an acceleration structure, or its build's scratch memory.
    AccelerationBuild,
    /// Traced through by fragment shaders' ray queries.
    AccelerationTraced,
    /// Written by compute shaders' storage accesses (a pretraced lookup's records).
    ComputeWrite,
    /// Read by fragment shaders' storage accesses (the records the compute pass wrote).
    FragmentStorageRead,
    /// Read texel by texel by compute shaders through a sampled view (a mip level above the
    /// one being made).
    ComputeSampled,
    /// Stored into by compute shaders, whole: earlier contents are not kept (a mip level of a
    /// face rebuilt whole).
    ComputeStored,
    /// Stored into by compute shaders in part, the rest kept (a face's mips above its dirty
    /// rectangles).
    ComputeStoredKept,
}

const BLIT_READ: Sync = (
    vk::PipelineStageFlags2::BLIT,
    vk::AccessFlags2::TRANSFER_READ,
);
const BLIT_WRITE: Sync = (
    vk::PipelineStageFlags2::BLIT,
    vk::AccessFlags2::TRANSFER_WRITE,
);
const FILL_WRITE: Sync = (
    vk::PipelineStageFlags2::ALL_TRANSFER,
    vk::AccessFlags2::TRANSFER_WRITE,
);
const CLEAR_WRITE: Sync = (
    vk::PipelineStageFlags2::CLEAR,
    vk::AccessFlags2::TRANSFER_WRITE,
);
const ANY_READ: Sync = (
    vk::PipelineStageFlags2::ALL_COMMANDS,
    vk::AccessFlags2::MEMORY_READ,
);
const STORAGE_RW: Sync = (
    vk::PipelineStageFlags2::FRAGMENT_SHADER,
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::SHADER_STORAGE_READ.as_raw()
            | vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw(),
    ),
);
const BUILD_RW: Sync = (
    vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR.as_raw()
            | vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR.as_raw(),
    ),
);
const TRACED: Sync = (
    vk::PipelineStageFlags2::FRAGMENT_SHADER,
    vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR,
);
const COMPUTE_WRITE: Sync = (
    vk::PipelineStageFlags2::COMPUTE_SHADER,
    vk::AccessFlags2::SHADER_STORAGE_WRITE,
);
const COMPUTE_SAMPLED: Sync = (
    vk::PipelineStageFlags2::COMPUTE_SHADER,
    vk::AccessFlags2::SHADER_SAMPLED_READ,
);
const STORAGE_READ: Sync = (
    vk::PipelineStageFlags2::FRAGMENT_SHADER,
    vk::AccessFlags2::SHADER_STORAGE_READ,
);

impl Use {
    /// The image layout of the use (buffers have none: `UNDEFINED`).
    fn layout(self) -> vk::ImageLayout {
        match self {
            Use::ColorTarget | Use::ColorKept => vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            Use::DepthTarget | Use::DepthKept => vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
            Use::FragmentRead => vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            Use::BlitSource | Use::CopySource => vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            Use::BlitDestination | Use::Cleared => vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            Use::ComputeSampled => vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            Use::ComputeStored | Use::ComputeStoredKept => vk::ImageLayout::GENERAL,
            Use::CopyDestination
            | Use::HostRead
            | Use::Filled
            | Use::ReadAnywhere
            | Use::FragmentStorage
            | Use::AccelerationBuild
            | Use::AccelerationTraced
            | Use::ComputeWrite
            | Use::FragmentStorageRead => vk::ImageLayout::UNDEFINED,
        }
    }

    fn sync(self) -> Sync {
        match self {
            Use::ColorTarget | Use::ColorKept => COLOR_OUT,
            Use::DepthTarget | Use::DepthKept => DEPTH_RW,
            Use::FragmentRead => SAMPLED,
            Use::BlitSource => BLIT_READ,
            Use::BlitDestination => BLIT_WRITE,
            Use::CopySource => COPY_READ,
            Use::CopyDestination => COPY_WRITE,
            Use::HostRead => (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
            Use::Filled => FILL_WRITE,
            Use::Cleared => CLEAR_WRITE,
            Use::ReadAnywhere => ANY_READ,
            Use::FragmentStorage => STORAGE_RW,
            Use::AccelerationBuild => BUILD_RW,
            Use::AccelerationTraced => TRACED,
            Use::ComputeWrite | Use::ComputeStored | Use::ComputeStoredKept => COMPUTE_WRITE,
            Use::FragmentStorageRead => STORAGE_READ,
            Use::ComputeSampled => COMPUTE_SAMPLED,
        }
    }

    fn writes(self) -> bool {
        matches!(
            self,
            Use::ColorTarget
                | Use::ColorKept
                | Use::DepthTarget
                | Use::DepthKept
                | Use::BlitDestination
                | Use::Cleared
                | Use::CopyDestination
                | Use::Filled
                | Use::FragmentStorage
                | Use::AccelerationBuild
                | Use::ComputeWrite
                | Use::ComputeStored
                | Use::ComputeStoredKept
        )
    }

    /// Whether the use overwrites every texel before reading any: the contents before it
    /// need not be kept (the barrier's old layout is `UNDEFINED`).
    fn discards(self) -> bool {
        matches!(
            self,
            Use::ColorTarget
                | Use::DepthTarget
                | Use::BlitDestination
                | Use::Cleared
                | Use::ComputeStored
        )
    }
}

/// A resource a frame uses: subresources of an image, or a buffer (whole).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Resource {
    Image(vk::Image, Subresources),
    Buffer(vk::Buffer),
}

impl Resource {
    /// The subresources `range` of `image`.
    pub fn image(image: vk::Image, range: vk::ImageSubresourceRange) -> Self {
        Resource::Image(image, Subresources::of(range))
    }

    /// Every subresource of `image`.
    pub fn whole(image: &crate::vk::image::Image) -> Self {
        Self::image(image.raw, image.full_range())
    }
}

/// A derived barrier: an image's, with its layout transition (from, to: layout, stages and
/// accesses), or a memory barrier for a buffer (from, to: stages and accesses).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Barrier {
    Image {
        image: vk::Image,
        range: Subresources,
        from: (vk::ImageLayout, Sync),
        to: (vk::ImageLayout, Sync),
    },
    Memory(Sync, Sync),
}

/// One subresource's (or a buffer's) state: its layout, every access since its last barrier,
/// whether one of them wrote, and what that barrier made visible (its destination: a layout
/// transition is a write, seen only by the stages and accesses it was made for).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct State {
    layout: vk::ImageLayout,
    since: Sync,
    written: bool,
    visible: Sync,
    /// Still as imported: its last use came before this frame's submission (an earlier
    /// frame's, or the host's own, which the submission orders).
    imported: bool,
}

impl State {
    fn resting(rest: Use) -> Self {
        Self {
            layout: rest.layout(),
            since: rest.sync(),
            written: rest.writes(),
            visible: rest.sync(),
            imported: false,
        }
    }

    /// At rest, as a frame finds it.
    fn imported(rest: Use) -> Self {
        Self {
            imported: true,
            ..Self::resting(rest)
        }
    }

    /// Nothing this renderer drew is in it: its contents are undefined (before the cube's
    /// first fill). Its first barrier still waits for the resting use's stages, in case an
    /// earlier frame used it that way (a cube whose contents were given up, after a floor).
    fn fresh(rest: Use) -> Self {
        Self {
            layout: vk::ImageLayout::UNDEFINED,
            since: rest.sync(),
            written: false,
            visible: NOTHING,
            imported: true,
        }
    }

    /// Still as imported fresh: not used this frame.
    fn is_fresh(&self) -> bool {
        self.layout == vk::ImageLayout::UNDEFINED && self.visible == NOTHING
    }
}

/// Whether every stage and access of `of` is in `within`.
fn covered(of: Sync, within: Sync) -> bool {
    within.0.contains(of.0) && within.1.contains(of.1)
}

/// A tracked resource: what it is (for an image, all of it), how it rests, and a state per
/// subresource (mip-major: level m of layer l at `m * layers + l`; one for a buffer).
struct Tracked {
    resource: Resource,
    rest: Use,
    states: Vec<State>,
}

/// The resources of one frame's declared passes and their states.
#[derive(Default)]
pub struct FrameGraph {
    tracked: Vec<Tracked>,
}

impl FrameGraph {
    /// Tracks all of `resource`, which rests as `rest` leaves it between frames; `fresh`
    /// when nothing has used it yet.
    pub(crate) fn import(&mut self, resource: Resource, rest: Use, fresh: bool) {
        debug_assert!(
            (self.tracked.iter()).all(|t| t.resource.handle() != resource.handle()),
            "{resource:?} imported twice"
        );
        let count = match resource {
            Resource::Image(_, all) => all.count(),
            Resource::Buffer(_) => 1,
        };
        let state = if fresh {
            State::fresh(rest)
        } else {
            State::imported(rest)
        };
        self.tracked.push(Tracked {
            resource,
            rest,
            states: vec![state; count],
        });
    }

    /// The barriers that make `uses` safe after every use declared before them; the
    /// subresources named are then in these uses' states. A resource never imported, or a
    /// range outside the imported image, is a bug in the pass that names it.
    pub(crate) fn uses(&mut self, uses: &[(Resource, Use)]) -> Vec<Barrier> {
        let mut barriers = Vec::new();
        for &(resource, to) in uses {
            let at = (self.tracked.iter()).position(|t| t.resource.handle() == resource.handle());
            let t = &mut self.tracked[at.expect("a declared resource is imported")];
            barriers.extend(t.transition(resource, to));
        }
        barriers
    }

    /// Records into `cmd` the barriers that make `uses` safe for the commands that follow
    /// ([`Self::uses`]).
    pub(crate) fn declare(
        &mut self,
        device: &Device,
        cmd: vk::CommandBuffer,
        uses: &[(Resource, Use)],
    ) {
        record(device, cmd, &self.uses(uses));
    }

    /// Records into `cmd` the barriers that put every resource back at rest ([`Self::finish`]).
    pub(crate) fn rest(&mut self, device: &Device, cmd: vk::CommandBuffer) {
        record(device, cmd, &self.finish());
    }

    /// The barriers that put every resource back at rest, for the next frame: none for a
    /// subresource whose layout and accesses since its last barrier are its resting use's
    /// already (the next frame's first barrier waits for exactly those), nor for one imported
    /// fresh and not used.
    pub(crate) fn finish(&mut self) -> Vec<Barrier> {
        let mut barriers = Vec::new();
        for t in &mut self.tracked {
            let rest = State::resting(t.rest);
            // A subresource still fresh was not used: the next frame imports it fresh too.
            let moved: Vec<usize> = (0..t.states.len())
                .filter(|&i| !t.states[i].is_fresh())
                .filter(|&i| (t.states[i].layout, t.states[i].since) != (rest.layout, rest.since))
                .collect();
            barriers.extend(t.transition_each(&moved, t.rest));
            t.states.fill(rest);
        }
        barriers
    }
}

impl Resource {
    /// The Vulkan handle, which identifies what is tracked (a range is a part of it).
    fn handle(&self) -> u64 {
        use vk::Handle;
        match self {
            Resource::Image(image, _) => image.as_raw(),
            Resource::Buffer(buffer) => buffer.as_raw(),
        }
    }
}

impl Tracked {
    /// The barriers before `to` on the part of this resource `used` names.
    fn transition(&mut self, used: Resource, to: Use) -> Vec<Barrier> {
        let indices = match (self.resource, used) {
            (Resource::Image(_, all), Resource::Image(_, part)) => all.indices(part),
            _ => vec![0],
        };
        self.transition_each(&indices, to)
    }

    /// The barriers before `to` on the subresources `indices`, merged over ranges where
    /// they are the same.
    fn transition_each(&mut self, indices: &[usize], to: Use) -> Vec<Barrier> {
        let mut needed: Vec<(usize, (vk::ImageLayout, Sync))> = Vec::new();
        for &i in indices {
            let is_buffer = matches!(self.resource, Resource::Buffer(_));
            if let Some(from) = step(&mut self.states[i], to, is_buffer) {
                needed.push((i, from));
            }
        }
        let target = (to.layout(), to.sync());
        match self.resource {
            Resource::Buffer(_) => (needed.into_iter())
                .map(|(_, (_, from))| Barrier::Memory(from, to.sync()))
                .collect(),
            Resource::Image(image, all) => (all.merge(needed).into_iter())
                .map(|(range, from)| Barrier::Image {
                    image,
                    range,
                    from,
                    to: target,
                })
                .collect(),
        }
    }
}

/// One subresource's step to `to`: the barrier's source side (old layout, stages and
/// accesses) if it needs one, and its state after. Reads in the layout they need after no
/// write need none, if the last barrier made the subresource visible to them (a read at
/// another stage than the layout transition was made for needs one: a blit source then a copy
/// source); a buffer the host used last before the frame was submitted needs none either (the
/// submission orders everything the host did before it; a host read declared within the
/// frame is the host's use after the fence, and what follows it in the frame waits for the
/// device's accesses before it like any other); anything else waits for every access since
/// the last barrier.
fn step(state: &mut State, to: Use, is_buffer: bool) -> Option<(vk::ImageLayout, Sync)> {
    let same_layout = state.layout == to.layout();
    let seen = covered(to.sync(), state.visible);
    if same_layout && !state.written && !to.writes() && seen {
        state.since = (state.since.0 | to.sync().0, state.since.1 | to.sync().1);
        return None;
    }
    let by_host = state.imported && state.since.0 == vk::PipelineStageFlags2::HOST;
    let from = state.since;
    let old = match to.discards() {
        true => vk::ImageLayout::UNDEFINED,
        false => state.layout,
    };
    *state = State::resting(to);
    (!(by_host && is_buffer)).then_some((old, from))
}

/// Records `barriers` (the images' in one call; a memory barrier that another before it
/// already is, once: buffers are made visible by global memory barriers, so two buffers left
/// by the same use need one).
fn record(device: &Device, cmd: vk::CommandBuffer, barriers: &[Barrier]) {
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
    for (i, b) in barriers.iter().enumerate() {
        if let Barrier::Memory(from, to) = *b {
            if !barriers[..i].contains(b) {
                memory_barrier(device, cmd, from, to);
            }
        }
    }
}

/// What a pass outside the renderer's own parts (a lookup's) records through: the frame's
/// command buffer, and the frame graph its uses are declared to before each command that
/// needs them (the graph records the barriers).
pub struct PassRecorder<'a> {
    device: &'a Device,
    cmd: vk::CommandBuffer,
    graph: &'a mut FrameGraph,
}

impl<'a> PassRecorder<'a> {
    pub(super) fn new(
        device: &'a Device,
        cmd: vk::CommandBuffer,
        graph: &'a mut FrameGraph,
    ) -> Self {
        Self { device, cmd, graph }
    }

    pub fn cmd(&self) -> vk::CommandBuffer {
        self.cmd
    }

    /// The commands that follow use `uses`: the barriers they need after everything declared
    /// before are recorded now.
    pub fn declare(&mut self, uses: &[(Resource, Use)]) {
        self.graph.declare(self.device, self.cmd, uses);
    }
}

#[cfg(test)]
mod tests;
