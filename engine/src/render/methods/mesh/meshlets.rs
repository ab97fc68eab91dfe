//! Meshlets: a mesh's triangles cut into groups small enough for one mesh-shader workgroup,
//! each with the bounds the task shader culls it by (a sphere and a cone of triangle normals,
//! in object space).
//!
//! Two builders, because the cube must match six-pass bit for bit, and primitive order decides
//! which of two fragments at equal depth wins:
//! - [`ordered`] keeps the mesh's triangle order: each meshlet is a run of consecutive
//!   triangles, so the meshlets in order replay the index buffer exactly. Objects drawn without
//!   back-face culling (open meshes, closed ones around the eye) use these.
//! - [`clustered`] grows spatially compact meshlets (narrow cones, tight spheres) and reorders
//!   triangles to do so. That is safe only for a closed mesh drawn with back faces culled: two
//!   front-facing triangles of such a mesh cover the same sample at the same depth only where
//!   they meet, and there the rasterization rules give a shared edge's sample to exactly one
//!   of them (they lie on opposite sides of it) and a shared vertex carries the same attributes
//!   in both. Its meshlets may span unconnected parts (a box's six faces share no vertex),
//!   so small meshes stay one workgroup.
//!
//! Both guarantee what meshoptimizer's `buildMeshlets` does: every triangle in exactly one
//! meshlet with its winding kept, at most [`MAX_VERTICES`] vertices and [`MAX_TRIANGLES`]
//! triangles per meshlet, a sphere that contains the meshlet's vertices, and a cone that
//! contains every triangle's normal (tested below).

use glam::{DVec3, Vec3};

/// Most vertices of one meshlet (`MESHLET_MAX_VERTICES` in `cube_mesh.glsl`). 64 with 124
/// triangles is the size meshoptimizer recommends: a regular grid patch fills both limits.
pub const MAX_VERTICES: usize = 64;
/// Most triangles of one meshlet (`MESHLET_MAX_TRIANGLES`); 124 keeps the index output a
/// multiple of four bytes on hardware that packs it, and is below every driver's limit (256).
pub const MAX_TRIANGLES: usize = 124;

/// `cone_cutoff` of a meshlet that no eye position sees wholly from behind (its normals spread
/// over a half-space or more, or a triangle is degenerate): above 1, so the cone test
/// `dot(centre - eye, axis) > cutoff * |centre - eye| + radius` never holds.
pub const NEVER_BACK_FACING: f32 = 2.0;

/// Angle (radians) by which every triangle must face away before a meshlet is culled, about
/// one degree. The rasterizer decides facing from rounded, snapped window coordinates, so a
/// triangle within rounding of edge-on may count as front-facing there: the margin keeps cone
/// culling strictly inside what back-face culling removes. It costs a sliver of culling.
pub const CONE_MARGIN_RAD: f64 = 0.02;

/// One meshlet, in the mesh's object space.
#[derive(Debug, Clone, PartialEq)]
pub struct Meshlet {
    /// Mesh vertex indices, at most [`MAX_VERTICES`], in order of first use.
    pub vertices: Vec<u32>,
    /// Triangles as indices into `vertices`, wound as in the mesh; at most [`MAX_TRIANGLES`].
    pub triangles: Vec<[u8; 3]>,
    /// Bounding sphere of the vertices.
    pub center: Vec3,
    pub radius: f32,
    /// Unit axis of the cone of triangle normals.
    pub cone_axis: Vec3,
    /// sin(half-angle of the cone + [`CONE_MARGIN_RAD`]), or [`NEVER_BACK_FACING`]. An eye
    /// `e` sees every triangle from behind when (the task shader's test)
    /// `dot(center - e, cone_axis) > cone_cutoff * |center - e| + radius`.
    pub cone_cutoff: f32,
}

impl Meshlet {
    /// Whether an eye at `eye` (object space) sees every triangle of the meshlet from behind,
    /// by the same test the task shader makes.
    ///
    /// Why it holds: let a be the cone's half-angle with the margin m added, d the distance
    /// from the eye to the centre, u the direction, and b = asin(radius / d) the half-angle
    /// under which the eye sees the sphere. The test says cos(angle(axis, u)) > sin a + sin b,
    /// which is at least sin(a + b), so angle(axis, u) < 90° - a - b: the eye sees every point
    /// p of the sphere within 90° - a of the axis. Every triangle normal n lies within a - m
    /// of the axis, so angle(n, p - eye) < 90° - m: dot(n, p - eye) > 0, the eye is behind
    /// every triangle's plane, by the margin.
    #[cfg(test)]
    pub fn back_facing_from(&self, eye: Vec3) -> bool {
        let to_center = self.center - eye;
        to_center.dot(self.cone_axis) > self.cone_cutoff * to_center.length() + self.radius
    }
}

