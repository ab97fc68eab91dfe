//! What every program that runs the engine from a command line shares, whichever crate it is
//! in (the `specchio` binary, the benchmark, the viewer): standard output that never panics
//! ([`stdout`], the `say!` macros), signals that stop a run before it places its output
//! ([`interrupt`]), the validation layer's verdict ([`validation`]), the allocator setting
//! every timed run records ([`allocator`]), and the range checks of command-line values
//! ([`args`]). Nothing in the renderer imports this module: it sits on top.

pub mod allocator;
pub mod args;
pub mod interrupt;
pub mod probe;
pub mod stdout;
pub mod validation;
