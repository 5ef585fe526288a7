//! Per-field statistics: minimum, maximum and mean of every numeric field of every topic
//! instance (`bool` and `char` left out, `timestamp` too), over its finite values. Rows are
//! staged as they come (a copy of their bytes) and each full stage is reduced one field at
//! a time, in a loop over rows still in cache; or the statistics are taken from columns
//! already made ([`ColumnStats`], what the Parquet conversion does with its own).

use std::collections::HashMap;
use std::sync::Arc;

use super::FieldStat;
use crate::columns::{ColumnBudget, ColumnKind, ColumnSpec, Source};
#[cfg(feature = "parquet")]
use crate::columns::{ColumnValues, Columns};
use crate::read::{Metadata, Row, RowVisitor, Subscription};
use crate::schema::{Primitive, Schema};

/// Bytes of rows staged before they are reduced.
const STAGE_BYTES: usize = 32 << 10;

/// Most columns of the formats whose field statistics are taken, all instances together
/// (counted before any is made): each costs about 400 bytes from its first row to the end
/// (its statistics, its name, its place in the output), so a log of formats defining very
/// wide topics (`uint8_t[65000]`, 65,000 columns in a 30-byte definition) in many instances
/// is bounded. PX4's logs have a few thousand columns in all. One walk's budget: the walks
/// of the field statistics are never split in parts, so `merge` does not check it.
pub(crate) const MAX_FIELDS: usize = 250_000;

/// Running statistics of one field, kept in the field's own kind of number: integers'
/// bounds as integers and their sum exact (every integer is finite), floats' bounds and sum
/// over their finite values.
#[derive(Debug, Clone, Copy)]
enum Stat {
    Signed {
        min: i64,
        max: i64,
        sum: i128,
        count: u64,
    },
    Unsigned {
        min: u64,
        max: u64,
        sum: u128,
        count: u64,
    },
    Float {
        min: f64,
        max: f64,
        sum: f64,
        count: u64,
    },
}

impl Stat {
    fn new(p: Primitive) -> Stat {
        match p {
            Primitive::Float | Primitive::Double => Stat::Float {
                min: f64::INFINITY,
                max: f64::NEG_INFINITY,
                sum: 0.0,
                count: 0,
            },
            p if p.is_unsigned_integer() => Stat::Unsigned {
                min: u64::MAX,
                max: 0,
                sum: 0,
                count: 0,
            },
            _ => Stat::Signed {
                min: i64::MAX,
                max: i64::MIN,
                sum: 0,
                count: 0,
            },
        }
    }

    /// Minimum, maximum and mean as `f64`, and the count of finite values.
    #[allow(clippy::cast_precision_loss)]
    fn finish(&self) -> (f64, f64, f64, u64) {
        match *self {
            Stat::Signed {
                min,
                max,
                sum,
                count,
            } => (min as f64, max as f64, sum as f64 / count as f64, count),
            Stat::Unsigned {
                min,
                max,
                sum,
                count,
            } => (min as f64, max as f64, sum as f64 / count as f64, count),
            Stat::Float {
                min,
                max,
                sum,
                count,
            } => (min, max, sum / count as f64, count),
        }
    }

    /// Both statistics as one.
    fn merge(&mut self, other: Stat) {
        match (self, other) {
            (
                Stat::Signed {
                    min,
                    max,
                    sum,
                    count,
                },
                Stat::Signed {
                    min: m,
                    max: x,
                    sum: s,
                    count: c,
                },
            ) => {
                *min = (*min).min(m);
                *max = (*max).max(x);
                *sum += s;
                *count += c;
            }
            (
                Stat::Unsigned {
                    min,
                    max,
                    sum,
                    count,
                },
                Stat::Unsigned {
                    min: m,
                    max: x,
                    sum: s,
                    count: c,
                },
            ) => {
                *min = (*min).min(m);
                *max = (*max).max(x);
                *sum += s;
                *count += c;
            }
            (
                Stat::Float {
                    min,
                    max,
                    sum,
                    count,
                },
                Stat::Float {
                    min: m,
                    max: x,
                    sum: s,
                    count: c,
                },
            ) => {
                *min = min.min(m);
                *max = max.max(x);
                *sum += s;
                *count += c;
            }
            // Statistics of one field are of one kind.
            _ => {}
        }
    }

