//! The material extensions weft reads from raw JSON: `KHR_materials_sheen`,
//! `KHR_materials_specular`, `KHR_materials_ior`, `KHR_materials_anisotropy`, and the per-primitive
//! mappings of `KHR_materials_variants`.
//!
//! Each parser checks types (a wrong type is an error naming the material and the key) and ranges
//! (a value out of range is clamped with a warning naming both), as the fabric extension does.
//! Texture references are returned unresolved ([`TexRef`]); the loader decodes them.

use serde_json::Value;

pub const SHEEN: &str = "KHR_materials_sheen";
pub const SPECULAR: &str = "KHR_materials_specular";
pub const IOR: &str = "KHR_materials_ior";
pub const ANISOTROPY: &str = "KHR_materials_anisotropy";
pub const VARIANTS: &str = "KHR_materials_variants";
pub const TRANSMISSION: &str = "KHR_materials_transmission";
pub const VOLUME: &str = "KHR_materials_volume";
pub const CLEARCOAT: &str = "KHR_materials_clearcoat";
pub const DIFFUSE_TRANSMISSION: &str = "KHR_materials_diffuse_transmission";
pub const IRIDESCENCE: &str = "KHR_materials_iridescence";
pub const DISPERSION: &str = "KHR_materials_dispersion";
/// Archived by Khronos, still required by older files (SpecGlossVsMetalRough).
pub const SPEC_GLOSS: &str = "KHR_materials_pbrSpecularGlossiness";

/// A glTF textureInfo, unresolved: the texture index, its texCoord, and the raw
/// KHR_texture_transform (parsed by the loader, like the core slots').
#[derive(Clone, Debug)]
pub struct TexRef {
    pub index: usize,
    pub tex_coord: u32,
    pub transform: Option<Value>,
}

#[derive(Clone, Debug)]
pub struct SheenExt {
    pub color: [f32; 3],
    pub roughness: f32,
    pub color_texture: Option<TexRef>,
    pub roughness_texture: Option<TexRef>,
}

#[derive(Clone, Debug)]
pub struct SpecularExt {
    pub factor: f32,
    pub color: [f32; 3],
    pub texture: Option<TexRef>,
    pub color_texture: Option<TexRef>,
}

#[derive(Clone, Debug)]
pub struct AnisotropyExt {
    pub strength: f32,
    pub rotation: f32,
    pub texture: Option<TexRef>,
}

#[derive(Clone, Debug)]
pub struct TransmissionExt {
    pub factor: f32,
    pub texture: Option<TexRef>,
}

#[derive(Clone, Debug)]
pub struct VolumeExt {
    pub thickness: f32,
    pub thickness_texture: Option<TexRef>,
    pub attenuation_color: [f32; 3],
    /// None: infinite (the default).
    pub attenuation_distance: Option<f32>,
}

#[derive(Clone, Debug)]
pub struct ClearcoatExt {
    pub factor: f32,
    pub texture: Option<TexRef>,
    pub roughness: f32,
    pub roughness_texture: Option<TexRef>,
    pub normal_texture: Option<TexRef>,
    pub normal_scale: f32,
}

#[derive(Clone, Debug)]
pub struct SpecGlossExt {
    pub diffuse: [f32; 4],
    pub diffuse_texture: Option<TexRef>,
    pub specular: [f32; 3],
    pub glossiness: f32,
    pub texture: Option<TexRef>,
}

#[derive(Clone, Debug)]
pub struct IridescenceExt {
    pub factor: f32,
    pub texture: Option<TexRef>,
    pub ior: f32,
    pub thickness_min: f32,
    pub thickness_max: f32,
    pub thickness_texture: Option<TexRef>,
}

#[derive(Clone, Debug)]
pub struct DiffuseTransmissionExt {
    pub factor: f32,
    pub texture: Option<TexRef>,
    pub color: [f32; 3],
    pub color_texture: Option<TexRef>,
}

/// What a parser reports back: an error message (the loader prefixes the file), or warnings.
pub struct Ctx<'a> {
    pub material: &'a str,
    pub extension: &'static str,
    pub warnings: Vec<String>,
}

