//! Encoding a conversion's tables beside its read: batches of rows as they came
//! ([`RowBatch`]) are made columns, their field statistics taken, and held until a row
//! group is written, each table's batches in the order they came. Either on the reading
//! thread ([`Encoder::inline`]) or on a pool of threads ([`Encoder::pool`]) that takes one
//! table at a time each, so that one log uses every core; when the pool falls behind, the
//! reading thread encodes batches too rather than wait for it, and it helps with the last
//! ones once it has read everything. Either way, when the batches held
//! by all tables pass the budget, the table holding most bytes per column is written as a
//! row group (of those no other thread is encoding): each column chunk has a cost of its own
//! (a column writer, its pages' headers, its metadata in the footer), so a table of many
//! columns waits until its row group is large.

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
    /// Bytes of Arrow batches all tables may hold before one is written.
    budget: usize,
    /// Bytes of row batches waiting for a worker before the reader waits.
    in_flight_limit: usize,
}

struct State<W: Output> {
    slots: Vec<Slot<W>>,
    /// Tables with batches waiting and no worker on them.
    ready: VecDeque<usize>,
    in_flight: usize,
    /// The sum of the slots' `memory`.
    held: usize,
    /// No batch will come any more.
    done: bool,
    failure: Option<Failure>,
}

struct Slot<W: Output> {
    queue: VecDeque<RowBatch>,
    /// The table, when no worker holds it.
    work: Option<TableWork<W>>,
    /// Whether it is in `ready`.
    queued: bool,
    /// Bytes of Arrow batches it holds, as last measured.
    memory: usize,
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
                    in_flight: 0,
                    held: 0,
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
            memory: 0,
            columns,
        });
        st.slots.len() - 1
    }

    /// Gives table `t` a batch: encoded now (inline) or by a worker (waiting while too many
    /// bytes are in flight). The first failure of any table is returned from then on.
    pub(super) fn push(&self, t: usize, batch: RowBatch) -> Result<(), Stopped> {
        if self.threads == 0 {
            let mut st = self.lock();
            if st.failure.is_some() {
                return Err(Stopped);
            }
            let mut work = st.slots[t].work.take().expect("inline: always held");
            let result = work.append(batch);
            st.slots[t].work = Some(work);
            if let Err(e) = result {
                st.fail(t, e);
                return Err(Stopped);
            }
            st.measure(t);
            return match self.within_budget(st) {
                Ok(_) => Ok(()),
                Err((k, e)) => {
                    self.lock().fail(k, e);
                    Err(Stopped)
                }
            };
        }
        let mut st = self.lock();
        while st.in_flight > self.shared.in_flight_limit && st.failure.is_none() {
            // Rather than wait for the workers, encode a batch of theirs on this thread.
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
        st.in_flight += batch.memory();
        let slot = &mut st.slots[t];
        slot.queue.push_back(batch);
        if slot.work.is_some() && !slot.queued {
            slot.queued = true;
            st.ready.push_back(t);
            self.shared.work.notify_one();
        }
        Ok(())
    }

    /// A worker: encodes ready tables until [`Encoder::finish`] and no batch is left. The
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

    /// One step of a worker: the next ready table's next batch encoded (and a row group
    /// written if the tables then hold more than the budget). Whether there was a ready
    /// table; [`Stopped`] if a table failed (the failure is kept, every thread woken).
    fn step<'a>(
        &'a self,
        mut st: MutexGuard<'a, State<W>>,
    ) -> Result<(MutexGuard<'a, State<W>>, bool), Stopped> {
        let Some(t) = st.ready.pop_front() else {
            return Ok((st, false));
        };
        let slot = &mut st.slots[t];
        slot.queued = false;
        // Being written as a row group by another thread, which requeues it after.
        let Some(mut work) = slot.work.take() else {
            return Ok((st, true));
        };
        let Some(batch) = slot.queue.pop_front() else {
            slot.work = Some(work);
            return Ok((st, true));
        };
        drop(st);
        // One batch at a time, the budget looked at after each: the row groups are as
        // large as the budget lets them be, not as many batches as came at once.
        let bytes = batch.memory();
        let result = work.append(batch);
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
        st.measure(t);
        let mut st = match self.within_budget(st) {
            Ok(st) => st,
            Err((k, e)) => {
                self.lock().fail(k, e);
                self.wake_all();
                return Err(Stopped);
            }
        };
        st.requeue(t, &self.shared.work);
        Ok((st, true))
    }

    /// While the tables hold more than the budget, writes the table holding most bytes per
    /// column, of those no other worker holds, as a row group (the fewer column chunks, the
    /// less their fixed costs).
    fn within_budget<'a>(
        &'a self,
        mut st: MutexGuard<'a, State<W>>,
    ) -> Result<MutexGuard<'a, State<W>>, Failure> {
        while st.held > self.shared.budget {
            let Some(k) = (0..st.slots.len())
                .filter(|&k| st.slots[k].work.is_some() && st.slots[k].memory > 0)
                .max_by_key(|&k| st.slots[k].memory / st.slots[k].columns)
            else {
                break;
            };
            let mut work = st.slots[k].work.take().expect("idle");
            drop(st);
            let result = work.flush();
            st = self.lock();
            st.slots[k].work = Some(work);
            if let Err(e) = result {
                return Err((k, e));
            }
            st.measure(k);
            st.requeue(k, &self.shared.work);
        }
        Ok(st)
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
    /// Re-reads the memory table `t` holds (it is idle).
    fn measure(&mut self, t: usize) {
        let now = self.slots[t].work.as_ref().map_or(0, |w| w.table.memory());
        self.held = self.held - self.slots[t].memory + now;
        self.slots[t].memory = now;
    }

    /// Makes idle table `t` ready again if batches came for it meanwhile.
    fn requeue(&mut self, t: usize, work: &Condvar) {
        let slot = &mut self.slots[t];
        if !slot.queue.is_empty() && !slot.queued && slot.work.is_some() {
            slot.queued = true;
            self.ready.push_back(t);
            work.notify_one();
        }
    }

    fn fail(&mut self, t: usize, e: ParquetError) {
        if self.failure.is_none() {
            self.failure = Some((t, e));
        }
    }
}