    fn count(&self) -> u64 {
        match *self {
            Stat::Signed { count, .. }
            | Stat::Unsigned { count, .. }
            | Stat::Float { count, .. } => count,
        }
    }
}

/// One topic instance's fields (of one format).
#[derive(Debug, Clone)]
struct Acc {
    topic: String,
    multi_id: u8,
    format: String,
    /// Rows staged: each row's first `row_len` bytes, back to back.
    stage: Vec<u8>,
    row_len: usize,
    /// Bytes staged before they are reduced (whole rows).
    stage_len: usize,
    /// Per counted field: its name, offset, type and column index.
    leaves: Vec<(String, usize, Primitive, usize)>,
    stats: Vec<Stat>,
    /// How a stage is reduced: the leaves in order, grouped where they can be.
    plan: Vec<Reduce>,
}

/// One step of reducing a stage ([`Acc::reduce`]).
#[derive(Debug, Clone, Copy)]
enum Reduce {
    /// The `i`-th leaf alone, a loop over the rows.
    Leaf(usize),
    /// `used` `f32` leaves side by side, the first the `first`-th: a loop over the rows,
    /// each row's four floats from the first one vector ([`reduce_floats`]).
    Floats { first: usize, used: usize },
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
            stage: Vec::with_capacity(stage_rows * spec.row_len()),
            row_len: spec.row_len(),
            stage_len: stage_rows * spec.row_len(),
            stats: leaves.iter().map(|(_, _, p, _)| Stat::new(*p)).collect(),
            plan: plan(&leaves, spec.row_len()),
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
    /// Each accumulator's index by topic, instance and format (a log of thousands of
    /// subscriptions is looked up in it, not searched).
    by_key: HashMap<(String, u8, String), usize>,
    /// The columns of each format bound (`None`: it has none to count).
    specs: HashMap<crate::schema::FormatId, Option<Arc<ColumnSpec>>>,
    /// The columns of the formats bound, all together ([`MAX_FIELDS`]), and the instances
    /// left out.
    budget: ColumnBudget,
    /// Per subscription, when they are taken from a walk ([`RowVisitor`]): 0 until its first
    /// row, then its accumulator + 1, or [`NONE`].
    by_sub: Vec<u32>,
}

/// `by_sub`: a subscription whose rows count in no accumulator.
const NONE: u32 = u32::MAX;

/// The statistics as a walk's only consumer: each row straight to its accumulator.
impl RowVisitor for FieldStats {
    #[inline]
    fn row(&mut self, _: &Metadata, row: &Row<'_>) {
        let i = row.subscription.index();
        let k = match self.by_sub.get(i) {
            Some(&k) if k != 0 => k,
            _ => self.first_row(row),
        };
        if k != NONE {
            self.row(k as usize - 1, row.data);
        }
    }

    fn fork(&self) -> FieldStats {
        FieldStats::default()
    }

    fn append(&mut self, other: FieldStats) {
        self.merge(other);
    }
}

impl FieldStats {
    /// The accumulator of a subscription's rows (one per topic instance and format).
    pub(super) fn bind(&mut self, sub: &Subscription, schema: &Schema) -> Option<usize> {
        let id = sub.format()?;
        let key = (
            sub.name.clone(),
            sub.multi_id,
            schema.format(id).to_string(),
        );
        if let Some(&k) = self.by_key.get(&key) {
            return Some(k);
        }
        // Counted before any column is made: an instance past the budget costs nothing.
        let columns = crate::columns::column_count(schema, id);
        if !self
            .budget
            .admit(MAX_FIELDS, &sub.name, sub.multi_id, columns)
        {
            return None;
        }
        // Made once per format, not once per instance.
        let spec = match self.specs.get(&id) {
            Some(spec) => spec.clone()?,
            None => {
                let spec = ColumnSpec::of(schema, id).map(Arc::new);
                self.specs.insert(id, spec.clone());
                spec?
            }
        };
        debug_assert_eq!(spec.columns().len(), columns, "column_count agrees");
        let stage_rows = (STAGE_BYTES / spec.row_len().max(1)).clamp(1, 4096);
        Some(self.push(Acc::new(&sub.name, sub.multi_id, spec, stage_rows)))
    }

