//! Scenes: what the renderer draws, as plain data with no GPU handles.
//!
//! `load` turns a glTF 2.0 file (`.gltf` or `.glb`) into a [`Scene`]: the node hierarchy is
//! flattened into [`Draw`]s with world matrices, tangents are generated (MikkTSpace) where the file
//! has none, lights come from `KHR_lights_punctual`, and the fabric extension
//! (`WEFT_materials_fabric`) is parsed into [`crate::fabric::FabricParams`]. Shadow settings come
//! from `extras`: a light's `shadows`, a node's `cast_shadows` / `receive_shadows` (the convention
//! is in `docs/scene-format.md`).
//! Animation (node TRS channels, skins, morph targets) is kept in [`Scene::rig`] and applied by
//! [`Scene::pose`] ([`animation`]).
//! [`default_scene`] is the built-in scene embedded in the binary.

use glam::{Mat3, Mat4, Vec2, Vec3};

mod accessor;
pub mod animation;
mod compressed;
mod gltf_load;
mod ktx;
mod material_ext;
mod resources;
mod tangents;
pub use animation::AnimationInfo;
pub use gltf_load::{
    default_scene, load, load_slice, load_slice_with, load_with, LoadOptions, DEFAULT_SCENE_GLB,
};

/// One vertex as the G-buffer pass reads it (std430-compatible, 56 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    /// xyz: tangent along +u; w: handedness sign (+1 or -1), bitangent = w * cross(n, t).
    pub tangent: [f32; 4],
    /// TEXCOORD_0, with the material's frame transform baked in ([`Material::uv`]).
    pub uv: [f32; 2],
    /// TEXCOORD_1 as the file has it ((0, 0) when it has none).
    pub uv1: [f32; 2],
}

/// A triangle list with one material, in object space.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub name: String,
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
    pub material: usize,
    /// COLOR_0, linear RGBA per vertex (alpha 1 where the file has RGB), multiplied into the base
    /// colour (for fabric, into the thread colours) and its alpha; empty when the mesh has none.
    pub colors: Vec<[f32; 4]>,
    /// How `indices` are assembled: triangles (TRIANGLES, and strips and fans turned into
    /// them), line segments (LINES, and loops and strips turned into them: pairs of indices) or
    /// points (POINTS). Lines and points are drawn 1 pixel wide, cast no shadow, and are unlit
    /// when the file gives them no normals (the loader gives them an unlit copy of their material,
    /// as glTF asks).
    pub topology: Topology,
}

/// The primitive assembly of a [`Mesh`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Topology {
    #[default]
    Triangles,
    Lines,
    Points,
}

impl Topology {
    /// Indices per primitive.
    pub fn arity(self) -> usize {
        match self {
            Topology::Triangles => 3,
            Topology::Lines => 2,
            Topology::Points => 1,
        }
    }
}

/// An instance of a mesh in the world.
#[derive(Clone, Debug)]
pub struct Draw {
    pub mesh: usize,
    pub world: Mat4,
    /// Whether this instance occludes shadow-casting lights (node `extras.cast_shadows`,
    /// default true).
    pub cast_shadows: bool,
    /// Whether shadows darken this instance (node `extras.receive_shadows`, default true).
    pub receive_shadows: bool,
    /// Whether the draw is shown: KHR_node_visibility hides a node's subtree (its meshes and
    /// lights), and a pose may show it again. A hidden draw is in no pass and no bounds.
    pub visible: bool,
}

