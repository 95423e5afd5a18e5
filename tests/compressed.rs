//! The files production pipelines ship: KHR_mesh_quantization, EXT_texture_webp and
//! EXT_/KHR_meshopt_compression.
//!
//! - The Khronos Avocado put through `gltf-transform` 4.5.1 (tests/data/compressed/README.md) loads
//!   to the mesh of the uncompressed file: same vertex and index counts, every position within the
//!   quantization step, normals, tangents and UVs within theirs.
//! - Files built here with meshoptimizer's own encoders cover every mode (ATTRIBUTES, TRIANGLES,
//!   INDICES, 16- and 32-bit indices) and the vertex filters a mesh uses, under both extension
//!   names and both vertex codec versions; the filters one by one are pinned in
//!   src/scene/compressed.rs's unit tests.
//! - Hostile data (a truncated or corrupted stream, counts that do not match, strides the
//!   specification forbids, data in a fallback buffer) is a clear error naming the file, the buffer
//!   view, the mesh that reads it and what is wrong; never a panic (the loader turns a panic into an
//!   error that says "the glTF reader failed", which these tests refuse).
//! - On the GPU (lavapipe, validation on), each compressed Avocado renders within a stated FLIP of
//!   the original.
//! - KTX2 (KHR_texture_basisu, tests/data/ktx2): UASTC + Zstandard made here with Binomial's
//!   encoder decodes to its source image within a stated bound, ETC1S (BasisLZ) files from
//!   Binomial's own encoder and KTX2 writer decode to exactly Binomial's own transcode, plain 8-bit
//!   layouts under every supercompression weft reads decode exactly, in the colour space of the
//!   material slot; damaged, truncated and unsupported files (broken BasisLZ global data and
//!   slices, BC7, cube maps, bad Zstandard and ZLIB streams) are errors naming the file, the
//!   material and the image, never a panic. The Avocado with UASTC textures (avocado_ktx2.glb) and
//!   with ETC1S textures (avocado_etc1s.glb) render within a stated FLIP of the original (below), and
//!   AnisotropyBarnLamp's textures decode when ../shared is present.
//! - Draco (KHR_draco_mesh_compression) decodes to the original mesh; damaged Draco data is an error.

mod common;

use std::path::{Path, PathBuf};

use glam::{Mat3, Vec3};
use serde_json::{json, Value};
use weft::scene::{self, Scene};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/compressed")
        .join(name)
}

fn load(name: &str) -> Scene {
    let scene = scene::load(&data(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    for w in &scene.warnings {
        assert!(!w.0.contains("extension"), "{name}: {w}");
    }
    scene
}

/// The one mesh of a file, in world space.
struct World {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    tangents: Vec<(Vec3, f32)>,
    uvs: Vec<[f32; 2]>,
    indices: Vec<u32>,
}

fn world(scene: &Scene) -> World {
    assert_eq!(scene.draws.len(), 1, "{}", scene.source);
    let draw = &scene.draws[0];
    let mesh = &scene.meshes[draw.mesh];
    let normal_matrix = Mat3::from_mat4(draw.world).inverse().transpose();
    let linear = Mat3::from_mat4(draw.world);
    World {
        positions: mesh
            .vertices
            .iter()
            .map(|v| draw.world.transform_point3(Vec3::from(v.position)))
            .collect(),
        normals: mesh
            .vertices
            .iter()
            .map(|v| (normal_matrix * Vec3::from(v.normal)).normalize())
            .collect(),
        tangents: mesh
            .vertices
            .iter()
            .map(|v| {
                let t = v.tangent;
                ((linear * Vec3::new(t[0], t[1], t[2])).normalize(), t[3])
            })
            .collect(),
        uvs: mesh.vertices.iter().map(|v| v.uv).collect(),
        indices: mesh.indices.clone(),
    }
}

/// Checks `got` against the uncompressed `want`: same counts; every vertex of `got` has a vertex
/// of `want` within `step` (and the other way round); among those, one whose normal, tangent and
/// UV agree within the attributes' quantization; every triangle of `got` is a triangle of `want`.
fn assert_same_mesh(name: &str, want: &World, got: &World, step: f32) {
    assert_eq!(
        got.positions.len(),
        want.positions.len(),
        "{name}: vertex count"
    );
    assert_eq!(got.indices.len(), want.indices.len(), "{name}: index count");
    let near = |p: Vec3, set: &[Vec3]| -> Vec<usize> {
        (0..set.len())
            .filter(|&i| set[i].distance(p) <= step)
            .collect()
    };
    let mut worst = 0.0f32;
    for (i, &p) in got.positions.iter().enumerate() {
        let close = near(p, &want.positions);
        assert!(
            !close.is_empty(),
            "{name}: vertex {i} at {p} has no original within {step}"
        );
        worst = worst.max(
            close
                .iter()
                .map(|&j| want.positions[j].distance(p))
                .fold(f32::MAX, f32::min),
        );
        // 10-bit octahedral normals and tangents (gltf-transform's default): under 0.2 degrees
        // off, cos > 0.99999; 0.9995 (1.8 degrees) leaves room for the renormalisation.
        let matches = close.iter().any(|&j| {
            got.normals[i].dot(want.normals[j]) > 0.9995
                && got.tangents[i].0.dot(want.tangents[j].0) > 0.9995
                && got.tangents[i].1 == want.tangents[j].1
                // 12-bit texture coordinates: within one step of 1/4095.
                && (0..2).all(|k| (got.uvs[i][k] - want.uvs[j][k]).abs() <= 1.0 / 4095.0)
        });
        assert!(matches, "{name}: vertex {i} at {p}: no original there has its normal {}, tangent {:?} and uv {:?}", got.normals[i], got.tangents[i], got.uvs[i]);
    }
    for &p in &want.positions {
        assert!(
            !near(p, &got.positions).is_empty(),
            "{name}: original vertex at {p} lost"
        );
    }
    // Triangles, as sets of corner positions (the codecs may rotate a triangle's corners).
    let corners =
        |w: &World, t: &[u32]| -> [Vec3; 3] { [0, 1, 2].map(|k| w.positions[t[k] as usize]) };
    let want_tris: Vec<[Vec3; 3]> = want
        .indices
        .chunks_exact(3)
        .map(|t| corners(want, t))
        .collect();
    for (k, t) in got.indices.chunks_exact(3).enumerate() {
        let c = corners(got, t);
        let found = want_tris
            .iter()
            .any(|w| (0..3).any(|r| (0..3).all(|m| w[(m + r) % 3].distance(c[m]) <= step)));
        assert!(
            found,
            "{name}: triangle {k} {c:?} is not a triangle of the original"
        );
    }
    eprintln!("{name}: worst position error {worst:e} (step {step:e})");
}

/// gltf-transform's default position quantization: 14 bits over the mesh's largest extent.
fn position_step(w: &World) -> f32 {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for &p in &w.positions {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    (hi - lo).max_element() / ((1 << 14) - 1) as f32
}

#[test]
fn quantized_avocado_matches_the_original() {
    let want = world(&load("avocado_small.glb"));
    let got = world(&load("avocado_quant.glb"));
    assert_same_mesh("avocado_quant.glb", &want, &got, position_step(&want));
}

#[test]
fn meshopt_avocado_matches_the_original_under_both_extension_names() {
    let want = world(&load("avocado_small.glb"));
    let step = position_step(&want);
    let got = world(&load("avocado_meshopt.glb"));
    assert_same_mesh("avocado_meshopt.glb", &want, &got, step);

    // KHR_meshopt_compression is the same JSON under the ratified name (both names are 23
    // characters, so the .glb's chunk lengths stay right).
    let bytes = std::fs::read(data("avocado_meshopt.glb")).unwrap();
    let khr = replace(
        &bytes,
        b"EXT_meshopt_compression",
        b"KHR_meshopt_compression",
    );
    assert_ne!(khr, bytes);
    let scene = scene::load_slice(&khr, "avocado_khr_meshopt.glb", None).expect("KHR file loads");
    assert_same_mesh("avocado_khr_meshopt.glb", &want, &world(&scene), step);
}

fn replace(bytes: &[u8], from: &[u8], to: &[u8]) -> Vec<u8> {
    assert_eq!(from.len(), to.len());
    let mut out = bytes.to_vec();
    let mut i = 0;
    while i + from.len() <= out.len() {
        if &out[i..i + from.len()] == from {
            out[i..i + from.len()].copy_from_slice(to);
            i += from.len();
        } else {
            i += 1;
        }
    }
    out
}

#[test]
fn webp_avocado_has_the_original_textures_within_lossy_coding() {
    let want = load("avocado_small.glb");
    let got = load("avocado_webp.glb");
    assert_same_mesh("avocado_webp.glb", &world(&want), &world(&got), 0.0);
    assert_eq!(got.textures.len(), want.textures.len());
    for (w, g) in want.textures.iter().zip(&got.textures) {
        assert_eq!(
            (g.width, g.height, g.color_space),
            (w.width, w.height, w.color_space),
            "{}",
            g.name
        );
        let diff = w
            .rgba8
            .iter()
            .zip(&g.rgba8)
            .map(|(a, b)| a.abs_diff(*b) as f64)
            .sum::<f64>()
            / w.rgba8.len() as f64;
        // gltf-transform's WebP is lossy (quality 80): a mean of a few levels in 255.
        assert!(diff < 6.0, "{}: mean difference {diff:.2} of 255", g.name);
        eprintln!("{}: mean difference {diff:.2} of 255", g.name);
    }
}

#[test]
fn ktx2_avocado_has_the_original_textures_within_uastc_coding() {
    let want = load("avocado_small.glb");
    let got = load("avocado_ktx2.glb");
    assert_same_mesh("avocado_ktx2.glb", &world(&want), &world(&got), 0.0);
    assert_eq!(got.textures.len(), want.textures.len());
    for (w, g) in want.textures.iter().zip(&got.textures) {
        assert_eq!(
            (g.width, g.height, g.color_space),
            (w.width, w.height, w.color_space),
            "{}",
            g.name
        );
        let (mean, max) = rgba_difference(&w.rgba8, &g.rgba8);
        eprintln!(
            "{}: mean difference {mean:.2}, largest {max} of 255",
            g.name
        );
        // UASTC at default quality: measured means 0.00 to 0.87 of 255 (the base colour's the
        // largest; lossy WebP at quality 80 is 0.19 to 2.81).
        assert!(mean < 1.5, "{}: mean difference {mean:.2} of 255", g.name);
    }
}

// --- files built here ---------------------------------------------------------------------------

/// A .glb from JSON and one binary chunk.
fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    common::glb(&serde_json::to_vec(json).unwrap(), bin)
}

/// A grid of `n` x `n` vertices on a gently curved sheet, in plain floats.
struct Grid {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 4]>,
    tangents: Vec<[f32; 4]>,
    uvs: Vec<[f32; 2]>,
    indices: Vec<u32>,
}

fn grid(n: u32) -> Grid {
    let mut g = Grid {
        positions: vec![],
        normals: vec![],
        tangents: vec![],
        uvs: vec![],
        indices: vec![],
    };
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f32 / (n - 1) as f32, j as f32 / (n - 1) as f32);
            let x = u * 2.0 - 1.0;
            // z = 0.2 x^2: normal (-0.4 x, 0, 1), tangent along +x (the u direction).
            g.positions.push([x, v * 2.0 - 1.0, 0.2 * x * x]);
            let nrm = Vec3::new(-0.4 * x, 0.0, 1.0).normalize();
            g.normals.push([nrm.x, nrm.y, nrm.z, 0.0]);
            let t = Vec3::new(1.0, 0.0, 0.4 * x).normalize();
            g.tangents.push([t.x, t.y, t.z, 1.0]);
            g.uvs.push([u, 1.0 - v]);
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i;
            g.indices.extend([a, a + 1, a + n, a + n, a + 1, a + n + 1]);
        }
    }
    g
}

