//! The whole-file view: one pass over bytes (owned, borrowed or memory-mapped) collects the
//! metadata and an index of data rows per subscription; rows are then read in place.

use std::path::Path;

use super::metadata::Applied;
use super::{
    Diagnostic, Dropout, FileHeader, FlagBits, LoggedMessage, MESSAGE_HEADER_LEN, Metadata,
    ParameterChange, ReadError, Row, Step, Subscription, Walker,
};
use crate::schema::Primitive;

enum Bytes<'a> {
    Borrowed(&'a [u8]),
    Owned(Vec<u8>),
    #[cfg(feature = "mmap")]
    Mapped(memmap2::Mmap),
}

impl Bytes<'_> {
    fn as_slice(&self) -> &[u8] {
        match self {
            Bytes::Borrowed(b) => b,
            Bytes::Owned(v) => v,
            #[cfg(feature = "mmap")]
            Bytes::Mapped(m) => m,
        }
    }
}

/// Where a subscription's rows are.
#[derive(Debug, Default, Clone)]
struct RowIndex {
    offsets: Vec<u64>,
    /// Unwrapped timestamps, kept only for subscriptions whose `timestamp` is not `uint64_t`.
    timestamps: Option<Vec<u64>>,
}

/// A whole ULog file, read once at open, then accessed in place.
///
/// ```no_run
/// # fn main() -> Result<(), ulog_runtime::ReadError> {
/// let log = ulog_runtime::Log::open("flight.ulg")?;
/// for sub in log.subscriptions() {
///     let rows = log.rows(sub);
///     println!("{} #{}: {} rows", sub.name, sub.multi_id, rows.len());
///     for row in rows {
///         let value = row.value().unwrap();
///         println!("  {} {value}", row.timestamp);
///     }
/// }
/// for problem in log.diagnostics() {
///     eprintln!("{problem}");
/// }
/// # Ok(()) }
/// ```
pub struct Log<'a> {
    bytes: Bytes<'a>,
    meta: Metadata,
    rows: Vec<RowIndex>,
    /// Subscription index of every row, in file order.
    order: Vec<u32>,
    logged: Vec<LoggedMessage>,
    changes: Vec<ParameterChange>,
    dropouts: Vec<Dropout>,
    sync_offsets: Vec<u64>,
    diagnostics: Vec<Diagnostic>,
}

impl std::fmt::Debug for Log<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Log")
            .field("len", &self.bytes.as_slice().len())
            .field("header", &self.meta.header)
            .field("subscriptions", &self.meta.subscriptions.len())
            .field("rows", &self.order.len())
            .field("diagnostics", &self.diagnostics.len())
            .finish_non_exhaustive()
    }
}

impl Log<'static> {
    /// Opens a file through a memory map.
    ///
    /// The map is read-only; like every memory-mapped reader, the file must not be truncated
    /// by another process while the `Log` lives.
    #[cfg(feature = "mmap")]
    pub fn open(path: impl AsRef<Path>) -> Result<Log<'static>, ReadError> {
        let file = std::fs::File::open(path)?;
        // SAFETY: the map is only read; the caller is told not to truncate the file meanwhile,
        // which is the contract of every memory-mapped file reader.
        #[allow(unsafe_code)]
        let map = unsafe { memmap2::Mmap::map(&file)? };
        Log::from_bytes(Bytes::Mapped(map))
    }

    /// Reads a whole file into memory.
    pub fn read(path: impl AsRef<Path>) -> Result<Log<'static>, ReadError> {
        Log::from_vec(std::fs::read(path)?)
    }

    /// Takes ownership of the bytes of a file.
    pub fn from_vec(bytes: Vec<u8>) -> Result<Log<'static>, ReadError> {
        Log::from_bytes(Bytes::Owned(bytes))
    }
}

