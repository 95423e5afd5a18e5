//! glTF animation: the node hierarchy kept from the file, keyframe sampling (step, linear, cubic
//! spline), skins and morph targets, and posing a [`Scene`] at a time of one of its animations.
//!
//! The loader flattens nodes into [`super::Draw`]s with world matrices; the [`Rig`] keeps what a
//! pose needs to redo that: each node's rest transform and parent, which draws, lights and
//! cameras each node places, the skins' joints and inverse bind matrices, and the meshes' joint
//! influences and morph target deltas. [`Scene::pose`] resets every node to its rest transform,
//! applies the animation's channels at the time, and recomputes world matrices, joint matrices,
//! morph weights, lights and cameras; the renderer re-uploads only those
//! (`Renderer::update_pose`). Skinning itself runs on the GPU (glsl/skin.comp); [`deform`] is its
//! CPU twin, used for bounds and by the tests.

use std::collections::BTreeMap;

use glam::{Mat3, Mat4, Quat, Vec3};

use super::tangents::UvTransform;
use super::{Camera, Light, LightKind, Material, Scene, TextureSlot, Vertex};
use crate::{Error, Result};

/// The most joints a skin may have: JOINTS_n is unsigned byte or unsigned short in glTF, so no
/// vertex can name a joint beyond 65535.
pub const MAX_JOINTS: usize = 1 << 16;
/// The most morph targets a primitive may have. glTF sets no limit; 256 deltas per vertex is far
/// beyond any exporter's (Blender's shape keys; ARKit faces use 52) and bounds the GPU's loop.
pub const MAX_MORPH_TARGETS: usize = 256;

/// An animation as `weft plan` lists it.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimationInfo {
    pub name: String,
    /// The last keyframe time over all channels, in seconds (0 for an animation with no usable
    /// channel).
    pub duration: f32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    /// Hermite spline with in- and out-tangents per keyframe (glTF Appendix C).
    CubicSpline,
}

/// What a channel animates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    Translation,
    Rotation,
    Scale,
    /// Morph target weights (as many per keyframe as the node's mesh has targets).
    Weights,
    /// A material's property (KHR_animation_pointer); the channel's target is the material.
    Material(MaterialProperty),
    /// A KHR_lights_punctual light's property (KHR_animation_pointer); the target is the light
    /// (its index in the file's list of lights: every node that places it follows).
    Light(LightProperty),
    /// A camera's property (KHR_animation_pointer); the target is the file's camera.
    Camera(CameraProperty),
    /// A node's KHR_node_visibility `visible` (KHR_animation_pointer; above 0.5 is shown).
    Visible,
}

/// A material property that KHR_animation_pointer can drive, by its JSON pointer below
/// `/materials/{index}/`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialProperty {
    BaseColor,
    Metallic,
    Roughness,
    Emissive,
    EmissiveStrength,
    AlphaCutoff,
    NormalScale,
    OcclusionStrength,
    Ior,
    Transmission,
    Thickness,
    AttenuationDistance,
    AttenuationColor,
    Specular,
    SpecularColor,
    SheenColor,
    SheenRoughness,
    Clearcoat,
    ClearcoatRoughness,
    ClearcoatNormalScale,
    Iridescence,
    IridescenceIor,
    IridescenceThicknessMin,
    IridescenceThicknessMax,
    AnisotropyStrength,
    AnisotropyRotation,
    Dispersion,
    DiffuseTransmission,
    DiffuseTransmissionColor,
    /// A texture slot's KHR_texture_transform: offset, rotation, scale.
    TextureOffset(TextureSlot),
    TextureRotation(TextureSlot),
    TextureScale(TextureSlot),
}

/// Where each texture slot's textureInfo is, below `/materials/{index}/`.
const SLOT_PATHS: [(TextureSlot, &str); TextureSlot::COUNT] = [
    (
        TextureSlot::BaseColor,
        "pbrMetallicRoughness/baseColorTexture",
    ),
    (
        TextureSlot::MetallicRoughness,
        "pbrMetallicRoughness/metallicRoughnessTexture",
    ),
    (TextureSlot::Normal, "normalTexture"),
    (TextureSlot::Emissive, "emissiveTexture"),
    (TextureSlot::Occlusion, "occlusionTexture"),
    (
        TextureSlot::SheenColor,
        "extensions/KHR_materials_sheen/sheenColorTexture",
    ),
    (
        TextureSlot::SheenRoughness,
        "extensions/KHR_materials_sheen/sheenRoughnessTexture",
    ),
    (
        TextureSlot::Specular,
        "extensions/KHR_materials_specular/specularTexture",
    ),
    (
        TextureSlot::SpecularColor,
        "extensions/KHR_materials_specular/specularColorTexture",
    ),
    (
        TextureSlot::Anisotropy,
        "extensions/KHR_materials_anisotropy/anisotropyTexture",
    ),
    (
        TextureSlot::Transmission,
        "extensions/KHR_materials_transmission/transmissionTexture",
    ),
    (
        TextureSlot::Thickness,
        "extensions/KHR_materials_volume/thicknessTexture",
    ),
    (
        TextureSlot::Clearcoat,
        "extensions/KHR_materials_clearcoat/clearcoatTexture",
    ),
    (
        TextureSlot::ClearcoatRoughness,
        "extensions/KHR_materials_clearcoat/clearcoatRoughnessTexture",
    ),
    (
        TextureSlot::ClearcoatNormal,
        "extensions/KHR_materials_clearcoat/clearcoatNormalTexture",
    ),
    (
        TextureSlot::DiffuseTransmission,
        "extensions/KHR_materials_diffuse_transmission/diffuseTransmissionTexture",
    ),
    (
        TextureSlot::DiffuseTransmissionColor,
        "extensions/KHR_materials_diffuse_transmission/diffuseTransmissionColorTexture",
    ),
    (
        TextureSlot::Iridescence,
        "extensions/KHR_materials_iridescence/iridescenceTexture",
    ),
    (
        TextureSlot::IridescenceThickness,
        "extensions/KHR_materials_iridescence/iridescenceThicknessTexture",
    ),
];

/// What a pose changes on a material beyond its own fields: the emission's factor and strength
/// (the material keeps their product) and each texture slot's KHR_texture_transform (the
/// material keeps, per slot, the map from the coordinates the vertices carry, which already
/// hold the first TEXCOORD_0 slot's transform at rest, `frame_inverse` undoing it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialState {
    pub emissive: [f32; 3],
    pub strength: f32,
    pub(super) transforms: [UvTransform; TextureSlot::COUNT],
    pub frame_inverse: [[f32; 3]; 2],
    /// The slots whose transform a channel moved (bit per slot).
    pub moved: u32,
}

