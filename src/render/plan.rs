//! The plan: what a frame needs, computed from the scene and the render options before any GPU
//! work. The frame runs exactly the passes listed here; `weft plan` prints it and tests assert on
//! it. (Filament's variant filtering is the model: features no material uses are not compiled in.)

use std::fmt;

use serde::Serialize;

use crate::scene::{LightKind, Scene, Topology};

use super::{Accuracy, DebugView, RenderOptions};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(into = "&'static str")]
pub enum Pass {
    /// Compute pass, once per distinct weave, when the scene is uploaded: the coverage textures.
    Weave,
    /// Raster pass writing the G-buffer targets and depth.
    GBuffer,
    /// Depth-only raster pass: every shadow-casting light's map, one tile each of the atlas.
    Shadow,
    /// Fullscreen passes after the G-buffer (`--occlusion gtao`, when an environment lights the
    /// scene): how open each pixel's hemisphere is, from the depth buffer, for the environment's
    /// light.
    Occlusion,
    /// Fullscreen pass: lights x materials from the G-buffer into the HDR target.
    Lighting,
    /// Raster pass after lighting (alphaMode BLEND): the blended draws, back to front, each
    /// fragment lit as the lighting pass lights a pixel and blended over the HDR target.
    Transparent,
    /// Exposure, tone curve and sRGB encoding into the 8-bit target.
    Tonemap,
    /// Fullscreen pass after tone mapping (`--aa fxaa`): edge anti-aliasing of the 8-bit image.
    Antialias,
    /// Compute passes, once per environment (cached by content hash): the radiance cube and its
    /// mips, the GGX-prefiltered specular cube (its last level the irradiance); the SH on the CPU.
    Environment,
}

impl From<Pass> for &'static str {
    fn from(pass: Pass) -> &'static str {
        pass.name()
    }
}

impl Pass {
    pub fn name(self) -> &'static str {
        match self {
            Pass::Weave => "weave",
            Pass::GBuffer => "gbuffer",
            Pass::Shadow => "shadow",
            Pass::Occlusion => "occlusion",
            Pass::Lighting => "lighting",
            Pass::Transparent => "transparent",
            Pass::Tonemap => "tonemap",
            Pass::Antialias => "antialias",
            Pass::Environment => "environment",
        }
    }
}

/// How many lights of each kind the scene has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct LightCounts {
    pub directional: usize,
    pub point: usize,
    pub spot: usize,
}

/// One weave texture to build.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WeavePlan {
    pub pattern: String,
    pub width: u32,
    pub height: u32,
    pub levels: u32,
    /// How the G-buffer pass reads it (`--weave-precision`): "summed-area table WxH RGBA32F",
    /// "texture RGBA16F", "texture RGBA8" or "analytic (not read)".
    pub lookup: String,
    /// The fabric materials that share it.
    pub materials: Vec<String>,
}

/// Which parts of the fabric model any material needs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct FabricFeatures {
    /// Some weave has gaps between threads (s_g > 0).
    pub gaps: bool,
    /// Some weave darkens threads where they dive under others (shadow strength and width > 0).
    pub thread_shadowing: bool,
    /// Some material has a specular lobe (Rs > 0).
    pub fresnel: bool,
    /// Some material uses the A-S coupled diffuse instead of Lambert.
    pub coupled_diffuse: bool,
    /// The far-field two-lobe mixture is evaluated (accuracy mixture or supersampled).
    pub far_field_mixture: bool,
    /// Some material's thread colours are multiplied by one of its textures (`thread_texture`
    /// naming a texture the material has).
    pub thread_texture: bool,
    /// Some material has thread-by-thread colours (stripes, checks, tartans): the G-buffer pass
    /// reads the thread-colour buffer for it.
    pub thread_colours: bool,
}

/// What makes two weave textures identical: pattern, gap and shadow (not colour or exponents).
pub(crate) fn weave_key(fabric: &crate::fabric::FabricParams) -> [u32; 7] {
    let p = fabric.weave_push(0, 0);
    [
        p.pattern_lo,
        p.pattern_hi,
        p.cols,
        p.rows,
        p.gap.to_bits(),
        p.shadow_dist.to_bits(),
        p.shadow_strength.to_bits(),
    ]
}

/// One shadow map to render: a light that asks for shadows (directional or spot), when something
/// casts and something receives.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ShadowPlan {
    /// Index into the scene's lights.
    #[serde(skip)]
    pub light: usize,
    /// The light's name (`light` in `weft plan --json`).
    #[serde(rename = "light")]
    pub name: String,
    /// Tile size in texels (the light's request, shrunk if the atlas would exceed
    /// [`MAX_ATLAS`]).
    pub resolution: u32,
    pub filter_radius: f32,
    pub bias: f32,
}

/// The largest shadow atlas side, in texels (every Vulkan device supports 4096; lavapipe and
/// desktop GPUs 16384).
pub const MAX_ATLAS: u32 = 8192;

/// Pixels per opaque triangle from which the G-buffer's depth pre-pass pays: drawing every
/// triangle twice costs vertex and setup work, shading each pixel once saves fragment work.
/// Measured on lavapipe (G-buffer ms without → with, docs/performance.md "A depth pre-pass"):
/// the default scene (26 k triangles) at 2.2 pixels a triangle 15.9 → 16.1, at 8.7 35.0 → 28.1;
/// MetalRoughSpheresNoTextures (1.04 M) at 2.0 414 → 448, at 8.0 777 → 695; DamagedHelmet (15
/// k) at 3.7 12.8 → 10.8, at 15 23.4 → 21.9.
pub const PREPASS_PIXELS_PER_TRIANGLE: usize = 4;

