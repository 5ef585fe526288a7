//! Read PX4 ULog (`.ulg`) flight logs.
//!
//! - [`schema`]: the one model of ULog formats: basic types, `F` format strings, layouts.
//! - [`read`]: a whole-file, zero-copy [`Log`] (bytes or a memory map) and a [`StreamReader`]
//!   over any `io::Read`; both read every message type of format versions 0 and 1, recover
//!   from corruption and report what they skipped as [`Diagnostic`]s.
//! - [`value`]: dynamic values for rows of any format, and a fast leaf walk.
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

mod error;
pub mod read;
pub mod schema;
pub mod value;
pub mod write;

pub use error::{Diagnostic, DiagnosticKind, ReadError};
pub use read::{Event, Log, Row, StreamReader};
pub use value::{Scalar, Value};
pub use write::{WriteError, Writer, WriterOptions};

/// The README's examples, compiled as doctests.
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
struct ReadmeDoctests;
