//! Shader modules, pipeline layouts, graphics pipelines (dynamic rendering, no render pass
//! objects) and compute pipelines.

use std::sync::Arc;

use ash::vk;

use super::device::Device;
use super::{GpuError, VkContext};

/// A pipeline layout: descriptor set layouts plus one push-constant range for all stages.
pub struct PipelineLayout {
    pub raw: vk::PipelineLayout,
    device: Arc<Device>,
}

impl PipelineLayout {
    /// A layout for graphics pipelines (push constants visible to every graphics stage the
    /// device has, see `Device::graphics_stages`).
    pub fn create(
        device: &Arc<Device>,
        set_layouts: &[vk::DescriptorSetLayout],
        push_constant_bytes: u32,
        name: &str,
    ) -> Result<Self, GpuError> {
        let stages = device.graphics_stages();
        Self::create_for(device, set_layouts, push_constant_bytes, stages, name)
    }

    /// A layout for a compute pipeline.
    pub fn create_compute(
        device: &Arc<Device>,
        set_layouts: &[vk::DescriptorSetLayout],
        push_constant_bytes: u32,
        name: &str,
    ) -> Result<Self, GpuError> {
        let stages = vk::ShaderStageFlags::COMPUTE;
        Self::create_for(device, set_layouts, push_constant_bytes, stages, name)
    }

    fn create_for(
        device: &Arc<Device>,
        set_layouts: &[vk::DescriptorSetLayout],
        push_constant_bytes: u32,
        stages: vk::ShaderStageFlags,
        name: &str,
    ) -> Result<Self, GpuError> {
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(stages)
            .offset(0)
            .size(push_constant_bytes)];
        let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(set_layouts);
        if push_constant_bytes > 0 {
            info = info.push_constant_ranges(&ranges);
        }
        // SAFETY: valid create info; the set layouts are live.
        let raw = unsafe { device.raw.create_pipeline_layout(&info, None) }
            .vk("vkCreatePipelineLayout")?;
        device.set_name(raw, name);
        Ok(Self {
            raw,
            device: Arc::clone(device),
        })
    }
}

impl Drop for PipelineLayout {
    fn drop(&mut self) {
        // SAFETY: no pending command buffer uses it.
        unsafe { self.device.raw.destroy_pipeline_layout(self.raw, None) };
    }
}

/// A compiled shader stage: SPIR-V words embedded at build time, and the values of its
/// specialization constants (what only the device knows, such as its sub-pixel precision).
#[derive(Clone, Copy)]
pub struct ShaderStage<'a> {
    pub stage: vk::ShaderStageFlags,
    pub spirv: &'a [u32],
    pub constants: &'a [SpecConstant],
}

impl<'a> ShaderStage<'a> {
    /// A stage whose specialization constants keep their defaults.
    pub const fn new(stage: vk::ShaderStageFlags, spirv: &'a [u32]) -> Self {
        Self {
            stage,
            spirv,
            constants: &[],
        }
    }
}

/// One specialization constant: its `constant_id` in the shader and a 32-bit value (a
/// `uint`, `int` or `bool` constant).
#[derive(Clone, Copy, Debug)]
pub struct SpecConstant {
    pub id: u32,
    pub value: u32,
}

/// Fixed-function state of a graphics pipeline; viewport and scissor are dynamic.
pub struct GraphicsPipelineDesc<'a> {
    pub stages: &'a [ShaderStage<'a>],
    /// Vertex buffer layout; empty for shaders that generate their vertices.
    pub vertex_bindings: &'a [vk::VertexInputBindingDescription],
    pub vertex_attributes: &'a [vk::VertexInputAttributeDescription],
    /// Every colour attachment's format, each written whole, never blended: one, or with the
    /// cube fill's id cube two, or the sensor's ray map's one per quantity.
    pub color_formats: &'a [vk::Format],
    pub depth_format: vk::Format,
    /// Ignored when `dynamic_culling` is set.
    pub cull_mode: vk::CullModeFlags,
    /// Cull mode and front face are set while recording (`vkCmdSetCullMode`,
    /// `vkCmdSetFrontFace`, core in Vulkan 1.3), per draw and per pass.
    pub dynamic_culling: bool,
    /// Reverse-Z everywhere (near = 1, far = 0), so "closer" is GREATER.
    pub depth_compare: vk::CompareOp,
    pub depth_write: bool,
    /// False: the colour attachment is left untouched (a depth-only pass).
    pub color_writes: bool,
    /// Multiview view mask (0: not multiview).
    pub view_mask: u32,
    /// Primitives are discarded before rasterization (the benchmark's geometry floor).
    pub rasterizer_discard: bool,
}

