//! Diagnostics: what went wrong in a flight, each a consumer of the rows with its rule in
//! its doc comment, reporting an episode (start, end, severity, evidence):
//!
//! - [`brownout`]: the battery's voltage per cell below 3.3 V while armed;
//! - [`ekf`]: an EKF innovation test ratio above 1 for a sustained time in flight;
//! - [`gps`]: GPS interference (accuracy spikes, satellites lost, jamming) after a fix;
//! - [`motor`]: one motor's output dropping or saturating while the others keep flying;
//! - [`rc`]: the RC signal lost while armed.
//!
//! Their JSON has flight-review-rs's keys (`id`, `summary`, `severity`, `timestamp_us`,
//! `end_timestamp_us`, `evidence` with its `type`), `end_timestamp_us` the episode's end.

pub mod brownout;
pub mod ekf;
pub mod gps;
pub mod motor;
pub mod rc;

use super::state::FlightState;
use crate::analysis::LazyIndex;
use crate::read::Metadata;

/// How bad a finding is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize),
    serde(rename_all = "lowercase")
)]
pub enum Severity {
    /// Worth a look.
    Warning,
    /// A flight in danger.
    Critical,
}

/// What a diagnostic rests on.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize), serde(tag = "type"))]
#[non_exhaustive]
pub enum Evidence {
    /// [`brownout`].
    BatteryBrownout {
        /// The battery instance.
        multi_id: u8,
        /// The lowest voltage of the episode, V.
        voltage_v: f64,
        /// The lowest voltage per cell, V.
        cell_voltage_v: f64,
        /// Cells, and where the count came from (`parameter`, `cell_count`, `estimated`).
        cells: u32,
        /// Where the cell count came from.
        cells_from: String,
        /// The threshold, V (cells × 3.3).
        critical_threshold_v: f64,
        /// The current then, A.
        current_a: Option<f64>,
    },
    /// [`ekf`].
    EkfFailure {
        /// The estimator instance.
        multi_id: u8,
        /// `velocity`, `position`, `height`, `magnetometer`, `airspeed`, `sideslip` or `heading`.
        innovation: String,
        /// The highest ratio of the episode.
        test_ratio: f64,
        /// 1.
        threshold: f64,
    },
    /// [`gps`].
    GpsInterference {
        /// The topic: `vehicle_gps_position`, or `sensor_gps` in a log without it.
        source: String,
        /// Its instance.
        multi_id: u8,
        /// The worst horizontal accuracy of the episode, m.
        eph_m: f64,
        /// The worst vertical accuracy, m.
        epv_m: f64,
        /// The fewest satellites.
        num_satellites: u32,
        /// The accuracy before the episode, m.
        baseline_eph_m: f64,
        /// The satellites before it.
        baseline_satellites: f64,
        /// The highest jamming indicator, where the topic has it.
        jamming_indicator: Option<f64>,
        /// The highest noise per ms, where the topic has it.
        noise_level: Option<f64>,
        /// What was seen: `eph spike`, `epv spike`, `satellites lost`, `jamming`, `fix lost`.
        reasons: Vec<String>,
    },
    /// [`motor`].
    MotorFailure {
        /// The `actuator_outputs` instance.
        multi_id: u8,
        /// The output channel.
        motor_index: usize,
        /// The output at the failure.
        pwm_value: f64,
        /// `drop_to_zero` or `locked_at_max`.
        failure_mode: String,
        /// The flight mode then.
        flight_mode: String,
        /// The median of the other motors then.
        others_median: f64,
    },
    /// [`rc`].
    RcLoss {
        /// The topic the loss was read from: `input_rc`, `failsafe_flags` or
        /// `vehicle_status`.
        source: String,
        /// Its instance.
        multi_id: u8,
        /// The last time a signal was received, µs.
        last_signal_timestamp_us: u64,
        /// How long it was lost, ms.
        signal_lost_duration_ms: u64,
    },
}

/// One finding.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Diagnostic {
    /// `battery_brownout`, `ekf_failure`, `gps_interference`, `motor_failure`, `rc_loss`.
    pub id: String,
    /// One sentence.
    pub summary: String,
    /// How bad.
    pub severity: Severity,
    /// The episode's start, µs.
    pub timestamp_us: u64,
    /// Its end, µs (`None` when a finding is an instant).
    pub end_timestamp_us: Option<u64>,
    /// What it rests on.
    pub evidence: Evidence,
}

