//! The fabric material: its parameters, the glTF extension `WEFT_materials_fabric` that carries
//! them, the weave patterns, and the `#[repr(C)]` structs the shaders read
//! (`glsl/include/fabric.glsl`, `glsl/weave.comp`).
//!
//! The model is `docs/fabric-model.md` (the project's twin of the design page). In short: an
//! Ashikhmin–Shirley lobe whose exponents swap with the direction of the thread on top, plus a
//! Lambert (or A–S coupled) diffuse term that is 0 in the gaps between threads and darkened where
//! a thread dives under another, all weighted by the weave's coverage of the pixel footprint.
//!
//! Parameters are clamped when a scene is loaded ([`FabricParams::from_gltf_extension`] warns), and
//! again, silently, by [`FabricParams::to_gpu`], so no NaN, infinity or out-of-range value can reach
//! a shader whatever built the params.

pub mod coverage;
pub mod draft;
mod pattern;
pub mod presets;
mod texture;

pub use pattern::{WeavePattern, MAX_CELLS};
pub use texture::{
    weave_level0_size, weave_level_size, weave_mip_count, weave_texels_cpu, ThreadColourTable,
    WeavePush, WeaveSat, WEAVE_TEXELS_PER_CELL, WEAVE_TEXEL_TOLERANCE,
};

use crate::Error;
use crate::Warning;

/// The glTF extension name.
pub const EXTENSION_NAME: &str = "WEFT_materials_fabric";

/// `GpuFabric::flags` bit: use the A–S coupled diffuse (eq. 5) instead of Lambert.
pub const FLAG_COUPLED_DIFFUSE: u32 = 1;

/// `GpuFabric::flags` bit: the thread colours are multiplied by the material's base colour texture.
pub const FLAG_TEXTURE_BASE_COLOR: u32 = 2;
/// `GpuFabric::flags` bit: the thread colours are multiplied by the material's sheen colour texture.
pub const FLAG_TEXTURE_SHEEN_COLOR: u32 = 4;
/// `GpuFabric::flags` bit 3: thread-by-thread colours (`warp_colours`, `weft_colours`); the
/// G-buffer pass reads them from the thread-colour buffer at `GpuFabric::colours` and writes the
/// footprint's shadow-weighted thread colour, which the lighting pass takes as both threads' albedo.
pub const FLAG_THREAD_COLOURS: u32 = 8;
/// `GpuFabric::flags` bit 4: a sheet of cloth (the extension's `transmission`): its gaps let
/// light straight through (the transparent pass blends it over what is behind by its thread
/// coverage) and each thread passes `GpuFabric::transmission` of its diffuse light through to
/// the other side (docs/fabric-model.md §9).
pub const FLAG_SHEET: u32 = 16;
/// The longest colour sequence of a warp or a weft (a tartan's sett is rarely over 200 threads).
pub const MAX_THREAD_COLOURS: usize = 256;

/// Which texture of the material, if any, is multiplied over the thread colours (the extension's
/// `thread_texture`): a print, a dye, a damask over the weave.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ThreadTexture {
    /// `"base_color"`: the material's `baseColorTexture` (the default; white where it has none).
    #[default]
    BaseColor,
    /// `"sheen_color"`: `KHR_materials_sheen`'s `sheenColorTexture` (white where it has none).
    SheenColor,
    /// `"none"`: plain thread colours.
    None,
}

impl ThreadTexture {
    /// The extension's spellings.
    pub const NAMES: [&'static str; 3] = ["base_color", "sheen_color", "none"];

    pub fn name(self) -> &'static str {
        match self {
            ThreadTexture::BaseColor => "base_color",
            ThreadTexture::SheenColor => "sheen_color",
            ThreadTexture::None => "none",
        }
    }

    pub fn by_name(name: &str) -> Option<ThreadTexture> {
        match name {
            "base_color" => Some(ThreadTexture::BaseColor),
            "sheen_color" => Some(ThreadTexture::SheenColor),
            "none" => Some(ThreadTexture::None),
            _ => None,
        }
    }

