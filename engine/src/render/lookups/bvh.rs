//! The `bvh` lookup: the exact mirror on any device. The mirror's fragment shader traces the
//! reflected pixel-centre ray through a BVH of our own in storage buffers (`shaders/include/
//! bvh.glsl`, built on the CPU by [`crate::bvh`]) and the room's box, and shades the hit as
//! the CPU reference does. It needs no extension, so it runs where `ray-query` cannot
//! (SwiftShader, GPUs without ray-tracing hardware), and it traces the sensor's ray map too,
//! so the ground-truth layers come from the colour's own light path there.
//!
//! Its buffers: both levels' node and triangle records in one (the top level's first, every
//! mesh's tree after them), the walls' frames and the drawables' index ranges, written once;
//! the top level's records and the objects rewritten through the frame's uploads whenever an
//! object moved (a rebuild on the CPU: see [`BvhPass::prepare`]).

use std::sync::Arc;

use ash::vk;
use glam::{Mat4, UVec4};
use gpu_allocator::MemoryLocation;

use super::pretrace::{self, Pretrace};
use super::{
    as_is, FrameObjects, LookupContext, LookupPass, MirrorLookup, MirrorPipelines, MirrorShaders,
    Rung, Start, TraceIn, TraceSet, Work,
};
use crate::bvh::layout::{BvhInstance, BvhWall};
use crate::bvh::{object_drawable, BvhLayout, MeshBvhs, Placed, TopLevel};
use crate::render::graph::{PassRecorder, Resource, Use};
use crate::scene::{Lookup, Scene};
use crate::vk::descriptors::{self, DescriptorPool, DescriptorSetLayout};
use crate::vk::device::{Device, DeviceInfo};
use crate::vk::memory::{Buffer, BufferDesc, Upload};
use crate::vk::uploads::FrameUploads;
use crate::vk::GpuError;

pub struct Bvh;

impl MirrorLookup for Bvh {
    fn summary(&self) -> &'static str {
        "the reflected ray traced through a BVH of our own in the shader: exact, no cube map, \
         no extension (any device)"
    }

    fn uses_cube(&self) -> bool {
        false
    }

    fn traces_ray_map(&self) -> bool {
        true
    }

    /// Second to hardware ray queries on a GPU (not measured against them: no GPU lent here had
    /// ray queries); first on a CPU driver (lavapipe 25, release, 512²: 0.57x to 0.85x
    /// ray-query's frame on the four benchmark scenes, docs/accuracy.md).
    fn ground_truth_rank(&self, device: &DeviceInfo) -> u32 {
        if device.is_cpu() {
            0
        } else {
            1
        }
    }

    /// Every mesh's tree triangles share one storage buffer (the cwbvh layout: 48 bytes a
    /// triangle, and bvh4 keeps more in its nodes), which a shader binds up to the device's
    /// `maxStorageBufferRange`: a lower bound, known before any tree is built.
    fn cannot_hold(&self, scene: &crate::scene::Scene, device: &DeviceInfo) -> Option<String> {
        let (triangles, bytes) = least_tree_bytes(scene);
        let range = device.limits.max_storage_buffer_range;
        // 0: a device read back from a record, whose range is unknown.
        (range > 0 && bytes > range).then(|| {
            format!(
                "the scene's {triangles} mesh triangles need {bytes} bytes of trees, more than \
                 this device binds in one storage buffer ({range}, maxStorageBufferRange)"
            )
        })
    }

    fn start(&self) -> Start {
        Start::Reflection
    }

    fn rungs(&self) -> &'static [Rung] {
        &[Rung {
            label: "bvh",
            lookup: Lookup::Bvh,
            order: 8,
            configure: as_is,
            footprint: false,
        }]
    }

    fn create(&self, ctx: &LookupContext<'_>) -> Result<Box<dyn LookupPass>, GpuError> {
        Ok(Box::new(BvhPass::create(ctx)?))
    }

    /// The shader's walk in `layout`, step for step on the CPU (`bvh::sensor_work`).
    fn sensor_work(
        &self,
        scene: &Scene,
        t_s: f64,
        layout: BvhLayout,
    ) -> Option<Result<Work, String>> {
        Some(crate::bvh::sensor_work(scene, t_s, layout).map_err(|e| e.to_string()))
    }
}

