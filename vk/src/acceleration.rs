//! Acceleration structures (`VK_KHR_acceleration_structure`), built on the device only: one
//! bottom-level structure per triangle mesh, built once, and a top-level structure over
//! instances of them, rebuilt each frame from host-written instance records.
//!
//! Each structure owns its handle and its buffer; `Drop` destroys them. Scratch memory is a
//! buffer of the builder's own, freed with it.

use std::sync::Arc;

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::commands::Submitter;
use super::device::Device;
use super::memory::{Buffer, BufferDesc};
use super::uploads::FrameUploads;
use super::{GpuError, VkContext};

/// The extension's device functions (loaded once per owner: a table of pointers).
type Ext = ash::khr::acceleration_structure::Device;

fn ext(device: &Device) -> Ext {
    Ext::new(&device.instance.raw, &device.raw)
}

/// The device address of `buffer` (its usage must include SHADER_DEVICE_ADDRESS).
pub fn buffer_address(device: &Device, buffer: &Buffer) -> vk::DeviceAddress {
    let info = vk::BufferDeviceAddressInfo::default().buffer(buffer.raw);
    // SAFETY: the buffer is live and was created with SHADER_DEVICE_ADDRESS usage.
    unsafe { device.raw.get_buffer_device_address(&info) }
}

/// Usage flags a buffer read by address as a build input needs.
pub const BUILD_INPUT_USAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS.as_raw()
        | vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR.as_raw(),
);

/// One acceleration structure and the buffer that holds it.
pub struct AccelerationStructure {
    pub raw: vk::AccelerationStructureKHR,
    /// What instances (for a bottom level) or shaders (for a top level) refer to it by.
    pub address: vk::DeviceAddress,
    ext: Ext,
    /// Destroyed after the structure (declared after it is not enough: see Drop).
    buffer: Option<Buffer>,
}

impl AccelerationStructure {
    fn create(
        device: &Arc<Device>,
        ty: vk::AccelerationStructureTypeKHR,
        size: u64,
        name: &str,
    ) -> Result<Self, GpuError> {
        let buffer = Buffer::create(
            device,
            &BufferDesc {
                size,
                usage: vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR
                    | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
                location: MemoryLocation::GpuOnly,
            },
            &format!("{name} (storage)"),
        )?;
        let ext = ext(device);
        let info = vk::AccelerationStructureCreateInfoKHR::default()
            .buffer(buffer.raw)
            .size(size)
            .ty(ty);
        // SAFETY: the buffer is live, has AS storage usage and holds `size` bytes at offset 0.
        let raw = unsafe { ext.create_acceleration_structure(&info, None) }
            .vk("vkCreateAccelerationStructureKHR")?;
        device.set_name(raw, name);
        let address_info =
            vk::AccelerationStructureDeviceAddressInfoKHR::default().acceleration_structure(raw);
        // SAFETY: raw was just created on this device.
        let address = unsafe { ext.get_acceleration_structure_device_address(&address_info) };
        Ok(Self {
            raw,
            address,
            ext,
            buffer: Some(buffer),
        })
    }

    /// The buffer holding the structure: what a frame graph tracks its builds and reads by
    /// (their barriers are memory barriers).
    pub fn storage(&self) -> vk::Buffer {
        self.buffer.as_ref().map_or(vk::Buffer::null(), |b| b.raw)
    }
}

impl Drop for AccelerationStructure {
    fn drop(&mut self) {
        // SAFETY: owners keep the structure alive until the GPU work that reads it has
        // completed (the renderer retires a replaced pass until its frames' fences); the
        // buffer is freed after the handle.
        unsafe { self.ext.destroy_acceleration_structure(self.raw, None) };
        self.buffer.take();
    }
}

/// One triangle mesh in the shared vertex and index buffers (positions are the first three
/// floats of each vertex).
#[derive(Debug, Clone, Copy)]
pub struct TriangleMesh {
    pub vertex_address: vk::DeviceAddress,
    pub vertex_stride: u64,
    /// Vertices of this mesh, counted from `first_vertex`.
    pub vertex_count: u32,
    pub first_vertex: u32,
    pub index_address: vk::DeviceAddress,
    /// Index of the mesh's first index in the index buffer.
    pub first_index: u32,
    pub index_count: u32,
}

