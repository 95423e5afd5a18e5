//! The Rust twins of `glsl/include/ibl.glsl`, `glsl/include/cube.glsl` and
//! `glsl/include/occlusion.glsl`, the std430 records of
//! their probe `glsl/ibl_probe.comp`, and the error each output may have.
//!
//! # The twins
//! Each GLSL function is written once here, generic over [`Real`], line for line as the GLSL
//! writes it (same operations in the same order, same clamps, the same f32 literals), and used
//! three ways:
//! - at `f32` it is the twin ([`ggx_sample_h`], [`as_sample_h`], [`cosine_sample`], [`fis_lod`],
//!   [`specular_occlusion`], [`cone_occlusion`], [`fabric_diffuse_albedo`], [`equirect_uv`], [`env_dir`],
//!   [`gtao_half_arc`], [`gtao_arc`], [`gtao_multibounce`]);
//! - at `f64` (with the ideal constants: π, not its f32 rounding) it is the exact formula;
//! - at [`Iv`] (interval arithmetic) it is the error analysis: an enclosure of every value a
//!   conforming implementation may return for that input (see below).
//!
//! The functions the rest of weft calls by other names are these, instantiated:
//! [`crate::env::sh_eval`] is `sh_irradiance` at f32, [`crate::env::sh_basis`] `sh_basis` at f64,
//! [`crate::env::hammersley`] `hammersley` at f64, [`crate::render::environment::cube_texel_dir`]
//! `cube_texel_dir` at f32, and the DFG table samples with `ggx_sample_h` at f64: one Rust copy
//! of each formula (issue 24 found four of the SH basis). [`crate::env::env_from_world`] makes
//! `env_dir`'s rows.
//!
//! # Error bounds
//! For each input and output, [`ibl_probe_bounds`] evaluates the formula in interval arithmetic
//! under a [`Model`] of the arithmetic. Every operation's result interval is the exact range of
//! the operation over its argument intervals, widened by the model's error for that operation
//! and rounded outwards to f32 values, and then widened to 0 where a denormal could be flushed.
//! The final interval therefore contains the exact real-valued formula (with each literal taken
//! anywhere between its f32 value and its ideal value, so it contains the f64 reference too) and
//! every result an implementation meeting the model can produce, whatever rounding direction
//! (nearest or towards zero), fused multiply-adds and summation order of `dot` (and of the SH sum)
//! it chooses; chains of products are taken in the order the SPIR-V has them.
//! The condition number of each output is therefore not estimated: it is what the intervals do.
//!
//! - [`Vulkan`]: the precision the Vulkan specification requires of a GPU ("Precision and
//!   Operation of SPIR-V Instructions"): `+ - *` and conversions correctly rounded (either
//!   direction), `/` 2.5 ulp, `inversesqrt` 2 ulp and `sqrt` inherited from `1/inversesqrt`,
//!   `exp2` 3 + 2|x| ulp, `log2` 3 ulp outside [0.5, 2] and 2^-21 absolute inside, `pow` inherited
//!   from `exp2(y·log2 x)`, `sin`/`cos` 2^-11 absolute, `tan` inherited from `sin/cos`, `atan` 4096
//!   ulp, `acos` inherited from `atan(sqrt(1 - x²), x)`, `dot` and `normalize` inherited from
//!   their products, sums, `sqrt` and `/`. Denormals may be flushed to zero.
//!   Two readings the spec leaves open are taken generously for the GPU: the `sin`/`cos` bound is
//!   stated for [-π, π] and is applied on [-2π, 2π] (the samplers' φ reaches 2π); `sqrt(0)` is
//!   taken to be 0 (the spec's `1/inversesqrt(0)` is a division by +∞, outside its stated range).
//! - [`CpuF32`]: what the f32 twin does on the CPU: correctly rounded (to nearest) `+ - * / sqrt`
//!   and the platform's `libm` within 2 ulp for `sin cos tan atan atan2 acos exp2 log2 powf`.
//!   It is the tight bound: the twin must lie in it, and so must the f64 reference.
//!
//! What bounds each output, in words (the intervals do the arithmetic):
//! - `env_dir`: three 3-term dot products of unit vectors: a few ulp of 1 (any summation order).
//! - `sh_irradiance`: a 9-term sum of SH coefficient × basis (the basis from at most three
//!   products): a few ulp of the sum of the terms' magnitudes, not of the result (cancellation
//!   is allowed for, which is what makes the bound absolute).
//! - `hammersley`: `i/n` to the division's 2.5 ulp; the radical inverse to one rounding of the
//!   uint-to-float conversion (exact below 2^24).
//! - `ggx_sample_h`, `cosine_sample`: the `sin`/`cos` of φ dominate on a GPU (2^-11 absolute in
//!   the tangential components); `cos θ` is a few ulp; `sin θ = sqrt(1 - cos²θ)` loses half the
//!   digits near the pole (the interval's `sqrt` of a few ulp of 1 shows it).
//! - `as_sample_h`: φ₀ = atan(√((eu+1)/(ev+1))·tan(πr/2)): `atan`'s 4096 ulp, and `tan` inherits
//!   `sin/cos`'s absolute 2^-11, so near r → 1 (cos(πr/2) < 2^-11) the GPU may return a tan of
//!   either sign and φ₀ is only known to [-π/2, π/2] (see the probe test's report); the exponent
//!   `eu cos²φ + ev sin²φ + 1` carries the error of `cos φ`, `sin φ` times `eu`, `ev`, and
//!   `cos θ = pow(xi, 1/E)` that of `log2` (2^-21 absolute near xi = 1, so cos θ may exceed 1).
//! - `fis_lod`: half `log2`'s error (2^-21 absolute when the ratio is in [0.5, 2]) plus the
//!   divisions' 2.5 ulp each, as `0.5·log2(1 + δ)`.
//! - `specular_occlusion`: `pow` as `exp2(y·log2 x)` with x = n·v + ao in [0, 2] (2^-21 absolute
//!   in log2) and `exp2(-16r-1)`'s 3 + 2|x| ulp, then the cancellation in `pow - 1 + ao`.
//! - `cone_occlusion`: no `acos` (its `acos01` is a polynomial times a square root, so the GPU
//!   rounds what the twin rounds); the error grows where a cap is small, in the ratio of two
//!   `1 - cos` and of two smoothsteps; the enclosure carries it.
//! - `fabric_diffuse_albedo`: a handful of roundings of numbers ≤ 1.
//! - `gtao_arc` and `gtao_half_arc` (one of its two terms): `sin`/`cos`'s 2^-11 absolute, times
//!   the angles (≤ π) that multiply them, in a sum of terms ≤ 1: absolute, a few 2^-11.
//! - `gtao_multibounce`: a cubic's few roundings of numbers ≤ 3, then `max` and `clamp`.
//! - `cube_texel_dir`: the division in `(t + ½)/size`, then `normalize` (2 + 2.5 + 2.5 ulp).
//! - `equirect_uv`: `atan`'s and `acos`'s (inherited from `atan`) 4096 ulp; u is compared modulo
//!   1 (the map wraps; at the seam u = 0 and u = 1 are the same column, and whether `atan(±0, x<0)`
//!   is +π or -π is not specified). At the poles `atan(0, 0)` is undefined in GLSL: u is then
//!   unconstrained, which the interval of `atan` over a box containing the origin says.