impl MaterialProperty {
    /// Every property with its JSON pointer below `/materials/{index}/` and its width.
    pub const ALL: [(MaterialProperty, &'static str, usize); 29] = {
        use MaterialProperty as P;
        [
            (P::BaseColor, "pbrMetallicRoughness/baseColorFactor", 4),
            (P::Metallic, "pbrMetallicRoughness/metallicFactor", 1),
            (P::Roughness, "pbrMetallicRoughness/roughnessFactor", 1),
            (P::Emissive, "emissiveFactor", 3),
            (
                P::EmissiveStrength,
                "extensions/KHR_materials_emissive_strength/emissiveStrength",
                1,
            ),
            (P::AlphaCutoff, "alphaCutoff", 1),
            (P::NormalScale, "normalTexture/scale", 1),
            (P::OcclusionStrength, "occlusionTexture/strength", 1),
            (P::Ior, "extensions/KHR_materials_ior/ior", 1),
            (
                P::Transmission,
                "extensions/KHR_materials_transmission/transmissionFactor",
                1,
            ),
            (
                P::Thickness,
                "extensions/KHR_materials_volume/thicknessFactor",
                1,
            ),
            (
                P::AttenuationDistance,
                "extensions/KHR_materials_volume/attenuationDistance",
                1,
            ),
            (
                P::AttenuationColor,
                "extensions/KHR_materials_volume/attenuationColor",
                3,
            ),
            (
                P::Specular,
                "extensions/KHR_materials_specular/specularFactor",
                1,
            ),
            (
                P::SpecularColor,
                "extensions/KHR_materials_specular/specularColorFactor",
                3,
            ),
            (
                P::SheenColor,
                "extensions/KHR_materials_sheen/sheenColorFactor",
                3,
            ),
            (
                P::SheenRoughness,
                "extensions/KHR_materials_sheen/sheenRoughnessFactor",
                1,
            ),
            (
                P::Clearcoat,
                "extensions/KHR_materials_clearcoat/clearcoatFactor",
                1,
            ),
            (
                P::ClearcoatRoughness,
                "extensions/KHR_materials_clearcoat/clearcoatRoughnessFactor",
                1,
            ),
            (
                P::ClearcoatNormalScale,
                "extensions/KHR_materials_clearcoat/clearcoatNormalTexture/scale",
                1,
            ),
            (
                P::Iridescence,
                "extensions/KHR_materials_iridescence/iridescenceFactor",
                1,
            ),
            (
                P::IridescenceIor,
                "extensions/KHR_materials_iridescence/iridescenceIor",
                1,
            ),
            (
                P::IridescenceThicknessMin,
                "extensions/KHR_materials_iridescence/iridescenceThicknessMinimum",
                1,
            ),
            (
                P::IridescenceThicknessMax,
                "extensions/KHR_materials_iridescence/iridescenceThicknessMaximum",
                1,
            ),
            (
                P::AnisotropyStrength,
                "extensions/KHR_materials_anisotropy/anisotropyStrength",
                1,
            ),
            (
                P::AnisotropyRotation,
                "extensions/KHR_materials_anisotropy/anisotropyRotation",
                1,
            ),
            (
                P::Dispersion,
                "extensions/KHR_materials_dispersion/dispersion",
                1,
            ),
            (
                P::DiffuseTransmission,
                "extensions/KHR_materials_diffuse_transmission/diffuseTransmissionFactor",
                1,
            ),
            (
                P::DiffuseTransmissionColor,
                "extensions/KHR_materials_diffuse_transmission/diffuseTransmissionColorFactor",
                3,
            ),
        ]
    };

    /// The property at `path` (the JSON pointer below `/materials/{index}/`), and its width.
    pub fn from_path(path: &str) -> Option<(MaterialProperty, usize)> {
        if let Some(&(m, _, w)) = MaterialProperty::ALL.iter().find(|(_, p, _)| *p == path) {
            return Some((m, w));
        }
        let (info, part) = path.split_once("/extensions/KHR_texture_transform/")?;
        let slot = SLOT_PATHS.iter().find(|(_, p)| *p == info)?.0;
        Some(match part {
            "offset" => (MaterialProperty::TextureOffset(slot), 2),
            "rotation" => (MaterialProperty::TextureRotation(slot), 1),
            "scale" => (MaterialProperty::TextureScale(slot), 2),
            _ => return None,
        })
    }

    /// Why `m` has nothing this property drives (the extension it belongs to is not on the
    /// material, or weft keeps it elsewhere), or None when it applies.
    pub fn missing_on(self, m: &Material) -> Option<&'static str> {
        use MaterialProperty as P;
        let has = match self {
            P::BaseColor
            | P::Metallic
            | P::Roughness
            | P::Emissive
            | P::EmissiveStrength
            | P::NormalScale
            | P::OcclusionStrength
            | P::Ior
            | P::Specular
            | P::SpecularColor => true,
            P::AlphaCutoff => m.alpha_cutoff.is_some(),
            P::Transmission
            | P::Thickness
            | P::AttenuationDistance
            | P::AttenuationColor
            | P::Dispersion => m.transmission.is_some(),
            P::SheenColor | P::SheenRoughness => m.sheen.is_some(),
            P::Clearcoat | P::ClearcoatRoughness | P::ClearcoatNormalScale => m.clearcoat.is_some(),
            P::Iridescence
            | P::IridescenceIor
            | P::IridescenceThicknessMin
            | P::IridescenceThicknessMax => m.iridescence.is_some(),
            P::AnisotropyStrength | P::AnisotropyRotation => m.anisotropy.is_some(),
            P::DiffuseTransmission | P::DiffuseTransmissionColor => {
                m.diffuse_transmission.is_some()
            }
            P::TextureOffset(slot) | P::TextureRotation(slot) | P::TextureScale(slot) => {
                if m.textures()[slot as usize].is_none() {
                    return Some("the texture it transforms is not on the material");
                }
                true
            }
        };
        if has {
            return None;
        }
        Some(match self {
            P::AlphaCutoff => "its alphaMode is not MASK",
            P::Transmission
            | P::Thickness
            | P::AttenuationDistance
            | P::AttenuationColor
            | P::Dispersion => "it has no KHR_materials_transmission",
            P::SheenColor | P::SheenRoughness => "it has no KHR_materials_sheen",
            P::Clearcoat | P::ClearcoatRoughness | P::ClearcoatNormalScale => {
                "it has no KHR_materials_clearcoat"
            }
            P::AnisotropyStrength | P::AnisotropyRotation => "it has no KHR_materials_anisotropy",
            P::DiffuseTransmission | P::DiffuseTransmissionColor => {
                "it has no KHR_materials_diffuse_transmission"
            }
            _ => "it has no KHR_materials_iridescence",
        })
    }

    /// Sets the property on `m` to `v` (its width of floats, finite), within the range the
    /// loader keeps the file's value in. The emissive factor and strength and the texture
    /// transforms go to `state` ([`Scene::pose`] makes the material's emission and slot maps
    /// from it once every channel has been applied).
    pub fn apply(self, m: &mut Material, v: &[f32], state: &mut MaterialState) {
        use MaterialProperty as P;
        let unit = |x: f32| x.clamp(0.0, 1.0);
        let colour = |v: &[f32]| [v[0].max(0.0), v[1].max(0.0), v[2].max(0.0)];
        match self {
            P::BaseColor => m.base_color = [v[0], v[1], v[2], v[3]],
            P::Metallic => m.metallic = unit(v[0]),
            P::Roughness => m.roughness = unit(v[0]),
            P::Emissive => state.emissive = colour(v),
            P::EmissiveStrength => state.strength = v[0].max(0.0),
            P::TextureOffset(slot) | P::TextureRotation(slot) | P::TextureScale(slot) => {
                let t = &mut state.transforms[slot as usize];
                match self {
                    P::TextureOffset(_) => t.offset = [v[0], v[1]],
                    P::TextureRotation(_) => t.rotation = v[0],
                    _ => t.scale = [v[0], v[1]],
                }
                state.moved |= 1 << slot as u32;
            }
            P::AlphaCutoff => m.alpha_cutoff = m.alpha_cutoff.map(|_| v[0]),
            P::NormalScale => m.normal_scale = v[0],
            P::OcclusionStrength => m.occlusion_strength = unit(v[0]),
            P::Ior => {
                m.specular.ior = if v[0] == 0.0 {
                    0.0
                } else {
                    v[0].clamp(1.0, 10.0)
                }
            }
            P::Specular => m.specular.factor = unit(v[0]),
            P::SpecularColor => m.specular.color = colour(v),
            P::Transmission => {
                if let Some(t) = &mut m.transmission {
                    t.factor = unit(v[0]);
                }
            }
            P::Thickness => {
                if let Some(t) = &mut m.transmission {
                    t.thickness = v[0].max(0.0);
                }
            }
            P::AttenuationDistance => {
                if let Some(t) = &mut m.transmission {
                    t.attenuation_distance = (v[0] > 0.0).then_some(v[0]);
                }
            }
            P::AttenuationColor => {
                if let Some(t) = &mut m.transmission {
                    t.attenuation_color = colour(v);
                }
            }
            P::Dispersion => {
                if let Some(t) = &mut m.transmission {
                    t.dispersion = v[0].max(0.0);
                }
            }
            P::SheenColor => {
                if let Some(s) = &mut m.sheen {
                    s.color = colour(v);
                }
            }
            P::SheenRoughness => {
                if let Some(s) = &mut m.sheen {
                    s.roughness = unit(v[0]);
                }
            }
            P::Clearcoat => {
                if let Some(c) = &mut m.clearcoat {
                    c.factor = unit(v[0]);
                }
            }
            P::ClearcoatRoughness => {
                if let Some(c) = &mut m.clearcoat {
                    c.roughness = unit(v[0]);
                }
            }
            P::ClearcoatNormalScale => {
                if let Some(c) = &mut m.clearcoat {
                    c.normal_scale = v[0];
                }
            }
            P::Iridescence => {
                if let Some(i) = &mut m.iridescence {
                    i.factor = unit(v[0]);
                }
            }
            P::IridescenceIor => {
                if let Some(i) = &mut m.iridescence {
                    i.ior = v[0].max(1.0);
                }
            }
            P::IridescenceThicknessMin => {
                if let Some(i) = &mut m.iridescence {
                    i.thickness_min = v[0].max(0.0);
                }
            }
            P::IridescenceThicknessMax => {
                if let Some(i) = &mut m.iridescence {
                    i.thickness_max = v[0].max(0.0);
                }
            }
            P::AnisotropyStrength => {
                if let Some(a) = &mut m.anisotropy {
                    a.strength = unit(v[0]);
                }
            }
            P::AnisotropyRotation => {
                if let Some(a) = &mut m.anisotropy {
                    a.rotation = v[0];
                }
            }
            P::DiffuseTransmission => {
                if let Some(d) = &mut m.diffuse_transmission {
                    d.factor = unit(v[0]);
                }
            }
            P::DiffuseTransmissionColor => {
                if let Some(d) = &mut m.diffuse_transmission {
                    d.color = colour(v);
                }
            }
        }
    }
}

