//! Where a sensor frame's range and ids come from, and whether its colour image shows what
//! they say: a segmentation or depth dataset is only as good as that agreement.

use serde::{Deserialize, Serialize};

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

    /// What the range layer measures.
    pub fn range_model(self) -> &'static str {
        match self {
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

    /// What the id layer names.
    pub fn id_model(self) -> &'static str {
        match self {
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

    /// Whether the colour image comes from the same light path as the range and ids.
    pub fn colour_agrees(self) -> bool {
        self != GroundTruth::Cube
    }

    /// What a user making a dataset must know, where the layers may disagree with the image.
    pub fn warning(self) -> Option<&'static str> {
        (self == GroundTruth::Cube).then_some(
            "range and ids come through the cube (its depth search and id cube), not traced: \
             they are exact only where the cube's centre saw what the mirror shows, and the \
             colour image's lookup may show another surface (docs/sensor.md, \"Ground truth\", \
             has the measured disagreement); a device with ray queries and the ray-query \
             lookup (the default for --sensor-outputs there) traces all three along one path",
        )
    }
}

/// `camera.json`'s `ground_truth`: where the layers come from, which lookup made the colour
/// image, and whether the two agree.
#[derive(Debug, Clone, Serialize)]
pub struct GroundTruthRecord {
    pub layers: GroundTruth,
    /// The colour image's lookup ("reference" for the reference's own colour).
    pub colour: String,
    pub colour_agrees: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<&'static str>,
}

impl GroundTruthRecord {
    pub fn new(layers: GroundTruth, colour: &str) -> Self {
        Self {
            layers,
            colour: colour.to_owned(),
            colour_agrees: layers.colour_agrees(),
            warning: layers.warning(),
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
