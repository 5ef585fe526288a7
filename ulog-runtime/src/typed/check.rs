//! The runtime check: a struct's [`TypedFormat`] against a file's format of the same name,
//! once, producing a [`DecodePlan`] of offsets in the file's layout.

use std::fmt;
use std::marker::PhantomData;

use super::widen::{FloatLoader, IntLoader, loaders, widens};
use super::{Topic, TypedField, TypedFormat, TypedKind};
use crate::read::Row;
use crate::schema::{Difference, FieldKind, FormatId, LayoutError, Schema, did_you_mean};

/// Where each field of a struct lives in a file's rows: made once by the runtime check, then
/// used for every row (offset reads only).
#[derive(Debug, Clone)]
pub struct DecodePlan {
    fields: Box<[FieldPlan]>,
}

/// Where one struct field lives in the file's layout.
#[derive(Clone)]
pub struct FieldPlan {
    offset: usize,
    stride: usize,
    present: bool,
    nested: Option<Box<DecodePlan>>,
    /// For `#[ulog(widen)]` fields: readers of the file's type (chosen once by the check).
    load_int: IntLoader,
    load_float: FloatLoader,
}

impl fmt::Debug for FieldPlan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FieldPlan")
            .field("offset", &self.offset)
            .field("stride", &self.stride)
            .field("present", &self.present)
            .field("nested", &self.nested)
            .finish_non_exhaustive()
    }
}

/// Loaders of a field that never converts.
const NO_LOADERS: (IntLoader, FloatLoader) = (|_, _| 0, |_, _| 0.0);

impl FieldPlan {
    const ABSENT: FieldPlan = FieldPlan {
        offset: 0,
        stride: 0,
        present: false,
        nested: None,
        load_int: NO_LOADERS.0,
        load_float: NO_LOADERS.1,
    };

    /// A widened field's value at `offset`, read as the file's type, as `i64`.
    #[inline(always)]
    pub fn load_int(&self, row: &[u8], offset: usize) -> i64 {
        (self.load_int)(row, offset)
    }

    /// A widened field's value at `offset`, read as the file's type, as `f64`.
    #[inline(always)]
    pub fn load_float(&self, row: &[u8], offset: usize) -> f64 {
        (self.load_float)(row, offset)
    }

    /// Byte offset of the field (its first element) from the start of the enclosing format.
    #[inline(always)]
    pub fn offset(&self) -> usize {
        self.offset
    }

    /// Distance between array elements in the file (the element's full size).
    #[inline(always)]
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// Whether the file has the field (only optional fields may be absent).
    #[inline(always)]
    pub fn is_present(&self) -> bool {
        self.present
    }

    /// The plan of a nested element, relative to the element's start.
    #[inline(always)]
    pub fn nested_plan(&self) -> &DecodePlan {
        // The check gives every present nested field its plan, and decoders read only
        // present fields.
        self.nested
            .as_deref()
            .expect("decode plan invariant: a present nested field has a nested plan")
    }
}

impl DecodePlan {
    /// Compares `format` (and the formats it nests) with the file's format of the same name in
    /// `schema`; every difference is collected into one [`TypedError::Mismatch`].
    pub fn check(format: &'static TypedFormat, schema: &Schema) -> Result<DecodePlan, TypedError> {
        DecodePlan::check_as(format, format.name, schema)
    }

    /// [`DecodePlan::check`] against the file's format named `topic`: a type read under
    /// another topic name with the same layout (PX4's `# TOPICS`).
    pub fn check_as(
        format: &'static TypedFormat,
        topic: &str,
        schema: &Schema,
    ) -> Result<DecodePlan, TypedError> {
        let id = schema.id(topic).ok_or_else(|| TypedError::NoSuchTopic {
            topic: topic.to_owned(),
            rust_type: format.rust_type,
            suggestions: schema.suggest(topic),
        })?;
        let resolved;
        let schema = if schema.resolved(id).is_some() {
            schema
        } else {
            let mut owned = schema.clone();
            owned
                .layout(id)
                .map_err(|error| TypedError::InvalidFormat {
                    topic: topic.to_owned(),
                    error,
                })?;
            resolved = owned;
            &resolved
        };
        let mut mismatches = Vec::new();
        let plan = check_format(format, id, schema, "", &mut mismatches);
        match plan {
            Some(plan) if mismatches.is_empty() => Ok(plan),
            _ => Err(TypedError::Mismatch {
                topic: topic.to_owned(),
                rust_type: format.rust_type,
                mismatches,
            }),
        }
    }