/// How one synthesized file is compressed, and what a test breaks in it.
#[derive(Clone)]
struct Recipe {
    ext: &'static str,
    vertex_version: i32,
    /// "TRIANGLES" or "INDICES".
    index_mode: &'static str,
    index_stride: usize,
    /// Applied to the JSON after it is built (to break it).
    edit: fn(&mut Value),
    /// Applied to the binary chunk (to break it).
    corrupt: fn(&mut Vec<u8>),
}

impl Default for Recipe {
    fn default() -> Self {
        Recipe {
            ext: "EXT_meshopt_compression",
            vertex_version: 0,
            index_mode: "TRIANGLES",
            index_stride: 2,
            edit: |_| {},
            corrupt: |_| {},
        }
    }
}

/// The grid as a meshopt-compressed .glb: POSITION as floats with the EXPONENTIAL filter, NORMAL as
/// 8-bit OCTAHEDRAL, TANGENT as 16-bit OCTAHEDRAL, TEXCOORD_0 as normalized 16-bit integers
/// (KHR_mesh_quantization) without a filter, indices in the recipe's mode. Buffer 0 is the .glb
/// chunk with the streams; buffer 1 the fallback. Views 0-3 are the attributes, view 4 the indices.
fn meshopt_glb(g: &Grid, r: &Recipe) -> Vec<u8> {
    let n = g.positions.len();
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut fallback_len = 0usize;
    let mut add = |stream: Vec<u8>,
                   mode: &str,
                   filter: &str,
                   stride: usize,
                   count: usize,
                   target: u32| {
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let mut ext = json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": stream.len(),
            "byteStride": stride, "count": count, "mode": mode});
        if filter != "NONE" {
            ext["filter"] = json!(filter);
        }
        let mut view = json!({"buffer": 1, "byteOffset": fallback_len, "byteLength": stride * count,
            "target": target, "extensions": {r.ext: ext}});
        if target == 34962 {
            view["byteStride"] = json!(stride);
        }
        views.push(view);
        fallback_len += (stride * count + 3) / 4 * 4;
        bin.extend(stream);
    };
    let v = Some(r.vertex_version);
    let pos = meshopt::encode_filter_exp(&g.positions, 23, meshopt::EncodeExpMode::SharedVector);
    add(
        meshopt::encode_vertex_buffer_level(&pos, 2, v).unwrap(),
        "ATTRIBUTES",
        "EXPONENTIAL",
        12,
        n,
        34962,
    );
    let nrm = meshopt::encode_filter_oct::<i8>(&g.normals, 8);
    add(
        meshopt::encode_vertex_buffer_level(&nrm, 2, v).unwrap(),
        "ATTRIBUTES",
        "OCTAHEDRAL",
        4,
        n,
        34962,
    );
    let tan = meshopt::encode_filter_oct::<i16>(&g.tangents, 12);
    add(
        meshopt::encode_vertex_buffer_level(&tan, 2, v).unwrap(),
        "ATTRIBUTES",
        "OCTAHEDRAL",
        8,
        n,
        34962,
    );
    let uv: Vec<[u16; 2]> = g
        .uvs
        .iter()
        .map(|t| t.map(|c| (c * 65535.0).round() as u16))
        .collect();
    add(
        meshopt::encode_vertex_buffer_level(&uv, 2, v).unwrap(),
        "ATTRIBUTES",
        "NONE",
        4,
        n,
        34962,
    );
    let indices = match r.index_mode {
        "TRIANGLES" => meshopt::encode_index_buffer(&g.indices, n).unwrap(),
        _ => meshopt::encode_index_sequence(&g.indices, n).unwrap(),
    };
    add(
        indices,
        r.index_mode,
        "NONE",
        r.index_stride,
        g.indices.len(),
        34963,
    );
    let (lo, hi) = g
        .positions
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), p| {
            (
                [0, 1, 2].map(|k| lo[k].min(p[k])),
                [0, 1, 2].map(|k| hi[k].max(p[k])),
            )
        });
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": [r.ext, "KHR_mesh_quantization"],
        "extensionsRequired": [r.ext, "KHR_mesh_quantization"],
        "buffers": [{"byteLength": bin.len()}, {"byteLength": fallback_len, "extensions": {r.ext: {"fallback": true}}}],
        "bufferViews": views,
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5120, "normalized": true, "count": n, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5122, "normalized": true, "count": n, "type": "VEC4"},
            {"bufferView": 3, "componentType": 5123, "normalized": true, "count": n, "type": "VEC2"},
            {"bufferView": 4, "componentType": if r.index_stride == 2 { 5123 } else { 5125 }, "count": g.indices.len(), "type": "SCALAR"},
        ],
        "meshes": [{"name": "sheet", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TANGENT": 2, "TEXCOORD_0": 3}, "indices": 4}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    });
    (r.edit)(&mut doc);
    (r.corrupt)(&mut bin);
    glb(&doc, &bin)
}

fn load_recipe(r: &Recipe) -> weft::Result<Scene> {
    scene::load_slice(&meshopt_glb(&grid(9), r), "sheet.glb", None)
}

#[test]
fn every_meshopt_mode_and_mesh_filter_decodes_to_the_grid() {
    let g = grid(9);
    for ext in ["EXT_meshopt_compression", "KHR_meshopt_compression"] {
        for vertex_version in [0, 1] {
            for (index_mode, index_stride) in [
                ("TRIANGLES", 2),
                ("TRIANGLES", 4),
                ("INDICES", 2),
                ("INDICES", 4),
            ] {
                let r = Recipe {
                    ext,
                    vertex_version,
                    index_mode,
                    index_stride,
                    ..Recipe::default()
                };
                let what = format!("{ext} v{vertex_version} {index_mode}/{index_stride}");
                let scene = load_recipe(&r).unwrap_or_else(|e| panic!("{what}: {e}"));
                assert!(scene.warnings.is_empty(), "{what}: {:?}", scene.warnings);
                let mesh = &scene.meshes[0];
                assert_eq!(mesh.vertices.len(), g.positions.len(), "{what}");
                for (k, (v, p)) in mesh.vertices.iter().zip(&g.positions).enumerate() {
                    // EXPONENTIAL with 23 mantissa bits and a shared exponent: within 2^-22 of the
                    // largest component (1).
                    for c in 0..3 {
                        assert!(
                            (v.position[c] - p[c]).abs() < 4e-7,
                            "{what}: vertex {k} {:?} against {p:?}",
                            v.position
                        );
                    }
                    // 8-bit octahedral normals: a few degrees; 12-bit tangents: a fraction of one.
                    let n = Vec3::from(v.normal);
                    assert!(
                        n.dot(Vec3::from_slice(&g.normals[k][..3])) > 0.997,
                        "{what}: normal {k} {n}"
                    );
                    let t = Vec3::from_slice(&v.tangent[..3]);
                    assert!(
                        t.dot(Vec3::from_slice(&g.tangents[k][..3])) > 0.9999,
                        "{what}: tangent {k} {t}"
                    );
                    assert_eq!(v.tangent[3], 1.0, "{what}: tangent sign {k}");
                    for c in 0..2 {
                        assert!(
                            (v.uv[c] - g.uvs[k][c]).abs() <= 0.5 / 65535.0 + 1e-7,
                            "{what}: uv {k}"
                        );
                    }
                }
                // The same triangles, each possibly rotated (TRIANGLES may rotate; INDICES keeps
                // the sequence exactly).
                assert_eq!(mesh.indices.len(), g.indices.len(), "{what}");
                for (a, b) in g.indices.chunks_exact(3).zip(mesh.indices.chunks_exact(3)) {
                    let rotations = [[b[0], b[1], b[2]], [b[1], b[2], b[0]], [b[2], b[0], b[1]]];
                    assert!(
                        rotations.contains(&[a[0], a[1], a[2]]),
                        "{what}: triangle {a:?} became {b:?}"
                    );
                    if index_mode == "INDICES" {
                        assert_eq!(a, b, "{what}");
                    }
                }
            }
        }
    }
}

// --- hostile data -------------------------------------------------------------------------------

fn error_of(r: &Recipe) -> String {
    match load_recipe(r) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

/// The message names the file, the view, who reads it, and contains each of `says`.
fn assert_names(msg: &str, view: usize, reader: &str, says: &[&str]) {
    assert!(!msg.contains("the glTF reader failed"), "a panic: {msg}");
    assert!(msg.contains("'sheet.glb'"), "no file name: {msg}");
    assert!(
        msg.contains(&format!("buffer view {view}")),
        "no buffer view {view}: {msg}"
    );
    assert!(msg.contains(reader), "no '{reader}': {msg}");
    for s in says {
        assert!(msg.contains(s), "no '{s}': {msg}");
    }
}

#[test]
fn a_truncated_or_corrupted_stream_is_an_error_naming_the_view_and_the_mesh() {
    // The POSITION stream one byte short: its tail block is then read from the wrong place.
    let r = Recipe {
        edit: |d| {
            let e = &mut d["bufferViews"][0]["extensions"]["EXT_meshopt_compression"];
            e["byteLength"] = json!(e["byteLength"].as_u64().unwrap() - 20);
        },
        ..Recipe::default()
    };
    assert_names(
        &error_of(&r),
        0,
        "mesh 'sheet' primitive 0, attribute POSITION",
        &["does not decode", "EXT_meshopt_compression"],
    );

    // The header byte of the NORMAL stream overwritten.
    let r = Recipe {
        corrupt: |bin| {
            // View 1's stream starts after view 0's, at the first 4-aligned offset; its header is
            // 0xa0 (version 0): find it after the first stream.
            let at = bin
                .iter()
                .enumerate()
                .skip(1)
                .find(|(_, &b)| b == 0xa0)
                .map(|(i, _)| i)
                .unwrap();
            bin[at] = 0x17;
        },
        ..Recipe::default()
    };
    let msg = error_of(&r);
    assert_names(
        &msg,
        1,
        "attribute NORMAL",
        &["does not decode", "not a meshopt stream"],
    );

    // The index stream truncated to 3 bytes.
    let r = Recipe {
        edit: |d| {
            d["bufferViews"][4]["extensions"]["EXT_meshopt_compression"]["byteLength"] = json!(3)
        },
        ..Recipe::default()
    };
    assert_names(
        &error_of(&r),
        4,
        "mesh 'sheet' primitive 0, indices",
        &["does not decode", "mode TRIANGLES"],
    );

    // The stream past the end of its buffer.
    let r = Recipe {
        edit: |d| {
            d["bufferViews"][3]["extensions"]["EXT_meshopt_compression"]["byteOffset"] =
                json!(1 << 20)
        },
        ..Recipe::default()
    };
    assert_names(
        &error_of(&r),
        3,
        "attribute TEXCOORD_0",
        &["lies outside that buffer", "truncated"],
    );

    // The whole binary chunk cut short (the .glb itself declares its length: a container error).
    let mut bytes = meshopt_glb(&grid(9), &Recipe::default());
    bytes.truncate(bytes.len() - 100);
    let msg = scene::load_slice(&bytes, "sheet.glb", None)
        .err()
        .expect("truncated")
        .to_string();
    assert!(
        msg.contains("'sheet.glb'") && msg.contains("truncated"),
        "{msg}"
    );
}

#[test]
fn counts_strides_and_modes_the_specification_forbids_are_errors() {
    type Edit = fn(&mut Value);
    let cases: &[(usize, Edit, &str)] = &[
        (
            0,
            |d| d["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["count"] = json!(80),
            "80 elements of 12 bytes make 960 bytes, and the buffer view's byteLength is 972",
        ),
        (
            0,
            |d| d["bufferViews"][0]["byteLength"] = json!(900),
            "the counts do not match",
        ),
        (
            1,
            |d| {
                d["bufferViews"][1]["extensions"]["EXT_meshopt_compression"]["byteStride"] =
                    json!(8)
            },
            "differs from the buffer view's own byteStride 4",
        ),
        (
            4,
            |d| {
                d["bufferViews"][4]["extensions"]["EXT_meshopt_compression"]["byteStride"] =
                    json!(3)
            },
            "its byteStride is 3; mode TRIANGLES needs 2 or 4",
        ),
        (
            4,
            |d| {
                d["bufferViews"][4]["extensions"]["EXT_meshopt_compression"]["filter"] =
                    json!("OCTAHEDRAL")
            },
            "only ATTRIBUTES takes a filter",
        ),
        (
            1,
            |d| {
                d["bufferViews"][1]["extensions"]["EXT_meshopt_compression"]["filter"] =
                    json!("QUATERNION")
            },
            "filter QUATERNION does not allow (it needs 8)",
        ),
        (
            1,
            |d| {
                d["bufferViews"][1]["extensions"]["EXT_meshopt_compression"]["filter"] =
                    json!("COLOR")
            },
            "COLOR is KHR_meshopt_compression's",
        ),
        (
            1,
            |d| {
                d["bufferViews"][1]["extensions"]["EXT_meshopt_compression"]["filter"] =
                    json!("SMOOTH")
            },
            "filter is \"SMOOTH\"",
        ),
        (
            2,
            |d| {
                d["bufferViews"][2]["extensions"]["EXT_meshopt_compression"]["mode"] =
                    json!("STRIPS")
            },
            "mode is \"STRIPS\"",
        ),
        (
            2,
            |d| {
                d["bufferViews"][2]["extensions"]["EXT_meshopt_compression"]
                    .as_object_mut()
                    .unwrap()
                    .remove("mode");
            },
            "\"mode\" is missing",
        ),
        (
            2,
            |d| d["bufferViews"][2]["extensions"]["EXT_meshopt_compression"]["count"] = json!(-4),
            "\"count\" is -4",
        ),
        (
            3,
            |d| d["bufferViews"][3]["extensions"]["EXT_meshopt_compression"]["buffer"] = json!(1),
            "a fallback buffer that holds no data",
        ),
        (
            3,
            |d| d["bufferViews"][3]["extensions"]["EXT_meshopt_compression"]["buffer"] = json!(7),
            "the file has 2 buffer(s)",
        ),
        (
            3,
            |d| d["bufferViews"][3]["extensions"]["EXT_meshopt_compression"] = json!(12),
            "not an object",
        ),
    ];
    for (view, edit, says) in cases {
        let r = Recipe {
            edit: *edit,
            ..Recipe::default()
        };
        let msg = error_of(&r);
        assert_names(&msg, *view, "mesh 'sheet'", &[says]);
    }
    // A view of the fallback buffer that is not itself compressed has no data.
    let r = Recipe {
        edit: |d| {
            d["bufferViews"][3]
                .as_object_mut()
                .unwrap()
                .remove("extensions");
        },
        ..Recipe::default()
    };
    let msg = error_of(&r);
    assert_names(
        &msg,
        3,
        "attribute TEXCOORD_0",
        &[
            "fallback buffer that holds no data",
            "not compressed itself",
        ],
    );
    // Stride 2 with TRIANGLES needs every index under 65536; a count that is not a multiple of 3.
    let r = Recipe {
        edit: |d| {
            let v = &mut d["bufferViews"][4];
            v["byteLength"] = json!(2 * 383);
            v["extensions"]["EXT_meshopt_compression"]["count"] = json!(383);
        },
        ..Recipe::default()
    };
    assert_names(&error_of(&r), 4, "indices", &["not a multiple of 3"]);
}

#[test]
fn damaged_streams_never_panic() {
    // Every byte of every stream of the Avocado, one at a time, replaced by a few values, and the
    // compressed lengths shortened: the load succeeds (meshoptimizer may decode garbage, which the
    // loader's own checks then judge) or fails with an input error, never with a caught panic.
    let bytes = std::fs::read(data("avocado_meshopt.glb")).unwrap();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let bin_start = 20 + json_len + 8;
    let doc: Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let mut streams = Vec::new();
    for v in doc["bufferViews"].as_array().unwrap() {
        if let Some(e) = v["extensions"].get("EXT_meshopt_compression") {
            let (o, l) = (
                e["byteOffset"].as_u64().unwrap() as usize,
                e["byteLength"].as_u64().unwrap() as usize,
            );
            streams.push(bin_start + o..bin_start + o + l);
        }
    }
    assert_eq!(streams.len(), 5);
    let mut rng = common::Rng(0x2026_0026);
    let (mut ok, mut refused) = (0, 0);
    for _ in 0..600 {
        let s = &streams[rng.below(streams.len())];
        let at = s.start + rng.below(s.len());
        let mut broken = bytes.clone();
        broken[at] = [0x00, 0xff, 0xa1, broken[at] ^ 0x55][rng.below(4)];
        match scene::load_slice(&broken, "broken.glb", None) {
            Ok(_) => ok += 1,
            Err(e) => {
                let msg = e.to_string();
                assert!(!msg.contains("the glTF reader failed"), "a panic: {msg}");
                assert!(msg.contains("'broken.glb'"), "{msg}");
                refused += 1;
            }
        }
    }
    eprintln!("{ok} damaged files loaded, {refused} refused");
    assert!(refused > 0, "no damage was noticed");
}

#[test]
fn webp_is_preferred_over_the_fallback_and_a_bad_source_is_an_error() {
    let png = encoded([200, 0, 0, 255], image::ImageFormat::Png);
    let webp = encoded([0, 200, 0, 255], image::ImageFormat::WebP);
    let mut bin = png.clone();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let webp_at = bin.len();
    bin.extend(&webp);
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let geometry_at = bin.len();
    for f in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend(f.to_le_bytes());
    }
    let doc = |texture: Value| {
        json!({
            "asset": {"version": "2.0"},
            "extensionsUsed": ["EXT_texture_webp"],
            "buffers": [{"byteLength": bin.len()}],
            "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": png.len()},
                {"buffer": 0, "byteOffset": webp_at, "byteLength": webp.len()},
                {"buffer": 0, "byteOffset": geometry_at, "byteLength": 36},
            ],
            "images": [{"bufferView": 0, "mimeType": "image/png"}, {"bufferView": 1, "mimeType": "image/webp"}],
            "textures": [texture],
            "materials": [{"name": "paint", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
            "accessors": [{"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
            "nodes": [{"mesh": 0}],
            "scenes": [{"nodes": [0]}],
        })
    };
    let texel = |texture: Value| -> weft::Result<[u8; 4]> {
        let scene = scene::load_slice(&glb(&doc(texture), &bin), "paint.glb", None)?;
        let t = &scene.textures[scene.materials[0].base_color_texture.unwrap()];
        Ok(t.rgba8[..4].try_into().unwrap())
    };
    // Both sources: the WebP one (green), not the PNG fallback (red).
    assert_eq!(
        texel(json!({"source": 0, "extensions": {"EXT_texture_webp": {"source": 1}}})).unwrap(),
        [0, 200, 0, 255]
    );
    // WebP only, as gltf-transform writes it (no core source).
    assert_eq!(
        texel(json!({"extensions": {"EXT_texture_webp": {"source": 1}}})).unwrap(),
        [0, 200, 0, 255]
    );
    // A WebP image as a core source decodes too.
    assert_eq!(texel(json!({"source": 1})).unwrap(), [0, 200, 0, 255]);
    for (texture, says) in [
        (
            json!({"extensions": {"EXT_texture_webp": {"source": 5}}}),
            "source of image 5, but the file has 2 image(s)",
        ),
        (
            json!({"extensions": {"EXT_texture_webp": {}}}),
            "without a valid \"source\"",
        ),
    ] {
        let msg = texel(texture).err().expect("an error").to_string();
        assert!(
            msg.contains("'paint.glb'") && msg.contains("texture 0") && msg.contains(says),
            "{msg}"
        );
    }
    // Damaged WebP bytes: an error naming the material, the image and the format.
    let mut broken = bin.clone();
    for b in &mut broken[webp_at + 12..webp_at + webp.len()] {
        *b = 0x5a;
    }
    let msg = scene::load_slice(&glb(&doc(json!({"source": 1})), &broken), "paint.glb", None)
        .err()
        .expect("an error")
        .to_string();
    assert!(
        msg.contains("'paint.glb'") && msg.contains("material 'paint'") && msg.contains("WebP"),
        "{msg}"
    );
}

fn encoded(rgba: [u8; 4], format: image::ImageFormat) -> Vec<u8> {
    let mut out = Vec::new();
    image::RgbaImage::from_pixel(4, 4, image::Rgba(rgba))
        .write_to(&mut std::io::Cursor::new(&mut out), format)
        .unwrap();
    out
}

#[test]
fn draco_avocado_matches_the_original() {
    // avocado_draco.glb was written by gltf-transform's `draco` command, which runs Google's own
    // Draco encoder (draco3dgltf): the decoder here (draco-core) is checked against the reference
    // encoder's bitstream, and the mesh against the uncompressed original: every vertex within
    // one 14-bit position step of an original one with its normal and tangent (the encoder's
    // defaults: 14-bit positions, 10-bit normals, 12-bit UVs).
    let want = world(&load("avocado_small.glb"));
    let got = world(&load("avocado_draco.glb"));
    assert_same_mesh("avocado_draco.glb", &want, &got, position_step(&want));
}

#[test]
fn damaged_draco_is_an_error_naming_the_primitive() {
    // The Draco bitstream's second half overwritten (the file keeps its size, so the GLB and its
    // JSON still parse): the decoder must refuse it, naming the file and the primitive.
    let bytes = std::fs::read(data("avocado_draco.glb")).unwrap();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let doc: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let view = doc["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]
        ["bufferView"]
        .as_u64()
        .unwrap() as usize;
    let offset = doc["bufferViews"][view]["byteOffset"].as_u64().unwrap_or(0) as usize;
    let length = doc["bufferViews"][view]["byteLength"].as_u64().unwrap() as usize;
    let bin = 20 + json_len + 8;
    let mut broken = bytes.clone();
    for b in &mut broken[bin + offset + length / 2..bin + offset + length] {
        *b = 0xA5;
    }
    let msg = scene::load_slice(&broken, "broken_draco.glb", None)
        .err()
        .expect("damaged Draco data is refused")
        .to_string();
    assert!(
        msg.contains("broken_draco.glb")
            && msg.contains("primitive 0")
            && msg.contains("Draco-compressed data")
            && msg.contains("does not decode"),
        "{msg}"
    );
    // Cut short instead: the bufferView then lies outside the buffer.
    let mut short = bytes[..bin + offset + length / 2].to_vec();
    let total = short.len() as u32;
    short[8..12].copy_from_slice(&total.to_le_bytes());
    let bin_len = (short.len() - bin) as u32;
    short[bin - 8..bin - 4].copy_from_slice(&bin_len.to_le_bytes());
    let msg = scene::load_slice(&short, "short_draco.glb", None)
        .err()
        .expect("a truncated file is refused")
        .to_string();
    assert!(msg.contains("short_draco.glb"), "{msg}");
}

// --- KTX2 / KHR_texture_basisu --------------------------------------------------------------------

fn ktx2_data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/ktx2")
        .join(name)
}

/// The source image of tests/data/ktx2: 62 x 46 (neither a multiple of UASTC's 4 x 4 blocks),
/// smooth gradients, a hard-edged checker in blue and an alpha ramp on the right half.
fn ktx2_pattern() -> image::RgbaImage {
    image::RgbaImage::from_fn(62, 46, |x, y| {
        image::Rgba([
            (x * 255 / 61) as u8,
            (y * 255 / 45) as u8,
            if (x / 8 + y / 8) % 2 == 0 { 40 } else { 215 },
            if x < 31 { 255 } else { (60 + y * 4) as u8 },
        ])
    })
}

/// A basic data format descriptor block (KDFS 1.3 section 5): colour model, transfer function,
/// texel block dimensions less one, bytes per plane 0, and samples of (bit offset, bit length less
/// one, channel id, upper).
fn dfd_block(
    model: u8,
    transfer: u8,
    dims: [u8; 4],
    bytes: u8,
    samples: &[(u16, u8, u8, u32)],
) -> Vec<u8> {
    let size = 24 + 16 * samples.len();
    let mut b = Vec::new();
    b.extend(0u32.to_le_bytes()); // vendor 0 (Khronos), descriptor type 0 (basic)
    b.extend(2u16.to_le_bytes()); // version 2
    b.extend((size as u16).to_le_bytes());
    b.extend([model, 1, transfer, 0]); // primaries BT.709, flags: straight alpha
    b.extend(dims);
    b.extend([bytes, 0, 0, 0, 0, 0, 0, 0]);
    for &(offset, length, channel, upper) in samples {
        b.extend(
            (u32::from(offset) | u32::from(length) << 16 | u32::from(channel) << 24).to_le_bytes(),
        );
        b.extend([0u8; 4]); // sample positions
        b.extend(0u32.to_le_bytes()); // lower
        b.extend(upper.to_le_bytes());
    }
    b
}

/// The descriptor of a UASTC file: one 128-bit sample whose channel id is RGB (0) or RGBA (3).
fn uastc_dfd(alpha: bool) -> Vec<u8> {
    dfd_block(
        166,
        2,
        [3, 3, 0, 0],
        16,
        &[(0, 127, if alpha { 3 } else { 0 }, u32::MAX)],
    )
}

/// The descriptor of 8-bit R, G, B, A samples in that order (`channels` of them).
fn rgba8_dfd(channels: usize) -> Vec<u8> {
    let ids = [0u8, 1, 2, 15];
    let samples: Vec<_> = (0..channels)
        .map(|c| ((c * 8) as u16, 7u8, ids[c], 255u32))
        .collect();
    dfd_block(1, 2, [0; 4], channels as u8, &samples)
}

/// A one-level 2D KTX2 file. `level` is stored as given (already supercompressed when `scheme`
/// is not 0); `uncompressed` is the length the level index declares for it.
fn ktx2_file(
    vk_format: u32,
    (width, height): (u32, u32),
    scheme: u32,
    dfd: &[u8],
    kvd: &[u8],
    level: &[u8],
    uncompressed: u64,
) -> Vec<u8> {
    let dfd_at = 80 + 24;
    let dfd_len = 4 + dfd.len();
    let kvd_at = dfd_at + dfd_len;
    let mut level_at = kvd_at + kvd.len();
    level_at = level_at.next_multiple_of(16);
    let mut f = Vec::new();
    f.extend(b"\xABKTX 20\xBB\r\n\x1A\n");
    for v in [vk_format, 1, width, height, 0, 0, 1, 1, scheme] {
        f.extend(v.to_le_bytes());
    }
    let kvd_at32 = if kvd.is_empty() { 0 } else { kvd_at as u32 };
    for v in [dfd_at as u32, dfd_len as u32, kvd_at32, kvd.len() as u32] {
        f.extend(v.to_le_bytes());
    }
    f.extend(0u64.to_le_bytes()); // no supercompression global data
    f.extend(0u64.to_le_bytes());
    for v in [level_at as u64, level.len() as u64, uncompressed] {
        f.extend(v.to_le_bytes());
    }
    f.extend((dfd_len as u32).to_le_bytes());
    f.extend(dfd);
    f.extend(kvd);
    f.resize(level_at, 0);
    f.extend(level);
    f
}

/// One key/value pair of a KTX2 key/value data section (NUL-terminated key and value, padded).
fn kv(key: &str, value: &str) -> Vec<u8> {
    let mut pair = Vec::new();
    pair.extend(key.as_bytes());
    pair.push(0);
    pair.extend(value.as_bytes());
    pair.push(0);
    let mut out = (pair.len() as u32).to_le_bytes().to_vec();
    out.extend(&pair);
    while out.len() % 4 != 0 {
        out.push(0);
    }
    out
}

/// UASTC blocks of an RGBA8 image from Binomial's encoder (basis-universal's `Compressor`, default
/// UASTC quality, no RDO, no mips), taken from the .basis file it writes (slice 0's data is the
/// raw 16-byte blocks).
fn uastc_blocks(rgba: &image::RgbaImage) -> Vec<u8> {
    use basis_universal::{BasisTextureFormat, Compressor, CompressorParams};
    let (w, h) = rgba.dimensions();
    let mut params = CompressorParams::new();
    params.set_basis_format(BasisTextureFormat::UASTC4x4);
    params.set_generate_mipmaps(false);
    params.set_print_status_to_stdout(false);
    params.source_image_mut(0).init(rgba.as_raw(), w, h, 4);
    let mut compressor = Compressor::new(2);
    // The encoder's API is unsafe (it trusts its parameters); these are its documented defaults
    // plus one 4-channel source image.
    unsafe {
        assert!(compressor.init(&params));
        compressor.process().expect("UASTC encoding");
    }
    let basis = compressor.basis_file();
    let le = |at: usize, n: usize| -> usize {
        (0..n).map(|i| (basis[at + i] as usize) << (8 * i)).sum()
    };
    // basis_file_header: m_total_slices at 14 (3 bytes), m_slice_desc_file_ofs at 65 (4 bytes);
    // basis_slice_desc: blocks x/y at 9 and 11 (2 bytes), file offset at 13, size at 17 (4 bytes).
    assert_eq!(le(14, 3), 1, "one slice");
    let desc = le(65, 4);
    let (bx, by) = (le(desc + 9, 2), le(desc + 11, 2));
    assert_eq!((bx, by), (w.div_ceil(4) as usize, h.div_ceil(4) as usize));
    let (ofs, size) = (le(desc + 13, 4), le(desc + 17, 4));
    assert_eq!(size, bx * by * 16);
    basis[ofs..ofs + size].to_vec()
}

/// A UASTC + Zstandard KTX2 file of an RGBA8 image.
fn uastc_zstd_ktx2(rgba: &image::RgbaImage) -> Vec<u8> {
    let blocks = uastc_blocks(rgba);
    let zstd =
        ruzstd::encoding::compress_to_vec(&blocks[..], ruzstd::encoding::CompressionLevel::Fastest);
    let alpha = rgba.pixels().any(|p| p.0[3] != 255);
    let orientation = kv("KTXorientation", "rd");
    ktx2_file(
        0,
        rgba.dimensions(),
        2,
        &uastc_dfd(alpha),
        &orientation,
        &zstd,
        blocks.len() as u64,
    )
}

/// Regenerates tests/data/ktx2 from [`ktx2_pattern`], and tests/data/compressed/avocado_ktx2.glb
/// from avocado_small.glb (each PNG texture replaced by UASTC + Zstandard KTX2, referenced as
/// gltf-transform does: KHR_texture_basisu required, no core source):
/// `cargo test --release --test compressed -- --ignored make_ktx2_test_files`. The KTX2 container
/// and its descriptor are written here.
#[test]
#[ignore]
fn make_ktx2_test_files() {
    let pattern = ktx2_pattern();
    std::fs::create_dir_all(ktx2_data("")).unwrap();
    pattern.save(ktx2_data("pattern.png")).unwrap();
    std::fs::write(
        ktx2_data("pattern_uastc_zstd.ktx2"),
        uastc_zstd_ktx2(&pattern),
    )
    .unwrap();
    // R8G8B8A8_SRGB (43), stored as is.
    let orientation = kv("KTXorientation", "rd");
    let raw = pattern.as_raw();
    let plain = ktx2_file(
        43,
        pattern.dimensions(),
        0,
        &rgba8_dfd(4),
        &orientation,
        raw,
        raw.len() as u64,
    );
    std::fs::write(ktx2_data("pattern_rgba8.ktx2"), plain).unwrap();

    // The Avocado with KTX2 textures: the .glb's JSON rewritten, the KTX2 files appended to its
    // binary chunk (the PNG bytes stay, unreferenced).
    let bytes = std::fs::read(data("avocado_small.glb")).unwrap();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut doc: Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let mut bin = bytes[20 + json_len + 8..].to_vec();
    let images = doc["images"].as_array().unwrap().len();
    for i in 0..images {
        let view = doc["images"][i]["bufferView"].as_u64().unwrap() as usize;
        let v = &doc["bufferViews"][view];
        let at = v["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = v["byteLength"].as_u64().unwrap() as usize;
        let png = image::load_from_memory(&bin[at..at + len])
            .unwrap()
            .into_rgba8();
        let ktx = uastc_zstd_ktx2(&png);
        while bin.len() % 16 != 0 {
            bin.push(0);
        }
        let new_view = doc["bufferViews"].as_array().unwrap().len();
        doc["bufferViews"]
            .as_array_mut()
            .unwrap()
            .push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": ktx.len()}));
        bin.extend(&ktx);
        doc["images"][i] = json!({"bufferView": new_view, "mimeType": "image/ktx2"});
    }
    for t in doc["textures"].as_array_mut().unwrap() {
        let source = t["source"].take();
        t.as_object_mut().unwrap().remove("source");
        t["extensions"] = json!({"KHR_texture_basisu": {"source": source}});
    }
    for list in ["extensionsUsed", "extensionsRequired"] {
        doc[list] = json!(["KHR_texture_basisu"]);
    }
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    std::fs::write(data("avocado_ktx2.glb"), glb(&doc, &bin)).unwrap();
}

/// A .glb with one triangle whose material uses texture 0 as base colour and as
/// metallic-roughness (so it is decoded once per colour space); `images` are stored in the binary
/// chunk with their media types, and `texture` is texture 0.
fn textured_glb(images: &[(&[u8], &str)], texture: Value, required: &[&str]) -> Vec<u8> {
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut image_json = Vec::new();
    for (i, (bytes, mime)) in images.iter().enumerate() {
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()}));
        image_json.push(json!({"bufferView": i, "mimeType": mime, "name": format!("img{i}")}));
        bin.extend(*bytes);
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
    }
    let geometry_at = bin.len();
    for f in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend(f.to_le_bytes());
    }
    views.push(json!({"buffer": 0, "byteOffset": geometry_at, "byteLength": 36}));
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": required,
        "extensionsRequired": required,
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "images": image_json,
        "textures": [texture],
        "materials": [{"name": "lamp metal", "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0}, "metallicRoughnessTexture": {"index": 0}}}],
        "accessors": [{"bufferView": images.len(), "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    });
    glb(&doc, &bin)
}

/// Loads a KTX2 file as the KHR_texture_basisu source of a texture whose core source is a red
/// 4 x 4 PNG; returns its base colour and metallic-roughness textures.
fn load_ktx2(ktx: &[u8]) -> weft::Result<(weft::scene::Texture, weft::scene::Texture)> {
    let red = encoded([255, 0, 0, 255], image::ImageFormat::Png);
    let glb = textured_glb(
        &[(&red, "image/png"), (ktx, "image/ktx2")],
        json!({"source": 0, "extensions": {"KHR_texture_basisu": {"source": 1}}}),
        &["KHR_texture_basisu"],
    );
    let scene = scene::load_slice(&glb, "lamp.glb", None)?;
    let m = &scene.materials[0];
    Ok((
        scene.textures[m.base_color_texture.unwrap()].clone(),
        scene.textures[m.metallic_roughness_texture.unwrap()].clone(),
    ))
}

/// Mean and largest absolute difference of two RGBA8 images, over all channels.
fn rgba_difference(a: &[u8], b: &[u8]) -> (f64, u8) {
    assert_eq!(a.len(), b.len());
    let mean = a
        .iter()
        .zip(b)
        .map(|(x, y)| x.abs_diff(*y) as f64)
        .sum::<f64>()
        / a.len() as f64;
    let max = a
        .iter()
        .zip(b)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0);
    (mean, max)
}

#[test]
fn ktx2_files_decode_to_their_source_in_the_slot_colour_space() {
    use weft::scene::ColorSpace;
    let pattern = ktx2_pattern();
    let on_disk = image::open(ktx2_data("pattern.png")).unwrap().into_rgba8();
    assert_eq!(
        on_disk, pattern,
        "tests/data/ktx2/pattern.png is the generator's pattern"
    );
    for (file, bound) in [
        // Stored as is: exact.
        ("pattern_rgba8.ktx2", (0.0, 0)),
        // UASTC (lossy, 8 bits per texel) through Zstandard: measured mean 0.81, largest 6 of
        // 255 (the checker's hard edges); bounded at about twice that.
        ("pattern_uastc_zstd.ktx2", (1.5, 12)),
    ] {
        let bytes = std::fs::read(ktx2_data(file)).unwrap();
        let (base, data) = load_ktx2(&bytes).unwrap_or_else(|e| panic!("{file}: {e}"));
        for t in [&base, &data] {
            assert_eq!((t.width, t.height), (62, 46), "{file}: {}", t.name);
        }
        // The slot decides the colour space, as for PNG; the texels are the file's either way.
        assert_eq!(base.color_space, ColorSpace::Srgb, "{file}");
        assert_eq!(data.color_space, ColorSpace::Linear, "{file}");
        assert_eq!(base.rgba8, data.rgba8, "{file}");
        let (mean, max) = rgba_difference(&base.rgba8, pattern.as_raw());
        eprintln!("{file}: mean difference {mean:.3}, largest {max} (of 255)");
        assert!(
            mean <= bound.0 && max <= bound.1,
            "{file}: mean {mean:.3}, largest {max}"
        );
    }
}

#[test]
fn plain_ktx2_layouts_and_supercompressions_decode_exactly() {
    let pattern = ktx2_pattern();
    let (w, h) = pattern.dimensions();
    let rgba = pattern.as_raw();
    let rd = kv("KTXorientation", "rd");
    let plain = |vk: u32, channels: usize, texels: &[u8], scheme: u32, kvd: &[u8]| {
        let level = match scheme {
            0 => texels.to_vec(),
            2 => ruzstd::encoding::compress_to_vec(
                texels,
                ruzstd::encoding::CompressionLevel::Fastest,
            ),
            3 => miniz_oxide::deflate::compress_to_vec_zlib(texels, 6),
            _ => unreachable!(),
        };
        ktx2_file(
            vk,
            (w, h),
            scheme,
            &rgba8_dfd(channels),
            kvd,
            &level,
            texels.len() as u64,
        )
    };
    let select =
        |f: &dyn Fn(&[u8]) -> Vec<u8>| -> Vec<u8> { rgba.chunks_exact(4).flat_map(f).collect() };
    let expand =
        |f: &dyn Fn(&[u8]) -> [u8; 4]| -> Vec<u8> { rgba.chunks_exact(4).flat_map(f).collect() };
    let rgb = select(&|p| p[..3].to_vec());
    let bgra = select(&|p| vec![p[2], p[1], p[0], p[3]]);
    let rg = select(&|p| p[..2].to_vec());
    let r = select(&|p| vec![p[0]]);
    let flipped: Vec<u8> = rgba
        .chunks_exact(w as usize * 4)
        .rev()
        .flatten()
        .copied()
        .collect();
    let cases: Vec<(&str, Vec<u8>, Vec<u8>)> = vec![
        ("R8G8B8A8_UNORM", plain(37, 4, rgba, 0, &rd), rgba.clone()),
        (
            "R8G8B8A8_SRGB, Zstandard",
            plain(43, 4, rgba, 2, &rd),
            rgba.clone(),
        ),
        (
            "R8G8B8A8_SRGB, ZLIB",
            plain(43, 4, rgba, 3, &[]),
            rgba.clone(),
        ),
        (
            "R8G8B8A8_SRGB, rows up",
            plain(43, 4, &flipped, 0, &kv("KTXorientation", "ru")),
            rgba.clone(),
        ),
        (
            "R8G8B8_SRGB",
            plain(29, 3, &rgb, 0, &rd),
            expand(&|p| [p[0], p[1], p[2], 255]),
        ),
        (
            "B8G8R8A8_SRGB, Zstandard",
            plain(50, 4, &bgra, 2, &rd),
            rgba.clone(),
        ),
        (
            "R8G8_UNORM",
            plain(16, 2, &rg, 0, &rd),
            expand(&|p| [p[0], p[1], 0, 255]),
        ),
        (
            "R8_UNORM",
            plain(9, 1, &r, 0, &rd),
            expand(&|p| [p[0], 0, 0, 255]),
        ),
    ];
    for (what, file, want) in cases {
        let (base, _) = load_ktx2(&file).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!((base.width, base.height), (w, h), "{what}");
        assert!(base.rgba8 == want, "{what}: texels differ");
    }
}

#[test]
fn ktx2_is_preferred_over_the_fallback_and_a_core_ktx2_source_reads_too() {
    let ktx = std::fs::read(ktx2_data("pattern_rgba8.ktx2")).unwrap();
    let red = encoded([255, 0, 0, 255], image::ImageFormat::Png);
    let first_texel = |texture: Value, required: &[&str]| -> [u8; 4] {
        let glb = textured_glb(
            &[(&red, "image/png"), (&ktx, "image/ktx2")],
            texture,
            required,
        );
        let scene = scene::load_slice(&glb, "lamp.glb", None).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            scene
                .warnings
                .iter()
                .all(|w| !w.0.contains("KHR_texture_basisu")),
            "{:?}",
            scene.warnings
        );
        let t = &scene.textures[scene.materials[0].base_color_texture.unwrap()];
        t.rgba8[..4].try_into().unwrap()
    };
    let want = ktx2_pattern().get_pixel(0, 0).0;
    // With a PNG fallback, extension only used: the KTX2 image.
    assert_eq!(
        first_texel(
            json!({"source": 0, "extensions": {"KHR_texture_basisu": {"source": 1}}}),
            &[]
        ),
        want
    );
    // Without a core source, required (as gltf-transform writes it).
    assert_eq!(
        first_texel(
            json!({"extensions": {"KHR_texture_basisu": {"source": 1}}}),
            &["KHR_texture_basisu"]
        ),
        want
    );
    // A core source that is a KTX2 file, no extension (as AnisotropyBarnLamp has it).
    assert_eq!(first_texel(json!({"source": 1}), &[]), want);
}

/// The loader's error for a KTX2 source made from `ktx`: it names the file, the material and the
/// image, and it is not a caught panic.
fn ktx2_error(ktx: &[u8]) -> String {
    let msg = load_ktx2(ktx).err().expect("an error").to_string();
    assert!(!msg.contains("the glTF reader failed"), "a panic: {msg}");
    assert!(
        msg.contains("'lamp.glb'")
            && msg.contains("material 'lamp metal'")
            && msg.contains("image 1 ('img1')"),
        "{msg}"
    );
    msg
}

#[test]
fn damaged_and_unsupported_ktx2_files_are_errors_naming_the_file_and_texture() {
    let uastc = std::fs::read(ktx2_data("pattern_uastc_zstd.ktx2")).unwrap();
    let level_at = u64::from_le_bytes(uastc[80..88].try_into().unwrap()) as usize;
    let set = |at: usize, bytes: &[u8]| {
        let mut f = uastc.clone();
        f[at..at + bytes.len()].copy_from_slice(bytes);
        f
    };
    let blocks = 16 * 12 * 16; // 62 x 46 is 16 x 12 blocks of 16 bytes
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "truncated in the header",
            uastc[..60].to_vec(),
            "damaged KTX2 file (unexpected end of buffer)",
        ),
        (
            "truncated in the level",
            uastc[..uastc.len() - 10].to_vec(),
            "damaged KTX2 file (unexpected end of buffer)",
        ),
        (
            "zero width",
            set(20, &0u32.to_le_bytes()),
            "damaged KTX2 file (zero pixel width)",
        ),
        (
            "not KTX2 but declared so",
            b"PNG? no".to_vec(),
            "does not start with the KTX2 identifier",
        ),
        (
            "a Zstandard stream of garbage",
            set(level_at, &[0x5a; 32]),
            "Zstandard-compressed level 0 does not decode",
        ),
        (
            "a level longer than it declares",
            set(80 + 16, &((blocks - 16) as u64).to_le_bytes()),
            "declares 3056 uncompressed bytes where its 62x46 format needs 3072",
        ),
        (
            "BasisLZ over UASTC",
            set(44, &1u32.to_le_bytes()),
            "supercompression is BasisLZ but whose data format descriptor is not ETC1S",
        ),
        (
            "an unknown supercompression",
            set(44, &7u32.to_le_bytes()),
            "supercompression scheme SupercompressionScheme(7)",
        ),
        (
            "BC7",
            set(12, &146u32.to_le_bytes()),
            "vkFormat BC7_SRGB_BLOCK, which weft does not read",
        ),
        (
            "a cube map",
            set(36, &6u32.to_le_bytes()),
            "KTX2 cube map (6 faces)",
        ),
        (
            "a 3D texture",
            set(28, &4u32.to_le_bytes()),
            "3D KTX2 texture (62x46x4)",
        ),
        (
            "an array",
            set(32, &3u32.to_le_bytes()),
            "texture array (3 layers)",
        ),
        (
            "a 1D texture",
            set(24, &0u32.to_le_bytes()),
            "one-dimensional KTX2 texture",
        ),
        (
            "huge",
            set(20, &100_000u32.to_le_bytes()),
            "100000x46 pixels; textures must be between 1 and 16384",
        ),
        (
            "a 256-texel block",
            set(104 + 4 + 12, &[255]),
            "texel block dimension of 256",
        ),
        (
            "an ETC1S descriptor over Zstandard",
            set(104 + 4 + 8, &[163]),
            "data format descriptor says ETC1S but whose supercompression is not BasisLZ",
        ),
        (
            "an RGB descriptor with no format",
            set(104 + 4 + 8, &[1]),
            "vkFormat UNDEFINED and a RGBSDA data format descriptor",
        ),
    ];
    for (what, file, says) in cases {
        let msg = ktx2_error(&file);
        assert!(msg.contains(says), "{what}: {msg}");
    }
    // Stored UASTC blocks whose level is too short for the image, without supercompression.
    let blocks_file = ktx2_file(
        0,
        (62, 46),
        0,
        &uastc_dfd(false),
        &[],
        &vec![0u8; blocks - 16],
        0,
    );
    let msg = ktx2_error(&blocks_file);
    assert!(
        msg.contains("holds 3056 bytes where its 62x46 format needs 3072"),
        "{msg}"
    );
    // A ZLIB stream that does not inflate.
    let zlib = ktx2_file(
        43,
        (62, 46),
        3,
        &rgba8_dfd(4),
        &[],
        &[0x78, 0x9c, 0xff, 0xff, 0, 1],
        62 * 46 * 4,
    );
    let msg = ktx2_error(&zlib);
    assert!(
        msg.contains("ZLIB-compressed level 0 does not decode"),
        "{msg}"
    );
}

/// ETC1S (BasisLZ) files written by Binomial's own encoder and KTX2 writer
/// (tools/make_etc1s_test_files.py) decode to exactly the texels Binomial's transcoder makes of
/// the same encoding in its .basis container (the reference PNGs beside them): with an alpha
/// slice, with a mip chain (seven image descriptors before the codebooks), and opaque.
#[test]
fn etc1s_ktx2_files_decode_to_binomial_s_own_transcode() {
    let pattern = ktx2_pattern();
    for (file, reference, opaque) in [
        ("pattern_etc1s.ktx2", "pattern_etc1s_reference.png", false),
        (
            "pattern_etc1s_mips.ktx2",
            "pattern_etc1s_mips_reference.png",
            false,
        ),
        (
            "pattern_etc1s_opaque.ktx2",
            "pattern_etc1s_opaque_reference.png",
            true,
        ),
    ] {
        let bytes = std::fs::read(ktx2_data(file)).unwrap();
        let (base, data) = load_ktx2(&bytes).unwrap_or_else(|e| panic!("{file}: {e}"));
        let want = image::open(ktx2_data(reference)).unwrap().into_rgba8();
        for t in [&base, &data] {
            assert_eq!((t.width, t.height), (62, 46), "{file}: {}", t.name);
            assert!(
                t.rgba8 == want.as_raw().as_slice(),
                "{file}: {} differs from {reference} by {:?} (mean, largest)",
                t.name,
                rgba_difference(&t.rgba8, want.as_raw())
            );
        }
        if opaque {
            assert!(base.rgba8.chunks_exact(4).all(|p| p[3] == 255), "{file}");
        }
        // ETC1S is a low-bit-rate code (about 1.5 bits per texel here); against the source
        // pattern the decode is reported, not judged: the exact reference above is the judge.
        let mut source = pattern.clone();
        if opaque {
            source.pixels_mut().for_each(|p| p.0[3] = 255);
        }
        let (mean, max) = rgba_difference(&base.rgba8, source.as_raw());
        eprintln!(
            "{file}: mean difference {mean:.2}, largest {max} (of 255) from the source pattern"
        );
    }
}

/// Damaged ETC1S files: each broken part of the BasisLZ global data or the slices is an error
/// naming what is wrong, never a crash or a half-decoded texture.
#[test]
fn damaged_etc1s_files_are_errors() {
    let good = std::fs::read(ktx2_data("pattern_etc1s.ktx2")).unwrap();
    let u32_at = |at: usize| u32::from_le_bytes(good[at..at + 4].try_into().unwrap()) as usize;
    let u64_at = |at: usize| u64::from_le_bytes(good[at..at + 8].try_into().unwrap()) as usize;
    let (sgd_at, sgd_len) = (u64_at(64), u64_at(72));
    let level_at = u64_at(80);
    let set = |at: usize, bytes: &[u8]| {
        let mut f = good.clone();
        f[at..at + bytes.len()].copy_from_slice(bytes);
        f
    };
    let endpoints_len = u32_at(sgd_at + 4);
    let image_desc = sgd_at + 20;
    let codebooks = image_desc + 20;
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "global data shorter than its header",
            set(72, &12u64.to_le_bytes()),
            "global data is shorter than its 20-byte header",
        ),
        (
            "global data shorter than its codebooks",
            set(72, &((sgd_len - 10) as u64).to_le_bytes()),
            "global data is",
        ),
        (
            "no endpoints",
            set(sgd_at, &0u16.to_le_bytes()),
            "empty endpoint or selector codebook",
        ),
        (
            "a colour slice past the level",
            set(image_desc + 4, &100_000u32.to_le_bytes()),
            "colour slice",
        ),
        (
            "an empty colour slice",
            set(image_desc + 8, &0u32.to_le_bytes()),
            "empty colour slice",
        ),
        (
            "an alpha slice past the level",
            set(image_desc + 16, &100_000u32.to_le_bytes()),
            "alpha slice",
        ),
        (
            "an endpoint codebook of garbage",
            {
                let mut f = good.clone();
                f[codebooks..codebooks + endpoints_len].fill(0xff);
                f
            },
            "codebooks or Huffman tables the Basis Universal transcoder rejected",
        ),
        (
            "a colour slice of garbage",
            {
                let mut f = good.clone();
                let (at, len) = (u32_at(image_desc + 4), u32_at(image_desc + 8));
                f[level_at + at..level_at + at + len].fill(0xff);
                f
            },
            "level 0 the Basis Universal transcoder rejected",
        ),
    ];
    for (what, file, says) in cases {
        let msg = ktx2_error(&file);
        assert!(msg.contains(says), "{what}: {msg}");
        assert!(
            msg.contains("ETC1S") || msg.contains("KTX2"),
            "{what}: {msg}"
        );
    }
}

