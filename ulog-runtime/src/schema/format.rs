//! Format definitions (`F` messages): the `name:type field;type[N] field;` grammar, parsed into
//! [`Format`] and printed back canonically.

use std::fmt;

use super::Primitive;

/// Largest array length a field may declare: one element per byte of the largest message.
pub const MAX_ARRAY_LEN: u32 = u16::MAX as u32;

/// The type of a field: a basic type or the name of another format (nested use).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum TypeRef {
    /// One of the twelve basic types.
    Primitive(Primitive),
    /// Another format, by name; it may be defined before or after this use.
    Nested(String),
}

impl TypeRef {
    /// Interprets a type name: a C basic type name, otherwise a nested format name.
    pub fn from_name(name: &str) -> TypeRef {
        match Primitive::from_c_name(name) {
            Some(p) => TypeRef::Primitive(p),
            None => TypeRef::Nested(name.to_owned()),
        }
    }

    /// The name as written in a format string.
    pub fn name(&self) -> &str {
        match self {
            TypeRef::Primitive(p) => p.c_name(),
            TypeRef::Nested(n) => n,
        }
    }
}

impl fmt::Display for TypeRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One field of a format: `type name` or `type[N] name`.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Field {
    /// The element type.
    pub ty: TypeRef,
    /// `Some(N)` for a fixed array of `N` elements (`N >= 1` in formats).
    pub array_len: Option<u16>,
    /// The field name.
    pub name: String,
}

impl Field {
    /// Whether this is a padding field (`_padding*`): its bytes count, its value does not.
    pub fn is_padding(&self) -> bool {
        is_padding_name(&self.name)
    }

    /// Number of elements: the array length, or 1 for a scalar.
    pub fn count(&self) -> usize {
        self.array_len.map_or(1, usize::from)
    }

    /// Parses a single format field such as `float[4] q` (no trailing `;`).
    pub fn parse(s: &str) -> Result<Field, FormatError> {
        parse_field(s, 0, Syntax::Format)
    }

    /// Parses the key of an `I`, `M`, `P` or `Q` message: the field syntax, except that the
    /// length may be 0 (`char[0]`) and the name may hold any visible ASCII character, as PX4
    /// writes keys such as `perf_counter_preflight-00`.
    pub fn parse_key(s: &str) -> Result<Field, FormatError> {
        parse_field(s, 0, Syntax::Key)
    }
}

impl fmt::Display for Field {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.array_len {
            Some(n) => write!(f, "{}[{}] {}", self.ty, n, self.name),
            None => write!(f, "{} {}", self.ty, self.name),
        }
    }
}

/// Whether a field name marks padding.
pub fn is_padding_name(name: &str) -> bool {
    name.starts_with("_padding")
}

/// A named composite type, as defined by one `F` message.
///
/// ```
/// use ulog_runtime::schema::Format;
/// let f: Format = "vehicle_attitude:uint64_t timestamp;float[4] q;uint8_t[4] _padding0;"
///     .parse()
///     .unwrap();
/// assert_eq!(f.name, "vehicle_attitude");
/// assert_eq!(f.fields.len(), 3);
/// assert!(f.fields[2].is_padding());
/// assert_eq!(
///     f.to_string(),
///     "vehicle_attitude:uint64_t timestamp;float[4] q;uint8_t[4] _padding0;"
/// );
/// ```
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Format {
    /// The message name (`a-zA-Z0-9_-/`, not a basic type name).
    pub name: String,
    /// The fields in declaration order (at least one).
    pub fields: Vec<Field>,
}

