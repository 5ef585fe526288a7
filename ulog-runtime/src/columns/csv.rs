//! CSV files of topic instances as pyulog's `ulog2csv` writes them: one file per instance,
//! `<stem>_<topic>_<multi_id>.csv`, a header of column names (padding inside nested types
//! shown, as ulog2csv does), integers in decimal, `bool` and `char` as their signed byte,
//! floats as numpy prints them ([`pytext`](crate::pytext)), `char[N]` as text.
//!
//! ```
//! use ulog_runtime::{Log, ULog, Writer, WriterOptions};
//! use ulog_runtime::columns::csv::{CsvOptions, write_csv};
//!
//! #[derive(ULog)]
//! struct Battery { timestamp: u64, voltage_v: f32, ok: bool }
//!
//! let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
//! let sub = w.topic::<Battery>(0)?;
//! w.write(&sub, &Battery { timestamp: 1, voltage_v: 16.2, ok: true })?;
//! let log = Log::from_vec(w.into_inner())?;
//! let mut out = Vec::new();
//! let instance = &log.instances(&[])[0];
//! write_csv(&log, instance, &mut out, &CsvOptions::default())?;
//! assert_eq!(String::from_utf8(out)?, "timestamp,voltage_v,ok\n1,16.2,1\n");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use super::{Admit, ColumnKind, ColumnSpec, Window, text};
use crate::Scalar;
use crate::pytext::{f32_text, f64_text};
use crate::read::{Log, Subscription};

use crate::schema::Primitive;

/// How CSV files are written.
#[derive(Debug, Clone, PartialEq)]
pub struct CsvOptions {
    /// Between fields (ulog2csv's `-d`).
    pub delimiter: String,
    /// Only the rows of this window (ulog2csv's `-ts`/`-te`).
    pub window: Window,
}

impl Default for CsvOptions {
    fn default() -> CsvOptions {
        CsvOptions {
            delimiter: ",".to_owned(),
            window: Window::default(),
        }
    }
}

/// Writes the rows of one topic instance (its subscriptions, as [`Log::instances`] gives
/// them) as ulog2csv does; returns the rows written.
pub fn write_csv(
    log: &Log<'_>,
    instance: &[&Subscription],
    out: impl Write,
    options: &CsvOptions,
) -> io::Result<usize> {
    write_csv_with(log, instance, out, options, &mut || {})
}

fn write_csv_with(
    log: &Log<'_>,
    instance: &[&Subscription],
    mut out: impl Write,
    options: &CsvOptions,
    progress: &mut dyn FnMut(),
) -> io::Result<usize> {
    let Some(id) = instance.first().and_then(|s| s.format()) else {
        return Ok(0);
    };
    let Some(spec) = ColumnSpec::of_ulog2csv(log.metadata().schema(), id) else {
        return Ok(0);
    };
    let cols = spec.columns();
    let header: Vec<&str> = cols.iter().map(|c| c.name.as_str()).collect();
    writeln!(out, "{}", header.join(&options.delimiter))?;
    // Each field as the file has it (the timestamp too, as ulog2csv shows it), found once.
    let file_types: Vec<Option<Primitive>> = cols
        .iter()
        .map(|c| match c.kind {
            ColumnKind::Text { .. } => None,
            ColumnKind::Value(_) => {
                Some(Primitive::from_c_name(&c.ulog_type).expect("a basic type"))
            }
        })
        .collect();
    let mut line = String::new();
    let mut count = 0;
    let mut started = false;
    for row in log.instance_rows(instance) {
        progress();
        match options.window.admit(row.timestamp, started) {
            Admit::Skip => continue,
            Admit::Stop => break,
            Admit::Take => started = true,
        }
        line.clear();
        for (k, (c, file_type)) in cols.iter().zip(&file_types).enumerate() {
            if k > 0 {
                line.push_str(&options.delimiter);
            }
            match (c.kind, file_type) {
                (ColumnKind::Text { len }, _) => {
                    let end = (c.offset + len).min(row.data.len());
                    line.push_str(&text(row.data.get(c.offset..end).unwrap_or_default()));
                }
                (_, Some(p)) => {
                    if let Some(b) = row.data.get(c.offset..c.offset + p.size()) {
                        write_number(&mut line, *p, b);
                    }
                }
                (_, None) => {}
            }
        }
        line.push('\n');
        out.write_all(line.as_bytes())?;
        count += 1;
    }
    out.flush()?;
    Ok(count)
}

/// A value as pyulog writes it: integers in decimal, `bool` and `char` as their signed byte
/// (pyulog reads both as `int8`), floats as numpy prints them.
fn write_number(out: &mut String, p: Primitive, b: &[u8]) {
    use std::fmt::Write as _;
    match Scalar::decode(p, b) {
        Some(Scalar::Float(x)) => out.push_str(&f32_text(x)),
        Some(Scalar::Double(x)) => out.push_str(&f64_text(x)),
        // The raw byte: a `bool` of 0x41 is 65 for pyulog, not 1.
        Some(Scalar::Bool(_)) => {
            let _ = write!(out, "{}", b[0] as i8);
        }
        Some(other) => {
            let _ = write!(out, "{other}");
        }
        None => {}
    }
}

/// One file of [`export`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CsvFile {
    /// Where.
    pub path: PathBuf,
    /// Rows written.
    pub rows: usize,
    /// The other topic whose file name this one's would have been, if it had to change.
    pub collided_with: Option<String>,
    /// The topic.
    pub topic: String,
    /// The instance.
    pub multi_id: u8,
}

/// Writes a CSV file per topic instance with rows (only `topics` if not empty) into `dir`,
/// named `<stem>_<topic>_<multi_id>.csv` through [`file_names`](crate::file_names) (safe,
/// unique). `progress` is called once per row read. Errors name the file.
pub fn export(
    log: &Log<'_>,
    stem: &str,
    dir: &Path,
    topics: &[String],
    options: &CsvOptions,
    progress: &mut dyn FnMut(),
) -> Result<Vec<CsvFile>, (PathBuf, io::Error)> {
    let mut names = crate::file_names::FileNames::new();
    let prefix = format!("{stem}_");
    let mut written = Vec::new();
    for instance in log.instances(topics) {
        let sub = instance[0];
        let name = names.unique(&prefix, &sub.name, &format!("_{}.csv", sub.multi_id));
        let path = dir.join(&name.file_name);
        let file = std::fs::File::create(&path).map_err(|e| (path.clone(), e))?;
        let rows = write_csv_with(log, &instance, io::BufWriter::new(file), options, progress)
            .map_err(|e| (path.clone(), e))?;
        written.push(CsvFile {
            path,
            rows,
            collided_with: name.collided_with,
            topic: sub.name.clone(),
            multi_id: sub.multi_id,
        });
    }
    Ok(written)
}
