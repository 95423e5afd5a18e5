//! KTX2 images (`KHR_texture_basisu`, or a core `texture.source` that is a `.ktx2` file), decoded
//! to RGBA8 for weft's ordinary texture path (which builds the mip chain itself and picks sRGB or
//! linear by the material slot, as for PNG):
//!
//! - the container is read by the `ktx2` crate, after weft's own check of the one field that crate
//!   trusts (a basic data format descriptor's texel block dimensions);
//! - supercompression: none, Zstandard (`ruzstd`) and ZLIB (`miniz_oxide`), each level's declared
//!   uncompressed length checked against what the format needs before anything is allocated;
//! - UASTC (vkFormat UNDEFINED with a UASTC descriptor) is transcoded to RGBA32 by Binomial's
//!   transcoder (`basis-universal`'s `LowLevelUastcTranscoder`, as Bevy does);
//! - ETC1S (BasisLZ supercompression) is transcoded to RGBA32 by Binomial's ETC1S transcoder,
//!   which the crate reaches only through a `.basis` file: the KTX2 file's global codebooks and
//!   level 0's slices are repacked as one (`etc1s_as_basis`), byte for byte;
//! - plain 8-bit UNORM/SRGB formats (R, RG, RGB, RGBA, BGR, BGRA) are read directly, R and RG
//!   filled out as Vulkan samples them (missing colour channels 0, alpha 1).
//!
//! Only level 0 is read; a file's smaller levels are ignored (weft generates its mip chain).
//! Every failure is an error whose text the caller prefixes with the file and the texture.

use ktx2::{ColorModel, Format, SupercompressionScheme};

/// The identifier every KTX2 file starts with.
pub(super) const MAGIC: &[u8; 12] = b"\xABKTX 20\xBB\r\n\x1A\n";

/// The way out of a damaged file.
const REENCODE: &str = "; re-encode the texture (for example with `toktx`) or re-export the scene";

/// Whether `bytes` (with the media type a data: URI or the image declares) is a KTX2 file.
pub(super) fn is_ktx2(bytes: &[u8], mime: Option<&str>) -> bool {
    bytes.starts_with(MAGIC) || mime == Some("image/ktx2")
}

/// A KTX2 file's level 0 as RGBA8, rows top to bottom, and (for a universal format whose file
/// carries its full mip chain) every level as BC7 blocks.
pub(super) struct Rgba8 {
    pub width: u32,
    pub height: u32,
    pub rgba8: Vec<u8>,
    pub bc7: Option<Vec<Vec<u8>>>,
}

/// The header fields that size the image, read before anything is decoded (for the caller's size
/// limits). `Err` is the reason the file cannot be read, to be completed by the caller.
pub(super) fn dimensions(bytes: &[u8]) -> Result<(u32, u32), String> {
    let reader = open(bytes)?;
    let h = reader.header();
    Ok((h.pixel_width, h.pixel_height.max(1)))
}

/// Parses the container. The `ktx2` crate bounds-checks every section and level, but unwraps a
/// basic descriptor's texel block dimensions plus one, which overflows for 255: checked here first.
fn open(bytes: &[u8]) -> Result<ktx2::Reader<&[u8]>, String> {
    if !bytes.starts_with(MAGIC) {
        return Err("does not start with the KTX2 identifier (it is declared image/ktx2 but is not a KTX2 file); fix the image's mimeType or give it a KTX2 file".into());
    }
    check_descriptor_blocks(bytes)?;
    ktx2::Reader::new(bytes).map_err(|e| format!("is a damaged KTX2 file ({e}){REENCODE}"))
}

