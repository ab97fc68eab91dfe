//! Loading and validating scene files.
//!
//! Parsing happens twice over the same text: once into toml's spanned document tree
//! ([`DeTable`]), which knows where every key and value sits, and once through serde into the
//! plain structs of `format.rs`. Validation works on the plain structs and names each value by
//! its dotted field path (`objects[2].size`); the path is looked up in the spanned tree to get
//! the line and column. One string is thus both the message's field name and the key to its
//! position, so they cannot disagree.

mod animation;
mod budget;
mod cameras;
mod clearance;
mod cube;
mod generators;
mod imaging;
mod locate;
mod materials;
mod mirror_shape;
mod numbers;
mod objects;
mod room;
mod sensor;
mod source;
#[cfg(test)]
mod tests;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};
use toml::de::DeTable;

use super::anim::Animation;
use super::error::SceneError;
use super::format::*;
use super::generate::Surroundings;
use super::mesh::Mesh;
use super::{Camera, Material, Mirror, Object, Room, Scene, SensorCamera};
use crate::files::{read_regular_file, MAX_SCENE_BYTES};
use locate::Locator;
use objects::MeshStore;

type R<T> = Result<T, SceneError>;
/// Builds a mesh on first use (the loader caches meshes by a key describing them).
type MeshBuilder = Box<dyn Fn() -> Result<Mesh, String>>;

/// How many evenly spaced times an animation is checked at (plus its keyframes).
const ANIMATION_SAMPLES: usize = 64;
/// Tessellation of `shape = "sphere"` objects: 48 segments and, as for every sphere, half as
/// many rings (see `objects::unit_shape`).
const SPHERE_SEGMENTS: u32 = 48;
/// Tessellation of `shape = "cylinder"` objects.
const CYLINDER_SEGMENTS: u32 = 48;

/// Reads and validates the scene file at `path`. Relative asset paths inside it are resolved
/// against the folder that contains it.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let bytes = read_regular_file(path, MAX_SCENE_BYTES).map_err(|e| SceneError::Io {
        file: path.to_path_buf(),
        source: e.into(),
    })?;
    let text = source::decode(path, bytes)?;
    load_str(&text, path)
}

/// Validates scene text as if it had been read from `path` (used in messages and to resolve
/// relative asset paths against `path`'s folder; the file itself is not read).
pub fn load_str(text: &str, path: &Path) -> Result<Scene, SceneError> {
    let doc = DeTable::parse(text).map_err(|e| source::syntax_error(path, text, &e))?;
    if doc.get_ref().is_empty() {
        return Err(SceneError::Empty {
            file: path.to_path_buf(),
        });
    }
    let locator = Locator {
        file: path,
        text,
        root: doc,
    };
    let spec: SceneFile = toml::from_str(text).map_err(|e| locator.serde_error(&e))?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    // Every position is stored relative to the mirror's centre (see `Scene::origin`); a
    // non-finite centre is reported by `mirror()`, so any origin will do until then.
    let origin = spec
        .mirror
        .as_ref()
        .map(|m| DVec3::from_array(m.center))
        .filter(|c| c.is_finite())
        .unwrap_or(DVec3::ZERO);
    Ctx {
        loc: locator,
        dir,
        origin,
    }
    .scene(spec)
}
/// A camera's imaging chain alone: `text` holds a `[sensor.imaging]` table and nothing else,
/// checked as a scene file's is, `name` naming it in messages. How a caller outside a scene
/// file states a camera (Python's `Scene(path, imaging={...})`).
pub fn imaging_str(text: &str, name: &Path) -> Result<super::imaging::Imaging, SceneError> {
    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Only {
        sensor: OnlySensor,
    }
    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct OnlySensor {
        imaging: ImagingSpec,
    }
    let doc = DeTable::parse(text).map_err(|e| source::syntax_error(name, text, &e))?;
    let loc = Locator {
        file: name,
        text,
        root: doc,
    };
    let spec: Only = toml::from_str(text).map_err(|e| loc.serde_error(&e))?;
    let ctx = Ctx {
        loc,
        dir: PathBuf::new(),
        origin: DVec3::ZERO,
    };
    ctx.imaging(&spec.sensor.imaging)
}

// ---------------------------------------------------------------------------------------------
// Validation.

struct Ctx<'a> {
    loc: Locator<'a>,
    dir: PathBuf,
    /// World position of the scene's local origin (the mirror's centre at time 0).
    origin: DVec3,
}

