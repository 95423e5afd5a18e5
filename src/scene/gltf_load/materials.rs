//! The materials: glTF metallic-roughness and its ratified extensions, `WEFT_materials_fabric`, texture slots, samplers and texture transforms.

use super::*;

impl<'a> Loader<'a> {
    // --- materials and textures -----------------------------------------------------------------

    pub(super) fn load_materials(&mut self) -> Result<()> {
        let doc = self.doc;
        for (index, m) in doc.materials().enumerate() {
            let (material, uv, transforms) = self.material(&m, index)?;
            self.scene.materials.push(material);
            self.material_uv.push(uv);
            self.slot_transforms.push(transforms);
        }
        self.scene.file_materials = self.scene.materials.len();
        Ok(())
    }

    pub(super) fn material(
        &mut self,
        m: &gltf::Material<'a>,
        index: usize,
    ) -> Result<(Material, UvTransform, [UvTransform; TextureSlot::COUNT])> {
        let name = m
            .name()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("material {index}"));
        let who = format!("material '{name}'");
        let pbr = m.pbr_metallic_roughness();

        let label = self.label.clone();
        let finite = |what: &str, values: &[f32]| -> Result<()> {
            if values.iter().all(|v| v.is_finite()) {
                Ok(())
            } else {
                Err(Error::input(format!(
                    "{label}: {who} has a non-finite {what} {values:?}; set it to a finite number"
                )))
            }
        };
        let base_color = pbr.base_color_factor();
        finite("baseColorFactor", &base_color)?;
        finite("metallicFactor", &[pbr.metallic_factor()])?;
        finite("roughnessFactor", &[pbr.roughness_factor()])?;
        let emissive_strength = m.emissive_strength().unwrap_or(1.0);
        finite("KHR_materials_emissive_strength", &[emissive_strength])?;
        let emissive_factor = m.emissive_factor();
        finite("emissiveFactor", &emissive_factor)?;
        let emissive = Vec3::from(emissive_factor) * emissive_strength;
        finite(
            "emitted radiance (emissiveFactor times KHR_materials_emissive_strength, which overflows)",
            &emissive.to_array(),
        )?;

        let clamp01 = |what: &str, v: f32, loader: &mut Self| -> f32 {
            if !(0.0..=1.0).contains(&v) {
                loader.warn(format_args!(
                    "{who} has {what} {v}, outside [0, 1]; clamped"
                ));
            }
            v.clamp(0.0, 1.0)
        };
        let metallic = clamp01("metallicFactor", pbr.metallic_factor(), self);
        let roughness = clamp01("roughnessFactor", pbr.roughness_factor(), self);