use crate::fabric::GpuFabric;

pub use super::interval::{CpuF32, Iv, Model, Real, Vulkan};

// ---------------------------------------------------------------------------------------------
// The probe's records.
// ---------------------------------------------------------------------------------------------

/// One input of `glsl/ibl_probe.comp` (std430, 432 bytes; `IblProbeInput` there).
///
/// | offset | field | meaning |
/// |---|---|---|
/// | 0   | `world: vec4` | `env_dir`: world direction (xyz) |
/// | 16  | `rot: vec4[3]` | `env_dir`: rows of `env_from_world` (xyz) |
/// | 64  | `normal: vec4` | `sh_irradiance`: env-space normal (xyz) |
/// | 80  | `sh: vec4[9]` | `sh_irradiance`: SH9 coefficients (rgb) |
/// | 224 | `xi: vec4` | xy: the xi of `ggx_sample_h`, `as_sample_h`, `cosine_sample` |
/// | 240 | `lobe: vec4` | x: GGX alpha, y: A–S eu, z: A–S ev |
/// | 256 | `lod: vec4` | x: pdf, y: face size (`fis_lod`); z: n·v, w: ao (`specular_occlusion`, `cone_occlusion`) |
/// | 272 | `misc: vec4` | x: roughness (`specular_occlusion`, `cone_occlusion`), y: n·k2 (`fabric_diffuse_albedo`), z: visibility, w: albedo (`gtao_multibounce`) |
/// | 288 | `counts: uvec4` | x: `hammersley` i, y: `hammersley` n, z: `fis_lod` n |
/// | 304 | `cube: uvec4` | `cube_texel_dir`: face, texel x, texel y, size |
/// | 320 | `dir: vec4` | `equirect_uv`: direction (xyz) |
/// | 336 | `fabric: GpuFabric` | `fabric_diffuse_albedo`: the material (80 bytes) |
/// | 416 | `arc: vec4` | `gtao_arc`: h0, h1, n |
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct IblProbeInput {
    pub world: [f32; 4],
    pub rot: [[f32; 4]; 3],
    pub normal: [f32; 4],
    pub sh: [[f32; 4]; 9],
    pub xi: [f32; 4],
    pub lobe: [f32; 4],
    pub lod: [f32; 4],
    pub misc: [f32; 4],
    pub counts: [u32; 4],
    pub cube: [u32; 4],
    pub dir: [f32; 4],
    pub fabric: GpuFabric,
    pub arc: [f32; 4],
}

/// One output of `glsl/ibl_probe.comp` (std430, 160 bytes; `IblProbeOutput` there).
///
/// | offset | field | x | y | z | w |
/// |---|---|---|---|---|---|
/// | 0   | `env_dir` | `env_dir` x | y | z | 0 |
/// | 16  | `irradiance` | `sh_irradiance` r | g | b | 0 |
/// | 32  | `ggx` | `ggx_sample_h` x | y | z | 0 |
/// | 48  | `as_h` | `as_sample_h` x | y | z | 0 |
/// | 64  | `cosine` | `cosine_sample` x | y | z | 0 |
/// | 80  | `cube` | `cube_texel_dir` x | y | z | 0 |
/// | 96  | `uv` | `hammersley` x | y | `equirect_uv` u | v |
/// | 112 | `scalars` | `fis_lod` | `specular_occlusion` | `fabric_diffuse_albedo` | `cone_occlusion` |
/// | 128 | `occlusion` | `gtao_arc` | `gtao_multibounce` | `gtao_half_arc`(h0, n) | 0 |
/// | 144 | `dominant` | `dominant_dir` x | y | z | 0 |
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct IblProbeOutput {
    pub env_dir: [f32; 4],
    pub irradiance: [f32; 4],
    pub ggx: [f32; 4],
    pub as_h: [f32; 4],
    pub cosine: [f32; 4],
    pub cube: [f32; 4],
    pub uv: [f32; 4],
    pub scalars: [f32; 4],
    pub occlusion: [f32; 4],
    pub dominant: [f32; 4],
}

