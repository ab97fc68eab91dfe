//! Render targets: the cube map (colour + depth, six layers) and the 2D view images.

use std::sync::Arc;

use ash::vk;

use super::graph::{Resource, Use};
use super::mip_pass::MipPass;
use crate::scene::{CubeFormat, CubeSettings, Scene};
use crate::vk::device::Device;
use crate::vk::image::{full_mip_count, Image, ImageDesc, ImageView, Sampler};
use crate::vk::GpuError;

/// Depth format of every pass: 32-bit float with reverse-Z keeps precision far away.
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
/// View images are linear HDR.
pub const VIEW_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// Lookup directions need full float: a texel of a 2048-texel face is 0.04 degrees.
pub const DIRECTION_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// The id cube's format: one drawable index per texel (walls 0..6, objects 6 + i).
pub const ID_FORMAT: vk::Format = vk::Format::R32_UINT;

/// The id cube: per texel of every face, the drawable the fill drew there
/// (`shaders/scene_id.frag.glsl`), made only for the sensor outputs
/// (`RenderOptions::id_cube`). Six layers of one level, read texel by texel like the depth.
pub struct IdCube {
    /// Views first: they must go before their image.
    pub face_views: Vec<ImageView>,
    pub layers_view: ImageView,
    pub image: Image,
}

impl IdCube {
    pub fn desc(settings: &CubeSettings) -> ImageDesc {
        let mut desc = ImageDesc::new_cube(
            ID_FORMAT,
            settings.face_size_px,
            1,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
        );
        desc.cube_compatible = false;
        desc
    }

    fn create(device: &Arc<Device>, settings: &CubeSettings) -> Result<Self, GpuError> {
        let image = Image::create(device, &Self::desc(settings), "id cube")?;
        let names = crate::scene::camera::FACE_NAMES;
        let face_views = (0..6)
            .map(|f| {
                let name = format!("id cube {}", names[f as usize]);
                image.view(vk::ImageViewType::TYPE_2D, f, 1, 0, 1, &name)
            })
            .collect::<Result<_, _>>()?;
        let layers_view = image.view(
            vk::ImageViewType::TYPE_2D_ARRAY,
            0,
            6,
            0,
            1,
            "id cube (layered)",
        )?;
        Ok(Self {
            face_views,
            layers_view,
            image,
        })
    }
}

/// The dynamic environment: a cube-compatible colour image with a mip chain, a six-layer
/// depth image, one attachment view per face and the cube view the mirror samples; and the
/// id cube when it is asked for.
pub struct CubeTarget {
    /// The mip chain's pass (with mipmaps): its views of the levels go before the colour.
    pub mips: Option<MipPass>,
    pub ids: Option<IdCube>,
    /// Views first: they must go before their images.
    pub face_views: Vec<ImageView>,
    pub depth_views: Vec<ImageView>,
    /// Mip 0 of all six faces as one 2D array: the attachment of the one-pass methods.
    pub layers_view: ImageView,
    pub depth_layers_view: ImageView,
    pub cube_view: ImageView,
    pub sampler: Sampler,
    pub color: Image,
    pub depth: Image,
    pub size: u32,
    pub format: vk::Format,
}

impl CubeTarget {
    /// The cube's images as the frame graph tracks them (colour, depth, and ids where there
    /// are), all resting as a fill leaves them between frames: sampled by fragment shaders.
    pub(super) fn resources(&self) -> Vec<(Resource, Use)> {
        let ids = self.ids.as_ref().map(|ids| &ids.image);
        [Some(&self.color), Some(&self.depth), ids]
            .into_iter()
            .flatten()
            .map(|image| (Resource::whole(image), Use::FragmentRead))
            .collect()
    }

    /// Levels `first..first + count` of face `face` (None: all six faces) of the colour.
    pub(super) fn color_levels(&self, first: u32, count: u32, face: Option<u32>) -> Resource {
        let all = self.color.full_range();
        let range = vk::ImageSubresourceRange {
            base_mip_level: first,
            level_count: count,
            base_array_layer: face.unwrap_or(all.base_array_layer),
            layer_count: if face.is_some() { 1 } else { all.layer_count },
            ..all
        };
        Resource::image(self.color.raw, range)
    }

    /// The fill's attachments besides the colour's mip 0: the depth, and the ids where there
    /// are (all layers).
    pub(super) fn depth_and_ids(&self) -> (Resource, Option<Resource>) {
        let whole = Resource::whole;
        (
            whole(&self.depth),
            self.ids.as_ref().map(|ids| whole(&ids.image)),
        )
    }

