//! Frames in flight, one part of the renderer: what each frame owns while the GPU runs it,
//! and the frame's life from submission to its results.
//!
//! With N frames in flight the CPU records frame k+1 (up to k+N-1) while the GPU still runs
//! frame k. Everything the host writes or reads for a frame is per slot: the command buffer
//! and its fence, the uploads' staging buffer (`vk::uploads`: views, objects, indirect
//! commands, meshlet draws and acceleration-structure instances reach the device buffers
//! through it), the query pools and the readback buffer. What only the GPU touches (the
//! cube, the view targets, the acceleration structures, the device buffers) is shared: the
//! frames run on one queue, and each barrier names the last use of the frame before, so the
//! frames' work is ordered as if it ran one after the other (validated with 2 and 3 frames in
//! flight: `tests/engine/in_flight.rs`).
//!
//! A slot is reused after its fence: its frame is then finished (timestamps, statistics,
//! tally and pixels read) and its results wait in `done` for [`Renderer::finish_frame`].

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Instant;

use super::queries::{FrameQueries, StatsRead};
use super::readback::Copies;
use super::retired::Retired;
use super::{FrameImages, FrameReport, Readback, Renderer};
use crate::vk::commands::Submitter;
use crate::vk::device::Device;
use crate::vk::fault::Hold;
use crate::vk::memory::Buffer;
use crate::vk::uploads::FrameUploads;
use crate::vk::GpuError;

/// At most this many frames in flight (`RenderOptions::frames_in_flight`): more only adds
/// latency and memory, since a frame's GPU work is serial on the one queue.
pub const MAX_FRAMES_IN_FLIGHT: usize = 3;

/// What one frame in flight owns.
pub(super) struct FrameSlot {
    pub submitter: Submitter,
    pub uploads: FrameUploads,
    pub queries: FrameQueries,
    /// Grown when a frame reads back more (safe: the slot's previous frame has finished), and
    /// swapped for `spare` while a window still holds a view in it (`DisplayPixels`).
    pub readback: Option<Arc<Buffer>>,
    /// The buffer a window held when the slot came round, kept for the next time it does
    /// (so a window that holds each view a little longer costs no buffer a frame).
    pub spare: Option<Arc<Buffer>>,
    /// The submitted frame, until it is finished.
    pending: Option<Pending>,
}

/// What finishing a submitted frame needs, kept from its recording.
pub(super) struct Pending {
    pub report: FrameReport,
    /// Where its images sit in the slot's readback buffer.
    pub copies: Copies,
    /// The statistics queries the frame reads (copied at its end).
    pub stats: StatsRead,
    /// Whether its timestamps and statistics are per face (a per-face method's update; not
    /// a floor's, whose fill is one query).
    pub per_face: bool,
    /// Whether the lookup's own passes ran (not in a floor's frame): its tally is this
    /// frame's.
    pub traced: bool,
    pub submitted: Instant,
    /// Its number in submission order (set when submitted).
    pub number: u64,
}

/// The slots, the one being recorded, and the frames submitted and finished.
pub(super) struct InFlight {
    slots: Vec<FrameSlot>,
    current: usize,
    /// Slots holding a submitted, unfinished frame, oldest first.
    order: VecDeque<usize>,
    /// Frames finished (to free their slot, or by `drain`) and not yet taken, oldest first.
    done: VecDeque<(FrameReport, FrameImages)>,
    /// Frames submitted so far.
    submitted: u64,
    /// A frame held on the GPU for a test (`fault::HOLD_FRAME_VAR`). Declared after the
    /// slots: dropped once their frames finished.
    hold: Option<Hold>,
    /// What the renderer let go of while frames in flight may still use it (the ray map's
    /// passes of a lookup switched away from). Declared after the slots, whose drop waits
    /// for their frames.
    retired: Retired<Box<dyn std::any::Any + Send>>,
}

impl Drop for InFlight {
    fn drop(&mut self) {
        // Let a held frame go before the slots wait for their frames.
        if let Some(hold) = &mut self.hold {
            hold.release();
        }
    }
}