/// A KHR_lights_punctual property that KHR_animation_pointer can drive, below
/// `/extensions/KHR_lights_punctual/lights/{index}/`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightProperty {
    Color,
    Intensity,
    Range,
    InnerCone,
    OuterCone,
}

impl LightProperty {
    /// The property at `path` (below the light), and its width.
    pub fn from_path(path: &str) -> Option<(LightProperty, usize)> {
        Some(match path {
            "color" => (LightProperty::Color, 3),
            "intensity" => (LightProperty::Intensity, 1),
            "range" => (LightProperty::Range, 1),
            "spot/innerConeAngle" => (LightProperty::InnerCone, 1),
            "spot/outerConeAngle" => (LightProperty::OuterCone, 1),
            _ => return None,
        })
    }

    /// Sets the property on `light` (cone angles only on a spot light; a range of 0 or less
    /// is infinite, the cones kept within 0 ≤ inner < outer ≤ π/2 as the loader keeps them).
    pub fn apply(self, light: &mut Light, v: &[f32]) {
        match self {
            LightProperty::Color => light.color = [v[0].max(0.0), v[1].max(0.0), v[2].max(0.0)],
            LightProperty::Intensity => light.intensity = v[0].max(0.0),
            LightProperty::Range => light.range = (v[0] > 0.0).then_some(v[0]),
            LightProperty::InnerCone | LightProperty::OuterCone => {
                if let LightKind::Spot {
                    inner_cone,
                    outer_cone,
                } = &mut light.kind
                {
                    let half = std::f32::consts::FRAC_PI_2;
                    if self == LightProperty::OuterCone {
                        *outer_cone = v[0].clamp(1e-4, half);
                    } else {
                        *inner_cone = v[0].max(0.0);
                    }
                    *inner_cone = inner_cone.min(*outer_cone * 0.9999);
                }
            }
        }
    }
}

/// A camera property that KHR_animation_pointer can drive, below `/cameras/{index}/`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraProperty {
    Yfov,
    AspectRatio,
    Znear,
    Zfar,
    Xmag,
    Ymag,
}

impl CameraProperty {
    /// The property at `path` (below the camera), and whether it is a perspective one.
    pub fn from_path(path: &str) -> Option<(CameraProperty, bool)> {
        Some(match path {
            "perspective/yfov" => (CameraProperty::Yfov, true),
            "perspective/aspectRatio" => (CameraProperty::AspectRatio, true),
            "perspective/znear" => (CameraProperty::Znear, true),
            "perspective/zfar" => (CameraProperty::Zfar, true),
            "orthographic/xmag" => (CameraProperty::Xmag, false),
            "orthographic/ymag" => (CameraProperty::Ymag, false),
            "orthographic/znear" => (CameraProperty::Znear, false),
            "orthographic/zfar" => (CameraProperty::Zfar, false),
            _ => return None,
        })
    }

    /// Sets the property on `camera`, kept valid: a field of view within (0, π), a near plane
    /// above 0 and a far plane beyond it, non-zero magnifications.
    pub fn apply(self, camera: &mut Camera, v: f32) {
        match self {
            CameraProperty::Yfov => camera.yfov = v.clamp(1e-4, std::f32::consts::PI - 1e-4),
            CameraProperty::AspectRatio => camera.aspect_ratio = (v > 0.0).then_some(v),
            CameraProperty::Znear => {
                camera.znear = v.max(1e-6);
                if let Some(f) = &mut camera.zfar {
                    *f = f.max(camera.znear * 1.0001);
                }
            }
            CameraProperty::Zfar => {
                camera.zfar = match camera.zfar {
                    Some(_) => Some(v.max(camera.znear * 1.0001)),
                    None => None,
                }
            }
            CameraProperty::Xmag | CameraProperty::Ymag => {
                if let Some(m) = &mut camera.orthographic {
                    let k = if self == CameraProperty::Xmag { 0 } else { 1 };
                    m[k] = if v.abs() > 1e-6 {
                        v
                    } else {
                        1e-6f32.copysign(v)
                    };
                }
            }
        }
    }
}

/// One sampler: keyframe times and values. `values` holds `width` floats per keyframe, three
/// times over for cubic splines (in-tangent, value, out-tangent per keyframe, as glTF stores them).
#[derive(Clone, Debug, PartialEq)]
pub struct Sampler {
    pub interpolation: Interpolation,
    /// Strictly increasing, finite, at least one.
    pub times: Vec<f32>,
    pub values: Vec<f32>,
    pub width: usize,
}

impl Sampler {
    /// Checks the keyframes (`what` names the sampler in messages).
    pub fn new(
        interpolation: Interpolation,
        times: Vec<f32>,
        values: Vec<f32>,
        width: usize,
        what: &str,
    ) -> std::result::Result<Sampler, String> {
        Sampler::counted(interpolation, times, values, width, width, what)
    }