/// Meshlets that keep the mesh's triangle order (see the module's comment).
pub fn ordered(positions: &[Vec3], indices: &[u32]) -> Vec<Meshlet> {
    let mut open = Open::new(positions.len());
    let mut out = Vec::new();
    for tri in triangles(indices) {
        if !open.fits(tri) {
            out.push(open.close(positions));
        }
        open.add(tri);
    }
    if !open.triangles.is_empty() {
        out.push(open.close(positions));
    }
    out
}

/// Spatially compact meshlets, for closed meshes drawn with back faces culled (see the
/// module's comment). Each meshlet grows from a seed by the adjacent triangle that adds the
/// fewest new vertices, ties going to the one nearest the meshlet and closest to its normal
/// (meshoptimizer's greedy order, without its spatial index). A seed is the leftover
/// neighbour of the previous meshlet with the fewest free neighbours (growth sweeps the
/// surface instead of leaving islands), else the first free triangle in index order; a
/// meshlet whose neighbours are used up continues with that first free triangle.
pub fn clustered(positions: &[Vec3], indices: &[u32]) -> Vec<Meshlet> {
    let mut mesh = Clusters::new(positions, indices);
    let mut open = Open::new(positions.len());
    let mut out = Vec::new();
    while let Some(seed) = mesh.seed() {
        mesh.grow(seed, &mut open, out.len() as u32 + 1);
        out.push(open.close(positions));
    }
    out
}

/// The state of [`clustered`]: the mesh's triangles with what the greedy growth scores them
/// by, and which are taken.
struct Clusters {
    tris: Vec<[u32; 3]>,
    adjacency: Adjacency,
    /// Unit normals (zero for degenerate triangles) and centroids.
    normals: Vec<Vec3>,
    centroids: Vec<Vec3>,
    /// 1 / a typical edge length: distances are compared in edges, so the normal term
    /// weighs alike on meshes of any size.
    per_edge: f32,
    assigned: Vec<bool>,
    /// Per triangle: the stamp of the meshlet whose candidate list holds it.
    listed: Vec<u32>,
    /// No triangle before this one is free.
    first_free: usize,
    /// The free triangles sharing a vertex with the meshlet being grown (or the last one).
    candidates: Vec<u32>,
}

impl Clusters {
    fn new(positions: &[Vec3], indices: &[u32]) -> Self {
        let tris: Vec<[u32; 3]> = triangles(indices).collect();
        let normals = tris
            .iter()
            .map(|&t| face_normal(positions, t).normalize_or_zero().as_vec3())
            .collect();
        let centroids = tris
            .iter()
            .map(|t| t.iter().map(|&v| positions[v as usize]).sum::<Vec3>() / 3.0)
            .collect();
        let edge = tris
            .iter()
            .map(|t| positions[t[0] as usize].distance(positions[t[1] as usize]))
            .sum::<f32>()
            / tris.len().max(1) as f32;
        Self {
            adjacency: Adjacency::new(positions.len(), &tris),
            normals,
            centroids,
            per_edge: if edge > 0.0 { 1.0 / edge } else { 1.0 },
            assigned: vec![false; tris.len()],
            listed: vec![0; tris.len()],
            first_free: 0,
            candidates: Vec::new(),
            tris,
        }
    }

    /// The first free triangle in index order.
    fn next_free(&mut self) -> Option<u32> {
        while self.first_free < self.tris.len() && self.assigned[self.first_free] {
            self.first_free += 1;
        }
        (self.first_free < self.tris.len()).then_some(self.first_free as u32)
    }

    /// The next meshlet's first triangle: the last meshlet's free neighbour with the fewest
    /// free neighbours of its own, else the first free triangle.
    fn seed(&mut self) -> Option<u32> {
        let free_neighbours = |t: u32| {
            self.adjacency
                .around(&self.tris[t as usize])
                .filter(|&u| !self.assigned[u as usize])
                .count()
        };
        let leftover = self
            .candidates
            .iter()
            .copied()
            .filter(|&t| !self.assigned[t as usize])
            .min_by_key(|&t| (free_neighbours(t), t));
        leftover.or_else(|| self.next_free())
    }

