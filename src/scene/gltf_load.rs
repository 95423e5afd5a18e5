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
pub const DEFAULT_SCENE_GLB: &[u8] = include_bytes!("../../assets/default.glb");

const DEFAULT_SCENE_SOURCE: &str = "built-in default scene";

/// The fabric material extension; its parameters are parsed by [`FabricParams`].
const FABRIC_EXTENSION: &str = "WEFT_materials_fabric";

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
    let (mut root, glb_bin) = parse(bytes, source)?;
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
            ..Scene::default()
        },
        variant: variant.map(|i| (i, variants.len())),
        textures: HashMap::new(),
        material_uv: Vec::new(),
        default_material: None,
        unlit_copies: HashMap::new(),
        mesh_ids: vec![None; doc.meshes().len()],
        lights: Vec::new(),
        cameras: Vec::new(),
        vertices_read: 0,
        indices_read: 0,
        texture_bytes_left: resources::MAX_TEXTURE_BYTES,
        triangles_drawn: 0,
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
fn parse(bytes: &[u8], source: &str) -> Result<(json::Root, Option<Vec<u8>>)> {
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
    Ok((root, bin))
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
    /// The KHR_materials_variants variant chosen, and how many the file has.
    variant: Option<(usize, usize)>,
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

    // --- materials and textures -----------------------------------------------------------------

    fn load_materials(&mut self) -> Result<()> {
        let doc = self.doc;
        for (index, m) in doc.materials().enumerate() {
            let (material, uv) = self.material(&m, index)?;
            self.scene.materials.push(material);
            self.material_uv.push(uv);
        }
        Ok(())
    }

    fn material(
        &mut self,
        m: &gltf::Material<'a>,
        index: usize,
    ) -> Result<(Material, UvTransform)> {
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
        Ok((material, uv))
    }

    /// KHR_texture_transform from raw JSON (normal textures).
    fn parse_texture_transform(
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
    fn sampler(
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
    fn texture(
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
        });
        let index = self.scene.textures.len() - 1;
        self.textures.insert(key, index);
        Ok(index)
    }

    // --- meshes ---------------------------------------------------------------------------------

    /// The scene meshes of glTF mesh `mesh` (one per triangle primitive), built on first use.
    fn mesh_ids(&mut self, mesh: &gltf::Mesh<'a>) -> Result<Vec<usize>> {
        if let Some(Some(ids)) = self.mesh_ids.get(mesh.index()) {
            return Ok(ids.clone());
        }
        let name = mesh
            .name()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("mesh {}", mesh.index()));
        let several = mesh.primitives().len() > 1;
        let mut ids = Vec::new();
        for prim in mesh.primitives() {
            let who = format!("mesh '{name}' primitive {}", prim.index());
            let mesh_name = if several {
                format!("{name} (primitive {})", prim.index())
            } else {
                name.clone()
            };
            if let Some((m, deform)) = self.primitive(&prim, &who, mesh_name)? {
                self.scene.meshes.push(m);
                let id = self.scene.meshes.len() - 1;
                if let Some(deform) = deform {
                    self.scene.rig.meshes.insert(id, deform);
                }
                ids.push(id);
            }
        }
        if let Some(slot) = self.mesh_ids.get_mut(mesh.index()) {
            *slot = Some(ids.clone());
        }
        Ok(ids)
    }

    /// The glTF material of a primitive: its variant's mapping when a variant was chosen and the
    /// primitive maps it, else its own.
    fn gltf_material(&self, prim: &gltf::Primitive<'a>) -> Result<Option<usize>> {
        if let (Some((variant, count)), Some(ext)) =
            (self.variant, prim.extension_value(material_ext::VARIANTS))
        {
            if let Some(m) =
                material_ext::mapped_material(ext, variant, count).map_err(|e| self.error(e))?
            {
                // The file's materials, not the loader's (its default material may follow them).
                if m >= self.doc.materials().len() {
                    return Err(self.error(format_args!(
                        "{}.mappings names material {m}, but the file has {} materials; fix the mapping",
                        material_ext::VARIANTS,
                        self.doc.materials().len()
                    )));
                }
                return Ok(Some(m));
            }
        }
        Ok(prim.material().index())
    }

    fn material_index(&mut self, prim: &gltf::Primitive<'a>) -> Result<usize> {
        Ok(match self.gltf_material(prim)? {
            Some(i) => i,
            None => *self.default_material.get_or_insert_with(|| {
                self.scene.materials.push(Material::default());
                self.scene.materials.len() - 1
            }),
        })
    }

    /// `value` (a material extension), or None with a warning saying `why` where the material
    /// is woven (`on_fabric`): the extensions the woven model does not combine with yet.
    fn not_on_fabric<T>(
        &mut self,
        value: Option<T>,
        on_fabric: bool,
        who: &str,
        extension: &str,
        why: &str,
    ) -> Option<T> {
        if value.is_some() && on_fabric {
            self.warn(format_args!(
                "{who} has both {extension} and {FABRIC_EXTENSION}; {why}"
            ));
            return None;
        }
        value
    }

    /// An unlit copy of material `index` (made once): what points and lines without normals are
    /// drawn with. A material that is unlit already is its own copy.
    fn unlit_copy(&mut self, index: usize) -> usize {
        if self.scene.materials.get(index).is_none_or(|m| m.unlit) {
            return index;
        }
        if let Some(&copy) = self.unlit_copies.get(&index) {
            return copy;
        }
        let m = &self.scene.materials[index];
        let copy = Material {
            name: format!("{} (unlit: points and lines without normals)", m.name),
            unlit: true,
            fabric: None,
            ..m.clone()
        };
        self.scene.materials.push(copy);
        let copy = self.scene.materials.len() - 1;
        self.unlit_copies.insert(index, copy);
        copy
    }

    /// Decodes a primitive's KHR_draco_mesh_compression bitstream.
    fn draco(&self, ext: &serde_json::Value, who: &str) -> Result<DracoPrimitive> {
        let view_index = ext
            .get("bufferView")
            .and_then(serde_json::Value::as_u64)
            .ok_or_else(|| {
                self.error(format_args!(
                    "{who}: {DRACO} has no bufferView index; fix the file or export it without Draco compression"
                ))
            })? as usize;
        let view = self.doc.views().nth(view_index).ok_or_else(|| {
            self.error(format_args!(
                "{who}: {DRACO} names bufferView {view_index}, but the file has {}; fix the file",
                self.doc.views().len()
            ))
        })?;
        let bytes = self
            .buffers
            .get(view.buffer().index())
            .and_then(|b| b.get(view.offset()..view.offset().checked_add(view.length())?))
            .ok_or_else(|| {
                self.error(format_args!(
                    "{who}: {DRACO}'s bufferView {view_index} (bytes {}..{} of buffer {}) lies outside its buffer; the file is truncated or broken: re-export it",
                    view.offset(),
                    view.offset().saturating_add(view.length()),
                    view.buffer().index()
                ))
            })?;
        let mut ids = HashMap::new();
        if let Some(map) = ext.get("attributes").and_then(serde_json::Value::as_object) {
            for (name, id) in map {
                let id = id
                    .as_u64()
                    .and_then(|i| u32::try_from(i).ok())
                    .ok_or_else(|| {
                        self.error(format_args!(
                        "{who}: {DRACO}.attributes.{name} is not a Draco attribute id; fix the file"
                    ))
                    })?;
                if !DRACO_SEMANTICS.contains(&name.as_str()) {
                    return Err(self.error(format_args!(
                        "{who}: its {name} attribute is Draco-compressed, which weft reads for {} only; export the file without Draco compression (or without {name})",
                        DRACO_SEMANTICS.join(", ")
                    )));
                }
                ids.insert(name.clone(), id);
            }
        }
        if !ids.contains_key("POSITION") {
            return Err(self.error(format_args!(
                "{who}: {DRACO} does not map POSITION; every primitive needs one: re-export the file"
            )));
        }
        let mut mesh = draco_core::Mesh::new();
        draco_core::MeshDecoder::new()
            .decode(&mut draco_core::DecoderBuffer::new(bytes), &mut mesh)
            .map_err(|e| {
                self.error(format_args!(
                    "{who}: its Draco-compressed data (bufferView {view_index}, {} bytes) does not decode ({e}); the file is damaged: re-export it, or export it without Draco compression",
                    bytes.len()
                ))
            })?;
        Ok(DracoPrimitive { mesh, ids })
    }

    fn primitive(
        &mut self,
        prim: &gltf::Primitive<'a>,
        who: &str,
        name: String,
    ) -> Result<Option<(Mesh, Option<MeshDeform>)>> {
        let buffers = self.buffers;
        let draco = match prim.extension_value(DRACO) {
            Some(ext) => Some(self.draco(ext, who)?),
            None => None,
        };
        let label = &self.label;
        let read = |semantic: &Semantic, dims: Dimensions| -> Result<Option<(usize, Vec<f32>)>> {
            if let Some(d) = &draco {
                if let Some(&id) = d.ids.get(&semantic.to_string()) {
                    let att = d.mesh.attribute_by_unique_id(id).ok_or_else(|| {
                        Error::input(format!("{label}: {}", format_args!(
                            "{who}: {DRACO} maps {} to Draco attribute {id}, which its compressed data does not have; re-export the file",
                            semantic.to_string()
                        )))
                    })?;
                    let n = match dims {
                        Dimensions::Scalar => 1,
                        Dimensions::Vec2 => 2,
                        Dimensions::Vec3 => 3,
                        _ => 4,
                    };
                    let mut values = att.read_f32s(d.mesh.num_points(), n);
                    if att.normalized() {
                        use draco_core::DataType as T;
                        let (scale, min) = match att.data_type() {
                            T::Uint8 => (1.0 / 255.0, 0.0),
                            T::Uint16 => (1.0 / 65535.0, 0.0),
                            T::Int8 => (1.0 / 127.0, -1.0),
                            T::Int16 => (1.0 / 32767.0, -1.0),
                            _ => (1.0, f32::MIN),
                        };
                        for v in &mut values {
                            *v = (*v * scale).max(min);
                        }
                    }
                    if values.iter().any(|v| !v.is_finite()) {
                        return Err(Error::input(format!("{label}: {}", format_args!(
                            "{who}: the Draco-compressed {} holds values that are not finite numbers; re-export the file",
                            semantic.to_string()
                        ))));
                    }
                    let acc = prim.get(semantic).map_or(usize::MAX, |a| a.index());
                    return Ok(Some((acc, values)));
                }
            }
            match prim.get(semantic) {
                None => Ok(None),
                Some(acc) => {
                    let what = format!("{who}, attribute {}", semantic.to_string());
                    let values = accessor::read_f32(
                        &acc,
                        dims,
                        buffers,
                        &Use {
                            source: &self.label,
                            what: &what,
                        },
                    )?;
                    Ok(Some((acc.index(), values)))
                }
            }
        };
        // Counted before reading, so the limit also bounds the time spent on primitives that turn
        // out to have no triangles.
        let claimed = prim.get(&Semantic::Positions).map_or(0, |a| a.count());
        self.vertices_read = self.vertices_read.saturating_add(claimed);
        if self.vertices_read > MAX_VERTICES {
            return Err(self.error(format_args!(
                "{who} brings the vertices read to {}, more than weft's limit of {MAX_VERTICES} for a scene (primitives that share an accessor count it each time); decimate or split the scene, or give primitives their own, smaller accessors",
                self.vertices_read
            )));
        }
        let (pos_accessor, positions) = read(&Semantic::Positions, Dimensions::Vec3)?.ok_or_else(|| {
            self.error(format_args!("{who} has no POSITION attribute; every primitive needs one: re-export the mesh"))
        })?;
        let count = positions.len() / 3;
        if u32::try_from(count).is_err() {
            return Err(self.error(format_args!(
                "{who} has {count} vertices; weft supports at most 2^32 - 1 per primitive: split the mesh"
            )));
        }
        let normals = read(&Semantic::Normals, Dimensions::Vec3)?;
        let tangents = read(&Semantic::Tangents, Dimensions::Vec4)?;
        let uvs = read(&Semantic::TexCoords(0), Dimensions::Vec2)?;
        // TEXCOORD_1 only when a texture of the primitive's material reads it.
        let wants_uv1 = self
            .gltf_material(prim)?
            .and_then(|m| self.scene.materials.get(m))
            .is_some_and(|m| m.uv.iter().any(|s| s.set == 1));
        let uvs1 = if wants_uv1 {
            let uvs1 = read(&Semantic::TexCoords(1), Dimensions::Vec2)?;
            if uvs1.is_none() {
                self.warn(format_args!(
                    "{who}'s material samples a texture with TEXCOORD_1, but the primitive has no TEXCOORD_1; it is sampled at (0, 0): add the second UV set or point the texture at texCoord 0"
                ));
            }
            uvs1
        } else {
            None
        };
        for (semantic, attr, n) in [
            ("NORMAL", &normals, 3),
            ("TANGENT", &tangents, 4),
            ("TEXCOORD_0", &uvs, 2),
            ("TEXCOORD_1", &uvs1, 2),
        ] {
            if let Some((acc, values)) = attr {
                if values.len() / n != count {
                    return Err(self.error(format_args!(
                        "{who}: attribute {semantic} (accessor {acc}) has {} elements but POSITION (accessor {pos_accessor}) has {count}; all attributes of a primitive must have the same count: re-export the mesh",
                        values.len() / n
                    )));
                }
            }
        }
        let mut colors = self.vertex_colors(prim, who, count)?;
        let mut deform = self.primitive_deform(prim, who, count)?;

        let mut indices = match (&draco, prim.indices()) {
            (Some(d), _) => {
                let faces = d.mesh.num_faces();
                self.indices_read = self.indices_read.saturating_add(faces.saturating_mul(3));
                if self.indices_read > MAX_INDICES {
                    return Err(self.error(format_args!(
                        "{who} brings the indices read to {}, more than weft's limit of {MAX_INDICES} ({} million triangles) for a scene; decimate the meshes or split the scene",
                        self.indices_read,
                        MAX_INDICES / 3 / 1_000_000
                    )));
                }
                let mut out = Vec::with_capacity(faces * 3);
                for f in 0..faces {
                    for p in d.mesh.face(draco_core::FaceIndex(f as u32)) {
                        if p.0 as usize >= count {
                            return Err(self.error(format_args!(
                                "{who}: its Draco-compressed face {f} names point {}, but the primitive has only {count} points; re-export the file",
                                p.0
                            )));
                        }
                        out.push(p.0);
                    }
                }
                out
            }
            (None, Some(acc)) => {
                let what = format!("{who}, indices");
                self.indices_read = self.indices_read.saturating_add(acc.count());
                if self.indices_read > MAX_INDICES {
                    return Err(self.error(format_args!(
                        "{who} brings the indices read to {}, more than weft's limit of {MAX_INDICES} ({} million triangles) for a scene; decimate the meshes or split the scene",
                        self.indices_read,
                        MAX_INDICES / 3 / 1_000_000
                    )));
                }
                let indices = accessor::read_u32(
                    &acc,
                    buffers,
                    &Use {
                        source: &self.label,
                        what: &what,
                    },
                )?;
                if let Some((k, &i)) = indices
                    .iter()
                    .enumerate()
                    .find(|(_, &i)| i as usize >= count)
                {
                    return Err(self.error(format_args!(
                        "{who}: index accessor {} holds index {i} at position {k}, but the primitive has only {count} vertices (POSITION accessor {pos_accessor}); fix the indices or re-export the mesh",
                        acc.index()
                    )));
                }
                indices
            }
            (None, None) => (0..count as u32).collect(),
        };
        let topology = match prim.mode() {
            Mode::Points => Topology::Points,
            Mode::Lines | Mode::LineLoop | Mode::LineStrip => Topology::Lines,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => Topology::Triangles,
        };
        match prim.mode() {
            Mode::TriangleStrip => indices = strip_to_list(&indices),
            Mode::TriangleFan => indices = fan_to_list(&indices),
            Mode::LineStrip => indices = line_strip_to_list(&indices, false),
            Mode::LineLoop => indices = line_strip_to_list(&indices, true),
            _ => {}
        }
        let arity = topology.arity();
        let unit = match topology {
            Topology::Triangles => "triangles",
            Topology::Lines => "line segments",
            Topology::Points => "points",
        };
        if indices.len() % arity != 0 {
            self.warn(format_args!(
                "{who} has {} indices, not a multiple of {arity}; the last {} are ignored",
                indices.len(),
                indices.len() % arity
            ));
            indices.truncate(indices.len() / arity * arity);
        }
        if indices.is_empty() {
            self.warn(format_args!("{who} has no {unit}; skipped"));
            return Ok(None);
        }

        // Positions: a non-finite vertex in a triangle breaks rasterisation, bounds and tangents.
        let position = |v: usize| [positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]];
        if let Some((corner, &v)) = indices
            .iter()
            .enumerate()
            .find(|(_, &v)| !position(v as usize).iter().all(|c| c.is_finite()))
        {
            return Err(self.error(format_args!(
                "{who}: vertex {v} of {} {} has the non-finite position {:?} (POSITION accessor {pos_accessor}); fix or delete that vertex in your modelling tool and re-export",
                &unit[..unit.len() - 1],
                corner / arity,
                position(v as usize)
            )));
        }

        let mut vertices: Vec<Vertex> = (0..count)
            .map(|v| Vertex {
                // Vertices no triangle uses are never drawn; keep them finite all the same.
                position: position(v).map(|c| if c.is_finite() { c } else { 0.0 }),
                normal: normals
                    .as_ref()
                    .map_or([0.0; 3], |(_, n)| [n[3 * v], n[3 * v + 1], n[3 * v + 2]]),
                tangent: tangents.as_ref().map_or([0.0; 4], |(_, t)| {
                    [t[4 * v], t[4 * v + 1], t[4 * v + 2], t[4 * v + 3]]
                }),
                uv: uvs
                    .as_ref()
                    .map_or([0.0; 2], |(_, t)| [t[2 * v], t[2 * v + 1]]),
                uv1: uvs1
                    .as_ref()
                    .map(|(_, t)| [t[2 * v], t[2 * v + 1]])
                    .filter(|uv| uv.iter().all(|c| c.is_finite()))
                    .unwrap_or([0.0; 2]),
            })
            .collect();

        let mut material = self.material_index(prim)?;
        if topology != Topology::Triangles && normals.is_none() {
            // glTF: points and lines without normals are drawn without lighting (their base
            // colour), through an unlit copy of their material.
            material = self.unlit_copy(material);
        }
        if topology != Topology::Triangles
            && self
                .scene
                .materials
                .get(material)
                .is_some_and(|m| m.needs_forward())
        {
            self.warn(format_args!(
                "{who}: {unit} are drawn opaque by the G-buffer pass; their material's alphaMode BLEND, transmission, clear coat, diffuse transmission or thin film is not applied to them"
            ));
        }
        let uv_transform = self
            .gltf_material(prim)?
            .and_then(|m| self.material_uv.get(m))
            .copied()
            .unwrap_or(UvTransform::IDENTITY);

        if uvs.is_some() {
            // The transform first: finite coordinates through a finite transform can still
            // overflow, and get the same repair as the file's own non-finite ones.
            let finite = |v: &Vertex| v.uv.iter().all(|c| c.is_finite());
            let in_file = vertices.iter().filter(|v| !finite(v)).count();
            if uv_transform != UvTransform::IDENTITY {
                for v in vertices.iter_mut() {
                    v.uv = uv_transform.apply(v.uv);
                }
            }
            let bad = vertices.iter().filter(|v| !finite(v)).count();
            if bad > 0 {
                let made = if bad > in_file {
                    format!(
                        " ({} of them made so by its material's KHR_texture_transform, whose result overflows 32-bit floating point)",
                        bad - in_file
                    )
                } else {
                    String::new()
                };
                self.warn(format_args!(
                    "{who} has {bad} non-finite texture coordinate(s){made}; replaced by (0, 0)"
                ));
                for v in vertices.iter_mut().filter(|v| !finite(v)) {
                    v.uv = [0.0, 0.0];
                }
            }
        } else {
            let m = self.scene.materials.get(material);
            let needs_uvs = m.is_some_and(|m| {
                m.fabric.is_some()
                    || m.base_color_texture.is_some()
                    || m.metallic_roughness_texture.is_some()
                    || m.normal_texture.is_some()
                    || m.emissive_texture.is_some()
            });
            if needs_uvs {
                let mname = m.map(|m| m.name.clone()).unwrap_or_default();
                self.warn(format_args!(
                    "{who} has no texture coordinates (TEXCOORD_0) but its material '{mname}' has textures or a weave; they will look flat: add UVs to the mesh"
                ));
            }
        }

        // Each slot's own transform runs in the shader, on these coordinates: one that
        // overflows on them would make the surface black.
        if let Some(m) = self.scene.materials.get_mut(material) {
            let slots: Vec<usize> = (0..m.uv.len())
                .filter(|&k| m.uv[k].overflows_on(&vertices))
                .collect();
            for &k in &slots {
                m.uv[k] = SlotUv::IDENTITY;
            }
            if !slots.is_empty() {
                let names: Vec<&str> = slots.iter().map(|&k| TextureSlot::NAMES[k]).collect();
                let mname = m.name.clone();
                self.warn(format_args!(
                    "{who}: the KHR_texture_transform of the {} texture of its material '{mname}' takes its texture coordinates out of the range of 32-bit floating point; sampled without the transform",
                    names.join(", ")
                ));
            }
        }

        if topology != Topology::Triangles {
            // No surface to take a normal or tangent frame from: the file's normals (repaired
            // where degenerate) and a fallback frame; unlit without normals (above).
            let bad = if normals.is_some() {
                vertices
                    .iter_mut()
                    .filter(|v| {
                        let n = glam::Vec3::from(v.normal);
                        !(n.length_squared() > 1e-12 && n.is_finite())
                    })
                    .map(|v| v.normal = [0.0, 0.0, 1.0])
                    .count()
            } else {
                for v in vertices.iter_mut() {
                    v.normal = [0.0, 0.0, 1.0];
                }
                0
            };
            for v in vertices.iter_mut() {
                v.normal = glam::Vec3::from(v.normal)
                    .normalize_or(glam::Vec3::Z)
                    .to_array();
                v.tangent = [0.0; 4];
            }
            tangents::repair_tangents(&mut vertices);
            if bad > 0 {
                self.warn(format_args!(
                    "{who}: {bad} normal(s) were zero-length or not finite; replaced by +Z"
                ));
            }
            return Ok(Some((
                Mesh {
                    name,
                    vertices,
                    indices,
                    material,
                    colors,
                    topology,
                },
                deform,
            )));
        }
        if normals.is_none() {
            tangents::generate_normals(&mut vertices, &indices);
            self.warn(format_args!(
                "{who} has no normals; generated them from the triangles (export normals for the intended shading)"
            ));
        }
        let bad_normals = tangents::repair_normals(&mut vertices, &indices);

        let bad_tangents = if tangents.is_some() && !uv_transform.turns_or_mirrors() {
            tangents::repair_tangents(&mut vertices)
        } else if uvs.is_some() {
            let before = (deform.is_some() || !colors.is_empty()).then(|| indices.clone());
            if !tangents::mikktspace_tangents(&mut vertices, &mut indices) {
                tangents::arbitrary_tangents(&mut vertices);
            }
            // MikkTSpace splits vertices whose corners need different tangents: the copies get
            // their original's joints, morph deltas and colour.
            if let Some(before) = before {
                let mut origin: Vec<usize> = (0..vertices.len()).collect();
                for (now, was) in indices.iter().zip(&before) {
                    if now != was {
                        if let Some(o) = origin.get_mut(*now as usize) {
                            *o = *was as usize;
                        }
                    }
                }
                if let Some(d) = deform.as_mut() {
                    d.extend_to(&origin[count..]);
                }
                if !colors.is_empty() {
                    for &o in &origin[count..] {
                        colors.push(colors.get(o).copied().unwrap_or([1.0; 4]));
                    }
                }
            }
            tangents::repair_tangents(&mut vertices)
        } else {
            tangents::arbitrary_tangents(&mut vertices);
            0
        };
        let repaired: Vec<String> = [(bad_normals, "normal"), (bad_tangents, "tangent")]
            .iter()
            .filter(|(n, _)| *n > 0)
            .map(|(n, what)| format!("{n} {what}(s)"))
            .collect();
        if !repaired.is_empty() {
            self.warn(format_args!(
                "{who}: {} were zero-length, degenerate or not finite; replaced by a fallback frame (check the mesh's normals and UVs in your modelling tool)",
                repaired.join(" and ")
            ));
        }

        Ok(Some((
            Mesh {
                name,
                vertices,
                indices,
                material,
                colors,
                topology: Topology::Triangles,
            },
            deform,
        )))
    }

    /// A primitive's COLOR_0 as linear RGBA per vertex (alpha 1 for VEC3), empty when it has
    /// none. glTF allows VEC3 or VEC4 of float, normalized unsigned byte or normalized unsigned
    /// short; anything else is ignored with a warning. Values are clamped to [0, 1] (a non-finite
    /// one becomes 1).
    fn vertex_colors(
        &mut self,
        prim: &gltf::Primitive<'a>,
        who: &str,
        count: usize,
    ) -> Result<Vec<[f32; 4]>> {
        use gltf::accessor::DataType;
        let Some(acc) = prim.get(&Semantic::Colors(0)) else {
            return Ok(Vec::new());
        };
        let n = match acc.dimensions() {
            Dimensions::Vec3 => 3,
            Dimensions::Vec4 => 4,
            other => {
                self.warn(format_args!(
                    "{who}: COLOR_0 (accessor {}) is {other:?}; glTF allows VEC3 or VEC4, so the vertex colours are ignored: re-export the mesh",
                    acc.index()
                ));
                return Ok(Vec::new());
            }
        };
        let allowed = match acc.data_type() {
            DataType::F32 => true,
            DataType::U8 | DataType::U16 => acc.normalized(),
            _ => false,
        };
        if !allowed {
            self.warn(format_args!(
                "{who}: COLOR_0 (accessor {}) has component type {:?}{}; glTF allows float, normalized unsigned byte or normalized unsigned short, so the vertex colours are ignored: re-export the mesh",
                acc.index(),
                acc.data_type(),
                if acc.normalized() { ", normalized" } else { "" }
            ));
            return Ok(Vec::new());
        }
        let what = format!("{who}, attribute COLOR_0");
        let values = accessor::read_f32(
            &acc,
            acc.dimensions(),
            self.buffers,
            &Use {
                source: &self.label,
                what: &what,
            },
        )?;
        if values.len() / n != count {
            return Err(self.error(format_args!(
                "{who}: attribute COLOR_0 (accessor {}) has {} elements but POSITION has {count}; all attributes of a primitive must have the same count: re-export the mesh",
                acc.index(),
                values.len() / n
            )));
        }
        let mut out_of_range = 0usize;
        let colors = values
            .chunks_exact(n)
            .map(|c| {
                let mut rgba = [1.0f32; 4];
                for (k, v) in c.iter().enumerate() {
                    rgba[k] = if v.is_finite() {
                        v.clamp(0.0, 1.0)
                    } else {
                        1.0
                    };
                    if rgba[k] != *v {
                        out_of_range += 1;
                    }
                }
                rgba
            })
            .collect();
        if out_of_range > 0 {
            self.warn(format_args!(
                "{who}: COLOR_0 (accessor {}) has {out_of_range} component(s) outside [0, 1] or not finite; clamped (a non-finite one to 1)",
                acc.index()
            ));
        }
        Ok(colors)
    }

    /// A primitive's joint influences (JOINTS_0 / WEIGHTS_0) and morph targets, None when it has
    /// neither. `count` is its vertex count, which every one of these accessors must match.
    fn primitive_deform(
        &mut self,
        prim: &gltf::Primitive<'a>,
        who: &str,
        count: usize,
    ) -> Result<Option<MeshDeform>> {
        let buffers = self.buffers;
        let label = self.label.clone();
        let read = |acc: gltf::Accessor, what: String, dims: Dimensions| -> Result<Vec<f32>> {
            let values = accessor::read_f32(
                &acc,
                dims,
                buffers,
                &Use {
                    source: &label,
                    what: &what,
                },
            )?;
            let n = match dims {
                Dimensions::Vec3 => 3,
                _ => 4,
            };
            if values.len() / n != count {
                return Err(Error::input(format!(
                    "{label}: {what} (accessor {}) has {} elements but POSITION has {count}; all attributes of a primitive must have the same count: re-export the mesh",
                    acc.index(),
                    values.len() / n
                )));
            }
            if values.iter().any(|v| !v.is_finite()) {
                return Err(Error::input(format!(
                    "{label}: {what} (accessor {}) holds a non-finite value; fix the mesh and re-export it",
                    acc.index()
                )));
            }
            Ok(values)
        };
        let mut deform = MeshDeform::default();
        match (
            prim.get(&Semantic::Joints(0)),
            prim.get(&Semantic::Weights(0)),
        ) {
            (Some(j), Some(w)) => {
                if !matches!(
                    j.data_type(),
                    gltf::accessor::DataType::U8 | gltf::accessor::DataType::U16
                ) || j.normalized()
                {
                    return Err(self.error(format_args!(
                        "{who}: JOINTS_0 (accessor {}) has component type {:?}{}; glTF requires unsigned byte or unsigned short joint indices: re-export the mesh",
                        j.index(),
                        j.data_type(),
                        if j.normalized() { ", normalized" } else { "" }
                    )));
                }
                let joints = read(j, format!("{who}, attribute JOINTS_0"), Dimensions::Vec4)?;
                let weights = read(w, format!("{who}, attribute WEIGHTS_0"), Dimensions::Vec4)?;
                let mut unweighted = 0;
                deform.skin = (0..count)
                    .map(|v| {
                        let mut w = [0f32; 4];
                        w.copy_from_slice(&weights[4 * v..4 * v + 4]);
                        let w = w.map(|x| x.max(0.0));
                        let sum: f32 = w.iter().sum();
                        let weights = if sum > 1e-6 {
                            // glTF asks for weights that sum to 1; exporters round (u8 weights
                            // especially), so they are normalised.
                            w.map(|x| x / sum)
                        } else {
                            unweighted += 1;
                            [1.0, 0.0, 0.0, 0.0]
                        };
                        VertexSkin {
                            joints: [0, 1, 2, 3].map(|k| joints[4 * v + k] as u32),
                            weights,
                        }
                    })
                    .collect();
                if unweighted > 0 {
                    self.warn(format_args!(
                        "{who} has {unweighted} vertex/vertices whose WEIGHTS_0 are all zero; they follow their first joint"
                    ));
                }
                if prim.get(&Semantic::Joints(1)).is_some() {
                    self.warn(format_args!(
                        "{who} has more than four joint influences per vertex (JOINTS_1); weft uses JOINTS_0 / WEIGHTS_0 only, so the skin deforms slightly differently"
                    ));
                }
            }
            (None, None) => {}
            _ => {
                self.warn(format_args!(
                    "{who} has only one of JOINTS_0 and WEIGHTS_0; a skinned primitive needs both, so it is drawn unskinned"
                ));
            }
        }
        let targets: Vec<_> = prim.morph_targets().collect();
        if targets.len() > animation::MAX_MORPH_TARGETS {
            return Err(self.error(format_args!(
                "{who} has {} morph targets, more than weft's limit of {}; bake or drop some shape keys",
                targets.len(),
                animation::MAX_MORPH_TARGETS
            )));
        }
        let triples = |v: Vec<f32>| -> Vec<[f32; 3]> {
            v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
        };
        for (k, t) in targets.iter().enumerate() {
            let mut target = MorphTarget::default();
            if let Some(a) = t.positions() {
                target.positions = triples(read(
                    a,
                    format!("{who}, morph target {k} POSITION"),
                    Dimensions::Vec3,
                )?);
            }
            if let Some(a) = t.normals() {
                target.normals = triples(read(
                    a,
                    format!("{who}, morph target {k} NORMAL"),
                    Dimensions::Vec3,
                )?);
            }
            if let Some(a) = t.tangents() {
                target.tangents = triples(read(
                    a,
                    format!("{who}, morph target {k} TANGENT"),
                    Dimensions::Vec3,
                )?);
            }
            deform.targets.push(target);
        }
        Ok((!deform.skin.is_empty() || !deform.targets.is_empty()).then_some(deform))
    }

    // --- lights and cameras ---------------------------------------------------------------------

    fn light_definitions(&mut self) -> Result<Vec<LightDef>> {
        let root = self.doc.as_json();
        let lights = root
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .map_or(&[][..], |l| &l.lights[..]);
        let mut out = Vec::with_capacity(lights.len());
        for (i, l) in lights.iter().enumerate() {
            let name = l.name.clone().unwrap_or_else(|| format!("light {i}"));
            let who = format!("light '{name}' (KHR_lights_punctual light {i})");
            use json::extensions::scene::khr_lights_punctual::Type;
            let kind = match (&l.type_, &l.spot) {
                (Checked::Valid(Type::Directional), _) => LightKind::Directional,
                (Checked::Valid(Type::Point), _) => LightKind::Point,
                (Checked::Valid(Type::Spot), Some(spot)) => {
                    let (inner, outer) = (spot.inner_cone_angle, spot.outer_cone_angle);
                    let half_pi = std::f32::consts::FRAC_PI_2;
                    if !(inner.is_finite()
                        && outer.is_finite()
                        && 0.0 <= inner
                        && inner < outer
                        && outer <= half_pi)
                    {
                        return Err(self.error(format_args!(
                            "{who} has innerConeAngle {inner} and outerConeAngle {outer}; they must satisfy 0 <= inner < outer <= pi/2 (radians): fix the spot angles"
                        )));
                    }
                    LightKind::Spot {
                        inner_cone: inner,
                        outer_cone: outer,
                    }
                }
                _ => {
                    return Err(self.error(format_args!(
                        "{who} has no valid type and spot parameters; re-export the light"
                    )))
                }
            };
            if !(l.intensity.is_finite() && l.intensity >= 0.0) {
                return Err(self.error(format_args!(
                    "{who} has intensity {}; it must be a finite number >= 0",
                    l.intensity
                )));
            }
            if !l.color.iter().all(|c| c.is_finite() && *c >= 0.0) {
                return Err(self.error(format_args!(
                    "{who} has colour {:?}; components must be finite and >= 0",
                    l.color
                )));
            }
            let range = match (kind, l.range) {
                // The extension defines no range for directional lights.
                (LightKind::Directional, _) | (_, None) => None,
                (_, Some(r)) if r.is_finite() && r > 0.0 => Some(r),
                (_, Some(r)) => {
                    return Err(self.error(format_args!(
                        "{who} has range {r}; it must be > 0 (or left out for no cut-off)"
                    )))
                }
            };
            let shadow = self.light_shadow(&l.extras, kind, &who)?;
            out.push(LightDef {
                name,
                kind,
                color: l.color,
                intensity: l.intensity,
                range,
                shadow,
            });
        }
        Ok(out)
    }

    /// The shadow settings a light asks for with `extras.shadows` (docs/scene-format.md): `true`
    /// for the defaults, an object of optional `resolution`, `filter_radius` and `bias`, `false`
    /// or absent for none. Numbers out of range are clamped with a warning, unknown keys warned
    /// about; a value of the wrong type is an error. Point lights get a warning and no shadows.
    fn light_shadow(
        &mut self,
        extras: &json::Extras,
        kind: LightKind,
        who: &str,
    ) -> Result<Option<Shadow>> {
        let Some(value) = extras_object(extras).and_then(|mut e| e.remove("shadows")) else {
            return Ok(None);
        };
        let example = r#"{"resolution": 2048, "filter_radius": 1.5, "bias": 1.0}"#;
        let fields = match value {
            serde_json::Value::Bool(false) => return Ok(None),
            serde_json::Value::Bool(true) => serde_json::Map::new(),
            serde_json::Value::Object(map) => map,
            other => {
                return Err(self.error(format_args!(
                    "{who} has extras.shadows = {}; it must be true (shadows with the default settings), false (no shadows) or an object such as {example} (each key optional): fix the light's extras",
                    short_json(&other)
                )))
            }
        };
        let mut shadow = Shadow::default();
        for (key, v) in &fields {
            let (lo, hi, what) = match key.as_str() {
                "resolution" => (
                    SHADOW_RESOLUTION_RANGE.0,
                    SHADOW_RESOLUTION_RANGE.1,
                    "the shadow map's size in texels",
                ),
                "filter_radius" => (
                    SHADOW_FILTER_RADIUS_RANGE.0,
                    SHADOW_FILTER_RADIUS_RANGE.1,
                    "the PCF filter radius in shadow-map texels",
                ),
                "bias" => (
                    SHADOW_BIAS_RANGE.0,
                    SHADOW_BIAS_RANGE.1,
                    "the depth bias in shadow-map texels",
                ),
                other => {
                    self.warn(format_args!(
                        "{who} has an unknown key '{other}' in extras.shadows (ignored); known keys: {SHADOW_KEYS}"
                    ));
                    continue;
                }
            };
            let x = match v.as_f64() {
                Some(x) if x.is_finite() && x.abs() <= f64::from(f32::MAX) => x,
                _ => {
                    let problem = if v.is_number() {
                        "a number too large for 32-bit floating point"
                    } else {
                        "not a number"
                    };
                    return Err(self.error(format_args!(
                        "{who} has extras.shadows.{key} = {}, {problem}; it must be a number ({what}, {lo} to {hi}): write one there, or remove the key for the default",
                        short_json(v)
                    )));
                }
            };
            let mut c = x.clamp(lo, hi);
            if key == "resolution" {
                c = c.round();
            }
            if c != x {
                let why = if (lo..=hi).contains(&x) {
                    "is not a whole number of texels; rounded to".to_string()
                } else {
                    format!("is outside [{lo}, {hi}]; clamped to")
                };
                self.warn(format_args!(
                    "{who} has extras.shadows.{key} = {}, which {why} {c}",
                    short_json(v)
                ));
            }
            match key.as_str() {
                "resolution" => shadow.resolution = c as u32,
                "filter_radius" => shadow.filter_radius = c as f32,
                _ => shadow.bias = c as f32,
            }
        }
        if kind == LightKind::Point {
            self.warn(format_args!(
                "{who} is a point light and asks for shadows (extras.shadows); weft casts shadows from directional and spot lights only, so this light is rendered without shadows"
            ));
            return Ok(None);
        }
        Ok(Some(shadow))
    }

    fn camera_definitions(&mut self) -> Result<Vec<Option<CameraDef>>> {
        let root = self.doc.as_json();
        let mut out = Vec::with_capacity(root.cameras.len());
        for (i, c) in root.cameras.iter().enumerate() {
            let name = c.name.clone().unwrap_or_else(|| format!("camera {i}"));
            let who = format!("camera '{name}' (camera {i})");
            let p = match (&c.type_, &c.perspective) {
                (Checked::Valid(json::camera::Type::Perspective), Some(p)) => p,
                (Checked::Valid(json::camera::Type::Orthographic), _) => {
                    let Some(o) = c.orthographic.as_ref() else {
                        return Err(self.error(format_args!(
                            "{who} has type orthographic but no \"orthographic\" object; add one with xmag, ymag, znear and zfar"
                        )));
                    };
                    if !(o.xmag.is_finite() && o.xmag != 0.0 && o.ymag.is_finite() && o.ymag != 0.0) {
                        return Err(self.error(format_args!(
                            "{who} has xmag {} and ymag {}; both must be finite and not zero (half the width and height of the view, in metres): fix the camera",
                            o.xmag, o.ymag
                        )));
                    }
                    if o.xmag < 0.0 || o.ymag < 0.0 {
                        self.warn(format_args!(
                            "{who} has a negative xmag or ymag ({}, {}); glTF asks for positive ones, so their magnitudes are used",
                            o.xmag, o.ymag
                        ));
                    }
                    if !(o.znear.is_finite() && o.znear >= 0.0 && o.zfar.is_finite() && o.zfar > o.znear) {
                        return Err(self.error(format_args!(
                            "{who} has znear {} and zfar {}; an orthographic camera needs 0 <= znear < zfar, both finite: fix the camera",
                            o.znear, o.zfar
                        )));
                    }
                    out.push(Some(CameraDef {
                        name,
                        orthographic: Some([o.xmag.abs(), o.ymag.abs()]),
                        yfov: 45f32.to_radians(),
                        znear: o.znear,
                        zfar: Some(o.zfar),
                        aspect_ratio: Some(o.xmag.abs() / o.ymag.abs()),
                    }));
                    continue;
                }
                _ => {
                    return Err(self.error(format_args!(
                        "{who} has type perspective but no \"perspective\" object; add one with yfov and znear"
                    )))
                }
            };
            if !(p.yfov.is_finite() && p.yfov > 0.0 && p.yfov < std::f32::consts::PI) {
                return Err(self.error(format_args!(
                    "{who} has yfov {} rad; the vertical field of view must be between 0 and pi radians (exclusive): set perspective.yfov, e.g. 0.7 for 40 degrees",
                    p.yfov
                )));
            }
            if !(p.znear.is_finite() && p.znear > 0.0) {
                return Err(self.error(format_args!(
                    "{who} has znear {}; the near plane distance must be > 0: set perspective.znear, e.g. 0.05",
                    p.znear
                )));
            }
            if let Some(zfar) = p.zfar {
                if !(zfar.is_finite() && zfar > p.znear) {
                    return Err(self.error(format_args!(
                        "{who} has zfar {zfar} with znear {}; zfar must be greater than znear (or left out for an infinite far plane)",
                        p.znear
                    )));
                }
            }
            if let Some(a) = p.aspect_ratio {
                if !(a.is_finite() && a > 0.0) {
                    return Err(self.error(format_args!(
                        "{who} has aspectRatio {a}; it must be > 0 (or left out)"
                    )));
                }
            }
            out.push(Some(CameraDef {
                name,
                orthographic: None,
                yfov: p.yfov,
                znear: p.znear,
                zfar: p.zfar,
                aspect_ratio: p.aspect_ratio,
            }));
        }
        Ok(out)
    }

    // --- the node tree --------------------------------------------------------------------------

    fn walk_nodes(&mut self) -> Result<()> {
        let doc = self.doc;
        let roots: Vec<gltf::Node<'a>> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(scene) => {
                if doc.scenes().len() > 1 {
                    let name = scene
                        .name()
                        .map(|n| format!(" ('{n}')"))
                        .unwrap_or_default();
                    self.warn(format_args!(
                        "has {} scenes; weft renders scene {}{name}",
                        doc.scenes().len(),
                        scene.index()
                    ));
                }
                scene.nodes().collect()
            }
            None => {
                // No scene: draw every node that is nobody's child.
                let mut is_child = vec![false; doc.nodes().len()];
                for node in doc.nodes() {
                    for child in node.children() {
                        if let Some(c) = is_child.get_mut(child.index()) {
                            *c = true;
                        }
                    }
                }
                let roots: Vec<_> = doc
                    .nodes()
                    .filter(|n| !is_child.get(n.index()).copied().unwrap_or(false))
                    .collect();
                if !roots.is_empty() {
                    self.warn("has no scenes; drawing every root node");
                }
                roots
            }
        };

        let mut visited = vec![false; doc.nodes().len()];
        let mut stack: Vec<(gltf::Node<'a>, Mat4, ShadowFlags)> = roots
            .into_iter()
            .rev()
            .map(|n| (n, Mat4::IDENTITY, ShadowFlags::DEFAULT))
            .collect();
        while let Some((node, parent, inherited)) = stack.pop() {
            let name = node
                .name()
                .map(str::to_owned)
                .unwrap_or_else(|| format!("node {}", node.index()));
            let who = format!("node '{name}' (node {})", node.index());
            match visited.get_mut(node.index()) {
                Some(seen) if !*seen => *seen = true,
                _ => {
                    return Err(self.error(format_args!(
                        "{who} is reached twice in the node hierarchy; glTF nodes must form trees (each node has at most one parent, no cycles): fix the \"children\" lists"
                    )))
                }
            }
            self.scene.rig.order.push(node.index());
            let world = parent * self.local_transform(&node, &who)?;
            if !world.is_finite() {
                return Err(self.error(format_args!(
                    "{who} has a world transform that is not finite (check its and its parents' translation, rotation, scale or matrix)"
                )));
            }
            let flags = self.node_shadow_flags(node.index(), inherited, &who)?;
            let instances = self.instance_transforms(&node, &who)?;
            if instances.is_some() && node.mesh().is_none() {
                self.warn(format_args!(
                    "{who} has {INSTANCING} but no mesh; the instances are ignored (the extension places a node's mesh)"
                ));
            }
            let instance_list = instances.clone().unwrap_or_else(|| vec![Mat4::IDENTITY]);
            if let (Some(list), Some(_)) = (&instances, node.mesh()) {
                self.scene.instanced_nodes += 1;
                self.scene.instances += list.len();
            }

            if let Some(mesh) = node.mesh() {
                let skin = node.skin().map(|s| s.index());
                let weights = self
                    .scene
                    .rig
                    .nodes
                    .get(node.index())
                    .map(|n| n.weights.clone())
                    .unwrap_or_default();
                for (id, &instance) in self
                    .mesh_ids(&mesh)?
                    .into_iter()
                    .flat_map(|id| instance_list.iter().map(move |m| (id, m)))
                {
                    let triangles = self.scene.meshes.get(id).map_or(0, |m| m.indices.len() / 3);
                    self.triangles_drawn = self.triangles_drawn.saturating_add(triangles as u64);
                    if self.triangles_drawn > MAX_DRAWN_TRIANGLES {
                        return Err(self.error(format_args!(
                            "{who} brings the triangles drawn to {}, more than weft's limit of {MAX_DRAWN_TRIANGLES} per frame; draw fewer copies of the mesh or decimate it",
                            self.triangles_drawn
                        )));
                    }
                    let deform = self.scene.rig.meshes.get(&id);
                    let targets = deform.map_or(0, |d| d.targets.len());
                    // A skin applies only to primitives with joints; the others follow the node.
                    let skin = skin.filter(|_| deform.is_some_and(|d| !d.skin.is_empty()));
                    self.scene.rig.draws.push(animation::DrawBinding {
                        draw: self.scene.draws.len(),
                        node: node.index(),
                        skin,
                        weights: (0..targets)
                            .map(|k| weights.get(k).copied().unwrap_or(0.0))
                            .collect(),
                        instance,
                    });
                    // A transmissive surface lets the light through: it casts no shadow (a
                    // shadow map holds opaque cover only).
                    let transmissive = self
                        .scene
                        .meshes
                        .get(id)
                        .and_then(|m| self.scene.materials.get(m.material))
                        .is_some_and(|m| m.transmission.as_ref().is_some_and(|t| t.factor > 0.0));
                    self.scene.draws.push(Draw {
                        cast_shadows: flags.cast && !transmissive,
                        receive_shadows: flags.receive,
                        ..Draw::new(id, world * instance)
                    });
                }
            }
            if let Some(camera) = node.camera() {
                let before = self.scene.cameras.len();
                self.place_camera(camera.index(), world, &who);
                if self.scene.cameras.len() > before {
                    self.scene.rig.cameras.push((before, node.index()));
                }
            }
            let light = doc
                .as_json()
                .nodes
                .get(node.index())
                .and_then(|n| n.extensions.as_ref())
                .and_then(|e| e.khr_lights_punctual.as_ref())
                .map(|l| l.light.value());
            if let Some(light) = light {
                let before = self.scene.lights.len();
                self.place_light(light, world, &who)?;
                if self.scene.lights.len() > before {
                    self.scene.rig.lights.push((before, node.index()));
                }
            }
            for child in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((child, world, flags));
            }
        }
        Ok(())
    }

    /// EXT_mesh_gpu_instancing: the node's instance transforms (translation × rotation × scale,
    /// each from its accessor or the identity), None when the node has no such extension. The
    /// accessors must have one count; rotations are normalised (a zero or non-finite one, like a
    /// non-finite translation or scale, is an error naming the instance).
    fn instance_transforms(
        &mut self,
        node: &gltf::Node<'a>,
        who: &str,
    ) -> Result<Option<Vec<Mat4>>> {
        let Some(ext) = node.extension_value(INSTANCING) else {
            return Ok(None);
        };
        let Some(attributes) = ext.get("attributes").and_then(|a| a.as_object()) else {
            return Err(self.error(format_args!(
                "{who}: {INSTANCING} has no \"attributes\" object; it needs TRANSLATION, ROTATION and/or SCALE accessors: fix or re-export the node"
            )));
        };
        let mut count: Option<(usize, &str)> = None;
        let mut columns: [Option<Vec<f32>>; 3] = [None, None, None];
        for (k, (key, dims, n)) in [
            ("TRANSLATION", Dimensions::Vec3, 3),
            ("ROTATION", Dimensions::Vec4, 4),
            ("SCALE", Dimensions::Vec3, 3),
        ]
        .into_iter()
        .enumerate()
        {
            let Some(value) = attributes.get(key) else {
                continue;
            };
            let Some(index) = value.as_u64().and_then(|i| usize::try_from(i).ok()) else {
                return Err(self.error(format_args!(
                    "{who}: {INSTANCING}.attributes.{key} is {}, not an accessor index: fix the node",
                    short_json(value)
                )));
            };
            let Some(acc) = self.doc.accessors().nth(index) else {
                return Err(self.error(format_args!(
                    "{who}: {INSTANCING}.attributes.{key} names accessor {index}, but the file has only {} accessor(s): fix the index",
                    self.doc.accessors().len()
                )));
            };
            if key == "ROTATION"
                && acc.data_type() != gltf::accessor::DataType::F32
                && !acc.normalized()
            {
                return Err(self.error(format_args!(
                    "{who}: {INSTANCING} ROTATION (accessor {index}) has component type {:?} without normalized; rotations are float or normalized byte or short quaternions: re-export the node",
                    acc.data_type()
                )));
            }
            let what = format!("{who}, {INSTANCING} {key}");
            let values = accessor::read_f32(
                &acc,
                dims,
                self.buffers,
                &Use {
                    source: &self.label,
                    what: &what,
                },
            )?;
            let c = values.len() / n;
            match count {
                Some((other, name)) if other != c => {
                    return Err(self.error(format_args!(
                        "{who}: {INSTANCING} {key} has {c} elements but {name} has {other}; every attribute has one element per instance: fix the accessors"
                    )))
                }
                _ => count = Some((c, key)),
            }
            columns[k] = Some(values);
        }
        let Some((count, _)) = count else {
            self.warn(format_args!(
                "{who}: {INSTANCING} has none of TRANSLATION, ROTATION and SCALE; the mesh is drawn once"
            ));
            return Ok(None);
        };
        let total = self.scene.instances.saturating_add(count);
        if total > MAX_INSTANCES {
            return Err(self.error(format_args!(
                "{who} brings the {INSTANCING} instances to {total}, more than weft's limit of {MAX_INSTANCES} (each is a draw of its own): use fewer instances"
            )));
        }
        let [t, r, s] = &columns;
        let mut out = Vec::with_capacity(count);
        for i in 0..count {
            let v3 = |c: &Option<Vec<f32>>, default: Vec3| {
                c.as_ref()
                    .map_or(default, |v| Vec3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2]))
            };
            let translation = v3(t, Vec3::ZERO);
            let scale = v3(s, Vec3::ONE);
            let rotation = r.as_ref().map_or(Quat::IDENTITY, |v| {
                Quat::from_xyzw(v[4 * i], v[4 * i + 1], v[4 * i + 2], v[4 * i + 3])
            });
            if !(translation.is_finite() && scale.is_finite() && rotation.is_finite())
                || rotation.length_squared() < 1e-12
            {
                return Err(self.error(format_args!(
                    "{who}: {INSTANCING} instance {i} has translation {translation}, rotation {rotation} and scale {scale}; each must be finite and the rotation a unit quaternion: fix the accessors"
                )));
            }
            out.push(Mat4::from_scale_rotation_translation(
                scale,
                rotation.normalize(),
                translation,
            ));
        }
        Ok(Some(out))
    }

    /// The node's `extras.cast_shadows` and `extras.receive_shadows` (true or false), each
    /// `inherited` from the parent when absent (docs/scene-format.md).
    fn node_shadow_flags(
        &mut self,
        index: usize,
        inherited: ShadowFlags,
        who: &str,
    ) -> Result<ShadowFlags> {
        let extras = self
            .doc
            .as_json()
            .nodes
            .get(index)
            .and_then(|n| extras_object(&n.extras));
        let Some(extras) = extras else {
            return Ok(inherited);
        };
        let flag = |key: &str, inherited: bool| -> Result<bool> {
            match extras.get(key) {
                None => Ok(inherited),
                Some(serde_json::Value::Bool(b)) => Ok(*b),
                Some(other) => Err(self.error(format_args!(
                    "{who} has extras.{key} = {}; it must be true or false (false: this node and its descendants {}; a descendant may set it again): fix the node's extras",
                    short_json(other),
                    if key == "cast_shadows" { "cast no shadows" } else { "are not darkened by shadows" },
                ))),
            }
        };
        let flags = ShadowFlags {
            cast: flag("cast_shadows", inherited.cast)?,
            receive: flag("receive_shadows", inherited.receive)?,
        };
        if extras.contains_key("shadows") {
            self.warn(format_args!(
                "{who} has extras.shadows, which weft ignores on a node: a light asks for shadows in its own extras (in the KHR_lights_punctual \"lights\" list), and a node sets extras.cast_shadows / extras.receive_shadows"
            ));
        }
        Ok(flags)
    }

    fn local_transform(&self, node: &gltf::Node<'a>, who: &str) -> Result<Mat4> {
        Ok(match node.transform() {
            gltf::scene::Transform::Matrix { matrix } => Mat4::from_cols_array_2d(&matrix),
            gltf::scene::Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => {
                let q = Quat::from_array(rotation);
                // glTF requires unit quaternions; exporters round, so normalise, but a zero one is wrong.
                let q = if q.length_squared() > 1e-12 && q.is_finite() {
                    q.normalize()
                } else {
                    return Err(self.error(format_args!(
                        "{who} has the rotation {rotation:?}, which is not a unit quaternion; set it to [x, y, z, w] of length 1 ([0, 0, 0, 1] for none)"
                    )));
                };
                Mat4::from_scale_rotation_translation(Vec3::from(scale), q, Vec3::from(translation))
            }
        })
    }

    fn place_light(&mut self, index: usize, world: Mat4, who: &str) -> Result<()> {
        let Some(def) = self.lights.get(index) else {
            return Err(self.error(format_args!(
                "{who} refers to light {index}, which does not exist; fix the node's KHR_lights_punctual.light"
            )));
        };
        let position = world.w_axis.truncate();
        let Some(direction) = (world * Vec4::new(0.0, 0.0, -1.0, 0.0))
            .truncate()
            .try_normalize()
        else {
            let name = def.name.clone();
            self.warn(format_args!(
                "{who} scales light '{name}' to nothing, so it has no direction; the light is skipped"
            ));
            return Ok(());
        };
        self.scene.lights.push(Light {
            name: def.name.clone(),
            kind: def.kind,
            color: def.color,
            intensity: def.intensity,
            range: def.range,
            position,
            direction,
            shadow: def.shadow,
        });
        Ok(())
    }

    fn place_camera(&mut self, index: usize, world: Mat4, who: &str) {
        let Some(Some(def)) = self.cameras.get(index) else {
            return;
        };
        // The view is the inverse of the node's rigid motion: scale (even mirroring) is removed,
        // keeping the view direction (-Z) and the up direction (+Y) of the node.
        let Some(mut camera) = animation::placed_camera(
            def.name.clone(),
            world,
            def.yfov,
            def.znear,
            def.zfar,
            def.aspect_ratio,
        ) else {
            let name = def.name.clone();
            self.warn(format_args!(
                "{who} scales camera '{name}' to nothing, so it has no orientation; the camera is skipped"
            ));
            return;
        };
        camera.orthographic = def.orthographic;
        self.scene.cameras.push(camera);
    }
}

