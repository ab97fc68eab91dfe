//! Mesh-shader layered fill (`VK_EXT_mesh_shader`): every mesh is cut into meshlets once, at
//! load ([`meshlets`]); each update lists the meshlets of the objects visible in some dirty
//! face, in draw order, and one draw call per run of equal back-face culling hands them to
//! task workgroups of [`gpu::TASK_MESHLETS`]. The task shader culls each meshlet against each
//! face its object is visible in (the face's frustum; the cone of its normals seen from the
//! cube's centre, when back faces are culled) and launches one mesh workgroup per surviving
//! (meshlet, face) pair. The mesh shader transforms the meshlet's vertices for that face with
//! six-pass's `precise` math, marks the triangles that cannot leave a fragment as culled
//! (outside one clip plane, or surely back-facing), and routes the rest to the face with the
//! per-primitive layer.
//!
//! Same pixels as six-pass: the clip coordinates are bit-identical, and within each face the
//! triangles arrive in six-pass's order wherever order can matter. Objects go in the frame's
//! draw order, meshlets of an object in order, and mesh workgroups rasterize in the order of
//! their task workgroups, then of their index (the specification's mesh shader primitive
//! ordering). An object drawn without back-face culling uses meshlets that replay its index
//! buffer; one drawn with back faces culled uses compact, reordered meshlets, which is safe
//! there (`meshlets`' comment says why). Culling only drops what the rasterizer would drop.

mod gpu;
mod library;
mod meshlets;

use std::sync::Arc;

use ash::vk;

use super::{
    CubeLayout, CubePlan, CubeRecorder, FillMethod, FillPass, MethodContext, Needs, Prepare,
};
use crate::vk::descriptors::{self, DescriptorPool, DescriptorSetLayout};
use crate::vk::device::{Device, Limit, OptionalFeatures};
use crate::vk::memory::{Buffer, BufferDesc};
use crate::vk::pipeline::{Pipeline, PipelineLayout, ShaderStage, SpecConstant};
use crate::vk::GpuError;
use gpu::{MeshPush, MeshletDraw, SPEC_SUB_PIXEL_BITS, TASK_MESHLETS};
use library::{DrawableMeshlets, MeshletBuffers, MeshletLibrary};

/// Task workgroups one draw call launches at most: the least `maxTaskWorkGroupCount[0]` the
/// specification allows (a longer run is split into several calls, still in order).
const MAX_TASK_WORKGROUPS: u32 = 65_535;

/// Subgroups at most this wide get the 8-invocation mesh shader (`cube_mesh_narrow.mesh`):
/// a mesh workgroup is then one subgroup, which lavapipe (8 lanes of 32 bits) runs without
/// switching coroutines at the shader's barrier. Wider subgroups (GPUs) get 32 invocations.
const NARROW_SUBGROUP: u32 = 8;

/// What both mesh methods need: the stage, and a layer per face.
fn needs() -> Needs {
    Needs {
        features: OptionalFeatures {
            mesh_shader: true,
            ..Default::default()
        },
        // A primitive may go to any of the six faces.
        limits: &[(Limit::MeshOutputLayers, 6)],
        probe: false,
    }
}

pub struct MeshShader;

impl FillMethod for MeshShader {
    fn name(&self) -> &'static str {
        "mesh"
    }

    fn summary(&self) -> &'static str {
        "one layered pass; task shaders cull meshlets per face, mesh shaders set gl_Layer"
    }

    fn needs(&self) -> Needs {
        needs()
    }

    fn layout(&self) -> CubeLayout {
        CubeLayout::Layered
    }

    fn create(&self, ctx: &MethodContext<'_>) -> Result<Box<dyn FillPass>, GpuError> {
        let narrow = subgroup_size(ctx.device) <= NARROW_SUBGROUP;
        Ok(Box::new(MeshFill::create(ctx, narrow)?))
    }
}

/// `mesh` with 32-invocation mesh workgroups on every device, where `mesh` picks 8 for narrow
/// subgroups: it keeps the GPUs' shader tested and measured on lavapipe.
pub struct MeshShaderWide;

