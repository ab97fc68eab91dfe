//! The exact reference: a CPU ray tracer that sees the mirror as it is.
//!
//! The cube map assumes the environment is infinitely far from the mirror's centre. The
//! reference makes no such assumption: a camera ray that hits the analytic sphere reflects and
//! is traced through a BVH of the scene's triangles to the surface it really meets. Cameras,
//! pixel centres, materials and shading are those of the rasterizer (the same `ViewBasis`, the
//! CPU twin of `materials.glsl`), so the only difference left is the cube map's approximation.
//!
//! The objects are kept in two levels (`objects.rs`): a tree per mesh in its model space, built
//! once, and a tree over the objects at the instant traced, so a new instant rebuilds only the
//! latter.
//!
//! Robustness: ray/sphere in the careful form, the hit put back on the sphere, the secondary
//! origin offset by Wächter and Binder's method, and watertight ray/triangle tests
//! (`intersect.rs`). Everything is in render space (centred on the mirror).

pub mod angular;
mod camera_rays;
pub mod geometry;
pub mod intersect;
pub mod materials;
pub mod objects;
pub mod render;
pub mod room;

use std::sync::Arc;

use glam::{Vec2, Vec3};
use serde::Serialize;

use crate::image::RgbaImage;
use crate::scene::camera::ViewBasis;
use crate::scene::state::SceneState;
use crate::scene::{MaterialKind, Scene};
use geometry::SceneGeometry;
use intersect::{mirror_reflection, offset_ray_origin};
use objects::MeshTrees;

/// Largest samples-per-pixel accepted (a 64 x 64 stratified grid).
pub const MAX_SPP: u32 = 4096;

/// The most camera paths (pixels x samples) one camera traces: 2^32, about two minutes at the
/// 35 M paths/s of a simple room on 2 cores and a quarter of an hour in a crowd (5 M/s);
/// each bound alone (8192² pixels, `spp` up to [`MAX_SPP`]) would allow days.
pub const MAX_CAMERA_PATHS: u64 = 1 << 32;

/// Why `spp` samples per pixel are too many for one of the scene's cameras (a sentence that
/// names the camera and what to change), if they are; also refuses `spp` outside
/// 1..=[`MAX_SPP`]. The sensor may also trace its exposure at `instants` more times (the
/// camera image's motion blur and rolling shutter: `sensor::imaging::exposure_renders`), each
/// a camera of its own: they count with the sensor's paths.
pub fn too_many_paths(scene: &Scene, spp: u32, instants: usize) -> Option<String> {
    if !(1..=MAX_SPP).contains(&spp) {
        return Some(format!("spp {spp}: must be 1 to {MAX_SPP}"));
    }
    let instants = instants as u64;
    let cameras = [
        ("observer", scene.observer.resolution, 1),
        ("sensor", scene.sensor.resolution, 1 + instants),
    ];
    cameras.into_iter().find_map(|(name, [w, h], renders)| {
        let paths = u64::from(w) * u64::from(h) * u64::from(spp) * renders;
        let over = match renders {
            1 => format!("spp {spp} at the {name}'s {w}x{h} pixels"),
            _ => format!(
                "spp {spp} at the {name}'s {w}x{h} pixels, traced once for the frame and once \
                 at each of its exposure's {instants} instants (sensor.imaging):"
            ),
        };
        (paths > MAX_CAMERA_PATHS).then(|| {
            let change = match renders {
                1 => format!("fewer samples or a smaller {name}.resolution"),
                _ => format!(
                    "fewer samples, a smaller {name}.resolution, fewer \
                     sensor.imaging.motion_blur_samples or a shorter \
                     sensor.imaging.rolling_shutter_s"
                ),
            };
            let is = if renders == 1 { " is" } else { "" };
            format!(
                "{over}{is} {paths} camera paths, more than the {MAX_CAMERA_PATHS} one camera \
                 may trace (minutes to hours on a CPU): {change}"
            )
        })
    })
}

