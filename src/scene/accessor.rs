//! Reading glTF accessors into plain vectors.
//!
//! The `gltf` crate's own reader trusts offsets, strides and counts (it slices and asserts), so a
//! truncated or hand-edited file could panic there. This reader checks every byte range against
//! the buffers first and turns each problem into an error that names the accessor.

use gltf::accessor::{sparse::IndexType, DataType, Dimensions};

use crate::Error;

/// Where an accessor is used, for messages: e.g. "mesh 'cloth' primitive 0, attribute NORMAL".
pub(super) struct Use<'a> {
    pub source: &'a str,
    pub what: &'a str,
}

impl Use<'_> {
    fn error(&self, accessor: usize, problem: impl std::fmt::Display) -> Error {
        Error::input(format!(
            "{}: {} reads accessor {accessor}, which {problem}; the file is damaged or was written by a broken exporter: re-export it (the Khronos glTF Validator pinpoints such problems)",
            self.source, self.what
        ))
    }
}

fn component_size(t: DataType) -> usize {
    match t {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

fn component_count(d: Dimensions) -> usize {
    match d {
        Dimensions::Scalar => 1,
        Dimensions::Vec2 => 2,
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 | Dimensions::Mat2 => 4,
        Dimensions::Mat3 => 9,
        Dimensions::Mat4 => 16,
    }
}

fn dimensions_name(d: Dimensions) -> &'static str {
    match d {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

/// Decodes one component as f32, applying glTF's normalisation rules for integer types.
fn decode_f32(t: DataType, normalized: bool, b: &[u8]) -> f32 {
    match (t, normalized) {
        (DataType::F32, _) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        (DataType::I8, false) => b[0] as i8 as f32,
        (DataType::U8, false) => b[0] as f32,
        (DataType::I16, false) => i16::from_le_bytes([b[0], b[1]]) as f32,
        (DataType::U16, false) => u16::from_le_bytes([b[0], b[1]]) as f32,
        (DataType::U32, false) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        (DataType::I8, true) => (b[0] as i8 as f32 / 127.0).max(-1.0),
        (DataType::U8, true) => b[0] as f32 / 255.0,
        (DataType::I16, true) => (i16::from_le_bytes([b[0], b[1]]) as f32 / 32767.0).max(-1.0),
        (DataType::U16, true) => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
        (DataType::U32, true) => {
            (u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64 / u32::MAX as f64) as f32
        }
    }
}

fn decode_u32(t: DataType, b: &[u8]) -> u32 {
    match t {
        DataType::U8 => b[0] as u32,
        DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
        // Only unsigned types reach here (checked by the caller).
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// `count` elements of `elem` bytes, `stride` apart, starting `offset` bytes into a buffer view.
struct Span {
    offset: usize,
    count: usize,
    elem: usize,
    stride: usize,
}

/// The bytes of `span` in buffer view `view`, checked against the view and its buffer.
fn strided_bytes<'b>(
    use_: &Use,
    accessor: usize,
    view: &gltf::buffer::View,
    span: Span,
    buffers: &'b [Vec<u8>],
) -> crate::Result<&'b [u8]> {
    let Span {
        offset,
        count,
        elem: elem_size,
        stride,
    } = span;
    let buffer = buffers.get(view.buffer().index()).ok_or_else(|| {
        use_.error(
            accessor,
            format_args!("uses buffer {} that was not loaded", view.buffer().index()),
        )
    })?;
    let view_end = view.offset().checked_add(view.length());
    let view_bytes = view_end.and_then(|end| buffer.get(view.offset()..end)).ok_or_else(|| {
        use_.error(
            accessor,
            format_args!(
                "uses buffer view {} (bytes {}..{} of buffer {}), but that buffer holds only {} bytes",
                view.index(),
                view.offset(),
                view.offset().saturating_add(view.length()),
                view.buffer().index(),
                buffer.len()
            ),
        )
    })?;
    if count == 0 {
        return Ok(&view_bytes[..0]);
    }
    let needed = stride
        .checked_mul(count - 1)
        .and_then(|n| n.checked_add(elem_size))
        .and_then(|n| n.checked_add(offset));
    match needed {
        Some(end) if end <= view_bytes.len() => Ok(&view_bytes[offset..end]),
        _ => Err(use_.error(
            accessor,
            format_args!(
                "needs {} element(s) of {elem_size} bytes every {stride} bytes from byte {offset} of buffer view {}, but the view is only {} bytes long",
                count,
                view.index(),
                view_bytes.len()
            ),
        )),
    }
}

/// Reads an accessor as `count * components` f32 values (integer types converted, normalised where
/// the accessor says so), after checking that it has dimensions `expect`.
pub(super) fn read_f32(
    acc: &gltf::Accessor,
    expect: Dimensions,
    buffers: &[Vec<u8>],
    use_: &Use,
) -> crate::Result<Vec<f32>> {
    read(
        acc,
        expect,
        buffers,
        use_,
        |t, b| decode_f32(t, acc.normalized(), b),
        0.0,
    )
}

/// Reads a scalar accessor of unsigned integers (vertex indices).
pub(super) fn read_u32(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    use_: &Use,
) -> crate::Result<Vec<u32>> {
    match acc.data_type() {
        DataType::U8 | DataType::U16 | DataType::U32 => {}
        other => {
            return Err(use_.error(
                acc.index(),
                format_args!(
                    "has component type {other:?}; indices must be unsigned byte, unsigned short or unsigned int"
                ),
            ))
        }
    }
    read(acc, Dimensions::Scalar, buffers, use_, decode_u32, 0)
}

fn read<T: Copy>(
    acc: &gltf::Accessor,
    expect: Dimensions,
    buffers: &[Vec<u8>],
    use_: &Use,
    decode: impl Fn(DataType, &[u8]) -> T,
    zero: T,
) -> crate::Result<Vec<T>> {
    let index = acc.index();
    if acc.dimensions() != expect {
        return Err(use_.error(
            index,
            format_args!(
                "has type {} where {} is required",
                dimensions_name(acc.dimensions()),
                dimensions_name(expect)
            ),
        ));
    }
    let n = component_count(expect);
    let csize = component_size(acc.data_type());
    let elem = n * csize;
    let count = acc.count();
    let total = count.checked_mul(n).ok_or_else(|| {
        use_.error(
            index,
            format_args!("claims {count} elements, more than any buffer can hold"),
        )
    })?;

    let mut out = Vec::new();
    match acc.view() {
        Some(view) => {
            let stride = view.stride().unwrap_or(elem);
            if stride < elem {
                return Err(use_.error(
                    index,
                    format_args!(
                        "has {elem}-byte elements but buffer view {} has a byte stride of only {stride}",
                        view.index()
                    ),
                ));
            }
            // Checked before allocating, so a bogus count cannot exhaust memory.
            let bytes = strided_bytes(
                use_,
                index,
                &view,
                Span {
                    offset: acc.offset(),
                    count,
                    elem,
                    stride,
                },
                buffers,
            )?;
            out.reserve_exact(total);
            for i in 0..count {
                let e = &bytes[i * stride..i * stride + elem];
                out.extend(e.chunks_exact(csize).map(|c| decode(acc.data_type(), c)));
            }
        }
        // No buffer view: zeros, then the sparse substitutions below. Nothing bounds the count
        // here, so cap it at something no real mesh reaches.
        None if total > 1 << 26 => {
            return Err(use_.error(
                index,
                format_args!("claims {count} elements without a buffer view"),
            ));
        }
        None => out.resize(total, zero),
    }

    if let Some(sparse) = acc.sparse() {
        let scount = sparse.count();
        let indices = sparse.indices();
        let isize = match indices.index_type() {
            IndexType::U8 => 1,
            IndexType::U16 => 2,
            IndexType::U32 => 4,
        };
        let itype = match indices.index_type() {
            IndexType::U8 => DataType::U8,
            IndexType::U16 => DataType::U16,
            IndexType::U32 => DataType::U32,
        };
        let ibytes = strided_bytes(
            use_,
            index,
            &indices.view(),
            Span {
                offset: indices.offset(),
                count: scount,
                elem: isize,
                stride: isize,
            },
            buffers,
        )?;
        let values = sparse.values();
        let vbytes = strided_bytes(
            use_,
            index,
            &values.view(),
            Span {
                offset: values.offset(),
                count: scount,
                elem,
                stride: elem,
            },
            buffers,
        )?;
        for (k, ib) in ibytes.chunks_exact(isize).enumerate() {
            let target = decode_u32(itype, ib) as usize;
            if target >= count {
                return Err(use_.error(
                    index,
                    format_args!("has a sparse substitution for element {target}, but it has only {count} elements"),
                ));
            }
            let e = &vbytes[k * elem..(k + 1) * elem];
            for (c, cb) in e.chunks_exact(csize).enumerate() {
                out[target * n + c] = decode(acc.data_type(), cb);
            }
        }
    }
    Ok(out)
}
