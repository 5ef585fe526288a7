//! A set of formats ([`Schema`]) and their resolved byte layouts ([`Layout`]): offsets, sizes,
//! nested types expanded, trailing padding known, cycles and unknown types reported.

use std::collections::HashMap;
use std::fmt;

use super::{Field, Format, Primitive, TypeRef};

/// Largest data payload a `D` message can carry (a `u16` size minus the 2-byte `msg_id`).
pub const MAX_DATA_SIZE: usize = u16::MAX as usize - 2;

/// Index of a format inside its [`Schema`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FormatId(pub(crate) u32);

impl FormatId {
    /// The position of the format in insertion order.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// What a field holds once resolved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldKind {
    /// A basic type.
    Primitive(Primitive),
    /// A nested format of the same schema.
    Nested(FormatId),
}

/// Where one field lives in a row.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FieldLayout {
    /// The field name.
    pub name: String,
    /// Byte offset from the start of the enclosing format.
    pub offset: usize,
    /// Element type.
    pub kind: FieldKind,
    /// `Some(N)` for arrays.
    pub array_len: Option<u16>,
    /// Size of one element in bytes (the nested format's full size for nested types).
    pub elem_size: usize,
    /// Whether the field is `_padding*`.
    pub padding: bool,
}

impl FieldLayout {
    /// Number of elements (1 for scalars).
    pub fn count(&self) -> usize {
        self.array_len.map_or(1, usize::from)
    }

    /// Total size in bytes.
    pub fn size(&self) -> usize {
        self.elem_size * self.count()
    }
}

/// The resolved byte layout of one format.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Layout {
    /// Full size in bytes, trailing padding included (the size when used nested).
    pub size: usize,
    /// Size without the trailing top-level `_padding*` fields: what `D` messages usually carry.
    pub payload_size: usize,
    /// One entry per field of the format, in declaration order.
    pub fields: Vec<FieldLayout>,
    /// Nesting depth: 1 for a format of basic types only, 1 + the deepest nested type otherwise.
    pub depth: usize,
}

impl Layout {
    /// Whether a `D` payload of `len` bytes is acceptable: anything from the size without
    /// trailing padding up to the full size.
    pub fn accepts_payload_len(&self, len: usize) -> bool {
        (self.payload_size..=self.size).contains(&len)
    }

    /// The field with this name.
    pub fn field(&self, name: &str) -> Option<&FieldLayout> {
        self.fields.iter().find(|f| f.name == name)
    }
}

/// Why a format has no layout.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum LayoutError {
    /// No format of this name exists.
    #[error("no format named `{0}`")]
    UnknownFormat(String),
    /// A field uses a type that is neither basic nor defined.
    #[error("{format}.{field}: type `{type_name}` is not a basic type and no format defines it")]
    UnknownType {
        /// The format with the bad field.
        format: String,
        /// The field.
        field: String,
        /// The undefined type.
        type_name: String,
    },
    /// Formats that contain each other.
    #[error("nested types form a cycle: {}", .0.join(" -> "))]
    Cycle(Vec<String>),
    /// The format is larger than one message can carry.
    #[error("{format} is {size} bytes, more than the {MAX_DATA_SIZE} bytes one message can carry")]
    TooLarge {
        /// The format.
        format: String,
        /// Its size (computed without overflow).
        size: u64,
    },
    /// A nested type that itself has no layout.
    #[error("{format}.{field}: nested type `{nested}` is invalid")]
    InvalidNested {
        /// The format.
        format: String,
        /// The field.
        field: String,
        /// The invalid nested format.
        nested: String,
    },
}

/// Two different definitions under one name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("format `{name}` is defined twice, differently: `{first}` and `{second}`")]
pub struct Redefinition {
    /// The name.
    pub name: String,
    /// The first definition, printed.
    pub first: String,
    /// The second definition, printed.
    pub second: String,
}

