//! File names from the names a log gives (topics), for exports that write a file per topic
//! (`ulog csv`, Parquet): a log's names can never write outside the output folder, never
//! collide silently, and never make a file name the system refuses.
//!
//! The mapping of a name to a file name part ([`component`]):
//! - `A-Z a-z 0-9 _ -` are kept and `/` becomes `_` (as pyulog's `ulog2csv` does, so names
//!   of the format grammar give pyulog's file names);
//! - every other byte of the name's UTF-8 (`.`, space, `%`, `\`, NUL, non-ASCII...) becomes
//!   `%XX`, its hexadecimal value: `..` is `%2E%2E`, so no name is `.` or `..` or holds a
//!   path separator;
//! - a file name longer than 255 bytes (the limit of common file systems) keeps the start of
//!   the name and ends it with `~` and 16 hexadecimal digits of a hash of the whole name.
//!
//! [`FileNames`] makes the names of one folder unique, comparing them without regard to
//! case (as macOS and Windows do): a second name that maps to a taken file name gets `~2`
//! (then `~3`...) before its extension, and the caller is told, to report it.
//!
//! Where an export goes, checked the same way by every verb and by the library's writers
//! before anything is written: [`prepare_file`] for one output file (`ulog cut`, `kml`,
//! `report`), [`prepare_folder`] for a folder of them (`ulog csv`, Parquet).

use std::collections::HashMap;
use std::io;
use std::path::Path;

/// Makes ready to write the file `path`: a folder there, or a path ending in a separator
/// (`out/`), is refused (kind `IsADirectory`: "a folder; the output is a file (give its
/// path)"), and so is a parent that is not a folder (kind `NotADirectory`); missing parent
/// folders are made.
///
/// ```
/// let e = ulog_runtime::file_names::prepare_file(&std::env::temp_dir()).unwrap_err();
/// assert_eq!(e.to_string(), "a folder; the output is a file (give its path)");
/// ```
pub fn prepare_file(path: &Path) -> io::Result<()> {
    // `out/` names a folder even where none is yet.
    let folder_named = path
        .as_os_str()
        .to_string_lossy()
        .ends_with(std::path::is_separator);
    if path.is_dir() || folder_named {
        return Err(io::Error::new(
            io::ErrorKind::IsADirectory,
            "a folder; the output is a file (give its path)",
        ));
    }
    match path.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(folder) => prepare_parent(folder),
        None => Ok(()),
    }
}

/// Makes ready the output folder `path` (made with its parents if missing): a file there
/// is refused (kind `NotADirectory`: "a file; the output is a folder (give a folder's
/// path)"), and so is a file among its parents.
///
/// ```
/// let log = std::env::temp_dir().join("prepare_folder_doc.ulg");
/// std::fs::write(&log, b"")?;
/// let e = ulog_runtime::file_names::prepare_folder(&log).unwrap_err();
/// assert_eq!(e.to_string(), "a file; the output is a folder (give a folder's path)");
/// # Ok::<(), std::io::Error>(())
/// ```
pub fn prepare_folder(path: &Path) -> io::Result<()> {
    if path.exists() && !path.is_dir() {
        return Err(io::Error::new(
            io::ErrorKind::NotADirectory,
            "a file; the output is a folder (give a folder's path)",
        ));
    }
    prepare_parent(path)
}

/// Makes `folder` and its parents, naming the first of them that is a file.
fn prepare_parent(folder: &Path) -> io::Result<()> {
    if let Some(file) = folder.ancestors().find(|p| p.is_file()) {
        return Err(io::Error::new(
            io::ErrorKind::NotADirectory,
            format!("`{}` is a file, not a folder", file.display()),
        ));
    }
    std::fs::create_dir_all(folder)
}

/// Longest file name the common file systems take, in bytes.
pub const MAX_FILE_NAME: usize = 255;

/// The file name part that stands for `name` (see the [module docs](self)).
///
/// ```
/// use ulog_runtime::file_names::component;
/// assert_eq!(component("vehicle_attitude"), "vehicle_attitude");
/// assert_eq!(component("sensors/gyro"), "sensors_gyro");
/// assert_eq!(component(".."), "%2E%2E");
/// assert_eq!(component("a b\0é"), "a%20b%00%C3%A9");
/// ```
pub fn component(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for b in name.bytes() {
        match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'_' | b'-' => out.push(char::from(b)),
            b'/' => out.push('_'),
            _ => out.push_str(&format!("%{b:02X}")),
        }
    }
    out
}

