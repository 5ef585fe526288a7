//! The twelve basic ULog types: their C names, sizes and little-endian decoding.

use std::fmt;

/// One of the twelve basic types a ULog format field can have.
///
/// ```
/// use ulog_runtime::schema::Primitive;
/// let p = Primitive::from_c_name("uint16_t").unwrap();
/// assert_eq!((p, p.size(), p.c_name()), (Primitive::UInt16, 2, "uint16_t"));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Primitive {
    /// `int8_t`
    Int8,
    /// `uint8_t`
    UInt8,
    /// `int16_t`
    Int16,
    /// `uint16_t`
    UInt16,
    /// `int32_t`
    Int32,
    /// `uint32_t`
    UInt32,
    /// `int64_t`
    Int64,
    /// `uint64_t`
    UInt64,
    /// `float` (IEEE 754 binary32)
    Float,
    /// `double` (IEEE 754 binary64)
    Double,
    /// `bool` (one byte; any non-zero byte is true)
    Bool,
    /// `char` (one byte; arrays of it are strings)
    Char,
}

impl Primitive {
    /// All twelve primitives, in the order of the specification's table.
    pub const ALL: [Primitive; 12] = [
        Primitive::Int8,
        Primitive::UInt8,
        Primitive::Int16,
        Primitive::UInt16,
        Primitive::Int32,
        Primitive::UInt32,
        Primitive::Int64,
        Primitive::UInt64,
        Primitive::Float,
        Primitive::Double,
        Primitive::Bool,
        Primitive::Char,
    ];

    /// Size in bytes.
    pub const fn size(self) -> usize {
        match self {
            Primitive::Int8 | Primitive::UInt8 | Primitive::Bool | Primitive::Char => 1,
            Primitive::Int16 | Primitive::UInt16 => 2,
            Primitive::Int32 | Primitive::UInt32 | Primitive::Float => 4,
            Primitive::Int64 | Primitive::UInt64 | Primitive::Double => 8,
        }
    }

    /// The C name used in format strings, e.g. `uint64_t` or `float`.
    pub const fn c_name(self) -> &'static str {
        match self {
            Primitive::Int8 => "int8_t",
            Primitive::UInt8 => "uint8_t",
            Primitive::Int16 => "int16_t",
            Primitive::UInt16 => "uint16_t",
            Primitive::Int32 => "int32_t",
            Primitive::UInt32 => "uint32_t",
            Primitive::Int64 => "int64_t",
            Primitive::UInt64 => "uint64_t",
            Primitive::Float => "float",
            Primitive::Double => "double",
            Primitive::Bool => "bool",
            Primitive::Char => "char",
        }
    }

    /// The primitive with this C name, if any (case sensitive, as the format is).
    pub fn from_c_name(name: &str) -> Option<Primitive> {
        Primitive::ALL.into_iter().find(|p| p.c_name() == name)
    }

    /// Whether this is an unsigned integer type usable as a version-0 timestamp.
    pub const fn is_unsigned_integer(self) -> bool {
        matches!(
            self,
            Primitive::UInt8 | Primitive::UInt16 | Primitive::UInt32 | Primitive::UInt64
        )
    }
}

impl fmt::Display for Primitive {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.c_name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_follow_the_spec_table() {
        let expected = [
            ("int8_t", 1),
            ("uint8_t", 1),
            ("int16_t", 2),
            ("uint16_t", 2),
            ("int32_t", 4),
            ("uint32_t", 4),
            ("int64_t", 8),
            ("uint64_t", 8),
            ("float", 4),
            ("double", 8),
            ("bool", 1),
            ("char", 1),
        ];
        for (name, size) in expected {
            let p = Primitive::from_c_name(name).expect(name);
            assert_eq!(p.size(), size, "{name}");
            assert_eq!(p.to_string(), name);
        }
        assert_eq!(Primitive::from_c_name("Float"), None);
        assert_eq!(Primitive::from_c_name("uint128_t"), None);
    }
}
