//! The glTF extensions that production pipelines (gltf-transform, gltfpack) use to make files
//! small, made readable before the rest of the loader sees the document:
//!
//! - `KHR_mesh_quantization`: integer positions, normals, tangents and texture coordinates. The
//!   accessor reader already decodes every component type with glTF's normalisation rules
//!   (src/scene/accessor.rs) and the node transforms that undo the quantization scale are ordinary
//!   node transforms, so this extension only needs to be accepted.
//! - `EXT_texture_webp`: a texture's WebP source is chosen over its fallback (weft reads both, and
//!   the extension's source is the one the file's author meant), and decoded by `image`'s WebP
//!   decoder (src/scene/resources.rs).
//! - `KHR_texture_basisu`: likewise a texture's KTX2 source is chosen over its fallback, and
//!   decoded (UASTC transcoded, Zstandard undone) by src/scene/ktx.rs.
//! - `EXT_meshopt_compression` / `KHR_meshopt_compression`: every compressed buffer view is decoded
//!   (modes ATTRIBUTES, TRIANGLES, INDICES; filters NONE, OCTAHEDRAL, QUATERNION, EXPONENTIAL and
//!   KHR's COLOR) by meshoptimizer, through the `meshopt` crate, into a buffer of its own that the
//!   view is then pointed at, so accessors read it as any other data. Fallback buffers are not
//!   loaded.
//!
//! Everything in a compressed view's description is checked against the specification before the
//! decoder runs (meshoptimizer asserts on impossible strides and counts), and a stream that does
//! not decode is an error naming the file, the buffer view, the mesh that reads it and the fix.

use gltf::json;
use gltf::json::validation::Checked;
use serde_json::Value;

use crate::{Error, Result};

pub(super) const QUANTIZATION: &str = "KHR_mesh_quantization";
pub(super) const WEBP: &str = "EXT_texture_webp";
pub(super) const MESHOPT_EXT: &str = "EXT_meshopt_compression";
pub(super) const MESHOPT_KHR: &str = "KHR_meshopt_compression";
pub(super) const BASISU: &str = "KHR_texture_basisu";

/// The extensions of this module: supported in `extensionsRequired`, and taken off that list
/// before the gltf crate's validator (which knows none of them) runs.
pub(super) const EXTENSIONS: [&str; 5] = [QUANTIZATION, WEBP, MESHOPT_EXT, MESHOPT_KHR, BASISU];

/// Decoded bytes of all of a scene's compressed buffer views together: 2 GiB, past the vertex and
/// index limits of src/scene/gltf_load/ for any layout. Checked from the JSON before decoding, so
/// a few bytes of stream cannot make weft allocate without bound.
pub(super) const MAX_DECODED_BYTES: u64 = 1 << 31;

/// The meshopt extension object of a buffer or buffer view, KHR first, with its name.
fn meshopt_ext(others: Option<&serde_json::Map<String, Value>>) -> Option<(&'static str, &Value)> {
    let others = others?;
    [MESHOPT_KHR, MESHOPT_EXT]
        .into_iter()
        .find_map(|name| others.get(name).map(|v| (name, v)))
}

/// Whether buffer `index` needs no data: a meshopt fallback buffer (marked `"fallback": true`, or
/// a placeholder without a uri that only compressed buffer views refer to). Such a buffer's bytes
/// are never read: each view into it is decoded from its compressed stream instead.
pub(super) fn is_fallback_buffer(root: &json::Root, index: usize) -> bool {
    let Some(buffer) = root.buffers.get(index) else {
        return false;
    };
    let marked = meshopt_ext(buffer.extensions.as_ref().map(|e| &e.others))
        .and_then(|(_, v)| v.get("fallback"))
        .and_then(Value::as_bool)
        .unwrap_or(false);
    if marked {
        return true;
    }
    // An unmarked placeholder: no uri, and every view into it is compressed.
    let mut views = root
        .buffer_views
        .iter()
        .filter(|v| v.buffer.value() == index)
        .peekable();
    buffer.uri.is_none()
        && views.peek().is_some()
        && views.all(|v| meshopt_ext(v.extensions.as_ref().map(|e| &e.others)).is_some())
}

