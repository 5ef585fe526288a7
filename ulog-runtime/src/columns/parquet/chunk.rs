//! One column chunk of a row group: a column's values, from every batch of the row group,
//! into pages compressed here with one ZSTD context a thread for every chunk it writes.
//!
//! - `FLOAT` and `DOUBLE` columns ([`write_float_chunk`]): PLAIN values are the values' own
//!   bytes, so each page is the batches' values copied once into a page buffer, their
//!   statistics taken in the same pass ([`super::statistics`]), and compressed from it
//!   (parquet-rs's writer copied each value into a buffer that grows from nothing every
//!   page, then that into the page).
//! - `INT64` columns ([`write_int64_chunk`]): each page's values DELTA_BINARY_PACKED
//!   ([`super::int64`]).
//! - The others (narrower integers widened to `INT32`, booleans, text), and every column
//!   when a dictionary is asked for: parquet-rs's column writer (PLAIN values, statistics,
//!   the page index), its pages handed to [`CompressingPages`].
//!
//! Pages made here have the page headers and the chunk metadata parquet-rs's writer gives
//! the same pages (tested against it), but for floats' statistics, which are in the
//! type-defined order ([`super::statistics`]). They are of required columns only (no
//! levels), as every column of a conversion is.
//!
//! parquet-rs's own compression makes a ZSTD compression and a decompression context for
//! each column chunk. Making one costs more than compressing a small chunk: each runs
//! `CPUID` three times, and on a virtual machine `CPUID` traps to the hypervisor (7.8 µs a
//! `CPUID` on a 2-core KVM Xeon, where making contexts took 9.6% of a conversion's CPU).
//! So the column writer is given uncompressed pages and this page writer compresses them,
//! writes them (header and data) into the chunk's buffer, and the chunk's metadata is
//! given the codec before the chunk is spliced into the row group.

use std::cell::RefCell;
use std::io::Write;

use bytes::Bytes;
use parquet::basic::{Compression, Encoding, EncodingMask, PageType, SortOrder, Type, ZstdLevel};
use parquet::column::page::{CompressedPage, Page, PageWriteSpec, PageWriter};
use parquet::column::writer::{ColumnCloseResult, ColumnWriter, get_column_writer};
use parquet::data_type::ByteArray;
use parquet::errors::ParquetError;
use parquet::file::metadata::{ColumnChunkMetaData, OffsetIndexBuilder, PageEncodingStats};
use parquet::file::properties::{WriterProperties, WriterPropertiesPtr};
use parquet::file::writer::{SerializedPageWriter, SerializedRowGroupWriter, TrackedWrite};
use parquet::schema::types::ColumnDescPtr;

use super::int64;
use super::statistics::FloatStatistics;
use crate::columns::ColumnValues;

/// The column writers' properties of a table: as the file's, without compression.
pub(super) struct ChunkProperties {
    /// For the columns whose statistics parquet-rs takes.
    pub(super) parquet: WriterPropertiesPtr,
    /// For `INT64` columns written by parquet-rs (with a dictionary): the same, their
    /// values DELTA_BINARY_PACKED where the dictionary gives up, as [`write_int64_chunk`]
    /// writes them.
    pub(super) int64: WriterPropertiesPtr,
    /// Whether `FLOAT`, `DOUBLE` and `INT64` columns' pages are made here
    /// ([`write_float_chunk`], [`write_int64_chunk`]: no dictionary), and if so whether a
    /// column index is made.
    pub(super) own_pages: Option<bool>,
}