/// The faster layout where it was measured (release builds, 512², `specchio bench` over the
/// four benchmark scenes, 30 November 2026; docs/accuracy.md, "Two, four or eight children a
/// node"): four-wide on SwiftShader, where a walk's cost is its box tests' arithmetic and the
/// four-wide walk took 0.56x to 0.75x the eight-wide walk's sensor view; eight-wide on
/// lavapipe, where a group of invocations steps through a walk together, each step costing
/// about the same whatever it reads, and the four-wide walk's third more steps took 1.2x to
/// 1.65x; eight-wide on a GPU (Ylitie et al. designed it for GPUs; not yet measured there
/// against the other).
pub fn default_layout(device: &DeviceInfo) -> BvhLayout {
    if device.short_name == "swiftshader" {
        BvhLayout::Bvh4
    } else {
        BvhLayout::Cwbvh
    }
}

/// The set's bindings, in `bvh.glsl`'s order: nodes (both levels), mesh triangles,
/// instances, walls, then `traced_surface.glsl`'s vertices, indices and drawable ranges, then
/// `pretrace.glsl`'s records.
const BINDINGS: u32 = 8;

/// The bvh lookup's per-renderer state. Field order is drop order.
struct BvhPass {
    /// The compute walk, where the device walks there ([`TraceIn::Compute`]).
    pretrace: Option<Pretrace>,
    pipelines: MirrorPipelines,
    _pool: DescriptorPool,
    set: vk::DescriptorSet,
    set_layout: DescriptorSetLayout,
    /// The meshes' trees as the record buffer holds them: after the top level's room (the
    /// records are on the device; the roots are what a top level is built from).
    meshes: MeshBvhs,
    /// Each object's mesh, in the scene's order.
    mesh_of: Vec<usize>,
    /// The top level's room in the node buffer: where the meshes' trees start.
    mesh_start: u32,
    /// The sensor ray map's walk in this layout, where the fragment shaders walk.
    ray_map: &'static [u32],
    /// The objects' transforms the top level was last built from (None: not yet built).
    placed_from: Option<Vec<Mat4>>,
    /// Both levels' nodes (bvh4: node and triangle records): the top level's room (rewritten
    /// when it is rebuilt), then the meshes' trees.
    nodes: Buffer,
    /// The objects, as the layout indexes them.
    instances: Buffer,
    /// The pretraced records (one, unread, where the fragment shaders walk).
    records: Buffer,
    _fixed: FixedBuffers,
}

impl BvhPass {
    fn create(ctx: &LookupContext<'_>) -> Result<Self, GpuError> {
        let device = ctx.device;
        let scene = ctx.scene;
        let layout = ctx.bvh_layout;
        let top_room = layout.top_room(scene.objects.len());
        // A scene past the device's range is refused before seconds of building trees it
        // could not bind.
        check_range(ctx, layout, least_tree_bytes(scene).1, "at least ")?;
        let meshes =
            MeshBvhs::build_at(layout, &scene.meshes, top_room as u32).map_err(unsupported)?;
        let (nodes, fixed) = fixed_buffers(ctx, &meshes, top_room)?;
        let instances = instance_buffer(device, top_room)?;
        let stage = vk::ShaderStageFlags::FRAGMENT | vk::ShaderStageFlags::COMPUTE;
        let pretraced = ctx.trace_in == TraceIn::Compute;
        let records = pretrace::records(ctx, pretraced)?;
        let bindings: Vec<_> = (0..BINDINGS)
            .map(|b| descriptors::binding(b, vk::DescriptorType::STORAGE_BUFFER, 1, stage))
            .collect();
        let set_layout = DescriptorSetLayout::create(device, &bindings, "bvh set layout")?;
        let size = vk::DescriptorPoolSize {
            ty: vk::DescriptorType::STORAGE_BUFFER,
            descriptor_count: BINDINGS,
        };
        let pool = DescriptorPool::create(device, 1, &[size], "bvh descriptors")?;
        let set = pool.allocate(&set_layout, "bvh set")?;
        let res = ctx.resources;
        let buffers = [
            &nodes,
            // bvh4: the node array again, read as triangles (bvh.glsl).
            fixed.triangles.as_ref().unwrap_or(&nodes),
            &instances,
            &fixed.walls,
            &res.vertices,
            &res.indices,
            &fixed.ranges,
            &records,
        ];
        for (binding, buffer) in (0..).zip(buffers) {
            let storage = vk::DescriptorType::STORAGE_BUFFER;
            descriptors::write_buffer(device, set, binding, storage, buffer.raw);
        }
        let code = LayoutShaders::of(layout);
        let shaders = if pretraced {
            MirrorShaders {
                colour: crate::shaders::MIRROR_BVH_PRETRACED_FRAG,
                directions: crate::shaders::MIRROR_BVH_PRETRACED_DIRECTION_FRAG,
            }
        } else {
            code.mirror
        };
        let pipelines = MirrorPipelines::create(ctx, set_layout.raw, shaders, "bvh mirror")?;
        let walk = code.trace_view;
        let pretrace = (pretraced)
            .then(|| Pretrace::create(ctx, set_layout.raw, walk))
            .transpose()?;
        Ok(Self {
            pretrace,
            records,
            pipelines,
            _pool: pool,
            set,
            set_layout,
            meshes,
            mesh_of: scene.objects.iter().map(|o| o.mesh).collect(),
            mesh_start: top_room as u32,
            ray_map: code.ray_map,
            placed_from: None,
            nodes,
            instances,
            _fixed: fixed,
        })
    }
}

