//! Loading and validating scene files.
//!
//! Parsing happens twice over the same text: once into toml's spanned document tree
//! ([`DeTable`]), which knows where every key and value sits, and once through serde into the
//! plain structs of `format.rs`. Validation works on the plain structs and names each value by
//! its dotted field path (`objects[2].size`); the path is looked up in the spanned tree to get
//! the line and column. One string is thus both the message's field name and the key to its
//! position, so they cannot disagree.

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{DVec3, Quat, Vec3};
use toml::de::{DeTable, DeValue};
use toml::Spanned;

use super::anim::{Animation, Repeat};
use super::error::{Location, SceneError};
use super::format::*;
use super::generate::{
    self, Params, ShapeChoice, Surroundings, DEFAULT_SEGMENTS, MAX_COUNT, MAX_SEGMENTS,
    PLACEMENT_TRIES,
};
use super::mesh::Mesh;
use super::texture::TextureData;
use super::{
    Camera, CubeFormat, CubeSettings, DirectionalLight, Lookup, Material, MaterialKind, Mirror,
    Object, RefreshPolicy, Room, Scene, SensorCamera, MAX_FACE_SIZE_PX, MAX_IMAGE_SIZE_PX,
};

type R<T> = Result<T, SceneError>;
/// Builds a mesh on first use (the loader caches meshes by a key describing them).
type MeshBuilder = Box<dyn Fn() -> Result<Mesh, String>>;

/// How many evenly spaced times an animation is checked at (plus its keyframes).
const ANIMATION_SAMPLES: usize = 64;
/// Tessellation of `shape = "sphere"` objects.
const SPHERE_SEGMENTS: u32 = 48;
const SPHERE_RINGS: u32 = 24;
/// Tessellation of `shape = "cylinder"` objects.
const CYLINDER_SEGMENTS: u32 = 48;

/// Reads and validates the scene file at `path`. Relative asset paths inside it are resolved
/// against the folder that contains it.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8(bytes).map_err(|e| SceneError::Io {
        file: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()),
    })?;
    load_str(&text, path)
}

/// Validates scene text as if it had been read from `path` (used in messages and to resolve
/// relative asset paths against `path`'s folder; the file itself is not read).
pub fn load_str(text: &str, path: &Path) -> Result<Scene, SceneError> {
    let doc = match DeTable::parse(text) {
        Ok(doc) => doc,
        Err(e) => {
            let location = match e.span() {
                Some(span) => Location::at_offset(path, text, span.start),
                None => Location::file_only(path),
            };
            return Err(SceneError::Syntax {
                location,
                message: e.message().trim().to_string(),
            });
        }
    };
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

// ---------------------------------------------------------------------------------------------
// Positions of fields in the source text.

struct Locator<'a> {
    file: &'a Path,
    text: &'a str,
    root: Spanned<DeTable<'a>>,
}

enum Segment<'p> {
    Key(&'p str),
    Index(usize),
}

/// `objects[2].animation.positions[0]` -> Key(objects) Index(2) Key(animation) ...
fn segments(path: &str) -> Vec<Segment<'_>> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let (name, mut rest) = part.split_at(part.find('[').unwrap_or(part.len()));
        if !name.is_empty() {
            out.push(Segment::Key(name));
        }
        while let Some(close) = rest.find(']') {
            if let Ok(i) = rest[1..close].parse() {
                out.push(Segment::Index(i));
            }
            rest = &rest[close + 1..];
        }
    }
    out
}

fn contains(span: &Range<usize>, offset: usize) -> bool {
    span.start <= offset && (offset < span.end || span.start == span.end)
}

impl<'a> Locator<'a> {
    /// The span of the value at `path`, or of the deepest part of it that exists (the table
    /// that lacks a missing field). `None` if not even the first key exists.
    fn span(&self, path: &str) -> Option<Range<usize>> {
        let mut best: Option<Range<usize>> = None;
        let mut table: Option<&DeTable<'a>> = Some(self.root.get_ref());
        let mut value: Option<&Spanned<DeValue<'a>>> = None;
        for seg in segments(path) {
            let next = match seg {
                Segment::Key(k) => {
                    let t = match value {
                        None => table,
                        Some(v) => v.get_ref().as_table(),
                    };
                    let Some((key, v)) =
                        t.and_then(|t| t.iter().find(|(key, _)| key.get_ref() == k))
                    else {
                        break;
                    };
                    // A `[table]`'s own span is its header; an inline value's is the value.
                    best = Some(if v.get_ref().is_table() && v.span().is_empty() {
                        key.span()
                    } else {
                        v.span()
                    });
                    v
                }
                Segment::Index(i) => {
                    let Some(v) = value
                        .and_then(|v| v.get_ref().as_array())
                        .and_then(|a| a.get(i))
                    else {
                        break;
                    };
                    best = Some(v.span());
                    v
                }
            };
            value = Some(next);
            table = None;
        }
        best
    }

    fn location(&self, path: &str) -> Location {
        match self.span(path) {
            Some(span) => Location::at_offset(self.file, self.text, span.start),
            None => Location::file_only(self.file),
        }
    }

    /// The dotted path of the deepest key or value whose span contains `offset`.
    fn path_at(&self, offset: usize) -> Option<String> {
        fn in_value(v: &Spanned<DeValue<'_>>, path: String, offset: usize) -> Option<String> {
            match v.get_ref() {
                DeValue::Table(t) => {
                    if let Some(p) = in_table(t, &path, offset) {
                        return Some(p);
                    }
                }
                DeValue::Array(a) => {
                    for (i, e) in a.iter().enumerate() {
                        if let Some(p) = in_value(e, format!("{path}[{i}]"), offset) {
                            return Some(p);
                        }
                    }
                }
                _ => {}
            }
            contains(&v.span(), offset).then_some(path)
        }
        fn in_table(t: &DeTable<'_>, prefix: &str, offset: usize) -> Option<String> {
            for (k, v) in t.iter() {
                let path = if prefix.is_empty() {
                    k.get_ref().to_string()
                } else {
                    format!("{prefix}.{}", k.get_ref())
                };
                if contains(&k.span(), offset) {
                    return Some(path);
                }
                if let Some(p) = in_value(v, path, offset) {
                    return Some(p);
                }
            }
            None
        }
        in_table(self.root.get_ref(), "", offset)
    }

    /// Turns a serde error (unknown field, wrong type, missing field) into a located error.
    fn serde_error(&self, e: &toml::de::Error) -> SceneError {
        let message = e.message().trim().to_string();
        let (location, mut field) = match e.span() {
            Some(span) => (
                Location::at_offset(self.file, self.text, span.start),
                self.path_at(span.start).unwrap_or_default(),
            ),
            None => (Location::file_only(self.file), String::new()),
        };
        // serde names the offending key in backticks; make sure the path ends with it.
        let named = |prefix: &str| {
            message
                .strip_prefix(prefix)
                .and_then(|rest| rest.split('`').next())
                .map(str::to_string)
        };
        let key = named("unknown field `").or_else(|| named("missing field `"));
        if let Some(key) = &key {
            if !(field == *key || field.ends_with(&format!(".{key}"))) {
                field = if field.is_empty() {
                    key.clone()
                } else {
                    format!("{field}.{key}")
                };
            }
        }
        if field.is_empty() {
            field = "(top level)".into();
        }
        if message.starts_with("unknown field") {
            SceneError::UnknownField {
                location,
                field,
                message,
            }
        } else if message.starts_with("missing field") {
            SceneError::Invalid {
                location,
                field,
                message: "required field is missing".into(),
            }
        } else {
            SceneError::WrongType {
                location,
                field,
                message,
            }
        }
    }
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

    /// A finite number that fits in f32.
    fn num(&self, field: &str, v: f64) -> R<f32> {
        if !v.is_finite() {
            return Err(self.invalid(field, format!("must be a finite number, got {v}")));
        }
        if v.abs() > f64::from(f32::MAX) {
            return Err(self.invalid(field, format!("out of range, got {v}")));
        }
        Ok(v as f32)
    }

    fn positive(&self, field: &str, v: f64) -> R<f32> {
        let x = self.num(field, v)?;
        if x <= 0.0 {
            return Err(self.invalid(field, format!("must be positive, got {v}")));
        }
        Ok(x)
    }

    /// A number in the open or closed interval described by `lo`/`hi`.
    fn in_range(&self, field: &str, v: f64, lo: f64, hi: f64, open: bool) -> R<f32> {
        let x = self.num(field, v)?;
        let ok = if open {
            v > lo && v < hi
        } else {
            v >= lo && v <= hi
        };
        if !ok {
            let (a, b) = if open { ("(", ")") } else { ("[", "]") };
            return Err(self.invalid(field, format!("must be in {a}{lo}, {hi}{b}, got {v}")));
        }
        Ok(x)
    }

    fn vec3(&self, field: &str, v: V3) -> R<Vec3> {
        let mut out = [0.0f32; 3];
        for (i, c) in v.iter().enumerate() {
            out[i] = self.num(&format!("{field}[{i}]"), *c)?;
        }
        Ok(Vec3::from(out))
    }

