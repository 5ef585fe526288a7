//! Encoding a conversion's tables beside its read: batches of rows as they came
//! ([`RowBatch`]) are made columns, their field statistics taken, and held until a row
//! group is written, each table's batches in the order they came. Either on the reading
//! thread ([`Encoder::inline`]) or on a pool of threads ([`Encoder::pool`]) that takes one
//! table at a time each, so that one log uses every core; when the pool falls behind, the
//! reading thread encodes batches too rather than wait for it, and it helps with the last
//! ones once it has read everything.
//!
//! The log file's SHA-256 can be taken here too ([`Encoder::hash`]): its bytes, copied as
//! they are read, are hashed in order by whichever thread is free, so that on two cores the
//! reading thread, which sets the pace, does not hash the whole file itself.
//!
//! Where row groups fall is decided as the batches are given, from the bytes their rows
//! take once columns, never from how far the threads have got: when the rows given and not
//! yet planned into a row group pass the budget, the table holding most of them per column
//! gets a row group at that point of its queue (each column chunk has a cost of its own: a
//! column writer, its pages' headers, its metadata in the footer; so a table of many
//! columns waits until its row group is large). The same log and options give the same
//! files, byte for byte, on any number of threads.

use std::collections::VecDeque;
use std::io::Write;
use std::sync::{Condvar, Mutex, MutexGuard};

use parquet::errors::ParquetError;

use super::Table;
use crate::analysis::ColumnStats;
use crate::columns::RowBatch;

/// Where a table is written: closed between row groups when it can be.
pub(super) trait Output: Write + Send {
    /// Gives back what the output holds between writes (a file handle).
    fn release(&mut self) {}
}

/// One table of a conversion and the field statistics of its columns.
pub(super) struct TableWork<W: Output> {
    pub(super) table: Table<W>,
    pub(super) stats: Option<ColumnStats>,
}

impl<W: Output> TableWork<W> {
    fn append(&mut self, batch: RowBatch) -> Result<(), ParquetError> {
        let columns = batch.columns();
        if let Some(s) = &mut self.stats {
            s.add(&columns);
        }
        let result = self.table.append(columns);
        self.release();
        result
    }

    fn flush(&mut self) -> Result<(), ParquetError> {
        let result = self.table.flush();
        self.release();
        result
    }

    /// Closes the file between row groups (each is flushed as written).
    fn release(&mut self) {
        if let Some(out) = self.table.output() {
            out.release();
        }
    }
}

/// Why a batch was not taken: a table failed ([`Encoder::take_tables`] says which and why).
#[derive(Debug)]
pub(super) struct Stopped;

/// Where a table's row group failed: its index, and why.
pub(super) type Failure = (usize, ParquetError);

/// What a table's queue holds, in the order it was given.
enum Item {
    /// Rows to make columns of.
    Batch(RowBatch),
    /// The rows so far, written as a row group.
    RowGroup,
}

/// The tables of one conversion and where they are encoded.
pub(super) struct Encoder<W: Output> {
    shared: Shared<W>,
    /// Encoder threads: none encodes on the reading thread.
    threads: usize,
}

struct Shared<W: Output> {
    state: Mutex<State<W>>,
    /// Workers wait here for a table with batches.
    work: Condvar,
    /// The reader waits here for the batches in flight to fall within their bound.
    room: Condvar,
    /// Bytes of rows (once columns) all tables may hold before one is written.
    budget: usize,
    /// Bytes of row batches and of the file to hash waiting for a worker before the reader
    /// waits.
    in_flight_limit: usize,
}

struct State<W: Output> {
    slots: Vec<Slot<W>>,
    /// Tables with batches waiting and no worker on them ([`HASH`]: the hash).
    ready: VecDeque<usize>,
    hash: Hash,
    in_flight: usize,
    /// The sum of the slots' `unplanned`.
    unplanned: usize,
    /// No batch will come any more.
    done: bool,
    failure: Option<Failure>,
}

/// `ready`'s name of the hash.
const HASH: usize = usize::MAX;

/// Hashed buffers kept to be filled again.
const FREE_BUFFERS: usize = 4;

/// The file's bytes to hash, in the order they were read, and the hash so far (when no
/// thread holds it).
struct Hash {
    queue: VecDeque<Vec<u8>>,
    /// Buffers hashed, to be filled again (not made anew: the pages of a new one are
    /// faulted in and zeroed by the kernel).
    free: Vec<Vec<u8>>,
    sha: Option<sha2::Sha256>,
    /// Whether it is in `ready`.
    queued: bool,
}

struct Slot<W: Output> {
    queue: VecDeque<Item>,
    /// The table, when no worker holds it.
    work: Option<TableWork<W>>,
    /// Whether it is in `ready`.
    queued: bool,
    /// Bytes its rows take once columns, given since its last row group was planned.
    unplanned: usize,
    /// Its columns (at least 1).
    columns: usize,
}