impl InFlight {
    pub fn create(device: &std::sync::Arc<Device>, count: usize) -> Result<Self, GpuError> {
        let slots = (0..count)
            .map(|i| {
                Ok(FrameSlot {
                    submitter: Submitter::create(device, &format!("frame {i}"))?,
                    uploads: FrameUploads::new(device, &format!("frame {i} uploads")),
                    queries: FrameQueries::create(device)?,
                    readback: None,
                    spare: None,
                    pending: None,
                })
            })
            .collect::<Result<Vec<_>, GpuError>>()?;
        Ok(Self {
            slots,
            current: 0,
            order: VecDeque::new(),
            done: VecDeque::new(),
            submitted: 0,
            hold: Hold::asked(device)?,
            retired: Retired::default(),
        })
    }

    /// The slot being recorded (or about to be).
    pub fn current(&self) -> &FrameSlot {
        &self.slots[self.current]
    }

    pub fn current_mut(&mut self) -> &mut FrameSlot {
        &mut self.slots[self.current]
    }

    /// The current slot's index, for the parts that keep per-slot state of their own.
    pub fn current_index(&self) -> usize {
        self.current
    }

    /// The number of the last frame submitted, if it may still be running (`None`: every
    /// submitted frame has been waited for).
    pub fn last_in_flight(&self) -> Option<u64> {
        (!self.order.is_empty()).then_some(self.submitted)
    }

    /// Keeps `object` until every frame submitted so far has finished (dropped now when none
    /// is in flight).
    pub fn retire(&mut self, object: Box<dyn std::any::Any + Send>) {
        let last = self.last_in_flight();
        self.retired.keep(last, object);
    }

    /// The newest finished frame's results (the one `render_frame` just waited for).
    pub fn take_newest(&mut self) -> Option<(FrameReport, FrameImages)> {
        self.done.pop_back()
    }
}

impl Renderer {
    /// Records, submits and does not wait: the frame's results come from
    /// [`Renderer::finish_frame`]. When all `frames_in_flight` slots are busy, this first
    /// waits for the oldest frame and finishes it (its results are kept for `finish_frame`).
    pub fn submit_frame(
        &mut self,
        frame: u64,
        t_s: f64,
        readback: Readback,
    ) -> Result<(), GpuError> {
        self.submit(super::FrameAsk::new(frame, t_s, readback))
    }

    /// The oldest submitted frame's report and pixels, waiting for it if it is still running;
    /// `None` when no frame is pending.
    pub fn finish_frame(&mut self) -> Result<Option<(FrameReport, FrameImages)>, GpuError> {
        if self.frames.done.is_empty() {
            if let Some(&oldest) = self.frames.order.front() {
                self.finish_slot(oldest)?;
            }
        }
        Ok(self.frames.done.pop_front())
    }

    /// The results of the frames that have finished by now, without waiting, oldest first.
    pub fn finished_frames(&mut self) -> Result<Vec<(FrameReport, FrameImages)>, GpuError> {
        while let Some(&oldest) = self.frames.order.front() {
            if !self.frames.slots[oldest].submitter.is_finished()? {
                break;
            }
            self.finish_slot(oldest)?;
        }
        Ok(self.frames.done.drain(..).collect())
    }

    /// Whether a frame can be submitted now without waiting: the slot it would use has no
    /// frame still running (a loop that must not wait for the GPU asks this first), and,
    /// when the scene's lookup was switched since the last frame, no frame at all. The old
    /// pass needs no wait (it is retired), but the new one uploads its buffers through the
    /// one queue, and on a driver that runs the queue in order that upload would wait
    /// behind the frames in flight inside the loop.
    pub fn ready_for_frame(&self) -> Result<bool, GpuError> {
        if self.mirror.lookup() != self.scene.mirror.lookup {
            return self.frames_finished();
        }
        let slot = &self.frames.slots[self.frames.current];
        Ok(slot.pending.is_none() || slot.submitter.is_finished()?)
    }

