//! What pyulog's command-line tools compute, as library calls with their output byte for
//! byte (the `ulog` verbs print these):
//!
//! - [`params`]: `ulog_params`' three formats (csv, octave, qgc);
//! - [`multi_info_text`]: `ulog_info -m NAME`, one multi info value as pyulog prints it;
//! - [`kml`]: `ulog2kml`, the GPS track colored by flight mode, as simplekml writes it;
//! - [`gps_dump`]: `ulog_extract_gps_dump`, the raw bytes a GPS receiver exchanged.
//!
//! [`pyulog_warnings`]: what pyulog prints while it reads. `ulog_messages` is
//! [`events::messages`](crate::events::messages) (feature `events`);
//! `ulog2csv` is [`columns::csv`](crate::columns::csv).

mod gps_dump;
mod kml;
mod params;

pub use gps_dump::{GpsDump, GpsDumpError, gps_dump};
pub use kml::{KmlError, KmlOptions, kml};
pub use params::{DefaultKind, ParamsError, ParamsFormat, ParamsOptions, param_text, params};

use crate::read::{Log, Metadata};
use crate::{DiagnosticKind, Value};

/// What pyulog prints on stdout while it reads a log, before any tool's output: `Warning:
/// unknown file version. Will attempt to read it anyway` for a version above 1, and
/// `Warning: no subscription found for message id N. Continuing, but file is most likely
/// corrupt` once per `msg_id` that data came for with no subscription. (The `ulog` verbs
/// that mirror a pyulog tool print them first, as it does.)
pub fn pyulog_warnings(log: &Log<'_>) -> Vec<String> {
    let mut out = Vec::new();
    if log.header().version > 1 {
        out.push("Warning: unknown file version. Will attempt to read it anyway".to_owned());
    }
    let mut warned = std::collections::HashSet::new();
    for d in log.diagnostics() {
        if let DiagnosticKind::UnknownMsgId { msg_id } = d.kind
            && warned.insert(msg_id)
        {
            out.push(format!(
                "Warning: no subscription found for message id {msg_id}. Continuing, but file is most likely corrupt"
            ));
        }
    }
    out
}

/// `ulog_info -m NAME`: each value of multi info `name` (a value and its continuations),
/// as pyulog prints it: `# NAME i (len: N):` and the bytes in hexadecimal for binary values,
/// `# NAME i:` and the text for text values; the parts joined by a newline if `newline`
/// (`-n`), else directly. `None` if the log has no such multi info (pyulog prints
/// `message NAME not found`).
///
/// ```
/// use ulog_runtime::{Log, Value, Writer, WriterOptions};
/// let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
/// w.multi_info("boot", &Value::String("line 1\n".into()), false)?;
/// w.multi_info("boot", &Value::String("line 2".into()), true)?;
/// let log = Log::from_vec(w.into_inner())?;
/// let text = ulog_runtime::tools::multi_info_text(log.metadata(), "boot", false).unwrap();
/// assert_eq!(text, "# boot 0:\nline 1\nline 2\n");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn multi_info_text(meta: &Metadata, name: &str, newline: bool) -> Option<String> {
    let m = meta.multi_info().iter().find(|m| m.key == name)?;
    let separator = if newline { "\n" } else { "" };
    // pyulog reads `char[N]` values as text, basic scalars as numbers, anything else (an
    // array of bytes or numbers) as its bytes.
    let text = m.type_name.starts_with("char[");
    let scalar = crate::schema::Primitive::from_c_name(&m.type_name).is_some();
    let mut out = String::new();
    for (i, (parts, values)) in m.raw.iter().zip(&m.values).enumerate() {
        if text {
            out.push_str(&format!("# {name} {i}:\n"));
            let texts: Vec<String> = parts.iter().map(|p| crate::read::text_of(p).0).collect();
            out.push_str(&texts.join(separator));
        } else if scalar {
            out.push_str(&format!("# {name} {i}:\n"));
            let texts: Vec<String> = values.iter().map(python_str).collect();
            out.push_str(&texts.join(separator));
        } else {
            let len: usize = parts.iter().map(Vec::len).sum();
            out.push_str(&format!("# {name} {i} (len: {len}):\n"));
            let hex: Vec<String> = parts
                .iter()
                .map(|p| {
                    p.iter()
                        .map(|b| format!("{b:02x}"))
                        .collect::<Vec<_>>()
                        .join(" ")
                })
                .collect();
            out.push_str(&hex.join(separator));
        }
        out.push('\n');
    }
    Some(out)
}

/// A value as Python's `str` shows the one pyulog reads.
fn python_str(v: &Value) -> String {
    match v {
        Value::Scalar(crate::Scalar::Float(x)) => crate::pytext::f64_text(f64::from(*x)),
        Value::Scalar(crate::Scalar::Double(x)) => crate::pytext::f64_text(*x),
        Value::Scalar(crate::Scalar::Bool(b)) => if *b { "True" } else { "False" }.to_owned(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}
