//! The triangles SwiftShader drops, said rather than left silent.
//!
//! SwiftShader (5.0, `SetupRoutine`) rasterizes a triangle that leaves the view by clipping it
//! to a polygon, but sets up the planes it interpolates depth and colours on, and the direction
//! it walks the polygon's edges in, from the *unclipped* corners, each projected and snapped
//! to 1/16 pixel (their `w` signs folded in). When those snapped corners have no area, the
//! depth plane divides by 0 and no pixel passes; when their area has the wrong sign, the
//! polygon is walked the wrong way round: either way nothing is drawn. It happens to a
//! triangle that crosses the
//! view's eye plane nearly edge-on and reaches far: a floor 3 m below a 64² cube face's eye
//! that reaches 3,500 m to each side projects every corner within half a sub-pixel of the
//! horizon, and the four side faces lose the floor (exactly from a room 6,144 m across at 64²,
//! 12,288 m at 128²: the threshold scales with the face size). lavapipe clips first and is right.
//!
//! We take the same steps on the CPU for the frame's first poses, where the driver is
//! SwiftShader, and say which surfaces and views it drops. Nothing is changed: what is drawn
//! is the driver's.

use std::collections::HashSet;
use std::sync::Mutex;

use glam::{DVec4, Mat4, Vec3, Vec4};

use super::gpu::ViewData;
use crate::scene::camera::FACE_NAMES;
use crate::scene::state::{room_meshes, SceneState};
use crate::scene::{Mesh, Scene};

/// Sub-pixel steps a pixel (SwiftShader's `SUBPIXEL_PRECISION_BITS` of 4).
const SUBPIXELS: f32 = 16.0;

/// The least a view must show of a triangle for its loss to be said: a 4 x 4 block. Below it
/// the loss is a facet seen edge-on at a silhouette, whose snapped area rounding flips (two
/// to seven pixels of a thin pole's facets in `scenes/hard/pole-and-box.toml`, the closed
/// pole's other facets still drawn there): no surface gone.
const SHOWN_PX: f64 = 16.0;

/// Whether SwiftShader draws no pixel of the triangle `clip` (clip-space corners) that the
/// view at `viewport` (x, y, width, height) shows [`SHOWN_PX`] pixels or more of.
pub fn dropped(clip: [Vec4; 3], viewport: Vec4) -> bool {
    let clipped = clip.iter().any(|c| outside(*c));
    if !clipped {
        // Unclipped, the polygon is the snapped triangle itself: the two agree.
        return false;
    }
    let exact = -orientation(clip);
    let snapped = snapped_area(clip, viewport);
    let wrong = snapped == 0.0 || (snapped > 0.0) != (exact > 0.0);
    // Last, as it is the dearest: a triangle that covers no pixel centre loses nothing.
    exact != 0.0 && wrong && shown_px(clip, viewport) >= SHOWN_PX
}

/// SwiftShader's clip test: outside any of `-w <= x, y <= w`, `0 <= z <= w`.
fn outside(c: Vec4) -> bool {
    c.x > c.w || c.y > c.w || c.z > c.w || c.x < -c.w || c.y < -c.w || c.z < 0.0
}

