//! The environment on the GPU: preprocessing once per environment (cached by content hash), and
//! the records the lighting pass reads.
//!
//! Preprocessing (one submission, `Pass::Environment` in the plan):
//! 1. the equirectangular map is uploaded (RGBA16F) and resampled into level 0 of the radiance
//!    cube by `env_cube.comp`; the cube's other levels are box-filtered by blits;
//! 2. `env_prefilter.comp` fills each level of the specular cube with the radiance convolved with
//!    GGX of that level's roughness (the split sum's first factor), by filtered importance
//!    sampling; its last level (roughness 1) is the irradiance every diffuse term reads, an exact
//!    cosine-weighted sum over the radiance cube's 32² level;
//! 3. the order-2 SH irradiance is projected on the CPU in f64 ([`crate::env::Environment::sh9`]:
//!    a few milliseconds) for the package's consumers and the probes.
//!
//! The DFG table of the split sum does not depend on the environment: it is computed once per
//! renderer on the CPU ([`crate::env::dfg_table`]) and uploaded.
//!
//! What preprocessing makes (both cubes with every level, and the SH) is kept in weft's cache on
//! disk ([`crate::cache`], kind `environment`), keyed by the map's content hash, the cubes' sizes,
//! the two shaders' SPIR-V, the device, its driver and weft's version: a later run with the same
//! environment uploads it instead (issue 29 item 4: the built-in studio's 190 ms at start-up).

use sha2::{Digest, Sha256};

use crate::env::Environment;
use crate::vk::{
    shaders, Binding, BindingKind, BufferLocation, BufferUsageFlags, ComputeDesc, Context, Format,
    Image, ImageDesc, ImageUsageFlags, Pipeline, Resource, Sampler, SetLayout, Stages, Usage,
};

pub const ENV_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
/// Face size of the GGX-prefiltered specular cube, and its levels (roughness level/(levels-1)):
/// 256² to 16², so that roughness 1 has 16² texels per face. With 128² and 6 levels it had 4², and
/// bilinear filtering between those texels, whose lobes point 22° apart, left a rough metal under
/// a contrasted environment up to 16 % off on its own (MultiUVTest under lightroom_14b: +31 % with
/// the sampling noise below).
pub const SPECULAR_SIZE: u32 = 256;
pub const SPECULAR_LEVELS: u32 = 5;
/// Samples per texel of the prefiltering at level 1 (filtered importance sampling needs few for a
/// narrow lobe), doubling per level: a wide lobe reads coarse mips of a few texels, where 32 fixed
/// samples (16 of them above the horizon at roughness 1) left the texel's value +50 % off.
pub const PREFILTER_SAMPLES: u32 = 32;

/// Samples per texel of specular level `level` ([`PREFILTER_SAMPLES`] doubling per level: 32, 64
/// and 128 for levels 1 to 3; level 0 is a copy and takes none, and the last level (roughness 1,
/// the irradiance) is an exact sum over the radiance cube's 32² level, env_prefilter.comp, which
/// ignores its count).
pub fn prefilter_samples(level: u32) -> u32 {
    PREFILTER_SAMPLES << level.saturating_sub(1)
}
/// Side of the DFG table (the environment module's, where the table is computed).
pub use crate::env::DFG_SIZE;

/// Push constants of env_cube.comp and env_prefilter.comp (16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CubePush {
    pub size: u32,
    pub roughness: f32,
    pub source_size: f32,
    pub samples: u32,
}

/// Face size of the radiance cube for a map `width` pixels wide: about one cube texel per map
/// texel (a face spans a quarter of the width), a power of two from 16 to 512.
pub fn radiance_size(width: u32) -> u32 {
    let quarter = (width / 4).max(16);
    (1u32 << (31 - quarter.leading_zeros())).clamp(16, 512)
}

/// `cube_texel_dir` of glsl/include/cube.glsl: the unit direction through the centre of texel
/// (x, y) of face `face` (+x, -x, +y, -y, +z, -z) of a `size` cube.
pub fn cube_texel_dir(face: u32, x: u32, y: u32, size: u32) -> [f32; 3] {
    crate::reference::ibl_twin::formula::cube_texel_dir::<f32>(face, x, y, size)
}