/// A set of formats with unique names, resolved into layouts on demand (and remembered).
///
/// ```
/// use ulog_runtime::schema::Schema;
/// let mut schema = Schema::new();
/// // Use before definition is allowed.
/// schema.insert("esc_status:uint64_t timestamp;esc_report[2] esc;uint8_t[3] _padding0;".parse().unwrap()).unwrap();
/// schema.insert("esc_report:int32_t esc_rpm;float esc_voltage;".parse().unwrap()).unwrap();
/// let layout = schema.layout_by_name("esc_status").unwrap();
/// assert_eq!((layout.size, layout.payload_size), (8 + 2 * 8 + 3, 8 + 2 * 8));
/// ```
#[derive(Debug, Clone, Default)]
pub struct Schema {
    formats: Vec<Format>,
    by_name: HashMap<String, FormatId>,
    layouts: Vec<Option<Result<Layout, LayoutError>>>,
}

impl Schema {
    /// An empty schema.
    pub fn new() -> Schema {
        Schema::default()
    }

    /// Adds a format. Defining the same format again is harmless and returns the existing id;
    /// a different definition under a known name is refused.
    pub fn insert(&mut self, format: Format) -> Result<FormatId, Redefinition> {
        if let Some(&id) = self.by_name.get(&format.name) {
            let existing = &self.formats[id.index()];
            if *existing == format {
                return Ok(id);
            }
            return Err(Redefinition {
                name: format.name.clone(),
                first: existing.to_string(),
                second: format.to_string(),
            });
        }
        let id = FormatId(u32::try_from(self.formats.len()).expect("fewer than 2^32 formats"));
        self.by_name.insert(format.name.clone(), id);
        self.formats.push(format);
        // A new name can complete formats that failed for lack of it.
        for slot in &mut self.layouts {
            if matches!(slot, Some(Err(_))) {
                *slot = None;
            }
        }
        self.layouts.push(None);
        Ok(id)
    }

    /// Number of formats.
    pub fn len(&self) -> usize {
        self.formats.len()
    }

    /// Whether there are no formats.
    pub fn is_empty(&self) -> bool {
        self.formats.is_empty()
    }

    /// Formats in insertion order.
    pub fn formats(&self) -> &[Format] {
        &self.formats
    }

    /// The id of the format with this name.
    pub fn id(&self, name: &str) -> Option<FormatId> {
        self.by_name.get(name).copied()
    }

    /// The format with this id.
    pub fn format(&self, id: FormatId) -> &Format {
        &self.formats[id.index()]
    }

    /// The format with this name.
    pub fn get(&self, name: &str) -> Option<&Format> {
        self.id(name).map(|id| self.format(id))
    }

    /// The names of formats closest to `name` (at most 3, closest first), for an error about
    /// a name the schema lacks.
    pub fn suggest(&self, name: &str) -> Vec<String> {
        super::suggest::closest_names(name, self.formats.iter().map(|f| f.name.as_str()))
    }

    /// The layout of a format, resolving it (and its nested types) if not done yet.
    pub fn layout(&mut self, id: FormatId) -> Result<&Layout, LayoutError> {
        if self.layouts[id.index()].is_none() {
            self.resolve(id);
        }
        match self.layouts[id.index()].as_ref() {
            Some(Ok(layout)) => Ok(layout),
            Some(Err(e)) => Err(e.clone()),
            None => unreachable!("resolve always fills the slot"),
        }
    }

    /// The layout of the format with this name.
    pub fn layout_by_name(&mut self, name: &str) -> Result<&Layout, LayoutError> {
        let id = self
            .id(name)
            .ok_or_else(|| LayoutError::UnknownFormat(name.to_owned()))?;
        self.layout(id)
    }

    /// The layout of a format already resolved by [`Schema::layout`] (directly or as a
    /// nested type of a resolved format); `None` otherwise.
    pub fn resolved(&self, id: FormatId) -> Option<&Layout> {
        self.layouts.get(id.index())?.as_ref()?.as_ref().ok()
    }

    /// Resolves every format; returns the errors by format name, in insertion order.
    pub fn resolve_all(&mut self) -> Vec<(String, LayoutError)> {
        let mut errors = Vec::new();
        for i in 0..self.formats.len() {
            let id = FormatId(i as u32);
            if let Err(e) = self.layout(id) {
                errors.push((self.formats[i].name.clone(), e));
            }
        }
        errors
    }