/// `det [x y w]` of the corners, in f64: its sign is the clipped polygon's winding, whatever
/// side of the eye each corner is on.
fn orientation(clip: [Vec4; 3]) -> f64 {
    let [a, b, c] = clip.map(|p| [f64::from(p.x), f64::from(p.y), f64::from(p.w)]);
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

/// The area SwiftShader computes from the unclipped corners, step for step in f32: each
/// corner projected with `1/w` (`w` = 0 taken as 1), snapped to the nearest 1/16 pixel
/// (clamped to an int), the area `(y0 - y2) x1 + (y2 - y1) x0 + (y1 - y0) x2`, negated when
/// an odd number of corners is behind the eye.
fn snapped_area(clip: [Vec4; 3], viewport: Vec4) -> f32 {
    let half = [viewport.z / 2.0 * SUBPIXELS, viewport.w / 2.0 * SUBPIXELS];
    let centre = [
        (viewport.x + viewport.z / 2.0) * SUBPIXELS,
        (viewport.y + viewport.w / 2.0) * SUBPIXELS,
    ];
    let snap = |v: f32| v.round_ties_even() as i32 as f32;
    let [(x0, y0), (x1, y1), (x2, y2)] = clip.map(|c| {
        let rhw = 1.0 / if c.w == 0.0 { 1.0 } else { c.w };
        (
            snap(centre[0] + c.x * rhw * half[0]),
            snap(centre[1] + c.y * rhw * half[1]),
        )
    });
    let area = (y0 - y2) * x1 + (y2 - y1) * x0 + (y1 - y0) * x2;
    let behind = clip.iter().filter(|c| c.w.is_sign_negative()).count();
    if behind % 2 == 1 {
        -area
    } else {
        area
    }
}

/// The pixels the view shows of the triangle: its area clipped to the view, in f64, where it
/// covers some pixel centre (crossed with each row of centres it spans); 0 where it covers
/// none.
fn shown_px(clip: [Vec4; 3], viewport: Vec4) -> f64 {
    let mut polygon: Vec<DVec4> = clip.iter().map(|c| c.as_dvec4()).collect();
    let planes: [fn(DVec4) -> f64; 6] = [
        |p| p.w - p.x,
        |p| p.w + p.x,
        |p| p.w - p.y,
        |p| p.w + p.y,
        |p| p.z,
        |p| p.w - p.z,
    ];
    for plane in planes {
        polygon = clip_polygon(&polygon, plane);
        if polygon.len() < 3 {
            return 0.0;
        }
    }
    let (w, h) = (f64::from(viewport.z), f64::from(viewport.w));
    let screen: Vec<[f64; 2]> = (polygon.iter())
        .map(|p| [(p.x / p.w + 1.0) * w / 2.0, (p.y / p.w + 1.0) * h / 2.0])
        .collect();
    let (lo, hi) = (screen.iter()).fold((f64::MAX, f64::MIN), |(lo, hi), p| {
        (lo.min(p[1]), hi.max(p[1]))
    });
    let rows = ((lo - 0.5).ceil().max(0.0) as u32)..=((hi - 0.5).floor().min(h - 1.0) as u32);
    let covers = rows.into_iter().any(|row| {
        let y = f64::from(row) + 0.5;
        // The convex polygon's span on this row: where its edges cross it.
        let (left, right) = (0..screen.len())
            .filter_map(|i| {
                let (a, b) = (screen[i], screen[(i + 1) % screen.len()]);
                let crosses = (a[1] <= y && y <= b[1]) || (b[1] <= y && y <= a[1]);
                (crosses && a[1] != b[1]).then(|| a[0] + (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1]))
            })
            .fold((f64::MAX, f64::MIN), |(l, r), x| (l.min(x), r.max(x)));
        let first = (left - 0.5).ceil().max(0.0);
        first <= right - 0.5 && first < w
    });
    if !covers {
        return 0.0;
    }
    let twice: f64 = (0..screen.len())
        .map(|i| {
            let (a, b) = (screen[i], screen[(i + 1) % screen.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum();
    twice.abs() / 2.0
}

/// One Sutherland–Hodgman step: the part of `polygon` where `inside(p) >= 0`.
fn clip_polygon(polygon: &[DVec4], inside: fn(DVec4) -> f64) -> Vec<DVec4> {
    let mut kept = Vec::with_capacity(polygon.len() + 1);
    for (i, &a) in polygon.iter().enumerate() {
        let b = polygon[(i + 1) % polygon.len()];
        let (da, db) = (inside(a), inside(b));
        if da >= 0.0 {
            kept.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            kept.push(a + (b - a) * (da / (da - db)));
        }
    }
    kept
}

/// The frame's views by name, in `ViewData` order.
fn view_name(i: usize) -> String {
    match i {
        0..6 => format!("cube face {}", FACE_NAMES[i]),
        6 => "observer".into(),
        7 => "sensor".into(),
        8 => "observer (side by side)".into(),
        _ => "sensor (side by side)".into(),
    }
}

/// What SwiftShader drops of the frame at `state`: per surface (a wall of the room or an
/// object, by name) the views it loses triangles in. `cube`: whether the cube's faces are
/// drawn (a lookup that reads no cube fills none).
pub fn losses(scene: &Scene, state: &SceneState, views: &[ViewData], cube: bool) -> Vec<String> {
    let walls = room_meshes(&scene.room);
    let surfaces = (walls.iter().enumerate())
        .map(|(f, m)| {
            (
                format!("the room's {} wall", FACE_NAMES[f]),
                m,
                state.world_to_render(),
            )
        })
        .chain(scene.objects.iter().enumerate().map(|(i, o)| {
            (
                format!("object {}", o.name),
                &scene.meshes[o.mesh],
                state.object_to_render(scene, i),
            )
        }));
    let mut said = Vec::new();
    for (name, mesh, to_render) in surfaces {
        let lost: Vec<String> = (views.iter().enumerate())
            .filter(|&(i, _)| cube || i >= 6)
            .filter(|(_, v)| mesh_loses(mesh, v.world_to_clip * to_render, v.viewport))
            .map(|(i, _)| view_name(i))
            .collect();
        if !lost.is_empty() {
            said.push(format!("{name} in {}", lost.join(", ")));
        }
    }
    said
}

/// Whether any triangle of `mesh`, taken to clip space by `to_clip`, is dropped.
fn mesh_loses(mesh: &Mesh, to_clip: Mat4, viewport: Vec4) -> bool {
    let clip: Vec<Vec4> = (mesh.positions.iter())
        .map(|&p: &Vec3| to_clip * p.extend(1.0))
        .collect();
    // Only a triangle with corners on both sides of the eye plane or beyond a side can be
    // clipped: a mesh wholly in front and inside is drawn as the driver snaps it.
    if !clip.iter().any(|&c| outside(c)) {
        return false;
    }
    (mesh.indices.chunks_exact(3))
        .any(|t| dropped([0, 1, 2].map(|k| clip[t[k] as usize]), viewport))
}

/// Says, once a process for each different text, what SwiftShader drops of the frame: on
/// stderr, since it is what the images will show, not an error.
pub fn warn(lost: &[String]) {
    static SAID: Mutex<Option<HashSet<String>>> = Mutex::new(None);
    if lost.is_empty() {
        return;
    }
    let text = format!(
        "warning: SwiftShader leaves out triangles of {}: they cross the view's eye plane \
         nearly edge-on and reach far, and it sets a clipped triangle up from its unclipped \
         corners snapped to 1/16 pixel, which have no area (docs/scene-format.md); split those \
         surfaces into smaller pieces, raise the cube's face size, or render on lavapipe",
        lost.join("; ")
    );
    let mut said = SAID.lock().unwrap_or_else(|e| e.into_inner());
    if said.get_or_insert_with(HashSet::new).insert(text.clone()) {
        eprintln!("{}", crate::text::bounded_message(&text));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::camera::ViewBasis;

    /// The two triangles of a square floor `size` m across, 3 m below the eye, in face +X's
    /// clip space (both windings: culling is not what drops them).
    fn floor(size: f32) -> Vec<[Vec4; 3]> {
        let h = size / 2.0;
        let corners = [(-h, -h), (h, -h), (h, h), (-h, h)].map(|(x, z)| Vec3::new(x, -3.0, z));
        let to_clip = ViewBasis::cube_face(Vec3::ZERO, 0).world_to_clip(0.05, 1e5);
        [[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]]
            .map(|t| t.map(|k| to_clip * corners[k].extend(1.0)))
            .to_vec()
    }

    fn face(size: f32) -> Vec4 {
        Vec4::new(0.0, 0.0, size, size)
    }

    #[test]
    fn a_far_floor_is_dropped_where_its_corners_snap_onto_one_line() {
        // The corners' height on a face of C texels: 3 / (S/2) * C/2 * 16 sub-pixels, which
        // rounds to 0 below 1/2: S > 6,144 m at 64², 12,288 m at 128² (both measured so).
        for (c, kept, lost) in [(64.0, 6000.0, 7000.0), (128.0, 12000.0, 12500.0)] {
            assert!(
                !floor(kept).iter().any(|&t| dropped(t, face(c))),
                "{kept} m at {c}"
            );
            // Of each winding, the triangle that reaches into the face.
            let dropped: Vec<bool> = floor(lost).iter().map(|&t| dropped(t, face(c))).collect();
            assert_eq!(dropped, [true, false, true, false], "{lost} m at {c}");
        }
    }

    #[test]
    fn a_triangle_in_front_or_behind_is_never_dropped() {
        let to_clip = ViewBasis::cube_face(Vec3::ZERO, 0).world_to_clip(0.05, 100.0);
        let corners = |x: f32| {
            [
                Vec3::new(x, -1.0, -1.0),
                Vec3::new(x, 1.0, 0.0),
                Vec3::new(x, -1.0, 1.0),
            ]
            .map(|p| to_clip * p.extend(1.0))
        };
        // In front and wholly inside, then reaching out of the face: drawn as snapped.
        assert!(!dropped(corners(5.0), face(64.0)));
        assert!(!dropped(corners(0.5), face(64.0)));
        // Behind the eye: nothing to draw.
        assert!(!dropped(corners(-5.0), face(64.0)));
    }

    #[test]
    fn a_sliver_between_pixel_centres_covers_none() {
        let to_clip = ViewBasis::cube_face(Vec3::ZERO, 0).world_to_clip(0.05, 100.0);
        // 0.2 texel high at the face's middle row boundary (texel centres at 31.5 and 32.5).
        let y = 0.2 / 32.0 * 10.0;
        let sliver = [
            Vec3::new(10.0, 0.0, -9.0),
            Vec3::new(10.0, 0.0, 9.0),
            Vec3::new(10.0, y, 0.0),
        ]
        .map(|p| to_clip * p.extend(1.0));
        // 5.76 texels in area (57.6 wide, 0.2 high), between two rows of centres.
        assert_eq!(shown_px(sliver, face(64.0)), 0.0);
        let wide = sliver.map(|c| c * Vec4::new(1.0, 20.0, 1.0, 1.0));
        assert!((shown_px(wide, face(64.0)) - 115.2).abs() < 1e-3);
    }
}
