//! GPU resources: buffers, images (with per-mip views), samplers, query pools, descriptor pools.
//! Each owns its memory through gpu-allocator and frees it on Drop.

use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::cmd::Usage;
use super::context::{vkerr, Context, Shared};
use crate::Error;

fn alloc_error(name: &str, e: gpu_allocator::AllocationError) -> Error {
    Error::device(format!(
        "allocating GPU memory for '{name}' failed: {e}; try a smaller --size or a smaller scene"
    ))
}

/// Where a buffer lives: `Upload` and `Readback` are host-visible.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferLocation {
    Upload,
    Readback,
    Device,
}

pub struct Buffer {
    shared: Arc<Shared>,
    pub(crate) raw: vk::Buffer,
    allocation: Option<Allocation>,
    /// The size of the Vulkan buffer: what was asked for, but at least 16 bytes.
    pub size: u64,
    /// The bytes asked for, what [`Buffer::read`] returns (a 1 x 1 RGBA8 readback is 4 bytes
    /// in a 16-byte buffer).
    len: u64,
    pub name: String,
}

impl Buffer {
    /// Copies `data` into a host-visible buffer at `offset` bytes.
    ///
    /// Waits first for any submission in flight (one may read this buffer).
    pub fn write<T: bytemuck::Pod>(&mut self, offset: u64, data: &[T]) -> crate::Result<()> {
        self.shared.settle();
        self.write_fresh(offset, data)
    }

    /// [`Buffer::write`] without the wait: only for a buffer no command has named yet.
    fn write_fresh<T: bytemuck::Pod>(&mut self, offset: u64, data: &[T]) -> crate::Result<()> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let name = self.name.clone();
        let slice = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| Error::device(format!("buffer '{name}' is not host-visible")))?;
        let start = offset as usize;
        let end = start + bytes.len();
        if end > slice.len() {
            return Err(Error::device(format!(
                "write of {} bytes past the end of buffer '{name}'",
                bytes.len()
            )));
        }
        slice[start..end].copy_from_slice(bytes);
        Ok(())
    }

    /// The contents of a host-visible buffer (after any submission in flight, which may write it).
    pub fn read(&self) -> crate::Result<&[u8]> {
        self.shared.settle();
        self.allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .map(|s| &s[..self.len as usize])
            .ok_or_else(|| Error::device(format!("buffer '{}' is not host-visible", self.name)))
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        self.shared.settle();
        unsafe { self.shared.device.destroy_buffer(self.raw, None) };
        if let (Some(a), Ok(mut guard)) = (self.allocation.take(), self.shared.allocator.lock()) {
            if let Some(alloc) = guard.as_mut() {
                let _ = alloc.free(a);
            }
        }
    }
}

/// A plain description of a 2-D image.
#[derive(Clone, Debug)]
pub struct ImageDesc {
    pub name: String,
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub mip_levels: u32,
    pub usage: vk::ImageUsageFlags,
    /// A cube map: six square layers (+x, -x, +y, -y, +z, -z), sampled as `samplerCube`, each
    /// mip level written as an `image2DArray` (layer = face).
    pub cube: bool,
    /// A second format the image is also viewed as (`vk::ImageCreateFlags::MUTABLE_FORMAT`, both
    /// listed in its format list), sampled through [`crate::vk::Resource::SampledAlias`]: e.g. an
    /// sRGB image's encoded bytes read as UNORM, without the sRGB decode. Same texel size.
    pub alias_format: Option<vk::Format>,
}

impl ImageDesc {
    pub fn new_2d(name: impl Into<String>, format: vk::Format, width: u32, height: u32) -> Self {
        ImageDesc {
            name: name.into(),
            format,
            width,
            height,
            mip_levels: 1,
            usage: vk::ImageUsageFlags::empty(),
            cube: false,
            alias_format: None,
        }
    }
    /// A cube map of `size` x `size` faces.
    pub fn new_cube(name: impl Into<String>, format: vk::Format, size: u32) -> Self {
        ImageDesc {
            cube: true,
            ..ImageDesc::new_2d(name, format, size, size)
        }
    }
    /// Array layers: 6 for a cube, else 1.
    pub fn layers(&self) -> u32 {
        if self.cube {
            6
        } else {
            1
        }
    }
    pub fn usage(mut self, usage: vk::ImageUsageFlags) -> Self {
        self.usage |= usage;
        self
    }
    /// Also viewed as `format` ([`ImageDesc::alias_format`]).
    pub fn alias(mut self, format: vk::Format) -> Self {
        self.alias_format = Some(format);
        self
    }
    /// A full mip chain down to 1x1.
    pub fn full_mips(mut self) -> Self {
        self.mip_levels = 32 - self.width.max(self.height).max(1).leading_zeros();
        self
    }
}

