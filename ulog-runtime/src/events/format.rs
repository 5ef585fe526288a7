//! Event arguments and messages as PX4's libevents formats them (the Python parser that
//! pyulog ships, `libevents_parse/parser.py`, rule for rule):
//!
//! - `{N}`: argument N (from 1) as Python's `str.format` shows it: integers in decimal,
//!   `float` as Python's `repr` of the value widened to a double
//!   ([`pytext::f64_text`](crate::pytext::f64_text)), enums as the description of their
//!   entry and bitfields as the descriptions of their bits joined by the separator (`|`),
//!   `(unknown: V)` for a value or bit no entry has; `{N:.K}` the number with K decimals
//!   (rounded half to even on its exact value); a unit after it (`{N:.1m}`, `m_v`, `m/s`,
//!   `m^2`, `C`) is appended after a space (`m_v` as `m`). A placeholder that does not parse
//!   or names no argument is kept as it is.
//! - `\x` is `x`, taken literally; `<param>P</param>` is `P` and `<a>C</a>` is `C` (both
//!   taken literally); `<profile name="dev">C</profile>` keeps `C` for the `dev` profile
//!   (`name="!dev"`: for all others), and `C` is formatted too; other tags are removed with
//!   their content; a `<` that starts no tag is kept.
//! - The result is stripped of whitespace at both ends, as Python's `str.strip` does.

use super::definitions::EnumDef;
use crate::pytext::f64_text;

/// An event argument's value, of its basic type.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ArgValue {
    /// `uint8_t`
    U8(u8),
    /// `int8_t`
    I8(i8),
    /// `uint16_t`
    U16(u16),
    /// `int16_t`
    I16(i16),
    /// `uint32_t`
    U32(u32),
    /// `int32_t`
    I32(i32),
    /// `uint64_t`
    U64(u64),
    /// `int64_t`
    I64(i64),
    /// `float`
    Float(f32),
}

impl ArgValue {
    /// The size of a basic type's values, `None` for a type that is not basic.
    pub fn size_of(ty: &str) -> Option<usize> {
        Some(match ty {
            "uint8_t" | "int8_t" => 1,
            "uint16_t" | "int16_t" => 2,
            "uint32_t" | "int32_t" | "float" => 4,
            "uint64_t" | "int64_t" => 8,
            _ => return None,
        })
    }

    /// A value of basic type `ty` from the start of `bytes` (little-endian).
    pub fn read(ty: &str, bytes: &[u8]) -> Option<ArgValue> {
        let b = bytes.get(..ArgValue::size_of(ty)?)?;
        Some(match ty {
            "uint8_t" => ArgValue::U8(b[0]),
            "int8_t" => ArgValue::I8(b[0] as i8),
            "uint16_t" => ArgValue::U16(u16::from_le_bytes(b.try_into().ok()?)),
            "int16_t" => ArgValue::I16(i16::from_le_bytes(b.try_into().ok()?)),
            "uint32_t" => ArgValue::U32(u32::from_le_bytes(b.try_into().ok()?)),
            "int32_t" => ArgValue::I32(i32::from_le_bytes(b.try_into().ok()?)),
            "uint64_t" => ArgValue::U64(u64::from_le_bytes(b.try_into().ok()?)),
            "int64_t" => ArgValue::I64(i64::from_le_bytes(b.try_into().ok()?)),
            "float" => ArgValue::Float(f32::from_le_bytes(b.try_into().ok()?)),
            _ => return None,
        })
    }

    /// The value as an integer, `None` for a float.
    pub fn as_int(self) -> Option<i128> {
        Some(match self {
            ArgValue::U8(v) => v.into(),
            ArgValue::I8(v) => v.into(),
            ArgValue::U16(v) => v.into(),
            ArgValue::I16(v) => v.into(),
            ArgValue::U32(v) => v.into(),
            ArgValue::I32(v) => v.into(),
            ArgValue::U64(v) => v.into(),
            ArgValue::I64(v) => v.into(),
            ArgValue::Float(_) => return None,
        })
    }

    /// The value as a double (as Python's `float()` makes one of an integer).
    pub fn as_f64(self) -> f64 {
        match self {
            ArgValue::Float(v) => f64::from(v),
            ArgValue::U64(v) => v as f64,
            ArgValue::I64(v) => v as f64,
            other => other.as_int().expect("an integer") as f64,
        }
    }
}

impl std::fmt::Display for ArgValue {
    /// As Python's `str.format("{}")` shows it.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.as_int() {
            Some(i) => write!(f, "{i}"),
            None => f.write_str(&f64_text(self.as_f64())),
        }
    }
}