fn short(v: &Value) -> String {
    let s = v.to_string();
    if s.len() > 60 {
        format!(
            "{}…",
            &s[..s.char_indices().nth(57).map_or(s.len(), |(i, _)| i)]
        )
    } else {
        s
    }
}

impl Ctx<'_> {
    fn err(&self, key: &str, what: impl std::fmt::Display) -> String {
        format!(
            "material '{}': {}.{key} {what}; fix the value in the file (the extension's specification gives types and ranges)",
            self.material, self.extension
        )
    }

    fn object<'v>(&self, v: &'v Value) -> Result<&'v serde_json::Map<String, Value>, String> {
        v.as_object().ok_or_else(|| {
            format!(
                "material '{}': {} must be a JSON object, got {}",
                self.material,
                self.extension,
                short(v)
            )
        })
    }

    /// A finite number, clamped to [lo, hi] with a warning.
    fn number(&mut self, key: &str, v: &Value, lo: f32, hi: f32) -> Result<f32, String> {
        let x = v
            .as_f64()
            .ok_or_else(|| self.err(key, format!("must be a number, got {}", short(v))))?
            as f32;
        if !x.is_finite() {
            return Err(self.err(key, format!("must be finite, got {}", short(v))));
        }
        if !(lo..=hi).contains(&x) {
            self.warnings.push(format!(
                "material '{}': {}.{key} is {x}, outside [{lo}, {hi}]; clamped",
                self.material, self.extension
            ));
        }
        Ok(x.clamp(lo, hi))
    }

    /// A finite number with no range (a rotation in radians).
    fn finite(&self, key: &str, v: &Value) -> Result<f32, String> {
        v.as_f64()
            .map(|x| x as f32)
            .filter(|x| x.is_finite())
            .ok_or_else(|| self.err(key, format!("must be a finite number, got {}", short(v))))
    }

    /// Three numbers, each clamped to [lo, hi] with a warning.
    fn colour(&mut self, key: &str, v: &Value, lo: f32, hi: f32) -> Result<[f32; 3], String> {
        let a = v.as_array().filter(|a| a.len() == 3).ok_or_else(|| {
            self.err(
                key,
                format!("must be an array of 3 numbers, got {}", short(v)),
            )
        })?;
        let mut out = [0.0; 3];
        for (o, x) in out.iter_mut().zip(a) {
            let n = x
                .as_f64()
                .map(|n| n as f32)
                .filter(|n| n.is_finite())
                .ok_or_else(|| {
                    self.err(
                        key,
                        format!("must be an array of 3 finite numbers, got {}", short(v)),
                    )
                })?;
            *o = n;
        }
        if out.iter().any(|x| !(lo..=hi).contains(x)) {
            self.warnings.push(format!(
                "material '{}': {}.{key} is {out:?}, outside [{lo}, {hi}]; clamped",
                self.material, self.extension
            ));
        }
        Ok(out.map(|x| x.clamp(lo, hi)))
    }

    fn texture(&self, key: &str, v: &Value) -> Result<TexRef, String> {
        let o = v.as_object().ok_or_else(|| {
            self.err(
                key,
                format!(
                    "must be a textureInfo object ({{\"index\": N}}), got {}",
                    short(v)
                ),
            )
        })?;
        let index = o
            .get("index")
            .and_then(Value::as_u64)
            .and_then(|i| usize::try_from(i).ok())
            .ok_or_else(|| {
                self.err(
                    key,
                    format!("needs an unsigned integer \"index\", got {}", short(v)),
                )
            })?;
        let tex_coord = match o.get("texCoord") {
            None => 0,
            Some(t) => t
                .as_u64()
                .and_then(|t| u32::try_from(t).ok())
                .ok_or_else(|| {
                    self.err(
                        key,
                        format!(
                            "has texCoord {}, which must be an unsigned integer",
                            short(t)
                        ),
                    )
                })?,
        };
        let transform = o
            .get("extensions")
            .and_then(|e| e.get("KHR_texture_transform"))
            .cloned();
        Ok(TexRef {
            index,
            tex_coord,
            transform,
        })
    }

    fn unknown(&mut self, key: &str) {
        if key != "extensions" && key != "extras" {
            self.warnings.push(format!(
                "material '{}': {} has the unknown key '{key}', ignored",
                self.material, self.extension
            ));
        }
    }
}

