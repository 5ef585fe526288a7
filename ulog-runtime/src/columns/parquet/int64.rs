//! `INT64` column chunks (the timestamps and every other 64-bit integer), whose pages are
//! made here ([`super::chunk::write_int64_chunk`]) rather than by parquet-rs's column
//! writer: a page's values DELTA_BINARY_PACKED ([`encode`]: timestamps' deltas are small,
//! where PLAIN they took ZSTD as much CPU as every other column together), and their
//! statistics in the column's order ([`Int64Statistics`]: signed, or unsigned for a
//! `uint64_t` column, whose values are stored as the same bits).
//!
//! parquet-rs's own DELTA_BINARY_PACKED encoder packs each value through a general bit
//! writer; this one packs a miniblock's 32 values through a 128-bit accumulator.

use parquet::basic::Type;
use parquet::errors::ParquetError;
use parquet::file::metadata::ColumnIndexBuilder;
use parquet::file::page_index::column_index::ColumnIndexMetaData;
use parquet::file::statistics::Statistics;

/// Values a block holds, and a miniblock (the format's usual sizes, parquet-rs's too).
const BLOCK: usize = 128;
const MINIBLOCKS: usize = 4;
const MINIBLOCK: usize = BLOCK / MINIBLOCKS;

/// Appends `values` to `out`, DELTA_BINARY_PACKED: a header (block size, miniblocks a
/// block, the number of values, the first value), then each block of up to 128 deltas
/// (wrapping, as the format asks: any two values have one) as its least delta and each
/// miniblock's 32 deltas above it, bit-packed at the width the miniblock's largest needs;
/// a last miniblock padded with zeros, and those after it width 0 and no bytes.
pub(super) fn encode(values: &[i64], out: &mut Vec<u8>) {
    uleb(out, BLOCK as u64);
    uleb(out, MINIBLOCKS as u64);
    uleb(out, values.len() as u64);
    let Some((&first, _)) = values.split_first() else {
        uleb(out, 0);
        return;
    };
    uleb(out, zigzag(first));
    let mut deltas = [0i64; BLOCK];
    // Each block's deltas: of the values from its first one's predecessor on.
    let mut at = 1;
    while at < values.len() {
        let n = (values.len() - at).min(BLOCK);
        for (d, pair) in deltas.iter_mut().zip(values[at - 1..at + n].windows(2)) {
            *d = pair[1].wrapping_sub(pair[0]);
        }
        block(&deltas[..n], out);
        at += n;
    }
}

/// One block of deltas (1 to 128 of them).
fn block(deltas: &[i64], out: &mut Vec<u8>) {
    let min = deltas.iter().copied().min().expect("a block has a delta");
    uleb(out, zigzag(min));
    let widths_at = out.len();
    out.extend_from_slice(&[0; MINIBLOCKS]);
    let mut above = [0u64; MINIBLOCK];
    for (m, mini) in deltas.chunks(MINIBLOCK).enumerate() {
        // Each delta above the least (a last miniblock padded with zeros); the bits of
        // all of them together need as many as the largest.
        let mut any = 0;
        for (a, &d) in above.iter_mut().zip(mini) {
            *a = d.wrapping_sub(min) as u64;
            any |= *a;
        }
        above[mini.len()..].fill(0);
        let width = (u64::BITS - any.leading_zeros()) as usize;
        out[widths_at + m] = width as u8;
        if width > 0 {
            pack(&above, width, out);
        }
    }
}

/// Appends 32 values of `width` bits (1 to 64) each: `4 * width` bytes, least significant
/// bits first.
fn pack(values: &[u64; MINIBLOCK], width: usize, out: &mut Vec<u8>) {
    let mut acc: u128 = 0;
    let mut bits = 0;
    for &v in values {
        acc |= u128::from(v) << bits;
        bits += width;
        if bits >= 64 {
            out.extend_from_slice(&(acc as u64).to_le_bytes());
            acc >>= 64;
            bits -= 64;
        }
    }
    // 32 * width bits is whole bytes.
    out.extend_from_slice(&acc.to_le_bytes()[..bits / 8]);
}

fn zigzag(v: i64) -> u64 {
    ((v << 1) ^ (v >> 63)) as u64
}

/// Appends `v` as ULEB128 (the format's and thrift's varint).
pub(super) fn uleb(out: &mut Vec<u8>, mut v: u64) {
    loop {
        let byte = (v & 0x7f) as u8;
        v >>= 7;
        if v == 0 {
            out.push(byte);
            return;
        }
        out.push(byte | 0x80);
    }
}

/// The statistics of one `INT64` column chunk, a page at a time: bounds in the column's
/// order, as parquet-rs's writer gives them.
#[derive(Debug)]
pub(super) struct Int64Statistics {
    /// A `uint64_t` column: its values' bits ordered as unsigned.
    unsigned: bool,
    /// Each page's least and greatest value.
    pages: Vec<(i64, i64)>,
}

impl Int64Statistics {
    pub(super) fn new(unsigned: bool) -> Int64Statistics {
        Int64Statistics {
            unsigned,
            pages: Vec::new(),
        }
    }

    /// Whether `a` comes after `b` in the column's order.
    fn greater(&self, a: i64, b: i64) -> bool {
        if self.unsigned {
            a as u64 > b as u64
        } else {
            a > b
        }
    }

    /// Takes a page of values (at least one).
    pub(super) fn page(&mut self, values: &[i64]) {
        let Some(&first) = values.first() else {
            return;
        };
        let bounds = if self.unsigned {
            let (lo, hi) = values.iter().fold((u64::MAX, 0), |(lo, hi), &v| {
                (lo.min(v as u64), hi.max(v as u64))
            });
            (lo as i64, hi as i64)
        } else {
            values
                .iter()
                .fold((first, first), |(lo, hi), &v| (lo.min(v), hi.max(v)))
        };
        self.pages.push(bounds);
    }

    /// The chunk's statistics (the deprecated `min`/`max` fields too for a signed column,
    /// as parquet-rs fills them), and its column index if `index`.
    pub(super) fn finish(
        self,
        index: bool,
    ) -> Result<(Statistics, Option<ColumnIndexMetaData>), ParquetError> {
        let bounds = self.pages.iter().copied().reduce(|(lo, hi), (l, h)| {
            (
                if self.greater(lo, l) { l } else { lo },
                if self.greater(h, hi) { h } else { hi },
            )
        });
        let statistics = Statistics::Int64(
            super::statistics::chunk_statistics(bounds)
                .with_backwards_compatible_min_max(!self.unsigned),
        );
        if !index || self.pages.is_empty() {
            return Ok((statistics, None));
        }
        let mut builder = ColumnIndexBuilder::new(Type::INT64);
        for &(lo, hi) in &self.pages {
            builder.append(
                false,
                lo.to_le_bytes().to_vec(),
                hi.to_le_bytes().to_vec(),
                0,
                None,
            );
        }
        builder.set_boundary_order(super::statistics::boundary_order(
            self.pages.iter().copied(),
            |a, b| self.greater(a, b),
        ));
        Ok((statistics, Some(builder.build()?)))
    }
}
