//! The one description of ULog formats used by the whole workspace: basic types, format strings,
//! and layouts resolved over a set of formats. Nothing else re-implements any of this.

mod diff;
mod format;
mod layout;
mod primitive;
mod suggest;

pub use diff::{Difference, diff};
pub use format::{
    Field, Format, FormatError, FormatErrorKind, MAX_ARRAY_LEN, TypeRef, check_field_name,
    check_message_name, is_field_name_char, is_message_name_char, is_padding_name,
};
pub use layout::{
    FieldKind, FieldLayout, FormatId, Layout, LayoutError, MAX_DATA_SIZE, Redefinition, Schema,
};
pub use primitive::Primitive;
pub use suggest::{closest_names, did_you_mean};
