//! Where a sensor frame's range and ids come from, and whether its colour image shows what
//! they say: a segmentation or depth dataset is only as good as that agreement.

use serde::{Deserialize, Serialize};

use crate::scene::Scene;

/// What a user making a dataset must know where the cube path's layers may disagree with the
/// image.
const CUBE_WARNING: &str = "range and ids come through the cube (its depth search and id \
     cube), not traced: they are exact only where the cube's centre saw what the mirror shows, \
     and the colour image's lookup may show another surface (docs/sensor.md, \"Ground truth\", \
     has the measured disagreement); a lookup that traces (ray-query or bvh, the default for \
     --sensor-outputs) traces all three along one path";

/// Why the cube path is exact for a central mirror.
const CENTRAL_CUBE: &str = "the mirror is central, its camera at its focus and the cube \
     rendered at its viewpoint: every reflected ray lies on a line through the cube's centre, so \
     the cube sees what each ray meets, and every lookup reads the cube in that ray's direction; \
     range, ids and colour agree up to texel sampling";

/// Whether the cube path is exact for `scene`'s sensor: a central mirror (a single viewpoint,
/// the shape's own camera at its focus, no `sensor.shift`) and the cube rendered at that
/// viewpoint (no `cube.offset`). A tilt keeps a pinhole's rays through the focus (the
/// hyperboloid's), but not an orthographic camera's (the paraboloid's): it focuses only rays
/// parallel to its axis. Every reflected ray then lies on a line through the cube's centre,
/// which saw the first surface along it.
pub fn cube_path_is_exact(scene: &Scene) -> bool {
    let s = &scene.sensor;
    let tilted_orthographic = s.orthographic_half_m > 0.0 && s.tilt_deg != 0.0;
    scene.mirror.shape.xi.is_some()
        && s.shift_m == glam::Vec3::ZERO
        && !tilted_orthographic
        && scene.cube.offset_m == glam::Vec3::ZERO
}

/// The source of a frame's range and id layers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GroundTruth {
    /// The CPU reference: every layer from the exact paths the colour samples too.
    Reference,
    /// Traced on the GPU along the colour pass's own reflected ray (the `ray-query` lookup,
    /// `shaders/mirror_ray.frag.glsl` built with `TRACED`): exact, and the colour shows what the ids say.
    Traced,
    /// Searched through the cube's depth and read from the id cube (every other lookup,
    /// `shaders/include/sensor_ray.glsl`): exact only where the cube's centre saw what the
    /// reflected ray meets, and the colour's lookup may show another surface.
    Cube,
}

impl GroundTruth {
    /// Its name, as the JSON records write it.
    pub fn name(self) -> &'static str {
        match self {
            GroundTruth::Reference => "reference",
            GroundTruth::Traced => "traced",
            GroundTruth::Cube => "cube",
        }
    }

    /// Whether these layers are exact for `scene` (the cube path is where it is central:
    /// [`cube_path_is_exact`]).
    pub fn exact_for(self, scene: &Scene) -> bool {
        self != GroundTruth::Cube || cube_path_is_exact(scene)
    }

    /// What the range layer measures (`exact`: [`Self::exact_for`]).
    pub fn range_model(self, exact: bool) -> &'static str {
        match self {
            GroundTruth::Cube if exact => {
                "exact (a central mirror's cube): the distance along the reflected ray to the \
                 first surface the cube's centre saw in its direction"
            }
            GroundTruth::Reference | GroundTruth::Traced => {
                "exact: the distance along the reflected ray to the first scene surface it meets"
            }
            GroundTruth::Cube => {
                "depth cube: the distance along the reflected ray to where it meets the surface \
                 the cube's depth stored (the distance lookup's search), an approximation where \
                 the mirror sees what the cube's centre does not (disocclusion) and at \
                 silhouettes; the room box's distance where the search finds no hit"
            }
        }
    }

    /// What the id layer names (`exact`: [`Self::exact_for`]).
    pub fn id_model(self, exact: bool) -> &'static str {
        match self {
            GroundTruth::Cube if exact => {
                "exact (a central mirror's cube): the drawable the cube fill drew at the texel \
                 (nearest) in the reflected ray's direction, the first one along it"
            }
            GroundTruth::Reference | GroundTruth::Traced => {
                "exact: the drawable the surface the reflected ray meets belongs to"
            }
            GroundTruth::Cube => {
                "id cube: the drawable the cube fill drew at the texel (nearest, never \
                 filtered) where the reflected ray meets the depth cube's surface; the wall the \
                 ray leaves the room box through where the search finds no hit"
            }
        }
    }

    /// What a user making a dataset of `scene` must know, where the layers may disagree with
    /// the image.
    pub fn warning(self, scene: &Scene) -> Option<&'static str> {
        (!self.exact_for(scene)).then_some(CUBE_WARNING)
    }
}

/// `camera.json`'s `ground_truth`: where the layers come from, which lookup made the colour
/// image, and whether the two agree.
#[derive(Debug, Clone, Serialize)]
pub struct GroundTruthRecord {
    pub layers: GroundTruth,
    /// The colour image's lookup ("reference" for the reference's own colour).
    pub colour: String,
    /// Whether the colour image shows what range and ids say: the layers come from the
    /// colour's own light path, or from a cube that sees what every reflected ray meets.
    pub colour_agrees: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<&'static str>,
    /// Why cube layers agree, where they do.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub exact_because: Option<&'static str>,
}

impl GroundTruthRecord {
    /// The record of `layers` for `scene`'s sensor, its colour image made by `colour`.
    pub fn new(layers: GroundTruth, colour: &str, scene: &Scene) -> Self {
        let exact = layers.exact_for(scene);
        Self {
            layers,
            colour: colour.to_owned(),
            colour_agrees: exact,
            warning: layers.warning(scene),
            exact_because: (exact && layers == GroundTruth::Cube).then_some(CENTRAL_CUBE),
        }
    }
}

#[cfg(test)]
mod name_tests {
    use super::GroundTruth;

    /// The name is the one the records' JSON carries.
    #[test]
    fn the_name_is_the_records() {
        for truth in [
            GroundTruth::Reference,
            GroundTruth::Traced,
            GroundTruth::Cube,
        ] {
            assert_eq!(serde_json::to_value(truth).unwrap(), truth.name());
        }
    }
}