impl Format {
    /// Parses `name:type field;type[N] field;`.
    pub fn parse(s: &str) -> Result<Format, FormatError> {
        let Some(colon) = s.find(':') else {
            return Err(FormatError::new(s.len(), FormatErrorKind::MissingColon));
        };
        let name = &s[..colon];
        check_message_name(name, 0)?;
        let mut fields: Vec<Field> = Vec::new();
        let mut pos = colon + 1;
        while pos < s.len() {
            let Some(rel) = s[pos..].find(';') else {
                return Err(FormatError::new(s.len(), FormatErrorKind::MissingSemicolon));
            };
            let field = parse_field(&s[pos..pos + rel], pos, Syntax::Format)?;
            if fields.iter().any(|f| f.name == field.name) {
                let name_pos = pos + rel - field.name.len();
                return Err(FormatError::new(
                    name_pos,
                    FormatErrorKind::DuplicateField(field.name),
                ));
            }
            fields.push(field);
            pos += rel + 1;
        }
        if fields.is_empty() {
            return Err(FormatError::new(s.len(), FormatErrorKind::NoFields));
        }
        Ok(Format {
            name: name.to_owned(),
            fields,
        })
    }

    /// Parses a format as a reader must take what writers produce: the grammar of
    /// [`Format::parse`], except that the message name may hold any character but `:`, a
    /// field name any but `;`, a type name any but ` ` and `[`, and empty fields (`;;`)
    /// are skipped, as pyulog takes them. Returns the format and, for each name outside the
    /// grammar, a note saying so; array lengths, missing names and duplicates are still
    /// errors.
    ///
    /// ```
    /// use ulog_runtime::schema::Format;
    /// assert!(Format::parse("gps.raw:uint64_t timestamp;").is_err());
    /// let (f, notes) = Format::parse_lax("gps.raw:uint64_t timestamp;float alt m;").unwrap();
    /// assert_eq!((f.name.as_str(), f.fields[1].name.as_str()), ("gps.raw", "alt m"));
    /// assert_eq!(notes.len(), 2);
    /// ```
    pub fn parse_lax(s: &str) -> Result<(Format, Vec<String>), FormatError> {
        let Some(colon) = s.find(':') else {
            return Err(FormatError::new(s.len(), FormatErrorKind::MissingColon));
        };
        let name = &s[..colon];
        if name.is_empty() {
            return Err(FormatError::new(0, FormatErrorKind::EmptyName));
        }
        let mut notes = Vec::new();
        if let Err(e) = check_message_name(name, 0) {
            notes.push(format!("message name `{name}`: {}", e.kind));
        }
        let mut fields: Vec<Field> = Vec::new();
        let mut pos = colon + 1;
        for part in s[colon + 1..].split(';') {
            let start = pos;
            pos += part.len() + 1;
            if part.is_empty() {
                continue;
            }
            let field = parse_field(part, start, Syntax::Lax)?;
            if let Err(e) = check_type_name(field.ty.name(), start) {
                notes.push(format!("type `{}`: {}", field.ty, e.kind));
            }
            if let Err(e) = check_field_name(&field.name, start) {
                notes.push(format!("field name `{}`: {}", field.name, e.kind));
            }
            if fields.iter().any(|f| f.name == field.name) {
                return Err(FormatError::new(
                    start,
                    FormatErrorKind::DuplicateField(field.name),
                ));
            }
            fields.push(field);
        }
        if fields.is_empty() {
            return Err(FormatError::new(s.len(), FormatErrorKind::NoFields));
        }
        Ok((
            Format {
                name: name.to_owned(),
                fields,
            },
            notes,
        ))
    }

    /// The field with this name.
    pub fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().find(|f| f.name == name)
    }

    /// Names of the formats this one uses as nested types, in field order (may repeat).
    pub fn nested_types(&self) -> impl Iterator<Item = &str> {
        self.fields.iter().filter_map(|f| match &f.ty {
            TypeRef::Nested(n) => Some(n.as_str()),
            TypeRef::Primitive(_) => None,
        })
    }
}

impl std::str::FromStr for Format {
    type Err = FormatError;
    fn from_str(s: &str) -> Result<Format, FormatError> {
        Format::parse(s)
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:", self.name)?;
        for field in &self.fields {
            write!(f, "{field};")?;
        }
        Ok(())
    }
}

