//! glTF 2.0 (`.gltf` or `.glb`) into a [`Scene`].
//!
//! Order of work: parse the container and the JSON, check `extensionsRequired` against what weft
//! supports, validate the document, load the buffers, then build materials (with their textures,
//! one per image and colour space), meshes (one per triangle primitive, completed with normals and
//! MikkTSpace tangents where the file has none) and walk the node tree into draws, lights and
//! cameras with world transforms.
//!
//! A scene file is user input: every problem is an [`Error::Input`] that names the file, the
//! object (mesh, material, accessor, image, camera, light) and a fix, or a [`Warning`] when the
//! scene can still be drawn. Nothing here indexes unchecked into the file's data.

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Quat, Vec3, Vec4};
use gltf::accessor::Dimensions;
use gltf::json;
use gltf::json::validation::{Checked, Validate};
use gltf::mesh::{Mode, Semantic};

use super::accessor::{self, Use};
use super::animation::{self, MeshDeform, MorphTarget, VertexSkin};
use super::compressed;
use super::material_ext::{self, TexRef};
use super::resources;
use super::tangents::{self, UvTransform};
use super::{
    Anisotropy, Clearcoat, ColorSpace, DiffuseTransmission, Draw, Iridescence, Light, LightKind,
    Material, Mesh, Scene, Shadow, Sheen, SlotUv, Specular, Texture, TextureSampler, TextureSlot,
    Topology, Transmission, Vertex, Warning,
};
use crate::fabric::FabricParams;
use crate::{Error, Result};

mod lights;
mod materials;
mod meshes;
mod nodes;
mod pointer;
mod skins;

/// Limits that keep an absurd or hostile file from exhausting memory or time: a few hundred bytes
/// of JSON can make many primitives read one large accessor, or many nodes draw one large mesh.
/// Each is far beyond what weft renders at interactive rates; the messages say how to get under
/// them (docs/robustness.md lists them with the catalogue of bad inputs).
///
/// Vertices read, summed over primitives (a primitive reading a shared accessor counts it again):
/// 2^25, a vertex buffer of about 1.9 GiB on the GPU, under the 2 GiB single allocation that many
/// drivers (lavapipe included) allow.
pub(super) const MAX_VERTICES: usize = 1 << 25;
/// Indices read, summed over primitives: 2^28 (1 GiB of indices, 89 million triangles).
pub(super) const MAX_INDICES: usize = 1 << 28;
/// Triangles drawn, summed over every node that draws a mesh: 2^28.
pub(super) const MAX_DRAWN_TRIANGLES: u64 = 1 << 28;

/// The built-in default scene (written by `tools/make_default_scene.py`).
pub const DEFAULT_SCENE_GLB: &[u8] = include_bytes!("../../../assets/default.glb");

const DEFAULT_SCENE_SOURCE: &str = "built-in default scene";

/// The fabric material extension; its parameters are parsed by [`FabricParams`].
const FABRIC_EXTENSION: &str = "WEFT_materials_fabric";

/// KHR_animation_pointer: animation channels that drive materials, lights and cameras.
const ANIMATION_POINTER: &str = "KHR_animation_pointer";

/// KHR_node_visibility: a node's `visible` false hides it and its subtree.
const NODE_VISIBILITY: &str = "KHR_node_visibility";

/// KHR_materials_unlit: base colour only, no lighting.
const UNLIT: &str = "KHR_materials_unlit";

/// EXT_mesh_gpu_instancing: a node places its mesh once per instance (TRANSLATION, ROTATION,
/// SCALE accessors).
const INSTANCING: &str = "EXT_mesh_gpu_instancing";

/// Instances, summed over the scene's instanced nodes: 2^20 (each is a draw of its own).
pub(super) const MAX_INSTANCES: usize = 1 << 20;

/// KHR_draco_mesh_compression: a primitive's attributes and indices in one Draco bitstream.
const DRACO: &str = "KHR_draco_mesh_compression";