    /// Its `GpuFabric::flags` bit.
    pub fn flag(self) -> u32 {
        match self {
            ThreadTexture::BaseColor => FLAG_TEXTURE_BASE_COLOR,
            ThreadTexture::SheenColor => FLAG_TEXTURE_SHEEN_COLOR,
            ThreadTexture::None => 0,
        }
    }
}

/// Accepted range of `repeat` (s_p, texture units).
pub const REPEAT_RANGE: (f32, f32) = (1e-6, 1e6);
/// Accepted range of the exponents.
pub const EXPONENT_RANGE: (f32, f32) = (0.0, 1e6);

/// The fabric model's parameters, as a scene file gives them.
#[derive(Clone, Debug, PartialEq)]
pub struct FabricParams {
    /// Which thread is on top in each cell.
    pub pattern: WeavePattern,
    /// `s_p`: the plain weave's repeat (two cells), texture units; a cell is `s_p/2`.
    pub repeat: f32,
    /// `s_g`: the gap between neighbouring threads, texture units, in `[0, s_p/2]`.
    pub gap: f32,
    /// A–S exponent along the thread (large: the microfacet normals of a thread barely tilt along
    /// it, so its highlight is narrow along the thread and stretched across it).
    pub e_along: f32,
    /// A–S exponent across the thread (small).
    pub e_across: f32,
    /// Diffuse albedo of the warp (vertical) thread, linear RGB in [0, 1].
    pub rd_warp: [f32; 3],
    /// Diffuse albedo of the weft (horizontal) thread.
    pub rd_weft: [f32; 3],
    /// Specular reflectance at normal incidence (Schlick), [0, 1].
    pub rs: f32,
    /// How much a thread's diffuse term is darkened where it dives under another: the factor is
    /// `1 - shadow_strength`. [0, 1].
    pub shadow_strength: f32,
    /// The fraction of each thread's length (between crossings, plain weave) that is darkened,
    /// measured from the edge of the crossing thread. [0, 1].
    pub shadow_width: f32,
    /// A–S eq. 5 coupled diffuse instead of the paper's Lambert `Rd/π`.
    pub coupled_diffuse: bool,
    /// The material's texture multiplied over the thread colours.
    pub thread_texture: ThreadTexture,
    /// Thread-by-thread colours of the warp (yarn-dyed stripes, checks, tartans): warp thread
    /// `i` (cell column `i`, counted from u = 0) has `warp_colours[i % len]`, linear RGB in
    /// [0, 1]; empty: every warp thread has `rd_warp`. At most [`MAX_THREAD_COLOURS`].
    pub warp_colours: Vec<[f32; 3]>,
    /// The same for the weft (pick `j`, cell row `j`, counted from v = 0).
    pub weft_colours: Vec<[f32; 3]>,
    /// A single sheet of cloth with nothing behind it (a curtain, a veil, a shirt held to the
    /// light): `Some(τ)`, the threads' diffuse transmittance in [0, 1], the share of a thread's
    /// diffuse light that leaves through its other side (as KHR_materials_diffuse_transmission
    /// splits a diffuse lobe: τ·albedo/π through, (1 − τ)·albedo/π reflected); its gaps let light
    /// straight through. `None` (the default): the cloth covers something (upholstery, a lined
    /// garment): its gaps are dark and nothing goes through.
    pub transmission: Option<f32>,
}

impl Default for FabricParams {
    fn default() -> Self {
        FabricParams {
            pattern: WeavePattern::plain(),
            repeat: 0.05,
            gap: 0.005,
            e_along: 200.0,
            e_across: 10.0,
            rd_warp: [0.5; 3],
            rd_weft: [0.5; 3],
            rs: 0.04,
            shadow_strength: 0.5,
            shadow_width: 0.25,
            coupled_diffuse: false,
            thread_texture: ThreadTexture::BaseColor,
            warp_colours: Vec::new(),
            weft_colours: Vec::new(),
            transmission: None,
        }
    }
}

