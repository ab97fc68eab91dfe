//! Scenes: the TOML file format, its validation, the resolved scene the renderer draws, the
//! scene's state at a time ([`state`]) and its cameras ([`camera`]). No Vulkan here: the exact
//! reference and the metrics use these types too.
//!
//! A scene file is parsed by [`load`] into a [`Scene`]: every mesh is triangulated in object
//! space, every material and texture is resolved to an index, and every value has been checked
//! (a bad value is a [`SceneError`] that names the file, line and field). The renderer never
//! sees the TOML; it sees only these types.
//!
//! World conventions (see `docs/conventions.md`): right-handed, +Y up, metres, seconds.

use std::path::PathBuf;

use glam::{DVec3, Quat, Vec2, Vec3};

use crate::mirror::MirrorShape;

mod anim;
mod asset;
pub mod camera;
mod error;
mod fixed;
mod format;
pub(crate) mod generate;
pub mod imaging;
mod load;
mod mesh;
pub mod pixel_rect;
pub mod state;
mod texture;

pub use crate::files::{
    read_regular_file, FileError, MAX_GLTF_BUFFER_BYTES, MAX_MESH_FILE_BYTES, MAX_SCENE_BYTES,
    MAX_TEXTURE_FILE_BYTES,
};
pub(crate) use anim::segment_distance;
pub use anim::{
    is_heading, is_scene_time, Animation, Repeat, HEADING_RULE, MAX_HEADING_DEG, MAX_SCENE_TIME_S,
    SCENE_TIME_RULE,
};
pub use asset::AssetError;
pub use error::{Location, SceneError};
pub use load::{imaging_str, load, load_str};
pub use mesh::{Mesh, MAX_MESH_INDICES, MAX_MESH_VERTICES};
pub use texture::{TextureData, MAX_TEXTURE_SIZE_PX};

/// Largest cube face the format accepts (texels per side); larger is an error, not a clamp.
pub const MAX_FACE_SIZE_PX: u32 = 8192;
/// The most samples along a mirror pixel's footprint (`[cube] anisotropy`): 16, the largest
/// maxAnisotropy GPUs offer; more would cost a sample each for footprints rarely that long.
pub const MAX_ANISOTROPY: u32 = 16;
/// The most repeats of a material's pattern per unit of texture coordinate (`tiles`), 2^20:
/// the shaders place a point in its cell from uv x tiles in single precision, which keeps 4
/// bits below the cell (a sixteenth of it) at uv = 1 with this many; 3e38 overflowed to
/// infinity there and wrote NaN pixels.
pub const MAX_TILES: f32 = 1_048_576.0;
/// The largest magnitude of a mesh's texture coordinate: uv x [`MAX_TILES`] stays far below
/// single precision's overflow (uv 1e38 made it infinite, and the pixel NaN).
pub const MAX_UV: f32 = 1e15;
/// Largest view image the format accepts on either side (pixels).
pub const MAX_IMAGE_SIZE_PX: u32 = 8192;

/// A fully validated scene, ready to render.
///
/// Every position in it (room, mirror, objects, cameras, animation points) is *local*:
/// relative to [`Scene::origin`], the mirror's centre at time 0. The file's coordinates are
/// f64; they are recentred in f64 and only then rounded to f32, so a scene placed 10^5 m from
/// the world origin renders exactly as it does at the origin (f32 alone would have 8 mm steps
/// there). Directions, sizes and scales are not positions and are unchanged.
#[derive(Debug, Clone)]
pub struct Scene {
    /// World position (the file's coordinates) of the local origin: world = origin + local.
    pub origin: DVec3,
    /// The file the scene came from (relative paths inside it were resolved against its folder).
    pub source: PathBuf,
    /// Free text from the file's `description`, for reports.
    pub description: String,
    pub room: Room,
    pub mirror: Mirror,
    /// Everything drawn into the cube map and the views besides the room and the mirror.
    pub objects: Vec<Object>,
    /// Triangle meshes in object space, referenced by [`Object::mesh`] and [`Room`].
    pub meshes: Vec<Mesh>,
    /// Materials referenced by index from objects and room walls.
    pub materials: Vec<Material>,
    /// Decoded PNG textures referenced by [`MaterialKind::Texture`].
    pub textures: Vec<TextureData>,
    pub observer: Camera,
    pub sensor: SensorCamera,
    pub cube: CubeSettings,
    pub refresh: RefreshPolicy,
    /// `None`: unlit albedo, as in the thesis.
    pub light: Option<DirectionalLight>,
}