        // Each texture slot's UV set and transform, in slot order (the first on TEXCOORD_0
        // becomes the frame transform baked into the vertices).
        let mut uv_transforms: Vec<(TextureSlot, UvTransform, u32, TextureSampler)> = Vec::new();
        let slot = |loader: &mut Self,
                    info_tex: gltf::Texture<'a>,
                    tex_coord: u32,
                    transform: Option<(UvTransform, Option<u32>)>,
                    kind: (TextureSlot, &'static str),
                    color_space: ColorSpace,
                    uv_transforms: &mut Vec<(TextureSlot, UvTransform, u32, TextureSampler)>|
         -> Result<usize> {
            let (slot_kind, slot_name) = kind;
            let (uv, mut set) = match transform {
                Some((t, set)) => (t, set.unwrap_or(tex_coord)),
                None => (UvTransform::IDENTITY, tex_coord),
            };
            if set > 1 {
                loader.warn(format_args!(
                    "{who}'s {slot_name} uses TEXCOORD_{set}; weft reads TEXCOORD_0 and TEXCOORD_1, so it is sampled with TEXCOORD_0"
                ));
                set = 0;
            }
            let sampler = loader.sampler(&info_tex, &who, slot_name)?;
            uv_transforms.push((slot_kind, uv, set, sampler));
            loader.texture(&info_tex, color_space, &who, slot_name)
        };

        let info_transform =
            |info: &gltf::texture::Info| -> Result<Option<(UvTransform, Option<u32>)>> {
                match info.texture_transform() {
                    None => Ok(None),
                    Some(t) => {
                        let uv = UvTransform {
                            offset: t.offset(),
                            rotation: t.rotation(),
                            scale: t.scale(),
                        };
                        finite(
                            "KHR_texture_transform",
                            &[
                                uv.offset[0],
                                uv.offset[1],
                                uv.rotation,
                                uv.scale[0],
                                uv.scale[1],
                            ],
                        )?;
                        Ok(Some((uv, t.tex_coord())))
                    }
                }
            };

        // KHR_materials_pbrSpecularGlossiness, where present, replaces the metallic-roughness
        // parameters (its specification: the file's fallback for viewers without it).
        let spec_gloss_present = m
            .extensions()
            .is_some_and(|e| e.contains_key(material_ext::SPEC_GLOSS));
        let base_color_texture = match pbr.base_color_texture().filter(|_| !spec_gloss_present) {
            Some(info) => Some(slot(
                self,
                info.texture(),
                info.tex_coord(),
                info_transform(&info)?,
                (TextureSlot::BaseColor, "base colour texture"),
                ColorSpace::Srgb,
                &mut uv_transforms,
            )?),
            None => None,
        };
        let metallic_roughness_texture = match pbr
            .metallic_roughness_texture()
            .filter(|_| !spec_gloss_present)
        {
            Some(info) => Some(slot(
                self,
                info.texture(),
                info.tex_coord(),
                info_transform(&info)?,
                (TextureSlot::MetallicRoughness, "metallic-roughness texture"),
                ColorSpace::Linear,
                &mut uv_transforms,
            )?),
            None => None,
        };
        let (normal_texture, normal_scale) = match m.normal_texture() {
            Some(normal) => {
                // The gltf crate leaves KHR_texture_transform on normal textures as raw JSON.
                let transform = match normal.extension_value("KHR_texture_transform") {
                    Some(v) => Some(self.parse_texture_transform(v, &who, "normal texture")?),
                    None => None,
                };
                let scale = normal.scale();
                finite("normalTexture.scale", &[scale])?;
                let t = slot(
                    self,
                    normal.texture(),
                    normal.tex_coord(),
                    transform,
                    (TextureSlot::Normal, "normal texture"),
                    ColorSpace::Linear,
                    &mut uv_transforms,
                )?;
                (Some(t), scale)
            }
            None => (None, 1.0),
        };
        let emissive_texture = match m.emissive_texture() {
            Some(info) => Some(slot(
                self,
                info.texture(),
                info.tex_coord(),
                info_transform(&info)?,
                (TextureSlot::Emissive, "emissive texture"),
                ColorSpace::Srgb,
                &mut uv_transforms,
            )?),
            None => None,
        };
        let (occlusion_texture, occlusion_strength) = match m.occlusion_texture() {
            Some(occ) => {
                let transform = match occ.extension_value("KHR_texture_transform") {
                    Some(v) => Some(self.parse_texture_transform(v, &who, "occlusion texture")?),
                    None => None,
                };
                let strength = occ.strength();
                finite("occlusionTexture.strength", &[strength])?;
                if !(0.0..=1.0).contains(&strength) {
                    self.warn(format_args!(
                        "{who} has occlusionTexture.strength {strength}, outside [0, 1]; clamped"
                    ));
                }
                let t = slot(
                    self,
                    occ.texture(),
                    occ.tex_coord(),
                    transform,
                    (TextureSlot::Occlusion, "occlusion texture"),
                    ColorSpace::Linear,
                    &mut uv_transforms,
                )?;
                (Some(t), strength.clamp(0.0, 1.0))
            }
            None => (None, 1.0),
        };
        let alpha_cutoff = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => None,
            gltf::material::AlphaMode::Mask => {
                let cutoff = m.alpha_cutoff().unwrap_or(0.5);
                finite("alphaCutoff", &[cutoff])?;
                if !(0.0..=1.0).contains(&cutoff) {
                    self.warn(format_args!(
                        "{who} has alphaCutoff {cutoff}, outside [0, 1]; clamped to {}",
                        cutoff.clamp(0.0, 1.0)
                    ));
                }
                Some(cutoff.clamp(0.0, 1.0))
            }
            gltf::material::AlphaMode::Blend => None,
        };
        let blend = m.alpha_mode() == gltf::material::AlphaMode::Blend;

