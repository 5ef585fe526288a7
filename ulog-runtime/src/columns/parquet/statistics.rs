//! The statistics of `FLOAT` and `DOUBLE` column chunks (minimum, maximum and NaN count, of
//! each page and of the chunk, and the column index made of the pages'), taken here from
//! the PLAIN values as they are copied into their page ([`super::chunk`]), in the format's
//! type-defined order, instead of by parquet-rs's column writer; and the footer that says
//! so.
//!
//! Why not parquet-rs's own: it marks float columns with the format's newer IEEE 754
//! total-order column order, which pyarrow 26 does not know yet, so that it ignores those
//! columns' bounds, as the format asks of a reader that does not know an order (DuckDB
//! reads them). The older type-defined order is read by every reader: NaN is never a bound
//! (a page of nothing but NaN has none, and then its chunk has no column index), a zero
//! minimum is written -0.0 and a zero maximum +0.0, and NaN values are counted. parquet-rs
//! 60 writes the column order from the type alone ([`type_defined_float_orders`] puts the
//! older one in the footer). And speed: parquet-rs reduces every batch it is given
//! (`min_max_f32`), and on the x86-64 baseline, which has no vector minimum of 32-bit
//! integers before SSE4.1, the compiler leaves its loop scalar: with statistics off, a
//! conversion of the 400 MB benchmark log took 11% less CPU (an Intel Xeon, 11 interleaved
//! runs). Here a page's `f32`s are reduced in SSE2 lanes on x86-64 (a portable loop
//! elsewhere) as they are copied into their page: the vector minimum and maximum of floats
//! leave NaN out by their operands' order, and a zero bound's sign is put right after (a
//! quarter of the instructions a value that integer keys in the IEEE 754 total order took).

use std::io::Write;

use parquet::basic::{BoundaryOrder, Type};
use parquet::errors::ParquetError;
use parquet::file::metadata::ColumnIndexBuilder;
use parquet::file::page_index::column_index::ColumnIndexMetaData;
use parquet::file::statistics::{Statistics, ValueStatistics};

/// One page's bounds (none when it holds nothing but NaN) and NaN count; an `f32` page's
/// bounds as `f64`s, which hold them exactly.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Page {
    bounds: Option<(f64, f64)>,
    nans: u64,
}

impl Page {
    /// The statistics of the values of both.
    fn merge(self, other: Page) -> Page {
        Page {
            bounds: match (self.bounds, other.bounds) {
                (Some((lo, hi)), Some((l, h))) => Some(signed_zeros((lo.min(l), hi.max(h)))),
                (one, None) | (None, one) => one,
            },
            nans: self.nans + other.nans,
        }
    }
}

/// Bounds in the type-defined order: a zero minimum is -0.0, a zero maximum +0.0.
fn signed_zeros((min, max): (f64, f64)) -> (f64, f64) {
    (
        if min == 0.0 { -0.0 } else { min },
        if max == 0.0 { 0.0 } else { max },
    )
}

/// The bounds (NaN left out) and NaN count of `values`, PLAIN `f64`s (8 bytes each).
fn reduce_f64(values: &[u8]) -> Page {
    let mut bounds: Option<(f64, f64)> = None;
    let mut nans = 0;
    for w in values.as_chunks::<8>().0 {
        let v = f64::from_le_bytes(*w);
        if v.is_nan() {
            nans += 1;
            continue;
        }
        bounds = Some(bounds.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))));
    }
    Page {
        bounds: bounds.map(signed_zeros),
        nans,
    }
}

/// Copies `values` into `to` (their PLAIN bytes: as many, 4 bytes each) and gives their
/// bounds (NaN left out) and NaN count, in one pass: the values are read once, and the
/// reduction waits on no memory of its own.
fn copy_reduce(values: &[f32], to: &mut [[u8; 4]]) -> Page {
    assert_eq!(values.len(), to.len(), "room for every value");
    // Per lane: the least and greatest value that is not NaN, and the NaNs seen. Which
    // zero a zero bound is does not matter: the type-defined one is put in at the end.
    let mut lanes = Lanes {
        mins: [f32::INFINITY; LANES],
        maxs: [f32::NEG_INFINITY; LANES],
        nans: [0; LANES],
    };
    let mut nans = 0u64;
    // Blocks within which no lane's NaN count can overflow.
    for (block, out) in values.chunks(LANES << 24).zip(to.chunks_mut(LANES << 24)) {
        let (chunks, rest) = block.as_chunks::<LANES>();
        let (outs, out_rest) = out.as_chunks_mut::<LANES>();
        // SAFETY: every x86-64 processor has SSE2 (the target's baseline).
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        unsafe {
            sse2::copy_reduce(chunks, outs, &mut lanes);
        }
        #[cfg(not(target_arch = "x86_64"))]
        for (chunk, o) in chunks.iter().zip(outs) {
            for (i, (v, o)) in chunk.iter().zip(o).enumerate() {
                *o = v.to_le_bytes();
                lanes.take(i, *v);
            }
        }
        for (i, (v, o)) in rest.iter().zip(out_rest).enumerate() {
            *o = v.to_le_bytes();
            lanes.take(i, *v);
        }
        nans += lanes.nans.iter().map(|&n| u64::from(n)).sum::<u64>();
        lanes.nans = [0; LANES];
    }
    let count = values.len() as u64;
    let bounds = (nans < count).then(|| {
        let min = lanes.mins.into_iter().fold(f32::INFINITY, f32::min);
        let max = lanes.maxs.into_iter().fold(f32::NEG_INFINITY, f32::max);
        signed_zeros((f64::from(min), f64::from(max)))
    });
    Page { bounds, nans }
}

