//! The mirror part of the renderer: the lookup's pass it holds (its pipelines, its set 1, its
//! per-frame work), rebuilt when the scene's lookup is switched in place (the viewer's menu);
//! the pass it replaces is kept for the frames in flight that still use it (`retired.rs`).

use std::sync::Arc;

use super::gpu;
use super::lookups::{self, LookupPass, TraceIn, TraceOrder};
use super::resources::SceneResources;
use super::retired::Retired;
use super::targets::CubeTarget;
use crate::scene::{Lookup, Scene};
use crate::vk::commands::Submitter;
use crate::vk::device::Device;
use crate::vk::GpuError;

/// How a tracing lookup traces: the order it hands its builds, and where it walks its rays
/// (None: the device's default).
pub(super) type Tracing = (TraceOrder, Option<TraceIn>, Option<crate::bvh::BvhLayout>);

/// What a lookup's pass is built from: the scene, the device, the scene on it, the cube, the
/// submitter.
pub(super) type Inputs<'a> = (
    &'a Scene,
    &'a Arc<Device>,
    &'a SceneResources,
    &'a CubeTarget,
    &'a Submitter,
);

pub(super) struct Mirror {
    pub pass: Box<dyn LookupPass>,
    /// Passes switched away from while frames in flight still used them.
    retired: Retired<Box<dyn LookupPass>>,
    lookup: Lookup,
    /// How the tracing lookups trace (kept for a lookup switched in place).
    tracing: Tracing,
    /// The renderer's frames in flight (a pass keeps per-frame copies of what the host reads).
    frames_in_flight: usize,
}

impl Mirror {
    pub fn create(
        inputs: Inputs<'_>,
        lookup: Lookup,
        tracing: Tracing,
        frames_in_flight: usize,
    ) -> Result<Self, GpuError> {
        Ok(Self {
            pass: create_pass(inputs, lookup, tracing, frames_in_flight)?,
            retired: Retired::default(),
            lookup,
            tracing,
            frames_in_flight,
        })
    }

    /// The lookup the pass is for.
    pub fn lookup(&self) -> Lookup {
        self.lookup
    }

    /// Rebuilds the pass when the scene's lookup is no longer the one it was made for. The
    /// old pass is kept until frame `in_flight` (the last submitted, if one may still run)
    /// has finished: no frame waits for the switch.
    pub fn follow(
        &mut self,
        inputs: Inputs<'_>,
        lookup: Lookup,
        in_flight: Option<u64>,
    ) -> Result<(), GpuError> {
        if lookup != self.lookup {
            let new = create_pass(inputs, lookup, self.tracing, self.frames_in_flight)?;
            let old = std::mem::replace(&mut self.pass, new);
            self.retired.keep(in_flight, old);
            self.lookup = lookup;
        }
        Ok(())
    }

    /// The pass frame `frame` was recorded with (its tally is that pass's).
    pub fn pass_recorded_for(&self, frame: u64) -> &dyn LookupPass {
        self.retired.used_by(frame).unwrap_or(&self.pass).as_ref()
    }

    /// Frame `frame` has finished: the passes no later frame used are destroyed.
    pub fn release_through(&mut self, frame: u64) {
        self.retired.release_through(frame);
    }
}

/// The pass of `lookup`, refused with the reason when the device cannot run it.
fn create_pass(
    (scene, device, resources, cube, submitter): Inputs<'_>,
    lookup: Lookup,
    (trace_order, trace_in, bvh_layout): Tracing,
    frames_in_flight: usize,
) -> Result<Box<dyn LookupPass>, GpuError> {
    if let Some(why) = lookups::missing_features(lookup, &device.info) {
        return Err(GpuError::Unsupported(format!("lookup {lookup}: {why}")));
    }
    let plugin = lookups::plugin(lookup);
    let pass = plugin.create(&lookups::LookupContext {
        lookup,
        scene,
        device,
        resources,
        cube,
        submitter,
        push_size: std::mem::size_of::<gpu::Push>() as u32,
        trace_order,
        frames_in_flight,
        trace_in: trace_in.unwrap_or_else(|| TraceIn::default_for(&device.info)),
        bvh_layout: bvh_layout.unwrap_or_else(|| lookups::default_bvh_layout(&device.info)),
    })?;
    // What the plug-in says decides the renderer's id cube before the pass exists.
    assert_eq!(
        pass.trace_set().is_some(),
        plugin.traces_ray_map(),
        "lookup {lookup}: its pass and its plug-in disagree on tracing the ray map"
    );
    Ok(pass)
}