/// `weft plan --json` is this struct serialised (`serde_json::to_value(&plan)`), with the
/// scene's animations and the LIGHT_TYPES mask added by the command.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Plan {
    pub width: u32,
    pub height: u32,
    /// The passes of one frame.
    pub passes: Vec<Pass>,
    /// Frames per image side (`--aa ssN`: N, the image the mean of N² frames at sub-pixel
    /// offsets, each running `passes`; 1 otherwise).
    pub supersample: u32,
    pub draws: usize,
    /// Draws hidden in this pose (KHR_node_visibility): planned for, drawn by no pass.
    pub hidden_draws: usize,
    pub triangles: usize,
    /// Draws of line and point primitives (glTF LINES, LINE_LOOP, LINE_STRIP, POINTS): drawn 1
    /// pixel wide by the G-buffer pass with pipelines of their own topology, casting no shadow.
    pub line_draws: usize,
    pub point_draws: usize,
    pub lights: LightCounts,
    /// Materials that use the fabric model (the rest use glTF metallic-roughness).
    pub fabric_materials: usize,
    /// Materials with KHR_materials_sheen, non-default KHR_materials_specular / _ior, and
    /// KHR_materials_anisotropy.
    pub sheen_materials: usize,
    pub specular_materials: usize,
    pub anisotropic_materials: usize,
    /// Materials with KHR_materials_unlit, and whether lighting.frag compiles the unlit path in
    /// (some material is unlit, or forced).
    pub unlit_materials: usize,
    #[serde(rename = "unlit_code")]
    pub unlit: bool,
    /// Drawn meshes with vertex colours (COLOR_0), and whether the G-buffer pass reads them
    /// (some mesh has them, or forced): without, no colour buffer is read and nothing multiplied.
    pub vertex_color_meshes: usize,
    #[serde(rename = "vertex_color_code")]
    pub vertex_colors: bool,
    /// alphaMode MASK: drawn draws with a MASK material, whether gbuffer.frag compiles the
    /// discard in (some, or forced), and the cut-out casters: MASK and BLEND draws that cast (the
    /// shadow pass then makes and uses its cut-out pipeline for them, when it runs; BLEND is cut
    /// at alpha 0.5).
    pub mask_draws: usize,
    #[serde(rename = "alpha_mask_code")]
    pub alpha_mask: bool,
    pub mask_casters: usize,
    /// alphaMode BLEND: drawn draws with a BLEND material (the transparent pass runs when there
    /// is one; they are not in the G-buffer).
    pub blend_draws: usize,
    /// KHR_materials_transmission: drawn draws with a transmissive material (the transparent pass
    /// draws them too, and copies the lit opaque image into a mip-mapped backdrop for them).
    pub transmission_draws: usize,
    /// KHR_materials_clearcoat: drawn draws with a coated material (the transparent pass draws
    /// them: the G-buffer has no room for a coat).
    pub coat_draws: usize,
    /// KHR_materials_diffuse_transmission: drawn draws with such a material (the transparent
    /// pass draws them).
    pub diffuse_transmission_draws: usize,
    /// Fabric sheets (`WEFT_materials_fabric` `transmission`): drawn draws whose cloth lets light
    /// through its gaps and threads (the transparent pass blends them by their thread coverage).
    pub sheet_draws: usize,
    /// Whether the forward pass compiles the sheets' code (FABRIC_SHEETS).
    pub fabric_sheets: bool,
    /// KHR_materials_iridescence: drawn draws with a thin film (the transparent pass draws
    /// them: the G-buffer has no room for a film).
    pub iridescence_draws: usize,
    /// KHR_materials_dispersion: drawn draws whose transmissive volume disperses (three refracted
    /// rays where one would do).
    pub dispersion_draws: usize,
    /// Draws the transparent pass draws opaque, writing depth: transmissive, coated, diffusely
    /// transmissive or iridescent, not BLEND.
    pub forward_opaque_draws: usize,
    /// Draws of fabric the transparent pass draws (blended or sheets): without any, its pipelines
    /// use forward_gltf.frag, the module without the woven model.
    pub forward_woven_draws: usize,
    /// EXT_mesh_gpu_instancing: nodes with instances, and the instances (each drawn as a draw of
    /// its own, counted in `draws`; no pipeline or pass of its own).
    pub instanced_nodes: usize,
    pub instances: usize,
    /// The camera the frame renders with: its name and projection (an orthographic camera needs
    /// no code of its own, only its projection matrix).
    pub camera: String,
    /// KHR_materials_variants: the file's variants and the one loaded (None: the defaults).
    pub variants: Vec<String>,
    pub variant: Option<String>,
    /// The file's glTF scenes and the one drawn (listed when it has more than one).
    pub gltf_scenes: Vec<String>,
    pub gltf_scene: Option<usize>,
    /// One per distinct weave (materials differing only in colour or exponents share one).
    pub weaves: Vec<WeavePlan>,
    pub features: FabricFeatures,
    /// Shadow maps to render (empty: no shadow pass and no shadow sampling).
    pub shadows: Vec<ShadowPlan>,
    /// Draws that cast and that receive shadows.
    pub shadow_casters: usize,
    pub shadow_receivers: usize,
    /// Whether lighting.frag samples shadow maps (some are planned, or forced).
    pub shadow_sampling: bool,
    /// Whether point and spot lights out of range are skipped per pixel (on unless forced off).
    pub range_culling: bool,
    /// Whether the light lists may also be sliced by view distance (render::tiles): range
    /// culling is on and the scene has at least `tiles::SLICE_FROM` lights (with fewer no tile can
    /// list that many, and the slices' code is not compiled).
    pub light_slices: bool,
    pub textures: usize,
    /// The texture slots ([`crate::scene::TextureSlot`], a bit each) some material has a texture
    /// in: gbuffer.frag samples only these (every material reads the 1x1 stand-in elsewhere, whose
    /// value the shader knows). All of them when forced.
    pub texture_slots: u32,
    /// Draws the G-buffer pass holds, by kind of material: fabric (the woven model) and glTF.
    /// With `material_kinds`, each kind is drawn by a G-buffer pipeline of its own, with the other
    /// kind's code compiled out, and the lighting pass shades each kind of pixel with a pipeline
    /// of its own (the G-buffer's stencil says which pixel is which); without (forced), one
    /// pipeline of each pass runs every kind's code.
    pub woven_draws: usize,
    pub gltf_draws: usize,
    /// The G-buffer pass's depth pre-pass: how many draws it draws depth-only first (its opaque
    /// triangle draws, MASK ones aside: their depth depends on the cut-out), so that the
    /// G-buffer shading runs once per pixel (then drawn with depth test GREATER_OR_EQUAL). 0:
    /// none. Planned where the frame has at least [`PREPASS_PIXELS_PER_TRIANGLE`] pixels per
    /// triangle of those draws (where fragments, not vertices, are the G-buffer's cost);
    /// `Force::depth_prepass` runs it anyway, where it must change no pixel,
    /// `Force::no_depth_prepass` skips it.
    pub depth_prepass: usize,
    #[serde(rename = "material_kinds_code")]
    pub material_kinds: bool,
    /// With the anti-aliasing pass: its edge search only on the 4 x 4 blocks that hold an edge
    /// (a first draw copies the pixels off an edge and marks them in the G-buffer's stencil;
    /// fxaa.frag then runs where no mark is), on a device with a depth-stencil format;
    /// `Force::fxaa_everywhere` runs it over every pixel instead, which must change no pixel.
    pub antialias_edge_blocks: bool,
    /// The glTF extensions the lighting compiles in (lighting.frag's GLTF_FEATURES: 1
    /// KHR_materials_sheen, 2 KHR_materials_anisotropy): those some deferred glTF material has
    /// (every one when fabric is shaded as glTF, or forced).
    pub gltf_features: u32,
    /// Of `textures`, those that carry their KTX2 file's full mip chain as BC7 (uploaded as BC7
    /// where the device samples it, else as RGBA8 with built mips).
    pub bc7_textures: usize,
    #[serde(serialize_with = "debug_view_name")]
    pub debug_view: DebugView,
    /// The tone curve compiled in (`--tonemap`'s name; "passthrough" for a debug view), into
    /// the tonemap pass's pipeline or, with `tone_in_lighting`, the lighting pass's: the others
    /// are in neither.
    pub tone_curve: &'static str,
    /// The lighting pass applies the tone curve and writes the 8-bit image itself, and the
    /// tonemap pass does not run: nothing reads the HDR image (no transparent pass blends over
    /// it, no HDR readback: `RenderOptions::read_hdr`, `weft render --exr`), unless forced
    /// (`Force::tonemap_pass`).
    pub tone_in_lighting: bool,
    /// The environment that lights the scene, if any.
    pub environment: Option<EnvPlan>,
    /// Screen-space occlusion of the environment's light (with an environment and
    /// `--occlusion gtao`, or for the occlusion debug view).
    pub occlusion: Option<OcclusionPlan>,
    /// World bounds of what casts shadows (of the whole scene when nothing casts): what the
    /// shadow maps cover and what the default occlusion radius is a share of. Computed only
    /// when one of them needs it (None otherwise, and for a scene with nothing to draw).
    #[serde(skip)]
    pub caster_bounds: Option<crate::scene::Bounds>,
}