#[test]
fn damaged_ktx2_files_never_panic() {
    // Every prefix length in steps, and random bytes of the UASTC and the ETC1S file replaced
    // (header, index, descriptor, key/value data, the Zstandard stream, the BasisLZ codebooks and
    // slices alike): the load decodes something (a damaged block still transcodes) or fails with an error naming the file and texture,
    // never with a caught panic.
    for file in ["pattern_uastc_zstd.ktx2", "pattern_etc1s.ktx2"] {
        damaged_ktx2_never_panics(&std::fs::read(ktx2_data(file)).unwrap(), file);
    }
}

fn damaged_ktx2_never_panics(uastc: &[u8], file: &str) {
    for len in (0..uastc.len()).step_by(7) {
        let msg = ktx2_error(&uastc[..len.max(12)]);
        assert!(msg.contains("KTX2"), "{file}: {msg}");
    }
    let mut rng = common::Rng(0x2026_2601);
    let (mut ok, mut refused) = (0, 0);
    for _ in 0..800 {
        let mut broken = uastc.to_vec();
        for _ in 0..1 + rng.below(3) {
            let at = 12 + rng.below(broken.len() - 12);
            broken[at] = [
                0x00,
                0xff,
                0x80,
                broken[at] ^ 0x55,
                broken[at].wrapping_add(1),
            ][rng.below(5)];
        }
        match load_ktx2(&broken) {
            Ok(_) => ok += 1,
            Err(_) => {
                ktx2_error(&broken);
                refused += 1;
            }
        }
    }
    eprintln!("{file}: {ok} damaged KTX2 files loaded, {refused} refused");
    assert!(
        refused > 100,
        "{file}: little damage was noticed: {refused}"
    );
}

