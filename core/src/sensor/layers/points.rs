//! Layer `points`: the point cloud, where each mirror pixel's reflected ray ends, with the id
//! of what it meets, as a binary PLY whose comments say its frame. Not in `default`: the ray
//! map and the range give it again.

use std::path::Path;

use super::{SensorLayer, SensorOutputs, Told, Writing};
use crate::output::OutputError;
use crate::sensor::dataset::{self as sensor_dataset, GeometryFrame};

pub const POINTS_FILE: &str = "points.ply";

pub struct Points;

impl SensorLayer for Points {
    fn name(&self) -> &'static str {
        "points"
    }

    fn about(&self) -> &'static str {
        "points.ply, where each mirror pixel's reflected ray ends, with its id"
    }

    fn files(&self) -> &'static [&'static str] {
        &[POINTS_FILE]
    }

    fn in_default(&self) -> bool {
        false
    }

    /// Not in a single render's outputs: a dataset's, not a single render's.
    fn in_single_render(&self) -> bool {
        false
    }

    /// A point's three coordinates and its id, for every pixel at most (those that met
    /// something are not known before the cloud is made).
    fn samples(&self, frame: &SensorOutputs) -> u64 {
        4 * u64::from(frame.rays.width) * u64::from(frame.rays.height)
    }

    fn write(&self, w: &Writing<'_>, dir: &Path) -> Result<Told, OutputError> {
        let o = w.frame;
        let origin = o.scene_origin;
        let (frame, to) = &o.geometry;
        let comments = [
            match frame {
                GeometryFrame::Scene => format!(
                    "frame: the scene's, local (world = [{}, {}, {}] + point), metres, +Y up",
                    origin.x, origin.y, origin.z
                ),
                other => format!("frame: {}, metres", other.says()),
            },
            "id: the drawable the ray met (sensor.id.json)".to_owned(),
        ];
        // Asked before the cloud is made, as the sink's own encoders ask (`Sink::ready`).
        w.out.ready(&dir.join(POINTS_FILE))?;
        let mut points = sensor_dataset::points(o);
        for (p, _) in &mut points {
            *p = to.point(*p);
        }
        let ply = sensor_dataset::ply::ply(&points, &comments);
        w.out.write_bytes(&dir.join(POINTS_FILE), &ply)?;
        Ok(Told::default())
    }
}
