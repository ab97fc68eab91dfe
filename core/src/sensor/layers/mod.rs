//! The layers a frame's sensor outputs are written as, by the names a user chooses them with
//! (`specchio dataset --outputs`, Python's `outputs=`), each a plug-in with one home: its
//! module below says its name, its files, whether the keywords take it, how it writes them
//! and what `camera.json` says of them; [`Layer::ALL`] is the registry. What a layer reads is
//! the frame's [`SensorOutputs`], which the renderer and the reference fill.
//!
//! To add a layer made from what a frame already holds (the image, rays, range, ids): write
//! its module, add it to [`Layer::ALL`], and name it in docs/sensor.md's list (a test
//! requires it there, in `specchio dataset --help` and in Python's `dataset` docs).

mod camera;
mod ids;
mod image;
mod panoramas;
mod points;
mod range;
mod range16;
mod rays;

use std::fmt;
use std::path::Path;

use crate::output::{OutputError, Sink};
use crate::sensor::SensorOutputs;

pub use ids::{ID_FILE, ID_MAP_FILE};
pub use image::IMAGE_FILES;
pub use panoramas::{PanoramaRecord, PANORAMA_FILES};
pub use points::POINTS_FILE;
pub use range::RANGE_FILE;
pub use range16::RANGE16_FILE;
pub use rays::{RAYS_FILE, RAY_CHANNELS};

pub const CAMERA_FILE: &str = "camera.json";

/// One layer of a frame's outputs: what it is and how it is written.
pub trait SensorLayer: Sync {
    /// The name a user chooses it by (`--outputs`, `outputs=`).
    fn name(&self) -> &'static str;
    /// What it holds and in which files, in a line (docs and help list it).
    fn about(&self) -> &'static str;
    /// Its files (`*`: any plain suffix).
    fn files(&self) -> &'static [&'static str];
    /// Whether `all` takes it.
    fn in_all(&self) -> bool {
        true
    }
    /// Whether `default` (what a dataset writes unless asked) takes it; only what `all` takes.
    fn in_default(&self) -> bool {
        self.in_all()
    }
    /// Whether a single render's sensor outputs (`render` and `reference --sensor-outputs`)
    /// hold it, where `all` takes it: not the image, which those commands write as their own
    /// view, nor a dataset's point cloud.
    fn in_single_render(&self) -> bool {
        true
    }
    /// Whether only a scene with a camera model (`[sensor.imaging]`) has it: a keyword then
    /// takes it only there, and a list that names it elsewhere is refused.
    fn needs_camera_model(&self) -> bool {
        false
    }
    /// How many samples (pixels times channels) its files of `frame` hold: the measure of its
    /// writing time that an estimate extrapolates (a 4096² sensor's outputs are seconds each).
    fn samples(&self, frame: &SensorOutputs) -> u64;
    /// Writes its files of `w.frame` into `dir`, and says what `camera.json` records of them.
    fn write(&self, w: &Writing<'_>, dir: &Path) -> Result<Told, OutputError>;
    /// What `camera.json` records when the layer was not chosen: nothing, by default.
    fn unchosen(&self) -> Told {
        Told::default()
    }
}

/// What a layer writes from, through what, and to whom its samples written are told (a
/// [`SensorLayer::samples`]'s worth as each layer ends).
pub struct Writing<'a> {
    pub frame: &'a SensorOutputs,
    pub out: &'a (dyn Sink + Sync),
    pub written: &'a (dyn Fn(u64) + Sync),
}