/// The name a log gives its exports: its file name without the `.ulg` extension (any case),
/// lossy UTF-8 (`logs/09_12_34.ulg` is `09_12_34`). Pass it through [`component`] or
/// [`FileNames`] before making a path of it.
///
/// ```
/// use ulog_runtime::file_names::log_stem;
/// assert_eq!(log_stem("logs/09_12_34.ulg".as_ref()), "09_12_34");
/// assert_eq!(log_stem("FLIGHT.ULG".as_ref()), "FLIGHT");
/// assert_eq!(log_stem("dump.bin".as_ref()), "dump.bin");
/// ```
pub fn log_stem(path: &std::path::Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    match name.len().checked_sub(4) {
        Some(dot) if name.is_char_boundary(dot) && name[dot..].eq_ignore_ascii_case(".ulg") => {
            name[..dot].to_owned()
        }
        _ => name,
    }
}

/// 64-bit FNV-1a: a stable hash for shortened names (the same name, the same file name, on
/// every machine and run).
fn fnv1a(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// `prefix + component(name) + suffix`, shortened as the [module docs](self) say when it is
/// longer than [`MAX_FILE_NAME`] bytes.
///
/// ```
/// use ulog_runtime::file_names::{file_name, MAX_FILE_NAME};
/// assert_eq!(file_name("log_", "gps", "_0.csv"), "log_gps_0.csv");
/// let long = file_name("log_", &"x".repeat(400), "_0.csv");
/// assert_eq!(long.len(), MAX_FILE_NAME);
/// assert!(long.starts_with("log_xxx") && long.ends_with("_0.csv"));
/// ```
pub fn file_name(prefix: &str, name: &str, suffix: &str) -> String {
    let part = component(name);
    if prefix.len() + part.len() + suffix.len() <= MAX_FILE_NAME {
        return format!("{prefix}{part}{suffix}");
    }
    let tag = format!("~{:016x}", fnv1a(name));
    let room = MAX_FILE_NAME.saturating_sub(prefix.len() + suffix.len() + tag.len());
    // `part` is ASCII: any byte is a character boundary. A prefix longer than a file name
    // is the caller's (a log's own file name); it is kept.
    format!("{prefix}{}{tag}{suffix}", &part[..room.min(part.len())])
}

/// Where the file at `path` is written before it is complete: `.partial` after its name (a
/// reader globbing `*.parquet` never sees a half-written one). A name that would pass
/// [`MAX_FILE_NAME`] bytes with it is cut and tagged with a hash of the whole name, as
/// [`file_name`] shortens, so that a name the file system takes always has a partial one it
/// takes too.
///
/// ```
/// use std::path::Path;
/// use ulog_runtime::file_names::{partial_path, MAX_FILE_NAME};
/// assert_eq!(partial_path(Path::new("out/gps_0.parquet")), Path::new("out/gps_0.parquet.partial"));
/// let long = format!("{}.parquet", "x".repeat(240));
/// let partial = partial_path(Path::new(&long));
/// let name = partial.file_name().unwrap().to_str().unwrap();
/// assert_eq!(name.len(), MAX_FILE_NAME);
/// assert!(name.starts_with("xxx") && name.ends_with(".partial"));
/// ```
pub fn partial_path(path: &std::path::Path) -> std::path::PathBuf {
    const SUFFIX: &str = ".partial";
    let name = path.file_name().unwrap_or_default();
    match name.to_str() {
        Some(name) if name.len() + SUFFIX.len() > MAX_FILE_NAME => {
            let tag = format!("~{:016x}", fnv1a(name));
            let mut cut = MAX_FILE_NAME - SUFFIX.len() - tag.len();
            while !name.is_char_boundary(cut) {
                cut -= 1;
            }
            path.with_file_name(format!("{}{tag}{SUFFIX}", &name[..cut]))
        }
        _ => {
            let mut name = name.to_os_string();
            name.push(SUFFIX);
            path.with_file_name(name)
        }
    }
}

/// The `n`-th choice of a file name for `name`: [`file_name`] for 1, then with `~n` before
/// the extension (the last `.` of `suffix`): what [`FileNames::unique`] tries in turn, for
/// callers that must look at each choice themselves (whether a folder of that name already
/// holds something else).
///
/// ```
/// use ulog_runtime::file_names::numbered;
/// assert_eq!(numbered("log=", "flight", "", 1), "log=flight");
/// assert_eq!(numbered("log=", "flight", "", 2), "log=flight~2");
/// assert_eq!(numbered("", "gps", "_0.csv", 3), "gps_0~3.csv");
/// ```
pub fn numbered(prefix: &str, name: &str, suffix: &str, n: u32) -> String {
    if n <= 1 {
        return file_name(prefix, name, suffix);
    }
    let (stem, ext) = match suffix.rfind('.') {
        Some(dot) => suffix.split_at(dot),
        None => (suffix, ""),
    };
    file_name(prefix, name, &format!("{stem}~{n}{ext}"))
}

/// The file names of one output folder, unique without regard to case.
#[derive(Debug, Default, Clone)]
pub struct FileNames {
    /// Lower-cased file name -> the name it was made for.
    taken: HashMap<String, String>,
}

/// A file name made by [`FileNames::unique`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UniqueName {
    /// The file name.
    pub file_name: String,
    /// When the first choice was taken: the name that took it.
    pub collided_with: Option<String>,
}