/// Points every texture with an `EXT_texture_webp` or `KHR_texture_basisu` source at that image
/// (weft decodes WebP and KTX2, and the extension's image is the one meant; the core source is a
/// fallback for viewers without the extension). WebP is taken first when a texture has both.
/// Runs before the gltf crate's validator, which requires a core source.
pub(super) fn choose_texture_sources(root: &mut json::Root, label: &str) -> Result<()> {
    let images = root.images.len();
    for (t, texture) in root.textures.iter_mut().enumerate() {
        let Some(ext) = texture.extensions.as_ref().map(|e| &e.others) else {
            continue;
        };
        let source_of = |name: &str| -> Result<Option<u32>> {
            let Some(value) = ext.get(name) else {
                return Ok(None);
            };
            match value.get("source").and_then(Value::as_u64) {
                Some(s) if (s as usize) < images => Ok(Some(s as u32)),
                Some(s) => Err(Error::input(format!(
                    "{label}: texture {t} has a {name} source of image {s}, but the file has {images} image(s); fix the texture's source"
                ))),
                None => Err(Error::input(format!(
                    "{label}: texture {t} has a {name} extension without a valid \"source\" (it must be an image index); fix the texture"
                ))),
            }
        };
        let webp = source_of(WEBP)?;
        let basisu = source_of(BASISU)?;
        if let Some(s) = webp.or(basisu) {
            texture.source = json::Index::new(s);
        }
    }
    Ok(())
}

/// A compressed buffer view's description, as the extension gives it.
struct Compressed {
    buffer: usize,
    offset: usize,
    length: usize,
    stride: usize,
    count: usize,
    mode: Mode,
    filter: Filter,
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Mode {
    Attributes,
    Triangles,
    Indices,
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Filter {
    None,
    Octahedral,
    Quaternion,
    Exponential,
    Color,
}

impl Mode {
    fn name(self) -> &'static str {
        match self {
            Mode::Attributes => "ATTRIBUTES",
            Mode::Triangles => "TRIANGLES",
            Mode::Indices => "INDICES",
        }
    }
}

impl Filter {
    fn name(self) -> &'static str {
        match self {
            Filter::None => "NONE",
            Filter::Octahedral => "OCTAHEDRAL",
            Filter::Quaternion => "QUATERNION",
            Filter::Exponential => "EXPONENTIAL",
            Filter::Color => "COLOR",
        }
    }
}

/// Who reads buffer view `view`, for messages: the first mesh primitive attribute or index list
/// whose accessor lies in it, else the first accessor or image, else nothing.
fn readers(root: &json::Root, view: usize) -> String {
    let in_view = |a: usize| {
        root.accessors
            .get(a)
            .and_then(|a| a.buffer_view)
            .is_some_and(|v| v.value() == view)
    };
    for (m, mesh) in root.meshes.iter().enumerate() {
        let name = mesh
            .name
            .as_ref()
            .map_or_else(|| format!("mesh {m}"), |n| format!("mesh '{n}'"));
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, acc) in &prim.attributes {
                if in_view(acc.value()) {
                    let semantic = match semantic {
                        Checked::Valid(s) => s.to_string(),
                        Checked::Invalid => "an unknown attribute".into(),
                    };
                    return format!(" (read by {name} primitive {p}, attribute {semantic})");
                }
            }
            if prim.indices.is_some_and(|i| in_view(i.value())) {
                return format!(" (read by {name} primitive {p}, indices)");
            }
        }
    }
    if let Some(a) = (0..root.accessors.len()).find(|&a| in_view(a)) {
        return format!(" (read by accessor {a})");
    }
    if let Some(i) = root
        .images
        .iter()
        .position(|i| i.buffer_view.is_some_and(|v| v.value() == view))
    {
        return format!(" (holding image {i})");
    }
    String::new()
}

/// A precise reason and fix for a required extension weft does not read, where there is more to say
/// than that it is unsupported.
pub(super) fn refusal_hint(ext: &str) -> Option<&'static str> {
    match ext {
        e if e.starts_with("KHR_materials_") => Some(
            "weft does not draw this material extension yet (docs/scene-format.md lists what it reads); re-export without it, or with it optional (in extensionsUsed only) so that the base material is drawn",
        ),
        _ => None,
    }
}

