//! No code: this crate exists for its manifest, which makes every build of the engine ask for
//! the same features of the dependencies the CLI and the Python wheel share (see its
//! `Cargo.toml`).