impl FillMethod for MeshShaderWide {
    fn name(&self) -> &'static str {
        "mesh-wide"
    }

    fn summary(&self) -> &'static str {
        "mesh with 32 invocations per mesh workgroup on every device; kept to measure"
    }

    fn variant_of(&self) -> Option<&'static str> {
        Some("mesh")
    }

    fn needs(&self) -> Needs {
        needs()
    }

    fn layout(&self) -> CubeLayout {
        CubeLayout::Layered
    }

    fn create(&self, ctx: &MethodContext<'_>) -> Result<Box<dyn FillPass>, GpuError> {
        Ok(Box::new(MeshFill::create(ctx, false)?))
    }
}

/// The method's per-renderer state. Field order is drop order: the pipeline and its layout,
/// then the pool (its set), the set layout, and the buffers the set points to.
struct MeshFill {
    pipeline: Pipeline,
    /// Set 0 (the scene) and set 1 (below), with the scene's push range.
    layout: PipelineLayout,
    _pool: DescriptorPool,
    /// Set 1: the meshlet buffers, `draws`, and the scene's vertex buffer.
    set: vk::DescriptorSet,
    _set_layout: DescriptorSetLayout,
    /// This update's meshlet draws, sized once for the most an update can have.
    draws: Buffer,
    _meshlets: MeshletBuffers,
    /// Per drawable: its meshlets in the buffers.
    drawables: Vec<DrawableMeshlets>,
    /// This update's runs of draws that share a cull mode, one draw call each.
    runs: Vec<Run>,
    /// `vkCmdDrawMeshTasksEXT`.
    mesh_ext: ash::ext::mesh_shader::Device,
}

/// Consecutive meshlet draws recorded with one cull mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Run {
    first: u32,
    count: u32,
    cull_back: bool,
}

impl MeshFill {
    /// `narrow`: 8 invocations per mesh workgroup (`cube_mesh_narrow.mesh`), else 32.
    fn create(ctx: &MethodContext<'_>, narrow: bool) -> Result<Self, GpuError> {
        let device = ctx.device;
        let library = MeshletLibrary::build(ctx.scene, ctx.drawables)?;
        let meshlets = MeshletBuffers::upload(ctx, &library)?;
        let draws = draws_buffer(device, &library)?;

        // Set 1, binding i: buffers[i] (cube_mesh.glsl's MESHLET_BINDINGS).
        let buffers = [
            &meshlets.meshlets,
            &meshlets.vertices,
            &meshlets.triangles,
            &draws,
            ctx.vertices,
        ];
        let set_layout = meshlet_set_layout(device, buffers.len() as u32)?;
        let pool = meshlet_pool(device, buffers.len() as u32)?;
        let set = pool.allocate(&set_layout, "meshlet set")?;
        for (binding, buffer) in buffers.iter().enumerate() {
            descriptors::write_buffer(device, set, binding as u32, STORAGE, buffer.raw);
        }
        let layout = PipelineLayout::create(
            device,
            &[ctx.scene_set_layout, set_layout.raw],
            std::mem::size_of::<MeshPush>() as u32,
            "mesh layout",
        )?;
        let pipeline = mesh_pipeline(ctx, &layout, narrow)?;
        Ok(Self {
            pipeline,
            layout,
            _pool: pool,
            set,
            _set_layout: set_layout,
            draws,
            _meshlets: meshlets,
            drawables: library.drawables,
            runs: Vec::new(),
            mesh_ext: ash::ext::mesh_shader::Device::new(&device.instance.raw, &device.raw),
        })
    }

    /// Records one run's draw calls (several when it needs more task workgroups than one call
    /// may launch).
    fn draw_run(&self, dev: &Device, cmd: vk::CommandBuffer, run: &Run) {
        let per_call = MAX_TASK_WORKGROUPS * TASK_MESHLETS;
        let mut first = run.first;
        let end = run.first + run.count;
        while first < end {
            let count = (end - first).min(per_call);
            let push = MeshPush {
                first_draw: first,
                draw_count: count,
                ..MeshPush::default()
            };
            // SAFETY: the push range covers the device's graphics stages and this many bytes.
            unsafe {
                dev.raw.cmd_push_constants(
                    cmd,
                    self.layout.raw,
                    dev.graphics_stages(),
                    0,
                    bytemuck::bytes_of(&push),
                )
            };
            // SAFETY: the mesh pipeline and both sets are bound; `draws` holds the run's
            // draws (written in `prepare`); the count is within maxTaskWorkGroupCount.
            unsafe {
                self.mesh_ext
                    .cmd_draw_mesh_tasks(cmd, count.div_ceil(TASK_MESHLETS), 1, 1)
            };
            first += count;
        }
    }
}

