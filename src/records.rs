//! GPU-side records (below `render`, so that the CPU reference shades the same records),
//! mirrored field for field by `glsl/include/frame.glsl` (std140 for the frame
//! uniform, std430 for the storage buffers and push constants). Sizes are asserted at compile time.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

use crate::scene::{Light, LightKind, Material, TextureSlot};
use crate::Error;

/// The largest output the renderer accepts on either side, before asking the device.
pub const MAX_SIZE: u32 = 16384;

/// Tile side in pixels (the light lists of `render::tiles`).
pub const TILE: u32 = 16;

/// Tiles across and down for an image of `width` x `height`.
pub fn tile_grid(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(TILE), height.div_ceil(TILE))
}

/// How fabric materials are shaded: the fabric model, or one of the simpler models the paper
/// compares it with (figures 1, 2 and 4; `weft compare`). Other materials are not affected.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(u32)]
pub enum Shading {
    /// The fabric model (docs/fabric-model.md §3).
    #[default]
    Fabric = 0,
    /// The Phong reflection model evaluated per vertex and interpolated (paper figure 1).
    Gouraud = 1,
    /// The Phong reflection model per pixel (paper figure 2a).
    Phong = 2,
    /// One Ashikhmin–Shirley lobe per pixel, threads along the tangent everywhere, no weave
    /// (paper figure 2b).
    PlainAshikhminShirley = 3,
}

