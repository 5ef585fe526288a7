//! The statistics of `FLOAT` column chunks (minimum, maximum and NaN count, of each page
//! and of the chunk, and the column index made of the pages'), taken here from each page's
//! PLAIN values as the page is compressed, instead of by parquet-rs's column writer.
//!
//! parquet-rs reduces every batch it is given (`min_max_f32`), and on the x86-64 baseline,
//! which has no vector minimum of 32-bit integers before SSE4.1, the compiler leaves its
//! loop scalar: with statistics off, a conversion of the 400 MB benchmark log took 11% less
//! CPU (an Intel Xeon, 11 interleaved runs). Here a page's values are reduced as the page
//! is handed over to be compressed, in SSE2 lanes on x86-64 (a portable loop elsewhere).
//!
//! The statistics are parquet-rs's, bit for bit, so the files are the same bytes: values
//! ordered as IEEE 754's total order (`f32::total_cmp`: -0 before +0), NaN left out of a
//! page's bounds unless the page holds nothing else (its bounds are then the NaNs' own, in
//! that order), NaN counted; the chunk's bounds merged from its pages' as parquet-rs merges
//! them; the column index's boundary order found as parquet-rs finds it. A test writes the
//! same tables both ways and compares the files.

use std::cmp::Ordering;

use parquet::basic::{BoundaryOrder, Type};
use parquet::errors::ParquetError;
use parquet::file::metadata::ColumnIndexBuilder;
use parquet::file::page_index::column_index::ColumnIndexMetaData;
use parquet::file::statistics::{Statistics, ValueStatistics};

