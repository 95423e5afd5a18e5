//! The woven model on any asset: `WEFT_materials_fabric` added to chosen materials of an existing
//! glTF document (`weft fabric`, and in memory for `weft render --fabric`), everything else left
//! as it is, with a fallback other viewers show. The page is `docs/fabric-on-assets.md`.
//!
//! - **What changes** in a chosen material: `extensions.WEFT_materials_fabric` is added (replaced
//!   if present), and, for presets, the fallback: `pbrMetallicRoughness.baseColorFactor` (the
//!   weave's far-field diffuse albedo), `metallicFactor: 0`, and `extensions.KHR_materials_sheen`
//!   (colour and roughness from the threads, see [`fallback_sheen`]). `extensionsUsed` gains the
//!   two names; `extensionsRequired` is not touched, so every viewer still opens the file.
//!   Nothing else in the JSON changes (key order and number spelling may: the document is
//!   re-serialised), and a `.glb`'s BIN chunk is copied byte for byte.
//! - **Pitch**: a world length (`0.8mm`, `1cm`, `0.01m`, `0.03in`; glTF units are metres),
//!   converted with the material's UV density: `sqrt(world area / UV area)` summed over every
//!   drawn triangle that uses the material, world positions through the node's full transform
//!   (scale included), UVs as the loader gives them to the renderer (`TEXCOORD_0`, with the
//!   material's texture transform when the loader bakes one). One cell is one thread pitch, so
//!   `repeat = 2·pitch/density` and cells per UV unit = `density/pitch`.
//! - **from-sheen**: [`from_sheen`] maps a material's `KHR_materials_sheen` and base colour to the
//!   fabric's parameters, and says what it mapped and what it could not.

use std::fmt;
use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};

use crate::fabric::{
    presets, presets::Preset, FabricParams, ThreadTexture, WeavePattern, EXTENSION_NAME,
    REPEAT_RANGE,
};
use crate::scene::Scene;
use crate::{Error, Result};

mod container;
mod fallback;
mod length;

pub use container::{copy_external_files, external_files, Container};
use fallback::{base_colour, num, rgb, sheet_transmission, texture_notes};
pub use fallback::{extension_json, fallback_sheen, far_field_albedo, from_sheen};
pub use length::{format_length, parse_length, uv_density, UvDensity};

/// The sheen extension of the fallback.
pub const SHEEN_EXTENSION: &str = "KHR_materials_sheen";

/// The ratio `e_along/e_across` that `from-sheen` gives the two exponents (the project default
/// 200/10 of `docs/fabric-model.md`).
pub const FROM_SHEEN_RATIO: f64 = 20.0;

/// A material by index or by name.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialRef {
    Index(usize),
    Name(String),
}

impl MaterialRef {
    /// All digits: an index; anything else: a name.
    pub fn parse(text: &str) -> MaterialRef {
        match text.parse::<usize>() {
            Ok(i) if text.chars().all(|c| c.is_ascii_digit()) => MaterialRef::Index(i),
            _ => MaterialRef::Name(text.to_string()),
        }
    }
}

impl fmt::Display for MaterialRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MaterialRef::Index(i) => write!(f, "{i}"),
            MaterialRef::Name(n) => write!(f, "'{n}'"),
        }
    }
}

/// Where the parameters come from.
#[derive(Clone, Debug)]
pub enum Source {
    Preset(&'static Preset),
    /// The material's own `KHR_materials_sheen` and base colour ([`from_sheen`]).
    FromSheen,
    /// The overrides alone over the extension's defaults, and nothing else of the material
    /// touched (no fallback written): how `weft view` saves a fabric the file already had,
    /// tuned in its panel ([`Overrides::exact`]). Not a command-line choice.
    Exact,
}

impl Source {
    pub fn parse(text: &str) -> Result<Source> {
        if text.eq_ignore_ascii_case("from-sheen") {
            return Ok(Source::FromSheen);
        }
        presets::by_name(text).map(Source::Preset).ok_or_else(|| {
            Error::input(format!(
                "unknown fabric preset '{text}'; use one of {}, or from-sheen (weft fabric --list-presets describes them)",
                presets::names()
            ))
        })
    }

    pub fn name(&self) -> &'static str {
        match self {
            Source::Preset(p) => p.name,
            Source::FromSheen => "from-sheen",
            Source::Exact => "as tuned",
        }
    }
}

/// A thread colour given on the command line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Colour {
    Rgb([f32; 3]),
    /// The material's `baseColorFactor` (linear RGB).
    Base,
}

