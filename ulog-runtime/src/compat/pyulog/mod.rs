//! A log as pyulog 1.3.0's `ULog(log_file, message_name_filter_list,
//! disable_str_exceptions, parse_header_only)` reads it: every attribute of its data model,
//! by its rules, quirks included, so that code built on it gives a pyulog script's answers.
//!
//! What pyulog does that this reproduces (this reader itself keeps more):
//! - the info key is the second word of `type key` (cut at the next space); a value of a type
//!   it cannot unpack is raw bytes; `char` a one-byte string of bytes;
//! - a row is taken only if its size is exactly the format's without its trailing padding;
//!   a row of another size, a row of a msg_id never subscribed, a format that cannot be
//!   resolved, mark the file corrupt and are left out;
//! - an `I`, `P`, `O`, `L`, `C` or `A` too short for what it holds, or a row whose
//!   timestamp (read as 8 bytes where the first field named `timestamp` starts) lies past
//!   its end, ends the data section there, silently;
//! - a message of an unknown type is skipped, and the sync bytes looked for in it; an
//!   impossible header (type 0, size 0 or above 10,000) moves on by one byte and looks for
//!   the next sync sequence in the rest of the file;
//! - a re-subscription of a msg_id replaces the subscription and drops its rows; a segment
//!   of appended data starts with no subscription; datasets are made per segment, the last
//!   subscribed first, then sorted by name and instance;
//! - `last_timestamp` is the largest row timestamp, a dropout's timestamp the largest seen
//!   when it was read, a changed parameter's too;
//! - text is UTF-8 with invalid bytes left out, or an error ([`PyulogError::Unicode`]) when
//!   strings are strict.
//!
//! Where pyulog would not finish (a header whose size leads its recovery backwards forever,
//! a format nesting itself, a format of millions of fields), this stops with the file
//! marked corrupt, or an error pyulog would raise ([`PyulogError::Recursion`]).

use std::collections::HashSet;

/// Which topics' rows are kept (pyulog's `message_name_filter_list`).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum NameFilter {
    /// Every topic (`None`).
    #[default]
    All,
    /// Topics named in the list.
    Names(Vec<String>),
    /// Topics whose name is part of this text (pyulog given a `str`: `name in text`).
    Substring(String),
}

impl NameFilter {
    fn keeps(&self, name: &str) -> bool {
        match self {
            NameFilter::All => true,
            NameFilter::Names(names) => names.iter().any(|n| n == name),
            NameFilter::Substring(text) => text.contains(name),
        }
    }
}

/// How to read.
#[derive(Debug, Clone, Default)]
pub struct PyulogOptions {
    /// The topics kept.
    pub filter: NameFilter,
    /// Strings must be UTF-8 (pyulog's `disable_str_exceptions=False`).
    pub strict_strings: bool,
    /// Only the header and the definitions (`parse_header_only`).
    pub header_only: bool,
    /// Where in the file (or stream) the bytes start: pyulog's positions are absolute.
    pub base_offset: u64,
}

/// A value as pyulog's `struct.unpack` or `parse_string` gives it.
#[derive(Debug, Clone, PartialEq)]
pub enum PyValue {
    /// A signed integer type.
    Int(i64),
    /// An unsigned integer type.
    UInt(u64),
    /// `float` (widened) or `double`.
    Float(f64),
    /// `bool`.
    Bool(bool),
    /// `char[N]`.
    Str(String),
    /// A scalar `char` (one byte) or a type pyulog does not unpack (raw bytes).
    Bytes(Vec<u8>),
}

/// A logged string (`L`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Logged {
    /// The level byte as written (`b'6'` is 54).
    pub level: u8,
    /// µs.
    pub timestamp: u64,
    /// The text.
    pub message: String,
}

/// A tagged logged string (`C`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tagged {
    /// The level byte.
    pub level: u8,
    /// The tag.
    pub tag: u16,
    /// µs.
    pub timestamp: u64,
    /// The text.
    pub message: String,
}

/// A format as pyulog keeps it: its fields as (type, array size or 0, name).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Format {
    /// The name before `:`.
    pub name: String,
    /// The fields.
    pub fields: Vec<(String, u32, String)>,
}

/// One of pyulog's `Data`: a subscription's rows.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Dataset {
    /// The topic.
    pub name: String,
    /// The instance.
    pub multi_id: u8,
    /// The msg_id.
    pub msg_id: u16,
    /// The flattened fields: (name, type), trailing padding removed.
    pub fields: Vec<(String, String)>,
    /// The index of the field named `timestamp`, or -1.
    pub timestamp_idx: i64,
    /// The rows, packed, each [`Dataset::row_size`] bytes.
    pub rows: Vec<u8>,
    /// Bytes a row.
    pub row_size: usize,
}