const _: () = {
    assert!(std::mem::size_of::<IblProbeInput>() == 432);
    assert!(std::mem::offset_of!(IblProbeInput, arc) == 416);
    assert!(std::mem::offset_of!(IblProbeInput, sh) == 80);
    assert!(std::mem::offset_of!(IblProbeInput, counts) == 288);
    assert!(std::mem::offset_of!(IblProbeInput, fabric) == 336);
    assert!(std::mem::size_of::<IblProbeOutput>() == 160);
    assert!(std::mem::offset_of!(IblProbeOutput, uv) == 96);
};

/// Number of f32 components of an [`IblProbeOutput`].
pub const IBL_PROBE_OUTPUTS: usize = 40;

/// Names of the output components, in memory order.
#[rustfmt::skip]
pub const IBL_PROBE_OUTPUT_NAMES: [&str; IBL_PROBE_OUTPUTS] = [
    "env_dir.x", "env_dir.y", "env_dir.z", "env_dir.w",
    "sh_irradiance.r", "sh_irradiance.g", "sh_irradiance.b", "sh_irradiance.w",
    "ggx_sample_h.x", "ggx_sample_h.y", "ggx_sample_h.z", "ggx_sample_h.w",
    "as_sample_h.x", "as_sample_h.y", "as_sample_h.z", "as_sample_h.w",
    "cosine_sample.x", "cosine_sample.y", "cosine_sample.z", "cosine_sample.w",
    "cube_texel_dir.x", "cube_texel_dir.y", "cube_texel_dir.z", "cube_texel_dir.w",
    "hammersley.x", "hammersley.y", "equirect_uv.u", "equirect_uv.v",
    "fis_lod", "specular_occlusion", "fabric_diffuse_albedo", "cone_occlusion",
    "gtao_arc", "gtao_multibounce", "gtao_half_arc", "occlusion.w",
    "dominant_dir.x", "dominant_dir.y", "dominant_dir.z", "dominant_dir.w",
];

/// The component compared modulo 1 (`equirect_uv`'s u: the map wraps).
pub const IBL_PROBE_CIRCULAR: usize = 26;

impl IblProbeOutput {
    pub fn to_array(&self) -> [f32; IBL_PROBE_OUTPUTS] {
        let mut a = [0.0; IBL_PROBE_OUTPUTS];
        a.copy_from_slice(bytemuck::cast_slice::<[f32; 4], f32>(&[
            self.env_dir,
            self.irradiance,
            self.ggx,
            self.as_h,
            self.cosine,
            self.cube,
            self.uv,
            self.scalars,
            self.occlusion,
            self.dominant,
        ]));
        a
    }

