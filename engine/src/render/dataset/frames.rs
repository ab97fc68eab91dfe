//! A dataset's frames: the robot's renderer ([`FrameWriter`]), what one render leaves to
//! encode ([`Rendered`]), and the pipeline that encodes frames' files on encoder threads
//! while the GPU renders the next ([`FrameWriter::frames`]).
//!
//! Why a pipeline: a frame's files (about 25 MB at 512²: EXR layers, two panoramas resampled
//! and encoded twice, PNG previews, a point cloud) cost the CPU more than the render costs
//! the device. On lavapipe a frame rendered in about 100 ms and encoded in about 270 ms; on
//! an NVIDIA H200 the whole frame took 400 ms, as long as on two CPU cores (docs/gpu.md).
//! Encoding beside the render, and each frame's independent files at the same time, takes
//! the encoding off the render's path.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::sync::{Arc, Mutex};

use super::{gpu_failed, place_robot, robot_scene};
use crate::image::RgbaImage;
use crate::output::{MemoryFiles, OutputError, Sink};
use crate::render::{lookups, Readback, RenderOptions, Renderer};
use crate::scene::{Lookup, Scene};
use crate::sensor::dataset::motion;
use crate::sensor::dataset::trajectory::Pose;
use crate::sensor::dataset::{self as sensor_dataset, IndexLine, PoseRecord};
use crate::sensor::dataset::{rep103, DatasetError, Frame, GeometryFrame, INDEX_FILE};
use crate::sensor::imaging;
use crate::sensor::layers::{Layer, Layers};
use crate::sensor::panorama::PanoramaFrame;
use crate::sensor::{GroundTruth, SensorOutputs};
use crate::vk::device::Device;
use crate::vk::GpuError;

/// A frame rendered and read back: everything its files are made from, no device in it.
pub struct Rendered {
    frame: usize,
    outputs: SensorOutputs,
    record: PoseRecord,
    /// The layers its files hold.
    layers: Layers,
}

impl Rendered {
    /// The frame's files, encoded in memory, the independent ones at the same time.
    pub fn encode(self) -> Result<Frame, DatasetError> {
        let folder = sensor_dataset::frame_folder(self.frame);
        let root = Path::new("");
        let files = MemoryFiles::new(root);
        let dir = root.join(&folder);
        write_frame(&files, &dir, &self.outputs, &self.record, self.layers)?;
        let index_line = IndexLine::of(&self.record).map_err(|e| OutputError::Encode {
            path: PathBuf::from(INDEX_FILE),
            message: e.to_string(),
        })?;
        Ok(Frame {
            frame: self.frame,
            files: files.into_files(),
            index_line,
        })
    }
}

/// A renderer whose mirror stands at a pose: the robot's sensor, frame by frame.
pub struct FrameWriter {
    renderer: Renderer,
    /// The scene as loaded: poses are placed relative to it.
    scene: Scene,
    lookup: Lookup,
    truth: GroundTruth,
    /// Frames encoded at the same time by [`FrameWriter::frames`].
    encoders: usize,
    /// Whose frame the panoramas are in (the robot's unless set: [`Self::set_panoramas`]).
    panoramas: PanoramaFrame,
    /// The frame the ray map and point cloud are in ([`Self::set_geometry_frame`]).
    geometry: GeometryFrame,
    /// The layers a frame's files hold (all the scene has unless set: [`Self::set_layers`]).
    layers: Layers,
    /// The trajectory the frames are poses of, by frame number, for the robot's motion during
    /// an exposure ([`Self::set_path`]); without it the robot stands still in each.
    path: Option<Arc<[Pose]>>,
}

impl FrameWriter {
    /// A renderer of `scene`'s robot on `device` with `lookup` (see
    /// [`choose_lookup`](super::choose_lookup)).
    pub fn new(device: &Arc<Device>, scene: &Scene, lookup: Lookup) -> Result<Self, GpuError> {
        // The traced ray map needs no id cube.
        let id_cube = !lookups::traces_ray_map(lookup);
        // The cube counted where this lookup makes one (the plan counted none).
        let face = match lookups::needs_cube(lookup, id_cube) {
            true => scene.cube.face_size_px,
            false => 0,
        };
        crate::memory::estimates::dataset(scene, face, 1)
            .map_err(|e| GpuError::OverBudget(format!("{lookup} lookup: {e}")))?;
        let options = RenderOptions {
            lookup: Some(lookup),
            id_cube,
            // One lookup for the writer's life: a traced one makes no cube.
            lookup_fixed: true,
            ..Default::default()
        };
        let renderer = Renderer::new(device, robot_scene(scene), &options)?;
        let truth = renderer.sensor_ground_truth();
        Ok(FrameWriter {
            renderer,
            scene: scene.clone(),
            lookup,
            truth,
            encoders: encoders_for(scene, face),
            panoramas: PanoramaFrame::Robot,
            geometry: GeometryFrame::Scene,
            layers: Layers::standard().for_scene(scene.sensor.imaging.is_some()),
            path: None,
        })
    }