/// Values reduced side by side.
const LANES: usize = 8;

/// Each lane's bounds (never NaN) and NaN count.
struct Lanes {
    mins: [f32; LANES],
    maxs: [f32; LANES],
    nans: [u32; LANES],
}

impl Lanes {
    /// Takes `v` into lane `i`.
    fn take(&mut self, i: usize, v: f32) {
        if v.is_nan() {
            self.nans[i] += 1;
        } else {
            self.mins[i] = self.mins[i].min(v);
            self.maxs[i] = self.maxs[i].max(v);
        }
    }
}

/// The lanes in SSE2 registers (every x86-64 processor has SSE2), whose minimum and
/// maximum instructions leave a NaN out when it is their first operand.
#[cfg(target_arch = "x86_64")]
mod sse2 {
    use std::arch::x86_64::{
        __m128, __m128i, _mm_castps_si128, _mm_cmpunord_ps, _mm_loadu_ps, _mm_max_ps, _mm_min_ps,
        _mm_set1_epi32, _mm_set1_ps, _mm_storeu_ps, _mm_storeu_si128, _mm_sub_epi32,
    };

    use super::{LANES, Lanes};

    /// Loads four floats.
    #[target_feature(enable = "sse2")]
    #[inline]
    fn load(values: &[f32; 4]) -> __m128 {
        // SAFETY: the 16 bytes are readable; the load has no alignment requirement.
        #[allow(unsafe_code)]
        unsafe {
            _mm_loadu_ps(values.as_ptr())
        }
    }

    /// Stores four floats as their PLAIN bytes (x86-64 is little-endian).
    #[target_feature(enable = "sse2")]
    #[inline]
    fn put(to: &mut [[u8; 4]; 4], v: __m128) {
        // SAFETY: `to` has room for 16 bytes; the store has no alignment requirement.
        #[allow(unsafe_code)]
        unsafe {
            _mm_storeu_ps(to.as_mut_ptr().cast(), v);
        }
    }

    /// Stores 4 lanes.
    #[target_feature(enable = "sse2")]
    #[inline]
    fn store(v: __m128) -> [f32; 4] {
        let mut out = [0f32; 4];
        // SAFETY: `out` has room for 16 bytes; the store has no alignment requirement.
        #[allow(unsafe_code)]
        unsafe {
            _mm_storeu_ps(out.as_mut_ptr(), v);
        }
        out
    }

    /// Stores 4 counts.
    #[target_feature(enable = "sse2")]
    #[inline]
    fn store_counts(v: __m128i) -> [i32; 4] {
        let mut out = [0i32; 4];
        // SAFETY: `out` has room for 16 bytes; the store has no alignment requirement.
        #[allow(unsafe_code)]
        unsafe {
            _mm_storeu_si128(out.as_mut_ptr().cast(), v);
        }
        out
    }