        // The material extensions (sheen, specular, ior, anisotropy), with their textures.
        let ext = |key: &str| m.extensions().and_then(|e| e.get(key));
        let mut ctx = material_ext::Ctx {
            material: &name,
            extension: material_ext::SHEEN,
            warnings: Vec::new(),
        };
        let sheen_ext = ext(material_ext::SHEEN)
            .map(|v| material_ext::sheen(&mut ctx, v))
            .transpose()
            .map_err(|e| self.error(e))?;
        ctx.extension = material_ext::SPECULAR;
        let specular_ext = ext(material_ext::SPECULAR)
            .map(|v| material_ext::specular(&mut ctx, v))
            .transpose()
            .map_err(|e| self.error(e))?;
        ctx.extension = material_ext::IOR;
        let ior = ext(material_ext::IOR)
            .map(|v| material_ext::ior(&mut ctx, v))
            .transpose()
            .map_err(|e| self.error(e))?;
        ctx.extension = material_ext::ANISOTROPY;
        let anisotropy_ext = ext(material_ext::ANISOTROPY)
            .map(|v| material_ext::anisotropy(&mut ctx, v))
            .transpose()
            .map_err(|e| self.error(e))?;
        ctx.extension = material_ext::TRANSMISSION;
        let transmission_ext = ext(material_ext::TRANSMISSION)
            .map(|v| material_ext::transmission(&mut ctx, v))
            .transpose()
            .map_err(|e| self.error(e))?;
        ctx.extension = material_ext::VOLUME;
        let volume_ext = ext(material_ext::VOLUME)
            .map(|v| material_ext::volume(&mut ctx, v))
            .transpose()
            .map_err(|e| self.error(e))?;
        ctx.extension = material_ext::DIFFUSE_TRANSMISSION;
        let diffuse_transmission_ext = ext(material_ext::DIFFUSE_TRANSMISSION)
            .map(|v| material_ext::diffuse_transmission(&mut ctx, v))
            .transpose()
            .map_err(|e| self.error(e))?;
        ctx.extension = material_ext::IRIDESCENCE;
        let iridescence_ext = ext(material_ext::IRIDESCENCE)
            .map(|v| material_ext::iridescence(&mut ctx, v))
            .transpose()
            .map_err(|e| self.error(e))?;
        ctx.extension = material_ext::DISPERSION;
        let dispersion = ext(material_ext::DISPERSION)
            .map(|v| material_ext::dispersion(&mut ctx, v))
            .transpose()
            .map_err(|e| self.error(e))?;
        ctx.extension = material_ext::SPEC_GLOSS;
        let spec_gloss_ext = ext(material_ext::SPEC_GLOSS)
            .map(|v| material_ext::spec_gloss(&mut ctx, v))
            .transpose()
            .map_err(|e| self.error(e))?;
        ctx.extension = material_ext::CLEARCOAT;
        let clearcoat_ext = ext(material_ext::CLEARCOAT)
            .map(|v| material_ext::clearcoat(&mut ctx, v))
            .transpose()
            .map_err(|e| self.error(e))?;
        for w in std::mem::take(&mut ctx.warnings) {
            self.warn(w);
        }
        let ext_texture =
            |loader: &mut Self,
             r: &Option<TexRef>,
             kind: (TextureSlot, &'static str),
             color_space: ColorSpace,
             uv_transforms: &mut Vec<(TextureSlot, UvTransform, u32, TextureSampler)>|
             -> Result<Option<usize>> {
                let Some(r) = r else { return Ok(None) };
                let Some(texture) = loader.doc.textures().nth(r.index) else {
                    return Err(loader.error(format_args!(
                    "{who}'s {} refers to texture {}, but the file has {} textures; fix the index",
                    kind.1,
                    r.index,
                    loader.doc.textures().len()
                )));
                };
                let transform = match &r.transform {
                    Some(v) => Some(loader.parse_texture_transform(v, &who, kind.1)?),
                    None => None,
                };
                slot(
                    loader,
                    texture,
                    r.tex_coord,
                    transform,
                    kind,
                    color_space,
                    uv_transforms,
                )
                .map(Some)
            };
        let sheen = match &sheen_ext {
            None => None,
            Some(e) => Some(Sheen {
                color: e.color,
                roughness: e.roughness,
                color_texture: ext_texture(
                    self,
                    &e.color_texture,
                    (TextureSlot::SheenColor, "sheen colour texture"),
                    ColorSpace::Srgb,
                    &mut uv_transforms,
                )?,
                roughness_texture: ext_texture(
                    self,
                    &e.roughness_texture,
                    (TextureSlot::SheenRoughness, "sheen roughness texture"),
                    ColorSpace::Linear,
                    &mut uv_transforms,
                )?,
            }),
        };
        let mut specular = Specular::default();
        if let Some(e) = &specular_ext {
            specular.factor = e.factor;
            specular.color = e.color;
            specular.texture = ext_texture(
                self,
                &e.texture,
                (TextureSlot::Specular, "specular texture"),
                ColorSpace::Linear,
                &mut uv_transforms,
            )?;
            specular.color_texture = ext_texture(
                self,
                &e.color_texture,
                (TextureSlot::SpecularColor, "specular colour texture"),
                ColorSpace::Srgb,
                &mut uv_transforms,
            )?;
        }
        if let Some(ior) = ior {
            specular.ior = ior;
        }
        // KHR_materials_pbrSpecularGlossiness in the metallic-roughness model: a dielectric
        // (metallic 0) whose diffuse is the base colour, whose F0 is the specular colour (through
        // KHR_materials_specular's colour: F0(ior 1.5) = 0.04 times specular / 0.04) and whose
        // roughness is 1 − glossiness. The one texture holds the specular colour (RGB, sRGB) and
        // the glossiness (A, linear): bound to the specular colour slot and, for its alpha, the
        // metallic-roughness slot (MATERIAL_SPEC_GLOSS tells the shader to read roughness from
        // there as 1 − glossiness · A).
        let (
            base_color,
            base_color_texture,
            metallic,
            roughness,
            metallic_roughness_texture,
            glossiness,
        ) = match &spec_gloss_ext {
            None => (
                base_color,
                base_color_texture,
                metallic,
                roughness,
                metallic_roughness_texture,
                None,
            ),
            Some(e) => {
                if specular_ext.is_some() || ior.is_some() {
                    self.warn(format_args!(
                            "{who} has {} with {} or {}; the specular-glossiness model sets its own specular colour and index, so those are ignored",
                            material_ext::SPEC_GLOSS,
                            material_ext::SPECULAR,
                            material_ext::IOR
                        ));
                }
                let texture = ext_texture(
                    self,
                    &e.texture,
                    (TextureSlot::SpecularColor, "specular-glossiness texture"),
                    ColorSpace::Srgb,
                    &mut uv_transforms,
                )?;
                let gloss_texture = ext_texture(
                    self,
                    &e.texture,
                    (
                        TextureSlot::MetallicRoughness,
                        "specular-glossiness texture",
                    ),
                    ColorSpace::Srgb,
                    &mut uv_transforms,
                )?;
                specular = Specular {
                    factor: 1.0,
                    color: e.specular.map(|c| c / 0.04),
                    texture: None,
                    color_texture: texture,
                    ior: 1.5,
                };
                let diffuse_texture = ext_texture(
                    self,
                    &e.diffuse_texture,
                    (TextureSlot::BaseColor, "diffuse texture"),
                    ColorSpace::Srgb,
                    &mut uv_transforms,
                )?;
                (
                    e.diffuse,
                    diffuse_texture,
                    0.0,
                    1.0 - e.glossiness,
                    gloss_texture,
                    Some(e.glossiness),
                )
            }
        };
        let anisotropy = match &anisotropy_ext {
            None => None,
            Some(e) => Some(Anisotropy {
                strength: e.strength,
                rotation: e.rotation,
                texture: ext_texture(
                    self,
                    &e.texture,
                    (TextureSlot::Anisotropy, "anisotropy texture"),
                    ColorSpace::Linear,
                    &mut uv_transforms,
                )?,
            }),
        };
        // KHR_materials_volume only means something with transmission (its specification).
        let transmission = match &transmission_ext {
            None => {
                if volume_ext.is_some() {
                    self.warn(format_args!(
                        "{who} has {} without {}; the volume is ignored (it only shapes transmitted light)",
                        material_ext::VOLUME,
                        material_ext::TRANSMISSION
                    ));
                }
                if dispersion.is_some_and(|d| d > 0.0) {
                    self.warn(format_args!(
                        "{who} has {} without {}; the dispersion is ignored (it only spreads refracted light)",
                        material_ext::DISPERSION,
                        material_ext::TRANSMISSION
                    ));
                }
                None
            }
            Some(e) => {
                let texture = ext_texture(
                    self,
                    &e.texture,
                    (TextureSlot::Transmission, "transmission texture"),
                    ColorSpace::Linear,
                    &mut uv_transforms,
                )?;
                let (thickness, thickness_texture, attenuation_color, attenuation_distance) =
                    match &volume_ext {
                        None => (0.0, None, [1.0; 3], None),
                        Some(v) => (
                            v.thickness,
                            ext_texture(
                                self,
                                &v.thickness_texture,
                                (TextureSlot::Thickness, "thickness texture"),
                                ColorSpace::Linear,
                                &mut uv_transforms,
                            )?,
                            v.attenuation_color,
                            v.attenuation_distance,
                        ),
                    };
                // KHR_materials_dispersion spreads the volume's refraction: meaningless
                // without a volume (a thin wall does not refract).
                if dispersion.is_some_and(|d| d > 0.0) && volume_ext.is_none() {
                    self.warn(format_args!(
                        "{who} has {} without {}; a thin wall does not refract, so the dispersion is ignored",
                        material_ext::DISPERSION,
                        material_ext::VOLUME
                    ));
                }
                Some(Transmission {
                    factor: e.factor,
                    texture,
                    thickness,
                    thickness_texture,
                    attenuation_color,
                    attenuation_distance,
                    dispersion: if volume_ext.is_some() {
                        dispersion.unwrap_or(0.0)
                    } else {
                        0.0
                    },
                })
            }
        };

        let clearcoat = match &clearcoat_ext {
            None => None,
            Some(e) => Some(Clearcoat {
                factor: e.factor,
                texture: ext_texture(
                    self,
                    &e.texture,
                    (TextureSlot::Clearcoat, "clearcoat texture"),
                    ColorSpace::Linear,
                    &mut uv_transforms,
                )?,
                roughness: e.roughness,
                roughness_texture: ext_texture(
                    self,
                    &e.roughness_texture,
                    (
                        TextureSlot::ClearcoatRoughness,
                        "clearcoat roughness texture",
                    ),
                    ColorSpace::Linear,
                    &mut uv_transforms,
                )?,
                normal_texture: ext_texture(
                    self,
                    &e.normal_texture,
                    (TextureSlot::ClearcoatNormal, "clearcoat normal texture"),
                    ColorSpace::Linear,
                    &mut uv_transforms,
                )?,
                normal_scale: e.normal_scale,
            }),
        };

        let diffuse_transmission = match &diffuse_transmission_ext {
            None => None,
            Some(e) => Some(DiffuseTransmission {
                factor: e.factor,
                texture: ext_texture(
                    self,
                    &e.texture,
                    (
                        TextureSlot::DiffuseTransmission,
                        "diffuse transmission texture",
                    ),
                    ColorSpace::Linear,
                    &mut uv_transforms,
                )?,
                color: e.color,
                color_texture: ext_texture(
                    self,
                    &e.color_texture,
                    (
                        TextureSlot::DiffuseTransmissionColor,
                        "diffuse transmission colour texture",
                    ),
                    ColorSpace::Srgb,
                    &mut uv_transforms,
                )?,
            }),
        };

        let iridescence = match &iridescence_ext {
            None => None,
            Some(e) => Some(Iridescence {
                factor: e.factor,
                texture: ext_texture(
                    self,
                    &e.texture,
                    (TextureSlot::Iridescence, "iridescence texture"),
                    ColorSpace::Linear,
                    &mut uv_transforms,
                )?,
                ior: e.ior,
                thickness_min: e.thickness_min,
                thickness_max: e.thickness_max,
                thickness_texture: ext_texture(
                    self,
                    &e.thickness_texture,
                    (
                        TextureSlot::IridescenceThickness,
                        "iridescence thickness texture",
                    ),
                    ColorSpace::Linear,
                    &mut uv_transforms,
                )?,
            }),
        };

        // TEXCOORD_0 carries one transform, baked into the vertices (so tangents and the weave
        // follow it): the first TEXCOORD_0 slot's. Every slot then gets its own map from the
        // baked coordinates (or from TEXCOORD_1) to its own.
        let frame = uv_transforms
            .iter()
            .find(|(_, t, set, _)| *set == 0 && t.inverse().is_some())
            .map_or(UvTransform::IDENTITY, |(_, t, _, _)| *t);
        let frame_inverse = frame.inverse().unwrap_or(UvTransform::IDENTITY.affine());
        let mut slot_uv = [SlotUv::IDENTITY; TextureSlot::COUNT];
        let mut samplers = [TextureSampler::default(); TextureSlot::COUNT];
        for (kind, t, set, sampler) in &uv_transforms {
            samplers[*kind as usize] = *sampler;
            let m = if *set == 0 {
                UvTransform::compose(t.affine(), frame_inverse)
            } else {
                t.affine()
            };
            slot_uv[*kind as usize] = SlotUv { set: *set, m };
        }
        let uv = frame;

        let fabric = match m.extensions().and_then(|e| e.get(FABRIC_EXTENSION)) {
            Some(value) => Some(
                FabricParams::from_gltf_extension(value, &name, &mut self.scene.warnings).map_err(
                    |e| match e {
                        Error::Input(msg) => self.error(msg),
                        other => other,
                    },
                )?,
            ),
            None => None,
        };

        let mut unlit = m.extensions().and_then(|e| e.get(UNLIT)).is_some();
        if unlit && fabric.is_some() {
            self.warn(format_args!(
                "{who} has both {UNLIT} and {FABRIC_EXTENSION}; the woven model is lit, so {UNLIT} is ignored on it"
            ));
            unlit = false;
        }

        let transmission = self.not_on_fabric(
            transmission,
            fabric.is_some(),
            &who,
            material_ext::TRANSMISSION,
            "light through the weave is not modelled yet, so the transmission is ignored on it",
        );
        let diffuse_transmission = self.not_on_fabric(diffuse_transmission, fabric.is_some(), &who, material_ext::DIFFUSE_TRANSMISSION, "light through the weave is not modelled yet, so the diffuse transmission is ignored on it");
        let iridescence = self.not_on_fabric(
            iridescence,
            fabric.is_some(),
            &who,
            material_ext::IRIDESCENCE,
            "the woven model's threads carry no thin film yet, so the iridescence is ignored on it",
        );
        let clearcoat = self.not_on_fabric(
            clearcoat,
            fabric.is_some(),
            &who,
            material_ext::CLEARCOAT,
            "the woven model has no coat yet, so the clearcoat is ignored on it",
        );
        let material = Material {
            name,
            base_color,
            metallic,
            roughness,
            emissive: emissive.to_array(),
            normal_scale,
            base_color_texture,
            metallic_roughness_texture,
            normal_texture,
            emissive_texture,
            occlusion_texture,
            occlusion_strength,
            double_sided: m.double_sided(),
            fabric,
            sheen,
            specular,
            anisotropy,
            transmission,
            clearcoat,
            diffuse_transmission,
            iridescence,
            glossiness,
            uv: slot_uv,
            samplers,
            unlit,
            alpha_cutoff,
            blend,
        };
        let mut transforms = [UvTransform::IDENTITY; TextureSlot::COUNT];
        for (kind, t, _, _) in &uv_transforms {
            transforms[*kind as usize] = *t;
        }
        Ok((material, uv, transforms))
    }

