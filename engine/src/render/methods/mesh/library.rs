//! The meshlets of every drawable, built once when the method is created and uploaded into
//! three buffers the task and mesh shaders index: meshlets, their vertex lists (absolute
//! indices into the scene's vertex buffer) and their packed triangles.

use std::collections::HashMap;
use std::ops::Range;

use super::gpu::{self, pack_triangle};
use super::meshlets::{self, Meshlet};
use crate::render::methods::MethodContext;
use crate::render::resources::Drawable;
use crate::scene::{Mesh, Scene};
use crate::vk::memory::Buffer;
use crate::vk::GpuError;
use ash::vk;

/// Where one drawable's meshlets sit in [`MeshletLibrary::meshlets`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DrawableMeshlets {
    /// In the mesh's triangle order: for draws without back-face culling.
    pub ordered: Range<u32>,
    /// Spatially compact: for draws with back faces culled (empty for an open mesh, whose
    /// back faces are never culled).
    pub clustered: Range<u32>,
}

impl DrawableMeshlets {
    /// The meshlets to draw with back faces culled (`cull_back`) or not, and whether the
    /// shaders may cull back-facing meshlets and triangles among them (only with back faces
    /// culled, where the compact meshlets are used).
    pub fn for_culling(&self, cull_back: bool) -> (Range<u32>, bool) {
        if cull_back && !self.clustered.is_empty() {
            (self.clustered.clone(), true)
        } else {
            (self.ordered.clone(), false)
        }
    }

    /// Most meshlets one update draws for this drawable.
    pub fn most(&self) -> usize {
        self.ordered.len().max(self.clustered.len())
    }
}

/// The meshlets of every drawable, on the CPU (flattened as the shaders read them).
#[derive(Debug, Default)]
pub struct MeshletLibrary {
    pub meshlets: Vec<gpu::Meshlet>,
    /// Absolute vertex indices (the drawable's vertex offset added).
    pub vertices: Vec<u32>,
    /// `gpu::pack_triangle` of each triangle's local indices.
    pub triangles: Vec<u32>,
    /// Per drawable (walls 0..6, then one per object).
    pub drawables: Vec<DrawableMeshlets>,
}

impl MeshletLibrary {
    /// Builds the meshlets of each mesh once (objects share meshes: a drawable's mesh is known
    /// by where it sits in the shared buffers), clustered ones only for closed meshes.
    pub fn build(scene: &Scene, drawables: &[Drawable]) -> Result<Self, GpuError> {
        let walls = crate::scene::state::room_meshes(&scene.room);
        let mut library = Self::default();
        let mut built: HashMap<(u32, i32), DrawableMeshlets> = HashMap::new();
        for (i, d) in drawables.iter().enumerate() {
            let mesh: &Mesh = match i.checked_sub(walls.len()) {
                None => &walls[i],
                Some(o) => &scene.meshes[scene.objects[o].mesh],
            };
            if mesh.indices.len() != d.index_count as usize {
                return Err(GpuError::Unsupported(format!(
                    "drawable {i} has {} indices but its mesh {}: drawables are no longer \
                     walls then objects",
                    d.index_count,
                    mesh.indices.len()
                )));
            }
            let ranges = built
                .entry((d.first_index, d.vertex_offset))
                .or_insert_with(|| library.add_mesh(mesh, d))
                .clone();
            library.drawables.push(ranges);
        }
        Ok(library)
    }

    fn add_mesh(&mut self, mesh: &Mesh, d: &Drawable) -> DrawableMeshlets {
        let ordered = meshlets::ordered(&mesh.positions, &mesh.indices);
        let ordered = self.append(&ordered, d.vertex_offset);
        let clustered = if d.cull_back {
            let clustered = meshlets::clustered(&mesh.positions, &mesh.indices);
            self.append(&clustered, d.vertex_offset)
        } else {
            ordered.end..ordered.end
        };
        DrawableMeshlets { ordered, clustered }
    }

    fn append(&mut self, meshlets: &[Meshlet], vertex_offset: i32) -> Range<u32> {
        let first = self.meshlets.len() as u32;
        for m in meshlets {
            self.meshlets.push(gpu::Meshlet {
                sphere: m.center.extend(m.radius),
                cone: m.cone_axis.extend(m.cone_cutoff),
                first_vertex: self.vertices.len() as u32,
                first_triangle: self.triangles.len() as u32,
                vertex_count: m.vertices.len() as u32,
                triangle_count: m.triangles.len() as u32,
            });
            self.vertices.extend(
                m.vertices
                    .iter()
                    .map(|&v| (i64::from(v) + i64::from(vertex_offset)) as u32),
            );
            self.triangles
                .extend(m.triangles.iter().map(|&t| pack_triangle(t)));
        }
        first..self.meshlets.len() as u32
    }

    /// Most meshlet draws one update can have (every drawable in some face).
    pub fn most_draws(&self) -> usize {
        self.drawables.iter().map(DrawableMeshlets::most).sum()
    }
}

/// The library's three buffers on the device: device-local, uploaded once.
pub struct MeshletBuffers {
    pub meshlets: Buffer,
    pub vertices: Buffer,
    pub triangles: Buffer,
}

impl MeshletBuffers {
    pub fn upload(ctx: &MethodContext<'_>, library: &MeshletLibrary) -> Result<Self, GpuError> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let mut made = ctx
            .upload(&[
                (bytemuck::cast_slice(&library.meshlets), storage, "meshlets"),
                (
                    bytemuck::cast_slice(&library.vertices),
                    storage,
                    "meshlet vertices",
                ),
                (
                    bytemuck::cast_slice(&library.triangles),
                    storage,
                    "meshlet triangles",
                ),
            ])?
            .into_iter();
        let mut next = || made.next().expect("one buffer per upload");
        Ok(Self {
            meshlets: next(),
            vertices: next(),
            triangles: next(),
        })
    }
}