impl Colour {
    /// `R,G,B` (linear, each in [0, 1]), one number for grey, or `base`.
    pub fn parse(flag: &str, text: &str) -> Result<Colour> {
        if text.eq_ignore_ascii_case("base") {
            return Ok(Colour::Base);
        }
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        let bad = || {
            Error::input(format!(
                "{flag} '{text}' is not a colour; give R,G,B (linear, each 0..1, e.g. 0.6,0.1,0.1), one number for grey, or 'base' for the material's base colour"
            ))
        };
        let values: Vec<f32> = parts
            .iter()
            .map(|p| p.parse::<f32>().ok().filter(|x| (0.0..=1.0).contains(x)))
            .collect::<Option<_>>()
            .ok_or_else(bad)?;
        match values[..] {
            [g] => Ok(Colour::Rgb([g; 3])),
            [r, g, b] => Ok(Colour::Rgb([r, g, b])),
            _ => Err(bad()),
        }
    }
}

/// Parameters given on the command line over the preset's.
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    /// Thread pitch, metres.
    pub pitch_m: Option<f64>,
    pub pattern: Option<WeavePattern>,
    /// Gap as a fraction of the pitch.
    pub gap_fraction: Option<f64>,
    pub e_along: Option<f32>,
    pub e_across: Option<f32>,
    pub rs: Option<f32>,
    pub shadow_strength: Option<f32>,
    pub shadow_width: Option<f32>,
    pub rd: Option<Colour>,
    pub rd_warp: Option<Colour>,
    pub rd_weft: Option<Colour>,
    pub coupled_diffuse: Option<bool>,
    /// The texture multiplied over the thread colours (default: the source's choice).
    pub thread_texture: Option<ThreadTexture>,
    /// Thread-by-thread colour sequences (a draft's `[WARP COLORS]`, `[WEFT COLORS]`).
    pub warp_colours: Option<Vec<[f32; 3]>>,
    pub weft_colours: Option<Vec<[f32; 3]>>,
    /// A single sheet: `Some(true)` (`--sheet`) with the preset's thread transmittance, or
    /// `transmission`; `Some(false)` not a sheet even where the material has
    /// KHR_materials_diffuse_transmission; None: as the file says.
    pub sheet: Option<bool>,
    /// The threads' diffuse transmittance (`--transmission`, implies a sheet).
    pub transmission: Option<f32>,
}

impl Overrides {
    /// The overrides that give exactly `p` (to the file's 6 digits) on a mesh of UV density
    /// `density`, whatever the preset: how `weft view` writes the parameters tuned in its panel
    /// through the same [`apply`] as `weft fabric`.
    pub fn exact(p: &FabricParams, density: &UvDensity) -> Overrides {
        let repeat = p.repeat as f64;
        Overrides {
            pitch_m: Some(repeat * density.metres_per_uv / 2.0),
            pattern: Some(p.pattern),
            gap_fraction: Some(p.gap as f64 / (repeat / 2.0)),
            e_along: Some(p.e_along),
            e_across: Some(p.e_across),
            rs: Some(p.rs),
            shadow_strength: Some(p.shadow_strength),
            shadow_width: Some(p.shadow_width),
            rd: None,
            rd_warp: Some(Colour::Rgb(p.rd_warp)),
            rd_weft: Some(Colour::Rgb(p.rd_weft)),
            coupled_diffuse: Some(p.coupled_diffuse),
            thread_texture: Some(p.thread_texture),
            warp_colours: Some(p.warp_colours.clone()),
            weft_colours: Some(p.weft_colours.clone()),
            sheet: Some(p.transmission.is_some()),
            transmission: p.transmission,
        }
    }

    /// A weaving draft's weave and thread colours over these overrides, where no colour
    /// override is set: a warp or weft of several colours becomes its colour sequence, thread by
    /// thread, reduced to its shortest period (a draft usually spells out several setts), and its
    /// mean the thread colour of the far-field fallback; of one colour, that colour. Returns the
    /// warnings to show: a period longer than [`crate::fabric::MAX_THREAD_COLOURS`] threads is drawn as
    /// its mean.
    pub fn apply_draft(&mut self, d: &crate::fabric::draft::Draft) -> Vec<String> {
        self.pattern = Some(d.pattern);
        let mut warnings = Vec::new();
        if self.rd.is_some() {
            return warnings;
        }
        for (side, warp) in [("warp", true), ("weft", false)] {
            let (rd, sequence) = if warp {
                (&mut self.rd_warp, &mut self.warp_colours)
            } else {
                (&mut self.rd_weft, &mut self.weft_colours)
            };
            if rd.is_some() {
                continue;
            }
            let (colours, mean) = if warp {
                (&d.warp_colours, d.mean_warp_colour())
            } else {
                (&d.weft_colours, d.mean_weft_colour())
            };
            *rd = mean.map(Colour::Rgb);
            if d.colour_count(warp) > 1 {
                let period = shortest_period(colours);
                if period.len() <= crate::fabric::MAX_THREAD_COLOURS {
                    *sequence = Some(period.to_vec());
                } else {
                    warnings.push(format!(
                        "the draft's {side} repeats its colours every {} threads, more than the {} a colour sequence holds: drawn as their mean (linear, weighted by thread count), right from afar, not thread by thread up close",
                        period.len(),
                        crate::fabric::MAX_THREAD_COLOURS
                    ));
                }
            }
        }
        warnings
    }
}

