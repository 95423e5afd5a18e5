//! The extension's JSON, the fallback other viewers show (far-field colour, sheen), and
//! `from-sheen`: a sheen material read as a fabric.

use serde_json::{json, Value};

use super::{Overrides, Source, FROM_SHEEN_RATIO, SHEEN_EXTENSION};
use crate::fabric::{presets, FabricParams, ThreadColourTable, ThreadTexture, WeavePattern};
use crate::{Error, Result};

/// A number for the file, rounded to 6 significant digits (f32 values would otherwise be
/// written as 0.6200000047683716).
pub(super) fn num(x: f64) -> Value {
    let rounded: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    json!(rounded)
}

/// A colour for the file.
pub(super) fn rgb(c: [f64; 3]) -> Value {
    Value::Array(c.iter().map(|&x| num(x)).collect())
}

/// The extension object for `p`, every field written out.
pub fn extension_json(p: &FabricParams) -> Value {
    let pattern = match WeavePattern::NAMES
        .iter()
        .find(|n| WeavePattern::by_name(n) == Some(p.pattern))
    {
        Some(n) => json!(n),
        None => json!(p.pattern.to_rows()),
    };
    let c = |c: [f32; 3]| rgb(c.map(|x| x as f64));
    let mut o = json!({
        "pattern": pattern,
        "repeat": num(p.repeat as f64),
        "gap": num(p.gap as f64),
        "e_along": num(p.e_along as f64),
        "e_across": num(p.e_across as f64),
        "rd_warp": c(p.rd_warp),
        "rd_weft": c(p.rd_weft),
        "rs": num(p.rs as f64),
        "shadow_strength": num(p.shadow_strength as f64),
        "shadow_width": num(p.shadow_width as f64),
    });
    if p.coupled_diffuse {
        o["coupled_diffuse"] = json!(true);
    }
    o["thread_texture"] = json!(p.thread_texture.name());
    for (key, list) in [
        ("warp_colours", &p.warp_colours),
        ("weft_colours", &p.weft_colours),
    ] {
        if !list.is_empty() {
            o[key] = json!(list.iter().map(|&x| c(x)).collect::<Vec<_>>());
        }
    }
    if let Some(t) = p.transmission {
        o["transmission"] = num(t as f64);
    }
    o
}

/// Whether the fabric is a single sheet, and its threads' diffuse transmittance: `--transmission`;
/// else the material's own `KHR_materials_diffuse_transmission` factor (a file that says its
/// surface lets diffuse light through is a sheet); else, with `--sheet`, the preset's
/// [`Preset::thread_transmittance`] (cotton-plain's for from-sheen); else not a sheet.
pub(super) fn sheet_transmission(
    material: &Value,
    who: &str,
    o: &Overrides,
    source: &Source,
    notes: &mut Vec<String>,
) -> Result<Option<f32>> {
    if o.sheet == Some(false) {
        return Ok(None);
    }
    if let Some(t) = o.transmission {
        notes.push(format!(
            "a single sheet: its gaps let light through, its threads {t} of their diffuse light"
        ));
        return Ok(Some(t));
    }
    if let Some(dt) = material
        .get("extensions")
        .and_then(|e| e.get("KHR_materials_diffuse_transmission"))
    {
        let factor = match dt.get("diffuseTransmissionFactor") {
            None => 0.0,
            Some(v) => v.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
                Error::input(format!(
                    "{who}: extensions.KHR_materials_diffuse_transmission.diffuseTransmissionFactor must be a number, got {v}; fix the material or give --transmission"
                ))
            })?,
        }
        .clamp(0.0, 1.0) as f32;
        notes.push(format!(
            "a single sheet, from KHR_materials_diffuse_transmission: its threads pass {factor} of their diffuse light (diffuseTransmissionFactor; its colour and textures are not mapped), its gaps let light through"
        ));
        return Ok(Some(factor));
    }
    if o.sheet == Some(true) {
        let t = match source {
            Source::Preset(p) => p.thread_transmittance,
            Source::FromSheen | Source::Exact => {
                presets::by_name("cotton-plain").map_or(0.3, |p| p.thread_transmittance)
            }
        };
        notes.push(format!("a single sheet: its gaps let light through, its threads {t} of their diffuse light (the preset's)"));
        return Ok(Some(t));
    }
    Ok(None)
}

