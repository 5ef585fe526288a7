//! Memory-mapped files (feature `mmap`): the bytes of a file without reading them into
//! memory, and one pass over every row that gives the pages back as it goes, so that the
//! resident memory of a walk stays bounded whatever the file size.

use std::path::Path;

use super::walk::{Fold, RowSink, Summary, Visiting, all_cores, collect, summary};
use super::{Metadata, ReadError, Row};

/// A file mapped read-only into memory. Like every memory-mapped reader, it needs the file
/// not to be truncated or rewritten in place by another process while the map lives: the
/// operating system ends the process (`SIGBUS`) when it reads a page the file no longer has.
/// For a file that may change meanwhile, read it into memory instead ([`Log::from_vec`]).
///
/// [`Log::from_vec`]: crate::Log::from_vec
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
    /// Maps a regular file. A folder or anything else ([`open_file`](super::open_file)'s
    /// errors: "is a folder, not a log file", "is not a regular file") is refused before
    /// the map would say "no such device".
    pub fn open(path: impl AsRef<Path>) -> Result<MappedFile, ReadError> {
        let file = super::open_file(path)?;
        // SAFETY: the map is only read; the caller is told not to truncate the file meanwhile,
        // which is the contract of every memory-mapped file reader.
        #[allow(unsafe_code)]
        let map = unsafe { memmap2::Mmap::map(&file)? };
        Ok(MappedFile { map })
    }

    /// [`fold_rows`](super::fold_rows) over the mapped file, giving the pages of the parts
    /// already walked back to the kernel (`MADV_DONTNEED`) as the walk advances: the
    /// resident memory stays at a few steps of 8 MB per thread, not the file's size. Pages
    /// walked again (a part a worker could not use) are read again from the file. While it
    /// walks, the kernel is told that the walk touches each page once (`MADV_SEQUENTIAL`),
    /// so that the walk neither pays for marking every page in use nor keeps the file in
    /// the page cache longer than another file read once. [`fold_file`](super::fold_file)
    /// does the same walk by positioned reads, at a cost that depends less on how the page
    /// cache holds the file.
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
        let _once = self.walk_once();
        let release = |from: u64, to: u64| self.release(from, to);
        let sink = Releasing {
            inner: Visiting::new(Fold::new(&init, &fold)),
            release: &release,
            done: None,
        };
        let (metadata, mut all) = collect(&self.map, sink, threads.max(1))?;
        let parts = std::mem::take(&mut all.sink.inner.visitor.parts);
        Ok((summary(metadata, all), parts))
    }

    /// Tells the kernel that the map is walked once from start to end, each part by its
    /// thread, and its pages given back behind the walk (`MADV_SEQUENTIAL`), until the
    /// guard drops (`MADV_NORMAL`, which takes back only this advice, not
    /// [`MappedFile::map_small_pages`]'s). The kernel then does not count the walk's touch
    /// of a page as a use that keeps the page in the cache longer: it neither marks the page
    /// accessed when the walk gives it back (`MADV_DONTNEED`), which in a cache of 4 KiB
    /// pages took a lock per page (12% of `scan`'s CPU on a 400 MB log, in its first run
    /// after the cache was refilled a page at a time), nor promotes it in the kernel's
    /// reclaim lists for that touch. Two walks of one map at once share the advice: the
    /// first to end takes it back for both (the other is then only slower).
    pub(crate) fn walk_once(&self) -> WalkOnce<'_> {
        #[cfg(target_os = "linux")]
        let _ = self.map.advise(memmap2::Advice::Sequential);
        WalkOnce(self)
    }

    /// Asks the kernel to map the file's pages one by one (`MADV_NOHUGEPAGE`), not in 2 MiB
    /// blocks when the page cache holds the file in large folios: for a walk that gives its
    /// pages back behind it ([`MappedFile::release`]), so that what is resident ahead of it
    /// stays a few pages. A kernel that does not know the advice leaves the map as it is.
    pub(crate) fn map_small_pages(&self) {
        #[cfg(target_os = "linux")]
        let _ = self.map.advise(memmap2::Advice::NoHugePage);
    }

    /// Drops the pages of `[from, to)` from the process (whole 64 KiB blocks only). Returns
    /// where the blocks it dropped end (`to` down to a block boundary, at least `from`):
    /// where the walk's next release starts, so that a block `to` cuts is released next
    /// time, not skipped.
    pub(crate) fn release(&self, from: u64, to: u64) -> u64 {
        // A multiple of every page size Linux uses (4, 16 and 64 KiB).
        const PAGE: u64 = 64 << 10;
        let from_page = from.div_ceil(PAGE) * PAGE;
        let to = to.min(self.map.len() as u64) / PAGE * PAGE;
        if to > from_page {
            // SAFETY: the map is shared and read-only, so MADV_DONTNEED only drops this
            // process's references to the pages: a later read faults the file's own bytes
            // back in, unchanged. (It is unsafe in general because a private writable map
            // would lose its changes.) A failure only leaves the pages resident.
            #[allow(unsafe_code)]
            let _ = unsafe {
                self.map.unchecked_advise_range(
                    memmap2::UncheckedAdvice::DontNeed,
                    from_page as usize,
                    (to - from_page) as usize,
                )
            };
        }
        to.max(from)
    }
}

