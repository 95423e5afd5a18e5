//! KHR_animation_pointer (ratified 2024): channels that drive a material's, a light's or a
//! camera's properties through a JSON pointer. Such a file was refused whole ("missing field
//! `node`": the gltf crate's schema predates the extension); now its pointer channels play, one
//! weft cannot follow is a warning naming it, and a sequence render re-uploads the driven
//! materials each frame (the GPU test at the end).

mod common;

use serde_json::{json, Value};
use weft::scene::{self, Scene};

/// A .glb: one triangle facing +Z (material 0, double-sided), a point light (light 0) and a
/// perspective camera (camera 0) on nodes, and one animation whose channels are `channels`
/// (their samplers: 0..n of `samplers`, each `(times, values, type)`).
fn glb(
    material: Value,
    channels: Vec<Value>,
    samplers: &[(&[f32], &[f32], &str)],
    required: bool,
) -> Vec<u8> {
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut push = |bin: &mut Vec<u8>, values: &[f32], acc: Value| {
        let at = bin.len();
        bin.extend(values.iter().flat_map(|x| x.to_le_bytes()));
        views.push(json!({"buffer": 0, "byteOffset": at, "byteLength": values.len() * 4}));
        let mut acc = acc;
        acc["bufferView"] = json!(views.len() - 1);
        acc["componentType"] = json!(5126);
        accessors.push(acc);
        accessors.len() - 1
    };
    let pos = push(
        &mut bin,
        &[-1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 0.0, 1.0, 0.0],
        json!({"count": 3, "type": "VEC3", "min": [-1.0, -1.0, 0.0], "max": [1.0, 1.0, 0.0]}),
    );
    let nrm = push(
        &mut bin,
        &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0],
        json!({"count": 3, "type": "VEC3"}),
    );
    // Texture coordinates inside the left texel of a 2 x 1 red | blue image (texture 0,
    // nearest filtering): a texture transform's offset of 0.5 in u shows the blue one.
    let uv = push(
        &mut bin,
        &[0.2, 0.4, 0.3, 0.4, 0.25, 0.6],
        json!({"count": 3, "type": "VEC2"}),
    );
    let mut anim_samplers = Vec::new();
    for (times, values, ty) in samplers {
        let input = push(
            &mut bin,
            times,
            json!({"count": times.len(), "type": "SCALAR", "min": [times[0]], "max": [times[times.len() - 1]]}),
        );
        let width = match *ty {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            _ => 4,
        };
        let output = push(
            &mut bin,
            values,
            json!({"count": values.len() / width, "type": ty}),
        );
        anim_samplers.push(json!({"input": input, "output": output, "interpolation": "LINEAR"}));
    }
    let mut png = Vec::new();
    image::RgbImage::from_fn(2, 1, |x, _| {
        image::Rgb(if x == 0 { [255, 0, 0] } else { [0, 0, 255] })
    })
    .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
    .unwrap();
    let png_at = bin.len();
    bin.extend_from_slice(&png);
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    views.push(json!({"buffer": 0, "byteOffset": png_at, "byteLength": png.len()}));
    let png_view = views.len() - 1;
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_animation_pointer", "KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_texture_transform"],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": accessors,
        "images": [{"bufferView": png_view, "mimeType": "image/png"}],
        "samplers": [{"magFilter": 9728, "minFilter": 9728}],
        "textures": [{"source": 0, "sampler": 0}],
        "materials": [material],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv}, "material": 0}]}],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 10.0, "color": [1.0, 1.0, 1.0]}]}},
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 100.0}}],
        "nodes": [
            {"mesh": 0},
            {"translation": [0.0, 0.0, 2.0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"translation": [0.0, 0.0, 3.0], "camera": 0}
        ],
        "scenes": [{"nodes": [0, 1, 2]}],
        "scene": 0,
        "animations": [{"name": "pointed", "channels": channels, "samplers": anim_samplers}]
    });
    if required {
        doc["extensionsRequired"] = json!(["KHR_animation_pointer"]);
    }
    common::glb(&serde_json::to_vec(&doc).unwrap(), &bin)
}