/// Everything pyulog's `ULog` holds after reading (its private attributes by name).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PyulogFile {
    /// `_file_corrupt`.
    pub file_corrupt: bool,
    /// `_start_timestamp`.
    pub start_timestamp: u64,
    /// `_last_timestamp`.
    pub last_timestamp: u64,
    /// `_msg_info_dict` and its types: (key, type, value) in the dict's order.
    pub info: Vec<(String, String, PyValue)>,
    /// `_msg_info_multiple_dict` and its types (the first message's).
    pub info_multiple: Vec<(String, String, Vec<Vec<PyValue>>)>,
    /// `_initial_parameters`, in the dict's order.
    pub initial_parameters: Vec<(String, PyValue)>,
    /// `_default_parameters`: per key (pyulog's: a bit's value less one), the dict's items.
    pub default_parameters: Vec<(u8, Vec<(String, PyValue)>)>,
    /// `_changed_parameters`: (timestamp, name, value).
    pub changed_parameters: Vec<(u64, String, PyValue)>,
    /// `_message_formats`, in the dict's order.
    pub formats: Vec<Format>,
    /// `_logged_messages`.
    pub logged: Vec<Logged>,
    /// `_logged_messages_tagged`: per tag in order of first appearance.
    pub tagged: Vec<(u16, Vec<Tagged>)>,
    /// `_dropouts`: (duration ms, timestamp).
    pub dropouts: Vec<(u16, u64)>,
    /// `_data_list`.
    pub data: Vec<Dataset>,
    /// `_filtered_message_ids`.
    pub filtered_ids: Vec<u16>,
    /// `_missing_message_ids`.
    pub missing_ids: Vec<u16>,
    /// `_file_version`.
    pub file_version: u8,
    /// `_compat_flags`.
    pub compat_flags: [u8; 8],
    /// `_incompat_flags`.
    pub incompat_flags: [u8; 8],
    /// `_appended_offsets`.
    pub appended_offsets: Vec<u64>,
    /// `_has_sync`.
    pub has_sync: bool,
    /// `_sync_seq_cnt`.
    pub sync_seq_cnt: u64,
    /// What pyulog prints on stdout while reading, line by line.
    pub printed: Vec<String>,
    /// Where pyulog stopped reading data before the end: the file offset of the first whole
    /// message of a data section whose parsing raised `struct.error` (a row whose format
    /// has no `timestamp` field, or a field that makes its offset run past the row; a
    /// logged string shorter than its header). pyulog takes that error for the end of the
    /// file, silently (`file_corruption` stays false), so the rows after it are missing
    /// from its datasets (and the rows of a topic a name filter leaves out are never
    /// parsed, so a filtered read can hold more). `None` when every data section was read
    /// to its end. (Not one of pyulog's attributes: this reader's note of what it left out.)
    pub stopped_at: Option<u64>,
}

/// Why pyulog's constructor raises.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum PyulogError {
    /// `ULogException` with this message.
    #[error("{0}")]
    Header(&'static str),
    /// `ULogIncompatibleFlagException`.
    #[error("Unknown incompatible flag set: cannot parse the log")]
    IncompatibleFlag,
    /// `UnicodeDecodeError('utf-8', bytes, start, end, reason)` (strict strings).
    #[error("'utf-8' codec can't decode byte at position {start}: {reason}")]
    Unicode {
        /// The bytes decoded.
        bytes: Vec<u8>,
        /// Where the invalid bytes start.
        start: usize,
        /// Where they end.
        end: usize,
        /// Python's reason.
        reason: &'static str,
    },
    /// `RecursionError`: a format nests itself.
    #[error("maximum recursion depth exceeded while flattening format `{0}`")]
    Recursion(String),
}

/// pyulog's message types.
const SYNC: [u8; 8] = [0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12];
const HEADER: &[u8; 7] = b"ULog\x01\x12\x35";
/// Flattened fields a subscription may have before it is taken as corrupt (pyulog would
/// run out of memory).
const MAX_FIELDS: usize = 1 << 20;
/// Nesting depth of formats beyond which pyulog's recursion fails.
const MAX_DEPTH: usize = 900;

/// A basic type's size, as `_UNPACK_TYPES` has it.
fn basic_size(t: &str) -> Option<usize> {
    Some(match t {
        "int8_t" | "uint8_t" | "bool" | "char" => 1,
        "int16_t" | "uint16_t" => 2,
        "int32_t" | "uint32_t" | "float" => 4,
        "int64_t" | "uint64_t" | "double" => 8,
        _ => return None,
    })
}

/// A Python exception that a message's parsing raises, as pyulog's handlers sort them.
#[derive(Debug)]
enum Raise {
    /// `IndexError`, `KeyError`, `ValueError`, `OverflowError`: the file is corrupt.
    Corrupt,
    /// `struct.error`: too few bytes for an unpack.
    Struct,
    /// Out of the constructor.
    Fatal(PyulogError),
}

type Step<T> = Result<T, Raise>;