impl std::ops::Deref for MappedFile {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        &self.map
    }
}

/// The map walked once ([`MappedFile::walk_once`]): the advice is taken back on drop.
#[cfg_attr(not(target_os = "linux"), allow(dead_code))]
pub(crate) struct WalkOnce<'m>(&'m MappedFile);

impl Drop for WalkOnce<'_> {
    fn drop(&mut self) {
        #[cfg(target_os = "linux")]
        let _ = self.0.map.advise(memmap2::Advice::Normal);
    }
}

/// A sink that gives pages back behind the rows it takes.
struct Releasing<'r, S> {
    inner: S,
    release: &'r (dyn Fn(u64, u64) -> u64 + Sync),
    /// Where this thread's walk released up to (`None` before its first row).
    done: Option<u64>,
}

impl<S: RowSink> RowSink for Releasing<'_, S> {
    #[inline]
    fn row(&mut self, meta: &Metadata, offset: u64, data: &[u8], sub: usize, timestamp: u64) {
        self.inner.row(meta, offset, data, sub, timestamp);
        let done = *self.done.get_or_insert(offset);
        if offset >= done + RELEASE_STEP + RELEASE_MARGIN {
            self.done = Some((self.release)(done, offset - RELEASE_MARGIN));
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

#[cfg(all(test, target_os = "linux", feature = "derive"))]
mod tests {
    use super::*;
    use crate::{ULog, Writer, WriterOptions};

    #[derive(ULog)]
    struct Sample {
        timestamp: u64,
        value: [f32; 6],
    }

    /// A log of about 20 MB in a file of its own (removed on drop).
    struct BigLog(std::path::PathBuf);

    impl BigLog {
        fn new(name: &str) -> BigLog {
            let path =
                std::env::temp_dir().join(format!("ulog-mapped-{name}-{}.ulg", std::process::id()));
            let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
            let mut w = Writer::new(file, WriterOptions::default()).unwrap();
            let topic = w.topic::<Sample>(0).unwrap();
            for t in 0..560_000u64 {
                let s = Sample {
                    timestamp: t,
                    value: [t as f32; 6],
                };
                w.write(&topic, &s).unwrap();
            }
            w.into_inner().into_inner().unwrap().sync_all().unwrap();
            BigLog(path)
        }
    }

    impl Drop for BigLog {
        fn drop(&mut self) {
            let _ = std::fs::remove_file(&self.0);
        }
    }

    /// The entry of `/proc/self/smaps` for the map at `base`, up to the end of the file.
    fn smaps_entry(base: u64) -> String {
        let smaps = std::fs::read_to_string("/proc/self/smaps").unwrap();
        let start = format!("{base:x}-");
        smaps
            .split_once(&format!("\n{start}"))
            .expect("the map is listed")
            .1
            .to_owned()
    }

    /// The kernel's flags of the map at `base` (`VmFlags:` of `/proc/self/smaps`).
    fn vm_flags(base: u64) -> Vec<String> {
        smaps_entry(base)
            .lines()
            .find_map(|l| l.strip_prefix("VmFlags:"))
            .expect("flags")
            .split_whitespace()
            .map(str::to_owned)
            .collect()
    }

    /// The kernel's page size for the map at `base`, from `/proc/self/smaps`.
    fn page_size(base: u64) -> u64 {
        let entry = smaps_entry(base);
        let kb = entry
            .lines()
            .find_map(|l| l.strip_prefix("KernelPageSize:"))
            .expect("a page size")
            .trim()
            .trim_end_matches(" kB")
            .parse::<u64>()
            .unwrap();
        kb << 10
    }

    /// Offsets of the pages of `bytes` this process has mapped in (`/proc/self/pagemap`:
    /// bit 63 of a page's entry says it is present).
    fn resident_pages(bytes: &[u8]) -> Vec<u64> {
        use std::io::{Read, Seek, SeekFrom};
        let base = bytes.as_ptr() as u64;
        let page = page_size(base);
        let pages = (bytes.len() as u64).div_ceil(page);
        let mut map = std::fs::File::open("/proc/self/pagemap").unwrap();
        map.seek(SeekFrom::Start(base / page * 8)).unwrap();
        let mut entries = vec![0u8; pages as usize * 8];
        map.read_exact(&mut entries).unwrap();
        entries
            .chunks_exact(8)
            .enumerate()
            .filter(|(_, e)| u64::from_le_bytes((*e).try_into().unwrap()) >> 63 == 1)
            .map(|(i, _)| i as u64 * page)
            .collect()
    }

    /// After a walk, the pages still mapped are in the walk's last step (`tail` bytes) or
    /// in the first 64 KiB block, which holds the header and definitions: none is left
    /// behind in the middle of the file.
    fn only_the_tail_is_resident(file: &MappedFile, tail: u64, what: &str) {
        let len = file.len() as u64;
        let behind: Vec<u64> = resident_pages(file)
            .into_iter()
            .filter(|&p| p >= 64 << 10 && p + tail < len)
            .collect();
        assert!(
            behind.is_empty(),
            "{what}: {} pages behind the walk stayed mapped, the first at {:?} of {len}",
            behind.len(),
            behind.first()
        );
    }

    #[test]
    fn a_folder_is_not_mapped() {
        let e = MappedFile::open(std::env::temp_dir()).unwrap_err();
        let ReadError::Io(e) = e else { panic!("{e:?}") };
        assert_eq!(e.kind(), std::io::ErrorKind::IsADirectory);
        assert_eq!(e.to_string(), "is a folder, not a log file");
    }

    #[test]
    fn a_mapped_walk_gives_back_every_page_behind_it() {
        let log = BigLog::new("fold");
        let file = MappedFile::open(&log.0).unwrap();
        let (summary, counts) = file.fold_rows_on(1, || 0u64, |n, _| *n += 1).unwrap();
        assert_eq!(counts.iter().sum::<u64>(), 560_000);
        assert_eq!(summary.rows, 560_000);
        // The last step and margin, a release block, and what the kernel maps around a
        // fault (64 KiB by default).
        only_the_tail_is_resident(
            &file,
            RELEASE_STEP + RELEASE_MARGIN + (128 << 10),
            "fold_rows",
        );
    }

    /// The walk tells the kernel it reads each page once (`sr`: `MADV_SEQUENTIAL`) while it
    /// walks, and takes the advice back after, for the map's later uses; an advice given
    /// before (small pages, `nh`) stays.
    #[test]
    fn a_mapped_walk_is_sequential_while_it_walks_only() {
        let log = BigLog::new("advice");
        let file = MappedFile::open(&log.0).unwrap();
        let base = file.as_ptr() as u64;
        file.map_small_pages();
        assert!(!vm_flags(base).contains(&"sr".to_owned()));
        assert!(vm_flags(base).contains(&"nh".to_owned()));
        let (_, seen) = file
            .fold_rows_on(
                2,
                || None,
                |flags: &mut Option<Vec<String>>, _| {
                    flags.get_or_insert_with(|| vm_flags(base));
                },
            )
            .unwrap();
        assert!(seen.iter().flatten().count() >= 1, "no part looked");
        for flags in seen.iter().flatten() {
            assert!(flags.contains(&"sr".to_owned()), "{flags:?}");
        }
        assert!(!vm_flags(base).contains(&"sr".to_owned()));
        assert!(vm_flags(base).contains(&"nh".to_owned()));
    }

    #[test]
    fn pyulogs_reading_of_a_mapped_file_gives_back_every_page_behind_it() {
        let log = BigLog::new("pyulog");
        let file = MappedFile::open(&log.0).unwrap();
        let f = crate::compat::pyulog::read_mapped(&file, &Default::default()).unwrap();
        assert_eq!(f.data[0].rows.len(), 560_000 * 32);
        only_the_tail_is_resident(&file, 1 << 20, "compat::pyulog::read_mapped");
    }
}
