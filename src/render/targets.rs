//! The render targets of one resolution (the G-buffer, depth, HDR and 8-bit output, and the
//! intermediates some passes add), their formats, and the memory check made before they exist.

use crate::vk::{Context, Format, Image, ImageDesc, ImageUsageFlags};
use crate::Error;

pub const ALBEDO_FORMAT: Format = Format::R8G8B8A8_SRGB;
/// Normal + tangent, octahedral, explicitly rounded 16-bit integers (frame.glsl's frame_encode).
pub const FRAME_FORMAT: Format = Format::R16G16B16A16_UINT;
pub const SURFACE_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
pub const FABRIC_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
pub const EMISSIVE_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
/// The dielectric specular layer (KHR_materials_specular): rgb F0, a: specular weight.
pub const SPECULAR_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
/// The G-buffer's depth: 32-bit float depth, with an 8-bit stencil where the device has
/// D32_SFLOAT_S8_UINT (the G-buffer marks each pixel's kind of material there, and the lighting
/// pass shades each kind by a pipeline of its own: `passes::lighting`).
pub fn depth_format(ctx: &Context) -> Format {
    if ctx.info().depth_stencil {
        Format::D32_SFLOAT_S8_UINT
    } else {
        Format::D32_SFLOAT
    }
}
pub const HDR_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
pub const LDR_FORMAT: Format = Format::R8G8B8A8_SRGB;
/// The tone-mapped image's bytes undecoded (its alias view, which FXAA takes luma from).
pub const LDR_ENCODED_FORMAT: Format = Format::R8G8B8A8_UNORM;
pub const WEAVE_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
/// The weave's summed-area table (`--weave-precision sat`): f32, fetched (never filtered).
pub const WEAVE_SAT_FORMAT: Format = Format::R32G32B32A32_SFLOAT;
pub const WEAVE_FORMAT_8: Format = Format::R8G8B8A8_UNORM;
pub const SHADOW_FORMAT: Format = Format::D32_SFLOAT;
/// fabric_lobes.frag's lobe sums per pixel (fabric_lobe_pack: each lobe's mean radiance as
/// RGB9E5, both weights as bfloat16, the pooling mask), which the lighting pass pools.
pub const LOBES_FORMAT: Format = Format::R32G32B32A32_UINT;
/// The occlusion pass's estimates and their blur (visibility, view distance; half resolution).
pub const OCCLUSION_FORMAT: Format = Format::R16G16_SFLOAT;
/// The occlusion pass's bounced light (rgb: irradiance/π from the occluders), half resolution.
pub const OCCLUSION_BOUNCE_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
/// The occlusion pass's half-resolution depth (each 2 x 2 block's top-left pixel's, exactly).
pub const OCCLUSION_DEPTH_FORMAT: Format = Format::R32_SFLOAT;
/// Each 2 x 2 block's top-left pixel as an occluder (occlusion_depth.frag's occluder_light_pack:
/// its diffuse light as three f32, its octahedral normal as the G-buffer stores it), half
/// resolution, which the occlusion estimates read for the bounce.
pub const OCCLUSION_LIGHT_FORMAT: Format = Format::R32G32B32A32_UINT;
/// The same depth as a depth attachment, which the estimates and their blur are drawn against
/// (at the far plane, depth test LESS) so that they run only where a surface is.
pub const OCCLUSION_COVERAGE_FORMAT: Format = Format::D32_SFLOAT;

/// The G-buffer and output targets of one resolution.
pub(crate) struct Targets {
    pub(crate) albedo: Image,
    pub(crate) frame: Image,
    pub(crate) surface: Image,
    pub(crate) fabric: Image,
    pub(crate) emissive: Image,
    pub(crate) specular: Image,
    pub(crate) depth: Image,
    /// The lit image in linear radiance (made by the first frame whose plan reads it: none
    /// where the lighting pass tone-maps, `Plan::tone_in_lighting`); [`Targets::hdr`].
    pub(crate) hdr_image: Option<Image>,
    pub(crate) ldr: Image,
    /// The lit opaque image with box-filtered mips, for transmissive surfaces (made by the first
    /// frame that has one).
    pub(crate) backdrop: Option<Image>,
    /// The tone-mapped image before edge anti-aliasing (made by the first frame that plans the
    /// anti-aliasing pass).
    pub(crate) tonemapped: Option<Image>,
    /// The occlusion pass's per-pixel estimates and their blur (made by the first frame that
    /// plans the pass).
    pub(crate) occlusion: Option<OcclusionTargets>,
    /// The fabric lobes' sums before the lighting pools them (made by the first frame that pools).
    pub(crate) lobes: Option<Image>,
}

