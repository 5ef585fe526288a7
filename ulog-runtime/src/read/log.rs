//! The whole-file view: one pass over bytes (owned, borrowed or memory-mapped; the walk of
//! `walk`) collects the metadata and an index of data rows per subscription; rows are then
//! read in place.

use std::path::Path;

use super::threads::on_threads;
use super::walk::{RowSink, all_cores, collect};
use super::{
    Diagnostic, Dropout, FileHeader, FlagBits, LoggedMessage, MESSAGE_HEADER_LEN, Metadata,
    ParameterChange, ReadError, Row, Subscription,
};
use crate::schema::Primitive;

enum Bytes<'a> {
    Borrowed(&'a [u8]),
    Owned(Vec<u8>),
    #[cfg(feature = "mmap")]
    Mapped(super::MappedFile),
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

/// File offsets of the data rows, in file order, and their subscriptions, 6 bytes a row:
/// chunks of offsets relative to a base, a new chunk where the distance no longer fits (and
/// one per part read in parallel, moved in rather than copied).
#[derive(Debug, Default)]
struct RowIndex {
    chunks: Vec<Chunk>,
    /// Capacity for the first chunk.
    reserve: usize,
}

#[derive(Debug)]
struct Chunk {
    base: u64,
    /// Row number of `offsets[0]`.
    first: usize,
    offsets: Vec<u32>,
    /// Each row's subscription, or [`MANY`] for one numbered that or higher.
    subs: Vec<u16>,
}

/// [`Chunk::subs`]: a subscription found from the row's message instead.
const MANY: u16 = u16::MAX;

impl Chunk {
    fn end(&self) -> usize {
        self.first + self.offsets.len()
    }
}

impl RowIndex {
    fn with_capacity(reserve: usize) -> RowIndex {
        RowIndex {
            reserve,
            ..RowIndex::default()
        }
    }

    fn len(&self) -> usize {
        self.chunks.last().map_or(0, Chunk::end)
    }

    #[inline]
    fn push(&mut self, offset: u64, sub: usize) {
        let sub = u16::try_from(sub).unwrap_or(MANY);
        if let Some(c) = self.chunks.last_mut()
            && let Ok(rel) = u32::try_from(offset - c.base)
        {
            c.offsets.push(rel);
            c.subs.push(sub);
            return;
        }
        self.new_chunk(offset, sub);
    }

    #[cold]
    fn new_chunk(&mut self, offset: u64, sub: u16) {
        let reserve = std::mem::take(&mut self.reserve).max(1024);
        let mut offsets = Vec::with_capacity(reserve);
        offsets.push(0);
        let mut subs = Vec::with_capacity(reserve);
        subs.push(sub);
        self.chunks.push(Chunk {
            base: offset,
            first: self.len(),
            offsets,
            subs,
        });
    }

    fn append(&mut self, other: RowIndex) {
        for mut c in other.chunks {
            c.first = self.len();
            self.chunks.push(c);
        }
    }

    /// Offset of row `i`, and the chunk it is in.
    fn get(&self, i: usize) -> (u64, usize) {
        let k = self.chunks.partition_point(|c| c.end() <= i);
        let c = &self.chunks[k];
        (c.base + u64::from(c.offsets[i - c.first]), k)
    }

    /// Calls `f` with the offset of each row of `range` and its subscription (or [`MANY`]),
    /// in order.
    fn for_each_offset(&self, range: std::ops::Range<usize>, mut f: impl FnMut(u64, u16)) {
        let first = self.chunks.partition_point(|c| c.end() <= range.start);
        for c in &self.chunks[first..] {
            if c.first >= range.end {
                break;
            }
            let from = range.start.max(c.first);
            let to = range.end.min(c.end());
            let rows = from - c.first..to - c.first;
            for (&rel, &sub) in c.offsets[rows.clone()].iter().zip(&c.subs[rows]) {
                f(c.base + u64::from(rel), sub);
            }
        }
    }

    fn shrink_to_fit(&mut self) {
        self.chunks.iter_mut().for_each(|c| {
            c.offsets.shrink_to_fit();
            c.subs.shrink_to_fit();
        });
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
    index: RowIndex,
    /// Unwrapped timestamps of rows whose `timestamp` is not `uint64_t`, by the file offset
    /// of the row's message (ascending).
    other_timestamps: Vec<(u64, u64)>,
    /// File offsets of the rows of each subscription, built at the first per-subscription
    /// access: a row is then read without a lookup in the index.
    by_sub: std::sync::OnceLock<Vec<Vec<u64>>>,
    logged: Vec<LoggedMessage>,
    changes: Vec<ParameterChange>,
    dropouts: Vec<Dropout>,
    sync_offsets: Vec<u64>,
    diagnostics: Vec<Diagnostic>,
}

impl RowSink for RowIndex {
    #[inline]
    fn row(&mut self, _: &Metadata, offset: u64, _: &[u8], sub: usize, _: u64) {
        self.push(offset, sub);
    }
    fn len(&self) -> usize {
        RowIndex::len(self)
    }
    fn fork(&self, bytes: usize) -> Self {
        // Real logs average well over 32 bytes a row; a wrong guess only costs a regrowth.
        RowIndex::with_capacity(bytes / 32)
    }
    fn append(&mut self, other: Self) {
        RowIndex::append(self, other);
    }
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
        Log::from_bytes(Bytes::Mapped(super::MappedFile::open(path)?))
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
        // Real logs average well over 32 bytes a row; a wrong guess only costs a regrowth.
        let index = RowIndex::default().fork(bytes.as_slice().len());
        let (meta, mut all) = collect(bytes.as_slice(), index, all_cores())?;
        all.sink.shrink_to_fit();
        Ok(Log {
            bytes,
            meta,
            index: all.sink,
            other_timestamps: all.other_timestamps,
            by_sub: std::sync::OnceLock::new(),
            logged: all.logged,
            changes: all.changes,
            dropouts: all.dropouts,
            sync_offsets: all.sync_offsets,
            diagnostics: all.diagnostics,
        })
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
    /// The first call of a log (of this or of anything per subscription: [`Log::topics`],
    /// [`Log::columns`]...) sorts the log's rows by subscription once, from the row index,
    /// on every core for a large log (8 bytes a row; about 20 ms for the 6.8 million rows
    /// of a 400 MB log on 2 cores).
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
        let rows = self.row_offsets(sub.index);
        Rows {
            log: self,
            // A subscription's rows are all its format's size, but for odd files.
            span: rows
                .first()
                .map_or(0, |&at| MESSAGE_HEADER_LEN + 2 + self.row_data(at).len()),
            rows: rows.iter(),
        }
    }

    /// The file offsets of the messages of the rows of the `index`-th subscription, in file
    /// order.
    pub(crate) fn row_offsets(&self, index: usize) -> &[u64] {
        let by_sub = self
            .by_sub
            .get_or_init(|| self.offsets_by_subscription(all_cores(), MIN_ROWS_A_THREAD));
        &by_sub[index]
    }

    /// The file offsets of each subscription's rows, in file order, the index split in
    /// runs of rows, one a thread (up to `threads`, a thread for `min_rows` rows or more):
    /// each run's rows counted per subscription (which the index keeps for each row), then
    /// every offset written in its place, the lists allocated once at their length.
    pub(super) fn offsets_by_subscription(&self, threads: usize, min_rows: usize) -> Vec<Vec<u64>> {
        let rows = self.index.len();
        let runs = threads.min(rows / min_rows.max(1)).max(1);
        let ranges: Vec<_> = (0..runs)
            .map(|k| rows * k / runs..rows * (k + 1) / runs)
            .collect();
        let subscriptions = self.meta.subscriptions.len();
        let sub_of = |at: u64, sub: u16| match sub {
            MANY => self.subscription_of(at),
            sub => usize::from(sub),
        };
        // How many rows each subscription has in each run.
        let counts: Vec<Vec<usize>> = on_threads(ranges.clone(), |range| {
            let mut counts = vec![0usize; subscriptions];
            self.index
                .for_each_offset(range, |at, sub| counts[sub_of(at, sub)] += 1);
            counts
        });
        let mut by_sub: Vec<Vec<u64>> = (0..subscriptions)
            .map(|s| vec![0; counts.iter().map(|c| c[s]).sum()])
            .collect();
        // Each list cut into the runs' places, in run order.
        let mut places: Vec<Vec<&mut [u64]>> = (0..runs).map(|_| Vec::new()).collect();
        for (s, list) in by_sub.iter_mut().enumerate() {
            let mut rest = list.as_mut_slice();
            for (run, counts) in places.iter_mut().zip(&counts) {
                let (place, after) = rest.split_at_mut(counts[s]);
                run.push(place);
                rest = after;
            }
        }
        on_threads(
            ranges.into_iter().zip(places).collect(),
            |(range, mut places)| {
                let mut filled = vec![0usize; places.len()];
                self.index.for_each_offset(range, |at, sub| {
                    let s = sub_of(at, sub);
                    places[s][filled[s]] = at;
                    filled[s] += 1;
                });
            },
        );
        by_sub
    }

    /// The subscription of the row whose message is at `at`.
    #[inline]
    fn subscription_of(&self, at: u64) -> usize {
        let bytes = self.bytes.as_slice();
        let id = at as usize + MESSAGE_HEADER_LEN;
        self.meta
            .subscription_at(u16::from_le_bytes([bytes[id], bytes[id + 1]]), at)
            .expect("indexed rows have a subscription")
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
        let chunk = self
            .index
            .chunks
            .partition_point(|c| c.end() <= range.start);
        DataRows {
            log: self,
            range,
            chunk,
        }
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
        self.diagnostics
            .iter()
            .filter_map(Diagnostic::damaged_range)
    }

    /// The data of the row whose message is at file offset `at` (no subscription lookup, no
    /// timestamp).
    #[inline(always)]
    pub(crate) fn row_data(&self, at: u64) -> &[u8] {
        let bytes = self.bytes.as_slice();
        let at = at as usize;
        let size = usize::from(u16::from_le_bytes([bytes[at], bytes[at + 1]]));
        &bytes[at + MESSAGE_HEADER_LEN + 2..at + MESSAGE_HEADER_LEN + size]
    }

    /// The row whose message is at file offset `at`.
    #[inline(always)]
    pub(crate) fn row_at(&self, at: u64) -> Row<'_> {
        let bytes = self.bytes.as_slice();
        let at = at as usize;
        let size = usize::from(u16::from_le_bytes([bytes[at], bytes[at + 1]]));
        let data = &bytes[at + MESSAGE_HEADER_LEN + 2..at + MESSAGE_HEADER_LEN + size];
        let msg_id = u16::from_le_bytes([
            bytes[at + MESSAGE_HEADER_LEN],
            bytes[at + MESSAGE_HEADER_LEN + 1],
        ]);
        let sub = self
            .meta
            .subscription_at(msg_id, at as u64)
            .expect("indexed rows have a subscription");
        let subscription = &self.meta.subscriptions[sub];
        let timestamp = match subscription.timestamp {
            Some((ts, Primitive::UInt64)) => {
                u64::from_le_bytes(data[ts..ts + 8].try_into().expect("8 bytes"))
            }
            _ => self
                .other_timestamps
                .binary_search_by_key(&(at as u64), |&(offset, _)| offset)
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

    pub(crate) fn row(&self, i: usize) -> Row<'_> {
        self.row_at(self.index.get(i).0)
    }
}

/// The rows of one subscription ([`Log::rows`]).
#[derive(Debug, Clone)]
pub struct Rows<'a> {
    log: &'a Log<'a>,
    rows: std::slice::Iter<'a, u64>,
    /// Bytes of the first row's message: how much of the rows ahead to prefetch.
    span: usize,
}