    /// Adds an accumulator of a topic, instance and format not seen yet; gives its index.
    fn push(&mut self, acc: Acc) -> usize {
        let k = self.accs.len();
        self.by_key
            .insert((acc.topic.clone(), acc.multi_id, acc.format.clone()), k);
        self.accs.push(acc);
        k
    }

    /// Binds a subscription at its first row of a walk.
    #[cold]
    fn first_row(&mut self, row: &Row<'_>) -> u32 {
        let i = row.subscription.index();
        if self.by_sub.len() <= i {
            self.by_sub.resize(i + 1, 0);
        }
        let k = self
            .bind(row.subscription, row.schema())
            .map_or(NONE, |k| k as u32 + 1);
        self.by_sub[i] = k;
        k
    }

    /// The statistics of columns taken apart ([`ColumnStats`]).
    #[cfg(feature = "parquet")]
    pub(crate) fn from_columns(stats: Vec<ColumnStats>) -> FieldStats {
        let mut fields = FieldStats::default();
        for c in stats {
            fields.push(c.0);
        }
        fields
    }

    #[inline]
    pub(super) fn row(&mut self, k: usize, data: &[u8]) {
        let acc = &mut self.accs[k];
        // Rows shorter than the fields need are left out (as columns leave them out).
        if let Some(row) = data.get(..acc.row_len) {
            acc.stage.extend_from_slice(row);
            if acc.stage.len() >= acc.stage_len {
                acc.reduce();
            }
        }
    }

    /// Takes in the statistics of another part of the rows.
    pub(super) fn merge(&mut self, mut other: FieldStats) {
        self.budget.append(std::mem::take(&mut other.budget));
        for mut theirs in other.accs.drain(..) {
            theirs.reduce();
            let key = (theirs.topic.clone(), theirs.multi_id, theirs.format.clone());
            match self.by_key.get(&key) {
                Some(&k) => {
                    let mine = &mut self.accs[k];
                    mine.reduce();
                    for (s, t) in mine.stats.iter_mut().zip(theirs.stats) {
                        s.merge(t);
                    }
                }
                None => {
                    self.push(theirs);
                }
            }
        }
    }

    /// The statistics of every counted field with a finite value, by topic, instance and
    /// field order; the instances left out for [`MAX_FIELDS`] said in `missing`.
    pub(super) fn finish(mut self, missing: &mut Vec<super::Missing>) -> Vec<FieldStat> {
        if let Some(reason) = self
            .budget
            .said(&format!("{MAX_FIELDS} counted in field statistics"))
        {
            missing.push(super::Missing {
                fact: "field_stats".to_owned(),
                reason,
            });
        }
        for a in &mut self.accs {
            a.reduce();
        }
        let mut out: Vec<FieldStat> = Vec::new();
        // Where each (topic, instance, field) is in `out`.
        let mut at: HashMap<(&str, u8, &str), usize> = HashMap::new();
        let mut accs: Vec<&Acc> = self.accs.iter().collect();
        accs.sort_by(|a, b| (&a.topic, a.multi_id).cmp(&(&b.topic, b.multi_id)));
        for a in accs {
            for ((name, ..), s) in a.leaves.iter().zip(&a.stats) {
                if s.count() == 0 {
                    continue;
                }
                let (min, max, mean, count) = s.finish();
                // Several formats of one instance (a resubscription): merged by name.
                let key = (a.topic.as_str(), a.multi_id, name.as_str());
                if let Some(&k) = at.get(&key) {
                    let f = &mut out[k];
                    let total = f.count + count;
                    f.mean = (f.mean * f.count as f64 + mean * count as f64) / total as f64;
                    f.min = f.min.min(min);
                    f.max = f.max.max(max);
                    f.count = total;
                    continue;
                }
                at.insert(key, out.len());
                out.push(FieldStat {
                    topic: a.topic.clone(),
                    multi_id: a.multi_id,
                    field: name.clone(),
                    min,
                    max,
                    mean,
                    count,
                });
            }
        }
        out
    }
}

