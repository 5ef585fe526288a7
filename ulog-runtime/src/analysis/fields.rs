//! Per-field statistics: minimum, maximum and mean of every numeric field of every topic
//! instance (`bool` and `char` left out, `timestamp` too), over its finite values. Rows are
//! staged as they come (a copy of their bytes) and each full stage is reduced one field at
//! a time, in a loop over rows still in cache; or the statistics are taken from columns
//! already made ([`ColumnStats`], what the Parquet conversion does with its own).

use std::sync::Arc;

use super::FieldStat;
use crate::columns::{ColumnKind, ColumnSpec, RowBatch, Source};
#[cfg(feature = "parquet")]
use crate::columns::{ColumnValues, Columns};
use crate::read::Subscription;
use crate::schema::{Primitive, Schema};

/// Bytes of rows staged before they are reduced.
const STAGE_BYTES: usize = 32 << 10;

/// Running statistics of one field.
#[derive(Debug, Clone, Copy)]
struct Stat {
    min: f64,
    max: f64,
    sum: f64,
    count: u64,
}

impl Default for Stat {
    fn default() -> Stat {
        Stat {
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            sum: 0.0,
            count: 0,
        }
    }
}

/// One topic instance's fields (of one format).
#[derive(Debug, Clone)]
struct Acc {
    topic: String,
    multi_id: u8,
    format: String,
    stage: RowBatch,
    stage_rows: usize,
    /// Per counted field: its name, offset, type and column index.
    leaves: Vec<(String, usize, Primitive, usize)>,
    stats: Vec<Stat>,
}

impl Acc {
    fn new(topic: &str, multi_id: u8, spec: Arc<ColumnSpec>, stage_rows: usize) -> Acc {
        let leaves: Vec<(String, usize, Primitive, usize)> = spec
            .columns()
            .iter()
            .enumerate()
            .filter_map(|(i, c)| match (c.source, c.kind) {
                (Source::Offset(at), ColumnKind::Value(p))
                    if c.name != "timestamp" && !matches!(p, Primitive::Bool | Primitive::Char) =>
                {
                    Some((c.name.clone(), at, p, i))
                }
                _ => None,
            })
            .collect();
        Acc {
            topic: topic.to_owned(),
            multi_id,
            format: spec.format().to_owned(),
            stage: RowBatch::with_capacity(spec, stage_rows),
            stage_rows,
            stats: vec![Stat::default(); leaves.len()],
            leaves,
        }
    }
}

/// The field statistics of one topic instance taken from its columns, batch by batch.
#[cfg(feature = "parquet")]
#[derive(Debug, Clone)]
pub(crate) struct ColumnStats(Acc);

#[cfg(feature = "parquet")]
impl ColumnStats {
    /// Statistics of the columns of `spec`, nothing seen.
    pub(crate) fn new(topic: &str, multi_id: u8, spec: Arc<ColumnSpec>) -> ColumnStats {
        ColumnStats(Acc::new(topic, multi_id, spec, 0))
    }

    /// Adds a batch of columns (made by the same spec).
    pub(crate) fn add(&mut self, columns: &Columns) {
        let values = columns.values();
        for ((.., i), stat) in self.0.leaves.iter().zip(&mut self.0.stats) {
            if let Some(v) = values.get(*i) {
                reduce_column(v, stat);
            }
        }
    }
}

/// Every topic instance's field statistics.
#[derive(Debug, Clone, Default)]
pub(super) struct FieldStats {
    accs: Vec<Acc>,
}

impl FieldStats {
    /// The accumulator of a subscription's rows (one per topic instance and format).
    pub(super) fn bind(&mut self, sub: &Subscription, schema: &Schema) -> Option<usize> {
        let spec = ColumnSpec::of(schema, sub.format()?)?;
        if let Some(k) = self.accs.iter().position(|a| {
            a.topic == sub.name && a.multi_id == sub.multi_id && a.format == spec.format()
        }) {
            return Some(k);
        }
        let stage_rows = (STAGE_BYTES / spec.row_len().max(1)).clamp(1, 4096);
        self.accs.push(Acc::new(
            &sub.name,
            sub.multi_id,
            Arc::new(spec),
            stage_rows,
        ));
        Some(self.accs.len() - 1)
    }

    /// The statistics of columns taken apart ([`ColumnStats`]).
    #[cfg(feature = "parquet")]
    pub(crate) fn from_columns(stats: Vec<ColumnStats>) -> FieldStats {
        FieldStats {
            accs: stats.into_iter().map(|c| c.0).collect(),
        }
    }

    #[inline]
    pub(super) fn row(&mut self, k: usize, data: &[u8]) {
        let acc = &mut self.accs[k];
        if acc.stage.push(data, 0) && acc.stage.rows() >= acc.stage_rows {
            acc.reduce();
        }
    }

    /// The statistics of every counted field with a finite value, by topic, instance and
    /// field order.
    pub(super) fn finish(mut self) -> Vec<FieldStat> {
        for a in &mut self.accs {
            a.reduce();
        }
        let mut out = Vec::new();
        let mut accs: Vec<&Acc> = self.accs.iter().collect();
        accs.sort_by(|a, b| (&a.topic, a.multi_id).cmp(&(&b.topic, b.multi_id)));
        for a in accs {
            for ((name, ..), s) in a.leaves.iter().zip(&a.stats) {
                if s.count == 0 {
                    continue;
                }
                // Several formats of one instance (a resubscription): merged by name.
                if let Some(f) = out.iter_mut().find(|f: &&mut FieldStat| {
                    f.topic == a.topic && f.multi_id == a.multi_id && f.field == *name
                }) {
                    let total = f.count + s.count;
                    f.mean = (f.mean * f.count as f64 + s.sum) / total as f64;
                    f.min = f.min.min(s.min);
                    f.max = f.max.max(s.max);
                    f.count = total;
                    continue;
                }
                out.push(FieldStat {
                    topic: a.topic.clone(),
                    multi_id: a.multi_id,
                    field: name.clone(),
                    min: s.min,
                    max: s.max,
                    mean: s.sum / s.count as f64,
                    count: s.count,
                });
            }
        }
        out
    }
}