/// The occlusion pass's three targets.
pub(crate) struct OcclusionTargets {
    /// The G-buffer's depth per 2 x 2 pixels (`OCCLUSION_DEPTH_FORMAT`, half the resolution
    /// rounded up), which the estimates' depth samples read.
    pub(crate) depth: Image,
    /// The same pixels as occluders (`OCCLUSION_LIGHT_FORMAT`; written with the bounce only).
    pub(crate) light: Image,
    /// The same depth as a depth attachment (`OCCLUSION_COVERAGE_FORMAT`): a fullscreen draw at
    /// the far plane with depth test LESS passes where a surface is and nowhere else.
    pub(crate) coverage: Image,
    /// Visibility and view distance per 2 x 2 pixels (`OCCLUSION_FORMAT`, half the resolution
    /// rounded up).
    pub(crate) raw: Image,
    /// The same blurred, which the lighting pass reads.
    pub(crate) visibility: Image,
    /// The occluders' bounced light per 2 x 2 pixels (`OCCLUSION_BOUNCE_FORMAT`; 0 without the
    /// bounce), and the same blurred, which the lighting pass reads.
    pub(crate) raw_bounce: Image,
    pub(crate) bounce: Image,
}

impl OcclusionTargets {
    pub(crate) fn new(ctx: &Context, width: u32, height: u32) -> crate::Result<OcclusionTargets> {
        let usage = ImageUsageFlags::COLOR_ATTACHMENT | ImageUsageFlags::SAMPLED;
        let (w, h) = (width.div_ceil(2), height.div_ceil(2));
        Ok(OcclusionTargets {
            depth: ctx.create_image(
                &ImageDesc::new_2d("occlusion depth", OCCLUSION_DEPTH_FORMAT, w, h).usage(usage),
            )?,
            light: ctx.create_image(
                &ImageDesc::new_2d("occluder light", OCCLUSION_LIGHT_FORMAT, w, h).usage(usage),
            )?,
            coverage: ctx.create_image(
                &ImageDesc::new_2d("occlusion coverage", OCCLUSION_COVERAGE_FORMAT, w, h)
                    .usage(ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT),
            )?,
            raw: ctx.create_image(
                &ImageDesc::new_2d("occlusion estimates", OCCLUSION_FORMAT, w, h).usage(usage),
            )?,
            visibility: ctx.create_image(
                &ImageDesc::new_2d("occlusion", OCCLUSION_FORMAT, w, h).usage(usage),
            )?,
            raw_bounce: ctx.create_image(
                &ImageDesc::new_2d("occlusion bounce estimates", OCCLUSION_BOUNCE_FORMAT, w, h)
                    .usage(usage),
            )?,
            bounce: ctx.create_image(
                &ImageDesc::new_2d("occlusion bounce", OCCLUSION_BOUNCE_FORMAT, w, h).usage(usage),
            )?,
        })
    }
}

impl Targets {
    pub(crate) fn new(ctx: &Context, width: u32, height: u32) -> crate::Result<Targets> {
        let color = ImageUsageFlags::COLOR_ATTACHMENT | ImageUsageFlags::SAMPLED;
        let read = ImageUsageFlags::TRANSFER_SRC;
        let t = |name: &str, format: Format, usage: ImageUsageFlags| {
            ctx.create_image(&ImageDesc::new_2d(name, format, width, height).usage(usage))
        };
        Ok(Targets {
            albedo: t("gbuffer albedo", ALBEDO_FORMAT, color | read)?,
            frame: t("gbuffer normal+tangent", FRAME_FORMAT, color | read)?,
            surface: t("gbuffer surface", SURFACE_FORMAT, color | read)?,
            fabric: t("gbuffer fabric coverage", FABRIC_FORMAT, color | read)?,
            emissive: t("gbuffer emissive", EMISSIVE_FORMAT, color | read)?,
            specular: t("gbuffer specular", SPECULAR_FORMAT, color | read)?,
            depth: t(
                "gbuffer depth",
                depth_format(ctx),
                ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | ImageUsageFlags::SAMPLED | read,
            )?,
            hdr_image: None,
            ldr: t("ldr", LDR_FORMAT, ImageUsageFlags::COLOR_ATTACHMENT | read)?,
            backdrop: None,
            tonemapped: None,
            occlusion: None,
            lobes: None,
        })
    }