    /// [`Sampler::new`], with messages counting the output accessor's elements of `element`
    /// floats each (`width` for a vector, 1 for morph weights, which glTF stores as scalars,
    /// `width` of them per keyframe).
    fn counted(
        interpolation: Interpolation,
        times: Vec<f32>,
        values: Vec<f32>,
        width: usize,
        element: usize,
        what: &str,
    ) -> std::result::Result<Sampler, String> {
        if times.is_empty() {
            return Err(format!("{what} has no keyframes"));
        }
        if let Some(k) = times.iter().position(|t| !t.is_finite() || *t < 0.0) {
            return Err(format!(
                "{what} has the keyframe time {} at keyframe {k}; times must be finite and not negative",
                times[k]
            ));
        }
        if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(format!(
                "{what} has keyframe times that do not increase ({} then {} at keyframes {k} and {}); glTF requires strictly increasing times",
                times[k],
                times[k + 1],
                k + 1
            ));
        }
        let per_key = if interpolation == Interpolation::CubicSpline {
            3 * width
        } else {
            width
        };
        if width == 0 || values.len() != times.len() * per_key {
            let element = element.max(1);
            return Err(format!(
                "{what} has {} keyframe times but {} output values; {:?} interpolation needs {} value(s) per keyframe ({} in all)",
                times.len(),
                values.len() / element,
                interpolation,
                per_key / element,
                times.len() * per_key / element
            ));
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(format!("{what} has a non-finite output value"));
        }
        Ok(Sampler {
            interpolation,
            times,
            values,
            width,
        })
    }

    /// The value at keyframe `k` (the middle third of a cubic spline's triple).
    fn value(&self, k: usize) -> &[f32] {
        let w = self.width;
        match self.interpolation {
            Interpolation::CubicSpline => &self.values[(3 * k + 1) * w..(3 * k + 2) * w],
            _ => &self.values[k * w..(k + 1) * w],
        }
    }

    /// Samples at `t` into `out` (`width` floats). Before the first keyframe the first value
    /// holds, after the last the last (glTF: the animation clamps). `rotation` makes the samples
    /// unit quaternions: linear interpolation is slerp along the shorter arc, cubic splines are
    /// normalised.
    pub fn sample(&self, t: f32, rotation: bool, out: &mut [f32]) {
        let w = self.width;
        let n = self.times.len();
        let last = n - 1;
        if n == 1 || t <= self.times[0] || t.is_nan() {
            out.copy_from_slice(self.value(0));
            return;
        }
        if t >= self.times[last] {
            out.copy_from_slice(self.value(last));
            return;
        }
        // The keyframe interval [times[k], times[k + 1]) holding t.
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let s = (t - t0) / dt;
        match self.interpolation {
            Interpolation::Step => out.copy_from_slice(self.value(k)),
            Interpolation::Linear => {
                let (a, b) = (self.value(k), self.value(k + 1));
                if rotation && w == 4 {
                    let q = slerp(quat(a), quat(b), s);
                    out.copy_from_slice(&q.to_array());
                } else {
                    for i in 0..w {
                        out[i] = a[i] + (b[i] - a[i]) * s;
                    }
                }
            }
            Interpolation::CubicSpline => {
                let v = &self.values;
                let (s2, s3) = (s * s, s * s * s);
                let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
                let h10 = s3 - 2.0 * s2 + s;
                let h01 = -2.0 * s3 + 3.0 * s2;
                let h11 = s3 - s2;
                for i in 0..w {
                    let p0 = v[(3 * k + 1) * w + i];
                    // The out-tangent of k and the in-tangent of k + 1, scaled by the interval.
                    let m0 = v[(3 * k + 2) * w + i] * dt;
                    let m1 = v[(3 * (k + 1)) * w + i] * dt;
                    let p1 = v[(3 * (k + 1) + 1) * w + i];
                    out[i] = h00 * p0 + h10 * m0 + h01 * p1 + h11 * m1;
                }
                if rotation && w == 4 {
                    let q = quat(out).normalize();
                    let q = if q.is_finite() {
                        q
                    } else {
                        quat(self.value(k)).normalize()
                    };
                    out.copy_from_slice(&q.to_array());
                }
            }
        }
    }

    /// The last keyframe time.
    pub fn end(&self) -> f32 {
        self.times.last().copied().unwrap_or(0.0)
    }
}

fn quat(v: &[f32]) -> Quat {
    Quat::from_xyzw(v[0], v[1], v[2], v[3])
}

/// Spherical linear interpolation from `a` to `b` along the shorter arc (b is negated when the
/// two are more than 90 degrees apart in quaternion space), normalised.
pub fn slerp(a: Quat, b: Quat, s: f32) -> Quat {
    let (a, mut b) = (a.normalize(), b.normalize());
    let mut d = a.dot(b);
    if d < 0.0 {
        b = -b;
        d = -d;
    }
    if d > 0.9995 {
        // Nearly parallel: linear, then normalised (sin θ is too small to divide by).
        return (a + (b - a) * s).normalize();
    }
    let theta = d.clamp(-1.0, 1.0).acos();
    let sin = theta.sin();
    let wa = ((1.0 - s) * theta).sin() / sin;
    let wb = (s * theta).sin() / sin;
    (a * wa + b * wb).normalize()
}

/// A channel: a sampler driving one property of one node (or, through KHR_animation_pointer,
/// of a material, light or camera).
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// Index into [`Rig::nodes`]; for [`Path::Material`] into `Scene::materials`, for
    /// [`Path::Light`] and [`Path::Camera`] the file's light or camera.
    pub node: usize,
    pub path: Path,
    pub sampler: Sampler,
}

impl Channel {
    /// A channel on `path` of `node` from a sampler's keyframes, checked as [`Sampler::new`]
    /// checks them and for what `path` needs: a rotation's keyframe values must be quaternions
    /// of non-zero length (glTF stores unit ones; a zero one is no rotation at all and would
    /// collapse the node or, interpolated, make its transform NaN). They are normalised, so
    /// STEP and LINEAR sampling see unit quaternions. The error says why the channel cannot be
    /// used (the loader drops it with a warning).
    pub fn new(
        node: usize,
        path: Path,
        interpolation: Interpolation,
        times: Vec<f32>,
        values: Vec<f32>,
        width: usize,
    ) -> std::result::Result<Channel, String> {
        let element = if path == Path::Weights { 1 } else { width };
        let mut sampler =
            Sampler::counted(interpolation, times, values, width, element, "its sampler")?;
        if path == Path::Rotation && width == 4 {
            for k in 0..sampler.times.len() {
                let q = quat(sampler.value(k));
                let length = q.length();
                if !(length > 1e-6 && length.is_finite()) {
                    return Err(format!(
                        "rotates by the quaternion {:?} at keyframe {k}, which has {} length; a rotation keyframe must be a unit quaternion",
                        q.to_array(),
                        if length.is_finite() { "zero" } else { "no finite" }
                    ));
                }
                if interpolation != Interpolation::CubicSpline {
                    let unit = q / length;
                    sampler.values[k * 4..k * 4 + 4].copy_from_slice(&unit.to_array());
                }
            }
        }
        Ok(Channel {
            node,
            path,
            sampler,
        })
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    pub name: String,
    pub channels: Vec<Channel>,
}

/// A node of the file, as a pose needs it.
#[derive(Clone, Debug)]
pub struct Node {
    pub parent: Option<usize>,
    /// A node given by `matrix` is not animatable (glTF forbids channels on it).
    pub matrix: Option<Mat4>,
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
    /// The node's morph weights at rest (the node's `weights`, else its mesh's).
    pub weights: Vec<f32>,
}

impl Node {
    fn local(&self, t: Vec3, r: Quat, s: Vec3) -> Mat4 {
        self.matrix
            .unwrap_or_else(|| Mat4::from_scale_rotation_translation(s, r, t))
    }
}

/// A skin: its joints (nodes) and their inverse bind matrices.
#[derive(Clone, Debug)]
pub struct Skin {
    pub name: String,
    pub joints: Vec<usize>,
    pub inverse_bind: Vec<Mat4>,
    /// World from bind-pose object space, per joint (world of the joint × inverse bind): a skinned
    /// vertex lands in world space, so a skinned draw's own world matrix is the identity (glTF
    /// ignores the transform of a skinned mesh's node).
    pub joint_matrices: Vec<Mat4>,
}

/// Per vertex: up to four joints (indices into the skin's joint list) and their weights.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VertexSkin {
    pub joints: [u32; 4],
    pub weights: [f32; 4],
}

/// One morph target's per-vertex deltas (empty where the target does not move that attribute).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MorphTarget {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub tangents: Vec<[f32; 3]>,
}