/// Reads `data` as pyulog does.
pub fn read(data: &[u8], options: &PyulogOptions) -> Result<PyulogFile, PyulogError> {
    read_releasing(data, options, None)
}

/// [`read`] of a memory-mapped file, its pages given back to the kernel behind the reading
/// (so that the process holds the rows, not the file and the rows). The map is from then on
/// mapped in small pages, never 2 MiB blocks (`MADV_NOHUGEPAGE`), so that little of the file
/// is resident ahead of the reading; while it is read, the kernel is told that the reading
/// touches each page once (`MADV_SEQUENTIAL`).
#[cfg(feature = "mmap")]
pub fn read_mapped(
    file: &crate::read::MappedFile,
    options: &PyulogOptions,
) -> Result<PyulogFile, PyulogError> {
    file.map_small_pages();
    let _once = file.walk_once();
    let release = |from: u64, to: u64| file.release(from, to);
    read_releasing(file, options, Some(&release))
}

/// What a dataset's rows get room for at its first row (at most what is left of the file).
const INITIAL_ROWS_BYTES: usize = 1 << 20;

/// Bytes behind the reading that are given back at once, and how far behind it. (What is
/// given back is never needed again but for a seek back to an appended segment's offset
/// within the last message, which reads the page again from the file: small steps keep
/// the file's share of the peak memory small, at one `madvise` per step.)
const RELEASE_STEP: usize = 256 << 10;
const RELEASE_MARGIN: usize = 16 << 10;

fn read_releasing(
    data: &[u8],
    options: &PyulogOptions,
    release: Option<&dyn Fn(u64, u64) -> u64>,
) -> Result<PyulogFile, PyulogError> {
    let mut r = Reader {
        data,
        pos: 0,
        release,
        released: 0,
        options,
        f: PyulogFile {
            has_sync: true,
            ..PyulogFile::default()
        },
        subscriptions: Vec::new(),
        by_msg_id: vec![0; 1 << 16],
        filtered: HashSet::new(),
        missing: HashSet::new(),
        seeks_back: Vec::new(),
    };
    r.header()?;
    r.f.last_timestamp = r.f.start_timestamp;
    r.definitions()?;
    if !options.header_only {
        let appended = r.f.incompat_flags[0] & 1 != 0 && !r.f.appended_offsets.is_empty();
        if appended {
            for offset in r.f.appended_offsets.clone() {
                r.data_section(Some(offset))?;
                // A seek to an offset before the bytes (or absurd) fails: corrupt.
                match offset.checked_sub(options.base_offset) {
                    Some(p) if offset < (1 << 63) => {
                        r.pos = usize::try_from(p).unwrap_or(usize::MAX)
                    }
                    _ => {
                        r.f.file_corrupt = true;
                        break;
                    }
                }
            }
        }
        r.data_section(None)?;
    }
    let mut f = r.f;
    f.filtered_ids = r.filtered.into_iter().collect();
    f.filtered_ids.sort_unstable();
    f.missing_ids = r.missing.into_iter().collect();
    f.missing_ids.sort_unstable();
    Ok(f)
}

/// A subscription being filled.
struct Sub {
    msg_id: u16,
    name: String,
    multi_id: u8,
    fields: Vec<(String, String)>,
    timestamp_idx: i64,
    row_size: usize,
    timestamp_offset: usize,
    rows: Vec<u8>,
}

struct Reader<'a> {
    data: &'a [u8],
    /// The file position, relative to the bytes' start (may be past their end).
    pos: usize,
    /// Gives back the pages of a range of `data` (a mapped file's), and up to where it has.
    release: Option<&'a dyn Fn(u64, u64) -> u64>,
    released: usize,
    options: &'a PyulogOptions,
    f: PyulogFile,
    /// `_subscriptions`, in insertion order (a replaced key keeps its place).
    subscriptions: Vec<Sub>,
    /// Per msg_id: its index in `subscriptions` + 1, or 0.
    by_msg_id: Vec<u32>,
    filtered: HashSet<u16>,
    missing: HashSet<u16>,
    /// Where the definitions section went back to after a short read ([`Reader::after_corrupt_definition`]).
    seeks_back: Vec<usize>,
}