    /// The cube's colour image: `settings.face_size_px` per face, six layers, a full mip
    /// chain when mipmaps are on.
    pub fn color_desc(settings: &CubeSettings) -> ImageDesc {
        let size = settings.face_size_px;
        let mips = if settings.mipmaps {
            full_mip_count(size)
        } else {
            1
        };
        // Levels 1.. are stored by the mip pass's compute shader.
        let stored = match mips {
            1 => vk::ImageUsageFlags::empty(),
            _ => vk::ImageUsageFlags::STORAGE,
        };
        ImageDesc::new_cube(
            cube_format(settings.format),
            size,
            mips,
            vk::ImageUsageFlags::COLOR_ATTACHMENT
                | vk::ImageUsageFlags::SAMPLED
                | vk::ImageUsageFlags::TRANSFER_SRC
                | vk::ImageUsageFlags::TRANSFER_DST
                | stored,
        )
    }

    /// The cube's depth: six layers of one level, kept after the fill and sampled by the
    /// `distance` lookup. It reads texels one by one (texelFetch on the six-layer array view,
    /// choosing the face itself), so the image need not be cube-compatible.
    pub fn depth_desc(settings: &CubeSettings) -> ImageDesc {
        let mut desc = ImageDesc::new_cube(
            DEPTH_FORMAT,
            settings.face_size_px,
            1,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
        );
        desc.cube_compatible = false;
        desc
    }

    /// The cube of `settings`, with the id cube when `ids`.
    pub fn create(
        device: &Arc<Device>,
        settings: &CubeSettings,
        ids: bool,
    ) -> Result<Self, GpuError> {
        let size = settings.face_size_px;
        check_face_size(device, size)?;
        let color_desc = Self::color_desc(settings);
        let (format, mips) = (color_desc.format, color_desc.mip_levels);
        if mips > 1 {
            check_storage_support(device, format)?;
        }
        let color = Image::create(device, &color_desc, "cube colour")?;
        let depth = Image::create(device, &Self::depth_desc(settings), "cube depth")?;
        let face_views = per_face_views(&color, "cube face")?;
        let depth_views = per_face_views(&depth, "cube depth")?;
        let layers_view = six_layer_view(&color, "cube faces (layered)")?;
        let depth_layers_view = six_layer_view(&depth, "cube depth (layered)")?;
        let cube_view = color.view(vk::ImageViewType::CUBE, 0, 6, 0, mips, "cube (sampled)")?;
        let sampler = cube_sampler(device)?;
        let ids = ids.then(|| IdCube::create(device, settings)).transpose()?;
        let mips = (mips > 1)
            .then(|| MipPass::create(device, &color, &sampler))
            .transpose()?;
        Ok(Self {
            mips,
            ids,
            face_views,
            depth_views,
            layers_view,
            depth_layers_view,
            cube_view,
            sampler,
            color,
            depth,
            size,
            format,
        })
    }

    pub fn mip_levels(&self) -> u32 {
        self.color.desc.mip_levels
    }
}

/// The Vulkan format of a cube format setting.
pub fn cube_format(format: CubeFormat) -> vk::Format {
    match format {
        CubeFormat::Rgba16Float => vk::Format::R16G16B16A16_SFLOAT,
        CubeFormat::Rgba8Unorm => vk::Format::R8G8B8A8_UNORM,
    }
}

/// Fails when a cube face of `size` texels is larger than the device allows.
fn check_face_size(device: &Device, size: u32) -> Result<(), GpuError> {
    if size > device.info.limits.max_image_dimension_cube {
        return Err(GpuError::Unsupported(format!(
            "cube face size {size} exceeds the device's maxImageDimensionCube {}",
            device.info.limits.max_image_dimension_cube
        )));
    }
    Ok(())
}

/// One 2D view of mip 0 per face of `image`, named `"{what} {face}"`.
fn per_face_views(image: &Image, what: &str) -> Result<Vec<ImageView>, GpuError> {
    let names = crate::scene::camera::FACE_NAMES;
    (0..6)
        .map(|f| {
            image.view(
                vk::ImageViewType::TYPE_2D,
                f,
                1,
                0,
                1,
                &format!("{what} {}", names[f as usize]),
            )
        })
        .collect()
}

/// Mip 0 of all six layers of `image` as one 2D array view.
fn six_layer_view(image: &Image, name: &str) -> Result<ImageView, GpuError> {
    image.view(vk::ImageViewType::TYPE_2D_ARRAY, 0, 6, 0, 1, name)
}