/// One material as the shaders read it (std430, 80 bytes; `GpuFabric` in `glsl/include/fabric.glsl`).
///
/// | offset | field | meaning |
/// |---|---|---|
/// | 0  | `rd_warp: vec3`, `rs: float` | warp diffuse albedo; Schlick's Rs |
/// | 16 | `rd_weft: vec3`, `e_along: float` | weft diffuse albedo; exponent along a thread |
/// | 32 | `e_across`, `cell_per_uv` | exponent across; cells per texture unit (`2/s_p`) |
/// | 40 | `flags: uint`, `shadow_strength` | bit 0 = coupled diffuse; bit 1, 2 = thread texture base, sheen colour |
/// | 48 | `pattern_lo`, `pattern_hi: uint` | bit `8j+i` = cell (i, j) weft-up |
/// | 56 | `cols`, `rows: uint` | pattern size in cells (1..8) |
/// | 64 | `gap`, `shadow_dist` | `s_g/s_p` and `shadow_width/2`, in cells |
/// | 72 | `colours`, `transmission` | with flag bit 3: where the material's record starts in the thread-colour buffer (vec4s; [`ThreadColourTable`]); with flag bit 4 (a sheet), the threads' diffuse transmittance τ, else 0 |
///
/// The weave texture covers one repeat: sample it at `st = (u, v)·cell_per_uv / (cols, rows)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuFabric {
    pub rd_warp: [f32; 3],
    pub rs: f32,
    pub rd_weft: [f32; 3],
    pub e_along: f32,
    pub e_across: f32,
    pub cell_per_uv: f32,
    pub flags: u32,
    pub shadow_strength: f32,
    pub pattern_lo: u32,
    pub pattern_hi: u32,
    pub cols: u32,
    pub rows: u32,
    pub gap: f32,
    pub shadow_dist: f32,
    pub colours: u32,
    pub transmission: f32,
}

const _: () = {
    assert!(std::mem::size_of::<GpuFabric>() == 80);
    assert!(std::mem::offset_of!(GpuFabric, rs) == 12);
    assert!(std::mem::offset_of!(GpuFabric, rd_weft) == 16);
    assert!(std::mem::offset_of!(GpuFabric, e_across) == 32);
    assert!(std::mem::offset_of!(GpuFabric, flags) == 40);
    assert!(std::mem::offset_of!(GpuFabric, pattern_lo) == 48);
    assert!(std::mem::offset_of!(GpuFabric, cols) == 56);
    assert!(std::mem::offset_of!(GpuFabric, gap) == 64);
};

impl GpuFabric {
    /// The struct's bytes as the shader reads them (little-endian, no padding).
    pub fn to_bytes(&self) -> [u8; 80] {
        // The struct is #[repr(C)] and Pod with no padding: its bytes are the std430 layout.
        bytemuck::bytes_of(self)
            .try_into()
            .expect("the size is asserted at compile time")
    }
}

/// The mean of `colours` (linear), or `fallback` when there are none: what a NaN entry of a
/// colour sequence becomes.
fn p_mean(colours: &[[f32; 3]], fallback: [f32; 3]) -> [f32; 3] {
    let ok: Vec<&[f32; 3]> = colours
        .iter()
        .filter(|c| c.iter().all(|x| x.is_finite()))
        .collect();
    if ok.is_empty() {
        return fallback;
    }
    std::array::from_fn(|k| ok.iter().map(|c| c[k]).sum::<f32>() / ok.len() as f32)
}

/// Clamps `x` into `[lo, hi]`; NaN becomes `fallback`.
fn clamp_or(x: f32, lo: f32, hi: f32, fallback: f32) -> f32 {
    if x.is_nan() {
        fallback
    } else {
        x.clamp(lo, hi)
    }
}

impl FabricParams {
    /// The plain-weave repeat `s_p` clamped, and the pattern repeat in texture units along u and v
    /// (`cols·s_p/2`, `rows·s_p/2`).
    pub fn repeat_uv(&self) -> [f64; 2] {
        let sp = clamp_or(self.repeat, REPEAT_RANGE.0, REPEAT_RANGE.1, 0.05) as f64;
        [
            self.pattern.cols() as f64 * sp / 2.0,
            self.pattern.rows() as f64 * sp / 2.0,
        ]
    }

