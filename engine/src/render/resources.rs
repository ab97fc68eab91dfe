//! The scene on the GPU: one vertex and index buffer for every mesh, materials, textures,
//! per-frame buffers and the descriptor sets that expose them to the shaders.

use std::sync::Arc;

use ash::vk;
use glam::{UVec4, Vec3, Vec4};

use super::draw::{barrier, COPY_WRITE, NOTHING, SAMPLED};
use super::gpu::{self, MaterialData, ObjectData, Vertex, ViewData};
use crate::render::lookups::build_order::triangles_in_split_order;
use crate::scene::state::room_meshes;
use crate::scene::{MaterialKind, Mesh, Scene};
use crate::vk::commands::{image_barriers, Submitter};
use crate::vk::descriptors::{self, DescriptorPool, DescriptorSetLayout};
use crate::vk::device::Device;
use crate::vk::image::{Image, ImageDesc, ImageView, Sampler};
use crate::vk::memory::{Buffer, BufferDesc, Upload};
use crate::vk::GpuError;

/// Views in the view buffer: the six cube faces first, then the cameras.
pub const VIEW_OBSERVER: u32 = 6;
pub const VIEW_SENSOR: u32 = 7;
/// The side-by-side image's left (observer) and right (sensor) viewports.
pub const VIEW_PAIR_LEFT: u32 = 8;
pub const VIEW_PAIR_RIGHT: u32 = 9;
pub const VIEW_COUNT: usize = 10;

/// One indexed draw: a mesh range in the shared buffers and its object-space bounds.
#[derive(Debug, Clone, Copy)]
pub struct Drawable {
    pub first_index: u32,
    pub index_count: u32,
    pub vertex_offset: i32,
    /// Vertices of the mesh, from `vertex_offset` (acceleration-structure builds need it).
    pub vertex_count: u32,
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
    /// Back faces may be culled (the mesh is closed: see `Mesh::closed`).
    pub cull_back: bool,
}

/// Owns every scene buffer and texture. Field order is drop order: sets' pool first.
pub struct SceneResources {
    /// Set 0 (scene) and set 1 (environment cube) live in this pool.
    pub pool: DescriptorPool,
    pub scene_set: vk::DescriptorSet,
    pub environment_set: vk::DescriptorSet,
    pub scene_set_layout: DescriptorSetLayout,
    pub environment_set_layout: DescriptorSetLayout,
    pub vertices: Buffer,
    pub indices: Buffer,
    /// With ray queries: the same triangles, each mesh's in the order its bottom-level build
    /// wants them (`render::lookups::build_order`: lavapipe keeps the order it is given), at the same
    /// ranges as in `indices`. The draws keep `indices`: their order decides early depth
    /// tests, which the benchmark's counters see.
    pub traced_indices: Option<Buffer>,
    /// Drawables 0..6 are the room walls (world space), then one per scene object.
    pub drawables: Vec<Drawable>,
    pub frame: Buffer,
    pub views: Buffer,
    pub objects: Buffer,
    pub materials: Buffer,
    /// Views before images (drop order).
    _texture_views: Vec<ImageView>,
    _textures: Vec<Image>,
    _texture_sampler: Sampler,
}