    /// A position: finite in the file (f64), stored relative to the origin. The subtraction
    /// happens in f64, so a scene far from the world origin keeps f32 precision near the mirror.
    fn point(&self, field: &str, v: V3) -> R<Vec3> {
        for (i, c) in v.iter().enumerate() {
            self.num(&format!("{field}[{i}]"), *c)?;
        }
        let local = DVec3::from_array(v) - self.origin;
        self.vec3(field, local.to_array())
    }

    /// A local position written back in the file's (world) coordinates, for messages.
    fn fmt_point(&self, v: Vec3) -> String {
        let w = self.origin + v.as_dvec3();
        format!("[{}, {}, {}]", w.x as f32, w.y as f32, w.z as f32)
    }

    fn positive3(&self, field: &str, v: V3) -> R<Vec3> {
        for (i, c) in v.iter().enumerate() {
            self.positive(&format!("{field}[{i}]"), *c)?;
        }
        self.vec3(field, v)
    }

    fn color(&self, field: &str, v: V3) -> R<Vec3> {
        for (i, c) in v.iter().enumerate() {
            self.in_range(&format!("{field}[{i}]"), *c, 0.0, 1.0, false)?;
        }
        self.vec3(field, v)
    }

    fn count(&self, field: &str, v: i64, max: u32) -> R<u32> {
        if v < 1 || v > i64::from(max) {
            return Err(self.invalid(field, format!("must be in 1..={max}, got {v}")));
        }
        Ok(v as u32)
    }

    fn resolution(&self, field: &str, v: Option<[i64; 2]>, default: [u32; 2]) -> R<[u32; 2]> {
        match v {
            None => Ok(default),
            Some([w, h]) => Ok([
                self.count(&format!("{field}[0]"), w, MAX_IMAGE_SIZE_PX)?,
                self.count(&format!("{field}[1]"), h, MAX_IMAGE_SIZE_PX)?,
            ]),
        }
    }

    fn scene(&self, spec: SceneFile) -> R<Scene> {
        let Some(room_spec) = &spec.room else {
            return Err(self.invalid("room", "missing [room] table (every scene needs a room)"));
        };
        let Some(mirror_spec) = &spec.mirror else {
            return Err(self.invalid("mirror", "missing [mirror] table (every scene needs one)"));
        };

        let mut textures = Vec::new();
        let materials = self.materials(&spec.materials, &mut textures)?;
        let material_index = |field: &str, name: &str| -> R<usize> {
            materials
                .iter()
                .position(|m| m.name == name)
                .ok_or_else(|| {
                    let known: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
                    self.invalid(
                        field,
                        format!(
                            "unknown material \"{name}\" (defined: {})",
                            known.join(", ")
                        ),
                    )
                })
        };

        let room = self.room(room_spec, &material_index)?;
        let mirror = self.mirror(mirror_spec, &room)?;

        let mut meshes = Vec::new();
        let mut mesh_cache: HashMap<String, usize> = HashMap::new();
        let mut objects = Vec::with_capacity(spec.objects.len());
        for (i, o) in spec.objects.iter().enumerate() {
            objects.push(self.object(i, o, &material_index, &mut meshes, &mut mesh_cache)?);
        }

        let observer = self.observer(spec.observer.as_ref(), &room, &mirror)?;
        let sensor = self.sensor(spec.sensor.as_ref(), &room, &mirror)?;
        // Generated objects come after the file's own, and keep clear of the cameras.
        let surroundings = Surroundings {
            room_center: room.center,
            room_size: room.size_m,
            mirror_center: mirror.center,
            mirror_radius: mirror.radius_m,
            sensor_offset: sensor.offset_m,
            observer: observer.position,
        };
        for (i, g) in spec.generate.iter().enumerate() {
            let params =
                self.generator(i, g, &material_index, &room, &mut meshes, &mut mesh_cache)?;
            let made = generate::expand(&params, &surroundings).map_err(|fail| {
                let (field, why) = if fail.orbit_outside > fail.too_close {
                    (
                        "moving",
                        "its orbit about the room's vertical axis left the room",
                    )
                } else {
                    (
                        "keep_clear",
                        "it was too close to the mirror, the sensor's view of it or the observer",
                    )
                };
                self.invalid(
                    &format!("generate[{i}].{field}"),
                    format!(
                        "cannot place {}[{}]: {PLACEMENT_TRIES} positions tried, {} too close, {} with the orbit outside the room; mostly {why} (enlarge the region, or lower keep_clear, size or moving)",
                        params.name, fail.object, fail.too_close, fail.orbit_outside
                    ),
                )
            })?;
            objects.extend(made);
        }
        let cube = self.cube(spec.cube.as_ref())?;
        let refresh = self.refresh(spec.refresh.as_ref())?;
        let light = match &spec.light {
            None => None,
            Some(l) => {
                let d = self.vec3("light.direction", l.direction)?;
                let direction = d
                    .try_normalize()
                    .filter(|n| n.is_finite())
                    .ok_or_else(|| self.invalid("light.direction", "must be a non-zero vector"))?;
                let ambient = match l.ambient {
                    Some(a) => self.in_range("light.ambient", a, 0.0, 1.0, false)?,
                    None => 0.3,
                };
                Some(DirectionalLight { direction, ambient })
            }
        };

        Ok(Scene {
            origin: self.origin,
            source: self.loc.file.to_path_buf(),
            description: spec.description.clone().unwrap_or_default(),
            room,
            mirror,
            objects,
            meshes,
            materials,
            textures,
            observer,
            sensor,
            cube,
            refresh,
            light,
        })
    }

    fn materials(
        &self,
        specs: &[MaterialSpec],
        textures: &mut Vec<TextureData>,
    ) -> R<Vec<Material>> {
        let mut out: Vec<Material> = Vec::with_capacity(specs.len());
        for (i, m) in specs.iter().enumerate() {
            let f = |name: &str| format!("materials[{i}].{name}");
            if m.name.trim().is_empty() {
                return Err(self.invalid(&f("name"), "must not be empty"));
            }
            if out.iter().any(|o| o.name == m.name) {
                return Err(self.invalid(
                    &f("name"),
                    format!("duplicate material name \"{}\"", m.name),
                ));
            }
            // Which optional fields each type takes; any other present field is an error.
            let allowed: &[&str] = match m.kind {
                MaterialType::Color => &["color"],
                MaterialType::Checker => &["a", "b", "tiles"],
                MaterialType::Grid => &["background", "line", "tiles", "line_width"],
                MaterialType::Texture => &["file", "tint", "tiles"],
                MaterialType::Direction => &[],
            };
            let present = [
                ("color", m.color.is_some()),
                ("a", m.a.is_some()),
                ("b", m.b.is_some()),
                ("tiles", m.tiles.is_some()),
                ("background", m.background.is_some()),
                ("line", m.line.is_some()),
                ("line_width", m.line_width.is_some()),
                ("file", m.file.is_some()),
                ("tint", m.tint.is_some()),
            ];
            for (name, is_set) in present {
                if is_set && !allowed.contains(&name) {
                    return Err(self.unused(
                        &f(name),
                        &format!("a material of type {:?} takes only {:?}", m.kind, allowed),
                    ));
                }
            }
            let need = |v: Option<V3>, name: &str| -> R<Vec3> {
                match v {
                    Some(v) => self.color(&f(name), v),
                    None => Err(self.missing(&f(name), &format!("{:?} materials need it", m.kind))),
                }
            };
            let tiles =
                |default: f64| -> R<f32> { self.positive(&f("tiles"), m.tiles.unwrap_or(default)) };
            let kind = match m.kind {
                MaterialType::Color => MaterialKind::Color {
                    color: need(m.color, "color")?,
                },
                MaterialType::Checker => MaterialKind::Checker {
                    a: need(m.a, "a")?,
                    b: need(m.b, "b")?,
                    tiles: tiles(8.0)?,
                },
                MaterialType::Grid => MaterialKind::Grid {
                    background: need(m.background, "background")?,
                    line: need(m.line, "line")?,
                    tiles: tiles(8.0)?,
                    line_width: match m.line_width {
                        Some(w) => {
                            let x = self.num(&f("line_width"), w)?;
                            if !(w > 0.0 && w <= 0.5) {
                                return Err(self.invalid(
                                    &f("line_width"),
                                    format!("must be in (0, 0.5], got {w}"),
                                ));
                            }
                            x
                        }
                        None => 0.05,
                    },
                },
                MaterialType::Texture => {
                    let Some(file) = &m.file else {
                        return Err(self.missing(&f("file"), "texture materials need a PNG file"));
                    };
                    let path = self.dir.join(file);
                    let index = match textures.iter().position(|t| t.path == path) {
                        Some(index) => index,
                        None => {
                            let t = TextureData::from_png(&path).map_err(|message| {
                                SceneError::Asset {
                                    location: self.loc.location(&f("file")),
                                    field: f("file"),
                                    asset: path.clone(),
                                    message,
                                }
                            })?;
                            textures.push(t);
                            textures.len() - 1
                        }
                    };
                    MaterialKind::Texture {
                        texture: index,
                        tint: match m.tint {
                            Some(t) => self.color(&f("tint"), t)?,
                            None => Vec3::ONE,
                        },
                        tiles: tiles(1.0)?,
                    }
                }
                MaterialType::Direction => MaterialKind::Direction,
            };
            out.push(Material {
                name: m.name.clone(),
                kind,
            });
        }
        Ok(out)
    }

