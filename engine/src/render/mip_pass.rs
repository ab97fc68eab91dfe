//! The cube's mip pass (`shaders/cube_mips.comp.glsl`): its pipeline for the cube's format,
//! a view of each level's six faces, and per level the set that reads the level above and
//! stores it. Made with the cube (`targets.rs`); recorded by `mips.rs`, which says why a
//! compute pass and not a blit.

use std::sync::Arc;

use ash::vk;

use super::gpu::MipBox;
use crate::vk::descriptors::{self, DescriptorPool, DescriptorSetLayout};
use crate::vk::device::Device;
use crate::vk::image::{Image, ImageView, Sampler};
use crate::vk::pipeline::{Pipeline, PipelineLayout};
use crate::vk::GpuError;

/// The pass that makes level m from level m - 1: its pipeline (one for the cube's format) and,
/// per level m, a set naming level m - 1 to read and level m to store. Field order is drop
/// order: the pipeline before its layout, the sets' pool before their layout, the views last
/// (`CubeTarget` holds this pass before its colour image, so they go before the image).
pub struct MipPass {
    /// `cube_mips.comp` for the cube's format (rgba16f or rgba8).
    pub(super) pipeline: Pipeline,
    /// One set and the `MipBox` push constants.
    pub(super) layout: PipelineLayout,
    /// `sets[m - 1]` makes level m.
    pub(super) sets: Vec<vk::DescriptorSet>,
    _pool: DescriptorPool,
    _set_layout: DescriptorSetLayout,
    /// Each level's six faces as one 2D array view.
    _levels: Vec<ImageView>,
}

impl MipPass {
    /// The pass for `color`, a cube of two or more levels, read through `sampler` (its filter
    /// unused: the shader fetches texels).
    pub fn create(
        device: &Arc<Device>,
        color: &Image,
        sampler: &Sampler,
    ) -> Result<Self, GpuError> {
        let count = color.desc.mip_levels;
        let levels = (0..count)
            .map(|m| {
                let name = format!("cube level {m} (layered)");
                color.view(vk::ImageViewType::TYPE_2D_ARRAY, 0, 6, m, 1, &name)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let compute = vk::ShaderStageFlags::COMPUTE;
        let set_layout = DescriptorSetLayout::create(
            device,
            &[
                descriptors::binding(0, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, 1, compute),
                descriptors::binding(1, vk::DescriptorType::STORAGE_IMAGE, 1, compute),
            ],
            "cube mips set layout",
        )?;
        let made = count - 1;
        let sizes = [
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                descriptor_count: made,
            },
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::STORAGE_IMAGE,
                descriptor_count: made,
            },
        ];
        let pool = DescriptorPool::create(device, made, &sizes, "cube mips descriptors")?;
        let mut sets = Vec::new();
        for m in 1..count as usize {
            let set = pool.allocate(&set_layout, &format!("cube mips, level {m}"))?;
            descriptors::write_images(device, set, 0, &[(levels[m - 1].raw, sampler.raw)]);
            descriptors::write_storage_image(device, set, 1, levels[m].raw);
            sets.push(set);
        }
        let push = std::mem::size_of::<MipBox>() as u32;
        let layout =
            PipelineLayout::create_compute(device, &[set_layout.raw], push, "cube mips layout")?;
        let spirv = match color.desc.format {
            vk::Format::R8G8B8A8_UNORM => crate::shaders::CUBE_MIPS_RGBA8_COMP,
            _ => crate::shaders::CUBE_MIPS_RGBA16F_COMP,
        };
        let pipeline = Pipeline::create_compute(device, &layout, spirv, "cube mips")?;
        Ok(Self {
            pipeline,
            layout,
            sets,
            _pool: pool,
            _set_layout: set_layout,
            _levels: levels,
        })
    }
}