impl FillPass for MeshFill {
    fn prepare(&mut self, plan: &CubePlan, ctx: &mut Prepare<'_>) -> Result<(), GpuError> {
        let (draws, runs) = meshlet_draws(&self.drawables, plan, ctx.cull_back);
        self.runs = runs;
        ctx.uploads.write(&self.draws, &draws)
    }

    fn record(&self, rec: &CubeRecorder<'_>, plan: &CubePlan) {
        rec.begin_cube(plan);
        if !self.runs.is_empty() {
            rec.bind(&self.pipeline);
            let (dev, cmd) = (rec.device(), rec.cmd());
            // SAFETY: set 1 of this pipeline's layout; its buffers live as long as `self`.
            // Set 0, bound with the scene's layout, stays bound: both layouts start alike.
            unsafe {
                dev.raw.cmd_bind_descriptor_sets(
                    cmd,
                    vk::PipelineBindPoint::GRAPHICS,
                    self.layout.raw,
                    1,
                    &[self.set],
                    &[],
                )
            };
            for run in &self.runs {
                rec.set_cull_back(run.cull_back);
                self.draw_run(dev, cmd, run);
            }
        }
        rec.end_cube();
    }
}

/// Every binding of set 1 is a storage buffer.
const STORAGE: vk::DescriptorType = vk::DescriptorType::STORAGE_BUFFER;

/// The buffer of an update's meshlet draws, sized for the most any update can have.
fn draws_buffer(device: &Arc<Device>, library: &MeshletLibrary) -> Result<Buffer, GpuError> {
    let draws_size = (library.most_draws().max(1) * std::mem::size_of::<MeshletDraw>()) as u64;
    Buffer::create(
        device,
        &BufferDesc::new_device_local(draws_size, vk::BufferUsageFlags::STORAGE_BUFFER),
        "meshlet draws",
    )
}

/// Set 1's layout: `count` storage buffers, read by the task and mesh shaders.
fn meshlet_set_layout(device: &Arc<Device>, count: u32) -> Result<DescriptorSetLayout, GpuError> {
    let stages = vk::ShaderStageFlags::TASK_EXT | vk::ShaderStageFlags::MESH_EXT;
    let bindings: Vec<_> = (0..count)
        .map(|b| descriptors::binding(b, STORAGE, 1, stages))
        .collect();
    DescriptorSetLayout::create(device, &bindings, "meshlet set layout")
}

/// The pool of set 1 alone: `count` storage buffers.
fn meshlet_pool(device: &Arc<Device>, count: u32) -> Result<DescriptorPool, GpuError> {
    DescriptorPool::create(
        device,
        1,
        &[vk::DescriptorPoolSize {
            ty: STORAGE,
            descriptor_count: count,
        }],
        "meshlet descriptors",
    )
}

/// The task and mesh pipeline, with the narrow or the wide mesh shader.
fn mesh_pipeline(
    ctx: &MethodContext<'_>,
    layout: &PipelineLayout,
    narrow: bool,
) -> Result<Pipeline, GpuError> {
    let mesh = if narrow {
        crate::shaders::CUBE_MESH_NARROW_MESH
    } else {
        crate::shaders::CUBE_MESH_MESH
    };
    // The mesh shader culls back faces with a margin of the rasterizer's snapping, whose
    // step only the device knows.
    let sub_pixel_bits = [SpecConstant {
        id: SPEC_SUB_PIXEL_BITS,
        value: ctx.device.info.limits.sub_pixel_precision_bits,
    }];
    ctx.pipeline_of(
        layout,
        &[
            ShaderStage::new(
                vk::ShaderStageFlags::TASK_EXT,
                crate::shaders::CUBE_MESH_TASK,
            ),
            ShaderStage {
                constants: &sub_pixel_bits,
                ..ShaderStage::new(vk::ShaderStageFlags::MESH_EXT, mesh)
            },
        ],
        "cube pipeline (mesh)",
    )
}

/// The device's subgroup size (core in Vulkan 1.1).
fn subgroup_size(device: &Device) -> u32 {
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let mut properties = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
    // SAFETY: the physical device belongs to this instance; the chain points at live locals.
    unsafe {
        device
            .instance
            .raw
            .get_physical_device_properties2(device.physical, &mut properties)
    };
    subgroup.subgroup_size
}

