//! Where the robot's images come from: a mirror lookup of the GPU renderer (the simulator the
//! user would build on) or the exact CPU reference (the stand-in for the real mirror). Each
//! source is one robot that renders a list of poses and describes every image.

use std::sync::Arc;

use anyhow::{bail, Result};
use glam::Vec3;
use specchio::image::RgbaImage;
use specchio::process::progress::Progress;
use specchio::reference::objects::MeshTrees;
use specchio::reference::Reference;
use specchio::render::{Readback, RenderOptions, Renderer};
use specchio::scene::camera::ViewBasis;
use specchio::scene::state::SceneState;
use specchio::scene::{Lookup, ObjectFrame, RefreshPolicy, Scene, SensorCamera};
use specchio::sensor::localise::{Descriptor, Signature};
use specchio::sensor::panorama::PanoramaLayout;
use specchio::sensor::SensorOptics;
use specchio::vk::device::Device;

/// The name of the exact reference among `--sources`.
pub const REFERENCE: &str = "reference";

/// One image source of the experiment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    Lookup(Lookup),
    Reference,
}

impl Source {
    pub fn name(self) -> &'static str {
        match self {
            Self::Lookup(l) => l.name(),
            Self::Reference => REFERENCE,
        }
    }
}

/// A `--sources` entry (a clap value parser).
pub fn parse(text: &str) -> Result<Source, String> {
    match text.trim() {
        REFERENCE => Ok(Source::Reference),
        t => Lookup::parse(t).map(Source::Lookup).ok_or_else(|| {
            format!(
                "`{text}` is not a source: `{REFERENCE}` or a lookup ({})",
                Lookup::names()
            )
        }),
    }
}

/// A pose to image: where the mirror is and which way the robot faces (radians about +Y).
pub type Pose = (Vec3, f64);

/// What every robot shares: the scene it carries, and the unwrap of its images in its own
/// frame (the robot does not know its heading, so it unwraps with the unturned optics).
pub struct Body {
    pub scene: Scene,
    pub layout: PanoramaLayout,
    pub optics: SensorOptics,
}

impl Body {
    /// The sensor turned by `heading`: the camera, its misalignment included, turns with
    /// the robot.
    fn turned_sensor(&self, heading: f64) -> SensorCamera {
        SensorCamera {
            heading_rad: heading as f32,
            ..self.scene.sensor.clone()
        }
    }
}

/// A robot whose images come from one source.
pub enum Robot<'a> {
    /// One renderer, reused for every pose: the mirror is moved and the cube re-rendered.
    Gpu {
        body: &'a Body,
        renderer: Box<Renderer>,
        frame: u64,
    },
    /// The exact reference: one BVH per scene time, the mirror moved through it per pose.
    Reference { body: &'a Body },
}

impl<'a> Robot<'a> {
    pub fn new(
        body: &'a Body,
        source: Source,
        device: Option<&Arc<Device>>,
        options: &RenderOptions,
    ) -> Result<Self> {
        match source {
            Source::Reference => Ok(Self::Reference { body }),
            Source::Lookup(lookup) => {
                let Some(device) = device else {
                    bail!("no device for the {lookup} source (a bug)");
                };
                let mut scene = body.scene.clone();
                scene.mirror.lookup = lookup;
                let options = RenderOptions {
                    // The robot moves every image: the whole cube is re-rendered anyway.
                    refresh: Some(RefreshPolicy::EveryFrame),
                    // One lookup for the source's life: a traced one makes no cube.
                    lookup_fixed: true,
                    ..options.clone()
                };
                Ok(Self::Gpu {
                    body,
                    renderer: Box::new(Renderer::new(device, scene, &options)?),
                    frame: 0,
                })
            }
        }
    }

