//! A window of a file read a chunk at a time ([`Window`]): the bytes a walk holds when it
//! does not hold the whole file, refilled from any reader ([`StreamReader`]) or by
//! positioned reads of one file that several threads read side by side ([`FileAt`], for
//! [`fold_file`]); and [`Source`], what a walk reads through: a window, or a whole file in
//! memory.
//!
//! [`StreamReader`]: super::StreamReader
//! [`fold_file`]: super::fold_file

use std::fs::File;
use std::io::{self, Read};

use super::ReadError;

/// The least free room in the buffer before a read, which asks for all the room there is
/// (the buffer starts at four of these, 512 KiB; with 64 KiB, `scan --stream` took 30% more
/// CPU time).
#[cfg(not(fuzzing))]
const CHUNK: usize = 128 * 1024;
/// In a fuzzing build, 16 bytes: the fuzzer's small inputs cross many window edges and
/// messages outgrow the buffer.
#[cfg(fuzzing)]
const CHUNK: usize = 16;

/// Where a window's bytes come from.
pub(super) trait Input {
    /// Reads into `buf` what comes next; 0 at the end.
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize>;
    /// Skips `n` bytes; returns how many it skipped (0: the end came first).
    fn skip(&mut self, n: u64) -> io::Result<u64>;
}

/// Any reader, read in order.
pub(super) struct Reading<R>(pub(super) R);

impl<R: Read> Input for Reading<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        self.0.read(buf)
    }
    fn skip(&mut self, n: u64) -> io::Result<u64> {
        io::copy(&mut (&mut self.0).take(n), &mut io::sink())
    }
}

/// A file read from a position of its own (`pread`; `seek_read` on Windows), so that threads
/// read one file side by side.
pub(super) struct FileAt<'f> {
    file: &'f File,
    pos: u64,
}

impl<'f> FileAt<'f> {
    pub(super) fn new(file: &'f File, pos: u64) -> FileAt<'f> {
        FileAt { file, pos }
    }
}

/// Whether [`FileAt`] reads at positions of its own, so that threads can share a file.
pub(super) const POSITIONED_READS: bool = cfg!(any(unix, windows));

impl Input for FileAt<'_> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = read_at(self.file, buf, self.pos)?;
        self.pos += n as u64;
        Ok(n)
    }
    fn skip(&mut self, n: u64) -> io::Result<u64> {
        // Beyond the end, the next read says so.
        self.pos = self.pos.saturating_add(n);
        Ok(n)
    }
}

/// Reads at `pos` of `file` into `buf`: how many bytes, 0 at the end.
pub(super) fn read_at(file: &File, buf: &mut [u8], pos: u64) -> io::Result<usize> {
    #[cfg(unix)]
    {
        std::os::unix::fs::FileExt::read_at(file, buf, pos)
    }
    #[cfg(windows)]
    {
        std::os::windows::fs::FileExt::seek_read(file, buf, pos)
    }
    #[cfg(not(any(unix, windows)))]
    {
        // No positioned read: through the cursor (callers read on one thread only here,
        // see `POSITIONED_READS`).
        use std::io::Seek;
        let mut f = file;
        f.seek(io::SeekFrom::Start(pos))?;
        f.read(buf)
    }
}

/// Fills `buf` from `pos` of `file` as far as the file goes; returns how many bytes.
pub(super) fn read_full_at(file: &File, buf: &mut [u8], pos: u64) -> io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match read_at(file, &mut buf[got..], pos + got as u64) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// A window of a file: `buf[start..end]` holds the file from offset `base`; `eof` once the
/// input has nothing more. Its memory stays bounded by a few messages (a message is at most
/// 64 KiB), whatever the file size.
pub(super) struct Window<I> {
    pub(super) input: I,
    pub(super) buf: Vec<u8>,
    pub(super) start: usize,
    pub(super) end: usize,
    pub(super) base: u64,
    pub(super) eof: bool,
}

impl<I: Input> Window<I> {
    /// An empty window of `input`, whose next byte is the file's at `base`.
    pub(super) fn new(input: I, base: u64) -> Window<I> {
        Window {
            input,
            buf: vec![0; 4 * CHUNK],
            start: 0,
            end: 0,
            base,
            eof: false,
        }
    }

    /// The bytes held.
    pub(super) fn bytes(&self) -> &[u8] {
        &self.buf[self.start..self.end]
    }

    /// Drops the bytes before `keep_from` and reads more (at least one byte, or hits the end).
    pub(super) fn fill(&mut self, keep_from: u64) -> Result<(), ReadError> {
        let keep_from = keep_from.max(self.base);
        let end = self.base + (self.end - self.start) as u64;
        if keep_from >= end {
            // Skip input up to `keep_from` (a jump to an appended segment, or past a part
            // another thread read).
            let mut to_skip = keep_from - end;
            (self.start, self.end, self.base) = (0, 0, end);
            while to_skip > 0 {
                let n = self.input.skip(to_skip)?;
                if n == 0 {
                    self.eof = true;
                    return Ok(());
                }
                to_skip -= n;
                self.base += n;
            }
        } else {
            self.start += (keep_from - self.base) as usize;
            self.base = keep_from;
        }
        // Make room for a chunk: move the window to the front, or grow the buffer.
        if self.buf.len() - self.end < CHUNK {
            self.buf.copy_within(self.start..self.end, 0);
            (self.start, self.end) = (0, self.end - self.start);
            if self.buf.len() - self.end < CHUNK {
                self.buf.resize(self.end + 2 * CHUNK, 0);
            }
        }
        loop {
            match self.input.read(&mut self.buf[self.end..]) {
                Ok(0) => {
                    self.eof = true;
                    return Ok(());
                }
                Ok(n) => {
                    self.end += n;
                    // A file that grew after its end was met.
                    self.eof = false;
                    return Ok(());
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e.into()),
            }
        }
    }
}

/// What a walk reads a file through: the bytes it holds, and more on demand.
pub(super) trait Source {
    /// The bytes held, the file offset of the first, and whether they reach the file's end.
    fn window(&self) -> (&[u8], u64, bool);
    /// Drops the bytes before `keep_from` and reads more: at least one byte, or the end.
    fn refill(&mut self, keep_from: u64) -> Result<(), ReadError>;
}

/// A whole file in memory: nothing more to read.
impl Source for &[u8] {
    fn window(&self) -> (&[u8], u64, bool) {
        (self, 0, true)
    }
    fn refill(&mut self, _: u64) -> Result<(), ReadError> {
        Ok(())
    }
}

impl<I: Input> Source for Window<I> {
    fn window(&self) -> (&[u8], u64, bool) {
        (self.bytes(), self.base, self.eof)
    }
    fn refill(&mut self, keep_from: u64) -> Result<(), ReadError> {
        self.fill(keep_from)
    }
}