impl<'a> Reader<'a> {
    /// `file.read(n)`: up to `n` bytes from the position, which advances by what was read.
    fn read(&mut self, n: usize) -> &'a [u8] {
        let data = self.data;
        if self.pos >= data.len() {
            return &[];
        }
        let end = self.pos.saturating_add(n).min(data.len());
        let out = &data[self.pos..end];
        self.pos = end;
        out
    }

    fn absolute(&self) -> u64 {
        self.options.base_offset + self.pos as u64
    }

    fn string(&self, bytes: &[u8]) -> Step<String> {
        parse_string(bytes, self.options.strict_strings).map_err(Raise::Fatal)
    }

    fn header(&mut self) -> Result<(), PyulogError> {
        let h = self.read(16);
        if h.len() != 16 {
            return Err(PyulogError::Header(
                "Invalid file format (Header too short)",
            ));
        }
        if &h[..7] != HEADER {
            return Err(PyulogError::Header(
                "Invalid file format (Failed to parse header)",
            ));
        }
        self.f.file_version = h[7];
        if h[7] > 1 {
            self.print("Warning: unknown file version. Will attempt to read it anyway");
        }
        self.f.start_timestamp = u64::from_le_bytes(h[8..16].try_into().expect("8 bytes"));
        Ok(())
    }

    fn print(&mut self, line: impl Into<String>) {
        self.f.printed.push_shared(line.into());
    }

    fn definitions(&mut self) -> Result<(), PyulogError> {
        loop {
            let start = self.pos;
            let head = self.read(3);
            if head.is_empty() {
                return Ok(());
            }
            match self.definition(start, head) {
                Ok(true) => return Ok(()),
                Ok(false) => {}
                Err(Raise::Fatal(e)) => return Err(e),
                Err(Raise::Corrupt | Raise::Struct) => {
                    if !self.f.file_corrupt {
                        self.print("File corruption detected while reading file definitions!");
                        self.f.file_corrupt = true;
                    }
                }
            }
        }
    }

    /// One message of the definitions section; whether the section ends there.
    fn definition(&mut self, start: usize, head: &[u8]) -> Step<bool> {
        if head.len() < 3 {
            return Err(Raise::Struct);
        }
        let size = usize::from(u16::from_le_bytes([head[0], head[1]]));
        let ty = head[2];
        let body = self.read(size);
        match ty {
            b'I' => {
                let (ty, key, value) = self.info(body)?;
                set(&mut self.f.info, key, (ty, value));
            }
            b'M' => self.info_multiple(body)?,
            b'F' => {
                let format = self.format(body)?;
                let name = format.name.clone();
                match self.f.formats.iter_mut().find(|f| f.name == name) {
                    Some(f) => *f = format,
                    None => self.f.formats.push_shared(format),
                }
            }
            b'P' => {
                let (_, key, value) = self.info(body)?;
                set1(&mut self.f.initial_parameters, key, value);
            }
            b'Q' => self.default_parameter(body)?,
            b'A' | b'L' | b'C' => {
                // pyulog seeks back by the size it asked for and 3: to this message, but
                // after a short read at the end of the file to before it, where the data
                // section then starts (this message if that is before the log's start).
                self.pos = self
                    .pos
                    .checked_sub(size + 3)
                    .map_or(start, |to| to.min(start));
                return Ok(true);
            }
            b'B' => {
                if self.absolute() != 16 + 3 + size as u64 {
                    let at = self.absolute();
                    self.print(format!(
                        "Error: FLAGS_BITS message must be first message. Offset: {at}"
                    ));
                }
                if size > 8 + 8 + 3 * 8 {
                    self.print("Warning: Flags Bit message is longer than expected");
                }
                if body.len() < 16 + 24 {
                    return Err(Raise::Struct);
                }
                self.f.compat_flags.copy_from_slice(&body[..8]);
                self.f.incompat_flags.copy_from_slice(&body[8..16]);
                let mut offsets: Vec<u64> = (0..3)
                    .map(|i| {
                        u64::from_le_bytes(body[16 + 8 * i..24 + 8 * i].try_into().expect("8"))
                    })
                    .collect();
                while offsets.last() == Some(&0) {
                    offsets.pop();
                }
                self.f.appended_offsets = offsets;
                if self.f.incompat_flags[0] & !1 != 0
                    || self.f.incompat_flags[1..].iter().any(|&b| b != 0)
                {
                    return Err(Raise::Fatal(PyulogError::IncompatibleFlag));
                }
            }
            _ => {
                if ty == 0 || size == 0 || size > 10000 {
                    self.f.file_corrupt = true;
                    self.pos = self.after_corrupt_definition(start, size);
                }
            }
        }
        Ok(false)
    }

    /// Where pyulog reads on after a corrupt header in the definitions section: it seeks
    /// back by the size it asked for and 2, which is the next byte after a whole message,
    /// but before this message after a short read at the end of the file (it reads messages
    /// again from there, as the bytes fall). Where that would read the same bytes again
    /// forever (pyulog never returns), would seek before the log's first byte (pyulog
    /// raises `OSError` for a path and loops for a file object), or after many such seeks
    /// (bounding the work), on from the next byte instead.
    fn after_corrupt_definition(&mut self, start: usize, size: usize) -> usize {
        const MOST_SEEKS_BACK: usize = 64;
        let back = (self.pos + 1).checked_sub(size + 3);
        match back {
            Some(to) if to > start => start + 1,
            Some(to)
                if self.seeks_back.len() < MOST_SEEKS_BACK && !self.seeks_back.contains(&to) =>
            {
                self.seeks_back.push_shared(to);
                to
            }
            _ => start + 1,
        }
    }

    /// `_MessageInfo`: (type, key, value).
    fn info(&self, data: &[u8]) -> Step<(String, String, PyValue)> {
        let key_len = usize::from(*data.first().ok_or(Raise::Struct)?);
        let type_key = self.string(slice(data, 1, 1 + key_len))?;
        let mut split = type_key.split(' ');
        let ty = split.next().unwrap_or_default().to_owned();
        let key = split.next().ok_or(Raise::Corrupt)?.to_owned();
        let raw = slice(data, 1 + key_len, data.len());
        let value = if ty.starts_with("char[") {
            PyValue::Str(self.string(raw)?)
        } else if let Some(size) = basic_size(&ty) {
            if raw.len() != size {
                return Err(Raise::Struct);
            }
            unpack(&ty, raw)
        } else {
            PyValue::Bytes(raw.to_vec())
        };
        Ok((ty, key, value))
    }

    fn info_multiple(&mut self, data: &[u8]) -> Step<()> {
        let continued = *data.first().ok_or(Raise::Struct)? != 0;
        let (ty, key, value) = self.info(&data[1..])?;
        match self.f.info_multiple.iter_mut().find(|m| m.0 == key) {
            Some(m) => {
                if continued {
                    m.2.last_mut().expect("never empty").push_shared(value);
                } else {
                    m.2.push_shared(vec![value]);
                }
            }
            None => self
                .f
                .info_multiple
                .push_shared((key, ty, vec![vec![value]])),
        }
        Ok(())
    }

    fn default_parameter(&mut self, data: &[u8]) -> Step<()> {
        let mut bits = *data.first().ok_or(Raise::Struct)?;
        let (_, key, value) = self.info(&data[1..])?;
        while bits != 0 {
            // pyulog's key: the lowest set bit's value less one (bits 0, 1, 2 give 0, 1, 3).
            let key_of_bit = (bits & bits.wrapping_neg()) - 1;
            bits &= bits - 1;
            let k = match self
                .f
                .default_parameters
                .iter()
                .position(|d| d.0 == key_of_bit)
            {
                Some(k) => k,
                None => {
                    self.f
                        .default_parameters
                        .push_shared((key_of_bit, Vec::new()));
                    self.f.default_parameters.len() - 1
                }
            };
            set1(
                &mut self.f.default_parameters[k].1,
                key.clone(),
                value.clone(),
            );
        }
        Ok(())
    }

    fn format(&self, data: &[u8]) -> Step<Format> {
        let text = self.string(data)?;
        let mut parts = text.split(':');
        let name = parts.next().unwrap_or_default().to_owned();
        let body = parts.next().ok_or(Raise::Corrupt)?;
        let mut fields = Vec::new();
        for t in body.split(';').filter(|t| !t.is_empty()) {
            let mut split = t.split(' ');
            let type_str = split.next().unwrap_or_default();
            let field = split.next().ok_or(Raise::Corrupt)?.to_owned();
            match type_str.find('[') {
                None => fields.push_shared((type_str.to_owned(), 0, field)),
                Some(a) => {
                    // Python's `type_str[a+1:b]`, `b` -1 when there is no `]`: before the
                    // last character (not byte: the text may hold any character).
                    let last_char = type_str.char_indices().last().map_or(0, |(i, _)| i);
                    let b = type_str
                        .find(']')
                        .map_or(last_char as isize, |b| b as isize);
                    let inner = if (a as isize + 1) < b {
                        &type_str[a + 1..b as usize]
                    } else {
                        ""
                    };
                    let n = crate::pytext::python_int(inner).ok_or(Raise::Corrupt)?;
                    if !(0..=0xFFFF).contains(&n) {
                        return Err(Raise::Corrupt);
                    }
                    fields.push_shared((type_str[..a].to_owned(), n as u32, field));
                }
            }
        }
        Ok(Format { name, fields })
    }

    fn data_section(&mut self, until: Option<u64>) -> Result<(), PyulogError> {
        let until = until.unwrap_or(1 << 50);
        let mut curr = self.absolute();
        loop {
            let start = self.pos;
            if let Some(release) = self.release
                && start >= self.released + RELEASE_STEP + RELEASE_MARGIN
            {
                let to = release(self.released as u64, (start - RELEASE_MARGIN) as u64);
                self.released = usize::try_from(to).unwrap_or(start);
            }
            let head = self.read(3);
            curr += head.len() as u64;
            if head.len() < 3 {
                break;
            }
            let size = usize::from(u16::from_le_bytes([head[0], head[1]]));
            let ty = head[2];
            let body = self.read(size);
            curr += body.len() as u64;
            if body.len() < size {
                break;
            }
            if curr > until {
                break;
            }
            match self.data_message(start, ty, body, &mut curr) {
                Ok(()) => {}
                Err(Raise::Fatal(e)) => return Err(e),
                Err(Raise::Struct) => {
                    let at = self.options.base_offset + start as u64;
                    self.f.stopped_at.get_or_insert(at);
                    break;
                }
                Err(Raise::Corrupt) => {
                    if !self.f.file_corrupt {
                        self.print("File corruption detected while reading file data!");
                        self.f.file_corrupt = true;
                    }
                }
            }
        }
        // Each subscription with rows is a dataset, the last subscribed first; then all
        // datasets by name and instance (a stable sort).
        for s in &self.subscriptions {
            self.by_msg_id[usize::from(s.msg_id)] = 0;
        }
        while let Some(s) = self.subscriptions.pop() {
            if !s.rows.is_empty() {
                self.f.data.push_shared(Dataset {
                    name: s.name,
                    multi_id: s.multi_id,
                    msg_id: s.msg_id,
                    fields: s.fields,
                    timestamp_idx: s.timestamp_idx,
                    rows: s.rows,
                    row_size: s.row_size,
                });
            }
        }
        self.f
            .data
            .sort_by(|a, b| (&a.name, a.multi_id).cmp(&(&b.name, b.multi_id)));
        Ok(())
    }

    fn data_message(&mut self, start: usize, ty: u8, body: &[u8], curr: &mut u64) -> Step<()> {
        match ty {
            b'D' => self.row(body)?,
            b'I' => {
                let (ty, key, value) = self.info(body)?;
                set(&mut self.f.info, key, (ty, value));
            }
            b'M' => self.info_multiple(body)?,
            b'P' => {
                let (_, key, value) = self.info(body)?;
                self.f
                    .changed_parameters
                    .push_shared((self.f.last_timestamp, key, value));
            }
            b'Q' => self.default_parameter(body)?,
            b'A' => self.subscribe(body)?,
            b'L' => {
                if body.len() < 9 {
                    return Err(Raise::Struct);
                }
                let message = self.string(&body[9..])?;
                self.f.logged.push_shared(Logged {
                    level: body[0],
                    timestamp: u64::from_le_bytes(body[1..9].try_into().expect("8")),
                    message,
                });
            }
            b'C' => {
                if body.len() < 11 {
                    return Err(Raise::Struct);
                }
                let tag = u16::from_le_bytes([body[1], body[2]]);
                let t = Tagged {
                    level: body[0],
                    tag,
                    timestamp: u64::from_le_bytes(body[3..11].try_into().expect("8")),
                    message: self.string(&body[11..])?,
                };
                match self.f.tagged.iter_mut().find(|g| g.0 == tag) {
                    Some(g) => g.1.push_shared(t),
                    None => self.f.tagged.push_shared((tag, vec![t])),
                }
            }
            b'O' => {
                if body.len() != 2 {
                    return Err(Raise::Struct);
                }
                let duration = u16::from_le_bytes([body[0], body[1]]);
                self.f
                    .dropouts
                    .push_shared((duration, self.f.last_timestamp));
            }
            b'S' => self.f.sync_seq_cnt += 1,
            _ => {
                let size = body.len();
                if ty == 0 || size == 0 || size > 10000 {
                    self.f.file_corrupt = true;
                    self.pos = start + 1;
                    *curr = self.absolute();
                    if self.f.has_sync {
                        self.find_sync(None);
                    }
                } else if self.f.has_sync {
                    self.find_sync(Some(size));
                }
            }
        }
        Ok(())
    }

    /// `_find_sync`: the position after the next sync sequence (in the `last` bytes just
    /// read, or in the rest of the file), or where it was.
    fn find_sync(&mut self, last: Option<usize>) {
        let from = match last {
            Some(n) => self.pos - n,
            None => self.pos,
        };
        let end = match last {
            Some(_) => self.pos.min(self.data.len()),
            None => self.data.len(),
        };
        let found = (from < end && end - from >= SYNC.len())
            .then(|| {
                self.data[from..end]
                    .windows(SYNC.len())
                    .position(|w| w == SYNC)
            })
            .flatten();
        match found {
            Some(i) => {
                self.pos = from + i + SYNC.len();
                self.f.file_corrupt = true;
            }
            None => {
                if last.is_none() {
                    self.f.has_sync = false;
                }
            }
        }
    }

    fn subscribe(&mut self, data: &[u8]) -> Step<()> {
        if data.len() < 3 {
            return Err(Raise::Struct);
        }
        let multi_id = data[0];
        let msg_id = u16::from_le_bytes([data[1], data[2]]);
        let name = self.string(&data[3..])?;
        let (fields, timestamp_idx) = fields_of(&self.f.formats, &name)?;
        // numpy refuses two fields of one name.
        let mut names = HashSet::with_capacity(fields.len());
        if !fields.iter().all(|f| names.insert(f.0.as_str())) {
            return Err(Raise::Corrupt);
        }
        let size = |f: &(String, String)| basic_size(&f.1).expect("basic");
        let timestamp_offset = fields
            .iter()
            .take_while(|f| f.0 != "timestamp")
            .map(size)
            .sum();
        let row_size = fields.iter().map(size).sum();
        if self.options.filter.keeps(&name) {
            let sub = Sub {
                msg_id,
                name,
                multi_id,
                fields,
                timestamp_idx,
                row_size,
                timestamp_offset,
                rows: Vec::new(),
            };
            match self.by_msg_id[usize::from(msg_id)] {
                0 => {
                    self.subscriptions.push_shared(sub);
                    self.by_msg_id[usize::from(msg_id)] = self.subscriptions.len() as u32;
                }
                i => self.subscriptions[i as usize - 1] = sub,
            }
        } else {
            self.filtered.insert(msg_id);
        }
        Ok(())
    }

    #[inline]
    fn row(&mut self, body: &[u8]) -> Step<()> {
        if body.len() < 2 {
            return Err(Raise::Struct);
        }
        let msg_id = u16::from_le_bytes([body[0], body[1]]);
        let i = self.by_msg_id[usize::from(msg_id)];
        let Some(sub) = i
            .checked_sub(1)
            .map(|i| &mut self.subscriptions[i as usize])
        else {
            if !self.filtered.contains(&msg_id) {
                if self.missing.insert(msg_id) {
                    self.f.printed.push_shared(format!(
                        "Warning: no subscription found for message id {msg_id}. Continuing, \
                         but file is most likely corrupt"
                    ));
                }
                self.f.file_corrupt = true;
            }
            return Ok(());
        };
        let row = &body[2..];
        if row.len() != sub.row_size {
            self.f.file_corrupt = true;
            return Ok(());
        }
        if sub.rows.capacity() == 0 {
            // At its first row, room for a MiB of rows (or what is left of the file): a
            // block of that size is mapped apart and grows in place, so growing leaves no
            // copies behind (a page is resident only once a row is in it).
            let left = self.data.len().saturating_sub(self.pos);
            sub.rows.reserve(left.min(INITIAL_ROWS_BYTES));
        }
        sub.rows.extend_from_slice(row);
        let t = row
            .get(sub.timestamp_offset..sub.timestamp_offset + 8)
            .ok_or(Raise::Struct)?;
        let t = u64::from_le_bytes(t.try_into().expect("8"));
        if t > self.f.last_timestamp {
            self.f.last_timestamp = t;
        }
        Ok(())
    }
}