/// The shortest prefix of `colours` that repeats to all of it (`colours` itself when none does).
fn shortest_period(colours: &[[f32; 3]]) -> &[[f32; 3]] {
    let n = colours.len();
    (1..n)
        .filter(|p| n % p == 0)
        .find(|&p| (p..n).all(|i| colours[i] == colours[i % p]))
        .map_or(colours, |p| &colours[..p])
}

/// Materials and what to give them.
#[derive(Clone, Debug)]
pub struct Request {
    pub materials: Vec<MaterialRef>,
    pub source: Source,
    pub overrides: Overrides,
}

impl Request {
    /// `MATERIAL=PRESET` or `MATERIAL=PRESET@PITCH` (`weft render --fabric`), the preset
    /// optionally followed by `+sheet` (a single sheet with the preset's thread transmittance,
    /// as `weft fabric --sheet`); MATERIAL is a name or an index, and may itself contain '='.
    pub fn parse_spec(spec: &str) -> Result<Request> {
        let (material, rest) = spec.rsplit_once('=').filter(|(m, _)| !m.is_empty()).ok_or_else(|| {
            Error::input(format!(
                "--fabric '{spec}' should be MATERIAL=PRESET or MATERIAL=PRESET@PITCH, optionally followed by :DRAFT.wif, PRESET optionally followed by +sheet (e.g. seat=denim-twill@0.8mm, 0=from-sheen, 0=cotton-plain@1mm:twill.wif, curtain=silk-satin+sheet@0.2mm); MATERIAL is a name or an index"
            ))
        })?;
        // A weaving draft after a colon: MATERIAL=PRESET[@PITCH]:DRAFT.wif.
        let (rest, draft) = match rest.split_once(':') {
            Some((r, d)) if !d.is_empty() => (r, Some(d)),
            _ => (rest, None),
        };
        let (preset, pitch) = match rest.split_once('@') {
            Some((p, pitch)) => (p, Some(parse_length(pitch)?)),
            None => (rest, None),
        };
        // A single sheet: PRESET+sheet.
        let (preset, sheet) = match preset.strip_suffix("+sheet") {
            Some(p) => (p, Some(true)),
            None => (preset, None),
        };
        let mut overrides = Overrides {
            pitch_m: pitch,
            sheet,
            ..Default::default()
        };
        if let Some(path) = draft {
            let d = crate::fabric::draft::Draft::load(Path::new(path))?;
            for w in overrides.apply_draft(&d) {
                eprintln!("warning: {path}: {w}");
            }
        }
        Ok(Request {
            materials: vec![MaterialRef::parse(material)],
            source: Source::parse(preset)?,
            overrides,
        })
    }
}

/// What was done to one material.
#[derive(Clone, Debug)]
pub struct Applied {
    pub index: usize,
    pub name: String,
    pub source: &'static str,
    pub params: FabricParams,
    pub pitch_m: f64,
    pub density: UvDensity,
    /// The fallback written, when it was: baseColorFactor and (sheen colour, sheen roughness).
    pub fallback: Option<([f64; 4], [f64; 3], f64)>,
    /// What the user should know: mappings, replaced values, unused textures.
    pub notes: Vec<String>,
}

impl Applied {
    /// Cells (one thread pitch each) per UV unit.
    pub fn cells_per_uv(&self) -> f64 {
        2.0 / self.params.repeat as f64
    }
}

impl fmt::Display for Applied {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let d = &self.density;
        let cells = self.cells_per_uv();
        writeln!(
            f,
            "material {} '{}': {} ({} weave)",
            self.index,
            self.name,
            self.source,
            self.params.pattern.name()
        )?;
        writeln!(
            f,
            "  UV density {} per UV unit over {} drawn primitive(s); thread pitch {} -> {:.1} cells per UV unit (repeat {:.6} UV)",
            format_length(d.metres_per_uv),
            d.primitives,
            format_length(self.pitch_m),
            cells,
            self.params.repeat
        )?;
        // What the renderer will show: the pitch each primitive gets.
        if d.max > 0.0 && (d.max / d.min) > 1.05 {
            writeln!(
                f,
                "  world pitch {} on average, {} to {} across its primitives (their UV scales differ)",
                format_length(d.metres_per_uv / cells),
                format_length(d.min / cells),
                format_length(d.max / cells)
            )?;
        } else {
            writeln!(
                f,
                "  world pitch {}",
                format_length(d.metres_per_uv / cells)
            )?;
        }
        if let Some((base, sheen, roughness)) = &self.fallback {
            writeln!(
                f,
                "  fallback: baseColorFactor [{:.3}, {:.3}, {:.3}, {:.3}], metallicFactor 0, {SHEEN_EXTENSION} sheenColorFactor [{:.3}, {:.3}, {:.3}] sheenRoughnessFactor {:.3}",
                base[0], base[1], base[2], base[3], sheen[0], sheen[1], sheen[2], roughness
            )?;
        }
        for n in &self.notes {
            writeln!(f, "  note: {n}")?;
        }
        Ok(())
    }
}