impl Acc {
    /// Folds the staged rows into the statistics.
    fn reduce(&mut self) {
        let stride = self.row_len;
        let bytes = &self.stage;
        if stride > 0 && !bytes.is_empty() {
            for step in &self.plan {
                match *step {
                    Reduce::Leaf(i) => {
                        let (_, at, p, _) = self.leaves[i];
                        reduce(bytes, stride, at, p, &mut self.stats[i]);
                    }
                    Reduce::Floats { first, used } => {
                        let at = self.leaves[first].1;
                        let stats = &mut self.stats[first..first + used];
                        if !reduce_floats(bytes, stride, at, stats) {
                            // A value that is not finite: each field looked at alone.
                            for (k, stat) in stats.iter_mut().enumerate() {
                                reduce(bytes, stride, at + 4 * k, Primitive::Float, stat);
                            }
                        }
                    }
                }
            }
        }
        self.stage.clear();
    }
}

/// The steps that reduce `leaves` (each `(name, offset, type, column)`, by offset) of rows
/// of `row_len` bytes: `f32` leaves side by side, two to four at a time, in blocks of 16
/// bytes ([`reduce_floats`]: a block may reach past them, not past the row), the others
/// alone.
fn plan(leaves: &[(String, usize, Primitive, usize)], row_len: usize) -> Vec<Reduce> {
    let mut plan = Vec::new();
    let mut i = 0;
    while i < leaves.len() {
        let at = leaves[i].1;
        let side_by_side = leaves[i..]
            .iter()
            .take(4)
            .enumerate()
            .take_while(|(k, (_, a, p, _))| *p == Primitive::Float && *a == at + 4 * k)
            .count();
        if cfg!(target_arch = "x86_64") && side_by_side >= 2 && at + 16 <= row_len {
            plan.push(Reduce::Floats {
                first: i,
                used: side_by_side,
            });
            i += side_by_side;
        } else {
            plan.push(Reduce::Leaf(i));
            i += 1;
        }
    }
    plan
}

/// Folds the first `stats.len()` (1 to 4) of the four `f32` at `at` of every row of
/// `bytes` (`stride` bytes a row) into `stats`, a row's four one vector, two rows at a
/// time, as long as every value taken is finite (a finite sum proves it, as in
/// [`fold_float`]); returns false, having changed nothing, otherwise.
#[cfg(target_arch = "x86_64")]
fn reduce_floats(bytes: &[u8], stride: usize, at: usize, stats: &mut [Stat]) -> bool {
    // SAFETY: SSE2 is part of every x86-64 processor (the target's baseline); the function
    // has no other precondition.
    #[allow(unsafe_code)]
    unsafe {
        reduce_floats_sse2(bytes, stride, at, stats)
    }
}

/// [`reduce_floats`] in SSE2 instructions.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "sse2")]
fn reduce_floats_sse2(bytes: &[u8], stride: usize, at: usize, stats: &mut [Stat]) -> bool {
    use std::arch::x86_64::{__m128, _mm_set_ps};
    assert!(at + 16 <= stride && (1..=4).contains(&stats.len()));
    // The four floats of a row (bounds checked once, by the block).
    let four = |row: &[u8]| -> __m128 {
        let b = row.first_chunk::<16>().expect("the block is in the row");
        let f = |k: usize| f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]);
        _mm_set_ps(f(3), f(2), f(1), f(0))
    };
    // Two rows at a time, one into each set of accumulators.
    let mut quads = Quads::new();
    let fields = &bytes[at..];
    let pairs = fields.chunks_exact(2 * stride);
    let rest = pairs.remainder();
    let mut n = 0u64;
    for pair in pairs {
        let (a, b) = pair.split_at(stride);
        quads.take(0, four(a));
        quads.take(1, four(b));
        n += 2;
    }
    // The rows after the pairs: one or two (the slice starts `at` bytes into the first
    // row, so its last pair may be cut short), each chunk a row's fields.
    for row in rest.chunks(stride) {
        quads.take(0, four(row));
        n += 1;
    }
    let (lo, hi, total) = quads.finish();
    if !total[..stats.len()].iter().sum::<f64>().is_finite() {
        return false;
    }
    for (k, stat) in stats.iter_mut().enumerate() {
        if let Stat::Float {
            min,
            max,
            sum,
            count,
        } = stat
        {
            *min = min.min(f64::from(lo[k]));
            *max = max.max(f64::from(hi[k]));
            *sum += total[k];
            *count += n;
        }
    }
    true
}