pub fn is_depth(format: vk::Format) -> bool {
    matches!(
        format,
        vk::Format::D32_SFLOAT
            | vk::Format::D16_UNORM
            | vk::Format::D24_UNORM_S8_UINT
            | vk::Format::D32_SFLOAT_S8_UINT
    )
}

/// Whether a depth format also has a stencil aspect.
pub fn has_stencil(format: vk::Format) -> bool {
    matches!(
        format,
        vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT
    )
}

/// Bytes per texel of the formats weft's buffer-image copies use; None for any other format.
/// Bytes of a `width` x `height` level of `format` tightly packed: texels, or 4 x 4 blocks of a
/// block-compressed format.
pub(crate) fn level_bytes(format: vk::Format, width: u32, height: u32) -> Option<u64> {
    match format {
        vk::Format::BC7_SRGB_BLOCK | vk::Format::BC7_UNORM_BLOCK => {
            Some(u64::from(width.div_ceil(4)) * u64::from(height.div_ceil(4)) * 16)
        }
        _ => Some(u64::from(width) * u64::from(height) * texel_bytes(format)?),
    }
}

pub(crate) fn texel_bytes(format: vk::Format) -> Option<u64> {
    use vk::Format as F;
    Some(match format {
        // (A depth-stencil format's depth aspect alone: what a copy of it reads.)
        F::R8G8B8A8_UNORM
        | F::R8G8B8A8_SRGB
        | F::D32_SFLOAT
        | F::D32_SFLOAT_S8_UINT
        | F::R32_SFLOAT => 4,
        F::D16_UNORM => 2,
        F::R16G16B16A16_SFLOAT | F::R16G16B16A16_UINT | F::R32G32_SFLOAT => 8,
        F::R32G32B32_SFLOAT => 12,
        F::R32G32B32A32_SFLOAT => 16,
        _ => return None,
    })
}

pub struct Image {
    shared: Arc<Shared>,
    pub(crate) raw: vk::Image,
    /// A view of every mip level.
    pub(crate) view: vk::ImageView,
    /// One view per mip level (for storage writes of a single level).
    pub(crate) mip_views: Vec<vk::ImageView>,
    /// A depth-stencil image's view of both aspects (its attachment view; `view`, of the depth
    /// alone, is what shaders sample); null for other images.
    pub(crate) attachment_view: vk::ImageView,
    /// The view of every mip level as `desc.alias_format`; null when it has none.
    pub(crate) alias_view: vk::ImageView,
    allocation: Option<Allocation>,
    pub desc: ImageDesc,
}

impl Image {
    pub fn extent(&self) -> (u32, u32) {
        (self.desc.width, self.desc.height)
    }
    /// The aspect its views sample and copies read: a depth-stencil image's depth.
    pub(crate) fn aspect(&self) -> vk::ImageAspectFlags {
        if is_depth(self.desc.format) {
            vk::ImageAspectFlags::DEPTH
        } else {
            vk::ImageAspectFlags::COLOR
        }
    }

    /// Every aspect (what a layout transition covers).
    pub(crate) fn full_aspect(&self) -> vk::ImageAspectFlags {
        if has_stencil(self.desc.format) {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        } else {
            self.aspect()
        }
    }

    /// The view a render pass attaches: both aspects of a depth-stencil image.
    pub(crate) fn attachment_view(&self) -> vk::ImageView {
        if self.attachment_view == vk::ImageView::null() {
            self.view
        } else {
            self.attachment_view
        }
    }

    /// The layout this image takes for a usage's generic `layout`: a depth-stencil image is read
    /// by shaders in DEPTH_STENCIL_READ_ONLY_OPTIMAL (so a pass can test its stencil while it
    /// samples its depth) and attached in DEPTH_STENCIL_ATTACHMENT_OPTIMAL.
    pub(crate) fn layout_for(&self, layout: vk::ImageLayout) -> vk::ImageLayout {
        if !has_stencil(self.desc.format) {
            return layout;
        }
        match layout {
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL => {
                vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL
            }
            vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL => {
                vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL
            }
            l => l,
        }
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        self.shared.settle();
        unsafe {
            for v in self.mip_views.drain(..) {
                self.shared.device.destroy_image_view(v, None);
            }
            for v in [self.attachment_view, self.alias_view] {
                if v != vk::ImageView::null() {
                    self.shared.device.destroy_image_view(v, None);
                }
            }
            self.shared.device.destroy_image_view(self.view, None);
            self.shared.device.destroy_image(self.raw, None);
        }
        if let (Some(a), Ok(mut guard)) = (self.allocation.take(), self.shared.allocator.lock()) {
            if let Some(alloc) = guard.as_mut() {
                let _ = alloc.free(a);
            }
        }
    }
}