    /// KHR_texture_transform from raw JSON (normal textures).
    pub(super) fn parse_texture_transform(
        &self,
        v: &serde_json::Value,
        who: &str,
        slot_name: &str,
    ) -> Result<(UvTransform, Option<u32>)> {
        let bad = || {
            self.error(format_args!(
                "{who}'s {slot_name} has a malformed KHR_texture_transform ({v}); offset and scale must be [x, y] numbers, rotation a number, texCoord an unsigned integer"
            ))
        };
        let pair = |key: &str, default: [f32; 2]| -> Result<[f32; 2]> {
            match v.get(key) {
                None => Ok(default),
                Some(serde_json::Value::Array(a)) if a.len() == 2 => {
                    let x = a[0].as_f64().ok_or_else(bad)? as f32;
                    let y = a[1].as_f64().ok_or_else(bad)? as f32;
                    Ok([x, y])
                }
                Some(_) => Err(bad()),
            }
        };
        let rotation = match v.get("rotation") {
            None => 0.0,
            Some(r) => r.as_f64().ok_or_else(bad)? as f32,
        };
        let tex_coord = match v.get("texCoord") {
            None => None,
            Some(t) => Some(
                t.as_u64()
                    .and_then(|t| u32::try_from(t).ok())
                    .ok_or_else(bad)?,
            ),
        };
        let uv = UvTransform {
            offset: pair("offset", [0.0, 0.0])?,
            rotation,
            scale: pair("scale", [1.0, 1.0])?,
        };
        if ![
            uv.offset[0],
            uv.offset[1],
            uv.rotation,
            uv.scale[0],
            uv.scale[1],
        ]
        .iter()
        .all(|x| x.is_finite())
        {
            return Err(bad());
        }
        Ok((uv, tex_coord))
    }