impl Shading {
    /// In the order of the comparison figure: simplest first.
    pub const ALL: [Shading; 4] = [
        Shading::Gouraud,
        Shading::Phong,
        Shading::PlainAshikhminShirley,
        Shading::Fabric,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Shading::Fabric => "fabric",
            Shading::Gouraud => "gouraud",
            Shading::Phong => "phong",
            Shading::PlainAshikhminShirley => "ashikhmin-shirley",
        }
    }

    /// The label under the model's panel in the comparison figure.
    pub fn label(self) -> &'static str {
        match self {
            Shading::Fabric => "Fabric model",
            Shading::Gouraud => "Gouraud",
            Shading::Phong => "Phong",
            Shading::PlainAshikhminShirley => "Ashikhmin-Shirley",
        }
    }

    pub fn parse(text: &str) -> crate::Result<Shading> {
        Shading::ALL
            .iter()
            .copied()
            .find(|s| s.name() == text)
            .ok_or_else(|| {
                Error::input(format!(
                    "unknown shading '{text}': choose one of {}",
                    Shading::ALL
                        .iter()
                        .map(|s| s.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameData {
    pub view: [[f32; 4]; 4],
    pub proj: [[f32; 4]; 4],
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub eye: [f32; 4],
    pub viewport: [f32; 4],
    /// rgb: ambient radiance from above; a: the exposure (linear, 2^EV), which the lighting
    /// pass applies where it tone-maps (lighting_main.glsl's TONE_CURVE).
    pub ambient_sky: [f32; 4],
    pub ambient_ground: [f32; 4],
    pub background: [f32; 4],
    pub light_count: u32,
    pub debug_view: u32,
    pub material_count: u32,
    /// Tiles across the image (the light lists of render::tiles).
    pub tile_columns: u32,
    /// Rows of the environment-from-world rotation (w unused).
    pub env_rot: [[f32; 4]; 3],
    /// x: intensity, y: the specular cube's last level, z: the radiance cube's face size, w: its
    /// last level.
    pub env_params: [f32; 4],
    /// x: 0 environment, 1 colour, 2 transparent; y: the environment background's blur (levels).
    pub env_background: [f32; 4],
    /// Irradiance/π, order-2 SH in env space (rgb, a unused).
    pub sh: [[f32; 4]; 9],
    /// The light clusters (render::tiles): x: depth slices (1: the tiles alone), y: the near
    /// distance the slices start at, z: slices per doubling of the view distance, w: tile rows.
    pub clusters: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<FrameData>() == 4 * 64 + 5 * 16 + 16 + 15 * 16);

impl FrameData {
    /// The frame uniform for `camera` at `width` x `height`, with no lights, materials or debug
    /// view yet. The projection is reversed-Z with an infinite far plane (depth 1 at the near
    /// plane, 0 at infinity), Y flipped for Vulkan's Y-down clip space.
    pub fn new(camera: &crate::scene::Camera, width: u32, height: u32) -> FrameData {
        let aspect = width as f32 / height as f32;
        // Reversed-Z keeps D32F depth precision nearly uniform, so a cloth 1.5 cm above a ball
        // does not z-fight at 15 m. The camera's zfar is not needed.
        let mut proj = match camera.orthographic {
            // Orthographic (glTF xmag, ymag): ymag kept, the half-width from the image's aspect,
            // reversed-Z between the far (0) and near (1) planes.
            Some([_, ymag]) => {
                let (h, w) = (ymag.abs().max(1e-6), ymag.abs().max(1e-6) * aspect);
                let near = camera.znear.max(0.0);
                let far = camera.zfar.filter(|f| *f > near).unwrap_or(near + 1e3);
                Mat4::orthographic_rh(-w, w, -h, h, far, near)
            }
            None => {
                Mat4::perspective_infinite_reverse_rh(camera.yfov, aspect, camera.znear.max(1e-6))
            }
        };
        proj.y_axis.y = -proj.y_axis.y;
        let view_proj = proj * camera.view;
        let camera_to_world = camera.view.inverse();
        let mut eye = camera_to_world.transform_point3(Vec3::ZERO);
        if camera.orthographic.is_some() {
            // Every view ray is parallel: the shaders take the direction to the viewer as
            // normalize(eye - p), so the eye is put far back along the view axis, where that
            // direction is the axis to within 1e-7 rad (1e6 times the far plane's distance).
            let back = camera_to_world
                .transform_vector3(Vec3::Z)
                .normalize_or(Vec3::Z);
            let far = camera.zfar.unwrap_or(1e3).abs().max(1.0);
            eye += back * (far * 1e6).min(1e30);
        }
        FrameData {
            view: camera.view.to_cols_array_2d(),
            proj: proj.to_cols_array_2d(),
            view_proj: view_proj.to_cols_array_2d(),
            inv_view_proj: view_proj.inverse().to_cols_array_2d(),
            eye: [eye.x, eye.y, eye.z, 1.0],
            viewport: [
                width as f32,
                height as f32,
                1.0 / width as f32,
                1.0 / height as f32,
            ],
            ambient_sky: AMBIENT_SKY,
            ambient_ground: AMBIENT_GROUND,
            background: BACKGROUND,
            light_count: 0,
            debug_view: 0,
            material_count: 0,
            tile_columns: tile_grid(width, height).0,
            env_rot: [
                [1.0, 0.0, 0.0, 0.0],
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0],
            ],
            env_params: [0.0; 4],
            env_background: [1.0, 0.0, 0.0, 0.0],
            sh: [[0.0; 4]; 9],
            clusters: [1.0, 1.0, 1.0, tile_grid(width, height).1 as f32],
        }
    }
}

impl FrameData {
    /// The same frame sampled at pixel centre + `jitter` (pixels, x right, y down): the projection
    /// is translated in clip space by 2·jitter/size, so the lighting pass's reconstruction from
    /// `inv_view_proj` follows the shifted sample.
    pub fn jittered(mut self, jitter: [f32; 2]) -> FrameData {
        if jitter == [0.0, 0.0] {
            return self;
        }
        let (w, h) = (self.viewport[0], self.viewport[1]);
        let shift =
            Mat4::from_translation(Vec3::new(-2.0 * jitter[0] / w, -2.0 * jitter[1] / h, 0.0));
        let proj = shift * Mat4::from_cols_array_2d(&self.proj);
        let view_proj = proj * Mat4::from_cols_array_2d(&self.view);
        self.proj = proj.to_cols_array_2d();
        self.view_proj = view_proj.to_cols_array_2d();
        self.inv_view_proj = view_proj.inverse().to_cols_array_2d();
        self
    }
}

/// Hemispherical ambient radiance from above and below, and the radiance of empty pixels.
pub const AMBIENT_SKY: [f32; 4] = [0.040, 0.045, 0.055, 0.0];
pub const AMBIENT_GROUND: [f32; 4] = [0.020, 0.018, 0.015, 0.0];
pub const BACKGROUND: [f32; 4] = [0.010, 0.012, 0.016, 0.0];

pub const LIGHT_DIRECTIONAL: f32 = 0.0;
pub const LIGHT_POINT: f32 = 1.0;
pub const LIGHT_SPOT: f32 = 2.0;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuLight {
    pub position_range: [f32; 4],
    pub direction_type: [f32; 4],
    pub color_intensity: [f32; 4],
    pub spot: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<GpuLight>() == 64);

impl GpuLight {
    pub fn new(light: &Light) -> GpuLight {
        let (kind, spot) = match light.kind {
            LightKind::Directional => (LIGHT_DIRECTIONAL, [0.0; 4]),
            LightKind::Point => (LIGHT_POINT, [0.0; 4]),
            LightKind::Spot {
                inner_cone,
                outer_cone,
            } => {
                // KHR_lights_punctual's recommended spot falloff, as a scale and offset of cos.
                let cos_outer = outer_cone.cos();
                let cos_inner = inner_cone.cos();
                let scale = 1.0 / (cos_inner - cos_outer).max(1e-3);
                (LIGHT_SPOT, [scale, -cos_outer * scale, 0.0, 0.0])
            }
        };
        let d = light.direction.normalize_or(Vec3::NEG_Y);
        GpuLight {
            position_range: [
                light.position.x,
                light.position.y,
                light.position.z,
                light.range.unwrap_or(0.0),
            ],
            direction_type: [d.x, d.y, d.z, kind],
            color_intensity: [
                light.color[0],
                light.color[1],
                light.color[2],
                light.intensity,
            ],
            spot,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuMaterial {
    pub base_color: [f32; 4],
    pub emissive_normal: [f32; 4],
    pub metallic_roughness: [f32; 4],
    /// KHR_materials_sheen: rgb colour (0: none), a: roughness.
    pub sheen: [f32; 4],
    /// KHR_materials_specular: rgb colour factor, a: specular factor.
    pub specular: [f32; 4],
    /// x: F0 from the ior, y: anisotropy strength, z: rotation, w: flags (a whole number).
    pub extra: [f32; 4],
    /// Per texture slot: the two rows of its affine UV map, row 0's w the UV set.
    pub uv: [[f32; 4]; 2 * TextureSlot::COUNT],
    /// x: the alphaCutoff of a MASK material (flag [`MATERIAL_MASK`]); KHR_materials_transmission
    /// and _volume: y the transmission factor, z the thickness factor (object space), w the
    /// attenuation distance (0: infinite).
    pub alpha: [f32; 4],
    /// KHR_materials_volume's attenuation colour (rgb, linear), a: the index of refraction.
    pub volume: [f32; 4],
    /// KHR_materials_clearcoat: x the factor, y the roughness, z the coat normal texture's scale
    /// (0 without one), w 1 where the coat normal texture's coordinates are not those the
    /// vertices' tangents follow (its set or its transform's linear part differs from the normal
    /// texture's): surface.glsl then takes its frame from their screen derivatives.
    pub coat: [f32; 4],
    /// KHR_materials_diffuse_transmission: x the factor, yzw the colour (linear).
    pub diffuse_transmission: [f32; 4],
    /// KHR_materials_iridescence: x the factor, y the film's ior, z and w its thickness (nm) at
    /// the thickness texture's 0 and 1 (the minimum and maximum).
    pub iridescence: [f32; 4],
    /// KHR_materials_dispersion: x 20 / the Abbe number (0: none), yzw unused.
    pub dispersion: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<GpuMaterial>() == 192 + 32 * TextureSlot::COUNT);

/// Material flags (frame.glsl's MATERIAL_*).
const MATERIAL_ANISOTROPY: u32 = 1;
const MATERIAL_ANISOTROPY_TEXTURE: u32 = 2;
/// KHR_materials_unlit (read by lighting.frag only when the plan compiles the unlit path in).
pub const MATERIAL_UNLIT: u32 = 4;
/// alphaMode MASK: `alpha[0]` is the cutoff.
pub const MATERIAL_MASK: u32 = 8;
/// alphaMode BLEND: forward.frag writes the base colour's alpha (else 1).
pub const MATERIAL_BLEND: u32 = 16;
/// KHR_materials_transmission: drawn by the transparent pass, which has the backdrop.
pub const MATERIAL_TRANSMISSION: u32 = 32;
/// KHR_materials_clearcoat: drawn by the transparent pass (the G-buffer has no room for a coat).
pub const MATERIAL_CLEARCOAT: u32 = 64;
/// KHR_materials_diffuse_transmission: drawn by the transparent pass.
pub const MATERIAL_DIFFUSE_TRANSMISSION: u32 = 128;
/// KHR_materials_iridescence: drawn by the transparent pass.
pub const MATERIAL_IRIDESCENCE: u32 = 256;
/// KHR_materials_pbrSpecularGlossiness: `metallic_roughness[1]` is the glossiness and the
/// metallic-roughness slot's alpha multiplies it (roughness = 1 − that).
pub const MATERIAL_SPEC_GLOSS: u32 = 512;

/// Whether a material's clear-coat normal texture reads other coordinates than those its
/// vertices' tangents follow ([`Material::tangent_slot`]): another UV set, or another linear
/// part of its transform (an offset moves a texture, not its frame).
fn coat_normal_has_own_frame(m: &Material) -> bool {
    use crate::scene::TextureSlot;
    let coat = TextureSlot::ClearcoatNormal;
    let has_coat_normal = m
        .clearcoat
        .as_ref()
        .is_some_and(|c| c.normal_texture.is_some());
    match m.tangent_slot() {
        Some(slot) if has_coat_normal && slot != coat => {
            let (own, theirs) = (&m.uv[coat as usize], &m.uv[slot as usize]);
            let linear = |s: &crate::scene::SlotUv| [s.m[0][0], s.m[0][1], s.m[1][0], s.m[1][1]];
            own.set != theirs.set || linear(own) != linear(theirs)
        }
        _ => false,
    }
}

impl GpuMaterial {
    pub fn new(m: &Material, fabric_index: Option<usize>) -> GpuMaterial {
        GpuMaterial {
            base_color: m.base_color,
            // Without a normal texture the scale is 0: the default 1x1 texture's 128/255 decodes
            // to 0.0039, not 0, and would tilt every normal by 0.32 degrees.
            emissive_normal: [
                m.emissive[0],
                m.emissive[1],
                m.emissive[2],
                if m.normal_texture.is_some() {
                    m.normal_scale
                } else {
                    0.0
                },
            ],
            metallic_roughness: [
                m.metallic,
                m.glossiness.unwrap_or(m.roughness),
                fabric_index.map(|i| i as f32 + 1.0).unwrap_or(0.0),
                if m.occlusion_texture.is_some() {
                    m.occlusion_strength
                } else {
                    0.0
                },
            ],
            sheen: match &m.sheen {
                Some(s) => [s.color[0], s.color[1], s.color[2], s.roughness],
                None => [0.0; 4],
            },
            specular: [
                m.specular.color[0],
                m.specular.color[1],
                m.specular.color[2],
                m.specular.factor,
            ],
            extra: {
                let (strength, rotation, flags) = match &m.anisotropy {
                    Some(a) => (
                        a.strength,
                        a.rotation,
                        MATERIAL_ANISOTROPY
                            | if a.texture.is_some() {
                                MATERIAL_ANISOTROPY_TEXTURE
                            } else {
                                0
                            },
                    ),
                    None => (0.0, 0.0, 0),
                };
                let flags = flags
                    | if m.unlit { MATERIAL_UNLIT } else { 0 }
                    // BLEND too: the shadow pass casts it cut out at alpha 0.5 (the G-buffer
                    // never draws it, so the cut-out there applies only to MASK).
                    | if m.alpha_cutoff.is_some() || m.blend {
                        MATERIAL_MASK
                    } else {
                        0
                    }
                    | if m.blend { MATERIAL_BLEND } else { 0 }
                    | if m.transmission.is_some() {
                        MATERIAL_TRANSMISSION
                    } else {
                        0
                    }
                    | if m.clearcoat.is_some() {
                        MATERIAL_CLEARCOAT
                    } else {
                        0
                    }
                    | if m.diffuse_transmission.is_some() {
                        MATERIAL_DIFFUSE_TRANSMISSION
                    } else {
                        0
                    }
                    | if m.iridescence.is_some() {
                        MATERIAL_IRIDESCENCE
                    } else {
                        0
                    }
                    | if m.glossiness.is_some() {
                        MATERIAL_SPEC_GLOSS
                    } else {
                        0
                    };
                [m.specular.f0_from_ior(), strength, rotation, flags as f32]
            },
            uv: {
                let mut uv = [[0.0; 4]; 2 * TextureSlot::COUNT];
                for (k, s) in m.uv.iter().enumerate() {
                    uv[2 * k] = [s.m[0][0], s.m[0][1], s.m[0][2], s.set as f32];
                    uv[2 * k + 1] = [s.m[1][0], s.m[1][1], s.m[1][2], 0.0];
                }
                uv
            },
            alpha: [
                m.alpha_cutoff
                    .unwrap_or(if m.blend { BLEND_SHADOW_CUTOFF } else { 0.0 }),
                m.transmission.as_ref().map_or(0.0, |t| t.factor),
                m.transmission.as_ref().map_or(0.0, |t| t.thickness),
                m.transmission
                    .as_ref()
                    .and_then(|t| t.attenuation_distance)
                    .unwrap_or(0.0),
            ],
            volume: {
                let c = m
                    .transmission
                    .as_ref()
                    .map_or([1.0; 3], |t| t.attenuation_color);
                [c[0], c[1], c[2], m.specular.ior]
            },
            coat: match &m.clearcoat {
                Some(c) => [
                    c.factor,
                    c.roughness,
                    if c.normal_texture.is_some() {
                        c.normal_scale
                    } else {
                        0.0
                    },
                    if coat_normal_has_own_frame(m) {
                        1.0
                    } else {
                        0.0
                    },
                ],
                None => [0.0; 4],
            },
            diffuse_transmission: match &m.diffuse_transmission {
                Some(d) => [d.factor, d.color[0], d.color[1], d.color[2]],
                None => [0.0, 1.0, 1.0, 1.0],
            },
            dispersion: [
                m.transmission.as_ref().map_or(0.0, |t| t.dispersion),
                0.0,
                0.0,
                0.0,
            ],
            iridescence: match &m.iridescence {
                Some(i) => [i.factor, i.ior, i.thickness_min, i.thickness_max],
                None => [0.0, 1.3, 0.0, 0.0],
            },
        }
    }
}

/// alphaMode BLEND surfaces cast shadows cut out where their alpha is below this (a shadow map
/// holds no partial cover): a glass at alpha 0.2 casts none, a curtain at 0.9 a solid one.
pub const BLEND_SHADOW_CUTOFF: f32 = 0.5;

/// Push constants of the G-buffer pass, one per draw (128 bytes: the guaranteed minimum).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct DrawPush {
    pub world: [[f32; 4]; 4],
    pub normal_matrix: [[f32; 4]; 3],
    pub material: u32,
    pub tangent_sign: f32,
    /// Bit 0 ([`DRAW_RECEIVES_SHADOWS`]): shadows darken this draw; bit 1
    /// ([`DRAW_WORLD_LIGHT`]): its vertices have the world light.
    pub flags: u32,
    /// With [`DRAW_WORLD_LIGHT`]: where the draw's vertices' world light begins in its buffer,
    /// less the draw's vertex offset (gbuffer.vert adds `gl_VertexIndex`; wrapping).
    pub world_base: u32,
}
const _: () = assert!(std::mem::size_of::<DrawPush>() == 128);

/// `DrawPush::flags`: the draw receives shadows.
pub const DRAW_RECEIVES_SHADOWS: u32 = 1;
/// `DrawPush::flags`: the draw's vertices have the world light (render::world_light).
pub const DRAW_WORLD_LIGHT: u32 = 2;

impl DrawPush {
    pub fn new(world: Mat4, material: u32) -> DrawPush {
        let m3 = glam::Mat3::from_mat4(world);
        let det = m3.determinant();
        let inv_t = if det.abs() > 1e-30 {
            m3.inverse().transpose()
        } else {
            glam::Mat3::IDENTITY
        };
        let c = |v: Vec3| [v.x, v.y, v.z, 0.0];
        DrawPush {
            world: world.to_cols_array_2d(),
            normal_matrix: [c(inv_t.x_axis), c(inv_t.y_axis), c(inv_t.z_axis)],
            material,
            tangent_sign: if det < 0.0 { -1.0 } else { 1.0 },
            flags: DRAW_RECEIVES_SHADOWS,
            world_base: 0,
        }
    }
}

/// One light's shadow map: `Shadow` of glsl/include/frame.glsl (std430, 96 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuShadow {
    /// The light's projection x view (reversed-Z), column-major.
    pub clip_from_world: [[f32; 4]; 4],
    /// xy: the tile's origin in atlas uv, zw: its size in atlas uv.
    pub tile: [f32; 4],
    /// x: normal offset (world units, per unit of distance for spot lights), y: 1 for spot
    /// (perspective), z: PCF radius in tile texels, w: one texel in atlas uv.
    pub params: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<GpuShadow>() == 96);

/// Push constants of the shadow pass, one per caster and light (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ShadowPush {
    pub clip_from_object: [[f32; 4]; 4],
}

/// Push constants of the shadow pass for alphaMode MASK casters (shadow_mask.vert/.frag, 80
/// bytes): the caster's material as well.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ShadowMaskPush {
    pub clip_from_object: [[f32; 4]; 4],
    pub material: u32,
    pub pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<ShadowMaskPush>() == 80);

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct TonemapPush {
    /// Linear scale, 2^EV (the tone curve is the pipeline's specialization constant 0).
    pub exposure: f32,
}