pub struct Sampler {
    shared: Arc<Shared>,
    pub(crate) raw: vk::Sampler,
}

impl Drop for Sampler {
    fn drop(&mut self) {
        self.shared.settle();
        unsafe { self.shared.device.destroy_sampler(self.raw, None) };
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    /// Trilinear with anisotropy where the device has it; repeat addressing.
    LinearRepeat,
    /// Nearest texel, nearest mip; repeat addressing.
    NearestRepeat,
    /// Nearest, clamped: for reading render targets.
    NearestClamp,
    /// Trilinear, clamped, no anisotropy: cube maps (seamless across faces in Vulkan) and
    /// look-up tables.
    LinearClamp,
    /// Depth comparison for shadow maps (`sampler2DShadow`): bilinear over the 2 x 2 compare
    /// results, clamped; a texel passes where the reference depth is greater than or equal to it
    /// (reversed-Z: nearer to the light, or level with the nearest occluder).
    ShadowCompare,
}

/// Addressing outside [0, 1] of a [`TextureSamplerDesc`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Address {
    Repeat,
    ClampToEdge,
    MirroredRepeat,
}

/// A material texture's sampler (a glTF sampler): addressing per axis, texel filters, and the
/// mip filter (None: the base level only). Anisotropy where the device has it when every filter
/// is linear.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TextureSamplerDesc {
    pub address_u: Address,
    pub address_v: Address,
    pub mag_linear: bool,
    pub min_linear: bool,
    /// None: no mipmapping; Some(true): linear between levels; Some(false): nearest level.
    pub mip_linear: Option<bool>,
}

/// Timestamp queries, read back in nanoseconds.
pub struct QueryPool {
    shared: Arc<Shared>,
    pub(crate) raw: vk::QueryPool,
    pub count: u32,
}

impl QueryPool {
    /// Nanoseconds of each timestamp written so far (relative to an arbitrary origin).
    pub fn read_ns(&self, count: u32) -> crate::Result<Vec<f64>> {
        if count > self.count {
            return Err(Error::device(format!(
                "reading {count} timestamps from a pool of {}",
                self.count
            )));
        }
        let mut data = vec![0u64; count as usize];
        unsafe {
            self.shared.device.get_query_pool_results(
                self.raw,
                0,
                &mut data,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .map_err(vkerr("vkGetQueryPoolResults"))?;
        let period = self.shared.info.timestamp_period_ns as f64;
        Ok(data.iter().map(|&t| t as f64 * period).collect())
    }
}

impl Drop for QueryPool {
    fn drop(&mut self) {
        self.shared.settle();
        unsafe { self.shared.device.destroy_query_pool(self.raw, None) };
    }
}

impl Context {
    pub fn create_buffer(
        &self,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: BufferLocation,
    ) -> crate::Result<Buffer> {
        let len = size;
        let size = size.max(16);
        let device = &self.shared.device;
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        let raw = unsafe { device.create_buffer(&info, None) }.map_err(vkerr("vkCreateBuffer"))?;
        let requirements = unsafe { device.get_buffer_memory_requirements(raw) };
        let location = match location {
            BufferLocation::Upload => MemoryLocation::CpuToGpu,
            BufferLocation::Readback => MemoryLocation::GpuToCpu,
            BufferLocation::Device => MemoryLocation::GpuOnly,
        };
        let allocation = self
            .shared
            .allocator
            .lock()
            .map_err(|_| Error::device("allocator lock poisoned"))?
            .as_mut()
            .expect("allocator lives as long as the context")
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                unsafe { device.destroy_buffer(raw, None) };
                return Err(alloc_error(name, e));
            }
        };
        let buffer = Buffer {
            shared: self.shared.clone(),
            raw,
            allocation: Some(allocation),
            size,
            len,
            name: name.into(),
        };
        let a = buffer.allocation.as_ref().expect("just set");
        unsafe { device.bind_buffer_memory(raw, a.memory(), a.offset()) }
            .map_err(vkerr("vkBindBufferMemory"))?;
        Ok(buffer)
    }

