//! The scene file exactly as written: serde structs mirroring the TOML, one per table.
//!
//! Nothing here is validated beyond TOML types; `load/` turns these into the resolved
//! [`super::Scene`]. Numbers are read as `f64`/`i64` so that out-of-range values (`1e300`,
//! `-1` for a size) reach the validator and get a message that says what the valid range is,
//! instead of a generic "expected u32". Every struct denies unknown fields so a typo is an
//! error, not a silently ignored setting.
//!
//! Where a value's meaning depends on a word (`type = "checker"`, `shape = "box"`), the struct
//! is flat with optional fields and the validator checks which fields that word needs or
//! forbids: serde's tagged enums lose the source position of errors inside them.
//!
//! Fixed-length arrays are read through `fixed.rs`, which refuses extra elements (serde alone
//! would drop them silently).

use std::fmt;

use serde::de::value::{MapAccessDeserializer, SeqAccessDeserializer};
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;

use super::fixed::{self, exact};

pub type V3 = [f64; 3];

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub description: Option<String>,
    pub room: Option<RoomSpec>,
    pub mirror: Option<MirrorSpec>,
    #[serde(default)]
    pub materials: Vec<MaterialSpec>,
    #[serde(default)]
    pub objects: Vec<ObjectSpec>,
    #[serde(default)]
    pub generate: Vec<GenerateSpec>,
    pub observer: Option<ObserverSpec>,
    pub sensor: Option<SensorSpec>,
    pub cube: Option<CubeSpec>,
    pub refresh: Option<RefreshSpec>,
    pub light: Option<LightSpec>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoomSpec {
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub center: Option<V3>,
    #[serde(deserialize_with = "fixed::exact")]
    pub size: V3,
    pub walls: WallsSpec,
}

