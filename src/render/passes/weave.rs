//! The weave pass: each distinct weave's coverage texture, every mip level computed by weave.comp
//! as the exact coverage of its texels' footprints (at upload, once per weave), and the two other
//! forms a frame may ask for: its RGBA8 copy and its summed-area table.

use crate::fabric::{weave_level0_size, weave_level_size, weave_mip_count, FabricParams};
use crate::vk::{
    shaders, BufferUsageFlags, ComputeDesc, Context, Image, ImageDesc, ImageUsageFlags, Pipeline,
    Resource, SetLayout, Usage,
};

use crate::render::frame::Renderer;
use crate::render::targets::{WEAVE_FORMAT, WEAVE_FORMAT_8, WEAVE_SAT_FORMAT};

/// The pass's compute pipeline (weave.comp) and its set layout (reflected): one storage image,
/// the mip level being written.
pub struct WeavePass {
    layout: SetLayout,
    pipeline: Pipeline,
}

impl WeavePass {
    pub fn new(ctx: &Context) -> crate::Result<WeavePass> {
        let [layout] = ctx.reflected_set_layouts(&[&shaders::WEAVE_COMP])?;
        let pipeline = ctx.create_compute_pipeline(&ComputeDesc {
            name: "weave",
            shader: &shaders::WEAVE_COMP,
            set_layouts: &[&layout],
            push_constant_size: std::mem::size_of::<crate::fabric::WeavePush>() as u32,
            constants: &[],
        })?;
        Ok(WeavePass { layout, pipeline })
    }

    pub fn pipeline(&self) -> &Pipeline {
        &self.pipeline
    }
}

impl Renderer {
    /// Builds a weave texture: every mip level computed by weave.comp as the exact coverage of its
    /// texels' footprints (not a downsampling of level 0).
    pub fn build_weave(&self, fabric: &FabricParams) -> crate::Result<Image> {
        let ctx = &self.ctx;
        let level0 = weave_level0_size(&fabric.pattern);
        let mut desc = ImageDesc::new_2d("weave", WEAVE_FORMAT, level0.0, level0.1).usage(
            ImageUsageFlags::STORAGE | ImageUsageFlags::SAMPLED | ImageUsageFlags::TRANSFER_SRC,
        );
        desc.mip_levels = weave_mip_count(level0);
        let image = ctx.create_image(&desc)?;
        let pool = ctx.create_descriptor_pool(desc.mip_levels)?;
        let sets = (0..desc.mip_levels)
            .map(|level| {
                pool.set(
                    &self.weave.layout,
                    &[(0, Resource::StorageImage(&image, level))],
                )
            })
            .collect::<crate::Result<Vec<_>>>()?;
        ctx.submit(|cmd| {
            cmd.transition(&image, Usage::Undefined, Usage::ComputeWrite, None);
            cmd.bind_pipeline(&self.weave.pipeline);
            for (level, set) in sets.iter().enumerate() {
                let (w, h) = weave_level_size(level0, level as u32);
                cmd.bind_sets(&self.weave.pipeline, 0, &[*set]);
                cmd.push_constants(&self.weave.pipeline, &fabric.weave_push(w, h));
                cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            }
            cmd.transition(&image, Usage::ComputeWrite, Usage::FragmentRead, None);
        })?;
        Ok(image)
    }

    /// The summed-area table of a weave ([`crate::fabric::WeaveSat`], computed on the
    /// CPU in f64), uploaded as one RGBA32F level.
    pub fn weave_sat(&self, fabric: &FabricParams) -> crate::Result<Image> {
        let level0 = weave_level0_size(&fabric.pattern);
        let sat = crate::fabric::WeaveSat::new(&fabric.weave_push(level0.0, level0.1));
        let desc = ImageDesc::new_2d(
            "weave summed-area table",
            WEAVE_SAT_FORMAT,
            sat.width,
            sat.height,
        )
        .usage(ImageUsageFlags::SAMPLED | ImageUsageFlags::TRANSFER_DST);
        let image = self.ctx.create_image(&desc)?;
        let bytes: Vec<u8> = sat
            .texels
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let staging = self.ctx.create_buffer_with(
            "weave summed-area staging",
            BufferUsageFlags::TRANSFER_SRC,
            &bytes,
        )?;
        self.ctx.submit(|cmd| {
            cmd.transition(&image, Usage::Undefined, Usage::TransferDst, None);
            cmd.copy_buffer_to_image_level(&staging, &image, 0);
            cmd.transition(&image, Usage::TransferDst, Usage::FragmentRead, None);
        })?;
        Ok(image)
    }

    /// The RGBA8 copy of a weave texture: every level read back and each coverage rounded to the
    /// nearest 1/255 here. A format-converting blit may round toward zero (lavapipe does), which
    /// darkened the far field by half a step on average (0.28 %: 54 against 61.5 dB).
    pub fn weave_rgba8(&self, weave: &Image) -> crate::Result<Image> {
        let mut desc = weave.desc.clone();
        desc.name = format!("{} (RGBA8)", desc.name);
        desc.format = WEAVE_FORMAT_8;
        desc.usage = ImageUsageFlags::SAMPLED
            | ImageUsageFlags::TRANSFER_DST
            | ImageUsageFlags::TRANSFER_SRC;
        let image = self.ctx.create_image(&desc)?;
        let levels = (0..desc.mip_levels)
            .map(|level| Ok(unorm8_round(&self.read_weave(weave, level)?)))
            .collect::<crate::Result<Vec<_>>>()?;
        self.ctx
            .fill_image_levels(&image, &levels, "weave rgba8 staging")?;
        Ok(image)
    }
}

/// Values in [0, 1] as UNORM8 bytes, rounded to nearest (NaN to 0).
pub fn unorm8_round(values: &[f32]) -> Vec<u8> {
    values
        .iter()
        .map(|v| {
            let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
            (v * 255.0).round() as u8
        })
        .collect()
}
