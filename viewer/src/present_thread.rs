//! The window's presents, made on a thread of their own.
//!
//! On a CPU driver `vkQueuePresentKHR` returns only after every submission before it has run
//! (Mesa's software present copies the finished image to the window). Called from the event
//! loop, a present after a slow frame held every key, click, resize and quit for that frame.
//! Here the loop hands the present to this thread and goes back to its events; it draws again
//! (acquires, submits) only once the present has returned ([`PresentThread::returned`]), so
//! the queue and the swapchain are never used from both threads at once (the device's queue
//! lock makes that sound, this order makes it never wait).

use std::sync::mpsc::{channel, Receiver, Sender, TryRecvError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

use specchio::vk::swapchain::Swapchain;
use specchio::vk::GpuError;

/// One present: the swapchain (kept alive by the job until it returns) and the image.
struct Job {
    swapchain: Arc<Swapchain>,
    index: u32,
}

/// A present's outcome: `Ok(true)` when the swapchain must be recreated.
type Outcome = Result<bool, GpuError>;

/// The present thread and the one present it may be running.
pub struct PresentThread {
    jobs: Option<Sender<Job>>,
    /// Each present's outcome and when it returned.
    outcomes: Receiver<(Outcome, Instant)>,
    /// A present was handed over and its outcome not yet received.
    pending: bool,
    /// An outcome received by [`Self::returned`] and not yet taken.
    arrived: Option<Outcome>,
    /// When the last present was handed over, and when the last one returned.
    handed_at: Option<Instant>,
    returned_at: Option<Instant>,
    thread: Option<JoinHandle<()>>,
}

impl PresentThread {
    pub fn start() -> Self {
        let (jobs, inbox) = channel::<Job>();
        let (outbox, outcomes) = channel();
        let thread = std::thread::Builder::new()
            .name("present".into())
            .spawn(move || {
                for job in inbox {
                    let outcome = job.swapchain.present(job.index);
                    let returned = Instant::now();
                    // The job's swapchain goes before the outcome does: once the loop has
                    // the outcome, it holds the only reference again.
                    drop(job);
                    if outbox.send((outcome, returned)).is_err() {
                        break;
                    }
                }
            })
            .ok();
        Self {
            jobs: Some(jobs),
            outcomes,
            pending: false,
            arrived: None,
            handed_at: None,
            returned_at: None,
            thread,
        }
    }

    /// Presents image `index` of `swapchain` on the thread; the caller does not touch the
    /// queue or the swapchain until [`Self::returned`] says it has.
    pub fn present(&mut self, swapchain: &Arc<Swapchain>, index: u32) -> Result<(), GpuError> {
        debug_assert!(!self.pending, "one present at a time");
        let job = Job {
            swapchain: Arc::clone(swapchain),
            index,
        };
        self.handed_at = Some(Instant::now());
        match self.thread.is_some() {
            // The thread could not be started: present here, as before.
            false => self.receive((job.swapchain.present(job.index), Instant::now())),
            true => {
                let sent = self.jobs.as_ref().map(|jobs| jobs.send(job));
                if !matches!(sent, Some(Ok(()))) {
                    return Err(gone());
                }
                self.pending = true;
            }
        }
        Ok(())
    }

    /// Whether the last present has returned (never waits).
    pub fn returned(&mut self) -> bool {
        if self.pending {
            match self.outcomes.try_recv() {
                Ok(outcome) => self.receive(outcome),
                Err(TryRecvError::Empty) => {}
                Err(TryRecvError::Disconnected) => self.receive((Err(gone()), Instant::now())),
            }
        }
        !self.pending
    }

    /// Whether a present was handed over and its outcome not yet taken ([`Self::take`]):
    /// running, or returned and unread.
    pub fn outstanding(&self) -> bool {
        self.pending || self.arrived.is_some()
    }

    /// The last present's outcome, waiting for it if it has not returned; `Ok(false)` when
    /// there is none.
    pub fn take(&mut self) -> Outcome {
        if self.pending {
            let outcome = (self.outcomes.recv()).unwrap_or_else(|_| (Err(gone()), Instant::now()));
            self.receive(outcome);
        }
        self.arrived.take().unwrap_or(Ok(false))
    }

    /// When the last present was handed over and when the last one returned (`None`
    /// before the first): what a key waited for (`answers.rs`). The one before is always
    /// taken before a present is handed over, so a return is never earlier than its
    /// hand-over and never later than the next one's.
    pub fn handed_at(&self) -> Option<Instant> {
        self.handed_at
    }

    pub fn returned_at(&self) -> Option<Instant> {
        self.returned_at
    }

    fn receive(&mut self, (outcome, at): (Outcome, Instant)) {
        self.pending = false;
        self.arrived = Some(outcome);
        self.returned_at = Some(at);
    }
}

impl Drop for PresentThread {
    fn drop(&mut self) {
        // Closing the channel ends the thread once its present (if any) has returned.
        self.jobs = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// The thread ended without answering (it cannot panic; this is for completeness).
fn gone() -> GpuError {
    GpuError::Unsupported("the present thread ended".into())
}