/// AnisotropyBarnLamp (../shared/realworld, when present): four UASTC + Zstandard 2048 x 2048
/// textures, referenced from core `texture.source`, decode; the base colour is copper.
#[test]
fn the_barn_lamp_ktx2_textures_decode() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(
        "../shared/realworld/khronos/AnisotropyBarnLamp/glTF-KTX2-Basisu/AnisotropyBarnLamp.gltf",
    );
    if !path.exists() {
        eprintln!("skipped: {} is not here", path.display());
        return;
    }
    let scene = scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(scene.textures.len() >= 4, "{}", scene.textures.len());
    for t in &scene.textures {
        assert_eq!((t.width, t.height), (2048, 2048), "{}", t.name);
    }
    let base = scene
        .textures
        .iter()
        .find(|t| t.name.contains("basecolor"))
        .expect("a base colour texture");
    let mut mean = [0f64; 3];
    for p in base.rgba8.chunks_exact(4) {
        for c in 0..3 {
            mean[c] += p[c] as f64;
        }
    }
    let mean = mean.map(|m| m / (base.rgba8.len() / 4) as f64);
    eprintln!("base colour mean {mean:?}");
    assert!(
        mean[0] > mean[1] && mean[1] > mean[2] && mean[0] > 60.0,
        "not copper: {mean:?}"
    );
    if let Some(dir) = std::env::var_os("WEFT_KTX2_DUMP") {
        for t in &scene.textures {
            let name = t.name.replace(['/', ' ', '(', ')', '\''], "_");
            image::RgbaImage::from_raw(t.width, t.height, t.rgba8.clone())
                .unwrap()
                .save(Path::new(&dir).join(format!("{name}.png")))
                .unwrap();
        }
    }
}

