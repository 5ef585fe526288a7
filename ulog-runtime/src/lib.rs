//! Read PX4 ULog (`.ulg`) flight logs.
//!
//! - [`schema`]: the one model of ULog formats: basic types, `F` format strings, layouts.
//! - [`read`]: a whole-file, zero-copy [`Log`] (bytes or a memory map) and a [`StreamReader`]
//!   over any `io::Read`; both read every message type of format versions 0 and 1, recover
//!   from corruption and report what they skipped as [`Diagnostic`]s.
//! - [`value`]: dynamic values for rows of any format, and a fast leaf walk.
//! - [`typed`]: Rust structs as ULog formats (`#[derive(ULog)]`), checked against a file's
//!   own definitions once, then decoded by offset reads ([`Log::topic`]) and written
//!   ([`Writer::topic`]).
//! - [`write`](mod@write): a [`Writer`] of version-1 files.
//! - [`rewrite`]: a log read as a stream and written again, cut to a time window, topics
//!   kept or dropped, rows transformed, anonymized.
//! - [`events`] (feature `events`): PX4 events decoded with the metadata the log embeds,
//!   and the messages of a log as pyulog's `ulog_messages` lists them.
//! - [`columns`]: a topic instance as typed columns (and, with features, Arrow record
//!   batches and Parquet files).
//! - [`analysis`]: what a log says about the flight: modes, statistics, battery, GPS,
//!   vibration, step responses, spectra, and diagnostics of what went wrong.
//! - [`tools`]: what pyulog's command-line tools compute (parameters in their formats, a
//!   multi info value, the KML track, the GPS dump), byte for byte.
//! - [`file_names`]: safe, unique file names for exports that write a file per topic.
//!
//! ```no_run
//! # fn main() -> Result<(), ulog_runtime::ReadError> {
//! let log = ulog_runtime::Log::open("flight.ulg")?;
//! let attitude = log.subscription("vehicle_attitude", 0).expect("logged");
//! for row in log.rows(attitude) {
//!     let q = row.value().unwrap();
//!     println!("{} {}", row.timestamp, q.field("q").unwrap());
//! }
//! # Ok(()) }
//! ```

// Lets `#[derive(ULog)]` output (which names `::ulog_runtime`) compile inside this crate too.
extern crate self as ulog_runtime;

#[doc(hidden)]
pub mod __private;
pub mod analysis;
#[cfg(feature = "cli")]
pub mod cli;
#[cfg(feature = "codegen")]
pub mod codegen;
pub mod columns;
pub mod compat;
#[cfg(feature = "serde")]
pub mod document;
mod error;
#[cfg(feature = "events")]
pub mod events;
pub mod file_names;
pub mod pytext;
pub mod read;
#[cfg(feature = "report")]
pub mod report;
pub mod rewrite;
pub mod schema;
pub mod tools;
pub mod typed;
pub mod value;
pub mod write;

pub use error::{Diagnostic, DiagnosticKind, ReadError};
pub use read::{Event, Log, LogLevel, Row, StreamReader};
pub use typed::{Char, Chars, Topic, TypedError, ULog};
#[cfg(feature = "derive")]
pub use ulog_derive::ULog;
pub use value::{Scalar, Value};
pub use write::{WriteError, Writer, WriterOptions};

/// The README's examples, compiled as doctests (with the features they use, as the
/// workspace's test run has them).
#[cfg(all(doctest, feature = "parquet"))]
#[doc = include_str!("../../README.md")]
struct ReadmeDoctests;