    /// The plan of the struct's `i`-th field (declaration order, padding fields included).
    #[inline(always)]
    pub fn field(&self, i: usize) -> &FieldPlan {
        &self.fields[i]
    }

    /// The plans of all fields, in declaration order.
    pub fn fields(&self) -> &[FieldPlan] {
        &self.fields
    }
}

/// Checks one format level; `prefix` is the path of the enclosing field (`esc[].`).
fn check_format(
    tf: &'static TypedFormat,
    id: FormatId,
    schema: &Schema,
    prefix: &str,
    out: &mut Vec<Mismatch>,
) -> Option<DecodePlan> {
    let Some(layout) = schema.resolved(id) else {
        out.push(Mismatch {
            path: prefix.trim_end_matches('.').to_owned(),
            kind: MismatchKind::Invalid {
                type_name: schema.format(id).name.clone(),
            },
        });
        return None;
    };
    // Exact mode: every difference of this level is said once, as a difference of the
    // formats, not again per field below.
    let mut exact_differs = false;
    if tf.exact {
        let file = schema.format(id);
        // The topic may be read under another name (`check_as`): compare the fields.
        let rust = tf.to_format_as(&file.name);
        if *file != rust {
            exact_differs = true;
            let path = prefix.trim_end_matches('.');
            let mut differences = crate::schema::diff(file, &rust);
            if differences.is_empty() {
                // Only the names of padding fields differ, which `diff` does not compare.
                differences.push(Difference::Padding {
                    first: padding_names(file),
                    second: padding_names(&rust),
                });
            }
            out.extend(differences.into_iter().map(|difference| Mismatch {
                path: path.to_owned(),
                kind: MismatchKind::NotExact {
                    difference,
                    rust_struct: tf.rust_type,
                },
            }));
        }
    }
    let mut fields = Vec::with_capacity(tf.fields.len());
    for field in tf.fields {
        if field.padding {
            fields.push(FieldPlan::ABSENT);
            continue;
        }
        let path = format!("{prefix}{}", field.name);
        let Some(file_field) = layout
            .fields
            .iter()
            .find(|f| !f.padding && f.name == field.name)
        else {
            if !field.optional && !exact_differs {
                out.push(Mismatch {
                    path,
                    kind: MismatchKind::Missing {
                        rust_struct: tf.rust_type,
                    },
                });
            }
            fields.push(FieldPlan::ABSENT);
            continue;
        };
        let widen = field.widen && !tf.exact;
        // Whether `#[ulog(widen)]` would make the field fit (worth saying when it is not set).
        let would_widen = !field.widen
            && !tf.exact
            && file_field.array_len == field.array_len
            && matches!(
                (field.kind, file_field.kind),
                (TypedKind::Primitive(a), FieldKind::Primitive(b)) if widens(b, a)
            );
        let type_mismatch = || Mismatch {
            path: path.clone(),
            kind: MismatchKind::Type {
                file: file_type(schema, file_field.kind, file_field.array_len),
                rust: field.rust_type.to_owned(),
                rust_struct: tf.rust_type,
                widen,
                would_widen,
            },
        };
        // A nested struct whose format name is not the file's: said with the name to give it.
        let misnamed = match (field.kind, file_field.kind) {
            (TypedKind::Nested(inner), FieldKind::Nested(inner_id))
                if schema.format(inner_id).name != inner.name =>
            {
                Some(Mismatch {
                    path: path.clone(),
                    kind: MismatchKind::NestedName {
                        file: file_type(schema, file_field.kind, file_field.array_len),
                        rust: field.rust_type.to_owned(),
                        rust_struct: tf.rust_type,
                        nested_struct: inner.rust_type,
                        nested_name: inner.name,
                        file_name: schema.format(inner_id).name.clone(),
                    },
                })
            }
            _ => None,
        };
        if let Some(m) = misnamed {
            if !exact_differs {
                out.push(m);
            }
            fields.push(FieldPlan::ABSENT);
            continue;
        }
        if file_field.array_len != field.array_len {
            if !exact_differs {
                out.push(type_mismatch());
                // The nested format's own differences too, so that every difference is
                // said at once (not one more after the length is fixed).
                if let (TypedKind::Nested(inner), FieldKind::Nested(inner_id)) =
                    (field.kind, file_field.kind)
                {
                    let brackets = if file_field.array_len.is_some() {
                        "[]"
                    } else {
                        ""
                    };
                    let prefix = format!("{path}{brackets}.");
                    check_format(inner, inner_id, schema, &prefix, out);
                }
            }
            fields.push(FieldPlan::ABSENT);
            continue;
        }
        let mut load = NO_LOADERS;
        let nested = match (field.kind, file_field.kind) {
            (TypedKind::Primitive(a), FieldKind::Primitive(b))
                if a == b || (widen && widens(b, a)) =>
            {
                if widen {
                    load = loaders(b);
                }
                None
            }
            (TypedKind::Nested(inner), FieldKind::Nested(inner_id))
                if schema.format(inner_id).name == inner.name =>
            {
                let brackets = if field.array_len.is_some() { "[]" } else { "" };
                let prefix = format!("{path}{brackets}.");
                Some(Box::new(check_format(
                    inner, inner_id, schema, &prefix, out,
                )?))
            }
            _ => {
                if !exact_differs {
                    out.push(type_mismatch());
                }
                fields.push(FieldPlan::ABSENT);
                continue;
            }
        };
        fields.push(FieldPlan {
            offset: file_field.offset,
            stride: file_field.elem_size,
            present: true,
            nested,
            load_int: load.0,
            load_float: load.1,
        });
    }
    Some(DecodePlan {
        fields: fields.into_boxed_slice(),
    })
}