// --- animation: nodes, skins, channels ---------------------------------------------------------

impl<'a> Loader<'a> {
    /// Every node's parent, rest transform and rest morph weights ([`animation::Rig::nodes`], by
    /// glTF node index).
    fn rig_nodes(&mut self) -> Result<()> {
        let doc = self.doc;
        let mut parent = vec![None; doc.nodes().len()];
        for node in doc.nodes() {
            for child in node.children() {
                if let Some(p) = parent.get_mut(child.index()) {
                    *p = Some(node.index());
                }
            }
        }
        for node in doc.nodes() {
            let targets = node
                .mesh()
                .and_then(|m| m.primitives().next())
                .map_or(0, |p| p.morph_targets().len());
            let weights = node
                .weights()
                .or_else(|| node.mesh().and_then(|m| m.weights()))
                .map(<[f32]>::to_vec)
                .unwrap_or_else(|| vec![0.0; targets]);
            if weights.iter().any(|w| !w.is_finite()) {
                return Err(self.error(format_args!(
                    "node {} (or its mesh) has a non-finite morph target weight in {weights:?}; set finite weights",
                    node.index()
                )));
            }
            let (matrix, translation, rotation, scale) = match node.transform() {
                gltf::scene::Transform::Matrix { matrix } => (
                    Some(Mat4::from_cols_array_2d(&matrix)),
                    Vec3::ZERO,
                    Quat::IDENTITY,
                    Vec3::ONE,
                ),
                gltf::scene::Transform::Decomposed {
                    translation,
                    rotation,
                    scale,
                } => {
                    let q = Quat::from_array(rotation);
                    // The walk refuses a bad quaternion on nodes the scene reaches.
                    let q = if q.length_squared() > 1e-12 && q.is_finite() {
                        q.normalize()
                    } else {
                        Quat::IDENTITY
                    };
                    (None, Vec3::from(translation), q, Vec3::from(scale))
                }
            };
            self.scene.rig.nodes.push(animation::Node {
                parent: parent.get(node.index()).copied().flatten(),
                matrix,
                translation,
                rotation,
                scale,
                weights,
            });
        }
        Ok(())
    }