thread_local! {
    /// This thread's ZSTD context, and the level it compresses at.
    static ZSTD: RefCell<Option<(i32, zstd::bulk::Compressor<'static>)>> =
        const { RefCell::new(None) };
    /// This thread's page buffer for [`write_float_chunk`] (a chunk's own would be a page
    /// zeroed for every chunk, most of them a few values).
    static PAGE: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` with this thread's ZSTD context at `level` (made on first use, or when the level
/// changes).
fn with_zstd<T>(
    level: i32,
    f: impl FnOnce(&mut zstd::bulk::Compressor<'static>) -> Result<T, ParquetError>,
) -> Result<T, ParquetError> {
    ZSTD.with(|cell| {
        let mut slot = cell.borrow_mut();
        if slot.as_ref().is_none_or(|(l, _)| *l != level) {
            let compressor = zstd::bulk::Compressor::new(level).map_err(zstd_error)?;
            *slot = Some((level, compressor));
        }
        let (_, compressor) = slot.as_mut().expect("just made");
        f(compressor)
    })
}

fn zstd_error(e: std::io::Error) -> ParquetError {
    ParquetError::General(format!("ZSTD: {e}"))
}

/// Compresses every page a column writer hands over, and writes it into `out`.
struct CompressingPages<'a> {
    out: &'a mut TrackedWrite<Vec<u8>>,
    zstd: &'a mut zstd::bulk::Compressor<'static>,
}

impl PageWriter for CompressingPages<'_> {
    fn write_page(&mut self, page: CompressedPage) -> parquet::errors::Result<PageWriteSpec> {
        let uncompressed = page.uncompressed_size();
        let compressed = |buf: &Bytes, zstd: &mut zstd::bulk::Compressor<'static>| {
            zstd.compress(buf).map(Bytes::from).map_err(zstd_error)
        };
        let page = match page.compressed_page() {
            Page::DataPage {
                buf,
                num_values,
                encoding,
                def_level_encoding,
                rep_level_encoding,
                statistics,
            } => Page::DataPage {
                buf: compressed(buf, self.zstd)?,
                num_values: *num_values,
                encoding: *encoding,
                def_level_encoding: *def_level_encoding,
                rep_level_encoding: *rep_level_encoding,
                statistics: statistics.clone(),
            },
            Page::DictionaryPage {
                buf,
                num_values,
                encoding,
                is_sorted,
            } => Page::DictionaryPage {
                buf: compressed(buf, self.zstd)?,
                num_values: *num_values,
                encoding: *encoding,
                is_sorted: *is_sorted,
            },
            // The writer's properties ask for version 1 data pages.
            Page::DataPageV2 { .. } => {
                return Err(ParquetError::General(
                    "data pages of version 2 are not written".to_owned(),
                ));
            }
        };
        SerializedPageWriter::new(self.out).write_page(CompressedPage::new(page, uncompressed))
    }

    fn close(&mut self) -> parquet::errors::Result<()> {
        self.out.flush()?;
        Ok(())
    }
}

/// Encodes one column of a row group, the values of `batches` in order (each a column of
/// one batch), with `props` (asking for no compression: the pages are compressed here, at
/// ZSTD `level`), and appends the chunk to `row_group`.
pub(super) fn write_chunk<'b, W: Write + Send>(
    row_group: &mut SerializedRowGroupWriter<'_, W>,
    descr: ColumnDescPtr,
    props: &ChunkProperties,
    level: i32,
    batches: impl Iterator<Item = &'b ColumnValues>,
) -> Result<(), ParquetError> {
    let kind = descr.physical_type();
    if let Some(page_index) = props.own_pages {
        let page_values = page_values(&props.parquet, kind);
        match kind {
            Type::FLOAT | Type::DOUBLE => {
                return write_float_chunk(
                    row_group,
                    descr,
                    page_values,
                    page_index,
                    level,
                    batches,
                );
            }
            Type::INT64 => {
                return write_int64_chunk(
                    row_group,
                    descr,
                    page_values,
                    page_index,
                    level,
                    batches,
                );
            }
            _ => {}
        }
    }
    let mut out = TrackedWrite::new(Vec::new());
    let close = with_zstd(level, |zstd| {
        let pages = CompressingPages {
            out: &mut out,
            zstd,
        };
        let column_props = if kind == Type::INT64 {
            &props.int64
        } else {
            &props.parquet
        };
        let mut writer = get_column_writer(descr, column_props.clone(), Box::new(pages));
        let mut widened = Widened::default();
        for values in batches {
            write_values(&mut writer, values, &mut widened)?;
        }
        writer.close()
    })?;
    let ColumnCloseResult {
        bytes_written,
        rows_written,
        metadata,
        bloom_filter,
        column_index,
        offset_index,
    } = close;
    let metadata = metadata
        .into_builder()
        .set_compression(Compression::ZSTD(ZstdLevel::try_new(level)?))
        .build()?;
    let chunk = Bytes::from(out.into_inner()?);
    row_group.append_column(
        &chunk,
        ColumnCloseResult {
            bytes_written,
            rows_written,
            metadata,
            bloom_filter,
            column_index,
            offset_index,
        },
    )
}

/// Values a data page made here holds (at least one): as many as the page size limit of
/// `props` (in the values' PLAIN bytes) and its row count limit allow.
fn page_values(props: &WriterProperties, kind: Type) -> usize {
    let width = if kind == Type::FLOAT { 4 } else { 8 };
    (props.data_page_size_limit() / width)
        .min(props.data_page_row_count_limit())
        .max(1)
}

/// Writes the chunk of a `FLOAT` or `DOUBLE` column (`descr`: a required one) as
/// [`write_chunk`] does others with parquet-rs's column writer (the same page headers and
/// chunk metadata): data pages (version 1) of `page_values` PLAIN values each (the last
/// one fewer), compressed at ZSTD `level`; the chunk's statistics, its offset index, and
/// its column index if `page_index`, taken from the values as they are copied
/// ([`FloatStatistics`]).
pub(super) fn write_float_chunk<'b, W: Write + Send>(
    row_group: &mut SerializedRowGroupWriter<'_, W>,
    descr: ColumnDescPtr,
    page_values: usize,
    page_index: bool,
    level: i32,
    batches: impl Iterator<Item = &'b ColumnValues>,
) -> Result<(), ParquetError> {
    required(&descr)?;
    let kind = descr.physical_type();
    let width = if kind == Type::DOUBLE { 8 } else { 4 };
    let page_bytes = page_values.max(1) * width;
    let mut page = PAGE.with_borrow_mut(std::mem::take);
    if page.len() < page_bytes {
        page.resize(page_bytes, 0);
    }
    let mut pages = FloatPages {
        chunk: ChunkPages::new(Encoding::PLAIN),
        stats: FloatStatistics::new(kind),
        page,
        page_bytes,
        filled: 0,
        width,
    };
    let written = with_zstd(level, |zstd| {
        for values in batches {
            match (values, kind) {
                (ColumnValues::Float(v), Type::FLOAT) => {
                    pages.put(v, FloatStatistics::copy_f32, zstd)?;
                }
                (ColumnValues::Double(v), Type::DOUBLE) => {
                    let copy = |stats: &mut FloatStatistics, v: &[f64], to: &mut [[u8; 8]]| {
                        for (to, x) in to.iter_mut().zip(v) {
                            *to = x.to_le_bytes();
                        }
                        stats.take_f64(to.as_flattened());
                    };
                    pages.put(v, copy, zstd)?;
                }
                _ => return Err(mismatch(values, kind)),
            }
        }
        pages.flush(zstd)
    });
    // The buffer is kept for the next chunk, whatever became of this one.
    PAGE.with_borrow_mut(|p| *p = std::mem::take(&mut pages.page));
    written?;
    let (statistics, column_index) = pages.stats.finish(page_index)?;
    pages
        .chunk
        .close(row_group, descr, level, statistics, column_index)
}

/// Writes the chunk of an `INT64` column (`descr`: a required one, its values `int64_t` or
/// `uint64_t`) as [`write_float_chunk`] does a float one, its pages of `page_values`
/// values DELTA_BINARY_PACKED ([`int64`]).
pub(super) fn write_int64_chunk<'b, W: Write + Send>(
    row_group: &mut SerializedRowGroupWriter<'_, W>,
    descr: ColumnDescPtr,
    page_values: usize,
    page_index: bool,
    level: i32,
    batches: impl Iterator<Item = &'b ColumnValues>,
) -> Result<(), ParquetError> {
    required(&descr)?;
    let batches: Vec<&ColumnValues> = batches.collect();
    let rows = batches.iter().map(|b| b.len()).sum::<usize>();
    // A page's room, no more than the chunk needs (most chunks are a few values).
    let page_values = page_values.max(1);
    let unsigned = descr.sort_order() == SortOrder::UNSIGNED;
    let mut stats = int64::Int64Statistics::new(unsigned);
    let mut chunk = ChunkPages::new(Encoding::DELTA_BINARY_PACKED);
    let mut page: Vec<i64> = Vec::with_capacity(page_values.min(rows));
    let mut encoded = Vec::new();
    with_zstd(level, |zstd| {
        let mut flush = |page: &mut Vec<i64>| -> Result<(), ParquetError> {
            if page.is_empty() {
                return Ok(());
            }
            stats.page(page);
            encoded.clear();
            int64::encode(page, &mut encoded);
            let num_values = u32::try_from(page.len()).map_err(|_| too_many("values"))?;
            chunk.write(zstd, &encoded, num_values)?;
            page.clear();
            Ok(())
        };
        for values in batches {
            match values {
                ColumnValues::Int64(v) => fill(v, |x| x, &mut page, page_values, &mut flush)?,
                // The same bits: the column's logical type says they are unsigned.
                ColumnValues::UInt64(v) => {
                    fill(v, |x| x as i64, &mut page, page_values, &mut flush)?;
                }
                _ => return Err(mismatch(values, Type::INT64)),
            }
        }
        flush(&mut page)
    })?;
    let (statistics, column_index) = stats.finish(page_index)?;
    chunk.close(row_group, descr, level, statistics, column_index)
}

/// Copies `values` (as `i64`s) into `page`, handing it to `flush` each time it holds
/// `page_values` of them.
fn fill<T: Copy>(
    mut values: &[T],
    as_i64: impl Fn(T) -> i64,
    page: &mut Vec<i64>,
    page_values: usize,
    flush: &mut dyn FnMut(&mut Vec<i64>) -> Result<(), ParquetError>,
) -> Result<(), ParquetError> {
    while !values.is_empty() {
        let n = values.len().min(page_values - page.len());
        page.extend(values[..n].iter().map(|&x| as_i64(x)));
        values = &values[n..];
        if page.len() == page_values {
            flush(page)?;
        }
    }
    Ok(())
}

/// Refuses a column that has levels: the pages made here have none.
fn required(descr: &ColumnDescPtr) -> Result<(), ParquetError> {
    if descr.max_def_level() != 0 || descr.max_rep_level() != 0 {
        return Err(ParquetError::General(format!(
            "column {} is not a required one: its pages are not made here",
            descr.path()
        )));
    }
    Ok(())
}

fn mismatch(values: &ColumnValues, kind: Type) -> ParquetError {
    ParquetError::General(format!(
        "a column of {} values given to a writer of {kind} values",
        values.type_name()
    ))
}

fn too_many(what: &str) -> ParquetError {
    ParquetError::General(format!("a column chunk of more {what} than Parquet counts"))
}

/// The pages of a column chunk written here: each page's header and compressed values,
/// and what the chunk's metadata and offset index say of them.
struct ChunkPages {
    out: TrackedWrite<Vec<u8>>,
    /// Every data page's.
    encoding: Encoding,
    offsets: OffsetIndexBuilder,
    /// Pages written, values in them, and their sizes (each with its header).
    count: u64,
    values: u64,
    compressed: u64,
    uncompressed: u64,
    bytes_written: u64,
    /// Where the first page begins in the chunk.
    first_offset: Option<u64>,
}

impl ChunkPages {
    fn new(encoding: Encoding) -> ChunkPages {
        ChunkPages {
            out: TrackedWrite::new(Vec::new()),
            encoding,
            offsets: OffsetIndexBuilder::new(),
            count: 0,
            values: 0,
            compressed: 0,
            uncompressed: 0,
            bytes_written: 0,
            first_offset: None,
        }
    }

    /// Writes a data page of `num_values` values, `data` their encoded bytes (compressed
    /// here).
    fn write(
        &mut self,
        zstd: &mut zstd::bulk::Compressor<'static>,
        data: &[u8],
        num_values: u32,
    ) -> Result<(), ParquetError> {
        let page = Page::DataPage {
            buf: Bytes::from(zstd.compress(data).map_err(zstd_error)?),
            num_values,
            encoding: self.encoding,
            def_level_encoding: Encoding::RLE,
            rep_level_encoding: Encoding::RLE,
            statistics: None,
        };
        let spec = SerializedPageWriter::new(&mut self.out)
            .write_page(CompressedPage::new(page, data.len()))?;
        let size = i32::try_from(spec.compressed_size).map_err(|_| too_many("bytes"))?;
        self.offsets.append_offset_and_size(
            i64::try_from(spec.offset).map_err(|_| too_many("bytes"))?,
            size,
        );
        self.offsets.append_row_count(i64::from(num_values));
        self.first_offset.get_or_insert(spec.offset);
        self.count += 1;
        self.values += u64::from(num_values);
        self.compressed += spec.compressed_size as u64;
        self.uncompressed += spec.uncompressed_size as u64;
        self.bytes_written += spec.bytes_written;
        Ok(())
    }

    /// The chunk's metadata, as parquet-rs's column writer makes it, and the chunk
    /// appended to `row_group`.
    fn close<W: Write + Send>(
        self,
        row_group: &mut SerializedRowGroupWriter<'_, W>,
        descr: ColumnDescPtr,
        level: i32,
        statistics: parquet::file::statistics::Statistics,
        column_index: Option<parquet::file::page_index::column_index::ColumnIndexMetaData>,
    ) -> Result<(), ParquetError> {
        // Row groups are written with rows only.
        if self.count == 0 {
            return Err(ParquetError::General(format!(
                "column {}: a column chunk of no values",
                descr.path()
            )));
        }
        let bytes = |n: u64| i64::try_from(n).map_err(|_| too_many("bytes"));
        let metadata = ColumnChunkMetaData::builder(descr)
            .set_compression(Compression::ZSTD(ZstdLevel::try_new(level)?))
            // Levels are RLE-encoded (there are none: the column is required).
            .set_encodings_mask(EncodingMask::new_from_encodings(
                [self.encoding, Encoding::RLE].iter(),
            ))
            .set_page_encoding_stats(vec![PageEncodingStats {
                page_type: PageType::DATA_PAGE,
                encoding: self.encoding,
                count: i32::try_from(self.count).map_err(|_| too_many("pages"))?,
            }])
            .set_total_compressed_size(bytes(self.compressed)?)
            .set_total_uncompressed_size(bytes(self.uncompressed)?)
            .set_num_values(i64::try_from(self.values).map_err(|_| too_many("values"))?)
            .set_data_page_offset(bytes(self.first_offset.unwrap_or(0))?)
            .set_dictionary_page_offset(None)
            .set_statistics(statistics)
            .build()?;
        let chunk = Bytes::from(self.out.into_inner()?);
        row_group.append_column(
            &chunk,
            ColumnCloseResult {
                bytes_written: self.bytes_written,
                rows_written: self.values,
                metadata,
                bloom_filter: None,
                column_index,
                offset_index: Some(self.offsets.build()),
            },
        )
    }
}

/// The pages of a `FLOAT` or `DOUBLE` column chunk being written ([`write_float_chunk`]).
struct FloatPages {
    chunk: ChunkPages,
    stats: FloatStatistics,
    /// The page being filled: the first `filled` of its `page_bytes` (the buffer may be
    /// longer).
    page: Vec<u8>,
    page_bytes: usize,
    filled: usize,
    /// Bytes a value.
    width: usize,
}

impl FloatPages {
    /// Copies `values` into pages (`copy`: copies values into a page, as their PLAIN bytes
    /// of `N` each, taking their statistics), writing each page that fills.
    fn put<T, const N: usize>(
        &mut self,
        mut values: &[T],
        copy: impl Fn(&mut FloatStatistics, &[T], &mut [[u8; N]]),
        zstd: &mut zstd::bulk::Compressor<'static>,
    ) -> Result<(), ParquetError> {
        debug_assert_eq!(N, self.width);
        while !values.is_empty() {
            let room = self.page[self.filled..self.page_bytes]
                .as_chunks_mut::<N>()
                .0;
            let (taken, rest) = values.split_at(values.len().min(room.len()));
            copy(&mut self.stats, taken, &mut room[..taken.len()]);
            self.filled += taken.len() * N;
            values = rest;
            if self.filled == self.page_bytes {
                self.flush(zstd)?;
            }
        }
        Ok(())
    }

    /// Writes the values gathered (if any) as a data page.
    fn flush(&mut self, zstd: &mut zstd::bulk::Compressor<'static>) -> Result<(), ParquetError> {
        if self.filled == 0 {
            return Ok(());
        }
        let num_values = u32::try_from(self.filled / self.width).map_err(|_| too_many("values"))?;
        self.stats.end_page()?;
        self.chunk
            .write(zstd, &self.page[..self.filled], num_values)?;
        self.filled = 0;
        Ok(())
    }
}

/// Room for values widened to their Parquet type, kept between the batches of a chunk.
#[derive(Default)]
struct Widened {
    int32: Vec<i32>,
    int64: Vec<i64>,
    bytes: Vec<ByteArray>,
}

/// Writes one batch's values of a column: 8- and 16-bit integers widened to `INT32`, unsigned
/// 32- and 64-bit ones reinterpreted as signed (as parquet-rs's Arrow writer does, the
/// column's logical type saying they are unsigned), text as byte arrays.
fn write_values(
    writer: &mut ColumnWriter<'_>,
    values: &ColumnValues,
    widened: &mut Widened,
) -> Result<(), ParquetError> {
    fn int32<'r, T: Copy>(room: &'r mut Vec<i32>, v: &[T], f: impl Fn(T) -> i32) -> &'r [i32] {
        room.clear();
        room.extend(v.iter().map(|&x| f(x)));
        room
    }
    let mismatch = || {
        ParquetError::General(format!(
            "a column of {} values given to a writer of another type",
            values.type_name()
        ))
    };
    match writer {
        ColumnWriter::Int32ColumnWriter(w) => {
            let v: &[i32] = match values {
                ColumnValues::Int32(v) => v,
                ColumnValues::Int8(v) => int32(&mut widened.int32, v, i32::from),
                ColumnValues::UInt8(v) => int32(&mut widened.int32, v, i32::from),
                ColumnValues::Char(v) => int32(&mut widened.int32, v, |b| i32::from(b as i8)),
                ColumnValues::Int16(v) => int32(&mut widened.int32, v, i32::from),
                ColumnValues::UInt16(v) => int32(&mut widened.int32, v, i32::from),
                ColumnValues::UInt32(v) => int32(&mut widened.int32, v, |x| x as i32),
                _ => return Err(mismatch()),
            };
            w.write_batch(v, None, None)?;
        }
        ColumnWriter::Int64ColumnWriter(w) => {
            let v: &[i64] = match values {
                ColumnValues::Int64(v) => v,
                ColumnValues::UInt64(v) => {
                    widened.int64.clear();
                    widened.int64.extend(v.iter().map(|&x| x as i64));
                    &widened.int64
                }
                _ => return Err(mismatch()),
            };
            w.write_batch(v, None, None)?;
        }
        ColumnWriter::FloatColumnWriter(w) => match values {
            ColumnValues::Float(v) => {
                w.write_batch(v, None, None)?;
            }
            _ => return Err(mismatch()),
        },
        ColumnWriter::DoubleColumnWriter(w) => match values {
            ColumnValues::Double(v) => {
                w.write_batch(v, None, None)?;
            }
            _ => return Err(mismatch()),
        },
        ColumnWriter::BoolColumnWriter(w) => match values {
            ColumnValues::Bool(v) => {
                w.write_batch(v, None, None)?;
            }
            _ => return Err(mismatch()),
        },
        ColumnWriter::ByteArrayColumnWriter(w) => match values {
            ColumnValues::Text(v) => {
                widened.bytes.clear();
                widened
                    .bytes
                    .extend(v.iter().map(|s| ByteArray::from(s.as_bytes().to_vec())));
                w.write_batch(&widened.bytes, None, None)?;
            }
            _ => return Err(mismatch()),
        },
        _ => return Err(mismatch()),
    }
    Ok(())
}