/// The texture slots of a TEXTURE_SLOTS mask, by name ("none" for none).
fn slot_names(mask: u32) -> String {
    let names: Vec<&str> = crate::scene::TextureSlot::NAMES
        .iter()
        .enumerate()
        .filter(|(i, _)| mask & (1 << i) != 0)
        .map(|(_, n)| *n)
        .collect();
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}

fn debug_view_name<S: serde::Serializer>(view: &DebugView, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(view.name())
}

/// Screen-space occlusion of the environment in a frame (the occlusion pass).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OcclusionPlan {
    /// "gtao" (with the occluders' bounced light) or "gtao-nobounce".
    pub method: &'static str,
    /// The occluders' bounced light as the screen shows it (occlusion.frag's BOUNCE;
    /// lighting.frag's OCCLUSION bit 1): asked for (`gtao`, `gtao-screen`) and not carried by
    /// the world light alone ([`OcclusionPlan::world_bounce`]).
    pub bounce: bool,
    /// How far occluders count, in world units (the last 60 % falling off), and whether it is
    /// the scene's (0.3 of its diagonal) or `--occlusion gtao:R`'s.
    pub radius: f32,
    pub radius_from: &'static str,
    /// Slices per pixel and depth samples per side of each (occlusion.frag's SLICES and STEPS).
    pub slices: u32,
    pub steps: u32,
    /// The estimates and their blur drawn only where a surface is (against a half-resolution
    /// depth attachment, depth test LESS at the far plane); `Force::occlusion_everywhere` draws
    /// them over every pixel.
    pub covered_only: bool,
    /// The world light baked per vertex (`--occlusion gtao`, render::world_light), when the
    /// scene allows it.
    pub world: Option<WorldLightPlan>,
    /// Why the world light was asked for and is not planned.
    pub world_off: Option<String>,
}

/// The world light of a frame (render::world_light): rays from each receiving vertex against
/// the occluding triangles, interpolated by the G-buffer into its specular target.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WorldLightPlan {
    pub vertices: usize,
    pub triangles: usize,
    pub rays_per_vertex: u32,
    /// The longest edge of a receiving triangle, world units (`world_light::longest_receiving_edge`).
    pub longest_edge: f32,
}

impl WorldLightPlan {
    /// The world light for `scene`, or why not: it needs a static scene (its bake holds for one
    /// pose), the G-buffer's specular target free (no material with KHR_materials_specular's
    /// factor, colour or textures), something to receive and to occlude, and at most
    /// `world_light::MAX_RAYS` rays.
    pub fn new(scene: &Scene) -> Result<WorldLightPlan, String> {
        use super::world_light::{extent, receives, MAX_RAYS, RAYS};
        if !scene.rig.animations.is_empty() || !scene.rig.meshes.is_empty() {
            return Err("the scene animates or deforms (a bake holds for one pose)".into());
        }
        let specular = scene.draws.iter().filter(|d| receives(scene, d)).any(|d| {
            scene.drawn_material(d).is_some_and(|m| {
                let s = &m.specular;
                m.fabric.is_none()
                    && (s.factor != 1.0
                        || s.color != [1.0; 3]
                        || s.texture.is_some()
                        || s.color_texture.is_some())
            })
        });
        if specular {
            return Err(
                "a material has KHR_materials_specular's data, which the G-buffer's specular target holds".into(),
            );
        }
        let (vertices, triangles) = extent(scene);
        if vertices == 0 || triangles == 0 {
            return Err("nothing both receives and occludes".into());
        }
        let rays = vertices as u64 * RAYS as u64;
        if rays > MAX_RAYS {
            return Err(format!(
                "{vertices} vertices would take {rays} rays, over the {MAX_RAYS} a bake may cast"
            ));
        }
        Ok(WorldLightPlan {
            vertices,
            triangles,
            rays_per_vertex: RAYS,
            longest_edge: super::world_light::longest_receiving_edge(scene),
        })
    }
}

impl OcclusionPlan {
    pub const SLICES: u32 = 2;
    pub const STEPS: u32 = 6;
    /// The world light carries the occluders' light alone where every receiving triangle's
    /// longest edge is at most this share of the occlusion radius: occluders nearer than a
    /// vertex's edges count in proportion to their distance there (world_light's `reach`), so
    /// what the screen's bounce would add is what lies within a quarter of its radius of a coarse
    /// vertex. Measured (`weft fidelity`, all 37 scenarios against Cycles, and SheenChair,
    /// SheenCloth and Duck against STELLAR): the world light with and without the screen's bounce
    /// within 0.2 dB on every scenario, the medians the same (docs/fidelity.md, "Does the
    /// screen's bounce still add anything beside the world light?").
    pub const WORLD_BOUNCE_EDGE: f32 = 0.25;

    /// Whether the world light carries the occluders' light alone: it is planned (only ever
    /// with the bounce asked for) and the screen's bounce is not, because every receiving
    /// triangle's longest edge is within [`OcclusionPlan::WORLD_BOUNCE_EDGE`] of the radius: the
    /// screen's bounce (which the lighting would take the greater of) adds nothing its vertices
    /// do not hold, and the occlusion pass leaves it out.
    pub fn world_bounce(&self) -> bool {
        self.world.is_some() && !self.bounce
    }

