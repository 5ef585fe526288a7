//! PX4's layout of a `.msg` file as its generator makes it, and so as its logger writes the
//! `F` format: fields sorted by the size of their basic type (largest first, file order
//! among equal sizes, nested messages last), `uint8_t[k] _paddingN` before each nested field
//! and at the end to align to 8 bytes.

use std::collections::HashMap;

use super::parse::{MsgFile, MsgType};
use crate::schema::{Field, Format, TypeRef};

/// PX4 aligns every message to its 64-bit timestamp.
const ALIGN: usize = 8;

/// The snake-case name PX4 gives a message type (`EscReport` -> `esc_report`): its nested
/// format name and, without `# TOPICS`, its topic name.
pub fn snake_case(type_name: &str) -> String {
    // As PX4's generator: `(.)([A-Z][a-z]+)` -> `\1_\2`, then `([a-z0-9])([A-Z])` -> `\1_\2`.
    let chars: Vec<char> = type_name.chars().collect();
    let mut out = String::with_capacity(type_name.len() + 4);
    for (i, &c) in chars.iter().enumerate() {
        if i > 0 && c.is_ascii_uppercase() {
            let prev = chars[i - 1];
            let starts_word = chars.get(i + 1).is_some_and(char::is_ascii_lowercase);
            if prev.is_ascii_lowercase() || prev.is_ascii_digit() || starts_word {
                out.push('_');
            }
        }
        out.push(c.to_ascii_lowercase());
    }
    out
}

/// Why a set of `.msg` files cannot be laid out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum LayoutProblem {
    /// `files[file].fields[field]` names a type no file and no other input defines.
    Unknown { file: usize, field: usize },
    /// The files (indices) nest each other, in this order.
    Cycle(Vec<(usize, usize)>),
}

/// Lays out every file; nested types are looked up among `files` by type name, then among
/// `external` formats (other inputs) by their snake-case name, with their sizes.
pub(crate) fn layout_all(
    files: &[MsgFile],
    external: &dyn Fn(&str) -> Option<usize>,
) -> Result<Vec<Format>, LayoutProblem> {
    let by_type: HashMap<&str, usize> = files
        .iter()
        .enumerate()
        .map(|(i, f)| (f.type_name.as_str(), i))
        .collect();
    let mut done: Vec<Option<(Format, usize)>> = vec![None; files.len()];
    for root in 0..files.len() {
        // Depth-first, iteratively: a stack of (file, its nested files still to lay out).
        let mut stack: Vec<usize> = vec![root];
        while let Some(&top) = stack.last() {
            if done[top].is_some() {
                stack.pop();
                continue;
            }
            let missing = files[top]
                .fields
                .iter()
                .enumerate()
                .find_map(|(k, f)| match &f.ty {
                    MsgType::Nested(name) => match by_type.get(name.as_str()) {
                        Some(&dep) if done[dep].is_none() => Some(Ok((k, dep))),
                        Some(_) => None,
                        None if external(&snake_case(name)).is_some() => None,
                        None => Some(Err(k)),
                    },
                    MsgType::Primitive(_) => None,
                });
            match missing {
                Some(Err(field)) => return Err(LayoutProblem::Unknown { file: top, field }),
                Some(Ok((field, dep))) => {
                    if let Some(at) = stack.iter().position(|&s| s == dep) {
                        let mut cycle: Vec<(usize, usize)> = stack[at..]
                            .windows(2)
                            .map(|w| (w[0], nested_field(&files[w[0]], &files[w[1]].type_name)))
                            .collect();
                        cycle.push((top, field));
                        return Err(LayoutProblem::Cycle(cycle));
                    }
                    stack.push(dep);
                }
                None => {
                    let size_of = |name: &str| match by_type.get(name) {
                        Some(&dep) => done[dep].as_ref().map(|(_, size)| *size),
                        None => external(&snake_case(name)),
                    };
                    done[top] = Some(layout_one(&files[top], &size_of));
                    stack.pop();
                }
            }
        }
    }
    Ok(done
        .into_iter()
        .map(|d| d.expect("every file laid out").0)
        .collect())
}

/// The first field of `file` of type `name`.
fn nested_field(file: &MsgFile, name: &str) -> usize {
    file.fields
        .iter()
        .position(|f| f.ty == MsgType::Nested(name.to_owned()))
        .unwrap_or(0)
}