/// Walks the data format descriptor's blocks (the same walk as `ktx2`'s, on bounds-checked
/// slices) and refuses a basic block whose texel block dimension byte is 255 (a 256-texel block:
/// no format has one).
fn check_descriptor_blocks(bytes: &[u8]) -> Result<(), String> {
    let u32_at = |at: usize| -> Option<u32> {
        Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?))
    };
    let damaged = || format!("is a damaged KTX2 file (unexpected end of buffer){REENCODE}");
    let (Some(offset), Some(length)) = (u32_at(48), u32_at(52)) else {
        return Err(damaged());
    };
    let end = (offset as usize).saturating_add(length as usize);
    // The descriptor starts with its own total length (4 bytes), then the blocks.
    let Some(mut blocks) = bytes.get((offset as usize).saturating_add(4)..end) else {
        // `ktx2` reports this one itself.
        return Ok(());
    };
    while blocks.len() >= 8 {
        let word = u32::from_le_bytes([blocks[0], blocks[1], blocks[2], blocks[3]]);
        let version = u16::from_le_bytes([blocks[4], blocks[5]]);
        let size = usize::from(u16::from_le_bytes([blocks[6], blocks[7]]));
        let basic = word == 0 && version == 2;
        if basic {
            if let Some(dims) = blocks.get(12..16) {
                if dims.contains(&255) {
                    return Err(format!(
                        "is a damaged KTX2 file (its data format descriptor gives a texel block dimension of 256){REENCODE}"
                    ));
                }
            }
        }
        if size < 8 || size > blocks.len() {
            break; // `ktx2` reports it
        }
        blocks = &blocks[size..];
    }
    Ok(())
}