/// The sampler the mirror reads the cube with.
fn cube_sampler(device: &Arc<Device>) -> Result<Sampler, GpuError> {
    // Trilinear; Vulkan filters across cube seams always. Anisotropic filtering is the
    // mirror shaders' own (footprint_filter.glsl), so that every device filters alike:
    // the sampler's would come on top of it, differently per device.
    Sampler::create(
        device,
        &vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::LINEAR)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(vk::LOD_CLAMP_NONE),
        "cube sampler",
    )
}

/// The mip pass reads a level through a sampled view and stores the next from a compute
/// shader, and the mirror samples the chain trilinearly: all required of the two cube
/// formats, and checked all the same.
fn check_storage_support(device: &Device, format: vk::Format) -> Result<(), GpuError> {
    // SAFETY: plain query.
    let props = unsafe {
        device
            .instance
            .raw
            .get_physical_device_format_properties(device.physical, format)
    };
    let need = vk::FormatFeatureFlags::STORAGE_IMAGE
        | vk::FormatFeatureFlags::SAMPLED_IMAGE
        | vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR;
    if props.optimal_tiling_features.contains(need) {
        Ok(())
    } else {
        Err(GpuError::Unsupported(format!(
            "{format:?} cannot be stored by a compute shader or filtered linearly on this \
             device, which the cube's mip chain needs: set mipmaps = false"
        )))
    }
}

/// A 2D colour + depth target for a camera view.
pub struct ViewTarget {
    pub color_view: ImageView,
    pub depth_view: ImageView,
    pub color: Image,
    pub depth: Image,
    pub width: u32,
    pub height: u32,
}

impl ViewTarget {
    /// Its colour and depth as the frame graph tracks them, each with how it rests between
    /// frames: the colour copied out for the readback, the depth as its pass left it.
    pub(super) fn resources(&self) -> [(Resource, Use); 2] {
        [
            (self.color_resource(), Use::CopySource),
            (Resource::whole(&self.depth), Use::DepthTarget),
        ]
    }

    pub(super) fn color_resource(&self) -> Resource {
        Resource::whole(&self.color)
    }

    /// The uses of a pass that draws it: both cleared and drawn into.
    pub(super) fn drawn(&self) -> [(Resource, Use); 2] {
        let [(color, _), (depth, _)] = self.resources();
        [(color, Use::ColorTarget), (depth, Use::DepthTarget)]
    }

    /// Colour (rendered, then copied out) and depth of a `width` x `height` view.
    pub fn descs(format: vk::Format, width: u32, height: u32) -> [ImageDesc; 2] {
        [
            ImageDesc::new_2d(
                format,
                width,
                height,
                vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
            ),
            ImageDesc::new_2d(
                DEPTH_FORMAT,
                width,
                height,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            ),
        ]
    }

    pub fn create(
        device: &Arc<Device>,
        format: vk::Format,
        width: u32,
        height: u32,
        name: &str,
    ) -> Result<Self, GpuError> {
        let [color_desc, depth_desc] = Self::descs(format, width, height);
        let color = Image::create(device, &color_desc, &format!("{name} colour"))?;
        let depth = Image::create(device, &depth_desc, &format!("{name} depth"))?;
        Ok(Self {
            color_view: color.view(vk::ImageViewType::TYPE_2D, 0, 1, 0, 1, name)?,
            depth_view: depth.view(
                vk::ImageViewType::TYPE_2D,
                0,
                1,
                0,
                1,
                &format!("{name} depth"),
            )?,
            color,
            depth,
            width,
            height,
        })
    }
}

/// The view passes' targets: the observer, the sensor and the side-by-side pair (RGBA16F),
/// and the two views' direction images (RGBA32F), each at its camera's resolution.
pub struct ViewTargets {
    pub observer: ViewTarget,
    pub sensor: ViewTarget,
    pub pair: ViewTarget,
    pub observer_directions: ViewTarget,
    pub sensor_directions: ViewTarget,
}

impl ViewTargets {
    pub fn create(device: &Arc<Device>, scene: &Scene) -> Result<Self, GpuError> {
        let [ow, oh] = scene.observer.resolution;
        let [sw, sh] = scene.sensor.resolution;
        let [pw, ph] = super::PAIR_SIZE;
        Ok(Self {
            observer: ViewTarget::create(device, VIEW_FORMAT, ow, oh, "observer")?,
            sensor: ViewTarget::create(device, VIEW_FORMAT, sw, sh, "sensor")?,
            pair: ViewTarget::create(device, VIEW_FORMAT, pw, ph, "views")?,
            observer_directions: ViewTarget::create(
                device,
                DIRECTION_FORMAT,
                ow,
                oh,
                "observer directions",
            )?,
            sensor_directions: ViewTarget::create(
                device,
                DIRECTION_FORMAT,
                sw,
                sh,
                "sensor directions",
            )?,
        })
    }
}