impl SceneResources {
    pub fn create(
        device: &Arc<Device>,
        scene: &Scene,
        submitter: &Submitter,
    ) -> Result<Self, GpuError> {
        // Meshes: walls, then each object's mesh (shared meshes are stored once).
        let walls = room_meshes(&scene.room);
        let mut vertices: Vec<Vertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let traces = device.enabled.ray_query;
        let mut traced_indices: Vec<u32> = Vec::new();
        let mut push_mesh =
            |m: &Mesh| {
                let d = Drawable {
                    first_index: indices.len() as u32,
                    index_count: m.indices.len() as u32,
                    vertex_offset: vertices.len() as i32,
                    vertex_count: m.positions.len() as u32,
                    bounds_min: m.bounds_min,
                    bounds_max: m.bounds_max,
                    cull_back: m.closed,
                };
                vertices.extend(m.positions.iter().zip(&m.normals).zip(&m.uvs).map(
                    |((p, n), uv)| Vertex {
                        position: p.to_array(),
                        normal: n.to_array(),
                        uv: uv.to_array(),
                    },
                ));
                indices.extend_from_slice(&m.indices);
                if traces {
                    traced_indices.extend(triangles_in_split_order(&m.positions, &m.indices));
                }
                d
            };
        let mut drawables: Vec<Drawable> = walls.iter().map(&mut push_mesh).collect();
        let mesh_draws: Vec<Drawable> = scene.meshes.iter().map(&mut push_mesh).collect();
        drawables.extend(scene.objects.iter().map(|o| mesh_draws[o.mesh]));

        let host = |size: usize, usage, name: &str| {
            Buffer::create(
                device,
                &BufferDesc::new_cpu_to_gpu(size as u64, usage),
                name,
            )
        };
        // Geometry never changes: device-local, read by every pass.
        // With ray queries, acceleration-structure builds read them by address too.
        let build_input = if device.enabled.ray_query {
            crate::vk::acceleration::BUILD_INPUT_USAGE
        } else {
            vk::BufferUsageFlags::empty()
        };
        let mut upload = Upload::begin(device, submitter)?;
        let vertex_buffer = upload.buffer(
            &vertices,
            // Storage too: a method may fetch vertices in its own shaders (mesh shading).
            vk::BufferUsageFlags::VERTEX_BUFFER
                | vk::BufferUsageFlags::STORAGE_BUFFER
                | build_input,
            "scene vertices",
        )?;
        let index_buffer = upload.buffer(
            &indices,
            vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER | build_input,
            "scene indices",
        )?;
        let traced_index_buffer = traces
            .then(|| {
                upload.buffer(
                    &traced_indices,
                    vk::BufferUsageFlags::STORAGE_BUFFER | build_input,
                    "scene indices (traced order)",
                )
            })
            .transpose()?;
        upload.finish()?;
        let materials_data: Vec<MaterialData> = scene.materials.iter().map(material_data).collect();
        let mut materials = host(
            std::mem::size_of_val(materials_data.as_slice()),
            vk::BufferUsageFlags::STORAGE_BUFFER,
            "materials",
        )?;
        materials.write(&materials_data)?;
        let frame = host(
            std::mem::size_of::<gpu::FrameData>(),
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            "frame data",
        )?;
        let views = host(
            VIEW_COUNT * std::mem::size_of::<ViewData>(),
            vk::BufferUsageFlags::STORAGE_BUFFER,
            "views",
        )?;
        let objects = host(
            drawables.len() * std::mem::size_of::<ObjectData>(),
            vk::BufferUsageFlags::STORAGE_BUFFER,
            "objects",
        )?;

        let (textures, texture_views) = upload_textures(device, scene, submitter)?;
        // Bilinear, repeating, no mips: simple enough for the CPU reference to reproduce.
        let texture_sampler = Sampler::create(
            device,
            &vk::SamplerCreateInfo::default()
                .mag_filter(vk::Filter::LINEAR)
                .min_filter(vk::Filter::LINEAR)
                .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
                .address_mode_u(vk::SamplerAddressMode::REPEAT)
                .address_mode_v(vk::SamplerAddressMode::REPEAT)
                .address_mode_w(vk::SamplerAddressMode::REPEAT)
                .max_lod(0.0),
            "material textures",
        )?;

        // Compute too: the materials check (materials_check.comp) reads the scene set.
        let all = device.graphics_stages() | vk::ShaderStageFlags::COMPUTE;
        let binding = |b, ty, count| descriptors::binding(b, ty, count, all);
        let scene_set_layout = DescriptorSetLayout::create(
            device,
            &[
                binding(0, vk::DescriptorType::UNIFORM_BUFFER, 1),
                binding(1, vk::DescriptorType::STORAGE_BUFFER, 1),
                binding(2, vk::DescriptorType::STORAGE_BUFFER, 1),
                binding(3, vk::DescriptorType::STORAGE_BUFFER, 1),
                binding(
                    4,
                    vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                    gpu::MAX_TEXTURES,
                ),
            ],
            "scene set layout",
        )?;
        let environment_set_layout = DescriptorSetLayout::create(
            device,
            &[binding(0, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, 1)],
            "environment set layout",
        )?;
        let pool = DescriptorPool::create(
            device,
            2,
            &[
                vk::DescriptorPoolSize {
                    ty: vk::DescriptorType::UNIFORM_BUFFER,
                    descriptor_count: 1,
                },
                vk::DescriptorPoolSize {
                    ty: vk::DescriptorType::STORAGE_BUFFER,
                    descriptor_count: 3,
                },
                vk::DescriptorPoolSize {
                    ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                    descriptor_count: gpu::MAX_TEXTURES + 1,
                },
            ],
            "scene descriptors",
        )?;
        let scene_set = pool.allocate(&scene_set_layout, "scene set")?;
        let environment_set = pool.allocate(&environment_set_layout, "environment set")?;
        descriptors::write_buffer(
            device,
            scene_set,
            0,
            vk::DescriptorType::UNIFORM_BUFFER,
            frame.raw,
        );
        descriptors::write_buffer(
            device,
            scene_set,
            1,
            vk::DescriptorType::STORAGE_BUFFER,
            views.raw,
        );
        descriptors::write_buffer(
            device,
            scene_set,
            2,
            vk::DescriptorType::STORAGE_BUFFER,
            objects.raw,
        );
        descriptors::write_buffer(
            device,
            scene_set,
            3,
            vk::DescriptorType::STORAGE_BUFFER,
            materials.raw,
        );
        // Every slot must hold a valid image; unused ones repeat slot 0 (a 1x1 white texel
        // when the scene has no textures).
        let slots: Vec<(vk::ImageView, vk::Sampler)> = (0..gpu::MAX_TEXTURES as usize)
            .map(|i| {
                (
                    texture_views[i.min(texture_views.len() - 1)].raw,
                    texture_sampler.raw,
                )
            })
            .collect();
        descriptors::write_images(device, scene_set, 4, &slots);

        Ok(Self {
            pool,
            scene_set,
            environment_set,
            scene_set_layout,
            environment_set_layout,
            vertices: vertex_buffer,
            indices: index_buffer,
            traced_indices: traced_index_buffer,
            drawables,
            frame,
            views,
            objects,
            materials,
            _texture_views: texture_views,
            _textures: textures,
            _texture_sampler: texture_sampler,
        })
    }
}

