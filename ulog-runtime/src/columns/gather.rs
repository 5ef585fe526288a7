//! One topic instance's columns gathered on several cores ([`Log::columns`] of a large
//! instance). The columns are allocated whole and left unwritten, so that the kernel maps
//! their pages as the threads write them, each its own; each thread takes a run of
//! consecutive rows and writes their values in place, in the run's share of every column.
//! An instance's rows are scattered through the file, so the gathering waits on memory more
//! than it computes, and two cores wait side by side.
//!
//! Each thread makes columns of a few kilobytes of rows at a time ([`RowBatch`], in cache)
//! and copies them to their place: the same code as one thread's [`ColumnBuilder`], so
//! the values are the same.
//!
//! [`ColumnBuilder`]: super::ColumnBuilder

use std::mem::MaybeUninit;
use std::sync::Arc;

use super::{ColumnSpec, ColumnValues, Columns, RowBatch, STAGE_BYTES, empty_columns};
use crate::read::{InstanceRows, on_threads};

/// Rows a thread takes at least: below, another thread costs more than it saves.
pub(super) const RUN_MIN_ROWS: usize = 32_768;

/// The columns of the rows of `runs` of `spec`, in order, each run on a thread of its own
/// (the first on this one); `None` if a row was too short for the spec's `row_len`
/// ([`ColumnBuilder`] leaves such a row out; here it would leave a gap).
pub(super) fn columns(spec: &Arc<ColumnSpec>, runs: Vec<InstanceRows<'_>>) -> Option<Columns> {
    let lens: Vec<usize> = runs.iter().map(|r| r.size_hint().0).collect();
    let rows = lens.iter().sum();
    // Room for every row; the values are written by the threads.
    let mut values = empty_columns(spec, rows);
    // Per run, its slots in every column.
    let mut slots: Vec<Vec<Slots<'_>>> = lens.iter().map(|_| Vec::new()).collect();
    for column in &mut values {
        for (run, s) in cut(column, &lens).into_iter().enumerate() {
            slots[run].push(s);
        }
    }
    let jobs: Vec<Job<'_, '_>> = runs.into_iter().zip(slots).collect();
    let written = on_threads(jobs, |(run, slots)| fill(spec, run, slots));
    // The reader leaves out rows whose size is not their format's, so none is too short
    // for the columns; were one left out, its run would leave slots unwritten: `None` (and
    // the text already written, in vectors of no length, is never dropped: a leak, not an
    // error).
    if written != lens {
        return None;
    }
    for column in &mut values {
        filled(column, rows);
    }
    Some(Columns {
        spec: spec.clone(),
        values,
        rows,
    })
}

/// Writes the values of the rows of `run` into `slots` (one per column, from its start),
/// a few kilobytes of rows at a time; returns the rows written.
fn fill(spec: &Arc<ColumnSpec>, run: InstanceRows<'_>, mut slots: Vec<Slots<'_>>) -> usize {
    let stage_rows = (STAGE_BYTES / spec.row_len.max(1)).clamp(1, 4096);
    let mut staged = RowBatch::with_capacity(spec.clone(), stage_rows);
    let mut made = empty_columns(spec, stage_rows);
    let mut at = 0;
    let mut put = |staged: &mut RowBatch, at: &mut usize| {
        let n = staged.rows();
        staged.append_to(&mut made);
        for (s, v) in slots.iter_mut().zip(&mut made) {
            // What `filled` relies on: one value a row in every column, each in its slot.
            assert_eq!(v.len(), n, "one value a row in every column");
            s.put(*at, v);
        }
        *at += n;
    };
    for row in run {
        if staged.push(row.data, row.timestamp) && staged.rows() >= stage_rows {
            put(&mut staged, &mut at);
        }
    }
    put(&mut staged, &mut at);
    at
}

/// A run of rows and its slots in every column.
type Job<'r, 's> = (InstanceRows<'r>, Vec<Slots<'s>>);

