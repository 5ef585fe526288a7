//! One pass over every row of a file read by positioned reads (`pread`) on several threads
//! ([`fold_file`]): what the memory map's fold does ([`MappedFile::fold_rows`]), each
//! thread copying its part of the file a window at a time into a buffer of its own instead
//! of mapping the file's pages.
//!
//! [`MappedFile::fold_rows`]: super::MappedFile::fold_rows

use std::fs::File;

use super::framer::Framer;
use super::message::{FileHeader, HEADER_LEN, MESSAGE_HEADER_LEN};
use super::walk::{BOUNDARY_CHAIN, BOUNDARY_SCAN, Parts, Summary, all_cores, fold_from};
use super::window::{FileAt, POSITIONED_READS, Window, read_full_at};
use super::{ReadError, Row};

/// Walks a whole file as [`fold_rows`](super::fold_rows) does, reading it by positioned
/// reads: on all cores for a large file (up to 8), each thread reading its part in windows
/// of a few hundred kilobytes. The result is [`fold_rows`](super::fold_rows)'s on the
/// file's bytes: the same rows, the accumulators in file order; what it says of `init` and
/// `fold` holds here too (`fold` may see rows that end up in no accumulator; the
/// accumulators have each row once).
///
/// Which one-pass reader to use:
/// - this one, for a file, when the page cache's state is not known (the usual case);
/// - [`MappedFile::fold_rows`](super::MappedFile::fold_rows) for a file just written or
///   read from start to end, which the cache holds in large folios: there it costs about a
///   tenth less CPU than this one (below);
/// - [`StreamReader`](super::StreamReader) on one core for any `io::Read` (a pipe, a
///   network stream), in bounded memory: it takes about the same CPU time as this one
///   (5% less on the 400 MB log), which buys wall time with the other cores, not CPU time;
/// - [`fold_rows`](super::fold_rows) for bytes already in memory.
///
/// Against a memory map ([`MappedFile::fold_rows`](super::MappedFile::fold_rows)):
/// - The cost depends less on how the kernel holds the file in its page cache. A map pays
///   for every page it maps and gives back, which costs much more when the cache holds the
///   file in 4 KiB pages (a file read piecemeal, or a cache that has been reclaimed and
///   refilled) than in the large folios a file read from start to end sits in; a read
///   copies every byte either way, and only its lookup of the cached pages costs more with
///   small ones. On a 400 MB log, against px4-ulog's CPU time, the map's walk took 0.33
///   (large folios) to 0.46 (4 KiB pages) and this one 0.36 to 0.45 (the README's section
///   "Side by side with PX4's converter and px4-ulog", and `benches/RESULTS.md`).
/// - A file truncated by another process meanwhile ends the walk early (a message the cut
///   falls in is reported as truncated; rows already read into a window are still folded),
///   where a map's read of a page the file no longer has ends the process (`SIGBUS`).
/// - Memory: a window of a few hundred kilobytes per thread, and, before the threads start,
///   a buffer of 1.3 MB for the search of each part's first boundary, one at a time.
///
/// The file is read from its start, whatever its cursor. On Unix the cursor does not move;
/// on Windows each read moves it (`seek_read`), which does not matter to reads that each
/// give their own position; on other platforms, which have no positioned reads, the file
/// is read on one thread through its cursor. A file that is not seekable, such as a pipe,
/// is an I/O error: read it with [`StreamReader`](super::StreamReader).
///
/// ```no_run
/// use ulog_runtime::read::{fold_file, open_file};
/// let file = open_file("flight.ulg")?;
/// let (summary, counts) = fold_file(&file, || 0usize, |n, _row| *n += 1)?;
/// assert_eq!(summary.rows, counts.iter().sum::<usize>());
/// # Ok::<(), ulog_runtime::ReadError>(())
/// ```
pub fn fold_file<T, I, F>(file: &File, init: I, fold: F) -> Result<(Summary, Vec<T>), ReadError>
where
    T: Send,
    I: Fn() -> T + Sync,
    F: Fn(&mut T, &Row<'_>) + Sync,
{
    fold_file_on(all_cores(), file, init, fold)
}

/// [`fold_file`] on at most `threads` threads (1: this thread only).
pub fn fold_file_on<T, I, F>(
    threads: usize,
    file: &File,
    init: I,
    fold: F,
) -> Result<(Summary, Vec<T>), ReadError>
where
    T: Send,
    I: Fn() -> T + Sync,
    F: Fn(&mut T, &Row<'_>) + Sync,
{
    let threads = if POSITIONED_READS { threads } else { 1 };
    let mut header = [0u8; HEADER_LEN];
    let got = read_full_at(file, &mut header, 0).map_err(not_seekable)?;
    let header = FileHeader::parse(&header[..got])?;
    let parts = FileParts {
        file,
        len: file.metadata()?.len(),
    };
    let mut src = parts.part(HEADER_LEN as u64);
    fold_from(header, &mut src, &parts, threads, &init, &fold)
}

/// A read error; for a file without positions (a pipe), one that says what reads it.
fn not_seekable(e: std::io::Error) -> ReadError {
    if e.kind() == std::io::ErrorKind::NotSeekable {
        return ReadError::Io(std::io::Error::new(
            e.kind(),
            "cannot be read at positions (a pipe?): read it with StreamReader",
        ));
    }
    e.into()
}

/// A file read in parts by positioned reads.
struct FileParts<'f> {
    file: &'f File,
    /// Its length when the walk began (a part past a later end reads nothing).
    len: u64,
}

impl<'f> Parts for FileParts<'f> {
    type Part<'p>
        = Window<FileAt<'f>>
    where
        Self: 'p;
    fn len(&self) -> u64 {
        self.len
    }
    fn part(&self, from: u64) -> Window<FileAt<'f>> {
        Window::new(FileAt::new(self.file, from), from)
    }
    fn boundary(&self, framer: &Framer, from: u64) -> Result<Option<u64>, ReadError> {
        // The scan's bytes and room for the chain of messages that starts at its end.
        let span = BOUNDARY_SCAN + BOUNDARY_CHAIN * (MESSAGE_HEADER_LEN + usize::from(u16::MAX));
        let len = usize::try_from(self.len.saturating_sub(from)).map_or(span, |l| l.min(span));
        let mut w = vec![0u8; len];
        let got = read_full_at(self.file, &mut w, from)?;
        Ok(framer.find_boundary(&w[..got], from, from, BOUNDARY_SCAN, BOUNDARY_CHAIN))
    }
}