    /// Copies every chunk's 8 values into `outs` and takes them into the lanes (their NaN
    /// counts below 2^32).
    #[target_feature(enable = "sse2")]
    pub(super) fn copy_reduce(
        chunks: &[[f32; LANES]],
        outs: &mut [[[u8; 4]; LANES]],
        lanes: &mut Lanes,
    ) {
        let mut mins = [_mm_set1_ps(f32::INFINITY); 2];
        let mut maxs = [_mm_set1_ps(f32::NEG_INFINITY); 2];
        let mut nans = [_mm_set1_epi32(0); 2];
        for (chunk, out) in chunks.iter().zip(outs) {
            let (halves, _) = chunk.as_chunks::<4>();
            let (out_halves, _) = out.as_chunks_mut::<4>();
            for (j, (half, to)) in halves.iter().zip(out_halves).enumerate() {
                let x = load(half);
                put(to, x);
                // `minps a, b` is `b` when either is NaN: with the value first, a NaN
                // leaves the bound as it was.
                mins[j] = _mm_min_ps(x, mins[j]);
                maxs[j] = _mm_max_ps(x, maxs[j]);
                // A NaN lane's mask is -1.
                nans[j] = _mm_sub_epi32(nans[j], _mm_castps_si128(_mm_cmpunord_ps(x, x)));
            }
        }
        for j in 0..2 {
            let (lo, hi, n) = (store(mins[j]), store(maxs[j]), store_counts(nans[j]));
            for i in 0..4 {
                let l = 4 * j + i;
                lanes.mins[l] = lanes.mins[l].min(lo[i]);
                lanes.maxs[l] = lanes.maxs[l].max(hi[i]);
                lanes.nans[l] += n[i] as u32;
            }
        }
    }
}

/// The statistics of one `FLOAT` or `DOUBLE` column chunk, a data page at a time.
#[derive(Debug)]
pub(super) struct FloatStatistics {
    /// `FLOAT` or `DOUBLE`.
    kind: Type,
    pages: Vec<Page>,
    /// The page being filled, once it has values.
    open: Option<Page>,
}

impl FloatStatistics {
    /// No page yet of a column of physical type `kind` (`FLOAT` or `DOUBLE`).
    pub(super) fn new(kind: Type) -> FloatStatistics {
        FloatStatistics {
            kind,
            pages: Vec::new(),
            open: None,
        }
    }

    /// Copies `f32` values of the page being filled into it (`to`: their PLAIN bytes) and
    /// takes them, in one pass.
    pub(super) fn copy_f32(&mut self, values: &[f32], to: &mut [[u8; 4]]) {
        let piece = copy_reduce(values, to);
        self.open = Some(self.open.map_or(piece, |p| p.merge(piece)));
    }

    /// Takes PLAIN `f64` values of the page being filled (8 bytes each), while they are
    /// still in cache.
    pub(super) fn take_f64(&mut self, plain: &[u8]) {
        let piece = reduce_f64(plain);
        self.open = Some(self.open.map_or(piece, |p| p.merge(piece)));
    }

    /// Ends the page being filled (an error if no value was taken into it).
    pub(super) fn end_page(&mut self) -> Result<(), ParquetError> {
        let page = self.open.take().ok_or_else(|| {
            ParquetError::General(format!("a {} data page of no values", self.kind))
        })?;
        self.pages.push(page);
        Ok(())
    }

    /// The chunk's statistics (filling the deprecated `min`/`max` fields too, as parquet-rs
    /// does for a column of signed order), and its column index if `index` (page
    /// statistics asked for) and every page has bounds.
    pub(super) fn finish(
        self,
        index: bool,
    ) -> Result<(Statistics, Option<ColumnIndexMetaData>), ParquetError> {
        let bounds = self
            .pages
            .iter()
            .filter_map(|p| p.bounds)
            .reduce(|(lo, hi), (l, h)| (lo.min(l), hi.max(h)))
            .map(signed_zeros);
        let nans = (!self.pages.is_empty()).then(|| self.pages.iter().map(|p| p.nans).sum());
        let statistics = if self.kind == Type::DOUBLE {
            Statistics::Double(
                chunk_statistics(bounds)
                    .with_nan_count(nans)
                    .with_backwards_compatible_min_max(true),
            )
        } else {
            // Bounds of `f32`s, held as `f64`s: exact back.
            let narrow = |v: f64| v as f32;
            Statistics::Float(
                chunk_statistics(bounds.map(|(lo, hi)| (narrow(lo), narrow(hi))))
                    .with_nan_count(nans)
                    .with_backwards_compatible_min_max(true),
            )
        };
        let pages: Option<Vec<(f64, f64, u64)>> = self
            .pages
            .iter()
            .map(|p| p.bounds.map(|(lo, hi)| (lo, hi, p.nans)))
            .collect();
        let Some(pages) = pages.filter(|_| index) else {
            return Ok((statistics, None));
        };
        let mut builder = ColumnIndexBuilder::new(self.kind);
        for &(lo, hi, nans) in &pages {
            let bytes = |v: f64| {
                if self.kind == Type::DOUBLE {
                    v.to_le_bytes().to_vec()
                } else {
                    (v as f32).to_le_bytes().to_vec()
                }
            };
            let nans = i64::try_from(nans).map_err(|_| {
                ParquetError::General("a page of more than i64::MAX NaNs".to_owned())
            })?;
            builder.append(false, bytes(lo), bytes(hi), 0, Some(nans));
        }
        builder.set_boundary_order(boundary_order(
            pages.iter().map(|&(lo, hi, _)| (lo, hi)),
            |a, b| a > b,
        ));
        Ok((statistics, Some(builder.build()?)))
    }
}

