//! Errors that stop reading ([`ReadError`]) and findings that do not ([`Diagnostic`]).

use std::fmt;

use crate::read::MalformedMessage;
use crate::schema::{FormatError, Redefinition};
use crate::value::PlanError;

/// `Debug` as the `Display` text, for errors: `fn main() -> Result<(), Box<dyn Error>>`
/// prints an error it returns with `Debug`, and that should read as well as the message.
macro_rules! debug_as_display {
    ($($ty:ty),* $(,)?) => {$(
        impl ::std::fmt::Debug for $ty {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                ::std::fmt::Display::fmt(self, f)
            }
        }
    )*};
}
pub(crate) use debug_as_display;

debug_as_display!(ReadError);

/// An error that stops reading a file.
#[derive(thiserror::Error)]
#[non_exhaustive]
pub enum ReadError {
    /// Reading the input failed.
    #[error("I/O error: {0}")]
    Io(#[from] std::io::Error),
    /// The input does not start with the ULog magic bytes.
    #[error("not a ULog file: the first bytes are not the ULog magic `55 4c 6f 67 01 12 35`")]
    NotULog,
    /// The input ends inside the 16-byte file header.
    #[error("file too short: {len} bytes, the ULog header alone is 16")]
    TooShort {
        /// Bytes available.
        len: usize,
    },
    /// The file is larger than the whole-file reader can index (1 TiB); stream it instead.
    #[error(
        "file of {len} bytes is larger than the 1 TiB the whole-file reader indexes; use StreamReader"
    )]
    FileTooLarge {
        /// Its length.
        len: u64,
    },
    /// The flag bits set an incompatible flag this reader does not know.
    #[error(
        "unknown incompatible flag: bit {bit} of incompat byte {byte} is set \
         (only DATA_APPENDED, bit 0 of byte 0, is known); this file needs a newer reader"
    )]
    IncompatibleFlags {
        /// Index of the byte in `incompat[8]`.
        byte: usize,
        /// Bit number within that byte.
        bit: u8,
    },
}

/// Something wrong or unusual found while reading, that reading went on after.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostic {
    /// File offset of the message (or first byte) concerned.
    pub offset: u64,
    /// What was found.
    pub kind: DiagnosticKind,
}

/// The text of what the log says (names, definitions) with its control characters written as
/// escapes (`\u{0}` for a NUL of a damaged definition, `\n`, `\u{1b}`): so that what a
/// damaged log makes a reader say stays one printable line.
pub(crate) fn printable(text: &str) -> std::borrow::Cow<'_, str> {
    if text.chars().any(char::is_control) {
        text.chars()
            .map(|c| {
                if c.is_control() {
                    c.escape_default().to_string()
                } else {
                    c.to_string()
                }
            })
            .collect::<String>()
            .into()
    } else {
        text.into()
    }
}

/// `at byte N: what`, the log's text in it with its control characters escaped (a NUL as
/// `\u{0}`); the kind's fields keep the text as read.
impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let what = self.kind.to_string();
        write!(f, "at byte {}: {}", self.offset, printable(&what))
    }
}

impl std::error::Error for Diagnostic {}

impl Diagnostic {
    /// The bytes this diagnostic reports as damaged (skipped, or a message cut short).
    pub fn damaged_range(&self) -> Option<std::ops::Range<u64>> {
        match self.kind {
            DiagnosticKind::Skipped { to, .. } => Some(self.offset..to),
            DiagnosticKind::Truncated {
                declared,
                available,
            } => Some(
                self.offset
                    ..self.offset
                        + crate::read::MESSAGE_HEADER_LEN as u64 * u64::from(declared.is_some())
                        + available,
            ),
            _ => None,
        }
    }

    /// Whether this reports damage (skipped or cut bytes, overlapping messages) rather than
    /// a message that was framed correctly but could not be used.
    pub fn is_corruption(&self) -> bool {
        matches!(
            self.kind,
            DiagnosticKind::Skipped { .. }
                | DiagnosticKind::Overlap { .. }
                | DiagnosticKind::Truncated { .. }
        )
    }
}