/// The flattened fields of a topic (trailing padding removed) and the index of
/// `timestamp` (-1 if none), as pyulog's `_MessageAddLogged` makes them.
fn fields_of(formats: &[Format], name: &str) -> Step<(Vec<(String, String)>, i64)> {
    let mut fields = Vec::new();
    let mut timestamp_idx = -1;
    flatten(formats, "", name, &mut fields, &mut timestamp_idx, 0)?;
    while fields
        .last()
        .is_some_and(|f: &(String, String)| f.0.starts_with("_padding"))
    {
        fields.pop();
    }
    Ok((fields, timestamp_idx))
}

fn flatten(
    formats: &[Format],
    prefix: &str,
    type_name: &str,
    out: &mut Vec<(String, String)>,
    timestamp_idx: &mut i64,
    depth: usize,
) -> Step<()> {
    if depth > MAX_DEPTH {
        return Err(Raise::Fatal(PyulogError::Recursion(type_name.to_owned())));
    }
    let format = formats
        .iter()
        .find(|f| f.name == type_name)
        .ok_or(Raise::Corrupt)?;
    for (ty, n, field) in &format.fields {
        if out.len() > MAX_FIELDS {
            return Err(Raise::Corrupt);
        }
        if basic_size(ty).is_some() {
            if *n > 0 {
                for i in 0..*n {
                    out.push_shared((format!("{prefix}{field}[{i}]"), ty.clone()));
                }
            } else {
                out.push_shared((format!("{prefix}{field}"), ty.clone()));
            }
            if prefix.is_empty() && field == "timestamp" {
                *timestamp_idx = out.len() as i64 - 1;
            }
        } else if *n > 0 {
            for i in 0..*n {
                let p = format!("{prefix}{field}[{i}].");
                flatten(formats, &p, ty, out, timestamp_idx, depth + 1)?;
            }
        } else {
            flatten(
                formats,
                &format!("{prefix}{field}."),
                ty,
                out,
                timestamp_idx,
                depth + 1,
            )?;
        }
    }
    Ok(())
}

