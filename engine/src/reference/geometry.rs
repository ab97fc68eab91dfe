//! The scene in render space (world minus the mirror centre): the room's walls as an analytic
//! box, the objects as triangles with a BVH over them.

use std::time::{Duration, Instant};

use glam::{Mat4, Vec2, Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::{Boundable, BvhBuildParams};

use super::intersect::{AxisVisitor, ShearedRay, TriangleHit};
use super::room::RoomBox;
use crate::scene::state::SceneState;
use crate::scene::{Mesh, Scene};

/// Per-vertex shading attributes of one object triangle, and what it belongs to.
#[derive(Debug, Clone, Copy)]
pub struct TriangleInfo {
    pub normals: [Vec3; 3],
    pub uvs: [Vec2; 3],
    /// Drawable index as on the GPU: 6 + scene object index (0..6 are the room's walls).
    pub object: u32,
    pub material: u32,
}

/// The scene at one instant: the room's box, and the objects' triangles with a BVH for
/// closest-hit queries.
pub struct SceneGeometry {
    room: RoomBox,
    /// The walls' materials, in the room box's face order.
    wall_materials: [u32; 6],
    /// The objects' triangles (not the walls').
    pub triangles: Vec<[Vec3; 3]>,
    pub info: Vec<TriangleInfo>,
    /// `None` when no object has a triangle (an empty room).
    bvh: Option<CwBvh>,
    /// The triangles again, in the BVH's leaf order and 16-byte aligned: the traversal reads
    /// them straight, without the BVH's index table, each corner one aligned load.
    leaf_triangles: Vec<[Vec3A; 3]>,
    /// Each object's (padded) bounding box when there are at most [`CULL_OBJECTS`] objects,
    /// else empty: see [`SceneGeometry::closest_hit`].
    object_boxes: Vec<Aabb>,
    /// Time spent building the BVH (the core build, as obvhs measures it, and in all).
    pub build_core: Duration,
    pub build_total: Duration,
}

/// A triangle whose bounding box is padded by a few float steps of its coordinates.
///
/// The triangle test is watertight, but a BVH node test is a slab test in float: a ray that
/// meets a room edge exactly (where two flat, zero-thickness wall boxes touch) can be rounded
/// out of both boxes and never reach the triangles. Padding every box makes traversal
/// conservative (the idea of Ize, "Robust BVH Ray Traversal", JCGT 2013, applied to the boxes
/// instead of the ray interval); the triangle test still decides every hit exactly.
struct PaddedTriangle([Vec3; 3]);

/// Box padding relative to the largest coordinate magnitude (about 64 float steps).
const BOX_PAD_RELATIVE: f32 = 64.0 * f32::EPSILON;

impl Boundable for PaddedTriangle {
    fn aabb(&self) -> Aabb {
        let [a, b, c] = self.0;
        padded_box(a.min(b).min(c), a.max(b).max(c))
    }
}

/// The box `lo..hi` padded as every box a traversal tests must be (see [`PaddedTriangle`]):
/// by [`BOX_PAD_RELATIVE`] of its largest coordinate magnitude, at least 1. The `bvh`
/// lookup's trees pad theirs the same way (`crate::bvh`).
pub fn padded_box(lo: Vec3, hi: Vec3) -> Aabb {
    let pad = BOX_PAD_RELATIVE * lo.abs().max(hi.abs()).max_element().max(1.0);
    Aabb {
        min: Vec3A::from(lo - pad),
        max: Vec3A::from(hi + pad),
    }
}

/// Up to this many objects, a ray tests each object's box before it enters the BVH: the width
/// of one CWBVH node, so never more box tests than the BVH's own root would make.
const CULL_OBJECTS: usize = 8;

/// The objects' bounding boxes (the union of their triangles' padded boxes), in object
/// order, or none when there are more than [`CULL_OBJECTS`] objects.
fn object_boxes(triangles: &[[Vec3; 3]], info: &[TriangleInfo]) -> Vec<Aabb> {
    let mut boxes: Vec<(u32, Aabb)> = Vec::new();
    for (&triangle, i) in triangles.iter().zip(info) {
        let b = PaddedTriangle(triangle).aabb();
        match boxes.last_mut() {
            Some((object, union)) if *object == i.object => *union = union.union(&b),
            _ => boxes.push((i.object, b)),
        }
    }
    if boxes.len() > CULL_OBJECTS {
        return Vec::new();
    }
    boxes.into_iter().map(|(_, b)| b).collect()
}

/// Whether the ray's interval (tmin, tmax) meets the box: the slab test of obvhs's own
/// nodes, with its finite inverse direction (an axis-parallel ray gives no NaN).
#[inline(always)]
fn ray_meets_box(ray: &Ray, b: &Aabb) -> bool {
    let t1 = (b.min - ray.origin) * ray.inv_direction;
    let t2 = (b.max - ray.origin) * ray.inv_direction;
    let near = t1.min(t2).max_element().max(ray.tmin);
    let far = t1.max(t2).min_element().min(ray.tmax);
    near <= far
}

/// What a ray met: a wall of the room, or an object's triangle at barycentrics (u, v).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Surface {
    Wall(usize),
    Triangle { index: u32, u: f32, v: f32 },
}