/// Reads `doc.materials[index]` mutably as an object.
fn material_mut(doc: &mut Value, index: usize) -> Option<&mut Map<String, Value>> {
    doc.get_mut("materials")?.get_mut(index)?.as_object_mut()
}

/// The indices of the materials `r` names; a name several materials share is an error.
fn resolve(doc: &Value, r: &MaterialRef) -> Result<usize> {
    let materials = doc
        .get("materials")
        .and_then(Value::as_array)
        .map(Vec::as_slice)
        .unwrap_or(&[]);
    let listing = || {
        if materials.is_empty() {
            "the file has no materials".to_string()
        } else {
            let names: Vec<String> = materials
                .iter()
                .enumerate()
                .map(|(i, m)| match m.get("name").and_then(Value::as_str) {
                    Some(n) => format!("{i} '{n}'"),
                    None => format!("{i} (unnamed)"),
                })
                .collect();
            format!("its materials are {}", names.join(", "))
        }
    };
    match r {
        MaterialRef::Index(i) if *i < materials.len() => Ok(*i),
        MaterialRef::Index(i) => Err(Error::input(format!(
            "there is no material {i}: {}",
            listing()
        ))),
        MaterialRef::Name(n) => {
            let found: Vec<usize> = materials
                .iter()
                .enumerate()
                .filter(|(_, m)| m.get("name").and_then(Value::as_str) == Some(n.as_str()))
                .map(|(i, _)| i)
                .collect();
            match found[..] {
                [i] => Ok(i),
                [] => Err(Error::input(format!(
                    "there is no material named '{n}': {}; give a name or an index",
                    listing()
                ))),
                _ => Err(Error::input(format!(
                    "{} materials are named '{n}' (indices {:?}); choose by index",
                    found.len(),
                    found
                ))),
            }
        }
    }
}

/// Whether some primitive using material `index` lacks TEXCOORD_0, and whether all do.
fn uv_coverage(doc: &Value, index: usize) -> (usize, usize) {
    let (mut with, mut without) = (0, 0);
    for mesh in doc
        .get("meshes")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
    {
        for prim in mesh
            .get("primitives")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            if prim.get("material").and_then(Value::as_u64) != Some(index as u64) {
                continue;
            }
            if prim
                .get("attributes")
                .and_then(|a| a.get("TEXCOORD_0"))
                .is_some()
            {
                with += 1;
            } else {
                without += 1;
            }
        }
    }
    (with, without)
}

/// The default material of the first primitive that a `KHR_materials_variants` mapping gives
/// material `index`.
fn variant_stand_in(doc: &Value, index: usize) -> Option<usize> {
    let meshes = doc.get("meshes")?.as_array()?;
    meshes
        .iter()
        .filter_map(|m| m.get("primitives")?.as_array())
        .flatten()
        .find_map(|prim| {
            let mappings = prim
                .get("extensions")?
                .get("KHR_materials_variants")?
                .get("mappings")?
                .as_array()?;
            mappings
                .iter()
                .any(|m| m.get("material").and_then(Value::as_u64) == Some(index as u64))
                .then(|| prim.get("material")?.as_u64().map(|m| m as usize))
                .flatten()
        })
}

/// Adds `name` to the document's `extensionsUsed` when missing.
fn use_extension(doc: &mut Value, name: &str) -> Result<()> {
    let root = doc
        .as_object_mut()
        .ok_or_else(|| Error::input("the glTF JSON is not an object"))?;
    let used = root
        .entry("extensionsUsed")
        .or_insert_with(|| Value::Array(Vec::new()));
    let list = used
        .as_array_mut()
        .ok_or_else(|| Error::input("the glTF's extensionsUsed is not an array; fix the file"))?;
    if !list.iter().any(|v| v.as_str() == Some(name)) {
        list.push(json!(name));
    }
    Ok(())
}

/// `obj[key]` as an object, created when missing; an error naming `who` and `path` when it is
/// something else.
fn object_at<'a>(
    obj: &'a mut Map<String, Value>,
    key: &str,
    who: &str,
) -> Result<&'a mut Map<String, Value>> {
    obj.entry(key)
        .or_insert_with(|| json!({}))
        .as_object_mut()
        .ok_or_else(|| Error::input(format!("{who}: '{key}' is not a JSON object; fix the file")))
}

