//! Shared code of the example programs, also used by the tests and the benchmarks so that
//! they measure exactly what the examples print.
//!
//! - [`Scan`]: the figures of the `scan` example (rows, leaves, sum of finite leaves).
//! - [`inflate`]: builds a large log from a real one, for benchmarks.

use std::collections::BTreeMap;
use std::io::Read;

use ulog_runtime::read::Subscription;
use ulog_runtime::{Event, Log, ReadError, Row, StreamReader};

/// Totals over rows: how many, how many non-padding leaf values, and the sum of the finite
/// ones as `f64` (`bool` as 0/1, `char` as a signed byte).
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub struct Totals {
    /// Rows.
    pub rows: u64,
    /// Leaf values.
    pub leaves: u64,
    /// Sum of the finite leaf values.
    pub sum: f64,
}

impl Totals {
    /// Adds one row, decoded through the dynamic leaf walk.
    #[inline]
    pub fn add(&mut self, row: &Row<'_>) {
        self.rows += 1;
        let Some(plan) = row.plan() else { return };
        let mut sum = 0.0f64;
        if plan.for_each_leaf(row.data, |v| {
            let x = v.as_f64();
            if x.is_finite() {
                sum += x;
            }
        }) {
            self.leaves += plan.leaf_count() as u64;
            self.sum += sum;
        }
    }
}

/// The figures of the `scan` example for one file: overall and per topic instance.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Scan {
    /// Every row of every subscription.
    pub all: Totals,
    /// Per topic instance, for subscriptions with rows.
    pub topics: BTreeMap<TopicKey, Totals>,
}

/// A topic instance: `(topic, multi_id, msg_id)`.
pub type TopicKey = (String, u8, u16);

/// Per-subscription totals, indexed like the reader's subscription list.
#[derive(Default)]
struct Tally(Vec<Totals>);

impl Tally {
    #[inline]
    fn add(&mut self, row: &Row<'_>) {
        let i = row.subscription.index();
        if self.0.len() <= i {
            self.0.resize(i + 1, Totals::default());
        }
        self.0[i].add(row);
    }

    fn merge(&mut self, other: Tally) {
        if self.0.len() < other.0.len() {
            self.0.resize(other.0.len(), Totals::default());
        }
        for (mine, t) in self.0.iter_mut().zip(other.0) {
            mine.rows += t.rows;
            mine.leaves += t.leaves;
            mine.sum += t.sum;
        }
    }

    /// Names the totals (`subscriptions` is the reader's list) and adds them up.
    fn finish(self, subscriptions: &[Subscription]) -> Scan {
        let mut scan = Scan::default();
        for (t, s) in self
            .0
            .into_iter()
            .zip(subscriptions)
            .filter(|(t, _)| t.rows > 0)
        {
            scan.all.rows += t.rows;
            scan.all.leaves += t.leaves;
            scan.all.sum += t.sum;
            let e = scan
                .topics
                .entry((s.name.clone(), s.multi_id, s.msg_id))
                .or_default();
            e.rows += t.rows;
            e.leaves += t.leaves;
            e.sum += t.sum;
        }
        scan
    }
}

impl Scan {
    /// Scans a whole-file log, the rows split in file order between the machine's cores.
    pub fn log(log: &Log<'_>) -> Scan {
        let threads = std::thread::available_parallelism()
            .map_or(1, usize::from)
            .min(8);
        let n = log.row_count();
        let mut tallies: Vec<Tally> = std::thread::scope(|scope| {
            let workers: Vec<_> = (0..threads)
                .map(|k| {
                    scope.spawn(move || {
                        let mut tally = Tally::default();
                        log.data_range(n * k / threads..n * (k + 1) / threads)
                            .for_each(|row| tally.add(&row));
                        tally
                    })
                })
                .collect();
            workers
                .into_iter()
                .map(|w| w.join().expect("scan threads do not panic"))
                .collect()
        });
        let mut tally = tallies.remove(0);
        for t in tallies {
            tally.merge(t);
        }
        tally.finish(log.subscriptions())
    }

    /// Scans a file held in memory in one pass ([`ulog_runtime::read::fold_rows`]): rows are
    /// decoded as they are found, on all cores for large files.
    pub fn bytes(bytes: &[u8]) -> Result<Scan, ReadError> {
        let (summary, parts) =
            ulog_runtime::read::fold_rows(bytes, Tally::default, |tally, row| tally.add(row))?;
        let mut parts = parts.into_iter();
        let mut tally = parts.next().unwrap_or_default();
        for t in parts {
            tally.merge(t);
        }
        Ok(tally.finish(summary.metadata.subscriptions()))
    }

    /// Scans a stream with [`StreamReader`], row by row.
    pub fn stream(input: impl Read) -> Result<Scan, ReadError> {
        let mut tally = Tally::default();
        let mut reader = StreamReader::new(input)?;
        while let Some(event) = reader.next_event()? {
            if let Event::Row(row) = event {
                tally.add(&row);
            }
        }
        Ok(tally.finish(reader.metadata().subscriptions()))
    }
}

/// Why a log cannot be inflated.
#[derive(Debug, thiserror::Error)]
pub enum InflateError {
    /// The source does not read.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// The source has damage or appended data, which repeating would multiply.
    #[error("the source log must be clean and without appended data ({0})")]
    NotClean(String),
    /// The source has no rows.
    #[error("the source log has no data rows")]
    NoRows,
}

/// Builds a log of at least `min_len` bytes from `source`: the whole source, then its data
/// rows again and again, each copy's `uint64_t` timestamps shifted past the previous copy's, so
/// every topic's timeline still increases.
pub fn inflate(source: &[u8], min_len: usize) -> Result<Vec<u8>, InflateError> {
    let log = Log::from_slice(source)?;
    if let Some(d) = log.diagnostics().first() {
        return Err(InflateError::NotClean(d.to_string()));
    }
    if log.flag_bits().is_some_and(|b| b.has_data_appended()) {
        return Err(InflateError::NotClean("data appended".to_owned()));
    }
    let (lo, hi) = log.data().fold((u64::MAX, 0), |(lo, hi), r| {
        (lo.min(r.timestamp), hi.max(r.timestamp))
    });
    if lo > hi {
        return Err(InflateError::NoRows);
    }
    let span = hi - lo + 1_000;
    let mut out = Vec::with_capacity(min_len + source.len());
    out.extend_from_slice(source);
    let mut copy = 1u64;
    while out.len() < min_len {
        for row in log.data() {
            let start = row.offset as usize;
            let header = 3 + 2; // message header + msg_id
            let msg = &source[start..start + header + row.data.len()];
            let at = out.len();
            out.extend_from_slice(msg);
            let sub = row.subscription;
            if sub.timestamp_type() == Some(ulog_runtime::schema::Primitive::UInt64) {
                let layout = log
                    .metadata()
                    .schema()
                    .resolved(sub.format().expect("rows have a format"));
                let ts_offset = layout
                    .and_then(|l| l.field("timestamp"))
                    .map_or(0, |f| f.offset);
                let t = at + header + ts_offset;
                out[t..t + 8].copy_from_slice(&(row.timestamp + copy * span).to_le_bytes());
            }
        }
        copy += 1;
    }
    Ok(out)
}