#[cfg(test)]
mod tests {
    use super::fold_file;
    use crate::ReadError;

    /// `bytes` in a file of their own (removed on drop).
    struct TempLog(std::path::PathBuf);

    impl TempLog {
        fn new(name: &str, bytes: &[u8]) -> TempLog {
            let path = std::env::temp_dir()
                .join(format!("ulog-positioned-{}-{name}.ulg", std::process::id()));
            std::fs::write(&path, bytes).unwrap();
            TempLog(path)
        }
    }

    impl Drop for TempLog {
        fn drop(&mut self) {
            let _ = std::fs::remove_file(&self.0);
        }
    }

    fn fold(bytes: &[u8], name: &str) -> Result<usize, ReadError> {
        let log = TempLog::new(name, bytes);
        let file = std::fs::File::open(&log.0)?;
        fold_file(&file, || 0usize, |n, _| *n += 1).map(|(s, _)| s.rows)
    }

    #[test]
    fn a_file_that_is_not_a_log_or_too_short_is_the_error_the_header_gives() {
        assert!(matches!(
            fold(b"PK\x03\x04 not a log at all", "zip"),
            Err(ReadError::NotULog)
        ));
        assert!(matches!(
            fold(b"ULog\x01", "short"),
            Err(ReadError::TooShort { len: 5 })
        ));
        assert!(matches!(
            fold(b"", "empty"),
            Err(ReadError::TooShort { len: 0 })
        ));
        // A header alone: a log without rows.
        let header = crate::read::FileHeader {
            version: 1,
            start_timestamp: 0,
        };
        assert_eq!(fold(&header.to_bytes(), "header").unwrap(), 0);
    }

    #[cfg(unix)]
    #[test]
    fn a_pipe_is_an_io_error_not_a_wait() {
        // A pipe has no positions to read at: the first read fails at once.
        let (reader, _writer) = std::io::pipe().unwrap();
        let file = std::fs::File::from(std::os::fd::OwnedFd::from(reader));
        let e = fold_file(&file, || (), |_, _| ()).unwrap_err();
        assert!(matches!(e, ReadError::Io(_)), "{e:?}");
        assert!(e.to_string().contains("read it with StreamReader"), "{e}");
    }
}
