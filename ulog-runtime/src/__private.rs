//! Paths used by code that `#[derive(ULog)]` generates, and nothing else. Not a public API:
//! anything here may change in any release.

pub use crate::schema::{MAX_DATA_SIZE, Primitive};
pub use crate::typed::{
    DecodePlan, DerivedElement, DerivedTopic, FieldPlan, FieldValue, Padding, TypedField,
    TypedFormat, TypedKind, ULog,
};
pub use std::vec::Vec;

/// Appends `len` zero bytes (a padding field).
#[inline]
pub fn encode_padding(len: u16, out: &mut Vec<u8>) {
    out.resize(out.len() + usize::from(len), 0);
}