/// The datasets pyulog would make, of every row this reader recovers of `log` (the same
/// file `file` was read from): one per subscription with rows whose topic `filter` keeps,
/// in pyulog's fields and order (by name and instance, the last subscribed first), each
/// row its first bytes as pyulog's fields lay them out (rows too short left out).
pub fn recovered_datasets(
    log: &crate::Log<'_>,
    file: &PyulogFile,
    filter: &NameFilter,
) -> Vec<Dataset> {
    let mut out = Vec::new();
    for sub in log.subscriptions().iter().rev() {
        if !filter.keeps(&sub.name) {
            continue;
        }
        let Ok((fields, timestamp_idx)) = fields_of(&file.formats, &sub.name) else {
            continue;
        };
        let row_size: usize = fields.iter().map(|f| basic_size(&f.1).unwrap_or(0)).sum();
        let mut rows = Vec::new();
        for row in log.rows(sub) {
            if let Some(r) = row.data.get(..row_size) {
                rows.extend_from_slice(r);
            }
        }
        if rows.is_empty() {
            continue;
        }
        out.push_shared(Dataset {
            name: sub.name.clone(),
            multi_id: sub.multi_id,
            msg_id: sub.msg_id,
            fields,
            timestamp_idx,
            rows,
            row_size,
        });
    }
    out.sort_by(|a, b| (&a.name, a.multi_id).cmp(&(&b.name, b.multi_id)));
    out
}