    fn room(&self, spec: &RoomSpec, material: &dyn Fn(&str, &str) -> R<usize>) -> R<Room> {
        let center = match spec.center {
            Some(c) => self.point("room.center", c)?,
            // The world origin, which is not the local one.
            None => self.point("room.center", [0.0; 3])?,
        };
        let size_m = self.positive3("room.size", spec.size)?;
        let wall_materials = match &spec.walls {
            WallsSpec::All(name) => [material("room.walls", name)?; 6],
            WallsSpec::Each(w) => [
                material("room.walls.px", &w.px)?,
                material("room.walls.nx", &w.nx)?,
                material("room.walls.py", &w.py)?,
                material("room.walls.ny", &w.ny)?,
                material("room.walls.pz", &w.pz)?,
                material("room.walls.nz", &w.nz)?,
            ],
        };
        Ok(Room {
            center,
            size_m,
            wall_materials,
        })
    }

    /// Converts an animation; `base` is the animated thing's position at rest.
    fn animation(&self, field: &str, a: &AnimationSpec, base: Vec3) -> R<Animation> {
        let f = |name: &str| format!("{field}.{name}");
        let allowed: &[&str] = match a.kind {
            AnimationType::Linear => &["to", "duration", "repeat"],
            AnimationType::Orbit => &["center", "axis", "period"],
            AnimationType::Keyframes => &["times", "positions", "repeat"],
        };
        let present = [
            ("to", a.to.is_some()),
            ("duration", a.duration.is_some()),
            ("repeat", a.repeat.is_some()),
            ("center", a.center.is_some()),
            ("axis", a.axis.is_some()),
            ("period", a.period.is_some()),
            ("times", a.times.is_some()),
            ("positions", a.positions.is_some()),
        ];
        for (name, is_set) in present {
            if is_set && !allowed.contains(&name) {
                return Err(self.unused(
                    &f(name),
                    &format!("a {:?} animation takes only {:?}", a.kind, allowed),
                ));
            }
        }
        let repeat = match a.repeat.unwrap_or(RepeatSpec::Once) {
            RepeatSpec::Once => Repeat::Once,
            RepeatSpec::Loop => Repeat::Loop,
            RepeatSpec::PingPong => Repeat::PingPong,
        };
        Ok(match a.kind {
            AnimationType::Linear => Animation::Linear {
                to: self.point(
                    &f("to"),
                    a.to.ok_or_else(|| self.missing(&f("to"), "the end point"))?,
                )?,
                duration_s: self.positive(
                    &f("duration"),
                    a.duration
                        .ok_or_else(|| self.missing(&f("duration"), "seconds"))?,
                )?,
                repeat,
            },
            AnimationType::Orbit => {
                let center = self.point(
                    &f("center"),
                    a.center
                        .ok_or_else(|| self.missing(&f("center"), "a point on the axis"))?,
                )?;
                let axis = self.vec3(&f("axis"), a.axis.unwrap_or([0.0, 1.0, 0.0]))?;
                let axis = axis
                    .try_normalize()
                    .filter(|n| n.is_finite())
                    .ok_or_else(|| self.invalid(&f("axis"), "must be a non-zero vector"))?;
                let period_s = self.positive(
                    &f("period"),
                    a.period
                        .ok_or_else(|| self.missing(&f("period"), "seconds per turn"))?,
                )?;
                Animation::Orbit {
                    center,
                    axis,
                    period_s,
                }
            }
            AnimationType::Keyframes => {
                let times = a
                    .times
                    .as_ref()
                    .ok_or_else(|| self.missing(&f("times"), "key times in seconds"))?;
                let positions = a
                    .positions
                    .as_ref()
                    .ok_or_else(|| self.missing(&f("positions"), "key positions"))?;
                if times.is_empty() {
                    return Err(self.invalid(&f("times"), "needs at least one key"));
                }
                if times.len() != positions.len() {
                    return Err(self.invalid(
                        &f("positions"),
                        format!(
                            "has {} entries but times has {}",
                            positions.len(),
                            times.len()
                        ),
                    ));
                }
                let mut times_s = Vec::with_capacity(times.len());
                for (i, &t) in times.iter().enumerate() {
                    let tf = format!("{field}.times[{i}]");
                    let x = self.num(&tf, t)?;
                    if i == 0 && t != 0.0 {
                        return Err(
                            self.invalid(&tf, format!("the first key time must be 0, got {t}"))
                        );
                    }
                    if i > 0 && x <= times_s[i - 1] {
                        return Err(self.invalid(
                            &tf,
                            format!(
                                "key times must strictly increase, got {t} after {}",
                                times[i - 1]
                            ),
                        ));
                    }
                    times_s.push(x);
                }
                let mut ps = Vec::with_capacity(positions.len());
                for (i, &p) in positions.iter().enumerate() {
                    ps.push(self.point(&format!("{field}.positions[{i}]"), p)?);
                }
                // Keyframes are absolute; the rest position must be where they start.
                if ps[0] != base {
                    return Err(self.invalid(
                        &format!("{field}.positions[0]"),
                        format!(
                            "the first keyframe {} must equal the position at rest {} (keyframe positions are absolute)",
                            self.fmt_point(ps[0]),
                            self.fmt_point(base)
                        ),
                    ));
                }
                Animation::Keyframes {
                    times_s,
                    positions: ps,
                    repeat,
                }
            }
        })
    }

    fn mirror(&self, spec: &MirrorSpec, room: &Room) -> R<Mirror> {
        let center = self.point("mirror.center", spec.center)?;
        let radius_m = self.positive("mirror.radius", spec.radius)?;
        let animation = match &spec.animation {
            Some(a) => Some(self.animation("mirror.animation", a, center)?),
            None => None,
        };
        let (lo, hi) = (
            room.center - room.size_m * 0.5,
            room.center + room.size_m * 0.5,
        );
        for t in sample_times(animation.as_ref()) {
            let c = position_at(animation.as_ref(), center, t);
            if (c - radius_m).cmplt(lo).any() || (c + radius_m).cmpgt(hi).any() {
                let field = if t == 0.0 {
                    "mirror.center"
                } else {
                    "mirror.animation"
                };
                return Err(self.invalid(
                    field,
                    format!(
                        "the mirror (radius {radius_m}) centred at {} {} is not entirely inside the room (from {} to {})",
                        self.fmt_point(c),
                        if t == 0.0 { "at time 0".to_string() } else { format!("at t = {t:.3} s") },
                        self.fmt_point(lo),
                        self.fmt_point(hi)
                    ),
                ));
            }
        }
        Ok(Mirror {
            center,
            radius_m,
            animation,
            lookup: match spec.lookup {
                None | Some(LookupSpec::Plain) => Lookup::Plain,
                Some(LookupSpec::Box) => Lookup::Box,
                Some(LookupSpec::RayQuery) => Lookup::RayQuery,
            },
        })
    }

    /// The cache key and loader of a mesh file named by `field`.
    fn mesh_file(&self, field: &str, file: &str) -> R<(String, MeshBuilder)> {
        let path = self.dir.join(file);
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let p = path.clone();
        let build: MeshBuilder = match ext.as_deref() {
            Some("obj") => Box::new(move || {
                if !p.is_file() {
                    return Err("file not found".into());
                }
                Mesh::from_obj(&p)
            }),
            Some("gltf") | Some("glb") => Box::new(move || {
                if !p.is_file() {
                    return Err("file not found".into());
                }
                Mesh::from_gltf(&p)
            }),
            _ => {
                return Err(self.invalid(
                    field,
                    format!("unsupported mesh file \"{file}\": expected .obj, .gltf or .glb"),
                ))
            }
        };
        Ok((format!("file:{}", path.display()), build))
    }

    /// The index of the mesh cached under `key`, building and storing it on first use. A build
    /// failure is an asset error at `field` (the field naming `file`, if any).
    fn cached_mesh(
        &self,
        field: &str,
        file: Option<&str>,
        key: String,
        build: MeshBuilder,
        meshes: &mut Vec<Mesh>,
        cache: &mut HashMap<String, usize>,
    ) -> R<usize> {
        if let Some(&index) = cache.get(&key) {
            return Ok(index);
        }
        let m = build().map_err(|message| SceneError::Asset {
            location: self.loc.location(field),
            field: field.to_string(),
            asset: self.dir.join(file.unwrap_or_default()),
            message,
        })?;
        meshes.push(m);
        cache.insert(key, meshes.len() - 1);
        Ok(meshes.len() - 1)
    }

