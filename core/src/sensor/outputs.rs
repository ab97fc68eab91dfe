//! The sensor outputs of one frame, from the exact reference or from the GPU's cube path, and
//! the files they are written to (`render --sensor-outputs`, `reference --sensor-outputs`;
//! docs/sensor.md lists them).

use std::borrow::Cow;
use std::path::Path;

use glam::{Mat3, Quat, Vec3};
use serde::Serialize;

use super::dataset::geometry::{GeometryFrame, Rigid};
use super::ground_truth::{GroundTruth, GroundTruthRecord};
pub use super::id_map::{IdMap, NO_ID};
use super::imaging::{self, CameraImage};
use super::layers::{self, Entries, Layers};
use super::optics::SensorOptics;
use super::panorama::{mirror_mask, PanoramaKind, PanoramaLayout};
use super::quantities::{PixelHit, Quantity, QuantityImages, DIRECTION_ID, ORIGIN_RANGE};
use super::ray_map::{PixelRay, RayMap};
use crate::image::RgbaImage;
use crate::mirror::MirrorShape;
use crate::output::{OutputError, Sink};
use crate::reference::ReferenceImages;
use crate::scene::Scene;

pub use super::layers::{
    CAMERA_FILE, ID_FILE, ID_MAP_FILE, RANGE16_FILE, RANGE_FILE, RAYS_FILE, RAY_CHANNELS,
};

/// A panorama a frame writes, not made yet ([`SensorOutputs::panorama_plans`]): its name
/// (`sensor.panorama.KIND`, `cube.panorama.KIND`), its layout, and where it is read from.
pub struct PanoramaPlan {
    pub name: String,
    pub layout: PanoramaLayout,
    /// Looked up in the cube map, else unwrapped from the sensor image.
    from_cube: bool,
}

/// One frame's sensor outputs.
#[derive(Debug, Clone)]
pub struct SensorOutputs {
    /// "reference" or "cube (plain lookup)", ... : where the layers come from.
    pub source: String,
    /// Where range and ids come from, and whether the colour image agrees with them.
    pub ground_truth: GroundTruthRecord,
    pub time_s: f64,
    /// The scene's local origin in the file's (world) coordinates: every position written is
    /// local (world = this + local), as the renderer and the reference work in f32 about it.
    pub scene_origin: glam::DVec3,
    pub optics: SensorOptics,
    pub rays: RayMap,
    /// Per pixel, metres along the reflected ray to what it meets (0 off the mirror).
    pub range: Vec<f32>,
    /// What `range` measures (the reference's exact hit, or the cube path's room box).
    pub range_model: &'static str,
    /// Per pixel, the drawable seen through the mirror (walls 0..6 in the cube-face order
    /// +X, -X, +Y, -Y, +Z, -Z, objects 6 + i), [`NO_ID`] for none.
    pub ids: Vec<u32>,
    pub id_model: &'static str,
    /// What each id names.
    pub id_map: IdMap,
    /// The GPU's per-pixel quantities of the ray map (`sensor::quantities`) beyond its own two,
    /// which `rays`, `range` and `ids` hold decoded (a frame a dataset's encoders hold then
    /// costs what it did before the registry); none for the reference. A layer reads any
    /// quantity through [`Self::quantity`], which computes those not held.
    pub gpu_quantities: QuantityImages,
    /// The sensor's colour image the panoramas unwrap.
    pub image: RgbaImage,
    /// The cube map's faces (mip 0), for the panoramas straight from the cube; None for the
    /// reference, which has no cube.
    pub cube: Option<Vec<RgbaImage>>,
    /// The scene azimuth (radians) the panoramas' left edge points along: 0 (the scene's
    /// frame) unless a robot's frame puts its forward axis there (a dataset's frames:
    /// [`PanoramaFrame::seam`](super::panorama::PanoramaFrame::seam)).
    pub panorama_seam_rad: f64,
    /// The frame the ray map (and a dataset's point cloud) is written in, and the map to it
    /// from the scene-local frame: the scene's unless a dataset asks (`--geometry-frame`).
    pub geometry: (GeometryFrame, Rigid),
    /// The image as the scene's camera reports it (`[sensor.imaging]`: noise, exposure,
    /// response, lens), beside the clean `image`; None until [`Self::expose`], and where the
    /// scene has no imaging chain.
    pub camera: Option<CameraImage>,
}