/// A graphics pipeline.
pub struct Pipeline {
    pub raw: vk::Pipeline,
    device: Arc<Device>,
}

impl Pipeline {
    /// A compute pipeline from one shader's SPIR-V.
    pub fn create_compute(
        device: &Arc<Device>,
        layout: &PipelineLayout,
        spirv: &[u32],
        name: &str,
    ) -> Result<Self, GpuError> {
        let modules = Modules::create(device, [spirv])?;
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(modules.raw[0])
            .name(c"main");
        let info = vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(layout.raw);
        // SAFETY: every pointer in info points at locals that outlive the call.
        let result = unsafe {
            (device.raw).create_compute_pipelines(vk::PipelineCache::null(), &[info], None)
        };
        Self::made(device, result, "vkCreateComputePipelines", name)
    }

    /// A graphics pipeline: the stages with their constants, the fixed-function state `desc`
    /// describes, dynamic rendering into its formats.
    pub fn create_graphics(
        device: &Arc<Device>,
        layout: &PipelineLayout,
        desc: &GraphicsPipelineDesc<'_>,
        name: &str,
    ) -> Result<Self, GpuError> {
        let modules = Modules::create(device, desc.stages.iter().map(|s| s.spirv))?;
        let constants = Constants::of(desc.stages);
        let specializations = constants.infos();
        let stages: Vec<_> = (desc.stages.iter().zip(&modules.raw).zip(&specializations))
            .map(|((s, &module), spec)| {
                let info = vk::PipelineShaderStageCreateInfo::default()
                    .stage(s.stage)
                    .module(module)
                    .name(c"main");
                if s.constants.is_empty() {
                    info
                } else {
                    info.specialization_info(spec)
                }
            })
            .collect();
        let fixed = FixedFunction::of(desc);
        let (vertex_input, input_assembly) = fixed.vertex_input();
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let raster = fixed.rasterization();
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = fixed.depth();
        let blend = fixed.blend();
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&fixed.dynamic);
        let mut rendering = fixed.rendering();
        let mut info = vk::GraphicsPipelineCreateInfo::default().stages(&stages);
        // A mesh pipeline makes its own primitives: it must have no vertex input or input
        // assembly state.
        let mesh = (desc.stages.iter()).any(|s| s.stage.contains(vk::ShaderStageFlags::MESH_EXT));
        if !mesh {
            info = info
                .vertex_input_state(&vertex_input)
                .input_assembly_state(&input_assembly);
        }
        let info = info
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout.raw)
            .push_next(&mut rendering);
        // SAFETY: every pointer in info points at locals that outlive the call.
        let result = unsafe {
            (device.raw).create_graphics_pipelines(vk::PipelineCache::null(), &[info], None)
        };
        Self::made(device, result, "vkCreateGraphicsPipelines", name)
    }

    /// The pipeline a `vkCreate*Pipelines` call made, named, or its error.
    fn made(
        device: &Arc<Device>,
        result: Result<Vec<vk::Pipeline>, (Vec<vk::Pipeline>, vk::Result)>,
        call: &'static str,
        name: &str,
    ) -> Result<Self, GpuError> {
        let raw = result.map_err(|(_, r)| r).vk(call)?[0];
        device.set_name(raw, name);
        Ok(Self {
            raw,
            device: Arc::clone(device),
        })
    }
}

/// Shader modules, needed only while a pipeline is made: destroyed when dropped, on success
/// and on every error path alike.
struct Modules<'a> {
    device: &'a Device,
    raw: Vec<vk::ShaderModule>,
}

impl<'a> Modules<'a> {
    fn create<'s>(
        device: &'a Device,
        spirv: impl IntoIterator<Item = &'s [u32]>,
    ) -> Result<Self, GpuError> {
        let mut modules = Self {
            device,
            raw: Vec::new(),
        };
        for words in spirv {
            let info = vk::ShaderModuleCreateInfo::default().code(words);
            // SAFETY: the words are SPIR-V produced by glslang at build time.
            let module = unsafe { device.raw.create_shader_module(&info, None) }
                .vk("vkCreateShaderModule")?;
            modules.raw.push(module);
        }
        Ok(modules)
    }
}

impl Drop for Modules<'_> {
    fn drop(&mut self) {
        for &m in &self.raw {
            // SAFETY: modules are not referenced once pipeline creation has returned.
            unsafe { self.device.raw.destroy_shader_module(m, None) };
        }
    }
}