/// Four lanes of `f32`s folded in SSE2 registers: each lane's bounds (the instructions'
/// minimum and maximum: a NaN would be kept or not, which the callers' finite sums rule
/// out) and sum (in `f64`), in two sets of accumulators that the caller gives values to in
/// turn, so that each addition waits on the last of its own set only.
#[cfg(target_arch = "x86_64")]
struct Quads {
    lo: [std::arch::x86_64::__m128; 2],
    hi: [std::arch::x86_64::__m128; 2],
    sums: [[std::arch::x86_64::__m128d; 2]; 2],
}

#[cfg(target_arch = "x86_64")]
impl Quads {
    #[target_feature(enable = "sse2")]
    fn new() -> Quads {
        use std::arch::x86_64::{_mm_set1_ps, _mm_setzero_pd};
        Quads {
            lo: [_mm_set1_ps(f32::INFINITY); 2],
            hi: [_mm_set1_ps(f32::NEG_INFINITY); 2],
            sums: [[_mm_setzero_pd(); 2]; 2],
        }
    }

    /// Takes four values, one a lane, into set `k` (0 or 1).
    #[target_feature(enable = "sse2")]
    #[inline]
    fn take(&mut self, k: usize, v: std::arch::x86_64::__m128) {
        use std::arch::x86_64::{_mm_add_pd, _mm_cvtps_pd, _mm_max_ps, _mm_min_ps, _mm_movehl_ps};
        self.lo[k] = _mm_min_ps(v, self.lo[k]);
        self.hi[k] = _mm_max_ps(v, self.hi[k]);
        self.sums[k][0] = _mm_add_pd(self.sums[k][0], _mm_cvtps_pd(v));
        self.sums[k][1] = _mm_add_pd(self.sums[k][1], _mm_cvtps_pd(_mm_movehl_ps(v, v)));
    }

    /// Each lane's least and greatest value and sum, the two sets together.
    #[target_feature(enable = "sse2")]
    fn finish(self) -> ([f32; 4], [f32; 4], [f64; 4]) {
        use std::arch::x86_64::{
            __m128, __m128d, _mm_cvtsd_f64, _mm_cvtss_f32, _mm_max_ps, _mm_min_ps, _mm_shuffle_ps,
            _mm_unpackhi_pd,
        };
        let lanes = |v: __m128| -> [f32; 4] {
            [
                _mm_cvtss_f32(v),
                _mm_cvtss_f32(_mm_shuffle_ps::<0b01_01_01_01>(v, v)),
                _mm_cvtss_f32(_mm_shuffle_ps::<0b10_10_10_10>(v, v)),
                _mm_cvtss_f32(_mm_shuffle_ps::<0b11_11_11_11>(v, v)),
            ]
        };
        let halves = |s: __m128d| [_mm_cvtsd_f64(s), _mm_cvtsd_f64(_mm_unpackhi_pd(s, s))];
        let total: [f64; 4] = std::array::from_fn(|k| {
            let (a, b) = (halves(self.sums[0][k / 2]), halves(self.sums[1][k / 2]));
            a[k % 2] + b[k % 2]
        });
        (
            lanes(_mm_min_ps(self.lo[0], self.lo[1])),
            lanes(_mm_max_ps(self.hi[0], self.hi[1])),
            total,
        )
    }
}

/// Elsewhere no step uses it ([`plan`]).
#[cfg(not(target_arch = "x86_64"))]
fn reduce_floats(_: &[u8], _: usize, _: usize, _: &mut [Stat]) -> bool {
    false
}