    /// The params with every value in range (NaN → the default, out of range → the nearest bound):
    /// what [`Self::to_gpu`] uses. No warnings: loading warns, see [`Self::from_gltf_extension`].
    pub fn sanitized(&self) -> FabricParams {
        let d = FabricParams::default();
        let repeat = clamp_or(self.repeat, REPEAT_RANGE.0, REPEAT_RANGE.1, d.repeat);
        let (elo, ehi) = EXPONENT_RANGE;
        let rgb = |c: [f32; 3], f: [f32; 3]| {
            [
                clamp_or(c[0], 0.0, 1.0, f[0]),
                clamp_or(c[1], 0.0, 1.0, f[1]),
                clamp_or(c[2], 0.0, 1.0, f[2]),
            ]
        };
        FabricParams {
            pattern: self.pattern,
            repeat,
            gap: clamp_or(self.gap, 0.0, repeat / 2.0, d.gap.min(repeat / 2.0)),
            e_along: clamp_or(self.e_along, elo, ehi, d.e_along),
            e_across: clamp_or(self.e_across, elo, ehi, d.e_across),
            rd_warp: rgb(self.rd_warp, d.rd_warp),
            rd_weft: rgb(self.rd_weft, d.rd_weft),
            rs: clamp_or(self.rs, 0.0, 1.0, d.rs),
            shadow_strength: clamp_or(self.shadow_strength, 0.0, 1.0, d.shadow_strength),
            shadow_width: clamp_or(self.shadow_width, 0.0, 1.0, d.shadow_width),
            coupled_diffuse: self.coupled_diffuse,
            thread_texture: self.thread_texture,
            warp_colours: self
                .warp_colours
                .iter()
                .take(MAX_THREAD_COLOURS)
                .map(|&c| rgb(c, p_mean(&self.warp_colours, d.rd_warp)))
                .collect(),
            weft_colours: self
                .weft_colours
                .iter()
                .take(MAX_THREAD_COLOURS)
                .map(|&c| rgb(c, p_mean(&self.weft_colours, d.rd_weft)))
                .collect(),
            transmission: self.transmission.map(|t| clamp_or(t, 0.0, 1.0, 0.0)),
        }
    }

    /// Whether the threads carry colour sequences (either side).
    pub fn has_thread_colours(&self) -> bool {
        !self.warp_colours.is_empty() || !self.weft_colours.is_empty()
    }

    /// The colour of warp thread `i` and of pick `j` (the sequences, else `rd_warp`, `rd_weft`).
    pub fn thread_colour(&self, warp: bool, index: usize) -> [f32; 3] {
        let (list, rd) = if warp {
            (&self.warp_colours, self.rd_warp)
        } else {
            (&self.weft_colours, self.rd_weft)
        };
        if list.is_empty() {
            rd
        } else {
            list[index % list.len()]
        }
    }

    /// The material as the shaders read it; values are sanitised first (see [`Self::sanitized`]).
    pub fn to_gpu(&self) -> GpuFabric {
        let p = self.sanitized();
        GpuFabric {
            rd_warp: p.rd_warp,
            rs: p.rs,
            rd_weft: p.rd_weft,
            e_along: p.e_along,
            e_across: p.e_across,
            cell_per_uv: (2.0 / p.repeat as f64) as f32,
            flags: if p.coupled_diffuse {
                FLAG_COUPLED_DIFFUSE
            } else {
                0
            } | p.thread_texture.flag()
                | if p.has_thread_colours() {
                    FLAG_THREAD_COLOURS
                } else {
                    0
                }
                | if p.transmission.is_some() {
                    FLAG_SHEET
                } else {
                    0
                },
            shadow_strength: p.shadow_strength,
            pattern_lo: p.pattern.bits_lo(),
            pattern_hi: p.pattern.bits_hi(),
            cols: p.pattern.cols() as u32,
            rows: p.pattern.rows() as u32,
            gap: ((p.gap as f64 / p.repeat as f64) as f32).clamp(0.0, 0.5),
            shadow_dist: 0.5 * p.shadow_width,
            // Set by the renderer, which lays out the thread-colour buffer.
            colours: 0,
            transmission: p.transmission.unwrap_or(0.0),
        }
    }

