//! `ulog_extract_gps_dump`: the raw bytes a GPS receiver exchanged with the autopilot, as
//! PX4 logs them in the `gps_dump` topic (`uint8_t len` whose bit 7 says "to the device",
//! `uint8_t[N] data`, and in newer firmware `uint8_t instance`).

use crate::Log;
use crate::columns::ColumnValues;

/// The two byte streams of one receiver.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct GpsDump {
    /// Bytes sent to the receiver.
    pub to_device: Vec<u8>,
    /// Bytes received from it.
    pub from_device: Vec<u8>,
    /// Dropouts in the log (bytes may be missing from the streams).
    pub dropouts: usize,
}

/// Why there is no dump.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum GpsDumpError {
    /// The log has no `gps_dump` rows (pyulog: `File ... does not contain gps_dump
    /// messages!`, exit 0).
    #[error("does not contain gps_dump messages")]
    NoGpsDump,
    /// The topic lacks `len` or `data[0]` (pyulog: `Error: gps_dump message has wrong
    /// format`).
    #[error("gps_dump message has wrong format")]
    WrongFormat,
    /// A row says it holds more bytes than its `data` array has.
    #[error("gps_dump row {row}: len {len} is more than its {size} data bytes")]
    TooLong {
        /// The row (from 0).
        row: usize,
        /// Its length.
        len: usize,
        /// Its `data` size.
        size: usize,
    },
}

/// The streams of receiver `instance` (0 the main one): rows of the first `gps_dump`
/// instance with rows whose `instance` field (0 when absent) is `instance`, as pyulog
/// extracts them.
pub fn gps_dump(log: &Log<'_>, instance: u8) -> Result<GpsDump, GpsDumpError> {
    let first = log
        .topics()
        .into_iter()
        .find(|t| t.name == "gps_dump")
        .ok_or(GpsDumpError::NoGpsDump)?;
    let cols = log
        .columns("gps_dump", first.multi_id)
        .map_err(|_| GpsDumpError::NoGpsDump)?;
    let bytes = |name: &str| cols.get(name).and_then(ColumnValues::as_uint8);
    let (Some(len), Some(_)) = (bytes("len"), bytes("data[0]")) else {
        return Err(GpsDumpError::WrongFormat);
    };
    let data: Vec<&[u8]> = (0..).map_while(|k| bytes(&format!("data[{k}]"))).collect();
    let instances = bytes("instance");
    let mut out = GpsDump {
        dropouts: log.dropouts().len(),
        ..GpsDump::default()
    };
    for (row, &l) in len.iter().enumerate() {
        if instances.map_or(0, |i| i[row]) != instance {
            continue;
        }
        let (n, stream) = if l & 0x80 != 0 {
            (usize::from(l & 0x7f), &mut out.to_device)
        } else {
            (usize::from(l), &mut out.from_device)
        };
        if n > data.len() {
            return Err(GpsDumpError::TooLong {
                row,
                len: n,
                size: data.len(),
            });
        }
        stream.extend(data[..n].iter().map(|column| column[row]));
    }
    Ok(out)
}