/// A chunk's statistics of a required column (no null) whose values lie within `bounds`
/// (`None`: no value), as parquet-rs's writer makes them, before its type's own settings.
pub(super) fn chunk_statistics<T>(bounds: Option<(T, T)>) -> ValueStatistics<T> {
    let (min, max) = bounds.unzip();
    ValueStatistics::new(min, max, None, Some(0), false)
}

/// The order of a chunk's pages by their bounds (`greater`: the column's order), as
/// parquet-rs's writer tells it: ascending if no page's minimum or maximum is below the
/// page before's (every page alike too), else descending if none is above, else unordered.
pub(super) fn boundary_order<T: Copy>(
    pages: impl Iterator<Item = (T, T)>,
    greater: impl Fn(T, T) -> bool,
) -> BoundaryOrder {
    let (mut ascending, mut descending) = (true, true);
    let mut last: Option<(T, T)> = None;
    for (lo, hi) in pages {
        if let Some((last_lo, last_hi)) = last {
            ascending &= !(greater(last_lo, lo) || greater(last_hi, hi));
            descending &= !(greater(lo, last_lo) || greater(hi, last_hi));
        }
        last = Some((lo, hi));
    }
    match (ascending, descending) {
        (true, _) => BoundaryOrder::ASCENDING,
        (false, true) => BoundaryOrder::DESCENDING,
        (false, false) => BoundaryOrder::UNORDERED,
    }
}

/// Puts the type-defined column order in a Parquet file's footer (`footer`: the file's last
/// bytes, the thrift `FileMetaData`, its length and `PAR1`) where parquet-rs 60 writes the
/// IEEE 754 total order: for `FLOAT` and `DOUBLE` columns, whose statistics
/// [`FloatStatistics`] takes in the type-defined order. `columns`: the file's leaf columns.
///
/// parquet-rs writes the column orders last in `FileMetaData` (field 7, a list of one
/// empty-struct union a column: `1C 00 00` for the type-defined order, `2C 00 00` for the
/// IEEE 754 one, in thrift's compact protocol), so the two are swapped in place, the
/// footer's length unchanged. Anything else there is an error: a later parquet-rs may lay
/// its footer out otherwise.
pub(super) fn type_defined_float_orders(
    footer: &mut [u8],
    columns: usize,
) -> Result<(), ParquetError> {
    let unexpected = |what: &str| {
        ParquetError::General(format!(
            "the footer's column orders are not where parquet-rs 60 writes them ({what})"
        ))
    };
    let n = footer.len();
    if n < 8 || footer[n - 4..] != *b"PAR1" {
        return Err(unexpected("no PAR1 at the end"));
    }
    let len = u32::from_le_bytes(footer[n - 8..n - 4].try_into().expect("4 bytes")) as usize;
    let meta_end = n - 8;
    let meta_start = meta_end
        .checked_sub(len)
        .ok_or_else(|| unexpected("a footer longer than the bytes"))?;
    let meta = &mut footer[meta_start..meta_end];
    // `... 19 <list header> <columns x 3 bytes> 00`: field 7 (after 6), a list of structs.
    let mut header = Vec::new();
    if columns < 15 {
        header.push(((columns as u8) << 4) | 0x0c);
    } else {
        header.push(0xfc);
        // The count as a varint (ULEB128).
        super::int64::uleb(&mut header, columns as u64);
    }
    let list = columns * 3;
    let at = meta
        .len()
        .checked_sub(1 + list + header.len() + 1)
        .ok_or_else(|| unexpected("a footer too short"))?;
    if meta[at] != 0x19
        || meta[at + 1..at + 1 + header.len()] != header[..]
        || meta[meta.len() - 1] != 0
    {
        return Err(unexpected("no list of one order a column at its end"));
    }
    let end = meta.len() - 1;
    let orders = &mut meta[at + 1 + header.len()..end];
    if !orders
        .chunks_exact(3)
        .all(|o| matches!(o, [0x1c | 0x2c, 0, 0]))
    {
        return Err(unexpected("an order that is neither"));
    }
    for order in orders.chunks_exact_mut(3) {
        order[0] = 0x1c;
    }
    Ok(())
}