/// The names of a format's padding fields.
fn padding_names(format: &crate::schema::Format) -> Vec<String> {
    format
        .fields
        .iter()
        .filter(|f| f.is_padding())
        .map(|f| f.name.clone())
        .collect()
}

/// A file field's type as a format string spells it: `int32_t`, `float[4]`, `esc_report[8]`.
fn file_type(schema: &Schema, kind: FieldKind, array_len: Option<u16>) -> String {
    let name = match kind {
        FieldKind::Primitive(p) => p.c_name(),
        FieldKind::Nested(id) => &schema.format(id).name,
    };
    match array_len {
        Some(n) => format!("{name}[{n}]"),
        None => name.to_owned(),
    }
}

/// One difference between a struct and a file's format.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mismatch {
    /// Field path from the topic, `[]` marking arrays of nested types: `esc[].esc_rpm`
    /// (empty for the topic itself).
    pub path: String,
    /// What differs.
    pub kind: MismatchKind,
}

/// What differs between a struct field and the file's field.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum MismatchKind {
    /// Different types or array lengths.
    Type {
        /// The file's type, as a format string spells it (`int32_t`, `float[4]`).
        file: String,
        /// The struct field's Rust type.
        rust: String,
        /// The struct that has the field.
        rust_struct: &'static str,
        /// Whether the field widens (`#[ulog(widen)]`): then the file's type is one it
        /// cannot hold every value of.
        widen: bool,
        /// Whether it would fit with `#[ulog(widen)]`, which it lacks: the struct's type
        /// holds every value of the file's.
        would_widen: bool,
    },
    /// A field the struct requires and the file lacks.
    Missing {
        /// The struct that has the field.
        rust_struct: &'static str,
    },
    /// Exact mode: the file's format is not identical to the struct's; one mismatch per
    /// difference ([`schema::diff`](crate::schema::diff) of the file's format, first, and
    /// the struct's).
    NotExact {
        /// What differs.
        difference: Difference,
        /// The struct.
        rust_struct: &'static str,
    },
    /// A nested struct whose format name is not the file's nested format's (formats are
    /// matched by name: `#[ulog(name = "...")]` on the nested struct gives it the file's).
    NestedName {
        /// The file's type, as a format string spells it (`esc_report[8]`).
        file: String,
        /// The struct field's Rust type (`[Motor; 8]`).
        rust: String,
        /// The struct that has the field.
        rust_struct: &'static str,
        /// The nested struct.
        nested_struct: &'static str,
        /// The nested struct's format name (`motor`).
        nested_name: &'static str,
        /// The file's nested format name (`esc_report`).
        file_name: String,
    },
    /// The file's nested format has no valid layout.
    Invalid {
        /// The nested format.
        type_name: String,
    },
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let path = &self.path;
        match &self.kind {
            MismatchKind::Type {
                file,
                rust,
                rust_struct,
                widen,
                would_widen,
            } => {
                write!(
                    f,
                    "{path} is {file} in the file, {rust} in struct {rust_struct}"
                )?;
                if *widen {
                    f.write_str(" (not a lossless widening)")?;
                }
                if *would_widen {
                    write!(
                        f,
                        " (every {file} value fits in {rust}: `#[ulog(widen)]` on the field \
                         accepts it)"
                    )?;
                }
                if let Some(hint) = char_hint(file, rust) {
                    write!(f, " ({hint})")?;
                }
                Ok(())
            }
            MismatchKind::Missing { rust_struct } => write!(
                f,
                "{path} is in struct {rust_struct} but not in the file \
                 (make it an `Option` to accept files without it)"
            ),
            MismatchKind::NotExact {
                difference,
                rust_struct,
            } => {
                let at = if path.is_empty() {
                    String::new()
                } else {
                    format!("{path}: ")
                };
                let text = difference.describe("the file", &format!("struct {rust_struct}"));
                write!(f, "{at}exact mode: {text}")
            }
            MismatchKind::NestedName {
                file,
                rust,
                rust_struct,
                nested_struct,
                nested_name,
                file_name,
            } => write!(
                f,
                "{path} is {file} in the file, {rust} in struct {rust_struct}: struct \
                 {nested_struct} is format `{nested_name}`, the file's is `{file_name}` \
                 (`#[ulog(name = \"{file_name}\")]` on struct {nested_struct} names it so)"
            ),
            MismatchKind::Invalid { type_name } => write!(
                f,
                "{path}: the file's format `{type_name}` has no valid layout"
            ),
        }
    }
}