/// The attributes weft reads from a Draco bitstream; a primitive whose Draco data holds any other
/// is refused by name rather than read as zeros (its accessors have no data of their own).
const DRACO_SEMANTICS: [&str; 5] = ["POSITION", "NORMAL", "TANGENT", "TEXCOORD_0", "TEXCOORD_1"];

/// A primitive's decoded Draco data: the mesh, and which Draco attribute (unique id) holds each
/// glTF attribute.
struct DracoPrimitive {
    mesh: draco_core::Mesh,
    ids: HashMap<String, u32>,
}

/// Metadata extensions: they describe the file (authorship, licence) and never change the
/// picture, so using them needs no warning.
const METADATA_EXTENSIONS: &[&str] = &["KHR_xmp", "KHR_xmp_json_ld"];

/// Extensions a file may list in `extensionsRequired`.
const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    ANIMATION_POINTER,
    NODE_VISIBILITY,
    DRACO,
    UNLIT,
    INSTANCING,
    "KHR_texture_transform",
    "KHR_materials_emissive_strength",
    material_ext::SHEEN,
    material_ext::SPECULAR,
    material_ext::IOR,
    material_ext::ANISOTROPY,
    material_ext::VARIANTS,
    material_ext::TRANSMISSION,
    material_ext::VOLUME,
    material_ext::CLEARCOAT,
    material_ext::DIFFUSE_TRANSMISSION,
    material_ext::IRIDESCENCE,
    material_ext::SPEC_GLOSS,
    material_ext::DISPERSION,
    FABRIC_EXTENSION,
    // Quantized, meshopt-compressed, WebP and KTX2 data: src/scene/compressed.rs.
    compressed::EXTENSIONS[0],
    compressed::EXTENSIONS[1],
    compressed::EXTENSIONS[2],
    compressed::EXTENSIONS[3],
    compressed::EXTENSIONS[4],
];

/// What a load may choose beyond the file itself.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// KHR_materials_variants: the variant to load (by name); None loads the file's default
    /// materials.
    pub variant: Option<String>,
    /// Which of the file's scenes to draw, by index or name (`--gltf-scene`); None draws the
    /// file's `scene`, else its first.
    pub scene: Option<String>,
}

/// The scene embedded in the binary: a draped cloth over a ball on a floor, a metal ball, three
/// lights and a camera.
pub fn default_scene() -> Scene {
    load_slice(DEFAULT_SCENE_GLB, DEFAULT_SCENE_SOURCE, None)
        .expect("the built-in default scene is valid (tests/scene_loading.rs loads it)")
}

/// Loads a `.gltf` (with its external or embedded buffers and images) or a `.glb` file.
pub fn load(path: &Path) -> Result<Scene> {
    load_with(path, &LoadOptions::default())
}

/// [`load`] with options (a material variant).
pub fn load_with(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let source = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            Error::input(format!(
                "scene file '{source}' does not exist; check the path (a relative path starts at the current directory), or leave the scene out to render the built-in default scene"
            ))
        } else if path.is_dir() {
            Error::input(format!("scene file '{source}' is a directory; pass the .gltf or .glb file inside it"))
        } else {
            Error::input(format!("scene file '{source}' could not be read: {e}; check that it is a readable file"))
        }
    })?;
    let base_dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let (scene, files) =
        resources::recording_files(|| load_slice_with(&bytes, &source, Some(base_dir), options));
    let mut scene = scene?;
    scene.files = std::iter::once(path.to_path_buf()).chain(files).collect();
    Ok(scene)
}

/// Loads a scene from the bytes of a `.gltf` or `.glb` file. `source` names it in messages;
/// `base_dir` is where relative URIs (external buffers and images) are resolved: None refuses them.
pub fn load_slice(bytes: &[u8], source: &str, base_dir: Option<&Path>) -> Result<Scene> {
    load_slice_with(bytes, source, base_dir, &LoadOptions::default())
}