    /// Whether every submitted frame has finished (no wait): the GPU holds nothing of this
    /// renderer's, so work queued now starts at once.
    pub fn frames_finished(&self) -> Result<bool, GpuError> {
        for &s in &self.frames.order {
            if !self.frames.slots[s].submitter.is_finished()? {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Whether a submitted frame's results have yet to be taken ([`Self::finished_frames`]):
    /// it is running, or it finished and nobody collected it. A loop deciding whether it may
    /// sleep until the next event asks this, not [`Self::frames_finished`]: a frame that
    /// finished after the loop last collected is "finished" and still uncollected, and a
    /// loop that slept then would keep its view until some event woke it.
    pub fn frames_uncollected(&self) -> bool {
        !self.frames.order.is_empty() || !self.frames.done.is_empty()
    }

    /// Makes the current slot free to record: its previous frame finished (waited for), and
    /// nothing left queued in its uploads by a recording that failed before its copies (they
    /// could name a buffer retired since, and would run twice).
    pub(super) fn acquire_slot(&mut self) -> Result<(), GpuError> {
        let current = self.frames.current;
        if self.frames.slots[current].pending.is_some() {
            // Slots are used in turn, so every older frame is finished first.
            while let Some(&oldest) = self.frames.order.front() {
                self.finish_slot(oldest)?;
                if oldest == current {
                    break;
                }
            }
        }
        self.frames.slots[current].uploads.clear();
        Ok(())
    }

    /// Waits for every submitted frame and finishes it (a frame rendered and read back at
    /// once: `render_frame`).
    pub(super) fn drain(&mut self) -> Result<(), GpuError> {
        while let Some(&oldest) = self.frames.order.front() {
            self.finish_slot(oldest)?;
        }
        Ok(())
    }

    /// Submits the current slot's recorded frame and moves to the next slot.
    pub(super) fn submit_slot(&mut self, pending: Pending) -> Result<(), GpuError> {
        let current = self.frames.current;
        self.frames.submitted += 1;
        let frame = self.frames.submitted;
        let held = (self.frames.hold.as_ref()).and_then(|h| h.wait_for(frame));
        let slot = &mut self.frames.slots[current];
        slot.submitter.submit_waiting(held.as_slice())?;
        slot.pending = Some(Pending {
            number: frame,
            ..pending
        });
        self.frames.order.push_back(current);
        self.frames.current = (current + 1) % self.frames.slots.len();
        Ok(())
    }

    /// Submits the current slot's recorded work (a check's, not a frame) and waits for it,
    /// outside the frames' queue.
    pub(super) fn submit_slot_and_wait(&mut self) -> Result<(), GpuError> {
        let current = self.frames.current;
        self.frames.slots[current].submitter.submit_and_wait()?;
        self.frames.current = (current + 1) % self.frames.slots.len();
        Ok(())
    }

    /// Waits for slot `s`'s frame and turns it into results in `done`.
    fn finish_slot(&mut self, s: usize) -> Result<(), GpuError> {
        debug_assert_eq!(
            self.frames.order.front(),
            Some(&s),
            "frames finish in order"
        );
        self.frames.order.pop_front();
        let slot = &mut self.frames.slots[s];
        // A frame may run for seconds (an 8192² sensor on a CPU driver): a command's hook may
        // end the process at a signal meanwhile (`process::interrupt`).
        slot.submitter.wait_watched()?;
        let Some(mut pending) = slot.pending.take() else {
            return Ok(());
        };
        pending.report.submit_wait_ms = pending.submitted.elapsed().as_secs_f64() * 1e3;
        let slot = &self.frames.slots[s];
        let mut report = pending.report;
        (slot.queries).read(&mut report, pending.stats, pending.per_face)?;
        if pending.traced {
            report.traced_rays = (self.mirror.pass_recorded_for(pending.number)).tally(s)?;
        }
        // Nothing after this frame uses what was let go before it: the ray map's pass first,
        // then the lookup pass whose set and layout it was made with.
        self.frames.retired.release_through(pending.number);
        self.mirror.release_through(pending.number);
        let images = pending.copies.decode(slot.readback.as_ref())?;
        self.frames.done.push_back((report, images));
        Ok(())
    }
}