/// A closest hit: its distance along the ray and the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub surface: Surface,
}

/// One closest-hit search through the BVH, compiled once per axis order of the triangle test
/// (see [`ShearedRay::with_axes`]).
struct Traversal<'g> {
    geometry: &'g SceneGeometry,
    bvh: &'g CwBvh,
    ray: Ray,
}

impl AxisVisitor for Traversal<'_> {
    type Output = Option<Hit>;

    #[inline(always)]
    fn visit<const KX: usize, const KY: usize, const KZ: usize>(
        self,
        sheared: &ShearedRay,
    ) -> Option<Hit> {
        let g = self.geometry;
        // The best hit so far as (leaf slot, hit): the scene's triangle index is looked up
        // once, for the final hit.
        let mut best: Option<(usize, TriangleHit)> = None;
        let mut ray_hit = RayHit::none();
        self.bvh.ray_traverse(self.ray, &mut ray_hit, |r, id| {
            let [v0, v1, v2] = g.leaf_triangles[id];
            match sheared.hit_triangle_in::<KX, KY, KZ>(v0, v1, v2, r.tmin, r.tmax) {
                Some(hit) => {
                    best = Some((id, hit));
                    hit.t
                }
                None => f32::INFINITY,
            }
        });
        best.map(|(id, hit)| Hit {
            t: hit.t,
            surface: Surface::Triangle {
                index: self.bvh.primitive_indices[id],
                u: hit.u,
                v: hit.v,
            },
        })
    }
}

impl SceneGeometry {
    pub fn build(scene: &Scene, state: &SceneState) -> Self {
        let mut triangles = Vec::new();
        let mut info = Vec::new();
        let mut add = |mesh: &Mesh, model: Mat4, object: u32, material: u32| {
            let normal_model = model.inverse().transpose();
            for tri in mesh.indices.chunks_exact(3) {
                let idx = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
                triangles.push(idx.map(|i| model.transform_point3(mesh.positions[i])));
                info.push(TriangleInfo {
                    normals: idx.map(|i| normal_model.transform_vector3(mesh.normals[i])),
                    uvs: idx.map(|i| mesh.uvs[i]),
                    object,
                    material,
                });
            }
        };
        for (i, o) in scene.objects.iter().enumerate() {
            add(
                &scene.meshes[o.mesh],
                state.object_to_render(scene, i),
                6 + i as u32,
                o.material as u32,
            );
        }
        let start = Instant::now();
        let boxes: Vec<PaddedTriangle> = triangles.iter().map(|&t| PaddedTriangle(t)).collect();
        let mut build_core = Duration::default();
        // `fast_build`: about 0.7 s for the heavy scene's 974k triangles on 2 cores, against
        // 1.0 s for `medium_build`, with no measurable loss in trace speed on our scenes.
        let bvh = (!boxes.is_empty())
            .then(|| build_cwbvh(&boxes, BvhBuildParams::fast_build(), &mut build_core));
        let leaf_triangles = bvh.as_ref().map_or_else(Vec::new, |bvh| {
            bvh.primitive_indices
                .iter()
                .map(|&i| triangles[i as usize].map(Vec3A::from))
                .collect()
        });
        Self {
            object_boxes: object_boxes(&triangles, &info),
            room: RoomBox::new(&scene.room, state.mirror_center),
            wall_materials: scene.room.wall_materials.map(|m| m as u32),
            triangles,
            info,
            bvh,
            leaf_triangles,
            build_core,
            build_total: start.elapsed(),
        }
    }

