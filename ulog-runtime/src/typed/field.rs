//! The Rust types a typed field may have, and how each maps to a ULog field type. This is the
//! only type table of the workspace: the derive refers to these impls and has none of its own.

use std::fmt;

use super::check::FieldPlan;
use super::{TypedKind, ULog};
use crate::schema::Primitive;

/// A `char[N]` field: text of at most `N` bytes, zero-filled after its end (ULog strings have
/// no terminator when they fill the array).
///
/// Made from text with `From<&str>`, which keeps what fits, cut at a character boundary, as
/// PX4 copies a string into a `char[N]` field; to refuse text that does not fit, use
/// `FromStr` (`"auto".parse()`, an error) or [`Chars::new`] (`None`). It prints as its text.
///
/// ```
/// use ulog_runtime::Chars;
/// let name: Chars<8> = Chars::new("rover").unwrap();
/// assert_eq!(name.as_str(), Ok("rover"));
/// assert_eq!(name.as_bytes(), b"rover\0\0\0");
/// assert!(Chars::<2>::new("rover").is_none());
///
/// let mode: Chars<8> = "auto".parse()?;
/// assert_eq!(mode.to_string(), "auto");
/// let checked = "mission".parse::<Chars<4>>();
/// assert_eq!(checked.unwrap_err().to_string(), "7 bytes of text do not fit in char[4]");
/// assert_eq!(Chars::<4>::from("mission").to_string(), "miss");
/// # Ok::<(), ulog_runtime::typed::CharsTooLong>(())
/// ```
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Chars<const N: usize>(pub [u8; N]);

impl<const N: usize> Chars<N> {
    /// The text, zero-filled to `N` bytes; `None` if it is longer than `N` bytes.
    pub fn new(text: &str) -> Option<Chars<N>> {
        let mut bytes = [0u8; N];
        bytes
            .get_mut(..text.len())?
            .copy_from_slice(text.as_bytes());
        Some(Chars(bytes))
    }

    /// All `N` bytes, the zero fill included.
    pub fn as_bytes(&self) -> &[u8; N] {
        &self.0
    }

    /// The bytes up to the first zero byte (all of them if there is none).
    pub fn text_bytes(&self) -> &[u8] {
        let end = self.0.iter().position(|&b| b == 0).unwrap_or(N);
        &self.0[..end]
    }

    /// The text up to the first zero byte, if it is UTF-8.
    pub fn as_str(&self) -> Result<&str, std::str::Utf8Error> {
        std::str::from_utf8(self.text_bytes())
    }

    /// The text up to the first zero byte, invalid UTF-8 replaced.
    pub fn to_string_lossy(&self) -> std::borrow::Cow<'_, str> {
        String::from_utf8_lossy(self.text_bytes())
    }
}

/// Text too long for a `char[N]` field ([`Chars`]'s `FromStr`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("{len} bytes of text do not fit in char[{capacity}]")]
pub struct CharsTooLong {
    /// Bytes of the text.
    pub len: usize,
    /// `N`.
    pub capacity: usize,
}

impl<const N: usize> std::str::FromStr for Chars<N> {
    type Err = CharsTooLong;
    fn from_str(text: &str) -> Result<Chars<N>, CharsTooLong> {
        Chars::new(text).ok_or(CharsTooLong {
            len: text.len(),
            capacity: N,
        })
    }
}

/// The text's first `N` bytes at most, cut at a character boundary (as PX4 fills a
/// `char[N]` field); `FromStr` refuses text that does not fit instead.
impl<const N: usize> From<&str> for Chars<N> {
    fn from(text: &str) -> Chars<N> {
        let mut end = text.len().min(N);
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        Chars::new(&text[..end]).expect("cut to fit")
    }
}

impl<const N: usize> Default for Chars<N> {
    fn default() -> Chars<N> {
        Chars([0; N])
    }
}

impl<const N: usize> fmt::Debug for Chars<N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(&*self.to_string_lossy(), f)
    }
}