/// One file's format and full size; every nested type's size is known.
fn layout_one(file: &MsgFile, size_of: &dyn Fn(&str) -> Option<usize>) -> (Format, usize) {
    let sort_size = |ty: &MsgType| match ty {
        MsgType::Primitive(p) => p.size(),
        MsgType::Nested(_) => 0,
    };
    let mut sorted: Vec<_> = file.fields.iter().collect();
    // Stable: equal sizes keep their file order.
    sorted.sort_by_key(|f| std::cmp::Reverse(sort_size(&f.ty)));
    let mut fields = Vec::with_capacity(sorted.len() + 2);
    let mut size = 0usize;
    let mut padding = 0;
    let mut pad = |size: &mut usize, fields: &mut Vec<Field>| {
        let k = (ALIGN - *size % ALIGN) % ALIGN;
        if k > 0 {
            fields.push(Field {
                ty: TypeRef::Primitive(crate::schema::Primitive::UInt8),
                array_len: Some(k as u16),
                name: format!("_padding{padding}"),
            });
            padding += 1;
            *size += k;
        }
    };
    for f in sorted {
        let count = f.array_len.map_or(1, usize::from);
        let ty = match &f.ty {
            MsgType::Primitive(p) => {
                size += p.size() * count;
                TypeRef::Primitive(*p)
            }
            MsgType::Nested(name) => {
                pad(&mut size, &mut fields);
                size += size_of(name).expect("nested types are laid out first") * count;
                TypeRef::Nested(snake_case(name))
            }
        };
        fields.push(Field {
            ty,
            array_len: f.array_len,
            name: f.name.clone(),
        });
    }
    pad(&mut size, &mut fields);
    let format = Format {
        name: snake_case(&file.type_name),
        fields,
    };
    (format, size)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn snake_case_follows_px4() {
        for (camel, snake) in [
            ("EscReport", "esc_report"),
            ("Px4ioStatus", "px4io_status"),
            ("VehicleGlobalPosition", "vehicle_global_position"),
            ("GPSPosition", "gps_position"),
            ("SensorGps", "sensor_gps"),
            ("Cpuload", "cpuload"),
        ] {
            assert_eq!(snake_case(camel), snake);
        }
    }

    fn file(name: &str, text: &str) -> MsgFile {
        super::super::parse::parse(Path::new(&format!("{name}.msg")), text).unwrap()
    }

    #[test]
    fn sorted_by_size_padded_before_nested_and_at_the_end() {
        let files = [
            file(
                "Outer",
                "uint8 count\nuint64 timestamp\nInner[2] items\nuint16 flags\nbool ok\nInner one\n",
            ),
            file("Inner", "uint8 a\nuint32 b\n"),
        ];
        let formats = layout_all(&files, &|_| None).unwrap();
        assert_eq!(
            formats[1].to_string(),
            "inner:uint32_t b;uint8_t a;uint8_t[3] _padding0;"
        );
        assert_eq!(
            formats[0].to_string(),
            "outer:uint64_t timestamp;uint16_t flags;uint8_t count;bool ok;uint8_t[4] _padding0;\
             inner[2] items;inner one;"
        );
        // An external nested type whose size is not a multiple of 8 shifts what follows.
        let files = [file("Uses", "uint64 timestamp\nOdd a\nOdd b\n")];
        let formats = layout_all(&files, &|n| (n == "odd").then_some(3)).unwrap();
        assert_eq!(
            formats[0].to_string(),
            "uses:uint64_t timestamp;odd a;uint8_t[5] _padding0;odd b;uint8_t[5] _padding1;"
        );
    }

    #[test]
    fn unknown_types_and_cycles_are_found() {
        let files = [file("A", "uint64 timestamp\nMissing m\n")];
        assert_eq!(
            layout_all(&files, &|_| None),
            Err(LayoutProblem::Unknown { file: 0, field: 1 })
        );
        let files = [
            file("A", "uint64 timestamp\nB b\n"),
            file("B", "uint8 x\nC c\n"),
            file("C", "A a\n"),
        ];
        assert_eq!(
            layout_all(&files, &|_| None),
            Err(LayoutProblem::Cycle(vec![(0, 1), (1, 1), (2, 0)]))
        );
    }
}