impl SensorOutputs {
    /// From the exact reference's sensor render at `t_s`: the exact ray map, masked where the
    /// pixel centre's ray really reaches the mirror (nothing in front of it), with the
    /// reference's centre-ray distance and object layers.
    pub fn from_reference(scene: &Scene, t_s: f64, images: &ReferenceImages) -> Self {
        let mut rays = RayMap::exact(scene, t_s);
        let seen: Vec<bool> = images.object.pixels.iter().map(|p| p[1] == 1.0).collect();
        for (ray, &seen) in rays.rays.iter_mut().zip(&seen) {
            if !seen {
                *ray = None;
            }
        }
        let range: Vec<f32> = (images.distance.pixels.iter().zip(&seen))
            .map(|(d, &s)| if s { d[0] } else { 0.0 })
            .collect();
        let ids: Vec<u32> = (images.object.pixels.iter().zip(&seen))
            .map(|(o, &s)| if s && o[0] >= 0.0 { o[0] as u32 } else { NO_ID })
            .collect();
        Self {
            source: "reference".into(),
            ground_truth: GroundTruthRecord::new(GroundTruth::Reference, "reference", scene),
            time_s: t_s,
            scene_origin: scene.origin,
            optics: SensorOptics::at(scene, t_s),
            rays,
            range,
            range_model: GroundTruth::Reference.range_model(true),
            ids,
            id_model: GroundTruth::Reference.id_model(true),
            id_map: IdMap::of(scene),
            gpu_quantities: QuantityImages::default(),
            image: images.color.clone(),
            cube: None,
            panorama_seam_rad: 0.0,
            geometry: (GeometryFrame::Scene, Rigid::IDENTITY),
            camera: None,
        }
    }

    /// From the GPU's ray-map pass (`shaders/mirror_ray.frag.glsl`): its `quantities`, of which
    /// [`ORIGIN_RANGE`] gives each mirror pixel's ray origin (render space) and range, and
    /// [`DIRECTION_ID`] the reflected direction and 1 + the id of what it meets (0, the clear
    /// value, off the mirror). `truth` says how they found it: traced, or through the cube's
    /// depth and id cube (where that search finds no hit, the room box's range and the wall
    /// the ray leaves through: `shaders/include/sensor_ray.glsl`); `lookup` made the colour
    /// `image`. The quantities come from the registry, so both are there: the engine's test
    /// holds its shaders' list to it.
    pub fn from_gpu(
        scene: &Scene,
        t_s: f64,
        (lookup, truth): (&str, GroundTruth),
        image: RgbaImage,
        mut quantities: QuantityImages,
        cube: Option<Vec<RgbaImage>>,
    ) -> Self {
        let mut registered = |q: &dyn Quantity| {
            let name = q.name();
            (quantities.remove(name))
                .unwrap_or_else(|| panic!("the ray map's pass writes every quantity: {name}"))
        };
        let (origin_range, direction_id) = (registered(&ORIGIN_RANGE), registered(&DIRECTION_ID));
        let optics = SensorOptics::at(scene, t_s);
        let seen = |d: &[f32; 4]| d[3] > 0.0;
        let pixels = || origin_range.pixels.iter().zip(&direction_id.pixels);
        let rays = pixels()
            .map(|(o, d)| {
                seen(d).then(|| PixelRay {
                    origin: Vec3::new(o[0], o[1], o[2]) + optics.mirror_center,
                    direction: Vec3::new(d[0], d[1], d[2]),
                })
            })
            .collect();
        let source = match truth {
            GroundTruth::Traced => format!("traced ({lookup} lookup)"),
            _ => format!("cube ({lookup} lookup)"),
        };
        let range = pixels()
            .map(|(o, d)| if seen(d) { o[3] } else { 0.0 })
            .collect();
        let ids = (direction_id.pixels.iter())
            .map(|d| if seen(d) { d[3] as u32 - 1 } else { NO_ID })
            .collect();
        Self {
            source,
            ground_truth: GroundTruthRecord::new(truth, lookup, scene),
            time_s: t_s,
            scene_origin: scene.origin,
            optics,
            rays: RayMap {
                width: origin_range.width,
                height: origin_range.height,
                rays,
            },
            range,
            range_model: truth.range_model(truth.exact_for(scene)),
            ids,
            id_model: truth.id_model(truth.exact_for(scene)),
            id_map: IdMap::of(scene),
            gpu_quantities: quantities,
            image,
            cube,
            panorama_seam_rad: 0.0,
            geometry: (GeometryFrame::Scene, Rigid::IDENTITY),
            camera: None,
        }
    }