    /// The file's skins (by glTF skin index), checked against the draws that use them.
    fn load_skins(&mut self) -> Result<()> {
        let doc = self.doc;
        for skin in doc.skins() {
            let name = skin
                .name()
                .map(str::to_owned)
                .unwrap_or_else(|| format!("skin {}", skin.index()));
            let who = format!("skin '{name}'");
            let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
            if joints.len() > animation::MAX_JOINTS {
                return Err(self.error(format_args!(
                    "{who} has {} joints, more than glTF's limit of {} (joint indices are unsigned shorts); split the skeleton",
                    joints.len(),
                    animation::MAX_JOINTS
                )));
            }
            let inverse_bind = match skin.inverse_bind_matrices() {
                None => vec![Mat4::IDENTITY; joints.len()],
                Some(acc) => {
                    let what = format!("{who}, inverseBindMatrices");
                    let index = acc.index();
                    let values = accessor::read_f32(
                        &acc,
                        Dimensions::Mat4,
                        self.buffers,
                        &Use {
                            source: &self.label,
                            what: &what,
                        },
                    )?;
                    let m: Vec<Mat4> = values.chunks_exact(16).map(Mat4::from_cols_slice).collect();
                    if m.len() != joints.len() {
                        return Err(self.error(format_args!(
                            "{who} has {} joints but its inverseBindMatrices (accessor {index}) hold {} matrices; glTF requires one per joint: re-export the skin",
                            joints.len(),
                            m.len()
                        )));
                    }
                    if let Some(k) = m.iter().position(|m| !m.is_finite()) {
                        return Err(self.error(format_args!(
                            "{who}: inverse bind matrix {k} is not finite; re-export the skin"
                        )));
                    }
                    m
                }
            };
            self.scene.rig.skins.push(animation::Skin {
                name,
                joint_matrices: vec![Mat4::IDENTITY; joints.len()],
                joints,
                inverse_bind,
            });
        }
        for b in &self.scene.rig.draws {
            let Some(s) = b.skin else { continue };
            let Some(d) = self.scene.draws.get(b.draw) else {
                continue;
            };
            let skin = &self.scene.rig.skins[s];
            let mesh = &self.scene.meshes[d.mesh];
            let Some(deform) = self.scene.rig.meshes.get(&d.mesh) else {
                continue;
            };
            for (v, vs) in deform.skin.iter().enumerate() {
                if let Some(k) = (0..4)
                    .find(|&k| vs.weights[k] > 0.0 && vs.joints[k] as usize >= skin.joints.len())
                {
                    return Err(self.error(format_args!(
                        "mesh '{}' (skinned by node {} with {}) has vertex {v} bound to joint {} (JOINTS_0), but the skin has only {} joint(s); fix the joint indices or the skin's joint list",
                        mesh.name,
                        b.node,
                        skin.name,
                        vs.joints[k],
                        skin.joints.len()
                    )));
                }
            }
        }
        Ok(())
    }