    fn object(
        &self,
        i: usize,
        o: &ObjectSpec,
        material: &dyn Fn(&str, &str) -> R<usize>,
        meshes: &mut Vec<Mesh>,
        cache: &mut HashMap<String, usize>,
    ) -> R<Object> {
        let f = |name: &str| format!("objects[{i}].{name}");
        let allowed: &[&str] = match o.shape {
            Shape::Box => &["size"],
            Shape::Sphere => &["radius"],
            Shape::Cylinder => &["radius", "height"],
            Shape::Mesh => &["file"],
        };
        let present = [
            ("size", o.size.is_some()),
            ("radius", o.radius.is_some()),
            ("height", o.height.is_some()),
            ("file", o.file.is_some()),
        ];
        for (name, is_set) in present {
            if is_set && !allowed.contains(&name) {
                return Err(self.unused(
                    &f(name),
                    &format!("shape {:?} takes only {:?}", o.shape, allowed),
                ));
            }
        }
        let need = |v: Option<f64>, name: &str| -> R<f32> {
            let v =
                v.ok_or_else(|| self.missing(&f(name), &format!("shape {:?} needs it", o.shape)))?;
            self.positive(&f(name), v)
        };
        // Built-in shapes are generated at their real size (no scale in the normals) and
        // shared between objects with the same parameters.
        let (key, build): (String, MeshBuilder) = match o.shape {
            Shape::Box => {
                let size = self.positive3(
                    &f("size"),
                    o.size
                        .ok_or_else(|| self.missing(&f("size"), "a box needs [x, y, z]"))?,
                )?;
                (
                    format!("box:{size}"),
                    Box::new(move || Ok(Mesh::cuboid(size * 0.5))),
                )
            }
            Shape::Sphere => {
                let r = need(o.radius, "radius")?;
                (
                    format!("sphere:{r}"),
                    Box::new(move || Ok(Mesh::uv_sphere(r, SPHERE_SEGMENTS, SPHERE_RINGS))),
                )
            }
            Shape::Cylinder => {
                let r = need(o.radius, "radius")?;
                let h = need(o.height, "height")?;
                (
                    format!("cylinder:{r}:{h}"),
                    Box::new(move || Ok(Mesh::cylinder(r, h * 0.5, CYLINDER_SEGMENTS))),
                )
            }
            Shape::Mesh => {
                let file = o
                    .file
                    .as_ref()
                    .ok_or_else(|| self.missing(&f("file"), "a .obj, .gltf or .glb file"))?;
                self.mesh_file(&f("file"), file)?
            }
        };
        let mesh = self.cached_mesh(&f("file"), o.file.as_deref(), key, build, meshes, cache)?;
        let material = material(&f("material"), &o.material)?;
        let rotation = match o.rotation {
            Some(r) => {
                let d = self.vec3(&f("rotation"), r)?;
                // Explicit product rather than a library Euler convention: Rx * Ry * Rz, so the
                // object turns about Z first, then Y, then X (as docs/scene-format.md says).
                Quat::from_rotation_x(d.x.to_radians())
                    * Quat::from_rotation_y(d.y.to_radians())
                    * Quat::from_rotation_z(d.z.to_radians())
            }
            None => Quat::IDENTITY,
        };
        let scale = match o.scale {
            None => Vec3::ONE,
            Some(ScaleSpec::Uniform(s)) => Vec3::splat(self.positive(&f("scale"), s)?),
            Some(ScaleSpec::PerAxis(s)) => self.positive3(&f("scale"), s)?,
        };
        let keyframe_start = match &o.animation {
            Some(AnimationSpec {
                kind: AnimationType::Keyframes,
                positions: Some(p),
                ..
            }) => p.first().copied(),
            _ => None,
        };
        let position = match (o.position, keyframe_start) {
            (Some(p), _) => self.point(&f("position"), p)?,
            // A keyframed object may leave out `position`: it starts at its first key.
            (None, Some(p)) => self.point(&format!("objects[{i}].animation.positions[0]"), p)?,
            (None, None) => return Err(self.missing(&f("position"), "where the object is")),
        };
        let animation = match &o.animation {
            Some(a) => Some(self.animation(&f("animation"), a, position)?),
            None => None,
        };
        Ok(Object {
            name: o.name.clone().unwrap_or_else(|| format!("objects[{i}]")),
            mesh,
            material,
            position,
            rotation,
            scale,
            animation,
        })
    }

    /// Validates a `[[generate]]` table and builds (or reuses) its unit meshes.
    fn generator(
        &self,
        i: usize,
        g: &GenerateSpec,
        material: &dyn Fn(&str, &str) -> R<usize>,
        room: &Room,
        meshes: &mut Vec<Mesh>,
        cache: &mut HashMap<String, usize>,
    ) -> R<Params> {
        let f = |name: &str| format!("generate[{i}].{name}");
        let name = match &g.name {
            Some(n) if n.trim().is_empty() => {
                return Err(self.invalid(&f("name"), "must not be empty"))
            }
            Some(n) => n.clone(),
            None => format!("generate[{i}]"),
        };
        let count = self.count(&f("count"), g.count, MAX_COUNT)?;
        let seed = match g.seed {
            None => 0,
            Some(s) => u64::try_from(s).map_err(|_| {
                self.invalid(&f("seed"), format!("must be in 0..={}, got {s}", i64::MAX))
            })?,
        };

        // Shapes: which fields they need.
        if g.shapes.is_empty() {
            return Err(self.invalid(&f("shapes"), "needs at least one shape"));
        }
        let has = |s: Shape| g.shapes.contains(&s);
        let round = has(Shape::Sphere) || has(Shape::Cylinder);
        if g.segments.is_some() && !round {
            return Err(self.unused(
                &f("segments"),
                "segments is used only when shapes has \"sphere\" or \"cylinder\"",
            ));
        }
        let segments = match g.segments {
            Some(n) if n < 3 || n > i64::from(MAX_SEGMENTS) => {
                return Err(self.invalid(
                    &f("segments"),
                    format!("must be in 3..={MAX_SEGMENTS}, got {n}"),
                ))
            }
            Some(n) => n as u32,
            None => DEFAULT_SEGMENTS,
        };
        match (&g.file, has(Shape::Mesh)) {
            (None, true) => {
                return Err(self.missing(&f("file"), "shapes has \"mesh\": a .obj, .gltf or .glb"))
            }
            (Some(_), false) => {
                return Err(self.unused(&f("file"), "file is used only when shapes has \"mesh\""))
            }
            _ => {}
        }
        let mut shapes = Vec::with_capacity(g.shapes.len());
        for &shape in &g.shapes {
            // Unit-size shapes (size 1 m) scaled per object; one mesh per shape and
            // tessellation, shared by every generator.
            let unit = |mesh| ShapeChoice {
                mesh,
                scale_per_size: 1.0,
                reach_per_size: 1.0,
            };
            let rings = (segments / 2).max(2);
            let choice = match shape {
                Shape::Box => unit(self.cached_mesh(
                    &f("shapes"),
                    None,
                    "unit-box".into(),
                    Box::new(|| Ok(Mesh::cuboid(Vec3::splat(0.5)))),
                    meshes,
                    cache,
                )?),
                Shape::Sphere => unit(self.cached_mesh(
                    &f("shapes"),
                    None,
                    format!("unit-sphere:{segments}"),
                    Box::new(move || Ok(Mesh::uv_sphere(0.5, segments, rings))),
                    meshes,
                    cache,
                )?),
                Shape::Cylinder => unit(self.cached_mesh(
                    &f("shapes"),
                    None,
                    format!("unit-cylinder:{segments}"),
                    Box::new(move || Ok(Mesh::cylinder(0.5, 0.5, segments))),
                    meshes,
                    cache,
                )?),
                Shape::Mesh => {
                    let file = g.file.as_deref().unwrap_or_default();
                    let (key, build) = self.mesh_file(&f("file"), file)?;
                    let index =
                        self.cached_mesh(&f("file"), Some(file), key, build, meshes, cache)?;
                    let m = &meshes[index];
                    // Size = the largest side of the bounding box; the clearance radius also
                    // covers the farthest vertex from the mesh's origin.
                    let side = (m.bounds_max - m.bounds_min).max_element();
                    if !(side > 0.0 && side.is_finite()) {
                        return Err(self.invalid(
                            &f("file"),
                            format!("mesh \"{file}\" has no extent to scale"),
                        ));
                    }
                    let farthest = m
                        .positions
                        .iter()
                        .map(|p| p.length())
                        .fold(0.0f32, f32::max);
                    ShapeChoice {
                        mesh: index,
                        scale_per_size: 1.0 / side,
                        reach_per_size: (farthest / side).max(1.0),
                    }
                }
            };
            shapes.push(choice);
        }

        if g.materials.is_empty() {
            return Err(self.invalid(&f("materials"), "needs at least one material"));
        }
        let mut materials = Vec::with_capacity(g.materials.len());
        for (j, m) in g.materials.iter().enumerate() {
            materials.push(material(&f(&format!("materials[{j}]")), m)?);
        }

        let size = self.interval(&f("size"), g.size)?;

        let region_min = self.point(&f("region_min"), g.region_min)?;
        let region_max = self.point(&f("region_max"), g.region_max)?;
        let (lo, hi) = (
            room.center - room.size_m * 0.5,
            room.center + room.size_m * 0.5,
        );
        // Messages give world coordinates, as the file does.
        let world = |axis: usize, v: f32| (self.origin[axis] + f64::from(v)) as f32;
        for axis in 0..3 {
            let (a, b) = (region_min[axis], region_max[axis]);
            let letter = ["x", "y", "z"][axis];
            for (field, v) in [("region_min", a), ("region_max", b)] {
                if v < lo[axis] || v > hi[axis] {
                    return Err(self.invalid(
                        &f(&format!("{field}[{axis}]")),
                        format!(
                            "{} is outside the room ({letter} from {} to {})",
                            world(axis, v),
                            world(axis, lo[axis]),
                            world(axis, hi[axis])
                        ),
                    ));
                }
            }
            if a > b {
                return Err(self.invalid(
                    &f(&format!("region_max[{axis}]")),
                    format!(
                        "must be >= region_min[{axis}] ({}), got {}",
                        world(axis, a),
                        world(axis, b)
                    ),
                ));
            }
        }

        let keep_clear = self.num(&f("keep_clear"), g.keep_clear.unwrap_or(0.0))?;
        if keep_clear < 0.0 {
            return Err(self.invalid(&f("keep_clear"), format!("must be >= 0, got {keep_clear}")));
        }
        let moving = self.in_range(&f("moving"), g.moving.unwrap_or(0.0), 0.0, 1.0, false)?;
        if g.period.is_some() && moving == 0.0 {
            return Err(self.unused(&f("period"), "period is used only when moving > 0"));
        }
        let period = self.interval(&f("period"), g.period.unwrap_or([8.0, 20.0]))?;

        Ok(Params {
            name,
            count,
            seed,
            shapes,
            materials,
            size,
            region_min,
            region_max,
            keep_clear,
            moving,
            period,
        })
    }