impl Draw {
    /// An instance that casts and receives shadows (the glTF default).
    pub fn new(mesh: usize, world: Mat4) -> Draw {
        Draw {
            mesh,
            world,
            cast_shadows: true,
            receive_shadows: true,
            visible: true,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorSpace {
    Srgb,
    Linear,
}

/// An RGBA8 texture, already decoded.
#[derive(Clone, Debug)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub color_space: ColorSpace,
    /// width * height * 4 bytes, rows top to bottom.
    pub rgba8: Vec<u8>,
    /// The same image's full mip chain as BC7 blocks (level 0 first; each level
    /// ceil(w/4) * ceil(h/4) * 16 bytes, block rows top to bottom), when it came from a KTX2 file
    /// in a universal format (UASTC, ETC1S) that carries its full chain. Uploaded as is where the
    /// device samples BC7 (a quarter of RGBA8's memory, the file's own mips); otherwise `rgba8` is
    /// uploaded and its mips are built by the device.
    pub bc7: Option<Vec<Vec<u8>>>,
}

/// glTF metallic-roughness material, plus the optional fabric model.
#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    pub base_color: [f32; 4],
    pub metallic: f32,
    pub roughness: f32,
    pub emissive: [f32; 3],
    pub normal_scale: f32,
    /// Indices into `Scene::textures`.
    pub base_color_texture: Option<usize>,
    pub metallic_roughness_texture: Option<usize>,
    pub normal_texture: Option<usize>,
    pub emissive_texture: Option<usize>,
    /// glTF occlusionTexture (red channel; TEXCOORD_0 with the material's transform) and its
    /// strength: it darkens environment light only (lamps are not occluded by it).
    pub occlusion_texture: Option<usize>,
    pub occlusion_strength: f32,
    pub double_sided: bool,
    pub fabric: Option<crate::fabric::FabricParams>,
    /// KHR_materials_sheen (None: no sheen layer).
    pub sheen: Option<Sheen>,
    /// KHR_materials_specular and KHR_materials_ior (the defaults are glTF's core material).
    pub specular: Specular,
    /// KHR_materials_anisotropy (None: isotropic).
    pub anisotropy: Option<Anisotropy>,
    /// KHR_materials_transmission with KHR_materials_volume (None: opaque to light).
    pub transmission: Option<Transmission>,
    /// KHR_materials_clearcoat (None: no coat).
    pub clearcoat: Option<Clearcoat>,
    /// KHR_materials_diffuse_transmission (None: the diffuse lobe only reflects).
    pub diffuse_transmission: Option<DiffuseTransmission>,
    /// KHR_materials_iridescence (None: no thin film).
    pub iridescence: Option<Iridescence>,
    /// KHR_materials_pbrSpecularGlossiness: the glossiness factor (`roughness` is 1 − it, and
    /// the metallic-roughness slot holds the specular-glossiness texture, whose alpha multiplies
    /// it); None: the metallic-roughness model.
    pub glossiness: Option<f32>,
    /// Where each texture slot ([`TextureSlot`]) reads its coordinates.
    pub uv: [SlotUv; TextureSlot::COUNT],
    /// How each texture slot is sampled: its glTF texture's sampler (wrap modes and filters).
    pub samplers: [TextureSampler; TextureSlot::COUNT],
    /// KHR_materials_unlit: the base colour (factor × texture × COLOR_0) is the pixel's
    /// radiance, with no lighting (not for fabric: the loader drops it there with a warning).
    pub unlit: bool,
    /// alphaMode MASK: the alphaCutoff (where the base colour's alpha, factor × texture ×
    /// COLOR_0, is below it, the surface is cut out, in the image and in shadow maps). None:
    /// opaque (alphaMode OPAQUE or BLEND).
    pub alpha_cutoff: Option<f32>,
    /// alphaMode BLEND: the surface is drawn after the opaque ones by the forward pass
    /// (`Pass::Transparent`), lit as they are and blended over them by its base colour's alpha.
    pub blend: bool,
}

impl Material {
    /// The texture slot whose coordinates the vertices' generated tangents follow: glTF's normal
    /// texture, or without one the clear coat's normal texture; None when it has neither.
    pub fn tangent_slot(&self) -> Option<TextureSlot> {
        if self.normal_texture.is_some() {
            Some(TextureSlot::Normal)
        } else if self
            .clearcoat
            .as_ref()
            .is_some_and(|c| c.normal_texture.is_some())
        {
            Some(TextureSlot::ClearcoatNormal)
        } else {
            None
        }
    }

    /// Whether the G-buffer cannot hold this material, so the transparent pass draws it:
    /// alphaMode BLEND, a fabric sheet, transmission, a clear coat, diffuse transmission, a
    /// thin film.
    pub fn needs_forward(&self) -> bool {
        self.blended()
            || self.transmission.is_some()
            || self.clearcoat.is_some()
            || self.diffuse_transmission.is_some()
            || self.iridescence.is_some()
    }

    /// Whether the transparent pass blends the surface over what is behind it: alphaMode BLEND,
    /// or a fabric that is a single sheet (its gaps let light through: `FabricParams::transmission`).
    pub fn blended(&self) -> bool {
        self.blend || self.is_sheet()
    }

    /// Whether the material is a fabric sheet (`FabricParams::transmission`).
    pub fn is_sheet(&self) -> bool {
        self.fabric
            .as_ref()
            .is_some_and(|f| f.transmission.is_some())
    }

    /// The material's textures (indices into `Scene::textures`) in [`TextureSlot`] order.
    pub fn textures(&self) -> [Option<usize>; TextureSlot::COUNT] {
        [
            self.base_color_texture,
            self.metallic_roughness_texture,
            self.normal_texture,
            self.emissive_texture,
            self.occlusion_texture,
            self.sheen.as_ref().and_then(|s| s.color_texture),
            self.sheen.as_ref().and_then(|s| s.roughness_texture),
            self.specular.texture,
            self.specular.color_texture,
            self.anisotropy.as_ref().and_then(|a| a.texture),
            self.transmission.as_ref().and_then(|t| t.texture),
            self.transmission.as_ref().and_then(|t| t.thickness_texture),
            self.clearcoat.as_ref().and_then(|c| c.texture),
            self.clearcoat.as_ref().and_then(|c| c.roughness_texture),
            self.clearcoat.as_ref().and_then(|c| c.normal_texture),
            self.diffuse_transmission.as_ref().and_then(|d| d.texture),
            self.diffuse_transmission
                .as_ref()
                .and_then(|d| d.color_texture),
            self.iridescence.as_ref().and_then(|i| i.texture),
            self.iridescence.as_ref().and_then(|i| i.thickness_texture),
        ]
    }
}

/// How texture coordinates outside [0, 1] are mapped (glTF `sampler.wrapS` / `wrapT`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// 10497, glTF's default.
    #[default]
    Repeat,
    /// 33071.
    ClampToEdge,
    /// 33648.
    MirroredRepeat,
}

/// Texel filter (glTF `magFilter`, and the texel part of `minFilter`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TexelFilter {
    Nearest,
    #[default]
    Linear,
}

/// The mip part of glTF's `minFilter`: `None` for NEAREST and LINEAR (the base level only).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum MipFilter {
    None,
    Nearest,
    #[default]
    Linear,
}