    /// Reads one output from the shader's buffer bytes (little-endian, 160 bytes).
    pub fn from_bytes(b: &[u8]) -> Self {
        let v = |k: usize| {
            let mut out = [0f32; 4];
            for (c, x) in out.iter_mut().enumerate() {
                let o = 16 * k + 4 * c;
                *x = f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]);
            }
            out
        };
        IblProbeOutput {
            env_dir: v(0),
            irradiance: v(1),
            ggx: v(2),
            as_h: v(3),
            cosine: v(4),
            cube: v(5),
            uv: v(6),
            scalars: v(7),
            occlusion: v(8),
            dominant: v(9),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The formulas, generic: line for line the GLSL.
// ---------------------------------------------------------------------------------------------

/// The functions of `glsl/include/ibl.glsl` and `glsl/include/cube.glsl`, line for line, over any
/// [`Real`]. At f32 they are the twins.
pub mod formula {
    use super::Real;
    use std::f64::consts::PI;

    /// `IBL_PI` (the GLSL literal rounds π to f32).
    pub fn pi<T: Real>() -> T {
        T::ideal(std::f32::consts::PI, PI)
    }

    /// `env_dir` (ibl.glsl).
    pub fn env_dir<T: Real>(w: [T; 3], r0: [T; 3], r1: [T; 3], r2: [T; 3]) -> [T; 3] {
        [T::dot3(r0, w), T::dot3(r1, w), T::dot3(r2, w)]
    }

    /// The nine real SH basis functions (bands 0..2) at unit direction `d`, as `sh_irradiance`
    /// (ibl.glsl) weighs them; [`crate::env::sh_basis`] is this at f64.
    pub fn sh_basis<T: Real>(d: [T; 3]) -> [T; 9] {
        let [x, y, z] = d;
        let c = |glsl: f32, ideal: f64| T::ideal(glsl, ideal);
        [
            c(0.282_094_8, 0.282_094_791_773_878_1),
            c(0.488_602_5, 0.488_602_511_902_919_9) * y,
            c(0.488_602_5, 0.488_602_511_902_919_9) * z,
            c(0.488_602_5, 0.488_602_511_902_919_9) * x,
            c(1.092_548_4, 1.092_548_430_592_079_2) * x * y,
            c(1.092_548_4, 1.092_548_430_592_079_2) * y * z,
            c(0.315_391_6, 0.315_391_565_252_520_0) * (T::lit(3.0) * z * z - T::lit(1.0)),
            c(1.092_548_4, 1.092_548_430_592_079_2) * x * z,
            c(0.546_274_2, 0.546_274_215_296_039_6) * (x * x - y * y),
        ]
    }

    /// `sh_irradiance` (ibl.glsl); [`crate::env::sh_eval`] is this at f32.
    pub fn sh_irradiance<T: Real>(sh: &[[T; 3]; 9], n: [T; 3]) -> [T; 3] {
        let b = sh_basis(n);
        let mut e = [T::lit(0.0); 3];
        for (ch, out) in e.iter_mut().enumerate() {
            let terms: Vec<T> = (0..9).map(|k| sh[k][ch] * b[k]).collect();
            *out = T::sum(&terms).max(T::lit(0.0));
        }
        e
    }

    /// `hammersley` (ibl.glsl); [`crate::env::hammersley`] is this at f64.
    pub fn hammersley<T: Real>(i: u32, n: u32) -> [T; 2] {
        [
            T::from_u32(i) / T::from_u32(n),
            T::from_u32(i.reverse_bits()) * T::lit(2.328_306_4e-10),
        ]
    }

    /// `ggx_sample_h` (ibl.glsl).
    pub fn ggx_sample_h<T: Real>(xi: [T; 2], alpha: T) -> [T; 3] {
        let one = T::lit(1.0);
        let a2 = alpha * alpha;
        let phi = T::lit(2.0) * pi::<T>() * xi[0];
        let den = (one - xi[1]) + a2 * xi[1];
        let cos_t = ((one - xi[1]) / den).sqrt();
        let sin_t = (a2 * xi[1] / den).sqrt();
        [sin_t * phi.cos(), sin_t * phi.sin(), cos_t]
    }

    /// `as_sample_h` (ibl.glsl).
    pub fn as_sample_h<T: Real>(xi: [T; 2], eu: T, ev: T) -> [T; 3] {
        as_sample_h_log(xi, eu, ev).0
    }

    /// `as_sample_h_log` (ibl.glsl): the half vector, the exponent E at its φ and log2 cos θ.
    pub fn as_sample_h_log<T: Real>(xi: [T; 2], eu: T, ev: T) -> ([T; 3], T, T) {
        let one = T::lit(1.0);
        let zero = T::lit(0.0);
        let q = (T::lit(4.0) * xi[0]).floor().clamp(zero, T::lit(3.0));
        let r = T::lit(4.0) * xi[0] - q;
        let x = T::lit(0.5) * pi::<T>() * r.min(T::lit(0.999_999_9));
        let k = ((eu + one) / (ev + one)).sqrt();
        let dx = x.cos().max(zero);
        let dy = k * x.sin();
        let len = (dx * dx + dy * dy).max(T::lit(1e-30)).sqrt();
        let (dx, dy) = (dx / len, dy / len);
        let qv = q.exact();
        let cp = if qv == 1.0 || qv == 2.0 {
            zero - dx
        } else {
            dx
        };
        let sp = if qv >= 2.0 { zero - dy } else { dy };
        let e = eu.mul_square(cp) + ev.mul_square(sp);
        let log_cos = xi[1].max(T::lit(1e-30)).log2() * (one / (e + one));
        let cos_t = log_cos.exp2();
        let sin_t = (one - cos_t * cos_t).max(zero).sqrt();
        ([sin_t * cp, sin_t * sp, cos_t], e, log_cos)
    }

    /// `cosine_sample` (ibl.glsl).
    pub fn cosine_sample<T: Real>(xi: [T; 2]) -> [T; 3] {
        let r = xi[0].sqrt();
        let phi = T::lit(2.0) * pi::<T>() * xi[1];
        [
            r * phi.cos(),
            r * phi.sin(),
            (T::lit(1.0) - xi[0]).max(T::lit(0.0)).sqrt(),
        ]
    }

    /// `fis_lod` (ibl.glsl).
    pub fn fis_lod<T: Real>(pdf: T, n: u32, size: T) -> T {
        let omega_s = T::lit(1.0) / (T::from_u32(n) * pdf.max(T::lit(1e-30)));
        let omega_p = T::lit(4.0) * pi::<T>() / (T::lit(6.0) * size * size);
        (T::lit(0.5) * (omega_s / omega_p).log2()).max(T::lit(0.0))
    }

    /// `specular_occlusion` (ibl.glsl).
    pub fn specular_occlusion<T: Real>(nv: T, ao: T, roughness: T) -> T {
        let e = (T::lit(-16.0) * roughness - T::lit(1.0)).exp2();
        ((nv + ao).max(T::lit(0.0)).pow(e) - T::lit(1.0) + ao).clamp(T::lit(0.0), T::lit(1.0))
    }

    /// `acos01` (ibl.glsl): acos on [0, 1], Abramowitz & Stegun 4.4.45.
    pub fn acos01<T: Real>(x: T) -> T {
        (T::lit(1.0) - x).sqrt()
            * (T::lit(1.5707288)
                + x * (T::lit(-0.2121144) + x * (T::lit(0.0742610) - T::lit(0.0187293) * x)))
    }

    /// `cap_overlap` (ibl.glsl).
    pub fn cap_overlap<T: Real>(a1: T, a2: T, d: T) -> T {
        let lo = a1.max(a2) - a1.min(a2);
        let x = ((a1 + a2 - d) / (a1 + a2 - lo).max(T::lit(1e-6))).clamp(T::lit(0.0), T::lit(1.0));
        x * x * (T::lit(3.0) - T::lit(2.0) * x)
    }

    /// `cone_occlusion` (ibl.glsl).
    // 3.321928 is log2(10) as the GLSL writes it: the twin keeps the shader's literal.
    #[allow(clippy::approx_constant)]
    pub fn cone_occlusion<T: Real>(nv: T, ao: T, roughness: T) -> T {
        let one = T::lit(1.0);
        let zero = T::lit(0.0);
        let cos_visible = (one - ao).clamp(zero, one).sqrt();
        let alpha = roughness * roughness;
        let cos_lobe = (T::lit(-3.321928) * alpha).exp2().clamp(zero, one);
        let d = acos01(nv.clamp(zero, one));
        let visible = acos01(cos_visible);
        let lobe = acos01(cos_lobe);
        let caps = ((one - cos_visible) / (one - cos_lobe).max(T::lit(1e-7))).min(one);
        let open = acos01(zero);
        let share =
            caps * cap_overlap(visible, lobe, d) / cap_overlap(open, lobe, d).max(T::lit(1e-6));
        if ao.exact() >= 1.0 {
            one
        } else {
            share.clamp(zero, one)
        }
    }

    /// `fabric_diffuse_albedo` (ibl.glsl), from the material's `rs` and `flags`.
    pub fn fabric_diffuse_albedo<T: Real>(rs: T, flags: u32, nk2: T) -> T {
        let one = T::lit(1.0);
        if flags & crate::fabric::FLAG_COUPLED_DIFFUSE == 0 {
            return one;
        }
        let b = one - T::lit(0.5) * nk2.clamp(T::lit(0.0), one);
        let b2 = b * b;
        (one - rs) * (one - b2 * b2 * b)
    }

    /// `gtao_half_arc` (occlusion.glsl).
    pub fn gtao_half_arc<T: Real>(h: T, n: T) -> T {
        let two = T::lit(2.0);
        T::lit(0.25) * (n.cos() + two * h * n.sin() - (two * h - n).cos())
    }

    /// `gtao_arc` (occlusion.glsl).
    pub fn gtao_arc<T: Real>(h0: T, h1: T, n: T) -> T {
        gtao_half_arc(h0, n) + gtao_half_arc(h1, n)
    }

    /// `gtao_multibounce` (occlusion.glsl).
    pub fn gtao_multibounce<T: Real>(v: T, albedo: T) -> T {
        let a = T::lit(2.0404) * albedo - T::lit(0.3324);
        let b = T::lit(-4.7951) * albedo + T::lit(0.6417);
        let c = T::lit(2.7552) * albedo + T::lit(0.6903);
        v.max(((v * a + b) * v + c) * v)
            .clamp(T::lit(0.0), T::lit(1.0))
    }

    /// `dominant_dir` (ibl.glsl): `normalize(mix(n, r, t))`, mix as `n·(1 - t) + r·t` and
    /// normalize as `v / sqrt(dot(v, v))` (the forms Vulkan's precision rules inherit from).
    pub fn dominant_dir<T: Real>(n: [T; 3], r: [T; 3], roughness: T) -> [T; 3] {
        let one = T::lit(1.0);
        let a = roughness * roughness;
        let t = (one - a) * ((one - a).sqrt() + a);
        let d = [0, 1, 2].map(|k| n[k] * (one - t) + r[k] * t);
        let l = T::dot3(d, d).sqrt();
        [d[0] / l, d[1] / l, d[2] / l]
    }

    /// `cube_texel_dir` (cube.glsl); [`crate::render::environment::cube_texel_dir`] is this at
    /// f32.
    pub fn cube_texel_dir<T: Real>(face: u32, x: u32, y: u32, size: u32) -> [T; 3] {
        let st =
            |t: u32| (T::from_u32(t) + T::lit(0.5)) / T::from_u32(size) * T::lit(2.0) - T::lit(1.0);
        let (s, t) = (st(x), st(y));
        let one = T::lit(1.0);
        let d = match face {
            0 => [one, -t, -s],
            1 => [-one, -t, s],
            2 => [s, one, t],
            3 => [s, -one, -t],
            4 => [s, -t, one],
            _ => [-s, -t, -one],
        };
        // normalize(d): inherited from d / sqrt(dot(d, d)).
        let l = T::dot3(d, d).sqrt();
        [d[0] / l, d[1] / l, d[2] / l]
    }

    /// `equirect_uv` (cube.glsl): u in [0, 1] (not wrapped, unlike [`crate::env::dir_to_uv`]).
    pub fn equirect_uv<T: Real>(d: [T; 3]) -> [T; 2] {
        let two_pi = T::ideal(2.0 * std::f32::consts::PI, 2.0 * PI);
        let u = T::lit(0.5) + d[0].atan2(-d[2]) / two_pi;
        let v = d[1].clamp(T::lit(-1.0), T::lit(1.0)).acos() / pi::<T>();
        [u, v]
    }
}

// ---------------------------------------------------------------------------------------------
// The f32 twins.
// ---------------------------------------------------------------------------------------------

/// `env_dir` of ibl.glsl: the environment direction of world direction `w`, from the rows of
/// [`crate::env::env_from_world`].
pub fn env_dir(w: [f32; 3], rows: &[[f32; 3]; 3]) -> [f32; 3] {
    formula::env_dir(w, rows[0], rows[1], rows[2])
}

/// `ggx_sample_h` of ibl.glsl: a GGX half vector in the local frame, pdf D(h)·h.z.
pub fn ggx_sample_h(xi: [f32; 2], alpha: f32) -> [f32; 3] {
    formula::ggx_sample_h(xi, alpha)
}

/// `as_sample_h` of ibl.glsl: an A–S half vector in the local frame (the f32 twin of
/// [`super::brdf::sampling::sample_h`], with the GLSL's clamps: `r ≤ 0.9999999`, `xi.y ≥ 1e-30`).
pub fn as_sample_h(xi: [f32; 2], eu: f32, ev: f32) -> [f32; 3] {
    formula::as_sample_h(xi, eu, ev)
}

/// `as_sample_h_log` of ibl.glsl: [`as_sample_h`] with the exponent E = eu cos²φ + ev sin²φ at the
/// sample and log2 cos θ = log2(xi.y)/(E + 1) (hn^E' of any exponent E' is exp2(E'·log2 cos θ)).
pub fn as_sample_h_log(xi: [f32; 2], eu: f32, ev: f32) -> ([f32; 3], f32, f32) {
    formula::as_sample_h_log(xi, eu, ev)
}

/// `cosine_sample` of ibl.glsl: a cosine-distributed direction in the local frame.
pub fn cosine_sample(xi: [f32; 2]) -> [f32; 3] {
    formula::cosine_sample(xi)
}

/// `fis_lod` of ibl.glsl: the filtered-importance-sampling mip level.
pub fn fis_lod(pdf: f32, n: u32, size: f32) -> f32 {
    formula::fis_lod(pdf, n, size)
}

/// `specular_occlusion` of ibl.glsl (Lagarde & de Rousiers 2014).
pub fn specular_occlusion(nv: f32, ao: f32, roughness: f32) -> f32 {
    formula::specular_occlusion(nv, ao, roughness)
}

/// `cone_occlusion` of ibl.glsl: the share of a lobe of `roughness` about the mirror direction
/// (`nv` from the normal) that a visibility cone of cosine-weighted visibility `ao` leaves.
pub fn cone_occlusion(nv: f32, ao: f32, roughness: f32) -> f32 {
    formula::cone_occlusion(nv, ao, roughness)
}

/// `fabric_diffuse_albedo` of ibl.glsl.
pub fn fabric_diffuse_albedo(f: &GpuFabric, nk2: f32) -> f32 {
    formula::fabric_diffuse_albedo(f.rs, f.flags, nk2)
}

/// `gtao_half_arc` of occlusion.glsl: one side of a slice's cosine-weighted arc, from the view
/// vector to the horizon `h` (radians, signed by side), the normal's projection at angle `n`.
pub fn gtao_half_arc(h: f32, n: f32) -> f32 {
    formula::gtao_half_arc(h, n)
}

/// `gtao_arc` of occlusion.glsl: the cosine-weighted visible arc of a slice between horizons
/// `h0 ≤ 0 ≤ h1`, the normal's projection at angle `n` (radians from the view vector).
pub fn gtao_arc(h0: f32, h1: f32, n: f32) -> f32 {
    formula::gtao_arc(h0, h1, n)
}

/// `gtao_multibounce` of occlusion.glsl: visibility `v` raised for light bounced between
/// occluders of albedo `albedo`.
pub fn gtao_multibounce(v: f32, albedo: f32) -> f32 {
    formula::gtao_multibounce(v, albedo)
}

/// `equirect_uv` of cube.glsl.
pub fn equirect_uv(d: [f32; 3]) -> [f32; 2] {
    formula::equirect_uv(d)
}

// ---------------------------------------------------------------------------------------------
// The probe on the CPU, and its bounds.
// ---------------------------------------------------------------------------------------------

fn xyz(v: [f32; 4]) -> [f32; 3] {
    [v[0], v[1], v[2]]
}

/// What `glsl/ibl_probe.comp` computes, by the twins (the existing ones where they exist:
/// `sh_eval`, `hammersley` (f64, rounded to f32 here), `cube_texel_dir`).
pub fn ibl_probe_cpu(inp: &IblProbeInput) -> IblProbeOutput {
    let v4 = |v: [f32; 3], w: f32| [v[0], v[1], v[2], w];
    let rows = [xyz(inp.rot[0]), xyz(inp.rot[1]), xyz(inp.rot[2])];
    let sh: [[f32; 3]; 9] = std::array::from_fn(|k| xyz(inp.sh[k]));
    let xi = [inp.xi[0], inp.xi[1]];
    let [hx, hy] = formula::hammersley::<f64>(inp.counts[0], inp.counts[1]);
    let uv = equirect_uv(xyz(inp.dir));
    let c = inp.cube;
    IblProbeOutput {
        env_dir: v4(env_dir(xyz(inp.world), &rows), 0.0),
        irradiance: v4(formula::sh_irradiance(&sh, xyz(inp.normal)), 0.0),
        ggx: v4(ggx_sample_h(xi, inp.lobe[0]), 0.0),
        as_h: v4(as_sample_h(xi, inp.lobe[1], inp.lobe[2]), 0.0),
        cosine: v4(cosine_sample(xi), 0.0),
        cube: v4(formula::cube_texel_dir::<f32>(c[0], c[1], c[2], c[3]), 0.0),
        uv: [hx as f32, hy as f32, uv[0], uv[1]],
        scalars: [
            fis_lod(inp.lod[0], inp.counts[2], inp.lod[1]),
            specular_occlusion(inp.lod[2], inp.lod[3], inp.misc[0]),
            fabric_diffuse_albedo(&inp.fabric, inp.misc[1]),
            cone_occlusion(inp.lod[2], inp.lod[3], inp.misc[0]),
        ],
        occlusion: [
            gtao_arc(inp.arc[0], inp.arc[1], inp.arc[2]),
            gtao_multibounce(inp.misc[2], inp.misc[3]),
            gtao_half_arc(inp.arc[0], inp.arc[2]),
            0.0,
        ],
        dominant: v4(
            formula::dominant_dir::<f32>(xyz(inp.normal), xyz(inp.dir), inp.misc[0]),
            0.0,
        ),
    }
}

/// The probe's formulas at any [`Real`], from the input's f32 values (in memory order of
/// [`IblProbeOutput`]): at f64 the exact formulas, at [`Iv`] the bounds.
pub fn ibl_probe_eval<T: Real>(inp: &IblProbeInput) -> [T; IBL_PROBE_OUTPUTS] {
    let l = |x: f32| T::lit(x);
    let v3 = |v: [f32; 4]| [l(v[0]), l(v[1]), l(v[2])];
    let zero = l(0.0);
    let xi = [l(inp.xi[0]), l(inp.xi[1])];
    let sh: [[T; 3]; 9] = std::array::from_fn(|k| v3(inp.sh[k]));
    let e = formula::env_dir(
        v3(inp.world),
        v3(inp.rot[0]),
        v3(inp.rot[1]),
        v3(inp.rot[2]),
    );
    let irr = formula::sh_irradiance(&sh, v3(inp.normal));
    let g = formula::ggx_sample_h(xi, l(inp.lobe[0]));
    let a = formula::as_sample_h(xi, l(inp.lobe[1]), l(inp.lobe[2]));
    let cs = formula::cosine_sample(xi);
    let c = inp.cube;
    let cube = formula::cube_texel_dir::<T>(c[0], c[1], c[2], c[3]);
    let h = formula::hammersley::<T>(inp.counts[0], inp.counts[1]);
    let uv = formula::equirect_uv(v3(inp.dir));
    let dom = formula::dominant_dir(v3(inp.normal), v3(inp.dir), l(inp.misc[0]));
    [
        e[0],
        e[1],
        e[2],
        zero,
        irr[0],
        irr[1],
        irr[2],
        zero,
        g[0],
        g[1],
        g[2],
        zero,
        a[0],
        a[1],
        a[2],
        zero,
        cs[0],
        cs[1],
        cs[2],
        zero,
        cube[0],
        cube[1],
        cube[2],
        zero,
        h[0],
        h[1],
        uv[0],
        uv[1],
        formula::fis_lod(l(inp.lod[0]), inp.counts[2], l(inp.lod[1])),
        formula::specular_occlusion(l(inp.lod[2]), l(inp.lod[3]), l(inp.misc[0])),
        formula::fabric_diffuse_albedo(l(inp.fabric.rs), inp.fabric.flags, l(inp.misc[1])),
        formula::cone_occlusion(l(inp.lod[2]), l(inp.lod[3]), l(inp.misc[0])),
        formula::gtao_arc(l(inp.arc[0]), l(inp.arc[1]), l(inp.arc[2])),
        formula::gtao_multibounce(l(inp.misc[2]), l(inp.misc[3])),
        formula::gtao_half_arc(l(inp.arc[0]), l(inp.arc[2])),
        zero,
        dom[0],
        dom[1],
        dom[2],
        zero,
    ]
}

/// The enclosure of each output of `inp` under model `M` (see the module docs).
pub fn ibl_probe_bounds<M: Model>(inp: &IblProbeInput) -> [Iv<M>; IBL_PROBE_OUTPUTS] {
    ibl_probe_eval::<Iv<M>>(inp)
}

/// `x` moved by a whole number of periods (1: u of the equirect map) next to `near`.
pub fn unwrap_near(x: f64, near: f64) -> f64 {
    x + (near - x).round()
}

/// `|got - twin|` as a fraction of the bound's width `hi - lo` (the largest difference two
/// values inside it can have), modulo 1 for `circular`: 0 when equal, infinite when `got` is not
/// finite or the bound is a single value that `got` misses. Whether `got` lies inside is
/// [`in_bound`]'s question.
pub fn bound_fraction<M: Model>(bound: Iv<M>, twin: f64, got: f64, circular: bool) -> f64 {
    if !got.is_finite() {
        return f64::INFINITY;
    }
    let d = if circular {
        let d = (got - twin).rem_euclid(1.0);
        d.min(1.0 - d)
    } else {
        (got - twin).abs()
    };
    if d == 0.0 {
        0.0
    } else if bound.width() > 0.0 {
        d / bound.width()
    } else {
        f64::INFINITY
    }
}

/// Whether `x` lies in `bound`, modulo 1 for `circular`, with a relative slack `slack` (for f64
/// values, whose own rounding the f32 enclosure need not contain).
pub fn in_bound<M: Model>(bound: Iv<M>, x: f64, circular: bool, slack: f64) -> bool {
    if !x.is_finite() {
        return false;
    }
    let x = if circular && bound.lo.is_finite() && bound.hi.is_finite() {
        unwrap_near(x, 0.5 * (bound.lo + bound.hi))
    } else {
        x
    };
    let s = slack * x.abs().max(1e-300);
    bound.lo - s <= x && x <= bound.hi + s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The share of a cap of half-angle `lobe` about an axis `d` from the normal that lies within
    /// the cap of half-angle `visible` about the normal, over its share within the hemisphere:
    /// quadrature over the lobe's cap in f64 (uniform in solid angle), no smoothstep.
    fn exact_cone_share(visible: f64, lobe: f64, d: f64) -> f64 {
        let (nt, np) = (400, 400);
        let (mut inside, mut above) = (0.0, 0.0);
        for i in 0..nt {
            let t = (i as f64 + 0.5) / nt as f64 * lobe;
            for j in 0..np {
                let p = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
                // A direction at angle t from the lobe's axis, the axis at angle d from the
                // normal (z), in the xz plane: its cosine to the normal.
                let cz = t.cos() * d.cos() - t.sin() * p.cos() * d.sin();
                let w = t.sin();
                if cz > visible.cos() {
                    inside += w;
                }
                if cz > 0.0 {
                    above += w;
                }
            }
        }
        if above > 0.0 {
            inside / above
        } else {
            0.0
        }
    }

    #[test]
    fn cone_occlusion_is_the_caps_overlap() {
        // Open: all; closed: nothing; seen square-on, the caps are concentric and the smoothstep
        // plays no part, so the share is exact.
        for &nv in &[0.0f32, 0.2, 0.7, 1.0] {
            for &r in &[0.0f32, 0.3, 0.9, 1.0] {
                assert_eq!(cone_occlusion(nv, 1.0, r), 1.0);
                assert_eq!(cone_occlusion(nv, 0.0, r), 0.0);
            }
        }
        // Against the caps' exact overlap (quadrature, f64): the smoothstep's error, measured
        // over ao 0.05..0.95, roughness 0.2..1, n·v 0.05..1, stays within MAX (below);
        // occlusion never grows with ao falling, and at grazing views it takes more than ao.
        let mut worst = 0.0f64;
        for &ao in &[0.05f64, 0.2, 0.4, 0.6, 0.8, 0.95] {
            for &nv in &[1.0f64, 0.8, 0.5, 0.3, 0.15, 0.05] {
                for &r in &[0.2f64, 0.4, 0.6, 0.8, 1.0] {
                    let ours = formula::cone_occlusion::<f64>(nv, ao, r);
                    let visible = (1.0 - ao).sqrt().acos();
                    let lobe = 10f64.powf(-(r * r)).acos();
                    let exact = exact_cone_share(visible, lobe, nv.acos());
                    worst = worst.max((ours - exact).abs());
                    if nv == 1.0 {
                        assert!(
                            (ours - exact).abs() < 5e-3,
                            "ao {ao} nv 1 r {r}: {ours} vs {exact}"
                        );
                    }
                    let less = formula::cone_occlusion::<f64>(nv, ao * 0.5, r);
                    assert!(less <= ours + 1e-12, "ao {ao} nv {nv} r {r}");
                }
            }
            let grazing = formula::cone_occlusion::<f64>(0.05, ao, 0.9);
            assert!(grazing < ao, "ao {ao}: grazing {grazing}");
        }
        // Measured 0.117 (ao 0.05-0.95, the smoothstep against the caps' true overlap; the
        // quadrature itself is good to about 0.003, the square-on cases say): 0.13.
        const MAX: f64 = 0.13;
        assert!(worst < MAX, "worst {worst}");
        eprintln!("cone_occlusion against the exact caps: worst {worst:.4}");
    }

    #[test]
    fn gtao_half_arc_is_its_integral() {
        // ∫ from 0 to h of cos(θ − n)·|sin θ| dθ by the midpoint rule (f64, 20,000 steps), for
        // horizons on both sides and normals across the half-circle; and the two halves make
        // the unoccluded slice's cos n + n·sin n.
        let pi = std::f64::consts::PI;
        for &n in &[-1.2f64, -0.4, 0.0, 0.3, 1.0, 1.5] {
            for &h in &[-2.5f64, -1.0, -0.2, 0.0, 0.4, 1.3, 2.9] {
                let steps = 20_000;
                let dt = h / steps as f64;
                let exact: f64 = (0..steps)
                    .map(|i| {
                        let t = (i as f64 + 0.5) * dt;
                        (t - n).cos() * t.sin().abs() * dt.abs()
                    })
                    .sum();
                let got = formula::gtao_half_arc(h, n);
                assert!((got - exact).abs() < 1e-6, "n {n} h {h}: {got} vs {exact}");
                assert!((gtao_half_arc(h as f32, n as f32) as f64 - exact).abs() < 1e-5);
            }
            let open = formula::gtao_arc(n - 0.5 * pi, n + 0.5 * pi, n);
            assert!(
                (open - (n.cos() + n * n.sin())).abs() < 1e-12,
                "n {n}: {open}"
            );
        }
    }

    #[test]
    fn twins_lie_in_their_tight_bounds() {
        for (xi, e) in [
            ([0.1f32, 0.7f32], (10.0f32, 1000.0f32)),
            ([0.2499999, 0.999_999_9], (1.0, 1.0)),
            ([0.75, 0.0], (1e4, 1.0)),
        ] {
            let t = as_sample_h(xi, e.0, e.1);
            let b = formula::as_sample_h(
                [Iv::<CpuF32>::lit(xi[0]), Iv::lit(xi[1])],
                Iv::lit(e.0),
                Iv::lit(e.1),
            );
            for k in 0..3 {
                assert!(
                    b[k].contains(t[k] as f64),
                    "{xi:?} {e:?} {k}: {} {:?}",
                    t[k],
                    b[k]
                );
            }
        }
    }
}
