//! `[[objects]]`: shapes, mesh files, transforms; meshes are built once per key and shared.

use std::collections::HashMap;

use glam::{Quat, Vec3};

use super::numbers::num_text;
use super::{Ctx, MeshBuilder, CYLINDER_SEGMENTS, R, SPHERE_SEGMENTS};
use crate::scene::error::SceneError;
use crate::scene::format::{AnimationSpec, AnimationType, FrameSpec, ObjectSpec, ScaleSpec, Shape};
use crate::scene::mesh::Mesh;
use crate::scene::{Object, ObjectFrame, DEFAULT_CLASS, MAX_CLASS_LEN};

/// How far from the sensor camera's eye an object in its frame may be (m): the robot's own
/// parts (a camera body, a lens barrel, a mount down to the floor) are within a few metres.
pub const MAX_SENSOR_OFFSET_M: f32 = 10.0;

/// The cache key and builder of a built-in shape at unit size (1 m across: a cube with edges 1,
/// a sphere of diameter 1 with `segments` around and max(2, segments / 2) rings, a cylinder of
/// diameter and height 1 with `segments` around). Objects of any size share it and get their
/// size through their transform (`Object::scale`), so a scene's memory does not grow with the
/// number of distinct sizes. `None` for `Shape::Mesh`.
pub(super) fn unit_shape(shape: Shape, segments: u32) -> Option<(String, MeshBuilder)> {
    let rings = (segments / 2).max(2);
    Some(match shape {
        Shape::Box => (
            "unit-box".into(),
            Box::new(|| Ok(Mesh::cuboid(Vec3::splat(0.5)))),
        ),
        Shape::Sphere => (
            format!("unit-sphere:{segments}"),
            Box::new(move || Ok(Mesh::uv_sphere(0.5, segments, rings))),
        ),
        Shape::Cylinder => (
            format!("unit-cylinder:{segments}"),
            Box::new(move || Ok(Mesh::cylinder(0.5, 0.5, segments))),
        ),
        Shape::Mesh => return None,
    })
}

/// The scene's distinct meshes, the key each was built under, and the triangles one pass over
/// the objects made so far draws (for the budget).
#[derive(Default)]
pub(super) struct MeshStore {
    pub meshes: Vec<Mesh>,
    pub cache: HashMap<String, usize>,
    pub triangles: u64,
}

