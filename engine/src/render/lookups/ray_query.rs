//! The `ray-query` lookup: the exact mirror on the GPU. The mirror's fragment shader traces
//! the reflected pixel-centre ray with `VK_KHR_ray_query` through a top-level acceleration
//! structure of every drawable (walls and objects) and shades the hit with `materials.glsl`,
//! as the CPU reference does. No cube map is read, so the renderer skips the cube fill.
//!
//! One bottom-level structure per mesh, built once on the device. The top-level structure is
//! rebuilt every frame from the drawables' transforms at time t, not refit: it holds one
//! instance per drawable (tens), which a rebuild handles in well under a millisecond, and a
//! rebuild's quality does not decay as objects move far from where the structure was first
//! built (a refit only stretches the old boxes).

use std::collections::HashMap;

use ash::vk;
use glam::UVec4;

use super::{LookupContext, LookupNeeds, LookupPass, MirrorLookup};
use crate::render::gpu::{ObjectData, Vertex, LOOKUP_RAY_QUERY};
use crate::render::targets::{DIRECTION_FORMAT, VIEW_FORMAT};
use crate::scene::Lookup;
use crate::vk::acceleration::{self, AccelerationStructure, TopLevel, TriangleMesh};
use crate::vk::descriptors::{self, DescriptorPool, DescriptorSetLayout};
use crate::vk::device::OptionalFeatures;
use crate::vk::memory::{Buffer, BufferDesc};
use crate::vk::pipeline::{Pipeline, PipelineLayout};
use crate::vk::GpuError;

pub struct RayQuery;

impl MirrorLookup for RayQuery {
    fn lookup(&self) -> Lookup {
        Lookup::RayQuery
    }

    fn summary(&self) -> &'static str {
        "the reflected ray traced through the scene (VK_KHR_ray_query): exact, no cube map"
    }

    fn needs(&self) -> LookupNeeds {
        LookupNeeds {
            features: OptionalFeatures {
                ray_query: true,
                ..Default::default()
            },
        }
    }

    fn uses_cube(&self) -> bool {
        false
    }

    fn flag(&self) -> u32 {
        LOOKUP_RAY_QUERY
    }

    fn create(&self, ctx: &LookupContext<'_>) -> Result<Box<dyn LookupPass>, GpuError> {
        if !ctx.device.enabled.ray_query {
            return Err(GpuError::Unsupported(
                "lookup ray-query: the device was created without ray queries".into(),
            ));
        }
        Ok(Box::new(RayQueryPass::create(ctx)?))
    }
}

/// The ray-query lookup's per-renderer state. Field order is drop order.
struct RayQueryPass {
    colour: Pipeline,
    directions: Pipeline,
    layout: PipelineLayout,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    _set_layout: DescriptorSetLayout,
    _ranges: Buffer,
    top: TopLevel,
    /// Index into `bottom` of each drawable's mesh.
    mesh_of: Vec<usize>,
    bottom: Vec<AccelerationStructure>,
}

impl RayQueryPass {
    fn create(ctx: &LookupContext<'_>) -> Result<Self, GpuError> {
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
            "ray-query drawable ranges",
        )?;
        range_buffer.write(&ranges)?;