    /// The image of quantity `q`: the GPU's where the frame holds it, else [`Quantity::of`] on
    /// each mirror pixel's hit (its ray, range and id), computed now: the reference's half, or
    /// for a GPU frame the ray map's own two quantities from what was decoded of them.
    pub fn quantity(&self, q: &dyn Quantity) -> Cow<'_, RgbaImage> {
        if let Some(image) = self.gpu_quantities.get(q.name()) {
            return Cow::Borrowed(image);
        }
        let pixels = (self.rays.rays.iter().zip(&self.range).zip(&self.ids))
            .map(|((ray, &range), &id)| {
                let hit = |r: &PixelRay| PixelHit {
                    mirror_point: r.origin - self.optics.mirror_center,
                    reflected: r.direction,
                    range,
                    id,
                };
                ray.as_ref().map_or([0.0; 4], |r| q.of(&hit(r)))
            })
            .collect();
        Cow::Owned(RgbaImage {
            width: self.rays.width,
            height: self.rays.height,
            pixels,
        })
    }

    /// Per pixel, the class of what it meets ([`IdMap::classes`]), [`NO_ID`] for none: the
    /// class layer beside the ids.
    pub fn class_ids(&self) -> Vec<u32> {
        self.id_map.classes_of(&self.ids)
    }

    /// Makes the camera image of the scene's `[sensor.imaging]` as frame `frame` (its noise
    /// drawn from the scene's seed and this number) from `light`, the image of the whole
    /// exposure (`imaging::integrate`), or the clean image of the frame's instant where it is
    /// None; nothing where the scene has no imaging chain.
    pub fn expose(&mut self, scene: &Scene, frame: u64, light: Option<&RgbaImage>) {
        let light = light.unwrap_or(&self.image);
        self.camera = (scene.sensor.imaging.as_ref())
            .map(|chain| imaging::expose(chain, light, &self.optics, frame));
    }

    /// The panoramas from the sensor image, and from the cube where there is one.
    pub fn panoramas(&self) -> Vec<(String, PanoramaLayout, RgbaImage)> {
        let mirror = self.mirror_mask();
        (self.panorama_plans().into_iter())
            .map(|p| {
                let image = self.panorama(&p, &mirror);
                (p.name, p.layout, image)
            })
            .collect()
    }

    /// Per pixel of the sensor image, whether it shows the mirror: what every panorama
    /// unwrapped from it reads (made once for them all, before they are made in parallel).
    pub fn mirror_mask(&self) -> Vec<bool> {
        mirror_mask(&self.optics, &self.image)
    }

    /// The panoramas this frame has, not made yet: a writer makes each where it writes it
    /// ([`Self::panorama`]), so that a stop between two comes before the next one's work.
    pub fn panorama_plans(&self) -> Vec<PanoramaPlan> {
        let mut all = Vec::new();
        for kind in PanoramaKind::ALL {
            let layout = PanoramaLayout::for_sensor(&self.optics, kind);
            let layout = layout.with_seam(self.panorama_seam_rad);
            all.push(PanoramaPlan {
                name: format!("sensor.panorama.{}", kind.name()),
                layout,
                from_cube: false,
            });
            if self.cube.is_some() {
                all.push(PanoramaPlan {
                    name: format!("cube.panorama.{}", kind.name()),
                    layout,
                    from_cube: true,
                });
            }
        }
        all
    }

    /// `plan`'s panorama; `mirror` is the sensor image's [`Self::mirror_mask`].
    pub fn panorama(&self, plan: &PanoramaPlan, mirror: &[bool]) -> RgbaImage {
        match (&self.cube, plan.from_cube) {
            (Some(faces), true) => plan.layout.from_cube(faces),
            _ => plan.layout.unwrap_within(&self.optics, &self.image, mirror),
        }
    }

    /// Writes the outputs of a single render into `dir` (staged in `out`): the layers of
    /// [`Layers::single_render`] (not the image, which the commands write as their view, nor
    /// the point cloud), and `camera.json`.
    /// `written` is told each layer's samples as it ends, out of [`Self::samples`].
    pub fn write(
        &self,
        out: &(impl Sink + Sync),
        dir: &Path,
        written: &(dyn Fn(u64) + Sync),
    ) -> Result<(), OutputError> {
        self.write_chosen(out, dir, Layers::single_render(), written)
    }

    /// The samples [`Self::write`] writes: the measure of its time, for an estimate.
    pub fn samples(&self) -> u64 {
        Layers::single_render().samples(self)
    }

    /// The `chosen` layers (each a plug-in, `layers/`: written beside each other) and
    /// `camera.json`, which says what each wrote; `written` is told each layer's samples as
    /// it ends.
    pub fn write_chosen(
        &self,
        out: &(impl Sink + Sync),
        dir: &Path,
        chosen: Layers,
        written: &(dyn Fn(u64) + Sync),
    ) -> Result<(), OutputError> {
        let writing = layers::Writing {
            frame: self,
            out,
            written,
        };
        let told = layers::write(&writing, dir, chosen)?;
        out.write_json(&dir.join(CAMERA_FILE), &self.camera_record(told))
    }

    /// `camera.json`: the camera, and what the layers `told` of the files they wrote beside
    /// it.
    pub(crate) fn camera_record(&self, told: layers::Told) -> CameraRecord {
        let o = &self.optics;
        let v = &o.view;
        let rotation = Mat3::from_cols(v.right, v.down, v.forward);
        let (w, h) = (o.width as f32, o.height as f32);
        let ortho = v.is_orthographic();
        CameraRecord {
            source: self.source.clone(),
            ground_truth: self.ground_truth.clone(),
            time_s: self.time_s,
            frame: "the scene frame: world minus scene_origin_m (the mirror's centre at time 0 in \
                    the scene file's coordinates), metres; the camera's axes x right, y down, \
                    z forward (OpenCV's)",
            scene_origin_m: self.scene_origin.to_array(),
            sensor: SensorRecord {
                position_m: (v.eye + o.mirror_center).to_array(),
                camera_to_world: rotation.transpose().to_cols_array_2d(),
                quaternion_xyzw: Quat::from_mat3(&rotation).to_array(),
                right: v.right.to_array(),
                down: v.down.to_array(),
                forward: v.forward.to_array(),
                image_size: [o.width, o.height],
                projection: if ortho { "orthographic" } else { "perspective" },
                fov_x_deg: (!ortho).then(|| 2.0 * v.tan_x.atan().to_degrees()),
                fov_y_deg: (!ortho).then(|| 2.0 * v.tan_y.atan().to_degrees()),
                focal_px: (!ortho).then(|| [0.5 * w / v.tan_x, 0.5 * h / v.tan_y]),
                pixels_per_m: ortho.then(|| [0.5 * w / v.half_x, 0.5 * h / v.half_y]),
                principal_point_px: [0.5 * w, 0.5 * h],
            },
            mirror: MirrorRecord {
                shape: o.shape.name(),
                fields: o.shape.fields().collect(),
                centre_m: o.mirror_center.to_array(),
                cube_centre_m: (o.mirror_center + o.cube_offset).to_array(),
                radius_m: o.radius_m,
                central: CentralRecord::of(&o.shape),
            },
            disc: DiscRecord {
                centre_px: o.disc_centre_px().to_array(),
                radius_px: o.disc_radius_px(),
                rim_angle_deg: o.rim_angle().map(f64::to_degrees),
                max_elevation_deg: o.max_elevation().to_degrees(),
            },
            layers: Entries(told.camera),
            files: Entries(told.files),
        }
    }
}