/// Adds the fabric (and for presets the fallback) to the chosen materials of `doc`. `scene` is
/// the same document loaded (for the UV density). Returns what was done, per material, in the
/// order asked.
pub fn apply(doc: &mut Value, scene: &Scene, requests: &[Request]) -> Result<Vec<Applied>> {
    let mut done: Vec<Applied> = Vec::new();
    for request in requests {
        for r in &request.materials {
            let index = resolve(doc, r)?;
            if done.iter().any(|a| a.index == index) {
                return Err(Error::input(format!(
                    "material {r} is chosen twice; give each material once"
                )));
            }
            let original = doc["materials"][index].clone();
            let name = original
                .get("name")
                .and_then(Value::as_str)
                .unwrap_or("")
                .to_string();
            let who = format!("material {index} '{name}'");
            let (with_uv, without_uv) = uv_coverage(doc, index);
            if with_uv == 0 && without_uv > 0 {
                return Err(Error::input(format!(
                    "{who} is used by {without_uv} primitive(s), none with texture coordinates (TEXCOORD_0), and the weave is laid out in UV space; unwrap the mesh (add UVs) or choose another material"
                )));
            }
            let mut notes = Vec::new();
            if without_uv > 0 {
                notes.push(format!(
                    "{without_uv} of its {} primitive(s) have no TEXCOORD_0: the weave looks flat there",
                    with_uv + without_uv
                ));
            }
            let density = match uv_density(scene, index, &who) {
                Ok(d) => d,
                // A material only a KHR_materials_variants variant uses: measure the primitives
                // it is mapped onto, through the material they draw with by default.
                Err(e) => match variant_stand_in(doc, index) {
                    Some(stand_in) if stand_in != index => {
                        let d = uv_density(scene, stand_in, &who).map_err(|_| e)?;
                        notes.push(format!(
                            "no node draws it by default (a KHR_materials_variants material): the pitch was converted on the primitives its variant maps it onto, which draw with material {stand_in} by default"
                        ));
                        d
                    }
                    _ => return Err(e),
                },
            };
            let (mut params, pitch_default) = match request.source {
                Source::Preset(p) => (p.params(1.0), p.pitch_m),
                Source::FromSheen => (
                    from_sheen(&original, &who, &mut notes)?,
                    presets::by_name("cotton-plain").map_or(0.37e-3, |p| p.pitch_m),
                ),
                Source::Exact => (
                    FabricParams::default(),
                    presets::by_name("cotton-plain").map_or(0.37e-3, |p| p.pitch_m),
                ),
            };
            let gap_default = match request.source {
                Source::Preset(p) => p.gap_fraction,
                Source::FromSheen | Source::Exact => {
                    presets::by_name("cotton-plain").map_or(0.1, |p| p.gap_fraction)
                }
            };
            let o = &request.overrides;
            let pitch_m = o.pitch_m.unwrap_or(pitch_default);
            let repeat = 2.0 * pitch_m / density.metres_per_uv;
            if !(repeat >= REPEAT_RANGE.0 as f64 && repeat <= REPEAT_RANGE.1 as f64) {
                return Err(Error::input(format!(
                    "{who}: a thread pitch of {} on a mesh of {} per UV unit is a repeat of {repeat:e} UV, outside the extension's range [{}, {}]; check the pitch's unit",
                    format_length(pitch_m),
                    format_length(density.metres_per_uv),
                    REPEAT_RANGE.0,
                    REPEAT_RANGE.1
                )));
            }
            params.repeat = repeat as f32;
            params.gap = (o.gap_fraction.unwrap_or(gap_default) * repeat / 2.0) as f32;
            if let Some(x) = o.pattern {
                params.pattern = x;
            }
            let base = base_colour(&original, &who)?;
            let colour = |c: Colour| match c {
                Colour::Rgb(c) => c,
                Colour::Base => [base[0], base[1], base[2]].map(|x| x.clamp(0.0, 1.0) as f32),
            };
            if let Some(c) = o.rd {
                params.rd_warp = colour(c);
                params.rd_weft = colour(c);
            }
            if let Some(c) = o.rd_warp {
                params.rd_warp = colour(c);
            }
            if let Some(c) = o.rd_weft {
                params.rd_weft = colour(c);
            }
            for (field, value) in [
                (&mut params.e_along, o.e_along),
                (&mut params.e_across, o.e_across),
                (&mut params.rs, o.rs),
                (&mut params.shadow_strength, o.shadow_strength),
                (&mut params.shadow_width, o.shadow_width),
            ] {
                if let Some(v) = value {
                    *field = v;
                }
            }
            if let Some(c) = o.coupled_diffuse {
                params.coupled_diffuse = c;
            }
            if let Some(t) = o.thread_texture {
                params.thread_texture = t;
            }
            if let Some(c) = &o.warp_colours {
                params.warp_colours = c.clone();
            }
            if let Some(c) = &o.weft_colours {
                params.weft_colours = c.clone();
            }
            params.transmission =
                sheet_transmission(&original, &who, o, &request.source, &mut notes)?;
            if params.has_thread_colours() {
                crate::fabric::ThreadColourTable::check(&params)
                    .map_err(|e| Error::input(format!("{who}: {e}")))?;
                notes.push(format!(
                    "thread by thread: {} warp and {} weft colours (repeat {} x {} cells)",
                    params.warp_colours.len().max(1),
                    params.weft_colours.len().max(1),
                    crate::fabric::ThreadColourTable::repeat_cells(&params)[0],
                    crate::fabric::ThreadColourTable::repeat_cells(&params)[1]
                ));
            }
            texture_notes(&original, &params, &mut notes);
            let sane = params.sanitized();
            if sane != params {
                return Err(Error::input(format!(
                    "{who}: a parameter is out of range ({params:?}); the ranges are in docs/fabric-model.md §4"
                )));
            }

            let m = material_mut(doc, index)
                .ok_or_else(|| Error::input(format!("{who} is not a JSON object")))?;
            let exts = object_at(m, "extensions", &who)?;
            if exts.contains_key(EXTENSION_NAME) {
                notes.push(format!("replaced its existing {EXTENSION_NAME}"));
            }
            // What the file says, read back by the loader's parser: the params reported are the
            // ones written (rounded to 6 digits), and they load without a warning.
            let written = extension_json(&params);
            let mut warnings = Vec::new();
            params = FabricParams::from_gltf_extension(&written, &name, &mut warnings)?;
            if let Some(w) = warnings.first() {
                return Err(Error::input(format!(
                    "{who}: the written extension would load with a warning: {w}"
                )));
            }
            exts.insert(EXTENSION_NAME.into(), written);
            let mut fallback = None;
            if let Source::Preset(_) = request.source {
                let (sheen_colour, sheen_roughness) = fallback_sheen(&params);
                if let Some(old) = exts.get(SHEEN_EXTENSION) {
                    notes.push(format!(
                        "replaced its {SHEEN_EXTENSION} {old} with the fallback (use from-sheen to keep and map it)"
                    ));
                }
                exts.insert(
                    SHEEN_EXTENSION.into(),
                    json!({
                        "sheenColorFactor": rgb(sheen_colour),
                        "sheenRoughnessFactor": num(sheen_roughness),
                    }),
                );
                let albedo = far_field_albedo(&params);
                let factor = [albedo[0], albedo[1], albedo[2], base[3]];
                let pbr = object_at(m, "pbrMetallicRoughness", &who)?;
                if pbr.contains_key("baseColorTexture") {
                    notes.push(
                        "its baseColorTexture stays: other viewers show it multiplied by the new baseColorFactor (the woven model's far field with the texture, as a product of their averages)".into(),
                    );
                }
                pbr.insert(
                    "baseColorFactor".into(),
                    Value::Array(factor.iter().map(|&x| num(x)).collect()),
                );
                pbr.insert("metallicFactor".into(), json!(0.0));
                fallback = Some((factor, sheen_colour, sheen_roughness));
            }
            done.push(Applied {
                index,
                name,
                source: request.source.name(),
                params,
                pitch_m,
                density,
                fallback,
                notes,
            });
        }
    }
    use_extension(doc, EXTENSION_NAME)?;
    if done.iter().any(|a| a.fallback.is_some()) {
        use_extension(doc, SHEEN_EXTENSION)?;
    }
    Ok(done)
}