    pub fn lookup(&self) -> Lookup {
        self.lookup
    }

    /// Where range and ids come from on this device with this lookup.
    pub fn ground_truth(&self) -> GroundTruth {
        self.truth
    }

    /// The sensor outputs of frame `frame`: the mirror moved and turned to `pose`, rendered at
    /// its time. The observer's view, rendered beside it, is returned too.
    pub fn outputs(
        &mut self,
        frame: usize,
        pose: &Pose,
    ) -> Result<(SensorOutputs, crate::image::RgbaImage), DatasetError> {
        let (outputs, observer) = self.render_outputs(frame, pose, true)?;
        let observer = observer.ok_or(DatasetError::NotReadBack { frame })?;
        Ok((outputs, observer))
    }

    /// [`Self::outputs`], with the observer's view drawn and read back only when `observer`
    /// (a dataset's frame has no use for it: the sensor's view alone is drawn).
    fn render_outputs(
        &mut self,
        frame: usize,
        pose: &Pose,
        observer: bool,
    ) -> Result<(SensorOutputs, Option<crate::image::RgbaImage>), DatasetError> {
        // The camera image, and its exposure's renders, only where a frame holds it.
        let camera = self.layers.has(Layer::CAMERA);
        let light = match camera {
            true => self.exposure(frame, pose)?,
            false => None,
        };
        let r = &mut self.renderer;
        place_robot(&mut r.scene, &self.scene, pose);
        let readback = Readback {
            views: observer,
            sensor: true,
            rays: true,
            ..Default::default()
        };
        let (_, images) =
            (r.render_frame(frame as u64, pose.time_s, readback)).map_err(gpu_failed)?;
        let missing = || DatasetError::NotReadBack { frame };
        let quantities = images.sensor_quantities.ok_or_else(missing)?;
        let sensor = images.sensor.ok_or_else(missing)?;
        let name = self.lookup.to_string();
        let mut outputs = SensorOutputs::from_gpu(
            &r.scene,
            pose.time_s,
            (&name, self.truth),
            sensor,
            quantities,
            None,
        );
        outputs.panorama_seam_rad = self.panoramas.seam(pose.heading_deg.to_radians());
        // base_link as pose.json places it (`PoseRecord::new`).
        let base = (
            rep103::point(pose.position),
            rep103::robot_orientation(pose.heading_deg),
        );
        let to = self.geometry.from_scene(outputs.scene_origin, base);
        outputs.geometry = (self.geometry, to);
        if camera {
            outputs.expose(&r.scene, frame as u64, light.as_ref());
        }
        Ok((outputs, images.observer))
    }

    /// The light of frame `frame`'s whole exposure at `pose` (`imaging::integrate`): the
    /// sensor's view at each of its instants, the robot where its path puts it then, the
    /// scene's animations where they are; None for an exposure of one instant.
    fn exposure(&mut self, frame: usize, pose: &Pose) -> Result<Option<RgbaImage>, DatasetError> {
        let Some(imaging) = self.scene.sensor.imaging.clone() else {
            return Ok(None);
        };
        let (r, scene) = (&mut self.renderer, &self.scene);
        let path = self.path.as_deref().filter(|p| frame < p.len());
        imaging::integrate(&imaging, pose.time_s, |t| {
            let at = match path {
                Some(path) => motion::pose_at(path, frame, t),
                None => Pose {
                    time_s: t,
                    ..pose.clone()
                },
            };
            place_robot(&mut r.scene, scene, &at);
            let readback = Readback {
                sensor: true,
                ..Default::default()
            };
            let (_, images) = (r.render_frame(frame as u64, t, readback)).map_err(gpu_failed)?;
            images.sensor.ok_or(DatasetError::NotReadBack { frame })
        })
    }

    /// Frame `frame` at `pose`, rendered; its files still to encode.
    pub fn render(&mut self, frame: usize, pose: &Pose) -> Result<Rendered, DatasetError> {
        let (outputs, _) = self.render_outputs(frame, pose, false)?;
        let record = PoseRecord::new(frame, pose, &outputs.optics, outputs.scene_origin);
        Ok(Rendered {
            frame,
            outputs,
            record,
            layers: self.layers,
        })
    }

    /// Frame `frame` of a dataset, at `pose`: its files, in memory.
    pub fn frame(&mut self, frame: usize, pose: &Pose) -> Result<Frame, DatasetError> {
        self.render(frame, pose)?.encode()
    }

