//! One dataset frame read back from its files, as the bag's messages need it: the bag is made
//! from the frame folders a run wrote, so that it holds exactly what they hold.

use glam::{DQuat, DVec3};

use super::BagError;
use crate::sensor::dataset::{GeometryFrame, PoseRecord, POSE_FILE};
pub use crate::sensor::imaging::CAMERA_IMAGE_FILE;
use crate::sensor::layers::{CAMERA_FILE, ID_FILE, IMAGE_FILES, POINTS_FILE};
use crate::sensor::layers::{RANGE16_FILE, RANGE_FILE};

/// Reads file `name` of frame `frame`: `None` where the frame has no such file (a layer not
/// chosen).
pub type ReadFile<'a> = dyn Fn(usize, &str) -> Result<Option<Vec<u8>>, BagError> + 'a;

/// A pose in ROS's `map`: a frame's origin and the rotation taking its axes to map's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placed {
    pub position: DVec3,
    pub rotation: DQuat,
}

impl Placed {
    /// `other` seen from this frame.
    pub fn to_local(&self, other: &Placed) -> Placed {
        let inverse = self.rotation.inverse();
        Placed {
            position: inverse * (other.position - self.position),
            rotation: (inverse * other.rotation).normalize(),
        }
    }
}

/// What a frame's pose and camera records say.
pub struct FramePose {
    pub time_s: f64,
    pub base_link: Placed,
    pub camera: Placed,
    /// The scene file's heading (degrees): the odometry's turn rate.
    pub heading_deg: f64,
}

impl FramePose {
    pub fn read(read: &ReadFile, frame: usize) -> Result<Self, BagError> {
        let bytes = need(read, frame, POSE_FILE)?;
        let r: PoseRecord = serde_json::from_slice(&bytes).map_err(|e| BagError::Frame {
            frame,
            file: POSE_FILE,
            why: e.to_string(),
        })?;
        let quat = |q: [f64; 4]| DQuat::from_array(q).normalize();
        Ok(Self {
            time_s: r.time_s,
            base_link: Placed {
                position: DVec3::from_array(r.ros.base_link_position_m),
                rotation: quat(r.ros.base_link_quaternion_xyzw),
            },
            camera: Placed {
                position: DVec3::from_array(r.ros.camera_optical_position_m),
                rotation: quat(r.ros.camera_optical_quaternion_xyzw),
            },
            heading_deg: r.scene.heading_deg,
        })
    }

    /// The bag's time stamp: the pose's time in nanoseconds, plus the bag's offset.
    pub fn stamp_ns(&self) -> u64 {
        super::stamp_ns(self.time_s)
    }
}

/// The sensor camera as `camera.json` describes it: its image size, and its pinhole
/// intrinsics where it is a perspective camera (a telecentric one has none).
pub struct CameraRecord {
    pub width: u32,
    pub height: u32,
    /// fx, fy, cx, cy in ROS's (OpenCV's) pixel coordinates, where pixel (0, 0)'s centre is
    /// the origin; `camera.json` puts its top-left corner there, half a pixel away.
    pub pinhole: Option<[f64; 4]>,
}

impl CameraRecord {
    pub fn read(read: &ReadFile, frame: usize) -> Result<Self, BagError> {
        let bytes = need(read, frame, CAMERA_FILE)?;
        let bad = |why: String| BagError::Frame {
            frame,
            file: CAMERA_FILE,
            why,
        };
        let v: serde_json::Value =
            serde_json::from_slice(&bytes).map_err(|e| bad(e.to_string()))?;
        let num = |pointer: &str| {
            (v.pointer(pointer).and_then(serde_json::Value::as_f64))
                .ok_or_else(|| bad(format!("no number at {pointer}")))
        };
        let side = |pointer: &str| {
            let n = num(pointer)?;
            match n >= 1.0 && n <= f64::from(u32::MAX) && n.fract() == 0.0 {
                true => Ok(n as u32),
                false => Err(bad(format!("{pointer} is {n}, not an image side"))),
            }
        };
        let (width, height) = (side("/sensor/image_size/0")?, side("/sensor/image_size/1")?);
        let pinhole = match v.pointer("/sensor/projection").and_then(|p| p.as_str()) {
            Some("perspective") => Some([
                num("/sensor/focal_px/0")?,
                num("/sensor/focal_px/1")?,
                num("/sensor/principal_point_px/0")? - 0.5,
                num("/sensor/principal_point_px/1")? - 0.5,
            ]),
            _ => None,
        };
        Ok(Self {
            width,
            height,
            pinhole,
        })
    }
}