/// Why a message could not be formatted (where the Python parser raises).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum FormatError {
    /// A number format (`{1:.2}`) for an enum's text.
    #[error(
        "argument {arg}: `{{{arg}:.{precision}}}` formats a number, and the argument is an enum"
    )]
    PrecisionOfEnum {
        /// The argument (from 1).
        arg: usize,
        /// The precision asked for.
        precision: usize,
    },
    /// A precision too large to print.
    #[error("argument {arg}: precision {precision} is more than 4096 digits")]
    Precision {
        /// The argument (from 1).
        arg: usize,
        /// The precision asked for.
        precision: usize,
    },
    /// An enum entry whose key is not an integer.
    #[error("enum entry `{0}` has a key that is not an integer")]
    EnumKey(String),
    /// An enum entry without a description.
    #[error("enum entry `{0}` has no description")]
    EnumDescription(String),
    /// A bitfield of values that are not integers.
    #[error("a bitfield of `float` values")]
    FloatBitfield,
}

/// An argument as formatting sees it: its value, and its enum if it has one.
pub type Arg<'a> = (ArgValue, Option<&'a EnumDef>);

/// An argument as a placeholder without precision shows it: the value, or its enum's text.
pub fn display_value(value: ArgValue, e: Option<&EnumDef>) -> Result<String, FormatError> {
    let Some(e) = e else {
        return Ok(value.to_string());
    };
    let entry = |wanted: i128| -> Result<Option<String>, FormatError> {
        for (key, name, description) in &e.entries {
            let Some(key) = *key else {
                return Err(FormatError::EnumKey(name.clone()));
            };
            if key == wanted {
                return description
                    .clone()
                    .map(Some)
                    .ok_or_else(|| FormatError::EnumDescription(name.clone()));
            }
        }
        Ok(None)
    };
    let Some(v) = value.as_int() else {
        if e.is_bitfield {
            return Err(FormatError::FloatBitfield);
        }
        // A float enum: entries compare by value.
        let x = value.as_f64();
        for (key, name, description) in &e.entries {
            let Some(key) = *key else {
                return Err(FormatError::EnumKey(name.clone()));
            };
            if key as f64 == x {
                return description
                    .clone()
                    .ok_or_else(|| FormatError::EnumDescription(name.clone()));
            }
        }
        return Ok(format!("(unknown: {value})"));
    };
    if !e.is_bitfield {
        return Ok(entry(v)?.unwrap_or_else(|| format!("(unknown: {value})")));
    }
    let bits = ArgValue::size_of(&e.base).unwrap_or(0) * 8;
    let mut out = String::new();
    let mut had_bit = false;
    for i in 0..bits.min(64) {
        let bit = 1i128 << i;
        if v & bit != 0 {
            if had_bit {
                out.push_str(&e.separator);
            }
            match entry(bit)? {
                Some(d) => out.push_str(&d),
                None => out.push_str(&format!("(unknown: {value})")),
            }
            had_bit = true;
        }
    }
    Ok(out)
}

