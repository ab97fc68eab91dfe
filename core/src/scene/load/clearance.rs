//! Objects kept out of the mirror: no object may reach into the sphere or enclose it, at time
//! 0 or at the sampled times of its own and the mirror's animation.
//!
//! The mirror is a perfect sphere the renderer draws analytically over everything: a cube map
//! rendered from its centre would store the inside of an object through it (the `box` and
//! `distance` lookups then show a ghost of it), the reference and the ray-query lookup would
//! trace from a surface inside the object, and the sensor would see the mirror through a solid.
//! No scene means that, so it is refused, naming the object and the mirror.

use glam::{Mat4, Vec3};

use super::numbers::{num_text, time_text};
use super::{position_at, sample_times_n, Ctx, R};
use crate::scene::{Mesh, Scene};

/// Where an object came from in the file, for the error's field.
pub(super) enum Origin {
    /// `[[objects]]` entry i.
    Listed(usize),
    /// Made by `[[generate]]` entry g.
    Generated(usize),
}

impl Ctx<'_> {
    /// Refuses the first object that reaches into the mirror (`origins[i]`: where object i
    /// came from).
    pub(super) fn objects_clear_of_mirror(&self, scene: &Scene, origins: &[Origin]) -> R<()> {
        let r = scene.mirror.radius_m;
        let mirror = |t: f64| position_at(scene.mirror.animation.as_ref(), scene.mirror.center, t);
        let frame = scene.sensor.frame();
        // Each mesh's farthest vertex from its origin: an object's reach is that times its
        // largest scale, whatever its rotation.
        let farthest: Vec<f32> = (scene.meshes.iter())
            .map(|m| m.positions.iter().map(|p| p.length()).fold(0.0, f32::max))
            .collect();
        for (o, origin) in scene.objects.iter().zip(origins) {
            // An object in the sensor's frame turns with it: the same at every time.
            let rotation = o.placement(frame, mirror(0.0), 0.0).1;
            let path = Sweep {
                mesh: &scene.meshes[o.mesh],
                object: &|t| o.placement(frame, mirror(t), t).0,
                mirror: &mirror,
                model: &|offset| Mat4::from_scale_rotation_translation(o.scale, rotation, offset),
                r,
            };
            // Most objects of a crowd never come near the mirror, which their paths' bounding
            // spheres prove at once, where the triangles' check samples 2,048 times (a crowd
            // of 200,000 moving under a moving mirror took two minutes to load).
            let reach = farthest[o.mesh] * o.scale.max_element();
            if o.frame == crate::scene::ObjectFrame::World && apart(scene, o, reach) {
                continue;
            }
            let times = merged(
                sample_times_n(o.animation.as_ref(), SAMPLES),
                sample_times_n(scene.mirror.animation.as_ref(), SAMPLES),
            );
            let Some((t, why)) = path.first_contact(&times) else {
                continue;
            };
            // An object in the sensor's frame has no animation: its offset is what it is.
            let carried = o.frame == crate::scene::ObjectFrame::Sensor;
            let field = match (origin, t == 0.0 || carried) {
                (Origin::Listed(k), true) => format!("objects[{k}].position"),
                (Origin::Listed(k), false) => format!("objects[{k}].animation"),
                (Origin::Generated(g), _) => format!("generate[{g}]"),
            };
            let when = if t == 0.0 {
                "at time 0".to_owned()
            } else {
                format!("at t = {} s", time_text(t))
            };
            return Err(self.invalid(
                &field,
                format!(
                    "object \"{}\" {why} the mirror (centre {}, radius {}) {when}; an object \
                     must stay outside the sphere",
                    o.name,
                    self.fmt_point(mirror(t)),
                    num_text(r)
                ),
            ));
        }
        Ok(())
    }
}

