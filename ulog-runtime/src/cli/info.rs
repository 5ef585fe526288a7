//! `ulog info`: header, flag bits, dropouts, damage, info and multi info, and a line per
//! topic instance.

use std::io::Write;
use std::path::Path;

use std::path::PathBuf;

use crate::read::UtcTime;
use crate::{Log, Value};

use crate::cli::Failure;
use crate::pytext::{f32_text, f64_text};

/// `ulog info FILE [-v] [-m NAME [-n]] [-i]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log.
    file: PathBuf,
    /// Also perf_* info, multi info values and every diagnostic.
    #[arg(short, long)]
    verbose: bool,
    /// Only this multi info message, every value joined, as pyulog's `ulog_info -m` prints
    /// it (binary values in hexadecimal).
    #[arg(short, long)]
    message: Option<String>,
    /// With `-m`: a newline between the parts of a value.
    #[arg(short, long, requires = "message")]
    newline: bool,
    /// Leave out bytes of text that are not UTF-8 (pyulog's `-i`); without it such text is
    /// an error.
    #[arg(short, long)]
    ignore: bool,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    let log = crate::cli::open(&args.file)?;
    crate::cli::check_utf8(&log, &args.file, args.ignore, "-i")?;
    if let Some(name) = &args.message {
        crate::cli::report_damage(&log, &args.file);
        crate::cli::pyulog_warnings(&log, out)?;
        match crate::tools::multi_info_text(log.metadata(), name, args.newline) {
            Some(text) => out.write_all(text.as_bytes())?,
            None => writeln!(out, "message {name} not found")?,
        }
        return Ok(());
    }
    info(&log, &args.file, args.verbose, out)
}

