//! The bytes a glTF file refers to: buffers (the .glb binary chunk, `data:` URIs, files beside the
//! scene) and images (decoded to RGBA8). Every failure names the file it was looking for.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use gltf::json;

use crate::Error;

/// Textures larger than this in either dimension are refused (it is also the smallest
/// maxImageDimension2D that Vulkan drivers commonly report).
pub(super) const MAX_TEXTURE_SIZE: u32 = 16384;

/// Decoded RGBA8 bytes of all of a scene's textures together (4 GiB: sixteen 8192 x 8192
/// textures; an image used both as colour and as data is decoded, and counted, twice). Checked
/// from the image headers before decoding, so a few small, highly compressed files cannot make
/// weft allocate tens of gigabytes.
pub(super) const MAX_TEXTURE_BYTES: u64 = 1 << 32;

/// Where a URI's bytes came from, for messages.
pub(super) enum Origin {
    DataUri,
    File(PathBuf),
}

/// Resolved contents of a URI, plus its media type when a `data:` URI declares one.
pub(super) struct Fetched {
    pub bytes: Vec<u8>,
    pub mime: Option<String>,
    pub origin: Origin,
}

/// Short printable form of a URI: data URIs are long, so only their media type is shown.
pub(super) fn describe_uri(uri: &str) -> String {
    match uri.strip_prefix("data:") {
        Some(rest) => format!(
            "an embedded data: URI ({})",
            rest.split([';', ','])
                .next()
                .filter(|m| !m.is_empty())
                .unwrap_or("no media type")
        ),
        None => format!("'{uri}'"),
    }
}

thread_local! {
    /// The files [`fetch`] read on this thread while [`recording_files`] runs.
    static READ: std::cell::RefCell<Option<Vec<PathBuf>>> = const { std::cell::RefCell::new(None) };
}

/// Runs `f` (a load), returning with its result the files beside the scene it read (buffers and
/// images), in order: what a command must not overwrite ([`super::Scene::files`]).
pub(super) fn recording_files<T>(f: impl FnOnce() -> T) -> (T, Vec<PathBuf>) {
    let outer = READ.with(|r| r.replace(Some(Vec::new())));
    let result = f();
    let files = READ.with(|r| r.replace(outer)).unwrap_or_default();
    (result, files)
}

/// Reads a URI relative to `base_dir`. `what` says who refers to it ("buffer 0", "material 'x'
/// (base colour texture) image 2"); `label` is the scene, for messages.
pub(super) fn fetch(
    uri: &str,
    base_dir: Option<&Path>,
    label: &str,
    what: &str,
) -> crate::Result<Fetched> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, payload) = rest.split_once(',').ok_or_else(|| {
            Error::input(format!("{label}: {what} has a data: URI with no ',' before its payload; re-export the file"))
        })?;
        let mime = header
            .split(';')
            .next()
            .filter(|m| !m.is_empty())
            .map(str::to_owned);
        let bytes = if header.ends_with(";base64") {
            decode_base64(payload).ok_or_else(|| {
                Error::input(format!(
                    "{label}: {what} has a data: URI whose base64 payload is malformed; re-export the file"
                ))
            })?
        } else {
            percent_decode(payload)
        };
        return Ok(Fetched {
            bytes,
            mime,
            origin: Origin::DataUri,
        });
    }

    let relative = if let Some(path) = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
    {
        PathBuf::from(String::from_utf8_lossy(&percent_decode(path)).into_owned())
    } else if let Some((scheme, _)) = uri.split_once(':').filter(|(s, _)| {
        // A one-letter "scheme" is a Windows drive ("C:\..."), not a URI scheme.
        s.len() > 1
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    }) {
        return Err(Error::input(format!(
            "{label}: {what} refers to '{uri}', a '{scheme}:' URI that weft cannot fetch; download the file, put it beside the scene and refer to it by a relative path"
        )));
    } else {
        PathBuf::from(String::from_utf8_lossy(&percent_decode(uri)).into_owned())
    };

    let Some(base_dir) = base_dir else {
        return Err(Error::input(format!(
            "{label}: {what} refers to the external file '{uri}', but this scene was loaded from memory, so there is no directory to find it in; load the scene from its file, or embed the data (a .glb, or data: URIs)"
        )));
    };
    let path = base_dir.join(&relative);
    match std::fs::read(&path) {
        Ok(bytes) => {
            READ.with(|r| {
                if let Some(files) = r.borrow_mut().as_mut() {
                    if !files.contains(&path) {
                        files.push(path.clone());
                    }
                }
            });
            Ok(Fetched { bytes, mime: None, origin: Origin::File(path) })
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(Error::input(format!(
            "{label}: {what} refers to '{uri}', but '{}' does not exist; put the file there or fix the uri in the scene",
            path.display()
        ))),
        Err(e) => Err(Error::input(format!(
            "{label}: {what} refers to '{uri}', but '{}' could not be read: {e}; check that it is a readable file",
            path.display()
        ))),
    }
}