/// How a mesh deforms: joint influences (empty: not skinned) and morph targets.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshDeform {
    pub skin: Vec<VertexSkin>,
    pub targets: Vec<MorphTarget>,
}

impl MeshDeform {
    /// Replaces the vertices by copies of vertices `origin`, in that order (a mesh unwelded for
    /// flat normals, or split by tangent generation): each copy moves as its original.
    pub fn select(&mut self, origin: &[usize]) {
        let pick = |list: &mut Vec<[f32; 3]>| {
            if !list.is_empty() {
                *list = origin
                    .iter()
                    .map(|&o| list.get(o).copied().unwrap_or([0.0; 3]))
                    .collect();
            }
        };
        if !self.skin.is_empty() {
            self.skin = origin
                .iter()
                .map(|&o| self.skin.get(o).copied().unwrap_or_default())
                .collect();
        }
        for t in &mut self.targets {
            pick(&mut t.positions);
            pick(&mut t.normals);
            pick(&mut t.tangents);
        }
    }
}

/// A draw a node places: which node, the skin that deforms it, its current morph weights.
#[derive(Clone, Debug, PartialEq)]
pub struct DrawBinding {
    /// Index into `Scene::draws`.
    pub draw: usize,
    pub node: usize,
    pub skin: Option<usize>,
    /// The current morph weights (one per target of the draw's mesh).
    pub weights: Vec<f32>,
    /// The instance's transform under its node (EXT_mesh_gpu_instancing; identity otherwise):
    /// the draw's world is the node's world times this.
    pub instance: Mat4,
}

/// What posing needs beyond the flattened scene.
#[derive(Clone, Debug, Default)]
pub struct Rig {
    pub nodes: Vec<Node>,
    /// Node indices with every parent before its children (the nodes the scene reaches).
    pub order: Vec<usize>,
    pub skins: Vec<Skin>,
    pub animations: Vec<Animation>,
    pub infos: Vec<AnimationInfo>,
    pub draws: Vec<DrawBinding>,
    /// By mesh index (`Scene::meshes`): the meshes that deform.
    pub meshes: BTreeMap<usize, MeshDeform>,
    /// (index into `Scene::lights`, node) and (index into `Scene::cameras`, node).
    pub lights: Vec<(usize, usize)>,
    pub cameras: Vec<(usize, usize)>,
    /// Per entry of `lights`: the file's light it places (its index in KHR_lights_punctual's
    /// list) and its intensity at rest (a hidden node's light is dark); per entry of
    /// `cameras`: the file's camera.
    pub light_defs: Vec<usize>,
    pub light_intensity: Vec<f32>,
    pub camera_defs: Vec<usize>,
    /// What KHR_animation_pointer channels drive besides nodes, at rest (None: no such channel).
    pub pointed: Option<Pointed>,
    /// Each node's own KHR_node_visibility `visible` at rest (true without the extension; empty
    /// when no node has it): a node is shown when it and every ancestor are.
    pub visible: Vec<bool>,
}

/// The materials, lights and cameras that some KHR_animation_pointer channel drives, as the
/// file has them: a pose starts from these, so a property one animation drives is back at
/// rest in another.
#[derive(Clone, Debug, Default)]
pub struct Pointed {
    /// By index into `Scene::materials`: the material at rest, with its emissiveFactor,
    /// KHR_materials_emissive_strength and texture transforms at rest.
    pub materials: BTreeMap<usize, (Material, MaterialState)>,
    /// (material, its unlit copy for points and lines): the copy follows the material.
    pub copies: Vec<(usize, usize)>,
    /// By index into `Scene::lights` and `Scene::cameras`: at rest.
    pub lights: BTreeMap<usize, Light>,
    pub cameras: BTreeMap<usize, Camera>,
}

/// The brightest emission a pose gives a material (an animated factor times an animated
/// strength can overflow; the HDR target holds half floats).
const MAX_EMISSION: f32 = 65504.0;

impl Rig {
    /// World matrices of every node with each node's (translation, rotation, scale) given.
    fn world_matrices(&self, trs: &[(Vec3, Quat, Vec3)]) -> Vec<Mat4> {
        let mut world = vec![Mat4::IDENTITY; self.nodes.len()];
        for &i in &self.order {
            let n = &self.nodes[i];
            let (t, r, s) = trs[i];
            let local = n.local(t, r, s);
            world[i] = match n.parent {
                Some(p) => world[p] * local,
                None => local,
            };
        }
        world
    }

    /// The binding of draw `draw`, if a node places it.
    pub fn binding(&self, draw: usize) -> Option<&DrawBinding> {
        self.draws.iter().find(|b| b.draw == draw)
    }

    /// Whether draw `draw` is deformed (skinned or morphed) on the GPU.
    pub fn deforms(&self, scene_mesh: usize, binding: &DrawBinding) -> bool {
        binding.skin.is_some()
            || self
                .meshes
                .get(&scene_mesh)
                .is_some_and(|m| !m.targets.is_empty())
    }
}

/// A camera's view from the world matrix of the node that holds it: the inverse of the node's
/// rigid motion (scale, even mirroring, removed; -Z the view direction, +Y up). None when the
/// node scales it to nothing.
pub(super) fn camera_view(world: Mat4) -> Option<Mat4> {
    let z = world.z_axis.truncate().try_normalize()?;
    let y = world.y_axis.truncate();
    let y = (y - z * z.dot(y)).try_normalize()?;
    let x = y.cross(z);
    let rigid = Mat4::from_cols(x.extend(0.0), y.extend(0.0), z.extend(0.0), world.w_axis);
    Some(rigid.inverse())
}

/// The position and direction (-Z, unit) of a light placed by a node with this world matrix.
pub(super) fn light_frame(world: Mat4) -> Option<(Vec3, Vec3)> {
    let d = (world * glam::Vec4::new(0.0, 0.0, -1.0, 0.0))
        .truncate()
        .try_normalize()?;
    Some((world.w_axis.truncate(), d))
}

impl Scene {
    /// The file's animations, with their durations.
    pub fn animations(&self) -> &[AnimationInfo] {
        &self.rig.infos
    }

    /// How many distinct nodes, materials, lights and cameras animation `index` drives (its
    /// usable channels; materials, lights and cameras through KHR_animation_pointer).
    pub fn animation_drives(&self, index: usize) -> [usize; 4] {
        let mut seen = std::collections::BTreeSet::new();
        for c in self
            .rig
            .animations
            .get(index)
            .map_or(&[][..], |a| &a.channels)
        {
            let kind = match c.path {
                Path::Material(_) => 1,
                Path::Light(_) => 2,
                Path::Camera(_) => 3,
                _ => 0,
            };
            seen.insert((kind, c.node));
        }
        let mut counts = [0; 4];
        for (kind, _) in seen {
            counts[kind] += 1;
        }
        counts
    }