/// This update's meshlet draws and their runs of equal culling: for each drawable visible in
/// some dirty face, in the plan's draw order, each of its meshlets (compact ones when its
/// back faces are culled, `cull` per drawable, else ordered ones) with the dirty faces the
/// drawable is visible in.
fn meshlet_draws(
    drawables: &[DrawableMeshlets],
    plan: &CubePlan,
    cull: &[bool],
) -> (Vec<MeshletDraw>, Vec<Run>) {
    let mut masks = vec![0u32; drawables.len()];
    for f in plan.faces() {
        for &o in &plan.visible[f as usize] {
            masks[o as usize] |= 1 << f;
        }
    }
    let mut draws = Vec::new();
    let mut runs: Vec<Run> = Vec::new();
    for &o in &plan.order {
        let face_mask = masks[o as usize];
        if face_mask == 0 {
            continue;
        }
        let cull_back = cull[o as usize];
        let (range, culled) = drawables[o as usize].for_culling(cull_back);
        let count = range.len() as u32;
        match runs.last_mut() {
            Some(run) if run.cull_back == cull_back => run.count += count,
            _ => runs.push(Run {
                first: draws.len() as u32,
                count,
                cull_back,
            }),
        }
        draws.extend(range.map(|meshlet| MeshletDraw {
            meshlet,
            object: o,
            face_mask,
            cull_back: u32::from(culled),
        }));
    }
    (draws, runs)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three drawables: 0 open (2 ordered meshlets), 1 and 2 closed (1 ordered, 3 clustered).
    fn drawables() -> Vec<DrawableMeshlets> {
        vec![
            DrawableMeshlets {
                ordered: 0..2,
                clustered: 2..2,
            },
            DrawableMeshlets {
                ordered: 2..3,
                clustered: 3..6,
            },
            DrawableMeshlets {
                ordered: 2..3,
                clustered: 3..6,
            },
        ]
    }

    /// Draw order 2, 0, 1; faces 0 and 4 dirty; drawable 2 is in both, 0 in face 4, 1 in
    /// none. Drawable 2 is culled (its clustered meshlets, cones on), 0 is open: two runs.
    #[test]
    fn draws_follow_the_plan_order_with_each_drawables_faces() {
        let plan = CubePlan {
            dirty: 0b1_0001,
            visible: [vec![2], vec![], vec![], vec![], vec![2, 0], vec![]],
            order: vec![2, 0, 1],
            ..Default::default()
        };
        let (draws, runs) = meshlet_draws(&drawables(), &plan, &[false, true, true]);
        let want = |meshlet, object, face_mask, cull_back| MeshletDraw {
            meshlet,
            object,
            face_mask,
            cull_back,
        };
        assert_eq!(
            draws,
            [
                want(3, 2, 0b1_0001, 1),
                want(4, 2, 0b1_0001, 1),
                want(5, 2, 0b1_0001, 1),
                want(0, 0, 0b1_0000, 0),
                want(1, 0, 0b1_0000, 0),
            ]
        );
        let run = |first, count, cull_back| Run {
            first,
            count,
            cull_back,
        };
        assert_eq!(runs, [run(0, 3, true), run(3, 2, false)]);
    }

    /// A closed drawable whose back faces may not be culled this update (the eye is inside
    /// it) is drawn with its ordered meshlets and no cone culling; nothing dirty, nothing drawn.
    #[test]
    fn unculled_closed_drawables_use_their_ordered_meshlets() {
        let mut plan = CubePlan {
            dirty: 0b100,
            visible: [vec![], vec![], vec![1], vec![], vec![], vec![]],
            order: vec![0, 1, 2],
            ..Default::default()
        };
        let (draws, runs) = meshlet_draws(&drawables(), &plan, &[false, false, true]);
        assert_eq!(
            draws,
            [MeshletDraw {
                meshlet: 2,
                object: 1,
                face_mask: 0b100,
                cull_back: 0
            }]
        );
        assert_eq!(runs.len(), 1);
        assert!(!runs[0].cull_back);
        plan.dirty = 0;
        plan.visible = Default::default();
        let (draws, runs) = meshlet_draws(&drawables(), &plan, &[true; 3]);
        assert!(draws.is_empty() && runs.is_empty());
    }
}