/// Decodes every meshopt-compressed buffer view of `root` from `buffers` into a new buffer of its
/// own (appended to `buffers` and to `root.buffers`) and points the view at it, offset 0; checks
/// that no view still reads a fallback buffer. After this the document has no compressed data
/// left for the loader to know about.
pub(super) fn decode_buffer_views(
    root: &mut json::Root,
    buffers: &mut Vec<Vec<u8>>,
    label: &str,
) -> Result<()> {
    // Before any view is rewritten (placeholders are recognised by their compressed views).
    let fallback: Vec<bool> = (0..root.buffers.len())
        .map(|b| is_fallback_buffer(root, b))
        .collect();
    // The file's own buffers: decoded ones are appended after them.
    let file_buffers = buffers.len();
    let mut decoded_total: u64 = 0;
    for v in 0..root.buffer_views.len() {
        let view = &root.buffer_views[v];
        let Some((ext, value)) = meshopt_ext(view.extensions.as_ref().map(|e| &e.others)) else {
            continue;
        };
        let who = || format!("buffer view {v}{}", readers(root, v));
        let bad = |problem: std::fmt::Arguments| {
            Error::input(format!(
                "{label}: {} is compressed with {ext}, but {problem}; the file is damaged or was written by a broken exporter: re-export it (for example with `gltf-transform meshopt`)",
                who()
            ))
        };
        let c = parse(ext, value, &bad)?;
        check(&c, view, &bad)?;
        decoded_total = decoded_total.saturating_add(view.byte_length.0);
        if decoded_total > MAX_DECODED_BYTES {
            return Err(Error::input(format!(
                "{label}: {} brings the decoded size of the file's compressed buffer views to {decoded_total} bytes, more than weft's limit of {} GiB; decimate or split the scene",
                who(),
                MAX_DECODED_BYTES >> 30
            )));
        }
        if fallback.get(c.buffer).copied().unwrap_or(false) {
            return Err(bad(format_args!(
                "its compressed data is in buffer {}, a fallback buffer that holds no data",
                c.buffer
            )));
        }
        let source = buffers[..file_buffers].get(c.buffer).ok_or_else(|| {
            bad(format_args!(
                "its compressed data is in buffer {}, and the file has {file_buffers} buffer(s)",
                c.buffer
            ))
        })?;
        let stream = c
            .offset
            .checked_add(c.length)
            .and_then(|end| source.get(c.offset..end))
            .ok_or_else(|| {
                bad(format_args!(
                    "its compressed stream (bytes {}..{} of buffer {}) lies outside that buffer, which holds {} bytes: the file is truncated",
                    c.offset,
                    c.offset.saturating_add(c.length),
                    c.buffer,
                    source.len()
                ))
            })?;
        let bytes = decode(&c, stream).map_err(|e| {
            bad(format_args!(
                "its {}-byte stream (mode {}, filter {}: {} elements of {} bytes, at byte {} of buffer {}) does not decode: {}",
                c.length,
                c.mode.name(),
                c.filter.name(),
                c.count,
                c.stride,
                c.offset,
                c.buffer,
                native_error(&e)
            ))
        })?;
        debug_assert_eq!(bytes.len() as u64, root.buffer_views[v].byte_length.0);

        // The decoded data becomes a buffer of its own; the view reads all of it.
        let mut buffer = root.buffers[root.buffer_views[v].buffer.value()].clone();
        buffer.byte_length = json::validation::USize64(bytes.len() as u64);
        buffer.uri = None;
        buffer.extensions = None;
        root.buffers.push(buffer);
        buffers.push(bytes);
        let view = &mut root.buffer_views[v];
        view.buffer = json::Index::new((buffers.len() - 1) as u32);
        view.byte_offset = None;
        view.extensions = None;
    }
    // Anything still in a fallback buffer has no data to read.
    for (v, view) in root.buffer_views.iter().enumerate() {
        let b = view.buffer.value();
        if fallback.get(b).copied().unwrap_or(false) && !readers(root, v).is_empty() {
            return Err(Error::input(format!(
                "{label}: buffer view {v}{} lies in buffer {b}, a meshopt fallback buffer that holds no data, but is not compressed itself; the file is damaged: re-export it",
                readers(root, v)
            )));
        }
    }
    Ok(())
}