/// The type that reads a file's `char` or `char[N]`, for a struct that gave bytes.
fn char_hint(file: &str, rust: &str) -> Option<String> {
    if file == "char" && matches!(rust, "u8" | "i8") {
        return Some("a `char` is read by `ulog_runtime::Char`".to_owned());
    }
    let n = file.strip_prefix("char[")?.strip_suffix(']')?;
    (rust == format!("[u8; {n}]") || rust == format!("[i8; {n}]"))
        .then(|| format!("`char[{n}]` text is read by `ulog_runtime::Chars<{n}>`"))
}

/// Why a typed view of a file could not be made.
#[derive(Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum TypedError {
    /// The file defines no format of this name.
    #[error("the file has no format `{topic}` (wanted by struct {rust_type}){}", did_you_mean(.suggestions))]
    NoSuchTopic {
        /// The topic.
        topic: String,
        /// The struct.
        rust_type: &'static str,
        /// The file's format names closest to `topic` (at most 3, closest first).
        suggestions: Vec<String>,
    },
    /// A stream's definitions are not all read yet, and none read so far is the format
    /// ([`StreamReader::typed`](crate::StreamReader::typed) called too early).
    #[error(
        "no format `{topic}` (wanted by struct {rust_type}) among the {read} read so far: the \
         stream's definitions are not all read yet (make the decoder at the topic's \
         `Event::Subscription`)"
    )]
    DefinitionsNotRead {
        /// The topic.
        topic: String,
        /// The struct.
        rust_type: &'static str,
        /// The formats read so far.
        read: usize,
    },
    /// The file defines the format but never subscribes to it.
    #[error("`{topic}` is defined in the file but was never logged (no subscription)")]
    NotLogged {
        /// The topic.
        topic: String,
    },
    /// No subscription with this instance number.
    #[error("`{topic}` has no instance {multi_id} in the file (instances: {available:?})")]
    NoInstance {
        /// The topic.
        topic: String,
        /// The instance asked for.
        multi_id: u8,
        /// The instances the file has.
        available: Vec<u8>,
    },
    /// The file's format cannot be laid out (a nested type missing, a cycle...).
    #[error("the file's format `{topic}` is invalid: {error}")]
    InvalidFormat {
        /// The topic.
        topic: String,
        /// Why.
        error: LayoutError,
    },
    /// The struct does not match the file's format; every difference is listed.
    #[error("{}", mismatch_lines(.topic, .rust_type, .mismatches))]
    Mismatch {
        /// The topic.
        topic: String,
        /// The struct.
        rust_type: &'static str,
        /// Every difference.
        mismatches: Vec<Mismatch>,
    },
}

crate::error::debug_as_display!(TypedError);

/// One difference on one line; several as a list, one per line.
fn mismatch_lines(topic: &str, rust_type: &str, mismatches: &[Mismatch]) -> String {
    match mismatches {
        [one] => format!("{topic}: {one}"),
        many => {
            let mut text = format!(
                "{topic}: {} differences between the file and struct {rust_type}:",
                many.len()
            );
            for m in many {
                text.push_str("\n  ");
                text.push_str(&m.to_string());
            }
            text
        }
    }
}

