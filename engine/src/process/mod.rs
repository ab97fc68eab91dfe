//! What every program that runs the engine from a command line shares, whichever crate it is
//! in (the `specchio` binary, the benchmark, the viewer): signals that stop a run before it
//! places its output ([`interrupt`]), the validation layer's verdict ([`validation`]), the allocator setting
//! every timed run records ([`allocator`]), how a run ends and the status it exits with ([`ending`]), long work said as it goes ([`progress`]), a reference run said and stoppable as it goes ([`traced`]), and the range checks of command-line values
//! ([`args`]). Nothing in the renderer imports this module: it sits on top. Standard output
//! that never panics ([`crate::stdout`], the `say!` macros) is below everything instead: the
//! Vulkan layer's test faults say what they do through it.

pub mod allocator;
pub mod args;
pub mod ending;
pub mod interrupt;
pub mod patience;
pub mod probe;
pub mod progress;
pub mod traced;
pub mod validation;