        let stage = vk::ShaderStageFlags::FRAGMENT;
        let set_layout = DescriptorSetLayout::create(
            device,
            &[
                descriptors::binding(0, vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, 1, stage),
                descriptors::binding(1, vk::DescriptorType::STORAGE_BUFFER, 1, stage),
                descriptors::binding(2, vk::DescriptorType::STORAGE_BUFFER, 1, stage),
                descriptors::binding(3, vk::DescriptorType::STORAGE_BUFFER, 1, stage),
            ],
            "ray-query set layout",
        )?;
        let pool = DescriptorPool::create(
            device,
            1,
            &[
                vk::DescriptorPoolSize {
                    ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR,
                    descriptor_count: 1,
                },
                vk::DescriptorPoolSize {
                    ty: vk::DescriptorType::STORAGE_BUFFER,
                    descriptor_count: 3,
                },
            ],
            "ray-query descriptors",
        )?;
        let set = pool.allocate(&set_layout, "ray-query set")?;
        write_structure(ctx, set, &top.structure);
        for (binding, buffer) in [(1, &res.vertices), (2, &res.indices), (3, &range_buffer)] {
            descriptors::write_buffer(
                device,
                set,
                binding,
                vk::DescriptorType::STORAGE_BUFFER,
                buffer.raw,
            );
        }
        let layout = PipelineLayout::create(
            device,
            &[res.scene_set_layout.raw, set_layout.raw],
            ctx.push_size,
            "ray-query mirror layout",
        )?;
        let colour = crate::render::pipelines::mirror_pipeline(
            device,
            &layout,
            crate::shaders::MIRROR_RAY_QUERY_FRAG,
            VIEW_FORMAT,
            "ray-query mirror pipeline",
        )?;
        let directions = crate::render::pipelines::mirror_pipeline(
            device,
            &layout,
            crate::shaders::MIRROR_RAY_QUERY_DIRECTION_FRAG,
            DIRECTION_FORMAT,
            "ray-query mirror direction pipeline",
        )?;
        Ok(Self {
            colour,
            directions,
            layout,
            _pool: pool,
            set,
            _set_layout: set_layout,
            _ranges: range_buffer,
            top,
            mesh_of,
            bottom,
        })
    }
}

/// One triangle mesh per distinct range of the index buffer (objects sharing a mesh share
/// its bottom-level structure), and which of them each drawable uses.
fn unique_meshes(ctx: &LookupContext<'_>) -> (Vec<TriangleMesh>, Vec<usize>) {
    let res = ctx.resources;
    let vertex_address = acceleration::buffer_address(ctx.device, &res.vertices);
    let index_address = acceleration::buffer_address(ctx.device, &res.indices);
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

/// Points binding 0 of `set` at the top-level structure.
fn write_structure(ctx: &LookupContext<'_>, set: vk::DescriptorSet, s: &AccelerationStructure) {
    let structures = [s.raw];
    let mut info = vk::WriteDescriptorSetAccelerationStructureKHR::default()
        .acceleration_structures(&structures);
    let write = vk::WriteDescriptorSet::default()
        .dst_set(set)
        .dst_binding(0)
        .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
        .descriptor_count(1)
        .push_next(&mut info);
    // SAFETY: the set and the structure are live; no command buffer using the set is pending.
    unsafe { ctx.device.raw.update_descriptor_sets(&[write], &[]) };
}

/// The instance record of drawable `index`: its model-to-render transform (row-major 3x4),
/// its index as the custom index (the shader's key to its ranges and object data), every
/// ray mask bit, both faces.
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
        instance_custom_index_and_mask: vk::Packed24_8::new(index as u32, 0xFF),
        instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
            0,
            vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw() as u8,
        ),
        acceleration_structure_reference: vk::AccelerationStructureReferenceKHR {
            device_handle: blas,
        },
    }
}

impl LookupPass for RayQueryPass {
    fn pipeline(&self, directions: bool) -> &Pipeline {
        if directions {
            &self.directions
        } else {
            &self.colour
        }
    }

    fn layout(&self) -> &PipelineLayout {
        &self.layout
    }

    fn set(&self) -> vk::DescriptorSet {
        self.set
    }

    fn prepare(&mut self, objects: &[ObjectData]) -> Result<(), GpuError> {
        let records: Vec<vk::AccelerationStructureInstanceKHR> = objects
            .iter()
            .enumerate()
            .map(|(i, o)| instance(i, o, self.bottom[self.mesh_of[i]].address))
            .collect();
        self.top.write_instances(&records)
    }

    fn record(&self, cmd: vk::CommandBuffer) {
        self.top.record_build(cmd);
    }
}