/// A preprocessed environment.
pub struct GpuEnvironment {
    pub hash: [u8; 32],
    pub radiance: Image,
    pub specular: Image,
    pub sh: [[f32; 3]; 9],
    /// Wall time of the preprocessing (or of the upload from the cache on disk), ms.
    pub build_ms: f64,
    /// Whether it came from the cache on disk.
    pub from_cache: bool,
}

/// Bytes of one level of a cube of face size `size` in [`ENV_FORMAT`].
fn level_bytes(size: u32, level: u32) -> usize {
    let s = (size >> level).max(1) as usize;
    s * s * 6 * 8
}

/// The levels of the radiance cube of face size `size` (a full chain).
fn radiance_levels(size: u32) -> u32 {
    32 - size.leading_zeros()
}

impl GpuEnvironment {
    pub fn radiance_size(&self) -> u32 {
        self.radiance.desc.width
    }
    pub fn radiance_levels(&self) -> u32 {
        self.radiance.desc.mip_levels
    }
}

/// The pipelines and fixed resources of environment lighting.
pub struct EnvPasses {
    layout: SetLayout,
    cube: Pipeline,
    prefilter: Pipeline,
    /// 1 x 1 black cubes bound when a frame has no environment.
    pub black: Image,
    pub dfg: Image,
    pub sampler: Sampler,
    equirect_sampler: Sampler,
}

