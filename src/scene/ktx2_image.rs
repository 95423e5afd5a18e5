//! KTX2 images (`KHR_texture_basisu`, or a KTX2 file as a core texture source) to RGBA8.
//!
//! The container is read by the `ktx2` crate; Zstandard supercompression is undone by `ruzstd`
//! (pure Rust); UASTC is transcoded to RGBA8 by Binomial's Basis Universal transcoder through the
//! `basis-universal` crate (the bindings Bevy uses). Plain KTX2 in R8G8B8A8 (UNORM or SRGB) is
//! taken as it is. What is not read is refused with its name: ETC1S (BasisLZ supercompression,
//! whose codebooks the crate's low-level transcoder cannot take), ZLIB supercompression, other
//! Vulkan formats, arrays, cube maps and 3D textures.
//!
//! Level 0 is used: weft builds every texture's mip chain itself (as for PNG), so the file's own
//! smaller levels are not uploaded. The texture's colour space comes from the slot that uses it,
//! as for PNG (the file's transfer function is not consulted).

use ktx2::{ColorModel, Format, SupercompressionScheme};

use super::resources::{Decoded, MAX_TEXTURE_BYTES, MAX_TEXTURE_SIZE};

/// The KTX2 file identifier (its first 12 bytes).
pub(super) const MAGIC: &[u8] = b"\xABKTX 20\xBB\r\n\x1A\n";

/// Decodes a KTX2 file's level 0 to RGBA8. `who` names the image and its user, `origin` where its
/// bytes came from; `bytes_left` is what remains of [`MAX_TEXTURE_BYTES`].
pub(super) fn decode(
    bytes: &[u8],
    label: &str,
    who: &str,
    origin: &str,
    bytes_left: &mut u64,
) -> crate::Result<Decoded> {
    let fail = |why: std::fmt::Arguments, fix: &str| {
        crate::Error::input(format!(
            "{label}: {who} comes from {origin} and is a KTX2 texture that {why}; {fix}"
        ))
    };
    let convert = "convert the texture to PNG (for example `gltf-transform png IN OUT`) or re-encode it as UASTC (`toktx --encode uastc --zcmp`)";
    let reader = ktx2::Reader::new(bytes).map_err(|e| {
        fail(format_args!("does not parse ({e})"), "the file is truncated or damaged: re-export it")
    })?;
    let h = reader.header();
    let (width, height) = (h.pixel_width, h.pixel_height.max(1));
    if h.pixel_depth > 1 || h.layer_count > 1 || h.face_count != 1 {
        return Err(fail(
            format_args!(
                "is a {} (depth {}, {} layers, {} faces), where a glTF texture is one 2D image",
                if h.face_count == 6 { "cube map" } else if h.pixel_depth > 1 { "3D texture" } else { "texture array" },
                h.pixel_depth,
                h.layer_count,
                h.face_count
            ),
            "export a single 2D texture",
        ));
    }
    if width > MAX_TEXTURE_SIZE || height > MAX_TEXTURE_SIZE {
        return Err(fail(
            format_args!("is {width}x{height} pixels, past weft's limit of {MAX_TEXTURE_SIZE} on each side"),
            "scale the image down",
        ));
    }
    let decoded_bytes = u64::from(width) * u64::from(height) * 4;
    if decoded_bytes > *bytes_left {
        return Err(fail(
            format_args!(
                "is {width}x{height} pixels, which brings the scene's decoded textures past weft's limit of {} GiB",
                MAX_TEXTURE_BYTES >> 30
            ),
            "scale the textures down",
        ));
    }

    let model = reader.color_model();
    let uastc = h.format.is_none() && model == Some(ColorModel::UASTC);
    let rgba8 = matches!(h.format, Some(Format::R8G8B8A8_UNORM | Format::R8G8B8A8_SRGB));
    if !uastc && !rgba8 {
        let what = match (h.format, model) {
            (None, Some(ColorModel::ETC1S)) => "is Basis Universal ETC1S (BasisLZ), which weft's transcoder (the basis-universal crate's low-level UASTC transcoder) does not read".to_owned(),
            (None, m) => format!("has no Vulkan format and colour model {m:?}, neither UASTC nor plain RGBA8"),
            (Some(f), _) => format!("stores Vulkan format {f:?}; weft reads UASTC (Basis Universal) and R8G8B8A8 KTX2 textures"),
        };
        return Err(fail(format_args!("{what}"), convert));
    }
    let level = reader
        .levels()
        .next()
        .ok_or_else(|| fail(format_args!("has no image level"), "re-export it"))?;
    // UASTC: 16 bytes per 4x4 block; RGBA8: 4 per pixel.
    let (bx, by) = (width.div_ceil(4), height.div_ceil(4));
    let expected = if uastc {
        u64::from(bx) * u64::from(by) * 16
    } else {
        decoded_bytes
    } as usize;
    let data: std::borrow::Cow<[u8]> = match h.supercompression_scheme {
        None => std::borrow::Cow::Borrowed(level.data),
        Some(SupercompressionScheme::Zstandard) => {
            let mut out = Vec::with_capacity(expected);
            ruzstd::decoding::FrameDecoder::new()
                .decode_all_to_vec(level.data, &mut out)
                .map_err(|e| {
                    fail(
                        format_args!("has a Zstandard-compressed level 0 that does not decompress to the {expected} bytes of a {width}x{height} image ({e})"),
                        "the file is truncated or damaged: re-export it",
                    )
                })?;
            std::borrow::Cow::Owned(out)
        }
        Some(other) => {
            return Err(fail(
                format_args!("uses {other:?} supercompression, which weft does not read (it reads Zstandard and none)"),
                convert,
            ))
        }
    };
    if data.len() != expected {
        return Err(fail(
            format_args!(
                "has {} bytes in level 0 where a {width}x{height} {} image has {expected}",
                data.len(),
                if uastc { "UASTC" } else { "RGBA8" }
            ),
            "the file is truncated or damaged: re-export it",
        ));
    }
    let rgba = if uastc {
        use basis_universal::{DecodeFlags, LowLevelUastcTranscoder, SliceParametersUastc, TranscoderBlockFormat};
        let has_alpha = reader
            .basic_dfd()
            .is_some_and(|d| d.sample_information().count() > 1);
        LowLevelUastcTranscoder::new()
            .transcode_slice(
                &data,
                SliceParametersUastc {
                    num_blocks_x: bx,
                    num_blocks_y: by,
                    has_alpha,
                    original_width: width,
                    original_height: height,
                },
                DecodeFlags::HIGH_QUALITY,
                TranscoderBlockFormat::RGBA32,
            )
            .map_err(|e| {
                fail(
                    format_args!("does not transcode from UASTC ({e:?})"),
                    "the file is damaged: re-export it",
                )
            })?
    } else {
        data.into_owned()
    };
    if rgba.len() as u64 != decoded_bytes {
        return Err(fail(
            format_args!("transcoded to {} bytes where {width}x{height} RGBA8 has {decoded_bytes}", rgba.len()),
            "re-export it",
        ));
    }
    *bytes_left -= decoded_bytes;
    Ok(Decoded { width, height, rgba8: rgba })
}