    /// `texture`'s sampler (glTF's defaults without one): wrap modes and filters.
    pub(super) fn sampler(
        &self,
        texture: &gltf::Texture<'a>,
        who: &str,
        slot: &str,
    ) -> Result<TextureSampler> {
        let root = self.doc.as_json();
        let Some(index) = root
            .textures
            .get(texture.index())
            .and_then(|t| t.sampler.as_ref())
            .map(|i| i.value())
        else {
            return Ok(TextureSampler::default());
        };
        let Some(sampler) = root.samplers.get(index) else {
            return Err(self.error(format_args!(
                "{who}'s {slot} uses sampler {index}, but the file has {} samplers; fix the index",
                root.samplers.len()
            )));
        };
        let code = |what: &str, c: &Checked<u32>| -> Result<u32> {
            match c {
                Checked::Valid(v) => Ok(*v),
                Checked::Invalid => Err(self.error(format_args!(
                    "{who}'s {slot}: sampler {index} has an invalid {what}; glTF allows the codes of the specification (e.g. 10497 REPEAT, 9729 LINEAR)"
                ))),
            }
        };
        let gl = |c: &Checked<gltf::texture::WrappingMode>| match c {
            Checked::Valid(v) => Checked::Valid(v.as_gl_enum()),
            Checked::Invalid => Checked::Invalid,
        };
        let wrap_s = code("wrapS", &gl(&sampler.wrap_s))?;
        let wrap_t = code("wrapT", &gl(&sampler.wrap_t))?;
        let mag = match &sampler.mag_filter {
            None => None,
            Some(Checked::Valid(f)) => Some(f.as_gl_enum()),
            Some(Checked::Invalid) => Some(code("magFilter", &Checked::Invalid)?),
        };
        let min = match &sampler.min_filter {
            None => None,
            Some(Checked::Valid(f)) => Some(f.as_gl_enum()),
            Some(Checked::Invalid) => Some(code("minFilter", &Checked::Invalid)?),
        };
        TextureSampler::from_gltf_codes(wrap_s, wrap_t, mag, min)
            .map_err(|why| self.error(format_args!("{who}'s {slot}: sampler {index}: {why}")))
    }

    /// The scene texture for `texture`'s image in `color_space`, decoding the image on first use.
    pub(super) fn texture(
        &mut self,
        texture: &gltf::Texture<'a>,
        color_space: ColorSpace,
        who: &str,
        slot: &str,
    ) -> Result<usize> {
        let image = texture.source().index();
        let key = (image, color_space == ColorSpace::Srgb);
        if let Some(&index) = self.textures.get(&key) {
            return Ok(index);
        }
        let root = self.doc.as_json();
        let what = format!("{who} ({slot})");
        let decoded = resources::load_image(
            root,
            self.buffers,
            image,
            self.base_dir,
            &self.label,
            &what,
            &mut self.texture_bytes_left,
        )?;
        let space = match color_space {
            ColorSpace::Srgb => "sRGB",
            ColorSpace::Linear => "linear",
        };
        self.scene.textures.push(Texture {
            name: format!("{} ({space})", resources::image_label(root, image)),
            width: decoded.width,
            height: decoded.height,
            color_space,
            rgba8: decoded.rgba8,
            bc7: decoded.bc7,
        });
        let index = self.scene.textures.len() - 1;
        self.textures.insert(key, index);
        Ok(index)
    }
}