pub fn sheen(ctx: &mut Ctx, v: &Value) -> Result<SheenExt, String> {
    let mut out = SheenExt {
        color: [0.0; 3],
        roughness: 0.0,
        color_texture: None,
        roughness_texture: None,
    };
    for (key, v) in ctx.object(v)? {
        match key.as_str() {
            "sheenColorFactor" => out.color = ctx.colour(key, v, 0.0, 1.0)?,
            "sheenRoughnessFactor" => out.roughness = ctx.number(key, v, 0.0, 1.0)?,
            "sheenColorTexture" => out.color_texture = Some(ctx.texture(key, v)?),
            "sheenRoughnessTexture" => out.roughness_texture = Some(ctx.texture(key, v)?),
            other => ctx.unknown(other),
        }
    }
    Ok(out)
}

pub fn specular(ctx: &mut Ctx, v: &Value) -> Result<SpecularExt, String> {
    let mut out = SpecularExt {
        factor: 1.0,
        color: [1.0; 3],
        texture: None,
        color_texture: None,
    };
    for (key, v) in ctx.object(v)? {
        match key.as_str() {
            "specularFactor" => out.factor = ctx.number(key, v, 0.0, 1.0)?,
            // The specification allows colours above 1 (F0 is clamped to 1 after the product);
            // 1000 bounds what a half float can carry.
            "specularColorFactor" => out.color = ctx.colour(key, v, 0.0, 1000.0)?,
            "specularTexture" => out.texture = Some(ctx.texture(key, v)?),
            "specularColorTexture" => out.color_texture = Some(ctx.texture(key, v)?),
            other => ctx.unknown(other),
        }
    }
    Ok(out)
}

/// KHR_materials_ior: the index of refraction (0 is allowed by the specification and means
/// F0 = 1; otherwise at least 1).
pub fn ior(ctx: &mut Ctx, v: &Value) -> Result<f32, String> {
    let mut ior = 1.5;
    for (key, v) in ctx.object(v)? {
        match key.as_str() {
            "ior" => {
                let x = ctx.finite(key, v)?;
                ior = if x == 0.0 {
                    0.0
                } else {
                    ctx.number(key, v, 1.0, 10.0)?
                };
            }
            other => ctx.unknown(other),
        }
    }
    Ok(ior)
}

pub fn anisotropy(ctx: &mut Ctx, v: &Value) -> Result<AnisotropyExt, String> {
    let mut out = AnisotropyExt {
        strength: 0.0,
        rotation: 0.0,
        texture: None,
    };
    for (key, v) in ctx.object(v)? {
        match key.as_str() {
            "anisotropyStrength" => out.strength = ctx.number(key, v, 0.0, 1.0)?,
            "anisotropyRotation" => out.rotation = ctx.finite(key, v)?,
            "anisotropyTexture" => out.texture = Some(ctx.texture(key, v)?),
            other => ctx.unknown(other),
        }
    }
    Ok(out)
}

pub fn transmission(ctx: &mut Ctx, v: &Value) -> Result<TransmissionExt, String> {
    let mut out = TransmissionExt {
        factor: 0.0,
        texture: None,
    };
    for (key, v) in ctx.object(v)? {
        match key.as_str() {
            "transmissionFactor" => out.factor = ctx.number(key, v, 0.0, 1.0)?,
            "transmissionTexture" => out.texture = Some(ctx.texture(key, v)?),
            other => ctx.unknown(other),
        }
    }
    Ok(out)
}

