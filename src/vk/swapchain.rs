//! Presenting to a window (`weft view`): the surface, the swapchain, frames in flight, and the
//! panel, drawn by egui-ash-renderer into the same command buffer.
//!
//! A frame: the renderer's passes run as one submission that is not waited for
//! (`Renderer::render_frame_overlapped`: the next frame waits for it, after recording itself);
//! then one short submission, not waited for either, copies its tonemapped image into this frame
//! slot's own copy (in the renderer's queue order, and its last barrier orders the renderer's
//! next writes to the image after its reads, so the next frame's tonemap pass cannot overwrite it
//! under a blit still in flight); then one submission that is not waited for blits that copy into
//! the acquired swapchain image, draws the panel over it and presents. [`FRAMES_IN_FLIGHT`] such
//! submissions may be in flight: the CPU waits only when it comes back to a frame slot whose
//! submission has not finished.

use std::any::Any;
use std::sync::Arc;
use std::time::Instant;

use ash::vk;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};

use super::context::{vkerr, Context};
use super::resources::{Buffer, BufferLocation, Image, ImageDesc};
use super::Usage;
use crate::Error;

/// Present submissions that may be in flight at once.
pub const FRAMES_IN_FLIGHT: usize = 2;

/// The panel to draw over the scene: egui's tessellated output for this frame.
pub struct PanelDraw<'a> {
    pub primitives: &'a [egui::ClippedPrimitive],
    pub textures: &'a egui::TexturesDelta,
    pub pixels_per_point: f32,
}

/// What [`Presenter::present`] did.
#[derive(Debug, Default)]
pub struct Presented {
    /// False when the swapchain no longer fits the window (resized, or suboptimal): call
    /// [`Presenter::resize`] and draw again.
    pub presented: bool,
    /// CPU time spent waiting: for the frame slot's previous submission (the frames-in-flight
    /// wait), and for the copy of the renderer's image.
    pub slot_wait_ms: f64,
    pub copy_ms: f64,
    /// The presented image (panel included), RGBA8 sRGB, rows top to bottom, when asked for.
    pub screenshot: Option<(u32, u32, Vec<u8>)>,
}

struct Slot {
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    acquired: vk::Semaphore,
    /// The submission copying the renderer's image into `source` (not waited for: the slot's
    /// fence, of the present submission after it in queue order, covers it too).
    copy: Option<super::InFlight>,
    /// This frame's copy of the renderer's tonemapped image.
    source: Option<Image>,
    /// egui textures to free once this slot's submission is done.
    free: Vec<egui::TextureId>,
}

pub struct Presenter {
    ctx: Context,
    surface_fn: ash::khr::surface::Instance,
    swapchain_fn: ash::khr::swapchain::Device,
    surface: vk::SurfaceKHR,
    swapchain: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    views: Vec<vk::ImageView>,
    /// Signalled by the submission that draws into swapchain image i, waited by its present (one
    /// per image: a present may still be waiting on one when the next frame starts).
    rendered: Vec<vk::Semaphore>,
    format: vk::Format,
    extent: vk::Extent2D,
    screenshots: bool,
    pool: vk::CommandPool,
    slots: Vec<Slot>,
    current: usize,
    egui: Option<egui_ash_renderer::Renderer>,
    /// The window the surface belongs to, kept alive until the surface is destroyed.
    _window: Arc<dyn Any + Send + Sync>,
}

