//! Motor failure: in flight (armed and, where the log says, in the air), one motor of an
//! `actuator_outputs` instance leaving the others: its output back at its idle level (below
//! idle plus a quarter of the way to the other motors' median, that median well above
//! idle) for at least 0.3 s (`drop_to_zero`), or at the highest output the motors reached
//! while the others' median stays 20% of their range below it for at least 1 s
//! (`locked_at_max`), at least two other motors flying. Motors are the channels below
//! `noutputs` whose disarmed output is at the bottom of the group's outputs and that ran
//! above their idle in flight: servos (centered) and unused channels never count. A
//! motor's idle is its output armed on the ground before the first takeoff, else its
//! disarmed one. An episode that begins within 1 s
//! of a disarm or a landing is left out: then every motor stops, which is the end of a
//! flight, not a failure.

use super::{Diagnostic, Evidence, Severity, secs};
use crate::analysis::LazyIndex;
use crate::analysis::modes::mode_name;
use crate::analysis::state::FlightState;
use crate::columns::Leaf;

/// How long one motor must stay at idle while the others fly, µs.
pub const DROP_US: u64 = 300_000;
/// How long one motor must stay at its maximum while the others do not, µs.
pub const LOCKED_US: u64 = 1_000_000;
/// Episodes starting this close to a disarm or a landing are not failures, µs.
pub const STOP_MARGIN_US: u64 = 1_000_000;

/// Where `actuator_outputs`' fields are.
pub(crate) struct Fields {
    multi_id: u8,
    noutputs: Option<Leaf>,
    outputs: Vec<Leaf>,
}

