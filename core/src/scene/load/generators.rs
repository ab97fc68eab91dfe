//! `[[generate]]`: validates a generator table and prepares its shared unit meshes; the
//! expansion into objects is `scene::generate`'s.

use super::numbers::{num_text, Range};
use super::objects::{unit_shape, MeshStore};
use super::{Ctx, R};
use crate::scene::format::{GenerateSpec, Shape};
use crate::scene::generate::{
    self, Params, ShapeChoice, Surroundings, DEFAULT_SEGMENTS, MAX_COUNT, MAX_SEGMENTS,
    PLACEMENT_TRIES,
};
use crate::scene::{Object, Room};

impl Ctx<'_> {
    /// The objects of `[[generate]]` table `i`: validated, checked against the triangle budget
    /// (before any object is made), then placed.
    pub(super) fn generated(
        &self,
        i: usize,
        g: &GenerateSpec,
        material: &dyn Fn(&str, &str) -> R<usize>,
        room: &Room,
        surroundings: &Surroundings,
        store: &mut MeshStore,
    ) -> R<Vec<Object>> {
        let params = self.generator(i, g, material, room, store)?;
        // Any object may draw the largest of the shapes: the bound holds for every seed.
        let largest = params
            .shapes
            .iter()
            .map(|s| store.meshes[s.mesh].triangle_count() as u64)
            .max()
            .unwrap_or(0);
        self.triangle_budget(
            &format!("generate[{i}].count"),
            &mut store.triangles,
            u64::from(params.count) * largest,
            &format!(
                "count {} x {largest} triangles (its largest shape; fewer segments make fewer)",
                params.count
            ),
        )?;
        generate::expand(&params, surroundings).map_err(|fail| {
            let (field, why) = if fail.orbit_outside > fail.too_close {
                ("moving", "its orbit about the room's vertical axis left the room")
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
        })
    }

    /// Validates a `[[generate]]` table and builds (or reuses) its unit meshes.
    pub(super) fn generator(
        &self,
        i: usize,
        g: &GenerateSpec,
        material: &dyn Fn(&str, &str) -> R<usize>,
        room: &Room,
        store: &mut MeshStore,
    ) -> R<Params> {
        let f = |name: &str| format!("generate[{i}].{name}");
        let name = match &g.name {
            Some(n) if n.trim().is_empty() => {
                return Err(self.invalid(&f("name"), "must not be empty"))
            }
            Some(n) => n.clone(),
            None => format!("generate[{i}]"),
        };
        let class = self.class(&f("class"), g.class.as_deref())?;
        let count = self.count(&f("count"), g.count, MAX_COUNT)?;
        let seed = match g.seed {
            None => 0,
            Some(s) => u64::try_from(s).map_err(|_| {
                self.invalid(&f("seed"), format!("must be in 0..={}, got {s}", i64::MAX))
            })?,
        };
        let shapes = self.generator_shapes(&f, g, store)?;
        if g.materials.is_empty() {
            return Err(self.invalid(&f("materials"), "needs at least one material"));
        }
        let materials = (g.materials.iter().enumerate())
            .map(|(j, m)| material(&f(&format!("materials[{j}]")), m))
            .collect::<R<Vec<usize>>>()?;
        let size = self.interval(&f("size"), g.size)?;
        // Every object it may make is an object, within the objects' scales.
        for choice in &shapes {
            for end in size {
                let scale = glam::Vec3::splat(end * choice.scale_per_size);
                if let Some(why) = super::objects::scale_out_of_range(scale) {
                    return Err(self.invalid(
                        &f("size"),
                        format!(
                            "a {} of size {} m is scaled by {}: {why}",
                            choice.name,
                            crate::text::num_text(end),
                            crate::text::num_text(scale.x)
                        ),
                    ));
                }
            }
        }
        let (region_min, region_max) = self.generator_region(&f, g, room)?;
        let keep_clear = self.non_negative(&f("keep_clear"), g.keep_clear.unwrap_or(0.0))?;
        let moving = self.ranged(
            &f("moving"),
            g.moving.unwrap_or(0.0),
            Range::closed(0.0, 1.0),
        )?;
        if g.period.is_some() && moving == 0.0 {
            return Err(self.unused(&f("period"), "period is used only when moving > 0"));
        }
        // Exactly round(moving × count) objects move (generate.rs): a share that rounds to
        // none moved nothing, and its period went unused, without a word.
        if moving > 0.0 && crate::scene::generate::movers(moving, count) == 0 {
            return Err(self.invalid(
                &f("moving"),
                format!(
                    "{} of {count} object(s) is none (exactly round(moving x count) move): give \
                     at least {}, or 0 for none",
                    crate::text::num_text(moving),
                    crate::text::num_text(crate::scene::generate::least_share(count))
                ),
            ));
        }
        let period = self.interval(&f("period"), g.period.unwrap_or([8.0, 20.0]))?;
        Ok(Params {
            name,
            class,
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

    /// The generator's shapes, each a unit mesh (built once per shape and tessellation, shared
    /// by every generator) with how it scales; checks the fields only some shapes use.
    fn generator_shapes(
        &self,
        f: &dyn Fn(&str) -> String,
        g: &GenerateSpec,
        store: &mut MeshStore,
    ) -> R<Vec<ShapeChoice>> {
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
            let choice = match unit_shape(shape, segments) {
                // Unit-size shapes (size 1 m) scaled per object.
                Some((key, build)) => ShapeChoice {
                    mesh: self.cached_mesh(&f("shapes"), None, key, build, store)?,
                    name: shape.name().to_owned(),
                    scale_per_size: 1.0,
                    reach_per_size: 1.0,
                },
                None => self.generator_mesh(f, g.file.as_deref().unwrap_or_default(), store)?,
            };
            shapes.push(choice);
        }
        Ok(shapes)
    }

    /// The `"mesh"` shape: the file's mesh, its size the largest side of its bounding box; the
    /// clearance radius also covers the farthest vertex from the mesh's origin.
    fn generator_mesh(
        &self,
        f: &dyn Fn(&str) -> String,
        file: &str,
        store: &mut MeshStore,
    ) -> R<ShapeChoice> {
        let (key, build) = self.mesh_file(&f("file"), file)?;
        let index = self.cached_mesh(&f("file"), Some(file), key, build, store)?;
        let m = &store.meshes[index];
        let side = (m.bounds_max - m.bounds_min).max_element();
        if !(side > 0.0 && side.is_finite()) {
            return Err(self.invalid(
                &f("file"),
                format!("mesh \"{file}\" has no extent to scale"),
            ));
        }
        let farthest = (m.positions.iter())
            .map(|p| p.length())
            .fold(0.0f32, f32::max);
        Ok(ShapeChoice {
            mesh: index,
            name: Shape::Mesh.describe(Some(file)),
            scale_per_size: 1.0 / side,
            reach_per_size: (farthest / side).max(1.0),
        })
    }

    /// The region objects are placed in: inside the room, its low corner at or below its
    /// high one, axis by axis. Messages give world coordinates, as the file does.
    fn generator_region(
        &self,
        f: &dyn Fn(&str) -> String,
        g: &GenerateSpec,
        room: &Room,
    ) -> R<(glam::Vec3, glam::Vec3)> {
        let region_min = self.point(&f("region_min"), g.region_min)?;
        let region_max = self.point(&f("region_max"), g.region_max)?;
        let (lo, hi) = (
            room.center - room.size_m * 0.5,
            room.center + room.size_m * 0.5,
        );
        let world = |axis: usize, v: f32| num_text((self.origin[axis] + f64::from(v)) as f32);
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
        Ok((region_min, region_max))
    }
}