/// Folds field `p` at `at` of every row of `bytes` (`stride` bytes a row) into `stat`.
fn reduce(bytes: &[u8], stride: usize, at: usize, p: Primitive, stat: &mut Stat) {
    macro_rules! rows {
        ($ty:ty, $fold:expr) => {{
            const SIZE: usize = size_of::<$ty>();
            assert!(at + SIZE <= stride, "the field is in the row");
            // From the first row's field on: each row's field starts a chunk of `stride`.
            let fields = &bytes[at..];
            let value =
                |c: &[u8]| <$ty>::from_le_bytes(*c.first_chunk::<SIZE>().expect("in the row"));
            let quads = fields.chunks_exact(stride * LANES);
            let rest = quads.remainder().chunks(stride).map(value);
            let quads = quads.map(|q| {
                let (a, q) = q.split_at(stride);
                let (b, q) = q.split_at(stride);
                let (c, d) = q.split_at(stride);
                [value(a), value(b), value(c), value(d)]
            });
            ($fold)(quads, rest, stat)
        }};
    }
    // A stage is at most 4,096 rows: the sums of values of 32 bits or less fit 64 bits.
    match p {
        Primitive::Int8 => rows!(i8, fold_signed::<_, i64>),
        Primitive::UInt8 => rows!(u8, fold_unsigned::<_, u64>),
        Primitive::Int16 => rows!(i16, fold_signed::<_, i64>),
        Primitive::UInt16 => rows!(u16, fold_unsigned::<_, u64>),
        Primitive::Int32 => rows!(i32, fold_signed::<_, i64>),
        Primitive::UInt32 => rows!(u32, fold_unsigned::<_, u64>),
        Primitive::Int64 => rows!(i64, fold_signed::<_, i128>),
        Primitive::UInt64 => rows!(u64, fold_unsigned::<_, u128>),
        Primitive::Float => rows!(f32, fold_float),
        Primitive::Double => rows!(f64, fold_float),
        Primitive::Bool | Primitive::Char => {}
    }
}

/// Folds the values of one column into `stat`, as [`reduce`] does rows.
#[cfg(feature = "parquet")]
fn reduce_column(values: &ColumnValues, stat: &mut Stat) {
    macro_rules! column {
        ($v:expr, $fold:expr) => {{
            // Pieces of 2^24 values: the 64-bit sums of 32-bit values do not overflow.
            for piece in $v.chunks(1 << 24) {
                let quads = piece.chunks_exact(LANES);
                let rest = quads.remainder().iter().copied();
                let quads = quads.map(|q| std::array::from_fn(|l| q[l]));
                ($fold)(quads, rest, stat)
            }
        }};
    }
    match values {
        ColumnValues::Int8(v) => column!(v, fold_signed::<_, i64>),
        ColumnValues::UInt8(v) => column!(v, fold_unsigned::<_, u64>),
        ColumnValues::Int16(v) => column!(v, fold_signed::<_, i64>),
        ColumnValues::UInt16(v) => column!(v, fold_unsigned::<_, u64>),
        ColumnValues::Int32(v) => column!(v, fold_signed::<_, i64>),
        ColumnValues::UInt32(v) => column!(v, fold_unsigned::<_, u64>),
        ColumnValues::Int64(v) => column!(v, fold_signed::<_, i128>),
        ColumnValues::UInt64(v) => column!(v, fold_unsigned::<_, u128>),
        ColumnValues::Float(v) => {
            // Most columns hold finite values only: 8 a step, in vectors.
            if !reduce_f32_column(v, stat) {
                column!(v, fold_float);
            }
        }
        ColumnValues::Double(v) => column!(v, fold_float),
        ColumnValues::Bool(_) | ColumnValues::Char(_) | ColumnValues::Text(_) => {}
    }
}

/// Folds a column of `f32` into `stat` (a `Float` one) as long as every value is finite
/// (a finite sum proves it, as in [`fold_float`]); returns false, having changed nothing,
/// otherwise.
#[cfg(feature = "parquet")]
fn reduce_f32_column(values: &[f32], stat: &mut Stat) -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: SSE2 is part of every x86-64 processor (the target's baseline); the
        // function has no other precondition.
        #[allow(unsafe_code)]
        unsafe {
            reduce_f32_column_sse2(values, stat)
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (values, stat);
        false
    }
}

/// [`reduce_f32_column`] in SSE2 instructions: 8 values a step, the first four into one set
/// of [`Quads`] and the next four into the other.
#[cfg(all(feature = "parquet", target_arch = "x86_64"))]
#[target_feature(enable = "sse2")]
fn reduce_f32_column_sse2(values: &[f32], stat: &mut Stat) -> bool {
    use std::arch::x86_64::_mm_set_ps;
    if !matches!(stat, Stat::Float { .. }) {
        return false;
    }
    let (blocks, rest) = values.as_chunks::<8>();
    let mut quads = Quads::new();
    for block in blocks {
        for (k, q) in block.as_chunks::<4>().0.iter().enumerate() {
            quads.take(k, _mm_set_ps(q[3], q[2], q[1], q[0]));
        }
    }
    let (lo, hi, totals) = quads.finish();
    let mut total: f64 = totals.iter().sum();
    let mut least = lo.into_iter().fold(f32::INFINITY, f32::min);
    let mut most = hi.into_iter().fold(f32::NEG_INFINITY, f32::max);
    for &v in rest {
        least = least.min(v);
        most = most.max(v);
        total += f64::from(v);
    }
    if !total.is_finite() {
        return false;
    }
    // (No value: bounds of infinities, which change no bound.)
    stat.merge(Stat::Float {
        min: f64::from(least),
        max: f64::from(most),
        sum: total,
        count: values.len() as u64,
    });
    true
}