/// A glTF sampler. The default (no sampler, or one without filters) is what glTF leaves to the
/// renderer for filters and REPEAT for wrapping: weft's trilinear with anisotropy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct TextureSampler {
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
    pub mag: TexelFilter,
    pub min: TexelFilter,
    pub mip: MipFilter,
}

impl TextureSampler {
    /// From glTF's numeric codes (None where the file gives none); unknown codes are errors
    /// naming the value.
    pub fn from_gltf_codes(
        wrap_s: u32,
        wrap_t: u32,
        mag: Option<u32>,
        min: Option<u32>,
    ) -> std::result::Result<TextureSampler, String> {
        let wrap = |code: u32, name: &str| {
            match code {
            10497 => Ok(Wrap::Repeat),
            33071 => Ok(Wrap::ClampToEdge),
            33648 => Ok(Wrap::MirroredRepeat),
            other => Err(format!(
                "{name} is {other}; glTF allows 10497 (REPEAT), 33071 (CLAMP_TO_EDGE) and 33648 (MIRRORED_REPEAT)"
            )),
        }
        };
        let mag = match mag {
            None | Some(9729) => TexelFilter::Linear,
            Some(9728) => TexelFilter::Nearest,
            Some(other) => {
                return Err(format!(
                    "magFilter is {other}; glTF allows 9728 (NEAREST) and 9729 (LINEAR)"
                ))
            }
        };
        let (min, mip) = match min {
            None | Some(9987) => (TexelFilter::Linear, MipFilter::Linear),
            Some(9728) => (TexelFilter::Nearest, MipFilter::None),
            Some(9729) => (TexelFilter::Linear, MipFilter::None),
            Some(9984) => (TexelFilter::Nearest, MipFilter::Nearest),
            Some(9985) => (TexelFilter::Linear, MipFilter::Nearest),
            Some(9986) => (TexelFilter::Nearest, MipFilter::Linear),
            Some(other) => {
                return Err(format!(
                    "minFilter is {other}; glTF allows 9728, 9729 and 9984 to 9987"
                ))
            }
        };
        Ok(TextureSampler {
            wrap_s: wrap(wrap_s, "wrapS")?,
            wrap_t: wrap(wrap_t, "wrapT")?,
            mag,
            min,
            mip,
        })
    }
}

/// The texture slots of a material, in the order of [`Material::uv`] (and of the GPU material's
/// per-slot transforms, glsl/include/frame.glsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureSlot {
    BaseColor = 0,
    MetallicRoughness = 1,
    Normal = 2,
    Emissive = 3,
    Occlusion = 4,
    SheenColor = 5,
    SheenRoughness = 6,
    Specular = 7,
    SpecularColor = 8,
    Anisotropy = 9,
    Transmission = 10,
    Thickness = 11,
    Clearcoat = 12,
    ClearcoatRoughness = 13,
    ClearcoatNormal = 14,
    DiffuseTransmission = 15,
    DiffuseTransmissionColor = 16,
    Iridescence = 17,
    IridescenceThickness = 18,
}

impl TextureSlot {
    pub const COUNT: usize = 19;
    /// The slots' names in messages, in slot order.
    pub const NAMES: [&'static str; TextureSlot::COUNT] = [
        "base colour",
        "metallic-roughness",
        "normal",
        "emissive",
        "occlusion",
        "sheen colour",
        "sheen roughness",
        "specular",
        "specular colour",
        "anisotropy",
        "transmission",
        "thickness",
        "clearcoat",
        "clearcoat roughness",
        "clearcoat normal",
        "diffuse transmission",
        "diffuse transmission colour",
        "iridescence",
        "iridescence thickness",
    ];
}

/// The texture coordinates of one texture slot: UV set `set` (0 or 1) through the affine map
/// `uv' = [m[0], m[1]] · (u, v, 1)`. For set 0 the map is relative to [`Vertex::uv`], which already
/// carries the material's frame transform (so it is the identity for slots that share it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlotUv {
    pub set: u32,
    pub m: [[f32; 3]; 2],
}

impl SlotUv {
    pub const IDENTITY: SlotUv = SlotUv {
        set: 0,
        m: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
    };

    /// `uv` through the map.
    pub fn apply(&self, uv: [f32; 2]) -> [f32; 2] {
        let [[a, b, c], [d, e, f]] = self.m;
        [a * uv[0] + b * uv[1] + c, d * uv[0] + e * uv[1] + f]
    }

    /// The slot's texture coordinates at `v`: its set's, through the map.
    pub fn coordinates(&self, v: &Vertex) -> [f32; 2] {
        self.apply(if self.set == 1 { v.uv1 } else { v.uv })
    }

    /// Whether the map takes some texture coordinate of `vertices` (of its set) out of 32-bit
    /// floating point: finite factors whose product overflows, which the shader would turn into
    /// a black surface. An affine map is largest at the corners of the coordinates' bounds, so
    /// those are what is tried.
    pub fn overflows_on(&self, vertices: &[Vertex]) -> bool {
        if *self == SlotUv::IDENTITY || vertices.is_empty() {
            return false;
        }
        let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
        for v in vertices {
            let uv = if self.set == 1 { v.uv1 } else { v.uv };
            for k in 0..2 {
                lo[k] = lo[k].min(uv[k]);
                hi[k] = hi[k].max(uv[k]);
            }
        }
        [
            [lo[0], lo[1]],
            [lo[0], hi[1]],
            [hi[0], lo[1]],
            [hi[0], hi[1]],
        ]
        .iter()
        .any(|&uv| !self.apply(uv).iter().all(|x| x.is_finite()))
    }
}