/// Reads the extension's JSON.
fn parse(
    ext: &'static str,
    value: &Value,
    bad: &dyn Fn(std::fmt::Arguments) -> Error,
) -> Result<Compressed> {
    let uint = |key: &str, default: Option<u64>| -> Result<usize> {
        match value.get(key) {
            None => default
                .map(|d| d as usize)
                .ok_or_else(|| bad(format_args!("its \"{key}\" is missing"))),
            Some(v) => v
                .as_u64()
                .and_then(|n| usize::try_from(n).ok())
                .ok_or_else(|| {
                    bad(format_args!(
                        "its \"{key}\" is {v}, where a non-negative integer is required"
                    ))
                }),
        }
    };
    let text = |key: &str| -> Result<Option<&str>> {
        match value.get(key) {
            None => Ok(None),
            Some(Value::String(s)) => Ok(Some(s)),
            Some(v) => Err(bad(format_args!(
                "its \"{key}\" is {v}, where a string is required"
            ))),
        }
    };
    if !value.is_object() {
        return Err(bad(format_args!(
            "its extension object is {value}, not an object"
        )));
    }
    let mode = match text("mode")? {
        Some("ATTRIBUTES") => Mode::Attributes,
        Some("TRIANGLES") => Mode::Triangles,
        Some("INDICES") => Mode::Indices,
        Some(other) => {
            return Err(bad(format_args!(
                "its mode is \"{other}\" (the modes are ATTRIBUTES, TRIANGLES and INDICES)"
            )))
        }
        None => return Err(bad(format_args!("its \"mode\" is missing"))),
    };
    let filter = match text("filter")? {
        None | Some("NONE") => Filter::None,
        Some("OCTAHEDRAL") => Filter::Octahedral,
        Some("QUATERNION") => Filter::Quaternion,
        Some("EXPONENTIAL") => Filter::Exponential,
        Some("COLOR") if ext == MESHOPT_KHR => Filter::Color,
        Some(other) => {
            return Err(bad(format_args!(
                "its filter is \"{other}\" (the filters of {ext} are NONE, OCTAHEDRAL, QUATERNION, EXPONENTIAL{})",
                if ext == MESHOPT_KHR { " and COLOR" } else { "; COLOR is KHR_meshopt_compression's" }
            )))
        }
    };
    Ok(Compressed {
        buffer: uint("buffer", None)?,
        offset: uint("byteOffset", Some(0))?,
        length: uint("byteLength", None)?,
        stride: uint("byteStride", None)?,
        count: uint("count", None)?,
        mode,
        filter,
    })
}

/// The specification's rules for a valid extension object (which are also what meshoptimizer's
/// decoders assume).
fn check(
    c: &Compressed,
    view: &json::buffer::View,
    bad: &dyn Fn(std::fmt::Arguments) -> Error,
) -> Result<()> {
    let s = c.stride;
    if let Some(parent) = view.byte_stride {
        if parent.0 != s {
            return Err(bad(format_args!(
                "its byteStride {s} differs from the buffer view's own byteStride {}",
                parent.0
            )));
        }
    }
    match c.mode {
        Mode::Attributes if s == 0 || s % 4 != 0 || s > 256 => {
            return Err(bad(format_args!(
                "its byteStride is {s}; mode ATTRIBUTES needs a multiple of 4 up to 256"
            )))
        }
        Mode::Triangles | Mode::Indices if s != 2 && s != 4 => {
            return Err(bad(format_args!(
                "its byteStride is {s}; mode {} needs 2 or 4 (16- or 32-bit indices)",
                c.mode.name()
            )))
        }
        Mode::Triangles if c.count % 3 != 0 => {
            return Err(bad(format_args!(
                "its count is {}, not a multiple of 3, which mode TRIANGLES needs",
                c.count
            )))
        }
        Mode::Triangles | Mode::Indices if c.filter != Filter::None => {
            return Err(bad(format_args!(
                "it has filter {} with mode {}; only ATTRIBUTES takes a filter",
                c.filter.name(),
                c.mode.name()
            )))
        }
        _ => {}
    }
    let ok = match c.filter {
        Filter::None | Filter::Exponential => true,
        Filter::Octahedral | Filter::Color => s == 4 || s == 8,
        Filter::Quaternion => s == 8,
    };
    if !ok {
        return Err(bad(format_args!(
            "its byteStride is {s}, which filter {} does not allow ({})",
            c.filter.name(),
            match c.filter {
                Filter::Quaternion => "it needs 8",
                _ => "it needs 4 or 8",
            }
        )));
    }
    let decoded = s.checked_mul(c.count).map(|n| n as u64);
    if decoded != Some(view.byte_length.0) {
        return Err(bad(format_args!(
            "{} elements of {s} bytes make {} bytes, and the buffer view's byteLength is {}: the counts do not match",
            c.count,
            decoded.map_or_else(|| "more than any buffer can hold".to_owned(), |n| n.to_string()),
            view.byte_length.0
        )));
    }
    Ok(())
}