impl<W: Output> Encoder<W> {
    /// Tables encoded on the thread that gives them their batches.
    pub(super) fn inline(budget: usize) -> Encoder<W> {
        Encoder::new(budget, 0)
    }

    /// Tables encoded by `threads` workers (at least one), each started with
    /// [`Encoder::work`] on a thread of its own.
    pub(super) fn pool(budget: usize, threads: usize) -> Encoder<W> {
        Encoder::new(budget, threads.max(1))
    }

    fn new(budget: usize, threads: usize) -> Encoder<W> {
        Encoder {
            shared: Shared {
                state: Mutex::new(State {
                    slots: Vec::new(),
                    ready: VecDeque::new(),
                    hash: Hash {
                        queue: VecDeque::new(),
                        free: Vec::new(),
                        sha: Some(sha2::Digest::new()),
                        queued: false,
                    },
                    in_flight: 0,
                    unplanned: 0,
                    done: false,
                    failure: None,
                }),
                work: Condvar::new(),
                room: Condvar::new(),
                budget,
                // Enough for each worker to have a batch and the reader to fill more.
                in_flight_limit: (budget / 4).max(1 << 20),
            },
            threads,
        }
    }

    /// The worker threads to start (0: encoding is inline).
    pub(super) fn threads(&self) -> usize {
        self.threads
    }

    fn lock(&self) -> MutexGuard<'_, State<W>> {
        // A worker that panicked leaves the state as it was between two steps.
        self.shared
            .state
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Adds a table; returns its index.
    pub(super) fn add(&self, work: TableWork<W>) -> usize {
        let mut st = self.lock();
        let columns = work.table.columns().max(1);
        st.slots.push(Slot {
            queue: VecDeque::new(),
            work: Some(work),
            queued: false,
            unplanned: 0,
            columns,
        });
        st.slots.len() - 1
    }

    /// Gives table `t` a batch, and plans the row groups its rows call for: encoded now
    /// (inline) or by a worker (waiting while too many bytes are in flight). The first
    /// failure of any table is returned from then on.
    pub(super) fn push(&self, t: usize, batch: RowBatch) -> Result<(), Stopped> {
        let mut st = self.room()?;
        let bytes = batch.rows() * batch.spec().stored_row_size();
        st.in_flight += batch.memory();
        st.slots[t].unplanned += bytes;
        st.unplanned += bytes;
        st.enqueue(t, Item::Batch(batch), &self.shared.work);
        // While the rows given pass the budget, the table holding most bytes per column
        // gets a row group after what it was given.
        while st.unplanned > self.shared.budget {
            let Some(k) = (0..st.slots.len())
                .filter(|&k| st.slots[k].unplanned > 0)
                .max_by_key(|&k| st.slots[k].unplanned / st.slots[k].columns)
            else {
                break;
            };
            let planned = std::mem::take(&mut st.slots[k].unplanned);
            st.unplanned -= planned;
            st.enqueue(k, Item::RowGroup, &self.shared.work);
        }
        if self.threads == 0 {
            // Inline: what was given is encoded now, on this thread.
            loop {
                let (next, worked) = self.step(st)?;
                if !worked {
                    break;
                }
                st = next;
            }
        }
        Ok(())
    }