    /// A host-visible buffer holding `data`.
    pub fn create_buffer_with<T: bytemuck::Pod>(
        &self,
        name: &str,
        usage: vk::BufferUsageFlags,
        data: &[T],
    ) -> crate::Result<Buffer> {
        let mut b = self.create_buffer(
            name,
            std::mem::size_of_val(data) as u64,
            usage,
            BufferLocation::Upload,
        )?;
        // Made just now: no submission in flight can name it, so nothing to wait for.
        b.write_fresh(0, data)?;
        Ok(b)
    }

    /// Fills every mip level of a freshly created `image` (in `Undefined` usage) from `levels`
    /// (level 0 first, each tightly packed) through staging buffers named `name`, and leaves it
    /// ready for fragment shaders to sample.
    pub fn fill_image_levels<L: AsRef<[u8]>>(
        &self,
        image: &Image,
        levels: &[L],
        name: &str,
    ) -> crate::Result<()> {
        let staging = levels
            .iter()
            .map(|bytes| {
                self.create_buffer_with(name, vk::BufferUsageFlags::TRANSFER_SRC, bytes.as_ref())
            })
            .collect::<crate::Result<Vec<_>>>()?;
        self.submit(|cmd| {
            cmd.transition(image, Usage::Undefined, Usage::TransferDst, None);
            for (level, buffer) in staging.iter().enumerate() {
                cmd.copy_buffer_to_image_level(buffer, image, level as u32);
            }
            cmd.transition(image, Usage::TransferDst, Usage::FragmentRead, None);
        })
    }