impl FileNames {
    /// No names taken.
    pub fn new() -> FileNames {
        FileNames::default()
    }

    /// A file name for `name` ([`file_name`]), made unique in this folder: `~2`, `~3`... go
    /// before the extension (the last `.` of `suffix`) when the file name is taken.
    ///
    /// ```
    /// use ulog_runtime::file_names::FileNames;
    /// let mut names = FileNames::new();
    /// assert_eq!(names.unique("log_", "a/b", "_0.csv").file_name, "log_a_b_0.csv");
    /// let second = names.unique("log_", "a_b", "_0.csv");
    /// assert_eq!(second.file_name, "log_a_b_0~2.csv");
    /// assert_eq!(second.collided_with.as_deref(), Some("a/b"));
    /// assert_eq!(names.unique("log_", "A_B", "_0.csv").file_name, "log_A_B_0~3.csv");
    /// ```
    pub fn unique(&mut self, prefix: &str, name: &str, suffix: &str) -> UniqueName {
        let first = file_name(prefix, name, suffix);
        let collided_with = self.taken.get(&first.to_lowercase()).cloned();
        let mut chosen = first.clone();
        if collided_with.is_some() {
            for n in 2.. {
                let candidate = numbered(prefix, name, suffix, n);
                if !self.taken.contains_key(&candidate.to_lowercase()) {
                    chosen = candidate;
                    break;
                }
            }
        }
        self.taken.insert(chosen.to_lowercase(), name.to_owned());
        UniqueName {
            file_name: chosen,
            collided_with,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_name_leaves_the_folder_or_breaks_the_file_system() {
        for name in [
            "..",
            ".",
            "/",
            "/etc/passwd",
            "../../x",
            "a\\b",
            "c:",
            "\0",
            "nul",
            " ",
            "",
            "é/../ü",
            "%2E%2E",
        ] {
            let f = file_name("log_", name, "_0.csv");
            assert!(!f.contains(['/', '\\', '\0', ':']), "{name:?} -> {f}");
            assert_ne!(f, ".");
            assert_ne!(f, "..");
            let path = std::path::Path::new("out").join(&f);
            assert_eq!(path.parent(), Some(std::path::Path::new("out")), "{name:?}");
            assert_eq!(path.components().count(), 2, "{name:?}");
        }
        assert_eq!(
            component("%2E%2E"),
            "%252E%252E",
            "the mapping is reversible"
        );
        // Long names: bounded, distinct, stable.
        let a = file_name("log_", &format!("{}a", "x".repeat(300)), ".csv");
        let b = file_name("log_", &format!("{}b", "x".repeat(300)), ".csv");
        assert!(a.len() <= MAX_FILE_NAME && b.len() <= MAX_FILE_NAME);
        assert_ne!(a, b);
        assert_eq!(
            a,
            file_name("log_", &format!("{}a", "x".repeat(300)), ".csv")
        );
        let multibyte = file_name("", &"é".repeat(200), ".csv");
        assert!(multibyte.len() <= MAX_FILE_NAME, "{}", multibyte.len());
    }

    #[test]
    fn collisions_are_told_and_resolved() {
        let mut names = FileNames::new();
        let first = names.unique("", "Gps", ".parquet");
        assert_eq!(first.collided_with, None);
        let second = names.unique("", "gps", ".parquet");
        assert_eq!(second.file_name, "gps~2.parquet");
        assert_eq!(second.collided_with.as_deref(), Some("Gps"));
        // A name that already looks like a resolved one does not take it silently.
        let third = names.unique("", "gps~2", ".parquet");
        assert_ne!(third.file_name.to_lowercase(), "gps~2.parquet");
    }
}