impl Default for SlotUv {
    fn default() -> SlotUv {
        SlotUv::IDENTITY
    }
}

/// KHR_materials_sheen: a Charlie-distribution sheen layer over the base material.
#[derive(Clone, Debug, PartialEq)]
pub struct Sheen {
    /// Linear sheenColorFactor.
    pub color: [f32; 3],
    /// sheenRoughnessFactor, in [0, 1].
    pub roughness: f32,
    /// sRGB; rgb multiplies `color`.
    pub color_texture: Option<usize>,
    /// Linear; alpha multiplies `roughness`.
    pub roughness_texture: Option<usize>,
}

/// KHR_materials_transmission (the fraction of light the dielectric lets through, its diffuse
/// lobe replaced by a refracted view of what is behind) and KHR_materials_volume (the thickness it
/// is refracted through and the attenuation on the way; thickness 0: thin-walled).
#[derive(Clone, Debug, PartialEq)]
pub struct Transmission {
    /// transmissionFactor, in [0, 1].
    pub factor: f32,
    /// Linear; red multiplies `factor`.
    pub texture: Option<usize>,
    /// thicknessFactor (object space; 0: thin-walled, no volume).
    pub thickness: f32,
    /// Linear; green multiplies `thickness`.
    pub thickness_texture: Option<usize>,
    /// attenuationColor (linear) and attenuationDistance (None: infinite, no attenuation).
    pub attenuation_color: [f32; 3],
    pub attenuation_distance: Option<f32>,
    /// KHR_materials_dispersion: 20 / the Abbe number (0: none); the volume's index spreads
    /// across the red, green and blue rays by (ior − 1) · 0.025 · dispersion either way.
    pub dispersion: f32,
}

/// KHR_materials_clearcoat: a clear dielectric layer (ior 1.5) over the material, with its own
/// roughness and normal.
#[derive(Clone, Debug, PartialEq)]
pub struct Clearcoat {
    /// clearcoatFactor, in [0, 1]; the texture's red multiplies it.
    pub factor: f32,
    pub texture: Option<usize>,
    /// clearcoatRoughnessFactor, in [0, 1]; the texture's green multiplies it.
    pub roughness: f32,
    pub roughness_texture: Option<usize>,
    /// The coat's own tangent-space normal texture and its scale (none: the geometry's normal,
    /// not the base's normal map).
    pub normal_texture: Option<usize>,
    pub normal_scale: f32,
}

/// KHR_materials_diffuse_transmission: the part of the diffuse lobe that goes through a thin
/// surface (Lambertian, to the other side) instead of being reflected, and its colour.
#[derive(Clone, Debug, PartialEq)]
pub struct DiffuseTransmission {
    /// diffuseTransmissionFactor, in [0, 1]; the texture's alpha multiplies it.
    pub factor: f32,
    pub texture: Option<usize>,
    /// diffuseTransmissionColorFactor (linear); the texture's rgb (sRGB) multiplies it.
    pub color: [f32; 3],
    pub color_texture: Option<usize>,
}

/// KHR_materials_iridescence: a thin dielectric film over the material whose interference
/// colours its Fresnel reflection (soap bubbles, oil on water, coated lenses).
#[derive(Clone, Debug, PartialEq)]
pub struct Iridescence {
    /// iridescenceFactor, in [0, 1]; the texture's red multiplies it.
    pub factor: f32,
    pub texture: Option<usize>,
    /// iridescenceIor: the film's index of refraction (≥ 1).
    pub ior: f32,
    /// iridescenceThicknessMinimum and _Maximum (nanometres): the film's thickness where the
    /// thickness texture's green is 0 and 1; without the texture, the maximum.
    pub thickness_min: f32,
    pub thickness_max: f32,
    pub thickness_texture: Option<usize>,
}

/// KHR_materials_specular (with KHR_materials_ior's index of refraction).
#[derive(Clone, Debug, PartialEq)]
pub struct Specular {
    /// specularFactor: the strength of the dielectric specular layer.
    pub factor: f32,
    /// specularColorFactor (linear; may exceed 1).
    pub color: [f32; 3],
    /// Linear; alpha multiplies `factor`.
    pub texture: Option<usize>,
    /// sRGB; rgb multiplies `color`.
    pub color_texture: Option<usize>,
    /// KHR_materials_ior (1.5 by default: F0 = 0.04).
    pub ior: f32,
}

impl Default for Specular {
    fn default() -> Specular {
        Specular {
            factor: 1.0,
            color: [1.0; 3],
            texture: None,
            color_texture: None,
            ior: 1.5,
        }
    }
}

impl Specular {
    /// F0 of the dielectric at normal incidence from the index of refraction, ((ior-1)/(ior+1))².
    pub fn f0_from_ior(&self) -> f32 {
        let r = (self.ior - 1.0) / (self.ior + 1.0);
        r * r
    }
}

/// KHR_materials_anisotropy: anisotropic GGX along a direction in the tangent frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Anisotropy {
    /// anisotropyStrength, in [0, 1].
    pub strength: f32,
    /// anisotropyRotation: radians, counter-clockwise from the tangent in the tangent plane.
    pub rotation: f32,
    /// Linear; rg: direction in the tangent frame (in [-1, 1] as 2·texel - 1), b: strength.
    pub texture: Option<usize>,
}

