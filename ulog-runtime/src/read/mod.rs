//! Reading ULog files: zero-copy over bytes or a memory map ([`Log`]), streaming over any
//! `io::Read` ([`StreamReader`]), or one pass over every row on all cores ([`fold_rows`] of
//! bytes, [`fold_file`] of a file by positioned reads, `MappedFile::fold_rows` of a map).
//! All share one framer (message boundaries and corruption recovery) and one interpreter
//! ([`Metadata`]).

mod file;
mod framer;
mod gps_clock;
mod log;
#[cfg(feature = "mmap")]
mod mapped;
mod message;
mod metadata;
mod positioned;
mod stream;
mod threads;
mod topics;
mod walk;
mod window;

#[cfg(feature = "cli")]
pub(crate) use file::not_a_log_file;
pub use file::open_file;
pub use gps_clock::GpsClock;
pub use log::{DataRows, Log, Rows};
#[cfg(feature = "mmap")]
pub use mapped::MappedFile;
pub use message::{
    FLAG_BITS_LEN, FileHeader, FlagBits, HEADER_LEN, KNOWN_VERSION, KeyValue, MAGIC,
    MESSAGE_HEADER_LEN, MalformedMessage, Message, MessageTooLarge, MessageType, SYNC_MAGIC,
    UtcTime,
};
pub use metadata::{
    DefaultParameter, Dropout, Info, LogLevel, LoggedMessage, Metadata, MultiInfo, ParamValue,
    Parameter, ParameterChange, Subscription, VersionInfo,
};
pub(crate) use metadata::{key_name, text_of};
pub use positioned::{fold_file, fold_file_on};
pub use stream::{Event, RawMessage, StreamReader};
pub(crate) use threads::on_threads;
pub use topics::{InstanceRows, MissingTopic, Skipped, TopicCheck, TopicSummary, check_topics};
pub(crate) use walk::{RowVisitor, all_cores, visit_rows};
pub use walk::{Summary, fold_rows, fold_rows_on, summarize};

use crate::error::{Diagnostic, DiagnosticKind, ReadError};
use crate::schema::{Primitive, Schema};
use crate::value::{RowPlan, Scalar, Value};
use framer::{FastRun, Frame, Framer};
use metadata::Applied;

/// One data row, borrowed from the file.
#[derive(Debug, Clone, Copy)]
pub struct Row<'a> {
    /// Microseconds: the row's `timestamp` field, unwrapped for version-0 small types.
    pub timestamp: u64,
    /// File offset of the `D` message.
    pub offset: u64,
    /// The packed row (may lack the trailing padding).
    pub data: &'a [u8],
    /// The subscription it belongs to.
    pub subscription: &'a Subscription,
    schema: &'a Schema,
}

impl<'a> Row<'a> {
    /// The row as a value tree (padding hidden, `char` arrays as text). `None` only for a
    /// row its format cannot decode: a format with no valid layout, or a row shorter than
    /// the format's payload without its trailing padding. The readers never hand over such
    /// rows (they skip them, and say so once in a [`Diagnostic`]), so
    /// for their rows this is always `Some`; a [`Row`] put together otherwise may be either.
    pub fn value(&self) -> Option<Value> {
        self.plan()?.value(self.schema, self.data)
    }

    /// Calls `f` with every leaf in column order, without allocating; `false` if the row
    /// cannot be decoded.
    #[inline]
    pub fn for_each_leaf(&self, f: impl FnMut(Scalar)) -> bool {
        match self.plan() {
            Some(plan) => plan.for_each_leaf(self.data, f),
            None => false,
        }
    }

    /// The dynamic decoding plan of this row's subscription.
    #[inline]
    pub fn plan(&self) -> Option<&'a RowPlan> {
        self.subscription.plan(self.schema)
    }

    /// The schema the row's format belongs to.
    pub fn schema(&self) -> &'a Schema {
        self.schema
    }
}

/// A row found by the fast path: file offset of the message, its data within the window,
/// subscription and timestamp.
struct FastRow {
    offset: u64,
    data: std::ops::Range<usize>,
    sub: usize,
    timestamp: u64,
}

impl FastRow {
    /// The row the framer peeked in the window that starts at file offset `base`.
    #[inline(always)]
    fn of(row: framer::PeekedRow, base: u64) -> FastRow {
        FastRow {
            offset: base + row.at as u64,
            data: row.at + MESSAGE_HEADER_LEN + 2..row.at + MESSAGE_HEADER_LEN + row.size,
            sub: row.sub,
            timestamp: row.timestamp,
        }
    }
}

/// What one step of walking a file produced.
enum Step<'w> {
    Applied {
        offset: u64,
        applied: Applied,
        payload: &'w [u8],
    },
    NeedMore {
        keep_from: u64,
    },
    End,
}