    /// lighting.frag's OCCLUSION: any bit the visibility, bit 1 the screen's bounce, bit 2 the
    /// world light.
    pub fn lighting_code(&self) -> u32 {
        match (self.world.is_some(), self.bounce) {
            (false, false) => 1,
            (false, true) => 2,
            (true, false) => 4,
            (true, true) => 6,
        }
    }
}

/// Environment lighting of a frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EnvPlan {
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// Face size of the radiance cube (and its levels), of the specular cube (and its levels).
    #[serde(rename = "radiance_cube")]
    pub radiance_size: u32,
    pub radiance_levels: u32,
    #[serde(rename = "specular_cube")]
    pub specular_size: u32,
    pub specular_levels: u32,
    /// The IBL level (approx, fis:N, mc:N).
    #[serde(rename = "ibl")]
    pub level: String,
    pub rotation: f32,
    pub intensity: f32,
    pub background: String,
    /// Fabric records whose lobes' exact albedo is tabulated (weft::reference::lobe_albedo): one
    /// per fabric material at the approx and fis levels when the woven model shades the fabric,
    /// none for Monte Carlo, the fabric shaded as glTF or the comparison models.
    pub lobe_albedo_tables: usize,
    /// At fis, where the woven model shades fabric in the deferred pass: the radius within which
    /// pixels whose surface agrees pool their lobe samples (fabric_lobes.frag, lighting.frag's
    /// POOL); 0: none.
    pub pool: u32,
}

/// lighting.frag's GLTF_FEATURES bits (frame.glsl's GLTF_FEATURE_*).
pub const GLTF_SHEEN: u32 = 1;
pub const GLTF_ANISOTROPY: u32 = 2;
pub const GLTF_FEATURES_ALL: u32 = 3;

impl Plan {
    /// The light types present, as lighting.frag's LIGHT_TYPES bits (1 directional, 2 point,
    /// 4 spot). A scene with no lights compiles no light code at all.
    pub fn light_types_mask(&self) -> u32 {
        (self.lights.directional > 0) as u32
            | ((self.lights.point > 0) as u32) << 1
            | ((self.lights.spot > 0) as u32) << 2
    }