/// What a lookup's walk reads and never rewrites, beside the node buffer.
struct FixedBuffers {
    /// The meshes' triangles, where the layout keeps them apart from its nodes (cwbvh).
    triangles: Option<Buffer>,
    walls: Buffer,
    ranges: Buffer,
}

/// The node buffer, its first `top_room` nodes left for the top level and the meshes' trees
/// after them, and what does not change: the meshes' triangles where the layout keeps them
/// apart, the walls' frames and each drawable's index range (walls first). Device-local.
fn fixed_buffers(
    ctx: &LookupContext<'_>,
    meshes: &MeshBvhs,
    top_room: usize,
) -> Result<(Buffer, FixedBuffers), GpuError> {
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let ranges: Vec<UVec4> = (ctx.resources.drawables.iter())
        .map(|d| UVec4::new(d.first_index, d.vertex_offset as u32, 0, 0))
        .collect();
    let mut nodes = vec![0u8; top_room * meshes.node_size()];
    nodes.extend_from_slice(meshes.node_bytes());
    // A shader reads one storage buffer up to the device's range (128 MiB at the least the
    // spec allows): the bvh4 layout keeps its triangles in its node array, about 67 bytes a
    // triangle, so a mesh of 2 million triangles may not fit where the range is the least.
    let sizes = [Some(nodes.len()), meshes.triangle_bytes().map(<[u8]>::len)];
    for size in sizes.into_iter().flatten() {
        check_range(ctx, meshes.layout(), size as u64, "")?;
    }
    let mut upload = Upload::begin(ctx.device, ctx.submitter)?;
    let usage = storage | vk::BufferUsageFlags::TRANSFER_DST;
    let node_buffer = upload.buffer(&nodes, usage, "bvh nodes")?;
    // A room without objects has no triangles; a buffer cannot be empty.
    let one_triangle = [0u8; std::mem::size_of::<crate::bvh::layout::BvhTriangle>()];
    let triangles = (meshes.triangle_bytes())
        .map(|t| if t.is_empty() { &one_triangle[..] } else { t })
        .map(|t| upload.buffer(t, storage, "bvh mesh triangles"))
        .transpose()?;
    let fixed = FixedBuffers {
        triangles,
        walls: upload.buffer(&BvhWall::of_room(&ctx.scene.room), storage, "bvh walls")?,
        ranges: upload.buffer(&ranges, storage, "bvh drawable ranges")?,
    };
    upload.finish()?;
    Ok((node_buffer, fixed))
}

/// The scene's mesh triangles, and the least bytes of the one storage buffer their trees take
/// in either layout: cwbvh keeps one 48-byte `BvhTriangle` a triangle in a buffer of its own,
/// bvh4 one such record a triangle in its node array beside its nodes. Known before any tree
/// is built.
fn least_tree_bytes(scene: &Scene) -> (u64, u64) {
    let triangles: u64 = scene.meshes.iter().map(|m| m.triangle_count() as u64).sum();
    let record = std::mem::size_of::<crate::bvh::layout::BvhTriangle>() as u64;
    (triangles, triangles * record)
}