impl Fields {
    pub(crate) fn bind(multi_id: u8, index: &LazyIndex<'_>) -> Option<Fields> {
        let outputs: Vec<Leaf> = (0..)
            .map_while(|k| index.get(&format!("output[{k}]")))
            .collect();
        (!outputs.is_empty()).then_some(Fields {
            multi_id,
            noutputs: index.get("noutputs"),
            outputs,
        })
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Failure {
    Drop,
    Locked,
}

#[derive(Debug, Clone, Default)]
struct Channel {
    /// The output while disarmed (the last seen before flying).
    disarmed: Option<f64>,
    /// The output armed on the ground before the first takeoff.
    armed_idle: Option<f64>,
    max: f64,
    /// Ran above idle in flight.
    ran: bool,
    /// The open episode: kind, start, mode, value, the others' median.
    episode: Option<(Failure, u64, &'static str, f64, f64)>,
    last: u64,
}

impl Channel {
    /// The output a running motor falls back to when it stops.
    fn idle(&self) -> Option<f64> {
        self.armed_idle.or(self.disarmed)
    }
}

#[derive(Debug, Clone, Default)]
struct Group {
    channels: Vec<Channel>,
    taken_off: bool,
}

/// A candidate finding: group, channel, kind, start, end, mode, value, others' median.
type Found = (u8, usize, Failure, u64, u64, &'static str, f64, f64);

/// Every output group's motors, the candidate episodes and the stops (disarms, landings).
#[derive(Debug, Clone, Default)]
pub(crate) struct Motors {
    groups: Vec<(u8, Group)>,
    found: Vec<Found>,
    stops: Vec<u64>,
    was_flying: bool,
}

impl Motors {
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    pub(crate) fn row(&mut self, f: &Fields, data: &[u8], t: u64, state: &FlightState) {
        let flying = state.flying();
        if self.was_flying && !flying {
            self.stops.push(t);
        }
        self.was_flying = flying;
        let n = f
            .noutputs
            .and_then(|l| l.f64(data))
            .map_or(f.outputs.len(), |n| (n as usize).min(f.outputs.len()));
        let g = match self.groups.iter().position(|(m, _)| *m == f.multi_id) {
            Some(i) => &mut self.groups[i].1,
            None => {
                self.groups.push((f.multi_id, Group::default()));
                &mut self.groups.last_mut().expect("pushed").1
            }
        };
        if g.channels.len() < n {
            g.channels.resize_with(n, Channel::default);
        }
        let values: Vec<f64> = f.outputs[..n]
            .iter()
            .map(|l| l.f64(data).unwrap_or(f64::NAN))
            .collect();
        if flying {
            g.taken_off = true;
        } else {
            for (c, &v) in g.channels.iter_mut().zip(&values) {
                if v.is_finite() {
                    if !state.armed {
                        c.disarmed = Some(v);
                    } else if !g.taken_off {
                        c.armed_idle = Some(v);
                    }
                }
                c.episode = None;
            }
            return;
        }
        // The group's floor: its channels' lowest disarmed output; a motor rests near it.
        let floor = g
            .channels
            .iter()
            .filter_map(|c| c.disarmed.or(c.armed_idle))
            .fold(f64::INFINITY, f64::min);
        let top = g
            .channels
            .iter()
            .zip(&values)
            .map(|(c, v)| c.max.max(*v))
            .filter(|v| v.is_finite())
            .fold(f64::NEG_INFINITY, f64::max);
        let range = top - floor;
        if !range.is_finite() || range <= 0.0 {
            return;
        }
        let is_motor = |c: &Channel| {
            c.disarmed
                .or(c.armed_idle)
                .is_some_and(|i| i <= floor + 0.1 * range)
        };
        for (c, &v) in g.channels.iter_mut().zip(&values) {
            if v.is_finite() {
                c.max = c.max.max(v);
                if is_motor(c) && v > c.idle().unwrap_or(floor) + 0.1 * range {
                    c.ran = true;
                }
            }
        }
        let motors: Vec<usize> = (0..values.len())
            .filter(|&k| g.channels[k].ran && is_motor(&g.channels[k]) && values[k].is_finite())
            .collect();
        if motors.len() < 3 {
            return;
        }
        let ceiling = motors
            .iter()
            .map(|&k| g.channels[k].max)
            .fold(f64::NEG_INFINITY, f64::max);
        let mode = state
            .nav_state
            .map_or("Unknown", |n| mode_name(n, state.version));
        for &k in &motors {
            let mut others: Vec<f64> = motors
                .iter()
                .filter(|&&j| j != k)
                .map(|&j| values[j])
                .collect();
            others.sort_by(f64::total_cmp);
            let median = others[others.len() / 2];
            let c = &mut g.channels[k];
            let idle = c.idle().unwrap_or(floor);
            let v = values[k];
            let now = if v < idle + 0.25 * (median - idle) && median > idle + 0.2 * range {
                Some(Failure::Drop)
            } else if v >= ceiling - 0.01 * range && median < ceiling - 0.2 * range {
                Some(Failure::Locked)
            } else {
                None
            };
            match (now, c.episode) {
                (Some(kind), None) => c.episode = Some((kind, t, mode, v, median)),
                (Some(kind), Some((open, ..))) if kind == open => {}
                (_, Some((kind, start, mode, value, median))) => {
                    let min = if kind == Failure::Drop {
                        DROP_US
                    } else {
                        LOCKED_US
                    };
                    if c.last >= start.saturating_add(min) {
                        self.found
                            .push((f.multi_id, k, kind, start, c.last, mode, value, median));
                    }
                    c.episode = now.map(|kind| (kind, t, mode, v, median));
                }
                (None, None) => {}
            }
            c.last = t;
        }
    }

    /// Whether any row was taken.
    pub(crate) fn seen(&self) -> bool {
        !self.groups.is_empty()
    }

    pub(crate) fn finish(mut self) -> Vec<Diagnostic> {
        for (m, g) in &self.groups {
            for (k, c) in g.channels.iter().enumerate() {
                if let Some((kind, start, mode, value, median)) = c.episode {
                    let min = if kind == Failure::Drop {
                        DROP_US
                    } else {
                        LOCKED_US
                    };
                    if c.last >= start.saturating_add(min) {
                        self.found
                            .push((*m, k, kind, start, c.last, mode, value, median));
                    }
                }
            }
        }
        let stops = self.stops;
        self.found
            .into_iter()
            // Not the end of a flight: no stop shortly after the episode began.
            .filter(|f| {
                !stops.iter().any(|&s| {
                    s.saturating_add(100_000) >= f.3 && s <= f.3.saturating_add(STOP_MARGIN_US)
                })
            })
            .map(|(multi_id, k, kind, start, end, mode, value, median)| {
                let (what, failure) = match kind {
                    Failure::Drop => ("dropped to idle", "drop_to_zero"),
                    Failure::Locked => ("locked at its maximum", "locked_at_max"),
                };
                Diagnostic {
                    id: "motor_failure".to_owned(),
                    summary: format!(
                        "Motor {k} of output group {multi_id} {what} ({value:.0}, the others at \
                         {median:.0}) for {:.1} s from {:.1} s in {mode} mode",
                        secs(end - start),
                        secs(start)
                    ),
                    severity: Severity::Critical,
                    timestamp_us: start,
                    end_timestamp_us: Some(end),
                    evidence: Evidence::MotorFailure {
                        multi_id,
                        motor_index: k,
                        pwm_value: value,
                        failure_mode: failure.to_owned(),
                        flight_mode: mode.to_owned(),
                        others_median: median,
                    },
                }
            })
            .collect()
    }
}
