//! The layers a frame's sensor outputs are written as, by the names a user chooses them with
//! (`specchio dataset --outputs`, Python's `outputs=`), and the files each is.

use std::fmt;

use super::imaging::CAMERA_IMAGE_FILE;

/// File names inside an output folder.
pub const IMAGE_FILES: [&str; 2] = ["sensor.exr", "sensor.png"];
pub const RAYS_FILE: &str = "sensor.rays.exr";
pub const RANGE_FILE: &str = "sensor.range.exr";
/// The range as 16-bit millimetres (layer `range16`).
pub const RANGE16_FILE: &str = "sensor.range.png";
pub const ID_FILE: &str = "sensor.id.exr";
/// What each id of [`ID_FILE`] is: the id map as JSON.
pub const ID_MAP_FILE: &str = "sensor.id.json";
pub const CAMERA_FILE: &str = "camera.json";
/// The panoramas' files: `sensor.panorama.KIND.exr` and `.png` (and from a cube,
/// `cube.panorama.*`, which a dataset never writes).
pub const PANORAMA_FILES: &str = "sensor.panorama.*";
pub const POINTS_FILE: &str = "points.ply";

/// One layer of a frame's outputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layer {
    /// The clean sensor image: linear EXR and an sRGB PNG preview.
    Image,
    /// The camera image of the scene's `[sensor.imaging]`.
    Camera,
    /// The ray map.
    Rays,
    Range,
    /// The range as a 16-bit PNG of whole millimetres (ROS's `16UC1` depth convention): chosen
    /// by name, not by `all`, which has the float range.
    Range16,
    /// The ids and classes, and the id map.
    Ids,
    Panoramas,
    /// The point cloud (a dataset's: where each mirror pixel's ray ends).
    Points,
}

impl Layer {
    pub const ALL: [Layer; 8] = [
        Layer::Image,
        Layer::Camera,
        Layer::Rays,
        Layer::Range,
        Layer::Range16,
        Layer::Ids,
        Layer::Panoramas,
        Layer::Points,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Layer::Image => "image",
            Layer::Camera => "camera",
            Layer::Rays => "rays",
            Layer::Range => "range",
            Layer::Range16 => "range16",
            Layer::Ids => "ids",
            Layer::Panoramas => "panoramas",
            Layer::Points => "points",
        }
    }

    /// Its files (`*`: any plain suffix).
    pub fn files(self) -> &'static [&'static str] {
        match self {
            Layer::Image => &IMAGE_FILES,
            Layer::Camera => &[CAMERA_IMAGE_FILE],
            Layer::Rays => &[RAYS_FILE],
            Layer::Range => &[RANGE_FILE],
            Layer::Range16 => &[RANGE16_FILE],
            Layer::Ids => &[ID_FILE, ID_MAP_FILE],
            Layer::Panoramas => &[PANORAMA_FILES],
            Layer::Points => &[POINTS_FILE],
        }
    }

    fn bit(self) -> u16 {
        1 << (self as u8)
    }
}

/// A choice of layers, and whether a keyword (`all`, `default`) made it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layers(u16);

/// The bit of [`Layers`] that says a keyword chose them, above every layer's.
const KEYWORD: u16 = 1 << 15;

impl Layers {
    /// Every layer (the camera image only where there is an imaging chain to make it), the
    /// range once: as floats, not again as `range16`'s millimetres.
    pub fn all() -> Self {
        let bits = Layer::ALL.iter().fold(KEYWORD, |bits, l| bits | l.bit());
        Layers(bits).without(Layer::Range16)
    }

    /// What a dataset writes unless asked otherwise (`default`): every layer of [`Self::all`]
    /// but the ray map and the point cloud, which the pose and one frame's ray map give again
    /// (the sensor is rigid on the robot) and which are most of a frame's bytes (2.7 and
    /// 1.9 MB of a thesis-room frame at 512²: docs/sensor.md).
    pub fn standard() -> Self {
        Self::all().without(Layer::Rays).without(Layer::Points)
    }

    /// Whether a keyword (`all`, `default`) chose these rather than a list: a keyword takes
    /// the camera image only where the scene has one; a list names it on purpose, even one
    /// that names what a keyword would.
    pub fn is_keyword(self) -> bool {
        self.0 & KEYWORD != 0
    }