impl<'a> Log<'a> {
    /// Reads a file held in memory, without copying it.
    pub fn from_slice(bytes: &'a [u8]) -> Result<Log<'a>, ReadError> {
        Log::from_bytes(Bytes::Borrowed(bytes))
    }

    fn from_bytes(bytes: Bytes<'a>) -> Result<Log<'a>, ReadError> {
        let data = bytes.as_slice();
        let header = FileHeader::parse(data)?;
        let mut walker = Walker::new(header);
        let mut log = Log {
            meta: Metadata::new(header),
            rows: Vec::new(),
            order: Vec::new(),
            logged: Vec::new(),
            changes: Vec::new(),
            dropouts: Vec::new(),
            sync_offsets: Vec::new(),
            diagnostics: walker.meta.header_diagnostic().into_iter().collect(),
            bytes: Bytes::Borrowed(&[]),
        };
        loop {
            match walker.step(data, 0, true)? {
                Step::Applied {
                    offset, applied, ..
                } => match applied {
                    Applied::Nothing => {}
                    Applied::Subscribed { .. } => {}
                    Applied::Row { sub, timestamp } => {
                        if log.rows.len() <= sub {
                            log.rows
                                .resize_with(walker.meta.subscriptions.len(), RowIndex::default);
                        }
                        let index = &mut log.rows[sub];
                        index.offsets.push(offset);
                        if walker.meta.subscriptions[sub].timestamp_type()
                            != Some(Primitive::UInt64)
                        {
                            index
                                .timestamps
                                .get_or_insert_with(Vec::new)
                                .push(timestamp);
                        }
                        log.order.push(sub as u32);
                    }
                    Applied::Logged(m) => log.logged.push(m),
                    Applied::Dropout(d) => log.dropouts.push(d),
                    Applied::ParameterChange(c) => log.changes.push(c),
                    Applied::Sync => log.sync_offsets.push(offset),
                    Applied::Diagnostic(d) => log.diagnostics.push(d),
                },
                Step::NeedMore { .. } | Step::End => break,
            }
        }
        log.rows
            .resize_with(walker.meta.subscriptions.len(), RowIndex::default);
        log.meta = walker.meta;
        log.bytes = bytes;
        Ok(log)
    }

    /// The file's bytes.
    pub fn bytes(&self) -> &[u8] {
        self.bytes.as_slice()
    }

    /// Everything but the data rows: formats, info, parameters, subscriptions.
    pub fn metadata(&self) -> &Metadata {
        &self.meta
    }

    /// The file header (version, start time).
    pub fn header(&self) -> FileHeader {
        self.meta.header
    }

    /// The flag bits, for files that have them.
    pub fn flag_bits(&self) -> Option<&FlagBits> {
        self.meta.flag_bits.as_ref()
    }

    /// Subscriptions in file order, including ones without data.
    pub fn subscriptions(&self) -> &[Subscription] {
        &self.meta.subscriptions
    }

    /// The last subscription to this topic instance.
    pub fn subscription(&self, name: &str, multi_id: u8) -> Option<&Subscription> {
        self.meta
            .subscriptions
            .iter()
            .rev()
            .find(|s| s.name == name && s.multi_id == multi_id)
    }

    /// The rows of one subscription, in file order.
    ///
    /// # Panics
    /// If `sub` does not come from this log.
    pub fn rows<'s>(&'s self, sub: &'s Subscription) -> Rows<'s> {
        let index = self.sub_index(sub);
        Rows {
            log: self,
            sub: index,
            next: 0,
            end: self.rows[index].offsets.len(),
        }
    }

    /// Every data row of every subscription, in file order.
    pub fn data(&self) -> DataRows<'_> {
        DataRows {
            log: self,
            next: 0,
            cursors: vec![0; self.rows.len()],
        }
    }

    /// Total number of data rows read.
    pub fn row_count(&self) -> usize {
        self.order.len()
    }

    /// Logged strings (`L` and `C`), in file order.
    pub fn logged_messages(&self) -> &[LoggedMessage] {
        &self.logged
    }

    /// Parameter changes in the data section, in file order.
    pub fn parameter_changes(&self) -> &[ParameterChange] {
        &self.changes
    }

    /// Dropouts, in file order.
    pub fn dropouts(&self) -> &[Dropout] {
        &self.dropouts
    }

    /// File offsets of the sync messages.
    pub fn sync_offsets(&self) -> &[u64] {
        &self.sync_offsets
    }

    /// Everything found wrong or unusual, in file order: skipped corrupt ranges, truncation,
    /// rows that did not fit their format, unknown message types...
    pub fn diagnostics(&self) -> &[Diagnostic] {
        &self.diagnostics
    }

    /// Byte ranges skipped as corrupt (truncated tails included).
    pub fn corrupt_ranges(&self) -> impl Iterator<Item = std::ops::Range<u64>> + '_ {
        self.diagnostics.iter().filter_map(|d| match d.kind {
            crate::DiagnosticKind::Skipped { to, .. } => Some(d.offset..to),
            crate::DiagnosticKind::Truncated {
                declared,
                available,
            } => Some(
                d.offset
                    ..d.offset
                        + MESSAGE_HEADER_LEN as u64 * u64::from(declared.is_some())
                        + available,
            ),
            _ => None,
        })
    }

