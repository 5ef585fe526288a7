//! RC loss: while armed, the RC signal lost for at least 0.5 s after a signal had been
//! received (a vehicle flown without RC reports nothing): a warning, critical from 5 s.
//! The episode ends when the signal is back or the vehicle disarms (or the log ends).
//!
//! "Lost" is read from the first of these sources the log has (the others then not used):
//! `input_rc`'s `rc_lost` or `rc_failsafe` (PX4's own test: a receiver that keeps sending
//! frames after the link is lost says so only in `rc_failsafe`); `failsafe_flags`'
//! `manual_control_signal_lost` (PX4 1.14 on); `vehicle_status`' `rc_signal_lost` (older
//! PX4).

use super::{Diagnostic, Evidence, Severity, secs};
use crate::analysis::LazyIndex;
use crate::analysis::state::FlightState;
use crate::columns::Leaf;

/// The shortest loss reported, µs.
pub const MIN_DURATION_US: u64 = 500_000;
/// Losses at least this long are critical.
pub const CRITICAL_US: u64 = 5_000_000;

/// Where an RC loss is read from, best first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Source {
    InputRc,
    FailsafeFlags,
    VehicleStatus,
}

impl Source {
    fn topic(self) -> &'static str {
        match self {
            Source::InputRc => "input_rc",
            Source::FailsafeFlags => "failsafe_flags",
            Source::VehicleStatus => "vehicle_status",
        }
    }
}

/// Where a source's "lost" flags are (any of them set: lost).
pub(crate) struct Fields {
    source: Source,
    multi_id: u8,
    lost: [Option<Leaf>; 2],
}

impl Fields {
    pub(crate) fn bind(topic: &str, multi_id: u8, index: &LazyIndex<'_>) -> Option<Fields> {
        let (source, lost) = match topic {
            "input_rc" => (
                Source::InputRc,
                [index.get("rc_lost"), index.get("rc_failsafe")],
            ),
            "failsafe_flags" => (
                Source::FailsafeFlags,
                [index.get("manual_control_signal_lost"), None],
            ),
            "vehicle_status" => (Source::VehicleStatus, [index.get("rc_signal_lost"), None]),
            _ => return None,
        };
        lost.iter().any(Option::is_some).then_some(Fields {
            source,
            multi_id,
            lost,
        })
    }
}

#[derive(Debug, Clone, Default)]
struct Link {
    last_signal: Option<u64>,
    since: Option<u64>,
    last: u64,
}

/// Every RC input's state, and the losses found.
#[derive(Debug, Clone, Default)]
pub(crate) struct RcLoss {
    links: Vec<((Source, u8), Link)>,
    found: Vec<(Source, u8, u64, u64, u64)>,
}

impl RcLoss {
    pub(crate) fn row(&mut self, f: &Fields, data: &[u8], t: u64, state: &FlightState) {
        let flags = f.lost.iter().flatten().filter_map(|l| l.f64(data));
        let Some(lost) = flags.fold(None, |any, v| Some(any.unwrap_or(false) || v != 0.0)) else {
            return;
        };
        let key = (f.source, f.multi_id);
        let l = match self.links.iter().position(|(k, _)| *k == key) {
            Some(i) => &mut self.links[i].1,
            None => {
                self.links.push((key, Link::default()));
                &mut self.links.last_mut().expect("pushed").1
            }
        };
        let losing = lost && state.armed && l.last_signal.is_some();
        match (losing, l.since) {
            (true, None) => l.since = Some(t),
            (false, Some(start)) => {
                if t.saturating_sub(start) >= MIN_DURATION_US {
                    self.found.push((
                        f.source,
                        f.multi_id,
                        start,
                        t,
                        l.last_signal.unwrap_or(start),
                    ));
                }
                l.since = None;
            }
            _ => {}
        }
        if !lost {
            l.last_signal = Some(t);
        }
        l.last = t;
    }

    /// The source the findings come from: the best the log has; `None` without any.
    pub(crate) fn source(&self) -> Option<Source> {
        self.links.iter().map(|((s, _), _)| *s).min()
    }

    pub(crate) fn finish(mut self, end: u64) -> Vec<Diagnostic> {
        for ((source, m), l) in &self.links {
            if let Some(start) = l.since {
                let stop = end.max(l.last);
                if stop.saturating_sub(start) >= MIN_DURATION_US {
                    self.found
                        .push((*source, *m, start, stop, l.last_signal.unwrap_or(start)));
                }
            }
        }
        let best = self.source();
        self.found
            .into_iter()
            .filter(|f| Some(f.0) == best)
            .map(|(source, multi_id, start, end, last_signal)| Diagnostic {
                id: "rc_loss".to_owned(),
                summary: format!(
                    "RC signal lost for {:.1} s from {:.1} s while armed ({})",
                    secs(end - start),
                    secs(start),
                    source.topic()
                ),
                severity: if end - start >= CRITICAL_US {
                    Severity::Critical
                } else {
                    Severity::Warning
                },
                timestamp_us: start,
                end_timestamp_us: Some(end),
                evidence: Evidence::RcLoss {
                    source: source.topic().to_owned(),
                    multi_id,
                    last_signal_timestamp_us: last_signal,
                    signal_lost_duration_ms: (end - start) / 1000,
                },
            })
            .collect()
    }
}