/// Where the diagnostics' topics' fields are.
pub(crate) enum Fields {
    Battery(brownout::Fields),
    Estimator(ekf::Fields),
    Gps(gps::Fields),
    Outputs(motor::Fields),
    Rc(rc::Fields),
}

impl Fields {
    pub(crate) fn bind(topic: &str, multi_id: u8, index: &LazyIndex<'_>) -> Option<Fields> {
        match topic {
            "battery_status" => brownout::Fields::bind(multi_id, index).map(Fields::Battery),
            "estimator_status" => ekf::Fields::bind(multi_id, index).map(Fields::Estimator),
            "vehicle_gps_position" | "sensor_gps" => {
                gps::Fields::bind(topic, multi_id, index).map(Fields::Gps)
            }
            "actuator_outputs" => motor::Fields::bind(multi_id, index).map(Fields::Outputs),
            "input_rc" | "failsafe_flags" | "vehicle_status" => {
                rc::Fields::bind(topic, multi_id, index).map(Fields::Rc)
            }
            _ => None,
        }
    }
}

/// Every diagnostic's state.
#[derive(Debug, Clone, Default)]
pub(crate) struct Diagnostics {
    brownout: brownout::Brownout,
    ekf: ekf::Ekf,
    gps: gps::Interference,
    motor: motor::Motors,
    rc: rc::RcLoss,
}

impl Diagnostics {
    pub(crate) fn row(&mut self, f: &Fields, data: &[u8], t: u64, state: &FlightState) {
        match f {
            Fields::Battery(f) => self.brownout.row(f, data, t, state),
            Fields::Estimator(f) => self.ekf.row(f, data, t, state),
            Fields::Gps(f) => self.gps.row(f, data, t, state),
            Fields::Outputs(f) => self.motor.row(f, data, t, state),
            Fields::Rc(f) => self.rc.row(f, data, t, state),
        }
    }

    /// Learns what the definitions say (the parameters' cell counts), before the rows.
    pub(crate) fn start(&mut self, meta: &Metadata) {
        self.brownout.start(meta);
    }

    /// Every finding, by start time; a diagnostic whose topics the log lacks is said in
    /// `missing` (no finding there means "not checked", not "nothing wrong").
    pub(crate) fn finish(self, end: u64, missing: &mut Vec<super::Missing>) -> Vec<Diagnostic> {
        let unchecked = [
            (
                self.brownout.seen(),
                "battery_brownout",
                "the log has no battery_status rows with a voltage",
            ),
            (
                self.ekf.seen(),
                "ekf_failure",
                "the log has no estimator_status rows with a finite innovation test ratio",
            ),
            (
                self.gps.seen(),
                "gps_interference",
                "the log has no vehicle_gps_position or sensor_gps rows with a fix type",
            ),
            (
                self.motor.seen(),
                "motor_failure",
                "the log has no actuator_outputs rows",
            ),
            (
                self.rc.source().is_some(),
                "rc_loss",
                "the log has no input_rc, failsafe_flags or vehicle_status rows that say \
                 whether the RC signal is lost",
            ),
        ];
        for (seen, fact, reason) in unchecked {
            if !seen {
                missing.push(super::Missing {
                    fact: fact.to_owned(),
                    reason: reason.to_owned(),
                });
            }
        }
        let mut out = Vec::new();
        out.extend(self.brownout.finish(end));
        out.extend(self.ekf.finish(end));
        out.extend(self.gps.finish(end));
        out.extend(self.motor.finish());
        out.extend(self.rc.finish(end));
        out.sort_by_key(|d| d.timestamp_us);
        out
    }
}

/// An episode of a condition over time: when it began, how bad it got.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Episode {
    pub(crate) since: Option<u64>,
    pub(crate) last: u64,
}

impl Episode {
    /// Whether the condition holds at `t`; on its end, the episode's (start, end).
    pub(crate) fn see(&mut self, holds: bool, t: u64) -> Option<(u64, u64)> {
        match (holds, self.since) {
            (true, None) => {
                self.since = Some(t);
                self.last = t;
                None
            }
            (true, Some(_)) => {
                self.last = t;
                None
            }
            (false, Some(start)) => {
                self.since = None;
                // Time that ran back (a damaged log) ends the episode where it began.
                Some((start, t.max(start)))
            }
            (false, None) => None,
        }
    }

    /// The episode still open at the end of the log.
    pub(crate) fn close(&mut self, end: u64) -> Option<(u64, u64)> {
        self.since.take().map(|s| (s, end.max(self.last).max(s)))
    }
}

/// Seconds, for summaries.
pub(crate) fn secs(us: u64) -> f64 {
    us as f64 / 1e6
}
