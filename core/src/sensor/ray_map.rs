//! The exact ray map of the sensor: per pixel centre, the ray the pixel sees after the mirror.
//!
//! Pure geometry (the sensor camera and the sphere), so it needs neither the GPU nor the
//! scene's contents; the CPU reference traces exactly these rays (both reflect through
//! [`mirror_reflection`], the one place the CPU computes the reflection).

use glam::{Vec2, Vec3};

use crate::reference::intersect::mirror_reflection;
use crate::scene::camera::ViewBasis;
use crate::scene::state::SceneState;
use crate::scene::Scene;

/// One mirror pixel's ray, in the scene frame (metres; world = `Scene::origin` + this): it leaves the mirror at `origin` along the
/// unit `direction`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelRay {
    pub origin: Vec3,
    pub direction: Vec3,
}

/// The sensor's ray map: per pixel (row 0 at the top, as every image here), the ray it sees
/// through the mirror, or None where the pixel does not see the mirror (the mask).
#[derive(Debug, Clone, PartialEq)]
pub struct RayMap {
    pub width: u32,
    pub height: u32,
    pub rays: Vec<Option<PixelRay>>,
}

impl RayMap {
    /// The exact ray map of the scene's sensor at time `t_s`, at the pixel centres.
    pub fn exact(scene: &Scene, t_s: f64) -> Self {
        let state = SceneState::at(scene, t_s);
        let [width, height] = scene.sensor.resolution;
        let view = state.sensor_view(scene, width as f32 / height as f32);
        let shape = &scene.mirror.shape;
        // Rows over rayon's threads, in order: a 4096² calibration is 16 M rays.
        use rayon::prelude::*;
        let rays = (0..height)
            .into_par_iter()
            .flat_map_iter(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| {
                let pixel = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let (from, d) = pixel_ray_from(&view, pixel, width, height);
                mirror_reflection(from, d, shape).map(|m| PixelRay {
                    // Render space is the scene frame minus the mirror's centre now.
                    origin: m.point + state.mirror_center,
                    direction: m.direction,
                })
            })
            .collect();
        Self {
            width,
            height,
            rays,
        }
    }

    /// The ray of pixel (x, y), None off the mirror.
    pub fn get(&self, x: u32, y: u32) -> Option<PixelRay> {
        self.rays[(y * self.width + x) as usize]
    }

    /// Pixels that see the mirror.
    pub fn mirror_pixels(&self) -> usize {
        self.rays.iter().filter(|r| r.is_some()).count()
    }
}

/// Where the camera ray through image point `pixel` (in pixels, (0, 0) the top-left corner)
/// starts (the eye of a pinhole, a point of an orthographic view's image plane) and its unit
/// direction.
pub fn pixel_ray_from(view: &ViewBasis, pixel: Vec2, width: u32, height: u32) -> (Vec3, Vec3) {
    let ndc_x = 2.0 * pixel.x / width as f32 - 1.0;
    let ndc_y = 2.0 * pixel.y / height as f32 - 1.0;
    (
        view.origin(ndc_x, ndc_y),
        view.ray(ndc_x, ndc_y).normalize(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thesis room's sensor sees the mirror at its image centre, looking straight back down
    /// from the sphere's lowest point, and not in its corners (the sphere fills a disc).
    #[test]
    fn the_thesis_sensor_sees_a_disc_with_the_nadir_at_its_centre() {
        let scene = crate::scene::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenes/thesis-room.toml"
        )))
        .unwrap();
        let map = RayMap::exact(&scene, 0.0);
        let (w, h) = (map.width, map.height);
        assert!(map.get(0, 0).is_none() && map.get(w - 1, h - 1).is_none());
        let c = map
            .get(w / 2, h / 2)
            .expect("the image centre sees the mirror");
        let bottom = scene.mirror.center - Vec3::Y * scene.mirror.radius_m;
        assert!((c.origin - bottom).length() < 0.01 * scene.mirror.radius_m);
        assert!(c.direction.dot(Vec3::NEG_Y) > 0.999, "{}", c.direction);
        for r in map.rays.iter().flatten() {
            let from_centre = r.origin - scene.mirror.center;
            assert!((from_centre.length() - scene.mirror.radius_m).abs() < 1e-4);
            assert!((r.direction.length() - 1.0).abs() < 1e-5);
            // A reflected ray leaves the sphere: it points away from the centre.
            assert!(r.direction.dot(from_centre) >= -1e-4);
        }
    }
}