/// [`load_slice`] with options (a material variant).
pub fn load_slice_with(
    bytes: &[u8],
    source: &str,
    base_dir: Option<&Path>,
    options: &LoadOptions,
) -> Result<Scene> {
    // Everything below checks the file before use, but the gltf crate's accessors unwrap on
    // documents that slip past its validator; a panic there must still reach the user as an error.
    // (crate::error::catch_panic: the `weft` binary's panic hook stays quiet meanwhile.)
    match crate::error::catch_panic(|| load_checked(bytes, source, base_dir, options)) {
        Ok(result) => result,
        Err(detail) => {
            Err(Error::input(format!(
                "'{source}': the glTF reader failed on this file ({detail}); it is probably malformed: check it with the Khronos glTF Validator and re-export it"
            )))
        }
    }
}

fn load_checked(
    bytes: &[u8],
    source: &str,
    base_dir: Option<&Path>,
    options: &LoadOptions,
) -> Result<Scene> {
    let label = format!("'{source}'");
    let (mut root, glb_bin, pointers) = parse(bytes, source)?;
    let mut warnings = Vec::new();
    check_extensions(&mut root, &label, &mut warnings)?;
    compressed::choose_texture_sources(&mut root, &label)?;
    validate(&root, &label)?;
    let mut buffers = resources::load_buffers(&root, glb_bin, base_dir, &label)?;
    compressed::decode_buffer_views(&mut root, &mut buffers, &label)?;
    let doc = gltf::Document::from_json_without_validation(root);

    let variants = material_ext::variant_names(doc.extension_value(material_ext::VARIANTS))
        .map_err(|e| Error::input(format!("{label}: {e}")))?;
    let variant = match &options.variant {
        None => None,
        Some(name) => match variants.iter().position(|v| v == name) {
            Some(i) => Some(i),
            None if variants.is_empty() => {
                return Err(Error::input(format!(
                    "{label} has no material variants (KHR_materials_variants), so --variant '{name}' cannot be applied; leave --variant out"
                )))
            }
            None => {
                return Err(Error::input(format!(
                    "{label} has no material variant '{name}'; its variants are: {} (`weft plan` lists them)",
                    variants.iter().map(|v| format!("'{v}'")).collect::<Vec<_>>().join(", ")
                )))
            }
        },
    };

    let scenes: Vec<String> = doc
        .scenes()
        .map(|s| match s.name() {
            Some(n) => format!("{} '{n}'", s.index()),
            None => s.index().to_string(),
        })
        .collect();
    let chosen_scene = match &options.scene {
        None => None,
        Some(want) => {
            let by_index = want
                .parse::<usize>()
                .ok()
                .filter(|&i| i < doc.scenes().len());
            let by_name = || doc.scenes().find(|s| s.name() == Some(want.as_str()));
            match by_index.or_else(|| by_name().map(|s| s.index())) {
                Some(i) => Some(i),
                None if scenes.is_empty() => {
                    return Err(Error::input(format!(
                        "{label} has no scenes, so --gltf-scene '{want}' cannot be applied; leave --gltf-scene out"
                    )))
                }
                None => {
                    return Err(Error::input(format!(
                        "{label} has no scene '{want}'; its scenes are: {} (by index or name; `weft plan` lists them)",
                        scenes.join(", ")
                    )))
                }
            }
        }
    };

    let mut loader = Loader {
        label,
        base_dir,
        doc: &doc,
        buffers: &buffers,
        scene: Scene {
            source: source.to_owned(),
            warnings,
            variant: options.variant.clone(),
            variants: variants.clone(),
            gltf_scenes: scenes,
            ..Scene::default()
        },
        variant: variant.map(|i| (i, variants.len())),
        chosen_scene,
        textures: HashMap::new(),
        material_uv: Vec::new(),
        slot_transforms: Vec::new(),
        default_material: None,
        unlit_copies: HashMap::new(),
        mesh_ids: vec![None; doc.meshes().len()],
        lights: Vec::new(),
        cameras: Vec::new(),
        vertices_read: 0,
        indices_read: 0,
        texture_bytes_left: resources::MAX_TEXTURE_BYTES,
        triangles_drawn: 0,
        pointers,
    };
    loader.load_materials()?;
    loader.lights = loader.light_definitions()?;
    loader.cameras = loader.camera_definitions()?;
    loader.rig_nodes()?;
    loader.walk_nodes()?;
    loader.load_skins()?;
    loader.load_animations()?;
    // Skinned draws take their world from the skin; everything else keeps the walk's matrices,
    // which the rest pose reproduces.
    loader.scene.rest_pose()?;
    if loader.scene.draws.is_empty() {
        loader.warn(
            "has nothing to draw: no node of the scene places a mesh with triangles, so the image shows only the background",
        );
    }
    Ok(loader.scene)
}