impl Default for Material {
    fn default() -> Self {
        // glTF's default material.
        Material {
            name: "default".into(),
            base_color: [1.0; 4],
            metallic: 1.0,
            roughness: 1.0,
            emissive: [0.0; 3],
            normal_scale: 1.0,
            base_color_texture: None,
            metallic_roughness_texture: None,
            normal_texture: None,
            emissive_texture: None,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            double_sided: false,
            fabric: None,
            sheen: None,
            specular: Specular::default(),
            anisotropy: None,
            transmission: None,
            clearcoat: None,
            diffuse_transmission: None,
            iridescence: None,
            glossiness: None,
            uv: [SlotUv::IDENTITY; TextureSlot::COUNT],
            samplers: [TextureSampler::default(); TextureSlot::COUNT],
            unlit: false,
            alpha_cutoff: None,
            blend: false,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    Directional,
    Point,
    /// Cone angles in radians, as in KHR_lights_punctual.
    Spot {
        inner_cone: f32,
        outer_cone: f32,
    },
}

/// A punctual light in world space (KHR_lights_punctual units: lux for directional, candela otherwise).
#[derive(Clone, Debug)]
pub struct Light {
    pub name: String,
    pub kind: LightKind,
    pub color: [f32; 3],
    pub intensity: f32,
    /// None = infinite.
    pub range: Option<f32>,
    pub position: Vec3,
    /// Direction the light travels (the node's -Z), unit length.
    pub direction: Vec3,
    /// Shadow map settings when the light casts shadows (directional and spot lights only; the
    /// light's `extras.shadows` in glTF). None = no shadows, no shadow map.
    pub shadow: Option<Shadow>,
}

/// How a light's shadow map is made and filtered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shadow {
    /// Shadow map size in texels (square), 64..=4096.
    pub resolution: u32,
    /// PCF filter radius in shadow-map texels, 0..=8 (0 = one hardware-compared bilinear tap).
    pub filter_radius: f32,
    /// Constant depth bias in shadow-map texels (scaled by the slope in the shader), 0..=64.
    pub bias: f32,
}

impl Default for Shadow {
    fn default() -> Shadow {
        Shadow {
            resolution: 1024,
            filter_radius: 1.5,
            bias: 1.0,
        }
    }
}

/// A camera in world space: perspective, or orthographic when `orthographic` is set.
#[derive(Clone, Debug)]
pub struct Camera {
    pub name: String,
    /// World-to-view transform (view space looks down -Z, +Y up).
    pub view: Mat4,
    /// Vertical field of view in radians, in (0, pi).
    pub yfov: f32,
    pub znear: f32,
    /// None = infinite far plane.
    pub zfar: Option<f32>,
    /// Aspect ratio stored in the file; the renderer uses the output image's.
    pub aspect_ratio: Option<f32>,
    /// An orthographic camera's glTF (xmag, ymag): half the width and height of the view
    /// volume. The renderer keeps ymag and takes the half-width from the output image's aspect
    /// (as it does with a perspective camera's yfov), and needs `zfar`. None: perspective.
    pub orthographic: Option<[f32; 2]>,
    /// Some for weft's automatic framing: what it frames, so that the renderer can frame it again
    /// for the image's aspect ratio ([`Camera::for_aspect`]). None for a file's camera and
    /// `--eye`.
    pub framing: Option<Framing>,
}

/// What an automatic framing frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Framing {
    pub bounds: Bounds,
    pub azimuth_degrees: f32,
    /// The scene's vertices in world space (at most [`FRAMING_POINTS`], evenly strided), which
    /// the view is fitted to: a model fills its bounding box's projection only in part (a
    /// draped cloth, a chair seen from above), so fitting the box's corners leaves it small and
    /// off-centre. Empty: the box's corners.
    pub points: std::sync::Arc<Vec<Vec3>>,
}

/// The automatic framing's camera name and vertical field of view.
pub const AUTO_FRAMING_NAME: &str = "automatic framing";
pub const AUTO_FRAMING_YFOV_DEGREES: f32 = 45.0;

/// At most this many vertices are kept for fitting the automatic framing.
pub const FRAMING_POINTS: usize = 1 << 16;

impl Camera {
    /// The camera for an image of this aspect ratio (width / height): an automatic framing is
    /// framed again to fill it; any other camera is returned as it is.
    pub fn for_aspect(&self, aspect: f32) -> Camera {
        match &self.framing {
            Some(f) if aspect.is_finite() && aspect > 0.0 => {
                let c = framing(
                    f.bounds,
                    f.points.clone(),
                    f.azimuth_degrees,
                    aspect.clamp(0.05, 20.0),
                );
                let usable = c.view.is_finite() && c.znear.is_finite() && c.znear > 0.0;
                if usable {
                    c
                } else {
                    self.clone()
                }
            }
            _ => self.clone(),
        }
    }
}

pub use crate::error::Warning;