/// Loads `bytes` (to check them and measure UV density), adds the fabric and returns the new
/// file's bytes. `base_dir` resolves external buffers and images, as for [`crate::scene::load_slice`].
pub fn transform(
    bytes: &[u8],
    source: &str,
    base_dir: Option<&Path>,
    requests: &[Request],
) -> Result<(Vec<u8>, Vec<Applied>)> {
    let scene = crate::scene::load_slice(bytes, source, base_dir)?;
    let mut container = Container::split(bytes, source)?;
    let applied = apply(&mut container.json, &scene, requests)
        .map_err(|e| Error::input(format!("'{source}': {e}")))?;
    Ok((container.to_bytes()?, applied))
}

/// The scene file at `path` (the built-in default scene when None): its bytes, its name for
/// messages, and the directory its external buffers and images resolve from (none for the
/// built-in scene).
pub fn scene_bytes(path: Option<&Path>) -> Result<(Vec<u8>, String, Option<PathBuf>)> {
    Ok(match path {
        Some(p) => {
            let bytes = std::fs::read(p).map_err(|e| {
                Error::input(format!(
                    "scene file '{}' could not be read: {e}",
                    p.display()
                ))
            })?;
            let dir = match p.parent() {
                Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                _ => PathBuf::from("."),
            };
            (bytes, p.display().to_string(), Some(dir))
        }
        None => (
            crate::scene::DEFAULT_SCENE_GLB.to_vec(),
            "built-in default scene".to_string(),
            None,
        ),
    })
}