impl TriangleMesh {
    fn geometry(&self) -> vk::AccelerationStructureGeometryKHR<'static> {
        let triangles = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
            .vertex_format(vk::Format::R32G32B32_SFLOAT)
            .vertex_data(vk::DeviceOrHostAddressConstKHR {
                device_address: self.vertex_address
                    + u64::from(self.first_vertex) * self.vertex_stride,
            })
            .vertex_stride(self.vertex_stride)
            .max_vertex(self.vertex_count.saturating_sub(1))
            .index_type(vk::IndexType::UINT32)
            .index_data(vk::DeviceOrHostAddressConstKHR {
                device_address: self.index_address + u64::from(self.first_index) * 4,
            });
        vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
            .geometry(vk::AccelerationStructureGeometryDataKHR { triangles })
            // Opaque: every hit is final, no any-hit logic (the reference has none either).
            .flags(vk::GeometryFlagsKHR::OPAQUE)
    }

    /// The mesh is addressed by moving the vertex and index addresses to its first vertex and
    /// index, not through the range's `firstVertex` and `primitiveOffset`: with those, lavapipe
    /// 25.0.7 built every mesh but the first wrongly (most reflected rays met nothing).
    fn range(&self) -> vk::AccelerationStructureBuildRangeInfoKHR {
        vk::AccelerationStructureBuildRangeInfoKHR {
            primitive_count: self.index_count / 3,
            primitive_offset: 0,
            first_vertex: 0,
            transform_offset: 0,
        }
    }
}

/// Sizes for building one structure from `geometry` with `counts` primitives.
fn build_sizes(
    ext: &Ext,
    info: &vk::AccelerationStructureBuildGeometryInfoKHR<'_>,
    counts: &[u32],
) -> vk::AccelerationStructureBuildSizesInfoKHR<'static> {
    let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
    // SAFETY: info describes valid geometry; counts has one entry per geometry.
    unsafe {
        ext.get_acceleration_structure_build_sizes(
            vk::AccelerationStructureBuildTypeKHR::DEVICE,
            info,
            counts,
            &mut sizes,
        )
    };
    sizes
}

/// The scratch alignment the device asks for (`minAccelerationStructureScratchOffsetAlignment`).
fn scratch_alignment(device: &Device) -> u64 {
    let mut props = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut props);
    // SAFETY: plain query; the extension is enabled on this device.
    unsafe {
        device
            .instance
            .raw
            .get_physical_device_properties2(device.physical, &mut props2)
    };
    u64::from(
        props
            .min_acceleration_structure_scratch_offset_alignment
            .max(1),
    )
}

/// A scratch buffer of at least `size` bytes and its address, aligned as the device asks.
fn scratch(device: &Arc<Device>, size: u64, name: &str) -> Result<(Buffer, u64), GpuError> {
    let align = scratch_alignment(device);
    let buffer = Buffer::create(
        device,
        &BufferDesc {
            size: size + align,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            location: MemoryLocation::GpuOnly,
        },
        name,
    )?;
    let address = buffer_address(device, &buffer).next_multiple_of(align);
    Ok((buffer, address))
}

/// Makes this build's writes visible to later builds and to fragment shaders' ray queries,
/// and orders it after earlier reads and builds of the same memory (the previous frame's).
fn build_barrier(device: &Device, cmd: vk::CommandBuffer, before: bool) {
    let (src_stage, src_access, dst_stage, dst_access) = if before {
        (
            vk::PipelineStageFlags2::FRAGMENT_SHADER
                | vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
            vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR,
            vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
            vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR
                | vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR,
        )
    } else {
        (
            vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
            vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR,
            vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR
                | vk::PipelineStageFlags2::FRAGMENT_SHADER,
            vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR,
        )
    };
    let barrier = [vk::MemoryBarrier2::default()
        .src_stage_mask(src_stage)
        .src_access_mask(src_access)
        .dst_stage_mask(dst_stage)
        .dst_access_mask(dst_access)];
    // SAFETY: cmd is recording.
    unsafe {
        device.raw.cmd_pipeline_barrier2(
            cmd,
            &vk::DependencyInfo::default().memory_barriers(&barrier),
        )
    };
}