    /// Iterative depth-first resolution: a hostile file's nesting depth cannot exhaust the stack.
    fn resolve(&mut self, root: FormatId) {
        let mut on_stack = vec![false; self.formats.len()];
        let mut stack = vec![root];
        on_stack[root.index()] = true;
        while let Some(&top) = stack.last() {
            let mut next = None;
            let mut failure = None;
            for field in &self.formats[top.index()].fields {
                let TypeRef::Nested(type_name) = &field.ty else {
                    continue;
                };
                let Some(&dep) = self.by_name.get(type_name) else {
                    failure = Some(LayoutError::UnknownType {
                        format: self.formats[top.index()].name.clone(),
                        field: field.name.clone(),
                        type_name: type_name.clone(),
                    });
                    break;
                };
                if self.layouts[dep.index()].is_some() {
                    continue;
                }
                if on_stack[dep.index()] {
                    let from = stack.iter().position(|&s| s == dep).unwrap_or(0);
                    let mut path: Vec<String> = stack[from..]
                        .iter()
                        .map(|s| self.formats[s.index()].name.clone())
                        .collect();
                    path.push(type_name.clone());
                    // Every member of the cycle gets the same error.
                    for &member in &stack[from..] {
                        self.layouts[member.index()] = Some(Err(LayoutError::Cycle(path.clone())));
                        on_stack[member.index()] = false;
                    }
                    stack.truncate(from);
                    next = None;
                    failure = None;
                    break;
                }
                next = Some(dep);
                break;
            }
            if stack.last() != Some(&top) {
                continue; // a cycle was cut off the stack
            }
            if let Some(dep) = next {
                on_stack[dep.index()] = true;
                stack.push(dep);
                continue;
            }
            let result = match failure {
                Some(e) => Err(e),
                None => self.compute(top),
            };
            self.layouts[top.index()] = Some(result);
            on_stack[top.index()] = false;
            stack.pop();
        }
    }

    /// Computes the layout of a format whose nested types all have a result already.
    fn compute(&self, id: FormatId) -> Result<Layout, LayoutError> {
        let format = &self.formats[id.index()];
        let mut offset: u64 = 0;
        let mut depth = 1;
        let mut fields = Vec::with_capacity(format.fields.len());
        for field in &format.fields {
            let (kind, elem_size) = self.element(format, field)?;
            if let FieldKind::Nested(dep) = kind {
                depth = depth.max(1 + self.resolved(dep).map_or(0, |l| l.depth));
            }
            fields.push(FieldLayout {
                name: field.name.clone(),
                offset: offset as usize,
                kind,
                array_len: field.array_len,
                elem_size,
                padding: field.is_padding(),
            });
            // Each term is below 2^32, so the sum of at most 2^16 of them cannot overflow.
            offset += elem_size as u64 * field.count() as u64;
        }
        if offset > MAX_DATA_SIZE as u64 {
            return Err(LayoutError::TooLarge {
                format: format.name.clone(),
                size: offset,
            });
        }
        let size = offset as usize;
        let trailing: usize = fields
            .iter()
            .rev()
            .take_while(|f| f.padding)
            .map(FieldLayout::size)
            .sum();
        Ok(Layout {
            size,
            payload_size: size - trailing,
            fields,
            depth,
        })
    }

    fn element(&self, format: &Format, field: &Field) -> Result<(FieldKind, usize), LayoutError> {
        match &field.ty {
            TypeRef::Primitive(p) => Ok((FieldKind::Primitive(*p), p.size())),
            TypeRef::Nested(name) => {
                let dep = self.by_name[name];
                match &self.layouts[dep.index()] {
                    Some(Ok(l)) => Ok((FieldKind::Nested(dep), l.size)),
                    _ => Err(LayoutError::InvalidNested {
                        format: format.name.clone(),
                        field: field.name.clone(),
                        nested: name.clone(),
                    }),
                }
            }
        }
    }
}

impl fmt::Display for Schema {
    /// One format string per line, in insertion order.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for format in &self.formats {
            writeln!(f, "{format}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn schema(defs: &[&str]) -> Schema {
        let mut s = Schema::new();
        for d in defs {
            s.insert(d.parse().unwrap()).unwrap();
        }
        s
    }

