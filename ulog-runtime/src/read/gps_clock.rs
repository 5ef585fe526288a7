//! The UTC date of a log's start from its first GPS fix, for logs whose header holds a time
//! since boot ([`GpsClock`]): what `metadata.json`, `ulog json` and the Parquet files'
//! `ulog.start_utc` give when the header has no date.

use crate::read::{FileHeader, Log, Row, Subscription, UtcTime};
use crate::schema::{FieldKind, Primitive, Schema};

/// The UTC time of a log's start from its first GPS fix: `time_utc_usec` of
/// `vehicle_gps_position` or `sensor_gps`, less the time from the log's start to that row.
/// A fix is a `time_utc_usec` in [`UtcTime::PLAUSIBLE_US`], from 2000 up to 2100 (a GPS
/// without one reports 0; a value past 2100 is taken for damage).
#[derive(Debug, Clone, Copy)]
pub struct GpsClock {
    log_start: u64,
    start: Option<u64>,
}

impl GpsClock {
    /// Topics whose `time_utc_usec` is read.
    pub const TOPICS: [&str; 2] = ["vehicle_gps_position", "sensor_gps"];

    /// A clock for a log whose header says it started at `log_start` µs.
    pub fn new(log_start: u64) -> GpsClock {
        GpsClock {
            log_start,
            start: None,
        }
    }

    /// The offset of the `uint64_t time_utc_usec` field of a subscription's rows, if it is
    /// one of [`GpsClock::TOPICS`] and has one.
    pub fn field(schema: &Schema, sub: &Subscription) -> Option<usize> {
        if !GpsClock::TOPICS.contains(&sub.name.as_str()) {
            return None;
        }
        let layout = schema.resolved(sub.format()?)?;
        layout
            .fields
            .iter()
            .find(|f| {
                f.name == "time_utc_usec"
                    && f.array_len.is_none()
                    && f.kind == FieldKind::Primitive(Primitive::UInt64)
            })
            .map(|f| f.offset)
    }

    /// Reads a row whose `time_utc_usec` is at `at`; returns whether the clock is set.
    pub fn watch(&mut self, row: &Row<'_>, at: usize) -> bool {
        if self.start.is_none()
            && let Some(b) = row.data.get(at..at + 8)
        {
            // A GPS without a fix reports 0, and a value beyond the century is a damaged
            // row, not a date.
            let utc = u64::from_le_bytes(b.try_into().expect("8 bytes"));
            if UtcTime::PLAUSIBLE_US.contains(&utc) {
                let since_start = row.timestamp.saturating_sub(self.log_start);
                self.start = Some(utc.saturating_sub(since_start));
            }
        }
        self.start.is_some()
    }

    /// The log's start in UTC, µs since 1970, once a fix was seen.
    pub fn start(&self) -> Option<u64> {
        self.start
    }

    /// A log's start date: the header's when it holds one ([`FileHeader::start_utc`]), else
    /// `gps_utc_start` (what a [`GpsClock`] found, µs since 1970). The one rule behind
    /// [`Log::start_utc`], `metadata.json`'s `start_utc` and the Parquet files'
    /// `ulog.start_utc`.
    pub fn date(header: FileHeader, gps_utc_start: Option<u64>) -> Option<UtcTime> {
        header
            .start_utc()
            .or_else(|| gps_utc_start.map(UtcTime::from_unix_us))
    }

    /// The start of a whole-file log in UTC from its first GPS fix in file order (µs since
    /// 1970), as a streaming pass with a [`GpsClock`] finds it, reading each GPS
    /// subscription's rows up to its first fix; `None` when no row has one.
    pub fn of_log(log: &Log<'_>) -> Option<u64> {
        let start = log.metadata().header().start_timestamp;
        let mut first: Option<(u64, u64)> = None; // (offset, start)
        for sub in log.subscriptions() {
            let Some(at) = GpsClock::field(log.metadata().schema(), sub) else {
                continue;
            };
            let mut clock = GpsClock::new(start);
            for row in log.rows(sub) {
                if first.is_some_and(|(offset, _)| row.offset > offset) {
                    break;
                }
                if clock.watch(&row, at) {
                    first = clock.start().map(|utc| (row.offset, utc));
                    break;
                }
            }
        }
        first.map(|(_, utc)| utc)
    }
}

impl Log<'_> {
    /// The log's start as a UTC date: the header's when it holds one, else from the first
    /// GPS fix ([`GpsClock::of_log`], which reads GPS rows up to it); `None` without either.
    pub fn start_utc(&self) -> Option<UtcTime> {
        let header = self.metadata().header();
        match header.start_utc() {
            Some(date) => Some(date),
            None => GpsClock::date(header, GpsClock::of_log(self)),
        }
    }
}