    /// The descriptor of the image at every pose, at scene time `t_s`; `what` names the
    /// poses in the progress lines and to `stop`, asked before each image; `whole` counts the
    /// run's images over all its parts ([`whole_run`]).
    pub fn describe(
        &mut self,
        poses: &[Pose],
        t_s: f64,
        descriptor: &dyn Descriptor,
        (what, stop, whole): (&str, super::Stop, Option<&Progress>),
    ) -> Result<Vec<Signature>> {
        // Said first, so that a long loop is never silent; the bar (on a terminal only)
        // counts its images.
        specchio::say_err!("localise: {} {what}", poses.len());
        let bar = indicatif::ProgressBar::new(poses.len() as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} images, {elapsed}")
                .expect("a valid template"),
        );
        // And, past its first seconds, about how long the rest will take, on any stderr.
        let progress = Progress::new(format!("localise: {what}"), poses.len() as u64, "images");
        let check = |i: usize| {
            bar.set_position(i as u64);
            if i > 0 {
                progress.add(1);
                whole.inspect(|w| w.add(1));
            }
            stop(&format!("after {i} of {} {what}", poses.len()))
        };
        let mut out = Vec::with_capacity(poses.len());
        match self {
            Self::Gpu {
                body,
                renderer,
                frame,
            } => {
                for (i, &(p, heading)) in poses.iter().enumerate() {
                    check(i)?;
                    let image = gpu_image(body, renderer, frame, (p, heading), t_s)?;
                    out.push(descriptor.describe(&body.layout.unwrap(&body.optics, &image)));
                }
            }
            Self::Reference { body } => {
                let [w, h] = body.scene.sensor.resolution;
                let meshes = Arc::new(MeshTrees::build(&body.scene.meshes));
                // The mirror moved through one BVH per scene time, unless the robot carries
                // parts of its own (objects in the sensor's frame), which move and turn with
                // it: then the objects' top level is built again at every pose.
                let carried = (body.scene.objects.iter()).any(|o| o.frame == ObjectFrame::Sensor);
                let mut still =
                    (!carried).then(|| Reference::with_meshes(&body.scene, t_s, meshes.clone()));
                for (i, &(p, heading)) in poses.iter().enumerate() {
                    check(i)?;
                    let view = sensor_view(body, heading);
                    // One sample at the pixel centre: the rasterizer's sample point.
                    let (images, _) = match &mut still {
                        Some(reference) => {
                            reference.move_mirror(p);
                            reference.render(&view, w, h, 1)
                        }
                        None => {
                            let sensor = body.turned_sensor(heading);
                            let state = SceneState::at_pose(&body.scene, t_s, (p, &sensor));
                            let posed = Reference::with_state(&body.scene, state, meshes.clone());
                            posed.render(&view, w, h, 1)
                        }
                    };
                    out.push(descriptor.describe(&body.layout.unwrap(&body.optics, &images.color)));
                }
            }
        }
        bar.finish_and_clear();
        // The part's last image (`check` counts each before the next).
        if !poses.is_empty() {
            whole.inspect(|w| w.add(1));
        }
        Ok(out)
    }
}

/// The whole run's images, counted over its parts (each source's landmarks, swept unless
/// `--landmarks` holds them, and its queries at each time), where there is more than one
/// part: each part says its own estimate, and this one says the run's, at the rate so far
/// (rough where sources differ in speed: the reference is the slowest).
pub(super) fn whole_run(plan: &super::Plan) -> Option<Progress> {
    let swept = |s: Source| (plan.saved.as_ref()).is_none_or(|db| db.source != s.name());
    let queries: usize = plan.queries.iter().map(Vec::len).sum();
    let landmarks = plan.landmark_poses.len();
    let parts: usize = (plan.sources.iter())
        .map(|&s| usize::from(swept(s)) + plan.times.len())
        .sum();
    let images: usize = (plan.sources.iter())
        .map(|&s| queries + if swept(s) { landmarks } else { 0 })
        .sum();
    (parts > 1).then(|| {
        let what = format!("localise: the whole run, {parts} parts");
        Progress::new(what, images as u64, "images")
    })
}

/// One sensor image from the GPU renderer with the robot at `pose`.
fn gpu_image(
    body: &Body,
    renderer: &mut Renderer,
    frame: &mut u64,
    (position, heading): Pose,
    t_s: f64,
) -> Result<RgbaImage> {
    renderer.scene.mirror.center = position;
    renderer.scene.sensor = body.turned_sensor(heading);
    let readback = Readback {
        views: true,
        ..Default::default()
    };
    let (_, images) = renderer.render_frame(*frame, t_s, readback)?;
    *frame += 1;
    let Some(image) = images.sensor else {
        bail!("the sensor image was not read back (a bug)");
    };
    Ok(image)
}

/// The reference's sensor camera (render space: below the mirror, looking up) turned by
/// `heading`, as the GPU renderer builds it from the turned sensor.
fn sensor_view(body: &Body, heading: f64) -> ViewBasis {
    let s = body.turned_sensor(heading);
    let [w, h] = s.resolution;
    s.view(s.up, w as f32 / h as f32)
}