impl Scene {
    /// The one of the robot's own parts (objects in the sensor's frame) that would reach farthest
    /// out of the room with the mirror's viewpoint at `mirror_center` and the sensor camera
    /// `sensor`, and how far (m, to the millimetre, at least 1 mm): every vertex of every part is
    /// placed and tested, so a mast that ends just above the floor passes and one lowered
    /// through it does not.
    pub fn robot_part_outside_room(
        &self,
        mirror_center: Vec3,
        sensor: &SensorCamera,
    ) -> Option<(&Object, f32)> {
        let lo = self.room.center - 0.5 * self.room.size_m;
        let hi = self.room.center + 0.5 * self.room.size_m;
        let frame = sensor.frame();
        let carried = self
            .objects
            .iter()
            .filter(|o| o.frame == ObjectFrame::Sensor);
        carried
            .map(|o| {
                let (at, turn) = o.placement(frame, mirror_center, 0.0);
                let out = (self.meshes[o.mesh].positions.iter())
                    .map(|&v| at + turn * (o.scale * v))
                    .map(|p| (lo - p).max(p - hi).max_element())
                    .fold(0.0f32, f32::max);
                (o, out)
            })
            .filter(|&(_, out)| out > 0.0)
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(o, out)| (o, ((out * 1000.0).round() / 1000.0).max(0.001)))
    }

    /// Whether anything in the scene moves with time (an animated object, mirror or observer):
    /// a still scene looks the same at every time, so a viewer need not draw it again.
    pub fn moves(&self) -> bool {
        self.mirror.animation.is_some()
            || self.observer.animation.is_some()
            || self.objects.iter().any(|o| o.animation.is_some())
    }
}

/// The room: an axis-aligned box seen from inside.
#[derive(Debug, Clone)]
pub struct Room {
    /// Centre of the box in world space (metres).
    pub center: Vec3,
    /// Full extent along x, y, z (metres), all > 0.
    pub size_m: Vec3,
    /// Material index of each wall, in cube-face order: +X, -X, +Y (ceiling), -Y (floor), +Z, -Z.
    pub wall_materials: [usize; 6],
}

/// The spherical mirror. It is analytic everywhere: never tessellated, never in the cube map.
#[derive(Debug, Clone)]
pub struct Mirror {
    /// The viewpoint at time 0 (world, metres): the sphere's centre, a central mirror's
    /// inner focus. The cube map is rendered from here.
    pub center: Vec3,
    /// The radius of the sphere about `center` that holds the whole mirror (metres, > 0;
    /// the sphere's own radius): objects and cameras stay outside it.
    pub radius_m: f32,
    /// The surface (`mirror.shape`).
    pub shape: MirrorShape,
    /// Moves the centre over time; `None` keeps it still.
    pub animation: Option<Animation>,
    /// How the reflected direction looks up the cube map.
    pub lookup: Lookup,
    /// The `distance` lookup's linear search: steps from the mirror to infinity
    /// (`mirror.distance_steps`, 1..=[`MAX_DISTANCE_STEPS`]).
    pub distance_steps: u32,
    /// The `distance` lookup's secant refinements of the bracket the linear search found
    /// (`mirror.secant_steps`, 0..=[`MAX_SECANT_STEPS`]).
    pub secant_steps: u32,
}

