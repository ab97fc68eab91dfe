//! What the traced lookups' tests share: their images against the reference's, pixel by
//! pixel, where the only differences allowed are ties (a ray meeting an edge between two
//! surfaces exactly, where rounding picks the side).

use specchio::image::RgbaImage;
use specchio::metrics::{compare, Mask};
use specchio::reference::Reference;
use specchio::render::{Readback, RenderOptions};
use specchio::scene::{Lookup, Scene};

use super::Gpu;

/// One 8-bit step: below it two colours are the same on screen.
pub const SAME: f32 = 1.0 / 255.0;

pub fn same(a: [f32; 4], b: [f32; 4]) -> bool {
    (0..3).all(|c| (a[c] - b[c]).abs() <= SAME)
}

/// Observer and sensor colour of a renderer with `lookup` at time `t_s` (frame 0).
pub fn lookup_images(gpu: &Gpu, s: &Scene, lookup: Lookup, t_s: f64) -> [RgbaImage; 2] {
    let options = RenderOptions {
        lookup: Some(lookup),
        ..Default::default()
    };
    images_with(gpu, s, &options, t_s)
}

/// Observer and sensor colour of a renderer with `options` (a lookup that draws no cube) at
/// time `t_s` (frame 0).
pub fn images_with(gpu: &Gpu, s: &Scene, options: &RenderOptions, t_s: f64) -> [RgbaImage; 2] {
    let readback = Readback {
        views: true,
        ..Default::default()
    };
    let (report, images) = super::render_with(gpu, s, options, t_s, readback);
    let lookup = options.lookup.unwrap_or(s.mirror.lookup);
    assert!(!report.cube_updated, "{lookup} must skip the cube fill");
    [images.observer.unwrap(), images.sensor.unwrap()]
}

/// The reference's colour at `t_s` and, per pixel, whether it sees the mirror.
pub fn reference_images(s: &Scene, t_s: f64) -> [(RgbaImage, Vec<bool>); 2] {
    let r = Reference::new(s, t_s);
    let [ow, oh] = s.observer.resolution;
    let [sw, sh] = s.sensor.resolution;
    let split = |(images, _): (specchio::reference::ReferenceImages, _)| {
        let mirror = images.direction.pixels.iter().map(|p| p[3] > 0.5).collect();
        (images.color, mirror)
    };
    [
        split(r.render(&r.observer_view(), ow, oh, 1)),
        split(r.render(&r.sensor_view(), sw, sh, 1)),
    ]
}

/// Mirror pixels whose colours differ, and of those the ones that are not ties: a tie is a
/// pixel on a boundary of the reference image (a neighbour in the reference has the test's
/// colour: the ray met the surface on the other side of the edge). Pixels off the mirror are
/// the rasterizer's, the same for every lookup, and are left to FLIP.
pub fn differences(
    test: &RgbaImage,
    reference: &RgbaImage,
    mirror: &[bool],
) -> (u64, Vec<(u32, u32)>) {
    let (w, h) = (reference.width as i64, reference.height as i64);
    let at = |img: &RgbaImage, x: i64, y: i64| img.pixels[(y * w + x) as usize];
    let mut differing = 0;
    let mut not_ties = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let t = at(test, x, y);
            if !mirror[(y * w + x) as usize] || same(t, at(reference, x, y)) {
                continue;
            }
            differing += 1;
            let tie = (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    let (nx, ny) = (x + dx, y + dy);
                    (0..w).contains(&nx) && (0..h).contains(&ny) && same(t, at(reference, nx, ny))
                })
            });
            if !tie {
                not_ties.push((x as u32, y as u32));
            }
        }
    }
    (differing, not_ties)
}

