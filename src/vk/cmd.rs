//! Command recording: a safe wrapper over one command buffer, and one-shot submission.
//!
//! Image layouts are named by what the image is used for next ([`Usage`]); a transition is a
//! synchronization2 barrier from one usage to another.

use std::marker::PhantomData;

use ash::vk;

use super::context::{vkerr, Context, Shared};
use super::pipeline::{DescriptorSet, Pipeline};
use super::resources::{has_stencil, level_bytes, texel_bytes, Buffer, Image, QueryPool};

/// How an image is used, which fixes its layout, stages and access.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Usage {
    Undefined,
    ColorAttachment,
    DepthAttachment,
    /// Sampled in fragment shaders.
    FragmentRead,
    /// Sampled in compute shaders.
    ComputeRead,
    /// Written as a storage image in compute shaders.
    ComputeWrite,
    TransferSrc,
    TransferDst,
}

impl Usage {
    fn parts(self) -> (vk::ImageLayout, vk::PipelineStageFlags2, vk::AccessFlags2) {
        use vk::{AccessFlags2 as A, ImageLayout as L, PipelineStageFlags2 as S};
        match self {
            Usage::Undefined => (L::UNDEFINED, S::TOP_OF_PIPE, A::NONE),
            Usage::ColorAttachment => (
                L::COLOR_ATTACHMENT_OPTIMAL,
                S::COLOR_ATTACHMENT_OUTPUT,
                A::COLOR_ATTACHMENT_WRITE | A::COLOR_ATTACHMENT_READ,
            ),
            Usage::DepthAttachment => (
                L::DEPTH_ATTACHMENT_OPTIMAL,
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_WRITE | A::DEPTH_STENCIL_ATTACHMENT_READ,
            ),
            Usage::FragmentRead => (
                L::SHADER_READ_ONLY_OPTIMAL,
                S::FRAGMENT_SHADER,
                A::SHADER_SAMPLED_READ,
            ),
            Usage::ComputeRead => (
                L::SHADER_READ_ONLY_OPTIMAL,
                S::COMPUTE_SHADER,
                A::SHADER_SAMPLED_READ,
            ),
            Usage::ComputeWrite => (
                L::GENERAL,
                S::COMPUTE_SHADER,
                A::SHADER_STORAGE_WRITE | A::SHADER_STORAGE_READ,
            ),
            Usage::TransferSrc => (L::TRANSFER_SRC_OPTIMAL, S::ALL_TRANSFER, A::TRANSFER_READ),
            Usage::TransferDst => (L::TRANSFER_DST_OPTIMAL, S::ALL_TRANSFER, A::TRANSFER_WRITE),
        }
    }
}

/// One attachment of a dynamic-rendering pass: the image and what the pass starts from.
pub struct Attachment<'a> {
    pub image: &'a Image,
    pub load: Load,
}

/// What a dynamic-rendering pass starts an attachment from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Load {
    /// Cleared to this value (depth: the first component; stencil 0).
    Clear([f32; 4]),
    /// As the image holds it.
    Keep,
    /// Anything (`LOAD_OP_DONT_CARE`): for a target every pixel a later pass reads is written
    /// first (a driver need not clear it; lavapipe's clear of a 1080p RGBA16F target is ~5 ms).
    Undefined,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cull {
    None,
    Back,
    Front,
}

/// A command buffer being recorded.
pub struct Cmd<'s> {
    shared: &'s Shared,
    raw: vk::CommandBuffer,
    /// Invariant in `'s`: a `&mut Cmd<'s>` cannot be shortened to accept resources that live
    /// less than the submission.
    _submission: PhantomData<fn(&'s ()) -> &'s ()>,
}

impl<'s> Cmd<'s> {
    fn device(&self) -> &ash::Device {
        &self.shared.device
    }