/// Rows ahead of the one read whose message the reader asks the processor to fetch: one
/// topic's rows are scattered through the file, and each is a cache miss otherwise.
pub(crate) const PREFETCH_ROWS: usize = 32;

/// Starts loading the cache lines of `bytes[at..at + span]` (at least the first) into the
/// cache (nothing out of bounds, or where the processor is not x86-64).
#[inline(always)]
pub(crate) fn prefetch(bytes: &[u8], at: u64, span: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        let at = at as usize;
        let mut line = 0;
        while let Some(b) = bytes.get(at + line) {
            // SAFETY: a prefetch never faults and reads nothing into the program; the
            // address is in bounds of a live slice anyway.
            #[allow(unsafe_code)]
            unsafe {
                core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(
                    std::ptr::from_ref(b).cast(),
                );
            }
            line += 64;
            if line >= span {
                break;
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (bytes, at, span);
}

impl<'a> Iterator for Rows<'a> {
    type Item = Row<'a>;

    #[inline]
    fn next(&mut self) -> Option<Row<'a>> {
        let &at = self.rows.next()?;
        if let Some(&ahead) = self.rows.as_slice().get(PREFETCH_ROWS) {
            prefetch(self.log.bytes.as_slice(), ahead, self.span);
        }
        Some(self.log.row_at(at))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.rows.size_hint()
    }
}

impl ExactSizeIterator for Rows<'_> {}

impl<'a> Rows<'a> {
    /// The rows left, in `parts` runs of consecutive rows (as many rows each as can be, in
    /// order; fewer runs than `parts` when there are fewer rows).
    pub(crate) fn split(self, parts: usize) -> Vec<Rows<'a>> {
        let rows = self.rows.as_slice();
        let per = rows.len().div_ceil(parts.max(1)).max(1);
        rows.chunks(per)
            .map(|run| Rows {
                log: self.log,
                rows: run.iter(),
                span: self.span,
            })
            .collect()
    }
}

