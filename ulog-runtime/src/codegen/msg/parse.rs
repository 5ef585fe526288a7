//! The `.msg` grammar as PX4 writes it: field lines, fixed arrays, nested message types by
//! file name, constants, comments (which become docs) and `# TOPICS` lines.

use std::path::{Path, PathBuf};

use crate::schema::{Primitive, check_field_name, is_padding_name};

/// One `.msg` file, parsed.
#[derive(Debug, Clone, PartialEq)]
pub struct MsgFile {
    /// The file.
    pub path: PathBuf,
    /// The message type name: the file name without `.msg` (`VehicleAttitude`).
    pub type_name: String,
    /// The comment block that opens the file.
    pub doc: Option<String>,
    /// Fields in file order.
    pub fields: Vec<MsgField>,
    /// Constants in file order.
    pub constants: Vec<Constant>,
    /// The names of every `# TOPICS` line, in order (empty: one topic, the snake-case name).
    pub topics: Vec<String>,
}

/// One field line: `float32[4] q  # comment`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MsgField {
    /// The element type.
    pub ty: MsgType,
    /// `Some(N)` for `type[N]`.
    pub array_len: Option<u16>,
    /// The field name.
    pub name: String,
    /// The comment lines above it and its trailing comment.
    pub doc: Option<String>,
    /// 1-based line.
    pub line: usize,
}

/// A field's element type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MsgType {
    /// A built-in type.
    Primitive(Primitive),
    /// Another message, by its type (file) name: `EscReport`.
    Nested(String),
}

/// A constant line: `uint8 ARMING_STATE_ARMED = 2`.
#[derive(Debug, Clone, PartialEq)]
pub struct Constant {
    /// The type (built-in only).
    pub ty: Primitive,
    /// The name.
    pub name: String,
    /// The value, checked to fit the type.
    pub value: ConstValue,
    /// The value as written (`0x1F`).
    pub text: String,
    /// The comment lines above it and its trailing comment.
    pub doc: Option<String>,
    /// 1-based line.
    pub line: usize,
}

/// The value of a [`Constant`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ConstValue {
    /// An integer (any integer type, and `char`).
    Int(i128),
    /// A float (`float32`, `float64`).
    Float(f64),
    /// A bool.
    Bool(bool),
}

/// A line that does not follow the grammar.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct MsgError {
    /// 1-based line.
    pub(crate) line: usize,
    /// What is wrong.
    pub(crate) message: String,
}

/// The built-in `.msg` types and their ULog types.
pub fn builtin(name: &str) -> Option<Primitive> {
    Some(match name {
        "bool" => Primitive::Bool,
        "char" => Primitive::Char,
        "int8" => Primitive::Int8,
        "uint8" | "byte" => Primitive::UInt8,
        "int16" => Primitive::Int16,
        "uint16" => Primitive::UInt16,
        "int32" => Primitive::Int32,
        "uint32" => Primitive::UInt32,
        "int64" => Primitive::Int64,
        "uint64" => Primitive::UInt64,
        "float32" => Primitive::Float,
        "float64" => Primitive::Double,
        _ => return None,
    })
}

