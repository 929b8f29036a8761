//! Bounds-checked reading of glTF accessors (plain, strided, normalised and sparse).
//!
//! The `gltf` crate validates the JSON (indices exist, enums are known) but not that an
//! accessor's bytes fit in its buffer view and buffer; this reader checks every range before it
//! touches a byte or allocates, so a lying file gives an error instead of a panic.

use gltf::accessor::{DataType, Dimensions};

use super::types::{ImportErrorKind, MAX_VERTICES};

/// Loaded buffers, indexed like the document's buffers (a GLB's BIN chunk is borrowed).
pub(crate) struct Buffers<'a>(pub Vec<std::borrow::Cow<'a, [u8]>>);

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

fn read_component(bytes: &[u8], t: DataType, normalized: bool) -> f32 {
    // Callers guarantee `bytes` holds one component.
    match t {
        DataType::F32 => f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
        DataType::U32 => {
            let v = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as f32;
            if normalized { v / u32::MAX as f32 } else { v }
        }
        DataType::U16 => {
            let v = f32::from(u16::from_le_bytes([bytes[0], bytes[1]]));
            if normalized { v / 65535.0 } else { v }
        }
        DataType::I16 => {
            let v = f32::from(i16::from_le_bytes([bytes[0], bytes[1]]));
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        DataType::U8 => {
            let v = f32::from(bytes[0]);
            if normalized { v / 255.0 } else { v }
        }
        DataType::I8 => {
            let v = f32::from(bytes[0] as i8);
            if normalized { (v / 127.0).max(-1.0) } else { v }
        }
    }
}

/// The bytes of a buffer view, checked against its buffer.
pub(crate) fn view_bytes<'a>(
    buffers: &'a Buffers<'_>,
    view: &gltf::buffer::View<'_>,
) -> Result<&'a [u8], String> {
    let buffer = buffers
        .0
        .get(view.buffer().index())
        .ok_or("its buffer was not loaded")?;
    let view_end = view
        .offset()
        .checked_add(view.length())
        .ok_or("buffer view range overflows")?;
    if view_end > buffer.len() {
        return Err(format!(
            "buffer view {} ends at byte {view_end}, past the end of buffer {} ({} bytes)",
            view.index(),
            view.buffer().index(),
            buffer.len()
        ));
    }
    Ok(&buffer[view.offset()..view_end])
}

/// The byte slice `[offset, offset + element_size + stride·(count−1))` of a buffer view, checked.
fn view_slice<'a>(
    buffers: &'a Buffers<'_>,
    view: &gltf::buffer::View<'_>,
    offset: usize,
    count: usize,
    element_size: usize,
) -> Result<(&'a [u8], usize), String> {
    let stride = view.stride().unwrap_or(element_size);
    if stride < element_size {
        return Err(format!(
            "byteStride {stride} is smaller than one element ({element_size} bytes)"
        ));
    }
    let view_bytes = view_bytes(buffers, view)?;
    if count == 0 {
        return Ok((&view_bytes[..0], stride));
    }
    let needed = (count - 1)
        .checked_mul(stride)
        .and_then(|n| n.checked_add(element_size))
        .and_then(|n| n.checked_add(offset))
        .ok_or("size overflows")?;
    if needed > view_bytes.len() {
        return Err(format!(
            "{count} elements need {needed} bytes from offset {offset}, but buffer view {} has {}",
            view.index(),
            view_bytes.len()
        ));
    }
    Ok((&view_bytes[offset..needed], stride))
}