/// `h:mm:ss` of a microsecond count, as pyulog prints it.
pub(crate) fn hms(us: u64) -> String {
    let s = us / 1_000_000;
    format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

/// A value for people: text without quotes, numbers as Python prints them, binary data
/// (byte arrays) summarized.
fn plain(v: &Value) -> String {
    if let Some(bytes) = binary(std::slice::from_ref(v)) {
        return summary(&bytes, 1);
    }
    match v {
        Value::String(s) => s.clone(),
        Value::Scalar(crate::Scalar::Float(x)) => f32_text(*x),
        Value::Scalar(crate::Scalar::Double(x)) => f64_text(*x),
        other => other.to_string(),
    }
}

/// Byte arrays longer than a line are binary data, printed as their size and sha256.
const BINARY_FROM: usize = 32;

/// The bytes of values that are byte arrays (`uint8_t[N]`, `int8_t[N]`), joined, if
/// together they are long enough to be binary data.
fn binary(parts: &[Value]) -> Option<Vec<u8>> {
    let mut bytes = Vec::new();
    for part in parts {
        let Value::Array(items) = part else {
            return None;
        };
        for item in items {
            match item.as_scalar()? {
                crate::Scalar::UInt8(b) => bytes.push(b),
                crate::Scalar::Int8(b) => bytes.push(b as u8),
                _ => return None,
            }
        }
    }
    (bytes.len() >= BINARY_FROM).then_some(bytes)
}

/// `16704 bytes in 15 parts, sha256 9f...`.
fn summary(bytes: &[u8], parts: usize) -> String {
    use sha2::Digest;
    let digest = sha2::Sha256::digest(bytes);
    let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
    let parts = if parts > 1 {
        format!(" in {parts} parts")
    } else {
        String::new()
    };
    format!("binary, {} bytes{parts}, sha256 {hex}", bytes.len())
}

fn info(log: &Log<'_>, file: &Path, verbose: bool, out: &mut impl Write) -> Result<(), Failure> {
    let meta = log.metadata();
    let header = log.header();
    writeln!(
        out,
        "File:       {} ({} bytes), ULog version {}",
        file.display(),
        log.bytes().len(),
        header.version
    )?;
    match (meta.software_version(), meta.version_info()) {
        (Some(v), _) => writeln!(out, "Software:   {v}")?,
        // pyulog gives no version string for one; the numbers `ver_sw_release` holds are
        // still shown.
        (None, Some(v)) => writeln!(
            out,
            "Software:   a development build (ver_sw_release {}.{}.{})",
            v.major, v.minor, v.patch
        )?,
        (None, None) => {}
    }
    let start = header.start_timestamp;
    let duration = meta.last_timestamp().saturating_sub(start);
    // A time since boot as h:mm:ss; an absolute time as its date (475214:49:10 hours since
    // 1970 says nothing).
    let (start_text, clock) = match header.start_utc() {
        Some(date) => (date.to_string(), ", an absolute time"),
        // Past 2100: a damaged header, not a date and not days since boot.
        None if start >= UtcTime::PLAUSIBLE_US.end => (
            "unknown".to_owned(),
            ": neither a time since boot nor a date",
        ),
        None => (hms(start), ""),
    };
    writeln!(
        out,
        "Logging:    start {start_text} ({start} µs{clock}), duration {} ({:.3} s)",
        hms(duration),
        duration as f64 / 1e6
    )?;
    // The duration is pyulog's (the last timestamp less the header's start): when it is 0,
    // say where the rows lie if the header's start is later than all of them. (The rows'
    // span is looked up only then: it indexes every row.)
    if duration == 0 {
        let topics = log.topics();
        let first = topics.iter().filter_map(|t| t.first_timestamp).min();
        let last = topics.iter().filter_map(|t| t.last_timestamp).max();
        if let Some((first, last)) = first.zip(last).filter(|&(_, last)| last < start) {
            writeln!(
                out,
                "            the header's start is later than every row: the rows run from {} s to {} s",
                first as f64 / 1e6,
                last as f64 / 1e6
            )?;
        }
    }
    match log.flag_bits() {
        Some(bits) => writeln!(
            out,
            "Flag bits:  compat {:#04x} (default parameters: {}), incompat {:#04x} (data appended: {}{})",
            bits.compat[0],
            if bits.has_default_parameters() {
                "yes"
            } else {
                "no"
            },
            bits.incompat[0],
            if bits.has_data_appended() {
                "yes"
            } else {
                "no"
            },
            bits.appended()
                .map(|o| format!(", at {o}"))
                .collect::<String>()
        )?,
        None if header.version == 0 => writeln!(out, "Flag bits:  none (a version-0 file)")?,
        None => writeln!(
            out,
            "Flag bits:  none: a version-{} file without its flag bits message",
            header.version
        )?,
    }
    let dropouts: Vec<u64> = log
        .dropouts()
        .iter()
        .map(|d| u64::from(d.duration_ms))
        .collect();
    if dropouts.is_empty() {
        writeln!(out, "Dropouts:   none")?;
    } else {
        let total: u64 = dropouts.iter().sum();
        writeln!(
            out,
            "Dropouts:   count: {}, total duration: {:.1} s, max: {} ms, mean: {} ms",
            dropouts.len(),
            total as f64 / 1000.0,
            dropouts.iter().max().unwrap_or(&0),
            total / dropouts.len() as u64
        )?;
    }
    let skipped: u64 = log.corrupt_ranges().map(|r| r.end - r.start).sum();
    if log.diagnostics().is_empty() {
        writeln!(out, "Damage:     none")?;
    } else {
        writeln!(
            out,
            "Damage:     {} problem{}, {skipped} byte{} skipped{}",
            log.diagnostics().len(),
            if log.diagnostics().len() == 1 {
                ""
            } else {
                "s"
            },
            if skipped == 1 { "" } else { "s" },
            if verbose { ":" } else { " (-v lists them)" }
        )?;
        if verbose {
            for d in log.diagnostics() {
                writeln!(out, "  {d}")?;
            }
        }
    }
    writeln!(out, "Info:")?;
    let mut info: Vec<_> = meta.info().iter().collect();
    info.sort_by(|a, b| a.key.cmp(&b.key));
    let width = info.iter().map(|i| i.key.len()).max().unwrap_or(0);
    for i in info
        .iter()
        .filter(|i| verbose || !i.key.starts_with("perf_"))
    {
        writeln!(out, "  {:<width$}  {}", i.key, plain(&i.value))?;
    }
    if !meta.multi_info().is_empty() {
        writeln!(out, "Multi info:")?;
        for m in meta.multi_info() {
            let count = m.values.len();
            let text = m.values.iter().any(|parts| binary(parts).is_none());
            writeln!(
                out,
                "  {} ({}, {count} value{}){}",
                m.key,
                m.type_name,
                if count == 1 { "" } else { "s" },
                if text && !verbose {
                    " (-v shows them)"
                } else {
                    ""
                }
            )?;
            for (k, parts) in m.values.iter().enumerate() {
                // Binary data (a compressed blob split over continued messages) as one
                // summary; text part by part, as pyulog lists them, with -v.
                if let Some(bytes) = binary(parts) {
                    writeln!(out, "    {k}: {}", summary(&bytes, parts.len()))?;
                } else if verbose {
                    let quoted: Vec<String> =
                        parts.iter().map(|p| format!("{:?}", plain(p))).collect();
                    writeln!(out, "    {k}: {}", quoted.join(" + "))?;
                }
            }
        }
    }
    writeln!(out)?;
    writeln!(
        out,
        " {:<40} {:>5} {:>6} {:>9} {:>11} {:>6} {:>9} {:>10}",
        "topic", "multi", "size", "rows", "bytes", "msg_id", "rate Hz", "duration s"
    )?;
    let mut subs: Vec<_> = log.subscriptions().iter().collect();
    subs.sort_by(|a, b| (&a.name, a.multi_id, a.msg_id).cmp(&(&b.name, b.multi_id, b.msg_id)));
    for sub in subs {
        let rows = log.rows(sub);
        let n = rows.len();
        if n == 0 && !verbose {
            continue;
        }
        let size = sub.payload_sizes().map_or(0, |(min, _)| min);
        // Over the rows' time span, earliest to latest: rows out of time order (a clock
        // stepped back) neither hide the rate nor make it negative.
        let (first, last) = log.rows(sub).fold((u64::MAX, 0), |(a, b), r| {
            (a.min(r.timestamp), b.max(r.timestamp))
        });
        let span = last.saturating_sub(first) as f64 / 1e6;
        writeln!(
            out,
            " {:<40} {:>5} {:>6} {:>9} {:>11} {:>6} {:>9} {:>10.1}",
            sub.name,
            sub.multi_id,
            size,
            n,
            size * n,
            sub.msg_id,
            rate_cell(n, span),
            span
        )?;
    }
    Ok(())
}

/// A topic's rate for the table, from its `rows` over `span` seconds: one decimal from
/// 1 Hz, three significant digits below (a row every 8 s is 0.125, every 14 s 0.0714: one
/// decimal showed 0.1 for both, and 0.0 below 0.05 Hz), in exponent form below 0.0001 Hz
/// (`1.16e-5`, a row a day), so that it fits the column; `-` when its rows span no time
/// (one row, or all at one time).
fn rate_cell(rows: usize, span: f64) -> String {
    if rows < 2 || span <= 0.0 {
        return "-".to_owned();
    }
    let rate = (rows - 1) as f64 / span;
    if rate >= 1.0 {
        format!("{rate:.1}")
    } else if rate >= 1e-4 {
        // Digits after the point for three significant ones (3 to 6).
        let decimals = (2 - rate.log10().floor() as i32).clamp(3, 6) as usize;
        format!("{rate:.decimals$}")
    } else {
        format!("{rate:.2e}")
    }
}
