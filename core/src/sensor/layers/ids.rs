//! Layer `ids`: per pixel, what the reflected ray meets, as 32-bit unsigned ids and classes
//! in one EXR (an id is a name, not a quantity: nothing may blend two), and the id map that
//! says what each id is.

use std::path::Path;

use super::{SensorLayer, SensorOutputs, Told, Writing};
use crate::output::json_text;
use crate::output::OutputError;
use crate::sensor::files::Samples;
use crate::sensor::id_map::NO_ID;

pub const ID_FILE: &str = "sensor.id.exr";
/// What each id of [`ID_FILE`] is: the id map as JSON.
pub const ID_MAP_FILE: &str = "sensor.id.json";

pub struct Ids;

impl SensorLayer for Ids {
    fn name(&self) -> &'static str {
        "ids"
    }

    fn about(&self) -> &'static str {
        "sensor.id.exr and sensor.id.json, the id and class of what each reflected ray meets"
    }

    fn files(&self) -> &'static [&'static str] {
        &[ID_FILE, ID_MAP_FILE]
    }

    /// The id and the class a pixel (the map is small).
    fn samples(&self, frame: &SensorOutputs) -> u64 {
        2 * u64::from(frame.rays.width) * u64::from(frame.rays.height)
    }

    fn write(&self, w: &Writing<'_>, dir: &Path) -> Result<Told, OutputError> {
        let o = w.frame;
        let ids = vec![
            ("id", Samples::U32(o.ids.clone())),
            ("class", Samples::U32(o.class_ids())),
        ];
        let size = (o.rays.width, o.rays.height);
        w.out.write_channels(&dir.join(ID_FILE), size, ids)?;
        let map = dir.join(ID_MAP_FILE);
        // Asked before the encoding, as the sink's own encoders ask (`Sink::ready`).
        w.out.ready(&map)?;
        w.out
            .write_bytes(&map, json_text(&map, &o.id_map)?.as_bytes())?;
        Ok(Told {
            files: vec![
                ("ids", super::record(ID_FILE)),
                ("id_model", super::record(o.id_model)),
                ("id_map", super::record(ID_MAP_FILE)),
                ("no_id", super::record(NO_ID)),
            ],
            ..Told::default()
        })
    }
}