/// What meshoptimizer's return code means.
fn native_error(e: &meshopt::Error) -> String {
    match e {
        meshopt::Error::Native(-1) => {
            "its header names no meshopt bitstream version this decoder knows (the data is not a meshopt stream, or a newer one)".into()
        }
        meshopt::Error::Native(-2) => "the stream ends early or is malformed".into(),
        meshopt::Error::Native(-3) => {
            "bytes are left over after the declared elements (byteLength, count or byteStride is wrong)".into()
        }
        other => format!("meshoptimizer reports {other}"),
    }
}

/// One vertex of `N` bytes, for meshoptimizer's vertex decoder (which takes the element size from
/// the type).
#[derive(Clone, Copy)]
struct Element<const N: usize>([u8; N]);

impl<const N: usize> Default for Element<N> {
    fn default() -> Self {
        Element([0; N])
    }
}

fn decode_attributes<const N: usize>(
    stream: &[u8],
    count: usize,
) -> std::result::Result<Vec<u8>, meshopt::Error> {
    let elements: Vec<Element<N>> = meshopt::decode_vertex_buffer(stream, count)?;
    let mut out = Vec::with_capacity(count * N);
    for e in &elements {
        out.extend_from_slice(&e.0);
    }
    Ok(out)
}

/// Decodes one stream to the buffer view's bytes (little-endian, as glTF stores them).
fn decode(c: &Compressed, stream: &[u8]) -> std::result::Result<Vec<u8>, meshopt::Error> {
    let n = c.count;
    let mut bytes = match (c.mode, c.stride) {
        (Mode::Triangles, 2) => le16(&meshopt::decode_index_buffer::<u16>(stream, n)?),
        (Mode::Triangles, _) => le32(&meshopt::decode_index_buffer::<u32>(stream, n)?),
        (Mode::Indices, 2) => le16(&meshopt::decode_index_sequence::<u16>(stream, n)?),
        (Mode::Indices, _) => le32(&meshopt::decode_index_sequence::<u32>(stream, n)?),
        (Mode::Attributes, stride) => {
            macro_rules! by_stride {
                ($($s:literal)*) => {
                    match stride {
                        $($s => decode_attributes::<$s>(stream, n)?,)*
                        // check() allows nothing else.
                        _ => return Err(meshopt::Error::Parse(format!("byte stride {stride}"))),
                    }
                };
            }
            by_stride!(4 8 12 16 20 24 28 32 36 40 44 48 52 56 60 64 68 72 76 80 84 88 92 96 100
                104 108 112 116 120 124 128 132 136 140 144 148 152 156 160 164 168 172 176 180 184
                188 192 196 200 204 208 212 216 220 224 228 232 236 240 244 248 252 256)
        }
    };
    match (c.filter, c.stride) {
        (Filter::None, _) => {}
        (Filter::Octahedral, 4) => with_i8x4(&mut bytes, meshopt::decode_filter_oct::<i8>),
        (Filter::Octahedral, _) => with_i16x4(&mut bytes, meshopt::decode_filter_oct::<i16>),
        (Filter::Quaternion, _) => with_i16x4(&mut bytes, meshopt::decode_filter_quat),
        // meshoptimizer picks the component width from the stride and reads the bytes as colour
        // (unsigned) itself: the Rust type only carries the stride.
        (Filter::Color, 4) => with_i8x4(&mut bytes, meshopt::decode_filter_color::<i8>),
        (Filter::Color, _) => with_i16x4(&mut bytes, meshopt::decode_filter_color::<i16>),
        // Each 32-bit value is decoded on its own, whatever the stride.
        (Filter::Exponential, _) => {
            let mut values: Vec<[u32; 1]> = bytes
                .chunks_exact(4)
                .map(|b| [u32::from_le_bytes([b[0], b[1], b[2], b[3]])])
                .collect();
            meshopt::decode_filter_exp(&mut values);
            bytes = le32(&values.iter().map(|v| v[0]).collect::<Vec<_>>());
        }
    }
    Ok(bytes)
}

