//! The scene as ray queries see it, shared by the lookups that trace (`ray-query` for every
//! mirror pixel, `distance-exact` for the rays its search cannot resolve): one bottom-level
//! acceleration structure per mesh, built once on the device, and a top-level one over every
//! drawable (walls and objects), plus the drawables' index ranges the shader needs to fetch a
//! hit triangle's attributes. Its four descriptors (`shaders/include/ray_query.glsl`) sit at
//! consecutive bindings from a first one the lookup chooses.
//!
//! The top-level structure is rebuilt every frame from the drawables' transforms at time t,
//! not refit: a rebuild's quality does not decay as objects move far from where the structure
//! was first built (a refit only stretches the old boxes). Its instance records are handed over
//! in traversal order ([`TraceOrder::Split`], `trees::split_order`) and each mesh's triangles
//! likewise (`SceneResources::traced_indices`): lavapipe builds its tree from the order it is
//! given, and the scene's own order (generated crowds are random) made it ~20x slower.

use std::collections::HashMap;

use ash::vk;
use glam::{UVec4, Vec3};

use super::{LookupContext, LookupNeeds};
use crate::render::gpu::{ObjectData, Vertex};
use crate::render::graph::{PassRecorder, Resource, Use};
use crate::trees::split_order::midpoint_split_order;
use crate::vk::acceleration::{self, AccelerationStructure, TopLevel, TriangleMesh};
use crate::vk::descriptors;
use crate::vk::device::{Device, OptionalFeatures};
use crate::vk::memory::{Buffer, BufferDesc};
use crate::vk::uploads::FrameUploads;
use crate::vk::GpuError;

/// The order acceleration-structure builds are handed their leaves in.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum TraceOrder {
    /// Instances and each mesh's triangles by a recursive median split of their boxes, the
    /// ranges a midpoint-splitting builder (lavapipe's) makes coherent (`trees::split_order`).
    #[default]
    Split,
    /// The scene's own order (drawables as listed, triangles as the mesh has them): what was
    /// built before, kept to measure the difference and to test that the images agree.
    Given,
}

impl TraceOrder {
    pub const ALL: [TraceOrder; 2] = [TraceOrder::Split, TraceOrder::Given];

    pub fn name(self) -> &'static str {
        match self {
            TraceOrder::Split => "split",
            TraceOrder::Given => "given",
        }
    }
}

impl std::fmt::Display for TraceOrder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The acceleration structures and the drawables' ranges. Field order is drop order.
pub struct SceneTrace {
    ranges: Buffer,
    top: TopLevel,
    /// Index into `bottom` of each drawable's mesh.
    mesh_of: Vec<usize>,
    bottom: Vec<AccelerationStructure>,
    order: TraceOrder,
    /// This frame's instance records (reused: no allocation per frame).
    records: Vec<vk::AccelerationStructureInstanceKHR>,
}

impl SceneTrace {
    /// What a lookup that traces needs from the device.
    pub const NEEDS: LookupNeeds = LookupNeeds {
        features: OptionalFeatures {
            ray_query: true,
            multiview: false,
            geometry_shader: false,
            shader_output_layer: false,
            multi_draw_indirect: false,
            mesh_shader: false,
        },
    };

    /// Refuses `lookup` when the device was created without ray queries.
    pub fn require(ctx: &LookupContext<'_>, lookup: &str) -> Result<(), GpuError> {
        if ctx.device.enabled.ray_query {
            Ok(())
        } else {
            Err(GpuError::Unsupported(format!(
                "lookup {lookup}: the device was created without ray queries"
            )))
        }
    }