impl DoubleEndedIterator for Rows<'_> {
    fn next_back(&mut self) -> Option<Self::Item> {
        self.rows.next_back().map(|&at| self.log.row_at(at))
    }
}

/// Rows of a log in file order ([`Log::data`], [`Log::data_range`]).
#[derive(Debug, Clone)]
pub struct DataRows<'a> {
    log: &'a Log<'a>,
    range: std::ops::Range<usize>,
    chunk: usize,
}

impl<'a> Iterator for DataRows<'a> {
    type Item = Row<'a>;

    #[inline]
    fn next(&mut self) -> Option<Row<'a>> {
        let i = self.range.next()?;
        let chunks = &self.log.index.chunks;
        while chunks[self.chunk].end() <= i {
            self.chunk += 1;
        }
        let c = &chunks[self.chunk];
        Some(self.log.row_at(c.base + u64::from(c.offsets[i - c.first])))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.range.size_hint()
    }

    /// Internal iteration, chunk by chunk (what `for_each`, `sum` and friends use).
    #[inline]
    fn fold<B, F: FnMut(B, Row<'a>) -> B>(self, init: B, mut f: F) -> B {
        let mut acc = init;
        let (log, range) = (self.log, self.range);
        for c in &log.index.chunks[self.chunk..] {
            if c.first >= range.end {
                break;
            }
            let from = range.start.max(c.first);
            let to = range.end.min(c.end());
            for &rel in &c.offsets[from - c.first..to - c.first] {
                acc = f(acc, log.row_at(c.base + u64::from(rel)));
            }
        }
        acc
    }
}

impl ExactSizeIterator for DataRows<'_> {}

impl DoubleEndedIterator for DataRows<'_> {
    fn next_back(&mut self) -> Option<Self::Item> {
        self.range.next_back().map(|i| self.log.row(i))
    }
}

/// Fewest rows a thread is given to sort by subscription (the first [`Log::rows`]).
const MIN_ROWS_A_THREAD: usize = 1 << 20;