    pub fn has(self, layer: Layer) -> bool {
        self.0 & layer.bit() != 0
    }

    pub fn without(self, layer: Layer) -> Self {
        Layers(self.0 & !layer.bit())
    }

    pub fn iter(self) -> impl Iterator<Item = Layer> {
        Layer::ALL.into_iter().filter(move |l| self.has(*l))
    }

    /// The layers a scene can have: [`Layer::Camera`] only with an imaging chain.
    pub fn for_scene(self, imaging: bool) -> Self {
        match imaging {
            true => self,
            false => self.without(Layer::Camera),
        }
    }

    /// Every file a frame of these layers holds, `camera.json` first.
    pub fn files(self) -> Vec<&'static str> {
        let mut files = vec![CAMERA_FILE];
        files.extend(self.iter().flat_map(|l| l.files().iter().copied()));
        files
    }
}

impl std::str::FromStr for Layers {
    type Err = String;

    /// `all`, `default`, or layer names separated by commas (`image,range,ids`), each once.
    fn from_str(text: &str) -> Result<Self, String> {
        match text.trim() {
            "all" => return Ok(Layers::all()),
            "default" => return Ok(Layers::standard()),
            _ => {}
        }
        let names = || {
            let all: Vec<&str> = Layer::ALL.iter().map(|l| l.name()).collect();
            all.join(", ")
        };
        let mut bits = 0u16;
        for word in text.split(',').map(str::trim) {
            let layer = (Layer::ALL.into_iter().find(|l| l.name() == word)).ok_or_else(|| {
                match word.is_empty() {
                    true => format!(
                        "`{text}`: an empty layer name; the layers: {}, or all, or default",
                        names()
                    ),
                    false => format!("`{word}` is not a layer: {}, or all, or default", names()),
                }
            })?;
            if bits & layer.bit() != 0 {
                return Err(format!("`{word}` is named twice"));
            }
            bits |= layer.bit();
        }
        Ok(Layers(bits))
    }
}

impl fmt::Display for Layers {
    /// The names, comma-separated, in [`Layer::ALL`]'s order: what [`Layers::from_str`] reads.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = self.iter().map(Layer::name).collect();
        f.write_str(&names.join(","))
    }
}

impl serde::Serialize for Layers {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.iter().map(Layer::name))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_back_and_mistakes_are_named() {
        let l: Layers = "image, range,ids".parse().unwrap();
        assert_eq!(l.to_string(), "image,range,ids");
        assert_eq!(
            l.files(),
            [
                "camera.json",
                "sensor.exr",
                "sensor.png",
                RANGE_FILE,
                ID_FILE,
                ID_MAP_FILE
            ]
        );
        assert_eq!("all".parse::<Layers>().unwrap(), Layers::all());
        // Written out, a keyword's layers read back as the same layers (as a list).
        let again = Layers::all().to_string().parse::<Layers>().unwrap();
        assert_eq!(again.to_string(), Layers::all().to_string());
        assert!(Layer::ALL
            .iter()
            .all(|&l| again.has(l) == Layers::all().has(l)));
        let e = "image,depth".parse::<Layers>().unwrap_err();
        assert_eq!(
            e,
            "`depth` is not a layer: image, camera, rays, range, range16, ids, panoramas, points, \
             or all, or default"
        );
        let standard: Layers = "default".parse().unwrap();
        assert_eq!(standard, Layers::standard());
        assert_eq!(standard.to_string(), "image,camera,range,ids,panoramas");
        assert!(standard.is_keyword() && Layers::all().is_keyword() && !l.is_keyword());
        let listed: Layers = "image,camera,range,ids,panoramas".parse().unwrap();
        assert!(!listed.is_keyword() && listed.to_string() == standard.to_string());
        assert!("image,,range"
            .parse::<Layers>()
            .unwrap_err()
            .contains("empty layer name"));
        assert_eq!(
            "ids,ids".parse::<Layers>().unwrap_err(),
            "`ids` is named twice"
        );
        assert!(!Layers::all().for_scene(false).has(Layer::Camera));
        assert!(
            !Layers::all().has(Layer::Range16),
            "all has the range once, as floats"
        );
        let mm: Layers = "range16".parse().unwrap();
        assert_eq!(mm.files(), ["camera.json", RANGE16_FILE]);
    }
}
