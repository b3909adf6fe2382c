//! The binary chunk and its index: one little-endian byte buffer, a buffer view per accessor
//! or image (each 4-byte aligned), and the accessors' JSON. Animation data that repeats (the
//! key times most bodies share, the presence scales) is stored once.

use std::collections::hash_map::DefaultHasher;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};

use serde::Serialize;

const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// What an accessor's elements are.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum Kind {
    Scalar,
    Vec2,
    Vec3,
    Vec4,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Scalar => "SCALAR",
            Kind::Vec2 => "VEC2",
            Kind::Vec3 => "VEC3",
            Kind::Vec4 => "VEC4",
        }
    }

    fn components(self) -> usize {
        match self {
            Kind::Scalar => 1,
            Kind::Vec2 => 2,
            Kind::Vec3 => 3,
            Kind::Vec4 => 4,
        }
    }
}

/// A glTF buffer view (of buffer 0). Typed rather than a JSON value: a large export has
/// hundreds of thousands of them.
#[derive(Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct View {
    buffer: u32,
    byte_offset: usize,
    byte_length: usize,
}

/// A glTF accessor over one buffer view.
#[derive(Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct Accessor {
    buffer_view: usize,
    component_type: u32,
    count: usize,
    #[serde(rename = "type")]
    kind: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    min: Option<Vec<f32>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    max: Option<Vec<f32>>,
}

/// The GLB's binary chunk, its buffer views and accessors, built in order.
#[derive(Default)]
pub(super) struct BufferBuilder {
    bin: Vec<u8>,
    views: Vec<View>,
    accessors: Vec<Accessor>,
    /// Accessors [`Self::shared_floats`] made, by kind and hash of their bytes.
    shared: HashMap<(Kind, u64), Vec<usize>>,
}

impl BufferBuilder {
    /// Appends `bytes` (padded to 4 bytes) as a buffer view; returns its index.
    pub(super) fn view(&mut self, bytes: &[u8]) -> usize {
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        self.views.push(View { buffer: 0, byte_offset: offset, byte_length: bytes.len() });
        self.views.len() - 1
    }

    /// `values` (`kind`'s components one after another) as a float accessor with its
    /// per-component bounds over the finite values; returns its index.
    pub(super) fn floats(&mut self, kind: Kind, values: &[f32]) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes);
        let (min, max) = bounds(kind.components(), values);
        self.accessors.push(Accessor {
            buffer_view: view,
            component_type: FLOAT,
            count: values.len() / kind.components(),
            kind: kind.name(),
            min: Some(min),
            max: Some(max),
        });
        self.accessors.len() - 1
    }

    /// As [`Self::floats`], but the same kind and values give the same accessor.
    pub(super) fn shared_floats(&mut self, kind: Kind, values: &[f32]) -> usize {
        let mut hasher = DefaultHasher::new();
        values.iter().for_each(|v| v.to_bits().hash(&mut hasher));
        let key = (kind, hasher.finish());
        let same_bits =
            |a: &[f32], b: &[f32]| a.iter().map(|v| v.to_bits()).eq(b.iter().map(|v| v.to_bits()));
        if let Some(candidates) = self.shared.get(&key) {
            if let Some(&found) = candidates.iter().find(|&&i| same_bits(&self.float_data(i), values)) {
                return found;
            }
        }
        let index = self.floats(kind, values);
        self.shared.entry(key).or_default().push(index);
        index
    }

    /// Triangle indices as an unsigned-int scalar accessor; returns its index.
    pub(super) fn indices(&mut self, values: &[u32]) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessors.push(Accessor {
            buffer_view: view,
            component_type: UNSIGNED_INT,
            count: values.len(),
            kind: "SCALAR",
            min: None,
            max: None,
        });
        self.accessors.len() - 1
    }

    /// The floats of accessor `index` (one [`Self::floats`] made), read back from the buffer.
    fn float_data(&self, index: usize) -> Vec<f32> {
        let view = &self.views[self.accessors[index].buffer_view];
        self.bin[view.byte_offset..view.byte_offset + view.byte_length]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect()
    }

    /// The binary chunk (a multiple of 4 bytes), the buffer views and the accessors.
    pub(super) fn finish(self) -> (Vec<u8>, Vec<View>, Vec<Accessor>) {
        (self.bin, self.views, self.accessors)
    }
}

/// Per-component minimum and maximum of the finite values (0 where a component has none).
fn bounds(components: usize, values: &[f32]) -> (Vec<f32>, Vec<f32>) {
    let mut min = vec![f32::INFINITY; components];
    let mut max = vec![f32::NEG_INFINITY; components];
    for element in values.chunks_exact(components) {
        for (c, &v) in element.iter().enumerate().filter(|(_, v)| v.is_finite()) {
            min[c] = min[c].min(v);
            max[c] = max[c].max(v);
        }
    }
    let finite_or_zero = |v: Vec<f32>| v.into_iter().map(|x| if x.is_finite() { x } else { 0.0 }).collect();
    (finite_or_zero(min), finite_or_zero(max))
}