/// Decodes level 0 of a KTX2 file. `Err` is the reason, phrased to follow "… which comes from
/// FILE and", with the fix.
pub(super) fn decode(bytes: &[u8]) -> Result<Rgba8, String> {
    let reader = open(bytes)?;
    let header = reader.header();
    let width = header.pixel_width;
    if header.pixel_height == 0 {
        return Err(format!(
            "is a one-dimensional KTX2 texture ({width} texels wide, no height); glTF textures are 2D: write it as a 2D image"
        ));
    }
    let height = header.pixel_height;
    let max = super::resources::MAX_TEXTURE_SIZE;
    if width > max || height > max {
        // The caller refuses these first (with the limit and the fix); checked again here since
        // the sizes below are computed from them.
        return Err(format!(
            "is {width}x{height} pixels; textures must be between 1 and {max} pixels on each side: scale the image down"
        ));
    }
    if header.pixel_depth > 1 {
        return Err(format!(
            "is a 3D KTX2 texture ({width}x{height}x{}); glTF textures are 2D: write it as a 2D image",
            header.pixel_depth
        ));
    }
    if header.face_count != 1 {
        return Err(format!(
            "is a KTX2 cube map ({} faces); glTF textures are 2D: write it as a 2D image",
            header.face_count
        ));
    }
    if header.layer_count > 1 {
        return Err(format!(
            "is a KTX2 texture array ({} layers); glTF textures are single 2D images: write one layer",
            header.layer_count
        ));
    }
    let Some(level) = reader.levels().next() else {
        return Err("is a KTX2 file with no image data".into());
    };

    // What level 0 must hold once supercompression is undone, and how to turn it into RGBA8.
    enum Kind {
        Etc1s,
        Uastc { has_alpha: bool },
        Plain { channels: usize, bgr: bool },
    }
    let dfd = reader.basic_dfd();
    let model = dfd.and_then(|d| d.color_model);
    let kind = match header.format {
        None if header.supercompression_scheme == Some(SupercompressionScheme::BasisLZ)
            || model == Some(ColorModel::ETC1S) =>
        {
            if header.supercompression_scheme != Some(SupercompressionScheme::BasisLZ)
                || model != Some(ColorModel::ETC1S)
            {
                return Err(format!(
                    "is a KTX2 texture whose {} (ETC1S data must be BasisLZ-supercompressed and BasisLZ must hold ETC1S); the file is damaged: re-encode it",
                    if model == Some(ColorModel::ETC1S) {
                        "data format descriptor says ETC1S but whose supercompression is not BasisLZ"
                    } else {
                        "supercompression is BasisLZ but whose data format descriptor is not ETC1S"
                    }
                ));
            }
            Kind::Etc1s
        }
        None if model == Some(ColorModel::UASTC) => {
            // UASTC's descriptor has one sample, whose channel id says what the blocks hold:
            // RGB 0, RGBA 3, RRR 4, RRRG 5, RG 6 (KTX2 specification, section 3.10.2).
            let has_alpha = dfd
                .and_then(|d| d.sample_information.first())
                .is_some_and(|s| matches!(s.channel_type, 3 | 5));
            Kind::Uastc { has_alpha }
        }
        None => {
            return Err(format!(
                "is a KTX2 texture with vkFormat UNDEFINED and a {} data format descriptor, which weft cannot read; only UASTC is read among the universal formats: re-encode it as UASTC or use PNG",
                match model {
                    Some(m) => format!("{m:?}"),
                    None => "missing".to_string(),
                }
            ))
        }
        Some(f) => {
            let (channels, bgr) = match f {
                Format::R8_UNORM | Format::R8_SRGB => (1, false),
                Format::R8G8_UNORM | Format::R8G8_SRGB => (2, false),
                Format::R8G8B8_UNORM | Format::R8G8B8_SRGB => (3, false),
                Format::B8G8R8_UNORM | Format::B8G8R8_SRGB => (3, true),
                Format::R8G8B8A8_UNORM | Format::R8G8B8A8_SRGB => (4, false),
                Format::B8G8R8A8_UNORM | Format::B8G8R8A8_SRGB => (4, true),
                other => {
                    return Err(format!(
                        "is a KTX2 texture in vkFormat {other:?}, which weft does not read (it reads UASTC and 8-bit UNORM/SRGB R, RG, RGB and RGBA); re-encode it as UASTC or as R8G8B8A8, or use PNG"
                    ))
                }
            };
            Kind::Plain { channels, bgr }
        }
    };

    let pixels = u64::from(width) * u64::from(height);
    let (blocks_x, blocks_y) = (width.div_ceil(4), height.div_ceil(4));
    let expected = match kind {
        // BasisLZ levels hold Huffman-coded slices of no fixed length.
        Kind::Etc1s => 0,
        Kind::Uastc { .. } => u64::from(blocks_x) * u64::from(blocks_y) * 16,
        Kind::Plain { channels, .. } => pixels * channels as u64,
    };
    let data = match kind {
        Kind::Etc1s => std::borrow::Cow::Borrowed(level.data),
        _ => unsupercompress(&header, &level, 0, expected)?,
    };

    // The file's own mip chain as BC7, for devices that sample BC7 (the renderer's choice): only
    // when the file carries the full chain (a device cannot build BC7 mips, and a texture without
    // them would alias where weft's RGBA8 path filters) and its rows go down (BC7 blocks cannot be
    // flipped without re-encoding).
    let up = reader
        .key_value_data()
        .find(|(key, _)| *key == "KTXorientation")
        .is_some_and(|(_, value)| value.get(1) == Some(&b'u'));
    let full_chain = header.level_count == 32 - width.max(height).leading_zeros();
    let want_bc7 = full_chain && !up;
    let mut bc7 = None;

    let mut rgba8 = match kind {
        Kind::Etc1s => {
            let levels: Vec<&[u8]> = if want_bc7 {
                reader.levels().map(|l| l.data).collect()
            } else {
                vec![&data]
            };
            let basis = etc1s_as_basis(
                reader.supercompression_global_data(),
                &levels,
                header.level_count.max(1),
                width,
                height,
            )?;
            let mut transcoder = basis_universal::Transcoder::new();
            transcoder.prepare_transcoding(&basis).map_err(|()| {
                "is a KTX2 ETC1S texture whose codebooks or Huffman tables the Basis Universal transcoder rejected: the file is damaged; re-encode it".to_string()
            })?;
            if want_bc7 {
                bc7 = Some(
                    (0..header.level_count)
                        .map(|level| {
                            etc1s_transcode(
                                &transcoder,
                                &basis,
                                level,
                                basis_universal::TranscoderTextureFormat::BC7_RGBA,
                                bc7_bytes(width, height, level),
                            )
                        })
                        .collect::<Result<Vec<_>, _>>()?,
                );
            }
            etc1s_transcode(
                &transcoder,
                &basis,
                0,
                basis_universal::TranscoderTextureFormat::RGBA32,
                pixels * 4,
            )?
        }
        Kind::Uastc { has_alpha } => {
            // basis-universal 0.3.1 sizes the RGBA32 output, and sets its row pitch, as
            // ceil(original_width / 4) pixels (it divides by the 4-texel block width even for an
            // uncompressed format), and the C++ transcoder then writes rows of that pitch: with
            // the true width the buffer is a quarter of the image and the transcoder writes past
            // it (heap corruption on the lamp's 2048 x 2048 textures). The transcoder uses the
            // width for nothing else once it is given a pitch (basisu_transcoder.cpp,
            // basisu_lowlevel_uastc_transcoder::transcode_slice), so four times the width gives a
            // pitch and a buffer of exactly `width` pixels, and clipping of the last block column
            // at `width`. Should the binding be fixed, the output is four times too large and the
            // length check below refuses it instead of reading it wrong.
            let transcoder = basis_universal::LowLevelUastcTranscoder::new();
            let out = transcoder
                .transcode_slice(
                    &data,
                    basis_universal::SliceParametersUastc {
                        num_blocks_x: blocks_x,
                        num_blocks_y: blocks_y,
                        has_alpha,
                        original_width: width * 4,
                        original_height: height,
                    },
                    basis_universal::DecodeFlags::HIGH_QUALITY,
                    basis_universal::TranscoderBlockFormat::RGBA32,
                )
                .map_err(|e| {
                    format!("is a KTX2 UASTC texture that the Basis Universal transcoder rejected ({e:?}): the file is damaged; re-encode it")
                })?;
            if want_bc7 {
                bc7 = Some(uastc_bc7_levels(&reader, &header, has_alpha)?);
            }
            if out.len() as u64 != pixels * 4 {
                return Err(format!(
                    "is a KTX2 UASTC texture whose transcoded level 0 is {} bytes instead of {} (the basis-universal binding has changed how it sizes its output: weft must be updated for it)",
                    out.len(),
                    pixels * 4
                ));
            }
            out
        }
        Kind::Plain { channels, bgr } => {
            let mut out = Vec::with_capacity(pixels as usize * 4);
            for px in data.chunks_exact(channels) {
                let texel = match (channels, bgr) {
                    (1, _) => [px[0], 0, 0, 255],
                    (2, _) => [px[0], px[1], 0, 255],
                    (3, false) => [px[0], px[1], px[2], 255],
                    (3, true) => [px[2], px[1], px[0], 255],
                    (_, false) => [px[0], px[1], px[2], px[3]],
                    (_, true) => [px[2], px[1], px[0], px[3]],
                };
                out.extend_from_slice(&texel);
            }
            out
        }
    };

    // KTXorientation "rd" (rows go down, the default) is glTF's; "ru" is flipped here.
    if up {
        let row = width as usize * 4;
        let rows: Vec<&[u8]> = rgba8.chunks_exact(row).rev().collect();
        rgba8 = rows.concat();
    }
    Ok(Rgba8 {
        width,
        height,
        rgba8,
        bc7,
    })
}

