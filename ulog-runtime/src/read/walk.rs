//! The one pass over a file's messages that every whole-file reader makes: the framer and
//! the interpreter stepped over the file's bytes (in memory, or a window refilled by reads),
//! the rows handed to a sink (a [`Log`]'s row index, a count, a fold), on several threads
//! for a large file, each extra thread reading a part that starts at a boundary beyond
//! doubt and used only if the sequential walk lands on it. [`summarize`], [`fold_rows`] and
//! the crate's visitors of every row are its front ends over bytes; `fold_file` and
//! `MappedFile::fold_rows` over a file and a map.
//!
//! [`Log`]: super::Log

#[cfg(doc)]
use super::Log;
use super::framer::Framer;
use super::metadata::Applied;
use super::window::Source;
use super::{
    Diagnostic, Dropout, FileHeader, LoggedMessage, MESSAGE_HEADER_LEN, Metadata, ParameterChange,
    ReadError, Row, Step, Walker,
};
use crate::schema::Primitive;

/// Where a walk puts the rows it finds: the row index of a [`Log`], a count
/// ([`summarize`]), or a fold ([`fold_rows`]).
pub(crate) trait RowSink: Send + Sized {
    /// Takes one row: its message offset, packed bytes, subscription and timestamp.
    fn row(&mut self, meta: &Metadata, offset: u64, data: &[u8], sub: usize, timestamp: u64);
    /// Rows taken so far.
    fn len(&self) -> usize;
    /// An empty sink for a part of about `bytes` bytes read by another thread.
    fn fork(&self, bytes: usize) -> Self;
    /// Appends what another thread's sink took, which comes next in file order.
    fn append(&mut self, other: Self);
}

/// Counts rows ([`summarize`]).
#[derive(Default)]
pub(super) struct RowCount(usize);

impl RowSink for RowCount {
    #[inline]
    fn row(&mut self, _: &Metadata, _: u64, _: &[u8], _: usize, _: u64) {
        self.0 += 1;
    }
    fn len(&self) -> usize {
        self.0
    }
    fn fork(&self, _: usize) -> Self {
        RowCount(0)
    }
    fn append(&mut self, other: Self) {
        self.0 += other.0;
    }
}

/// Folds rows into accumulators, one per contiguous part of the file ([`fold_rows`]).
pub(crate) struct Fold<'f, T, I, F> {
    init: &'f I,
    fold: &'f F,
    pub(crate) parts: Vec<T>,
}

impl<'f, T, I: Fn() -> T, F> Fold<'f, T, I, F> {
    pub(crate) fn new(init: &'f I, fold: &'f F) -> Self {
        Fold {
            init,
            fold,
            parts: vec![init()],
        }
    }
}

