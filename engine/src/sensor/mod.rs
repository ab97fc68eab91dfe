//! The catadioptric sensor as a robotics user sees it: the rays its pixels really see (the
//! non-central ray map, ground truth for calibration), and what is derived from them.
//!
//! A spherical mirror has no single effective viewpoint (its viewpoints form a caustic), so
//! every pixel's ray has its own origin on the mirror; [`ray_map`] gives both per pixel.

pub mod central;
pub mod ray_map;

pub use ray_map::{PixelRay, RayMap};