    /// Grows `open` (empty) from `seed` until a limit is reached or nothing fits.
    fn grow(&mut self, seed: u32, open: &mut Open, stamp: u32) {
        self.candidates.clear();
        let mut normal_sum = Vec3::ZERO;
        let mut centroid_sum = Vec3::ZERO;
        let mut next = Some(seed);
        while let Some(t) = next {
            let tri = self.tris[t as usize];
            open.add(tri);
            self.assigned[t as usize] = true;
            normal_sum += self.normals[t as usize];
            centroid_sum += self.centroids[t as usize];
            for u in self.adjacency.around(&tri) {
                if !self.assigned[u as usize] && self.listed[u as usize] != stamp {
                    self.listed[u as usize] = stamp;
                    self.candidates.push(u);
                }
            }
            if open.triangles.len() == MAX_TRIANGLES {
                return;
            }
            let assigned = &self.assigned;
            self.candidates.retain(|&u| !assigned[u as usize]);
            let center = centroid_sum / open.triangles.len() as f32;
            next = self.best_candidate(open, center, normal_sum.normalize_or_zero());
            if next.is_none() && self.candidates.is_empty() {
                // This part of the mesh is used up: carry on with the next free triangle.
                next = self
                    .next_free()
                    .filter(|&u| open.fits(self.tris[u as usize]));
            }
        }
    }

    /// The candidate that fits and adds the fewest new vertices, then lies nearest the
    /// meshlet's `center` and closest to its mean normal `axis`; ties to the lowest index.
    fn best_candidate(&self, open: &Open, center: Vec3, axis: Vec3) -> Option<u32> {
        let score = |u: u32| {
            let spread = 1.0 - self.normals[u as usize].dot(axis);
            let distance = self.centroids[u as usize].distance(center) * self.per_edge;
            (
                open.new_vertices(self.tris[u as usize]),
                distance + 2.0 * spread,
            )
        };
        self.candidates
            .iter()
            .copied()
            .filter(|&u| open.fits(self.tris[u as usize]))
            .map(|u| (score(u), u))
            .min_by(|(a, ua), (b, ub)| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(ua.cmp(ub)))
            .map(|(_, u)| u)
    }
}

fn triangles(indices: &[u32]) -> impl Iterator<Item = [u32; 3]> + '_ {
    indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]])
}

/// The triangle's normal by its winding (counter-clockwise from the front), unnormalized, in
/// f64 so that the cone is computed from exact products of the f32 positions.
fn face_normal(positions: &[Vec3], t: [u32; 3]) -> DVec3 {
    let p = |i: usize| positions[t[i] as usize].as_dvec3();
    (p(1) - p(0)).cross(p(2) - p(0))
}

/// Which triangles use each vertex (compressed rows).
struct Adjacency {
    offsets: Vec<u32>,
    triangles: Vec<u32>,
}

impl Adjacency {
    fn new(vertex_count: usize, tris: &[[u32; 3]]) -> Self {
        let mut offsets = vec![0u32; vertex_count + 1];
        for t in tris {
            for &v in t {
                offsets[v as usize + 1] += 1;
            }
        }
        for i in 0..vertex_count {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut triangles = vec![0u32; offsets[vertex_count] as usize];
        for (i, t) in tris.iter().enumerate() {
            for &v in t {
                triangles[fill[v as usize] as usize] = i as u32;
                fill[v as usize] += 1;
            }
        }
        Self { offsets, triangles }
    }

    /// Every triangle sharing a vertex with `tri` (itself included, some more than once).
    fn around<'a>(&'a self, tri: &'a [u32; 3]) -> impl Iterator<Item = u32> + 'a {
        tri.iter().flat_map(move |&v| {
            let (a, b) = (self.offsets[v as usize], self.offsets[v as usize + 1]);
            self.triangles[a as usize..b as usize].iter().copied()
        })
    }
}

/// The meshlet being built.
struct Open {
    vertices: Vec<u32>,
    triangles: Vec<[u8; 3]>,
    /// Per mesh vertex: its index in `vertices`, or `u8::MAX` when absent (reset on close).
    local: Vec<u8>,
}

const _: () = assert!(MAX_VERTICES < u8::MAX as usize);

impl Open {
    fn new(vertex_count: usize) -> Self {
        Self {
            vertices: Vec::with_capacity(MAX_VERTICES),
            triangles: Vec::with_capacity(MAX_TRIANGLES),
            local: vec![u8::MAX; vertex_count],
        }
    }