/// Sample positions in the unit pixel for `n` samples: the centres of `n` cells of equal area
/// that tile the pixel, so the pattern is stratified for every `n`, not only for squares.
/// `round(sqrt(n))` rows; the first `n mod rows` rows hold one cell more; each row is as tall
/// as its share of the cells (cells per row / n) and is cut into equal cells. A square `n`
/// gives the regular grid; `n = 1` the pixel centre; the mean of the pattern is always the
/// centre. Deterministic, so reference images repeat bit for bit.
pub fn sample_offsets(n: u32) -> Vec<Vec2> {
    let n = n.max(1);
    let rows = (f64::from(n).sqrt().round() as u32).clamp(1, n);
    let (base, extra) = (n / rows, n % rows);
    let mut offsets = Vec::with_capacity(n as usize);
    let mut top = 0u32; // cells above this row: the row starts at top / n
    for row in 0..rows {
        let cells = base + u32::from(row < extra);
        // Centre of the row: (top + cells / 2) / n, in exact integer halves.
        let y = (2 * top + cells) as f32 / (2 * n) as f32;
        for c in 0..cells {
            let x = (2 * c + 1) as f32 / (2 * cells) as f32;
            offsets.push(Vec2::new(x, y));
        }
        top += cells;
    }
    offsets
}

/// One camera's reference images. Row 0 is the top, as everywhere.
#[derive(Debug, Clone)]
pub struct ReferenceImages {
    /// Linear RGB, the average over the pixel's samples; alpha 1.
    pub color: RgbaImage,
    /// For mirror pixels: the exact unit direction from the cube's centre (the mirror's
    /// viewpoint unless `cube.offset` moves it) to the surface the reflected pixel-centre ray
    /// really hits, in rgb; alpha 1. Elsewhere 0.
    pub direction: RgbaImage,
    /// r: distance along the reflected ray to its hit (mirror pixels), g: distance along the
    /// camera ray to the first surface (the mirror or a scene surface). 0 where none.
    pub distance: RgbaImage,
    /// r: drawable index of the surface finally seen (walls 0..6, objects 6 + i), -1 for none;
    /// g: 1 when seen in the mirror; b (mirror pixels): how many surfaces hide that surface
    /// from the cube's centre (0: a cube map rendered there stores it).
    pub object: RgbaImage,
}

/// Counters and timings of one reference render.
#[derive(Debug, Clone, Default, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceStats {
    pub triangles: usize,
    /// The meshes' trees (built once for the scene) and the top level over the objects
    /// (built for this instant), in ms.
    pub bvh_meshes_ms: f64,
    pub bvh_top_level_ms: f64,
    /// Camera rays plus reflected rays (of the camera paths and the centre paths).
    pub rays: u64,
    pub trace_ms: f64,
    pub rays_per_second: f64,
    pub mirror_pixels: u64,
    /// Rays that met nothing at all (in a closed room this should be 0).
    pub misses: u64,
    /// Colour samples: pixels x spp. Each is one camera ray plus, on the mirror, its reflection.
    pub camera_paths: u64,
    /// Extra pixel-centre paths traced only for the per-pixel layers, where the sample pattern
    /// has no sample at the centre (0 for spp 1, 9, 25, ...); their rays are in `rays`.
    pub centre_paths: u64,
    /// Mirror pixels by how many surfaces hide what their reflected ray meets from the
    /// mirror's centre: [0] are stored in a cube map rendered there, [n] would be in its
    /// (n+1)-th depth layer; the last entry counts 7 or more.
    #[serde(default)]
    pub hidden_layers: [u64; 8],
    pub spp: u32,
    pub threads: usize,
}

/// What one traced pixel-sample found.
#[derive(Debug, Clone, Copy, Default)]
struct Sample {
    color: Vec3,
    /// The reflected ray's hit (render space, relative to the mirror centre); only the pixel
    /// centre's is used, normalised into the direction layer when the image is assembled, so
    /// the colour samples do not pay for a normalisation they never use.
    reflected_hit: Vec3,
    reflected_t: f32,
    primary_t: f32,
    object: f32,
    via_mirror: bool,
    rays: u32,
    missed: bool,
}