/// An image in a `sensor_msgs` encoding, its rows packed.
pub struct RawImage {
    pub width: u32,
    pub height: u32,
    pub encoding: &'static str,
    pub bytes_per_pixel: u32,
    pub data: Vec<u8>,
}

/// The camera image (`sensor.camera.png`) as the camera gives it: `rgb16` (the code in the
/// top bits, as the PNG holds it) or `rgb8`, little-endian.
pub fn camera_image(read: &ReadFile, frame: usize) -> Result<Option<RawImage>, BagError> {
    let Some(bytes) = read(frame, CAMERA_IMAGE_FILE)? else {
        return Ok(None);
    };
    let bad = |why: String| BagError::Frame {
        frame,
        file: CAMERA_IMAGE_FILE,
        why,
    };
    let (info, buf) = decode_png(&bytes).map_err(bad)?;
    let (encoding, bytes_per_pixel) = match (info.color_type, info.bit_depth) {
        (::png::ColorType::Rgb, ::png::BitDepth::Eight) => ("rgb8", 3),
        (::png::ColorType::Rgb, ::png::BitDepth::Sixteen) => ("rgb16", 6),
        (colour, depth) => return Err(bad(format!("{colour:?} {depth:?}, not RGB 8 or 16"))),
    };
    Ok(Some(RawImage {
        width: info.width,
        height: info.height,
        encoding,
        bytes_per_pixel,
        data: buf,
    }))
}

/// The clean image (`sensor.png`, sRGB) as `rgb8`.
pub fn clean_image(read: &ReadFile, frame: usize) -> Result<Option<RawImage>, BagError> {
    let file = IMAGE_FILES[1];
    let Some(bytes) = read(frame, file)? else {
        return Ok(None);
    };
    let (width, height, rgba) = crate::image::png::decode_rgba8(&bytes, u32::MAX)
        .map_err(|why| BagError::Frame { frame, file, why })?;
    let data = rgba
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    Ok(Some(RawImage {
        width,
        height,
        encoding: "rgb8",
        bytes_per_pixel: 3,
        data,
    }))
}

/// The range (`32FC1`, metres along the reflected ray; NaN off the mirror, as REP-117 asks of
/// a float range with no return, where the file says 0), the range in millimetres (`16UC1`, 0
/// for no return, as its PNG), and the ids and classes (`32SC1`, -1 for none).
pub fn range_and_ids(
    read: &ReadFile,
    frame: usize,
) -> Result<Vec<(&'static str, RawImage)>, BagError> {
    let mut out = Vec::new();
    let channels = |file: &'static str| -> Result<_, BagError> {
        let Some(bytes) = read(frame, file)? else {
            return Ok(None);
        };
        let layer = crate::image::exr::decode_channels(&bytes).map_err(|e| BagError::Frame {
            frame,
            file,
            why: e.to_string(),
        })?;
        Ok(Some(layer))
    };
    let missing = |file: &'static str, channel: &str| BagError::Frame {
        frame,
        file,
        why: format!("no channel `{channel}` of the type it is written with"),
    };
    let image = |(w, h): (usize, usize), encoding, data: Vec<u8>| RawImage {
        width: w as u32,
        height: h as u32,
        encoding,
        bytes_per_pixel: 4,
        data,
    };
    if let Some(layer) = channels(RANGE_FILE)? {
        let range = crate::image::exr::f32_channel(&layer.channels, "range")
            .ok_or_else(|| missing(RANGE_FILE, "range"))?;
        // No surface meets a ray at distance 0: a 0 is a pixel without a ray.
        let no_return = |v: f32| if v == 0.0 { f32::NAN } else { v };
        let data = range
            .iter()
            .flat_map(|&v| no_return(v).to_le_bytes())
            .collect();
        out.push(("range", image(layer.size, "32FC1", data)));
    }
    if let Some(bytes) = read(frame, RANGE16_FILE)? {
        let bad = |why: String| BagError::Frame {
            frame,
            file: RANGE16_FILE,
            why,
        };
        let (info, buf) = decode_png(&bytes).map_err(bad)?;
        if (info.color_type, info.bit_depth)
            != (::png::ColorType::Grayscale, ::png::BitDepth::Sixteen)
        {
            return Err(bad(format!(
                "{:?} {:?}, not 16-bit grey",
                info.color_type, info.bit_depth
            )));
        }
        let size = (info.width as usize, info.height as usize);
        out.push((
            "range_mm",
            RawImage {
                bytes_per_pixel: 2,
                ..image(size, "16UC1", buf)
            },
        ));
    }
    if let Some(layer) = channels(ID_FILE)? {
        for name in ["id", "class"] {
            let ids = crate::image::exr::u32_channel(&layer.channels, name)
                .ok_or_else(|| missing(ID_FILE, name))?;
            // 2^32 - 1 (none) is -1 as a signed 32-bit integer; no id or class comes near 2^31.
            let data = ids.iter().flat_map(|&v| (v as i32).to_le_bytes()).collect();
            out.push((name, image(layer.size, "32SC1", data)));
        }
    }
    Ok(out)
}