    pub fn create_image(&self, desc: &ImageDesc) -> crate::Result<Image> {
        let max = self.shared.info.max_image_dimension_2d;
        if desc.width == 0 || desc.height == 0 || desc.width > max || desc.height > max {
            return Err(Error::device(format!(
                "image '{}' of {}x{} is outside what the device '{}' supports (1 to {max} per side): choose a smaller --size",
                desc.name, desc.width, desc.height, self.shared.info.name
            )));
        }
        // Every image gets views (below), and Vulkan allows a view only of an image with a
        // view-capable usage.
        let viewable = vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT;
        if !desc.usage.intersects(viewable) {
            return Err(Error::device(format!(
                "image '{}' has usage {:?}: it needs one of SAMPLED, STORAGE, COLOR_ATTACHMENT \
                 or DEPTH_STENCIL_ATTACHMENT",
                desc.name, desc.usage
            )));
        }
        if desc.cube && desc.width != desc.height {
            return Err(Error::device(format!(
                "cube image '{}' must have square faces, not {}x{}",
                desc.name, desc.width, desc.height
            )));
        }
        let device = &self.shared.device;
        let mut flags = if desc.cube {
            vk::ImageCreateFlags::CUBE_COMPATIBLE
        } else {
            vk::ImageCreateFlags::empty()
        };
        let formats: Vec<vk::Format> = match desc.alias_format {
            Some(alias) => {
                // Vulkan lets a MUTABLE_FORMAT image be viewed in formats of its own compatibility
                // class, never a depth or stencil one; of the colour formats weft knows the size
                // of, those of one size share a class.
                if texel_bytes(alias) != texel_bytes(desc.format)
                    || texel_bytes(alias).is_none()
                    || is_depth(alias)
                    || is_depth(desc.format)
                {
                    return Err(Error::device(format!(
                        "image '{}': {alias:?} is not a view format of {:?}",
                        desc.name, desc.format
                    )));
                }
                flags |= vk::ImageCreateFlags::MUTABLE_FORMAT;
                vec![desc.format, alias]
            }
            None => Vec::new(),
        };
        let mut format_list = vk::ImageFormatListCreateInfo::default().view_formats(&formats);
        let mut info = vk::ImageCreateInfo::default()
            .flags(flags)
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D {
                width: desc.width,
                height: desc.height,
                depth: 1,
            })
            .mip_levels(desc.mip_levels)
            .array_layers(desc.layers())
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        if !formats.is_empty() {
            info = info.push_next(&mut format_list);
        }
        let raw = unsafe { device.create_image(&info, None) }.map_err(|e| match e {
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
                Error::device(format!(
                    "image '{}' of {}x{} does not fit in device memory: choose a smaller --size",
                    desc.name, desc.width, desc.height
                ))
            }
            other => Error::Vulkan {
                what: "vkCreateImage",
                result: other,
            },
        })?;
        let requirements = unsafe { device.get_image_memory_requirements(raw) };
        let allocation = self
            .shared
            .allocator
            .lock()
            .map_err(|_| Error::device("allocator lock poisoned"))?
            .as_mut()
            .expect("allocator lives as long as the context")
            .allocate(&AllocationCreateDesc {
                name: &desc.name,
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                unsafe { device.destroy_image(raw, None) };
                return Err(alloc_error(&desc.name, e));
            }
        };
        let mut image = Image {
            shared: self.shared.clone(),
            raw,
            view: vk::ImageView::null(),
            mip_views: Vec::new(),
            attachment_view: vk::ImageView::null(),
            alias_view: vk::ImageView::null(),
            allocation: Some(allocation),
            desc: desc.clone(),
        };
        let a = image.allocation.as_ref().expect("just set");
        unsafe { device.bind_image_memory(raw, a.memory(), a.offset()) }
            .map_err(vkerr("vkBindImageMemory"))?;
        let aspect = image.aspect();
        let layers = desc.layers();
        let make_format_view = |base: u32,
                                count: u32,
                                view_type: vk::ImageViewType,
                                aspect: vk::ImageAspectFlags,
                                format: vk::Format| {
            let info = vk::ImageViewCreateInfo::default()
                .image(raw)
                .view_type(view_type)
                .format(format)
                .subresource_range(vk::ImageSubresourceRange {
                    aspect_mask: aspect,
                    base_mip_level: base,
                    level_count: count,
                    base_array_layer: 0,
                    layer_count: layers,
                });
            unsafe { device.create_image_view(&info, None) }.map_err(vkerr("vkCreateImageView"))
        };
        let make_aspect_view =
            |base: u32, count: u32, view_type: vk::ImageViewType, aspect: vk::ImageAspectFlags| {
                make_format_view(base, count, view_type, aspect, desc.format)
            };
        let make_view = |base: u32, count: u32, view_type: vk::ImageViewType| {
            make_aspect_view(base, count, view_type, aspect)
        };
        let (sampled_type, storage_type) = if desc.cube {
            (vk::ImageViewType::CUBE, vk::ImageViewType::TYPE_2D_ARRAY)
        } else {
            (vk::ImageViewType::TYPE_2D, vk::ImageViewType::TYPE_2D)
        };
        image.view = make_view(0, desc.mip_levels, sampled_type)?;
        if has_stencil(desc.format) {
            image.attachment_view =
                make_aspect_view(0, desc.mip_levels, sampled_type, image.full_aspect())?;
        }
        if let Some(alias) = desc.alias_format {
            image.alias_view = make_format_view(0, desc.mip_levels, sampled_type, aspect, alias)?;
        }
        if (desc.mip_levels > 1 || desc.cube) && desc.usage.contains(vk::ImageUsageFlags::STORAGE) {
            for level in 0..desc.mip_levels {
                let v = make_view(level, 1, storage_type)?;
                image.mip_views.push(v);
            }
        }
        if self.shared.info.is_cpu() {
            write_first(&mut image);
        }
        Ok(image)
    }

    pub fn create_sampler(&self, filter: Filter) -> crate::Result<Sampler> {
        let (mag, mip, address, aniso) = match filter {
            Filter::LinearRepeat => (
                vk::Filter::LINEAR,
                vk::SamplerMipmapMode::LINEAR,
                vk::SamplerAddressMode::REPEAT,
                self.shared.anisotropy,
            ),
            Filter::NearestRepeat => (
                vk::Filter::NEAREST,
                vk::SamplerMipmapMode::NEAREST,
                vk::SamplerAddressMode::REPEAT,
                false,
            ),
            Filter::LinearClamp => (
                vk::Filter::LINEAR,
                vk::SamplerMipmapMode::LINEAR,
                vk::SamplerAddressMode::CLAMP_TO_EDGE,
                false,
            ),
            Filter::NearestClamp | Filter::ShadowCompare => (
                if filter == Filter::ShadowCompare {
                    vk::Filter::LINEAR
                } else {
                    vk::Filter::NEAREST
                },
                vk::SamplerMipmapMode::NEAREST,
                vk::SamplerAddressMode::CLAMP_TO_EDGE,
                false,
            ),
        };
        let max_aniso = self.shared.limits.max_sampler_anisotropy.min(16.0);
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(mag)
            .min_filter(mag)
            .mipmap_mode(mip)
            .address_mode_u(address)
            .address_mode_v(address)
            .address_mode_w(address)
            .anisotropy_enable(aniso)
            .max_anisotropy(if aniso { max_aniso } else { 1.0 })
            .min_lod(0.0)
            .max_lod(vk::LOD_CLAMP_NONE)
            .compare_enable(filter == Filter::ShadowCompare)
            .compare_op(vk::CompareOp::GREATER_OR_EQUAL);
        let raw = unsafe { self.shared.device.create_sampler(&info, None) }
            .map_err(vkerr("vkCreateSampler"))?;
        Ok(Sampler {
            shared: self.shared.clone(),
            raw,
        })
    }

    /// A sampler for a material texture ([`TextureSamplerDesc`]).
    pub fn create_texture_sampler(&self, desc: TextureSamplerDesc) -> crate::Result<Sampler> {
        let address = |a: Address| match a {
            Address::Repeat => vk::SamplerAddressMode::REPEAT,
            Address::ClampToEdge => vk::SamplerAddressMode::CLAMP_TO_EDGE,
            Address::MirroredRepeat => vk::SamplerAddressMode::MIRRORED_REPEAT,
        };
        let filter = |linear: bool| {
            if linear {
                vk::Filter::LINEAR
            } else {
                vk::Filter::NEAREST
            }
        };
        let aniso = self.shared.anisotropy
            && desc.mag_linear
            && desc.min_linear
            && desc.mip_linear == Some(true);
        let max_aniso = self.shared.limits.max_sampler_anisotropy.min(16.0);
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter(desc.mag_linear))
            .min_filter(filter(desc.min_linear))
            .mipmap_mode(if desc.mip_linear == Some(true) {
                vk::SamplerMipmapMode::LINEAR
            } else {
                vk::SamplerMipmapMode::NEAREST
            })
            .address_mode_u(address(desc.address_u))
            .address_mode_v(address(desc.address_v))
            .address_mode_w(address(desc.address_u))
            .anisotropy_enable(aniso)
            .max_anisotropy(if aniso { max_aniso } else { 1.0 })
            .min_lod(0.0)
            // glTF's NEAREST and LINEAR minification read the base level only (Vulkan's
            // equivalent of a non-mipmapped minFilter: maxLod 0.25 keeps magnification
            // distinguishable from minification, as the Vulkan spec recommends).
            .max_lod(if desc.mip_linear.is_none() {
                0.25
            } else {
                vk::LOD_CLAMP_NONE
            });
        let raw = unsafe { self.shared.device.create_sampler(&info, None) }
            .map_err(vkerr("vkCreateSampler"))?;
        Ok(Sampler {
            shared: self.shared.clone(),
            raw,
        })
    }

    /// A timestamp query pool, or None where the device has no timestamps.
    pub fn create_query_pool(&self, count: u32) -> crate::Result<Option<QueryPool>> {
        if !self.shared.info.timestamps {
            return Ok(None);
        }
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(count);
        let raw = unsafe { self.shared.device.create_query_pool(&info, None) }
            .map_err(vkerr("vkCreateQueryPool"))?;
        Ok(Some(QueryPool {
            shared: self.shared.clone(),
            raw,
            count,
        }))
    }
}