/// Builds one bottom-level structure per mesh on the device, in one submission, and waits.
/// Built for fast tracing: the meshes never change.
pub fn build_bottom_levels(
    device: &Arc<Device>,
    submitter: &Submitter,
    meshes: &[TriangleMesh],
) -> Result<Vec<AccelerationStructure>, GpuError> {
    let ext = ext(device);
    let flags = vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE;
    let mut structures = Vec::with_capacity(meshes.len());
    let mut scratch_sizes = Vec::with_capacity(meshes.len());
    for (i, m) in meshes.iter().enumerate() {
        let geometry = [m.geometry()];
        let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
            .flags(flags)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(&geometry);
        let sizes = build_sizes(&ext, &info, &[m.index_count / 3]);
        structures.push(AccelerationStructure::create(
            device,
            vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
            sizes.acceleration_structure_size,
            &format!("mesh {i} BLAS"),
        )?);
        scratch_sizes.push(sizes.build_scratch_size);
    }
    // One scratch region per build, so that the builds need no barriers between them.
    let align = scratch_alignment(device);
    let offsets: Vec<u64> = scratch_sizes
        .iter()
        .scan(0u64, |at, &s| {
            let here = *at;
            *at += s.next_multiple_of(align);
            Some(here)
        })
        .collect();
    let total: u64 = scratch_sizes
        .iter()
        .map(|s| s.next_multiple_of(align))
        .sum();
    let (scratch_buffer, scratch_address) = scratch(device, total, "BLAS scratch")?;
    let geometries: Vec<[vk::AccelerationStructureGeometryKHR<'_>; 1]> =
        meshes.iter().map(|m| [m.geometry()]).collect();
    let infos: Vec<vk::AccelerationStructureBuildGeometryInfoKHR<'_>> = geometries
        .iter()
        .zip(&structures)
        .zip(&offsets)
        .map(|((g, s), &offset)| {
            vk::AccelerationStructureBuildGeometryInfoKHR::default()
                .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
                .flags(flags)
                .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
                .dst_acceleration_structure(s.raw)
                .geometries(g)
                .scratch_data(vk::DeviceOrHostAddressKHR {
                    device_address: scratch_address + offset,
                })
        })
        .collect();
    let ranges: Vec<[vk::AccelerationStructureBuildRangeInfoKHR; 1]> =
        meshes.iter().map(|m| [m.range()]).collect();
    let range_refs: Vec<&[vk::AccelerationStructureBuildRangeInfoKHR]> =
        ranges.iter().map(|r| r.as_slice()).collect();
    let cmd = submitter.begin()?;
    if !infos.is_empty() {
        // SAFETY: every structure, scratch region and input buffer is live and sized by
        // build_sizes; the regions do not overlap.
        unsafe { ext.cmd_build_acceleration_structures(cmd, &infos, &range_refs) };
    }
    build_barrier(device, cmd, false);
    submitter.submit_and_wait()?;
    drop(scratch_buffer);
    Ok(structures)
}

/// A top-level structure over up to `capacity` instances, rebuilt by [`TopLevel::record_build`]
/// from the records last written by [`TopLevel::write_instances`].
pub struct TopLevel {
    pub structure: AccelerationStructure,
    instances: Buffer,
    instances_address: vk::DeviceAddress,
    /// Held for the builds (read through `scratch_address`).
    scratch: Buffer,
    scratch_address: vk::DeviceAddress,
    count: u32,
    capacity: u32,
    ext: Ext,
}

impl TopLevel {
    /// Rebuilt each frame (not refit): see `docs/accuracy.md`. PREFER_FAST_BUILD since it is
    /// built as often as it is traced.
    const FLAGS: vk::BuildAccelerationStructureFlagsKHR =
        vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_BUILD;

    pub fn create(device: &Arc<Device>, capacity: u32, name: &str) -> Result<Self, GpuError> {
        let ext = ext(device);
        let record = std::mem::size_of::<vk::AccelerationStructureInstanceKHR>() as u64;
        let instances = Buffer::create(
            device,
            &BufferDesc::new_device_local(u64::from(capacity.max(1)) * record, BUILD_INPUT_USAGE),
            &format!("{name} instances"),
        )?;
        let instances_address = buffer_address(device, &instances);
        let geometry = [Self::geometry(instances_address)];
        let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::TOP_LEVEL)
            .flags(Self::FLAGS)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(&geometry);
        let sizes = build_sizes(&ext, &info, &[capacity]);
        let structure = AccelerationStructure::create(
            device,
            vk::AccelerationStructureTypeKHR::TOP_LEVEL,
            sizes.acceleration_structure_size,
            name,
        )?;
        let (scratch, scratch_address) =
            scratch(device, sizes.build_scratch_size, &format!("{name} scratch"))?;
        Ok(Self {
            structure,
            instances,
            instances_address,
            scratch,
            scratch_address,
            count: 0,
            capacity,
            ext,
        })
    }

    fn geometry(address: vk::DeviceAddress) -> vk::AccelerationStructureGeometryKHR<'static> {
        let instances = vk::AccelerationStructureGeometryInstancesDataKHR::default()
            .array_of_pointers(false)
            .data(vk::DeviceOrHostAddressConstKHR {
                device_address: address,
            });
        vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::INSTANCES)
            .geometry(vk::AccelerationStructureGeometryDataKHR { instances })
    }

    /// Queues this frame's instance records for the frame's build (through `uploads`: the
    /// frames in flight may still be building from the last ones).
    pub fn write_instances(
        &mut self,
        uploads: &mut FrameUploads,
        records: &[vk::AccelerationStructureInstanceKHR],
    ) -> Result<(), GpuError> {
        if records.len() > self.capacity as usize {
            return Err(GpuError::Unsupported(format!(
                "{} instances in a top-level structure made for {}",
                records.len(),
                self.capacity
            )));
        }
        // SAFETY: the record is plain data (repr(C) integers and floats, no padding), so its
        // bytes are well defined; the slice covers exactly the records.
        let bytes = unsafe {
            std::slice::from_raw_parts(
                records.as_ptr().cast::<u8>(),
                std::mem::size_of_val(records),
            )
        };
        uploads.write(&self.instances, bytes)?;
        self.count = records.len() as u32;
        Ok(())
    }

    /// The buffers a rebuild writes: the structure's storage and the build's scratch. The
    /// caller orders the build with them (the renderer's frame graph: after the last frame's
    /// build and ray queries, before this frame's ray queries); the instances are an upload,
    /// read by any later command.
    pub fn written_by_build(&self) -> [vk::Buffer; 2] {
        [self.structure.storage(), self.scratch.raw]
    }

    /// Records the rebuild (ordered by the caller: [`Self::written_by_build`]).
    pub fn record_build(&self, cmd: vk::CommandBuffer) {
        let geometry = [Self::geometry(self.instances_address)];
        let info = [vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::TOP_LEVEL)
            .flags(Self::FLAGS)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .dst_acceleration_structure(self.structure.raw)
            .geometries(&geometry)
            .scratch_data(vk::DeviceOrHostAddressKHR {
                device_address: self.scratch_address,
            })];
        let range = [vk::AccelerationStructureBuildRangeInfoKHR {
            primitive_count: self.count,
            ..Default::default()
        }];
        // SAFETY: structure, scratch and instance buffer are live and sized for `capacity`
        // instances; count <= capacity (write_instances).
        unsafe {
            self.ext
                .cmd_build_acceleration_structures(cmd, &info, &[range.as_slice()])
        };
    }
}