// --- on the GPU ---------------------------------------------------------------------------------

/// A KTX2 file that carries its full mip chain is uploaded as BC7 with the file's own levels on a
/// device that samples BC7 (lavapipe does), and renders like the RGBA8 path with the device's mip
/// chain: magnified (level 0) and minified (the file's smaller levels).
#[test]
fn a_bc7_upload_renders_like_rgba8() {
    use weft::render::{RenderOptions, Renderer};
    let ctx = common::context();
    let lavapipe =
        ctx.info().driver_name.contains("llvmpipe") || ctx.info().name.contains("llvmpipe");
    eprintln!(
        "device '{}' samples BC7: {}",
        ctx.info().name,
        ctx.samples_bc7()
    );
    if lavapipe {
        assert!(ctx.samples_bc7(), "lavapipe (Mesa >= 21) samples BC7");
    } else if !ctx.samples_bc7() {
        eprintln!("skipped: this device does not sample BC7");
        return;
    }
    let mut renderer = Renderer::new(ctx).expect("renderer");
    // A unit quad facing +Z with UVs over the whole texture, shown by its emission (black base
    // colour): the texels reach the picture as they are, whatever the lighting.
    let ktx = std::fs::read(ktx2_data("pattern_etc1s_mips.ktx2")).unwrap();
    let mut bin = ktx.clone();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let geometry_at = bin.len();
    for v in [
        [0.0f32, 0.0, 0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0, 1.0, 1.0],
        [1.0, 1.0, 0.0, 1.0, 0.0],
        [0.0, 1.0, 0.0, 0.0, 0.0],
    ] {
        for f in v {
            bin.extend(f.to_le_bytes());
        }
    }
    let indices_at = bin.len();
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_texture_basisu"],
        "extensionsRequired": ["KHR_texture_basisu"],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": ktx.len()},
            {"buffer": 0, "byteOffset": geometry_at, "byteLength": 80, "byteStride": 20},
            {"buffer": 0, "byteOffset": indices_at, "byteLength": 12},
        ],
        "images": [{"bufferView": 0, "mimeType": "image/ktx2"}],
        "textures": [{"extensions": {"KHR_texture_basisu": {"source": 0}}}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0},
            "emissiveTexture": {"index": 0}, "emissiveFactor": [1, 1, 1]}],
        "accessors": [
            {"bufferView": 1, "byteOffset": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "byteOffset": 12, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    });
    let scene = scene::load_slice(&glb(&doc, &bin), "bc7.glb", None).unwrap();
    for t in &scene.textures {
        let levels = t
            .bc7
            .as_ref()
            .expect("a full-chain ETC1S file has BC7 levels");
        assert_eq!(levels.len(), 6, "62 x 46 has six levels down to 1 x 1");
    }
    let mut rgba8_only = scene.clone();
    rgba8_only.textures.iter_mut().for_each(|t| t.bc7 = None);
    // A single-level file keeps the RGBA8 path.
    let single = std::fs::read(ktx2_data("pattern_etc1s.ktx2")).unwrap();
    assert!(load_ktx2(&single).unwrap().0.bc7.is_none());
    // Magnified (256 x 256: level 0, ETC1S -> BC7 against the exact ETC1S decode), the FLIP;
    // minified (24 x 24, about three texels per pixel: the file's levels 1-2, which basisu
    // filtered with a Kaiser window, against the device's box-filtered ones: visibly softer, by
    // design), the mean colour, which any mip filter keeps and a wrong colour space would not.
    for size in [256, 24] {
        let options = RenderOptions {
            width: size,
            height: size,
            ..Default::default()
        };
        let bc7 = renderer.render(&scene, &options).unwrap();
        let rgba8 = renderer.render(&rgba8_only, &options).unwrap();
        let flip = weft::bench::flip_mean(&rgba8, &bc7);
        let mean = |f: &weft::render::Frame| -> Vec<f64> {
            (0..3)
                .map(|c| {
                    f.ldr.chunks_exact(4).map(|p| p[c] as f64).sum::<f64>()
                        / (f.ldr.len() / 4) as f64
                })
                .collect()
        };
        let (m_bc7, m_rgba8) = (mean(&bc7), mean(&rgba8));
        let shift = (0..3)
            .map(|c| (m_bc7[c] - m_rgba8[c]).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "{size} x {size}: BC7 against RGBA8, mean FLIP {flip:.5}, mean colour {m_bc7:.2?} against {m_rgba8:.2?} (largest shift {shift:.2} of 255)"
        );
        if let Some(dir) = std::env::var_os("WEFT_BC7_DUMP") {
            for (name, frame) in [("bc7", &bc7), ("rgba8", &rgba8)] {
                let path = Path::new(&dir).join(format!("{name}_{size}.png"));
                weft::render::write_png(&path, frame.width, frame.height, &frame.ldr).unwrap();
            }
        }
        assert!(
            flip > 0.0,
            "{size}: the BC7 path drew the same pixels: was it used?"
        );
        if size == 256 {
            // Measured 0.0188; bound 1.3x.
            assert!(flip <= 0.025, "{size}: mean FLIP {flip} > 0.025");
        }
        // Measured 0.11 (256) and 1.84 (24) of 255; bound 3 (sampling BC7_UNORM as if it were
        // sRGB, or the reverse, moves these means by tens).
        assert!(
            shift <= 3.0,
            "{size}: the mean colour moved by {shift:.2} of 255"
        );
    }
}