/// The framer and the interpreter, stepped together over a window of file bytes.
#[derive(Clone)]
struct Walker {
    framer: Framer,
    meta: Metadata,
    /// Counts the messages that change how rows of an already subscribed `msg_id` are framed
    /// or read (flag bits, a `msg_id` subscribed again): two walkers with the same epoch read
    /// the rows they both know alike. (A walker that lacks a newer subscription stops at its
    /// first row instead of misreading it.)
    epoch: u64,
}

impl Walker {
    fn new(header: FileHeader) -> Walker {
        Walker {
            framer: Framer::new(),
            meta: Metadata::new(header),
            epoch: 0,
        }
    }

    /// The next row if the fast path applies (a strongly plausible `D` message, whole in the
    /// window `[base, base + w.len())`, of a subscription with a `uint64_t` timestamp).
    #[inline]
    fn fast_row(&mut self, w: &[u8], base: u64) -> Option<FastRow> {
        let peeked = self.framer.peek_data(w, base)?;
        let row = FastRow::of(peeked, base);
        self.framer.commit(row.offset, peeked.size);
        self.meta.saw_timestamp(row.timestamp);
        Some(row)
    }

    /// Starts a run of fast rows at the current position of the window `[base, base +
    /// w.len())` ([`Framer::run_start`]); `None` if the fast path does not apply here.
    #[inline]
    fn run_start(&self, w: &[u8], base: u64) -> Option<FastRun> {
        self.framer.run_start(w, base, u64::MAX)
    }

    /// The run's next row ([`Framer::run_next`]), in the window the run started in.
    #[inline(always)]
    fn run_next(&self, run: &mut FastRun, w: &[u8], base: u64) -> Option<FastRow> {
        Some(FastRow::of(self.framer.run_next(run, w)?, base))
    }

    /// Ends a run of fast rows: the position moves past them, and the metadata's latest
    /// timestamp takes in theirs.
    #[inline]
    fn run_end(&mut self, run: FastRun, base: u64) {
        let latest = self.framer.run_end(run, base);
        self.meta.saw_timestamp(latest);
    }

    /// The rows of the fast path from the current position on, while they come, before
    /// `limit` ([`Framer::data_run`]): each given to `f` with the metadata, until `f` returns
    /// `false`. Returns whether any row was taken. The metadata's latest timestamp takes in
    /// the run's at its end.
    #[inline]
    fn fast_rows(
        &mut self,
        w: &[u8],
        base: u64,
        limit: u64,
        mut f: impl FnMut(&Metadata, FastRow) -> bool,
    ) -> bool {
        let meta = &self.meta;
        let mut any = false;
        let latest = self.framer.data_run(w, base, limit, |r| {
            any = true;
            f(meta, FastRow::of(r, base))
        });
        if any {
            self.meta.saw_timestamp(latest);
        }
        any
    }

    fn step<'w>(&mut self, w: &'w [u8], base: u64, eof: bool) -> Result<Step<'w>, ReadError> {
        let diag = |offset, kind| Step::Applied {
            offset,
            applied: Applied::Diagnostic(Diagnostic { offset, kind }),
            payload: &[],
        };
        Ok(match self.framer.next(w, base, eof) {
            Frame::Message { offset, ty, size } => {
                let start = (offset - base) as usize + MESSAGE_HEADER_LEN;
                let payload = &w[start..start + usize::from(size)];
                let applied = match Message::parse(ty, payload) {
                    Ok(msg) => self.meta.apply(offset, msg)?,
                    Err(e) => Applied::Diagnostic(Diagnostic {
                        offset,
                        kind: DiagnosticKind::Malformed(e),
                    }),
                };
                if let Applied::Subscribed {
                    msg_id,
                    sizes,
                    duplicate,
                    ..
                } = &applied
                {
                    let sub = self.meta.subscriptions.len() - 1;
                    let u64_timestamp = match self.meta.subscriptions[sub].timestamp {
                        Some((at, Primitive::UInt64)) => Some(at),
                        _ => None,
                    };
                    self.framer.subscribe(*msg_id, *sizes, sub, u64_timestamp);
                    if duplicate.is_some() {
                        self.epoch += 1;
                    }
                }
                if ty == b'B' {
                    self.epoch += 1;
                }
                Step::Applied {
                    offset,
                    applied,
                    payload,
                }
            }
            Frame::Skipped { from, to } => {
                diag(from, DiagnosticKind::Skipped { to, len: to - from })
            }
            Frame::Overlap { prev, next } => diag(prev, DiagnosticKind::Overlap { next }),
            Frame::Truncated {
                offset,
                declared,
                available,
            } => diag(
                offset,
                DiagnosticKind::Truncated {
                    declared,
                    available,
                },
            ),
            Frame::BadAppendedOffset { offset } => {
                diag(offset, DiagnosticKind::BadAppendedOffset(offset))
            }
            Frame::NeedMore { keep_from } => Step::NeedMore { keep_from },
            Frame::End => Step::End,
        })
    }
}

#[cfg(test)]
mod tests;