    /// Vertices of `tri` not yet in the meshlet (a degenerate triangle may repeat one).
    fn new_vertices(&self, tri: [u32; 3]) -> usize {
        (0..3)
            .filter(|&i| self.local[tri[i] as usize] == u8::MAX && !tri[..i].contains(&tri[i]))
            .count()
    }

    fn fits(&self, tri: [u32; 3]) -> bool {
        self.triangles.len() < MAX_TRIANGLES
            && self.vertices.len() + self.new_vertices(tri) <= MAX_VERTICES
    }

    fn add(&mut self, tri: [u32; 3]) {
        let local = tri.map(|v| {
            let slot = &mut self.local[v as usize];
            if *slot == u8::MAX {
                *slot = self.vertices.len() as u8;
                self.vertices.push(v);
            }
            *slot
        });
        self.triangles.push(local);
    }

    /// The finished meshlet with its bounds; the builder is empty again.
    fn close(&mut self, positions: &[Vec3]) -> Meshlet {
        for &v in &self.vertices {
            self.local[v as usize] = u8::MAX;
        }
        let vertices = std::mem::take(&mut self.vertices);
        let triangles = std::mem::take(&mut self.triangles);
        let (center, radius) = sphere(positions, &vertices);
        let (cone_axis, cone_cutoff) = cone(positions, &vertices, &triangles);
        Meshlet {
            vertices,
            triangles,
            center,
            radius,
            cone_axis,
            cone_cutoff,
        }
    }
}

/// A sphere around `vertices`: the centre of their box, the farthest vertex's distance
/// (computed in f64 from the stored f32 centre and rounded up).
fn sphere(positions: &[Vec3], vertices: &[u32]) -> (Vec3, f32) {
    let points = || vertices.iter().map(|&v| positions[v as usize].as_dvec3());
    let lo = points().fold(DVec3::INFINITY, DVec3::min);
    let hi = points().fold(DVec3::NEG_INFINITY, DVec3::max);
    let center = ((lo + hi) * 0.5).as_vec3();
    let radius = points()
        .map(|p| p.distance(center.as_dvec3()))
        .fold(0.0, f64::max);
    (center, round_up(radius))
}

/// The cone of the triangles' normals: axis the mean unit normal, half-angle the largest
/// angle from it, widened by [`CONE_MARGIN_RAD`]; [`NEVER_BACK_FACING`] when a triangle has no
/// direction (degenerate) or the cone reaches a half-space.
fn cone(positions: &[Vec3], vertices: &[u32], triangles: &[[u8; 3]]) -> (Vec3, f32) {
    let normals: Vec<DVec3> = triangles
        .iter()
        .map(|t| face_normal(positions, t.map(|i| vertices[i as usize])))
        .collect();
    let never = (Vec3::Z, NEVER_BACK_FACING);
    // A triangle whose edges are parallel to within f64 rounding has no reliable facing.
    let degenerate = |n: &DVec3| n.length_squared() <= f64::MIN_POSITIVE;
    if normals.iter().any(degenerate) {
        return never;
    }
    let sum: DVec3 = normals.iter().map(|n| n.normalize()).sum();
    if sum.length() < 1e-6 {
        return never;
    }
    // The shader uses the f32 axis: measure the spread against that one.
    let axis = sum.normalize().as_vec3();
    let axis64 = axis.as_dvec3().normalize();
    let min_dot = normals
        .iter()
        .map(|n| n.normalize().dot(axis64))
        .fold(1.0, f64::min);
    let half_angle = min_dot.clamp(-1.0, 1.0).acos() + CONE_MARGIN_RAD;
    if half_angle >= std::f64::consts::FRAC_PI_2 {
        return never;
    }
    (axis, round_up(half_angle.sin()))
}

/// `x` as an f32 no smaller than it (a relative nudge bigger than one f32 rounding step).
fn round_up(x: f64) -> f32 {
    (x * (1.0 + 1e-6) + f64::from(f32::MIN_POSITIVE)) as f32
}

#[cfg(test)]
mod tests;