    /// The index of an animation given by name or by index (`--animation NAME|INDEX`).
    pub fn find_animation(&self, name_or_index: &str) -> Result<usize> {
        let list = || {
            if self.rig.infos.is_empty() {
                "it has no animations".to_string()
            } else {
                format!(
                    "its animations are: {}",
                    self.rig
                        .infos
                        .iter()
                        .enumerate()
                        .map(|(i, a)| format!("{i} '{}'", a.name))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            }
        };
        if let Some(i) = self.rig.infos.iter().position(|a| a.name == name_or_index) {
            return Ok(i);
        }
        match name_or_index.parse::<usize>() {
            Ok(i) if i < self.rig.infos.len() => Ok(i),
            _ => Err(Error::input(format!(
                "{} has no animation '{name_or_index}'; {} (`weft plan` lists them): pass a name or an index",
                self.source,
                list()
            ))),
        }
    }

    /// Pose the scene at `time` seconds of animation `index` (times outside [0, duration] clamp
    /// per glTF sampling rules): updates draws' world matrices, cameras, lights, joint matrices,
    /// morph weights. Every node not animated by `index` is at its rest transform, whatever the
    /// previous pose was.
    pub fn pose(&mut self, index: usize, time: f32) -> Result<()> {
        if index >= self.rig.animations.len() {
            return Err(Error::input(format!(
                "animation {index} does not exist in {}: it has {} animation(s) (`weft plan` lists them)",
                self.source,
                self.rig.animations.len()
            )));
        }
        if !time.is_finite() {
            return Err(Error::input(format!(
                "animation time {time} is not a finite number of seconds; pass e.g. --time 0.5"
            )));
        }
        let mut states = self.reset_pointed();
        let rig = &self.rig;
        let animation = &rig.animations[index];
        let mut trs: Vec<(Vec3, Quat, Vec3)> = rig
            .nodes
            .iter()
            .map(|n| (n.translation, n.rotation, n.scale))
            .collect();
        let mut weights: Vec<Vec<f32>> = rig.nodes.iter().map(|n| n.weights.clone()).collect();
        let mut visible = rig.visible.clone();
        let mut buf = Vec::new();
        for c in &animation.channels {
            buf.resize(c.sampler.width, 0.0);
            c.sampler.sample(time, c.path == Path::Rotation, &mut buf);
            match c.path {
                Path::Translation => trs[c.node].0 = Vec3::from_slice(&buf),
                Path::Rotation => trs[c.node].1 = quat(&buf),
                Path::Scale => trs[c.node].2 = Vec3::from_slice(&buf),
                Path::Weights => {
                    let w = &mut weights[c.node];
                    let n = w.len().min(buf.len());
                    w[..n].copy_from_slice(&buf[..n]);
                }
                Path::Visible => {
                    if visible.is_empty() {
                        visible = vec![true; rig.nodes.len()];
                    }
                    if let Some(v) = visible.get_mut(c.node) {
                        *v = buf[0] > 0.5;
                    }
                }
                Path::Material(p) => {
                    if let (Some(m), Some(e)) =
                        (self.materials.get_mut(c.node), states.get_mut(&c.node))
                    {
                        p.apply(m, &buf, e);
                    }
                }
                Path::Light(p) => {
                    for (k, &(l, _)) in rig.lights.iter().enumerate() {
                        if rig.light_defs.get(k) == Some(&c.node) {
                            if let Some(light) = self.lights.get_mut(l) {
                                p.apply(light, &buf);
                            }
                        }
                    }
                }
                Path::Camera(p) => {
                    for (k, &(i, _)) in rig.cameras.iter().enumerate() {
                        if rig.camera_defs.get(k) == Some(&c.node) {
                            if let Some(camera) = self.cameras.get_mut(i) {
                                p.apply(camera, buf[0]);
                            }
                        }
                    }
                }
            }
        }
        self.finish_pointed(&states);
        self.apply_pose(&trs, &weights, &visible)
    }

    /// Puts what KHR_animation_pointer channels drive back at rest, and returns the driven
    /// materials' states at rest (by material) for the channels to change.
    fn reset_pointed(&mut self) -> BTreeMap<usize, MaterialState> {
        let Some(p) = &self.rig.pointed else {
            return BTreeMap::new();
        };
        for (&i, (m, _)) in &p.materials {
            if let Some(slot) = self.materials.get_mut(i) {
                *slot = m.clone();
            }
        }
        for (&i, l) in &p.lights {
            if let Some(slot) = self.lights.get_mut(i) {
                *slot = l.clone();
            }
        }
        for (&i, c) in &p.cameras {
            if let Some(slot) = self.cameras.get_mut(i) {
                *slot = c.clone();
            }
        }
        p.materials.iter().map(|(&i, (_, st))| (i, *st)).collect()
    }

    /// The driven materials' emission from their (posed) factor and strength, their moved
    /// slots' maps, and their unlit copies made again from them.
    fn finish_pointed(&mut self, states: &BTreeMap<usize, MaterialState>) {
        for (&i, st) in states {
            let Some(m) = self.materials.get_mut(i) else {
                continue;
            };
            m.emissive = st.emissive.map(|f| (f * st.strength).min(MAX_EMISSION));
            for slot in 0..TextureSlot::COUNT {
                if st.moved & (1 << slot) == 0 {
                    continue;
                }
                let t = st.transforms[slot].affine();
                let uv = &mut m.uv[slot];
                uv.m = if uv.set == 0 {
                    UvTransform::compose(t, st.frame_inverse)
                } else {
                    t
                };
            }
        }
        let Some(p) = &self.rig.pointed else {
            return;
        };
        for &(original, copy) in &p.copies {
            if !p.materials.contains_key(&original) || copy >= self.materials.len() {
                continue;
            }
            let Some(source) = self.materials.get(original).cloned() else {
                continue;
            };
            let name = std::mem::take(&mut self.materials[copy].name);
            self.materials[copy] = Material {
                name,
                unlit: true,
                fabric: None,
                ..source
            };
        }
    }

    /// Puts every node back at rest (the pose of the file without animation).
    pub fn rest_pose(&mut self) -> Result<()> {
        let states = self.reset_pointed();
        self.finish_pointed(&states);
        let trs: Vec<_> = self
            .rig
            .nodes
            .iter()
            .map(|n| (n.translation, n.rotation, n.scale))
            .collect();
        let weights: Vec<_> = self.rig.nodes.iter().map(|n| n.weights.clone()).collect();
        let visible = self.rig.visible.clone();
        self.apply_pose(&trs, &weights, &visible)
    }

    fn apply_pose(
        &mut self,
        trs: &[(Vec3, Quat, Vec3)],
        weights: &[Vec<f32>],
        visible: &[bool],
    ) -> Result<()> {
        let world = self.rig.world_matrices(trs);
        // KHR_node_visibility: shown where the node and every ancestor are (parents come first
        // in `order`).
        let mut shown = vec![true; self.rig.nodes.len()];
        if !visible.is_empty() {
            for &i in &self.rig.order {
                let own = visible.get(i).copied().unwrap_or(true);
                let parent = self.rig.nodes[i].parent.and_then(|p| shown.get(p).copied());
                shown[i] = own && parent.unwrap_or(true);
            }
        }
        if let Some(i) = world.iter().position(|m| !m.is_finite()) {
            return Err(Error::input(format!(
                "{}: node {i} has a world transform that is not finite in this pose (its or its parents' translation, rotation or scale, as the file or the animation sets them, overflow 32-bit floating point); check the node and the animation's output values",
                self.source
            )));
        }
        // Finite factors can still overflow: each product the GPU will use is checked where it
        // is made, so a mesh never vanishes silently.
        for skin in &mut self.rig.skins {
            for (k, &j) in skin.joints.iter().enumerate() {
                let m = world[j] * skin.inverse_bind[k];
                if !m.is_finite() {
                    return Err(Error::input(format!(
                        "{}: skin '{}': the matrix of joint {k} (node {j}'s world transform times its inverse bind matrix) overflows 32-bit floating point in this pose; check the skin's inverse bind matrices and the joint's scale",
                        self.source, skin.name
                    )));
                }
                skin.joint_matrices[k] = m;
            }
        }
        let mut bindings = std::mem::take(&mut self.rig.draws);
        for b in &mut bindings {
            if let Some(d) = self.draws.get_mut(b.draw) {
                d.visible = shown.get(b.node).copied().unwrap_or(true);
                d.world = if b.skin.is_some() {
                    Mat4::IDENTITY
                } else {
                    world[b.node] * b.instance
                };
            }
            let w = &weights[b.node];
            for (k, x) in b.weights.iter_mut().enumerate() {
                *x = w.get(k).copied().unwrap_or(0.0);
            }
        }
        self.rig.draws = bindings;
        self.check_deformed()?;
        for (k, &(l, n)) in self.rig.lights.iter().enumerate() {
            let pointed = self
                .rig
                .pointed
                .as_ref()
                .is_some_and(|p| p.lights.contains_key(&l));
            let Some(light) = self.lights.get_mut(l) else {
                continue;
            };
            // A pointed light's intensity is this pose's already; the others' is the file's
            // (a pose that hid it left 0).
            if !pointed {
                if let Some(&i) = self.rig.light_intensity.get(k) {
                    light.intensity = i;
                }
            }
            if !shown.get(n).copied().unwrap_or(true) {
                light.intensity = 0.0;
            }
            if let Some((p, d)) = light_frame(world[n]) {
                light.position = p;
                light.direction = d;
            }
        }
        for &(c, n) in &self.rig.cameras {
            if let (Some(camera), Some(view)) = (self.cameras.get_mut(c), camera_view(world[n])) {
                camera.view = view;
            }
        }
        Ok(())
    }

    /// Refuses a pose in which a deforming draw's morph targets (weights times deltas) or skin
    /// (joint matrices times positions) take a vertex out of 32-bit floating point: the GPU
    /// would draw NaN, and the mesh would vanish without a word.
    fn check_deformed(&self) -> Result<()> {
        let empty = MeshDeform::default();
        for b in &self.rig.draws {
            let Some(d) = self.draws.get(b.draw) else {
                continue;
            };
            let Some(mesh) = self.meshes.get(d.mesh) else {
                continue;
            };
            if !self.rig.deforms(d.mesh, b) {
                continue;
            }
            let deform = self.rig.meshes.get(&d.mesh).unwrap_or(&empty);
            let skin = b.skin.and_then(|s| self.rig.skins.get(s));
            let joints = skin.map(|s| &s.joint_matrices[..]);
            let morphed = b.weights.iter().any(|w| *w != 0.0);
            if !morphed && joints.is_none() {
                continue;
            }
            for (i, v) in mesh.vertices.iter().enumerate() {
                let (p, n, t) = deform_raw(v, i, deform, &b.weights, None);
                let by = if !(p.is_finite() && n.is_finite() && t.is_finite()) && morphed {
                    format!(
                        "its morph targets (weights {:?} times the targets' deltas)",
                        b.weights
                    )
                } else if joints.is_some() && {
                    let (p, n, t) = deform_raw(v, i, deform, &b.weights, joints);
                    !(p.is_finite() && n.is_finite() && t.is_finite())
                } {
                    format!(
                        "its skin '{}' (the joint matrices times the vertex)",
                        skin.map_or("", |s| s.name.as_str())
                    )
                } else {
                    continue;
                };
                return Err(Error::input(format!(
                    "{}: mesh '{}' (node {}): {by} move vertex {i} out of the range of 32-bit floating point in this pose, so the mesh cannot be drawn; check the morph weights and target deltas, or the skin's inverse bind matrices and joint scales",
                    self.source, mesh.name, b.node
                )));
            }
        }
        Ok(())
    }

    /// The vertices of draw `draw` as the GPU deforms them (morph targets, then skinning; the
    /// CPU twin of glsl/skin.comp), in the space the draw's world matrix maps from (world space for
    /// skinned draws, whose world is the identity). None for a draw that does not deform.
    pub fn deformed_vertices(&self, draw: usize) -> Option<Vec<Vertex>> {
        let b = self.rig.binding(draw)?;
        let d = self.draws.get(draw)?;
        let mesh = self.meshes.get(d.mesh)?;
        if !self.rig.deforms(d.mesh, b) {
            return None;
        }
        let empty = MeshDeform::default();
        let deform = self.rig.meshes.get(&d.mesh).unwrap_or(&empty);
        let joints = b
            .skin
            .and_then(|s| self.rig.skins.get(s))
            .map(|s| &s.joint_matrices[..]);
        Some(
            mesh.vertices
                .iter()
                .enumerate()
                .map(|(i, v)| deform_vertex(v, i, deform, &b.weights, joints))
                .collect(),
        )
    }
}

/// One vertex through the morph targets (weighted deltas) and the skin (the weighted sum of its
/// joints' matrices): position transformed, normal by the cofactor matrix (the inverse transpose
/// up to scale), tangent by the matrix and made orthogonal to the normal again, its handedness
/// flipped where the skin mirrors. Mirrored exactly by glsl/skin.comp.
pub fn deform_vertex(
    v: &Vertex,
    index: usize,
    deform: &MeshDeform,
    weights: &[f32],
    joints: Option<&[Mat4]>,
) -> Vertex {
    let (p, n, t) = deform_raw(v, index, deform, weights, joints);
    let w = v.tangent[3] * skin_sign(index, deform, joints);
    let n = n.try_normalize().unwrap_or(Vec3::Z);
    let t = (t - n * n.dot(t))
        .try_normalize()
        .unwrap_or_else(|| n.any_orthonormal_vector());
    Vertex {
        position: p.to_array(),
        normal: n.to_array(),
        tangent: [t.x, t.y, t.z, w],
        ..*v
    }
}

/// The skin matrix of vertex `index` (the weighted sum of its joints' matrices), None when not
/// skinned.
fn skin_matrix(index: usize, deform: &MeshDeform, joints: Option<&[Mat4]>) -> Option<Mat4> {
    let (joints, s) = (joints?, deform.skin.get(index)?);
    let mut m = Mat4::ZERO;
    for k in 0..4 {
        if let Some(j) = joints.get(s.joints[k] as usize) {
            m += *j * s.weights[k];
        }
    }
    Some(m)
}

/// -1 where the skin mirrors vertex `index`, else 1.
fn skin_sign(index: usize, deform: &MeshDeform, joints: Option<&[Mat4]>) -> f32 {
    match skin_matrix(index, deform, joints) {
        Some(m) if Mat3::from_mat4(m).determinant() < 0.0 => -1.0,
        _ => 1.0,
    }
}

/// [`deform_vertex`] before normalising: position, normal and tangent (xyz) as morphed and
/// skinned, where overflow shows as non-finite values.
fn deform_raw(
    v: &Vertex,
    index: usize,
    deform: &MeshDeform,
    weights: &[f32],
    joints: Option<&[Mat4]>,
) -> (Vec3, Vec3, Vec3) {
    let mut p = Vec3::from(v.position);
    let mut n = Vec3::from(v.normal);
    let mut t = Vec3::new(v.tangent[0], v.tangent[1], v.tangent[2]);
    for (target, &k) in deform.targets.iter().zip(weights) {
        if let Some(d) = target.positions.get(index) {
            p += Vec3::from(*d) * k;
        }
        if let Some(d) = target.normals.get(index) {
            n += Vec3::from(*d) * k;
        }
        if let Some(d) = target.tangents.get(index) {
            t += Vec3::from(*d) * k;
        }
    }
    if let Some(m) = skin_matrix(index, deform, joints) {
        p = m.transform_point3(p);
        let m3 = Mat3::from_mat4(m);
        let det = m3.determinant();
        let cof = cofactor(m3);
        let sign = if det < 0.0 { -1.0 } else { 1.0 };
        n = cof * n * sign;
        t = m3 * t;
    }
    (p, n, t)
}

/// The cofactor matrix of `m` (det(m) · m⁻ᵀ, defined for singular m too): what normals transform
/// by, before normalising.
pub fn cofactor(m: Mat3) -> Mat3 {
    let (a, b, c) = (m.x_axis, m.y_axis, m.z_axis);
    Mat3::from_cols(b.cross(c), c.cross(a), a.cross(b))
}

/// A camera placed by node `node` in pose `world` (used by the loader too).
pub(super) fn placed_camera(
    name: String,
    world: Mat4,
    yfov: f32,
    znear: f32,
    zfar: Option<f32>,
    aspect_ratio: Option<f32>,
) -> Option<Camera> {
    Some(Camera {
        name,
        view: camera_view(world)?,
        yfov,
        znear,
        zfar,
        aspect_ratio,
        orthographic: None,
        framing: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sampler(i: Interpolation, times: &[f32], values: &[f32], width: usize) -> Sampler {
        Sampler::new(i, times.to_vec(), values.to_vec(), width, "test").unwrap()
    }

    fn at(s: &Sampler, t: f32, rotation: bool) -> Vec<f32> {
        let mut out = vec![0.0; s.width];
        s.sample(t, rotation, &mut out);
        out
    }

    #[test]
    fn step_holds_the_previous_keyframe() {
        let s = sampler(
            Interpolation::Step,
            &[1.0, 2.0, 4.0],
            &[10.0, 20.0, 40.0],
            1,
        );
        assert_eq!(at(&s, 0.0, false), [10.0]); // before the first: clamped
        assert_eq!(at(&s, 1.0, false), [10.0]);
        assert_eq!(at(&s, 1.99, false), [10.0]);
        assert_eq!(at(&s, 2.0, false), [20.0]);
        assert_eq!(at(&s, 3.9, false), [20.0]);
        assert_eq!(at(&s, 9.0, false), [40.0]); // after the last: clamped
    }

    #[test]
    fn linear_interpolates_and_clamps() {
        let s = sampler(
            Interpolation::Linear,
            &[0.0, 2.0],
            &[0.0, 1.0, 2.0, 4.0, 5.0, 6.0],
            3,
        );
        // At t = 0.5: a quarter of the way, by hand: 0 + 4/4, 1 + 4/4, 2 + 4/4.
        assert_eq!(at(&s, 0.5, false), [1.0, 2.0, 3.0]);
        assert_eq!(at(&s, -1.0, false), [0.0, 1.0, 2.0]);
        assert_eq!(at(&s, 5.0, false), [4.0, 5.0, 6.0]);
    }

    #[test]
    fn cubic_spline_scales_tangents_by_the_keyframe_interval() {
        // One scalar, keyframes at t = 1 and t = 3 (interval 2): values 0 and 1, out-tangent of
        // the first 1.5, in-tangent of the second -0.5 (the others unused).
        // Layout per keyframe: in, value, out.
        let s = sampler(
            Interpolation::CubicSpline,
            &[1.0, 3.0],
            &[9.0, 0.0, 1.5, -0.5, 1.0, 9.0],
            1,
        );
        // At t = 2: s = 0.5, h00 = 0.5, h10 = 0.125, h01 = 0.5, h11 = -0.125;
        // p = 0.5·0 + 0.125·(1.5·2) + 0.5·1 - 0.125·(-0.5·2) = 0.375 + 0.5 + 0.125 = 1.0.
        let v = at(&s, 2.0, false)[0];
        assert!((v - 1.0).abs() < 1e-6, "{v}");
        // At t = 1.5: s = 0.25: h00 = 0.84375, h10 = 0.140625, h01 = 0.15625, h11 = -0.046875;
        // p = 0.140625·3 + 0.15625 + 0.046875·1 = 0.421875 + 0.15625 + 0.046875 = 0.625.
        let v = at(&s, 1.5, false)[0];
        assert!((v - 0.625).abs() < 1e-6, "{v}");
        // Without the interval scaling it would be 0.140625·1.5 + 0.15625 + 0.0234375 = 0.390625:
        // the case above tells the two apart. Clamped outside: the values, not the tangents.
        assert_eq!(at(&s, 0.0, false), [0.0]);
        assert_eq!(at(&s, 7.0, false), [1.0]);
    }

    #[test]
    fn slerp_takes_the_shorter_arc() {
        // 0 and 270 degrees about z; 270 degrees is -90 the short way, and the quaternion for it
        // is given with w < 0 (the long representation): halfway must be -45 degrees.
        let a = Quat::IDENTITY;
        let b = Quat::from_rotation_z(270f32.to_radians());
        assert!(a.dot(b) < 0.0);
        let s = sampler(
            Interpolation::Linear,
            &[0.0, 1.0],
            &[a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w],
            4,
        );
        let q = quat(&at(&s, 0.5, true));
        let expect = Quat::from_rotation_z(-45f32.to_radians());
        assert!(q.dot(expect).abs() > 1.0 - 1e-6, "{q:?} vs {expect:?}");
        // And a quarter of the way along 0..90 degrees is 22.5 degrees (constant angular speed,
        // which a normalised lerp does not have: it would give 20.7).
        let b = Quat::from_rotation_z(90f32.to_radians());
        let q = slerp(a, b, 0.25);
        let angle = 2.0 * q.z.atan2(q.w);
        assert!(
            (angle.to_degrees() - 22.5).abs() < 1e-4,
            "{}",
            angle.to_degrees()
        );
    }

    #[test]
    fn cubic_rotation_is_normalised() {
        let a = Quat::IDENTITY;
        let b = Quat::from_rotation_x(1.0);
        let z = [0.0f32; 4];
        let mut v = Vec::new();
        v.extend_from_slice(&z);
        v.extend_from_slice(&a.to_array());
        v.extend_from_slice(&z);
        v.extend_from_slice(&z);
        v.extend_from_slice(&b.to_array());
        v.extend_from_slice(&z);
        let s = sampler(Interpolation::CubicSpline, &[0.0, 1.0], &v, 4);
        let q = quat(&at(&s, 0.3, true));
        assert!((q.length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn bad_keyframes_are_refused_with_a_reason() {
        let e = Sampler::new(
            Interpolation::Linear,
            vec![0.0, 1.0, 1.0],
            vec![0.0; 3],
            1,
            "s",
        )
        .unwrap_err();
        assert!(e.contains("do not increase"), "{e}");
        let e =
            Sampler::new(Interpolation::Linear, vec![0.0, 1.0], vec![0.0; 3], 1, "s").unwrap_err();
        assert!(e.contains("2 keyframe times but 3 output values"), "{e}");
        let e = Sampler::new(
            Interpolation::CubicSpline,
            vec![0.0, 1.0],
            vec![0.0; 2],
            1,
            "s",
        )
        .unwrap_err();
        assert!(e.contains("3 value(s) per keyframe"), "{e}");
        let e = Sampler::new(Interpolation::Step, vec![f32::NAN], vec![0.0], 1, "s").unwrap_err();
        assert!(e.contains("finite"), "{e}");
        assert!(Sampler::new(Interpolation::Step, vec![], vec![], 1, "s").is_err());
    }

    #[test]
    fn skinned_tangent_follows_the_joint_and_keeps_handedness() {
        // A vertex fully bound to a joint turned 90 degrees about z and mirrored in x.
        let v = Vertex {
            position: [1.0, 0.0, 0.0],
            normal: [0.0, 0.0, 1.0],
            tangent: [1.0, 0.0, 0.0, 1.0],
            ..Default::default()
        };
        let deform = MeshDeform {
            skin: vec![VertexSkin {
                joints: [0, 0, 0, 0],
                weights: [1.0, 0.0, 0.0, 0.0],
            }],
            targets: Vec::new(),
        };
        let turn = Mat4::from_rotation_z(90f32.to_radians());
        let out = deform_vertex(&v, 0, &deform, &[], Some(&[turn]));
        let close = |a: [f32; 3], b: [f32; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-6);
        assert!(close(out.position, [0.0, 1.0, 0.0]));
        assert!(close(
            [out.tangent[0], out.tangent[1], out.tangent[2]],
            [0.0, 1.0, 0.0]
        ));
        assert_eq!(out.tangent[3], 1.0);
        let mirror = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let out = deform_vertex(&v, 0, &deform, &[], Some(&[mirror]));
        assert!(close(out.normal, [0.0, 0.0, 1.0]));
        assert!(close(
            [out.tangent[0], out.tangent[1], out.tangent[2]],
            [-1.0, 0.0, 0.0]
        ));
        assert_eq!(out.tangent[3], -1.0);
    }
}
