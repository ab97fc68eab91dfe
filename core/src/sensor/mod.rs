//! The catadioptric sensor as a robotics user sees it: the rays its pixels really see (the
//! non-central ray map, ground truth for calibration), and what is derived from them.
//!
//! A spherical mirror has no single effective viewpoint (its viewpoints form a caustic), so
//! every pixel's ray has its own origin on the mirror; [`ray_map`] gives both per pixel.
//! [`optics`] finds the mirror's image disc from the pose and the sphere, [`panorama`] unwraps
//! the sensor image (and reads the same panoramas from a cube map), and [`outputs`] gathers one
//! frame's layers from the reference or the GPU and writes them ([`files`]: EXR channels).

pub mod bag;
pub mod central;
pub mod dataset;
pub mod files;
pub mod ground_truth;
pub mod id_map;
pub mod imaging;
pub mod layers;
pub mod localise;
pub mod optics;
pub mod outputs;
pub mod panorama;
pub mod quantities;
pub mod ray_map;
pub mod solve;

pub use ground_truth::GroundTruth;
pub use optics::SensorOptics;
pub use outputs::SensorOutputs;
pub use ray_map::{PixelRay, RayMap};

#[cfg(test)]
mod tests;