impl<T, I, F> RowVisitor for Fold<'_, T, I, F>
where
    T: Send,
    I: Fn() -> T + Sync,
    F: Fn(&mut T, &Row<'_>) + Sync,
{
    #[inline]
    fn row(&mut self, _: &Metadata, row: &Row<'_>) {
        if let Some(acc) = self.parts.last_mut() {
            (self.fold)(acc, row);
        }
    }
    fn fork(&self) -> Self {
        Fold::new(self.init, self.fold)
    }
    fn append(&mut self, other: Self) {
        self.parts.extend(other.parts);
        // Rows after the appended part start a new accumulator, keeping file order.
        self.parts.push((self.init)());
    }
}

/// What walking (part of) a file collects besides the metadata.
pub(crate) struct Collected<S> {
    pub(crate) sink: S,
    pub(super) other_timestamps: Vec<(u64, u64)>,
    pub(super) logged: Vec<LoggedMessage>,
    pub(super) changes: Vec<ParameterChange>,
    pub(super) dropouts: Vec<Dropout>,
    pub(super) sync_offsets: Vec<u64>,
    pub(super) diagnostics: Vec<Diagnostic>,
    /// Latest row timestamp (worker parts).
    max_timestamp: u64,
}

/// How far a walk went.
enum Walked {
    /// Reached the limit (the next message starts at or after it).
    Limit,
    /// The file ended.
    End,
    /// A worker stopped before a message it leaves to the sequential walk.
    Stopped,
}

/// Below this many bytes of data a file is read on one thread.
#[cfg(not(fuzzing))]
const PARALLEL_MIN_LEN: usize = 8 << 20;
/// In a fuzzing build, a few hundred bytes: the fuzzer's small inputs are split between
/// threads too, so that it tries the parallel walk's boundaries and checks.
#[cfg(fuzzing)]
const PARALLEL_MIN_LEN: usize = 256;

impl<S: RowSink> Collected<S> {
    fn new(sink: S) -> Collected<S> {
        Collected {
            sink,
            other_timestamps: Vec::new(),
            logged: Vec::new(),
            changes: Vec::new(),
            dropouts: Vec::new(),
            sync_offsets: Vec::new(),
            diagnostics: Vec::new(),
            max_timestamp: 0,
        }
    }

    /// Walks from the walker's position until the next message starts at or after `limit`.
    /// A worker (`worker`) takes only rows, sync, logged strings, dropouts and parameter
    /// changes, and stops before anything else, which the sequential walk then reads.
    fn walk(
        &mut self,
        walker: &mut Walker,
        src: &mut impl Source,
        limit: u64,
        worker: bool,
    ) -> Result<Walked, ReadError> {
        loop {
            let (pos, prev) = (walker.framer.pos(), walker.framer.prev());
            if pos >= limit {
                return Ok(Walked::Limit);
            }
            let (data, base, eof) = src.window();
            let (sink, mut latest) = (&mut self.sink, self.max_timestamp);
            let taken = walker.fast_rows(data, base, limit, |meta, row| {
                sink.row(meta, row.offset, &data[row.data], row.sub, row.timestamp);
                latest = latest.max(row.timestamp);
                true
            });
            if taken {
                self.max_timestamp = latest;
                continue;
            }
            if worker {
                // The message at `pos`, if the window holds all of it.
                let message = pos
                    .checked_sub(base)
                    .and_then(|at| usize::try_from(at).ok())
                    .and_then(|at| {
                        let h = data.get(at..at + MESSAGE_HEADER_LEN)?;
                        let size = usize::from(u16::from_le_bytes([h[0], h[1]]));
                        data.get(at..at + MESSAGE_HEADER_LEN + size)
                    });
                if message.is_none() && !eof {
                    // A message the window cuts (the fast path takes only whole ones).
                    src.refill(pos)?;
                    continue;
                }
                let plain = !walker.framer.is_busy()
                    && message.is_some_and(|m| matches!(m[2], b'S' | b'L' | b'C' | b'O' | b'P'));
                if !plain {
                    return Ok(Walked::Stopped);
                }
            }
            match walker.step(data, base, eof)? {
                Step::Applied {
                    offset,
                    applied,
                    payload,
                } => match applied {
                    Applied::Sync => self.sync_offsets.push(offset),
                    Applied::Logged(m) => self.logged.push(m),
                    Applied::Dropout(d) => self.dropouts.push(d),
                    Applied::ParameterChange(c) => self.changes.push(c),
                    _ if worker => {
                        walker.framer.resume_at(pos, prev);
                        return Ok(Walked::Stopped);
                    }
                    Applied::Nothing => {}
                    Applied::Subscribed {
                        diagnostic,
                        duplicate,
                        ..
                    } => self
                        .diagnostics
                        .extend(diagnostic.into_iter().chain(duplicate.map(|d| *d))),
                    Applied::Row { sub, timestamp } => {
                        if walker.meta.subscriptions[sub].timestamp_type()
                            != Some(Primitive::UInt64)
                        {
                            self.other_timestamps.push((offset, timestamp));
                        }
                        self.sink
                            .row(&walker.meta, offset, &payload[2..], sub, timestamp);
                    }
                    Applied::Noted(d) | Applied::Diagnostic(d) => self.diagnostics.push(d),
                },
                Step::NeedMore { keep_from } if !eof => src.refill(keep_from)?,
                Step::NeedMore { .. } | Step::End => return Ok(Walked::End),
            }
        }
    }

    /// Appends a worker's part; `before` is the latest data timestamp before the part, which
    /// the part's dropouts and parameter changes are dated with when it is later than theirs.
    fn append(&mut self, mut part: Collected<S>, before: u64) {
        self.sink.append(part.sink);
        self.other_timestamps.append(&mut part.other_timestamps);
        self.logged.append(&mut part.logged);
        self.changes
            .extend(part.changes.into_iter().map(|c| ParameterChange {
                timestamp: c.timestamp.max(before),
                ..c
            }));
        self.dropouts
            .extend(part.dropouts.into_iter().map(|d| Dropout {
                timestamp: d.timestamp.max(before),
                ..d
            }));
        self.sync_offsets.append(&mut part.sync_offsets);
        self.diagnostics.append(&mut part.diagnostics);
    }
}

/// What a whole file holds besides its rows, as [`summarize`] finds it.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct Summary {
    /// Formats, info, parameters, subscriptions.
    pub metadata: Metadata,
    /// Number of data rows.
    pub rows: usize,
    /// Logged strings, in file order.
    pub logged_messages: Vec<LoggedMessage>,
    /// Parameter changes, in file order.
    pub parameter_changes: Vec<ParameterChange>,
    /// Dropouts, in file order.
    pub dropouts: Vec<Dropout>,
    /// Offsets of the sync messages.
    pub sync_offsets: Vec<u64>,
    /// Everything found wrong or unusual (see [`Log::diagnostics`]).
    pub diagnostics: Vec<Diagnostic>,
}

