//! Reading images back to the host: a frame's output, the G-buffer and weave textures (tests).

use crate::vk::{BufferLocation, BufferUsageFlags, Context, Image, Usage};
use crate::Error;

use super::frame::Renderer;

impl Renderer {
    /// Reads mip `level` of an RGBA8 weave texture ([`Renderer::weave_rgba8`]) back (for tests).
    pub fn read_weave_rgba8(&self, image: &Image, level: u32) -> crate::Result<Vec<u8>> {
        read_image_level(&self.ctx, image, level, Usage::FragmentRead, 4)
    }

    /// Reads mip `level` of a weave texture back as RGBA f32 (for tests).
    pub fn read_weave(&self, image: &Image, level: u32) -> crate::Result<Vec<f32>> {
        let raw = read_image_level(&self.ctx, image, level, Usage::FragmentRead, 8)?;
        Ok(raw
            .chunks_exact(2)
            .map(|b| f16_to_f32(u16::from_le_bytes([b[0], b[1]])))
            .collect())
    }

    /// Reads back the G-buffer of the last frame (for tests and debugging): albedo RGBA8,
    /// then the five RGBA16F targets as f32, then depth.
    pub fn read_gbuffer(&self) -> crate::Result<GBufferReadback> {
        let t = self
            .targets
            .as_ref()
            .ok_or_else(|| Error::input("no frame has been rendered yet"))?;
        let ctx = &self.ctx;
        let half = |img: &Image| -> crate::Result<Vec<f32>> {
            let raw = read_image(ctx, img, Usage::FragmentRead, 8)?;
            Ok(raw
                .chunks_exact(2)
                .map(|b| f16_to_f32(u16::from_le_bytes([b[0], b[1]])))
                .collect())
        };
        let depth_raw = read_image(ctx, &t.depth, Usage::FragmentRead, 4)?;
        Ok(GBufferReadback {
            albedo: read_image(ctx, &t.albedo, Usage::FragmentRead, 4)?,
            frame: read_image(ctx, &t.frame, Usage::FragmentRead, 8)?
                .chunks_exact(2)
                .map(|b| frame_decode(u16::from_le_bytes([b[0], b[1]])))
                .collect(),
            surface: half(&t.surface)?,
            fabric: half(&t.fabric)?,
            emissive: half(&t.emissive)?,
            specular: half(&t.specular)?,
            depth: depth_raw
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect(),
        })
    }
}

/// `frame_decode` of frame.glsl: one stored octahedral coordinate back to [-1, 1].
pub fn frame_decode(stored: u16) -> f32 {
    (stored as f32 - 32768.0) / 32767.0
}

/// The G-buffer of a frame on the CPU (the frame target decoded to its octahedral coordinates).
pub struct GBufferReadback {
    pub albedo: Vec<u8>,
    pub frame: Vec<f32>,
    pub surface: Vec<f32>,
    pub fabric: Vec<f32>,
    pub emissive: Vec<f32>,
    pub specular: Vec<f32>,
    pub depth: Vec<f32>,
}

/// Copies mip 0 of `image` (currently in `from` usage) to the host; `texel` bytes per texel.
pub(crate) fn read_image(
    ctx: &Context,
    image: &Image,
    from: Usage,
    texel: u64,
) -> crate::Result<Vec<u8>> {
    read_image_level(ctx, image, 0, from, texel)
}

pub(crate) fn read_image_level(
    ctx: &Context,
    image: &Image,
    level: u32,
    from: Usage,
    texel: u64,
) -> crate::Result<Vec<u8>> {
    let w = (image.desc.width >> level).max(1);
    let h = (image.desc.height >> level).max(1);
    let buffer = ctx.create_buffer(
        &format!("readback of {}", image.desc.name),
        w as u64 * h as u64 * texel,
        BufferUsageFlags::TRANSFER_DST,
        BufferLocation::Readback,
    )?;
    ctx.submit(|cmd| {
        cmd.transition(image, from, Usage::TransferSrc, Some((level, 1)));
        cmd.copy_image_to_buffer(image, level, &buffer);
        cmd.transition(image, Usage::TransferSrc, from, Some((level, 1)));
        cmd.buffer_barrier();
    })?;
    Ok(buffer.read()?.to_vec())
}

/// IEEE 754 half to single precision (the `half` crate's conversion).
pub fn f16_to_f32(h: u16) -> f32 {
    half::f16::from_bits(h).to_f32()
}

#[cfg(test)]
mod tests {
    use super::f16_to_f32;

    #[test]
    fn half_conversion() {
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0xc000), -2.0);
        assert_eq!(f16_to_f32(0x7bff), 65504.0);
        assert_eq!(f16_to_f32(0x0001), 2f32.powi(-24));
        assert_eq!(f16_to_f32(0x0200), 2f32.powi(-15));
        assert!(f16_to_f32(0x7c00).is_infinite());
        assert!(f16_to_f32(0x7e00).is_nan());
    }
}