/// One run's share of one column: where its rows' values go.
enum Slots<'a> {
    Int8(&'a mut [MaybeUninit<i8>]),
    UInt8(&'a mut [MaybeUninit<u8>]),
    Int16(&'a mut [MaybeUninit<i16>]),
    UInt16(&'a mut [MaybeUninit<u16>]),
    Int32(&'a mut [MaybeUninit<i32>]),
    UInt32(&'a mut [MaybeUninit<u32>]),
    Int64(&'a mut [MaybeUninit<i64>]),
    UInt64(&'a mut [MaybeUninit<u64>]),
    Float(&'a mut [MaybeUninit<f32>]),
    Double(&'a mut [MaybeUninit<f64>]),
    Bool(&'a mut [MaybeUninit<bool>]),
    Char(&'a mut [MaybeUninit<u8>]),
    Text(&'a mut [MaybeUninit<String>]),
}

/// Applies `$m!(vector, Variant)` to the vector of whichever variant `$values` is.
macro_rules! each_variant {
    ($values:expr, $m:ident) => {
        match $values {
            ColumnValues::Int8(v) => $m!(v, Int8),
            ColumnValues::UInt8(v) => $m!(v, UInt8),
            ColumnValues::Int16(v) => $m!(v, Int16),
            ColumnValues::UInt16(v) => $m!(v, UInt16),
            ColumnValues::Int32(v) => $m!(v, Int32),
            ColumnValues::UInt32(v) => $m!(v, UInt32),
            ColumnValues::Int64(v) => $m!(v, Int64),
            ColumnValues::UInt64(v) => $m!(v, UInt64),
            ColumnValues::Float(v) => $m!(v, Float),
            ColumnValues::Double(v) => $m!(v, Double),
            ColumnValues::Bool(v) => $m!(v, Bool),
            ColumnValues::Char(v) => $m!(v, Char),
            ColumnValues::Text(v) => $m!(v, Text),
        }
    };
}

/// The room of `column` (empty, with room for the sum of `lens`) cut into consecutive runs
/// of `lens` values.
fn cut<'a>(column: &'a mut ColumnValues, lens: &[usize]) -> Vec<Slots<'a>> {
    macro_rules! cut {
        ($v:expr, $variant:ident) => {{
            let mut rest: &mut [_] = $v.spare_capacity_mut();
            lens.iter()
                .map(|&n| {
                    let (run, after) = std::mem::take(&mut rest).split_at_mut(n);
                    rest = after;
                    Slots::$variant(run)
                })
                .collect()
        }};
    }
    each_variant!(column, cut)
}

impl Slots<'_> {
    /// Moves the values of `made` (of the same type) to these slots from `at` on, leaving
    /// `made` empty.
    fn put(&mut self, at: usize, made: &mut ColumnValues) {
        macro_rules! put {
            ($v:expr, $variant:ident) => {{
                let Slots::$variant(slots) = self else {
                    unreachable!("slots and values of one spec");
                };
                assert!(at + $v.len() <= slots.len(), "a run's values fit its slots");
                for (slot, value) in slots[at..].iter_mut().zip($v.drain(..)) {
                    slot.write(value);
                }
            }};
        }
        each_variant!(made, put);
    }
}

/// Makes the first `rows` values of `column`'s room its values, once every one is written.
fn filled(column: &mut ColumnValues, rows: usize) {
    macro_rules! filled {
        ($v:expr, $variant:ident) => {{
            assert!($v.is_empty() && $v.capacity() >= rows, "room for the rows");
            // SAFETY: `columns` calls this only when every run wrote as many values as it
            // has rows (`fill` writes its slots from the first on, without a gap, one value
            // a row in every column), and the runs' slots are the first `rows` of the room.
            #[allow(unsafe_code)]
            unsafe {
                $v.set_len(rows)
            };
        }};
    }
    each_variant!(column, filled);
}
