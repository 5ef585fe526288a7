//! One column chunk of a row group: a column's values, from every batch of the row group,
//! encoded by parquet-rs's column writer (PLAIN values, statistics, the page index) into
//! pages that are compressed here, with one ZSTD context a thread for every chunk it
//! writes. A `FLOAT` or `DOUBLE` column's statistics are taken from its pages here too
//! ([`super::statistics`]).
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
use parquet::basic::{Compression, Encoding, Type, ZstdLevel};
use parquet::column::page::{CompressedPage, Page, PageWriteSpec, PageWriter};
use parquet::column::writer::{ColumnCloseResult, ColumnWriter, get_column_writer};
use parquet::data_type::ByteArray;
use parquet::errors::ParquetError;
use parquet::file::properties::WriterPropertiesPtr;
use parquet::file::writer::{SerializedPageWriter, SerializedRowGroupWriter, TrackedWrite};
use parquet::schema::types::ColumnDescPtr;

use super::statistics::FloatStatistics;
use crate::columns::ColumnValues;

/// The column writers' properties of a table: as the file's, without compression.
pub(super) struct ChunkProperties {
    /// For the columns whose statistics parquet-rs takes.
    pub(super) parquet: WriterPropertiesPtr,
    /// For `FLOAT` and `DOUBLE` columns, when their statistics are taken here (statistics
    /// off, and the values PLAIN: no dictionary); and whether a column index is made.
    pub(super) float: Option<(WriterPropertiesPtr, bool)>,
}

thread_local! {
    /// This thread's ZSTD context, and the level it compresses at.
    static ZSTD: RefCell<Option<(i32, zstd::bulk::Compressor<'static>)>> =
        const { RefCell::new(None) };
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
    /// The statistics taken here, of a `FLOAT` or `DOUBLE` column's data pages.
    float: Option<&'a mut FloatStatistics>,
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
            } => {
                if let Some(stats) = self.float.as_deref_mut() {
                    if *encoding != Encoding::PLAIN {
                        return Err(ParquetError::General(format!(
                            "a float data page encoded {encoding}: its statistics are taken \
                             from PLAIN values only"
                        )));
                    }
                    stats.page(buf, *num_values)?;
                }
                Page::DataPage {
                    buf: compressed(buf, self.zstd)?,
                    num_values: *num_values,
                    encoding: *encoding,
                    def_level_encoding: *def_level_encoding,
                    rep_level_encoding: *rep_level_encoding,
                    statistics: statistics.clone(),
                }
            }
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
    let float = props
        .float
        .as_ref()
        .filter(|_| matches!(kind, Type::FLOAT | Type::DOUBLE));
    let mut stats = float.map(|_| FloatStatistics::new(kind));
    let mut out = TrackedWrite::new(Vec::new());
    let close = with_zstd(level, |zstd| {
        let pages = CompressingPages {
            out: &mut out,
            zstd,
            float: stats.as_mut(),
        };
        let column_props = float.map_or(&props.parquet, |(p, _)| p).clone();
        let mut writer = get_column_writer(descr, column_props, Box::new(pages));
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
    let mut metadata = metadata
        .into_builder()
        .set_compression(Compression::ZSTD(ZstdLevel::try_new(level)?));
    let mut column_index = column_index;
    if let (Some(stats), Some((_, page_index))) = (stats, float) {
        let (statistics, index) = stats.finish(*page_index)?;
        metadata = metadata.set_statistics(statistics);
        column_index = index;
    }
    let metadata = metadata.build()?;
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