    /// Barrier: `image` (mips `levels`, or all when None) goes from `from` to `to`.
    pub fn transition(
        &mut self,
        image: &'s Image,
        from: Usage,
        to: Usage,
        levels: Option<(u32, u32)>,
    ) {
        let (old_layout, src_stage, src_access) = from.parts();
        let (new_layout, dst_stage, dst_access) = to.parts();
        let (old_layout, new_layout) = (image.layout_for(old_layout), image.layout_for(new_layout));
        // A depth-stencil image read by shaders may also be a read-only attachment whose stencil
        // a pass tests (begin_rendering_stencil_test): its reads include the fragment tests'.
        let tests = |layout: vk::ImageLayout, stage, access| {
            if layout == vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL {
                (
                    stage
                        | vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS
                        | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS,
                    access | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ,
                )
            } else {
                (stage, access)
            }
        };
        let (src_stage, src_access) = tests(old_layout, src_stage, src_access);
        let (dst_stage, dst_access) = tests(new_layout, dst_stage, dst_access);
        let (base, count) = levels.unwrap_or((0, image.desc.mip_levels));
        let barrier = vk::ImageMemoryBarrier2::default()
            .src_stage_mask(src_stage)
            .src_access_mask(src_access)
            .dst_stage_mask(dst_stage)
            .dst_access_mask(dst_access)
            .old_layout(old_layout)
            .new_layout(new_layout)
            .image(image.raw)
            .subresource_range(vk::ImageSubresourceRange {
                aspect_mask: image.full_aspect(),
                base_mip_level: base,
                level_count: count,
                base_array_layer: 0,
                layer_count: image.desc.layers(),
            });
        let barriers = [barrier];
        let dep = vk::DependencyInfo::default().image_memory_barriers(&barriers);
        unsafe { self.device().cmd_pipeline_barrier2(self.raw, &dep) };
    }

    /// A global memory barrier: `src` stages' `src_access` before `dst` stages' `dst_access`.
    fn memory_barrier(
        &mut self,
        (src, src_access): (vk::PipelineStageFlags2, vk::AccessFlags2),
        (dst, dst_access): (vk::PipelineStageFlags2, vk::AccessFlags2),
    ) {
        let barrier = [vk::MemoryBarrier2::default()
            .src_stage_mask(src)
            .src_access_mask(src_access)
            .dst_stage_mask(dst)
            .dst_access_mask(dst_access)];
        let dep = vk::DependencyInfo::default().memory_barriers(&barrier);
        unsafe { self.device().cmd_pipeline_barrier2(self.raw, &dep) };
    }

    /// Makes transfer writes to buffers (a readback copy) visible to host reads after the
    /// submission's fence.
    pub fn buffer_barrier(&mut self) {
        self.memory_barrier(
            (
                vk::PipelineStageFlags2::ALL_TRANSFER,
                vk::AccessFlags2::TRANSFER_WRITE,
            ),
            (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ),
        );
    }

    /// Orders a compute pass that rewrites vertex data after earlier vertex-input reads of it
    /// (write after read: an execution dependency).
    pub fn vertex_reads_before_compute(&mut self) {
        self.memory_barrier(
            (
                vk::PipelineStageFlags2::VERTEX_ATTRIBUTE_INPUT,
                vk::AccessFlags2::NONE,
            ),
            (
                vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::NONE,
            ),
        );
    }

    /// Makes compute-shader writes to buffers visible to later vertex-input reads and to host
    /// reads after the submission's fence (a posed vertex buffer).
    pub fn compute_writes_before_vertex_reads(&mut self) {
        self.memory_barrier(
            (
                vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::SHADER_STORAGE_WRITE,
            ),
            (
                vk::PipelineStageFlags2::VERTEX_ATTRIBUTE_INPUT | vk::PipelineStageFlags2::HOST,
                vk::AccessFlags2::VERTEX_ATTRIBUTE_READ | vk::AccessFlags2::HOST_READ,
            ),
        );
    }