/// Default linear search steps of the `distance` lookup (GPU Gems 3 ch. 17 used 10 to 30).
pub const DEFAULT_DISTANCE_STEPS: u32 = 16;
/// Default secant refinements of the `distance` lookup.
pub const DEFAULT_SECANT_STEPS: u32 = 2;
/// Upper limits of the two (a ray's cost grows linearly with each).
pub const MAX_DISTANCE_STEPS: u32 = 256;
pub const MAX_SECANT_STEPS: u32 = 32;

/// Makes [`Lookup`] from the registry's entries (`crate::lookup_registry`): the variants with
/// their docs, their names (serde's too), and `ALL` in the registry's order.
macro_rules! lookup_enum {
    ($( $(#[$doc:meta])* $variant:ident = $name:literal => $plugin:path; )*) => {
        /// How the mirror turns a reflected ray into a cube-map lookup direction. The
        /// variants are the registry's (`crate::lookup_registry`); what each needs and does
        /// lives in its plug-in (`render::lookups`): the scene only names it.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
        pub enum Lookup {
            $( $(#[$doc])* #[serde(rename = $name)] $variant, )*
        }

        impl Lookup {
            /// Every lookup, in the order the CLI, `specchio info` and the docs list them.
            pub const ALL: [Lookup; [$($name),*].len()] = [$(Lookup::$variant),*];

            /// The name in scene files, on the command line and in every report (kebab-case).
            pub fn name(self) -> &'static str {
                match self {
                    $(Lookup::$variant => $name,)*
                }
            }
        }
    };
}

crate::lookup_registry::with_lookups!(lookup_enum);

/// The registry's first: the thesis's lookup.
impl Default for Lookup {
    fn default() -> Self {
        Lookup::ALL[0]
    }
}

impl Lookup {
    pub fn parse(name: &str) -> Option<Lookup> {
        Self::ALL.into_iter().find(|l| l.name() == name)
    }

    /// Every name, comma-separated (for error messages and help).
    pub fn names() -> String {
        Self::ALL.map(Lookup::name).join(", ")
    }
}

impl std::fmt::Display for Lookup {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The class of an object whose scene file gives none.
pub const DEFAULT_CLASS: &str = "object";
/// The longest class name a scene file may give (bytes).
pub const MAX_CLASS_LEN: usize = 64;

/// One drawable object: a mesh instance with a material and a rigid transform.
#[derive(Debug, Clone)]
pub struct Object {
    /// Name from the file (or `objects[i]`), for reports and debug labels.
    pub name: String,
    /// What kind of thing it is (`chair`; [`DEFAULT_CLASS`] when the file does not say): the
    /// label of its pixels in the sensor's class layer.
    pub class: String,
    /// Index into [`Scene::meshes`].
    pub mesh: usize,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// What it is drawn as: `box`, `sphere`, `cylinder`, or `mesh FILE` (the file as the
    /// scene names it), for reports and the sensor's id map.
    pub shape: String,
    /// Whose frame `position` and `rotation` are in: the scene's, or the sensor camera's
    /// (a part of the robot: the camera's body, its lens barrel, a mount).
    pub frame: ObjectFrame,
    /// Position of the object's origin at time 0 (scene space, metres), or, in the sensor's
    /// frame, its offset from the camera's eye along the camera's axes.
    pub position: Vec3,
    /// Orientation (object to world, or to the camera's axes in the sensor's frame).
    pub rotation: Quat,
    /// Per-axis scale, all > 0.
    pub scale: Vec3,
    /// Moves the position over time; `None` keeps it still.
    pub animation: Option<Animation>,
}

/// Whose frame an object is placed in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObjectFrame {
    /// The scene's: it stays where the file puts it unless its animation moves it.
    World,
    /// The sensor camera's (docs/conventions.md "View space": origin at the eye, x right,
    /// y down, z forward towards the mirror): it moves and turns with the camera, so with the
    /// mirror's animation and with every pose a dataset or the localisation stands the robot
    /// at. It has no animation of its own.
    Sensor,
}

impl Object {
    /// Where the object is and how it is turned (scene space) when the mirror's viewpoint is at
    /// `mirror_center`, the sensor camera's frame is `sensor_frame` ([`SensorCamera::frame`],
    /// found once by the caller for every object) and `t_s` is the time its own animation is
    /// evaluated at.
    pub fn placement(
        &self,
        sensor_frame: (Vec3, Quat),
        mirror_center: Vec3,
        t_s: f64,
    ) -> (Vec3, Quat) {
        match self.frame {
            ObjectFrame::World => {
                let position = match &self.animation {
                    Some(a) => a.position_at(self.position, t_s),
                    None => self.position,
                };
                (position, self.rotation)
            }
            ObjectFrame::Sensor => {
                let (eye, axes) = sensor_frame;
                (
                    mirror_center + eye + axes * self.position,
                    axes * self.rotation,
                )
            }
        }
    }
}

/// A material: an albedo function of the surface point. Evaluated identically by
/// `shaders/include/materials.glsl` (GPU) and by the CPU reference.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    pub name: String,
    pub kind: MaterialKind,
}

/// What a material computes. Colours are linear RGB in [0, 1].
#[derive(Debug, Clone, PartialEq)]
pub enum MaterialKind {
    /// A constant albedo.
    Color { color: Vec3 },
    /// Squares alternating between `a` and `b`; `tiles` squares per unit of texture coordinate.
    Checker { a: Vec3, b: Vec3, tiles: f32 },
    /// Lines of colour `line` on `background`; `tiles` cells per unit of texture coordinate,
    /// lines `line_width` wide as a fraction of a cell (0, 0.5].
    Grid {
        background: Vec3,
        line: Vec3,
        tiles: f32,
        line_width: f32,
    },
    /// An image, repeated `tiles` times per unit of texture coordinate, tinted by `tint`.
    Texture {
        texture: usize,
        tint: Vec3,
        tiles: f32,
    },
    /// Colour = 0.5 + 0.5 * normalize(p - mirror centre): a known answer for every direction,
    /// used to test the cube-face orientation.
    Direction,
}

/// A perspective camera.
#[derive(Debug, Clone)]
pub struct Camera {
    /// Position at time 0 (world, metres).
    pub position: Vec3,
    /// Rotation about +Y in degrees; 0 looks along -Z, 90 looks along -X.
    pub yaw_deg: f32,
    /// Elevation in degrees, in (-90, 90); positive looks up.
    pub pitch_deg: f32,
    /// Vertical field of view in degrees, in [0.1, 179.99] (docs/scene-format.md says why).
    pub fov_y_deg: f32,
    /// Image size in pixels (width, height).
    pub resolution: [u32; 2],
    /// Moves the position over time; `None` keeps it still.
    pub animation: Option<Animation>,
}

/// The catadioptric sensor: a camera fixed below the mirror, looking straight up at it.
#[derive(Debug, Clone)]
pub struct SensorCamera {
    /// Distance below the mirror centre (metres), > radius: the camera sits at centre - offset * Y.
    pub offset_m: f32,
    /// Vertical field of view in degrees, in [0.1, 179.99].
    pub fov_y_deg: f32,
    /// Image size in pixels (width, height).
    pub resolution: [u32; 2],
    /// The image's up direction in world space (must not be parallel to +Y); default -Z.
    pub up: Vec3,
    /// The camera moved off where the mirror puts it (metres, world axes): an assembly's
    /// misalignment (`sensor.shift`); zero by default.
    pub shift_m: Vec3,
    /// The camera's axis turned this far (degrees) about the world X axis, from +Y towards
    /// +Z (`sensor.tilt`); 0 by default.
    pub tilt_deg: f32,
    /// Half the height (m) of an orthographic camera's image (a paraboloid's); 0 for a
    /// pinhole, whose vertical field of view is `fov_y_deg`.
    pub orthographic_half_m: f32,
    /// The robot's heading (radians about +Y): turns the image's up, the shift and the tilt
    /// with it. 0 from the scene file; the localisation turns the robot.
    pub heading_rad: f32,
    /// The camera's imaging chain (`[sensor.imaging]`): where the scene gives one, a noisy
    /// camera image is made beside the clean one.
    pub imaging: Option<imaging::Imaging>,
}

impl SensorCamera {
    /// Where the camera is relative to the mirror's viewpoint (m): `offset_m` below it, moved
    /// by the (turned) shift.
    pub fn eye(&self) -> Vec3 {
        Vec3::new(0.0, -self.offset_m, 0.0) + Quat::from_rotation_y(self.heading_rad) * self.shift_m
    }

    /// The camera's eye relative to the mirror's viewpoint and the rotation from its axes
    /// (x right, y down, z forward) to the world's: the frame of the objects placed in it
    /// ([`ObjectFrame::Sensor`]).
    pub fn frame(&self) -> (Vec3, Quat) {
        let v = self.view(self.up, 1.0);
        let axes = glam::Mat3::from_cols(v.right, v.down, v.forward);
        (v.eye, Quat::from_mat3(&axes).normalize())
    }

    /// The camera in render space (the mirror's viewpoint at the origin), its image's up
    /// direction `up` (world), for an image of aspect `aspect` (width / height).
    pub fn view(&self, up: Vec3, aspect: f32) -> camera::ViewBasis {
        let turn = Quat::from_rotation_y(self.heading_rad);
        let eye = self.eye();
        let forward = turn * (Quat::from_rotation_x(self.tilt_deg.to_radians()) * Vec3::Y);
        let up = turn * up;
        if self.orthographic_half_m > 0.0 {
            return camera::ViewBasis::orthographic(
                eye,
                forward,
                up,
                self.orthographic_half_m,
                aspect,
            );
        }
        camera::ViewBasis::look(eye, forward, up, self.fov_y_deg, aspect)
    }
}

/// How the cube map is made.
#[derive(Debug, Clone, PartialEq)]
pub struct CubeSettings {
    /// Texels per face side, in 1..=MAX_FACE_SIZE_PX.
    pub face_size_px: u32,
    /// Texel format of the colour faces.
    pub format: CubeFormat,
    /// Where the cube is rendered from, relative to the mirror's viewpoint (metres; it moves
    /// with the mirror): zero by default, inside the mirror's reach.
    pub offset_m: Vec3,
    /// Near and far planes of the six 90-degree projections (metres): by default half the
    /// clearance from the cube's centre to the mirror's reach, and 1.01 x the farthest room
    /// corner's distance from the cube's centre; never clipping what the mirror shows (the
    /// near plane's corners inside the reach, far >= that distance).
    pub near_m: f32,
    pub far_m: f32,
    /// Build a full mip chain after each fill (trilinear lookups).
    pub mipmaps: bool,
    /// The most samples the mirror's footprint filter takes along a pixel's footprint, in
    /// 1..=[`MAX_ANISOTROPY`] (1: isotropic trilinear; shaders/include/footprint_filter.glsl).
    pub anisotropy: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CubeFormat {
    /// RGBA 16-bit float: linear HDR (the default).
    Rgba16Float,
    /// RGBA 8-bit unorm: the thesis's format; cheaper, banding in dark gradients.
    Rgba8Unorm,
}

/// The default far plane, as a multiple of the farthest room corner's distance from the cube's
/// centre (a margin so that rounding never clips the corner itself). Nothing outside the room
/// can be seen.
pub const FAR_MARGIN: f32 = 1.01;

/// When the cube map is re-rendered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RefreshPolicy {
    /// Every frame, whether anything moved or not.
    EveryFrame,
    /// Only when something that the cube sees (an object or the mirror) moved since the last fill.
    OnChange,
    /// Every n-th frame (n >= 1), counting from frame 0.
    EveryN(u32),
}

/// One directional light; shading becomes albedo * (ambient + (1 - ambient) * max(0, N.L)).
#[derive(Debug, Clone, PartialEq)]
pub struct DirectionalLight {
    /// Unit vector pointing from the surface towards the light (world).
    pub direction: Vec3,
    /// Fraction of albedo seen in full shadow, in [0, 1].
    pub ambient: f32,
}

/// Convenience for code that needs both a 2D texture coordinate and a position.
pub type Uv = Vec2;