impl Ctx<'_> {
    fn invalid(&self, field: &str, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            location: self.loc.location(field),
            field: field.to_string(),
            message: message.into(),
        }
    }

    fn missing(&self, field: &str, why: &str) -> SceneError {
        self.invalid(field, format!("required field is missing ({why})"))
    }

    fn unused(&self, field: &str, why: &str) -> SceneError {
        self.invalid(field, format!("not allowed here: {why}"))
    }

    /// The validated scene, built in the order its parts depend on each other.
    fn scene(&self, spec: SceneFile) -> R<Scene> {
        let (room_spec, mirror_spec) = self.required_tables(&spec)?;

        let mut textures = Vec::new();
        let materials = self.materials(&spec.materials, &mut textures)?;
        let by_name = material_indices(&materials);
        let material_index =
            |field: &str, name: &str| self.material_index(&by_name, &materials, field, name);

        let room = self.room(room_spec, &material_index)?;
        let mirror = self.mirror(mirror_spec, &room)?;
        // Before any mesh is built: a room f32 cannot hold fails here.
        let extent = self.extent(&room, &mirror)?;

        let mut store = MeshStore::default();
        let mut objects = self.listed_objects(&spec, &material_index, &mut store)?;
        let observer = self.observer(spec.observer.as_ref(), &room, &mirror)?;
        let sensor = self.sensor(spec.sensor.as_ref(), &room, &mirror)?;
        // Generated objects come after the file's own, and keep clear of the cameras.
        let surroundings = surroundings(&room, &mirror, &sensor, &observer);
        let origins = self.generated_objects(
            &spec,
            &material_index,
            &room,
            &surroundings,
            &mut store,
            &mut objects,
        )?;
        let cube = self.cube(spec.cube.as_ref(), &mirror, extent)?;
        let refresh = self.refresh(spec.refresh.as_ref())?;
        let light = self.light(spec.light.as_ref())?;

        let scene = Scene {
            origin: self.origin,
            source: self.loc.file.to_path_buf(),
            description: spec.description.clone().unwrap_or_default(),
            room,
            mirror,
            objects,
            meshes: store.meshes,
            materials,
            textures,
            observer,
            sensor,
            cube,
            refresh,
            light,
        };
        self.objects_clear_of_mirror(&scene, &origins)?;
        self.robot_inside_room(&scene)?;
        Ok(scene)
    }

    /// The [room] and [mirror] tables, which every scene must have.
    fn required_tables<'s>(&self, spec: &'s SceneFile) -> R<(&'s RoomSpec, &'s MirrorSpec)> {
        let Some(room_spec) = &spec.room else {
            return Err(self.invalid("room", "missing [room] table (every scene needs a room)"));
        };
        let Some(mirror_spec) = &spec.mirror else {
            return Err(self.invalid("mirror", "missing [mirror] table (every scene needs one)"));
        };
        Ok((room_spec, mirror_spec))
    }

    /// The index of the material called `name`, referred to at `field`.
    fn material_index(
        &self,
        by_name: &HashMap<&str, usize>,
        materials: &[Material],
        field: &str,
        name: &str,
    ) -> R<usize> {
        by_name.get(name).copied().ok_or_else(|| {
            self.invalid(
                field,
                format!(
                    "unknown material \"{name}\" (defined: {})",
                    some_names(materials)
                ),
            )
        })
    }

    /// The file's own [[objects]], after the scene's object budget is checked.
    fn listed_objects(
        &self,
        spec: &SceneFile,
        material_index: &dyn Fn(&str, &str) -> R<usize>,
        store: &mut MeshStore,
    ) -> R<Vec<Object>> {
        // Counted before any object is made; triangles summed as objects are resolved, and a
        // generator's before it is expanded.
        self.object_budget(spec)?;
        let mut objects = Vec::with_capacity(spec.objects.len());
        for (i, o) in spec.objects.iter().enumerate() {
            objects.push(self.object(i, o, material_index, store)?);
        }
        Ok(objects)
    }

    /// Expands each [[generate]] table onto the end of `objects`; returns where every object
    /// came from, listed ones included.
    fn generated_objects(
        &self,
        spec: &SceneFile,
        material_index: &dyn Fn(&str, &str) -> R<usize>,
        room: &Room,
        surroundings: &Surroundings,
        store: &mut MeshStore,
        objects: &mut Vec<Object>,
    ) -> R<Vec<clearance::Origin>> {
        let mut origins: Vec<clearance::Origin> =
            (0..objects.len()).map(clearance::Origin::Listed).collect();
        for (i, g) in spec.generate.iter().enumerate() {
            let made = self.generated(i, g, material_index, room, surroundings, store)?;
            origins.extend(made.iter().map(|_| clearance::Origin::Generated(i)));
            objects.extend(made);
        }
        Ok(origins)
    }
}

/// Material indices by name: a map, not a scan per object, since scenes may hold many
/// materials and many objects.
fn material_indices(materials: &[Material]) -> HashMap<&str, usize> {
    materials
        .iter()
        .enumerate()
        .map(|(i, m)| (m.name.as_str(), i))
        .collect()
}

/// What generators keep clear of: the room, the mirror and the two cameras.
fn surroundings(
    room: &Room,
    mirror: &Mirror,
    sensor: &SensorCamera,
    observer: &Camera,
) -> Surroundings {
    Surroundings {
        room_center: room.center,
        room_size: room.size_m,
        mirror_center: mirror.center,
        mirror_radius: mirror.radius_m,
        sensor_offset: sensor.offset_m,
        observer: observer.position,
    }
}

fn sample_times(a: Option<&Animation>) -> Vec<f64> {
    sample_times_n(a, ANIMATION_SAMPLES)
}

/// `samples` evenly spaced times over the animation's cycle (and its keyframes); time 0 alone
/// without one.
fn sample_times_n(a: Option<&Animation>, samples: usize) -> Vec<f64> {
    a.map_or_else(|| vec![0.0], |a| a.sample_times(samples))
}

fn position_at(a: Option<&Animation>, base: Vec3, t: f64) -> Vec3 {
    match a {
        Some(a) => a.position_at(base, t),
        None => base,
    }
}

/// The materials' names for a message: all of a few, the first of many and how many more.
fn some_names(materials: &[crate::scene::Material]) -> String {
    const SHOWN: usize = 12;
    let names: Vec<&str> = materials
        .iter()
        .take(SHOWN)
        .map(|m| m.name.as_str())
        .collect();
    match materials.len().saturating_sub(SHOWN) {
        0 => names.join(", "),
        more => format!("{}, and {more} more", names.join(", ")),
    }
}