/// Renders frames 0 and 1 of `bytes` (a .glb) as a one-frame-per-second sequence in one
/// process (lavapipe, validation on, no environment; `extra` arguments added), and returns each
/// frame's pixel at (32, 30) of 64x48: a sequence poses each frame and re-uploads what changed.
fn sequence_centres(bytes: &[u8], extra: &[&str]) -> ([u8; 3], [u8; 3]) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scene.glb");
    std::fs::write(&file, bytes).unwrap();
    let out = dir.path().join("f%04d.png");
    let o = common::weft()
        .args(["render", "--validate", "--size", "64x48", "--env", "none"])
        .args(extra)
        .args(["--frames-range", "0..1", "--fps", "1", "-o"])
        .arg(&out)
        .arg(&file)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let centre = |f: u32| {
        image::open(dir.path().join(format!("f{f:04}.png")))
            .unwrap()
            .to_rgb8()
            .get_pixel(32, 30)
            .0
    };
    (centre(0), centre(1))
}

fn pointer(sampler: usize, pointer: &str) -> Value {
    json!({"sampler": sampler, "target": {"path": "pointer", "extensions": {"KHR_animation_pointer": {"pointer": pointer}}}})
}

fn load(bytes: &[u8]) -> Scene {
    scene::load_slice(bytes, "pointer.glb", None).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: &[f32], b: &[f32]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5)
}

#[test]
fn material_factors_follow_their_pointers() {
    let material = json!({
        "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0},
        "emissiveFactor": [0.0, 0.0, 0.0],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0}},
        "doubleSided": true
    });
    let bytes = glb(
        material,
        vec![
            pointer(0, "/materials/0/pbrMetallicRoughness/baseColorFactor"),
            pointer(1, "/materials/0/pbrMetallicRoughness/roughnessFactor"),
            pointer(2, "/materials/0/emissiveFactor"),
        ],
        &[
            (
                &[0.0, 1.0],
                &[1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0],
                "VEC4",
            ),
            // Keyframes outside [0, 1] are clamped as the loader clamps the file's factor.
            (&[0.0, 1.0], &[0.2, 1.6], "SCALAR"),
            (&[0.0, 2.0], &[0.0, 0.0, 0.0, 1.0, 0.5, 0.0], "VEC3"),
        ],
        true,
    );
    let mut s = load(&bytes);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.animations()[0].duration, 2.0);
    s.pose(0, 0.5).unwrap();
    let m = &s.materials[0];
    assert!(
        close(&m.base_color, &[0.5, 0.0, 0.5, 1.0]),
        "{:?}",
        m.base_color
    );
    assert!((m.roughness - 0.9).abs() < 1e-5, "{}", m.roughness);
    // emissiveFactor (0.25, 0.125, 0) times the file's emissiveStrength 2.
    assert!(close(&m.emissive, &[0.5, 0.25, 0.0]), "{:?}", m.emissive);
    s.pose(0, 1.0).unwrap();
    assert!(close(&s.materials[0].base_color, &[0.0, 0.0, 1.0, 1.0]));
    assert_eq!(s.materials[0].roughness, 1.0);
    // Back at rest: the file's values.
    s.rest_pose().unwrap();
    let m = &s.materials[0];
    assert!(
        close(&m.base_color, &[1.0, 0.0, 0.0, 1.0]),
        "{:?}",
        m.base_color
    );
    assert!(close(&m.emissive, &[0.0, 0.0, 0.0]));
    assert_eq!(m.roughness, 1.0, "glTF's default roughness factor");
}