/// `data[a:b]` as Python slices it.
fn slice(data: &[u8], a: usize, b: usize) -> &[u8] {
    let a = a.min(data.len());
    &data[a..b.clamp(a, data.len())]
}

/// `Vec::push` growing the vector through `Vec::reserve`. Every element type has its own
/// copy of `push`'s growth code, which the linker places beside that type's other code,
/// all over a program as large as the Python module; `reserve`'s growth is one function for
/// every type, which the rows already run. A read growing its lists this way touches fewer
/// pages of the module's code, each of which the kernel maps with the pages around it:
/// `ulog.ULog`'s peak memory is that much smaller (the README's Python section).
trait PushShared<T> {
    fn push_shared(&mut self, value: T);
}

impl<T> PushShared<T> for Vec<T> {
    #[inline]
    fn push_shared(&mut self, value: T) {
        self.reserve(1);
        self.push(value);
    }
}

/// Sets a dict entry (a key keeps its first place).
fn set(dict: &mut Vec<(String, String, PyValue)>, key: String, (ty, value): (String, PyValue)) {
    match dict.iter_mut().find(|e| e.0 == key) {
        Some(e) => {
            e.1 = ty;
            e.2 = value;
        }
        None => dict.push_shared((key, ty, value)),
    }
}

fn set1(dict: &mut Vec<(String, PyValue)>, key: String, value: PyValue) {
    match dict.iter_mut().find(|e| e.0 == key) {
        Some(e) => e.1 = value,
        None => dict.push_shared((key, value)),
    }
}