/// The scene prepared for tracing at one instant.
pub struct Reference<'a> {
    scene: &'a Scene,
    state: SceneState,
    pub geometry: SceneGeometry,
    /// From this render space (centred on the mirror where it is now) to the BVH's (centred
    /// where the mirror was when it was built): zero until [`Reference::move_mirror`].
    shift: Vec3,
}

impl<'a> Reference<'a> {
    pub fn new(scene: &'a Scene, t_s: f64) -> Self {
        Self::with_meshes(scene, t_s, Arc::new(MeshTrees::build(&scene.meshes)))
    }

    /// The scene at `t_s`, its meshes' trees built before (for `scene`'s meshes): what a
    /// frame of a moving scene builds is the top level over its objects alone.
    pub fn with_meshes(scene: &'a Scene, t_s: f64, meshes: Arc<MeshTrees>) -> Self {
        Self::with_state(scene, SceneState::at(scene, t_s), meshes)
    }

    /// The scene as `state` places it (the robot stood at a pose: [`SceneState::at_pose`]),
    /// its meshes' trees built before.
    pub fn with_state(scene: &'a Scene, state: SceneState, meshes: Arc<MeshTrees>) -> Self {
        let geometry = SceneGeometry::with_meshes(scene, &state, meshes);
        Self {
            scene,
            state,
            geometry,
            shift: Vec3::ZERO,
        }
    }

    /// Puts the mirror's centre at `center` (world) without rebuilding the BVH: the mirror
    /// (and the sensor with it) moves through a fixed scene, so the rays are shifted into the
    /// BVH's space instead (a robot sweeping poses traces many images per build). Only for a
    /// scene without objects in the sensor's frame, which move with the robot: stand it with
    /// [`SceneState::at_pose`] and [`Self::with_state`] instead.
    pub fn move_mirror(&mut self, center: Vec3) {
        self.shift += center - self.state.mirror_center;
        self.state.mirror_center = center;
    }

    pub fn observer_view(&self) -> ViewBasis {
        let [w, h] = self.scene.observer.resolution;
        self.state.observer_view(self.scene, w as f32 / h as f32)
    }

    pub fn sensor_view(&self) -> ViewBasis {
        let [w, h] = self.scene.sensor.resolution;
        self.state.sensor_view(self.scene, w as f32 / h as f32)
    }

    /// Shades the closest scene surface along `o + t d`, t > t_min.
    fn surface(&self, o: Vec3, d: Vec3, t_min: f32) -> Option<(Vec3, f32, u32)> {
        let hit = self
            .geometry
            .closest_hit(o + self.shift, d, t_min, f32::INFINITY)?;
        Some(self.shade_hit(o, d, &hit))
    }

    /// Colour, distance and drawable of a hit found along `o + t d`.
    fn shade_hit(&self, o: Vec3, d: Vec3, hit: &geometry::Hit) -> (Vec3, f32, u32) {
        let p = o + hit.t * d;
        let (object, material) = self.geometry.drawable(hit);
        let material = &self.scene.materials[material as usize];
        // Only what the material and the light read is interpolated (flat colours and unlit
        // rooms are common, and this runs once per camera path); the same numbers otherwise.
        let uv = match material.kind {
            MaterialKind::Color { .. } | MaterialKind::Direction => Vec2::ZERO,
            _ => self.geometry.uv(hit, p + self.shift),
        };
        let albedo = materials::material_albedo(material, p, uv, &self.scene.textures);
        let light = self.scene.light.as_ref();
        let n = light.map_or(Vec3::ZERO, |_| self.geometry.normal(hit));
        let color = materials::shade(albedo, n, light);
        (color, hit.t, object)
    }

    /// Whether no object's triangle can stand between `eye` and the mirror: none reaches into
    /// the box around the eye and the sphere, padded. Every camera ray that meets the sphere
    /// runs inside that box up to the sphere (the box is convex and holds both ends), so when
    /// it is empty the BVH cannot find anything before the mirror and [`Self::trace`] asks only
    /// the room's walls (an eye outside the room sees one before the mirror). The
    /// padding (a millimetre per metre of the box's coordinates) is far above the rounding of a
    /// triangle test's t, so the answer is the one the traversal would give.
    fn nothing_before_mirror(&self, eye: Vec3) -> bool {
        let r = Vec3::splat(self.scene.mirror.radius_m);
        // The box in the BVH's space (see `shift`), where the triangle tests run.
        let (lo, hi) = (eye.min(-r) + self.shift, eye.max(r) + self.shift);
        let pad = 1e-3 * lo.abs().max(hi.abs()).max_element().max(1.0);
        !self.geometry.any_triangle_in_box(lo - pad, hi + pad)
    }