#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Where the scene came from (a path, or "built-in default scene"), for messages.
    pub source: String,
    pub meshes: Vec<Mesh>,
    pub draws: Vec<Draw>,
    pub materials: Vec<Material>,
    /// How many of `materials` are the file's own, in its order (`materials[i]` is the file's
    /// material `i` for `i` below it); those after it the loader made (the glTF default
    /// material, unlit copies for points and lines) or staging added (the default ground).
    pub file_materials: usize,
    pub textures: Vec<Texture>,
    pub lights: Vec<Light>,
    pub cameras: Vec<Camera>,
    pub warnings: Vec<Warning>,
    /// The files the scene was read from: the scene file, then the buffers and images beside
    /// it that it refers to (empty for a scene loaded from memory). What a command must not
    /// write over (`render::check_outputs`).
    pub files: Vec<std::path::PathBuf>,
    /// KHR_materials_variants: the file's variant names, and the one the scene was loaded with.
    pub variants: Vec<String>,
    pub variant: Option<String>,
    /// The file's scenes ("index" or "index 'name'"), and the one drawn (None for a file
    /// without scenes, whose root nodes are drawn).
    pub gltf_scenes: Vec<String>,
    pub gltf_scene: Option<usize>,
    /// EXT_mesh_gpu_instancing: the nodes that place their mesh several times, and their
    /// instances summed (each instance is a draw of its own: a node with 125 instances of a
    /// one-primitive mesh makes 125 draws).
    pub instanced_nodes: usize,
    pub instances: usize,
    /// The node hierarchy, skins, morph targets and animations ([`animation`]): what
    /// [`Scene::pose`] needs to move the draws, lights and cameras above.
    pub rig: animation::Rig,
}

/// Axis-aligned bounds in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub min: Vec3,
    pub max: Vec3,
}

impl Scene {
    /// The material `mesh` is drawn with, as the GPU reads it (an index past the last material
    /// reads the last); None when the scene has no material.
    pub fn mesh_material(&self, mesh: &Mesh) -> Option<&Material> {
        self.materials
            .get(mesh.material.min(self.materials.len().saturating_sub(1)))
    }

    /// The material draw `d` is drawn with ([`Scene::mesh_material`]); None without a mesh.
    pub fn drawn_material(&self, d: &Draw) -> Option<&Material> {
        self.mesh_material(self.meshes.get(d.mesh)?)
    }

    /// World-space bounds of every drawn vertex; None for a scene with nothing to draw.
    pub fn bounds(&self) -> Option<Bounds> {
        self.bounds_of(|d| d.visible)
    }

    /// World-space bounds of the draws that cast shadows (what a shadow map must cover).
    pub fn caster_bounds(&self) -> Option<Bounds> {
        self.bounds_of(|d| d.cast_shadows && d.visible)
    }

    fn bounds_of(&self, keep: impl Fn(&Draw) -> bool) -> Option<Bounds> {
        let mut min = Vec3::splat(f32::INFINITY);
        let mut max = Vec3::splat(f32::NEG_INFINITY);
        for (i, d) in self.draws.iter().enumerate().filter(|(_, d)| keep(d)) {
            // A skinned or morphed draw's bounds are those of its current pose.
            let deformed = self.deformed_vertices(i);
            let vertices = deformed.as_deref().unwrap_or(&self.meshes[d.mesh].vertices);
            for v in vertices {
                let p = d.world.transform_point3(Vec3::from(v.position));
                if p.is_finite() {
                    min = min.min(p);
                    max = max.max(p);
                }
            }
        }
        (min.x <= max.x).then_some(Bounds { min, max })
    }

    /// The camera to render with: the file's camera `index`, or (when None) the file's first camera,
    /// or an automatic framing of the bounds seen from the front, slightly above.
    pub fn camera(&self, index: Option<usize>) -> Result<Camera, crate::Error> {
        match index {
            Some(i) => self.cameras.get(i).cloned().ok_or_else(|| {
                crate::Error::input(format!(
                    "camera {i} does not exist in {}: it has {} camera(s); pass --camera with an index below {}, or leave it out for automatic framing",
                    self.source,
                    self.cameras.len(),
                    self.cameras.len().max(1)
                ))
            }),
            None => Ok(self.cameras.first().cloned().unwrap_or_else(|| self.auto_camera())),
        }
    }

    /// [`Scene::camera`] for an image of this aspect ratio (width / height), as
    /// [`Camera::for_aspect`] makes it, with an automatic framing fitted once, at that aspect
    /// (the renderer's per-frame camera: the fit reads every vertex of the pose).
    pub fn camera_for_aspect(
        &self,
        index: Option<usize>,
        aspect: f32,
    ) -> Result<Camera, crate::Error> {
        if index.is_none() && self.cameras.is_empty() {
            return Ok(self.auto_camera_for_aspect(aspect));
        }
        self.camera(index).map(|c| c.for_aspect(aspect))
    }

    /// Whether [`Scene::camera`] with this index is the automatic framing (the scene has no
    /// camera and none is asked for), without fitting it.
    pub fn camera_is_automatic(&self, index: Option<usize>) -> bool {
        index.is_none() && self.cameras.is_empty()
    }