/// Formats a message or description template with the event's arguments, for `profile`
/// (PX4's tools use `dev`). See the [module docs](self).
pub fn format_message(
    template: &str,
    args: &[Arg<'_>],
    profile: &str,
) -> Result<String, FormatError> {
    let mut msg: Vec<char> = template.chars().collect();
    let mut i = 0;
    while i < msg.len() {
        match msg[i] {
            '\\' => {
                // The backslash goes; the next character is taken as it is.
                msg.remove(i);
                i += 1;
            }
            '<' => {
                let Some(tag) = parse_tag(&msg[i..]) else {
                    i += 1;
                    continue;
                };
                let content_start = i + tag.content_start;
                let end_tag: Vec<char> = format!("</{}>", tag.name).chars().collect();
                let Some(end) = find(&msg, &end_tag, content_start) else {
                    i += 1;
                    continue;
                };
                let content: Vec<char> = msg[content_start..end].to_vec();
                let (replacement, skip) = match tag.name.as_str() {
                    "profile" => {
                        let name = tag.value.unwrap_or_default();
                        let remove = match name.strip_prefix('!') {
                            Some(not) => profile == not,
                            None => profile != name,
                        };
                        (if remove { Vec::new() } else { content }, 0)
                    }
                    "a" | "param" => {
                        let n = content.len();
                        (content, n)
                    }
                    _ => (Vec::new(), 0),
                };
                msg.splice(i..end + end_tag.len(), replacement);
                i += skip;
            }
            '{' => {
                let Some(close) = msg[i..].iter().position(|&c| c == '}').map(|p| i + p) else {
                    i += 1;
                    continue;
                };
                let spec: String = msg[i + 1..close].iter().collect();
                let Some(p) =
                    parse_placeholder(&spec).filter(|p| p.arg >= 1 && p.arg <= args.len())
                else {
                    i += 1;
                    continue;
                };
                let (value, e) = args[p.arg - 1];
                let mut text = match p.precision {
                    None => display_value(value, e)?,
                    Some(precision) if e.is_some() => {
                        return Err(FormatError::PrecisionOfEnum {
                            arg: p.arg,
                            precision,
                        });
                    }
                    Some(precision) if precision > 4096 => {
                        return Err(FormatError::Precision {
                            arg: p.arg,
                            precision,
                        });
                    }
                    Some(precision) => fixed(value.as_f64(), precision),
                };
                if let Some(unit) = p.unit {
                    text.push(' ');
                    text.push_str(if unit == "m_v" { "m" } else { unit });
                }
                let n = text.chars().count();
                msg.splice(i..=close, text.chars());
                i += n;
            }
            _ => i += 1,
        }
    }
    let out: String = msg.into_iter().collect();
    Ok(out.trim_matches(is_python_space).to_owned())
}

/// `x` with `precision` decimals as Python's `'{:.Nf}'` writes it.
fn fixed(x: f64, precision: usize) -> String {
    if x.is_nan() {
        "nan".to_owned()
    } else {
        // Rust rounds the exact value half to even, as Python does; infinities are `inf`.
        format!("{x:.precision$}")
    }
}

/// Python's `str.isspace`: Unicode whitespace and the separators `\x1c`..`\x1f`.
fn is_python_space(c: char) -> bool {
    c.is_whitespace() || ('\x1c'..='\x1f').contains(&c)
}

fn find(hay: &[char], needle: &[char], from: usize) -> Option<usize> {
    if from > hay.len() {
        return None;
    }
    hay[from..]
        .windows(needle.len())
        .position(|w| w == needle)
        .map(|p| from + p)
}

/// A tag at the start of `s`: `<name>` or `<name attr="value">`, followed by at least one
/// character (the regex `^<([a-z]+)(?: ([a-z]+)="([^"]*)")?>(.)`).
struct Tag {
    name: String,
    value: Option<String>,
    /// Where its content starts, from the `<`.
    content_start: usize,
}

fn parse_tag(s: &[char]) -> Option<Tag> {
    let lower = |c: &char| c.is_ascii_lowercase();
    let name_len = s.iter().skip(1).take_while(|c| lower(c)).count();
    if name_len == 0 {
        return None;
    }
    let name: String = s[1..=name_len].iter().collect();
    let after_name = 1 + name_len;
    // With an attribute, if one parses and `>` and a character follow it.
    if s.get(after_name) == Some(&' ') {
        let attr_start = after_name + 1;
        let attr_len = s[attr_start.min(s.len())..]
            .iter()
            .take_while(|c| lower(c))
            .count();
        let eq = attr_start + attr_len;
        if attr_len > 0 && s.get(eq) == Some(&'=') && s.get(eq + 1) == Some(&'"') {
            let value_start = eq + 2;
            if let Some(q) = s[value_start.min(s.len())..].iter().position(|&c| c == '"') {
                let close = value_start + q + 1;
                if s.get(close) == Some(&'>') && close + 1 < s.len() {
                    return Some(Tag {
                        name,
                        value: Some(s[value_start..value_start + q].iter().collect()),
                        content_start: close + 1,
                    });
                }
            }
        }
    }
    (s.get(after_name) == Some(&'>') && after_name + 1 < s.len()).then_some(Tag {
        name,
        value: None,
        content_start: after_name + 1,
    })
}

/// A placeholder's inside: `N`, `N:`, `N:.K`, each with an optional unit (the regex
/// `^(\d+)(?::(?:\.(\d+))?)?(m|m_v|m/s|m\^2|C)?$`).
struct Placeholder {
    arg: usize,
    precision: Option<usize>,
    unit: Option<&'static str>,
}

fn parse_placeholder(spec: &str) -> Option<Placeholder> {
    let digits = spec.bytes().take_while(u8::is_ascii_digit).count();
    if digits == 0 {
        return None;
    }
    // A number too large for an index names no argument.
    let arg = spec[..digits].parse::<usize>().unwrap_or(usize::MAX);
    let mut rest = &spec[digits..];
    let mut precision = None;
    if let Some(r) = rest.strip_prefix(':') {
        rest = r;
        if let Some(r) = r.strip_prefix('.') {
            let n = r.bytes().take_while(u8::is_ascii_digit).count();
            if n == 0 {
                // `:.` must have digits; without them the whole group is absent, and `:`
                // cannot stand before a `.`.
                return None;
            }
            precision = Some(r[..n].parse::<usize>().unwrap_or(usize::MAX));
            rest = &r[n..];
        }
    }
    let unit = match rest {
        "" => None,
        "m" => Some("m"),
        "m_v" => Some("m_v"),
        "m/s" => Some("m/s"),
        "m^2" => Some("m^2"),
        "C" => Some("C"),
        _ => return None,
    };
    Some(Placeholder {
        arg,
        precision,
        unit,
    })
}