/// Loads every buffer of the document: the GLB binary chunk for a buffer without a uri, else its uri.
pub(super) fn load_buffers(
    root: &json::Root,
    mut glb_bin: Option<Vec<u8>>,
    base_dir: Option<&Path>,
    label: &str,
) -> crate::Result<Vec<Vec<u8>>> {
    let mut out = Vec::with_capacity(root.buffers.len());
    for (i, buffer) in root.buffers.iter().enumerate() {
        let what = match &buffer.name {
            Some(name) => format!("buffer {i} ('{name}')"),
            None => format!("buffer {i}"),
        };
        // A meshopt fallback buffer is never read: its views are decoded from their compressed
        // streams (src/scene/compressed.rs), so it has no data to load.
        if buffer.uri.is_none() && super::compressed::is_fallback_buffer(root, i) {
            out.push(Vec::new());
            continue;
        }
        let (bytes, from) = match &buffer.uri {
            Some(uri) => (fetch(uri, base_dir, label, &what)?.bytes, describe_uri(uri)),
            None => match glb_bin.take() {
                Some(bin) => (bin, "the .glb binary chunk".to_owned()),
                None => {
                    return Err(Error::input(format!(
                        "{label}: {what} has no uri, so its data must be the binary chunk of a .glb file, but {}; re-export the scene",
                        if i == 0 { "the file has none" } else { "only the first buffer may use it" }
                    )))
                }
            },
        };
        let declared = buffer.byte_length.0;
        if (bytes.len() as u64) < declared {
            return Err(Error::input(format!(
                "{label}: {what} declares {declared} bytes but {from} holds only {}; the data is truncated or belongs to another export: re-export the scene",
                bytes.len()
            )));
        }
        out.push(bytes);
    }
    Ok(out)
}

/// An image decoded to RGBA8, rows top to bottom.
pub(super) struct Decoded {
    pub width: u32,
    pub height: u32,
    pub rgba8: Vec<u8>,
    /// A KTX2 file's own mip chain as BC7 blocks ([`super::Texture::bc7`]).
    pub bc7: Option<Vec<Vec<u8>>>,
}

/// A printable name for image `index`: its name or uri when it has one.
pub(super) fn image_label(root: &json::Root, index: usize) -> String {
    match root.images.get(index) {
        Some(image) => match (&image.uri, &image.name) {
            (Some(uri), _) if !uri.starts_with("data:") => format!("image {index} ('{uri}')"),
            (_, Some(name)) => format!("image {index} ('{name}')"),
            _ => format!("image {index}"),
        },
        None => format!("image {index}"),
    }
}