/// Bytes of mip `level` of a `width` x `height` BC7 image: 16 per 4 x 4 block.
fn bc7_bytes(width: u32, height: u32, level: u32) -> u64 {
    let (w, h) = ((width >> level).max(1), (height >> level).max(1));
    u64::from(w.div_ceil(4)) * u64::from(h.div_ceil(4)) * 16
}

/// Every level of a UASTC file transcoded to BC7 (UASTC is designed to map onto BC7 nearly
/// losslessly).
fn uastc_bc7_levels(
    reader: &ktx2::Reader<&[u8]>,
    header: &ktx2::Header,
    has_alpha: bool,
) -> Result<Vec<Vec<u8>>, String> {
    let transcoder = basis_universal::LowLevelUastcTranscoder::new();
    reader
        .levels()
        .enumerate()
        .map(|(level, data)| {
            let level = level as u32;
            let (w, h) = (
                (header.pixel_width >> level).max(1),
                (header.pixel_height >> level).max(1),
            );
            let expected = bc7_bytes(header.pixel_width, header.pixel_height, level);
            // A UASTC block is 16 bytes, as a BC7 block is.
            let blocks = unsupercompress(header, &data, level, expected)?;
            let out = transcoder
                .transcode_slice(
                    &blocks,
                    basis_universal::SliceParametersUastc {
                        num_blocks_x: w.div_ceil(4),
                        num_blocks_y: h.div_ceil(4),
                        has_alpha,
                        original_width: w,
                        original_height: h,
                    },
                    basis_universal::DecodeFlags::HIGH_QUALITY,
                    basis_universal::TranscoderBlockFormat::BC7,
                )
                .map_err(|e| {
                    format!("is a KTX2 UASTC texture whose mip level {level} the Basis Universal transcoder rejected ({e:?}): the file is damaged; re-encode it")
                })?;
            if out.len() as u64 != expected {
                return Err(format!(
                    "is a KTX2 UASTC texture whose mip level {level} transcodes to {} bytes of BC7 instead of {expected} (the basis-universal binding has changed: weft must be updated for it)",
                    out.len()
                ));
            }
            Ok(out)
        })
        .collect()
}