/// `weft render --fabric`: the scene at `path` (the built-in default scene when None) with the
/// fabric added in memory, by the same [`transform`] as `weft fabric`, then loaded.
pub fn load_with_fabric(
    path: Option<&Path>,
    specs: &[String],
    options: &crate::scene::LoadOptions,
) -> Result<(Scene, Vec<Applied>)> {
    let requests: Vec<Request> = specs
        .iter()
        .map(|s| Request::parse_spec(s))
        .collect::<Result<_>>()?;
    let (bytes, source, base_dir) = scene_bytes(path)?;
    let (out, applied) = transform(&bytes, &source, base_dir.as_deref(), &requests)?;
    let scene = crate::scene::load_slice_with(&out, &source, base_dir.as_deref(), options)?;
    Ok((scene, applied))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_and_their_errors() {
        assert_eq!(parse_length("0.8mm").unwrap(), 0.8e-3);
        assert!((parse_length("1 cm").unwrap() - 0.01).abs() < 1e-15);
        assert_eq!(parse_length("2m").unwrap(), 2.0);
        assert!((parse_length("0.1in").unwrap() - 0.00254).abs() < 1e-15);
        for (bad, needle) in [
            ("0.8", "no unit"),
            ("0.8ft", "'ft'"),
            ("mm", "not a number"),
            ("xmm", "'xmm'"),
            ("-1mm", "positive"),
            ("0mm", "positive"),
        ] {
            let e = parse_length(bad).unwrap_err().to_string();
            assert!(e.contains(needle), "{bad}: {e}");
        }
    }

    #[test]
    fn specs_parse_and_fail_clearly() {
        let r = Request::parse_spec("seat=denim-twill@0.8mm").unwrap();
        assert_eq!(r.materials, vec![MaterialRef::Name("seat".into())]);
        assert_eq!(r.source.name(), "denim-twill");
        assert_eq!(r.overrides.pitch_m, Some(0.8e-3));
        let r = Request::parse_spec("a=b=from-sheen").unwrap();
        assert_eq!(r.materials, vec![MaterialRef::Name("a=b".into())]);
        assert_eq!(
            Request::parse_spec("3=silk-satin").unwrap().materials,
            vec![MaterialRef::Index(3)]
        );
        let e = Request::parse_spec("seat=tweed").unwrap_err().to_string();
        assert!(e.contains("'tweed'") && e.contains("cotton-plain"), "{e}");
        assert!(Request::parse_spec("denim-twill").is_err());
        assert!(Request::parse_spec("seat=denim-twill@3").is_err());
        // A single sheet.
        let r = Request::parse_spec("curtain=silk-satin+sheet@0.2mm").unwrap();
        assert_eq!(r.source.name(), "silk-satin");
        assert_eq!(r.overrides.sheet, Some(true));
        assert_eq!(r.overrides.pitch_m, Some(0.2e-3));
        assert_eq!(
            Request::parse_spec("0=silk-satin").unwrap().overrides.sheet,
            None
        );
        let e = Request::parse_spec("0=silk-satin+sheer")
            .unwrap_err()
            .to_string();
        assert!(e.contains("'silk-satin+sheer'"), "{e}");
    }

    #[test]
    fn colours_parse() {
        assert_eq!(Colour::parse("--rd", "base").unwrap(), Colour::Base);
        assert_eq!(Colour::parse("--rd", "0.5").unwrap(), Colour::Rgb([0.5; 3]));
        assert_eq!(
            Colour::parse("--rd", "0.1,0.2,0.3").unwrap(),
            Colour::Rgb([0.1, 0.2, 0.3])
        );
        for bad in ["1,2", "0.1,0.2,1.5", "red"] {
            assert!(Colour::parse("--rd", bad)
                .unwrap_err()
                .to_string()
                .contains("--rd"));
        }
    }

    #[test]
    fn from_sheen_keeps_the_sheen_colour_texture_as_thread_colour() {
        // With a sheenColorTexture: rd = sheenColorFactor, the texture over it, and said.
        let m = json!({
            "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 1], "baseColorTexture": {"index": 0}},
            "extensions": {SHEEN_EXTENSION: {"sheenRoughnessFactor": 0.5, "sheenColorFactor": [1, 0.5, 0.25],
                "sheenColorTexture": {"index": 1}}}
        });
        let mut notes = Vec::new();
        let p = from_sheen(&m, "material 0 'x'", &mut notes).unwrap();
        assert_eq!(p.thread_texture, ThreadTexture::SheenColor);
        assert_eq!(p.rd_warp, [1.0, 0.5, 0.25]);
        assert!(
            notes
                .iter()
                .any(|n| n.contains("sheenColorTexture is the thread colour")),
            "{notes:?}"
        );
        assert!(
            notes
                .iter()
                .any(|n| n.contains("baseColorTexture is not used")),
            "{notes:?}"
        );
        // Without one: the base colour and its texture, as before.
        let m = json!({
            "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 1], "baseColorTexture": {"index": 0}},
            "extensions": {SHEEN_EXTENSION: {"sheenRoughnessFactor": 0.5, "sheenColorFactor": [1, 0.5, 0.25]}}
        });
        let mut notes = Vec::new();
        let p = from_sheen(&m, "material 0 'x'", &mut notes).unwrap();
        assert_eq!(p.thread_texture, ThreadTexture::BaseColor);
        assert_eq!(p.rd_warp, [0.2, 0.4, 0.6]);
        // The texture notes say what each texture does, and the extension round-trips the field.
        let mut notes = Vec::new();
        texture_notes(
            &json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}, "normalTexture": {"index": 1}, "occlusionTexture": {"index": 2}}),
            &p,
            &mut notes,
        );
        assert_eq!(notes.len(), 3, "{notes:?}");
        assert!(
            notes[0].contains("baseColorTexture multiplies the thread colours"),
            "{notes:?}"
        );
        let back =
            FabricParams::from_gltf_extension(&extension_json(&p), "x", &mut Vec::new()).unwrap();
        assert_eq!(back.thread_texture, ThreadTexture::BaseColor);
        let none = FabricParams {
            thread_texture: ThreadTexture::None,
            ..p.clone()
        };
        let back = FabricParams::from_gltf_extension(&extension_json(&none), "x", &mut Vec::new())
            .unwrap();
        assert_eq!(back.thread_texture, ThreadTexture::None);
        let e = FabricParams::from_gltf_extension(
            &json!({"thread_texture": "albedo"}),
            "x",
            &mut Vec::new(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("thread_texture") && e.contains("base_color"),
            "{e}"
        );
    }

    #[test]
    fn sheen_roughness_round_trips_through_from_sheen() {
        // from-sheen is the inverse of the fallback's roughness, so a fabric made from a sheen
        // asset writes back (nearly) the roughness it came from.
        for r in [0.2, 0.3, 0.5, 0.7] {
            let m = json!({"extensions": {SHEEN_EXTENSION: {"sheenRoughnessFactor": r, "sheenColorFactor": [1, 0, 0]}}});
            let mut notes = Vec::new();
            let p = from_sheen(&m, "material 0 'x'", &mut notes).unwrap();
            let (_, back) = fallback_sheen(&p);
            assert!((back - r).abs() < 0.02, "{r} -> {back} ({p:?})");
            assert!(
                notes.iter().any(|n| n.contains("sheenColorFactor")),
                "{notes:?}"
            );
        }
        let e = from_sheen(&json!({}), "material 0 'x'", &mut Vec::new())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("material 0 'x'") && e.contains(SHEEN_EXTENSION),
            "{e}"
        );
        let bad = json!({"extensions": {SHEEN_EXTENSION: {"sheenRoughnessFactor": "rough"}}});
        let e = from_sheen(&bad, "material 0 'x'", &mut Vec::new())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("material 0 'x'") && e.contains("sheenRoughnessFactor"),
            "{e}"
        );
    }

    #[test]
    fn a_colour_sequence_reduces_to_its_shortest_period() {
        let (a, b, c) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
        assert_eq!(shortest_period(&[a, b, a, b, a, b]), &[a, b]);
        assert_eq!(shortest_period(&[a, a, b, a, a, b]), &[a, a, b]);
        assert_eq!(shortest_period(&[a, b, c, a, b]), &[a, b, c, a, b]);
        assert_eq!(shortest_period(&[a, b, a, c]), &[a, b, a, c]);
        assert_eq!(shortest_period(&[c]), &[c]);
    }

    #[test]
    fn far_field_albedo_is_the_plain_weave_formula() {
        // docs/fabric-model.md §2: s_warp + s_weft = 1 − 4g² − strength·width·(1 − 2g) for a
        // plain weave.
        let p = FabricParams {
            rd_warp: [0.5; 3],
            rd_weft: [0.5; 3],
            ..Default::default()
        };
        let g = (p.gap / p.repeat) as f64;
        let sh = 1.0 - 4.0 * g * g - 0.5 * 0.25 * (1.0 - 2.0 * g);
        let a = far_field_albedo(&p);
        assert!((a[0] - 0.5 * sh).abs() < 1e-5, "{a:?} vs {}", 0.5 * sh);
    }
}