/// Reads an accessor as `count × components` floats (normalised integers mapped to [0,1] or
/// [−1,1]), applying sparse substitution. Checks that the element type is `expected` if given.
pub(crate) fn read_floats(
    buffers: &Buffers<'_>,
    accessor: &gltf::Accessor<'_>,
    expected: Option<Dimensions>,
) -> Result<Vec<f32>, ImportErrorKind> {
    let fail = |problem: String| ImportErrorKind::BadAccessor {
        accessor: accessor.index(),
        role: String::new(),
        problem,
    };
    let dims = accessor.dimensions();
    if let Some(expected) = expected
        && dims != expected
    {
        return Err(fail(format!("type is {dims:?}, expected {expected:?}")));
    }
    let count = accessor.count();
    if count > MAX_VERTICES {
        return Err(ImportErrorKind::TooLarge(format!(
            "accessor {} declares {count} elements (at most {MAX_VERTICES})",
            accessor.index()
        )));
    }
    let data_type = accessor.data_type();
    let components = component_count(dims);
    let csize = component_size(data_type);
    if matches!(dims, Dimensions::Mat2 | Dimensions::Mat3) && csize < 4 {
        return Err(ImportErrorKind::Unsupported(format!(
            "accessor {}: {dims:?} with {data_type:?} components (column padding)",
            accessor.index()
        )));
    }
    let element_size = components * csize;
    let mut out = vec![0.0f32; count * components];
    if let Some(view) = accessor.view() {
        let (bytes, stride) =
            view_slice(buffers, &view, accessor.offset(), count, element_size).map_err(fail)?;
        if data_type == DataType::F32 && stride == element_size {
            // The common case (tightly packed floats) as one straight pass.
            for (slot, b) in out.iter_mut().zip(bytes.chunks_exact(4)) {
                *slot = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            }
        } else {
            for (i, chunk) in out.chunks_exact_mut(components).enumerate() {
                let start = i * stride;
                for (c, slot) in chunk.iter_mut().enumerate() {
                    let at = start + c * csize;
                    *slot =
                        read_component(&bytes[at..at + csize], data_type, accessor.normalized());
                }
            }
        }
    }
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        if n > count {
            return Err(fail(format!(
                "sparse count {n} exceeds the accessor count {count}"
            )));
        }
        let index_type = match sparse.indices().index_type() {
            gltf::accessor::sparse::IndexType::U8 => DataType::U8,
            gltf::accessor::sparse::IndexType::U16 => DataType::U16,
            gltf::accessor::sparse::IndexType::U32 => DataType::U32,
        };
        let isize = component_size(index_type);
        // Sparse data is tightly packed regardless of any byteStride on the view.
        let packed = |what: &str, view: &gltf::buffer::View<'_>, offset: usize, size: usize| {
            view_slice(buffers, view, offset, n, size)
                .map(|(bytes, _)| bytes)
                .map_err(|p| fail(format!("sparse {what}: {p}")))
        };
        let indices = sparse.indices();
        let values = sparse.values();
        let index_bytes = packed("indices", &indices.view(), indices.offset(), isize)?;
        let value_bytes = packed("values", &values.view(), values.offset(), element_size)?;
        if index_bytes.len() < n * isize || value_bytes.len() < n * element_size {
            return Err(fail("sparse data is shorter than its count".into()));
        }
        let mut previous: Option<usize> = None;
        for k in 0..n {
            let index = read_component(&index_bytes[k * isize..(k + 1) * isize], index_type, false)
                as usize;
            if index >= count {
                return Err(fail(format!(
                    "sparse index {index} is past the accessor count {count}"
                )));
            }
            if previous.is_some_and(|p| index <= p) {
                return Err(fail(format!(
                    "sparse indices are not strictly increasing at entry {k}"
                )));
            }
            previous = Some(index);
            for c in 0..components {
                let at = k * element_size + c * csize;
                out[index * components + c] = read_component(
                    &value_bytes[at..at + csize],
                    data_type,
                    accessor.normalized(),
                );
            }
        }
    }
    Ok(out)
}

/// Reads an index-like accessor (unsigned integers only) as u32s.
pub(crate) fn read_indices(
    buffers: &Buffers<'_>,
    accessor: &gltf::Accessor<'_>,
) -> Result<Vec<u32>, ImportErrorKind> {
    if !matches!(
        accessor.data_type(),
        DataType::U8 | DataType::U16 | DataType::U32
    ) || accessor.normalized()
    {
        return Err(ImportErrorKind::BadAccessor {
            accessor: accessor.index(),
            role: String::new(),
            problem: format!(
                "indices must be unsigned integers, found {:?}",
                accessor.data_type()
            ),
        });
    }
    // u32 values above 2^24 are not exact in f32, so read integers directly.
    let count = accessor.count();
    if count > super::types::MAX_TRIANGLES * 3 {
        return Err(ImportErrorKind::TooLarge(format!(
            "accessor {} declares {count} indices",
            accessor.index()
        )));
    }
    if accessor.sparse().is_some() || accessor.view().is_none() {
        let floats = read_floats(buffers, accessor, None)?;
        return Ok(floats.into_iter().map(|f| f as u32).collect());
    }
    let csize = component_size(accessor.data_type());
    let components = component_count(accessor.dimensions());
    let element_size = csize * components;
    let Some(view) = accessor.view() else {
        return Ok(Vec::new());
    };
    let (bytes, stride) = view_slice(buffers, &view, accessor.offset(), count, element_size)
        .map_err(|problem| ImportErrorKind::BadAccessor {
            accessor: accessor.index(),
            role: String::new(),
            problem,
        })?;
    let mut out = Vec::with_capacity(count * components);
    for i in 0..count {
        for c in 0..components {
            let at = i * stride + c * csize;
            let b = &bytes[at..at + csize];
            out.push(match csize {
                1 => u32::from(b[0]),
                2 => u32::from(u16::from_le_bytes([b[0], b[1]])),
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            });
        }
    }
    Ok(out)
}