impl EnvPasses {
    pub fn new(ctx: &Context) -> crate::Result<EnvPasses> {
        let layout = ctx.create_set_layout(&[
            Binding {
                binding: 0,
                kind: BindingKind::StorageImage,
                stages: Stages::COMPUTE,
            },
            Binding {
                binding: 1,
                kind: BindingKind::SampledImage,
                stages: Stages::COMPUTE,
            },
        ])?;
        let make = |name: &'static str, shader| {
            ctx.create_compute_pipeline(&ComputeDesc {
                name,
                shader,
                set_layouts: &[&layout],
                push_constant_size: std::mem::size_of::<CubePush>() as u32,
                constants: &[],
            })
        };
        let cube = make("env_cube", &shaders::ENV_CUBE_COMP)?;
        let prefilter = make("env_prefilter", &shaders::ENV_PREFILTER_COMP)?;
        let black = ctx.create_image(
            &ImageDesc::new_cube("no environment", ENV_FORMAT, 1)
                .usage(ImageUsageFlags::SAMPLED | ImageUsageFlags::TRANSFER_DST),
        )?;
        let zeros = ctx.create_buffer_with(
            "no environment staging",
            BufferUsageFlags::TRANSFER_SRC,
            &[0u16; 4 * 6],
        )?;
        let table = crate::env::dfg_table_kept();
        let one = half::f16::ONE.to_bits();
        let texels: Vec<u16> = table
            .iter()
            .flat_map(|[a, b, e]| [a.to_bits(), b.to_bits(), e.to_bits(), one])
            .collect();
        let dfg = ctx.create_image(
            &ImageDesc::new_2d("DFG table", ENV_FORMAT, DFG_SIZE, DFG_SIZE)
                .usage(ImageUsageFlags::SAMPLED | ImageUsageFlags::TRANSFER_DST),
        )?;
        let dfg_staging =
            ctx.create_buffer_with("DFG staging", BufferUsageFlags::TRANSFER_SRC, &texels)?;
        ctx.submit(|cmd| {
            cmd.transition(&black, Usage::Undefined, Usage::TransferDst, None);
            cmd.copy_buffer_to_image(&zeros, &black);
            cmd.transition(&black, Usage::TransferDst, Usage::FragmentRead, None);
            cmd.transition(&dfg, Usage::Undefined, Usage::TransferDst, None);
            cmd.copy_buffer_to_image(&dfg_staging, &dfg);
            cmd.transition(&dfg, Usage::TransferDst, Usage::FragmentRead, None);
        })?;
        Ok(EnvPasses {
            layout,
            cube,
            prefilter,
            black,
            dfg,
            sampler: ctx.create_sampler(crate::vk::Filter::LinearClamp)?,
            equirect_sampler: ctx.create_sampler(crate::vk::Filter::LinearRepeat)?,
        })
    }

    pub fn pipelines(&self) -> [&Pipeline; 2] {
        [&self.cube, &self.prefilter]
    }

    /// The key of `env`'s entry in the cache on disk.
    pub(crate) fn cache_key(ctx: &Context, env: &Environment) -> Vec<u8> {
        let mut key = b"environment v2 ".to_vec();
        key.extend_from_slice(&env.hash());
        let mut shaders = Sha256::new();
        shaders.update(shaders::ENV_CUBE_COMP.spirv);
        shaders.update(shaders::ENV_PREFILTER_COMP.spirv);
        key.extend_from_slice(&shaders.finalize());
        for v in [radiance_size(env.width), SPECULAR_SIZE, SPECULAR_LEVELS]
            .into_iter()
            .chain((0..SPECULAR_LEVELS).map(prefilter_samples))
        {
            key.extend_from_slice(&v.to_le_bytes());
        }
        for text in [
            &ctx.info().name,
            &ctx.info().driver_name,
            &ctx.info().driver_info,
        ] {
            key.extend_from_slice(text.as_bytes());
            key.push(0);
        }
        key.extend_from_slice(env!("CARGO_PKG_VERSION").as_bytes());
        key
    }

    /// The cache entry's payload: the SH (27 f32), then each level of the radiance cube, then
    /// of the specular cube, as the images hold them. Its length for a radiance cube of `size`.
    fn payload_len(size: u32) -> usize {
        27 * 4
            + (0..radiance_levels(size))
                .map(|l| level_bytes(size, l))
                .sum::<usize>()
            + (0..SPECULAR_LEVELS)
                .map(|l| level_bytes(SPECULAR_SIZE, l))
                .sum::<usize>()
    }

    /// `env` preprocessed: from the cache on disk when it holds it, else computed (and then
    /// stored there, best effort).
    pub fn build(&self, ctx: &Context, env: &Environment) -> crate::Result<GpuEnvironment> {
        let start = std::time::Instant::now();
        let key = Self::cache_key(ctx, env);
        if let Some(payload) = crate::cache::read("environment", &key) {
            if let Some(mut g) = Self::upload_cached(ctx, env, &payload)? {
                g.build_ms = start.elapsed().as_secs_f64() * 1e3;
                return Ok(g);
            }
        }
        let mut g = self.compute(ctx, env)?;
        g.build_ms = start.elapsed().as_secs_f64() * 1e3;
        if crate::cache::dir().is_some() {
            if let Ok(payload) = Self::read_back(ctx, &g) {
                crate::cache::write("environment", &key, &payload);
            }
        }
        Ok(g)
    }

    /// The cubes' images of an environment with a radiance cube of face `size`.
    fn cube_images(ctx: &Context, size: u32) -> crate::Result<(Image, Image)> {
        let radiance = ctx.create_image(
            &ImageDesc::new_cube("environment radiance cube", ENV_FORMAT, size)
                .usage(
                    ImageUsageFlags::STORAGE
                        | ImageUsageFlags::SAMPLED
                        | ImageUsageFlags::TRANSFER_SRC
                        | ImageUsageFlags::TRANSFER_DST,
                )
                .full_mips(),
        )?;
        let mut desc = ImageDesc::new_cube("environment specular cube", ENV_FORMAT, SPECULAR_SIZE)
            .usage(
                ImageUsageFlags::STORAGE
                    | ImageUsageFlags::SAMPLED
                    | ImageUsageFlags::TRANSFER_SRC
                    | ImageUsageFlags::TRANSFER_DST,
            );
        desc.mip_levels = SPECULAR_LEVELS;
        let specular = ctx.create_image(&desc)?;
        Ok((radiance, specular))
    }

    /// The environment from a cache entry's payload (None: not a payload for this environment).
    fn upload_cached(
        ctx: &Context,
        env: &Environment,
        payload: &[u8],
    ) -> crate::Result<Option<GpuEnvironment>> {
        let size = radiance_size(env.width);
        if payload.len() != Self::payload_len(size) {
            return Ok(None);
        }
        let mut sh = [[0f32; 3]; 9];
        for (k, v) in sh.iter_mut().flatten().enumerate() {
            let b = &payload[4 * k..4 * k + 4];
            *v = f32::from_le_bytes(b.try_into().expect("4 bytes"));
        }
        if !sh.iter().flatten().all(|v| v.is_finite()) {
            return Ok(None);
        }
        let (radiance, specular) = Self::cube_images(ctx, size)?;
        let mut at = 27 * 4;
        let mut staged = Vec::new();
        for (image, cube, levels) in [
            (&radiance, size, radiance.desc.mip_levels),
            (&specular, SPECULAR_SIZE, SPECULAR_LEVELS),
        ] {
            for level in 0..levels {
                let n = level_bytes(cube, level);
                let buffer = ctx.create_buffer_with(
                    "environment cache staging",
                    BufferUsageFlags::TRANSFER_SRC,
                    &payload[at..at + n],
                )?;
                at += n;
                staged.push((image, level, buffer));
            }
        }
        ctx.submit(|cmd| {
            cmd.transition(&radiance, Usage::Undefined, Usage::TransferDst, None);
            cmd.transition(&specular, Usage::Undefined, Usage::TransferDst, None);
            for (image, level, buffer) in &staged {
                cmd.copy_buffer_to_image_level(buffer, image, *level);
            }
            cmd.transition(&radiance, Usage::TransferDst, Usage::FragmentRead, None);
            cmd.transition(&specular, Usage::TransferDst, Usage::FragmentRead, None);
        })?;
        drop(staged);
        Ok(Some(GpuEnvironment {
            hash: env.hash(),
            radiance,
            specular,
            sh,
            build_ms: 0.0,
            from_cache: true,
        }))
    }

    /// A cache entry's payload of a preprocessed environment (its cubes read back).
    fn read_back(ctx: &Context, g: &GpuEnvironment) -> crate::Result<Vec<u8>> {
        let mut buffers = Vec::new();
        for (image, cube) in [
            (&g.radiance, g.radiance_size()),
            (&g.specular, SPECULAR_SIZE),
        ] {
            for level in 0..image.desc.mip_levels {
                let buffer = ctx.create_buffer(
                    "environment cache readback",
                    level_bytes(cube, level) as u64,
                    BufferUsageFlags::TRANSFER_DST,
                    BufferLocation::Readback,
                )?;
                buffers.push((image, level, buffer));
            }
        }
        ctx.submit(|cmd| {
            cmd.transition(&g.radiance, Usage::FragmentRead, Usage::TransferSrc, None);
            cmd.transition(&g.specular, Usage::FragmentRead, Usage::TransferSrc, None);
            for (image, level, buffer) in &buffers {
                cmd.copy_image_to_buffer(image, *level, buffer);
            }
            cmd.transition(&g.radiance, Usage::TransferSrc, Usage::FragmentRead, None);
            cmd.transition(&g.specular, Usage::TransferSrc, Usage::FragmentRead, None);
        })?;
        let mut payload: Vec<u8> =
            g.sh.iter()
                .flatten()
                .flat_map(|v| v.to_le_bytes())
                .collect();
        for (_, _, buffer) in &buffers {
            payload.extend_from_slice(buffer.read()?);
        }
        Ok(payload)
    }

    /// Preprocesses `env` on the device: the radiance cube with its mips, the specular cube, the
    /// SH.
    fn compute(&self, ctx: &Context, env: &Environment) -> crate::Result<GpuEnvironment> {
        let texels: Vec<u16> = env
            .rgb
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 1.0].map(|x| half::f16::from_f32(x).to_bits()))
            .collect();
        let equirect = ctx.create_image(
            &ImageDesc::new_2d(
                format!("environment {}", env.name),
                ENV_FORMAT,
                env.width,
                env.height,
            )
            .usage(ImageUsageFlags::SAMPLED | ImageUsageFlags::TRANSFER_DST),
        )?;
        let staging = ctx.create_buffer_with(
            "environment staging",
            BufferUsageFlags::TRANSFER_SRC,
            &texels,
        )?;
        let size = radiance_size(env.width);
        let (radiance, specular) = Self::cube_images(ctx, size)?;
        let pool = ctx.create_descriptor_pool(1 + SPECULAR_LEVELS)?;
        let cube_set = pool.set(
            &self.layout,
            &[
                (0, Resource::StorageImage(&radiance, 0)),
                (1, Resource::Sampled(&equirect, &self.equirect_sampler)),
            ],
        )?;
        let prefilter_sets = (0..SPECULAR_LEVELS)
            .map(|level| {
                pool.set(
                    &self.layout,
                    &[
                        (0, Resource::StorageImage(&specular, level)),
                        (1, Resource::Sampled(&radiance, &self.sampler)),
                    ],
                )
            })
            .collect::<crate::Result<Vec<_>>>()?;
        ctx.submit(|cmd| {
            cmd.transition(&equirect, Usage::Undefined, Usage::TransferDst, None);
            cmd.copy_buffer_to_image(&staging, &equirect);
            cmd.transition(&equirect, Usage::TransferDst, Usage::ComputeRead, None);
            cmd.transition(
                &radiance,
                Usage::Undefined,
                Usage::ComputeWrite,
                Some((0, 1)),
            );
            cmd.bind_pipeline(&self.cube);
            cmd.bind_sets(&self.cube, 0, &[cube_set]);
            cmd.push_constants(
                &self.cube,
                &CubePush {
                    size,
                    roughness: 0.0,
                    source_size: env.width as f32,
                    samples: 1,
                },
            );
            cmd.dispatch(size.div_ceil(8), size.div_ceil(8), 6);
            cmd.transition(
                &radiance,
                Usage::ComputeWrite,
                Usage::TransferDst,
                Some((0, 1)),
            );
            cmd.generate_mips(&radiance, Usage::ComputeRead);
            cmd.transition(&specular, Usage::Undefined, Usage::ComputeWrite, None);
            cmd.bind_pipeline(&self.prefilter);
            for (level, set) in prefilter_sets.iter().enumerate() {
                let s = (SPECULAR_SIZE >> level).max(1);
                cmd.bind_sets(&self.prefilter, 0, &[*set]);
                cmd.push_constants(
                    &self.prefilter,
                    &CubePush {
                        size: s,
                        roughness: level as f32 / (SPECULAR_LEVELS - 1) as f32,
                        source_size: size as f32,
                        samples: prefilter_samples(level as u32),
                    },
                );
                cmd.dispatch(s.div_ceil(8), s.div_ceil(8), 6);
            }
            cmd.transition(&specular, Usage::ComputeWrite, Usage::FragmentRead, None);
            cmd.transition(&radiance, Usage::ComputeRead, Usage::FragmentRead, None);
        })?;
        let sh = env.sh9();
        Ok(GpuEnvironment {
            hash: env.hash(),
            radiance,
            specular,
            sh,
            build_ms: 0.0,
            from_cache: false,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_faces_point_where_vulkan_says() {
        let c = |f| cube_texel_dir(f, 0, 0, 1);
        assert_eq!(c(0), [1.0, 0.0, 0.0]);
        assert_eq!(c(1), [-1.0, 0.0, 0.0]);
        assert_eq!(c(2), [0.0, 1.0, 0.0]);
        assert_eq!(c(3), [0.0, -1.0, 0.0]);
        assert_eq!(c(4), [0.0, 0.0, 1.0]);
        assert_eq!(c(5), [0.0, 0.0, -1.0]);
        assert_eq!(radiance_size(1024), 256);
        assert_eq!(radiance_size(1440), 256);
        assert_eq!(radiance_size(64), 16);
        assert_eq!(radiance_size(100_000), 512);
    }
}