impl Acc {
    /// Folds the staged rows into the statistics.
    fn reduce(&mut self) {
        let stride = self.stage.spec().row_len();
        let bytes = self.stage.bytes();
        if stride > 0 && !bytes.is_empty() {
            for ((_, at, p, _), stat) in self.leaves.iter().zip(&mut self.stats) {
                reduce(bytes, stride, *at, *p, stat);
            }
        }
        self.stage.clear();
    }
}

/// Folds field `p` at `at` of every row of `bytes` (`stride` bytes a row) into `stat`:
/// four rows at a time into four sets of accumulators (a sum's additions do not wait for
/// each other), a value that is not finite selected away rather than branched around.
#[allow(clippy::cast_precision_loss)]
fn reduce(bytes: &[u8], stride: usize, at: usize, p: Primitive, stat: &mut Stat) {
    macro_rules! fold {
        ($ty:ty) => {{
            const SIZE: usize = size_of::<$ty>();
            let value = |r: &[u8]| -> f64 {
                let (v, _) = r[at..].split_first_chunk::<SIZE>().expect("in the row");
                <$ty>::from_le_bytes(*v) as f64
            };
            let mut lanes = [Lane::new(stat.min, stat.max); 4];
            let mut quads = bytes.chunks_exact(stride * 4);
            for q in &mut quads {
                for (lane, r) in lanes.iter_mut().zip(q.chunks_exact(stride)) {
                    lane.take(value(r));
                }
            }
            for r in quads.remainder().chunks_exact(stride) {
                lanes[0].take(value(r));
            }
            for l in lanes {
                stat.min = stat.min.min(l.min);
                stat.max = stat.max.max(l.max);
                stat.sum += l.sum;
                stat.count += l.count;
            }
        }};
    }
    match p {
        Primitive::Int8 => fold!(i8),
        Primitive::UInt8 => fold!(u8),
        Primitive::Int16 => fold!(i16),
        Primitive::UInt16 => fold!(u16),
        Primitive::Int32 => fold!(i32),
        Primitive::UInt32 => fold!(u32),
        Primitive::Int64 => fold!(i64),
        Primitive::UInt64 => fold!(u64),
        Primitive::Float => fold!(f32),
        Primitive::Double => fold!(f64),
        Primitive::Bool | Primitive::Char => {}
    }
}

/// Folds the values of one column into `stat`, as [`reduce`] does rows.
#[cfg(feature = "parquet")]
#[allow(clippy::cast_precision_loss)]
fn reduce_column(values: &ColumnValues, stat: &mut Stat) {
    fn fold<T: Copy>(values: &[T], to_f64: impl Fn(T) -> f64, stat: &mut Stat) {
        let mut lanes = [Lane::new(stat.min, stat.max); 4];
        let mut quads = values.chunks_exact(4);
        for q in &mut quads {
            for (lane, &v) in lanes.iter_mut().zip(q) {
                lane.take(to_f64(v));
            }
        }
        for &v in quads.remainder() {
            lanes[0].take(to_f64(v));
        }
        for l in lanes {
            stat.min = stat.min.min(l.min);
            stat.max = stat.max.max(l.max);
            stat.sum += l.sum;
            stat.count += l.count;
        }
    }
    match values {
        ColumnValues::Int8(v) => fold(v, f64::from, stat),
        ColumnValues::UInt8(v) => fold(v, f64::from, stat),
        ColumnValues::Int16(v) => fold(v, f64::from, stat),
        ColumnValues::UInt16(v) => fold(v, f64::from, stat),
        ColumnValues::Int32(v) => fold(v, f64::from, stat),
        ColumnValues::UInt32(v) => fold(v, f64::from, stat),
        ColumnValues::Int64(v) => fold(v, |x| x as f64, stat),
        ColumnValues::UInt64(v) => fold(v, |x| x as f64, stat),
        ColumnValues::Float(v) => fold(v, f64::from, stat),
        ColumnValues::Double(v) => fold(v, |x| x, stat),
        ColumnValues::Bool(_) | ColumnValues::Char(_) | ColumnValues::Text(_) => {}
    }
}

/// One set of accumulators.
#[derive(Clone, Copy)]
struct Lane {
    min: f64,
    max: f64,
    sum: f64,
    count: u64,
}

impl Lane {
    fn new(min: f64, max: f64) -> Lane {
        Lane {
            min,
            max,
            sum: 0.0,
            count: 0,
        }
    }

    #[inline(always)]
    fn take(&mut self, v: f64) {
        let finite = v.is_finite();
        // NaN compares false both ways: it moves neither bound.
        let bound = if finite { v } else { f64::NAN };
        if bound < self.min {
            self.min = bound;
        }
        if bound > self.max {
            self.max = bound;
        }
        self.sum += if finite { v } else { 0.0 };
        self.count += u64::from(finite);
    }
}
