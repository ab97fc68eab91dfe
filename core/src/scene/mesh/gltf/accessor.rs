//! Reading glTF accessors: every index, type, count, offset, stride and byte range is checked
//! against the document and the buffers before a byte is read, and each refusal names the
//! JSON path of the value at fault.

use gltf::json::accessor::{Accessor, ComponentType, Type};
use gltf::json::validation::Checked;
use gltf::json::Root;

use crate::scene::asset::AssetError;

/// What a semantic may be stored as.
#[derive(Clone, Copy)]
pub(super) enum Want {
    /// POSITION and NORMAL: three floats.
    Vec3F32,
    /// TEXCOORD_0: two floats, or two normalized unsigned bytes or shorts.
    Vec2Uv,
    /// Indices: unsigned byte, short or int scalars, not normalized.
    Index,
}

impl Want {
    fn ty(self) -> Type {
        match self {
            Want::Vec3F32 => Type::Vec3,
            Want::Vec2Uv => Type::Vec2,
            Want::Index => Type::Scalar,
        }
    }

    fn allows(self, c: ComponentType, normalized: bool) -> bool {
        use ComponentType::*;
        match self {
            Want::Vec3F32 => c == F32,
            Want::Vec2Uv => c == F32 || (normalized && matches!(c, U8 | U16)),
            Want::Index => !normalized && matches!(c, U8 | U16 | U32),
        }
    }

    fn allowed(self) -> &'static str {
        match self {
            Want::Vec3F32 => "VEC3 of FLOAT (5126)",
            Want::Vec2Uv => "VEC2 of FLOAT (5126), or of normalized UNSIGNED_BYTE (5121) or UNSIGNED_SHORT (5123)",
            Want::Index => "SCALAR of UNSIGNED_BYTE (5121), UNSIGNED_SHORT (5123) or UNSIGNED_INT (5125), not normalized",
        }
    }
}

/// A checked accessor: where its elements are and how to decode them.
pub(super) struct Layout<'b> {
    /// The bytes of the view, from the accessor's first element on; `None` for an accessor
    /// without a buffer view (all zeros, as glTF defines).
    data: Option<&'b [u8]>,
    pub count: usize,
    stride: usize,
    component: ComponentType,
    components: usize,
}

/// Checks accessor `index` (named by `user`, the JSON path that refers to it) for use as
/// `want`, and returns its layout. `buffers` are the loaded buffers, each `byteLength` long.
pub(super) fn layout<'b>(
    root: &Root,
    buffers: &'b [Vec<u8>],
    index: usize,
    user: &str,
    want: Want,
) -> Result<Layout<'b>, AssetError> {
    let Some(a) = root.accessors.get(index) else {
        return Err(AssetError::gltf(
            user,
            format!(
                "refers to accessors[{index}], but the file has {} accessors",
                root.accessors.len()
            ),
        ));
    };
    let (component, components) = element_type(a, index, user, want)?;
    if a.sparse.is_some() {
        return Err(AssetError::gltf(
            format!("accessors[{index}].sparse"),
            "sparse accessors are not supported",
        ));
    }
    let count = element_count(a, index)?;
    let unplaced = Layout {
        data: None,
        count,
        stride: component.size() * components,
        component,
        components,
    };
    match a.buffer_view {
        None => Ok(unplaced),
        Some(view_index) => placed(root, buffers, a, index, view_index.value(), unplaced),
    }
}

/// The accessor's component type and components per element, checked to suit `want`.
fn element_type(
    a: &Accessor,
    index: usize,
    user: &str,
    want: Want,
) -> Result<(ComponentType, usize), AssetError> {
    let wrong = || {
        AssetError::gltf(
            format!("accessors[{index}]"),
            format!("used as {user}, which must be {}", want.allowed()),
        )
    };
    let (Checked::Valid(ty), Checked::Valid(c)) = (&a.type_, &a.component_type) else {
        return Err(wrong());
    };
    let component = c.0;
    if *ty != want.ty() || !want.allows(component, a.normalized) {
        return Err(wrong());
    }
    let components = match ty {
        Type::Vec3 => 3,
        Type::Vec2 => 2,
        _ => 1,
    };
    Ok((component, components))
}

/// The accessor's element count, required to be at least 1.
fn element_count(a: &Accessor, index: usize) -> Result<usize, AssetError> {
    let count = usize::try_from(a.count.0).unwrap_or(usize::MAX);
    if count == 0 {
        return Err(AssetError::gltf(
            format!("accessors[{index}].count"),
            "is 0; an accessor holds at least 1 element",
        ));
    }
    Ok(count)
}

