//! Rendering a camera with the reference: every pixel's samples traced in parallel (rows
//! over rayon's threads), then the images (colour, direction, distance, object) and the
//! statistics assembled from the pixels.

use std::time::{Duration, Instant};

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::camera_rays::CameraRays;
use super::{sample_offsets, Reference, ReferenceImages, ReferenceStats, Sample, MAX_SPP};
use crate::image::RgbaImage;
use crate::scene::camera::ViewBasis;
use crate::watch::{Stopped, Unwatched, Watch};

/// One pixel: its centre sample (for the per-pixel layers), the averaged colour, the rays it
/// took and how many met nothing.
#[derive(Debug, Clone, Copy)]
struct Pixel {
    centre: Sample,
    color: Vec3,
    rays: u32,
    misses: u32,
}

/// How a camera's pixels are sampled: the camera's rays at the sample `offsets`, which of
/// them is the pixel centre (if one is), and whether nothing stands between the eye and the
/// mirror.
struct Sampling<'a> {
    camera: &'a CameraRays,
    offsets: &'a [Vec2],
    centre_index: Option<usize>,
    clear: bool,
}

impl Reference<'_> {
    /// Renders a camera at `width` x `height` with `spp` samples per pixel at the cell centres
    /// of [`sample_offsets`] (spp = 1 traces the pixel centre, exactly the rasterizer's sample
    /// point). The per-pixel layers (direction, distance, object) are those of the pixel centre:
    /// one of the samples when the pattern has it, else one more path per pixel.
    pub fn render(
        &self,
        view: &ViewBasis,
        width: u32,
        height: u32,
        spp: u32,
    ) -> (ReferenceImages, ReferenceStats) {
        self.render_watched(view, width, height, spp, &Unwatched)
            .expect("an unwatched render is never stopped")
    }

    /// [`Self::render`], each row reported to `watch` as it is done; [`Stopped`] when `watch`
    /// said to stop. It is asked before every pixel, not only every row: a row of 8192 pixels
    /// at 4096 samples is seconds of work.
    pub fn render_watched(
        &self,
        view: &ViewBasis,
        width: u32,
        height: u32,
        spp: u32,
        watch: &dyn Watch,
    ) -> Result<(ReferenceImages, ReferenceStats), Stopped> {
        let spp = spp.clamp(1, MAX_SPP);
        let offsets = sample_offsets(spp);
        let start = Instant::now();
        let camera = CameraRays::new(view, width, height, &offsets);
        let sampling = Sampling {
            camera: &camera,
            offsets: &offsets,
            centre_index: offsets.iter().position(|o| *o == Vec2::splat(0.5)),
            // An orthographic view's rays start all over its image plane: no one box to test.
            clear: !view.is_orthographic() && self.nothing_before_mirror(view.eye),
        };
        let rows: Vec<Option<Vec<Pixel>>> = (0..height)
            .into_par_iter()
            .map(|y| {
                let row = self.trace_row(&sampling, y, width, watch)?;
                watch.rows_done(1);
                Some(row)
            })
            .collect();
        let rows: Vec<Vec<Pixel>> = rows.into_iter().collect::<Option<_>>().ok_or(Stopped)?;
        let trace = start.elapsed();
        // After the timing: a segment query per mirror pixel, not part of the camera paths.
        let hidden: Vec<u32> = rows
            .par_iter()
            .flat_map_iter(|row| row.iter().map(|p| self.hidden_from_centre(&p.centre)))
            .collect();
        let pixels: Vec<(&Pixel, u32)> = rows.iter().flatten().zip(hidden).collect();
        let images = self.images(&pixels, width, height);
        let centre_traced_apart = sampling.centre_index.is_none();
        let stats = self.stats(&pixels, [width, height, spp], centre_traced_apart, trace);
        Ok((images, stats))
    }

    /// Row `y`'s pixels: each sample traced, the colours averaged, the centre kept; None when
    /// `watch` says to stop before a pixel.
    fn trace_row(
        &self,
        sampling: &Sampling<'_>,
        y: u32,
        width: u32,
        watch: &dyn Watch,
    ) -> Option<Vec<Pixel>> {
        let camera = sampling.camera;
        let row_terms = camera.row_terms(y);
        let spp = sampling.offsets.len();
        (0..width)
            .map(|x| {
                if watch.stop() {
                    return None;
                }
                let (mut sum, mut rays, mut misses) = (Vec3::ZERO, 0u32, 0u32);
                let mut centre = None;
                for k in 0..spp {
                    let from = camera.origin(x, y, k);
                    let s = self.trace(from, camera.ray(x, k, &row_terms), sampling.clear);
                    sum += s.color;
                    rays += s.rays;
                    misses += u32::from(s.missed);
                    if Some(k) == sampling.centre_index {
                        centre = Some(s);
                    }
                }
                // Not one of the samples: traced for the layers only (not a colour sample,
                // so it is counted apart from the camera paths).
                let centre = centre.unwrap_or_else(|| {
                    let origin = camera.centre_origin(x, y);
                    let c = self.trace(origin, camera.centre(x, y), sampling.clear);
                    rays += c.rays;
                    c
                });
                Some(Pixel {
                    centre,
                    color: sum / spp as f32,
                    rays,
                    misses,
                })
            })
            .collect()
    }

    /// The four images from the pixels and how many surfaces hide each one's hit.
    fn images(&self, pixels: &[(&Pixel, u32)], width: u32, height: u32) -> ReferenceImages {
        let image = |f: &dyn Fn(&Pixel, u32) -> [f32; 4]| RgbaImage {
            width,
            height,
            pixels: pixels.iter().map(|&(p, h)| f(p, h)).collect(),
        };
        ReferenceImages {
            color: image(&|p, _| [p.color.x, p.color.y, p.color.z, 1.0]),
            direction: image(&|p, _| {
                let from_cube = p.centre.reflected_hit - self.scene.cube.offset_m;
                // A reflected ray that met nothing has no point to look at: 0, as the GPU's.
                let d = if p.centre.via_mirror && !p.centre.missed {
                    from_cube.normalize_or_zero()
                } else {
                    Vec3::ZERO
                };
                [d.x, d.y, d.z, if p.centre.via_mirror { 1.0 } else { 0.0 }]
            }),
            distance: image(&|p, _| [p.centre.reflected_t, p.centre.primary_t, 0.0, 1.0]),
            object: image(&|p, hidden| {
                let via_mirror = if p.centre.via_mirror { 1.0 } else { 0.0 };
                [p.centre.object, via_mirror, hidden as f32, 1.0]
            }),
        }
    }

    /// The render's statistics (`[width, height, spp]`; `centre_traced_apart`: the pixel
    /// centre was not a sample, so each pixel took one more path).
    fn stats(
        &self,
        pixels: &[(&Pixel, u32)],
        [width, height, spp]: [u32; 3],
        centre_traced_apart: bool,
        trace: Duration,
    ) -> ReferenceStats {
        let rays: u64 = pixels.iter().map(|(p, _)| u64::from(p.rays)).sum();
        let mut hidden_layers = [0u64; 8];
        for &(_, h) in pixels.iter().filter(|(p, _)| p.centre.via_mirror) {
            hidden_layers[(h as usize).min(7)] += 1;
        }
        let pixel_count = u64::from(width) * u64::from(height);
        ReferenceStats {
            triangles: self.geometry.triangle_count(),
            bvh_meshes_ms: self.geometry.mesh_build.as_secs_f64() * 1e3,
            bvh_top_level_ms: self.geometry.top_build.as_secs_f64() * 1e3,
            rays,
            trace_ms: trace.as_secs_f64() * 1e3,
            rays_per_second: rays as f64 / trace.as_secs_f64().max(1e-9),
            mirror_pixels: pixels.iter().filter(|(p, _)| p.centre.via_mirror).count() as u64,
            misses: pixels.iter().map(|(p, _)| u64::from(p.misses)).sum(),
            camera_paths: pixel_count * u64::from(spp),
            centre_paths: if centre_traced_apart { pixel_count } else { 0 },
            hidden_layers,
            spp,
            threads: rayon::current_num_threads(),
        }
    }
}