/// Splits a .glb into JSON and binary chunk, or takes the bytes as .gltf JSON, and deserialises
/// the document.
fn parse(
    bytes: &[u8],
    source: &str,
) -> Result<(json::Root, Option<Vec<u8>>, pointer::PointerChannels)> {
    let not_gltf = |why: &str| {
        Error::input(format!(
            "'{source}' is not a glTF 2.0 file (.gltf JSON or .glb): {why}; pass a scene exported as glTF 2.0"
        ))
    };
    let (text, bin): (std::borrow::Cow<[u8]>, Option<Vec<u8>>) = if bytes.starts_with(b"glTF") {
        let broken = |why: &dyn std::fmt::Display| {
            Error::input(format!(
                "'{source}' starts like a binary glTF (.glb) file but its container is broken ({why}); the file is truncated or damaged: re-export it"
            ))
        };
        // The gltf crate subtracts the header's size from the declared length unchecked (an
        // overflow panic in builds with overflow checks): refuse such headers first.
        let declared = bytes
            .get(8..12)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        match declared {
            None => return Err(broken(&"the 12-byte header is incomplete")),
            Some(length) if length < 12 => {
                return Err(broken(&format_args!(
                "the header declares a total length of {length} bytes, less than the header itself"
            )))
            }
            Some(_) => {}
        }
        let glb = gltf::Glb::from_slice(bytes).map_err(|e| broken(&e))?;
        (glb.json, glb.bin.map(|b| b.into_owned()))
    } else {
        (std::borrow::Cow::Borrowed(bytes), None)
    };
    let text = text
        .strip_prefix(b"\xEF\xBB\xBF".as_slice())
        .unwrap_or(&text);
    // KHR_animation_pointer's channels are not of the schema the gltf crate knows: read apart.
    let (rewritten, pointers) = match pointer::take_channels(text) {
        Some((json, pointers)) => (Some(json), pointers),
        None => (None, pointer::PointerChannels::default()),
    };
    let text: &[u8] = rewritten.as_deref().unwrap_or(text);

    // Parsed once as glTF; only a file that does not parse is parsed again, as plain JSON, to
    // say why (large embedded buffers make a second parse cost time and peak memory).
    // serde_json refuses nesting deeper than 128 when it builds values, but captures raw
    // "extras" without that limit: the depth is checked here (a scan, no allocation), so a
    // 20000-deep "extras" is refused as before (by the plain-JSON parse's error below).
    let parsed = serde_json::from_slice::<json::Root>(text);
    let too_deep = parsed.is_ok() && json_depth(text) > 128;
    let version: Option<String> = match &parsed {
        Ok(root) if !too_deep => Some(root.asset.version.clone()),
        _ => match serde_json::from_slice::<serde_json::Value>(text) {
            Ok(value) => value
                .get("asset")
                .and_then(|a| a.get("version"))
                .and_then(|v| v.as_str())
                .map(str::to_owned),
            Err(e) => {
                let first = text.iter().find(|b| !b.is_ascii_whitespace());
                return Err(if first == Some(&b'{') {
                    not_gltf(&format!("it looks like JSON but does not parse ({e})"))
                } else {
                    not_gltf("it is neither JSON nor a .glb container")
                });
            }
        },
    };
    match version.as_deref() {
        None => return Err(not_gltf("its JSON has no \"asset\": {\"version\": \"2.0\"} object")),
        Some(v) if !v.starts_with("2.") => {
            return Err(Error::input(format!(
                "'{source}' is a glTF {v} file; weft reads glTF 2.0 only: convert it (Blender or gltf-transform can) and try again"
            )))
        }
        Some(_) => {}
    }
    let root: json::Root = parsed.map_err(|e| {
        Error::input(format!(
            "'{source}' is not a valid glTF 2.0 file: {e}; fix the JSON or re-export the scene (the Khronos glTF Validator explains such problems)"
        ))
    })?;
    Ok((root, bin, pointers))
}