/// `unplaced` (a layout with tightly packed elements and no data) placed in buffer view
/// `view_index`: its stride and byte range checked, and its data the view's bytes.
fn placed<'b>(
    root: &Root,
    buffers: &'b [Vec<u8>],
    a: &Accessor,
    index: usize,
    view_index: usize,
    unplaced: Layout<'b>,
) -> Result<Layout<'b>, AssetError> {
    let element = unplaced.component.size() * unplaced.components;
    let view_bytes = view(
        root,
        buffers,
        view_index,
        &format!("accessors[{index}].bufferView"),
    )?;
    let stride = view_stride(root, view_index, element, index)?;
    let count = unplaced.count;
    let offset = a.byte_offset.map_or(0, |o| o.0);
    // First byte past the last element, in u128 so no count or offset can overflow.
    let end = u128::from(offset) + (count as u128 - 1) * stride as u128 + element as u128;
    if end > view_bytes.len() as u128 {
        return Err(AssetError::gltf(
            format!("accessors[{index}].count"),
            format!(
                "{count} elements of {element} bytes, {stride} apart, from byte {offset} need {end} bytes, \
                 but bufferViews[{view_index}] holds {} (an accessor must lie inside its buffer view)",
                view_bytes.len()
            ),
        ));
    }
    Ok(Layout {
        data: Some(&view_bytes[offset as usize..]),
        stride,
        ..unplaced
    })
}

/// The distance between elements in buffer view `view_index`, checked against glTF's rules
/// and the `element` size of accessor `index`.
fn view_stride(
    root: &Root,
    view_index: usize,
    element: usize,
    index: usize,
) -> Result<usize, AssetError> {
    match root.buffer_views[view_index].byte_stride {
        None => Ok(element),
        Some(s) if (4..=252).contains(&s.0) && s.0 % 4 == 0 && s.0 >= element => Ok(s.0),
        Some(s) => Err(AssetError::gltf(
            format!("bufferViews[{view_index}].byteStride"),
            format!("is {}; must be a multiple of 4 in 4..=252 and at least the {element}-byte element of accessors[{index}]", s.0),
        )),
    }
}

/// The bytes of buffer view `index` (referred to at `user`), checked to lie in its buffer.
fn view<'b>(
    root: &Root,
    buffers: &'b [Vec<u8>],
    index: usize,
    user: &str,
) -> Result<&'b [u8], AssetError> {
    let Some(v) = root.buffer_views.get(index) else {
        return Err(AssetError::gltf(
            user,
            format!(
                "refers to bufferViews[{index}], but the file has {} buffer views",
                root.buffer_views.len()
            ),
        ));
    };
    let b = v.buffer.value();
    let Some(buffer) = buffers.get(b) else {
        return Err(AssetError::gltf(
            format!("bufferViews[{index}].buffer"),
            format!(
                "refers to buffers[{b}], but the file has {} buffers",
                buffers.len()
            ),
        ));
    };
    let offset = v.byte_offset.map_or(0, |o| o.0);
    let end = u128::from(offset) + u128::from(v.byte_length.0);
    if end > buffer.len() as u128 {
        return Err(AssetError::gltf(
            format!("bufferViews[{index}].byteLength"),
            format!(
                "{} bytes from byte {offset} end at {end}, past the {} bytes of buffers[{b}]",
                v.byte_length.0,
                buffer.len()
            ),
        ));
    }
    Ok(&buffer[offset as usize..end as usize])
}

impl Layout<'_> {
    /// Component `k` of element `i`, as f32 (normalized integers mapped to [0, 1]).
    fn float(&self, i: usize, k: usize) -> f32 {
        match self.component {
            ComponentType::U8 => f32::from(self.uint(i, k) as u8) / 255.0,
            ComponentType::U16 => f32::from(self.uint(i, k) as u16) / 65535.0,
            _ => f32::from_bits(self.uint(i, k)),
        }
    }

    /// The raw little-endian bits of component `k` of element `i`; zero without a view.
    fn uint(&self, i: usize, k: usize) -> u32 {
        let Some(data) = self.data else {
            return 0;
        };
        let size = self.component.size();
        let at = i * self.stride + k * size;
        // `layout` checked that every element lies inside `data`.
        let b = &data[at..at + size];
        match size {
            1 => u32::from(b[0]),
            2 => u32::from(u16::from_le_bytes([b[0], b[1]])),
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        }
    }

    pub fn vec3s(&self) -> Vec<[f32; 3]> {
        (0..self.count)
            .map(|i| [0, 1, 2].map(|k| self.float(i, k)))
            .collect()
    }

    pub fn vec2s(&self) -> Vec<[f32; 2]> {
        (0..self.count)
            .map(|i| [0, 1].map(|k| self.float(i, k)))
            .collect()
    }

    pub fn indices(&self) -> Vec<u32> {
        debug_assert_eq!(self.components, 1);
        (0..self.count).map(|i| self.uint(i, 0)).collect()
    }
}
