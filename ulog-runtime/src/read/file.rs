//! Opening a log file by path ([`open_file`]): what every reader of a path (the memory map,
//! the Parquet converter) opens through, so that a folder, a device, a pipe or a socket is
//! refused with the same plain message everywhere, before anything waits on it or maps it.

use std::fs::File;
use std::io;
use std::path::Path;

/// Opens `path` for reading if it is a regular file (or a link to one). A folder is an error
/// of kind `IsADirectory` ("is a folder, not a log file"), anything else that is not a
/// regular file (a device such as `/dev/stdin`, a named pipe, a socket) one of kind
/// `InvalidInput` ("is not a regular file"), found from the path before the file is opened,
/// so a named pipe with no writer is refused, not waited on.
///
/// ```
/// let e = ulog_runtime::read::open_file(std::env::temp_dir()).unwrap_err();
/// assert_eq!(e.to_string(), "is a folder, not a log file");
/// ```
pub fn open_file(path: impl AsRef<Path>) -> io::Result<File> {
    let path = path.as_ref();
    match not_a_log_file(&std::fs::metadata(path)?) {
        Some(e) => Err(e),
        None => File::open(path),
    }
}

/// Why a file of this kind cannot be a log ([`open_file`]'s refusals), or `None` for a
/// regular file.
pub(crate) fn not_a_log_file(kind: &std::fs::Metadata) -> Option<io::Error> {
    if kind.is_dir() {
        Some(io::Error::new(
            io::ErrorKind::IsADirectory,
            "is a folder, not a log file",
        ))
    } else if !kind.is_file() {
        Some(io::Error::new(
            io::ErrorKind::InvalidInput,
            "is not a regular file",
        ))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_regular_file_is_opened() {
        let e = open_file(std::env::temp_dir()).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::IsADirectory);
        #[cfg(unix)]
        {
            let e = open_file("/dev/null").unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
            assert_eq!(e.to_string(), "is not a regular file");
        }
        let missing = open_file(std::env::temp_dir().join("no such log.ulg")).unwrap_err();
        assert_eq!(missing.kind(), io::ErrorKind::NotFound);
        let path = std::env::temp_dir().join(format!("open_file_{}.ulg", std::process::id()));
        std::fs::write(&path, b"ULog").unwrap();
        let opened = open_file(&path);
        std::fs::remove_file(&path).unwrap();
        assert_eq!(opened.unwrap().metadata().unwrap().len(), 4);
    }
}