/// Fetches and decodes image `index`. `what` names the material and slot that use it;
/// `bytes_left` is what remains of [`MAX_TEXTURE_BYTES`], reduced by this image's decoded size.
pub(super) fn load_image(
    root: &json::Root,
    buffers: &[Vec<u8>],
    index: usize,
    base_dir: Option<&Path>,
    label: &str,
    what: &str,
    bytes_left: &mut u64,
) -> crate::Result<Decoded> {
    let image_name = image_label(root, index);
    let who = format!("{what} uses {image_name}, which");
    let image = root.images.get(index).ok_or_else(|| {
        Error::input(format!(
            "{label}: {what} uses image {index}, which does not exist; fix the texture's source"
        ))
    })?;

    let (bytes, mime, origin) = match (&image.uri, &image.buffer_view) {
        (Some(uri), _) => {
            let f = fetch(uri, base_dir, label, &format!("{what} uses image {index}, which"))?;
            let origin = match f.origin {
                Origin::DataUri => "its data: URI".to_owned(),
                Origin::File(p) => format!("'{}'", p.display()),
            };
            (std::borrow::Cow::Owned(f.bytes), f.mime, origin)
        }
        (None, Some(view_index)) => {
            let view = root.buffer_views.get(view_index.value()).ok_or_else(|| {
                Error::input(format!(
                    "{label}: {who} uses buffer view {}, which does not exist; re-export the scene",
                    view_index.value()
                ))
            })?;
            let start = view.byte_offset.map_or(0, |o| o.0) as usize;
            let bytes = buffers
                .get(view.buffer.value())
                .and_then(|b| b.get(start..start.checked_add(view.byte_length.0 as usize)?))
                .ok_or_else(|| {
                    Error::input(format!(
                        "{label}: {who} is stored in buffer view {}, which lies outside its buffer; re-export the scene",
                        view_index.value()
                    ))
                })?;
            let mime = image.mime_type.as_ref().map(|m| m.0.clone());
            (std::borrow::Cow::Borrowed(bytes), mime, format!("buffer view {}", view_index.value()))
        }
        (None, None) => {
            return Err(Error::input(format!(
                "{label}: {who} has neither a uri nor a bufferView; give the image a source or remove the texture"
            )))
        }
    };

    // KTX2 (KHR_texture_basisu, or a core texture.source as AnisotropyBarnLamp has it).
    if super::ktx::is_ktx2(&bytes, mime.as_deref()) {
        let refused =
            |why: String| Error::input(format!("{label}: {who} comes from {origin} and {why}"));
        let (width, height) = super::ktx::dimensions(&bytes).map_err(refused)?;
        check_size(width, height, label, &who, &origin, bytes_left)?;
        let decoded = super::ktx::decode(&bytes).map_err(refused)?;
        return Ok(Decoded {
            width: decoded.width,
            height: decoded.height,
            rgba8: decoded.rgba8,
            bc7: decoded.bc7,
        });
    }

    let format = match mime.as_deref() {
        Some("image/png") => Some(image::ImageFormat::Png),
        Some("image/jpeg") => Some(image::ImageFormat::Jpeg),
        Some("image/webp") => Some(image::ImageFormat::WebP),
        _ => None,
    };
    let format = match format.or_else(|| image::guess_format(&bytes).ok()) {
        Some(
            f @ (image::ImageFormat::Png | image::ImageFormat::Jpeg | image::ImageFormat::WebP),
        ) => f,
        other => {
            let kind = match (other, mime.as_deref()) {
                (Some(f), _) => format!("{f:?}"),
                (None, Some(m)) => m.to_owned(),
                (None, None) => "not a recognisable image".to_owned(),
            };
            return Err(Error::input(format!(
                "{label}: {who} comes from {origin} and is {kind}; weft reads PNG, JPEG, WebP and KTX2 textures: convert the image"
            )));
        }
    };

    let reader = image::ImageReader::with_format(Cursor::new(&bytes[..]), format);
    let (width, height) = reader.into_dimensions().map_err(|e| {
        Error::input(format!(
            "{label}: {who} comes from {origin} and could not be decoded as {format:?}: {e}; re-save the image"
        ))
    })?;
    check_size(width, height, label, &who, &origin, bytes_left)?;
    let mut reader = image::ImageReader::with_format(Cursor::new(&bytes[..]), format);
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIZE);
    limits.max_image_height = Some(MAX_TEXTURE_SIZE);
    // Room for the largest allowed image at 16-bit RGBA while decoding.
    limits.max_alloc = Some(u64::from(MAX_TEXTURE_SIZE).pow(2) * 8 + (64 << 20));
    reader.limits(limits);
    let decoded = reader.decode().map_err(|e| {
        Error::input(format!(
            "{label}: {who} comes from {origin} and could not be decoded as {format:?}: {e}; re-save the image"
        ))
    })?;
    let rgba = decoded.into_rgba8();
    Ok(Decoded {
        width: rgba.width(),
        height: rgba.height(),
        rgba8: rgba.into_raw(),
        bc7: None,
    })
}

/// Refuses an image of `width` x `height` beyond [`MAX_TEXTURE_SIZE`] or past what is left of
/// [`MAX_TEXTURE_BYTES`]; otherwise takes its RGBA8 size from `bytes_left`.
fn check_size(
    width: u32,
    height: u32,
    label: &str,
    who: &str,
    origin: &str,
    bytes_left: &mut u64,
) -> crate::Result<()> {
    if width > MAX_TEXTURE_SIZE || height > MAX_TEXTURE_SIZE || width == 0 || height == 0 {
        return Err(Error::input(format!(
            "{label}: {who} comes from {origin} and is {width}x{height} pixels; textures must be between 1 and {MAX_TEXTURE_SIZE} pixels on each side: scale the image down"
        )));
    }
    let decoded_bytes = u64::from(width) * u64::from(height) * 4;
    if decoded_bytes > *bytes_left {
        return Err(Error::input(format!(
            "{label}: {who} comes from {origin} and is {width}x{height} pixels, which brings the scene's decoded textures past weft's limit of {} GiB; scale the textures down",
            MAX_TEXTURE_BYTES >> 30
        )));
    }
    *bytes_left -= decoded_bytes;
    Ok(())
}

