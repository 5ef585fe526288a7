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

/// One data row in the file-order index: the message offset in the high 40 bits, the
/// subscription index in the low 24.
#[derive(Debug, Clone, Copy)]
struct RowRef(u64);

const SUB_BITS: u32 = 24;
/// Largest file the row index can address (1 TiB).
const MAX_FILE_LEN: u64 = 1 << (64 - SUB_BITS);

impl RowRef {
    #[inline]
    fn new(offset: usize, sub: usize) -> RowRef {
        RowRef(((offset as u64) << SUB_BITS) | sub as u64)
    }
    #[inline]
    fn offset(self) -> usize {
        (self.0 >> SUB_BITS) as usize
    }
    #[inline]
    fn sub(self) -> usize {
        (self.0 & ((1 << SUB_BITS) - 1)) as usize
    }
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
    /// Every row, in file order.
    index: Vec<RowRef>,
    /// Unwrapped timestamps of rows whose `timestamp` is not `uint64_t`, by row number.
    other_timestamps: Vec<(usize, u64)>,
    /// Row numbers per subscription, built at the first per-subscription access.
    by_sub: std::sync::OnceLock<Vec<Vec<usize>>>,
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
            .field("rows", &self.index.len())
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
        if data.len() as u64 >= MAX_FILE_LEN {
            return Err(ReadError::FileTooLarge {
                len: data.len() as u64,
            });
        }
        let mut walker = Walker::new(header);
        let mut log = Log {
            meta: Metadata::new(header),
            // Real logs average well over 32 bytes a row; a wrong guess only costs a regrowth.
            index: Vec::with_capacity(data.len() / 32),
            other_timestamps: Vec::new(),
            by_sub: std::sync::OnceLock::new(),
            logged: Vec::new(),
            changes: Vec::new(),
            dropouts: Vec::new(),
            sync_offsets: Vec::new(),
            diagnostics: walker.meta.header_diagnostic().into_iter().collect(),
            bytes: Bytes::Borrowed(&[]),
        };
        loop {
            if let Some((offset, sub, _)) = walker.fast_row(data) {
                log.index.push(RowRef::new(offset, sub));
                continue;
            }
            match walker.step(data, 0, true)? {
                Step::Applied {
                    offset, applied, ..
                } => match applied {
                    Applied::Nothing | Applied::Subscribed { .. } => {}
                    Applied::Row { sub, timestamp } => {
                        if walker.meta.subscriptions[sub].timestamp_type()
                            != Some(Primitive::UInt64)
                        {
                            log.other_timestamps.push((log.index.len(), timestamp));
                        }
                        log.index.push(RowRef::new(offset as usize, sub));
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
        log.index.shrink_to_fit();
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
        assert!(
            self.meta
                .subscriptions
                .get(sub.index)
                .is_some_and(|s| std::ptr::eq(s, sub)),
            "the subscription belongs to this log"
        );
        let by_sub = self.by_sub.get_or_init(|| {
            let mut by_sub = vec![Vec::new(); self.meta.subscriptions.len()];
            for (i, r) in self.index.iter().enumerate() {
                by_sub[r.sub()].push(i);
            }
            by_sub
        });
        Rows {
            log: self,
            rows: by_sub[sub.index].iter(),
        }
    }

    /// Every data row of every subscription, in file order.
    pub fn data(&self) -> DataRows<'_> {
        self.data_range(0..self.index.len())
    }

    /// The data rows numbered `range` in file order (row `i` is the `i`-th of
    /// [`Log::data`]), e.g. to decode parts of a file on several threads.
    ///
    /// # Panics
    /// If the range goes beyond [`Log::row_count`].
    pub fn data_range(&self, range: std::ops::Range<usize>) -> DataRows<'_> {
        assert!(
            range.start <= range.end && range.end <= self.index.len(),
            "row range out of bounds"
        );
        DataRows { log: self, range }
    }

    /// Total number of data rows read.
    pub fn row_count(&self) -> usize {
        self.index.len()
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

    /// Row number `i` in file order.
    #[inline]
    fn row(&self, i: usize) -> Row<'_> {
        let r = self.index[i];
        let (at, sub) = (r.offset(), r.sub());
        let bytes = self.bytes.as_slice();
        let size = usize::from(u16::from_le_bytes([bytes[at], bytes[at + 1]]));
        let data = &bytes[at + MESSAGE_HEADER_LEN + 2..at + MESSAGE_HEADER_LEN + size];
        let subscription = &self.meta.subscriptions[sub];
        let timestamp = match subscription.timestamp {
            Some((ts, Primitive::UInt64)) => {
                u64::from_le_bytes(data[ts..ts + 8].try_into().expect("8 bytes"))
            }
            _ => self
                .other_timestamps
                .binary_search_by_key(&i, |&(row, _)| row)
                .map_or(0, |k| self.other_timestamps[k].1),
        };
        Row {
            timestamp,
            offset: at as u64,
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
    rows: std::slice::Iter<'a, usize>,
}

impl<'a> Iterator for Rows<'a> {
    type Item = Row<'a>;

    #[inline]
    fn next(&mut self) -> Option<Row<'a>> {
        self.rows.next().map(|&i| self.log.row(i))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.rows.size_hint()
    }
}

impl ExactSizeIterator for Rows<'_> {}

impl DoubleEndedIterator for Rows<'_> {
    fn next_back(&mut self) -> Option<Self::Item> {
        self.rows.next_back().map(|&i| self.log.row(i))
    }
}

/// Rows of a log in file order ([`Log::data`], [`Log::data_range`]).
#[derive(Debug, Clone)]
pub struct DataRows<'a> {
    log: &'a Log<'a>,
    range: std::ops::Range<usize>,
}

impl<'a> Iterator for DataRows<'a> {
    type Item = Row<'a>;

    #[inline]
    fn next(&mut self) -> Option<Row<'a>> {
        self.range.next().map(|i| self.log.row(i))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.range.size_hint()
    }
}

impl ExactSizeIterator for DataRows<'_> {}

impl DoubleEndedIterator for DataRows<'_> {
    fn next_back(&mut self) -> Option<Self::Item> {
        self.range.next_back().map(|i| self.log.row(i))
    }
}
