//! `[[objects]]`: shapes, mesh files, transforms; meshes are built once per key and shared.

use std::collections::HashMap;

use glam::{Quat, Vec3};

use super::{Ctx, MeshBuilder, CYLINDER_SEGMENTS, R, SPHERE_RINGS, SPHERE_SEGMENTS};
use crate::scene::error::SceneError;
use crate::scene::format::{AnimationSpec, AnimationType, ObjectSpec, ScaleSpec, Shape};
use crate::scene::mesh::Mesh;
use crate::scene::Object;

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
    pub(super) fn cached_mesh(
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

    pub(super) fn object(
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
}