#[test]
fn lights_cameras_and_nodes_follow_their_pointers() {
    let bytes = glb(
        json!({"doubleSided": true}),
        vec![
            pointer(0, "/extensions/KHR_lights_punctual/lights/0/intensity"),
            pointer(1, "/extensions/KHR_lights_punctual/lights/0/color"),
            pointer(2, "/cameras/0/perspective/yfov"),
            pointer(3, "/nodes/0/translation"),
        ],
        &[
            (&[0.0, 1.0], &[10.0, 30.0], "SCALAR"),
            (&[0.0, 1.0], &[1.0, 1.0, 1.0, 0.0, 1.0, 0.0], "VEC3"),
            (&[0.0, 1.0], &[0.8, 0.4], "SCALAR"),
            (&[0.0, 1.0], &[0.0, 0.0, 0.0, 0.0, 2.0, 0.0], "VEC3"),
        ],
        false,
    );
    let mut s = load(&bytes);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    s.pose(0, 0.5).unwrap();
    assert!((s.lights[0].intensity - 20.0).abs() < 1e-4);
    assert!(close(&s.lights[0].color, &[0.5, 1.0, 0.5]));
    assert!((s.cameras[0].yfov - 0.6).abs() < 1e-6);
    assert!(close(
        &s.draws[0].world.w_axis.truncate().to_array(),
        &[0.0, 1.0, 0.0]
    ));
    // The light keeps its node's place while its intensity is driven.
    assert!(close(&s.lights[0].position.to_array(), &[0.0, 0.0, 2.0]));
    s.rest_pose().unwrap();
    assert_eq!(s.lights[0].intensity, 10.0);
    assert_eq!(s.cameras[0].yfov, 0.8);
}

#[test]
fn a_pointer_weft_cannot_follow_is_a_warning_naming_it_and_the_rest_plays() {
    let bytes = glb(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0]}}),
        vec![
            pointer(
                0,
                "/materials/0/pbrMetallicRoughness/baseColorTexture/texCoord",
            ),
            pointer(
                1,
                "/materials/0/extensions/KHR_materials_transmission/transmissionFactor",
            ),
            pointer(1, "/materials/7/pbrMetallicRoughness/metallicFactor"),
            pointer(1, "/materials/0/pbrMetallicRoughness/metallicFactor"),
            json!({"sampler": 1, "target": {"path": "pointer"}}),
        ],
        &[
            (&[0.0, 1.0], &[0.0, 1.0], "SCALAR"),
            (&[0.0, 1.0], &[1.0, 0.0], "SCALAR"),
        ],
        true,
    );
    let mut s = load(&bytes);
    let w: Vec<&str> = s.warnings.iter().map(|w| w.0.as_str()).collect();
    let has = |a: &str, b: &str| {
        w.iter()
            .any(|w| w.contains(a) && w.contains(b) && w.contains("ignored"))
    };
    assert!(
        has("channel 0", "texCoord', which weft does not animate"),
        "{w:?}"
    );
    assert!(
        has("channel 1", "it has no KHR_materials_transmission"),
        "{w:?}"
    );
    assert!(
        has(
            "channel 2",
            "material 7, but the file has only 1 material(s)"
        ),
        "{w:?}"
    );
    assert!(
        has(
            "channel 4",
            "no KHR_animation_pointer extension with a pointer"
        ),
        "{w:?}"
    );
    assert_eq!(w.len(), 4, "{w:?}");
    s.pose(0, 1.0).unwrap();
    assert_eq!(s.materials[0].metallic, 0.0, "channel 3 plays");
}

/// Node channels keep the file's numbering in messages when pointer channels sit between them.
#[test]
fn node_channel_messages_name_the_files_channel() {
    let bytes = glb(
        json!({}),
        vec![
            pointer(0, "/materials/0/pbrMetallicRoughness/metallicFactor"),
            json!({"sampler": 0, "target": {"node": 0, "path": "weights"}}),
        ],
        &[(&[0.0, 1.0], &[1.0, 0.0], "SCALAR")],
        false,
    );
    let s = load(&bytes);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.0.contains("channel 1") && w.0.contains("no morph targets")),
        "{:?}",
        s.warnings
    );
}