impl<const N: usize> fmt::Display for Chars<N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.to_string_lossy())
    }
}

/// A single (non-array) ULog value: one of the 10 numeric types, `bool`, or a nested type
/// deriving [`ULog`]. Arrays `[T; N]` of these are fields too.
#[diagnostic::on_unimplemented(
    message = "`{Self}` cannot be an element of a ULog array",
    label = "not a ULog element type",
    note = "array elements are u8, i8, u16, i16, u32, i32, u64, i64, f32, f64, bool, `Char`, or a struct deriving `ULog`; arrays of arrays (multi-dimensional) do not exist in ULog: flatten them to one `[T; N]`"
)]
pub trait Element: Sized {
    /// The ULog type of one element.
    const KIND: TypedKind;
    /// Appends the packed little-endian encoding.
    fn encode_element(&self, out: &mut Vec<u8>);
    /// Decodes the element at `offset` of `row`; `plan` is the field's (its nested plan for
    /// nested types).
    fn decode_at(plan: &FieldPlan, row: &[u8], offset: usize) -> Self;
    /// Decodes the element of a `#[ulog(widen)]` field: the file's type may be narrower, and
    /// the plan's loader for it converts. Types that do not widen decode as usual.
    #[inline(always)]
    fn decode_at_widened(plan: &FieldPlan, row: &[u8], offset: usize) -> Self {
        Self::decode_at(plan, row, offset)
    }
}

/// A Rust type usable as a field of a `#[derive(ULog)]` struct.
#[diagnostic::on_unimplemented(
    message = "`{Self}` cannot be a ULog field",
    label = "not a ULog field type",
    note = "ULog fields are u8, i8, u16, i16, u32, i32, u64, i64, f32, f64, bool, `Char` (one char byte), `Chars<N>` (char[N] text), arrays `[T; N]` of those, structs deriving `ULog` and arrays of them, or `Option` of any of these but `Option` (a field the file may lack); arrays of arrays (multi-dimensional) do not exist in ULog: flatten them to one `[T; N]`"
)]
pub trait FieldValue: Sized {
    /// The ULog element type.
    const KIND: TypedKind;
    /// `Some(N)` for arrays (`[T; N]`, `Chars<N>`).
    const ARRAY_LEN: Option<u16>;
    /// Whether the field may be missing from a file (`Option<T>`).
    const OPTIONAL: bool = false;
    /// Appends the packed little-endian encoding.
    fn encode_field(&self, out: &mut Vec<u8>);
    /// Decodes the field from a row through its plan.
    fn decode_field(plan: &FieldPlan, row: &[u8]) -> Self;
    /// Decodes a `#[ulog(widen)]` field, whose file type may be narrower.
    #[inline(always)]
    fn decode_field_widened(plan: &FieldPlan, row: &[u8]) -> Self {
        Self::decode_field(plan, row)
    }
}

/// Reads `N` bytes at `offset`; the decode plan guarantees they are inside the row.
#[inline(always)]
fn bytes_at<const N: usize>(row: &[u8], offset: usize) -> [u8; N] {
    let mut out = [0u8; N];
    out.copy_from_slice(&row[offset..offset + N]);
    out
}