/// Parses the text of a `.msg` file (`path` names it in the result).
pub(crate) fn parse(path: &Path, text: &str) -> Result<MsgFile, MsgError> {
    let type_name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut file = MsgFile {
        path: path.to_owned(),
        type_name,
        doc: None,
        fields: Vec::new(),
        constants: Vec::new(),
        topics: Vec::new(),
    };
    // Comment lines waiting for the field or constant below them.
    let mut pending: Vec<String> = Vec::new();
    let mut at_top = true;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let (code, comment) = match raw.find('#') {
            Some(at) => (&raw[..at], Some(raw[at + 1..].trim())),
            None => (raw, None),
        };
        let code = code.trim();
        if code.is_empty() {
            match comment {
                Some(c) if topics_line(c).is_some() => {
                    let names = topics_line(c).expect("checked");
                    for name in names.split_whitespace() {
                        crate::schema::check_message_name(name, 0).map_err(|e| MsgError {
                            line,
                            message: format!(
                                "`# TOPICS` name `{name}` is not a topic name: {}",
                                e.kind
                            ),
                        })?;
                        if !file.topics.iter().any(|t| t == name) {
                            file.topics.push(name.to_owned());
                        }
                    }
                }
                Some(c) => pending.push(c.to_owned()),
                None => {
                    // A blank line ends a comment block: the first one documents the file.
                    if at_top && !pending.is_empty() {
                        file.doc = Some(pending.join("\n"));
                        at_top = false;
                    }
                    pending.clear();
                }
            }
            continue;
        }
        if at_top && !pending.is_empty() {
            file.doc = Some(pending.join("\n"));
            pending.clear();
        }
        at_top = false;
        let mut doc = std::mem::take(&mut pending);
        doc.extend(comment.filter(|c| !c.is_empty()).map(str::to_owned));
        let doc = (!doc.is_empty()).then(|| doc.join("\n"));
        let err = |message: String| MsgError { line, message };
        // `=` makes a constant, but not in `[<=N]` (a ROS bounded array, refused below).
        let equals = code
            .char_indices()
            .find(|&(i, c)| c == '=' && !code[..i].ends_with('<'))
            .map(|(i, _)| i);
        if let Some(at) = equals {
            let (left, value) = (&code[..at], &code[at + 1..]);
            let constant = parse_constant(left.trim(), value.trim(), doc, line).map_err(err)?;
            if file.constants.iter().any(|c| c.name == constant.name) {
                return Err(MsgError {
                    line,
                    message: format!("constant `{}` is defined twice", constant.name),
                });
            }
            file.constants.push(constant);
        } else {
            let field = parse_field(code, doc, line).map_err(err)?;
            if file.fields.iter().any(|f| f.name == field.name) {
                return Err(MsgError {
                    line,
                    message: format!("field `{}` is defined twice", field.name),
                });
            }
            file.fields.push(field);
        }
    }
    if at_top && !pending.is_empty() {
        file.doc = Some(pending.join("\n"));
    }
    Ok(file)
}

/// The names of a `# TOPICS a b c` comment (the text after `#`).
fn topics_line(comment: &str) -> Option<&str> {
    let rest = comment.strip_prefix("TOPICS")?;
    (rest.is_empty() || rest.starts_with(char::is_whitespace)).then_some(rest)
}

fn split_type_name(code: &str) -> Result<(&str, &str), String> {
    let mut words = code.split_whitespace();
    match (words.next(), words.next(), words.next()) {
        (Some(ty), Some(name), None) => Ok((ty, name)),
        _ => Err(format!(
            "`{code}` is neither a field (`type name`) nor a constant (`type NAME = value`)"
        )),
    }
}

fn parse_field(code: &str, doc: Option<String>, line: usize) -> Result<MsgField, String> {
    let (ty, name) = split_type_name(code)?;
    let (base, array_len) = match ty.split_once('[') {
        None => (ty, None),
        Some((base, rest)) => {
            let digits = rest
                .strip_suffix(']')
                .ok_or_else(|| format!("bad array length in `{ty}`: missing `]`"))?;
            if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
                return Err(format!(
                    "bad array length in `{ty}`: `{digits}` is not a number \
                     (PX4 messages have fixed-size arrays only)"
                ));
            }
            match digits.parse::<u16>() {
                Ok(n) if n >= 1 => (base, Some(n)),
                _ => {
                    return Err(format!(
                        "bad array length in `{ty}`: arrays have 1 to 65535 elements"
                    ));
                }
            }
        }
    };
    let ty = match builtin(base) {
        Some(p) => MsgType::Primitive(p),
        None if is_message_type_name(base) => MsgType::Nested(base.to_owned()),
        None => {
            return Err(format!(
                "unknown type `{base}`: not a built-in type (bool, char, int8..uint64, \
                 float32, float64) nor a message name"
            ));
        }
    };
    check_field_name(name, 0).map_err(|e| format!("bad field name `{name}`: {}", e.kind))?;
    if is_padding_name(name) {
        return Err(format!(
            "field `{name}`: names starting with `_padding` are PX4's padding, inserted by the layout"
        ));
    }
    Ok(MsgField {
        ty,
        array_len,
        name: name.to_owned(),
        doc,
        line,
    })
}