/// A point of a cloud: its scene-local position and the id of what it is on.
pub type Point = ([f32; 3], u32);

/// The point cloud (`points.ply`), whose header must say it is in `geometry` (a frame
/// rendered for another dataset's choice is refused, not moved by the wrong transform).
pub fn points(
    read: &ReadFile,
    frame: usize,
    geometry: GeometryFrame,
) -> Result<Option<Vec<Point>>, BagError> {
    let Some(bytes) = read(frame, POINTS_FILE)? else {
        return Ok(None);
    };
    let bad = |why: &str| BagError::Frame {
        frame,
        file: POINTS_FILE,
        why: why.to_owned(),
    };
    let end = b"end_header\n";
    let at = (bytes.windows(end.len()).position(|w| w == end))
        .ok_or_else(|| bad("no end_header line"))?;
    let (header, body) = (
        String::from_utf8_lossy(&bytes[..at]),
        &bytes[at + end.len()..],
    );
    let said = (header.lines()).find_map(|l| l.strip_prefix("comment frame: "));
    if said.and_then(GeometryFrame::of_ply_comment) != Some(geometry) {
        let why = format!(
            "its header says the frame is `{}`, not the dataset's {geometry} frame",
            said.unwrap_or("(none)")
        );
        return Err(bad(&why));
    }
    if body.len() % 16 != 0 {
        return Err(bad("its body is not whole points of 16 bytes"));
    }
    let f = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    Ok(Some(
        body.chunks_exact(16)
            .map(|p| {
                let id = u32::from_le_bytes([p[12], p[13], p[14], p[15]]);
                ([f(&p[0..]), f(&p[4..]), f(&p[8..])], id)
            })
            .collect(),
    ))
}

/// A PNG's header and samples as stored, but 16-bit samples little-endian, as a message holds
/// them (PNG stores them big-endian); the error is a message for the caller to place.
fn decode_png(bytes: &[u8]) -> Result<(::png::OutputInfo, Vec<u8>), String> {
    let decoder = ::png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
    let size = reader.output_buffer_size().ok_or("too large")?;
    let mut buf = vec![0; size];
    let info = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    buf.truncate(info.buffer_size());
    if info.bit_depth == ::png::BitDepth::Sixteen {
        for pair in buf.chunks_exact_mut(2) {
            pair.swap(0, 1);
        }
    }
    Ok((info, buf))
}

fn need(read: &ReadFile, frame: usize, file: &'static str) -> Result<Vec<u8>, BagError> {
    read(frame, file)?.ok_or(BagError::Frame {
        frame,
        file,
        why: "missing".into(),
    })
}