/// `camera.json`: the sensor's pose and intrinsics, the mirror, its image disc, and the files.
#[derive(Debug, Serialize)]
pub struct CameraRecord {
    pub source: String,
    pub ground_truth: GroundTruthRecord,
    pub time_s: f64,
    pub frame: &'static str,
    /// World (the scene file's coordinates) = this + every position here and in the files.
    pub scene_origin_m: [f64; 3],
    pub sensor: SensorRecord,
    pub mirror: MirrorRecord,
    pub disc: DiscRecord,
    /// What the layers record beside `files`: the camera image's chain (`imaging`), where
    /// that layer was written.
    #[serde(flatten)]
    pub layers: Entries,
    /// The files written beside `camera.json`, as each layer records them.
    pub files: Entries,
}

#[derive(Debug, Serialize)]
pub struct SensorRecord {
    pub position_m: [f32; 3],
    /// Rows of the camera-to-world rotation (its columns are right, down, forward).
    pub camera_to_world: [[f32; 3]; 3],
    /// The same rotation as a unit quaternion (x, y, z, w).
    pub quaternion_xyzw: [f32; 4],
    pub right: [f32; 3],
    pub down: [f32; 3],
    pub forward: [f32; 3],
    pub image_size: [u32; 2],
    /// "perspective" (a pinhole), or "orthographic" (a paraboloid's telecentric camera: its
    /// rays run along `forward` from the image plane through `position_m`).
    pub projection: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fov_x_deg: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fov_y_deg: Option<f32>,
    /// Pinhole intrinsics in pixels: fx, fy, and the principal point (cx, cy), with pixel
    /// (0, 0)'s top-left corner at the origin (its centre at 0.5, 0.5).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub focal_px: Option<[f32; 2]>,
    /// An orthographic camera's scale: image pixels per metre across and down.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pixels_per_m: Option<[f32; 2]>,
    pub principal_point_px: [f32; 2],
}

