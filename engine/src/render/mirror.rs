//! The mirror part of the renderer: the lookup's pass it holds (its pipelines, its set 1, its
//! per-frame work), rebuilt when the scene's lookup is switched in place (the viewer's menu).

use std::sync::Arc;

use super::gpu;
use super::lookups::{self, LookupPass, TraceOrder};
use super::resources::SceneResources;
use super::targets::CubeTarget;
use crate::scene::{Lookup, Scene};
use crate::vk::commands::Submitter;
use crate::vk::device::Device;
use crate::vk::GpuError;

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
    lookup: Lookup,
    /// The order the tracing lookups hand their builds (kept for a lookup switched in place).
    trace_order: TraceOrder,
    /// The renderer's frames in flight (a pass keeps per-frame copies of what the host reads).
    frames_in_flight: usize,
}

impl Mirror {
    pub fn create(
        inputs: Inputs<'_>,
        lookup: Lookup,
        trace_order: TraceOrder,
        frames_in_flight: usize,
    ) -> Result<Self, GpuError> {
        Ok(Self {
            pass: create_pass(inputs, lookup, trace_order, frames_in_flight)?,
            lookup,
            trace_order,
            frames_in_flight,
        })
    }

    /// The lookup the pass is for.
    pub fn lookup(&self) -> Lookup {
        self.lookup
    }

    /// Rebuilds the pass when the scene's lookup is no longer the one it was made for (the
    /// caller has waited for the frames that used the old one).
    pub fn follow(&mut self, inputs: Inputs<'_>, lookup: Lookup) -> Result<(), GpuError> {
        if lookup != self.lookup {
            self.pass = create_pass(inputs, lookup, self.trace_order, self.frames_in_flight)?;
            self.lookup = lookup;
        }
        Ok(())
    }
}

/// The pass of `lookup`, refused with the reason when the device cannot run it.
fn create_pass(
    (scene, device, resources, cube, submitter): Inputs<'_>,
    lookup: Lookup,
    trace_order: TraceOrder,
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
    })?;
    // What the plug-in says decides the renderer's id cube before the pass exists.
    assert_eq!(
        pass.trace_set().is_some(),
        plugin.traces_ray_map(),
        "lookup {lookup}: its pass and its plug-in disagree on tracing the ray map"
    );
    Ok(pass)
}