fn le16(v: &[u16]) -> Vec<u8> {
    v.iter().flat_map(|i| i.to_le_bytes()).collect()
}

fn le32(v: &[u32]) -> Vec<u8> {
    v.iter().flat_map(|i| i.to_le_bytes()).collect()
}

fn with_i8x4(bytes: &mut [u8], filter: impl Fn(&mut [[i8; 4]])) {
    let mut values: Vec<[i8; 4]> = bytes
        .chunks_exact(4)
        .map(|b| [b[0] as i8, b[1] as i8, b[2] as i8, b[3] as i8])
        .collect();
    filter(&mut values);
    for (out, v) in bytes.chunks_exact_mut(4).zip(&values) {
        out.copy_from_slice(&v.map(|c| c as u8));
    }
}

fn with_i16x4(bytes: &mut [u8], filter: impl Fn(&mut [[i16; 4]])) {
    let mut values: Vec<[i16; 4]> = bytes
        .chunks_exact(8)
        .map(|b| std::array::from_fn(|k| i16::from_le_bytes([b[2 * k], b[2 * k + 1]])))
        .collect();
    filter(&mut values);
    for (out, v) in bytes.chunks_exact_mut(8).zip(&values) {
        for (k, c) in v.iter().enumerate() {
            out[2 * k..2 * k + 2].copy_from_slice(&c.to_le_bytes());
        }
    }
}

#[cfg(test)]
mod tests {
    //! Each filter and mode against meshoptimizer's own encoders: what decode() returns is what
    //! was encoded, within the filter's precision.
    use super::*;

    fn compressed(
        mode: Mode,
        filter: Filter,
        stride: usize,
        count: usize,
        length: usize,
    ) -> Compressed {
        Compressed {
            buffer: 0,
            offset: 0,
            length,
            stride,
            count,
            mode,
            filter,
        }
    }

    fn attributes<T>(elements: &[T], filter: Filter, version: Option<i32>) -> Vec<u8> {
        let stream = meshopt::encode_vertex_buffer_level(elements, 2, version).unwrap();
        let stride = std::mem::size_of::<T>();
        let c = compressed(
            Mode::Attributes,
            filter,
            stride,
            elements.len(),
            stream.len(),
        );
        let bytes = decode(&c, &stream).expect("decodes");
        assert_eq!(bytes.len(), stride * elements.len());
        bytes
    }