    /// Builds the bottom-level structures (waiting for the device) and an empty top level.
    pub fn create(ctx: &LookupContext<'_>) -> Result<Self, GpuError> {
        let device = ctx.device;
        let res = ctx.resources;
        let (meshes, mesh_of) = unique_meshes(ctx);
        let bottom = acceleration::build_bottom_levels(device, ctx.submitter, &meshes)?;
        let top = TopLevel::create(device, res.drawables.len() as u32, "scene TLAS")?;
        // Where each drawable's triangles start: the shader fetches their attributes.
        let ranges: Vec<UVec4> = res
            .drawables
            .iter()
            .map(|d| UVec4::new(d.first_index, d.vertex_offset as u32, 0, 0))
            .collect();
        let mut range_buffer = Buffer::create(
            device,
            &BufferDesc::new_cpu_to_gpu(
                std::mem::size_of_val(ranges.as_slice()) as u64,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            ),
            "traced drawable ranges",
        )?;
        range_buffer.write(&ranges)?;
        Ok(Self {
            ranges: range_buffer,
            top,
            mesh_of,
            bottom,
            order: ctx.trace_order,
            records: Vec::with_capacity(res.drawables.len()),
        })
    }

    /// The set-layout bindings `ray_query.glsl` reads, from binding `first` on: the top-level
    /// structure, then the vertex, index and range buffers.
    pub fn bindings(first: u32) -> [vk::DescriptorSetLayoutBinding<'static>; 4] {
        let stage = vk::ShaderStageFlags::FRAGMENT;
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        [
            descriptors::binding(
                first,
                vk::DescriptorType::ACCELERATION_STRUCTURE_KHR,
                1,
                stage,
            ),
            descriptors::binding(first + 1, storage, 1, stage),
            descriptors::binding(first + 2, storage, 1, stage),
            descriptors::binding(first + 3, storage, 1, stage),
        ]
    }

    /// What a pool needs for one set holding [`SceneTrace::bindings`].
    pub fn pool_sizes() -> [vk::DescriptorPoolSize; 2] {
        [
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR,
                descriptor_count: 1,
            },
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::STORAGE_BUFFER,
                descriptor_count: 3,
            },
        ]
    }

    /// Points [`SceneTrace::bindings`] of `set`, from `first`, at this scene.
    pub fn write(&self, ctx: &LookupContext<'_>, set: vk::DescriptorSet, first: u32) {
        let res = ctx.resources;
        write_structure(ctx.device, set, first, &self.top.structure);
        // The triangle order the bottom levels were built from: a hit's primitive index
        // counts in it.
        let indices = traced_indices(ctx);
        let buffers = [&res.vertices, indices, &self.ranges];
        for (binding, buffer) in (first + 1..).zip(buffers) {
            descriptors::write_buffer(
                ctx.device,
                set,
                binding,
                vk::DescriptorType::STORAGE_BUFFER,
                buffer.raw,
            );
        }
    }

    /// This frame's instances (the drawables at time t, walls first, and their render-space
    /// bounds), handed to the build in [`TraceOrder`]. Each keeps its drawable index as its
    /// custom index, so the order changes nothing the shaders see.
    pub fn prepare(
        &mut self,
        uploads: &mut FrameUploads,
        objects: &[ObjectData],
        bounds: &[(Vec3, Vec3)],
    ) -> Result<(), GpuError> {
        let order: Vec<u32> = match self.order {
            TraceOrder::Split => midpoint_split_order(bounds),
            TraceOrder::Given => (0..objects.len() as u32).collect(),
        };
        self.records.clear();
        self.records.extend(order.iter().map(|&i| {
            let i = i as usize;
            instance(i, &objects[i], self.bottom[self.mesh_of[i]].address)
        }));
        self.top.write_instances(uploads, &self.records)
    }

    /// What the top level's rebuild writes (its structure, its scratch), resting as the last
    /// frame left them: the structure traced by the fragment shaders, the scratch built with.
    pub fn resources(&self) -> Vec<(Resource, Use)> {
        let [structure, scratch] = self.top.written_by_build();
        vec![
            (Resource::Buffer(structure), Use::AccelerationTraced),
            (Resource::Buffer(scratch), Use::AccelerationBuild),
        ]
    }

    /// Records the top level's rebuild: after the last frame's build and ray queries (its
    /// instances are this frame's uploads, read anywhere once copied), before this frame's.
    pub fn record(&self, pass: &mut PassRecorder<'_>) {
        let [structure, scratch] = self.top.written_by_build().map(Resource::Buffer);
        pass.declare(&[
            (structure, Use::AccelerationBuild),
            (scratch, Use::AccelerationBuild),
        ]);
        self.top.record_build(pass.cmd());
        pass.declare(&[(structure, Use::AccelerationTraced)]);
    }
}