/// The weave's far-field diffuse albedo: each thread's colour times its shadow-weighted area over
/// one whole repeat (exact, `weave_box` over the repeat). This is
/// what the fabric's Lambert term averages to where the weave is too small to see.
pub fn far_field_albedo(p: &FabricParams) -> [f64; 3] {
    // Thread by thread: Σ s·colour over the colour repeat, per unit area, cell by cell.
    if p.has_thread_colours() {
        let w = crate::fabric::coverage::weave_of(p);
        let [wc, hc] = ThreadColourTable::repeat_cells(p);
        let mut out = [0.0; 3];
        for j in 0..hc as usize {
            let cf = p.thread_colour(false, j);
            for i in 0..wc as usize {
                let cw = p.thread_colour(true, i);
                let (x, y) = (i as f64, j as f64);
                let c = crate::fabric::coverage::double::weave_box(&w, x, y, x + 1.0, y + 1.0);
                for k in 0..3 {
                    out[k] += (c[2] * cw[k] as f64 + c[3] * cf[k] as f64) / (wc * hc) as f64;
                }
            }
        }
        return out;
    }
    let [ru, rv] = p.repeat_uv();
    let [_, _, s_warp, s_weft] = crate::fabric::coverage::weave_box_uv(p, 0.0, ru, 0.0, rv);
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        *o = s_warp * p.rd_warp[k] as f64 + s_weft * p.rd_weft[k] as f64;
    }
    out
}

/// `KHR_materials_sheen` for viewers without the woven model:
///
/// - **sheenRoughnessFactor** from the lobe's width. The A–S lobe's peak is
///   `sqrt((eu+1)(ev+1))/(2π)`, that of an isotropic Phong lobe of exponent E is `(E+1)/(2π)`, so
///   the isotropic lobe of the same solid angle has `E = sqrt((eu+1)(ev+1)) − 1`; Walter et al.
///   2007 (§5.2) relate Phong and Beckmann: `α = sqrt(2/(E+2))`; glTF's roughness is `sqrt(α)`.
///   Charlie's shape is not Beckmann's, so this matches widths, not lobes.
/// - **sheenColorFactor**: `sqrt(thread colour) × thread coverage` (the gaps reflect nothing):
///   the threads' colour, paler, as a fibre's grazing sheen looks. Chosen by eye; not a fit.
pub fn fallback_sheen(p: &FabricParams) -> ([f64; 3], f64) {
    let [ru, rv] = p.repeat_uv();
    let [c_warp, c_weft, _, _] = crate::fabric::coverage::weave_box_uv(p, 0.0, ru, 0.0, rv);
    let thread = c_warp + c_weft;
    let mut colour = [0.0; 3];
    if thread > 0.0 {
        for (k, c) in colour.iter_mut().enumerate() {
            let mean = (c_warp * p.rd_warp[k] as f64 + c_weft * p.rd_weft[k] as f64) / thread;
            *c = (mean.max(0.0).sqrt() * thread).clamp(0.0, 1.0);
        }
    }
    let e = (((p.e_along as f64 + 1.0) * (p.e_across as f64 + 1.0)).sqrt() - 1.0).max(0.0);
    let alpha = (2.0 / (e + 2.0)).sqrt();
    (colour, alpha.sqrt().clamp(0.0, 1.0))
}

/// A number at `key` of a JSON object, or `default` when absent; an error naming the material
/// and the key when it is not a finite number.
fn read_number(obj: &Value, key: &str, default: f64, who: &str, path: &str) -> Result<f64> {
    match obj.get(key) {
        None => Ok(default),
        Some(v) => v.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
            Error::input(format!(
                "{who}: {path}.{key} must be a number, got {v}; fix the material or choose a preset instead of from-sheen"
            ))
        }),
    }
}

