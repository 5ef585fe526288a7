//! The leaves of a format by pyulog's column names, for code that reads or writes a few
//! fields of rows by name (row transforms, anonymizing, the flight analysis).

use std::collections::HashMap;

use super::{ColumnKind, ColumnSpec, Source};
use crate::schema::{FormatId, Primitive, Schema};
use crate::value::Scalar;

/// Where one leaf of a row lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Leaf {
    /// A value of a basic type at this offset.
    Value(usize, Primitive),
    /// A `char[N]` array at this offset.
    Text(usize, usize),
}

/// The leaves of a format by pyulog's column names (`timestamp`, `q[0]`,
/// `esc[3].esc_rpm`), padding left out: what [`RowFields`] reads and writes.
#[derive(Debug, Clone)]
pub(crate) struct FieldIndex {
    names: Vec<String>,
    leaves: HashMap<String, Leaf>,
}

impl FieldIndex {
    /// How many fields it names.
    pub(crate) fn len(&self) -> usize {
        self.names.len()
    }

    /// The index of format `id`, if its layout is resolved.
    pub(crate) fn of(schema: &Schema, id: FormatId) -> Option<FieldIndex> {
        let spec = ColumnSpec::of(schema, id)?;
        let mut names = Vec::with_capacity(spec.columns().len());
        let mut leaves = HashMap::with_capacity(spec.columns().len());
        for c in spec.columns() {
            let leaf = match (c.kind, c.source) {
                // The file's type, not the unwrapped `u64` of the column.
                (_, Source::Timestamp) => {
                    Leaf::Value(c.offset, Primitive::from_c_name(&c.ulog_type)?)
                }
                (ColumnKind::Value(p), _) => Leaf::Value(c.offset, p),
                (ColumnKind::Text { len }, _) => Leaf::Text(c.offset, len),
            };
            names.push(c.name.clone());
            leaves.insert(c.name.clone(), leaf);
        }
        Some(FieldIndex { names, leaves })
    }

    /// The leaves, in column order.
    pub(crate) fn iter(&self) -> impl Iterator<Item = (&str, Leaf)> {
        self.names.iter().map(|n| (n.as_str(), self.leaves[n]))
    }

    pub(crate) fn get(&self, name: &str) -> Option<Leaf> {
        self.leaves.get(name).copied()
    }
}

impl Leaf {
    /// The value of this leaf of `row` as `f64` (`None` for text, or a row too short).
    #[inline]
    pub(crate) fn f64(self, row: &[u8]) -> Option<f64> {
        match self {
            // The common case, without the dispatch on the type.
            Leaf::Value(at, Primitive::Float) => {
                let (v, _) = row.get(at..)?.split_first_chunk::<4>()?;
                Some(f64::from(f32::from_le_bytes(*v)))
            }
            Leaf::Value(at, p) => {
                Scalar::decode(p, row.get(at..at + p.size())?).map(Scalar::as_f64)
            }
            Leaf::Text(..) => None,
        }
    }
}