/// On a CPU device (lavapipe), touches every page of a fresh render target's memory with a write,
/// from the host, before any pass uses it. There the image's memory is fresh anonymous memory of
/// this process (mapped: lavapipe's one memory type is host-visible), and a render pass's first
/// write to a page is often a read first: llvmpipe's fragment code loads the destination to merge
/// a partly covered quad. A read maps the kernel's shared zero page, and the write after it must
/// replace that page and flush every core's TLB (an interrupt to each; in a virtual machine a
/// costly one). A write first faults each page in once with nothing to flush. Measured on 2 cores
/// (docs/performance.md "Time to the first picture"): the first frame's G-buffer pass 300 -> 180
/// ms (169 warm), lighting 352 -> 261 (256 warm). The contents need not survive: every pass
/// starts a target from `Usage::Undefined` or clears it. A real GPU's memory is not the process's,
/// and is not touched.
fn write_first(image: &mut Image) {
    let target = vk::ImageUsageFlags::COLOR_ATTACHMENT
        | vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
        | vk::ImageUsageFlags::STORAGE;
    if !image.desc.usage.intersects(target) {
        return;
    }
    if let Some(bytes) = image.allocation.as_mut().and_then(|a| a.mapped_slice_mut()) {
        const PAGE: usize = 4096;
        for b in bytes.iter_mut().step_by(PAGE) {
            *b = 0;
        }
        if let Some(last) = bytes.last_mut() {
            *last = 0;
        }
    }
}