    /// The HDR target (`HDR_FORMAT`), which the frame makes where its plan writes or reads it
    /// (every plan but one whose lighting pass tone-maps).
    pub(crate) fn hdr(&self) -> &Image {
        self.hdr_image
            .as_ref()
            .expect("the frame makes the HDR target where its plan uses it")
    }

    /// Makes the HDR target if it is not made yet.
    pub(crate) fn make_hdr(&mut self, ctx: &Context) -> crate::Result<()> {
        if self.hdr_image.is_none() {
            let (width, height) = self.ldr.extent();
            self.hdr_image = Some(ctx.create_image(
                &ImageDesc::new_2d("hdr", HDR_FORMAT, width, height).usage(
                    ImageUsageFlags::COLOR_ATTACHMENT
                        | ImageUsageFlags::SAMPLED
                        | ImageUsageFlags::TRANSFER_SRC,
                ),
            )?);
        }
        Ok(())
    }

    /// Where the tone-mapped 8-bit image is written (by the tonemap pass, or by the lighting
    /// pass where it tone-maps): the anti-aliasing pass's input when it follows (`antialiased`,
    /// the target made), else the output.
    pub(crate) fn tone_mapped_target(&self, antialiased: bool) -> &Image {
        match (&self.tonemapped, antialiased) {
            (Some(i), true) => i,
            _ => &self.ldr,
        }
    }

    pub(crate) fn gbuffer_colors(&self) -> [&Image; 6] {
        [
            &self.albedo,
            &self.frame,
            &self.surface,
            &self.fabric,
            &self.emissive,
            &self.specular,
        ]
    }
}

/// Bytes a pixel of the render targets takes on the device (six G-buffer targets, depth and
/// stencil, which drivers keep as 8 bytes, HDR, LDR: 64).
pub const TARGET_BYTES_PER_PIXEL: u64 = 4 + 8 + 8 + 8 + 8 + 8 + 8 + 8 + 4;

/// Bytes a pixel of the readback takes in host memory: the LDR buffer and its copy (4 + 4), and
/// with `read_hdr` the half-float buffer and the f32 image (8 + 16).
pub fn readback_bytes_per_pixel(read_hdr: bool) -> u64 {
    8 + if read_hdr { 24 } else { 0 }
}

/// The memory the host can still give (MemAvailable of /proc/meminfo), where known.
pub fn host_available_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// Refuses, before any target is created, a frame size the device cannot hold: a side beyond
/// maxImageDimension2D, render targets beyond the device's largest device-local heap, or, on a
/// CPU device, targets and readback beyond 90 % of the memory the host has available. A CPU device's
/// "device memory" is system memory: its heap size is nominal (lavapipe reports 2 GiB and
/// allocates beyond it), and an allocation too large is met by the kernel's OOM killer rather
/// than an error, so there the host's available memory is the bound.
pub fn check_target_memory(
    info: &crate::vk::DeviceInfo,
    host_available: Option<u64>,
    width: u32,
    height: u32,
    read_hdr: bool,
) -> crate::Result<()> {
    let max = info.max_image_dimension_2d;
    if width > max || height > max {
        return Err(Error::device(format!(
            "--size {width}x{height} is larger than the device '{}' supports ({max} pixels a side): choose a smaller --size",
            info.name
        )));
    }
    let gib = |b: u64| b as f64 / f64::from(1u32 << 30);
    let pixels = u64::from(width) * u64::from(height);
    let targets = pixels * TARGET_BYTES_PER_PIXEL;
    let heap = info.device_local_heap_bytes;
    if !info.is_cpu() && heap > 0 && targets > heap {
        return Err(Error::device(format!(
            "--size {width}x{height} needs {:.1} GiB of device memory for its render targets ({TARGET_BYTES_PER_PIXEL} bytes a pixel); the device '{}' has {:.1} GiB: choose a smaller --size",
            gib(targets),
            info.name,
            gib(heap)
        )));
    }
    if info.is_cpu() {
        if let Some(available) = host_available {
            let total = targets + pixels * readback_bytes_per_pixel(read_hdr);
            // A tenth kept back for what the estimate leaves out: the scene, its textures and
            // buffers, pipelines, the allocator's slack, the rest of the process.
            if total > available / 10 * 9 {
                return Err(Error::device(format!(
                    "--size {width}x{height} needs {:.1} GiB of memory for its render targets and readback on the CPU device '{}'; the system has {:.1} GiB available (weft plans for at most 90 % of it): choose a smaller --size, or close other programs",
                    gib(total),
                    info.name,
                    gib(available)
                )));
            }
        }
    }
    Ok(())
}