/// A format string that does not follow the grammar: where (byte position) and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("at byte {pos}: {kind}")]
pub struct FormatError {
    /// Byte position in the parsed string.
    pub pos: usize,
    /// What is wrong.
    pub kind: FormatErrorKind,
}

impl FormatError {
    fn new(pos: usize, kind: FormatErrorKind) -> FormatError {
        FormatError { pos, kind }
    }
}

/// The reasons a format string is rejected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum FormatErrorKind {
    /// No `:` separates the message name from the fields.
    #[error("missing `:` after the message name")]
    MissingColon,
    /// The message name is empty.
    #[error("empty message name")]
    EmptyName,
    /// A message or type name has a character outside `a-zA-Z0-9_-/`.
    #[error("character {0:?} is not allowed in a message name (allowed: a-z A-Z 0-9 _ - /)")]
    InvalidNameChar(char),
    /// The message name is one of the basic types.
    #[error("message name `{0}` is a basic type name")]
    NameIsBasicType(String),
    /// The last field is not terminated by `;`.
    #[error("missing `;` after the last field")]
    MissingSemicolon,
    /// Two `;` with nothing between them.
    #[error("empty field")]
    EmptyField,
    /// The format has no fields.
    #[error("a format needs at least one field")]
    NoFields,
    /// A field has no type.
    #[error("empty type name")]
    EmptyType,
    /// An array length that is not a decimal number closed by `]`.
    #[error("bad array length: {0}")]
    BadArrayLength(&'static str),
    /// `[0]`.
    #[error("array length 0 (arrays have at least one element)")]
    ZeroArrayLength,
    /// An array length larger than any message.
    #[error("array length {0} exceeds {MAX_ARRAY_LEN}")]
    ArrayLengthTooLarge(String),
    /// No single space between type and field name.
    #[error("expected one space between the type and the field name")]
    MissingSpace,
    /// The field name is empty.
    #[error("empty field name")]
    EmptyFieldName,
    /// A field name has a character outside `a-zA-Z0-9_`.
    #[error("character {0:?} is not allowed in a field name (allowed: a-z A-Z 0-9 _)")]
    InvalidFieldNameChar(char),
    /// Two fields share a name.
    #[error("duplicate field name `{0}`")]
    DuplicateField(String),
}

/// Whether `c` may appear in a message (format) name.
pub fn is_message_name_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '/')
}

/// Whether `c` may appear in a field name.
pub fn is_field_name_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// Checks a message name; `base` is its byte position for error reports.
pub fn check_message_name(name: &str, base: usize) -> Result<(), FormatError> {
    if name.is_empty() {
        return Err(FormatError::new(base, FormatErrorKind::EmptyName));
    }
    check_type_name(name, base)?;
    if Primitive::from_c_name(name).is_some() {
        return Err(FormatError::new(
            base,
            FormatErrorKind::NameIsBasicType(name.to_owned()),
        ));
    }
    Ok(())
}

fn check_type_name(name: &str, base: usize) -> Result<(), FormatError> {
    if let Some((i, c)) = name.char_indices().find(|&(_, c)| !is_message_name_char(c)) {
        return Err(FormatError::new(
            base + i,
            FormatErrorKind::InvalidNameChar(c),
        ));
    }
    Ok(())
}