/// Lanes of accumulators, each taking every fourth value: a sum's additions do not wait for
/// each other.
const LANES: usize = 4;

/// Folds signed integers (in groups of [`LANES`], then the rest) into `stat` (a `Signed`
/// one): bounds as `i64`, the sum exact (each lane's in `L`, which the caller chooses wide
/// enough for its values).
#[inline(always)]
fn fold_signed<T, L>(
    quads: impl Iterator<Item = [T; LANES]>,
    rest: impl Iterator<Item = T>,
    stat: &mut Stat,
) where
    T: Copy + Into<i64>,
    L: Copy + Default + std::ops::AddAssign + From<i64>,
    i128: From<L>,
{
    if let Stat::Signed {
        min,
        max,
        sum,
        count,
    } = stat
    {
        fold_integers::<T, i64, L, i128>(quads, rest, (min, max, sum, count));
    }
}

/// Folds unsigned integers into `stat` (an `Unsigned` one), as [`fold_signed`] does signed
/// ones.
#[inline(always)]
fn fold_unsigned<T, L>(
    quads: impl Iterator<Item = [T; LANES]>,
    rest: impl Iterator<Item = T>,
    stat: &mut Stat,
) where
    T: Copy + Into<u64>,
    L: Copy + Default + std::ops::AddAssign + From<u64>,
    u128: From<L>,
{
    if let Stat::Unsigned {
        min,
        max,
        sum,
        count,
    } = stat
    {
        fold_integers::<T, u64, L, u128>(quads, rest, (min, max, sum, count));
    }
}

/// Folds integers into running bounds (`B`, which every value converts into) and an exact
/// sum (`S`, wider; each lane's sum in `L`), and counts them.
#[inline(always)]
fn fold_integers<T, B, L, S>(
    quads: impl Iterator<Item = [T; LANES]>,
    rest: impl Iterator<Item = T>,
    (min, max, sum, count): (&mut B, &mut B, &mut S, &mut u64),
) where
    T: Copy + Into<B>,
    B: Copy + Ord,
    L: Copy + Default + std::ops::AddAssign + From<B>,
    S: std::ops::AddAssign + From<L>,
{
    let (mut lo, mut hi, mut total) = ([*min; LANES], [*max; LANES], [L::default(); LANES]);
    let mut n = 0u64;
    let mut take = |l: usize, v: T| {
        let v: B = v.into();
        lo[l] = lo[l].min(v);
        hi[l] = hi[l].max(v);
        total[l] += L::from(v);
    };
    for q in quads {
        for (l, v) in q.into_iter().enumerate() {
            take(l, v);
        }
        n += LANES as u64;
    }
    for v in rest {
        take(0, v);
        n += 1;
    }
    *min = lo.into_iter().fold(*min, B::min);
    *max = hi.into_iter().fold(*max, B::max);
    for t in total {
        *sum += S::from(t);
    }
    *count += n;
}

/// A float field's values.
trait Float: Copy + Into<f64> {
    /// Smallest and largest of `a` and `b` (only called where neither is NaN; `min` and
    /// `max` make vector code of them).
    fn lesser(a: Self, b: Self) -> Self;
    fn greater(a: Self, b: Self) -> Self;
    const INFINITY: Self;
    const NEG_INFINITY: Self;
}

impl Float for f32 {
    #[inline(always)]
    fn lesser(a: f32, b: f32) -> f32 {
        a.min(b)
    }
    #[inline(always)]
    fn greater(a: f32, b: f32) -> f32 {
        a.max(b)
    }
    const INFINITY: f32 = f32::INFINITY;
    const NEG_INFINITY: f32 = f32::NEG_INFINITY;
}

