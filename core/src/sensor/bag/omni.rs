//! The catadioptric model a bag of a central mirror carries (`/omni/camera_info`, the `omni`
//! TF frame and the calibration files as attachments): Mei's unified model as `specchio
//! calibrate` fits it to the exact ray map.
//!
//! `CameraInfo` has no field for the unified model's ξ, and ROS has no distortion model for
//! it; the bag says `distortion_model: "mei"` with `d = [xi, k1, k2, p1, p2]`, the order of
//! camodocal's MEI camera (which VINS and its kin read), and `k` is OpenCV omnidir's K. The
//! `omni` frame sits at the single viewpoint with the sensor camera's axes: the model's frame
//! with its z reversed, since the mirror makes the model's frame left-handed and a TF frame
//! cannot be; a point (x, y, z) in `omni` is the model's (x, y, -z)
//! (`sensor::central::ros`).

use glam::DVec3;

use super::msgs::Intrinsics;
use crate::scene::Scene;
use crate::sensor::central::{export, Calibration, FitError, MeiModel, OcamModel, Watch};
use crate::sensor::SensorOptics;

/// The TF frame of the unified model.
pub const OMNI: &str = "omni";

/// A central mirror's unified model, where the bag puts it.
pub struct Omni {
    pub model: MeiModel,
    pub width: u32,
    pub height: u32,
    /// The single viewpoint in the sensor camera's optical frame (m).
    pub viewpoint_in_camera: DVec3,
    /// The OCamCalib model fitted with it, for the attachments.
    ocam: OcamModel,
}

impl Omni {
    /// Why a central mirror's bag goes without its unified model (its sensor is too large to
    /// calibrate), said by the command and by Python alike; none for a mirror that is not
    /// central, which has no such model to miss.
    pub fn missing(scene: &Scene) -> Option<String> {
        scene
            .mirror
            .shape
            .xi()
            .and_then(|_| Calibration::too_large(scene))
    }

    /// The model of `scene`'s sensor (at time 0: the mount and the optics do not change along
    /// a trajectory), where its mirror is central and small enough to calibrate; the
    /// calibration's parts said to `watch` (every part but the files, which it does not write).
    pub fn of_scene(scene: &Scene, watch: &dyn Watch) -> Result<Option<Self>, FitError> {
        if scene.mirror.shape.xi().is_none() || Self::missing(scene).is_some() {
            return Ok(None);
        }
        let (cal, _) = Calibration::of_scene_watched(scene, 0.0, watch)?;
        let optics = SensorOptics::at(scene, 0.0);
        let view = &optics.view;
        let camera = (view.eye + optics.mirror_center).as_dvec3();
        let v = cal.viewpoint - camera;
        let axis = |a: glam::Vec3| a.as_dvec3().normalize();
        let viewpoint_in_camera = DVec3::new(
            v.dot(axis(view.right)),
            v.dot(axis(view.down)),
            v.dot(axis(view.forward)),
        );
        let (m, w, h) = (cal.mei, cal.width, cal.height);
        Ok(Some(Self {
            model: m,
            width: w,
            height: h,
            viewpoint_in_camera,
            ocam: cal.ocam,
        }))
    }

    /// The files `specchio calibrate` writes for the tools, attached to the bag: (name, media
    /// type, bytes); the Kalibr camchain names `image_topic`, the bag's camera image topic.
    pub fn attachments(&self, image_topic: &str) -> Vec<(&'static str, &'static str, Vec<u8>)> {
        let (m, w, h) = (&self.model, self.width, self.height);
        let yaml = "application/yaml";
        vec![
            (
                "opencv_omnidir.yaml",
                yaml,
                export::opencv_yaml(m, w, h).into_bytes(),
            ),
            (
                "kalibr_camchain.yaml",
                yaml,
                export::kalibr_yaml(m, w, h, image_topic).into_bytes(),
            ),
            (
                "ocamcalib_calib_results.txt",
                "text/plain",
                export::ocamcalib_txt(&self.ocam).into_bytes(),
            ),
        ]
    }

    /// `/omni/camera_info`'s numbers.
    pub fn intrinsics(&self) -> Intrinsics {
        let m = &self.model;
        Intrinsics {
            width: self.width,
            height: self.height,
            distortion_model: "mei".into(),
            d: vec![m.xi, m.k1, m.k2, m.p1, m.p2],
            k: [m.fx, m.skew, m.cx, 0.0, m.fy, m.cy, 0.0, 0.0, 1.0],
        }
    }
}