    /// The closest hit along `o + t d` with t in (t_min, t_max): the room's wall where the ray
    /// crosses it, unless an object's triangle is nearer. The wall's distance bounds the
    /// objects' traversal; an object exactly on a wall's plane (a picture hung flat on it)
    /// wins the tie, as it is what is meant to be seen there.
    ///
    /// In a room with a few objects, a ray that meets none of their boxes before the wall
    /// does not enter the BVH: setting up a traversal (its stack, the root's eight child
    /// boxes decoded from their quantised form) costs about as much as the wall itself, and
    /// most rays in such a room pass beside every object (docs/accuracy.md, "Speed").
    pub fn closest_hit(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        let wall = self.wall_hit(o, d, t_min, t_max);
        let object = self.bvh.as_ref().and_then(|bvh| {
            // The next float above the wall's t (positive and finite: bits + 1).
            let limit = wall.map_or(t_max, |w| f32::from_bits(w.t.to_bits() + 1));
            let ray = Ray::new(Vec3A::from(o), Vec3A::from(d), t_min, limit);
            let boxes = &self.object_boxes;
            if !boxes.is_empty() && !boxes.iter().any(|b| ray_meets_box(&ray, b)) {
                return None;
            }
            ShearedRay::new(o, d).with_axes(Traversal {
                geometry: self,
                bvh,
                ray,
            })
        });
        object.or(wall)
    }

    /// How many object surfaces the segment from `from` to `to` crosses, its far end left
    /// out (the last 0.01 % of its length, where the surface it ends on lies). From the
    /// cube's centre to what a reflected ray really meets, that is the depth layer the
    /// surface would be in, seen from the centre: 0 when the cube map stores it, n when n
    /// surfaces hide it (a closed object in between counts twice, in and out). The walls
    /// are never in between: the room is convex.
    pub fn surfaces_between(&self, from: Vec3, to: Vec3) -> u32 {
        let Some(bvh) = &self.bvh else { return 0 };
        let (d, length) = ((to - from).normalize_or_zero(), from.distance(to));
        if d == Vec3::ZERO {
            return 0;
        }
        let end = length * (1.0 - 1e-4);
        let sheared = ShearedRay::new(from, d);
        let ray = Ray::new(Vec3A::from(from), Vec3A::from(d), 0.0, end);
        let mut count = 0;
        let mut ray_hit = RayHit::none();
        // Every hit is counted and none accepted (the callback answers "no hit"), so the
        // traversal visits every triangle the segment meets instead of stopping at the first.
        bvh.ray_traverse(ray, &mut ray_hit, |r, id| {
            let [v0, v1, v2] = self.leaf_triangles[id].map(Vec3::from);
            if sheared.hit_triangle(v0, v1, v2, r.tmin, end).is_some() {
                count += 1;
            }
            f32::INFINITY
        });
        count
    }

    /// Where `o + t d` crosses the room's walls with t in (t_min, t_max), objects ignored.
    pub fn wall_hit(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        self.room.first_crossing(o, d, t_min, t_max).map(|w| Hit {
            t: w.t,
            surface: Surface::Wall(w.face),
        })
    }