    /// Begins dynamic rendering over the full extent of the first attachment, and sets the
    /// viewport and scissor to it.
    pub fn begin_rendering(&mut self, colors: &[Attachment<'s>], depth: Option<Attachment<'s>>) {
        let extent = colors
            .first()
            .or(depth.as_ref())
            .map(|a| a.image.extent())
            .unwrap_or((1, 1));
        let attachment = |a: &Attachment, layout: vk::ImageLayout, depth: bool| {
            let clear = match (a.load, depth) {
                (Load::Clear(c), false) => vk::ClearValue {
                    color: vk::ClearColorValue { float32: c },
                },
                (Load::Clear(c), true) => vk::ClearValue {
                    depth_stencil: vk::ClearDepthStencilValue {
                        depth: c[0],
                        stencil: 0,
                    },
                },
                _ => vk::ClearValue::default(),
            };
            vk::RenderingAttachmentInfo::default()
                .image_view(a.image.attachment_view())
                .image_layout(a.image.layout_for(layout))
                .load_op(match a.load {
                    Load::Clear(_) => vk::AttachmentLoadOp::CLEAR,
                    Load::Keep => vk::AttachmentLoadOp::LOAD,
                    Load::Undefined => vk::AttachmentLoadOp::DONT_CARE,
                })
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(clear)
        };
        let color_infos: Vec<_> = colors
            .iter()
            .map(|a| attachment(a, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, false))
            .collect();
        let depth_info = depth
            .as_ref()
            .map(|a| attachment(a, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, true));
        let mut info = vk::RenderingInfo::default()
            .layer_count(1)
            .color_attachments(&color_infos);
        if let Some(d) = depth_info.as_ref() {
            info = info.depth_attachment(d);
            if depth
                .as_ref()
                .is_some_and(|a| has_stencil(a.image.desc.format))
            {
                info = info.stencil_attachment(d);
            }
        }
        self.begin(info, extent);
    }

    /// Begins a dynamic-rendering pass into `colors` (loaded) that tests the stencil of the
    /// depth-stencil image `depth_stencil` without writing it, while the pass's shaders may sample
    /// its depth: both read-only, in DEPTH_STENCIL_READ_ONLY_OPTIMAL (its `Usage::FragmentRead`).
    pub fn begin_rendering_stencil_test(&mut self, colors: &[&'s Image], depth_stencil: &'s Image) {
        let extent = depth_stencil.extent();
        let color_infos: Vec<_> = colors
            .iter()
            .map(|image| {
                vk::RenderingAttachmentInfo::default()
                    .image_view(image.view)
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(vk::AttachmentLoadOp::LOAD)
                    .store_op(vk::AttachmentStoreOp::STORE)
            })
            .collect();
        let ds = vk::RenderingAttachmentInfo::default()
            .image_view(depth_stencil.attachment_view())
            .image_layout(vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::NONE);
        let info = vk::RenderingInfo::default()
            .layer_count(1)
            .color_attachments(&color_infos)
            .depth_attachment(&ds)
            .stencil_attachment(&ds);
        self.begin(info, extent);
    }

    /// The stencil reference value of the draws that follow (pipelines that write or test the
    /// stencil take it from here).
    pub fn set_stencil_reference(&mut self, reference: u32) {
        unsafe {
            self.device().cmd_set_stencil_reference(
                self.raw,
                vk::StencilFaceFlags::FRONT_AND_BACK,
                reference,
            )
        };
    }

    /// Begins `info` over the whole of attachments `extent` pixels large (its render area), with
    /// the viewport and scissor the same and the default cull and front face.
    fn begin(&mut self, info: vk::RenderingInfo, extent: (u32, u32)) {
        let area = vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: vk::Extent2D {
                width: extent.0,
                height: extent.1,
            },
        };
        let info = info.render_area(area);
        unsafe {
            self.device().cmd_begin_rendering(self.raw, &info);
            let viewport = vk::Viewport {
                x: 0.0,
                y: 0.0,
                width: extent.0 as f32,
                height: extent.1 as f32,
                min_depth: 0.0,
                max_depth: 1.0,
            };
            self.device().cmd_set_viewport(self.raw, 0, &[viewport]);
            self.device().cmd_set_scissor(self.raw, 0, &[area]);
            self.device()
                .cmd_set_cull_mode(self.raw, vk::CullModeFlags::NONE);
            self.device()
                .cmd_set_front_face(self.raw, vk::FrontFace::COUNTER_CLOCKWISE);
        }
    }

    /// Restricts drawing to the rectangle (x, y, width, height) of the attachments: viewport and
    /// scissor both.
    pub fn set_viewport(&mut self, x: u32, y: u32, width: u32, height: u32) {
        let viewport = vk::Viewport {
            x: x as f32,
            y: y as f32,
            width: width as f32,
            height: height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        let scissor = vk::Rect2D {
            offset: vk::Offset2D {
                x: x as i32,
                y: y as i32,
            },
            extent: vk::Extent2D { width, height },
        };
        unsafe {
            self.device().cmd_set_viewport(self.raw, 0, &[viewport]);
            self.device().cmd_set_scissor(self.raw, 0, &[scissor]);
        }
    }

    pub fn end_rendering(&mut self) {
        unsafe { self.device().cmd_end_rendering(self.raw) };
    }

    pub fn set_cull(&mut self, cull: Cull) {
        let mode = match cull {
            Cull::None => vk::CullModeFlags::NONE,
            Cull::Back => vk::CullModeFlags::BACK,
            Cull::Front => vk::CullModeFlags::FRONT,
        };
        unsafe { self.device().cmd_set_cull_mode(self.raw, mode) };
    }

    /// Which winding is a front face for the following draws: counter-clockwise (the default at
    /// each `begin_rendering`), or clockwise for a draw whose world transform mirrors it (a
    /// negative determinant: glTF's rule), so that culling and `gl_FrontFacing` see its true
    /// outside.
    pub fn set_front_face(&mut self, mirrored: bool) {
        let face = if mirrored {
            vk::FrontFace::CLOCKWISE
        } else {
            vk::FrontFace::COUNTER_CLOCKWISE
        };
        unsafe { self.device().cmd_set_front_face(self.raw, face) };
    }

    pub fn bind_pipeline(&mut self, pipeline: &'s Pipeline) {
        unsafe {
            self.device()
                .cmd_bind_pipeline(self.raw, pipeline.bind_point, pipeline.raw)
        };
    }

    pub fn bind_sets(&mut self, pipeline: &'s Pipeline, first: u32, sets: &[DescriptorSet<'s>]) {
        let raw: Vec<_> = sets.iter().map(|s| s.raw).collect();
        unsafe {
            self.device().cmd_bind_descriptor_sets(
                self.raw,
                pipeline.bind_point,
                pipeline.layout,
                first,
                &raw,
                &[],
            )
        };
    }

    pub fn push_constants<T: bytemuck::Pod>(&mut self, pipeline: &'s Pipeline, value: &T) {
        let bytes = bytemuck::bytes_of(value);
        unsafe {
            self.device().cmd_push_constants(
                self.raw,
                pipeline.layout,
                pipeline.push_stages,
                0,
                bytes,
            )
        };
    }

    pub fn bind_vertex_buffer(&mut self, buffer: &'s Buffer) {
        unsafe {
            self.device()
                .cmd_bind_vertex_buffers(self.raw, 0, &[buffer.raw], &[0])
        };
    }

    pub fn bind_index_buffer(&mut self, buffer: &'s Buffer) {
        unsafe {
            self.device()
                .cmd_bind_index_buffer(self.raw, buffer.raw, 0, vk::IndexType::UINT32)
        };
    }

    pub fn draw(&mut self, vertices: u32) {
        unsafe { self.device().cmd_draw(self.raw, vertices, 1, 0, 0) };
    }

    pub fn draw_indexed(&mut self, index_count: u32, first_index: u32, vertex_offset: i32) {
        unsafe {
            self.device()
                .cmd_draw_indexed(self.raw, index_count, 1, first_index, vertex_offset, 0)
        };
    }

    pub fn dispatch(&mut self, x: u32, y: u32, z: u32) {
        unsafe { self.device().cmd_dispatch(self.raw, x, y, z) };
    }

    /// Copies a buffer into mip 0 of an image in `TransferDst` usage.
    ///
    /// # Panics
    /// If the buffer is smaller than the image's level 0 (the GPU would read past its end), or
    /// the format is not one [`level_bytes`] knows.
    pub fn copy_buffer_to_image(&mut self, buffer: &'s Buffer, image: &'s Image) {
        self.copy_buffer_to_image_level(buffer, image, 0);
    }

    /// Copies a buffer (tightly packed) into mip `level` of an image in `TransferDst` usage.
    ///
    /// # Panics
    /// If `level` is not a level of the image, the buffer is smaller than that level (the GPU
    /// would read past its end), or the format is not one [`level_bytes`] knows.
    pub fn copy_buffer_to_image_level(&mut self, buffer: &'s Buffer, image: &'s Image, level: u32) {
        check_copy_size(buffer, image, level);
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: image.aspect(),
                mip_level: level,
                base_array_layer: 0,
                layer_count: image.desc.layers(),
            })
            .image_extent(vk::Extent3D {
                width: (image.desc.width >> level).max(1),
                height: (image.desc.height >> level).max(1),
                depth: 1,
            });
        unsafe {
            self.device().cmd_copy_buffer_to_image(
                self.raw,
                buffer.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
    }

    /// Copies mip `level` of an image in `TransferSrc` usage into a buffer, tightly packed.
    ///
    /// # Panics
    /// If `level` is not a level of the image, or the buffer is too small for it (the GPU would
    /// write past its end).
    pub fn copy_image_to_buffer(&mut self, image: &'s Image, level: u32, buffer: &'s Buffer) {
        check_copy_size(buffer, image, level);
        let w = (image.desc.width >> level).max(1);
        let h = (image.desc.height >> level).max(1);
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: image.aspect(),
                mip_level: level,
                base_array_layer: 0,
                layer_count: image.desc.layers(),
            })
            .image_extent(vk::Extent3D {
                width: w,
                height: h,
                depth: 1,
            });
        unsafe {
            self.device().cmd_copy_image_to_buffer(
                self.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer.raw,
                &[region],
            )
        };
    }

    /// Fills mips 1.. of an image whose mip 0 is in `TransferDst` usage by successive linear blits;
    /// leaves the whole image in `to` usage.
    pub fn generate_mips(&mut self, image: &'s Image, to: Usage) {
        let levels = image.desc.mip_levels;
        let (mut w, mut h) = (image.desc.width as i32, image.desc.height as i32);
        for level in 1..levels {
            self.transition(
                image,
                Usage::TransferDst,
                Usage::TransferSrc,
                Some((level - 1, 1)),
            );
            self.transition(
                image,
                Usage::Undefined,
                Usage::TransferDst,
                Some((level, 1)),
            );
            let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
            let layers = |mip_level| vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level,
                base_array_layer: 0,
                layer_count: image.desc.layers(),
            };
            let blit = vk::ImageBlit::default()
                .src_subresource(layers(level - 1))
                .src_offsets([vk::Offset3D::default(), vk::Offset3D { x: w, y: h, z: 1 }])
                .dst_subresource(layers(level))
                .dst_offsets([vk::Offset3D::default(), vk::Offset3D { x: nw, y: nh, z: 1 }]);
            unsafe {
                self.device().cmd_blit_image(
                    self.raw,
                    image.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    image.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[blit],
                    vk::Filter::LINEAR,
                )
            };
            self.transition(image, Usage::TransferSrc, to, Some((level - 1, 1)));
            (w, h) = (nw, nh);
        }
        self.transition(image, Usage::TransferDst, to, Some((levels - 1, 1)));
    }

    /// Copies mip 0 of `src` (in `TransferSrc` usage) into mip 0 of `dst` (in `TransferDst`) bit
    /// for bit: the formats must have the same texel size (e.g. RGBA8 sRGB into RGBA8 UNORM).
    ///
    /// # Panics
    /// If the two level-0 sizes or texel sizes differ.
    pub fn copy_image(&mut self, src: &'s Image, dst: &'s Image) {
        assert_eq!(src.extent(), dst.extent(), "copy_image: sizes differ");
        assert_eq!(
            texel_bytes(src.desc.format),
            texel_bytes(dst.desc.format),
            "copy_image: texel sizes differ"
        );
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: src.aspect(),
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let region = vk::ImageCopy::default()
            .src_subresource(layers)
            .dst_subresource(layers)
            .extent(vk::Extent3D {
                width: src.desc.width,
                height: src.desc.height,
                depth: 1,
            });
        unsafe {
            self.device().cmd_copy_image(
                self.raw,
                src.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
    }

    /// Copies mip `level` of `src` (in `TransferSrc` usage) into the same level of `dst` (in
    /// `TransferDst`), converting the format; both levels must have the same size.
    pub fn blit_level(&mut self, src: &'s Image, dst: &'s Image, level: u32) {
        let w = (src.desc.width >> level).max(1) as i32;
        let h = (src.desc.height >> level).max(1) as i32;
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: level,
            base_array_layer: 0,
            layer_count: src.desc.layers().min(dst.desc.layers()),
        };
        let region = vk::ImageBlit::default()
            .src_subresource(layers)
            .src_offsets([vk::Offset3D::default(), vk::Offset3D { x: w, y: h, z: 1 }])
            .dst_subresource(layers)
            .dst_offsets([vk::Offset3D::default(), vk::Offset3D { x: w, y: h, z: 1 }]);
        unsafe {
            self.device().cmd_blit_image(
                self.raw,
                src.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
                vk::Filter::NEAREST,
            )
        };
    }

    pub fn reset_queries(&mut self, pool: &'s QueryPool) {
        unsafe {
            self.device()
                .cmd_reset_query_pool(self.raw, pool.raw, 0, pool.count)
        };
    }

    /// Writes a timestamp once all previously submitted work has finished.
    ///
    /// # Panics
    /// If `index` is not a query of the pool.
    pub fn timestamp(&mut self, pool: &'s QueryPool, index: u32) {
        assert!(
            index < pool.count,
            "timestamp {index} of a pool of {}",
            pool.count
        );
        unsafe {
            self.device().cmd_write_timestamp2(
                self.raw,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                pool.raw,
                index,
            )
        };
    }
}