    /// Traces one camera ray (unit `d` from `eye`). `clear`: [`Self::nothing_before_mirror`]
    /// for this eye.
    fn trace(&self, eye: Vec3, d: Vec3, clear: bool) -> Sample {
        let mirror = mirror_reflection(eye, d, &self.scene.mirror.shape);
        let mirror_t = mirror.map(|m| m.t);
        let mut s = Sample {
            object: -1.0,
            rays: 1,
            ..Sample::default()
        };
        let eye_bvh = eye + self.shift;
        let first = match mirror_t {
            Some(limit) if clear => self.geometry.wall_hit(eye_bvh, d, 0.0, limit),
            Some(limit) => self.geometry.closest_hit(eye_bvh, d, 0.0, limit),
            None => self.geometry.closest_hit(eye_bvh, d, 0.0, f32::INFINITY),
        };
        match (first, mirror) {
            // A scene surface in front of the mirror.
            (Some(hit), _) => {
                let (color, t, object) = self.shade_hit(eye, d, &hit);
                s.color = color;
                s.primary_t = t;
                s.object = object as f32;
            }
            // Neither the mirror nor anything else: out of the room.
            (None, None) => s.missed = true,
            (None, Some(m)) => {
                // The mirror: the same reflection as the sensor's ray map.
                let (n, p, r) = (m.normal, m.point, m.direction);
                s.primary_t = m.t;
                s.via_mirror = true;
                s.rays = 2;
                let origin = offset_ray_origin(p, n);
                match self.surface(origin, r, 0.0) {
                    Some((color, t2, object)) => {
                        s.color = color;
                        s.reflected_t = t2;
                        s.object = object as f32;
                        s.reflected_hit = origin + t2 * r;
                    }
                    None => s.missed = true,
                }
            }
        }
        s
    }

    /// How many surfaces stand between the cube's centre (where a cube map is rendered) and
    /// the surface a mirror sample's reflected ray really meets: what no single-layer cube
    /// lookup can see, however exact its search. 0 for a sample off the mirror.
    fn hidden_from_centre(&self, sample: &Sample) -> u32 {
        if !sample.via_mirror || sample.missed {
            return 0;
        }
        // Render space is the mirror's; the BVH's space is shifted from it.
        let centre = self.scene.cube.offset_m + self.shift;
        let to = sample.reflected_hit + self.shift;
        self.geometry.surfaces_between(centre, to)
    }
}

#[cfg(test)]
mod tests {
    use super::{sample_offsets, Reference};
    use glam::Vec2;
    use std::path::Path;

    /// The path budget counts the sensor's exposure: 512² at 4 spp is 2^20 paths, within
    /// 2^32 alone and with 4,095 more traces, beyond it with 4,096 (said with what to change).
    #[test]
    fn the_path_budget_counts_the_exposure() {
        let text = "[room]\ncenter = [0, 3, 0]\nsize = [10, 6, 10]\nwalls = \"w\"\n\
            [mirror]\ncenter = [0, 3, 0]\nradius = 1\n\
            [[materials]]\nname = \"w\"\ntype = \"color\"\ncolor = [0.5, 0.5, 0.5]\n\
            [sensor]\nresolution = [512, 512]\n";
        let scene = crate::scene::load_str(text, Path::new("paths.toml")).unwrap();
        assert_eq!(super::too_many_paths(&scene, 4, 0), None);
        assert_eq!(super::too_many_paths(&scene, 4, 4095), None);
        let why = super::too_many_paths(&scene, 4, 4096).expect("beyond the budget");
        assert!(
            why.starts_with("spp 4 at the sensor's 512x512 pixels, traced once for the frame and once at each of its exposure's 4096 instants (sensor.imaging): 4296015872 camera paths")
                && why.ends_with(": fewer samples, a smaller sensor.resolution, fewer sensor.imaging.motion_blur_samples or a shorter sensor.imaging.rolling_shutter_s"),
            "{why}"
        );
    }

