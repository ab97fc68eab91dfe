//! The exact reference: a CPU ray tracer that sees the mirror as it is.
//!
//! The cube map assumes the environment is infinitely far from the mirror's centre. The
//! reference makes no such assumption: a camera ray that hits the analytic sphere reflects and
//! is traced through a BVH of the scene's triangles to the surface it really meets. Cameras,
//! pixel centres, materials and shading are those of the rasterizer (the same `ViewBasis`, the
//! CPU twin of `materials.glsl`), so the only difference left is the cube map's approximation.
//!
//! Robustness: ray/sphere in the careful form, the hit put back on the sphere, the secondary
//! origin offset by Wächter and Binder's method, and watertight ray/triangle tests
//! (`intersect.rs`). Everything is in render space (centred on the mirror).

pub mod angular;
pub mod geometry;
pub mod intersect;
pub mod materials;

use std::time::Instant;

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use crate::image::RgbaImage;
use crate::scene::camera::ViewBasis;
use crate::scene::state::SceneState;
use crate::scene::Scene;
use geometry::SceneGeometry;
use intersect::{offset_ray_origin, ray_sphere};

/// Largest samples-per-pixel accepted (a 64 x 64 stratified grid).
pub const MAX_SPP: u32 = 4096;

/// One camera's reference images. Row 0 is the top, as everywhere.
#[derive(Debug, Clone)]
pub struct ReferenceImages {
    /// Linear RGB, the average over the pixel's samples; alpha 1.
    pub color: RgbaImage,
    /// For mirror pixels: the exact unit direction from the mirror centre (the cube's centre) to
    /// the surface the reflected pixel-centre ray really hits, in rgb; alpha 1. Elsewhere 0.
    pub direction: RgbaImage,
    /// r: distance along the reflected ray to its hit (mirror pixels), g: distance along the
    /// camera ray to the first surface (the mirror or a scene surface). 0 where none.
    pub distance: RgbaImage,
    /// r: drawable index of the surface finally seen (walls 0..6, objects 6 + i), -1 for none;
    /// g: 1 when seen in the mirror.
    pub object: RgbaImage,
}

/// Counters and timings of one reference render.
#[derive(Debug, Clone, Default, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceStats {
    pub triangles: usize,
    pub bvh_build_core_ms: f64,
    pub bvh_build_total_ms: f64,
    /// Camera rays plus reflected rays.
    pub rays: u64,
    pub trace_ms: f64,
    pub rays_per_second: f64,
    pub mirror_pixels: u64,
    /// Rays that met nothing at all (in a closed room this should be 0).
    pub misses: u64,
    pub spp: u32,
    pub threads: usize,
}

/// What one traced pixel-sample found.
#[derive(Debug, Clone, Copy, Default)]
struct Sample {
    color: Vec3,
    direction: Vec3,
    reflected_t: f32,
    primary_t: f32,
    object: f32,
    via_mirror: bool,
    rays: u32,
    missed: bool,
}

/// One pixel: its centre sample (for the per-pixel layers), the averaged colour, the rays it
/// took and how many met nothing.
#[derive(Debug, Clone, Copy)]
struct Pixel {
    centre: Sample,
    color: Vec3,
    rays: u32,
    misses: u32,
}

/// The scene prepared for tracing at one instant.
pub struct Reference<'a> {
    scene: &'a Scene,
    state: SceneState,
    pub geometry: SceneGeometry,
}

impl<'a> Reference<'a> {
    pub fn new(scene: &'a Scene, t_s: f64) -> Self {
        let state = SceneState::at(scene, t_s);
        let geometry = SceneGeometry::build(scene, &state);
        Self {
            scene,
            state,
            geometry,
        }
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
        let hit = self.geometry.closest_hit(o, d, t_min, f32::INFINITY)?;
        Some(self.shade_hit(o, d, &hit))
    }

    /// Colour, distance and drawable of a hit found along `o + t d`.
    fn shade_hit(&self, o: Vec3, d: Vec3, hit: &geometry::Hit) -> (Vec3, f32, u32) {
        let p = o + hit.hit.t * d;
        let (n, uv) = self.geometry.attributes(hit);
        let info = &self.geometry.info[hit.triangle as usize];
        let material = &self.scene.materials[info.material as usize];
        let albedo = materials::material_albedo(material, p, uv, &self.scene.textures);
        let color = materials::shade(albedo, n, self.scene.light.as_ref());
        (color, hit.hit.t, info.object)
    }