/// The mirror: `centre_m` is its viewpoint (the sphere's centre, a central mirror's inner
/// focus, a cone's bounding sphere's centre); `radius_m` the radius about it that holds it.
#[derive(Debug, Serialize)]
pub struct MirrorRecord {
    pub shape: &'static str,
    /// The shape's own fields as the scene gave them (`[mirror]`: metres, or degrees for a
    /// cone's `half_angle`).
    pub fields: std::collections::BTreeMap<&'static str, f64>,
    pub centre_m: [f32; 3],
    /// Where the cube map is rendered from: `centre_m` unless the scene's `cube.offset`
    /// moves it.
    pub cube_centre_m: [f32; 3],
    pub radius_m: f32,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub central: Option<CentralRecord>,
}

/// A central mirror's geometry: the unified model's xi its camera at its focus makes, and
/// its rim (radius, and height above the viewpoint).
#[derive(Debug, Serialize)]
pub struct CentralRecord {
    pub xi: f64,
    pub rim_radius_m: f64,
    pub rim_height_m: f64,
    /// The camera's distance below the viewpoint where the shape fixes it (a hyperboloid's
    /// outer focus); none for the paraboloid's orthographic camera.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub camera_distance_m: Option<f64>,
}

impl CentralRecord {
    fn of(shape: &MirrorShape) -> Option<Self> {
        let (rim_radius_m, rim_height_m) = shape.rim()?;
        Some(Self {
            xi: shape.xi()?,
            rim_radius_m,
            rim_height_m,
            camera_distance_m: shape.camera_distance_m(),
        })
    }
}

/// The mirror's image (`optics`): a disc, derived from the pose and the mirror's shape.
#[derive(Debug, Serialize)]
pub struct DiscRecord {
    pub centre_px: [f32; 2],
    pub radius_px: f32,
    /// The rim's angle from a pinhole's axis; none for an orthographic camera.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rim_angle_deg: Option<f64>,
    pub max_elevation_deg: f64,
}