/// What `camera.json` records of a layer's files: entries of its `files` object, and entries
/// beside `files` (the camera model's `imaging`), each in the order given.
#[derive(Default)]
pub struct Told {
    pub files: Vec<(&'static str, Record)>,
    pub camera: Vec<(&'static str, Record)>,
}

/// One entry's value, kept as its own type until `camera.json` is written: its fields stay in
/// the order the type gives them (a `serde_json::Value` would sort them).
pub type Record = Box<dyn erased_serde::Serialize + Send + Sync>;

/// `value` as a [`Record`].
fn record<T: serde::Serialize + Send + Sync + 'static>(value: T) -> Record {
    Box::new(value)
}

/// Entries of a JSON object in the order given (registry order: a file stays the same bytes
/// whatever order the layers were written in).
#[derive(Default)]
pub struct Entries(pub Vec<(&'static str, Record)>);

impl serde::Serialize for Entries {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_map(self.0.iter().map(|(k, v)| (k, v)))
    }
}

impl fmt::Debug for Entries {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let keys: Vec<&str> = self.0.iter().map(|(k, _)| *k).collect();
        write!(f, "Entries({keys:?})")
    }
}

/// Writes the `chosen` layers of `w.frame` into `dir`, each beside the others, and returns what
/// `camera.json` records of every layer (of those not chosen too), in [`Layer::ALL`]'s order.
pub fn write(w: &Writing<'_>, dir: &Path, chosen: Layers) -> Result<Told, OutputError> {
    use rayon::prelude::*;
    let told: Vec<Told> = (Layer::ALL.par_iter())
        .map(|layer| match chosen.has(*layer) {
            true => {
                let told = layer.0.write(w, dir)?;
                (w.written)(layer.0.samples(w.frame));
                Ok(told)
            }
            false => Ok(layer.0.unchosen()),
        })
        .collect::<Result<_, _>>()?;
    Ok(told.into_iter().fold(Told::default(), |mut all, t| {
        all.files.extend(t.files);
        all.camera.extend(t.camera);
        all
    }))
}

/// One layer: a handle on its plug-in.
#[derive(Clone, Copy)]
pub struct Layer(&'static dyn SensorLayer);

impl Layer {
    pub const IMAGE: Layer = Layer(&image::Image);
    pub const CAMERA: Layer = Layer(&camera::Camera);
    pub const RAYS: Layer = Layer(&rays::Rays);
    pub const POINTS: Layer = Layer(&points::Points);
    pub const PANORAMAS: Layer = Layer(&panoramas::Panoramas);

    /// The registry: every layer, in the order they are listed, written and recorded.
    pub const ALL: [Layer; 8] = [
        Layer::IMAGE,
        Layer::CAMERA,
        Layer::RAYS,
        Layer(&range::Range),
        Layer(&range16::Range16),
        Layer(&ids::Ids),
        Layer::PANORAMAS,
        Layer::POINTS,
    ];

    pub fn name(self) -> &'static str {
        self.0.name()
    }

    pub fn about(self) -> &'static str {
        self.0.about()
    }

    /// Its files (`*`: any plain suffix).
    pub fn files(self) -> &'static [&'static str] {
        self.0.files()
    }

    /// The layer named `name`.
    pub fn named(name: &str) -> Option<Layer> {
        Layer::ALL.into_iter().find(|l| l.name() == name)
    }

    fn bit(self) -> u16 {
        let at = (Layer::ALL.iter()).position(|l| *l == self);
        1 << at.expect("every layer is in the registry")
    }
}

impl PartialEq for Layer {
    fn eq(&self, other: &Layer) -> bool {
        self.name() == other.name()
    }
}

impl Eq for Layer {}

impl fmt::Debug for Layer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Layer({})", self.name())
    }
}

/// A choice of layers, and whether a keyword (`all`, `default`) made it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layers(u16);

/// The bit of [`Layers`] that says a keyword chose them, above every layer's.
const KEYWORD: u16 = 1 << 15;
const _: () = assert!(
    Layer::ALL.len() < 15,
    "a layer's bit must stay below KEYWORD's"
);

impl Layers {
    /// The layers a keyword takes: those `take` says.
    fn keyword(take: impl Fn(&dyn SensorLayer) -> bool) -> Self {
        let taken = Layer::ALL.into_iter().filter(|l| take(l.0));
        Layers(taken.fold(KEYWORD, |bits, l| bits | l.bit()))
    }

    /// Every layer there is, chosen by no keyword: what any frame's files may be.
    pub fn every() -> Self {
        Layers(Layer::ALL.iter().fold(0, |bits, l| bits | l.bit()))
    }