    /// How many frames may encode at the same time; 0 encodes each frame on the calling
    /// thread after it renders (no pipeline: the least memory).
    pub fn set_encoders(&mut self, encoders: usize) {
        self.encoders = encoders;
    }

    /// Unwraps the panoramas in `frame`'s frame (a dataset's `Plan::panoramas`).
    pub fn set_panoramas(&mut self, frame: PanoramaFrame) {
        self.panoramas = frame;
    }

    /// Writes the ray map and the point cloud in `frame` (a dataset's `Plan::geometry`).
    pub fn set_geometry_frame(&mut self, frame: GeometryFrame) {
        self.geometry = frame;
    }

    /// The robot follows `path` (a dataset's poses, by frame number) during each frame's
    /// exposure, for the camera image's motion blur.
    pub fn set_path(&mut self, path: &[Pose]) {
        self.path = Some(path.into());
    }

    /// Writes only the `layers` chosen into a frame's files (a dataset's `Plan::outputs`).
    pub fn set_layers(&mut self, layers: Layers) {
        self.layers = layers;
    }

    /// The frames `poses` (index, pose) in order, each given to `take` on this thread.
    /// Frames are encoded on encoder threads while the next ones render; `between(i)` runs
    /// before frame `i` renders, and an error from it, `take` or a frame stops the run (the
    /// frames already given stay given; a frame's error is reported in the frames' order).
    /// Besides the frame rendering, at most one more frame than there are encoders is held:
    /// encoding, encoded and waiting for an earlier one, or being taken.
    pub fn frames<'p>(
        &mut self,
        poses: impl IntoIterator<Item = (usize, &'p Pose)>,
        between: &mut dyn FnMut(usize) -> Result<(), DatasetError>,
        take: &mut dyn FnMut(Frame) -> Result<(), DatasetError>,
    ) -> Result<(), DatasetError> {
        let encoders = self.encoders;
        if encoders == 0 {
            for (i, pose) in poses {
                between(i)?;
                take(self.frame(i, pose)?)?;
            }
            return Ok(());
        }
        // A rendezvous: a frame is handed over only to an encoder that is free.
        let (to_encode, rendered) = sync_channel::<(usize, Rendered)>(0);
        let rendered = Mutex::new(rendered);
        std::thread::scope(|s| {
            // Room for every encoder's result, so that no encoder waits on the caller.
            let (to_take, encoded) = sync_channel(encoders);
            for n in 0..encoders {
                let (rendered, to_take) = (&rendered, to_take.clone());
                let encoder = move || encode_until_closed(rendered, to_take);
                let started = (std::thread::Builder::new().name(format!("specchio-encoder-{n}")))
                    .spawn_scoped(s, encoder);
                if let Err(e) = started {
                    // The encoders started wait for frames: closing the channel ends them,
                    // or the scope would wait for them forever.
                    drop(to_encode);
                    let why = format!("cannot start a frame encoder: {e}");
                    return Err(DatasetError::Stopped(why));
                }
            }
            drop(to_take);
            // Owns the caller's ends of the channels: however it returns, they close, and
            // each encoder ends after the frame it is on.
            let run = move || {
                let mut order = InOrder::new(encoders);
                for (i, pose) in poses {
                    between(i)?;
                    let job = self.render(i, pose)?;
                    order.make_room(&encoded, take)?;
                    to_encode.send((order.sent, job)).map_err(|_| gone())?;
                    order.sent += 1;
                    // The earlier frames ready, taken while this one encodes.
                    while order.next_ready() {
                        order.take_next(take)?;
                    }
                }
                drop(to_encode);
                while order.taken < order.sent {
                    match order.next_ready() {
                        true => order.take_next(take)?,
                        false => order.receive(&encoded)?,
                    }
                }
                Ok(())
            };
            run()
        })
    }
}

/// An encoder: takes rendered frames until the caller closes its end, and sends back each
/// one's files or error. A panic while encoding becomes that frame's error, so that every
/// frame handed out comes back and the caller never waits for a lost one.
fn encode_until_closed(
    rendered: &Mutex<Receiver<(usize, Rendered)>>,
    to_take: SyncSender<(usize, Result<Frame, DatasetError>)>,
) {
    loop {
        let job = rendered.lock().map(|r| r.recv());
        let Ok(Ok((seq, job))) = job else {
            return; // the caller is done, or stopped
        };
        let frame = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| job.encode()))
            .unwrap_or_else(|panic| {
                let why = (panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_default();
                Err(DatasetError::Stopped(format!(
                    "a frame encoder failed (a bug): {why}"
                )))
            });
        if to_take.send((seq, frame)).is_err() {
            return;
        }
    }
}