impl Presenter {
    /// A surface and swapchain for `window` (of the display `ctx` was made for, see
    /// [`Context::new_for_display`]), `width` x `height` pixels.
    pub fn new<W>(
        ctx: &Context,
        window: Arc<W>,
        width: u32,
        height: u32,
    ) -> crate::Result<Presenter>
    where
        W: HasWindowHandle + HasDisplayHandle + Send + Sync + 'static,
    {
        let sh = &ctx.shared;
        let handle_err = |e: raw_window_handle::HandleError| {
            Error::device(format!("the window has no usable handle: {e}"))
        };
        let display = window.display_handle().map_err(handle_err)?.as_raw();
        let win = window.window_handle().map_err(handle_err)?.as_raw();
        // SAFETY: the handles are of a live window, which `_window` keeps alive until Drop has
        // destroyed the surface; the instance was made with this display's extensions.
        let surface =
            unsafe { ash_window::create_surface(&sh.entry, &sh.instance, display, win, None) }
                .map_err(vkerr("vkCreateSurfaceKHR"))?;
        let surface_fn = ash::khr::surface::Instance::new(&sh.entry, &sh.instance);
        let supported = unsafe {
            surface_fn.get_physical_device_surface_support(sh.physical, sh.queue_family, surface)
        }
        .unwrap_or(false);
        if !supported {
            unsafe { surface_fn.destroy_surface(surface, None) };
            return Err(Error::device(format!(
                "the Vulkan device '{}' cannot present to this window: choose another with --device, or use weft render",
                sh.info.name
            )));
        }
        let swapchain_fn = ash::khr::swapchain::Device::new(&sh.instance, &sh.device);
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(sh.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let pool = match unsafe { sh.device.create_command_pool(&pool_info, None) } {
            Ok(p) => p,
            Err(e) => {
                unsafe { surface_fn.destroy_surface(surface, None) };
                return Err(vkerr("vkCreateCommandPool")(e));
            }
        };
        let mut p = Presenter {
            ctx: ctx.clone(),
            surface_fn,
            swapchain_fn,
            surface,
            swapchain: vk::SwapchainKHR::null(),
            images: Vec::new(),
            views: Vec::new(),
            rendered: Vec::new(),
            format: vk::Format::UNDEFINED,
            extent: vk::Extent2D { width, height },
            screenshots: false,
            pool,
            slots: Vec::new(),
            current: 0,
            egui: None,
            _window: window,
        };
        // From here on Drop cleans up whatever was made.
        let dev = &p.ctx.shared.device;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(FRAMES_IN_FLIGHT as u32);
        let cmds = unsafe { dev.allocate_command_buffers(&alloc) }
            .map_err(vkerr("vkAllocateCommandBuffers"))?;
        for cmd in cmds {
            let fence = unsafe {
                dev.create_fence(
                    &vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED),
                    None,
                )
            }
            .map_err(vkerr("vkCreateFence"))?;
            let acquired = match unsafe { dev.create_semaphore(&Default::default(), None) } {
                Ok(s) => s,
                Err(e) => {
                    unsafe { dev.destroy_fence(fence, None) };
                    return Err(vkerr("vkCreateSemaphore")(e));
                }
            };
            p.slots.push(Slot {
                cmd,
                fence,
                acquired,
                copy: None,
                source: None,
                free: Vec::new(),
            });
        }
        p.create_swapchain(width, height)?;
        let srgb = matches!(
            p.format,
            vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB
        );
        // egui-ash-renderer compiles its pipeline here and destroys it on drop: on lavapipe, like
        // weft's own pipelines, only with the queue idle and locked (Shared::compile_lock;
        // without it `weft view` with its panel aborted with heap corruption at 128-bit vectors,
        // docs/regression.md "Driver configurations").
        let compiling = p.ctx.shared.compile_lock()?;
        let egui = egui_ash_renderer::Renderer::with_default_allocator(
            &p.ctx.shared.instance,
            p.ctx.shared.physical,
            p.ctx.shared.device.clone(),
            egui_ash_renderer::DynamicRendering {
                color_attachment_format: p.format,
                depth_attachment_format: None,
            },
            egui_ash_renderer::Options {
                in_flight_frames: FRAMES_IN_FLIGHT,
                enable_depth_test: false,
                enable_depth_write: false,
                srgb_framebuffer: srgb,
            },
        )
        .map_err(|e| Error::device(format!("creating the panel's renderer failed: {e}")))?;
        drop(compiling);
        p.egui = Some(egui);
        Ok(p)
    }

    pub fn extent(&self) -> (u32, u32) {
        (self.extent.width, self.extent.height)
    }

    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// Makes the swapchain again for a window now `width` x `height` (waits for the device).
    pub fn resize(&mut self, width: u32, height: u32) -> crate::Result<()> {
        self.ctx.wait_idle()?;
        self.create_swapchain(width, height)
    }