impl Ctx<'_> {
    /// Refuses a scene whose robot carries a part (an object in the sensor's frame) out of the
    /// room, at time 0 or at the sampled times of the mirror's animation.
    pub(super) fn robot_inside_room(&self, scene: &Scene) -> R<()> {
        let animation = scene.mirror.animation.as_ref();
        for t in super::sample_times(animation) {
            let at = position_at(animation, scene.mirror.center, t);
            let Some((part, out)) = scene.robot_part_outside_room(at, &scene.sensor) else {
                continue;
            };
            let k = (scene.objects.iter()).position(|o| std::ptr::eq(o, part));
            let when = match t == 0.0 {
                true => "at time 0".to_owned(),
                false => format!("at t = {} s, as the mirror moves", time_text(t)),
            };
            return Err(self.invalid(
                &format!("objects[{}].position", k.unwrap_or_default()),
                format!(
                    "the robot's part \"{}\" reaches {} m out of the room {when}{}; a part the \
                     sensor carries must stay inside it",
                    part.name,
                    num_text(out),
                    sensor_moved(&scene.sensor)
                ),
            ));
        }
        Ok(())
    }
}

/// Where the sensor's own settings carry its parts, for a part they carry out of the room:
/// " (sensor.shift [4.97, 0, 0] m and sensor.tilt 10 degrees move the sensor and what it
/// carries)", or nothing for a sensor where the mirror puts it.
fn sensor_moved(sensor: &crate::scene::SensorCamera) -> String {
    let s = sensor.shift_m;
    let shift = (s != glam::Vec3::ZERO).then(|| {
        let [x, y, z] = [s.x, s.y, s.z].map(num_text);
        format!("sensor.shift [{x}, {y}, {z}] m")
    });
    let tilt = (sensor.tilt_deg != 0.0)
        .then(|| format!("sensor.tilt {} degrees", num_text(sensor.tilt_deg)));
    match (shift, tilt) {
        (None, None) => String::new(),
        (Some(s), None) | (None, Some(s)) => format!(" ({s} moves the sensor and what it carries)"),
        (Some(s), Some(t)) => format!(" ({s} and {t} move the sensor and what it carries)"),
    }
}

/// Times an object and the mirror are sampled at: more than the cameras' 64 per cycle (an
/// object's far end sweeps faster than its centre). Between two samples the check is not
/// left to chance: see [`Sweep::first_contact`].
const SAMPLES: usize = 1024;

/// Whether object `o` (its surface within `reach` of its origin) and the mirror can never
/// meet, wherever along their paths each is: the object's path (a point, a segment, a circle,
/// a polyline) stays farther from the sphere holding every position of the mirror's centre
/// than `reach` and the mirror's radius. A proof, not a sample; `false` leaves the object to
/// the triangles' check.
fn apart(scene: &Scene, o: &crate::scene::Object, reach: f32) -> bool {
    let (cm, rm) = (scene.mirror.animation.as_ref()).map_or((scene.mirror.center, 0.0), |a| {
        a.bounding_sphere(scene.mirror.center)
    });
    let d = (o.animation.as_ref()).map_or(o.position.distance(cm), |a| {
        a.distance_bound(o.position, cm)
    });
    let gap = d - rm - reach - scene.mirror.radius_m;
    // A gap within rounding of the sizes is no proof.
    gap > 1e-5 * (d.abs() + rm + reach + scene.mirror.radius_m)
}

/// Two lists of sample times as one, sorted, each time once.
fn merged(mut a: Vec<f64>, b: Vec<f64>) -> Vec<f64> {
    a.extend(b);
    a.sort_by(f64::total_cmp);
    a.dedup();
    a
}

/// How far a path between two samples may be longer than the straight line between its ends:
/// 1 for straight pieces (linear motion and keyframes, whose corners are samples), and for an
/// orbit's arc of at most 1/1024 of a turn, 1 + 1.6e-6: 1e-3 covers both with room to spare.
const PATH_SLACK: f32 = 1.0 + 1e-3;

/// How many times an interval between two samples may be halved.
const MAX_HALVINGS: u32 = 40;

