//! Memory-mapped files (feature `mmap`): the bytes of a file without reading them into
//! memory, and one pass over every row that gives the pages back as it goes, so that the
//! resident memory of a walk stays bounded whatever the file size.

use std::path::Path;

use super::log::{Fold, RowSink, Summary, all_cores, collect, summary};
use super::{Metadata, ReadError, Row};

/// A file mapped read-only into memory. Like every memory-mapped reader, it needs the file
/// not to be truncated by another process while the map lives.
///
/// ```no_run
/// use ulog_runtime::read::MappedFile;
/// let file = MappedFile::open("flight.ulg")?;
/// let (summary, counts) = file.fold_rows(|| 0usize, |n, _row| *n += 1)?;
/// assert_eq!(summary.rows, counts.iter().sum::<usize>());
/// # Ok::<(), ulog_runtime::ReadError>(())
/// ```
#[derive(Debug)]
pub struct MappedFile {
    map: memmap2::Mmap,
}

/// Pages are given back in steps of this many bytes...
const RELEASE_STEP: u64 = 8 << 20;
/// ...and never within this distance of the walk, which may look back one message.
const RELEASE_MARGIN: u64 = 256 << 10;

impl MappedFile {
    /// Maps a file.
    pub fn open(path: impl AsRef<Path>) -> Result<MappedFile, ReadError> {
        let file = std::fs::File::open(path)?;
        // SAFETY: the map is only read; the caller is told not to truncate the file meanwhile,
        // which is the contract of every memory-mapped file reader.
        #[allow(unsafe_code)]
        let map = unsafe { memmap2::Mmap::map(&file)? };
        Ok(MappedFile { map })
    }

    /// [`fold_rows`](super::fold_rows) over the mapped file, giving the pages of the parts
    /// already walked back to the kernel (`MADV_DONTNEED`) as the walk advances: the
    /// resident memory stays at a few steps of 8 MB per thread, not the file's size. Pages
    /// walked again (a part a worker could not use) are read again from the file.
    pub fn fold_rows<T, I, F>(&self, init: I, fold: F) -> Result<(Summary, Vec<T>), ReadError>
    where
        T: Send,
        I: Fn() -> T + Sync,
        F: Fn(&mut T, &Row<'_>) + Sync,
    {
        self.fold_rows_on(all_cores(), init, fold)
    }

    /// [`MappedFile::fold_rows`] on at most `threads` threads (1: this thread only).
    pub fn fold_rows_on<T, I, F>(
        &self,
        threads: usize,
        init: I,
        fold: F,
    ) -> Result<(Summary, Vec<T>), ReadError>
    where
        T: Send,
        I: Fn() -> T + Sync,
        F: Fn(&mut T, &Row<'_>) + Sync,
    {
        let release = |from: u64, to: u64| self.release(from, to);
        let sink = Releasing {
            inner: Fold::new(&init, &fold),
            release: &release,
            done: None,
        };
        let (metadata, mut all) = collect(&self.map, sink, threads.max(1))?;
        let parts = std::mem::take(&mut all.sink.inner.parts);
        Ok((summary(metadata, all), parts))
    }

    /// Drops the pages of `[from, to)` from the process (whole pages only).
    pub(crate) fn release(&self, from: u64, to: u64) {
        const PAGE: u64 = 4096;
        let from = from.div_ceil(PAGE) * PAGE;
        let to = to / PAGE * PAGE;
        if to > from {
            // SAFETY: the map is shared and read-only, so MADV_DONTNEED only drops this
            // process's references to the pages: a later read faults the file's own bytes
            // back in, unchanged. (It is unsafe in general because a private writable map
            // would lose its changes.) A failure only leaves the pages resident.
            #[allow(unsafe_code)]
            let _ = unsafe {
                self.map.unchecked_advise_range(
                    memmap2::UncheckedAdvice::DontNeed,
                    from as usize,
                    (to - from) as usize,
                )
            };
        }
    }
}

impl std::ops::Deref for MappedFile {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        &self.map
    }
}

/// A sink that gives pages back behind the rows it takes.
struct Releasing<'r, S> {
    inner: S,
    release: &'r (dyn Fn(u64, u64) + Sync),
    /// Where this thread's walk released up to (`None` before its first row).
    done: Option<u64>,
}

impl<S: RowSink> RowSink for Releasing<'_, S> {
    #[inline]
    fn row(&mut self, meta: &Metadata, offset: u64, data: &[u8], sub: usize, timestamp: u64) {
        self.inner.row(meta, offset, data, sub, timestamp);
        let done = *self.done.get_or_insert(offset);
        if offset >= done + RELEASE_STEP + RELEASE_MARGIN {
            let to = offset - RELEASE_MARGIN;
            (self.release)(done, to);
            self.done = Some(to);
        }
    }
    fn len(&self) -> usize {
        self.inner.len()
    }
    fn fork(&self, bytes: usize) -> Self {
        Releasing {
            inner: self.inner.fork(bytes),
            release: self.release,
            done: None,
        }
    }
    fn append(&mut self, other: Self) {
        self.inner.append(other.inner);
    }
}