    fn create_swapchain(&mut self, width: u32, height: u32) -> crate::Result<()> {
        let sh = &self.ctx.shared;
        let caps = unsafe {
            self.surface_fn
                .get_physical_device_surface_capabilities(sh.physical, self.surface)
        }
        .map_err(vkerr("vkGetPhysicalDeviceSurfaceCapabilitiesKHR"))?;
        let formats = unsafe {
            self.surface_fn
                .get_physical_device_surface_formats(sh.physical, self.surface)
        }
        .map_err(vkerr("vkGetPhysicalDeviceSurfaceFormatsKHR"))?;
        // An sRGB format first: the renderer's image is sRGB-encoded, and a blit between two
        // sRGB formats keeps the values; a UNORM one gets a bit-exact copy instead (see present).
        let pick = [
            vk::Format::B8G8R8A8_SRGB,
            vk::Format::R8G8B8A8_SRGB,
            vk::Format::B8G8R8A8_UNORM,
            vk::Format::R8G8B8A8_UNORM,
        ];
        let format = pick
            .iter()
            .find_map(|f| {
                formats
                    .iter()
                    .find(|s| s.format == *f && s.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)
            })
            .copied()
            .ok_or_else(|| {
                Error::device(format!(
                    "the window offers no 8-bit RGBA/BGRA swapchain format (it offers {:?})",
                    formats.iter().map(|f| f.format).collect::<Vec<_>>()
                ))
            })?;
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        if extent.width == 0 || extent.height == 0 {
            return Err(Error::device("the window has no area (minimised?)"));
        }
        let mut count = (caps.min_image_count + 1).max(FRAMES_IN_FLIGHT as u32 + 1);
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        self.screenshots = caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_SRC);
        let mut usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_DST;
        if self.screenshots {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        let old = self.swapchain;
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            // FIFO: always there, and paced by the display (the frame loop's timing is then the
            // renderer's unless it is faster than the display).
            .present_mode(vk::PresentModeKHR::FIFO)
            .clipped(true)
            .old_swapchain(old);
        let swapchain = unsafe { self.swapchain_fn.create_swapchain(&info, None) }
            .map_err(vkerr("vkCreateSwapchainKHR"))?;
        self.destroy_swapchain_objects();
        if old != vk::SwapchainKHR::null() {
            unsafe { self.swapchain_fn.destroy_swapchain(old, None) };
        }
        self.swapchain = swapchain;
        self.format = format.format;
        self.extent = extent;
        self.images = unsafe { self.swapchain_fn.get_swapchain_images(swapchain) }
            .map_err(vkerr("vkGetSwapchainImagesKHR"))?;
        let dev = &self.ctx.shared.device;
        for &image in &self.images {
            let view_info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(format.format)
                .subresource_range(color_range());
            self.views.push(
                unsafe { dev.create_image_view(&view_info, None) }
                    .map_err(vkerr("vkCreateImageView"))?,
            );
            self.rendered.push(
                unsafe { dev.create_semaphore(&Default::default(), None) }
                    .map_err(vkerr("vkCreateSemaphore"))?,
            );
        }
        Ok(())
    }

    fn destroy_swapchain_objects(&mut self) {
        let dev = &self.ctx.shared.device;
        for v in self.views.drain(..) {
            unsafe { dev.destroy_image_view(v, None) };
        }
        for s in self.rendered.drain(..) {
            unsafe { dev.destroy_semaphore(s, None) };
        }
        self.images.clear();
    }