/// An object moving against the moving mirror.
struct Sweep<'a> {
    mesh: &'a Mesh,
    /// Where the object and the mirror's centre are at time t.
    object: &'a dyn Fn(f64) -> Vec3,
    mirror: &'a dyn Fn(f64) -> Vec3,
    /// The object's model matrix with its origin at this offset from the mirror's centre.
    model: &'a dyn Fn(Vec3) -> Mat4,
    r: f32,
}

impl Sweep<'_> {
    fn offset(&self, t: f64) -> Vec3 {
        (self.object)(t) - (self.mirror)(t)
    }

    /// The first time (and how) the object reaches into the sphere: at a sample, or between
    /// two. Between samples a rigid object moving by a path of length L gets no closer than
    /// its clearance at either end minus L, so an interval whose two clearances leave
    /// `(c_a + c_b - L) / 2 > 0` is clear; any other is halved until it is, or until the
    /// object is found inside, or until its path is below a micrometre per metre of radius
    /// (a touch within rounding).
    fn first_contact(&self, times: &[f64]) -> Option<(f64, &'static str)> {
        let mut last: Option<(f64, f32)> = None;
        for &t in times {
            let c = match clearance(self.mesh, (self.model)(self.offset(t)), self.r) {
                Ok(c) => c,
                Err(why) => return Some((t, why)),
            };
            if let Some((ta, ca)) = last {
                if let Some(hit) = self.between((ta, ca), (t, c), 0) {
                    return Some(hit);
                }
            }
            last = Some((t, c));
        }
        None
    }

    fn between(
        &self,
        (ta, ca): (f64, f32),
        (tb, cb): (f64, f32),
        depth: u32,
    ) -> Option<(f64, &'static str)> {
        let moved = (self.object)(tb) - (self.object)(ta);
        let carried = (self.mirror)(tb) - (self.mirror)(ta);
        let path = (moved.length() + carried.length()) * PATH_SLACK;
        if (ca + cb - path) / 2.0 > 0.0 || path <= 1e-6 * self.r || depth == MAX_HALVINGS {
            return None;
        }
        let tm = 0.5 * (ta + tb);
        let cm = match clearance(self.mesh, (self.model)(self.offset(tm)), self.r) {
            Ok(c) => c,
            Err(why) => return Some((tm, why)),
        };
        self.between((ta, ca), (tm, cm), depth + 1)
            .or_else(|| self.between((tm, cm), (tb, cb), depth + 1))
    }
}

/// How far the mesh, placed by `model` (the sphere at the origin), stays outside a sphere of
/// radius `r` (a lower bound: from its bounding box when that is clear of the sphere), or how
/// it reaches in: "reaches into" when a triangle comes closer than `r` to the centre,
/// "encloses" when a closed mesh holds the centre.
fn clearance(mesh: &Mesh, model: Mat4, r: f32) -> Result<f32, &'static str> {
    // The transformed bounds first: most objects are nowhere near.
    let corners = (0..8).map(|c| {
        let pick = |bit: u32, lo: f32, hi: f32| if c & bit == 0 { lo } else { hi };
        let (lo, hi) = (mesh.bounds_min, mesh.bounds_max);
        model.transform_point3(Vec3::new(
            pick(1, lo.x, hi.x),
            pick(2, lo.y, hi.y),
            pick(4, lo.z, hi.z),
        ))
    });
    let (lo, hi) = corners.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
        (lo.min(p), hi.max(p))
    });
    let box_distance = Vec3::ZERO.clamp(lo, hi).length();
    if box_distance >= r {
        return Ok(box_distance - r);
    }
    let triangles = mesh
        .indices
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| model.transform_point3(mesh.positions[t[k] as usize])));
    let mut crossings = [0u32; 3];
    let mut nearest = f32::INFINITY;
    for [a, b, c] in triangles {
        let d = closest_to_origin(a, b, c).length();
        if d < r {
            return Err("reaches into");
        }
        nearest = nearest.min(d);
        for (n, &dir) in crossings.iter_mut().zip(&PROBES) {
            *n += u32::from(crosses(dir, a, b, c));
        }
    }
    // A ray through an edge or a vertex counts two triangles or none: the majority of three
    // rays in unrelated directions decides.
    let odd = crossings.iter().filter(|&&n| n % 2 == 1).count();
    if mesh.closed && odd >= 2 {
        return Err("encloses");
    }
    Ok(nearest - r)
}