    /// The shortcut that skips the BVH before the mirror ([`Reference::nothing_before_mirror`])
    /// changes no sample: every ray of a 64 x 64 grid through both cameras traces bit for bit
    /// as with the full traversal, in scenes where the shortcut is taken (the six-colour room's
    /// empty middle) and where an object stands near the mirror and it must be refused.
    #[test]
    fn skipping_the_bvh_before_the_mirror_changes_no_sample() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let mut taken = Vec::new();
        for rel in [
            "scenes/test/six-colour-room.toml",
            "scenes/hard/pole-and-box.toml",
            "scenes/many-objects.toml",
        ] {
            let scene = crate::scene::load(&root.join(rel)).unwrap();
            let r = Reference::new(&scene, 0.0);
            for (name, view) in [("observer", r.observer_view()), ("sensor", r.sensor_view())] {
                let clear = r.nothing_before_mirror(view.eye);
                taken.push(clear);
                let mut mirror = 0;
                for k in 0..64 * 64 {
                    let (x, y) = ((k % 64) as f32 + 0.5, (k / 64) as f32 + 0.5);
                    let d = view.ray(x / 32.0 - 1.0, y / 32.0 - 1.0).normalize();
                    let (fast, full) = (r.trace(view.eye, d, clear), r.trace(view.eye, d, false));
                    // Debug prints every float exactly (and tells -0 from 0).
                    assert_eq!(format!("{fast:?}"), format!("{full:?}"), "{rel} {name} {k}");
                    mirror += u32::from(full.via_mirror);
                }
                assert!(mirror > 0, "{rel} {name}: no ray met the mirror");
                eprintln!("{rel} {name}: shortcut {clear}, {mirror} mirror rays");
            }
        }
        assert!(taken.contains(&true) && taken.contains(&false), "{taken:?}");
    }

    #[test]
    fn small_patterns_are_the_known_cell_centres() {
        assert_eq!(sample_offsets(1), [Vec2::splat(0.5)]);
        // One row of two cells (round(sqrt 2) = 1).
        assert_eq!(
            sample_offsets(2),
            [Vec2::new(0.25, 0.5), Vec2::new(0.75, 0.5)]
        );
        // Two rows: two cells in a row 2/3 tall, one in a row 1/3 tall.
        assert_eq!(
            sample_offsets(3),
            [
                Vec2::new(0.25, 1.0 / 3.0),
                Vec2::new(0.75, 1.0 / 3.0),
                Vec2::new(0.5, 5.0 / 6.0)
            ]
        );
        let grid: Vec<Vec2> = (0..16)
            .map(|k| Vec2::new((k % 4) as f32 + 0.5, (k / 4) as f32 + 0.5) / 4.0)
            .collect();
        assert_eq!(sample_offsets(16), grid);
    }

    /// Every N from 1 to 300: N samples, each the centre of its own cell, the cells of equal
    /// area tiling the pixel (each row's cells fill it; the rows' heights sum to 1); no two
    /// samples alike; the pattern's mean is the pixel centre (no bias towards a side, the
    /// fault of taking the first N cells of a ceil(sqrt N)^2 grid).
    #[test]
    fn every_count_is_stratified_in_equal_cells_centred_on_the_pixel() {
        for n in 1..=300u32 {
            let s = sample_offsets(n);
            assert_eq!(s.len(), n as usize);
            let mean = s.iter().copied().sum::<Vec2>() / n as f32;
            assert!(
                (mean - Vec2::splat(0.5)).abs().max_element() < 1e-5,
                "{n}: mean {mean}"
            );
            let mut rows: Vec<(f32, u32)> = Vec::new();
            for p in &s {
                assert!(p.x > 0.0 && p.x < 1.0 && p.y > 0.0 && p.y < 1.0, "{n}: {p}");
                match rows.last_mut() {
                    Some((y, count)) if *y == p.y => *count += 1,
                    _ => rows.push((p.y, 1)),
                }
            }
            // Row r of c cells is c/n tall and centred on its y: consecutive rows must touch.
            let mut top = 0.0f64;
            for &(y, c) in &rows {
                let height = f64::from(c) / f64::from(n);
                assert!(
                    (f64::from(y) - (top + height / 2.0)).abs() < 1e-6,
                    "{n}: row at {y}"
                );
                top += height;
            }
            assert!((top - 1.0).abs() < 1e-9, "{n}: rows cover {top}");
            let mut sorted: Vec<(u32, u32)> =
                s.iter().map(|p| (p.x.to_bits(), p.y.to_bits())).collect();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), n as usize, "{n}: repeated samples");
        }
    }

    /// Moving the mirror through a built scene gives the images of a scene built with the
    /// mirror there: only the rays' shift into the BVH's space differs (rounding, so a few
    /// silhouette pixels may flip; the rest agree to float precision).
    #[test]
    fn a_moved_mirror_sees_what_a_mirror_built_there_sees() {
        use super::Reference;
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/thesis-room.toml");
        let mut scene = crate::scene::load(std::path::Path::new(path)).unwrap();
        scene.mirror.animation = None;
        scene.sensor.resolution = [48, 48];
        let target = scene.mirror.center + glam::Vec3::new(0.7, 0.0, -0.4);
        let mut moved = Reference::new(&scene, 0.0);
        moved.move_mirror(target);
        let mut there = scene.clone();
        there.mirror.center = target;
        let built = Reference::new(&there, 0.0);
        let (a, _) = moved.render(&moved.sensor_view(), 48, 48, 1);
        let (b, _) = built.render(&built.sensor_view(), 48, 48, 1);
        let differ = a
            .color
            .pixels
            .iter()
            .zip(&b.color.pixels)
            .filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| (x - y).abs() > 1e-4))
            .count();
        assert!(differ <= 48 * 48 / 100, "{differ} of 2304 pixels differ");
        // The move is real: the image differs from the unmoved mirror's.
        let home = Reference::new(&scene, 0.0);
        let (c, _) = home.render(&home.sensor_view(), 48, 48, 1);
        assert_ne!(a.color.pixels, c.color.pixels);
    }

    /// A robot that carries parts of its own (hyperbolic-room's lens barrel, camera body and
    /// mast, in the sensor's frame), stood at a pose through [`SceneState::at_pose`], is the
    /// scene built with the mirror there and the sensor turned, pixel for pixel: its parts came
    /// along and turned with it (the localisation's reference robot stands this way). Moving
    /// the mirror through the built scene instead leaves them behind: the centre pixel differs.
    #[test]
    fn a_robot_stood_at_a_pose_carries_its_parts() {
        use super::objects::MeshTrees;
        use super::Reference;
        use crate::scene::state::SceneState;
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenes/hyperbolic-room.toml"
        );
        let mut scene = crate::scene::load(std::path::Path::new(path)).unwrap();
        scene.sensor.resolution = [48, 48];
        let target = scene.mirror.center + glam::Vec3::new(1.0, 0.0, -0.5);
        let mut turned = scene.sensor.clone();
        turned.heading_rad = 1.0;
        let meshes = std::sync::Arc::new(MeshTrees::build(&scene.meshes));
        let state = SceneState::at_pose(&scene, 0.0, (target, &turned));
        let stood = Reference::with_state(&scene, state, meshes);
        let mut there = scene.clone();
        there.mirror.center = target;
        there.sensor = turned.clone();
        let built = Reference::new(&there, 0.0);
        let view = built.sensor_view();
        let (a, _) = stood.render(&view, 48, 48, 1);
        let (b, _) = built.render(&view, 48, 48, 1);
        assert_eq!(a.color.pixels, b.color.pixels);
        let mut moved = Reference::new(&scene, 0.0);
        moved.move_mirror(target);
        let (c, _) = moved.render(&view, 48, 48, 1);
        let centre = 24 * 48 + 24;
        assert_ne!(
            c.color.pixels[centre], b.color.pixels[centre],
            "the parts left behind"
        );
    }
}