    #[test]
    fn offsets_sizes_and_trailing_padding() {
        let mut s = schema(&[
            "outer:uint64_t timestamp;inner[2] a;uint8_t b;uint8_t[3] _padding0;",
            "inner:float x;uint8_t[2] _padding0;int16_t y;",
        ]);
        let inner = s.layout_by_name("inner").unwrap().clone();
        assert_eq!((inner.size, inner.payload_size), (8, 8));
        assert_eq!(
            inner.fields.iter().map(|f| f.offset).collect::<Vec<_>>(),
            [0, 4, 6]
        );
        let outer = s.layout_by_name("outer").unwrap();
        assert_eq!((outer.size, outer.payload_size), (28, 25));
        assert_eq!(outer.fields[1].offset, 8);
        assert_eq!(outer.fields[1].elem_size, 8);
        assert_eq!(outer.fields[2].offset, 24);
        assert!(outer.accepts_payload_len(25) && outer.accepts_payload_len(28));
        assert!(!outer.accepts_payload_len(24) && !outer.accepts_payload_len(29));
    }

    #[test]
    fn unknown_types_and_cycles_are_reported() {
        let mut s = schema(&["a:b x;", "b:c y;", "c:a z;", "d:nope n;", "e:d q;"]);
        let cycle = s.layout_by_name("a").unwrap_err();
        assert_eq!(
            cycle,
            LayoutError::Cycle(vec!["a".into(), "b".into(), "c".into(), "a".into()])
        );
        assert!(matches!(s.layout_by_name("b"), Err(LayoutError::Cycle(_))));
        assert_eq!(
            s.layout_by_name("d").unwrap_err().to_string(),
            "d.n: type `nope` is not a basic type and no format defines it"
        );
        assert!(matches!(
            s.layout_by_name("e"),
            Err(LayoutError::InvalidNested { .. })
        ));
        // Defining the missing type later completes the formats that needed it.
        s.insert("nope:uint8_t v;".parse().unwrap()).unwrap();
        assert_eq!(s.layout_by_name("e").unwrap().size, 1);
    }

    #[test]
    fn self_reference_is_a_cycle() {
        let mut s = schema(&["a:uint8_t v;a w;"]);
        assert_eq!(
            s.layout_by_name("a").unwrap_err(),
            LayoutError::Cycle(vec!["a".into(), "a".into()])
        );
    }

    #[test]
    fn oversized_formats_are_refused_without_overflow() {
        let mut s = schema(&[
            "big:uint64_t[65535] v;",
            "huge:big[65535] b;",
            "ok:uint8_t[65533] v;",
        ]);
        assert_eq!(
            s.layout_by_name("big").unwrap_err(),
            LayoutError::TooLarge {
                format: "big".into(),
                size: 8 * 65535
            }
        );
        assert!(matches!(
            s.layout_by_name("huge"),
            Err(LayoutError::InvalidNested { .. })
        ));
        assert_eq!(s.layout_by_name("ok").unwrap().size, MAX_DATA_SIZE);
    }

    #[test]
    fn deep_nesting_does_not_overflow_the_stack() {
        let mut s = Schema::new();
        for i in 0..20_000 {
            s.insert(format!("t{i}:t{} n;", i + 1).parse().unwrap())
                .unwrap();
        }
        s.insert("t20000:uint8_t v;".parse().unwrap()).unwrap();
        assert_eq!(s.layout_by_name("t0").unwrap().size, 1);
        assert_eq!(s.layout_by_name("t0").unwrap().depth, 20_001);
    }

    #[test]
    fn redefinition_is_refused_but_repetition_is_not() {
        let mut s = schema(&["a:uint8_t v;"]);
        assert_eq!(
            s.insert("a:uint8_t v;".parse().unwrap()).unwrap().index(),
            0
        );
        let e = s.insert("a:uint16_t v;".parse().unwrap()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "format `a` is defined twice, differently: `a:uint8_t v;` and `a:uint16_t v;`"
        );
    }
}