    /// Unit vectors spread over the sphere, and a sign in w.
    fn directions(n: usize) -> Vec<[f32; 4]> {
        (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
                let r = (1.0 - z * z).sqrt();
                let phi = i as f32 * 2.399_963;
                [
                    r * phi.cos(),
                    r * phi.sin(),
                    z,
                    if i % 3 == 0 { -1.0 } else { 1.0 },
                ]
            })
            .collect()
    }

    fn i16s(bytes: &[u8]) -> Vec<i16> {
        bytes
            .chunks_exact(2)
            .map(|b| i16::from_le_bytes([b[0], b[1]]))
            .collect()
    }

    #[test]
    fn octahedral_filter_restores_unit_vectors_at_8_and_16_bits() {
        let dirs = directions(300);
        for version in [Some(0), Some(1)] {
            let enc8 = meshopt::encode_filter_oct::<i8>(&dirs, 8);
            let out = attributes(&enc8, Filter::Octahedral, version);
            for (d, e) in dirs.iter().zip(out.chunks_exact(4)) {
                let v = [e[0] as i8, e[1] as i8, e[2] as i8].map(|c| c as f32 / 127.0);
                let dot = v[0] * d[0] + v[1] * d[1] + v[2] * d[2];
                let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                // 8-bit octahedral: a few degrees at worst.
                assert!(dot / len > 0.995, "{v:?} against {d:?}");
            }
            let enc16 = meshopt::encode_filter_oct::<i16>(&dirs, 16);
            let out = i16s(&attributes(&enc16, Filter::Octahedral, version));
            for (d, e) in dirs.iter().zip(out.chunks_exact(4)) {
                let v = [e[0], e[1], e[2]].map(|c| c as f32 / 32767.0);
                // The decoder's integers are not exactly unit length: compare directions.
                let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                let dot = (v[0] * d[0] + v[1] * d[1] + v[2] * d[2]) / len;
                assert!(dot > 0.99999, "{v:?} against {d:?}");
                // W is kept: the tangent's sign.
                assert_eq!(e[3].signum() as f32, d[3], "w of {d:?}");
            }
        }
    }

    #[test]
    fn quaternion_filter_restores_unit_quaternions() {
        let quats: Vec<[f32; 4]> = directions(200)
            .iter()
            .map(|d| {
                let (s, c) = (0.3 * d[3] + d[0]).sin_cos();
                [d[0] * s, d[1] * s, d[2] * s, c]
            })
            .map(|q| {
                let l = q.iter().map(|c| c * c).sum::<f32>().sqrt();
                q.map(|c| c / l)
            })
            .collect();
        let enc = meshopt::encode_filter_quat(&quats, 12);
        let out = i16s(&attributes(&enc, Filter::Quaternion, None));
        for (q, e) in quats.iter().zip(out.chunks_exact(4)) {
            let v: Vec<f32> = e.iter().map(|&c| c as f32 / 32767.0).collect();
            // q and -q are one rotation.
            let dot: f32 = (0..4).map(|k| v[k] * q[k]).sum();
            assert!(dot.abs() > 0.9995, "{v:?} against {q:?}");
        }
    }

    #[test]
    fn exponential_filter_restores_floats_for_any_stride() {
        let points: Vec<[f32; 3]> = (0..250)
            .map(|i| {
                let t = i as f32 * 0.37;
                [t.sin() * 12.5, -0.001 * t, 1e4 + t]
            })
            .collect();
        let enc = meshopt::encode_filter_exp(&points, 23, meshopt::EncodeExpMode::Separate);
        let out = attributes(&enc, Filter::Exponential, Some(1));
        for (p, e) in points.iter().zip(out.chunks_exact(12)) {
            for k in 0..3 {
                let b = &e[4 * k..4 * k + 4];
                let v = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                // 23-bit signed mantissa: 22 bits of magnitude under an exponent of at most
                // twice |p|, rounded: within 2^-22 |p|.
                assert!(
                    (v - p[k]).abs() <= p[k].abs() * 2f32.powi(-22),
                    "{v} against {}",
                    p[k]
                );
            }
        }
    }

    #[test]
    fn color_filter_restores_rgba_at_8_and_16_bits() {
        let colors: Vec<[f32; 4]> = (0..100)
            .map(|i| {
                let t = i as f32 / 99.0;
                [t, 1.0 - t, (t * 7.0).fract(), 0.5 + 0.5 * t]
            })
            .collect();
        let enc8 = meshopt::encode_filter_color::<u8>(&colors, 8);
        let out = attributes(&enc8, Filter::Color, Some(1));
        for (c, e) in colors.iter().zip(out.chunks_exact(4)) {
            for k in 0..4 {
                let v = e[k] as f32 / 255.0;
                // YCoCg at 8 bits (alpha at 7): within a few steps.
                assert!((v - c[k]).abs() < 4.0 / 255.0, "{v} against {}", c[k]);
            }
        }
        let enc16 = meshopt::encode_filter_color::<u16>(&colors, 16);
        let out = attributes(&enc16, Filter::Color, Some(1));
        for (c, e) in colors.iter().zip(out.chunks_exact(8)) {
            for k in 0..4 {
                let v = u16::from_le_bytes([e[2 * k], e[2 * k + 1]]) as f32 / 65535.0;
                assert!((v - c[k]).abs() < 4.0 / 65535.0, "{v} against {}", c[k]);
            }
        }
    }

    #[test]
    fn index_modes_restore_the_triangles_and_the_sequence() {
        // A strip of quads: triangle lists for TRIANGLES, any sequence for INDICES.
        let tris: Vec<u32> = (0..40u32)
            .flat_map(|q| [2 * q, 2 * q + 1, 2 * q + 2, 2 * q + 2, 2 * q + 1, 2 * q + 3])
            .collect();
        let stream = meshopt::encode_index_buffer(&tris, 82).unwrap();
        for stride in [2, 4] {
            let c = compressed(
                Mode::Triangles,
                Filter::None,
                stride,
                tris.len(),
                stream.len(),
            );
            let bytes = decode(&c, &stream).unwrap();
            let got: Vec<u32> = match stride {
                2 => bytes
                    .chunks_exact(2)
                    .map(|b| u16::from_le_bytes([b[0], b[1]]) as u32)
                    .collect(),
                _ => bytes
                    .chunks_exact(4)
                    .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .collect(),
            };
            // The codec may rotate a triangle's corners, never change the triangle or its winding.
            for (a, b) in tris.chunks_exact(3).zip(got.chunks_exact(3)) {
                let rotations = [[b[0], b[1], b[2]], [b[1], b[2], b[0]], [b[2], b[0], b[1]]];
                assert!(
                    rotations.contains(&[a[0], a[1], a[2]]),
                    "{a:?} became {b:?}"
                );
            }
        }
        let sequence: Vec<u32> = (0..500u32).map(|i| (i * 7919) % 1000).collect();
        let stream = meshopt::encode_index_sequence(&sequence, 1000).unwrap();
        for stride in [2, 4] {
            let c = compressed(
                Mode::Indices,
                Filter::None,
                stride,
                sequence.len(),
                stream.len(),
            );
            let bytes = decode(&c, &stream).unwrap();
            let got: Vec<u32> = match stride {
                2 => bytes
                    .chunks_exact(2)
                    .map(|b| u16::from_le_bytes([b[0], b[1]]) as u32)
                    .collect(),
                _ => bytes
                    .chunks_exact(4)
                    .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .collect(),
            };
            assert_eq!(got, sequence);
        }
    }

    #[test]
    fn every_attribute_stride_round_trips_unfiltered() {
        // 4 to 256 bytes: the dispatch over strides covers them all.
        for stride in (4..=256).step_by(4) {
            let data: Vec<u8> = (0..stride * 37).map(|i| (i * 31 % 251) as u8).collect();
            let stream = encode_bytes(&data, stride);
            let c = compressed(Mode::Attributes, Filter::None, stride, 37, stream.len());
            assert_eq!(decode(&c, &stream).unwrap(), data, "stride {stride}");
        }
    }

    /// Encodes `bytes` as vertices of `stride` bytes (the encoder takes the element size from the
    /// type, as the decoder does).
    fn encode_bytes(bytes: &[u8], stride: usize) -> Vec<u8> {
        fn enc<const N: usize>(bytes: &[u8]) -> Vec<u8> {
            let elements: Vec<Element<N>> = bytes
                .chunks_exact(N)
                .map(|c| Element(c.try_into().unwrap()))
                .collect();
            meshopt::encode_vertex_buffer(&elements).unwrap()
        }
        macro_rules! by_stride {
            ($($s:literal)*) => {
                match stride {
                    $($s => enc::<$s>(bytes),)*
                    _ => unreachable!(),
                }
            };
        }
        by_stride!(4 8 12 16 20 24 28 32 36 40 44 48 52 56 60 64 68 72 76 80 84 88 92 96 100
            104 108 112 116 120 124 128 132 136 140 144 148 152 156 160 164 168 172 176 180 184
            188 192 196 200 204 208 212 216 220 224 228 232 236 240 244 248 252 256)
    }
}