/// A checked decoder of one topic's rows: made once against a file's formats, then decoding
/// each row by offset reads only.
///
/// ```
/// # use ulog_runtime::{ULog, typed::TypedDecoder, schema::Schema};
/// #[derive(ULog, Debug, PartialEq)]
/// struct Gps { timestamp: u64, alt: f32 }
///
/// let mut schema = Schema::new();
/// // The file's format has another field and a different order: still a match.
/// schema.insert("gps:float alt;uint8_t sats;uint64_t timestamp;".parse().unwrap()).unwrap();
/// let decoder = TypedDecoder::<Gps>::new(&schema)?;
/// let mut row = 2.5f32.to_le_bytes().to_vec();
/// row.push(9);
/// row.extend_from_slice(&7u64.to_le_bytes());
/// assert_eq!(decoder.decode(&row), Some(Gps { timestamp: 7, alt: 2.5 }));
/// # Ok::<(), ulog_runtime::typed::TypedError>(())
/// ```
pub struct TypedDecoder<T> {
    plan: DecodePlan,
    format: FormatId,
    min_len: usize,
    _type: PhantomData<fn() -> T>,
}

impl<T> fmt::Debug for TypedDecoder<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("TypedDecoder")
            .field("format", &self.format)
            .field("min_len", &self.min_len)
            .finish_non_exhaustive()
    }
}

impl<T> Clone for TypedDecoder<T> {
    fn clone(&self) -> Self {
        TypedDecoder {
            plan: self.plan.clone(),
            format: self.format,
            min_len: self.min_len,
            _type: PhantomData,
        }
    }
}

impl<T: Topic> TypedDecoder<T> {
    /// Checks `T` against the format of the same name in `schema` (a file's:
    /// [`Metadata::schema`](crate::read::Metadata::schema)).
    pub fn new(schema: &Schema) -> Result<TypedDecoder<T>, TypedError> {
        TypedDecoder::new_as(schema, T::FORMAT.name)
    }

    /// Checks `T` against the format named `topic` in `schema`: `T` read under another topic
    /// name with the same layout (see [`TypedFormat::topics`](super::TypedFormat::topics)).
    pub fn new_as(schema: &Schema, topic: &str) -> Result<TypedDecoder<T>, TypedError> {
        let plan = DecodePlan::check_as(&T::FORMAT, topic, schema)?;
        let format = schema.id(topic).expect("checked above");
        let min_len = read_end(&plan, &T::FORMAT);
        Ok(TypedDecoder {
            plan,
            format,
            min_len,
            _type: PhantomData,
        })
    }

    /// Decodes a row of the checked format; `None` if it is too short for the fields read.
    #[inline]
    pub fn decode(&self, data: &[u8]) -> Option<T> {
        (data.len() >= self.min_len).then(|| T::decode(&self.plan, data))
    }

    /// Decodes a row the log accepted for the checked format: such rows are at least the
    /// format's size without trailing padding, and every field the plan reads lies before
    /// that (only top-level trailing padding is left out of rows), so no length check is
    /// needed per row.
    #[inline]
    pub(crate) fn decode_accepted(&self, data: &[u8]) -> T {
        T::decode(&self.plan, data)
    }

    /// The length a row needs for every field the plan reads.
    pub(crate) fn min_len(&self) -> usize {
        self.min_len
    }

    /// Decodes a row read from the file this decoder was checked against; `None` for a row
    /// of another topic.
    #[inline]
    pub fn decode_row(&self, row: &Row<'_>) -> Option<T> {
        if row.subscription.format() != Some(self.format) {
            return None;
        }
        self.decode(row.data)
    }

    /// The plan.
    pub fn plan(&self) -> &DecodePlan {
        &self.plan
    }

    /// The file format it was checked against.
    pub fn format(&self) -> FormatId {
        self.format
    }
}

/// The end of the last byte the plan reads (0 for a plan that reads nothing).
fn read_end(plan: &DecodePlan, tf: &TypedFormat) -> usize {
    plan.fields
        .iter()
        .zip(tf.fields)
        .filter(|(p, _)| p.present)
        .map(|(p, f): (&FieldPlan, &TypedField)| {
            let count = f.array_len.map_or(1, usize::from);
            let last_start = p.offset + count.saturating_sub(1) * p.stride;
            // The file's element size: a widened field reads fewer bytes than its Rust type.
            let last_len = match (f.kind, &p.nested) {
                (TypedKind::Nested(inner), Some(nested)) => read_end(nested, inner),
                _ => p.stride,
            };
            last_start + last_len
        })
        .max()
        .unwrap_or(0)
}