/// Each stage's specialization constants: map entries into its values' bytes, both alive
/// until the pipeline is made.
struct Constants {
    entries: Vec<Vec<vk::SpecializationMapEntry>>,
    values: Vec<Vec<u8>>,
}

impl Constants {
    fn of(stages: &[ShaderStage<'_>]) -> Self {
        let entries = (stages.iter())
            .map(|s| {
                (s.constants.iter().enumerate())
                    .map(|(i, c)| vk::SpecializationMapEntry {
                        constant_id: c.id,
                        offset: (4 * i) as u32,
                        size: 4,
                    })
                    .collect()
            })
            .collect();
        let values = (stages.iter())
            .map(|s| {
                s.constants
                    .iter()
                    .flat_map(|c| c.value.to_ne_bytes())
                    .collect()
            })
            .collect();
        Self { entries, values }
    }

    /// One `VkSpecializationInfo` per stage (empty for a stage without constants).
    fn infos(&self) -> Vec<vk::SpecializationInfo<'_>> {
        (self.entries.iter().zip(&self.values))
            .map(|(e, v)| vk::SpecializationInfo::default().map_entries(e).data(v))
            .collect()
    }
}

/// The fixed-function state of `desc`, with the arrays the create infos point into.
struct FixedFunction<'a> {
    desc: &'a GraphicsPipelineDesc<'a>,
    attachments: Vec<vk::PipelineColorBlendAttachmentState>,
    dynamic: Vec<vk::DynamicState>,
}

impl<'a> FixedFunction<'a> {
    fn of(desc: &'a GraphicsPipelineDesc<'a>) -> Self {
        let write_mask = if desc.color_writes {
            vk::ColorComponentFlags::RGBA
        } else {
            vk::ColorComponentFlags::empty()
        };
        let attachment =
            vk::PipelineColorBlendAttachmentState::default().color_write_mask(write_mask);
        let mut dynamic = vec![vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        if desc.dynamic_culling {
            dynamic.extend([vk::DynamicState::CULL_MODE, vk::DynamicState::FRONT_FACE]);
        }
        Self {
            desc,
            attachments: vec![attachment; desc.color_formats.len()],
            dynamic,
        }
    }

    /// The vertex buffers' layout and triangle lists (not for mesh pipelines).
    fn vertex_input(
        &self,
    ) -> (
        vk::PipelineVertexInputStateCreateInfo<'a>,
        vk::PipelineInputAssemblyStateCreateInfo<'static>,
    ) {
        (
            vk::PipelineVertexInputStateCreateInfo::default()
                .vertex_binding_descriptions(self.desc.vertex_bindings)
                .vertex_attribute_descriptions(self.desc.vertex_attributes),
            vk::PipelineInputAssemblyStateCreateInfo::default()
                .topology(vk::PrimitiveTopology::TRIANGLE_LIST),
        )
    }

    fn rasterization(&self) -> vk::PipelineRasterizationStateCreateInfo<'static> {
        vk::PipelineRasterizationStateCreateInfo::default()
            .rasterizer_discard_enable(self.desc.rasterizer_discard)
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(self.desc.cull_mode)
            // A triangle counter-clockwise seen from outside keeps positive area in our views
            // (x right, y down, not mirrored), so CCW is front. Cube faces are mirrored, but
            // the scene pipelines do not cull, so only the mirror's bounding cube relies on it.
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0)
    }

    fn depth(&self) -> vk::PipelineDepthStencilStateCreateInfo<'static> {
        vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_write_enable(self.desc.depth_write)
            .depth_compare_op(self.desc.depth_compare)
    }

    /// One attachment's state per colour attachment (the id cube's too): written whole,
    /// never blended.
    fn blend(&self) -> vk::PipelineColorBlendStateCreateInfo<'_> {
        vk::PipelineColorBlendStateCreateInfo::default().attachments(&self.attachments)
    }

    /// Dynamic rendering into the colour (and id) and depth formats, with the view mask.
    fn rendering(&self) -> vk::PipelineRenderingCreateInfo<'_> {
        vk::PipelineRenderingCreateInfo::default()
            .view_mask(self.desc.view_mask)
            .color_attachment_formats(self.desc.color_formats)
            .depth_attachment_format(self.desc.depth_format)
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        // SAFETY: no pending command buffer uses it.
        unsafe { self.device.raw.destroy_pipeline(self.raw, None) };
    }
}