/// The deepest nesting of arrays and objects in JSON text (brackets inside strings not counted).
fn json_depth(text: &[u8]) -> usize {
    let (mut depth, mut deepest) = (0usize, 0usize);
    let (mut in_string, mut escaped) = (false, false);
    for &b in text {
        if in_string {
            match (escaped, b) {
                (true, _) => escaped = false,
                (false, b'\\') => escaped = true,
                (false, b'"') => in_string = false,
                _ => {}
            }
            continue;
        }
        match b {
            b'"' => in_string = true,
            b'[' | b'{' => {
                depth += 1;
                deepest = deepest.max(depth);
            }
            b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    deepest
}

/// Refuses required extensions weft cannot honour and warns about used ones it ignores. Removes
/// weft's own extension from `extensionsRequired`, since the gltf crate's validator only knows its own.
fn check_extensions(root: &mut json::Root, label: &str, warnings: &mut Vec<Warning>) -> Result<()> {
    if let Some(ext) = root
        .extensions_required
        .iter()
        .find(|e| !SUPPORTED_EXTENSIONS.contains(&e.as_str()))
    {
        if let Some(hint) = compressed::refusal_hint(ext) {
            return Err(Error::input(format!(
                "{label} requires the glTF extension '{ext}': {hint}"
            )));
        }
        return Err(Error::input(format!(
            "{label} requires the glTF extension '{ext}', which weft does not support (it supports {}); re-export the scene without that extension (for example, turn off mesh compression in the exporter)",
            SUPPORTED_EXTENSIONS.join(", ")
        )));
    }
    for ext in &root.extensions_used {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str())
            && !METADATA_EXTENSIONS.contains(&ext.as_str())
        {
            warnings.push(Warning(format!(
                "{label} uses the glTF extension '{ext}', which weft ignores; the scene may look different than intended"
            )));
        }
    }
    // The extensions weft reads from raw JSON itself are unknown to the gltf crate's validator,
    // which refuses unknown required extensions: take them off before it runs.
    const OWN: &[&str] = &[
        FABRIC_EXTENSION,
        UNLIT,
        INSTANCING,
        material_ext::SHEEN,
        material_ext::SPECULAR,
        material_ext::IOR,
        material_ext::ANISOTROPY,
        material_ext::VARIANTS,
        material_ext::TRANSMISSION,
        material_ext::VOLUME,
        material_ext::CLEARCOAT,
        material_ext::DIFFUSE_TRANSMISSION,
        material_ext::IRIDESCENCE,
        material_ext::SPEC_GLOSS,
        material_ext::DISPERSION,
        DRACO,
        ANIMATION_POINTER,
        NODE_VISIBILITY,
    ];
    root.extensions_required
        .retain(|e| !OWN.contains(&e.as_str()) && !compressed::EXTENSIONS.contains(&e.as_str()));
    Ok(())
}

/// Runs the gltf crate's validator (index bounds, required fields, enum values) and reports its
/// findings as one error.
fn validate(root: &json::Root, label: &str) -> Result<()> {
    // The validator's POSITION hook indexes the accessor list without a bounds check: check first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                if index.value() >= root.accessors.len() {
                    let name = match semantic {
                        Checked::Valid(s) => s.to_string(),
                        Checked::Invalid => "an unknown attribute".into(),
                    };
                    return Err(Error::input(format!(
                        "{label}: mesh {m} primitive {p} reads {name} from accessor {}, but the file has only {} accessor(s); fix the attribute's accessor index or re-export the scene",
                        index.value(),
                        root.accessors.len()
                    )));
                }
            }
        }
    }

    // Nor does its animation hook check a channel's target path before unwrapping it.
    for (a, anim) in root.animations.iter().enumerate() {
        for (c, channel) in anim.channels.iter().enumerate() {
            if matches!(channel.target.path, Checked::Invalid) {
                return Err(Error::input(format!(
                    "{label}: animation {a} channel {c} has a target path that is not translation, rotation, scale or weights; fix the channel or re-export the animation"
                )));
            }
        }
    }

    let mut problems: Vec<String> = Vec::new();
    root.validate(
        root,
        json::Path::new,
        &mut |path: &dyn Fn() -> json::Path, error| {
            use json::validation::Error as E;
            let at = path().to_string();
            // glTF 2.0 lets an accessor go without a bufferView (KHR_draco_mesh_compression's
            // accessors describe data that lives in the Draco bitstream); the crate insists.
            if matches!(error, E::Missing)
                && at.starts_with("accessors[")
                && at.ends_with(".bufferView")
            {
                return;
            }
            let what = match error {
                E::IndexOutOfBounds => "refers to an object that does not exist",
                E::Invalid => "has an invalid value",
                E::Missing => "is required but missing",
                E::Oversize => "is too large",
                E::Unsupported => "is not supported",
            };
            problems.push(format!("{at} {what}"));
        },
    );
    match problems.split_first() {
        None => Ok(()),
        Some((first, rest)) => Err(Error::input(format!(
            "{label} is not a valid glTF 2.0 file: {first}{}; fix the file or re-export the scene (the Khronos glTF Validator lists every problem)",
            if rest.is_empty() { String::new() } else { format!(" (and {} more problem(s): {})", rest.len(), rest.join("; ")) }
        ))),
    }
}