/// An output whose writes can be held back (a file's footer), to be patched before they
/// are written.
pub(super) struct Held<W: Write> {
    pub(super) inner: W,
    held: Option<Vec<u8>>,
}

impl<W: Write> Held<W> {
    pub(super) fn new(inner: W) -> Held<W> {
        Held { inner, held: None }
    }

    /// Holds back what is written from now on.
    pub(super) fn hold(&mut self) {
        self.held.get_or_insert_with(Vec::new);
    }

    /// Writes what was held back, once `patch` has seen it, and writes through again.
    pub(super) fn write_held(
        &mut self,
        patch: impl FnOnce(&mut [u8]) -> Result<(), ParquetError>,
    ) -> Result<(), ParquetError> {
        let mut held = self.held.take().unwrap_or_default();
        patch(&mut held)?;
        self.inner.write_all(&held)?;
        self.inner.flush()?;
        Ok(())
    }
}

impl<W: Write> Write for Held<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match &mut self.held {
            Some(held) => {
                held.extend_from_slice(buf);
                Ok(buf.len())
            }
            None => self.inner.write(buf),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match self.held {
            Some(_) => Ok(()),
            None => self.inner.flush(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A page's bounds (as bits of `f64`s) and NaN count, its values `f32`s and `f64`s.
    fn pages(values: &[f32]) -> [(Option<(u64, u64)>, u64); 2] {
        let narrow: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let wide: Vec<u8> = values
            .iter()
            .flat_map(|&v| f64::from(v).to_le_bytes())
            .collect();
        let mut copied = vec![[0u8; 4]; values.len()];
        let narrow_page = copy_reduce(values, &mut copied);
        assert_eq!(copied.concat(), narrow, "the PLAIN bytes copied");
        [narrow_page, reduce_f64(&wide)].map(|p| {
            (
                p.bounds.map(|(lo, hi)| (lo.to_bits(), hi.to_bits())),
                p.nans,
            )
        })
    }

    /// The bounds by the type-defined order's rules, written here from the format's text:
    /// over the values that are not NaN (none if there are none), a zero minimum -0.0 and a
    /// zero maximum +0.0.
    fn expected(values: &[f32]) -> (Option<(u64, u64)>, u64) {
        let numbers: Vec<f64> = values
            .iter()
            .filter(|v| !v.is_nan())
            .map(|&v| f64::from(v))
            .collect();
        let nans = (values.len() - numbers.len()) as u64;
        if numbers.is_empty() {
            return (None, nans);
        }
        let mut lo = numbers.iter().copied().fold(f64::INFINITY, f64::min);
        let mut hi = numbers.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if lo == 0.0 {
            lo = -0.0;
        }
        if hi == 0.0 {
            hi = 0.0;
        }
        (Some((lo.to_bits(), hi.to_bits())), nans)
    }

    #[test]
    fn a_pages_bounds_leave_nan_out_and_sign_their_zeros() {
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
            let want = expected(&values);
            let [narrow, wide] = pages(&values);
            assert_eq!(narrow, want, "f32 {values:?}");
            assert_eq!(wide, want, "f64 {values:?}");
        }
    }

    /// The footer's orders: the IEEE 754 ones made type-defined, in place; a footer laid out
    /// otherwise refused, untouched.
    #[test]
    fn the_footers_float_orders_become_type_defined() {
        // `FileMetaData`'s end as parquet-rs writes it for 3 and for 20 columns (field 6,
        // the `created_by` text "x", then field 7), its length and `PAR1`.
        for columns in [3usize, 20] {
            let mut meta = vec![0x18, 0x01, b'x', 0x19];
            if columns < 15 {
                meta.push(((columns as u8) << 4) | 0x0c);
            } else {
                meta.extend([0xfc, columns as u8]);
            }
            for k in 0..columns {
                meta.extend(if k % 2 == 1 {
                    [0x2c, 0, 0]
                } else {
                    [0x1c, 0, 0]
                });
            }
            meta.push(0);
            let mut footer = meta.clone();
            footer.extend((meta.len() as u32).to_le_bytes());
            footer.extend(b"PAR1");
            type_defined_float_orders(&mut footer, columns).unwrap();
            let orders = &footer[meta.len() - 1 - 3 * columns..meta.len() - 1];
            assert!(orders.chunks(3).all(|o| o == [0x1c, 0, 0]), "{orders:?}");
            // One column more than the footer holds: refused, nothing changed.
            let mut other = meta.clone();
            other.extend((meta.len() as u32).to_le_bytes());
            other.extend(b"PAR1");
            let before = other.clone();
            assert!(type_defined_float_orders(&mut other, columns + 1).is_err());
            assert_eq!(other, before);
        }
    }
}