/// Standard or URL-safe base64, padding optional, whitespace ignored. None if malformed.
pub(super) fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(text.len() / 4 * 3 + 3);
    let mut acc: u32 = 0;
    let mut bits = 0;
    let mut padding = false;
    for c in text.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' => {
                padding = true;
                continue;
            }
            b' ' | b'\n' | b'\r' | b'\t' => continue,
            _ => return None,
        };
        if padding {
            return None; // data after padding
        }
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    // 6 leftover bits cannot be: one base64 digit alone never ends a valid encoding.
    (bits < 6).then_some(out)
}

/// Decodes %XX escapes (URIs in glTF are percent-encoded: RFC 3986 section 2.1, exactly two hex
/// digits); malformed escapes are kept as they are.
pub(super) fn percent_decode(text: &str) -> Vec<u8> {
    // The value of one hex digit. Not `u8::from_str_radix`, which accepts a sign: "%+1" would
    // decode to 0x01.
    let hex = |c: u8| (c as char).to_digit(16).map(|d| d as u8);
    let b = text.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            if let (Some(hi), Some(lo)) = (
                b.get(i + 1).copied().and_then(hex),
                b.get(i + 2).copied().and_then(hex),
            ) {
                out.push(hi << 4 | lo);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_escapes_need_exactly_two_hex_digits() {
        // A sign is not a hex digit: kept as written (from_str_radix decoded "%+1" to 0x01).
        assert_eq!(percent_decode("a%+1b"), b"a%+1b");
        assert_eq!(percent_decode("%-1"), b"%-1");
        assert_eq!(percent_decode("%+f%+F"), b"%+f%+F");
        // Well-formed escapes, either case, at the very end too.
        assert_eq!(percent_decode("my%20file%2Fx%2f.png"), b"my file/x/.png");
        assert_eq!(percent_decode("%41"), b"A");
        assert_eq!(percent_decode("%ff%00"), [0xff, 0x00]);
        // Too short, not hex, or a multi-byte character after the %: kept.
        assert_eq!(percent_decode("%4"), b"%4");
        assert_eq!(percent_decode("%"), b"%");
        assert_eq!(percent_decode("%g1"), b"%g1");
        assert_eq!(percent_decode("%\u{e9}1"), "%\u{e9}1".as_bytes());
    }

    #[test]
    fn decoded_textures_are_counted_against_the_budget_before_decoding() {
        let mut png = Vec::new();
        image::RgbaImage::new(2, 2)
            .write_to(&mut Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let root: json::Root = serde_json::from_value(serde_json::json!({
            "asset": {"version": "2.0"},
            "bufferViews": [{"buffer": 0, "byteLength": png.len()}],
            "images": [{"bufferView": 0, "mimeType": "image/png"}],
        }))
        .unwrap();
        let buffers = vec![png];
        let load =
            |left: &mut u64| load_image(&root, &buffers, 0, None, "'t.gltf'", "material 'm'", left);
        // A 2x2 RGBA8 image is 16 bytes: one byte short of room is an error, and nothing is spent.
        let mut left = 15;
        let err = load(&mut left).err().expect("over the budget").to_string();
        assert!(
            err.contains("2x2 pixels") && err.contains("limit of 4 GiB"),
            "{err}"
        );
        assert_eq!(left, 15);
        let mut left = 16;
        assert_eq!(load(&mut left).unwrap().rgba8.len(), 16);
        assert_eq!(left, 0);
    }

    #[test]
    fn base64_round_trips_known_values() {
        assert_eq!(decode_base64("TWFu").unwrap(), b"Man");
        assert_eq!(decode_base64("TWE=").unwrap(), b"Ma");
        assert_eq!(decode_base64("TQ==").unwrap(), b"M");
        assert_eq!(decode_base64("TQ").unwrap(), b"M");
        assert_eq!(decode_base64("").unwrap(), b"");
        assert!(decode_base64("T").is_none());
        assert!(decode_base64("TQ==TQ").is_none());
        assert!(decode_base64("T*Q=").is_none());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.png"), b"a b.png");
        assert_eq!(percent_decode("100%"), b"100%");
        assert_eq!(percent_decode("%zz"), b"%zz");
        assert_eq!(percent_decode("%41"), b"A");
    }
}