    /// The file's animations: every channel checked, a broken one dropped with a warning (the
    /// scene still renders, and the rest of the animation still plays).
    fn load_animations(&mut self) -> Result<()> {
        let doc = self.doc;
        for anim in doc.animations() {
            let name = anim
                .name()
                .map(str::to_owned)
                .unwrap_or_else(|| format!("animation {}", anim.index()));
            let mut channels = Vec::new();
            for (c, channel) in anim.channels().enumerate() {
                let who = format!("animation '{name}' channel {c}");
                // The gltf crate's validator does not check a channel's target node, and its
                // Target::node() unwraps it: check before anything asks for it.
                let node = doc.as_json().animations[anim.index()].channels[c]
                    .target
                    .node
                    .value();
                if node >= doc.nodes().len() {
                    self.warn(format_args!(
                        "{who} targets node {node}, but the file has only {} node(s); the channel is ignored",
                        doc.nodes().len()
                    ));
                    continue;
                }
                match self.channel(&channel, &who) {
                    Ok(Some(ch)) => channels.push(ch),
                    Ok(None) => {}
                    Err(why) => self.warn(format_args!("{who} {why}; the channel is ignored")),
                }
            }
            let duration = channels
                .iter()
                .map(|c: &animation::Channel| c.sampler.end())
                .fold(0.0f32, f32::max);
            self.scene.rig.infos.push(animation::AnimationInfo {
                name: name.clone(),
                duration,
            });
            self.scene
                .rig
                .animations
                .push(animation::Animation { name, channels });
        }
        Ok(())
    }