    /// Traces one camera ray (unit `d` from `eye`).
    fn trace(&self, eye: Vec3, d: Vec3) -> Sample {
        let radius = self.scene.mirror.radius_m;
        let mirror_t = ray_sphere(eye, d, Vec3::ZERO, radius);
        let limit = mirror_t.unwrap_or(f32::INFINITY);
        let mut s = Sample {
            object: -1.0,
            rays: 1,
            ..Sample::default()
        };
        match (self.geometry.closest_hit(eye, d, 0.0, limit), mirror_t) {
            // A scene surface in front of the mirror.
            (Some(hit), _) => {
                let (color, t, object) = self.shade_hit(eye, d, &hit);
                s.color = color;
                s.primary_t = t;
                s.object = object as f32;
            }
            // Neither the mirror nor anything else: out of the room.
            (None, None) => s.missed = true,
            (None, Some(t)) => {
                // The mirror: the hit put back on the sphere, the normal from the sphere equation.
                let n = (eye + t * d).normalize();
                let p = n * radius;
                let r = d - 2.0 * d.dot(n) * n;
                s.primary_t = t;
                s.via_mirror = true;
                s.rays = 2;
                let origin = offset_ray_origin(p, n);
                match self.surface(origin, r, 0.0) {
                    Some((color, t2, object)) => {
                        s.color = color;
                        s.reflected_t = t2;
                        s.object = object as f32;
                        s.direction = (origin + t2 * r).normalize();
                    }
                    None => s.missed = true,
                }
            }
        }
        s
    }

    /// Renders a camera at `width` x `height` with `spp` samples per pixel on a fixed stratified
    /// grid (spp = 1 traces the pixel centre, exactly the rasterizer's sample point).
    pub fn render(
        &self,
        view: &ViewBasis,
        width: u32,
        height: u32,
        spp: u32,
    ) -> (ReferenceImages, ReferenceStats) {
        let spp = spp.clamp(1, MAX_SPP);
        let grid = (f64::from(spp).sqrt().ceil()) as u32;
        let offsets: Vec<Vec2> = (0..spp)
            .map(|k| {
                Vec2::new(
                    ((k % grid) as f32 + 0.5) / grid as f32,
                    ((k / grid) as f32 + 0.5) / grid as f32,
                )
            })
            .collect();
        let start = Instant::now();
        let ray = |px: f32, py: f32| {
            let ndc_x = 2.0 * px / width as f32 - 1.0;
            let ndc_y = 2.0 * py / height as f32 - 1.0;
            view.ray(ndc_x, ndc_y).normalize()
        };
        let rows: Vec<Vec<Pixel>> = (0..height)
            .into_par_iter()
            .map(|y| {
                (0..width)
                    .map(|x| {
                        let centre = self.trace(view.eye, ray(x as f32 + 0.5, y as f32 + 0.5));
                        let (mut sum, mut rays, mut misses) = (Vec3::ZERO, 0u32, 0u32);
                        if spp == 1 {
                            sum = centre.color;
                            rays = centre.rays;
                            misses = u32::from(centre.missed);
                        } else {
                            for o in &offsets {
                                let s = self.trace(view.eye, ray(x as f32 + o.x, y as f32 + o.y));
                                sum += s.color;
                                rays += s.rays;
                                misses += u32::from(s.missed);
                            }
                            rays += centre.rays;
                        }
                        Pixel {
                            centre,
                            color: sum / spp as f32,
                            rays,
                            misses,
                        }
                    })
                    .collect()
            })
            .collect();
        let trace = start.elapsed();
        let image = |f: &dyn Fn(&Pixel) -> [f32; 4]| RgbaImage {
            width,
            height,
            pixels: rows.iter().flatten().map(f).collect(),
        };
        let images = ReferenceImages {
            color: image(&|p| [p.color.x, p.color.y, p.color.z, 1.0]),
            direction: image(&|p| {
                let d = p.centre.direction;
                [d.x, d.y, d.z, if p.centre.via_mirror { 1.0 } else { 0.0 }]
            }),
            distance: image(&|p| [p.centre.reflected_t, p.centre.primary_t, 0.0, 1.0]),
            object: image(&|p| {
                [
                    p.centre.object,
                    if p.centre.via_mirror { 1.0 } else { 0.0 },
                    0.0,
                    1.0,
                ]
            }),
        };
        let rays: u64 = rows.iter().flatten().map(|p| u64::from(p.rays)).sum();
        let stats = ReferenceStats {
            triangles: self.geometry.triangle_count(),
            bvh_build_core_ms: self.geometry.build_core.as_secs_f64() * 1e3,
            bvh_build_total_ms: self.geometry.build_total.as_secs_f64() * 1e3,
            rays,
            trace_ms: trace.as_secs_f64() * 1e3,
            rays_per_second: rays as f64 / trace.as_secs_f64().max(1e-9),
            mirror_pixels: rows
                .iter()
                .flatten()
                .filter(|p| p.centre.via_mirror)
                .count() as u64,
            misses: rows.iter().flatten().map(|p| u64::from(p.misses)).sum(),
            spp,
            threads: rayon::current_num_threads(),
        };
        (images, stats)
    }
}