    /// Push constants for building this material's weave texture, level of size `width × height`.
    pub fn weave_push(&self, width: u32, height: u32) -> WeavePush {
        let g = self.to_gpu();
        WeavePush {
            pattern_lo: g.pattern_lo,
            pattern_hi: g.pattern_hi,
            cols: g.cols,
            rows: g.rows,
            gap: g.gap,
            shadow_dist: g.shadow_dist,
            shadow_strength: g.shadow_strength,
            width,
            height,
        }
    }

    /// Parses the `WEFT_materials_fabric` extension object of material `material_name`.
    ///
    /// Missing fields take [`FabricParams::default`]'s values. Out-of-range numbers are clamped
    /// with a warning naming the material, the field and the range; unknown fields are warned
    /// about and ignored. Non-numbers where a number belongs, NaN or infinite numbers, unknown
    /// pattern names and malformed custom patterns are errors naming the material and the field.
    /// The schema is in `docs/fabric-model.md`.
    pub fn from_gltf_extension(
        value: &serde_json::Value,
        material_name: &str,
        warnings: &mut Vec<Warning>,
    ) -> crate::Result<FabricParams> {
        let ctx = Ctx {
            material: material_name,
        };
        let obj = value.as_object().ok_or_else(|| {
            Error::input(format!(
                "material '{material_name}': {EXTENSION_NAME} must be a JSON object, got {}",
                short(value)
            ))
        })?;
        let d = FabricParams::default();
        let mut p = d.clone();
        let mut rd: Option<[f32; 3]> = None;
        let mut rd_warp: Option<[f32; 3]> = None;
        let mut rd_weft: Option<[f32; 3]> = None;
        let mut raw_gap: Option<f32> = None;

        for (key, v) in obj {
            match key.as_str() {
                "pattern" => p.pattern = ctx.pattern(v)?,
                "repeat" => p.repeat = ctx.number(key, v, REPEAT_RANGE.0, REPEAT_RANGE.1, "s_p > 0", warnings)?,
                // The gap's upper bound depends on the repeat: checked below.
                "gap" => raw_gap = Some(ctx.finite(key, v)?),
                "e_along" => p.e_along = ctx.number(key, v, EXPONENT_RANGE.0, EXPONENT_RANGE.1, "", warnings)?,
                "e_across" => p.e_across = ctx.number(key, v, EXPONENT_RANGE.0, EXPONENT_RANGE.1, "", warnings)?,
                "rd" => rd = Some(ctx.colour(key, v, warnings)?),
                "rd_warp" => rd_warp = Some(ctx.colour(key, v, warnings)?),
                "rd_weft" => rd_weft = Some(ctx.colour(key, v, warnings)?),
                "warp_colours" => p.warp_colours = ctx.colours(key, v, warnings)?,
                "weft_colours" => p.weft_colours = ctx.colours(key, v, warnings)?,
                "rs" => p.rs = ctx.number(key, v, 0.0, 1.0, "", warnings)?,
                "shadow_strength" => p.shadow_strength = ctx.number(key, v, 0.0, 1.0, "", warnings)?,
                "shadow_width" => p.shadow_width = ctx.number(key, v, 0.0, 1.0, "", warnings)?,
                "transmission" => {
                    p.transmission = Some(ctx.number(key, v, 0.0, 1.0, "the threads' diffuse transmittance", warnings)?)
                }
                "thread_texture" => {
                    let name = v.as_str().ok_or_else(|| {
                        ctx.err(key, format!("must be one of {:?}, got {}", ThreadTexture::NAMES, short(v)))
                    })?;
                    p.thread_texture = ThreadTexture::by_name(name).ok_or_else(|| {
                        ctx.err(
                            key,
                            format!("is \"{name}\", which is not one of {:?}", ThreadTexture::NAMES),
                        )
                    })?
                }
                "coupled_diffuse" => {
                    p.coupled_diffuse = v
                        .as_bool()
                        .ok_or_else(|| ctx.err(key, format!("must be true or false, got {}", short(v))))?
                }
                // glTF's own extension points, allowed on every object.
                "extensions" | "extras" => {}
                other => warnings.push(Warning(format!(
                    "material '{material_name}': {EXTENSION_NAME} has unknown field '{other}' (ignored); \
                     known fields: pattern, repeat, gap, e_along, e_across, rd, rd_warp, rd_weft, \
                     warp_colours, weft_colours, rs, shadow_strength, shadow_width, coupled_diffuse, \
                     thread_texture, transmission"
                ))),
            }
        }
        if let Some(g) = raw_gap {
            let hi = p.repeat / 2.0;
            p.gap = g.clamp(0.0, hi);
            if p.gap != g {
                warnings.push(Warning(format!(
                    "material '{material_name}': {EXTENSION_NAME}.gap = {g} is outside [0, repeat/2 = {hi}]; clamped to {}",
                    p.gap
                )));
            }
        } else {
            p.gap = d.gap.min(p.repeat / 2.0);
        }
        let base = rd.unwrap_or(d.rd_warp);
        p.rd_warp = rd_warp.unwrap_or(base);
        p.rd_weft = rd_weft.unwrap_or(base);
        if p.has_thread_colours() {
            ThreadColourTable::check(&p).map_err(|e| {
                Error::input(format!(
                    "material '{material_name}': {EXTENSION_NAME}.warp_colours/weft_colours: {e}"
                ))
            })?;
        }
        Ok(p)
    }
}