macro_rules! numeric_elements {
    ($($ty:ty => $prim:ident, $loader:ident),* $(,)?) => {$(
        // Not listed as "other types that implement `Element`" in errors: the trait's
        // note already names every field type.
        #[diagnostic::do_not_recommend]
        impl Element for $ty {
            const KIND: TypedKind = TypedKind::Primitive(Primitive::$prim);
            #[inline]
            fn encode_element(&self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
            #[inline(always)]
            fn decode_at(_: &FieldPlan, row: &[u8], offset: usize) -> $ty {
                <$ty>::from_le_bytes(bytes_at(row, offset))
            }
            /// The check accepted only file types whose every value this type holds, so the
            /// conversion is exact.
            #[inline(always)]
            #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
            fn decode_at_widened(plan: &FieldPlan, row: &[u8], offset: usize) -> $ty {
                plan.$loader(row, offset) as $ty
            }
        }
    )*};
}

numeric_elements! {
    u8 => UInt8, load_int, i8 => Int8, load_int, u16 => UInt16, load_int,
    i16 => Int16, load_int, u32 => UInt32, load_int, i32 => Int32, load_int,
    u64 => UInt64, load_int, i64 => Int64, load_int, f32 => Float, load_float,
    f64 => Double, load_float,
}

#[diagnostic::do_not_recommend]
impl Element for bool {
    const KIND: TypedKind = TypedKind::Primitive(Primitive::Bool);
    #[inline]
    fn encode_element(&self, out: &mut Vec<u8>) {
        out.push(u8::from(*self));
    }
    /// Any non-zero byte is `true`, as in C.
    #[inline(always)]
    fn decode_at(_: &FieldPlan, row: &[u8], offset: usize) -> bool {
        row[offset] != 0
    }
}

/// A single `char` field (`char c;`): one byte, not text. pyulog shows it as a signed byte;
/// [`Char::as_char`] gives the character of an ASCII byte. `char[N]` text is [`Chars<N>`].
///
/// ```
/// use ulog_runtime::{Char, ULog};
/// #[derive(ULog)]
/// struct Sample { timestamp: u64, mode: Char }
/// assert_eq!(Sample::FORMAT.to_format().to_string(), "sample:uint64_t timestamp;char mode;");
/// assert_eq!(Char(b'A').as_char(), Some('A'));
/// ```
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Char(pub u8);

impl Char {
    /// The character, if the byte is ASCII.
    pub fn as_char(self) -> Option<char> {
        self.0.is_ascii().then_some(char::from(self.0))
    }
}

impl fmt::Debug for Char {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.as_char() {
            Some(c) => write!(f, "Char({c:?})"),
            None => write!(f, "Char({:#04x})", self.0),
        }
    }
}

#[diagnostic::do_not_recommend]
impl Element for Char {
    const KIND: TypedKind = TypedKind::Primitive(Primitive::Char);
    #[inline]
    fn encode_element(&self, out: &mut Vec<u8>) {
        out.push(self.0);
    }
    #[inline(always)]
    fn decode_at(_: &FieldPlan, row: &[u8], offset: usize) -> Char {
        Char(row[offset])
    }
}

/// What `#[derive(ULog)]` implements to make a struct a nested element (its [`Element`]
/// impl is this blanket one). Through a blanket impl marked `do_not_recommend`, the user's
/// structs are never listed as "other types that implement `Element`" in errors, and the
/// derive's output needs no diagnostic attribute (which `#![no_implicit_prelude]` code
/// cannot name).
#[doc(hidden)]
pub trait DerivedElement: ULog {}

#[diagnostic::do_not_recommend]
impl<T: DerivedElement> Element for T {
    const KIND: TypedKind = TypedKind::Nested(&T::FORMAT);
    #[inline]
    fn encode_element(&self, out: &mut Vec<u8>) {
        self.encode(out);
    }
    #[inline]
    fn decode_at(plan: &FieldPlan, row: &[u8], offset: usize) -> T {
        T::decode(plan.nested_plan(), &row[offset..])
    }
}

#[diagnostic::do_not_recommend]
impl<E: Element> FieldValue for E {
    const KIND: TypedKind = E::KIND;
    const ARRAY_LEN: Option<u16> = None;
    #[inline]
    fn encode_field(&self, out: &mut Vec<u8>) {
        self.encode_element(out);
    }
    #[inline(always)]
    fn decode_field(plan: &FieldPlan, row: &[u8]) -> E {
        E::decode_at(plan, row, plan.offset())
    }
    #[inline(always)]
    fn decode_field_widened(plan: &FieldPlan, row: &[u8]) -> E {
        E::decode_at_widened(plan, row, plan.offset())
    }
}