/// One material name for all six walls, or one per wall. (Not `#[serde(untagged)]`: its
/// error, "did not match any variant", says neither what is wrong nor what is allowed; see
/// `fixed.rs` for the hand-written reader.)
#[derive(Debug)]
pub enum WallsSpec {
    All(String),
    Each(EachWall),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EachWall {
    pub px: String,
    pub nx: String,
    pub py: String,
    pub ny: String,
    pub pz: String,
    pub nz: String,
}

/// `[mirror]`. Its shape's fields are whatever the shape registered in `crate::mirror`
/// reads, so the table is read by hand ([`MirrorSpec::deserialize`]): the common fields typed,
/// every other key kept, with its value, for the loader to check against the shape.
#[derive(Debug)]
pub struct MirrorSpec {
    /// `mirror.shape`: a name from `crate::mirror`'s registry; the sphere when left out.
    pub shape: Option<String>,
    pub center: V3,
    pub animation: Option<AnimationSpec>,
    /// Read as the scene's own lookup names (`Lookup`'s serde names, one list).
    pub lookup: Option<super::Lookup>,
    pub distance_steps: Option<i64>,
    pub secant_steps: Option<i64>,
    /// Every other key, in file order: a shape's fields (`radius`, `focal_distance`, ...) or
    /// a mistake, which the loader names with its line.
    pub shape_fields: Vec<(String, toml::Value)>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MaterialType {
    Color,
    Checker,
    Grid,
    Texture,
    Direction,
}

impl MaterialType {
    /// As the file writes it (`type = "checker"`).
    pub fn name(self) -> &'static str {
        match self {
            MaterialType::Color => "color",
            MaterialType::Checker => "checker",
            MaterialType::Grid => "grid",
            MaterialType::Texture => "texture",
            MaterialType::Direction => "direction",
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    pub name: String,
    #[serde(rename = "type")]
    pub kind: MaterialType,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub color: Option<V3>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub a: Option<V3>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub b: Option<V3>,
    pub tiles: Option<f64>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub background: Option<V3>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub line: Option<V3>,
    pub line_width: Option<f64>,
    pub file: Option<String>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub tint: Option<V3>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Shape {
    Box,
    Sphere,
    Cylinder,
    Mesh,
}

impl Shape {
    /// The name the scene file uses.
    pub fn name(self) -> &'static str {
        match self {
            Shape::Box => "box",
            Shape::Sphere => "sphere",
            Shape::Cylinder => "cylinder",
            Shape::Mesh => "mesh",
        }
    }

    /// What an object of this shape is drawn as, for reports and id maps: the shape's name,
    /// and for a mesh the file as the scene names it (`mesh chair.obj`).
    pub fn describe(self, file: Option<&str>) -> String {
        match (self, file) {
            (Shape::Mesh, Some(file)) => format!("mesh {file}"),
            (shape, _) => shape.name().to_owned(),
        }
    }
}

/// `scale = 2` or `scale = [1, 2, 1]` (read by hand in `fixed.rs`, as `WallsSpec`).
#[derive(Debug, Clone, Copy)]
pub enum ScaleSpec {
    Uniform(f64),
    PerAxis(V3),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    pub name: Option<String>,
    /// What kind of thing it is (`chair`), the label of its pixels in the class layer.
    pub class: Option<String>,
    pub shape: Shape,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub size: Option<V3>,
    pub radius: Option<f64>,
    pub height: Option<f64>,
    pub file: Option<String>,
    /// Whose frame `position` and `rotation` are in (default: the scene's).
    pub frame: Option<FrameSpec>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub position: Option<V3>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub rotation: Option<V3>,
    pub scale: Option<ScaleSpec>,
    pub material: String,
    pub animation: Option<AnimationSpec>,
}

/// `objects[i].frame`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FrameSpec {
    World,
    Sensor,
}

/// `[[generate]]`: many objects placed by a seeded PRNG (see `generate.rs`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GenerateSpec {
    pub name: Option<String>,
    /// The class of every object it makes.
    pub class: Option<String>,
    pub count: i64,
    pub seed: Option<i64>,
    pub shapes: Vec<Shape>,
    pub file: Option<String>,
    #[serde(deserialize_with = "fixed::exact")]
    pub size: [f64; 2],
    pub segments: Option<i64>,
    #[serde(deserialize_with = "fixed::exact")]
    pub region_min: V3,
    #[serde(deserialize_with = "fixed::exact")]
    pub region_max: V3,
    pub keep_clear: Option<f64>,
    pub materials: Vec<String>,
    pub moving: Option<f64>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub period: Option<[f64; 2]>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AnimationType {
    Linear,
    Orbit,
    Keyframes,
}

impl AnimationType {
    /// As a scene writes it (`type = "orbit"`).
    pub fn name(self) -> &'static str {
        match self {
            AnimationType::Linear => "linear",
            AnimationType::Orbit => "orbit",
            AnimationType::Keyframes => "keyframes",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RepeatSpec {
    Once,
    Loop,
    PingPong,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnimationSpec {
    #[serde(rename = "type")]
    pub kind: AnimationType,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub to: Option<V3>,
    pub duration: Option<f64>,
    pub repeat: Option<RepeatSpec>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub center: Option<V3>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub axis: Option<V3>,
    pub period: Option<f64>,
    pub times: Option<Vec<f64>>,
    #[serde(default, deserialize_with = "fixed::exact_list")]
    pub positions: Option<Vec<V3>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObserverSpec {
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub position: Option<V3>,
    pub yaw: Option<f64>,
    pub pitch: Option<f64>,
    pub fov_y: Option<f64>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub resolution: Option<[i64; 2]>,
    pub animation: Option<AnimationSpec>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSpec {
    pub offset: Option<f64>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub shift: Option<V3>,
    pub tilt: Option<f64>,
    pub fov_y: Option<f64>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub resolution: Option<[i64; 2]>,
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub up: Option<V3>,
    pub imaging: Option<ImagingSpec>,
}

/// `[sensor.imaging]`: every field optional (the default camera's value).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImagingSpec {
    pub exposure_s: Option<f64>,
    pub gain_db: Option<f64>,
    pub unit_flux_e_per_s: Option<f64>,
    pub full_well_e: Option<f64>,
    pub read_noise_e: Option<f64>,
    pub dark_current_e_per_s: Option<f64>,
    pub system_gain_dn_per_e: Option<f64>,
    pub bit_depth: Option<i64>,
    pub black_level_dn: Option<f64>,
    pub response: Option<String>,
    pub gamma: Option<f64>,
    pub response_table: Option<Vec<f64>>,
    pub vignetting: Option<f64>,
    pub blur_px: Option<f64>,
    pub seed: Option<i64>,
    pub motion_blur_samples: Option<i64>,
    pub rolling_shutter_s: Option<f64>,
    pub prnu_percent: Option<f64>,
    pub dsnu_e: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
pub enum CubeFormatSpec {
    #[serde(rename = "rgba16f")]
    Rgba16f,
    #[serde(rename = "rgba8")]
    Rgba8,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CubeSpec {
    pub face_size: Option<i64>,
    /// Where the cube is rendered from, relative to the mirror's viewpoint.
    #[serde(default, deserialize_with = "fixed::exact_opt")]
    pub offset: Option<V3>,
    pub format: Option<CubeFormatSpec>,
    pub near: Option<f64>,
    pub far: Option<f64>,
    pub mipmaps: Option<bool>,
    pub anisotropy: Option<i64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PolicySpec {
    EveryFrame,
    OnChange,
    EveryN,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RefreshSpec {
    pub policy: PolicySpec,
    pub n: Option<i64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightSpec {
    #[serde(deserialize_with = "fixed::exact")]
    pub direction: V3,
    pub ambient: Option<f64>,
}

// The two fields that take one of two shapes (`walls`, `scale`), read by hand: serde's
// untagged enums answer any mistake with "data did not match any variant of untagged enum",
// which names neither what is wrong nor what is allowed.

impl<'de> Deserialize<'de> for WallsSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Walls;
        impl<'de> Visitor<'de> for Walls {
            type Value = WallsSpec;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(
                    "a material name for all six walls, or a table { px, nx, py, ny, pz, nz } naming one per wall",
                )
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<WallsSpec, E> {
                Ok(WallsSpec::All(v.to_string()))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<WallsSpec, A::Error> {
                EachWall::deserialize(MapAccessDeserializer::new(map)).map(WallsSpec::Each)
            }
        }
        d.deserialize_any(Walls)
    }
}

impl<'de> Deserialize<'de> for ScaleSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Scale;
        impl<'de> Visitor<'de> for Scale {
            type Value = ScaleSpec;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number (uniform scale) or an array of exactly 3 numbers [x, y, z]")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<ScaleSpec, E> {
                Ok(ScaleSpec::Uniform(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<ScaleSpec, E> {
                Ok(ScaleSpec::Uniform(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<ScaleSpec, E> {
                Ok(ScaleSpec::Uniform(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<ScaleSpec, A::Error> {
                exact(SeqAccessDeserializer::new(seq)).map(ScaleSpec::PerAxis)
            }
        }
        d.deserialize_any(Scale)
    }
}

/// The common keys of `[mirror]`; any other is a shape's field or a mistake.
pub const MIRROR_KEYS: [&str; 6] = [
    "shape",
    "center",
    "animation",
    "lookup",
    "distance_steps",
    "secant_steps",
];

impl<'de> Deserialize<'de> for MirrorSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        /// `center`, read strictly (exactly three numbers).
        #[derive(Deserialize)]
        #[serde(transparent)]
        struct Center(#[serde(deserialize_with = "fixed::exact")] V3);

        struct Mirror;
        impl<'de> Visitor<'de> for Mirror {
            type Value = MirrorSpec;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a [mirror] table")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<MirrorSpec, A::Error> {
                let mut center = None;
                let mut m = MirrorSpec {
                    shape: None,
                    center: [0.0; 3],
                    animation: None,
                    lookup: None,
                    distance_steps: None,
                    secant_steps: None,
                    shape_fields: Vec::new(),
                };
                while let Some(key) = map.next_key::<String>()? {
                    match key.as_str() {
                        "shape" => m.shape = Some(map.next_value()?),
                        "center" => center = Some(map.next_value::<Center>()?.0),
                        "animation" => m.animation = Some(map.next_value()?),
                        "lookup" => m.lookup = Some(map.next_value()?),
                        "distance_steps" => m.distance_steps = Some(map.next_value()?),
                        "secant_steps" => m.secant_steps = Some(map.next_value()?),
                        _ => m.shape_fields.push((key, map.next_value()?)),
                    }
                }
                m.center = center.ok_or_else(|| de::Error::missing_field("center"))?;
                Ok(m)
            }
        }
        d.deserialize_map(Mirror)
    }
}