/// A sequence re-uploads the driven material every frame (`Renderer::update_pose`): frame 0 is
/// red, frame 1 blue, in one process (lavapipe, validation on).
#[test]
fn a_sequence_shows_the_driven_colour_in_every_frame() {
    let bytes = glb(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}, "doubleSided": true}),
        vec![pointer(
            0,
            "/materials/0/pbrMetallicRoughness/baseColorFactor",
        )],
        &[(
            &[0.0, 1.0],
            &[1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0],
            "VEC4",
        )],
        false,
    );
    let (first, second) = sequence_centres(&bytes, &[]);
    assert!(first[0] > 60 && first[2] < 10, "frame 0 is red: {first:?}");
    assert!(
        second[2] > 60 && second[0] < 10,
        "frame 1 is blue: {second:?}"
    );
}

/// A texture transform's offset, driven: the slot's map moves (relative to the coordinates the
/// vertices carry, which hold the file's transform), and the rendered colour with it.
#[test]
fn a_texture_transform_follows_its_pointer() {
    let tex = |offset: [f32; 2]| {
        json!({"pbrMetallicRoughness": {"metallicFactor": 0.0, "baseColorTexture": {"index": 0,
            "extensions": {"KHR_texture_transform": {"offset": offset}}}}, "doubleSided": true})
    };
    let path = "/materials/0/pbrMetallicRoughness/baseColorTexture/extensions/KHR_texture_transform/offset";
    let bytes = glb(
        tex([0.0, 0.0]),
        vec![pointer(0, path)],
        &[(&[0.0, 1.0], &[0.0, 0.0, 0.5, 0.0], "VEC2")],
        false,
    );
    let mut s = load(&bytes);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    s.pose(0, 1.0).unwrap();
    let m = s.materials[0].uv[0].m;
    assert!(close(&[m[0][2], m[1][2]], &[0.5, 0.0]), "{m:?}");
    // The file's own transform is baked into the vertices: a pose moves relative to it.
    let baked = glb(
        tex([0.25, 0.0]),
        vec![pointer(0, path)],
        &[(&[0.0, 1.0], &[0.25, 0.0, 0.75, 0.0], "VEC2")],
        false,
    );
    let mut s = load(&baked);
    s.pose(0, 0.0).unwrap();
    assert!(
        close(&[s.materials[0].uv[0].m[0][2]], &[0.0]),
        "{:?}",
        s.materials[0].uv[0].m
    );
    s.pose(0, 1.0).unwrap();
    assert!(
        close(&[s.materials[0].uv[0].m[0][2]], &[0.5]),
        "{:?}",
        s.materials[0].uv[0].m
    );

    let (first, second) = sequence_centres(&bytes, &[]);
    assert!(
        first[0] > 60 && first[2] < 10,
        "frame 0 shows the red texel: {first:?}"
    );
    assert!(
        second[2] > 60 && second[0] < 10,
        "frame 1 shows the blue texel: {second:?}"
    );
}

/// `bytes` (a .glb from [`glb`]) with its JSON changed by `f`.
fn patch(bytes: &[u8], f: impl FnOnce(&mut Value)) -> Vec<u8> {
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut doc: Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    f(&mut doc);
    let bin_len =
        u32::from_le_bytes(bytes[20 + json_len..24 + json_len].try_into().unwrap()) as usize;
    common::glb(
        &serde_json::to_vec(&doc).unwrap(),
        &bytes[28 + json_len..28 + json_len + bin_len],
    )
}