/// `struct.unpack` of a basic type of exactly its size.
fn unpack(ty: &str, b: &[u8]) -> PyValue {
    macro_rules! le {
        ($t:ty) => {
            <$t>::from_le_bytes(b.try_into().expect("sized"))
        };
    }
    match ty {
        "int8_t" => PyValue::Int(i64::from(b[0] as i8)),
        "uint8_t" => PyValue::UInt(u64::from(b[0])),
        "int16_t" => PyValue::Int(i64::from(le!(i16))),
        "uint16_t" => PyValue::UInt(u64::from(le!(u16))),
        "int32_t" => PyValue::Int(i64::from(le!(i32))),
        "uint32_t" => PyValue::UInt(u64::from(le!(u32))),
        "int64_t" => PyValue::Int(le!(i64)),
        "uint64_t" => PyValue::UInt(le!(u64)),
        "float" => PyValue::Float(f64::from(le!(f32))),
        "double" => PyValue::Float(le!(f64)),
        "bool" => PyValue::Bool(b[0] != 0),
        _ => PyValue::Bytes(b.to_vec()),
    }
}

/// pyulog's `parse_string`: UTF-8, invalid bytes left out (or an error when strict).
pub fn parse_string(bytes: &[u8], strict: bool) -> Result<String, PyulogError> {
    match std::str::from_utf8(bytes) {
        Ok(s) => Ok(s.to_owned()),
        Err(e) if strict => {
            let start = e.valid_up_to();
            let (end, reason) = match e.error_len() {
                None => (bytes.len(), "unexpected end of data"),
                Some(n) => {
                    let b = bytes[start];
                    let start_byte = matches!(b, 0xC2..=0xF4);
                    (
                        start + n,
                        if start_byte {
                            "invalid continuation byte"
                        } else {
                            "invalid start byte"
                        },
                    )
                }
            };
            Err(PyulogError::Unicode {
                bytes: bytes.to_vec(),
                start,
                end,
                reason,
            })
        }
        Err(_) => Ok(bytes.utf8_chunks().map(|c| c.valid()).collect()),
    }
}

#[cfg(test)]
mod tests;