/// Walks a whole file as [`Log::from_slice`] does (every message framed and validated,
/// corruption recovered and reported, on several threads for large files) but keeps no row
/// index: the fastest way to check a file, count its rows or read its metadata.
///
/// ```
/// # use ulog_runtime::read::{summarize, FileHeader, Message};
/// let mut bytes = FileHeader { version: 1, start_timestamp: 0 }.to_bytes().to_vec();
/// Message::Format(b"t:uint64_t timestamp;").encode(&mut bytes).unwrap();
/// Message::Subscribe { multi_id: 0, msg_id: 0, name: b"t" }.encode(&mut bytes).unwrap();
/// Message::Data { msg_id: 0, data: &7u64.to_le_bytes() }.encode(&mut bytes).unwrap();
/// let summary = summarize(&bytes).unwrap();
/// assert_eq!((summary.rows, summary.diagnostics.len()), (1, 0));
/// ```
pub fn summarize(bytes: &[u8]) -> Result<Summary, ReadError> {
    let (metadata, all) = collect(bytes, RowCount::default(), all_cores())?;
    Ok(summary(metadata, all))
}

pub(crate) fn summary<S: RowSink>(metadata: Metadata, all: Collected<S>) -> Summary {
    Summary {
        metadata,
        rows: all.sink.len(),
        logged_messages: all.logged,
        parameter_changes: all.changes,
        dropouts: all.dropouts,
        sync_offsets: all.sync_offsets,
        diagnostics: all.diagnostics,
    }
}