    fn sub_index(&self, sub: &Subscription) -> usize {
        let index = self
            .meta
            .subscriptions
            .iter()
            .position(|s| std::ptr::eq(s, sub))
            .expect("the subscription belongs to this log");
        index
    }

    fn row(&self, sub: usize, i: usize) -> Row<'_> {
        let index = &self.rows[sub];
        let offset = index.offsets[i];
        let bytes = self.bytes.as_slice();
        let at = offset as usize;
        let size = usize::from(u16::from_le_bytes([bytes[at], bytes[at + 1]]));
        let data = &bytes[at + MESSAGE_HEADER_LEN + 2..at + MESSAGE_HEADER_LEN + size];
        let subscription = &self.meta.subscriptions[sub];
        let timestamp = match &index.timestamps {
            Some(t) => t[i],
            None => {
                let at = subscription.timestamp.map_or(0, |(at, _)| at);
                u64::from_le_bytes(data[at..at + 8].try_into().unwrap_or_default())
            }
        };
        Row {
            timestamp,
            offset,
            data,
            subscription,
            schema: &self.meta.schema,
        }
    }
}

/// The rows of one subscription ([`Log::rows`]).
#[derive(Debug, Clone)]
pub struct Rows<'a> {
    log: &'a Log<'a>,
    sub: usize,
    next: usize,
    end: usize,
}

impl<'a> Iterator for Rows<'a> {
    type Item = Row<'a>;

    #[inline]
    fn next(&mut self) -> Option<Row<'a>> {
        if self.next == self.end {
            return None;
        }
        self.next += 1;
        Some(self.log.row(self.sub, self.next - 1))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.end - self.next, Some(self.end - self.next))
    }
}

impl ExactSizeIterator for Rows<'_> {}

impl DoubleEndedIterator for Rows<'_> {
    fn next_back(&mut self) -> Option<Self::Item> {
        if self.next == self.end {
            return None;
        }
        self.end -= 1;
        Some(self.log.row(self.sub, self.end))
    }
}

/// Every row of a log in file order ([`Log::data`]).
#[derive(Debug, Clone)]
pub struct DataRows<'a> {
    log: &'a Log<'a>,
    next: usize,
    cursors: Vec<usize>,
}

impl<'a> Iterator for DataRows<'a> {
    type Item = Row<'a>;

    #[inline]
    fn next(&mut self) -> Option<Row<'a>> {
        let sub = *self.log.order.get(self.next)? as usize;
        self.next += 1;
        let i = self.cursors[sub];
        self.cursors[sub] += 1;
        Some(self.log.row(sub, i))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.log.order.len() - self.next;
        (n, Some(n))
    }
}

impl ExactSizeIterator for DataRows<'_> {}