#[test]
fn compressed_avocados_render_like_the_original() {
    use weft::render::{RenderOptions, Renderer};
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let options = RenderOptions {
        width: 256,
        height: 256,
        ..Default::default()
    };
    let render = |renderer: &mut Renderer, name: &str| {
        renderer
            .render(&load(name), &options)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
    };
    let original = render(&mut renderer, "avocado_small.glb");
    // Measured on lavapipe: see each bound's comment.
    for (name, bound) in [
        // Positions within 4e-6 m, normals within 0.2 degrees: the same picture but for a few
        // edge pixels.
        ("avocado_quant.glb", 0.002),
        ("avocado_meshopt.glb", 0.002),
        // Lossy WebP (quality 80) textures: measured 0.0204 since the automatic framing fits
        // the model (issue 28 item 9: the avocado covers about twice the pixels, and the mean
        // is over the frame), below 0.02 before.
        ("avocado_webp.glb", 0.027),
        // UASTC + Zstandard KTX2 textures (made by `make_ktx2_test_files`): measured 0.0092
        // (0.0046 before the framing fitted the model: twice the pixels on the avocado).
        ("avocado_ktx2.glb", 0.012),
        // ETC1S (BasisLZ) KTX2 textures made by Binomial's encoder
        // (tools/make_etc1s_test_files.py, default quality 128, about 1.5 bits per texel): measured
        // 0.0253, as lossy as the WebP; bounded at 1.3x as the others.
        ("avocado_etc1s.glb", 0.033),
    ] {
        let frame = render(&mut renderer, name);
        let flip = weft::bench::flip_mean(&original, &frame);
        eprintln!("{name}: mean FLIP {flip:.5} against the original");
        assert!(flip <= bound, "{name}: mean FLIP {flip} > {bound}");
    }
}