/// Walks a whole file as [`summarize`] does and folds every row into an accumulator as it is
/// found: the fastest way through every row, as it reads the file once and, for large files,
/// on all cores. Each thread folds a contiguous part of the file into accumulators of its
/// own, made by `init`; the accumulators come back in file order, so combining them in that
/// order gives the same result on every run. The rows are exactly those [`Log::data`]
/// yields, each in exactly one accumulator.
///
/// What to expect of the closures:
/// - `init` is called once for a file below 8 MB, and up to `2 × threads - 1` times for a
///   larger one (an accumulator may stay empty).
/// - `fold` may also see rows that end up in no accumulator. A thread that reads a part
///   ahead starts at a message boundary it finds, with the subscriptions known when the
///   walk split; its part is kept only if the sequential walk lands on that boundary in
///   the same state, else it is dropped and the sequential walk folds those rows again (a
///   damaged file, or a log that defines formats or subscribes anew in the middle: a log
///   written twice into one file, say). A dropped part's rows may even have been read
///   under an older subscription of their `msg_id`. So keep the result in the accumulator:
///   a side effect of `fold` (a counter, a channel, a print) may happen for rows the
///   result does not have, or has under another topic.
/// - A panic in `fold` or `init` on any thread reaches the caller as that panic.
///
/// ```
/// # use ulog_runtime::read::{fold_rows, FileHeader, Message};
/// # let mut bytes = FileHeader { version: 1, start_timestamp: 0 }.to_bytes().to_vec();
/// # Message::Format(b"t:uint64_t timestamp;float x;").encode(&mut bytes).unwrap();
/// # Message::Subscribe { multi_id: 0, msg_id: 0, name: b"t" }.encode(&mut bytes).unwrap();
/// # for i in 0..3u64 {
/// #     let mut row = i.to_le_bytes().to_vec();
/// #     row.extend_from_slice(&(i as f32).to_le_bytes());
/// #     Message::Data { msg_id: 0, data: &row }.encode(&mut bytes).unwrap();
/// # }
/// // Sum of every leaf of every row.
/// let (summary, parts) = fold_rows(&bytes, || 0.0f64, |sum, row| {
///     row.for_each_leaf(|v| *sum += v.as_f64());
/// })
/// .unwrap();
/// assert_eq!((summary.rows, parts.iter().sum::<f64>()), (3, 6.0));
/// ```
pub fn fold_rows<T, I, F>(bytes: &[u8], init: I, fold: F) -> Result<(Summary, Vec<T>), ReadError>
where
    T: Send,
    I: Fn() -> T + Sync,
    F: Fn(&mut T, &Row<'_>) + Sync,
{
    fold_rows_on(all_cores(), bytes, init, fold)
}

/// [`fold_rows`] on at most `threads` threads (1: this thread only), for programs that read
/// many logs at once, one log a thread.
pub fn fold_rows_on<T, I, F>(
    threads: usize,
    bytes: &[u8],
    init: I,
    fold: F,
) -> Result<(Summary, Vec<T>), ReadError>
where
    T: Send,
    I: Fn() -> T + Sync,
    F: Fn(&mut T, &Row<'_>) + Sync,
{
    let header = FileHeader::parse(bytes)?;
    let mut src = bytes;
    fold_from(header, &mut src, &bytes, threads, &init, &fold)
}

/// Folds every row of a file whose header is `header`, read through `src` (its window at the
/// start of the file) and in `parts` on up to `threads` threads: [`fold_rows`] of bytes,
/// [`fold_file`](super::fold_file) of a file.
pub(crate) fn fold_from<T, I, F, P: Parts>(
    header: FileHeader,
    src: &mut impl Source,
    parts: &P,
    threads: usize,
    init: &I,
    fold: &F,
) -> Result<(Summary, Vec<T>), ReadError>
where
    T: Send,
    I: Fn() -> T + Sync,
    F: Fn(&mut T, &Row<'_>) + Sync,
{
    let sink = Visiting::new(Fold::new(init, fold));
    let (metadata, mut all) = collect_from(header, src, parts, sink, threads.max(1))?;
    let parts = std::mem::take(&mut all.sink.visitor.parts);
    Ok((summary(metadata, all), parts))
}

/// A consumer of every row of a walk, with the metadata read up to it, that can be split
/// between threads reading parts of the file ([`visit_rows`]).
pub(crate) trait RowVisitor: Send + Sized {
    /// Takes one row, in file order within its part.
    fn row(&mut self, meta: &Metadata, row: &Row<'_>);
    /// An empty visitor for a part read by another thread.
    fn fork(&self) -> Self;
    /// Takes in what another thread's visitor saw, of the part that comes next.
    fn append(&mut self, other: Self);
}

/// A visitor as a walk's sink ([`visit_rows`], [`fold_rows`]).
pub(crate) struct Visiting<V> {
    pub(crate) visitor: V,
    rows: usize,
}

impl<V> Visiting<V> {
    pub(crate) fn new(visitor: V) -> Visiting<V> {
        Visiting { visitor, rows: 0 }
    }
}

impl<V: RowVisitor> RowSink for Visiting<V> {
    #[inline]
    fn row(&mut self, meta: &Metadata, offset: u64, data: &[u8], sub: usize, timestamp: u64) {
        let row = Row {
            timestamp,
            offset,
            data,
            subscription: &meta.subscriptions[sub],
            schema: &meta.schema,
        };
        self.visitor.row(meta, &row);
        self.rows += 1;
    }
    fn len(&self) -> usize {
        self.rows
    }
    fn fork(&self, _: usize) -> Self {
        Visiting {
            visitor: self.visitor.fork(),
            rows: 0,
        }
    }
    fn append(&mut self, other: Self) {
        self.rows += other.rows;
        self.visitor.append(other.visitor);
    }
}

/// Walks a whole file as [`fold_rows_on`] does, on at most `threads` threads, every row to
/// `visitor` (or to its forks, for parts read by other threads, appended in file order).
pub(crate) fn visit_rows<V: RowVisitor>(
    bytes: &[u8],
    visitor: V,
    threads: usize,
) -> Result<(Summary, V), ReadError> {
    let (metadata, all) = collect(bytes, Visiting::new(visitor), threads.max(1))?;
    let Collected {
        sink: Visiting { visitor, rows },
        logged,
        changes,
        dropouts,
        sync_offsets,
        diagnostics,
        ..
    } = all;
    let summary = Summary {
        metadata,
        rows,
        logged_messages: logged,
        parameter_changes: changes,
        dropouts,
        sync_offsets,
        diagnostics,
    };
    Ok((summary, visitor))
}

/// The threads a walk (or a gathering of columns) uses by default: every core, up to 8.
/// Asked of the system once per process: the question reads the control groups' files,
/// tens of microseconds a call.
pub(crate) fn all_cores() -> usize {
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *CORES.get_or_init(|| {
        std::thread::available_parallelism()
            .map_or(1, usize::from)
            .min(8)
    })
}

/// Walks a whole file on up to `threads` threads, rows going to `sink`.
pub(crate) fn collect<S: RowSink>(
    data: &[u8],
    sink: S,
    threads: usize,
) -> Result<(Metadata, Collected<S>), ReadError> {
    let header = FileHeader::parse(data)?;
    let mut src = data;
    collect_from(header, &mut src, &data, sink, threads)
}

/// [`collect`] of a file whose header is `header`, read through `src` (its window at the
/// start of the file), in `parts` on up to `threads` threads.
pub(crate) fn collect_from<S: RowSink, P: Parts>(
    header: FileHeader,
    src: &mut impl Source,
    parts: &P,
    sink: S,
    threads: usize,
) -> Result<(Metadata, Collected<S>), ReadError> {
    let mut walker = Walker::new(header);
    let mut all = Collected::new(sink);
    all.diagnostics.extend(walker.meta.header_diagnostic());
    // The definitions and the start of the data, where logs subscribe most topics, on
    // this thread.
    let prefix = (parts.len() / 64).min(8 << 20);
    all.walk(&mut walker, src, prefix, false)?;
    walk_rest(&mut all, &mut walker, src, parts, threads)?;
    Ok((walker.meta, all))
}

/// A file that threads can read parts of side by side: in memory, or by positioned reads.
pub(crate) trait Parts: Sync {
    /// What a thread reads its part through.
    type Part<'p>: Source + Send
    where
        Self: 'p;
    /// The file's length.
    fn len(&self) -> u64;
    /// A source whose window starts at `from`.
    fn part(&self, from: u64) -> Self::Part<'_>;
    /// [`Framer::find_boundary`] in the megabyte from `from` on.
    ///
    /// [`Framer::find_boundary`]: super::framer::Framer::find_boundary
    fn boundary(&self, framer: &Framer, from: u64) -> Result<Option<u64>, ReadError>;
}

/// How far from a part's planned start its first boundary is looked for.
pub(crate) const BOUNDARY_SCAN: usize = 1 << 20;
/// How many strongly plausible messages in a row make a boundary.
pub(crate) const BOUNDARY_CHAIN: usize = 4;

impl<'a> Parts for &'a [u8] {
    type Part<'p>
        = &'a [u8]
    where
        Self: 'p;
    fn len(&self) -> u64 {
        <[u8]>::len(self) as u64
    }
    fn part(&self, _: u64) -> &'a [u8] {
        self
    }
    fn boundary(&self, framer: &Framer, from: u64) -> Result<Option<u64>, ReadError> {
        Ok(framer.find_boundary(self, 0, from, BOUNDARY_SCAN, BOUNDARY_CHAIN))
    }
}

/// Reads the rest of the file, in parts on several threads when it is large.
///
/// Each extra thread starts at a boundary beyond doubt (a chain of strongly plausible
/// messages) with a copy of the walker, and reads only messages that cannot change how
/// later ones are read. Its part is used only if this thread's own walk lands exactly on
/// that boundary with the state the copy had; otherwise this thread reads the part itself.
/// The result is the same as a sequential read either way.
fn walk_rest<S: RowSink, P: Parts>(
    all: &mut Collected<S>,
    walker: &mut Walker,
    src: &mut impl Source,
    parts: &P,
    threads: usize,
) -> Result<(), ReadError> {
    let start = walker.framer.pos();
    let len = parts.len();
    let rest = len.saturating_sub(start);
    if threads < 2
        || rest < PARALLEL_MIN_LEN as u64
        || walker.framer.has_segments()
        || walker.framer.is_busy()
    {
        all.walk(walker, src, u64::MAX, false)?;
        return Ok(());
    }
    let mut bounds: Vec<u64> = Vec::new();
    for k in 1..threads as u64 {
        // (In 128 bits: the length of a sparse file can be near 2^63.)
        let near = u64::try_from(u128::from(len) * u128::from(k) / threads as u128)
            .unwrap_or(len)
            .max(start);
        bounds.extend(parts.boundary(&walker.framer, near)?);
    }
    bounds.sort_unstable();
    bounds.dedup();
    bounds.push(len);
    let snapshot = walker.clone();
    std::thread::scope(|scope| -> Result<(), ReadError> {
        let workers: Vec<_> = bounds
            .windows(2)
            .map(|w| {
                let (from, to) = (w[0], w[1]);
                let mut copy = snapshot.clone();
                let sink = all
                    .sink
                    .fork(usize::try_from(to - from).unwrap_or(usize::MAX));
                scope.spawn(move || {
                    copy.framer.resume_at(from, None);
                    let mut part = Collected::new(sink);
                    let mut src = parts.part(from);
                    let walked = part.walk(&mut copy, &mut src, to, true);
                    (walked.map(|_| ()), copy, part)
                })
            })
            .collect();
        // A worker's panic (the caller's `fold`, say) reaches the caller as itself, even when
        // the walk fails meanwhile: every worker is joined before an error is returned.
        let join = |w: std::thread::ScopedJoinHandle<'_, _>| {
            w.join().unwrap_or_else(|p| std::panic::resume_unwind(p))
        };
        let mut workers = workers.into_iter();
        let mut limit = bounds[0];
        let mut failed = None;
        for worker in workers.by_ref() {
            if let Err(e) = all.walk(walker, src, limit, false) {
                let _ = join(worker);
                failed = Some(e);
                break;
            }
            let (walked, copy, part) = join(worker);
            if let Err(e) = walked {
                failed = Some(e);
                break;
            }
            let usable = walker.framer.pos() == limit
                && !walker.framer.is_busy()
                && walker.epoch == snapshot.epoch;
            let next = bounds.iter().copied().find(|&b| b > limit).unwrap_or(len);
            if usable {
                let before = walker.meta.last_timestamp();
                let dropped: u64 = part.dropouts.iter().map(|d| u64::from(d.duration_ms)).sum();
                walker.meta.absorb(
                    part.max_timestamp,
                    part.sync_offsets.len() as u64,
                    dropped,
                    copy.meta.in_data_section(),
                );
                walker
                    .framer
                    .resume_at(copy.framer.pos(), copy.framer.prev());
                all.append(part, before);
            }
            limit = next;
        }
        if let Some(e) = failed {
            for w in workers {
                let _ = join(w);
            }
            return Err(e);
        }
        all.walk(walker, src, u64::MAX, false)?;
        Ok(())
    })
}