/// How the mesh reaches into the sphere, if it does (the tests' view of [`clearance`]).
#[cfg(test)]
fn reaches_into(mesh: &Mesh, model: Mat4, r: f32) -> Option<&'static str> {
    clearance(mesh, model, r).err()
}

/// Directions of the rays that count a closed mesh's crossings: unrelated to the axes and to
/// each other, so that no ray of a box or a tessellated solid runs along an edge.
const PROBES: [Vec3; 3] = [
    Vec3::new(0.8017, 0.3921, 0.4511),
    Vec3::new(-0.2737, 0.8853, -0.3759),
    Vec3::new(0.3313, -0.5189, -0.7880),
];

/// The point of triangle abc closest to the origin (Ericson, "Real-Time Collision Detection",
/// 5.1.5: by the Voronoi region of the triangle the origin lies in).
fn closest_to_origin(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, -a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = -b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = -c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Whether the ray from the origin along `d` crosses triangle abc (Moller-Trumbore); a closed
/// mesh crossed an odd number of times holds the origin.
fn crosses(d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> bool {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < f32::EPSILON * e1.length() * e2.length() {
        return false;
    }
    let s = -a / det;
    let u = s.dot(p);
    let q = s.cross(e1);
    let v = d.dot(q);
    let t = e2.dot(q);
    (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && t > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_closest_point_is_found_in_every_region() {
        let (a, b, c) = (
            Vec3::new(1.0, -1.0, 2.0),
            Vec3::new(1.0, 1.0, 2.0),
            Vec3::new(-1.0, 0.0, 2.0),
        );
        // The origin projects inside: the closest point is straight ahead.
        assert!(closest_to_origin(a, b, c).abs_diff_eq(Vec3::new(0.0, 0.0, 2.0), 1e-6));
        // The origin in a vertex's region, then in an edge's (the plane z = 1).
        let p = |x: f32, y: f32| Vec3::new(x, y, 1.0);
        let (a, b, c) = (p(1.0, 1.0), p(2.0, 1.0), p(1.0, 2.0));
        assert!(closest_to_origin(a, b, c).abs_diff_eq(a, 1e-6));
        assert!(
            closest_to_origin(c, a, b).abs_diff_eq(a, 1e-6),
            "any vertex order"
        );
        let on_edge = closest_to_origin(p(-1.0, 1.0), p(1.0, 1.0), p(0.0, 2.0));
        assert!(on_edge.abs_diff_eq(p(0.0, 1.0), 1e-6), "{on_edge}");
    }

    #[test]
    fn a_box_through_the_sphere_reaches_in_and_one_around_it_encloses_it() {
        let unit = Mesh::cuboid(Vec3::splat(0.5));
        let at = |scale: f32, x: f32| {
            Mat4::from_scale_rotation_translation(
                Vec3::splat(scale),
                glam::Quat::IDENTITY,
                Vec3::new(x, 0.0, 0.0),
            )
        };
        // A 0.2 m box 0.55 m from a 0.5 m sphere's centre: its near face is 0.45 m away.
        assert_eq!(
            reaches_into(&unit, at(0.2, 0.55), 0.5),
            Some("reaches into")
        );
        // 0.65 m: its near face is 0.55 m away, outside.
        assert_eq!(reaches_into(&unit, at(0.2, 0.65), 0.5), None);
        // A 4 m box around the sphere: no face comes near, but it holds the centre.
        assert_eq!(reaches_into(&unit, at(4.0, 0.1), 0.5), Some("encloses"));
    }
}
