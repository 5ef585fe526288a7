//! Lossless widening (`#[ulog(widen)]`): which file types a wider Rust field holds every
//! value of, and the loaders the decode plan keeps for them, chosen once per field by the
//! check so that rows are converted without branching on types.

use crate::schema::Primitive;

/// Reads the value at an offset of a row as `i64` (every integer a widened field accepts
/// fits: `uint64_t` only ever widens into `u64`, bit for bit).
pub(crate) type IntLoader = fn(&[u8], usize) -> i64;
/// Reads the value at an offset of a row as `f64` (exact for `float`, `double` and integers
/// of up to 32 bits, the only types a widened float field accepts).
pub(crate) type FloatLoader = fn(&[u8], usize) -> f64;

/// Whether a Rust field of type `rust` holds every value of the file type `file`:
/// - unsigned integers take unsigned integers of at most their size;
/// - signed integers take signed integers of at most their size and unsigned ones smaller
///   than them;
/// - `f64` takes `float` and integers of up to 32 bits, `f32` integers of up to 16 bits;
/// - anything else (signed into unsigned, `int64_t` into `f64`, `bool`, `char`) only itself.
pub const fn widens(file: Primitive, rust: Primitive) -> bool {
    use Primitive::*;
    if file as u8 == rust as u8 {
        return true;
    }
    let (fs, rs) = (file.size(), rust.size());
    match (kind(file), kind(rust)) {
        (Kind::Unsigned, Kind::Unsigned) | (Kind::Signed, Kind::Signed) => fs <= rs,
        (Kind::Unsigned, Kind::Signed) => fs < rs,
        (Kind::Unsigned | Kind::Signed, Kind::Float) => {
            fs <= if matches!(rust, Double) { 4 } else { 2 }
        }
        (Kind::Float, Kind::Float) => matches!((file, rust), (Float, Double)),
        _ => false,
    }
}

#[derive(Clone, Copy)]
enum Kind {
    Unsigned,
    Signed,
    Float,
    Other,
}

const fn kind(p: Primitive) -> Kind {
    use Primitive::*;
    match p {
        UInt8 | UInt16 | UInt32 | UInt64 => Kind::Unsigned,
        Int8 | Int16 | Int32 | Int64 => Kind::Signed,
        Float | Double => Kind::Float,
        Bool | Char => Kind::Other,
    }
}

/// The narrowest type every one of `types` widens into, if there is one (for merging the
/// formats of several logs into one Rust type).
pub fn common_type(types: &[Primitive]) -> Option<Primitive> {
    // Candidates from narrow to wide; the first that takes every type wins.
    const ORDER: [Primitive; 12] = [
        Primitive::Bool,
        Primitive::Char,
        Primitive::UInt8,
        Primitive::Int8,
        Primitive::UInt16,
        Primitive::Int16,
        Primitive::UInt32,
        Primitive::Int32,
        Primitive::Float,
        Primitive::UInt64,
        Primitive::Int64,
        Primitive::Double,
    ];
    ORDER
        .into_iter()
        .find(|&c| types.iter().all(|&t| widens(t, c)))
}

macro_rules! loaders {
    ($($prim:ident => $ty:ty),* $(,)?) => {
        /// The loaders for a file field of type `file`: as `i64` and as `f64`.
        pub(crate) fn loaders(file: Primitive) -> (IntLoader, FloatLoader) {
            match file {
                $(Primitive::$prim => (
                    |row, at| {
                        let bytes = row[at..at + size_of::<$ty>()].try_into().expect("sized");
                        #[allow(clippy::cast_possible_wrap, clippy::cast_possible_truncation)]
                        { <$ty>::from_le_bytes(bytes) as i64 }
                    },
                    |row, at| {
                        let bytes = row[at..at + size_of::<$ty>()].try_into().expect("sized");
                        #[allow(clippy::cast_precision_loss)]
                        { <$ty>::from_le_bytes(bytes) as f64 }
                    },
                ),)*
                Primitive::Bool | Primitive::Char => (|row, at| i64::from(row[at]), |row, at| f64::from(row[at])),
            }
        }
    };
}

loaders! {
    Int8 => i8, UInt8 => u8, Int16 => i16, UInt16 => u16, Int32 => i32, UInt32 => u32,
    Int64 => i64, UInt64 => u64, Float => f32, Double => f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use Primitive::*;

    #[test]
    fn widening_is_lossless_only() {
        for (file, rust) in [
            (UInt8, UInt32),
            (UInt8, Int16),
            (UInt16, Int32),
            (Int32, Int64),
            (UInt32, Int64),
            (Float, Double),
            (Int32, Double),
            (UInt32, Double),
            (Int16, Float),
            (UInt64, UInt64),
        ] {
            assert!(widens(file, rust), "{file} into {rust}");
        }
        for (file, rust) in [
            (Int8, UInt32),
            (UInt32, Int32),
            (UInt64, Int64),
            (Int64, Double),
            (Int32, Float),
            (Double, Float),
            (UInt16, UInt8),
            (Bool, UInt8),
            (UInt8, Bool),
            (Char, Int8),
            (Float, Int64),
        ] {
            assert!(!widens(file, rust), "{file} into {rust}");
        }
    }

    #[test]
    fn common_types_are_the_narrowest_that_hold_all() {
        assert_eq!(common_type(&[Int32, UInt8]), Some(Int32));
        assert_eq!(common_type(&[UInt32, Int32]), Some(Int64));
        assert_eq!(common_type(&[Float, UInt16]), Some(Float));
        assert_eq!(common_type(&[Float, Int32]), Some(Double));
        assert_eq!(common_type(&[UInt64, Int8]), None);
        assert_eq!(common_type(&[Double, Int64]), None);
        assert_eq!(common_type(&[Bool, UInt8]), None);
        assert_eq!(common_type(&[Char]), Some(Char));
        assert_eq!(common_type(&[UInt8, UInt8]), Some(UInt8));
    }

    #[test]
    fn loaders_read_the_file_type() {
        let row = [0xfe, 0xff, 0xff, 0xff, 0, 0, 0xc0, 0x3f];
        let (int, _) = loaders(Int32);
        assert_eq!(int(&row, 0), -2);
        let (int, _) = loaders(UInt32);
        assert_eq!(int(&row, 0), 0xffff_fffe);
        let (_, float) = loaders(Float);
        assert_eq!(float(&row, 4), 1.5);
        let (int, _) = loaders(UInt64);
        assert_eq!(int(&[0xff; 8], 0) as u64, u64::MAX);
    }
}