    /// Shows `scene` (the renderer's tonemapped image, in `ColorAttachment` usage, as the tonemap
    /// pass leaves it) from column `x0` of the window on (the panel's width; the rest is cleared),
    /// with the panel over it, and with `screenshot` reads the presented image back. `scene` is
    /// copied before this returns, so the renderer may draw the next frame into it at once.
    pub fn present(
        &mut self,
        scene: &Image,
        x0: u32,
        panel: Option<PanelDraw>,
        screenshot: bool,
    ) -> crate::Result<Presented> {
        if screenshot && !self.screenshots {
            return Err(Error::device(
                "this window's swapchain images cannot be read back (no TRANSFER_SRC usage): screenshots are not available",
            ));
        }
        let mut out = Presented::default();
        let ctx = self.ctx.clone();
        let sh = &ctx.shared;
        let dev = &sh.device;
        let slot_index = self.current;

        // The slot's previous submission: the only wait of the frames in flight.
        let t = Instant::now();
        let fence = self.slots[slot_index].fence;
        unsafe { dev.wait_for_fences(&[fence], true, u64::MAX) }
            .map_err(vkerr("vkWaitForFences"))?;
        // Its copy came before it in queue order: done, so this frees its command buffer.
        if let Some(copy) = self.slots[slot_index].copy.take() {
            copy.wait()?;
        }
        out.slot_wait_ms = t.elapsed().as_secs_f64() * 1e3;
        if let Some(egui) = self.egui.as_mut() {
            let free = std::mem::take(&mut self.slots[slot_index].free);
            if !free.is_empty() {
                // The other slot's submission, in flight, may still draw with them.
                let fences: Vec<vk::Fence> = self.slots.iter().map(|s| s.fence).collect();
                unsafe { dev.wait_for_fences(&fences, true, u64::MAX) }
                    .map_err(vkerr("vkWaitForFences"))?;
            }
            egui.free_textures(&free)
                .map_err(|e| Error::device(format!("freeing the panel's textures failed: {e}")))?;
        }

        // This slot's copy of the scene image: same bits, in a format whose blit to the
        // swapchain keeps them (sRGB to sRGB, or UNORM to UNORM).
        let srgb = matches!(
            self.format,
            vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB
        );
        let source_format = if srgb {
            vk::Format::R8G8B8A8_SRGB
        } else {
            vk::Format::R8G8B8A8_UNORM
        };
        let fits = self.slots[slot_index]
            .source
            .as_ref()
            .is_some_and(|s| s.extent() == scene.extent() && s.desc.format == source_format);
        if !fits {
            self.slots[slot_index].source = None;
            let (w, h) = scene.extent();
            self.slots[slot_index].source = Some(ctx.create_image(
                &ImageDesc::new_2d("view frame copy", source_format, w, h).usage(
                    // SAMPLED only because every weft image gets a view.
                    vk::ImageUsageFlags::TRANSFER_DST
                        | vk::ImageUsageFlags::TRANSFER_SRC
                        | vk::ImageUsageFlags::SAMPLED,
                ),
            )?);
        }
        let t = Instant::now();
        {
            let source = self.slots[slot_index].source.as_ref().expect("made above");
            // Not waited for: the renderer's next frame is ordered after it by the last
            // barrier (its writes to `scene` wait for the copy's reads), and the present
            // submission below by the one before it.
            let copy = ctx
                .record(|cmd| {
                    cmd.transition(scene, Usage::ColorAttachment, Usage::TransferSrc, None);
                    cmd.transition(source, Usage::Undefined, Usage::TransferDst, None);
                    cmd.copy_image(scene, source);
                    cmd.transition(source, Usage::TransferDst, Usage::TransferSrc, None);
                    cmd.transition(scene, Usage::TransferSrc, Usage::ColorAttachment, None);
                })?
                .submit()?;
            self.slots[slot_index].copy = Some(copy);
        }
        out.copy_ms = t.elapsed().as_secs_f64() * 1e3;

        // The panel's new textures (egui-ash-renderer uploads them with a submission of its own
        // on the shared queue, which must not be used by two threads at once).
        if let (Some(egui), Some(p)) = (self.egui.as_mut(), panel.as_ref()) {
            if !p.textures.set.is_empty() {
                let _queue = sh
                    .queue_lock
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                egui.set_textures(sh.queue, self.pool, &p.textures.set)
                    .map_err(|e| {
                        Error::device(format!("uploading the panel's textures failed: {e}"))
                    })?;
            }
            self.slots[slot_index].free = p.textures.free.clone();
        }

        let slot = &self.slots[slot_index];
        let acquired = unsafe {
            self.swapchain_fn.acquire_next_image(
                self.swapchain,
                u64::MAX,
                slot.acquired,
                vk::Fence::null(),
            )
        };
        let (image_index, suboptimal) = match acquired {
            Ok(r) => r,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => return Ok(out),
            Err(e) => return Err(vkerr("vkAcquireNextImageKHR")(e)),
        };
        let i = image_index as usize;
        let (image, view) = (self.images[i], self.views[i]);
        let extent = self.extent;
        let source = slot.source.as_ref().expect("made above");
        let readback = if screenshot {
            Some(ctx.create_buffer(
                "view screenshot",
                u64::from(extent.width) * u64::from(extent.height) * 4,
                vk::BufferUsageFlags::TRANSFER_DST,
                BufferLocation::Readback,
            )?)
        } else {
            None
        };

        let cmd = slot.cmd;
        unsafe {
            dev.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())
                .map_err(vkerr("vkResetCommandBuffer"))?;
            dev.begin_command_buffer(
                cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )
            .map_err(vkerr("vkBeginCommandBuffer"))?;
        }
        use vk::{AccessFlags2 as A, ImageLayout as L, PipelineStageFlags2 as S};
        let barrier = |from: (L, S, A), to: (L, S, A)| {
            let b = [vk::ImageMemoryBarrier2::default()
                .src_stage_mask(from.1)
                .src_access_mask(from.2)
                .dst_stage_mask(to.1)
                .dst_access_mask(to.2)
                .old_layout(from.0)
                .new_layout(to.0)
                .image(image)
                .subresource_range(color_range())];
            unsafe {
                dev.cmd_pipeline_barrier2(
                    cmd,
                    &vk::DependencyInfo::default().image_memory_barriers(&b),
                )
            };
        };
        // The acquire semaphore is waited at ALL_TRANSFER; the first barrier's source scope is
        // that stage, so the layout change happens after the image is free.
        barrier(
            (L::UNDEFINED, S::ALL_TRANSFER, A::NONE),
            (L::TRANSFER_DST_OPTIMAL, S::ALL_TRANSFER, A::TRANSFER_WRITE),
        );
        let clear = vk::ClearColorValue {
            float32: [0.0, 0.0, 0.0, 1.0],
        };
        unsafe {
            dev.cmd_clear_color_image(
                cmd,
                image,
                L::TRANSFER_DST_OPTIMAL,
                &clear,
                &[color_range()],
            )
        };
        let clear_done = [vk::MemoryBarrier2::default()
            .src_stage_mask(S::ALL_TRANSFER)
            .src_access_mask(A::TRANSFER_WRITE)
            .dst_stage_mask(S::ALL_TRANSFER)
            .dst_access_mask(A::TRANSFER_WRITE)];
        unsafe {
            dev.cmd_pipeline_barrier2(
                cmd,
                &vk::DependencyInfo::default().memory_barriers(&clear_done),
            )
        };
        let x0 = x0.min(extent.width.saturating_sub(1));
        let (sw, shh) = source.extent();
        let blit = vk::ImageBlit::default()
            .src_subresource(color_layers())
            .src_offsets([
                vk::Offset3D::default(),
                vk::Offset3D {
                    x: sw as i32,
                    y: shh as i32,
                    z: 1,
                },
            ])
            .dst_subresource(color_layers())
            .dst_offsets([
                vk::Offset3D {
                    x: x0 as i32,
                    y: 0,
                    z: 0,
                },
                vk::Offset3D {
                    x: extent.width as i32,
                    y: extent.height as i32,
                    z: 1,
                },
            ]);
        unsafe {
            dev.cmd_blit_image(
                cmd,
                source.raw,
                L::TRANSFER_SRC_OPTIMAL,
                image,
                L::TRANSFER_DST_OPTIMAL,
                &[blit],
                vk::Filter::NEAREST,
            )
        };
        barrier(
            (L::TRANSFER_DST_OPTIMAL, S::ALL_TRANSFER, A::TRANSFER_WRITE),
            (
                L::COLOR_ATTACHMENT_OPTIMAL,
                S::COLOR_ATTACHMENT_OUTPUT,
                A::COLOR_ATTACHMENT_READ | A::COLOR_ATTACHMENT_WRITE,
            ),
        );
        if let (Some(egui), Some(p)) = (self.egui.as_mut(), panel.as_ref()) {
            let attachment = [vk::RenderingAttachmentInfo::default()
                .image_view(view)
                .image_layout(L::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::LOAD)
                .store_op(vk::AttachmentStoreOp::STORE)];
            let rendering = vk::RenderingInfo::default()
                .render_area(vk::Rect2D {
                    offset: vk::Offset2D::default(),
                    extent,
                })
                .layer_count(1)
                .color_attachments(&attachment);
            unsafe { dev.cmd_begin_rendering(cmd, &rendering) };
            let drawn = egui.cmd_draw(cmd, extent, p.pixels_per_point, p.primitives);
            unsafe { dev.cmd_end_rendering(cmd) };
            drawn.map_err(|e| Error::device(format!("drawing the panel failed: {e}")))?;
        }
        let color = (
            L::COLOR_ATTACHMENT_OPTIMAL,
            S::COLOR_ATTACHMENT_OUTPUT,
            A::COLOR_ATTACHMENT_WRITE,
        );
        if let Some(buffer) = &readback {
            barrier(
                color,
                (L::TRANSFER_SRC_OPTIMAL, S::ALL_TRANSFER, A::TRANSFER_READ),
            );
            let region = vk::BufferImageCopy::default()
                .image_subresource(color_layers())
                .image_extent(vk::Extent3D {
                    width: extent.width,
                    height: extent.height,
                    depth: 1,
                });
            unsafe {
                dev.cmd_copy_image_to_buffer(
                    cmd,
                    image,
                    L::TRANSFER_SRC_OPTIMAL,
                    buffer.raw,
                    &[region],
                )
            };
            let host = [vk::MemoryBarrier2::default()
                .src_stage_mask(S::ALL_TRANSFER)
                .src_access_mask(A::TRANSFER_WRITE)
                .dst_stage_mask(S::HOST)
                .dst_access_mask(A::HOST_READ)];
            unsafe {
                dev.cmd_pipeline_barrier2(
                    cmd,
                    &vk::DependencyInfo::default().memory_barriers(&host),
                )
            };
            barrier(
                (L::TRANSFER_SRC_OPTIMAL, S::ALL_TRANSFER, A::NONE),
                (L::PRESENT_SRC_KHR, S::NONE, A::NONE),
            );
        } else {
            barrier(color, (L::PRESENT_SRC_KHR, S::NONE, A::NONE));
        }
        unsafe { dev.end_command_buffer(cmd) }.map_err(vkerr("vkEndCommandBuffer"))?;