/// Sensor pixels whose centre lies on a diagonal of the image. With the mirror and the sensor on
/// the vertical axis of a room square in x and z (checked), those pixels reflect in the planes
/// x = ±z through that axis, into the room's vertical corner edges, where two walls are met at
/// the same distance: which one a traversal reports first is a tie (the six-colour room's
/// test above finds the same pixels against the reference).
pub fn on_a_diagonal(s: &Scene, x: u32, y: u32) -> bool {
    // In half pixels from the image's centre, so that the centres are whole numbers.
    let [w, h] = s.sensor.resolution;
    (2 * x + 1).abs_diff(w) == (2 * y + 1).abs_diff(h)
}

/// Whether the room is square in x and z around the mirror and the sensor, so that
/// [`on_a_diagonal`] holds.
pub fn symmetric_about_the_mirror(s: &Scene) -> bool {
    let (room, mirror) = (&s.room, &s.mirror);
    room.size_m.x == room.size_m.z
        && room.center.x == mirror.center.x
        && room.center.z == mirror.center.z
        && s.sensor.resolution[0] == s.sensor.resolution[1]
}

/// What [`agreement`] measured: the tie pixels, and the mean FLIP over the observer's and the
/// sensor's pixels together, over all of them and over those that see the mirror (the
/// lookup's own part; the rest is the rasterizer's).
#[derive(Debug, Clone, Copy)]
pub struct Agreement {
    pub ties: u64,
    pub flip: f64,
    pub mirror_flip: f64,
}

/// `lookup` against the reference on `s` at `t_s` (`name` in messages): every difference on
/// the mirror is a tie, or a sensor pixel on a diagonal of a room symmetric about the mirror
/// ([`on_a_diagonal`]: it reflects into a room corner's edge, whatever colours the two walls
/// show around it).
pub fn agreement(gpu: &Gpu, (name, s): (&str, &Scene), lookup: Lookup, t_s: f64) -> Agreement {
    let options = RenderOptions {
        lookup: Some(lookup),
        ..Default::default()
    };
    agreement_with(gpu, (name, s), &options, t_s)
}

/// [`agreement`] of a renderer with `options`.
pub fn agreement_with(
    gpu: &Gpu,
    (name, s): (&str, &Scene),
    options: &RenderOptions,
    t_s: f64,
) -> Agreement {
    let lookup = options.lookup.unwrap_or(s.mirror.lookup);
    let test = images_with(gpu, s, options, t_s);
    let exact = reference_images(s, t_s);
    let mut ties = 0;
    let (mut all, mut on_mirror) = ((0.0, 0u64), (0.0, 0u64));
    for ((t, (e, mirror)), view) in test.iter().zip(&exact).zip(["observer", "sensor"]) {
        let (differing, mut not_ties) = differences(t, e, mirror);
        if view == "sensor" && symmetric_about_the_mirror(s) {
            not_ties.retain(|&(x, y)| !on_a_diagonal(s, x, y));
        }
        assert!(
            not_ties.is_empty(),
            "{name} {view} ({lookup}): {} of {differing} differing pixels are no edge ties, first at {:?}",
            not_ties.len(),
            &not_ties[..not_ties.len().min(5)]
        );
        ties += differing;
        let mask = Mask {
            width: e.width,
            height: e.height,
            selected: mirror.clone(),
        };
        let whole = compare(t, e, None).expect("same size");
        let masked = compare(t, e, Some(&mask)).expect("same size");
        for (sum, c) in [(&mut all, &whole), (&mut on_mirror, &masked)] {
            sum.0 += c.flip_mean.expect("flip") * c.pixels_compared as f64;
            sum.1 += c.pixels_compared;
        }
        eprintln!(
            "{name} {view} ({lookup}): {differing} tie pixels, FLIP mean {:.6}, on the mirror {:.6}",
            whole.flip_mean.unwrap(),
            masked.flip_mean.unwrap()
        );
    }
    Agreement {
        ties,
        flip: all.0 / all.1 as f64,
        mirror_flip: on_mirror.0 / on_mirror.1 as f64,
    }
}
