//! Row transforms: a row's fields by path, read and written in place ([`RowFields`]), and a
//! typed struct written back into the file's layout ([`scatter`]).

pub(crate) use crate::columns::{FieldIndex, Leaf};
use crate::schema::Primitive;
use crate::typed::{DecodePlan, TypedFormat, TypedKind};
use crate::value::Scalar;

/// Why a field of a row could not be written ([`RowFields`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FieldError {
    /// The row has no field of this name.
    #[error("no field `{name}`{}", crate::schema::did_you_mean(.suggestions))]
    NoSuchField {
        /// The name asked for.
        name: String,
        /// The closest names the row has.
        suggestions: Vec<String>,
    },
    /// A value of another type ([`RowFields::set`] writes the field's own type only).
    #[error("`{name}` is {field}, not {value}")]
    Type {
        /// The field.
        name: String,
        /// Its type.
        field: &'static str,
        /// The value's type.
        value: &'static str,
    },
    /// A number the field's type cannot hold exactly ([`RowFields::set_f64`]).
    #[error("`{name}` is {field}: {value} does not fit")]
    OutOfRange {
        /// The field.
        name: String,
        /// Its type.
        field: &'static str,
        /// The value.
        value: f64,
    },
    /// Text longer than the field's `char[N]`.
    #[error("`{name}` is char[{len}]: {bytes} bytes of text do not fit")]
    TooLong {
        /// The field.
        name: String,
        /// `N`.
        len: usize,
        /// Bytes of the text.
        bytes: usize,
    },
}

/// One row's fields, read and written in place by name (pyulog's column names: `x`,
/// `q[0]`, `esc[3].esc_rpm`; padding is not a field): what a dynamic row transform
/// ([`Rewrite::map_rows`](super::Rewrite::map_rows)) gets. Writing converts nothing
/// silently: [`RowFields::set`] takes the field's own type, [`RowFields::set_f64`] any
/// number the type holds exactly (a float field takes the nearest `f32`).
///
/// ```
/// use ulog_runtime::rewrite::Rewrite;
/// use ulog_runtime::{Log, Scalar, ULog, Writer, WriterOptions};
///
/// #[derive(ULog)]
/// struct Battery { timestamp: u64, voltage_v: f32, cell_count: u8 }
///
/// let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
/// let sub = w.topic::<Battery>(0)?;
/// w.write(&sub, &Battery { timestamp: 1, voltage_v: 16.0, cell_count: 4 })?;
/// let input = w.into_inner();
///
/// let mut out = Vec::new();
/// Rewrite::new()
///     .map_rows("battery", |row| {
///         let v = row.get("voltage_v").unwrap().as_f64();
///         row.set_f64("voltage_v", v / 4.0).unwrap();
///         row.set("cell_count", Scalar::UInt8(1)).unwrap();
///     })
///     .run(&input[..], &mut out)?;
/// let log = Log::from_vec(out)?;
/// let b = log.columns("battery", 0)?;
/// assert_eq!(b.get("voltage_v").unwrap().as_float(), Some(&[4.0f32][..]));
/// assert_eq!(b.get("cell_count").unwrap().as_uint8(), Some(&[1u8][..]));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct RowFields<'a> {
    pub(crate) row: &'a mut [u8],
    pub(crate) index: &'a FieldIndex,
    pub(crate) timestamp: u64,
}