/// The findings a reader reports and goes on after.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DiagnosticKind {
    /// The header's version byte is newer than this reader knows.
    #[error("file version {0} is newer than 1; reading it as version 1")]
    UnknownVersion(u8),
    /// A message of a type this reader does not know, skipped.
    #[error("unknown message type {ty:#04x} ({size} bytes), skipped")]
    UnknownMessageType {
        /// The type byte.
        ty: u8,
        /// Its payload size.
        size: u16,
    },
    /// Bytes that are not part of any message (corruption); reading resumed at `to`.
    #[error("corrupt data: {len} bytes skipped, resuming at byte {to}")]
    Skipped {
        /// First byte after the skipped range (the range starts at the diagnostic's offset).
        to: u64,
        /// Length of the skipped range.
        len: u64,
    },
    /// A message whose declared size runs into the next message found.
    #[error("message declares a size that runs into the message at byte {next}")]
    Overlap {
        /// Where the next message was found.
        next: u64,
    },
    /// A message cut by the end of the file or of its data segment; dropped.
    #[error("message cut short: {}, {available} available; dropped", match .declared { Some(d) => format!("{d} payload bytes declared"), None => "header incomplete".to_owned() })]
    Truncated {
        /// The size its header declares, if the header is complete.
        declared: Option<u16>,
        /// Payload bytes present.
        available: u64,
    },
    /// An appended-data offset in the flag bits that is impossible (backwards or past the end).
    #[error("appended data offset {0} is impossible (backwards or past the end), ignored")]
    BadAppendedOffset(u64),
    /// A flag-bits message anywhere but first.
    #[error("flag bits message is not the first message, ignored")]
    FlagBitsNotFirst,
    /// A message too short for its type.
    #[error("{0}")]
    Malformed(MalformedMessage),
    /// A format definition that does not follow the grammar.
    #[error("invalid format definition `{text}`: {error}")]
    InvalidFormat {
        /// The definition.
        text: String,
        /// Why.
        error: FormatError,
    },
    /// A second, different definition of a format; the first is kept.
    #[error("{0}; keeping the first")]
    Redefinition(Redefinition),
    /// A format definition outside the grammar, kept under its names as pyulog reads it.
    #[error("format definition `{text}` kept as it is: {notes}")]
    OddFormat {
        /// The definition.
        text: String,
        /// What is outside the grammar.
        notes: String,
        /// Whether the definition is not UTF-8 (its invalid bytes left out).
        not_utf8: bool,
    },
    /// An `I`/`M`/`P`/`Q` key or value that does not follow the format, kept as far as it
    /// goes (see [`Info`](crate::read::Info)).
    #[error("`{key}`: {reason}")]
    KeptValue {
        /// The key text.
        key: String,
        /// What is odd and how the value is kept.
        reason: String,
        /// Whether the key or a text value is not UTF-8 (pyulog's tools fail on it
        /// without `-i`).
        not_utf8: bool,
    },
    /// An `I`/`M`/`P`/`Q` key or value that cannot be decoded; it is left out.
    #[error("invalid `{key}` value: {reason}")]
    InvalidValue {
        /// The key text.
        key: String,
        /// Why.
        reason: String,
    },
    /// A subscription whose format cannot be decoded; its rows are skipped.
    #[error("subscription `{topic}` (msg_id {msg_id}): {error}")]
    BadSubscription {
        /// The topic.
        topic: String,
        /// Its id.
        msg_id: u16,
        /// Why.
        error: PlanError,
    },
    /// A subscription reuses a `msg_id`; later data goes to the new one.
    #[error("msg_id {msg_id} subscribed again (was `{previous}`), now `{topic}`")]
    DuplicateMsgId {
        /// The id.
        msg_id: u16,
        /// The earlier topic.
        previous: String,
        /// The new topic.
        topic: String,
    },
    /// A subscribed format without a `timestamp` of an unsigned integer type; rows get 0.
    #[error("topic `{topic}` has no unsigned integer `timestamp` field; its rows get timestamp 0")]
    MissingTimestamp {
        /// The topic.
        topic: String,
    },
    /// Data for an id no subscription declared; the row is skipped.
    #[error("data for msg_id {msg_id}, which no subscription declares; row skipped")]
    UnknownMsgId {
        /// The id.
        msg_id: u16,
    },
    /// Data whose length does not fit its format; the row is skipped.
    #[error(
        "`{topic}` (multi_id {multi_id}, msg_id {msg_id}): {len}-byte row, the format needs {min}..={max}; row skipped"
    )]
    PayloadSize {
        /// The topic.
        topic: String,
        /// The instance.
        multi_id: u8,
        /// The id.
        msg_id: u16,
        /// Bytes present.
        len: usize,
        /// Size without trailing padding.
        min: usize,
        /// Full size.
        max: usize,
    },
}