/// Panics unless `buffer` holds mip `level` of `image` (all layers), tightly packed.
fn check_copy_size(buffer: &Buffer, image: &Image, level: u32) {
    assert!(
        level < image.desc.mip_levels,
        "copy of mip level {level} of image '{}', which has {}",
        image.desc.name,
        image.desc.mip_levels
    );
    let w = (image.desc.width >> level).max(1);
    let h = (image.desc.height >> level).max(1);
    let need = level_bytes(image.desc.format, w, h).unwrap_or_else(|| {
        panic!(
            "buffer copies of format {:?} (image '{}') are not supported",
            image.desc.format, image.desc.name
        )
    }) * u64::from(image.desc.layers());
    assert!(
        buffer.size >= need,
        "buffer '{}' of {} bytes is too small for level {level} of image '{}' ({need} bytes)",
        buffer.name,
        buffer.size,
        image.desc.name
    );
}

impl Context {
    /// Records commands with `record`, submits them, and waits for the GPU to finish.
    ///
    /// Every resource a command names (buffers, images, pipelines, descriptor sets, query pools)
    /// is borrowed for `'s`, a lifetime that outlives this call: the borrow checker keeps each one
    /// alive until the GPU has finished with it. Dropping a recorded resource inside `record`
    /// does not compile:
    ///
    /// ```compile_fail,E0505
    /// # fn misuse(ctx: &weft::vk::Context) -> weft::Result<()> {
    /// use weft::vk::{BufferLocation, BufferUsageFlags};
    /// let vertices = ctx.create_buffer("v", 64, BufferUsageFlags::VERTEX_BUFFER, BufferLocation::Device)?;
    /// ctx.submit(|cmd| {
    ///     cmd.bind_vertex_buffer(&vertices);
    ///     drop(vertices); // freed before the command buffer runs
    /// })?;
    /// # Ok(()) }
    /// ```
    ///
    /// nor does recording a resource that is created (and so freed) inside `record`:
    ///
    /// ```compile_fail,E0597
    /// # fn misuse(ctx: &weft::vk::Context) -> weft::Result<()> {
    /// use weft::vk::{BufferLocation, BufferUsageFlags};
    /// ctx.submit(|cmd| {
    ///     let vertices = ctx
    ///         .create_buffer("v", 64, BufferUsageFlags::VERTEX_BUFFER, BufferLocation::Device)
    ///         .unwrap();
    ///     cmd.bind_vertex_buffer(&vertices);
    /// })?;
    /// # Ok(()) }
    /// ```
    ///
    /// The same code with the buffer alive for the whole submission compiles (the controls for
    /// the two above: stable rustdoc does not check a `compile_fail` test's error code):
    ///
    /// ```no_run
    /// # fn fine(ctx: &weft::vk::Context) -> weft::Result<()> {
    /// use weft::vk::{BufferLocation, BufferUsageFlags};
    /// let vertices = ctx.create_buffer("v", 64, BufferUsageFlags::VERTEX_BUFFER, BufferLocation::Device)?;
    /// ctx.submit(|cmd| cmd.bind_vertex_buffer(&vertices))?;
    /// drop(vertices); // after the fence: fine
    /// # Ok(()) }
    /// ```
    pub fn submit<'s, R>(&'s self, record: impl FnOnce(&mut Cmd<'s>) -> R) -> crate::Result<R> {
        let device = &self.shared.device;
        // The pool and the queue are shared by every thread holding this context: one submission
        // at a time (declared before `guard`, so it is released after the buffer is freed). The
        // lock guards no data: a panic in an earlier `record` (a [`Cmd`] check) poisons it but
        // leaves nothing half-done, since `guard` freed that command buffer unsubmitted.
        let _queue = self
            .shared
            .queue_lock
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.shared.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let raw = unsafe { device.allocate_command_buffers(&alloc) }
            .map_err(vkerr("vkAllocateCommandBuffers"))?[0];
        struct Free<'a>(&'a Shared, vk::CommandBuffer, vk::Fence);
        impl Drop for Free<'_> {
            fn drop(&mut self) {
                unsafe {
                    if self.2 != vk::Fence::null() {
                        self.0.device.destroy_fence(self.2, None);
                    }
                    self.0
                        .device
                        .free_command_buffers(self.0.command_pool, &[self.1]);
                }
            }
        }
        let mut guard = Free(&self.shared, raw, vk::Fence::null());
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        unsafe { device.begin_command_buffer(raw, &begin) }
            .map_err(vkerr("vkBeginCommandBuffer"))?;
        let mut cmd = Cmd {
            shared: &self.shared,
            raw,
            _submission: PhantomData,
        };
        let result = record(&mut cmd);
        unsafe { device.end_command_buffer(raw) }.map_err(vkerr("vkEndCommandBuffer"))?;
        let fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }
            .map_err(vkerr("vkCreateFence"))?;
        guard.2 = fence;
        let cmd_infos = [vk::CommandBufferSubmitInfo::default().command_buffer(raw)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmd_infos)];
        unsafe { device.queue_submit2(self.shared.queue, &submit, fence) }
            .map_err(vkerr("vkQueueSubmit2"))?;
        self.shared
            .submissions
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        unsafe { device.wait_for_fences(&[fence], true, u64::MAX) }
            .map_err(vkerr("vkWaitForFences"))?;
        Ok(result)
    }
}