#[cfg(test)]
thread_local! {
    /// Tests: whether this thread's conversions leave `FLOAT` statistics to parquet-rs, as
    /// the reference the statistics taken here are compared with.
    pub(super) static BY_PARQUET_RS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// The key of a float's bits that orders as `f32::total_cmp` does, as a signed integer
/// (its own inverse).
#[inline(always)]
fn key(bits: u32) -> i32 {
    (bits ^ ((bits as i32 >> 31) as u32 >> 1)) as i32
}

/// The float of a key.
fn float(key_: i32) -> f32 {
    f32::from_bits(key(key_ as u32) as u32)
}

/// Whether the bits are a NaN's.
#[inline(always)]
fn is_nan(bits: u32) -> bool {
    bits & 0x7fff_ffff > 0x7f80_0000
}

/// One page's bounds and NaN count.
#[derive(Debug, Clone, Copy)]
struct Page {
    min: f32,
    max: f32,
    nans: u64,
}

/// The bounds (NaN left out unless every value is one) and NaN count of `values`, PLAIN
/// `f32`s (at least one; 4 bytes each).
fn reduce(values: &[u8]) -> Page {
    // Per lane: the least and greatest key of a value that is not NaN, and the NaNs seen.
    // A NaN is replaced by each bound's identity, with masks rather than branches.
    let mut lanes = Lanes {
        mins: [i32::MAX; LANES],
        maxs: [i32::MIN; LANES],
        nans: [0; LANES],
    };
    let mut nans = 0u64;
    // Blocks within which no lane's NaN count can overflow.
    for block in values.chunks((LANES * 4) << 24) {
        let (chunks, rest) = block.as_chunks::<{ LANES * 4 }>();
        // SAFETY: every x86-64 processor has SSE2 (the target's baseline).
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        unsafe {
            sse2::reduce(chunks, &mut lanes);
        }
        #[cfg(not(target_arch = "x86_64"))]
        for chunk in chunks {
            for (i, w) in chunk.as_chunks::<4>().0.iter().enumerate() {
                lanes.take(i, u32::from_le_bytes(*w));
            }
        }
        for (i, w) in rest.as_chunks::<4>().0.iter().enumerate() {
            lanes.take(i, u32::from_le_bytes(*w));
        }
        nans += lanes.nans.iter().map(|&n| u64::from(n)).sum::<u64>();
        lanes.nans = [0; LANES];
    }
    let count = (values.len() / 4) as u64;
    let (min, max) = if nans == count {
        // Nothing but NaN: the bounds are the NaNs' own, in total order.
        let keys = values
            .as_chunks::<4>()
            .0
            .iter()
            .map(|w| key(u32::from_le_bytes(*w)));
        keys.fold((i32::MAX, i32::MIN), |(lo, hi), k| (lo.min(k), hi.max(k)))
    } else {
        (
            lanes.mins.into_iter().min().expect("lanes"),
            lanes.maxs.into_iter().max().expect("lanes"),
        )
    };
    Page {
        min: float(min),
        max: float(max),
        nans,
    }
}

/// Values reduced side by side.
const LANES: usize = 8;

/// Each lane's bounds (keys) and NaN count.
struct Lanes {
    mins: [i32; LANES],
    maxs: [i32; LANES],
    nans: [u32; LANES],
}

impl Lanes {
    /// Takes the float of `bits` into lane `i`.
    fn take(&mut self, i: usize, bits: u32) {
        let nan = is_nan(bits);
        let k = key(bits);
        self.mins[i] = self.mins[i].min(if nan { i32::MAX } else { k });
        self.maxs[i] = self.maxs[i].max(if nan { i32::MIN } else { k });
        self.nans[i] += u32::from(nan);
    }
}

/// The lanes in SSE2 registers (every x86-64 processor has SSE2): the compiler leaves
/// the portable loop scalar, as the baseline has no vector minimum of 32-bit integers.
#[cfg(target_arch = "x86_64")]
mod sse2 {
    use std::arch::x86_64::{
        __m128i, _mm_and_si128, _mm_andnot_si128, _mm_cmpgt_epi32, _mm_loadu_si128, _mm_or_si128,
        _mm_set1_epi32, _mm_srai_epi32, _mm_srli_epi32, _mm_storeu_si128, _mm_sub_epi32,
        _mm_xor_si128,
    };

    use super::{LANES, Lanes};

    /// `a` where `mask` is set, `b` elsewhere.
    #[target_feature(enable = "sse2")]
    #[inline]
    fn select(mask: __m128i, a: __m128i, b: __m128i) -> __m128i {
        _mm_or_si128(_mm_and_si128(mask, a), _mm_andnot_si128(mask, b))
    }

    /// Loads 16 bytes.
    #[target_feature(enable = "sse2")]
    #[inline]
    fn load(bytes: &[u8; 16]) -> __m128i {
        // SAFETY: the 16 bytes are readable; the load has no alignment requirement.
        #[allow(unsafe_code)]
        unsafe {
            _mm_loadu_si128(bytes.as_ptr().cast())
        }
    }

    /// Stores 4 lanes.
    #[target_feature(enable = "sse2")]
    #[inline]
    fn store(v: __m128i) -> [i32; 4] {
        let mut out = [0i32; 4];
        // SAFETY: `out` has room for 16 bytes; the store has no alignment requirement.
        #[allow(unsafe_code)]
        unsafe {
            _mm_storeu_si128(out.as_mut_ptr().cast(), v);
        }
        out
    }

    /// Takes every chunk's 8 values into the lanes (their NaN counts below 2^32).
    #[target_feature(enable = "sse2")]
    pub(super) fn reduce(chunks: &[[u8; LANES * 4]], lanes: &mut Lanes) {
        let magnitude = _mm_set1_epi32(0x7fff_ffff);
        let infinity = _mm_set1_epi32(0x7f80_0000);
        let top = _mm_set1_epi32(i32::MAX);
        let bottom = _mm_set1_epi32(i32::MIN);
        let mut mins = [top; 2];
        let mut maxs = [bottom; 2];
        let mut nans = [_mm_set1_epi32(0); 2];
        for chunk in chunks {
            let (halves, _) = chunk.as_chunks::<16>();
            for (j, half) in halves.iter().enumerate() {
                let x = load(half);
                // The total-order key: a negative float's magnitude bits flipped.
                let key = _mm_xor_si128(x, _mm_srli_epi32(_mm_srai_epi32(x, 31), 1));
                let nan = _mm_cmpgt_epi32(_mm_and_si128(x, magnitude), infinity);
                let low = select(nan, top, key);
                let high = select(nan, bottom, key);
                mins[j] = select(_mm_cmpgt_epi32(mins[j], low), low, mins[j]);
                maxs[j] = select(_mm_cmpgt_epi32(high, maxs[j]), high, maxs[j]);
                // A NaN lane's mask is -1.
                nans[j] = _mm_sub_epi32(nans[j], nan);
            }
        }
        for j in 0..2 {
            let (lo, hi, n) = (store(mins[j]), store(maxs[j]), store(nans[j]));
            for i in 0..4 {
                let l = 4 * j + i;
                lanes.mins[l] = lanes.mins[l].min(lo[i]);
                lanes.maxs[l] = lanes.maxs[l].max(hi[i]);
                lanes.nans[l] += n[i] as u32;
            }
        }
    }
}

/// `a > b` in total order.
fn greater(a: f32, b: f32) -> bool {
    a.total_cmp(&b) == Ordering::Greater
}

/// `current` and `new` merged as parquet-rs merges bounds: a NaN never replaces a number,
/// a number always replaces a NaN; otherwise the one `wins` over the other.
fn merge(current: Option<f32>, new: f32, wins: impl Fn(f32, f32) -> bool) -> f32 {
    match current {
        None => new,
        Some(cur) => match (cur.is_nan(), new.is_nan()) {
            (false, true) => cur,
            (true, false) => new,
            _ if wins(new, cur) => new,
            _ => cur,
        },
    }
}

/// The statistics of one `FLOAT` column chunk, a data page at a time.
#[derive(Debug, Default)]
pub(super) struct FloatStatistics {
    pages: Vec<Page>,
}

impl FloatStatistics {
    /// Takes the statistics of a data page: `num_values` PLAIN values, nothing else (a
    /// column of required values has no levels).
    pub(super) fn page(&mut self, buf: &[u8], num_values: u32) -> Result<(), ParquetError> {
        if num_values == 0 || buf.len() != num_values as usize * 4 {
            return Err(ParquetError::General(format!(
                "a FLOAT data page of {num_values} values in {} bytes: not PLAIN values only, \
                 so its statistics cannot be taken from them",
                buf.len()
            )));
        }
        self.pages.push(reduce(buf));
        Ok(())
    }

    /// The chunk's statistics (`signed`: whether they also fill the deprecated `min`/`max`
    /// fields, as parquet-rs does for a column of signed order), and the column index if
    /// `index` (page statistics asked for).
    pub(super) fn finish(
        self,
        signed: bool,
        index: bool,
    ) -> Result<(Statistics, Option<ColumnIndexMetaData>), ParquetError> {
        let mut min = None;
        let mut max = None;
        let mut nans = None;
        for p in &self.pages {
            min = Some(merge(min, p.min, |a, b| greater(b, a)));
            max = Some(merge(max, p.max, greater));
            *nans.get_or_insert(0) += p.nans;
        }
        let statistics = ValueStatistics::new(min, max, None, Some(0), false)
            .with_nan_count(nans)
            .with_backwards_compatible_min_max(signed);
        if !index {
            return Ok((Statistics::Float(statistics), None));
        }
        let mut builder = ColumnIndexBuilder::new(Type::FLOAT);
        let (mut ascending, mut descending) = (true, true);
        for (i, p) in self.pages.iter().enumerate() {
            if let Some(last) = i.checked_sub(1).map(|j| self.pages[j]) {
                if greater(last.min, p.min) || greater(last.max, p.max) {
                    ascending = false;
                }
                if greater(p.min, last.min) || greater(p.max, last.max) {
                    descending = false;
                }
            }
            let nans = i64::try_from(p.nans).map_err(|_| {
                ParquetError::General("a page of more than i64::MAX NaNs".to_owned())
            })?;
            builder.append(
                false,
                p.min.to_le_bytes().to_vec(),
                p.max.to_le_bytes().to_vec(),
                0,
                Some(nans),
            );
        }
        builder.set_boundary_order(match (ascending, descending) {
            (true, _) => BoundaryOrder::ASCENDING,
            (false, true) => BoundaryOrder::DESCENDING,
            (false, false) => BoundaryOrder::UNORDERED,
        });
        Ok((Statistics::Float(statistics), Some(builder.build()?)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn page(values: &[f32]) -> Page {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        reduce(&bytes)
    }

    /// The bounds by the definition: total order over the values that are not NaN, or over
    /// all when every one is.
    fn expected(values: &[f32]) -> (u32, u32, u64) {
        let numbers: Vec<f32> = values.iter().copied().filter(|v| !v.is_nan()).collect();
        let pool = if numbers.is_empty() { values } else { &numbers };
        let min = pool.iter().copied().min_by(f32::total_cmp).unwrap();
        let max = pool.iter().copied().max_by(f32::total_cmp).unwrap();
        let nans = (values.len() - numbers.len()) as u64;
        (min.to_bits(), max.to_bits(), nans)
    }

    #[test]
    fn a_pages_bounds_follow_total_order_and_leave_nan_out() {
        let neg_nan = f32::from_bits(0xffc0_0001);
        let cases: Vec<Vec<f32>> = vec![
            vec![1.0],
            vec![0.0, -0.0],
            vec![-0.0, 0.0, -0.0],
            vec![0.0; 19],
            vec![-0.0; 9],
            vec![f32::NAN, 3.0, -2.5, f32::NAN, f32::INFINITY],
            vec![f32::NEG_INFINITY, f32::NAN, neg_nan],
            vec![f32::NAN; 17],
            vec![f32::NAN, neg_nan, f32::from_bits(0x7f80_0001)],
            (0..1000).map(|i| (i as f32 - 500.0) * 0.37).collect(),
            (0..77)
                .map(|i| if i % 5 == 0 { f32::NAN } else { -(i as f32) })
                .collect(),
            vec![
                f32::MIN_POSITIVE / 4.0,
                -f32::MIN_POSITIVE / 4.0,
                f32::MAX,
                f32::MIN,
            ],
        ];
        for values in cases {
            let p = page(&values);
            assert_eq!(
                (p.min.to_bits(), p.max.to_bits(), p.nans),
                expected(&values),
                "{values:?}"
            );
        }
    }
}