/// `N` as an array length of a format; another `N` fails to compile.
const fn array_len(n: usize) -> u16 {
    assert!(
        n >= 1 && n <= u16::MAX as usize,
        "ULog array lengths are 1..=65535"
    );
    n as u16
}

#[diagnostic::do_not_recommend]
impl<E: Element, const N: usize> FieldValue for [E; N] {
    const KIND: TypedKind = E::KIND;
    const ARRAY_LEN: Option<u16> = Some(array_len(N));
    #[inline]
    fn encode_field(&self, out: &mut Vec<u8>) {
        for e in self {
            e.encode_element(out);
        }
    }
    #[inline]
    fn decode_field(plan: &FieldPlan, row: &[u8]) -> [E; N] {
        let (start, stride) = (plan.offset(), plan.stride());
        std::array::from_fn(|i| E::decode_at(plan, row, start + i * stride))
    }
    #[inline]
    fn decode_field_widened(plan: &FieldPlan, row: &[u8]) -> [E; N] {
        let (start, stride) = (plan.offset(), plan.stride());
        std::array::from_fn(|i| E::decode_at_widened(plan, row, start + i * stride))
    }
}

#[diagnostic::do_not_recommend]
impl<const N: usize> FieldValue for Chars<N> {
    const KIND: TypedKind = TypedKind::Primitive(Primitive::Char);
    const ARRAY_LEN: Option<u16> = Some(array_len(N));
    #[inline]
    fn encode_field(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.0);
    }
    #[inline]
    fn decode_field(plan: &FieldPlan, row: &[u8]) -> Chars<N> {
        Chars(bytes_at(row, plan.offset()))
    }
}

/// A field type an `Option` field may hold: every [`FieldValue`] but an `Option` itself.
/// `Option<Option<T>>` has no form in a file (a field is there or not), so it does not
/// compile (`cannot be a ULog field`): its inner `None` would be written as zeros and read
/// back as `Some(Some(0))`.
pub trait RequiredField: FieldValue {}

#[diagnostic::do_not_recommend]
impl<E: Element> RequiredField for E {}

#[diagnostic::do_not_recommend]
impl<E: Element, const N: usize> RequiredField for [E; N] {}

#[diagnostic::do_not_recommend]
impl<const N: usize> RequiredField for Chars<N> {}

/// A field a file may lack: `None` when the file's format has no field of that name.
/// Writing `None` writes zeros.
#[diagnostic::do_not_recommend]
impl<F: RequiredField> FieldValue for Option<F> {
    const KIND: TypedKind = F::KIND;
    const ARRAY_LEN: Option<u16> = F::ARRAY_LEN;
    const OPTIONAL: bool = true;
    fn encode_field(&self, out: &mut Vec<u8>) {
        match self {
            Some(v) => v.encode_field(out),
            None => {
                let size = super::kind_size(F::KIND) * F::ARRAY_LEN.map_or(1, usize::from);
                out.resize(out.len() + size, 0);
            }
        }
    }
    #[inline]
    fn decode_field(plan: &FieldPlan, row: &[u8]) -> Option<F> {
        plan.is_present().then(|| F::decode_field(plan, row))
    }
    #[inline]
    fn decode_field_widened(plan: &FieldPlan, row: &[u8]) -> Option<F> {
        plan.is_present()
            .then(|| F::decode_field_widened(plan, row))
    }
}

/// A padding field, `[u8; N]`: written as zeros, never read.
#[diagnostic::on_unimplemented(
    message = "a `#[ulog(padding)]` field must be a byte array `[u8; N]`, not `{Self}`",
    label = "not `[u8; N]`"
)]
pub trait Padding: Sized {
    /// Its length in bytes.
    const LEN: u16;
    /// The value a decoded struct holds.
    const ZERO: Self;
}

#[diagnostic::do_not_recommend]
impl<const N: usize> Padding for [u8; N] {
    const LEN: u16 = array_len(N);
    const ZERO: [u8; N] = [0; N];
}