        let waits = [vk::SemaphoreSubmitInfo::default()
            .semaphore(slot.acquired)
            .stage_mask(S::ALL_TRANSFER)];
        let signals = [vk::SemaphoreSubmitInfo::default()
            .semaphore(self.rendered[i])
            .stage_mask(S::ALL_COMMANDS)];
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = [vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signals)];
        let present_result = {
            let _queue = sh
                .queue_lock
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            unsafe { dev.reset_fences(&[slot.fence]) }.map_err(vkerr("vkResetFences"))?;
            unsafe { dev.queue_submit2(sh.queue, &submit, slot.fence) }
                .map_err(vkerr("vkQueueSubmit2"))?;
            sh.submissions
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let wait = [self.rendered[i]];
            let swapchains = [self.swapchain];
            let indices = [image_index];
            let present = vk::PresentInfoKHR::default()
                .wait_semaphores(&wait)
                .swapchains(&swapchains)
                .image_indices(&indices);
            unsafe { self.swapchain_fn.queue_present(sh.queue, &present) }
        };
        self.current = (self.current + 1) % FRAMES_IN_FLIGHT;
        out.presented = match present_result {
            Ok(sub) => !(sub || suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => false,
            Err(e) => return Err(vkerr("vkQueuePresentKHR")(e)),
        };
        if let Some(buffer) = readback {
            unsafe { dev.wait_for_fences(&[slot.fence], true, u64::MAX) }
                .map_err(vkerr("vkWaitForFences"))?;
            out.screenshot = Some((extent.width, extent.height, to_rgba(self.format, buffer)?));
        }
        ctx.check_validation()?;
        Ok(out)
    }
}