    /// A camera at `eye` looking at `target` (Y up), with vertical field of view `yfov`; near and
    /// far planes fitted to the scene's bounds.
    pub fn look_at_camera(
        &self,
        eye: Vec3,
        target: Vec3,
        yfov: f32,
    ) -> Result<Camera, crate::Error> {
        let dir = target - eye;
        if !eye.is_finite() || !target.is_finite() || dir.length() < 1e-6 {
            return Err(crate::Error::input(format!(
                "camera eye {eye} and target {target} must be finite and apart"
            )));
        }
        if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
            return Err(crate::Error::input(format!(
                "field of view {} degrees is out of range: use a value between 0 and 180 (exclusive)",
                yfov.to_degrees()
            )));
        }
        let up = if dir.normalize().y.abs() > 0.999 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        let b = self.bounds().unwrap_or(Bounds {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        });
        let far = (b.max - b.min).length() + (eye - (b.min + b.max) * 0.5).length();
        // Bounds near the f32 limit overflow `far`: then the far plane is infinite.
        let (znear, zfar) = if (far * 1.5).is_finite() {
            ((far * 1e-4).max(1e-3), Some(far * 1.5))
        } else {
            (1e-3, None)
        };
        let view = Mat4::look_at_rh(eye, target, up);
        if !view.is_finite() {
            return Err(crate::Error::input(format!(
                "camera eye {eye} and target {target} are too far from the origin to render in 32-bit floating point; move them closer"
            )));
        }
        Ok(Camera {
            name: "--eye/--target".into(),
            view,
            yfov,
            znear,
            zfar,
            aspect_ratio: None,
            orthographic: None,
            framing: None,
        })
    }

    /// Frames the scene's bounds: looks at the centre from 20 degrees above, from the +Z side, or
    /// from the side the single-sided surfaces face when +Z sees mostly their backs
    /// ([`Scene::framing_azimuth`]). Bounds too large to frame in f32 (coordinates near +-3e38)
    /// get the framing of the unit cube.
    /// The camera is framed for a square image; [`Camera::for_aspect`] frames it again for the
    /// image it renders (the renderer does).
    pub fn auto_camera(&self) -> Camera {
        self.auto_camera_for_aspect(1.0)
    }

    /// [`Scene::auto_camera`] for an image of this aspect ratio (width / height; clamped to
    /// [0.05, 20], and 1 when not a positive number).
    fn auto_camera_for_aspect(&self, aspect: f32) -> Camera {
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect.clamp(0.05, 20.0)
        } else {
            1.0
        };
        let unit = Bounds {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        let azimuth = self.framing_azimuth();
        let camera = match self.framing_points() {
            Some((b, points)) => framing(b, points, azimuth, aspect),
            None => framing(unit, Default::default(), azimuth, aspect),
        };
        let usable = camera.view.is_finite()
            && camera.znear.is_finite()
            && camera.znear > 0.0
            && camera
                .zfar
                .is_some_and(|f| f.is_finite() && f > camera.znear);
        if usable {
            camera
        } else {
            framing(unit, Default::default(), azimuth, aspect)
        }
    }

    /// The scene's bounds ([`Scene::bounds`]) and its finite world-space vertices (posed, for a
    /// skinned or morphed draw), evenly strided to at most [`FRAMING_POINTS`], for the
    /// automatic framing to fit; one pass over the vertices.
    fn framing_points(&self) -> Option<(Bounds, std::sync::Arc<Vec<Vec3>>)> {
        let total: usize = self
            .draws
            .iter()
            .filter_map(|d| self.meshes.get(d.mesh))
            .map(|m| m.vertices.len())
            .sum();
        let stride = total.div_ceil(FRAMING_POINTS).max(1);
        let mut points = Vec::with_capacity(total.min(FRAMING_POINTS));
        let (mut min, mut max) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let mut k = 0usize;
        for (i, d) in self.draws.iter().enumerate().filter(|(_, d)| d.visible) {
            let Some(mesh) = self.meshes.get(d.mesh) else {
                continue;
            };
            let deformed = self.deformed_vertices(i);
            let vertices = deformed.as_deref().unwrap_or(&mesh.vertices);
            for v in vertices {
                let p = d.world.transform_point3(Vec3::from(v.position));
                if p.is_finite() {
                    min = min.min(p);
                    max = max.max(p);
                    if k % stride == 0 {
                        points.push(p);
                    }
                }
                k += 1;
            }
        }
        (min.x <= max.x).then(|| (Bounds { min, max }, std::sync::Arc::new(points)))
    }

    /// The side automatic framing looks from, as degrees about +Y from +Z (0: the front; 90:
    /// +X; 180: the back; 270: -X). Single-sided surfaces show only their fronts (the side
    /// their counter-clockwise winding faces), so a sheet whose normals all point away from +Z
    /// (a curtain seen from behind) would show nothing but its shadow: the side that sees the
    /// most front-facing area (projected, double-sided surfaces counted from both sides) is
    /// chosen, unless +Z sees at least half as much. A closed mesh shows about as much front
    /// from every side, and keeps +Z. At most about a million triangles are sampled.
    pub fn framing_azimuth(&self) -> f32 {
        const SIDES: [f32; 4] = [0.0, 90.0, 180.0, 270.0];
        let e = 20f32.to_radians();
        let dirs = SIDES.map(|a| {
            let a = a.to_radians();
            Vec3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos())
        });
        let triangles: usize = self
            .draws
            .iter()
            .filter_map(|d| self.meshes.get(d.mesh))
            .filter(|m| m.topology == Topology::Triangles)
            .map(|m| m.indices.len() / 3)
            .sum();
        let stride = (triangles >> 20).max(1);
        let mut front = [0f64; 4];
        for d in self.draws.iter().filter(|d| d.visible) {
            let Some(mesh) = self.meshes.get(d.mesh) else {
                continue;
            };
            let two_sided = self.mesh_material(mesh).is_some_and(|m| m.double_sided);
            // A mirroring transform turns the winding, and with it the front.
            let sign = if Mat3::from_mat4(d.world).determinant() < 0.0 {
                -1.0
            } else {
                1.0
            };
            let at = |i: u32| {
                mesh.vertices
                    .get(i as usize)
                    .map(|v| d.world.transform_point3(Vec3::from(v.position)))
            };
            if mesh.topology != Topology::Triangles {
                continue;
            }
            for t in mesh.indices.chunks_exact(3).step_by(stride) {
                let (Some(a), Some(b), Some(c)) = (at(t[0]), at(t[1]), at(t[2])) else {
                    continue;
                };
                let n = (b - a).cross(c - a) * sign;
                if !n.is_finite() {
                    continue;
                }
                for (f, dir) in front.iter_mut().zip(&dirs) {
                    let seen = f64::from(n.dot(*dir));
                    *f += if two_sided { seen.abs() } else { seen.max(0.0) };
                }
            }
        }
        let best = (0..4).fold(0, |b, k| if front[k] > front[b] { k } else { b });
        if front[0] >= 0.5 * front[best] {
            0.0
        } else {
            SIDES[best]
        }
    }
}