    /// The state once the bytes in flight are within their bound: until then this thread
    /// does the workers' work rather than wait for them. [`Stopped`] once a table failed.
    fn room(&self) -> Result<MutexGuard<'_, State<W>>, Stopped> {
        let mut st = self.lock();
        while self.threads > 0 && st.in_flight > self.shared.in_flight_limit && st.failure.is_none()
        {
            let (next, worked) = self.step(st)?;
            st = if worked {
                next
            } else {
                self.shared
                    .room
                    .wait(next)
                    .unwrap_or_else(std::sync::PoisonError::into_inner)
            };
        }
        if st.failure.is_some() {
            return Err(Stopped);
        }
        Ok(st)
    }

    /// Gives the hash the file's next bytes (with workers only: inline, the caller hashes
    /// them itself).
    pub(super) fn hash(&self, bytes: &[u8]) -> Result<(), Stopped> {
        debug_assert!(self.threads > 0, "hashed by workers");
        let mut copy = self.lock().hash.free.pop().unwrap_or_default();
        copy.clear();
        copy.extend_from_slice(bytes);
        let bytes = copy;
        let mut st = self.room()?;
        st.in_flight += bytes.len();
        st.hash.queue.push_back(bytes);
        st.requeue_hash(&self.shared.work);
        Ok(())
    }

    /// The hash of every byte given to [`Encoder::hash`], once the workers have stopped.
    pub(super) fn take_hash(&self) -> sha2::Sha256 {
        let mut st = self.lock();
        // An invariant, not an input's fault: a wrong digest would name another log.
        assert!(st.hash.queue.is_empty(), "every byte given is hashed");
        st.hash.sha.take().expect("no worker holds the hash")
    }

    /// A worker: encodes ready tables and hashes the file's bytes given until
    /// [`Encoder::finish`] and no batch or byte is left. The
    /// reading thread may call it too once it has given every batch, to help.
    pub(super) fn work(&self) {
        let mut st = self.lock();
        loop {
            if st.failure.is_some() {
                return;
            }
            let Ok((next, worked)) = self.step(st) else {
                return;
            };
            st = next;
            if !worked {
                if st.done {
                    return;
                }
                st = self
                    .shared
                    .work
                    .wait(st)
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
            }
        }
    }

    /// One step of a worker: the next ready table's next batch encoded, or its row group
    /// written. Whether there was a ready table; [`Stopped`] if a table failed (the failure
    /// is kept, every thread woken).
    fn step<'a>(
        &'a self,
        mut st: MutexGuard<'a, State<W>>,
    ) -> Result<(MutexGuard<'a, State<W>>, bool), Stopped> {
        let Some(t) = st.ready.pop_front() else {
            return Ok((st, false));
        };
        if t == HASH {
            return Ok((self.hash_step(st), true));
        }
        let slot = &mut st.slots[t];
        slot.queued = false;
        // A table is ready only while no worker holds it (`enqueue`, `requeue`).
        let mut work = slot.work.take().expect("a ready table is idle");
        let Some(item) = slot.queue.pop_front() else {
            slot.work = Some(work);
            return Ok((st, true));
        };
        drop(st);
        let (bytes, result) = match item {
            Item::Batch(batch) => (batch.memory(), work.append(batch)),
            Item::RowGroup => (0, work.flush()),
        };
        st = self.lock();
        st.in_flight -= bytes;
        self.shared.room.notify_all();
        st.slots[t].work = Some(work);
        if let Err(e) = result {
            st.fail(t, e);
            drop(st);
            self.wake_all();
            return Err(Stopped);
        }
        st.requeue(t, &self.shared.work);
        Ok((st, true))
    }

    /// One step of the hash: its next bytes.
    fn hash_step<'a>(&'a self, mut st: MutexGuard<'a, State<W>>) -> MutexGuard<'a, State<W>> {
        st.hash.queued = false;
        // The hash is ready only while no thread holds it (`requeue_hash`).
        let mut sha = st.hash.sha.take().expect("a ready hash is idle");
        let bytes = st.hash.queue.pop_front();
        drop(st);
        let n = bytes.as_ref().map_or(0, |b| {
            sha2::Digest::update(&mut sha, b);
            b.len()
        });
        let mut st = self.lock();
        if let Some(b) = bytes
            && st.hash.free.len() < FREE_BUFFERS
        {
            st.hash.free.push(b);
        }
        st.in_flight -= n;
        self.shared.room.notify_all();
        st.hash.sha = Some(sha);
        st.requeue_hash(&self.shared.work);
        st
    }

    fn wake_all(&self) {
        self.shared.work.notify_all();
        self.shared.room.notify_all();
    }

    /// Tells the workers no batch will come; once they have stopped (the caller joins
    /// them), [`Encoder::take_tables`] gives the tables back.
    pub(super) fn finish(&self) {
        self.lock().done = true;
        self.wake_all();
    }

    /// The tables, in the order they were added, or the first failure (taken out: the
    /// encoder holds nothing after).
    pub(super) fn take_tables(&self) -> Result<Vec<TableWork<W>>, Failure> {
        let mut st = self.lock();
        if let Some(f) = st.failure.take() {
            return Err(f);
        }
        Ok(std::mem::take(&mut st.slots)
            .into_iter()
            .map(|s| s.work.expect("every worker has stopped"))
            .collect())
    }
}

impl<W: Output> State<W> {
    /// Adds `item` to table `t`'s queue, and makes the table ready if it is idle.
    fn enqueue(&mut self, t: usize, item: Item, work: &Condvar) {
        self.slots[t].queue.push_back(item);
        self.requeue(t, work);
    }

    /// Makes idle table `t` ready again if items came for it meanwhile.
    fn requeue(&mut self, t: usize, work: &Condvar) {
        let slot = &mut self.slots[t];
        if !slot.queue.is_empty() && !slot.queued && slot.work.is_some() {
            slot.queued = true;
            self.ready.push_back(t);
            work.notify_one();
        }
    }

    /// Makes the idle hash ready again if bytes came for it meanwhile.
    fn requeue_hash(&mut self, work: &Condvar) {
        let hash = &mut self.hash;
        if !hash.queue.is_empty() && !hash.queued && hash.sha.is_some() {
            hash.queued = true;
            self.ready.push_back(HASH);
            work.notify_one();
        }
    }

    fn fail(&mut self, t: usize, e: ParquetError) {
        if self.failure.is_none() {
            self.failure = Some((t, e));
        }
    }
}