    /// The drawable index (walls 0..6, objects 6 + i) and material of a hit's surface.
    pub fn drawable(&self, hit: &Hit) -> (u32, u32) {
        match hit.surface {
            Surface::Wall(face) => (face as u32, self.wall_materials[face]),
            Surface::Triangle { index, .. } => {
                let i = &self.info[index as usize];
                (i.object, i.material)
            }
        }
    }

    /// Interpolated (unnormalised) shading normal at a hit.
    pub fn normal(&self, hit: &Hit) -> Vec3 {
        match hit.surface {
            Surface::Wall(face) => self.room.normal(face),
            Surface::Triangle { index, u, v } => {
                let i = &self.info[index as usize];
                i.normals[0] * (1.0 - u - v) + i.normals[1] * u + i.normals[2] * v
            }
        }
    }

    /// Texture coordinates at a hit, which lies at `p` (in the BVH's space).
    pub fn uv(&self, hit: &Hit, p: Vec3) -> Vec2 {
        match hit.surface {
            Surface::Wall(face) => self.room.uv(face, p),
            Surface::Triangle { index, u, v } => {
                let i = &self.info[index as usize];
                i.uvs[0] * (1.0 - u - v) + i.uvs[1] * u + i.uvs[2] * v
            }
        }
    }

    /// Whether any object triangle reaches into the closed box `lo..=hi` (by its bounding box, so a
    /// "yes" may be a near miss; a "no" is certain: no point of any triangle is in the box).
    pub fn any_triangle_in_box(&self, lo: Vec3, hi: Vec3) -> bool {
        self.triangles.iter().any(|&[a, b, c]| {
            let (t_lo, t_hi) = (a.min(b).min(c), a.max(b).max(c));
            t_lo.cmple(hi).all() && t_hi.cmpge(lo).all()
        })
    }

    /// The objects' triangles (the walls are not triangles here).
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use obvhs::triangle::Triangle;

    use super::*;

    /// Closest hit distance through obvhs's Möller–Trumbore test instead of ours, over the
    /// objects' BVH and the room's wall triangles (render space), the way the reference
    /// traced before the walls became a box.
    fn closest_t_moller(
        g: &SceneGeometry,
        walls: &[[Vec3; 3]],
        o: Vec3,
        d: Vec3,
        t_min: f32,
    ) -> f32 {
        let ray = Ray::new(Vec3A::from(o), Vec3A::from(d), t_min, f32::INFINITY);
        let moller = |[v0, v1, v2]: [Vec3; 3], r: &Ray| {
            let tri = Triangle {
                v0: v0.into(),
                v1: v1.into(),
                v2: v2.into(),
            };
            let t = tri.intersect(r);
            if t > r.tmin && t < r.tmax {
                t
            } else {
                f32::INFINITY
            }
        };
        let mut best = walls
            .iter()
            .map(|&w| moller(w, &ray))
            .fold(f32::INFINITY, f32::min);
        let mut ray_hit = RayHit::none();
        let bvh = g.bvh.as_ref().unwrap();
        bvh.ray_traverse(ray, &mut ray_hit, |r, id| {
            let t = moller(g.triangles[bvh.primitive_indices[id] as usize], r);
            best = best.min(t);
            t
        });
        best
    }

    /// The room's wall triangles in render space.
    fn wall_triangles(scene: &Scene, state: &SceneState) -> Vec<[Vec3; 3]> {
        let walls = crate::scene::state::room_meshes(&scene.room);
        let to_render = state.world_to_render();
        let corners = |m: &Mesh, t: &[u32]| {
            [0, 1, 2].map(|k| to_render.transform_point3(m.positions[t[k] as usize]))
        };
        walls
            .iter()
            .flat_map(|m| m.indices.chunks_exact(3).map(move |t| corners(m, t)))
            .collect()
    }