    pub fn new(scene: &Scene, options: &RenderOptions) -> Plan {
        let mut lights = LightCounts::default();
        for l in &scene.lights {
            match l.kind {
                LightKind::Directional => lights.directional += 1,
                LightKind::Point => lights.point += 1,
                LightKind::Spot { .. } => lights.spot += 1,
            }
        }
        let topology = |d: &crate::scene::Draw| {
            scene
                .meshes
                .get(d.mesh)
                .map_or(Topology::Triangles, |m| m.topology)
        };
        let triangles = scene
            .draws
            .iter()
            .filter(|d| topology(d) == Topology::Triangles)
            .map(|d| scene.meshes[d.mesh].indices.len() / 3)
            .sum();
        let line_draws = scene
            .draws
            .iter()
            .filter(|d| topology(d) == Topology::Lines)
            .count();
        let point_draws = scene
            .draws
            .iter()
            .filter(|d| topology(d) == Topology::Points)
            .count();
        let mut keys = Vec::new();
        let mut weaves: Vec<WeavePlan> = Vec::new();
        let mut features = FabricFeatures::default();
        for m in &scene.materials {
            let Some(f) = &m.fabric else { continue };
            let g = f.to_gpu();
            features.gaps |= g.gap > 0.0;
            features.thread_shadowing |= g.shadow_strength > 0.0 && g.shadow_dist > 0.0;
            features.fresnel |= g.rs > 0.0;
            features.coupled_diffuse |= f.coupled_diffuse;
            features.thread_colours |= f.has_thread_colours();
            features.thread_texture |= match f.thread_texture {
                crate::fabric::ThreadTexture::BaseColor => m.base_color_texture.is_some(),
                crate::fabric::ThreadTexture::SheenColor => {
                    m.sheen.as_ref().is_some_and(|s| s.color_texture.is_some())
                }
                crate::fabric::ThreadTexture::None => false,
            };
            let key = weave_key(f);
            match keys.iter().position(|k| *k == key) {
                Some(i) => weaves[i].materials.push(m.name.clone()),
                None => {
                    keys.push(key);
                    let (width, height) = crate::fabric::weave_level0_size(&f.pattern);
                    weaves.push(WeavePlan {
                        pattern: f.pattern.name(),
                        width,
                        height,
                        levels: crate::fabric::weave_mip_count((width, height)),
                        lookup: match options.weave_precision {
                            super::WeavePrecision::Sat => {
                                let (w, h) = crate::fabric::WeaveSat::size_for(
                                    f.pattern.cols() as u32,
                                    f.pattern.rows() as u32,
                                    (width, height),
                                );
                                format!("summed-area table {w}x{h} RGBA32F")
                            }
                            super::WeavePrecision::Rgba16f => "texture RGBA16F".into(),
                            super::WeavePrecision::Rgba8 => "texture RGBA8".into(),
                            super::WeavePrecision::Analytic => "analytic (not read)".into(),
                        },
                        materials: vec![m.name.clone()],
                    });
                }
            }
        }
        features.far_field_mixture = !weaves.is_empty()
            && matches!(
                options.accuracy,
                Accuracy::Mixture | Accuracy::Supersampled(_)
            );
        // Shadows: lights that ask (point lights cannot: the loader warned), when something casts
        // and something receives, or every light that asks when forced.
        let shadow_casters = scene.draws.iter().filter(|d| d.cast_shadows).count();
        let shadow_receivers = scene.draws.iter().filter(|d| d.receive_shadows).count();
        let useful = shadow_casters > 0 && shadow_receivers > 0;
        let mut shadows: Vec<ShadowPlan> = scene
            .lights
            .iter()
            .enumerate()
            .filter(|(_, l)| l.kind != LightKind::Point && (useful || options.force.shadows))
            .filter_map(|(i, l)| {
                l.shadow.map(|s| ShadowPlan {
                    light: i,
                    name: l.name.clone(),
                    resolution: s.resolution.clamp(1, 4096),
                    filter_radius: s.filter_radius,
                    bias: s.bias,
                })
            })
            .collect();
        // Shrink every tile alike if the atlas would be too large.
        let layout = super::shadow::AtlasLayout::new(&shadows);
        if layout.size() > MAX_ATLAS {
            let cell = MAX_ATLAS / layout.cells;
            for s in &mut shadows {
                s.resolution =
                    (s.resolution as u64 * cell as u64 / layout.cell as u64).max(1) as u32;
            }
        }
        // Draws by what their material needs.
        let material_of = |d: &crate::scene::Draw| scene.drawn_material(d);
        // (Triangles only: points and lines are the G-buffer pass's whatever their material.)
        let count = |keep: &dyn Fn(&crate::scene::Material) -> bool| {
            scene
                .draws
                .iter()
                .filter(|d| topology(d) == Topology::Triangles && material_of(d).is_some_and(keep))
                .count()
        };
        let mask_draws = count(&|m| m.alpha_cutoff.is_some());
        let mask_casters = scene
            .draws
            .iter()
            .filter(|d| {
                d.cast_shadows
                    && material_of(d).is_some_and(|m| m.alpha_cutoff.is_some() || m.blend)
            })
            .count();
        let blend_draws = count(&|m| m.blended());
        let sheet_draws = count(&|m| m.is_sheet());
        let transmission_draws = count(&|m| m.transmission.is_some());
        let forward_opaque_draws = count(&|m| m.needs_forward() && !m.blended());
        let forward_woven_draws = count(&|m| m.needs_forward() && m.fabric.is_some());
        let coat_draws = count(&|m| m.clearcoat.is_some());
        let diffuse_transmission_draws = count(&|m| m.diffuse_transmission.is_some());
        let iridescence_draws = count(&|m| m.iridescence.is_some());
        let dispersion_draws =
            count(&|m| m.transmission.as_ref().is_some_and(|t| t.dispersion > 0.0));
        // Environment preprocessing only when an environment lights the scene (debug views show
        // no lighting, so they need none either).
        let mut environment = options
            .environment
            .as_ref()
            .filter(|_| options.debug_view == DebugView::None)
            .map(|e| {
                let radiance_size = super::environment::radiance_size(e.env.width);
                // Read only where the woven model shades fabric under the environment: not with
                // the fabric shaded as glTF, nor by the paper's comparison models.
                let lobe_albedo_tables = match e.level {
                    crate::env::IblLevel::Fis(_) | crate::env::IblLevel::Approx
                        if options.shading == crate::records::Shading::Fabric
                            && !options.fabric_as_pbr =>
                    {
                        scene
                            .materials
                            .iter()
                            .filter(|m| m.fabric.is_some())
                            .count()
                    }
                    _ => 0,
                };
                EnvPlan {
                    name: e.env.name.clone(),
                    width: e.env.width,
                    height: e.env.height,
                    radiance_size,
                    radiance_levels: 32 - radiance_size.leading_zeros(),
                    specular_size: super::environment::SPECULAR_SIZE,
                    specular_levels: super::environment::SPECULAR_LEVELS,
                    level: e.level.name(),
                    rotation: e.rotation,
                    intensity: e.intensity,
                    background: match e.background {
                        crate::env::Background::Env { blur } if blur > 0.0 => {
                            format!("environment, blurred {blur}")
                        }
                        crate::env::Background::Env { .. } => "environment".into(),
                        crate::env::Background::Color(c) => format!("colour {c:?}"),
                        crate::env::Background::None => "transparent".into(),
                    },
                    lobe_albedo_tables,
                    // Where fis estimates the woven model's lobes (which read the tables).
                    pool: if matches!(e.level, crate::env::IblLevel::Fis(_))
                        && lobe_albedo_tables > 0
                    {
                        e.pool.min(crate::env::MAX_POOL)
                    } else {
                        0
                    },
                }
            });
        // Occlusion of the environment's light, when there is one (or the debug view shows it).
        let (occlusion_radius, bounce, world) = match options.occlusion {
            super::Occlusion::Gtao {
                radius,
                bounce,
                world,
            } if environment.is_some() || options.debug_view == DebugView::Occlusion => (
                Some(radius),
                bounce,
                world && bounce && environment.is_some(),
            ),
            _ => (None, false, false),
        };
        let world_light = world.then(|| WorldLightPlan::new(scene));
        // What casts (the whole scene when nothing does), once per frame, only when shadow maps
        // must cover it or the occlusion radius is a share of it.
        let caster_bounds = if !shadows.is_empty() || occlusion_radius == Some(None) {
            scene.caster_bounds().or_else(|| scene.bounds())
        } else {
            None
        };
        let occlusion = match occlusion_radius {
            Some(radius) => {
                let scene_radius = || {
                    caster_bounds
                        .map(|b| (b.max - b.min).length() * super::Occlusion::RADIUS_OF_DIAGONAL)
                        .filter(|r| r.is_finite() && *r > 0.0)
                        .unwrap_or(1.0)
                };
                let given = radius.is_some();
                let radius = radius.unwrap_or_else(scene_radius);
                let world_bounce = bounce
                    && !options.force.screen_bounce
                    && world_light.as_ref().is_some_and(|w| {
                        w.as_ref().is_ok_and(|w| {
                            w.longest_edge <= OcclusionPlan::WORLD_BOUNCE_EDGE * radius
                        })
                    });
                Some(OcclusionPlan {
                    method: if bounce { "gtao" } else { "gtao-nobounce" },
                    bounce: bounce && !world_bounce,
                    radius,
                    radius_from: if given {
                        "--occlusion"
                    } else {
                        "0.3 of the scene's diagonal"
                    },
                    slices: OcclusionPlan::SLICES,
                    steps: OcclusionPlan::STEPS,
                    covered_only: !options.force.occlusion_everywhere,
                    world: world_light.clone().and_then(Result::ok),
                    world_off: world_light.clone().and_then(Result::err),
                })
            }
            _ => None,
        };
        // The lighting pass tone-maps where nothing reads the HDR image after it: saves a
        // fullscreen pass (9-14 ms of a 1080p frame on lavapipe) and the HDR target's write and read.
        let tone_in_lighting = blend_draws + forward_opaque_draws == 0
            && !options.read_hdr
            && !options.force.tonemap_pass;
        // The passes in the order a frame runs them, each only when the scene needs it.
        let passes: Vec<Pass> = [
            // Environment preprocessing when an environment lights the scene.
            (Pass::Environment, environment.is_some()),
            // The weave textures, with fabric.
            (Pass::Weave, !weaves.is_empty()),
            (Pass::GBuffer, true),
            // Shadow maps when a light asks, something casts and something receives.
            (Pass::Shadow, !shadows.is_empty()),
            // Occlusion of the environment's light from the depth buffer.
            (Pass::Occlusion, occlusion.is_some()),
            (Pass::Lighting, true),
            // What the G-buffer cannot hold: BLEND and transmissive draws.
            (Pass::Transparent, blend_draws + forward_opaque_draws > 0),
            // Exposure and the tone curve, where the lighting pass does not apply them itself.
            (Pass::Tonemap, !tone_in_lighting),
            // Edge anti-aliasing of the shaded image (debug views show the G-buffer as it is).
            (
                Pass::Antialias,
                options.antialias == super::Antialias::Fxaa
                    && options.debug_view == DebugView::None,
            ),
        ]
        .into_iter()
        .filter(|(_, runs)| *runs)
        .map(|(pass, _)| pass)
        .collect();
        let antialias_edge_blocks =
            passes.contains(&Pass::Antialias) && !options.force.fxaa_everywhere;
        let unlit_materials = scene.materials.iter().filter(|m| m.unlit).count();
        // The G-buffer's draws by kind of material (lines and points are its whatever their
        // material).
        let deferred = |woven: bool| {
            scene
                .draws
                .iter()
                .filter(|d| {
                    let m = material_of(d);
                    let forward =
                        topology(d) == Topology::Triangles && m.is_some_and(|m| m.needs_forward());
                    !forward && m.is_some_and(|m| m.fabric.is_some()) == woven
                })
                .count()
        };
        let (woven_draws, gltf_draws) = (deferred(true), deferred(false));
        // The depth pre-pass' draws: opaque triangles the G-buffer draws (as the pass picks them:
        // GpuDraw's alpha_mask and forward).
        let prepassed: Vec<&crate::scene::Draw> = scene
            .draws
            .iter()
            .filter(|d| {
                topology(d) == Topology::Triangles
                    && material_of(d)
                        .is_some_and(|m| !m.needs_forward() && m.alpha_cutoff.is_none() && !m.blend)
            })
            .collect();
        let prepassed_triangles: usize = prepassed
            .iter()
            .map(|d| scene.meshes[d.mesh].indices.len() / 3)
            .sum();
        let pixels = options.width as usize * options.height as usize;
        let pays =
            !prepassed.is_empty() && pixels >= PREPASS_PIXELS_PER_TRIANGLE * prepassed_triangles;
        let depth_prepass =
            if options.force.no_depth_prepass || !(pays || options.force.depth_prepass) {
                0
            } else {
                prepassed.len()
            };
        // The lobes are pooled where the deferred pass shades woven pixels: a scene whose fabric
        // is all forward-lit (sheets) has none to pool, no lobe sums draw and no target for it.
        if woven_draws == 0 {
            if let Some(e) = environment.as_mut() {
                e.pool = 0;
            }
        }
        let all_kinds = options.force.material_kinds;
        let texture_slots = if all_kinds {
            (1u32 << crate::scene::TextureSlot::COUNT) - 1
        } else {
            scene.materials.iter().fold(0u32, |bits, m| {
                m.textures()
                    .iter()
                    .enumerate()
                    .filter(|(_, t)| t.is_some())
                    .fold(bits, |bits, (slot, _)| bits | 1 << slot)
            })
        };
        let gltf_like = |m: &&crate::scene::Material| m.fabric.is_none() || options.fabric_as_pbr;
        let gltf_features = if all_kinds || (options.fabric_as_pbr && woven_draws > 0) {
            GLTF_FEATURES_ALL
        } else {
            let has = |f: &dyn Fn(&crate::scene::Material) -> bool| {
                scene.materials.iter().filter(gltf_like).any(f)
            };
            (if has(&|m| m.sheen.is_some()) {
                GLTF_SHEEN
            } else {
                0
            }) | (if has(&|m| m.anisotropy.is_some()) {
                GLTF_ANISOTROPY
            } else {
                0
            })
        };
        let mut drawn = vec![false; scene.meshes.len()];
        for d in &scene.draws {
            if let Some(x) = drawn.get_mut(d.mesh) {
                *x = true;
            }
        }
        let vertex_color_meshes = scene
            .meshes
            .iter()
            .zip(&drawn)
            .filter(|(m, &drawn)| drawn && !m.colors.is_empty())
            .count();
        Plan {
            width: options.width,
            mask_draws,
            alpha_mask: mask_draws > 0 || options.force.alpha_mask,
            mask_casters,
            blend_draws,
            transmission_draws,
            forward_opaque_draws,
            forward_woven_draws,
            coat_draws,
            diffuse_transmission_draws,
            sheet_draws,
            fabric_sheets: sheet_draws > 0 || options.force.fabric_sheets,
            iridescence_draws,
            dispersion_draws,
            unlit_materials,
            unlit: unlit_materials > 0 || options.force.unlit,
            vertex_color_meshes,
            vertex_colors: vertex_color_meshes > 0 || options.force.vertex_colors,
            // The automatic framing is described without fitting it (the fit reads every
            // vertex, and the plan is made every frame).
            camera: match options.camera_override.clone().map(Ok).unwrap_or_else(|| {
                if scene.camera_is_automatic(options.camera) {
                    Err(None)
                } else {
                    scene.camera(options.camera).map_err(Some)
                }
            }) {
                Err(None) => format!(
                    "'{}', perspective (yfov {:.1}°)",
                    crate::scene::AUTO_FRAMING_NAME,
                    crate::scene::AUTO_FRAMING_YFOV_DEGREES
                ),
                Ok(c) => match c.orthographic {
                    Some([x, y]) => format!("'{}', orthographic (xmag {x}, ymag {y})", c.name),
                    None => format!(
                        "'{}', perspective (yfov {:.1}°)",
                        c.name,
                        c.yfov.to_degrees()
                    ),
                },
                Err(Some(_)) => "none (the index is out of range)".into(),
            },
            instanced_nodes: scene.instanced_nodes,
            instances: scene.instances,
            height: options.height,
            passes,
            draws: scene.draws.len(),
            hidden_draws: scene.draws.iter().filter(|d| !d.visible).count(),
            triangles,
            line_draws,
            point_draws,
            lights,
            sheen_materials: scene
                .materials
                .iter()
                .filter(|m| m.fabric.is_none() && m.sheen.is_some())
                .count(),
            specular_materials: scene
                .materials
                .iter()
                .filter(|m| m.fabric.is_none() && m.specular != crate::scene::Specular::default())
                .count(),
            anisotropic_materials: scene
                .materials
                .iter()
                .filter(|m| m.fabric.is_none() && m.anisotropy.is_some())
                .count(),
            variants: scene.variants.clone(),
            variant: scene.variant.clone(),
            gltf_scenes: scene.gltf_scenes.clone(),
            gltf_scene: scene.gltf_scene,
            fabric_materials: scene
                .materials
                .iter()
                .filter(|m| m.fabric.is_some())
                .count(),
            weaves,
            features,
            shadow_sampling: !shadows.is_empty() || options.force.shadows,
            shadows,
            shadow_casters,
            shadow_receivers,
            range_culling: !options.force.no_range_culling,
            light_slices: !options.force.no_range_culling
                && scene.lights.len() as f64 >= super::tiles::SLICE_FROM,
            textures: scene.textures.len(),
            texture_slots,
            woven_draws,
            depth_prepass,
            gltf_draws,
            material_kinds: !all_kinds,
            antialias_edge_blocks,
            gltf_features,
            bc7_textures: scene.textures.iter().filter(|t| t.bc7.is_some()).count(),
            debug_view: options.debug_view,
            tone_curve: match super::passes::tonemap::TonemapPass::curve(options) {
                super::passes::tonemap::CURVE_PASSTHROUGH => "passthrough",
                _ => options.tonemap.name(),
            },
            tone_in_lighting,
            supersample: options.supersample(),
            environment,
            occlusion,
            caster_bounds,
        }
    }

