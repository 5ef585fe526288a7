//! RC loss: while armed, `input_rc.rc_lost` set for at least 0.5 s after a signal had been
//! received (a vehicle flown without RC reports nothing): a warning, critical from 5 s.
//! The episode ends when the signal is back or the vehicle disarms (or the log ends).

use super::{Diagnostic, Evidence, Severity, secs};
use crate::analysis::LazyIndex;
use crate::analysis::state::FlightState;
use crate::columns::Leaf;

/// The shortest loss reported, µs.
pub const MIN_DURATION_US: u64 = 500_000;
/// Losses at least this long are critical.
pub const CRITICAL_US: u64 = 5_000_000;

/// Where `input_rc`'s fields are.
pub(crate) struct Fields {
    multi_id: u8,
    lost: Leaf,
}

impl Fields {
    pub(crate) fn bind(multi_id: u8, index: &LazyIndex<'_>) -> Option<Fields> {
        Some(Fields {
            multi_id,
            lost: index.get("rc_lost")?,
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
    links: Vec<(u8, Link)>,
    found: Vec<(u8, u64, u64, u64)>,
}

impl RcLoss {
    pub(crate) fn row(&mut self, f: &Fields, data: &[u8], t: u64, state: &FlightState) {
        let Some(lost) = f.lost.f64(data).map(|v| v != 0.0) else {
            return;
        };
        let l = match self.links.iter().position(|(m, _)| *m == f.multi_id) {
            Some(i) => &mut self.links[i].1,
            None => {
                self.links.push((f.multi_id, Link::default()));
                &mut self.links.last_mut().expect("pushed").1
            }
        };
        let losing = lost && state.armed && l.last_signal.is_some();
        match (losing, l.since) {
            (true, None) => l.since = Some(t),
            (false, Some(start)) => {
                if t.saturating_sub(start) >= MIN_DURATION_US {
                    self.found
                        .push((f.multi_id, start, t, l.last_signal.unwrap_or(start)));
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

    pub(crate) fn finish(mut self, end: u64) -> Vec<Diagnostic> {
        for (m, l) in &self.links {
            if let Some(start) = l.since {
                let stop = end.max(l.last);
                if stop.saturating_sub(start) >= MIN_DURATION_US {
                    self.found
                        .push((*m, start, stop, l.last_signal.unwrap_or(start)));
                }
            }
        }
        self.found
            .into_iter()
            .map(|(multi_id, start, end, last_signal)| Diagnostic {
                id: "rc_loss".to_owned(),
                summary: format!(
                    "RC signal lost for {:.1} s from {:.1} s while armed",
                    secs(end - start),
                    secs(start)
                ),
                severity: if end - start >= CRITICAL_US {
                    Severity::Critical
                } else {
                    Severity::Warning
                },
                timestamp_us: start,
                end_timestamp_us: Some(end),
                evidence: Evidence::RcLoss {
                    multi_id,
                    last_signal_timestamp_us: last_signal,
                    signal_lost_duration_ms: (end - start) / 1000,
                },
            })
            .collect()
    }
}