impl RowFields<'_> {
    /// The row's timestamp (µs, unwrapped for version-0 logs), as it was read.
    pub fn timestamp(&self) -> u64 {
        self.timestamp
    }

    /// The field names, in column order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.index.iter().map(|(n, _)| n)
    }

    fn leaf(&self, name: &str) -> Result<Leaf, FieldError> {
        self.index.get(name).ok_or_else(|| FieldError::NoSuchField {
            name: name.to_owned(),
            suggestions: crate::schema::closest_names(name, self.names()),
        })
    }

    /// The value of a field of a basic type; `None` if there is no such field, it is text,
    /// or the row is too short to hold it.
    pub fn get(&self, name: &str) -> Option<Scalar> {
        match self.index.get(name)? {
            Leaf::Value(at, p) => Scalar::decode(p, self.row.get(at..at + p.size())?),
            Leaf::Text(..) => None,
        }
    }

    /// The text of a `char[N]` field (up to its first zero byte, lossy UTF-8).
    pub fn text(&self, name: &str) -> Option<String> {
        match self.index.get(name)? {
            Leaf::Text(at, len) => {
                let bytes = self.row.get(at..at + len)?;
                let end = bytes.iter().position(|&b| b == 0).unwrap_or(len);
                Some(String::from_utf8_lossy(&bytes[..end]).into_owned())
            }
            Leaf::Value(..) => None,
        }
    }

    /// Writes a value of the field's own type.
    pub fn set(&mut self, name: &str, value: Scalar) -> Result<(), FieldError> {
        match self.leaf(name)? {
            Leaf::Value(at, p) if p == value.primitive() => {
                let mut bytes = Vec::with_capacity(8);
                crate::write::push_scalar(&mut bytes, value);
                if let Some(dst) = self.row.get_mut(at..at + bytes.len()) {
                    dst.copy_from_slice(&bytes);
                }
                Ok(())
            }
            leaf => Err(FieldError::Type {
                name: name.to_owned(),
                field: leaf_type(leaf),
                value: value.primitive().c_name(),
            }),
        }
    }

    /// Writes a number into a field of any numeric type that holds it: the nearest `f32`
    /// for `float`, the value for `double`, an integer type only an integral value in its
    /// range (and `bool` 0 or 1).
    pub fn set_f64(&mut self, name: &str, value: f64) -> Result<(), FieldError> {
        let leaf = self.leaf(name)?;
        let Leaf::Value(_, p) = leaf else {
            return Err(FieldError::Type {
                name: name.to_owned(),
                field: leaf_type(leaf),
                value: "double",
            });
        };
        let out_of_range = || FieldError::OutOfRange {
            name: name.to_owned(),
            field: p.c_name(),
            value,
        };
        let int = |lo: f64, hi: f64| {
            (value.fract() == 0.0 && value >= lo && value <= hi)
                .then_some(value)
                .ok_or_else(out_of_range)
        };
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let scalar = match p {
            Primitive::Float => Scalar::Float(value as f32),
            Primitive::Double => Scalar::Double(value),
            Primitive::Int8 => Scalar::Int8(int(-128.0, 127.0)? as i8),
            Primitive::UInt8 => Scalar::UInt8(int(0.0, 255.0)? as u8),
            Primitive::Int16 => Scalar::Int16(int(-32_768.0, 32_767.0)? as i16),
            Primitive::UInt16 => Scalar::UInt16(int(0.0, 65_535.0)? as u16),
            Primitive::Int32 => Scalar::Int32(int(-2_147_483_648.0, 2_147_483_647.0)? as i32),
            Primitive::UInt32 => Scalar::UInt32(int(0.0, 4_294_967_295.0)? as u32),
            // Every integral f64 below 2^63 (2^64) converts exactly.
            Primitive::Int64 => {
                Scalar::Int64(int(-9.223_372_036_854_776e18, 9.223_372_036_854_775e18)? as i64)
            }
            Primitive::UInt64 => Scalar::UInt64(int(0.0, 1.844_674_407_370_955e19)? as u64),
            Primitive::Bool => Scalar::Bool(int(0.0, 1.0)? == 1.0),
            Primitive::Char => {
                return Err(FieldError::Type {
                    name: name.to_owned(),
                    field: "char",
                    value: "double",
                });
            }
        };
        self.set(name, scalar)
    }

    /// Writes the text of a `char[N]` field, zero-filled after it.
    pub fn set_text(&mut self, name: &str, text: &str) -> Result<(), FieldError> {
        match self.leaf(name)? {
            Leaf::Text(at, len) => {
                if text.len() > len {
                    return Err(FieldError::TooLong {
                        name: name.to_owned(),
                        len,
                        bytes: text.len(),
                    });
                }
                if let Some(dst) = self.row.get_mut(at..at + len) {
                    dst.fill(0);
                    dst[..text.len()].copy_from_slice(text.as_bytes());
                }
                Ok(())
            }
            leaf => Err(FieldError::Type {
                name: name.to_owned(),
                field: leaf_type(leaf),
                value: "text",
            }),
        }
    }
}

fn leaf_type(leaf: Leaf) -> &'static str {
    match leaf {
        Leaf::Value(_, p) => p.c_name(),
        Leaf::Text(..) => "char[N]",
    }
}

/// Whether a typed format (or one it nests) has a widened field: its values cannot be
/// written back into a file whose type may be narrower.
pub(crate) fn widens(tf: &TypedFormat) -> bool {
    tf.fields.iter().any(|f| {
        f.widen
            || match f.kind {
                TypedKind::Nested(inner) => widens(inner),
                TypedKind::Primitive(_) => false,
            }
    })
}

/// Copies every field of `encoded` (a value of `tf` as `ULog::encode` lays it out) to
/// where `plan` says the file's layout has it in `row`: a struct read with fields left out,
/// reordered or nested written back into the row it came from, the other bytes kept.
pub(crate) fn scatter(tf: &TypedFormat, plan: &DecodePlan, encoded: &[u8], row: &mut [u8]) {
    let mut at = 0;
    for (i, field) in tf.fields.iter().enumerate() {
        let count = field.array_len.map_or(1, usize::from);
        let elem = crate::typed::kind_size(field.kind);
        let p = plan.field(i);
        if !field.padding && p.is_present() {
            for k in 0..count {
                let src = &encoded[at + k * elem..at + (k + 1) * elem];
                let dst = p.offset() + k * p.stride();
                match field.kind {
                    TypedKind::Primitive(_) => {
                        if let Some(d) = row.get_mut(dst..dst + elem) {
                            d.copy_from_slice(src);
                        }
                    }
                    TypedKind::Nested(inner) => {
                        if let Some(d) = row.get_mut(dst..) {
                            scatter(inner, p.nested_plan(), src, d);
                        }
                    }
                }
            }
        }
        at += count * elem;
    }
}