/// Frames `points` (the model's vertices; the corners of bounds `b` when empty) from
/// `azimuth_degrees` (about +Y from +Z), 20 degrees above, for an image of this aspect ratio
/// (width / height): their projection centred, the camera as close as it can be with every point
/// inside the view, 5 % in from its edges, so the model fills the frame along its limiting side
/// (as model-viewer frames a model), where a bounding sphere left a long, flat model small
/// (GlamVelvetSofa filled 40 % of a 16:9 frame's width) and the box's corners a draped cloth
/// (SheenCloth, half the frame). Past [`FRAMING_POINTS`] vertices the points are a stride of
/// them, so an extreme vertex between two kept ones may reach into the margin.
fn framing(
    b: Bounds,
    points: std::sync::Arc<Vec<Vec3>>,
    azimuth_degrees: f32,
    aspect: f32,
) -> Camera {
    let radius = ((b.max - b.min).length() * 0.5).max(1e-3);
    let yfov = AUTO_FRAMING_YFOV_DEGREES.to_radians();
    let (e, a) = (20f32.to_radians(), azimuth_degrees.to_radians());
    // From the centre towards the eye; the view's right and up.
    let dir = Vec3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos());
    let right = Vec3::Y.cross(dir).normalize();
    let up = dir.cross(right).normalize();
    let corners: Vec<Vec3> = (0..8)
        .map(|k| {
            Vec3::new(
                if k & 1 == 0 { b.min.x } else { b.max.x },
                if k & 2 == 0 { b.min.y } else { b.max.y },
                if k & 4 == 0 { b.min.z } else { b.max.z },
            )
        })
        .collect();
    let fit: &[Vec3] = if points.is_empty() { &corners } else { &points };
    // The distance at which every point is inside the view, 5 % in from its edges: a point `c`
    // (from the target) at depth `dist - c·dir` needs |c·right| <= that depth · tan of the half
    // field of view across, and |c·up| the same with the vertical half angle.
    let tan_v = (yfov * 0.5).tan() / 1.05;
    let tan_h = tan_v * aspect;
    let fit_distance = |center: Vec3| {
        fit.iter().fold(0f32, |dist, p| {
            let c = *p - center;
            let z = c.dot(dir);
            dist.max(z + c.dot(right).abs() / tan_h)
                .max(z + c.dot(up).abs() / tan_v)
        })
    };
    // Centre the points' projection: from the bounds' centre, move the target by the middle of
    // the points' extent across the image (in units of the half view at the target's depth),
    // four times (perspective makes one step approximate).
    let mut center = (b.min + b.max) * 0.5;
    for _ in 0..4 {
        let dist = fit_distance(center);
        let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
        for p in fit {
            let c = *p - center;
            let depth = (dist - c.dot(dir)).max(1e-6 * radius);
            let s = Vec2::new(c.dot(right) / (depth * tan_h), c.dot(up) / (depth * tan_v));
            lo = lo.min(s);
            hi = hi.max(s);
        }
        let mid = (lo + hi) * 0.5;
        let shift = right * (mid.x * dist * tan_h) + up * (mid.y * dist * tan_v);
        if !shift.is_finite() {
            break;
        }
        center += shift;
    }
    let dist = fit_distance(center);
    let nearest = |set: &[Vec3]| {
        set.iter()
            .fold(f32::MIN, |n, p| n.max((*p - center).dot(dir)))
    };
    // A flat or tiny bound still gets a camera in front of it.
    let dist = dist.max(nearest(fit) + radius * 0.1).max(radius * 0.1);
    let eye = center + dir * dist;
    Camera {
        name: AUTO_FRAMING_NAME.into(),
        view: Mat4::look_at_rh(eye, center, Vec3::Y),
        yfov,
        // The near plane before the whole box (the points are a sample of the vertices).
        znear: ((dist - nearest(&corners)) * 0.5).max(radius * 1e-3),
        zfar: Some(dist + radius * 2.0),
        aspect_ratio: None,
        orthographic: None,
        framing: Some(Framing {
            bounds: b,
            azimuth_degrees,
            points,
        }),
    }
}