/// Checks a field name; `base` is its byte position for error reports.
pub fn check_field_name(name: &str, base: usize) -> Result<(), FormatError> {
    if name.is_empty() {
        return Err(FormatError::new(base, FormatErrorKind::EmptyFieldName));
    }
    if let Some((i, c)) = name.char_indices().find(|&(_, c)| !is_field_name_char(c)) {
        return Err(FormatError::new(
            base + i,
            FormatErrorKind::InvalidFieldNameChar(c),
        ));
    }
    Ok(())
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Syntax {
    Format,
    Key,
    /// What writers produce: any type and field name (checked, noted by the caller).
    Lax,
}

/// Parses `type name` / `type[N] name`; `base` is the byte position of `s` in the whole string.
fn parse_field(s: &str, base: usize, syntax: Syntax) -> Result<Field, FormatError> {
    if s.is_empty() {
        return Err(FormatError::new(base, FormatErrorKind::EmptyField));
    }
    let type_end = s.find(['[', ' ']).unwrap_or(s.len());
    let type_name = &s[..type_end];
    if type_name.is_empty() {
        return Err(FormatError::new(base, FormatErrorKind::EmptyType));
    }
    if syntax != Syntax::Lax {
        check_type_name(type_name, base)?;
    }
    let mut pos = type_end;
    let mut array_len = None;
    if s[pos..].starts_with('[') {
        let digits_start = pos + 1;
        let Some(close) = s[digits_start..].find(']') else {
            return Err(FormatError::new(
                base + pos,
                FormatErrorKind::BadArrayLength("missing `]`"),
            ));
        };
        let digits = &s[digits_start..digits_start + close];
        if digits.is_empty() {
            return Err(FormatError::new(
                base + digits_start,
                FormatErrorKind::BadArrayLength("no digits between `[` and `]`"),
            ));
        }
        if let Some((i, _)) = digits.char_indices().find(|(_, c)| !c.is_ascii_digit()) {
            return Err(FormatError::new(
                base + digits_start + i,
                FormatErrorKind::BadArrayLength("not a decimal number"),
            ));
        }
        let trimmed = digits.trim_start_matches('0');
        let len = if trimmed.len() > 5 {
            None
        } else {
            trimmed.parse::<u32>().ok().or(Some(0))
        };
        match len {
            Some(0) if syntax != Syntax::Key => {
                return Err(FormatError::new(
                    base + digits_start,
                    FormatErrorKind::ZeroArrayLength,
                ));
            }
            Some(n) if n <= MAX_ARRAY_LEN => array_len = Some(n as u16),
            _ => {
                return Err(FormatError::new(
                    base + digits_start,
                    FormatErrorKind::ArrayLengthTooLarge(digits.to_owned()),
                ));
            }
        }
        pos = digits_start + close + 1;
    }
    if !s[pos..].starts_with(' ') {
        return Err(FormatError::new(base + pos, FormatErrorKind::MissingSpace));
    }
    pos += 1;
    let name = &s[pos..];
    match syntax {
        Syntax::Format => check_field_name(name, base + pos)?,
        Syntax::Lax if name.is_empty() => {
            return Err(FormatError::new(
                base + pos,
                FormatErrorKind::EmptyFieldName,
            ));
        }
        Syntax::Lax => {}
        Syntax::Key => {
            if name.is_empty() {
                return Err(FormatError::new(
                    base + pos,
                    FormatErrorKind::EmptyFieldName,
                ));
            }
            if let Some((i, c)) = name.char_indices().find(|&(_, c)| !c.is_ascii_graphic()) {
                return Err(FormatError::new(
                    base + pos + i,
                    FormatErrorKind::InvalidFieldNameChar(c),
                ));
            }
        }
    }
    Ok(Field {
        ty: TypeRef::from_name(type_name),
        array_len,
        name: name.to_owned(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(s: &str) -> FormatError {
        Format::parse(s).expect_err(s)
    }

    #[test]
    fn parses_nested_arrays_and_padding() {
        let f = Format::parse("esc_status:uint64_t timestamp;uint8_t esc_count;esc_report[8] esc;uint8_t[3] _padding0;").unwrap();
        assert_eq!(f.name, "esc_status");
        assert_eq!(
            f.fields[2],
            Field {
                ty: TypeRef::Nested("esc_report".into()),
                array_len: Some(8),
                name: "esc".into()
            }
        );
        assert_eq!(f.fields[1].ty, TypeRef::Primitive(Primitive::UInt8));
        assert!(f.fields[3].is_padding());
        assert_eq!(f.nested_types().collect::<Vec<_>>(), ["esc_report"]);
    }

    #[test]
    fn print_then_parse_is_identity() {
        for s in [
            "a:bool b;",
            "x/y-z_1:char[10] name;double[2] d;int8_t _padding0;",
            "t:uint64_t timestamp;nested[65535] n;",
        ] {
            let f = Format::parse(s).unwrap();
            assert_eq!(f.to_string(), s);
            assert_eq!(Format::parse(&f.to_string()).unwrap(), f);
        }
    }

    #[test]
    fn rejections_name_the_position_and_reason() {
        let cases: &[(&str, usize, FormatErrorKind)] = &[
            ("no_colon", 8, FormatErrorKind::MissingColon),
            (":uint8_t a;", 0, FormatErrorKind::EmptyName),
            ("a b:uint8_t a;", 1, FormatErrorKind::InvalidNameChar(' ')),
            (
                "float:uint8_t a;",
                0,
                FormatErrorKind::NameIsBasicType("float".into()),
            ),
            ("m:uint8_t a", 11, FormatErrorKind::MissingSemicolon),
            ("m:uint8_t a;;", 12, FormatErrorKind::EmptyField),
            ("m:", 2, FormatErrorKind::NoFields),
            ("m: a;", 2, FormatErrorKind::EmptyType),
            (
                "m:uint8_t[] a;",
                10,
                FormatErrorKind::BadArrayLength("no digits between `[` and `]`"),
            ),
            (
                "m:uint8_t[x] a;",
                10,
                FormatErrorKind::BadArrayLength("not a decimal number"),
            ),
            (
                "m:uint8_t[3 a;",
                9,
                FormatErrorKind::BadArrayLength("missing `]`"),
            ),
            ("m:uint8_t[0] a;", 10, FormatErrorKind::ZeroArrayLength),
            (
                "m:uint8_t[65536] a;",
                10,
                FormatErrorKind::ArrayLengthTooLarge("65536".into()),
            ),
            (
                "m:uint8_t[99999999999999999999] a;",
                10,
                FormatErrorKind::ArrayLengthTooLarge("99999999999999999999".into()),
            ),
            ("m:uint8_t[2][3] a;", 12, FormatErrorKind::MissingSpace),
            ("m:uint8_t ;", 10, FormatErrorKind::EmptyFieldName),
            (
                "m:uint8_t  a;",
                10,
                FormatErrorKind::InvalidFieldNameChar(' '),
            ),
            (
                "m:uint8_t a-b;",
                11,
                FormatErrorKind::InvalidFieldNameChar('-'),
            ),
            (
                "m:uint8_t é;",
                10,
                FormatErrorKind::InvalidFieldNameChar('é'),
            ),
            ("m:ui.nt8_t a;", 4, FormatErrorKind::InvalidNameChar('.')),
            (
                "m:uint8_t a;float a;",
                18,
                FormatErrorKind::DuplicateField("a".into()),
            ),
        ];
        for (s, pos, kind) in cases {
            let e = err(s);
            assert_eq!((e.pos, &e.kind), (*pos, kind), "{s}");
        }
    }

    #[test]
    fn error_message_reads_well() {
        let e = err("m:uint8_t[0] a;");
        assert_eq!(
            e.to_string(),
            "at byte 10: array length 0 (arrays have at least one element)"
        );
    }

    #[test]
    fn info_keys_are_laxer_than_format_fields() {
        let f = Field::parse_key("char[0] sys_uuid").unwrap();
        assert_eq!(f.array_len, Some(0));
        assert!(Field::parse("char[0] sys_uuid").is_err());
        assert_eq!(
            Field::parse_key("uint32_t perf_counter_preflight-00")
                .unwrap()
                .name,
            "perf_counter_preflight-00"
        );
        assert!(Field::parse("uint32_t perf-counter").is_err());
        assert_eq!(Field::parse("int32_t[2] x").unwrap().count(), 2);
        assert!(Field::parse_key("int32_t").is_err());
        assert!(Field::parse_key("int32_t a b").is_err());
    }
}