    /// `[min, max]` with 0 < min <= max.
    fn interval(&self, field: &str, v: [f64; 2]) -> R<[f32; 2]> {
        let lo = self.positive(&format!("{field}[0]"), v[0])?;
        let hi = self.positive(&format!("{field}[1]"), v[1])?;
        if hi < lo {
            return Err(self.invalid(
                &format!("{field}[1]"),
                format!("must be >= {field}[0] ({lo}), got {hi}"),
            ));
        }
        Ok([lo, hi])
    }

    fn observer(&self, spec: Option<&ObserverSpec>, room: &Room, mirror: &Mirror) -> R<Camera> {
        // Without [observer]: stand 40% of the room's depth in front of (+Z of) the room
        // centre, at the mirror's height, looking along -Z towards it.
        let default_position = Vec3::new(
            mirror.center.x,
            mirror.center.y,
            room.center.z + 0.4 * room.size_m.z,
        );
        let empty = ObserverSpec {
            position: None,
            yaw: None,
            pitch: None,
            fov_y: None,
            resolution: None,
            animation: None,
        };
        let s = spec.unwrap_or(&empty);
        let position = match s.position {
            Some(p) => self.point("observer.position", p)?,
            None => default_position,
        };
        let camera = Camera {
            position,
            yaw_deg: self.num("observer.yaw", s.yaw.unwrap_or(0.0))?,
            pitch_deg: self.in_range(
                "observer.pitch",
                s.pitch.unwrap_or(0.0),
                -90.0,
                90.0,
                true,
            )?,
            fov_y_deg: self.in_range(
                "observer.fov_y",
                s.fov_y.unwrap_or(60.0),
                0.0,
                180.0,
                true,
            )?,
            resolution: self.resolution("observer.resolution", s.resolution, [800, 600])?,
            animation: match &s.animation {
                Some(a) => Some(self.animation("observer.animation", a, position)?),
                None => None,
            },
        };
        let (lo, hi) = (
            room.center - room.size_m * 0.5,
            room.center + room.size_m * 0.5,
        );
        let mut times = sample_times(camera.animation.as_ref());
        times.extend(sample_times(mirror.animation.as_ref()));
        for t in times {
            let p = position_at(camera.animation.as_ref(), camera.position, t);
            let field = if t == 0.0 {
                "observer.position"
            } else {
                "observer.animation"
            };
            let when = if t == 0.0 {
                "at time 0".to_string()
            } else {
                format!("at t = {t:.3} s")
            };
            let c = position_at(mirror.animation.as_ref(), mirror.center, t);
            if p.distance(c) <= mirror.radius_m {
                return Err(self.invalid(
                    field,
                    format!(
                        "the observer at {} is inside the mirror sphere (centre {}, radius {}) {when}",
                        self.fmt_point(p),
                        self.fmt_point(c),
                        mirror.radius_m
                    ),
                ));
            }
            if p.cmplt(lo).any() || p.cmpgt(hi).any() {
                return Err(self.invalid(
                    field,
                    format!(
                        "the observer at {} is outside the room {when}",
                        self.fmt_point(p)
                    ),
                ));
            }
        }
        Ok(camera)
    }

    fn sensor(&self, spec: Option<&SensorSpec>, room: &Room, mirror: &Mirror) -> R<SensorCamera> {
        let empty = SensorSpec {
            offset: None,
            fov_y: None,
            resolution: None,
            up: None,
        };
        let s = spec.unwrap_or(&empty);
        let offset_m = self.positive("sensor.offset", s.offset.unwrap_or(2.5))?;
        if offset_m <= mirror.radius_m {
            return Err(self.invalid(
                "sensor.offset",
                format!(
                    "must be greater than the mirror radius {}, got {offset_m}",
                    mirror.radius_m
                ),
            ));
        }
        let up = self.vec3("sensor.up", s.up.unwrap_or([0.0, 0.0, -1.0]))?;
        let up = up
            .try_normalize()
            .filter(|u| u.is_finite() && u.cross(Vec3::Y).length() > 1e-3)
            .ok_or_else(|| {
                self.invalid(
                    "sensor.up",
                    "must be non-zero and not parallel to the Y axis",
                )
            })?;
        let floor = room.center.y - 0.5 * room.size_m.y;
        for t in sample_times(mirror.animation.as_ref()) {
            let y = position_at(mirror.animation.as_ref(), mirror.center, t).y - offset_m;
            if y < floor {
                return Err(self.invalid(
                    "sensor.offset",
                    format!(
                        "puts the sensor at y = {} (t = {t:.3} s), below the floor at y = {}",
                        (self.origin.y + f64::from(y)) as f32,
                        (self.origin.y + f64::from(floor)) as f32
                    ),
                ));
            }
        }
        Ok(SensorCamera {
            offset_m,
            fov_y_deg: self.in_range("sensor.fov_y", s.fov_y.unwrap_or(60.0), 0.0, 180.0, true)?,
            resolution: self.resolution("sensor.resolution", s.resolution, [512, 512])?,
            up,
        })
    }

    fn cube(&self, spec: Option<&CubeSpec>) -> R<CubeSettings> {
        let empty = CubeSpec {
            face_size: None,
            format: None,
            near: None,
            far: None,
            mipmaps: None,
            anisotropy: None,
        };
        let c = spec.unwrap_or(&empty);
        let near_m = self.positive("cube.near", c.near.unwrap_or(0.5))?;
        let far_m = self.positive("cube.far", c.far.unwrap_or(100.0))?;
        if near_m >= far_m {
            // Blame whichever the file sets (far if both or neither... far is the usual typo).
            let field = if c.far.is_some() || c.near.is_none() {
                "cube.far"
            } else {
                "cube.near"
            };
            return Err(self.invalid(
                field,
                format!("near ({near_m}) must be less than far ({far_m})"),
            ));
        }
        let max_anisotropy = self.num("cube.anisotropy", c.anisotropy.unwrap_or(16.0))?;
        if max_anisotropy < 1.0 {
            return Err(self.invalid(
                "cube.anisotropy",
                format!("must be >= 1, got {max_anisotropy}"),
            ));
        }
        Ok(CubeSettings {
            face_size_px: self.count(
                "cube.face_size",
                c.face_size.unwrap_or(512),
                MAX_FACE_SIZE_PX,
            )?,
            format: match c.format.unwrap_or(CubeFormatSpec::Rgba16f) {
                CubeFormatSpec::Rgba16f => CubeFormat::Rgba16Float,
                CubeFormatSpec::Rgba8 => CubeFormat::Rgba8Unorm,
            },
            near_m,
            far_m,
            mipmaps: c.mipmaps.unwrap_or(true),
            max_anisotropy,
        })
    }

    fn refresh(&self, spec: Option<&RefreshSpec>) -> R<RefreshPolicy> {
        let Some(r) = spec else {
            return Ok(RefreshPolicy::OnChange);
        };
        match (r.policy, r.n) {
            (PolicySpec::EveryN, Some(n)) => Ok(RefreshPolicy::EveryN(self.count(
                "refresh.n",
                n,
                u32::MAX,
            )?)),
            (PolicySpec::EveryN, None) => {
                Err(self.missing("refresh.n", "policy \"every-n\" needs n"))
            }
            (_, Some(_)) => {
                Err(self.unused("refresh.n", "n is used only with policy = \"every-n\""))
            }
            (PolicySpec::EveryFrame, None) => Ok(RefreshPolicy::EveryFrame),
            (PolicySpec::OnChange, None) => Ok(RefreshPolicy::OnChange),
        }
    }
}