impl Float for f64 {
    #[inline(always)]
    fn lesser(a: f64, b: f64) -> f64 {
        a.min(b)
    }
    #[inline(always)]
    fn greater(a: f64, b: f64) -> f64 {
        a.max(b)
    }
    const INFINITY: f64 = f64::INFINITY;
    const NEG_INFINITY: f64 = f64::NEG_INFINITY;
}

/// Folds floats into `stat` (a `Float` one) over their finite values. Most fields have no
/// value that is not finite: the values are first folded as if none were (bounds in the
/// field's own type, the sum in `f64`), which a finite sum proves (a NaN or an infinity
/// would have made the sum one); otherwise again, each value looked at.
#[inline(always)]
fn fold_float<T: Float>(
    quads: impl Iterator<Item = [T; LANES]> + Clone,
    rest: impl Iterator<Item = T> + Clone,
    stat: &mut Stat,
) {
    if !matches!(stat, Stat::Float { .. }) {
        return;
    }
    let (mut lo, mut hi, mut total) = (
        [T::INFINITY; LANES],
        [T::NEG_INFINITY; LANES],
        [0.0f64; LANES],
    );
    let mut n = 0u64;
    let mut take = |l: usize, v: T| {
        lo[l] = T::lesser(v, lo[l]);
        hi[l] = T::greater(v, hi[l]);
        total[l] += v.into();
    };
    for q in quads.clone() {
        for (l, v) in q.into_iter().enumerate() {
            take(l, v);
        }
        n += LANES as u64;
    }
    for v in rest.clone() {
        take(0, v);
        n += 1;
    }
    let all: f64 = total.into_iter().sum();
    if all.is_finite() {
        stat.merge(Stat::Float {
            min: lo.into_iter().map(Into::into).fold(f64::INFINITY, f64::min),
            max: hi
                .into_iter()
                .map(Into::into)
                .fold(f64::NEG_INFINITY, f64::max),
            sum: all,
            count: n,
        });
        return;
    }
    for v in quads.flatten().chain(rest) {
        let v: f64 = v.into();
        if v.is_finite() {
            stat.merge(Stat::Float {
                min: v,
                max: v,
                sum: v,
                count: 1,
            });
        }
    }
}

#[cfg(all(test, feature = "parquet"))]
mod tests {
    use super::{Stat, reduce_column};
    use crate::columns::ColumnValues;
    use crate::schema::Primitive;

    /// The statistics of `values` folded one value at a time: finite values only.
    fn naive(values: &[f32]) -> (f64, f64, f64, u64) {
        let finite: Vec<f64> = values
            .iter()
            .map(|&v| f64::from(v))
            .filter(|v| v.is_finite())
            .collect();
        let min = finite.iter().copied().fold(f64::INFINITY, f64::min);
        let max = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let sum: f64 = finite.iter().sum();
        (min, max, sum, finite.len() as u64)
    }

    /// A column of `f32` is folded as value by value would, whatever its length (a
    /// multiple of the vector step or not) and wherever a NaN or an infinity lies.
    #[test]
    fn float_columns_fold_as_value_by_value() {
        for len in [0usize, 1, 3, 15, 16, 17, 33, 1000] {
            let base: Vec<f32> = (0..len)
                .map(|i| ((i as f32) * 0.37).sin() * 1e3 - if i % 7 == 0 { 0.0 } else { 2.5 })
                .collect();
            let mut cases = vec![base.clone()];
            for odd in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                for at in [0, len / 2, len.saturating_sub(1)] {
                    if at < len {
                        let mut v = base.clone();
                        v[at] = odd;
                        cases.push(v);
                    }
                }
            }
            for values in cases {
                let mut stat = Stat::new(Primitive::Float);
                // Twice: a second column folds into what the first left.
                reduce_column(&ColumnValues::Float(values.clone()), &mut stat);
                reduce_column(&ColumnValues::Float(values.clone()), &mut stat);
                let Stat::Float {
                    min,
                    max,
                    sum,
                    count,
                } = stat
                else {
                    panic!("a float's statistics");
                };
                let (want_min, want_max, want_sum, want_count) = naive(&values);
                assert_eq!(
                    (count, min, max),
                    (2 * want_count, want_min, want_max),
                    "{values:?}"
                );
                assert!(
                    (sum - 2.0 * want_sum).abs() <= 1e-9 * want_sum.abs().max(1.0),
                    "{len}: {sum} against {}",
                    2.0 * want_sum
                );
            }
        }
    }
}