/// Commands recorded by [`Context::record`], not yet submitted: the resources they name stay
/// borrowed for `'s` until [`Recording::submit`]. Dropped unsubmitted, the command buffer is freed.
pub struct Recording<'s> {
    ctx: &'s Context,
    raw: vk::CommandBuffer,
}

/// A submission in flight ([`Recording::submit`]): its command buffer and fence. It borrows
/// nothing: from the submission on, what keeps the resources its commands name alive is that
/// every resource waits for all submissions in flight before it is destroyed (and host access to
/// a buffer waits too; `Shared::settle`). [`InFlight::wait`] waits for the fence and frees the
/// command buffer; dropping it does the same.
pub struct InFlight {
    shared: std::sync::Arc<Shared>,
    raw: vk::CommandBuffer,
    fence: vk::Fence,
}

impl Context {
    /// Records commands with `record` into a command buffer of its own, without submitting them
    /// ([`Recording::submit`]): so that a frame can be recorded while the previous one runs.
    /// Every resource a command names is borrowed for `'s`, as with [`Context::submit`].
    pub fn record<'s>(&'s self, record: impl FnOnce(&mut Cmd<'s>)) -> crate::Result<Recording<'s>> {
        let device = &self.shared.device;
        // The command pool is shared: allocation and recording hold the queue lock.
        let lock = || {
            self.shared
                .queue_lock
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
        };
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.shared.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let raw = {
            let _queue = lock();
            unsafe { device.allocate_command_buffers(&alloc) }
                .map_err(vkerr("vkAllocateCommandBuffers"))?[0]
        };
        // Frees the buffer on an early return or a panic in `record` (its Drop takes the queue
        // lock, so it is declared before the guard below, and dropped after it).
        let recording = Recording { ctx: self, raw };
        {
            let _queue = lock();
            let begin = vk::CommandBufferBeginInfo::default()
                .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            unsafe { device.begin_command_buffer(raw, &begin) }
                .map_err(vkerr("vkBeginCommandBuffer"))?;
            let mut cmd = Cmd {
                shared: &self.shared,
                raw,
                _submission: PhantomData,
            };
            record(&mut cmd);
            unsafe { device.end_command_buffer(raw) }.map_err(vkerr("vkEndCommandBuffer"))?;
        }
        Ok(recording)
    }
}

impl Recording<'_> {
    /// Submits the commands and returns without waiting for them.
    pub fn submit(self) -> crate::Result<InFlight> {
        let shared = &self.ctx.shared;
        let device = &shared.device;
        let fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }
            .map_err(vkerr("vkCreateFence"))?;
        let _queue = shared
            .queue_lock
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let cmd_infos = [vk::CommandBufferSubmitInfo::default().command_buffer(self.raw)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmd_infos)];
        if let Err(e) = unsafe { device.queue_submit2(shared.queue, &submit, fence) } {
            unsafe { device.destroy_fence(fence, None) };
            return Err(vkerr("vkQueueSubmit2")(e));
        }
        // Registered before `self`, which borrows every resource the commands name for `'s`,
        // is gone: from here on a resource's Drop waits for this fence.
        shared
            .in_flight
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .push(fence);
        shared
            .submissions
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        drop(_queue);
        let raw = self.raw;
        let in_flight = InFlight {
            shared: shared.clone(),
            raw,
            fence,
        };
        // The command buffer now belongs to the InFlight.
        std::mem::forget(self);
        Ok(in_flight)
    }
}