/// Level `index`'s bytes with its supercompression undone, exactly `expected` bytes long.
fn unsupercompress<'a>(
    header: &ktx2::Header,
    level: &ktx2::Level<'a>,
    index: u32,
    expected: u64,
) -> Result<std::borrow::Cow<'a, [u8]>, String> {
    let scheme = header.supercompression_scheme;
    if scheme.is_some() && level.uncompressed_byte_length != expected {
        return Err(format!(
            "is a KTX2 texture whose level {index} declares {} uncompressed bytes where its {}x{} format needs {expected}; the file is damaged: re-encode it",
            level.uncompressed_byte_length, header.pixel_width, header.pixel_height
        ));
    }
    let data = match scheme {
        None => std::borrow::Cow::Borrowed(level.data),
        Some(SupercompressionScheme::Zstandard) => {
            let mut out = Vec::with_capacity(expected as usize);
            ruzstd::decoding::FrameDecoder::new()
                .decode_all_to_vec(level.data, &mut out)
                .map_err(|e| {
                    format!("is a KTX2 texture whose Zstandard-compressed level {index} does not decode ({e}); the file is damaged: re-encode it")
                })?;
            std::borrow::Cow::Owned(out)
        }
        Some(SupercompressionScheme::ZLIB) => {
            let out = miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(
                level.data,
                expected as usize,
            )
            .map_err(|e| {
                format!("is a KTX2 texture whose ZLIB-compressed level {index} does not decode ({:?}); the file is damaged: re-encode it", e.status)
            })?;
            std::borrow::Cow::Owned(out)
        }
        Some(other) => {
            return Err(format!(
                "is a KTX2 texture with supercompression scheme {other:?}, which weft does not read (it reads none, Zstandard and ZLIB); re-encode it with Zstandard"
            ))
        }
    };
    if data.len() as u64 != expected {
        return Err(format!(
            "is a KTX2 texture whose level {index} holds {} bytes where its {}x{} format needs {expected}; the file is damaged or truncated: re-encode it",
            data.len(),
            header.pixel_width,
            header.pixel_height
        ));
    }
    Ok(data)
}

