//! `ulog_params`: a log's parameters in pyulog's formats.

use std::io::{self, Write};

use crate::pytext::f64_text;
use crate::read::{Log, ParamValue};

/// An output format of `ulog_params` (`-f`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ParamsFormat {
    /// `NAME,initial,change...` per line.
    #[default]
    Csv,
    /// Octave text: `# name NAME`, then a scalar or a 1-row matrix of the values.
    Octave,
    /// QGroundControl's parameter file: `1<TAB>1<TAB>NAME<TAB>value<TAB>type`.
    Qgc,
}

/// Which default values to print (`-d`) instead of the configured ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DefaultKind {
    /// The system defaults (`Q` messages with bit 0).
    System,
    /// The current setup's defaults (bit 1).
    CurrentSetup,
}

/// How `ulog_params` prints ([`params`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamsOptions {
    /// The format.
    pub format: ParamsFormat,
    /// Only the initial values (`-i`; csv and octave). With `timestamps`, the changes are
    /// still listed, each stamped with the header's start time, as pyulog stamps them when
    /// it reads a log for `-i` (it reads no data rows then).
    pub initial: bool,
    /// Only the parameters that changed during the log (csv; not in pyulog).
    pub changed: bool,
    /// csv: after each parameter, its values and a `timestamp` line (`-t`).
    pub timestamps: bool,
    /// csv: between name and values (`-l`).
    pub delimiter: String,
    /// Default values instead of the configured ones (`-d`; implies `initial`).
    pub default: Option<DefaultKind>,
}

impl Default for ParamsOptions {
    fn default() -> ParamsOptions {
        ParamsOptions {
            format: ParamsFormat::Csv,
            initial: false,
            changed: false,
            timestamps: false,
            delimiter: ",".to_owned(),
            default: None,
        }
    }
}

/// Why [`params`] could not print.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ParamsError {
    /// Default values asked for, and the log's flag bits say it has none.
    #[error("the log has no default parameters (its flag bits say so)")]
    NoDefaults,
    /// Writing failed.
    #[error(transparent)]
    Io(#[from] io::Error),
}

/// A parameter value as pyulog prints it: integers in decimal, `float` as Python's repr of
/// the value widened to a double.
pub fn param_text(v: ParamValue) -> String {
    match v {
        ParamValue::Int32(i) => i.to_string(),
        ParamValue::Float(f) => f64_text(f64::from(f)),
    }
}

/// Writes a log's parameters as pyulog's `ulog_params` does, sorted by name.
pub fn params(
    log: &Log<'_>,
    options: &ParamsOptions,
    out: &mut impl Write,
) -> Result<(), ParamsError> {
    let meta = log.metadata();
    let mut initial = options.initial;
    let mut params: Vec<(String, ParamValue)> = match options.default {
        None => meta
            .initial_parameters()
            .iter()
            .map(|p| (p.name.clone(), p.value))
            .collect(),
        Some(kind) => {
            // pyulog asks the flag bits.
            if !meta.flag_bits().is_some_and(|b| b.has_default_parameters()) {
                return Err(ParamsError::NoDefaults);
            }
            initial = true;
            let bit = match kind {
                DefaultKind::System => 1,
                DefaultKind::CurrentSetup => 2,
            };
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
    let changed = log.changed_parameters();
    let changes_of = |name: &str| -> &[&crate::read::ParameterChange] {
        changed
            .binary_search_by(|(n, _)| (*n).cmp(name))
            .map_or(&[], |i| &changed[i].1)
    };
    match options.format {
        ParamsFormat::Csv => {
            let d = &options.delimiter;
            for (name, value) in params {
                let changes = changes_of(&name);
                if options.changed && changes.is_empty() {
                    continue;
                }
                write!(out, "{name}{d}{}", param_text(value))?;
                if options.timestamps || !initial {
                    for c in changes {
                        write!(out, "{d}{}", param_text(c.value))?;
                    }
                }
                if options.timestamps {
                    write!(out, "\ntimestamp{d}0")?;
                    for c in changes {
                        // With `-i` pyulog reads the log with an empty topic filter: no
                        // data row moves its clock on, so every change is stamped with the
                        // header's start time.
                        let t = if options.initial {
                            log.header().start_timestamp
                        } else {
                            c.timestamp
                        };
                        write!(out, "{d}{t}")?;
                    }
                }
                writeln!(out)?;
            }
        }
        ParamsFormat::Octave => {
            for (name, value) in params {
                write!(out, "# name {name}")?;
                let mut values = vec![value];
                if !initial {
                    values.extend(changes_of(&name).iter().map(|c| c.value));
                }
                if values.len() > 1 {
                    write!(
                        out,
                        "\n# type: matrix\n# rows: 1\n# columns: {}\n",
                        values.len()
                    )?;
                    for v in values {
                        write!(out, "{} ", param_text(v))?;
                    }
                } else {
                    write!(out, "\n# type: scalar\n{}", param_text(values[0]))?;
                }
                writeln!(out)?;
            }
        }
        ParamsFormat::Qgc => {
            for (name, value) in params {
                // MAVLink's parameter types: 9 REAL32, 6 INT32.
                let ty = match value {
                    ParamValue::Float(_) => 9,
                    ParamValue::Int32(_) => 6,
                };
                writeln!(out, "1\t1\t{name}\t{}\t{ty}", param_text(value))?;
            }
        }
    }
    Ok(())
}