/// Error and warning context while parsing one material's extension.
struct Ctx<'a> {
    material: &'a str,
}

impl Ctx<'_> {
    fn err(&self, field: &str, what: String) -> Error {
        Error::input(format!(
            "material '{}': {EXTENSION_NAME}.{field} {what}",
            self.material
        ))
    }

    /// A finite number, or an error.
    fn finite(&self, field: &str, v: &serde_json::Value) -> crate::Result<f32> {
        let x = v
            .as_f64()
            .ok_or_else(|| self.err(field, format!("must be a number, got {}", short(v))))?;
        if !x.is_finite() || x.abs() > f32::MAX as f64 {
            return Err(self.err(field, format!("must be a finite number, got {x}")));
        }
        Ok(x as f32)
    }

    /// A finite number clamped into `[lo, hi]` with a warning when it was outside.
    fn number(
        &self,
        field: &str,
        v: &serde_json::Value,
        lo: f32,
        hi: f32,
        note: &str,
        warnings: &mut Vec<Warning>,
    ) -> crate::Result<f32> {
        let x = self.finite(field, v)?;
        let c = x.clamp(lo, hi);
        if c != x {
            let note = if note.is_empty() {
                String::new()
            } else {
                format!(" ({note})")
            };
            warnings.push(Warning(format!(
                "material '{}': {EXTENSION_NAME}.{field} = {x} is outside [{lo}, {hi}]{note}; clamped to {c}",
                self.material
            )));
        }
        Ok(c)
    }

    /// `[r, g, b]` or one number for grey, each in [0, 1].
    fn colour(
        &self,
        field: &str,
        v: &serde_json::Value,
        warnings: &mut Vec<Warning>,
    ) -> crate::Result<[f32; 3]> {
        if v.is_number() {
            let x = self.number(field, v, 0.0, 1.0, "", warnings)?;
            return Ok([x; 3]);
        }
        let a = v.as_array().filter(|a| a.len() == 3).ok_or_else(|| {
            self.err(
                field,
                format!(
                    "must be [r, g, b] (three numbers in [0, 1]) or one number, got {}",
                    short(v)
                ),
            )
        })?;
        let mut c = [0.0; 3];
        for (k, x) in a.iter().enumerate() {
            c[k] = self.number(&format!("{field}[{k}]"), x, 0.0, 1.0, "", warnings)?;
        }
        Ok(c)
    }

    /// A colour sequence: an array of 1 to [`MAX_THREAD_COLOURS`] colours, each as `colour`.
    fn colours(
        &self,
        field: &str,
        v: &serde_json::Value,
        warnings: &mut Vec<Warning>,
    ) -> crate::Result<Vec<[f32; 3]>> {
        let a = v
            .as_array()
            .filter(|a| (1..=MAX_THREAD_COLOURS).contains(&a.len()))
            .ok_or_else(|| {
                self.err(
                    field,
                    format!(
                        "must be an array of 1 to {MAX_THREAD_COLOURS} colours (each [r, g, b] in [0, 1] or one number), one per thread of the sequence, got {}",
                        short(v)
                    ),
                )
            })?;
        a.iter()
            .enumerate()
            .map(|(i, c)| self.colour(&format!("{field}[{i}]"), c, warnings))
            .collect()
    }

    fn pattern(&self, v: &serde_json::Value) -> crate::Result<WeavePattern> {
        if let Some(name) = v.as_str() {
            return WeavePattern::by_name(name).ok_or_else(|| {
                self.err(
                    "pattern",
                    format!(
                        "is \"{name}\", which is not a known pattern; use one of {:?} or an array of \
                         rows like [\"-|\", \"|-\"] ('-' weft up, '|' warp up)",
                        WeavePattern::NAMES
                    ),
                )
            });
        }
        if let Some(rows) = v.as_array() {
            let strs: Option<Vec<&str>> = rows.iter().map(|r| r.as_str()).collect();
            let strs = strs.ok_or_else(|| {
                self.err(
                    "pattern",
                    format!("must be an array of strings, got {}", short(v)),
                )
            })?;
            return WeavePattern::from_rows(&strs).map_err(|e| self.err("pattern", e.to_string()));
        }
        Err(self.err(
            "pattern",
            format!(
                "must be a pattern name ({:?}) or an array of row strings, got {}",
                WeavePattern::NAMES,
                short(v)
            ),
        ))
    }
}