/// A KHR_lights_punctual light before a node places it.
struct LightDef {
    name: String,
    kind: LightKind,
    color: [f32; 3],
    intensity: f32,
    range: Option<f32>,
    shadow: Option<Shadow>,
}

/// Whether a node's meshes cast and receive shadows: set by the node's `extras.cast_shadows` /
/// `extras.receive_shadows`, inherited from the parent otherwise.
#[derive(Clone, Copy)]
struct ShadowFlags {
    cast: bool,
    receive: bool,
}

impl ShadowFlags {
    const DEFAULT: ShadowFlags = ShadowFlags {
        cast: true,
        receive: true,
    };
}

/// What weft reads from a light's `extras.shadows` (docs/scene-format.md).
const SHADOW_KEYS: &str = "resolution, filter_radius, bias";
/// Shadow map size in texels.
const SHADOW_RESOLUTION_RANGE: (f64, f64) = (64.0, 4096.0);
/// PCF filter radius in shadow-map texels.
const SHADOW_FILTER_RADIUS_RANGE: (f64, f64) = (0.0, 8.0);
/// Constant depth bias in shadow-map texels.
const SHADOW_BIAS_RANGE: (f64, f64) = (0.0, 64.0);

/// A JSON value for a message, cut to a readable length.
fn short_json(v: &serde_json::Value) -> String {
    let s = v.to_string();
    if s.chars().count() > 60 {
        format!("{}…", s.chars().take(60).collect::<String>())
    } else {
        s
    }
}

/// The `extras` of a glTF object as JSON, when it is an object; other values (extras belong to
/// any application) are no concern of weft's.
fn extras_object(extras: &json::Extras) -> Option<serde_json::Map<String, serde_json::Value>> {
    let raw = extras.as_ref()?;
    match serde_json::from_str(raw.get()) {
        Ok(serde_json::Value::Object(map)) => Some(map),
        _ => None,
    }
}

/// A TRIANGLE_STRIP's vertex sequence as a triangle list, with the winding of glTF 2.0 §3.7.2.1:
/// triangle i is (v_i, v_{i+1+i%2}, v_{i+2-i%2}), so every other triangle swaps its last two
/// corners and all face the same way. Degenerate triangles (two equal indices, which exporters
/// use to join strips) are dropped.
pub(super) fn strip_to_list(strip: &[u32]) -> Vec<u32> {
    let mut list = Vec::with_capacity(strip.len().saturating_sub(2) * 3);
    for i in 0..strip.len().saturating_sub(2) {
        let odd = i % 2;
        let t = [strip[i], strip[i + 1 + odd], strip[i + 2 - odd]];
        if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
            list.extend_from_slice(&t);
        }
    }
    list
}