/// An array of `n` numbers at `key`, or `default`.
fn read_numbers<const N: usize>(
    obj: &Value,
    key: &str,
    default: [f64; N],
    who: &str,
    path: &str,
) -> Result<[f64; N]> {
    let Some(v) = obj.get(key) else {
        return Ok(default);
    };
    let bad = || {
        Error::input(format!(
            "{who}: {path}.{key} must be an array of {N} numbers, got {v}; fix the material or choose a preset instead of from-sheen"
        ))
    };
    let a = v.as_array().filter(|a| a.len() == N).ok_or_else(bad)?;
    let mut out = default;
    for (o, x) in out.iter_mut().zip(a) {
        *o = x.as_f64().filter(|x| x.is_finite()).ok_or_else(bad)?;
    }
    Ok(out)
}

/// The material's `baseColorFactor` (linear RGBA; glTF's default white).
pub(super) fn base_colour(material: &Value, who: &str) -> Result<[f64; 4]> {
    let pbr = material
        .get("pbrMetallicRoughness")
        .cloned()
        .unwrap_or(json!({}));
    read_numbers(
        &pbr,
        "baseColorFactor",
        [1.0; 4],
        who,
        "pbrMetallicRoughness",
    )
}

/// The fabric for a material with `KHR_materials_sheen`, and what the mapping did:
///
/// - `rd_warp = rd_weft = baseColorFactor.rgb` (clamped to [0, 1]), the base colour texture (if
///   any) over them; or, where the sheen has a `sheenColorTexture`, `rd = sheenColorFactor` with
///   that texture over them (`thread_texture: "sheen_color"`): the sheen colour is the fibres';
/// - the exponents from `sheenRoughnessFactor` r (clamped to [0.05, 1]), the inverse of
///   [`fallback_sheen`]'s roughness: `α = r²`, `E = 2/α² − 2`, split with
///   `e_along/e_across` = [`FROM_SHEEN_RATIO`] at the same peak, `sqrt((ea+1)(ex+1)) = E + 1`;
/// - `rs = 0.04` (glTF's default dielectric F0, IOR 1.5);
/// - plain weave, gap and shadows of cotton-plain: the sheen carries no weave;
/// - without a sheen colour texture, `sheenColorFactor` has no counterpart (the woven highlight
///   is untinted Fresnel); `sheenRoughnessTexture` never has one. Said in the notes.
pub fn from_sheen(material: &Value, who: &str, notes: &mut Vec<String>) -> Result<FabricParams> {
    let sheen = material
        .get("extensions")
        .and_then(|e| e.get(SHEEN_EXTENSION))
        .ok_or_else(|| {
            Error::input(format!(
                "{who} has no {SHEEN_EXTENSION} to map from; choose a preset ({}) instead of from-sheen",
                presets::names()
            ))
        })?;
    if !sheen.is_object() {
        return Err(Error::input(format!(
            "{who}: extensions.{SHEEN_EXTENSION} must be an object, got {sheen}"
        )));
    }
    let path = format!("extensions.{SHEEN_EXTENSION}");
    let colour = read_numbers(sheen, "sheenColorFactor", [0.0; 3], who, &path)?;
    let r = read_number(sheen, "sheenRoughnessFactor", 0.0, who, &path)?;
    let base = base_colour(material, who)?;
    let rc = r.clamp(0.05, 1.0);
    let alpha = rc * rc;
    let e = (2.0 / (alpha * alpha) - 2.0).max(0.0);
    let e_across = ((e + 1.0) / FROM_SHEEN_RATIO.sqrt() - 1.0).max(0.0);
    if e_across == 0.0 {
        notes.push(format!(
            "from-sheen: sheenRoughnessFactor {r} is rougher than the broadest lobe of ratio {FROM_SHEEN_RATIO} (about 0.78): e_across is 0"
        ));
    }
    let e_along = FROM_SHEEN_RATIO * (e_across + 1.0) - 1.0;
    let cotton = presets::by_name("cotton-plain").expect("cotton-plain is a preset");
    let sheen_texture = sheen.get("sheenColorTexture").is_some();
    let thread = if sheen_texture {
        colour
    } else {
        [base[0], base[1], base[2]]
    };
    let rd = thread.map(|x| x.clamp(0.0, 1.0) as f32);
    let mut p = cotton.params(1.0);
    p.rd_warp = rd;
    p.rd_weft = rd;
    p.rs = 0.04;
    p.e_along = (e_along as f32).clamp(0.0, 1e6);
    p.e_across = (e_across as f32).clamp(0.0, 1e6);
    p.thread_texture = if sheen_texture {
        ThreadTexture::SheenColor
    } else {
        ThreadTexture::BaseColor
    };
    notes.push(format!(
        "from-sheen: rd = {} [{:.3}, {:.3}, {:.3}]; sheenRoughnessFactor {r}{} -> isotropic exponent {e:.1} -> e_along {:.1}, e_across {:.1} (ratio {FROM_SHEEN_RATIO}); rs 0.04 (glTF default F0); plain weave with cotton-plain's gap and shadow",
        if sheen_texture { "sheenColorFactor" } else { "baseColorFactor" },
        rd[0], rd[1], rd[2],
        if rc != r { format!(" (clamped to {rc})") } else { String::new() },
        p.e_along, p.e_across
    ));
    let base_texture = material
        .get("pbrMetallicRoughness")
        .and_then(|p| p.get("baseColorTexture"))
        .is_some();
    if sheen_texture {
        notes.push(
            "from-sheen: its sheenColorTexture is the thread colour's texture (thread_texture \"sheen_color\"), multiplied over sheenColorFactor".into(),
        );
        if base_texture {
            notes.push(
                "from-sheen: its baseColorTexture is not used by the woven model (the sheen colour texture is); the material keeps it for other viewers".into(),
            );
        }
    } else if colour.iter().all(|&c| c == 0.0) {
        notes.push(
            "from-sheen: sheenColorFactor is 0 (this material's sheen is off); only its base colour and roughness were used".into(),
        );
    } else {
        notes.push(format!(
            "from-sheen: sheenColorFactor [{:.3}, {:.3}, {:.3}] is not mapped (the woven highlight is untinted Fresnel; without a sheenColorTexture the base colour is the thread colour)",
            colour[0], colour[1], colour[2]
        ));
    }
    if sheen.get("sheenRoughnessTexture").is_some() {
        notes.push(
            "from-sheen: sheenRoughnessTexture is not used by the woven model (its lobe widths are per material); the material keeps it for other viewers".into(),
        );
    }
    Ok(p)
}