/// The frames handed out and back, and the ones back early: encoders finish out of order,
/// and frames (or their errors) are taken in order.
struct InOrder {
    encoders: usize,
    sent: usize,
    received: usize,
    taken: usize,
    early: BTreeMap<usize, Result<Frame, DatasetError>>,
}

impl InOrder {
    fn new(encoders: usize) -> Self {
        InOrder {
            encoders,
            sent: 0,
            received: 0,
            taken: 0,
            early: BTreeMap::new(),
        }
    }

    /// Waits until an encoder is free and at most `encoders` frames are held, taking the
    /// frames next in order while that is what holds the room.
    fn make_room(
        &mut self,
        encoded: &Receiver<(usize, Result<Frame, DatasetError>)>,
        take: &mut dyn FnMut(Frame) -> Result<(), DatasetError>,
    ) -> Result<(), DatasetError> {
        loop {
            let free = self.sent - self.received < self.encoders;
            let room = self.sent - self.taken <= self.encoders;
            if free && room {
                return Ok(());
            }
            // Without room the next frame in order is ready or still encoding; without a
            // free encoder one is encoding. Either way the wait ends.
            match !room && self.next_ready() {
                true => self.take_next(take)?,
                false => self.receive(encoded)?,
            }
        }
    }

    /// Waits for the next frame an encoder finishes.
    fn receive(
        &mut self,
        encoded: &Receiver<(usize, Result<Frame, DatasetError>)>,
    ) -> Result<(), DatasetError> {
        let (seq, frame) = encoded.recv().map_err(|_| gone())?;
        self.received += 1;
        self.early.insert(seq, frame);
        Ok(())
    }

    fn next_ready(&self) -> bool {
        self.early.contains_key(&self.taken)
    }

    /// Gives `take` the next frame in order (ready), or returns its error.
    fn take_next(
        &mut self,
        take: &mut dyn FnMut(Frame) -> Result<(), DatasetError>,
    ) -> Result<(), DatasetError> {
        let frame = self.early.remove(&self.taken).ok_or_else(gone)?;
        self.taken += 1;
        take(frame?)
    }
}

/// The encoders ended with frames still out: they cannot, each frame comes back (a panic as
/// its error), so this is a bug made visible instead of a hang.
fn gone() -> DatasetError {
    DatasetError::Stopped("a frame encoder stopped without its frame".into())
}

/// Encoders for this machine and `scene`: a quarter of the cores, 1 to 4, and no more than the
/// memory budget holds frames for (a held frame is its outputs and files: about 83 MB at a
/// 512² sensor); 0 (no pipeline) where it holds only the frame rendering. Each frame's encoding is parallel already (its files at once, EXR chunks and
/// panorama rows on rayon's pool); more encoders fill the stretches that are not (a PNG's
/// deflate, the point cloud).
fn encoders_for(scene: &Scene, face_size_px: u32) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    encoders_within(cores, |held| {
        crate::memory::estimates::dataset(scene, face_size_px, held).is_ok()
    })
}

/// [`encoders_for`] on `cores` cores, where `fits(n)` says whether `n` frames fit in memory.
fn encoders_within(cores: usize, fits: impl Fn(u64) -> bool) -> usize {
    let mut encoders = (cores / 4).clamp(1, 4);
    // The frame rendering, and at most one more held than there are encoders.
    while encoders > 0 && !fits(encoders as u64 + 2) {
        encoders -= 1;
    }
    encoders
}

/// A frame's folder: the pose, and the `layers` chosen (each written beside the others).
fn write_frame(
    out: &(impl Sink + Sync),
    dir: &Path,
    o: &SensorOutputs,
    pose: &PoseRecord,
    layers: Layers,
) -> Result<(), OutputError> {
    out.write_json(&dir.join(sensor_dataset::POSE_FILE), pose)?;
    o.write_chosen(out, dir, layers, &|_| {})
}

#[cfg(test)]
mod tests {
    use super::encoders_within;

    #[test]
    fn encoders_are_a_quarter_of_the_cores_within_memory() {
        let any = |_| true;
        assert_eq!(encoders_within(1, any), 1);
        assert_eq!(encoders_within(2, any), 1);
        assert_eq!(encoders_within(8, any), 2);
        assert_eq!(encoders_within(16, any), 4);
        assert_eq!(encoders_within(128, any), 4);
        // Memory for four frames: the one rendering and three held for two encoders.
        assert_eq!(encoders_within(16, |held| held <= 4), 2);
        // Memory for two: no pipeline, each frame encoded after it renders.
        assert_eq!(encoders_within(16, |held| held <= 2), 0);
        assert_eq!(encoders_within(16, |_| false), 0);
    }
}
