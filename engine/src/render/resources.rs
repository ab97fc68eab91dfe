//! The scene on the GPU: one vertex and index buffer for every mesh, materials, textures,
//! per-frame buffers and the descriptor sets that expose them to the shaders.

use std::sync::Arc;

use ash::vk;
use glam::{UVec4, Vec3, Vec4};

use super::draw::{barrier, COPY_WRITE, NOTHING, SAMPLED};
use super::gpu::{self, MaterialData, ObjectData, Vertex, ViewData};
use crate::scene::state::room_meshes;
use crate::scene::{MaterialKind, Mesh, Scene, TextureData};
use crate::trees::split_order::triangles_in_split_order;
use crate::vk::commands::{image_barriers, Submitter};
use crate::vk::descriptors::{self, DescriptorPool, DescriptorSetLayout};
use crate::vk::device::Device;
use crate::vk::image::{color_copy_region, Image, ImageDesc, ImageView, Sampler};
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
    /// wants them (`trees::split_order`: lavapipe keeps the order it is given), at the same
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
    /// Uploads `scene`: its meshes, materials and textures, the per-frame buffers, and the
    /// descriptor sets that show them to the shaders.
    pub fn create(
        device: &Arc<Device>,
        scene: &Scene,
        submitter: &Submitter,
    ) -> Result<Self, GpuError> {
        let meshes = Meshes::gather(scene, device.enabled.ray_query);
        let (vertices, indices, traced_indices) = upload_meshes(device, submitter, &meshes)?;
        let materials = material_buffer(device, scene)?;
        let [frame, views, objects] = per_frame_buffers(device, meshes.drawables.len())?;
        let (textures, texture_views) = upload_textures(device, scene, submitter)?;
        let texture_sampler = texture_sampler(device)?;
        let sets = SceneSets::create(device)?;
        let slots = [&frame, &views, &objects, &materials];
        sets.write_scene(device, slots, &texture_views, &texture_sampler);
        Ok(Self {
            pool: sets.pool,
            scene_set: sets.scene,
            environment_set: sets.environment,
            scene_set_layout: sets.scene_layout,
            environment_set_layout: sets.environment_layout,
            vertices,
            indices,
            traced_indices,
            drawables: meshes.drawables,
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

/// Every mesh's vertices and indices in one array each, with its drawable: walls first, then
/// one drawable per object (a mesh shared by several objects is stored once).
struct Meshes {
    vertices: Vec<Vertex>,
    indices: Vec<u32>,
    /// With ray queries, the same triangles in the order their builds want them.
    traced_indices: Option<Vec<u32>>,
    drawables: Vec<Drawable>,
}

impl Meshes {
    fn gather(scene: &Scene, traces: bool) -> Self {
        let mut all = Self {
            vertices: Vec::new(),
            indices: Vec::new(),
            traced_indices: traces.then(Vec::new),
            drawables: Vec::new(),
        };
        let walls: Vec<Drawable> = (room_meshes(&scene.room).iter())
            .map(|m| all.push(m))
            .collect();
        let meshes: Vec<Drawable> = scene.meshes.iter().map(|m| all.push(m)).collect();
        all.drawables = walls;
        all.drawables
            .extend(scene.objects.iter().map(|o| meshes[o.mesh]));
        all
    }

    /// Appends `m`; returns its drawable.
    fn push(&mut self, m: &Mesh) -> Drawable {
        let d = Drawable {
            first_index: self.indices.len() as u32,
            index_count: m.indices.len() as u32,
            vertex_offset: self.vertices.len() as i32,
            vertex_count: m.positions.len() as u32,
            bounds_min: m.bounds_min,
            bounds_max: m.bounds_max,
            cull_back: m.closed,
        };
        let vertices = m.positions.iter().zip(&m.normals).zip(&m.uvs);
        self.vertices.extend(vertices.map(|((p, n), uv)| Vertex {
            position: p.to_array(),
            normal: n.to_array(),
            uv: uv.to_array(),
        }));
        self.indices.extend_from_slice(&m.indices);
        if let Some(traced) = &mut self.traced_indices {
            traced.extend(triangles_in_split_order(&m.positions, &m.indices));
        }
        d
    }
}

/// The geometry, device-local (it never changes; every pass reads it): vertices, indices and
/// the traced order's indices. With ray queries, acceleration-structure builds read them by
/// address too.
fn upload_meshes(
    device: &Arc<Device>,
    submitter: &Submitter,
    meshes: &Meshes,
) -> Result<(Buffer, Buffer, Option<Buffer>), GpuError> {
    let build_input = if device.enabled.ray_query {
        crate::vk::acceleration::BUILD_INPUT_USAGE
    } else {
        vk::BufferUsageFlags::empty()
    };
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER | build_input;
    let mut upload = Upload::begin(device, submitter)?;
    // Storage too: a method may fetch vertices in its own shaders (mesh shading).
    let vertex_usage = vk::BufferUsageFlags::VERTEX_BUFFER | storage;
    let vertices = upload.buffer(&meshes.vertices, vertex_usage, "scene vertices")?;
    let index_usage = vk::BufferUsageFlags::INDEX_BUFFER | storage;
    let indices = upload.buffer(&meshes.indices, index_usage, "scene indices")?;
    let traced = (meshes.traced_indices.as_ref())
        .map(|t| upload.buffer(t, storage, "scene indices (traced order)"))
        .transpose()?;
    upload.finish()?;
    Ok((vertices, indices, traced))
}

/// A buffer the host writes and the device reads.
fn host_buffer(
    device: &Arc<Device>,
    size: usize,
    usage: vk::BufferUsageFlags,
    name: &str,
) -> Result<Buffer, GpuError> {
    Buffer::create(
        device,
        &BufferDesc::new_cpu_to_gpu(size as u64, usage),
        name,
    )
}

/// The materials, written once.
fn material_buffer(device: &Arc<Device>, scene: &Scene) -> Result<Buffer, GpuError> {
    let data: Vec<MaterialData> = scene.materials.iter().map(material_data).collect();
    let size = std::mem::size_of_val(data.as_slice());
    let mut materials = host_buffer(
        device,
        size,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        "materials",
    )?;
    materials.write(&data)?;
    Ok(materials)
}

/// The buffers written every frame: the frame's data, the views, the objects' transforms.
fn per_frame_buffers(device: &Arc<Device>, drawables: usize) -> Result<[Buffer; 3], GpuError> {
    // Device-local: each frame's data reaches them through its uploads (`vk::uploads`), so
    // that the frames in flight share these buffers and the sets that name them.
    let buffer = |size: usize, usage, name| {
        Buffer::create(
            device,
            &BufferDesc::new_device_local(size as u64, usage),
            name,
        )
    };
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    Ok([
        buffer(
            std::mem::size_of::<gpu::FrameData>(),
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            "frame data",
        )?,
        buffer(
            VIEW_COUNT * std::mem::size_of::<ViewData>(),
            storage,
            "views",
        )?,
        buffer(
            drawables * std::mem::size_of::<ObjectData>(),
            storage,
            "objects",
        )?,
    ])
}

/// Bilinear, repeating, no mips: simple enough for the CPU reference to reproduce.
fn texture_sampler(device: &Arc<Device>) -> Result<Sampler, GpuError> {
    Sampler::create(
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
    )
}

/// Set 0 (the scene: frame data, views, objects, materials, textures) and set 1 (the
/// environment cube, written by the renderer), with their layouts and pool.
struct SceneSets {
    pool: DescriptorPool,
    scene: vk::DescriptorSet,
    environment: vk::DescriptorSet,
    scene_layout: DescriptorSetLayout,
    environment_layout: DescriptorSetLayout,
}

impl SceneSets {
    fn create(device: &Arc<Device>) -> Result<Self, GpuError> {
        // Compute too: the materials check (materials_check.comp) reads the scene set.
        let all = device.graphics_stages() | vk::ShaderStageFlags::COMPUTE;
        let binding = |b, ty, count| descriptors::binding(b, ty, count, all);
        let storage = vk::DescriptorType::STORAGE_BUFFER;
        let sampled = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
        let scene_layout = DescriptorSetLayout::create(
            device,
            &[
                binding(0, vk::DescriptorType::UNIFORM_BUFFER, 1),
                binding(1, storage, 1),
                binding(2, storage, 1),
                binding(3, storage, 1),
                binding(4, sampled, gpu::MAX_TEXTURES),
            ],
            "scene set layout",
        )?;
        let environment_layout = DescriptorSetLayout::create(
            device,
            &[binding(0, sampled, 1)],
            "environment set layout",
        )?;
        let size = |ty, descriptor_count| vk::DescriptorPoolSize {
            ty,
            descriptor_count,
        };
        let pool = DescriptorPool::create(
            device,
            2,
            &[
                size(vk::DescriptorType::UNIFORM_BUFFER, 1),
                size(storage, 3),
                size(sampled, gpu::MAX_TEXTURES + 1),
            ],
            "scene descriptors",
        )?;
        let scene = pool.allocate(&scene_layout, "scene set")?;
        let environment = pool.allocate(&environment_layout, "environment set")?;
        Ok(Self {
            pool,
            scene,
            environment,
            scene_layout,
            environment_layout,
        })
    }

    /// Set 0's bindings: the frame's uniform (0), the views, objects and materials (1..=3),
    /// and the textures (4). Every texture slot must hold a valid image; unused ones repeat
    /// slot 0 (a 1x1 white texel when the scene has no textures).
    fn write_scene(
        &self,
        device: &Arc<Device>,
        [frame, views, objects, materials]: [&Buffer; 4],
        texture_views: &[ImageView],
        sampler: &Sampler,
    ) {
        descriptors::write_buffer(
            device,
            self.scene,
            0,
            vk::DescriptorType::UNIFORM_BUFFER,
            frame.raw,
        );
        for (binding, buffer) in [(1, views), (2, objects), (3, materials)] {
            let storage = vk::DescriptorType::STORAGE_BUFFER;
            descriptors::write_buffer(device, self.scene, binding, storage, buffer.raw);
        }
        let slots: Vec<(vk::ImageView, vk::Sampler)> = (0..gpu::MAX_TEXTURES as usize)
            .map(|i| {
                (
                    texture_views[i.min(texture_views.len() - 1)].raw,
                    sampler.raw,
                )
            })
            .collect();
        descriptors::write_images(device, self.scene, 4, &slots);
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
    check_texture_count(scene)?;
    let white = white_texel();
    let list: Vec<&TextureData> = if scene.textures.is_empty() {
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
        let buf = staging_buffer(device, t, &name)?;
        let image = texture_image(device, t, &name)?;
        record_texture_copy(device, cmd, &buf, &image, t);
        views.push(image.view(vk::ImageViewType::TYPE_2D, 0, 1, 0, 1, &name)?);
        images.push(image);
        staging.push(buf);
    }
    submitter.submit_and_wait()?;
    drop(staging);
    Ok((images, views))
}

/// Fails when the scene has more textures than the scene set has slots for.
fn check_texture_count(scene: &Scene) -> Result<(), GpuError> {
    if scene.textures.len() > gpu::MAX_TEXTURES as usize {
        return Err(GpuError::Unsupported(format!(
            "{} textures; at most {} are supported",
            scene.textures.len(),
            gpu::MAX_TEXTURES
        )));
    }
    Ok(())
}

/// The texture of a scene without textures: one white texel.
fn white_texel() -> TextureData {
    TextureData {
        path: "white".into(),
        width: 1,
        height: 1,
        rgba8: vec![255; 4],
    }
}

/// A host-visible copy of `t`'s texels, the source of its upload.
fn staging_buffer(device: &Arc<Device>, t: &TextureData, name: &str) -> Result<Buffer, GpuError> {
    let mut buf = Buffer::create(
        device,
        &BufferDesc::new_cpu_to_gpu(t.rgba8.len() as u64, vk::BufferUsageFlags::TRANSFER_SRC),
        &format!("{name} staging"),
    )?;
    buf.write(&t.rgba8)?;
    Ok(buf)
}

/// The sRGB image `t` is copied into and sampled from.
fn texture_image(device: &Arc<Device>, t: &TextureData, name: &str) -> Result<Image, GpuError> {
    Image::create(
        device,
        &ImageDesc::new_2d(
            vk::Format::R8G8B8A8_SRGB,
            t.width,
            t.height,
            vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
        ),
        name,
    )
}

/// Records `buf`'s copy into `image`, moving the image to transfer-destination layout and
/// then to shader-read layout.
fn record_texture_copy(
    device: &Device,
    cmd: vk::CommandBuffer,
    buf: &Buffer,
    image: &Image,
    t: &TextureData,
) {
    let range = image.full_range();
    let to_dst = barrier(
        image.raw,
        range,
        (vk::ImageLayout::UNDEFINED, NOTHING),
        (vk::ImageLayout::TRANSFER_DST_OPTIMAL, COPY_WRITE),
    );
    image_barriers(device, cmd, &[to_dst]);
    let region = color_copy_region(0, 1, [t.width, t.height]);
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
}