impl Drop for Recording<'_> {
    fn drop(&mut self) {
        let shared = &self.ctx.shared;
        let _queue = shared
            .queue_lock
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        unsafe {
            shared
                .device
                .free_command_buffers(shared.command_pool, &[self.raw])
        };
    }
}

impl InFlight {
    /// Waits for the submission to finish, then frees its command buffer and fence.
    pub fn wait(mut self) -> crate::Result<()> {
        self.finish()
    }

    /// Whether the device has finished the submission (does not wait).
    pub fn is_done(&self) -> bool {
        unsafe { self.shared.device.get_fence_status(self.fence) }.unwrap_or(false)
    }

    fn finish(&mut self) -> crate::Result<()> {
        if self.fence == vk::Fence::null() {
            return Ok(());
        }
        let shared = &self.shared;
        let waited = {
            // Under the lock that `Shared::settle` waits under: the fence is not destroyed while
            // another thread waits for it.
            let mut pending = shared
                .in_flight
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            let waited = unsafe { shared.device.wait_for_fences(&[self.fence], true, u64::MAX) }
                .map_err(vkerr("vkWaitForFences"));
            pending.retain(|&f| f != self.fence);
            unsafe { shared.device.destroy_fence(self.fence, None) };
            waited
        };
        self.fence = vk::Fence::null();
        let _queue = shared
            .queue_lock
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        unsafe {
            shared
                .device
                .free_command_buffers(shared.command_pool, &[self.raw])
        };
        waited
    }
}

impl Drop for InFlight {
    fn drop(&mut self) {
        let _ = self.finish();
    }
}