    /// Testing the objects' boxes before the BVH ([`SceneGeometry::closest_hit`]) changes no
    /// hit, bit for bit: rays aimed at every object triangle's corners and edge midpoints (where
    /// a box test rounds hardest), and random rays from random points in the room and on the
    /// mirror, each traced with the boxes and without them. The rooms with few objects test
    /// it; the furnished room (17 objects) shows it is off where the BVH's root does the same.
    #[test]
    fn testing_the_object_boxes_first_changes_no_hit() {
        let on_object = |hit: Option<Hit>| {
            matches!(
                hit,
                Some(Hit {
                    surface: Surface::Triangle { .. },
                    ..
                })
            )
        };
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        for (rel, culled) in [
            ("scenes/hard/pole-and-box.toml", true),
            ("scenes/thesis-room.toml", true),
            ("scenes/moving-objects.toml", true),
            ("scenes/furnished-room.toml", false),
        ] {
            let scene = crate::scene::load(&root.join(rel)).unwrap();
            let state = SceneState::at(&scene, 1.0);
            let with_boxes = SceneGeometry::build(&scene, &state);
            let mut without = SceneGeometry::build(&scene, &state);
            assert_eq!(!with_boxes.object_boxes.is_empty(), culled, "{rel}");
            without.object_boxes.clear();
            let half = scene.room.size_m / 2.0;
            let (lo, hi) = (scene.room.center - half, scene.room.center + half);
            let mut random = crate::random::SplitMix64::new(7);
            let mut unit = || random.unit() as f32;
            let (mut rays, mut hits) = (0, 0);
            for [a, b, c] in &with_boxes.triangles {
                for target in [
                    *a,
                    *b,
                    *c,
                    (*a + *b) / 2.0,
                    (*b + *c) / 2.0,
                    (*c + *a) / 2.0,
                ] {
                    let origin = state
                        .world_to_render()
                        .transform_point3(lo + (hi - lo) * Vec3::new(unit(), unit(), unit()));
                    let d = (target - origin).normalize();
                    let culled = with_boxes.closest_hit(origin, d, 0.0, f32::INFINITY);
                    assert_eq!(culled, without.closest_hit(origin, d, 0.0, f32::INFINITY));
                    rays += 1;
                    hits += usize::from(on_object(culled));
                }
            }
            for _ in 0..20_000 {
                let d = Vec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5).normalize();
                let on_mirror = d * scene.mirror.radius_m;
                let culled = with_boxes.closest_hit(on_mirror, d, 1e-4, f32::INFINITY);
                assert_eq!(
                    culled,
                    without.closest_hit(on_mirror, d, 1e-4, f32::INFINITY)
                );
                rays += 1;
                hits += usize::from(on_object(culled));
            }
            eprintln!(
                "{rel}: {rays} rays, {hits} object hits, the same with and without the boxes"
            );
            assert!(hits > 100, "{rel}: too few object hits ({hits}) to tell");
        }
    }

    /// Known layers in the pole-and-box hard case (mirror at the origin, so render space is
    /// world space): the crate's front face is stored in a cube map at the centre (0), the
    /// wall behind the crate is behind its front and back faces (2), as is the wall behind
    /// the pole; a wall seen past everything has nothing in front (0).
    #[test]
    fn surfaces_between_the_centre_and_a_hit_count_the_depth_layers() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let scene = crate::scene::load(&root.join("scenes/hard/pole-and-box.toml")).unwrap();
        let g = SceneGeometry::build(&scene, &SceneState::at(&scene, 0.0));
        let centre = Vec3::ZERO;
        let layers = |target: Vec3| {
            let d = target.normalize();
            let first = g.closest_hit(centre, d, 0.0, f32::INFINITY).unwrap();
            let wall = g.wall_hit(centre, d, 0.0, f32::INFINITY).unwrap();
            (
                g.surfaces_between(centre, centre + first.t * d),
                g.surfaces_between(centre, centre + wall.t * d),
                first.surface == wall.surface,
            )
        };
        // Through the crate's centre, then through the pole's axis at mid-height.
        assert_eq!(layers(Vec3::new(-1.9, -0.6, -2.2)), (0, 2, false));
        assert_eq!(layers(Vec3::new(0.6, 0.1, -2.5)), (0, 2, false));
        // Away from both: the wall is the first surface, nothing in front of it.
        assert_eq!(layers(Vec3::new(1.0, 0.2, 1.0)), (0, 0, true));
    }

    /// Whole scenes, the rays the reference really traces (from the mirror's surface) aimed
    /// exactly at points on triangle edges, every other ray at a vertex: our watertight test
    /// against obvhs's Möller–Trumbore, which its source says is not watertight. In a closed
    /// room every ray must hit something, and a ray aimed at a wall's edge or corner nothing
    /// beyond that point (an object's silhouette edge may be grazed by a rounding step, so
    /// those are not asserted); a ray that passes an edge it should have hit lands on something
    /// farther (or nothing). Prints the counts (docs/accuracy.md quotes them); asserts ours
    /// never misses and never passes through a wall's edge.
    #[test]
    fn watertight_against_moller_trumbore_on_whole_scenes() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        for rel in ["scenes/thesis-room.toml", "scenes/many-objects.toml"] {
            let scene = crate::scene::load(&root.join(rel)).unwrap();
            let state = SceneState::at(&scene, 0.0);
            let g = SceneGeometry::build(&scene, &state);
            let walls = wall_triangles(&scene, &state);
            // Targets on the walls' triangles (as the rasterizer draws them) and the objects'.
            let targets: Vec<([Vec3; 3], bool)> = (walls.iter().map(|&w| (w, true)))
                .chain(g.triangles.iter().map(|&t| (t, false)))
                .collect();
            let r = scene.mirror.radius_m;
            let mut rng = crate::random::SplitMix64::new(0x9E37_79B9_7F4A_7C15);
            // The top 24 bits, mapped to [0, 1).
            let mut next = || (rng.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
            let n = 200_000;
            let (mut ours_missed, mut ours_passed) = (0, 0);
            let (mut theirs_missed, mut theirs_passed, mut theirs_farther) = (0, 0, 0);
            for i in 0..n {
                let index = (next() * targets.len() as f32) as usize % targets.len();
                let (tri, wall) = targets[index];
                let e = (next() * 3.0) as usize % 3;
                let s = if i % 2 == 0 { next() } else { 0.0 };
                let target = tri[e].lerp(tri[(e + 1) % 3], s);
                // An origin on the mirror (render space: centred at 0), on the target's side.
                let dir = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5);
                let o = (target.normalize_or_zero() + dir * 0.5).normalize_or_zero() * r * 1.0001;
                let d = (target - o).normalize_or_zero();
                if d == Vec3::ZERO {
                    continue;
                }
                let ours = g.closest_hit(o, d, 0.0, f32::INFINITY).map(|h| h.t);
                let theirs = closest_t_moller(&g, &walls, o, d, 0.0);
                match ours {
                    None => ours_missed += 1,
                    Some(t) => {
                        // At a wall's edge or corner (the room is concave: no silhouettes
                        // to graze), ours stops at the aimed point or at something in front.
                        let dist = (target - o).length();
                        if wall && t > dist * (1.0 + 1e-4) {
                            ours_passed += 1;
                        }
                        // (A miss is INFINITY, so it counts here too.)
                        if wall && theirs > dist * (1.0 + 1e-4) {
                            theirs_passed += 1;
                        }
                        if !theirs.is_finite() {
                            theirs_missed += 1;
                        } else if theirs > t * (1.0 + 1e-4) + 1e-5 {
                            theirs_farther += 1;
                        }
                    }
                }
            }
            eprintln!(
                "{rel}: {n} rays at edges and vertices: watertight missed {ours_missed}, passed through a wall edge {ours_passed}; \
                 Moller-Trumbore missed {theirs_missed}, passed through a wall edge {theirs_passed}, \
                 found something farther than ours {theirs_farther}"
            );
            assert_eq!((ours_missed, ours_passed), (0, 0), "{rel}");
        }
    }
}