/// Refuses a storage buffer of `size` bytes (`qualifier`: "at least " where it is a bound)
/// past the device's range, said with the way out: a user who never chose bvh (the sensor
/// outputs' and datasets' default on a CPU driver) met only the limit.
fn check_range(
    ctx: &LookupContext<'_>,
    layout: BvhLayout,
    size: u64,
    qualifier: &str,
) -> Result<(), GpuError> {
    let range = ctx.device.info.limits.max_storage_buffer_range;
    if size <= range {
        return Ok(());
    }
    Err(GpuError::Unsupported(format!(
        "lookup bvh: the scene's trees ({} layout) need a storage buffer of {qualifier}{size} \
         bytes; this device binds at most {range} (maxStorageBufferRange): trace with the \
         ray-query lookup where the device has ray queries (`--lookup ray-query`; \
         `lookup=\"ray-query\"` in Python), or give the meshes fewer triangles",
        layout.name()
    )))
}

/// The objects, rewritten with each top level: one per record of the top level's room.
fn instance_buffer(device: &Arc<Device>, top_room: usize) -> Result<Buffer, GpuError> {
    let desc = BufferDesc {
        size: (top_room * std::mem::size_of::<BvhInstance>()) as u64,
        usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
        location: MemoryLocation::GpuOnly,
    };
    Buffer::create(device, &desc, "bvh instances")
}

/// A layout's shader modules: the mirror's colour and direction passes, the sensor ray map's
/// pass and the compute walk.
struct LayoutShaders {
    mirror: MirrorShaders,
    ray_map: &'static [u32],
    trace_view: &'static [u32],
}

impl LayoutShaders {
    fn of(layout: BvhLayout) -> Self {
        use crate::shaders::*;
        match layout {
            BvhLayout::Cwbvh => Self {
                mirror: MirrorShaders {
                    colour: MIRROR_BVH_FRAG,
                    directions: MIRROR_BVH_DIRECTION_FRAG,
                },
                ray_map: MIRROR_RAY_BVH_FRAG,
                trace_view: TRACE_VIEW_BVH_COMP,
            },
            BvhLayout::Bvh4 => Self {
                mirror: MirrorShaders {
                    colour: MIRROR_BVH4_FRAG,
                    directions: MIRROR_BVH4_DIRECTION_FRAG,
                },
                ray_map: MIRROR_RAY_BVH4_FRAG,
                trace_view: TRACE_VIEW_BVH4_COMP,
            },
        }
    }
}

fn unsupported(e: crate::bvh::BvhError) -> GpuError {
    GpuError::Unsupported(format!("lookup bvh: {e}"))
}

impl LookupPass for BvhPass {
    fn pipelines(&self) -> &MirrorPipelines {
        &self.pipelines
    }

    fn set(&self) -> vk::DescriptorSet {
        self.set
    }

    fn trace_set(&self) -> Option<TraceSet> {
        Some(TraceSet {
            layout: self.set_layout.raw,
            set: self.set,
            ray_map: if self.pretrace.is_some() {
                crate::shaders::MIRROR_RAY_BVH_PRETRACED_FRAG
            } else {
                self.ray_map
            },
        })
    }

    fn resources(&self, _slot: usize) -> Vec<(Resource, Use)> {
        let records = Resource::Buffer(self.records.raw);
        (self.pretrace.iter())
            .map(|_| (records, Use::FragmentStorageRead))
            .collect()
    }

    fn pretraces(&self) -> bool {
        self.pretrace.is_some()
    }

    fn bvh_layout(&self) -> Option<BvhLayout> {
        Some(self.meshes.layout())
    }

    fn pretrace(&self, pass: &mut PassRecorder<'_>, scene_set: vk::DescriptorSet, view: u32) {
        if let Some(p) = &self.pretrace {
            p.record(pass, &self.records, [scene_set, self.set], view);
        }
    }