/// A TRIANGLE_FAN's vertex sequence as a triangle list (glTF 2.0 §3.7.2.1: triangle i is
/// (v_{i+1}, v_{i+2}, v_0)); degenerate triangles are dropped.
pub(super) fn fan_to_list(fan: &[u32]) -> Vec<u32> {
    let mut list = Vec::with_capacity(fan.len().saturating_sub(2) * 3);
    for i in 0..fan.len().saturating_sub(2) {
        let t = [fan[i + 1], fan[i + 2], fan[0]];
        if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
            list.extend_from_slice(&t);
        }
    }
    list
}

/// A LINE_STRIP's (or, closed, a LINE_LOOP's) vertex sequence as a list of segments (glTF 2.0
/// §3.7.2.1: segment i is (v_i, v_{i+1}), and a loop adds (v_{n-1}, v_0)).
pub(super) fn line_strip_to_list(strip: &[u32], closed: bool) -> Vec<u32> {
    let mut list = Vec::with_capacity(strip.len() * 2);
    for w in strip.windows(2) {
        list.extend_from_slice(w);
    }
    if closed && strip.len() > 2 {
        list.extend_from_slice(&[strip[strip.len() - 1], strip[0]]);
    }
    list
}

/// A camera before a node places it.
struct CameraDef {
    name: String,
    /// Orthographic: (xmag, ymag), and `yfov` is unused.
    orthographic: Option<[f32; 2]>,
    yfov: f32,
    znear: f32,
    zfar: Option<f32>,
    aspect_ratio: Option<f32>,
}

struct Loader<'a> {
    /// The source, quoted, for messages.
    label: String,
    base_dir: Option<&'a Path>,
    doc: &'a gltf::Document,
    buffers: &'a [Vec<u8>],
    scene: Scene,
    /// (image index, is sRGB) -> index into `scene.textures`.
    textures: HashMap<(usize, bool), usize>,
    /// Per glTF material: the texture transform baked into the texture coordinates of its meshes.
    material_uv: Vec<UvTransform>,
    /// Per glTF material: each texture slot's KHR_texture_transform (identity without one), for
    /// KHR_animation_pointer channels that move it.
    slot_transforms: Vec<[UvTransform; TextureSlot::COUNT]>,
    /// The KHR_materials_variants variant chosen, and how many the file has.
    variant: Option<(usize, usize)>,
    /// The scene `--gltf-scene` chose (None: the file's default).
    chosen_scene: Option<usize>,
    /// Index of `Material::default()` in `scene.materials`, once a primitive needed it.
    default_material: Option<usize>,
    /// Unlit copies of materials (by index) for points and lines without normals.
    unlit_copies: HashMap<usize, usize>,
    /// Per glTF mesh: the scene meshes made from its primitives, once a node used it.
    mesh_ids: Vec<Option<Vec<usize>>>,
    lights: Vec<LightDef>,
    /// Per glTF camera (None for none: every camera is read, or the file refused).
    cameras: Vec<Option<CameraDef>>,
    /// What the file has cost so far, against the limits above.
    vertices_read: usize,
    indices_read: usize,
    texture_bytes_left: u64,
    triangles_drawn: u64,
    /// The file's KHR_animation_pointer channels, taken out of the JSON before the gltf crate
    /// read it.
    pointers: pointer::PointerChannels,
}

impl<'a> Loader<'a> {
    fn warn(&mut self, message: impl std::fmt::Display) {
        self.scene
            .warnings
            .push(Warning(format!("{}: {message}", self.label)));
    }

    fn error(&self, message: impl std::fmt::Display) -> Error {
        Error::input(format!("{}: {message}", self.label))
    }
}