    fn channel(
        &mut self,
        channel: &gltf::animation::Channel<'a>,
        who: &str,
    ) -> std::result::Result<Option<animation::Channel>, String> {
        use gltf::animation::{Interpolation as I, Property};
        let target = channel.target();
        let node = target.node();
        let (path, width, dims) = match target.property() {
            Property::Translation => (animation::Path::Translation, 3, Dimensions::Vec3),
            Property::Rotation => (animation::Path::Rotation, 4, Dimensions::Vec4),
            Property::Scale => (animation::Path::Scale, 3, Dimensions::Vec3),
            Property::MorphTargetWeights => {
                let targets = self
                    .scene
                    .rig
                    .nodes
                    .get(node.index())
                    .map_or(0, |n| n.weights.len());
                if targets == 0 {
                    return Err(format!(
                        "animates the morph weights of node {}, which has no morph targets",
                        node.index()
                    ));
                }
                (animation::Path::Weights, targets, Dimensions::Scalar)
            }
        };
        if self
            .scene
            .rig
            .nodes
            .get(node.index())
            .is_some_and(|n| n.matrix.is_some())
            && path != animation::Path::Weights
        {
            return Err(format!(
                "animates node {}, which is given by a matrix (glTF allows channels only on nodes with translation, rotation and scale)",
                node.index()
            ));
        }
        let sampler = channel.sampler();
        let read = |acc: gltf::Accessor, dims: Dimensions, what: &str| {
            accessor::read_f32(
                &acc,
                dims,
                self.buffers,
                &Use {
                    source: &self.label,
                    what: &format!("{who}, {what}"),
                },
            )
            .map_err(|e| format!("cannot be read: {e}"))
        };
        let times = read(sampler.input(), Dimensions::Scalar, "sampler input")?;
        let values = read(sampler.output(), dims, "sampler output")?;
        let interpolation = match sampler.interpolation() {
            I::Step => animation::Interpolation::Step,
            I::Linear => animation::Interpolation::Linear,
            I::CubicSpline => animation::Interpolation::CubicSpline,
        };
        animation::Channel::new(node.index(), path, interpolation, times, values, width).map(Some)
    }
}