pub fn clearcoat(ctx: &mut Ctx, v: &Value) -> Result<ClearcoatExt, String> {
    let mut out = ClearcoatExt {
        factor: 0.0,
        texture: None,
        roughness: 0.0,
        roughness_texture: None,
        normal_texture: None,
        normal_scale: 1.0,
    };
    for (key, v) in ctx.object(v)? {
        match key.as_str() {
            "clearcoatFactor" => out.factor = ctx.number(key, v, 0.0, 1.0)?,
            "clearcoatTexture" => out.texture = Some(ctx.texture(key, v)?),
            "clearcoatRoughnessFactor" => out.roughness = ctx.number(key, v, 0.0, 1.0)?,
            "clearcoatRoughnessTexture" => out.roughness_texture = Some(ctx.texture(key, v)?),
            "clearcoatNormalTexture" => {
                out.normal_texture = Some(ctx.texture(key, v)?);
                if let Some(s) = v.get("scale") {
                    out.normal_scale =
                        ctx.number("clearcoatNormalTexture.scale", s, -100.0, 100.0)?;
                }
            }
            other => ctx.unknown(other),
        }
    }
    Ok(out)
}

pub fn spec_gloss(ctx: &mut Ctx, v: &Value) -> Result<SpecGlossExt, String> {
    let mut out = SpecGlossExt {
        diffuse: [1.0; 4],
        diffuse_texture: None,
        specular: [1.0; 3],
        glossiness: 1.0,
        texture: None,
    };
    for (key, v) in ctx.object(v)? {
        match key.as_str() {
            "diffuseFactor" => {
                // Four numbers: the colour and its alpha, each in [0, 1].
                let a = v.as_array().filter(|a| a.len() == 4).ok_or_else(|| {
                    ctx.err(
                        key,
                        format!("must be an array of 4 numbers, got {}", short(v)),
                    )
                })?;
                let rgb = ctx.colour(key, &Value::Array(a[..3].to_vec()), 0.0, 1.0)?;
                let alpha = ctx.number(key, &a[3], 0.0, 1.0)?;
                out.diffuse = [rgb[0], rgb[1], rgb[2], alpha];
            }
            "diffuseTexture" => out.diffuse_texture = Some(ctx.texture(key, v)?),
            "specularFactor" => out.specular = ctx.colour(key, v, 0.0, 1.0)?,
            "glossinessFactor" => out.glossiness = ctx.number(key, v, 0.0, 1.0)?,
            "specularGlossinessTexture" => out.texture = Some(ctx.texture(key, v)?),
            other => ctx.unknown(other),
        }
    }
    Ok(out)
}

pub fn iridescence(ctx: &mut Ctx, v: &Value) -> Result<IridescenceExt, String> {
    let mut out = IridescenceExt {
        factor: 0.0,
        texture: None,
        ior: 1.3,
        thickness_min: 100.0,
        thickness_max: 400.0,
        thickness_texture: None,
    };
    for (key, v) in ctx.object(v)? {
        match key.as_str() {
            "iridescenceFactor" => out.factor = ctx.number(key, v, 0.0, 1.0)?,
            "iridescenceTexture" => out.texture = Some(ctx.texture(key, v)?),
            // The specification asks for at least 1; a film thinner than air is not a film.
            "iridescenceIor" => out.ior = ctx.number(key, v, 1.0, 10.0)?,
            // Nanometres; a film of over 100 µm shows no colours (its orders blur out).
            "iridescenceThicknessMinimum" => out.thickness_min = ctx.number(key, v, 0.0, 1e5)?,
            "iridescenceThicknessMaximum" => out.thickness_max = ctx.number(key, v, 0.0, 1e5)?,
            "iridescenceThicknessTexture" => out.thickness_texture = Some(ctx.texture(key, v)?),
            other => ctx.unknown(other),
        }
    }
    Ok(out)
}

pub fn diffuse_transmission(ctx: &mut Ctx, v: &Value) -> Result<DiffuseTransmissionExt, String> {
    let mut out = DiffuseTransmissionExt {
        factor: 0.0,
        texture: None,
        color: [1.0; 3],
        color_texture: None,
    };
    for (key, v) in ctx.object(v)? {
        match key.as_str() {
            "diffuseTransmissionFactor" => out.factor = ctx.number(key, v, 0.0, 1.0)?,
            "diffuseTransmissionTexture" => out.texture = Some(ctx.texture(key, v)?),
            "diffuseTransmissionColorFactor" => out.color = ctx.colour(key, v, 0.0, 1.0)?,
            "diffuseTransmissionColorTexture" => out.color_texture = Some(ctx.texture(key, v)?),
            other => ctx.unknown(other),
        }
    }
    Ok(out)
}