    /// `all`: every layer that says so (the camera image only where there is an imaging
    /// chain to make it, [`Self::for_scene`]); the range once, as floats, not again as
    /// `range16`'s millimetres.
    pub fn all() -> Self {
        Self::keyword(|l| l.in_all())
    }

    /// What a dataset writes unless asked otherwise (`default`): every layer of [`Self::all`]
    /// but the ray map and the point cloud, which the pose and one frame's ray map give again
    /// (the sensor is rigid on the robot) and which are most of a frame's bytes (2.7 and
    /// 1.9 MB of a thesis-room frame at 512²: docs/sensor.md).
    pub fn standard() -> Self {
        Self::keyword(|l| l.in_all() && l.in_default())
    }

    /// What a single render's sensor outputs hold (`SensorOutputs::write`): the layers of
    /// `all` that say so.
    pub fn single_render() -> Self {
        Self::keyword(|l| l.in_all() && l.in_single_render())
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

    /// The layers a scene can have: those that need a camera model only with an imaging
    /// chain.
    pub fn for_scene(self, imaging: bool) -> Self {
        let needing = Layer::ALL.into_iter().filter(|l| l.0.needs_camera_model());
        match imaging {
            true => self,
            false => needing.fold(self, Layers::without),
        }
    }

    /// The layers chosen that need a camera model (refused by name where there is none).
    pub fn needing_camera_model(self) -> impl Iterator<Item = Layer> {
        self.iter().filter(|l| l.0.needs_camera_model())
    }

    /// The samples the layers' files of `frame` hold ([`SensorLayer::samples`]).
    pub fn samples(self, frame: &SensorOutputs) -> u64 {
        self.iter().map(|layer| layer.0.samples(frame)).sum()
    }

    /// Every file a frame of these layers holds, `camera.json` first.
    pub fn files(self) -> Vec<&'static str> {
        let mut files = vec![CAMERA_FILE];
        files.extend(self.iter().flat_map(|l| l.files().iter().copied()));
        files
    }
}

/// The layers and the keywords as a help text says them (`specchio dataset --outputs`): each
/// layer's name and what it holds, then what `all` and `default` leave out.
pub fn help() -> String {
    let layers: Vec<String> = (Layer::ALL.iter())
        .map(|l| format!("{} ({})", l.name(), l.about()))
        .collect();
    let left_out = |keyword: Layers, from: Layers| {
        let out: Vec<&str> = (from.iter())
            .filter(|l| !keyword.has(*l))
            .map(Layer::name)
            .collect();
        out.join(" and ")
    };
    format!(
        "The layers each frame holds, comma-separated: {}; or all: every layer the scene has but \
         {}; or default (what a dataset writes unless asked): all but {}. camera.json and \
         pose.json always",
        layers.join(", "),
        left_out(Layers::all(), Layers::every()),
        left_out(Layers::standard(), Layers::all()),
    )
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
            let layer =
                (Layer::ALL.into_iter().find(|l| l.name() == word)).ok_or_else(|| match word {
                    "" => format!(
                        "`{text}`: an empty layer name; the layers: {}, or all, or default",
                        names()
                    ),
                    "all" | "default" => format!(
                        "`{word}` stands alone, not among layer names (`{text}`): give `{word}`, \
                         or the layers by name"
                    ),
                    _ => format!("`{word}` is not a layer: {}, or all, or default", names()),
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
mod registry_tests;
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
        let e = "all,image".parse::<Layers>().unwrap_err();
        assert_eq!(
            e,
            "`all` stands alone, not among layer names (`all,image`): give `all`, or the layers \
             by name"
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
        assert!(!Layers::all().for_scene(false).has(Layer::CAMERA));
        assert!(
            !Layers::all().has(Layer::named("range16").unwrap()),
            "all has the range once, as floats"
        );
        let mm: Layers = "range16".parse().unwrap();
        assert_eq!(mm.files(), ["camera.json", RANGE16_FILE]);
    }
}