/// One triangle mesh per distinct range of the index buffer (objects sharing a mesh share
/// its bottom-level structure), and which of them each drawable uses.
fn unique_meshes(ctx: &LookupContext<'_>) -> (Vec<TriangleMesh>, Vec<usize>) {
    let res = ctx.resources;
    let vertex_address = acceleration::buffer_address(ctx.device, &res.vertices);
    let index_address = acceleration::buffer_address(ctx.device, traced_indices(ctx));
    let mut meshes = Vec::new();
    let mut seen: HashMap<(u32, i32), usize> = HashMap::new();
    let mesh_of = res
        .drawables
        .iter()
        .map(|d| {
            *seen
                .entry((d.first_index, d.vertex_offset))
                .or_insert_with(|| {
                    meshes.push(TriangleMesh {
                        vertex_address,
                        vertex_stride: std::mem::size_of::<Vertex>() as u64,
                        vertex_count: d.vertex_count,
                        first_vertex: d.vertex_offset as u32,
                        index_address,
                        first_index: d.first_index,
                        index_count: d.index_count,
                    });
                    meshes.len() - 1
                })
        })
        .collect();
    (meshes, mesh_of)
}

/// The index buffer the bottom levels are built from: each mesh's triangles in split order
/// (made with the scene's buffers on a device with ray queries), or as the scene has them.
fn traced_indices<'a>(ctx: &LookupContext<'a>) -> &'a Buffer {
    let res = ctx.resources;
    match (ctx.trace_order, &res.traced_indices) {
        (TraceOrder::Split, Some(sorted)) => sorted,
        _ => &res.indices,
    }
}

/// Points `binding` of `set` at the top-level structure.
fn write_structure(
    device: &Device,
    set: vk::DescriptorSet,
    binding: u32,
    s: &AccelerationStructure,
) {
    let structures = [s.raw];
    let mut info = vk::WriteDescriptorSetAccelerationStructureKHR::default()
        .acceleration_structures(&structures);
    let write = vk::WriteDescriptorSet::default()
        .dst_set(set)
        .dst_binding(binding)
        .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
        .descriptor_count(1)
        .push_next(&mut info);
    // SAFETY: the set and the structure are live; no command buffer using the set is pending.
    unsafe { device.raw.update_descriptor_sets(&[write], &[]) };
}

/// The instance record of drawable `index`: its model-to-render transform (row-major 3x4),
/// its index as the custom index (the shader's key to its ranges and object data), its mask
/// (a wall's or an object's: ray_query.glsl traces the two apart), both faces.
fn instance(
    index: usize,
    o: &ObjectData,
    blas: vk::DeviceAddress,
) -> vk::AccelerationStructureInstanceKHR {
    let m = o.model_to_world;
    let rows = [m.row(0), m.row(1), m.row(2)];
    let matrix: [f32; 12] = std::array::from_fn(|i| rows[i / 4][i % 4]);
    vk::AccelerationStructureInstanceKHR {
        transform: vk::TransformMatrixKHR { matrix },
        instance_custom_index_and_mask: vk::Packed24_8::new(index as u32, ray_mask(index)),
        instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
            0,
            vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw() as u8,
        ),
        acceleration_structure_reference: vk::AccelerationStructureReferenceKHR {
            device_handle: blas,
        },
    }
}

/// The ray mask of drawable `index`: walls 0..6, objects after them (shared.glsl's
/// `RAY_MASK_WALLS`, `RAY_MASK_OBJECTS`).
fn ray_mask(index: usize) -> u8 {
    use crate::shaders::shared::{RAY_MASK_OBJECTS, RAY_MASK_WALLS};
    let mask = if index < 6 {
        RAY_MASK_WALLS
    } else {
        RAY_MASK_OBJECTS
    };
    mask as u8
}
