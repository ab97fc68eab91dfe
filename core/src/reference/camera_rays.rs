//! A camera's sample rays, with the work shared between samples done once.
//!
//! A sample's direction is `forward + x_term + y_term`, normalised, where `x_term` depends only
//! on the sample's column position and `y_term` only on its row position
//! ([`ViewBasis::ray`]). Both take a few multiplies and an NDC conversion; with 16 samples per
//! pixel that was redone for every sample. Here `forward + x_term` is tabled once per column and
//! distinct x offset, and `y_term` once per image row and sample, so a sample costs one add and
//! the normalisation. The arithmetic is [`ViewBasis::ray`]'s, in its order, so the directions
//! are the same bit for bit (`the_grid_gives_the_view_rays_bit_for_bit`).

use glam::{Vec2, Vec3};

use crate::scene::camera::ViewBasis;

pub struct CameraRays {
    /// `forward + x_term` for column `x` and distinct x offset `j`: `columns[x * xs + j]`.
    columns: Vec<Vec3>,
    /// The distinct x offsets themselves (an orthographic view's origins need them).
    distinct: Vec<f32>,
    /// Distinct x offsets in the pattern (a few per row of cells, not one per sample).
    xs: usize,
    /// For each sample of the pattern: its index among the distinct x offsets, and its y offset.
    samples: Vec<(usize, f32)>,
    view: ViewBasis,
    width: f32,
    height: f32,
}

/// The NDC coordinate of pixel position `p` across `size` pixels, as the renderers compute it.
fn ndc(p: f32, size: f32) -> f32 {
    2.0 * p / size - 1.0
}

impl CameraRays {
    /// Rays through `offsets` (in the unit pixel) of every pixel of a `width` x `height` image.
    pub fn new(view: &ViewBasis, width: u32, height: u32, offsets: &[Vec2]) -> Self {
        let mut distinct: Vec<f32> = Vec::new();
        let samples = offsets
            .iter()
            .map(|o| {
                let j = match distinct.iter().position(|x| x.to_bits() == o.x.to_bits()) {
                    Some(j) => j,
                    None => {
                        distinct.push(o.x);
                        distinct.len() - 1
                    }
                };
                (j, o.y)
            })
            .collect();
        let columns = (0..width)
            .flat_map(|x| distinct.iter().map(move |&ox| (x, ox)))
            .map(|(x, ox)| {
                let ndc_x = ndc(x as f32 + ox, width as f32);
                view.forward + ndc_x * view.tan_x * view.right
            })
            .collect();
        Self {
            columns,
            xs: distinct.len(),
            distinct,
            samples,
            view: *view,
            width: width as f32,
            height: height as f32,
        }
    }

    /// The y terms of row `y`, one per sample (reused across the row's pixels).
    pub fn row_terms(&self, y: u32) -> Vec<Vec3> {
        let v = &self.view;
        self.samples
            .iter()
            .map(|&(_, oy)| ndc(y as f32 + oy, self.height) * v.tan_y * v.down)
            .collect()
    }

    /// The unit direction of sample `k` in column `x`, given its row's [`Self::row_terms`].
    #[inline]
    pub fn ray(&self, x: u32, k: usize, row_terms: &[Vec3]) -> Vec3 {
        let j = self.samples[k].0;
        (self.columns[x as usize * self.xs + j] + row_terms[k]).normalize()
    }

    /// Where sample `k` of pixel (x, y) starts: the eye of a pinhole; on an orthographic
    /// view's image plane, where its NDC point lies.
    pub fn origin(&self, x: u32, y: u32, k: usize) -> Vec3 {
        let (j, oy) = self.samples[k];
        self.view.origin(
            ndc(x as f32 + self.distinct[j], self.width),
            ndc(y as f32 + oy, self.height),
        )
    }

    /// [`Self::origin`] of the centre of pixel (x, y).
    pub fn centre_origin(&self, x: u32, y: u32) -> Vec3 {
        self.view.origin(
            ndc(x as f32 + 0.5, self.width),
            ndc(y as f32 + 0.5, self.height),
        )
    }

    /// The unit ray through the centre of pixel (x, y), computed directly (for a pixel whose
    /// pattern has no sample there).
    pub fn centre(&self, x: u32, y: u32) -> Vec3 {
        let ndc_x = ndc(x as f32 + 0.5, self.width);
        let ndc_y = ndc(y as f32 + 0.5, self.height);
        self.view.ray(ndc_x, ndc_y).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::CameraRays;
    use crate::reference::sample_offsets;
    use glam::Vec3;

    /// Every sample of small images, at square and non-square counts, through the grid and
    /// through `ViewBasis::ray` directly (what the reference traced before): the same bits.
    #[test]
    fn the_grid_gives_the_view_rays_bit_for_bit() {
        let view = crate::scene::camera::ViewBasis::look(
            Vec3::new(0.3, -2.5, 0.1),
            Vec3::new(0.05, 1.0, -0.02).normalize(),
            Vec3::NEG_Z,
            60.0,
            37.0 / 23.0,
        );
        for spp in [1, 2, 3, 7, 16, 17] {
            let (w, h) = (37, 23);
            let offsets = sample_offsets(spp);
            let grid = CameraRays::new(&view, w, h, &offsets);
            for y in 0..h {
                let terms = grid.row_terms(y);
                for x in 0..w {
                    for (k, o) in offsets.iter().enumerate() {
                        let ndc_x = 2.0 * (x as f32 + o.x) / w as f32 - 1.0;
                        let ndc_y = 2.0 * (y as f32 + o.y) / h as f32 - 1.0;
                        let want = view.ray(ndc_x, ndc_y).normalize();
                        let got = grid.ray(x, k, &terms);
                        if *o == glam::Vec2::splat(0.5) {
                            assert_eq!(grid.centre(x, y), want);
                        }
                        assert_eq!(
                            got.to_array().map(f32::to_bits),
                            want.to_array().map(f32::to_bits),
                            "spp {spp} ({x}, {y}) sample {k}"
                        );
                    }
                }
            }
        }
    }
}
