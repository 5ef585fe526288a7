//! How two formats of one name differ, field by field: what one has and the other lacks,
//! types that changed, an order that changed, padding that moved.

use std::fmt;

use super::{Field, Format};

/// One difference between a first and a second format (see [`diff`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Difference {
    /// A field only the first has.
    OnlyInFirst(Field),
    /// A field only the second has.
    OnlyInSecond(Field),
    /// A field both have, with another type or array length.
    Retyped {
        /// The field.
        name: String,
        /// Its type in the first, as a format spells it (`float[4]`).
        first: String,
        /// Its type in the second.
        second: String,
    },
    /// The fields both have come in another order.
    Reordered {
        /// Their order in the first.
        first: Vec<String>,
        /// Their order in the second.
        second: Vec<String>,
    },
    /// The padding differs (count, sizes or places).
    Padding {
        /// The first's padding fields, each with the field it follows (`after timestamp`).
        first: Vec<String>,
        /// The second's.
        second: Vec<String>,
    },
}

/// Every difference between two formats, in the order above; empty when the fields are the
/// same (the names of the formats are not compared).
///
/// ```
/// use ulog_runtime::schema::{diff, Difference, Format};
/// let log: Format = "a:uint64_t timestamp;float x;uint8_t[4] _padding0;".parse().unwrap();
/// let msg: Format = "a:uint64_t timestamp;double x;".parse().unwrap();
/// let d = diff(&log, &msg);
/// assert!(matches!(&d[0], Difference::Retyped { name, .. } if name == "x"));
/// assert_eq!(d[0].describe("the log", "the .msg"), "field `x` is float in the log, double in the .msg");
/// ```
pub fn diff(first: &Format, second: &Format) -> Vec<Difference> {
    let data = |f: &Format| -> Vec<Field> {
        f.fields
            .iter()
            .filter(|x| !x.is_padding())
            .cloned()
            .collect()
    };
    let (a, b) = (data(first), data(second));
    let mut out = Vec::new();
    for f in &a {
        if !b.iter().any(|g| g.name == f.name) {
            out.push(Difference::OnlyInFirst(f.clone()));
        }
    }
    for g in &b {
        if !a.iter().any(|f| f.name == g.name) {
            out.push(Difference::OnlyInSecond(g.clone()));
        }
    }
    for f in &a {
        if let Some(g) = b.iter().find(|g| g.name == f.name)
            && (f.ty != g.ty || f.array_len != g.array_len)
        {
            out.push(Difference::Retyped {
                name: f.name.clone(),
                first: type_text(f),
                second: type_text(g),
            });
        }
    }
    let common = |x: &[Field], y: &[Field]| -> Vec<String> {
        x.iter()
            .filter(|f| y.iter().any(|g| g.name == f.name))
            .map(|f| f.name.clone())
            .collect()
    };
    let (order_a, order_b) = (common(&a, &b), common(&b, &a));
    if order_a != order_b {
        out.push(Difference::Reordered {
            first: order_a,
            second: order_b,
        });
    }
    let (pad_a, pad_b) = (padding(first), padding(second));
    if pad_a != pad_b {
        out.push(Difference::Padding {
            first: pad_a,
            second: pad_b,
        });
    }
    out
}

/// `float[4]`, `esc_report[8]`, `uint64_t`.
fn type_text(f: &Field) -> String {
    match f.array_len {
        Some(n) => format!("{}[{n}]", f.ty),
        None => f.ty.to_string(),
    }
}

/// Each padding field as `uint8_t[3] after esc_count`.
fn padding(format: &Format) -> Vec<String> {
    let mut last = "the start".to_owned();
    let mut out = Vec::new();
    for f in &format.fields {
        if f.is_padding() {
            out.push(format!("{} after {last}", type_text(f)));
        } else {
            last = format!("`{}`", f.name);
        }
    }
    out
}

impl Difference {
    /// A sentence naming the two formats `first` and `second` (e.g. "the log", "the .msg").
    pub fn describe(&self, first: &str, second: &str) -> String {
        let list = |v: &[String]| {
            if v.is_empty() {
                "none".to_owned()
            } else {
                v.join(", ")
            }
        };
        match self {
            Difference::OnlyInFirst(f) => format!("field `{f}` is in {first}, not in {second}"),
            Difference::OnlyInSecond(f) => format!("field `{f}` is in {second}, not in {first}"),
            Difference::Retyped {
                name,
                first: a,
                second: b,
            } => format!("field `{name}` is {a} in {first}, {b} in {second}"),
            Difference::Reordered {
                first: a,
                second: b,
            } => format!(
                "fields in another order: {} in {first}, {} in {second}",
                a.join(" "),
                b.join(" ")
            ),
            Difference::Padding {
                first: a,
                second: b,
            } => format!(
                "padding differs: {} in {first}; {} in {second}",
                list(a),
                list(b)
            ),
        }
    }
}

impl fmt::Display for Difference {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.describe("the first", "the second"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d(a: &str, b: &str) -> Vec<String> {
        diff(&a.parse().unwrap(), &b.parse().unwrap())
            .iter()
            .map(|d| d.describe("A", "B"))
            .collect()
    }

    #[test]
    fn every_kind_of_difference_is_named() {
        assert!(d("t:uint64_t timestamp;", "u:uint64_t timestamp;").is_empty());
        assert_eq!(
            d(
                "t:uint64_t timestamp;float x;uint8_t y;uint8_t[3] _padding0;",
                "t:uint64_t timestamp;uint8_t y;double x;int8_t z;"
            ),
            [
                "field `int8_t z` is in B, not in A",
                "field `x` is float in A, double in B",
                "fields in another order: timestamp x y in A, timestamp y x in B",
                "padding differs: uint8_t[3] after `y` in A; none in B",
            ]
        );
        assert_eq!(
            d("t:uint64_t timestamp;float[4] q;", "t:uint64_t timestamp;"),
            ["field `float[4] q` is in A, not in B"]
        );
    }
}