/// The BasisLZ global data of a KTX2 file (KTX2 specification, section 3.12: the ETC1S
/// codebooks and Huffman tables shared by every image, and one descriptor per image) with the
/// slices of `levels` (level 0 first; the first `levels.len()` of the file's `level_count`),
/// repacked as the equivalent `.basis` file (Binomial's own container, whose layout is
/// `basis_file_header` and `basis_slice_desc` in basisu_file_headers.h): the `basis-universal`
/// crate exposes Binomial's ETC1S transcoder only through that container. The codebooks, tables
/// and slices are copied byte for byte; only the headers are written here.
fn etc1s_as_basis(
    global: &[u8],
    levels: &[&[u8]],
    level_count: u32,
    width: u32,
    height: u32,
) -> Result<Vec<u8>, String> {
    let damaged = |what: &str| {
        format!("is a KTX2 ETC1S texture whose BasisLZ {what}; the file is damaged: re-encode it")
    };
    let u16_at = |at: usize| {
        global
            .get(at..at + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
    };
    let u32_at = |at: usize| {
        global
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    const HEADER: usize = 20;
    const IMAGE_DESC: usize = 20;
    let (
        Some(endpoint_count),
        Some(selector_count),
        Some(endpoints_len),
        Some(selectors_len),
        Some(tables_len),
        Some(extended_len),
    ) = (
        u16_at(0),
        u16_at(2),
        u32_at(4),
        u32_at(8),
        u32_at(12),
        u32_at(16),
    )
    else {
        return Err(damaged("global data is shorter than its 20-byte header"));
    };
    if endpoint_count == 0
        || selector_count == 0
        || endpoints_len == 0
        || selectors_len == 0
        || tables_len == 0
    {
        return Err(damaged(
            "global data has an empty endpoint or selector codebook or no Huffman tables",
        ));
    }
    // One descriptor per image: layers x faces x levels, and weft has refused all but one layer
    // and one face; level 0's comes first.
    let codebooks = HEADER + IMAGE_DESC * level_count as usize;
    let needed = codebooks as u64
        + u64::from(endpoints_len)
        + u64::from(selectors_len)
        + u64::from(tables_len)
        + u64::from(extended_len);
    if (global.len() as u64) < needed {
        return Err(damaged(&format!(
            "global data is {} bytes where its header and {level_count} image descriptors need {needed}",
            global.len()
        )));
    }
    // Each level's colour slice and, when level 0 has one, alpha slice.
    let alpha = u32_at(HEADER + 16).is_some_and(|length| length > 0);
    let mut slices: Vec<(u32, bool, &[u8])> = Vec::new();
    for (level, data) in levels.iter().enumerate() {
        let desc =
            |field: usize| u32_at(HEADER + IMAGE_DESC * level + 4 * field).unwrap_or(0) as usize;
        let slice = |offset: usize, length: usize, what: &str| {
            data.get(offset..offset.saturating_add(length)).ok_or_else(|| {
                damaged(&format!(
                    "{what} slice of level {level} ({length} bytes at {offset}) lies outside the level's {} bytes",
                    data.len()
                ))
            })
        };
        let (rgb_offset, rgb_length, alpha_offset, alpha_length) =
            (desc(1), desc(2), desc(3), desc(4));
        if rgb_length == 0 {
            return Err(damaged(&format!("level {level} has an empty colour slice")));
        }
        slices.push((
            level as u32,
            false,
            slice(rgb_offset, rgb_length, "colour")?,
        ));
        if alpha {
            if alpha_length == 0 {
                return Err(damaged(&format!(
                    "level {level} has no alpha slice where level 0 has one"
                )));
            }
            slices.push((
                level as u32,
                true,
                slice(alpha_offset, alpha_length, "alpha")?,
            ));
        }
    }
    let endpoints = &global[codebooks..codebooks + endpoints_len as usize];
    let selectors_at = codebooks + endpoints_len as usize;
    let selectors = &global[selectors_at..selectors_at + selectors_len as usize];
    let tables_at = selectors_at + selectors_len as usize;
    let tables = &global[tables_at..tables_at + tables_len as usize];

    // basis_file_header: 77 packed bytes, little-endian fields of the widths below.
    const BASIS_HEADER: usize = 77;
    const SLICE_DESC: usize = 23;
    let endpoints_at = BASIS_HEADER + SLICE_DESC * slices.len();
    let selectors_at = endpoints_at + endpoints.len();
    let tables_at = selectors_at + selectors.len();
    let slices_at = tables_at + tables.len();
    let total = slices_at + slices.iter().map(|s| s.2.len()).sum::<usize>();
    if u32::try_from(total).is_err() {
        return Err(damaged("slices and codebooks exceed 4 GiB"));
    }
    let mut out = Vec::with_capacity(total);
    let put = |out: &mut Vec<u8>, value: u64, bytes: usize| {
        out.extend((0..bytes).map(|i| (value >> (8 * i)) as u8));
    };
    const ETC1S: u64 = 1;
    const HAS_ALPHA_SLICES: u64 = 4;
    put(&mut out, u64::from(u16::from_le_bytes(*b"sB")), 2); // m_sig: ('B' << 8) | 's'
    put(&mut out, 0x13, 2); // m_ver: the version the transcoder reads
    put(&mut out, BASIS_HEADER as u64, 2); // m_header_size
    put(&mut out, 0, 2); // m_header_crc16, filled in below
    put(&mut out, (total - BASIS_HEADER) as u64, 4); // m_data_size
    put(&mut out, 0, 2); // m_data_crc16, filled in below
    put(&mut out, slices.len() as u64, 3); // m_total_slices
    put(&mut out, 1, 3); // m_total_images
    put(&mut out, 0, 1); // m_tex_format: ETC1S
    put(
        &mut out,
        ETC1S | if alpha { HAS_ALPHA_SLICES } else { 0 },
        2,
    );
    put(&mut out, 0, 1); // m_tex_type: 2D
    put(&mut out, 0, 3); // m_us_per_frame
    put(&mut out, 0, 4 + 4 + 4); // m_reserved, m_userdata0, m_userdata1
    put(&mut out, u64::from(endpoint_count), 2);
    put(&mut out, endpoints_at as u64, 4);
    put(&mut out, endpoints.len() as u64, 3);
    put(&mut out, u64::from(selector_count), 2);
    put(&mut out, selectors_at as u64, 4);
    put(&mut out, selectors.len() as u64, 3);
    put(&mut out, tables_at as u64, 4);
    put(&mut out, tables.len() as u64, 4);
    put(&mut out, BASIS_HEADER as u64, 4); // m_slice_desc_file_ofs
    put(&mut out, 0, 4 + 4); // m_extended_file_ofs, m_extended_file_size
    debug_assert_eq!(out.len(), BASIS_HEADER);
    let mut at = slices_at;
    for &(level, is_alpha, data) in &slices {
        let (w, h) = ((width >> level).max(1), (height >> level).max(1));
        put(&mut out, 0, 3); // m_image_index
        put(&mut out, u64::from(level), 1); // m_level_index
        put(&mut out, u64::from(is_alpha), 1); // m_flags: cSliceDescFlagsHasAlpha
        put(&mut out, u64::from(w), 2);
        put(&mut out, u64::from(h), 2);
        put(&mut out, u64::from(w.div_ceil(4)), 2);
        put(&mut out, u64::from(h.div_ceil(4)), 2);
        put(&mut out, at as u64, 4);
        put(&mut out, data.len() as u64, 4);
        put(&mut out, u64::from(crc16(data)), 2);
        at += data.len();
    }
    for part in [endpoints, selectors, tables] {
        out.extend_from_slice(part);
    }
    for (_, _, data) in &slices {
        out.extend_from_slice(data);
    }
    let data_crc = crc16(&out[BASIS_HEADER..]);
    out[12..14].copy_from_slice(&data_crc.to_le_bytes());
    let header_crc = crc16(&out[8..BASIS_HEADER]);
    out[6..8].copy_from_slice(&header_crc.to_le_bytes());
    Ok(out)
}

/// Binomial's CRC-16 of the `.basis` container (`basist::crc16`, CCITT polynomial, inverted).
fn crc16(bytes: &[u8]) -> u16 {
    let mut crc = !0u16;
    for &b in bytes {
        let q = u16::from(b) ^ (crc >> 8);
        let k = (q >> 4) ^ q;
        crc = (crc << 8) ^ k ^ (k << 5) ^ (k << 12);
    }
    !crc
}

/// Mip `level` of a `.basis` ETC1S file (from `etc1s_as_basis`, prepared in `transcoder`) in
/// `format`, which must come out `expected` bytes long.
fn etc1s_transcode(
    transcoder: &basis_universal::Transcoder,
    basis: &[u8],
    level: u32,
    format: basis_universal::TranscoderTextureFormat,
    expected: u64,
) -> Result<Vec<u8>, String> {
    let out = transcoder
        .transcode_image_level(
            basis,
            format,
            basis_universal::TranscodeParameters {
                level_index: level,
                ..Default::default()
            },
        )
        .map_err(|e| {
            format!("is a KTX2 ETC1S texture whose level {level} the Basis Universal transcoder rejected ({e:?}): the file is damaged; re-encode it")
        })?;
    if out.len() as u64 != expected {
        return Err(format!(
            "is a KTX2 ETC1S texture whose level {level} transcodes to {} bytes of {format:?} instead of {expected} (the basis-universal binding has changed how it sizes its output: weft must be updated for it)",
            out.len()
        ));
    }
    Ok(out)
}