fn to_rgba(format: vk::Format, buffer: Buffer) -> crate::Result<Vec<u8>> {
    let mut bytes = buffer.read()?.to_vec();
    if matches!(
        format,
        vk::Format::B8G8R8A8_SRGB | vk::Format::B8G8R8A8_UNORM
    ) {
        for px in bytes.chunks_exact_mut(4) {
            px.swap(0, 2);
        }
    }
    // The window is opaque: what the swapchain holds in alpha is not what is shown.
    for px in bytes.chunks_exact_mut(4) {
        px[3] = 255;
    }
    Ok(bytes)
}

fn color_range() -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    }
}

fn color_layers() -> vk::ImageSubresourceLayers {
    vk::ImageSubresourceLayers {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        mip_level: 0,
        base_array_layer: 0,
        layer_count: 1,
    }
}

impl Drop for Presenter {
    fn drop(&mut self) {
        let _ = self.ctx.wait_idle();
        // egui's buffers and textures first (its pipeline destroyed under the compile lock, as it
        // was made), then this module's objects, then the surface.
        {
            let ctx = self.ctx.clone();
            let _compiling = ctx.shared.compile_lock();
            self.egui = None;
        }
        self.destroy_swapchain_objects();
        let dev = &self.ctx.shared.device;
        unsafe {
            for s in self.slots.drain(..) {
                dev.destroy_fence(s.fence, None);
                dev.destroy_semaphore(s.acquired, None);
            }
            dev.destroy_command_pool(self.pool, None);
            if self.swapchain != vk::SwapchainKHR::null() {
                self.swapchain_fn.destroy_swapchain(self.swapchain, None);
            }
            self.surface_fn.destroy_surface(self.surface, None);
        }
    }
}