/// A JSON value for a message, cut to a readable length.
fn short(v: &serde_json::Value) -> String {
    let s = v.to_string();
    if s.chars().count() > 60 {
        format!("{}…", s.chars().take(60).collect::<String>())
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn parse(v: serde_json::Value) -> (crate::Result<FabricParams>, Vec<Warning>) {
        let mut w = Vec::new();
        let r = FabricParams::from_gltf_extension(&v, "cloth", &mut w);
        (r, w)
    }

    #[test]
    fn example_object_parses_without_warnings() {
        let (p, w) = parse(
            json!({"pattern": "plain", "repeat": 0.05, "gap": 0.005, "e_along": 200.0,
            "e_across": 10.0, "rd": [0.6,0.1,0.1], "rs": 0.04, "shadow_strength": 0.5, "shadow_width": 0.25}),
        );
        let p = p.unwrap();
        assert!(w.is_empty(), "{w:?}");
        assert_eq!(p.rd_warp, [0.6, 0.1, 0.1]);
        assert_eq!(p.rd_weft, [0.6, 0.1, 0.1]);
        assert_eq!(p.pattern, WeavePattern::plain());
        assert!(!p.coupled_diffuse);
    }

    #[test]
    fn defaults_and_separate_colours() {
        let (p, w) = parse(
            json!({"rd": 0.3, "rd_weft": [0.1, 0.2, 0.3], "coupled_diffuse": true, "pattern": "satin"}),
        );
        let p = p.unwrap();
        assert!(w.is_empty());
        assert_eq!(p.rd_warp, [0.3; 3]);
        assert_eq!(p.rd_weft, [0.1, 0.2, 0.3]);
        assert!(p.coupled_diffuse);
        assert_eq!(p.pattern, WeavePattern::satin());
        assert_eq!(p.repeat, FabricParams::default().repeat);
    }

    #[test]
    fn out_of_range_is_clamped_with_a_warning() {
        let (p, w) = parse(
            json!({"e_along": 2e7, "e_across": -3, "rs": 1.5, "repeat": 0.01, "gap": 0.02,
            "rd": [0.5, 2.0, -1.0], "shadow_width": 3, "bogus": 1}),
        );
        let p = p.unwrap();
        assert_eq!(p.e_along, 1e6);
        assert_eq!(p.e_across, 0.0);
        assert_eq!(p.rs, 1.0);
        assert_eq!(p.gap, 0.005);
        assert_eq!(p.rd_warp, [0.5, 1.0, 0.0]);
        assert_eq!(p.shadow_width, 1.0);
        let all = w.iter().map(|w| w.0.clone()).collect::<Vec<_>>().join("\n");
        for needle in [
            "e_along",
            "e_across",
            "rs",
            "gap",
            "rd[1]",
            "rd[2]",
            "shadow_width",
            "bogus",
            "[0, 1000000]",
        ] {
            assert!(all.contains(needle), "no warning mentions {needle}:\n{all}");
        }
        assert!(w.iter().all(|w| w.0.contains("'cloth'")));
        assert_eq!(w.len(), 8);
    }

    #[test]
    fn bad_values_are_errors_naming_material_and_field() {
        for (v, field) in [
            (json!({"rs": "shiny"}), "rs"),
            (json!({"pattern": "herringbone"}), "pattern"),
            (json!({"pattern": ["-|", "|"]}), "pattern"),
            (json!({"pattern": 3}), "pattern"),
            (json!({"rd": [1, 2]}), "rd"),
            (json!({"coupled_diffuse": 1}), "coupled_diffuse"),
            (json!({"e_along": null}), "e_along"),
        ] {
            let (r, _) = parse(v.clone());
            let e = r.expect_err(&format!("{v} should fail")).to_string();
            assert!(e.contains("'cloth'") && e.contains(field), "{e}");
        }
        let (r, _) = parse(json!([1, 2]));
        assert!(r.is_err());
    }

    #[test]
    fn transmission_makes_a_sheet() {
        let (p, w) = parse(json!({"transmission": 0.4}));
        let p = p.unwrap();
        assert!(w.is_empty(), "{w:?}");
        assert_eq!(p.transmission, Some(0.4));
        let g = p.to_gpu();
        assert_eq!((g.flags & FLAG_SHEET, g.transmission), (FLAG_SHEET, 0.4));
        // Absent: not a sheet; out of range: clamped with a warning; not a number: an error.
        let g = parse(json!({})).0.unwrap().to_gpu();
        assert_eq!((g.flags & FLAG_SHEET, g.transmission), (0, 0.0));
        let (p, w) = parse(json!({"transmission": 1.5}));
        assert_eq!(p.unwrap().transmission, Some(1.0));
        assert!(w.len() == 1 && w[0].0.contains("transmission"), "{w:?}");
        let e = parse(json!({"transmission": "sheer"}))
            .0
            .unwrap_err()
            .to_string();
        assert!(e.contains("'cloth'") && e.contains("transmission"), "{e}");
        // NaN never reaches the GPU.
        let p = FabricParams {
            transmission: Some(f32::NAN),
            ..Default::default()
        };
        assert_eq!(p.to_gpu().transmission, 0.0);
    }

    #[test]
    fn nan_and_inf_never_reach_the_gpu() {
        let p = FabricParams {
            e_along: f32::NAN,
            e_across: f32::INFINITY,
            rs: -1.0,
            repeat: 0.0,
            gap: f32::NAN,
            rd_warp: [f32::NAN, 2.0, f32::NEG_INFINITY],
            shadow_strength: f32::NAN,
            ..Default::default()
        };
        let g = p.to_gpu();
        let floats = [
            g.rs,
            g.e_along,
            g.e_across,
            g.cell_per_uv,
            g.shadow_strength,
            g.gap,
            g.shadow_dist,
        ];
        assert!(
            floats.iter().chain(g.rd_warp.iter()).all(|x| x.is_finite()),
            "{g:?}"
        );
        assert_eq!(g.e_across, 1e6);
        assert_eq!(g.e_along, 200.0);
        assert!(g.gap <= 0.5);
    }
}