/// KHR_node_visibility (ratified): `visible` false hides a node's subtree (its meshes and its
/// lights, not its cameras), and a pointer channel shows it again.
#[test]
fn node_visibility_hides_the_subtree_and_a_pointer_shows_it() {
    let red = json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}, "doubleSided": true});
    let path = "/nodes/3/extensions/KHR_node_visibility/visible";
    let bytes = patch(
        &glb(
            red,
            vec![pointer(0, path)],
            &[(&[0.0, 1.0], &[0.0, 1.0], "SCALAR")],
            false,
        ),
        |doc| {
            // Node 3 (hidden) holds the mesh node 0 and the light node 1 as children; its
            // child's own `visible` true does not show it.
            doc["nodes"][0]["extensions"] = json!({"KHR_node_visibility": {"visible": true}});
            doc["nodes"]
                .as_array_mut()
                .unwrap()
                .push(json!({"children": [0, 1], "extensions": {"KHR_node_visibility": {"visible": false}}}));
            doc["scenes"][0]["nodes"] = json!([3, 2]);
            doc["extensionsUsed"]
                .as_array_mut()
                .unwrap()
                .push(json!("KHR_node_visibility"));
            doc["extensionsRequired"] = json!(["KHR_node_visibility"]);
        },
    );
    let mut s = load(&bytes);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert!(!s.draws[0].visible, "hidden at rest");
    assert_eq!(s.lights[0].intensity, 0.0, "its light is dark");
    assert!(s.bounds().is_none(), "a hidden draw is in no bounds");
    assert_eq!(s.cameras.len(), 1, "cameras are not hidden");
    s.pose(0, 1.0).unwrap();
    assert!(s.draws[0].visible);
    assert_eq!(s.lights[0].intensity, 10.0);
    s.pose(0, 0.0).unwrap();
    assert!(!s.draws[0].visible);

    // On the GPU (lavapipe, validation on): frame 0 shows the background where the red
    // triangle is, frame 1 the triangle.
    let (hidden, shown) = sequence_centres(&bytes, &["--background", "color:0,0,0"]);
    assert!(
        hidden[0] < 10,
        "frame 0: the hidden triangle is not drawn: {hidden:?}"
    );
    assert!(
        shown[0] > 60 && shown[2] < 10,
        "frame 1: the red triangle: {shown:?}"
    );
}

/// `/meshes/M/weights` animates the default morph weights: the nodes that draw mesh M without
/// weights of their own follow it, a node with its own keeps them.
#[test]
fn a_meshs_default_weights_drive_the_nodes_without_their_own() {
    let bytes = patch(
        &glb(
            json!({}),
            vec![pointer(0, "/meshes/0/weights")],
            &[(&[0.0, 1.0], &[0.0, 1.0], "SCALAR")],
            false,
        ),
        |doc| {
            // One morph target moving every vertex by the normal (accessor 1), default weight 0;
            // node 3 draws the mesh with its own weight 0.25.
            doc["meshes"][0]["primitives"][0]["targets"] = json!([{"POSITION": 1}]);
            doc["meshes"][0]["weights"] = json!([0.0]);
            doc["accessors"][1]["min"] = json!([0.0, 0.0, 1.0]);
            doc["accessors"][1]["max"] = json!([0.0, 0.0, 1.0]);
            doc["nodes"]
                .as_array_mut()
                .unwrap()
                .push(json!({"mesh": 0, "weights": [0.25], "translation": [3.0, 0.0, 0.0]}));
            doc["scenes"][0]["nodes"]
                .as_array_mut()
                .unwrap()
                .push(json!(3));
        },
    );
    let mut s = load(&bytes);
    assert!(
        s.warnings.iter().all(|w| !w.0.contains("channel")),
        "{:?}",
        s.warnings
    );
    let weight = |s: &Scene, node: usize| {
        s.rig
            .draws
            .iter()
            .find(|b| b.node == node)
            .map(|b| b.weights.clone())
            .unwrap()
    };
    s.pose(0, 0.5).unwrap();
    assert_eq!(
        weight(&s, 0),
        vec![0.5],
        "node 0 follows the mesh's weights"
    );
    assert_eq!(weight(&s, 3), vec![0.25], "node 3 keeps its own");
    assert_eq!(s.animation_drives(0), [1, 0, 0, 0]);
}
