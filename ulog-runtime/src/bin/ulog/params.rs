//! `ulog params`: parameters as pyulog's `ulog_params` writes them.

use std::io::Write;
use std::path::PathBuf;

use ulog_runtime::Log;
use ulog_runtime::read::ParamValue;

use crate::Failure;
use ulog_runtime::pytext::f64_text;

/// `ulog params FILE [-i] [-c] [-t] [-l D] [-d system|current_setup]`.
#[derive(clap::Args)]
pub(crate) struct Args {
    /// The log.
    file: PathBuf,
    /// Only the initial values (no changes).
    #[arg(short, long)]
    initial: bool,
    /// Only the parameters that changed during the log.
    #[arg(short, long)]
    changed: bool,
    /// After each parameter, a line with the change timestamps.
    #[arg(short, long)]
    timestamps: bool,
    /// Separator between name and values.
    #[arg(short = 'l', long, default_value = ",")]
    delimiter: String,
    /// Print default parameters instead: `system` or `current_setup`.
    #[arg(short, long, value_parser = ["system", "current_setup"])]
    default: Option<String>,
}

pub(crate) fn run(args: &Args, out: &mut impl Write) -> Result<(), Failure> {
    params(
        &crate::open(&args.file)?,
        args.initial,
        args.changed,
        args.timestamps,
        &args.delimiter,
        args.default.as_deref(),
        out,
    )
}

fn param_text(v: ParamValue) -> String {
    match v {
        ParamValue::Int32(i) => i.to_string(),
        // pyulog holds the float32 as a Python float and prints its repr.
        ParamValue::Float(f) => f64_text(f64::from(f)),
    }
}

/// As pyulog's `ulog_params` (csv format): `NAME<d>initial<d>change...`, sorted by name.
#[allow(clippy::too_many_arguments)]
fn params(
    log: &Log<'_>,
    initial: bool,
    changed: bool,
    timestamps: bool,
    delimiter: &str,
    default: Option<&str>,
    out: &mut impl Write,
) -> Result<(), Failure> {
    let meta = log.metadata();
    let mut params: Vec<(String, ParamValue)> = match default {
        None => meta
            .initial_parameters()
            .iter()
            .map(|p| (p.name.clone(), p.value))
            .collect(),
        Some(kind) => {
            let bit = if kind == "system" { 1 } else { 2 };
            let mut defaults: Vec<(String, ParamValue)> = Vec::new();
            for d in meta.default_parameters() {
                if d.default_types & bit != 0 {
                    // A later default replaces an earlier one, as in pyulog's dictionary.
                    defaults.retain(|(n, _)| *n != d.name);
                    defaults.push((d.name.clone(), d.value));
                }
            }
            defaults
        }
    };
    params.sort_by(|a, b| a.0.cmp(&b.0));
    for (name, value) in params {
        let changes: Vec<_> = log
            .parameter_changes()
            .iter()
            .filter(|c| c.name == name)
            .collect();
        if changed && changes.is_empty() {
            continue;
        }
        write!(out, "{name}{delimiter}{}", param_text(value))?;
        if timestamps {
            for c in &changes {
                write!(out, "{delimiter}{}", param_text(c.value))?;
            }
            write!(out, "\ntimestamp{delimiter}0")?;
            for c in &changes {
                write!(out, "{delimiter}{}", c.timestamp)?;
            }
        } else if !initial {
            for c in &changes {
                write!(out, "{delimiter}{}", param_text(c.value))?;
            }
        }
        writeln!(out)?;
    }
    Ok(())
}