    /// lighting.frag's IBL constant: 0 without an environment.
    /// lighting.frag's RANGE_CULLING: 0 off, 1 per tile, 2 per tile and slice of view distance.
    pub fn range_code(&self) -> u32 {
        match (self.range_culling, self.light_slices) {
            (false, _) => 0,
            (true, false) => 1,
            (true, true) => 2,
        }
    }

    /// lighting.frag's and fabric_lobes.frag's POOL: the plan's radius, or 1 where forced on
    /// (`Force::pool`) and the plan has none.
    pub fn pool_code(&self, options: &RenderOptions) -> u32 {
        match self.environment.as_ref().map_or(0, |e| e.pool) {
            0 => options.force.pool as u32,
            r => r,
        }
    }

    pub fn ibl_code(&self, options: &RenderOptions) -> u32 {
        match (&self.environment, &options.environment) {
            (Some(_), Some(e)) => e.level.code(),
            _ => 0,
        }
    }

    pub fn runs(&self, pass: Pass) -> bool {
        self.passes.contains(&pass)
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "output      {}x{}", self.width, self.height)?;
        writeln!(
            f,
            "passes      {}",
            self.passes
                .iter()
                .map(|p| p.name())
                .collect::<Vec<_>>()
                .join(" -> ")
        )?;
        writeln!(
            f,
            "draws       {} ({} triangles){}",
            self.draws,
            self.triangles,
            if self.hidden_draws > 0 {
                format!(
                    "; {} hidden (KHR_node_visibility: planned, drawn by no pass)",
                    self.hidden_draws
                )
            } else {
                String::new()
            }
        )?;
        if self.line_draws + self.point_draws > 0 {
            writeln!(
                f,
                "primitives  {} line and {} point draw(s): 1 pixel wide, G-buffer pipelines of their own topology, no shadows",
                self.line_draws, self.point_draws
            )?;
        }
        writeln!(f, "camera      {}", self.camera)?;
        if self.instanced_nodes > 0 {
            writeln!(
                f,
                "instancing  {} instance(s) on {} node(s) (EXT_mesh_gpu_instancing), one draw each",
                self.instances, self.instanced_nodes
            )?;
        }
        writeln!(
            f,
            "lights      {} directional, {} point, {} spot",
            self.lights.directional, self.lights.point, self.lights.spot
        )?;
        writeln!(
            f,
            "materials   {} fabric, {} sheen, {} specular, {} anisotropic, {} unlit (unlit code {})",
            self.fabric_materials,
            self.sheen_materials,
            self.specular_materials,
            self.anisotropic_materials,
            self.unlit_materials,
            if self.unlit { "compiled" } else { "none" }
        )?;
        writeln!(
            f,
            "kinds       {} fabric and {} glTF draw(s) in the G-buffer: {}; texture slots sampled: {}; glTF extension code: {}",
            self.woven_draws,
            self.gltf_draws,
            if self.material_kinds {
                "a G-buffer and a lighting pipeline per kind, each with only its own code"
            } else {
                "one pipeline of each pass with every kind's code (forced)"
            },
            slot_names(self.texture_slots),
            match self.gltf_features {
                0 => "none".to_string(),
                f => [(GLTF_SHEEN, "sheen"), (GLTF_ANISOTROPY, "anisotropy")]
                    .iter()
                    .filter(|(bit, _)| f & bit != 0)
                    .map(|(_, n)| *n)
                    .collect::<Vec<_>>()
                    .join(", "),
            }
        )?;
        if self.depth_prepass > 0 {
            writeln!(
                f,
                "depth       a depth pre-pass of {} opaque draw(s) before the G-buffer's shading, which then runs once per pixel (depth test GREATER_OR_EQUAL; planned from {} pixels per triangle)",
                self.depth_prepass, PREPASS_PIXELS_PER_TRIANGLE
            )?;
        }
        writeln!(
            f,
            "alpha mask  {} draw(s) with alphaMode MASK; {} cut-out caster(s) (MASK, BLEND at alpha 0.5) (cut-out code {}{})",
            self.mask_draws,
            self.mask_casters,
            if self.alpha_mask { "compiled" } else { "none" },
            if self.mask_casters > 0 && !self.shadows.is_empty() {
                ", cut-out shadow pipeline"
            } else {
                ""
            }
        )?;
        if self.blend_draws > 0 {
            writeln!(
                f,
                "blend       {} draw(s) blended over what is behind (alphaMode BLEND, fabric sheets): forward-lit after the lighting pass, sorted back to front by their bounds' centres",
                self.blend_draws
            )?;
        }
        if self.diffuse_transmission_draws > 0 {
            writeln!(
                f,
                "diff. trans. {} draw(s) with KHR_materials_diffuse_transmission: drawn by the transparent pass, lit from both sides",
                self.diffuse_transmission_draws
            )?;
        }
        if self.sheet_draws > 0 {
            writeln!(
                f,
                "fabric sheet {} draw(s) of cloth with nothing behind it: blended by the thread coverage (the gaps let light straight through), the threads lit from both sides",
                self.sheet_draws
            )?;
        }
        if self.dispersion_draws > 0 {
            writeln!(
                f,
                "dispersion  {} draw(s) with KHR_materials_dispersion: the backdrop read along three refracted rays",
                self.dispersion_draws
            )?;
        }
        if self.iridescence_draws > 0 {
            writeln!(
                f,
                "iridescence {} draw(s) with KHR_materials_iridescence: thin-film Fresnel, drawn by the transparent pass",
                self.iridescence_draws
            )?;
        }
        if self.coat_draws > 0 {
            writeln!(
                f,
                "clearcoat   {} draw(s) with KHR_materials_clearcoat: drawn by the transparent pass (no G-buffer bytes for coats)",
                self.coat_draws
            )?;
        }
        if self.transmission_draws > 0 {
            writeln!(
                f,
                "transmission {} draw(s) with KHR_materials_transmission: drawn by the transparent pass over a backdrop (the lit opaque image, RGBA16F {}x{} with mips)",
                self.transmission_draws, self.width, self.height
            )?;
        }
        writeln!(
            f,
            "vertex col. {} drawn mesh(es) with COLOR_0 (colour code {})",
            self.vertex_color_meshes,
            if self.vertex_colors {
                "compiled"
            } else {
                "none"
            }
        )?;
        if self.gltf_scenes.len() > 1 {
            writeln!(
                f,
                "scenes      {} (drawn: {}; --gltf-scene picks)",
                self.gltf_scenes.join(", "),
                self.gltf_scene
                    .map_or("none".to_string(), |i| i.to_string())
            )?;
        }
        if !self.variants.is_empty() {
            writeln!(
                f,
                "variants    {} (loaded: {})",
                self.variants.join(", "),
                self.variant.as_deref().unwrap_or("the file's defaults")
            )?;
        }
        for w in &self.weaves {
            let materials = w.materials.join(", ");
            writeln!(
                f,
                "weave       {} {}x{}, {} levels, read as {}, for {materials}",
                w.pattern, w.width, w.height, w.levels, w.lookup
            )?;
        }
        let ft = &self.features;
        writeln!(
            f,
            "features    gaps {}, thread shadowing {}, fresnel {}, coupled diffuse {}, far-field mixture {}, thread texture {}, thread colours {}",
            ft.gaps, ft.thread_shadowing, ft.fresnel, ft.coupled_diffuse, ft.far_field_mixture, ft.thread_texture, ft.thread_colours
        )?;
        writeln!(
            f,
            "light code  {:#05b} (1 directional, 2 point, 4 spot)",
            self.light_types_mask()
        )?;
        if self.shadows.is_empty() {
            writeln!(
                f,
                "shadows     none ({} casting, {} receiving draws)",
                self.shadow_casters, self.shadow_receivers
            )?;
        }
        for s in &self.shadows {
            writeln!(
                f,
                "shadow map  {} {r}x{r}, PCF radius {} texels, bias {} texels",
                s.name,
                s.filter_radius,
                s.bias,
                r = s.resolution
            )?;
        }
        writeln!(
            f,
            "lighting    shadow sampling {}, range culling {}{}",
            self.shadow_sampling,
            self.range_culling,
            if self.light_slices {
                " (light lists per tile and slice of view distance where tiles list many)"
            } else {
                ""
            }
        )?;
        match &self.environment {
            None => writeln!(f, "environment none (fixed hemispherical ambient)")?,
            Some(e) => writeln!(
                f,
                "environment {} {}x{}: radiance cube {}² ({} levels), specular cube {}² ({} levels, the last the irradiance: an exact sum over the radiance cube's 32² level); IBL {}, rotation {}°, intensity {}, background {}",
                e.name,
                e.width,
                e.height,
                e.radiance_size,
                e.radiance_levels,
                e.specular_size,
                e.specular_levels,
                e.level,
                e.rotation,
                e.intensity,
                e.background
            )?,
        }
        if let Some(e) = self
            .environment
            .as_ref()
            .filter(|e| e.lobe_albedo_tables > 0)
        {
            writeln!(
                f,
                "            fabric lobes: exact albedo tables for {} fabric record(s) ({} x {} views each), the look-ups give the mean radiance",
                e.lobe_albedo_tables,
                crate::env::lobe_albedo::LOBE_ALBEDO_MU,
                crate::env::lobe_albedo::LOBE_ALBEDO_PHI
            )?;
        }
        if let Some(r) = self.environment.as_ref().map(|e| e.pool).filter(|&r| r > 0) {
            let side = 2 * r + 1;
            writeln!(
                f,
                "            fabric lobes: a lobe-sums draw before the lighting; each pixel's fis samples pooled with those of the {side}x{side} pixels around it where the surface agrees (up to {}x the samples)",
                side * side
            )?;
        }
        match &self.occlusion {
            None => writeln!(
                f,
                "occlusion   none (the environment's light is darkened by occlusion textures only)"
            )?,
            Some(o) => writeln!(
                f,
                "occlusion   {} of the environment's light, radius {} ({}), at half resolution over a half-resolution depth copy: {} slices x {} steps per side per estimate, 4x4 blur, {}; {}",
                o.method,
                o.radius,
                o.radius_from,
                o.slices,
                o.steps,
                if o.covered_only {
                    "both drawn only where a surface is (against the depth copy)"
                } else {
                    "both over every pixel (forced)"
                },
                if o.bounce {
                    "the light the occluders on screen bounce, where it exceeds the multi-bounce fit"
                } else if o.world_bounce() {
                    "the occluders' light from the world light alone (every receiving triangle's edges within a quarter of the radius: the screen's bounce adds nothing its vertices do not hold; left out of the pass)"
                } else {
                    "the multi-bounce fit alone"
                }
            )?,
        }
        if let Some(o) = &self.occlusion {
            if let Some(w) = &o.world {
                writeln!(
                    f,
                    "world light baked per vertex on the CPU (once per scene and environment, then weft's cache on disk): {} vertices x {} rays against {} triangles (the visibility, then the hit surfaces' light); the G-buffer's specular target carries it, the lighting takes the lesser visibility of screen and world and {}; longest receiving edge {:.3}",
                    w.vertices,
                    w.rays_per_vertex,
                    w.triangles,
                    if o.world_bounce() {
                        "the world's bounce"
                    } else {
                        "the greater bounce of the two"
                    },
                    w.longest_edge
                )?;
            } else if let Some(why) = &o.world_off {
                writeln!(f, "world light none: {why}")?;
            }
        }
        if self.bc7_textures > 0 {
            writeln!(
                f,
                "textures    {} ({} with their file's BC7 mip chain: uploaded as BC7 where the device samples BC7)",
                self.textures, self.bc7_textures
            )?;
        } else {
            writeln!(f, "textures    {}", self.textures)?;
        }
        if self.supersample > 1 {
            let n = self.supersample;
            writeln!(
                f,
                "supersample ss{n}: {} frames at the centres of a {n}x{n} grid of sub-pixel offsets, averaged (tone-mapped in linear display light, HDR in radiance)",
                n * n
            )?;
        }
        if self.tone_in_lighting {
            writeln!(
                f,
                "tone curve  {} in the lighting pass, which writes the 8-bit image itself (nothing reads the HDR image: no transparent pass, no HDR output); the only curve compiled in",
                self.tone_curve
            )?;
        } else {
            writeln!(
                f,
                "tone curve  {} (the only curve compiled into the tonemap pass's pipeline)",
                self.tone_curve
            )?;
        }
        if self.runs(Pass::Antialias) {
            writeln!(
                f,
                "antialias   fxaa, {}",
                if self.antialias_edge_blocks {
                    "its edge search only on the 4x4 blocks with an edge: a first draw copies the pixels off an edge and marks them in the stencil (on a device with a depth-stencil format)"
                } else {
                    "its edge search over every pixel (forced)"
                }
            )?;
        }
        write!(f, "debug view  {}", self.debug_view.name())
    }
}