/// What the woven model does with each texture of the material (said, never silent): the thread
/// texture multiplies the thread colours; the normal map and the occlusion texture stay.
pub(super) fn texture_notes(material: &Value, p: &FabricParams, notes: &mut Vec<String>) {
    let pbr = material.get("pbrMetallicRoughness");
    let has = |obj: Option<&Value>, key: &str| obj.and_then(|o| o.get(key)).is_some();
    let sheen = material
        .get("extensions")
        .and_then(|e| e.get(SHEEN_EXTENSION));
    let base = has(pbr, "baseColorTexture");
    let sheen_colour = has(sheen, "sheenColorTexture");
    match p.thread_texture {
        ThreadTexture::BaseColor if base => notes.push(
            "textures: its baseColorTexture multiplies the thread colours (thread_texture \"base_color\": the print, dye or damask over the weave)".into(),
        ),
        ThreadTexture::SheenColor if sheen_colour => notes.push(
            "textures: its sheenColorTexture multiplies the thread colours (thread_texture \"sheen_color\")".into(),
        ),
        ThreadTexture::BaseColor | ThreadTexture::SheenColor => notes.push(format!(
            "textures: thread_texture \"{}\" but the material has no such texture: plain thread colours",
            p.thread_texture.name()
        )),
        ThreadTexture::None if base || sheen_colour => notes.push(
            "textures: thread_texture \"none\": the woven model ignores its colour textures".into(),
        ),
        ThreadTexture::None => {}
    }
    if material.get("normalTexture").is_some() {
        notes.push("textures: its normalTexture stays and bends the weave's shading frame".into());
    }
    if material.get("occlusionTexture").is_some() {
        notes.push(
            "textures: its occlusionTexture stays and darkens the environment light on the weave (glTF: indirect light only)".into(),
        );
    }
}