fn material_data(m: &crate::scene::Material) -> MaterialData {
    let c = |v: Vec3| v.extend(1.0);
    let (kind, texture, a, b, params) = match &m.kind {
        MaterialKind::Color { color } => {
            (gpu::MATERIAL_COLOR, 0, c(*color), Vec4::ZERO, Vec4::ZERO)
        }
        MaterialKind::Checker { a, b, tiles } => (
            gpu::MATERIAL_CHECKER,
            0,
            c(*a),
            c(*b),
            Vec4::new(*tiles, 0.0, 0.0, 0.0),
        ),
        MaterialKind::Grid {
            background,
            line,
            tiles,
            line_width,
        } => (
            gpu::MATERIAL_GRID,
            0,
            c(*background),
            c(*line),
            Vec4::new(*tiles, *line_width, 0.0, 0.0),
        ),
        MaterialKind::Texture {
            texture,
            tint,
            tiles,
        } => (
            gpu::MATERIAL_TEXTURE,
            *texture as u32,
            c(*tint),
            Vec4::ZERO,
            Vec4::new(*tiles, 0.0, 0.0, 0.0),
        ),
        MaterialKind::Direction => (
            gpu::MATERIAL_DIRECTION,
            0,
            Vec4::ZERO,
            Vec4::ZERO,
            Vec4::ZERO,
        ),
    };
    MaterialData {
        kind_texture: UVec4::new(kind, texture, 0, 0),
        color_a: a,
        color_b: b,
        params,
    }
}

/// Uploads every scene texture (or one white texel) as sRGB images ready for sampling.
fn upload_textures(
    device: &Arc<Device>,
    scene: &Scene,
    submitter: &Submitter,
) -> Result<(Vec<Image>, Vec<ImageView>), GpuError> {
    if scene.textures.len() > gpu::MAX_TEXTURES as usize {
        return Err(GpuError::Unsupported(format!(
            "{} textures; at most {} are supported",
            scene.textures.len(),
            gpu::MAX_TEXTURES
        )));
    }
    let white = crate::scene::TextureData {
        path: "white".into(),
        width: 1,
        height: 1,
        rgba8: vec![255; 4],
    };
    let list: Vec<&crate::scene::TextureData> = if scene.textures.is_empty() {
        vec![&white]
    } else {
        scene.textures.iter().collect()
    };
    let mut staging = Vec::new();
    let mut images = Vec::new();
    let mut views = Vec::new();
    let cmd = submitter.begin()?;
    for (i, t) in list.iter().enumerate() {
        let name = format!("texture {i} ({})", t.path.display());
        let mut buf = Buffer::create(
            device,
            &BufferDesc::new_cpu_to_gpu(t.rgba8.len() as u64, vk::BufferUsageFlags::TRANSFER_SRC),
            &format!("{name} staging"),
        )?;
        buf.write(&t.rgba8)?;
        let image = Image::create(
            device,
            &ImageDesc::new_2d(
                vk::Format::R8G8B8A8_SRGB,
                t.width,
                t.height,
                vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            ),
            &name,
        )?;
        let range = image.full_range();
        let to_dst = barrier(
            image.raw,
            range,
            (vk::ImageLayout::UNDEFINED, NOTHING),
            (vk::ImageLayout::TRANSFER_DST_OPTIMAL, COPY_WRITE),
        );
        image_barriers(device, cmd, &[to_dst]);
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D {
                width: t.width,
                height: t.height,
                depth: 1,
            });
        // SAFETY: buffer and image are live; the image is in TRANSFER_DST layout.
        unsafe {
            device.raw.cmd_copy_buffer_to_image(
                cmd,
                buf.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
        let to_sampled = barrier(
            image.raw,
            range,
            (vk::ImageLayout::TRANSFER_DST_OPTIMAL, COPY_WRITE),
            (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, SAMPLED),
        );
        image_barriers(device, cmd, &[to_sampled]);
        views.push(image.view(vk::ImageViewType::TYPE_2D, 0, 1, 0, 1, &name)?);
        images.push(image);
        staging.push(buf);
    }
    submitter.submit_and_wait()?;
    drop(staging);
    Ok((images, views))
}