pub fn volume(ctx: &mut Ctx, v: &Value) -> Result<VolumeExt, String> {
    let mut out = VolumeExt {
        thickness: 0.0,
        thickness_texture: None,
        attenuation_color: [1.0; 3],
        attenuation_distance: None,
    };
    for (key, v) in ctx.object(v)? {
        match key.as_str() {
            // Object-space distances; 1e6 bounds what the shader's arithmetic needs.
            "thicknessFactor" => out.thickness = ctx.number(key, v, 0.0, 1e6)?,
            "thicknessTexture" => out.thickness_texture = Some(ctx.texture(key, v)?),
            "attenuationColor" => out.attenuation_color = ctx.colour(key, v, 0.0, 1.0)?,
            "attenuationDistance" => {
                let d = ctx.finite(key, v)?;
                if d <= 0.0 {
                    return Err(ctx.err(key, format!("must be positive, got {d}")));
                }
                out.attenuation_distance = Some(d);
            }
            other => ctx.unknown(other),
        }
    }
    Ok(out)
}

/// KHR_materials_dispersion's `dispersion` (20 / the Abbe number; 0 by default).
pub fn dispersion(ctx: &mut Ctx, v: &Value) -> Result<f32, String> {
    let mut out = 0.0;
    for (key, v) in ctx.object(v)? {
        match key.as_str() {
            // An Abbe number below 1 (dispersion above 20) is beyond any glass or crystal.
            "dispersion" => out = ctx.number(key, v, 0.0, 20.0)?,
            other => ctx.unknown(other),
        }
    }
    Ok(out)
}

/// The root's `KHR_materials_variants.variants[].name`s.
pub fn variant_names(root: Option<&Value>) -> Result<Vec<String>, String> {
    let Some(root) = root else {
        return Ok(Vec::new());
    };
    let list = root
        .get("variants")
        .and_then(Value::as_array)
        .ok_or_else(|| format!("{VARIANTS} on the root must have a \"variants\" array of {{\"name\": ...}} objects"))?;
    list.iter()
        .enumerate()
        .map(|(i, v)| {
            v.get("name")
                .and_then(Value::as_str)
                .map(str::to_owned)
                .ok_or_else(|| {
                    format!(
                        "{VARIANTS}.variants[{i}] needs a string \"name\", got {}",
                        short(v)
                    )
                })
        })
        .collect()
}

/// The material a primitive's `KHR_materials_variants.mappings` gives variant `variant`, if any.
pub fn mapped_material(
    prim_ext: &Value,
    variant: usize,
    variants: usize,
) -> Result<Option<usize>, String> {
    let mappings = prim_ext
        .get("mappings")
        .and_then(Value::as_array)
        .ok_or_else(|| format!("{VARIANTS} on a primitive must have a \"mappings\" array"))?;
    for (i, m) in mappings.iter().enumerate() {
        let material = m
            .get("material")
            .and_then(Value::as_u64)
            .and_then(|x| usize::try_from(x).ok())
            .ok_or_else(|| {
                format!("{VARIANTS}.mappings[{i}] needs an unsigned integer \"material\"")
            })?;
        let list = m.get("variants").and_then(Value::as_array).ok_or_else(|| {
            format!("{VARIANTS}.mappings[{i}] needs a \"variants\" array of indices")
        })?;
        for x in list {
            let x = x
                .as_u64()
                .and_then(|x| usize::try_from(x).ok())
                .filter(|&x| x < variants)
                .ok_or_else(|| format!("{VARIANTS}.mappings[{i}].variants holds {x}, which is not the index of one of the file's {variants} variant(s)"))?;
            if x == variant {
                return Ok(Some(material));
            }
        }
    }
    Ok(None)
}