fn sample_times(a: Option<&Animation>) -> Vec<f64> {
    match a {
        Some(a) => a.sample_times(ANIMATION_SAMPLES),
        None => vec![0.0],
    }
}

fn position_at(a: Option<&Animation>, base: Vec3, t: f64) -> Vec3 {
    match a {
        Some(a) => a.position_at(base, t),
        None => base,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn repo(rel: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(rel)
    }

    /// (file in tests/scenes/bad, expected line, text the field/message must contain).
    /// The expectations repeat each file's first-line comment.
    const BAD: &[(&str, Option<u32>, &str)] = &[
        ("syntax-error.toml", Some(4), "TOML syntax error"),
        ("unknown-field.toml", Some(4), "mirror.radus"),
        (
            "negative-radius.toml",
            Some(4),
            "mirror.radius: must be positive",
        ),
        (
            "nan-radius.toml",
            Some(4),
            "mirror.radius: must be a finite number",
        ),
        (
            "zero-face-size.toml",
            Some(6),
            "cube.face_size: must be in 1..=8192, got 0",
        ),
        (
            "huge-face-size.toml",
            Some(6),
            "cube.face_size: must be in 1..=8192, got 16384",
        ),
        (
            "missing-texture.toml",
            Some(12),
            "materials[0].file: cannot load",
        ),
        ("missing-mesh.toml", Some(8), "objects[0].file: cannot load"),
        ("mirror-outside-room.toml", Some(3), "mirror.center"),
        ("observer-inside-mirror.toml", Some(6), "observer.position"),
        (
            "empty.toml",
            None,
            "scene is empty: expected at least [room] and [mirror]",
        ),
        ("wrong-type.toml", Some(4), "mirror.radius"),
        (
            "unknown-material.toml",
            Some(9),
            "objects[0].material: unknown material \"gold\"",
        ),
        (
            "inf-position.toml",
            Some(8),
            "objects[0].position[0]: must be a finite number, got inf",
        ),
        ("near-not-below-far.toml", Some(7), "cube.far"),
        (
            "animated-mirror-leaves-room.toml",
            Some(5),
            "mirror.animation",
        ),
        ("sensor-up-parallel.toml", Some(6), "sensor.up"),
        ("sensor-inside-mirror.toml", Some(6), "sensor.offset"),
        (
            "keyframes-not-increasing.toml",
            Some(5),
            "mirror.animation.times[2]",
        ),
        (
            "colour-out-of-range.toml",
            Some(12),
            "materials[0].color[1]",
        ),
        (
            "generate-count-zero.toml",
            Some(11),
            "generate[0].count: must be in 1..=100000, got 0",
        ),
        (
            "generate-count-huge.toml",
            Some(11),
            "generate[0].count: must be in 1..=100000, got 1000000000",
        ),
        (
            "generate-region-outside-room.toml",
            Some(15),
            "generate[0].region_max[1]: 7.5 is outside the room (y from 0 to 6)",
        ),
        (
            "generate-unknown-material.toml",
            Some(16),
            "generate[0].materials[1]: unknown material \"gold\"",
        ),
        (
            "generate-nan-size.toml",
            Some(13),
            "generate[0].size[0]: must be a finite number, got NaN",
        ),
    ];

    #[test]
    fn every_bad_scene_fails_naming_file_line_and_field() {
        let dir = repo("tests/scenes/bad");
        let mut on_disk: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".toml"))
            .collect();
        on_disk.sort();
        let mut listed: Vec<String> = BAD.iter().map(|b| b.0.to_string()).collect();
        listed.sort();
        assert_eq!(
            on_disk, listed,
            "every bad scene needs an entry in the table"
        );

        for &(name, line, needle) in BAD {
            let path = dir.join(name);
            let err = match load(&path) {
                Ok(_) => panic!("{name} loaded but should fail"),
                Err(e) => e,
            };
            let text = err.to_string();
            assert!(
                text.contains(name),
                "{name}: message does not name the file: {text}"
            );
            assert_eq!(err.line(), line, "{name}: wrong line in {text}");
            if let Some(line) = line {
                assert!(text.contains(&format!("{name}:{line}:")), "{name}: {text}");
            }
            assert!(
                text.contains(needle),
                "{name}: expected {needle:?} in {text}"
            );
        }
    }

    #[test]
    fn asset_errors_name_the_asset_path() {
        let err = load(&repo("tests/scenes/bad/missing-mesh.toml")).unwrap_err();
        assert!(matches!(err, SceneError::Asset { .. }));
        assert!(err.to_string().contains("does-not-exist.obj"), "{err}");
        let err = load(&repo("tests/scenes/bad/missing-texture.toml")).unwrap_err();
        assert!(err.to_string().contains("does-not-exist.png"), "{err}");
    }

    #[test]
    fn error_kinds() {
        let p = Path::new("x.toml");
        assert!(matches!(load_str("", p), Err(SceneError::Empty { .. })));
        assert!(matches!(
            load_str("# just a comment\n", p),
            Err(SceneError::Empty { .. })
        ));
        let e = load(Path::new("/nonexistent/scene.toml")).unwrap_err();
        assert!(matches!(e, SceneError::Io { .. }));
        assert!(e.to_string().contains("/nonexistent/scene.toml"));
        let e = load(&repo("tests/scenes/bad/unknown-field.toml")).unwrap_err();
        assert!(matches!(e, SceneError::UnknownField { .. }), "{e}");
        assert_eq!(e.field(), Some("mirror.radus"));
        let e = load(&repo("tests/scenes/bad/wrong-type.toml")).unwrap_err();
        assert!(matches!(e, SceneError::WrongType { .. }), "{e}");
        assert_eq!(e.field(), Some("mirror.radius"));
    }

    const MINIMAL: &str = "[room]\ncenter = [0, 3, 0]\nsize = [10, 6, 10]\nwalls = \"w\"\n\
        [mirror]\ncenter = [0, 3, 0]\nradius = 1\n\
        [[materials]]\nname = \"w\"\ntype = \"color\"\ncolor = [0.5, 0.5, 0.5]\n";

    #[test]
    fn rotation_is_rx_ry_rz_as_documented() {
        let text = format!(
            "{MINIMAL}[[objects]]\nshape = \"box\"\nsize = [1, 1, 1]\nposition = [2, 2, 2]\n\
             rotation = [30, 45, 60]\nmaterial = \"w\"\n"
        );
        let s = load_str(&text, Path::new("rot.toml")).unwrap();
        let expected = Quat::from_rotation_x(30f32.to_radians())
            * Quat::from_rotation_y(45f32.to_radians())
            * Quat::from_rotation_z(60f32.to_radians());
        assert!(s.objects[0].rotation.dot(expected).abs() > 1.0 - 1e-6);
    }

    #[test]
    fn defaults_are_applied() {
        let s = load_str(MINIMAL, Path::new("min.toml")).unwrap();
        assert_eq!(s.cube.face_size_px, 512);
        assert_eq!(s.cube.format, CubeFormat::Rgba16Float);
        assert_eq!((s.cube.near_m, s.cube.far_m), (0.5, 100.0));
        assert!(s.cube.mipmaps);
        assert_eq!(s.cube.max_anisotropy, 16.0);
        assert_eq!(s.refresh, RefreshPolicy::OnChange);
        assert_eq!(s.observer.resolution, [800, 600]);
        assert_eq!(s.observer.fov_y_deg, 60.0);
        assert_eq!(s.sensor.resolution, [512, 512]);
        assert_eq!(s.sensor.up, Vec3::NEG_Z);
        assert_eq!(s.sensor.offset_m, 2.5);
        assert!(s.light.is_none());
        assert!(s.objects.is_empty());
    }

    #[test]
    fn more_rules_with_their_fields() {
        let cases: &[(&str, &str)] = &[
            ("[refresh]\npolicy = \"every-n\"\n", "refresh.n: required field is missing"),
            ("[refresh]\npolicy = \"on-change\"\nn = 3\n", "refresh.n: not allowed here"),
            ("[cube]\nanisotropy = 0.5\n", "cube.anisotropy"),
            ("[cube]\nformat = \"rgb32\"\n", "cube.format"),
            ("[observer]\npitch = 90\n", "observer.pitch: must be in (-90, 90)"),
            ("[observer]\nfov_y = 180\n", "observer.fov_y"),
            ("[observer]\nresolution = [0, 10]\n", "observer.resolution[0]"),
            ("[sensor]\nup = [0, 0, 0]\n", "sensor.up"),
            ("[light]\ndirection = [0, 0, 0]\n", "light.direction"),
            ("[light]\ndirection = [0, 1, 0]\nambient = 2\n", "light.ambient"),
            ("[[objects]]\nshape = \"sphere\"\nsize = [1, 1, 1]\nposition = [2, 2, 2]\nmaterial = \"w\"\n", "objects[0].size: not allowed here"),
            ("[[objects]]\nshape = \"box\"\nsize = [1, 0, 1]\nposition = [2, 2, 2]\nmaterial = \"w\"\n", "objects[0].size[1]: must be positive"),
            ("[[objects]]\nshape = \"cylinder\"\nradius = 1\nposition = [2, 2, 2]\nmaterial = \"w\"\n", "objects[0].height: required"),
            ("[[objects]]\nshape = \"box\"\nsize = [1, 1, 1]\nposition = [2, 2, 2]\nscale = -1\nmaterial = \"w\"\n", "objects[0].scale"),
            ("[[objects]]\nshape = \"mesh\"\nfile = \"x.stl\"\nposition = [2, 2, 2]\nmaterial = \"w\"\n", "objects[0].file: unsupported"),
            ("[[objects]]\nshape = \"box\"\nsize = [1, 1, 1]\nposition = [2, 2, 2]\nmaterial = \"w\"\nanimation = { type = \"orbit\", center = [0, 0, 0], period = 0 }\n", "objects[0].animation.period: must be positive"),
            ("[[objects]]\nshape = \"box\"\nsize = [1, 1, 1]\nposition = [2, 2, 2]\nmaterial = \"w\"\nanimation = { type = \"linear\", to = [0, 0, 0], duration = 1, period = 2 }\n", "objects[0].animation.period: not allowed"),
            ("[[objects]]\nshape = \"box\"\nsize = [1, 1, 1]\nposition = [2, 2, 2]\nmaterial = \"w\"\nanimation = { type = \"keyframes\", times = [0, 1], positions = [[1, 1, 1], [2, 2, 2]] }\n", "objects[0].animation.positions[0]: the first keyframe"),
            ("[[materials]]\nname = \"w\"\ntype = \"color\"\ncolor = [1, 1, 1]\n", "materials[1].name: duplicate"),
            ("[[materials]]\nname = \"g\"\ntype = \"grid\"\nbackground = [1, 1, 1]\nline = [0, 0, 0]\nline_width = 0.7\n", "materials[1].line_width"),
        ];
        for (extra, needle) in cases {
            let text = format!("{MINIMAL}{extra}");
            let err = load_str(&text, Path::new("case.toml")).expect_err(extra);
            let msg = err.to_string();
            assert!(
                msg.contains(needle),
                "{extra:?}: expected {needle:?} in {msg}"
            );
            assert!(msg.starts_with("case.toml:"), "{msg}");
            assert!(err.line().is_some(), "{msg}");
        }
    }

    #[test]
    fn shipped_scenes_load() {
        for rel in [
            "scenes/thesis-room.toml",
            "scenes/moving-objects.toml",
            "scenes/many-objects.toml",
            "scenes/test/six-colour-room.toml",
            "scenes/test/direction-room.toml",
            "scenes/hard/near-walls.toml",
            "scenes/hard/far-field.toml",
            "scenes/heavy.toml",
        ] {
            let s = load(&repo(rel)).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(s.mirror.radius_m, 1.0, "{rel}");
            for o in &s.objects {
                assert!(o.mesh < s.meshes.len() && o.material < s.materials.len());
            }
            for m in s.room.wall_materials {
                assert!(m < s.materials.len());
            }
        }
        // The heavy scene states its size: about a million triangles.
        let heavy = load(&repo("scenes/heavy.toml")).unwrap();
        let triangles: usize = heavy
            .objects
            .iter()
            .map(|o| heavy.meshes[o.mesh].triangle_count())
            .sum();
        assert_eq!((heavy.objects.len(), triangles + 12), (2800, 974_440));
        let thesis = load(&repo("scenes/thesis-room.toml")).unwrap();
        assert_eq!(thesis.sensor.offset_m, 2.5);
        assert_eq!(thesis.cube.face_size_px, 512);
        assert_eq!(thesis.textures.len(), 1);
        assert_eq!(
            (thesis.textures[0].width, thesis.textures[0].height),
            (128, 128)
        );
        assert!(thesis.objects.iter().any(|o| o.animation.is_some()));

        let moving = load(&repo("scenes/moving-objects.toml")).unwrap();
        let moving_count = moving
            .objects
            .iter()
            .filter(|o| o.animation.is_some())
            .count();
        assert!(moving_count >= 6);
        assert!(moving.mirror.animation.is_some());
        // Distinct meshes: 2 box sizes, 2 sphere radii, 2 cylinders, the OBJ and the glTF.
        assert_eq!(moving.meshes.len(), 8);

        let six = load(&repo("scenes/test/six-colour-room.toml")).unwrap();
        let colour = |face: usize| match &six.materials[six.room.wall_materials[face]].kind {
            MaterialKind::Color { color } => *color,
            other => panic!("{other:?}"),
        };
        assert_eq!(colour(0), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(colour(1), Vec3::new(0.0, 1.0, 1.0));
        assert_eq!(colour(2), Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(colour(3), Vec3::new(1.0, 0.0, 1.0));
        assert_eq!(colour(4), Vec3::new(0.0, 0.0, 1.0));
        assert_eq!(colour(5), Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(six.refresh, RefreshPolicy::EveryFrame);
    }

    fn triangles(s: &Scene) -> usize {
        s.objects
            .iter()
            .map(|o| s.meshes[o.mesh].triangle_count())
            .sum()
    }

    /// An object as exactly comparable data: name, mesh, material, the bits of position,
    /// rotation and scale, and the animation.
    type ObjectBits = (String, usize, usize, [u32; 10], Option<Animation>);

    fn bits(s: &Scene) -> Vec<ObjectBits> {
        s.objects
            .iter()
            .map(|o| {
                let (p, r, k) = (o.position, o.rotation, o.scale);
                let v = [p.x, p.y, p.z, r.x, r.y, r.z, r.w, k.x, k.y, k.z];
                (
                    o.name.clone(),
                    o.mesh,
                    o.material,
                    v.map(f32::to_bits),
                    o.animation.clone(),
                )
            })
            .collect()
    }

    #[test]
    fn many_objects_scene_has_the_stated_counts() {
        let s = load(&repo("scenes/many-objects.toml")).unwrap_or_else(|e| panic!("{e}"));
        let moving = s.objects.iter().filter(|o| o.animation.is_some()).count();
        let tris = triangles(&s);
        eprintln!(
            "many-objects: {} objects, {tris} triangles, {moving} moving, {} meshes",
            s.objects.len(),
            s.meshes.len()
        );
        assert_eq!(s.objects.len(), 2000);
        assert!((190_000..=210_000).contains(&tris), "{tris} triangles");
        assert_eq!(moving, 200);
        // One mesh per (shape, tessellation): box, sphere 16, cylinder 16.
        assert_eq!(s.meshes.len(), 3);
        assert_eq!(s.refresh, RefreshPolicy::OnChange);
        assert_eq!(s.cube.face_size_px, 512);
        assert_eq!(s.mirror.radius_m, 1.0);
    }

    #[test]
    fn generation_is_deterministic_and_seeded() {
        let path = repo("scenes/many-objects.toml");
        let a = load(&path).unwrap();
        let b = load(&path).unwrap();
        assert_eq!(bits(&a), bits(&b));
        assert_eq!(a.meshes, b.meshes);

        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("seed = 7\n"));
        let c = load_str(&text.replace("seed = 7\n", "seed = 8\n"), &path).unwrap();
        let (a, c) = (bits(&a), bits(&c));
        // The first generator is untouched; the reseeded one has a different layout.
        assert_eq!(a[..1800], c[..1800]);
        let same = a[1800..]
            .iter()
            .zip(&c[1800..])
            .filter(|(x, y)| x.3[..3] == y.3[..3])
            .count();
        assert_eq!(same, 0, "{same} of 200 positions unchanged by the new seed");
    }

    #[test]
    fn generated_objects_stay_in_their_region_and_clear_of_the_mirror() {
        let s = load(&repo("scenes/many-objects.toml")).unwrap();
        let (lo, hi) = (
            s.room.center - s.room.size_m * 0.5,
            s.room.center + s.room.size_m * 0.5,
        );
        let regions = [
            (
                "clutter[",
                Vec3::new(-4.6, 0.2, -4.6),
                Vec3::new(4.6, 5.6, 4.6),
            ),
            (
                "orbiters[",
                Vec3::new(-4.5, 0.5, -4.5),
                Vec3::new(4.5, 5.5, 4.5),
            ),
        ];
        let keep_clear = 0.5;
        let sensor = s.mirror.center - Vec3::Y * s.sensor.offset_m;
        // The regions are written in world coordinates; positions are local to the mirror.
        let local = s.origin.as_vec3();
        for o in &s.objects {
            let (_, rmin, rmax) = regions
                .iter()
                .find(|r| o.name.starts_with(r.0))
                .map(|&(n, a, b)| (n, a - local, b - local))
                .unwrap_or_else(|| panic!("{}", o.name));
            assert!(
                o.position.cmpge(rmin).all() && o.position.cmple(rmax).all(),
                "{} at {} outside its region",
                o.name,
                o.position
            );
            // Built-in unit shapes: the scale is the size.
            let size = o.scale.x;
            assert!(o.scale == Vec3::splat(size) && (0.1..=0.4).contains(&size));
            for t in sample_times(o.animation.as_ref()) {
                let p = position_at(o.animation.as_ref(), o.position, t);
                assert!(
                    p.cmpge(lo).all() && p.cmple(hi).all(),
                    "{} leaves the room",
                    o.name
                );
                let d = p.distance(s.mirror.center);
                assert!(
                    d > s.mirror.radius_m + keep_clear + size - 1e-4,
                    "{} at t = {t} is {d} m from the mirror centre",
                    o.name
                );
                // The sensor's line of sight (the vertical segment below the mirror centre).
                let y = p.y.clamp(sensor.y, s.mirror.center.y);
                let to_axis = p.distance(Vec3::new(sensor.x, y, sensor.z));
                assert!(to_axis > s.mirror.radius_m + keep_clear + size - 1e-4);
                assert!(p.distance(s.observer.position) > keep_clear + size - 1e-4);
            }
        }
    }

    #[test]
    fn generator_rules_with_their_fields() {
        let gen = "[[generate]]\ncount = 10\nshapes = [\"box\"]\nsize = [0.1, 0.2]\n\
                   region_min = [-4, 1, -4]\nregion_max = [4, 5, 4]\nmaterials = [\"w\"]\n";
        let ok = load_str(&format!("{MINIMAL}{gen}"), Path::new("g.toml")).unwrap();
        assert_eq!(ok.objects.len(), 10);
        assert_eq!(ok.objects[3].name, "generate[0][3]");
        assert!(ok.objects.iter().all(|o| o.animation.is_none()));
        let cases: &[(&str, &str)] = &[
            ("count = 10", "count = 0"),
            ("count = 10", "count = 100001"),
            ("count = 10", "count = 10\nseed = -1"),
            ("shapes = [\"box\"]", "shapes = []"),
            ("shapes = [\"box\"]", "shapes = [\"mesh\"]"),
            ("shapes = [\"box\"]", "shapes = [\"box\"]\nfile = \"a.obj\""),
            ("shapes = [\"box\"]", "shapes = [\"box\"]\nsegments = 8"),
            ("shapes = [\"box\"]", "shapes = [\"sphere\"]\nsegments = 2"),
            ("size = [0.1, 0.2]", "size = [0.3, 0.2]"),
            ("size = [0.1, 0.2]", "size = [0, 0.2]"),
            ("region_max = [4, 5, 4]", "region_max = [4, 0.5, 4]"),
            ("region_min = [-4, 1, -4]", "region_min = [-4, -1, -4]"),
            ("materials = [\"w\"]", "materials = []"),
            ("materials = [\"w\"]", "materials = [\"w\", \"gold\"]"),
            ("count = 10", "count = 10\nkeep_clear = -1"),
            ("count = 10", "count = 10\nmoving = 1.5"),
            ("count = 10", "count = 10\nperiod = [8, 20]"),
            ("count = 10", "count = 10\nmoving = 1\nperiod = [20, 8]"),
            ("count = 10", "count = 10\nname = \" \""),
            ("count = 10", "count = 10\ncolour = 3"),
            // The region lies inside the mirror's keep-clear zone: nowhere to put anything.
            (
                "region_min = [-4, 1, -4]\nregion_max = [4, 5, 4]",
                "region_min = [-0.5, 2.5, -0.5]\nregion_max = [0.5, 3.5, 0.5]\nkeep_clear = 0.1",
            ),
            // Every position in the region's corners is too far out for an orbit.
            (
                "region_min = [-4, 1, -4]\nregion_max = [4, 5, 4]",
                "region_min = [4, 1, 4]\nregion_max = [4.9, 5, 4.9]\nmoving = 1",
            ),
        ];
        let expected = [
            "generate[0].count: must be in 1..=100000, got 0",
            "generate[0].count: must be in 1..=100000, got 100001",
            "generate[0].seed: must be in 0..=",
            "generate[0].shapes: needs at least one shape",
            "generate[0].file: required field is missing",
            "generate[0].file: not allowed here",
            "generate[0].segments: not allowed here",
            "generate[0].segments: must be in 3..=256, got 2",
            "generate[0].size[1]: must be >= generate[0].size[0]",
            "generate[0].size[0]: must be positive",
            "generate[0].region_max[1]: must be >= region_min[1]",
            "generate[0].region_min[1]: -1 is outside the room (y from 0 to 6)",
            "generate[0].materials: needs at least one material",
            "generate[0].materials[1]: unknown material \"gold\"",
            "generate[0].keep_clear: must be >= 0",
            "generate[0].moving: must be in [0, 1]",
            "generate[0].period: not allowed here",
            "generate[0].period[1]: must be >=",
            "generate[0].name: must not be empty",
            "generate[0].colour: unknown field",
            "generate[0].keep_clear: cannot place generate[0][0]",
            "generate[0].moving: cannot place generate[0][0]",
        ];
        assert_eq!(cases.len(), expected.len());
        for ((from, to), needle) in cases.iter().zip(expected) {
            assert!(gen.contains(from), "{from}");
            let text = format!("{MINIMAL}{}", gen.replace(from, to));
            let err = load_str(&text, Path::new("case.toml")).expect_err(to);
            let msg = err.to_string();
            assert!(msg.contains(needle), "{to:?}: expected {needle:?} in {msg}");
            assert!(msg.starts_with("case.toml:"), "{msg}");
            assert!(err.line().is_some(), "{msg}");
        }
    }

    #[test]
    fn generated_meshes_are_shared_and_scaled() {
        let text = format!(
            "{MINIMAL}[[objects]]\nshape = \"mesh\"\nfile = \"meshes/arrow.obj\"\n\
             position = [3, 1, 3]\nmaterial = \"w\"\n\
             [[generate]]\nname = \"a\"\ncount = 50\nshapes = [\"box\", \"sphere\", \"mesh\"]\n\
             file = \"meshes/arrow.obj\"\nsize = [0.2, 0.2]\nsegments = 8\n\
             region_min = [-4, 1, -4]\nregion_max = [4, 5, 4]\nmaterials = [\"w\"]\n\
             [[generate]]\nname = \"b\"\ncount = 50\nshapes = [\"box\", \"cylinder\"]\n\
             size = [0.3, 0.5]\nsegments = 8\n\
             region_min = [-4, 1, -4]\nregion_max = [4, 5, 4]\nmaterials = [\"w\"]\n"
        );
        let s = load_str(&text, &repo("scenes/gen.toml")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.objects.len(), 101);
        assert_eq!(s.objects[1].name, "a[0]");
        assert_eq!(s.objects[100].name, "b[49]");
        // arrow (shared with the file's object), unit box, sphere 8, cylinder 8.
        assert_eq!(s.meshes.len(), 4);
        let arrow = &s.meshes[s.objects[0].mesh];
        let side = (arrow.bounds_max - arrow.bounds_min).max_element();
        for o in &s.objects[1..] {
            let m = &s.meshes[o.mesh];
            // Every generated object's bounding box has the drawn size as its largest side.
            let extent = ((m.bounds_max - m.bounds_min) * o.scale).max_element();
            if o.name.starts_with("a[") {
                assert!((extent - 0.2).abs() < 1e-5, "{}: {extent}", o.name);
            } else {
                assert!((0.3 - 1e-5..=0.5 + 1e-5).contains(&extent), "{}", o.name);
            }
            if o.mesh == s.objects[0].mesh {
                assert!((o.scale.x - 0.2 / side).abs() < 1e-6);
            }
        }
        let sphere = s
            .meshes
            .iter()
            .filter(|m| m.triangle_count() == 8 * 6)
            .count();
        assert_eq!(sphere, 1, "sphere of 8 segments x 4 rings: 48 triangles");
    }

    #[test]
    fn obj_and_gltf_meshes_load_with_expected_triangles() {
        let obj = Mesh::from_obj(&repo("scenes/meshes/arrow.obj")).unwrap();
        assert_eq!(obj.triangle_count(), 18);
        let gltf = Mesh::from_gltf(&repo("scenes/meshes/pyramid.gltf")).unwrap();
        assert_eq!(gltf.triangle_count(), 6);
        // The node's scale 0.5 and translation +0.25 y are applied.
        assert!((gltf.bounds_min - Vec3::new(-0.5, 0.25, -0.5)).length() < 1e-6);
        assert!((gltf.bounds_max - Vec3::new(0.5, 1.0, 0.5)).length() < 1e-6);
        for m in [&obj, &gltf] {
            // Closed and outward: positive signed volume; face normals agree with winding.
            let vol: f32 = m
                .indices
                .chunks_exact(3)
                .map(|t| {
                    let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
                    a.dot(b.cross(c)) / 6.0
                })
                .sum();
            assert!(vol > 0.0);
            for t in m.indices.chunks_exact(3) {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
                assert!((b - a).cross(c - a).dot(m.normals[t[0] as usize]) > 0.0);
            }
        }
        assert!(Mesh::from_obj(&repo("scenes/meshes/missing.obj")).is_err());
    }
}