impl Ctx<'_> {
    /// The cache key and loader of a mesh file named by `field`.
    pub(super) fn mesh_file(&self, field: &str, file: &str) -> R<(String, MeshBuilder)> {
        let path = self.dir.join(file);
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let p = path.clone();
        let build: MeshBuilder = match ext.as_deref() {
            // The loaders read through `files::read_regular_file`, which says what the path
            // is when it is not a regular file (a folder, a FIFO, a symlink loop, missing).
            Some("obj") => Box::new(move || Mesh::from_obj(&p)),
            Some("gltf") | Some("glb") => Box::new(move || Mesh::from_gltf(&p)),
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
    pub(super) fn cached_mesh(
        &self,
        field: &str,
        file: Option<&str>,
        key: String,
        build: MeshBuilder,
        store: &mut MeshStore,
    ) -> R<usize> {
        let MeshStore { meshes, cache, .. } = store;
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
        self.geometry_budget(field, meshes)?;
        cache.insert(key, meshes.len() - 1);
        Ok(meshes.len() - 1)
    }

    pub(super) fn object(
        &self,
        i: usize,
        o: &ObjectSpec,
        material: &dyn Fn(&str, &str) -> R<usize>,
        store: &mut MeshStore,
    ) -> R<Object> {
        let f = |name: &str| format!("objects[{i}].{name}");
        self.shape_keys(&f, o)?;
        let (mesh, size) = self.object_mesh(&f, o, store)?;
        let triangles = store.meshes[mesh].triangle_count() as u64;
        self.triangle_budget(
            &format!("objects[{i}]"),
            &mut store.triangles,
            triangles,
            "this object",
        )?;
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
        let scale = self.object_scale(&f, o, size)?;
        let frame = self.object_frame(&f, o)?;
        let position = match frame {
            ObjectFrame::World => self.object_position(i, &f, o)?,
            ObjectFrame::Sensor => self.offset_from_sensor(&f("position"), o)?,
        };
        let animation = match &o.animation {
            Some(a) => Some(self.animation(&f("animation"), a, position)?),
            None => None,
        };
        Ok(Object {
            name: o.name.clone().unwrap_or_else(|| format!("objects[{i}]")),
            class: self.class(&f("class"), o.class.as_deref())?,
            mesh,
            material,
            shape: o.shape.describe(o.file.as_deref()),
            frame,
            position,
            rotation,
            scale,
            animation,
        })
    }

    /// An object's class as the file gives it (`field`), or [`DEFAULT_CLASS`]: 1 to
    /// [`MAX_CLASS_LEN`] letters, digits, `_` or `-`, so that it is one word in any tool's
    /// label file.
    pub(super) fn class(&self, field: &str, class: Option<&str>) -> R<String> {
        let Some(class) = class else {
            return Ok(DEFAULT_CLASS.to_owned());
        };
        let word = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
        if class.is_empty() || class.len() > MAX_CLASS_LEN || !class.chars().all(word) {
            let why = format!(
                "must be 1 to {MAX_CLASS_LEN} letters, digits, `_` or `-` (a class such as \
                 \"chair\"), got {class:?}"
            );
            return Err(self.invalid(field, why));
        }
        Ok(class.to_owned())
    }

    /// Refuses a key that the object's shape does not take.
    fn shape_keys(&self, f: &dyn Fn(&str) -> String, o: &ObjectSpec) -> R<()> {
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
                    &format!(
                        "shape = \"{}\" takes only {}",
                        o.shape.name(),
                        allowed.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The object's mesh in the store and the size its shape gives it. Built-in shapes share
    /// one unit mesh per shape and tessellation (also with the generators); the object's size
    /// becomes a scale in its transform, which the renderer and the reference apply to normals
    /// through the inverse transpose.
    fn object_mesh(
        &self,
        f: &dyn Fn(&str) -> String,
        o: &ObjectSpec,
        store: &mut MeshStore,
    ) -> R<(usize, Vec3)> {
        let need = |v: Option<f64>, name: &str| -> R<f32> {
            let needs = || format!("shape = \"{}\" needs it", o.shape.name());
            let v = v.ok_or_else(|| self.missing(&f(name), &needs()))?;
            self.positive(&f(name), v)
        };
        let (size, segments) = match o.shape {
            Shape::Box => (
                self.positive3(
                    &f("size"),
                    o.size
                        .ok_or_else(|| self.missing(&f("size"), "a box needs [x, y, z]"))?,
                )?,
                0,
            ),
            Shape::Sphere => (
                Vec3::splat(2.0 * need(o.radius, "radius")?),
                SPHERE_SEGMENTS,
            ),
            Shape::Cylinder => {
                let d = 2.0 * need(o.radius, "radius")?;
                let h = need(o.height, "height")?;
                (Vec3::new(d, h, d), CYLINDER_SEGMENTS)
            }
            Shape::Mesh => (Vec3::ONE, 0),
        };
        let (key, build): (String, MeshBuilder) = match unit_shape(o.shape, segments) {
            Some(unit) => unit,
            None => {
                let file = (o.file.as_ref())
                    .ok_or_else(|| self.missing(&f("file"), "a .obj, .gltf or .glb file"))?;
                self.mesh_file(&f("file"), file)?
            }
        };
        let mesh = self.cached_mesh(&f("file"), o.file.as_deref(), key, build, store)?;
        Ok((mesh, size))
    }

    /// The shape's size times the object's scale, in one f32 scale per axis within
    /// [`OBJECT_SCALE`] (1e30 x 1e30 and 1e-30 x 1e-30 are not even f32s).
    fn object_scale(&self, f: &dyn Fn(&str) -> String, o: &ObjectSpec, size: Vec3) -> R<Vec3> {
        let scale = match o.scale {
            None => Vec3::ONE,
            Some(ScaleSpec::Uniform(s)) => Vec3::splat(self.positive(&f("scale"), s)?),
            Some(ScaleSpec::PerAxis(s)) => self.positive3(&f("scale"), s)?,
        };
        let scale = size * scale;
        if !(scale.is_finite() && scale.min_element() > 0.0) {
            return Err(self.invalid(
                &f("scale"),
                format!(
                    "size x scale is {}, which single precision cannot hold (each must be a positive finite number)",
                    scale
                ),
            ));
        }
        if let Some(why) = scale_out_of_range(scale) {
            return Err(self.invalid(&f("scale"), format!("size x scale is {scale}: {why}")));
        }
        Ok(scale)
    }

    /// Whose frame the object is placed in. One in the sensor's moves with the camera and
    /// takes no animation of its own.
    fn object_frame(&self, f: &dyn Fn(&str) -> String, o: &ObjectSpec) -> R<ObjectFrame> {
        match o.frame {
            None | Some(FrameSpec::World) => Ok(ObjectFrame::World),
            Some(FrameSpec::Sensor) if o.animation.is_some() => Err(self.unused(
                &f("animation"),
                "an object in the sensor's frame moves with the sensor camera (the robot); \
                 it takes no animation of its own",
            )),
            Some(FrameSpec::Sensor) => Ok(ObjectFrame::Sensor),
        }
    }

    /// An object's offset from the sensor camera's eye (metres, along the camera's axes: x
    /// right, y down, z forward); within [`MAX_SENSOR_OFFSET_M`], since a part of the robot
    /// stays near its camera.
    fn offset_from_sensor(&self, field: &str, o: &ObjectSpec) -> R<Vec3> {
        let p = o
            .position
            .ok_or_else(|| self.missing(field, "the offset from the sensor camera's eye"))?;
        let v = self.vec3(field, p)?;
        if v.length() > MAX_SENSOR_OFFSET_M {
            return Err(self.invalid(
                field,
                format!(
                    "an offset of {} m from the sensor camera; a part of the robot placed in \
                     the sensor's frame stays within {MAX_SENSOR_OFFSET_M} m of it",
                    num_text(v.length())
                ),
            ));
        }
        Ok(v)
    }

    /// Where the object is: its `position`, or, for a keyframed object that leaves it out,
    /// its first key.
    fn object_position(&self, i: usize, f: &dyn Fn(&str) -> String, o: &ObjectSpec) -> R<Vec3> {
        let keyframe_start = match &o.animation {
            Some(AnimationSpec {
                kind: AnimationType::Keyframes,
                positions: Some(p),
                ..
            }) => p.first().copied(),
            _ => None,
        };
        match (o.position, keyframe_start) {
            (Some(p), _) => self.point(&f("position"), p),
            (None, Some(p)) => self.point(&format!("objects[{i}].animation.positions[0]"), p),
            (None, None) => Err(self.missing(&f("position"), "where the object is")),
        }
    }
}

/// The scales (model to render, per axis) an object may have: the exact tracers (the
/// reference, `bvh`) enter an object through its inverse transform in single precision, whose
/// entries are the scales' reciprocals and whose determinant their product: below 1e-11 or
/// above 1e11 an axis leaves too little of the floats (a box 1e-13 m thick had no inverse
/// at all for `bvh`, and the reference placed it in render space instead: the two disagreed
/// on a hundred pixels). An object smaller than 1e-11 m or larger than 1e11 m in a room a
/// single-precision renderer resolves is a mistake in the file.
pub const OBJECT_SCALE: (f32, f32) = (1e-11, 1e11);

/// Why `scale` is outside [`OBJECT_SCALE`], if it is.
pub(super) fn scale_out_of_range(scale: Vec3) -> Option<String> {
    let (lo, hi) = OBJECT_SCALE;
    (scale.min_element() < lo || scale.max_element() > hi).then(|| {
        format!(
            "each axis must be within [{lo:e}, {hi:e}] (the exact tracers move rays into the \
             object's own space by the inverse scale, in single precision)"
        )
    })
}
