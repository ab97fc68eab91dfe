//! SPIR-V compiled from `shaders/` at build time (see `engine/build.rs`).
//!
//! Each `shaders/NAME.STAGE.glsl` becomes a constant `NAME_STAGE: &[u32]`.
#![allow(clippy::unreadable_literal)]

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

#[cfg(test)]
mod tests {
    use crate::sensor::quantities;

    /// The quantities the ray map's shader writes (one file each, engine/build.rs) are the
    /// registry's, each once: a GLSL half without its reference half, or the reverse, fails.
    #[test]
    fn the_ray_maps_quantities_are_the_registrys() {
        let mut glsl: Vec<&str> = super::SENSOR_QUANTITIES.to_vec();
        let mut rust: Vec<&str> = quantities::ALL.iter().map(|q| q.name()).collect();
        glsl.sort();
        rust.sort();
        assert_eq!(
            glsl, rust,
            "shaders/include/quantities/ against sensor::quantities::ALL"
        );
    }
}