    /// The top level, rebuilt on the CPU from this frame's object transforms when any of them
    /// differs from the last build's (a still scene builds it once) or the refresh policy
    /// renews everything every frame, and queued for upload. A rebuild, not a refit: the tree
    /// stays as good wherever the objects go.
    fn prepare(
        &mut self,
        uploads: &mut FrameUploads,
        frame: &FrameObjects<'_>,
    ) -> Result<(), GpuError> {
        let transforms: Vec<Mat4> = (frame.objects[6..].iter())
            .map(|o| o.model_to_world)
            .collect();
        if !frame.every_frame && self.placed_from.as_ref() == Some(&transforms) {
            return Ok(());
        }
        let placed: Vec<Placed> = (transforms.iter().zip(&self.mesh_of).enumerate())
            .map(|(i, (m, &mesh))| Placed {
                mesh,
                model_to_world: *m,
                drawable: object_drawable(i),
            })
            .collect();
        let top = TopLevel::build(&self.meshes, &placed).map_err(unsupported)?;
        let nodes = top.node_bytes();
        assert!(
            nodes.len() <= self.mesh_start as usize * self.meshes.node_size(),
            "a top level of {} objects has {} bytes of nodes",
            placed.len(),
            nodes.len()
        );
        // Into the node buffer's first nodes, its room for them.
        uploads.write(&self.nodes, nodes)?;
        uploads.write(&self.instances, top.instances())?;
        self.placed_from = Some(transforms);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use std::mem::offset_of;

    use crate::bvh::bvh4::{Bvh4Node, BVH4_STACK_SIZE};
    use crate::bvh::cwbvh::{WideNode, BVH_STACK_SIZE};
    use crate::bvh::layout::BvhTriangle;

    use super::*;

    /// The Rust mirrors of `bvh.glsl`'s structs have the SPIR-V's offsets, every member of
    /// theirs is mirrored, and the constants the CPU-only `bvh` module keeps are
    /// `shared.glsl`'s.
    #[test]
    fn the_bvh_structs_and_constants_match_the_shaders() {
        macro_rules! member {
            ($s:ident, $m:ident) => {
                (stringify!($s), stringify!($m), offset_of!($s, $m))
            };
        }
        let rust = [
            member!(WideNode, grid),
            member!(WideNode, links),
            member!(WideNode, x_planes),
            member!(WideNode, y_planes),
            member!(WideNode, z_planes),
            member!(Bvh4Node, grid),
            member!(Bvh4Node, links),
            member!(Bvh4Node, planes),
            member!(BvhTriangle, v0),
            member!(BvhTriangle, v1),
            member!(BvhTriangle, v2),
            member!(BvhInstance, world_to_model),
            member!(BvhInstance, tree),
            member!(BvhWall, offset),
            member!(BvhWall, right),
            member!(BvhWall, up),
        ];
        for &(s, m, offset) in &rust {
            let spirv = (crate::shaders::SPIRV_MEMBER_OFFSETS.iter())
                .find(|(s2, m2, _)| *s2 == s && *m2 == m)
                .unwrap_or_else(|| panic!("{s}.{m} is not in any shader's SPIR-V"));
            assert_eq!(spirv.2 as usize, offset, "{s}.{m}");
        }
        for (s, m, _) in crate::shaders::SPIRV_MEMBER_OFFSETS {
            if rust.iter().any(|(s2, _, _)| s2 == s) {
                let mirrored = rust.iter().any(|(s2, m2, _)| s2 == s && m2 == m);
                assert!(mirrored, "{s}.{m} not mirrored");
            }
        }
        assert_eq!(BVH_STACK_SIZE, crate::shaders::shared::BVH_STACK_SIZE);
        assert_eq!(BVH4_STACK_SIZE, crate::shaders::shared::BVH4_STACK_SIZE);
        assert_eq!(
            crate::reference::intersect::MODEL_RAY_MOVES,
            crate::shaders::shared::MODEL_RAY_MOVES
        );
        assert_eq!(
            crate::reference::intersect::MODEL_RAY_GAP_EXPONENT,
            crate::shaders::shared::MODEL_RAY_GAP_EXPONENT
        );
        assert_eq!(
            crate::reference::room::ON_WALL_SLACK_EXPONENT,
            crate::shaders::shared::ON_WALL_SLACK_EXPONENT
        );
    }
}