/// A message type name: a file name PX4 can generate a C++ type from (`EscReport`; ROS
/// types such as `string` are not PX4's).
fn is_message_type_name(name: &str) -> bool {
    name.starts_with(|c: char| c.is_ascii_uppercase())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

fn parse_constant(
    left: &str,
    value: &str,
    doc: Option<String>,
    line: usize,
) -> Result<Constant, String> {
    let (ty_name, name) = split_type_name(left)?;
    let ty = builtin(ty_name).ok_or_else(|| {
        format!("constant `{name}`: unknown type `{ty_name}` (constants have built-in types)")
    })?;
    if !name.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
        || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
    {
        return Err(format!("bad constant name `{name}`"));
    }
    let parsed =
        const_value(ty, value).map_err(|why| format!("constant `{name}`: `{value}` {why}"))?;
    Ok(Constant {
        ty,
        name: name.to_owned(),
        value: parsed,
        text: value.to_owned(),
        doc,
        line,
    })
}

/// The value of a constant of type `ty`, checked to fit it.
fn const_value(ty: Primitive, text: &str) -> Result<ConstValue, String> {
    match ty {
        Primitive::Bool => match text.to_ascii_lowercase().as_str() {
            "true" | "1" => Ok(ConstValue::Bool(true)),
            "false" | "0" => Ok(ConstValue::Bool(false)),
            _ => Err("is not a bool (true, false, 1, 0)".to_owned()),
        },
        Primitive::Float | Primitive::Double => {
            let v: f64 = text
                .parse()
                .ok()
                .or_else(|| parse_int(text).map(|i| i as f64))
                .ok_or_else(|| "is not a number".to_owned())?;
            if !v.is_finite() {
                return Err("is not a finite number".to_owned());
            }
            if ty == Primitive::Float && v.abs() > f64::from(f32::MAX) {
                return Err("does not fit float32".to_owned());
            }
            Ok(ConstValue::Float(v))
        }
        _ => {
            let v = parse_int(text).ok_or_else(|| "is not an integer".to_owned())?;
            let (min, max): (i128, i128) = match ty {
                Primitive::Int8 => (i8::MIN.into(), i8::MAX.into()),
                Primitive::UInt8 | Primitive::Char => (0, u8::MAX.into()),
                Primitive::Int16 => (i16::MIN.into(), i16::MAX.into()),
                Primitive::UInt16 => (0, u16::MAX.into()),
                Primitive::Int32 => (i32::MIN.into(), i32::MAX.into()),
                Primitive::UInt32 => (0, u32::MAX.into()),
                Primitive::Int64 => (i64::MIN.into(), i64::MAX.into()),
                _ => (0, u64::MAX.into()),
            };
            if !(min..=max).contains(&v) {
                let name = super::msg_type_name(ty);
                return Err(format!("does not fit {name} ({min}..={max})"));
            }
            Ok(ConstValue::Int(v))
        }
    }
}

/// Decimal or `0x` hexadecimal, optionally negative.
fn parse_int(text: &str) -> Option<i128> {
    let (negative, digits) = match text.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, text.strip_prefix('+').unwrap_or(text)),
    };
    let magnitude = match digits
        .strip_prefix("0x")
        .or_else(|| digits.strip_prefix("0X"))
    {
        Some(hex) if !hex.is_empty() => i128::from_str_radix(hex, 16).ok()?,
        Some(_) => return None,
        None if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) => {
            digits.parse().ok()?
        }
        None => return None,
    };
    Some(if negative { -magnitude } else { magnitude })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_text(text: &str) -> Result<MsgFile, MsgError> {
        parse(Path::new("msg/TestMessage.msg"), text)
    }

    #[test]
    fn fields_constants_topics_and_docs() {
        let f = parse_text(
            "# The file doc.\n# Second line.\n\nuint8 MODE_A = 0x1F # hex\nint8 LOW = -2\n\
             float32 SCALE = 1.5\nbool ON = true\n\n# Above the field.\nuint64 timestamp # µs\n\
             float32[4] q\nEscReport[8] esc # reports\n# TOPICS a b\n#TOPICS c\n",
        )
        .unwrap();
        assert_eq!(f.type_name, "TestMessage");
        assert_eq!(f.doc.as_deref(), Some("The file doc.\nSecond line."));
        assert_eq!(f.topics, ["a", "b", "c"]);
        let c: Vec<(&str, ConstValue)> = f
            .constants
            .iter()
            .map(|c| (c.name.as_str(), c.value))
            .collect();
        assert_eq!(
            c,
            [
                ("MODE_A", ConstValue::Int(31)),
                ("LOW", ConstValue::Int(-2)),
                ("SCALE", ConstValue::Float(1.5)),
                ("ON", ConstValue::Bool(true))
            ]
        );
        assert_eq!(f.constants[0].doc.as_deref(), Some("hex"));
        assert_eq!(f.fields[0].doc.as_deref(), Some("Above the field.\nµs"));
        assert_eq!(f.fields[0].line, 10);
        assert_eq!(f.fields[1].array_len, Some(4));
        assert_eq!(f.fields[2].ty, MsgType::Nested("EscReport".into()));
        assert_eq!(f.fields[2].doc.as_deref(), Some("reports"));
        // A comment with `=` after the `#` is not a constant.
        let f = parse_text("float32 scale # >= 1, or -1 if unknown\n").unwrap();
        assert_eq!((f.fields.len(), f.constants.len()), (1, 0));
    }

    #[test]
    fn errors_name_the_line_and_reason() {
        let cases = [
            (
                "uint64 timestamp\nstring name\n",
                2,
                "unknown type `string`",
            ),
            ("float32[0] q\n", 1, "arrays have 1 to 65535 elements"),
            ("float32[<=4] q\n", 1, "`<=4` is not a number"),
            ("float32[4 q\n", 1, "missing `]`"),
            ("uint8 a\nuint16 a\n", 2, "field `a` is defined twice"),
            (
                "uint8 X = 256\n",
                1,
                "constant `X`: `256` does not fit uint8 (0..=255)",
            ),
            ("int8 X = -129\n", 1, "does not fit int8"),
            ("uint16 X = -1\n", 1, "does not fit uint16"),
            ("bool X = 2\n", 1, "is not a bool"),
            ("float32 X = 1e39\n", 1, "does not fit float32"),
            ("uint8 X = 0xZZ\n", 1, "is not an integer"),
            (
                "uint8 X = 1\nuint8 X = 2\n",
                2,
                "constant `X` is defined twice",
            ),
            (
                "EscReport X = 1\n",
                1,
                "unknown type `EscReport` (constants have built-in types)",
            ),
            ("uint8 a b\n", 1, "is neither a field"),
            ("uint8 bad-name\n", 1, "bad field name `bad-name`"),
            ("uint8 _padding0\n", 1, "PX4's padding"),
            ("# TOPICS good bad!name\n", 1, "`# TOPICS` name `bad!name`"),
        ];
        for (text, line, message) in cases {
            let e = parse_text(text).unwrap_err();
            assert_eq!(e.line, line, "{text:?}: {e:?}");
            assert!(e.message.contains(message), "{text:?}: {}", e.message);
        }
    }
}
