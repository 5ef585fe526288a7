//! Flight analysis: what a log says about the flight, from its rows in file order. Flight
//! modes and VTOL states, armed and in-air intervals, flight statistics, battery, GPS
//! quality and track, vibration, non-default parameters, per-field statistics, the rate
//! controllers' step responses and the gyro and accelerometer spectra, and diagnostics of
//! what went wrong (battery brownout, EKF innovation failure, GPS interference, a motor
//! failure, RC loss), each with its rule in its doc comment.
//!
//! The JSON ([`Analysis`] with serde) uses the key names of PX4's Flight Review v2
//! converter (`flight_modes`, `stats.total_distance_m`, `battery.min_voltage_v`...) where it
//! has the same fact; what it adds has keys of its own. A fact the log cannot give (a topic
//! or field it lacks, a version that logs it otherwise) is absent (`null`, or an empty
//! list) and [`Analysis::missing`] says why; nothing fails for it.
//!
//! Each concern is its own file, a consumer of the same rows: `state` (armed, in air,
//! mode), `modes`, `motion`, `sensors`, `fields`, `params`, [`diagnostics`], `spectral`.
//! [`Analyzer`] feeds them one pass ([`Analysis::of_reader`]); over a whole file's bytes
//! ([`Analysis::of_bytes`], [`Analysis::of_log`]) they share two walks on two threads, the
//! per-field statistics on one, the rest on the other, with the same result.
//!
//! ```no_run
//! # fn main() -> Result<(), ulog_runtime::ReadError> {
//! let log = ulog_runtime::Log::open("flight.ulg")?;
//! let analysis = ulog_runtime::analysis::Analysis::of_log(&log);
//! for m in &analysis.flight_modes {
//!     println!("{} for {:.1} s", m.mode, m.duration_s);
//! }
//! for d in &analysis.diagnostics {
//!     println!("{:?}: {}", d.severity, d.summary);
//! }
//! # Ok(()) }
//! ```

pub mod diagnostics;
mod fields;
#[cfg(feature = "parquet")]
pub(crate) use fields::ColumnStats;
mod modes;
mod motion;
mod params;
mod sensors;
mod spectral;
mod state;
mod summary;

use std::io::Read;
use std::num::NonZero;

use crate::read::{Log, Metadata, Row, RowVisitor, Subscription, visit_rows};
use crate::{Event, ReadError, StreamReader};

pub use diagnostics::{Diagnostic, Evidence, Severity};
pub use sensors::{
    VIBRATION_CRITICAL_MEAN, VIBRATION_CRITICAL_PEAK, VIBRATION_GOOD_MEAN, VIBRATION_GOOD_PEAK,
};

/// Everything the analysis found ([module docs](self)).
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct Analysis {
    /// Segments of `vehicle_status.nav_state`, with PX4's mode names.
    pub flight_modes: Vec<ModeSegment>,
    /// VTOL states (multicopter, fixed-wing, transition) of a VTOL.
    pub vtol_states: Vec<VtolSegment>,
    /// When the vehicle was armed.
    pub armed: Vec<Interval>,
    /// When it was in the air (from `vehicle_land_detected`): takeoffs and landings.
    pub flights: Vec<Interval>,
    /// Motion, from `vehicle_local_position`, `vehicle_attitude` and
    /// `vehicle_angular_velocity`.
    pub stats: Stats,
    /// `battery_status`.
    pub battery: Battery,
    /// `vehicle_gps_position` (or `sensor_gps`).
    pub gps_quality: GpsQuality,
    /// `vehicle_imu_status.accel_vibration_metric`.
    pub vibration: Vibration,
    /// Parameters whose value is not the log's default.
    pub non_default_params: Vec<NonDefault>,
    /// The GPS track, one point a second, with the flight mode at each point.
    pub gps_track: Vec<TrackPoint>,
    /// Minimum, maximum and mean of every numeric field of every topic instance.
    pub field_stats: Vec<FieldStat>,
    /// What went wrong (see [`diagnostics`]).
    pub diagnostics: Vec<Diagnostic>,
    /// The rate controllers' step responses, per axis.
    pub step_response: Vec<AxisResponse>,
    /// Power spectral densities of the gyro and the accelerometer, per axis.
    pub spectra: Vec<SpectrumOf>,
    /// The facts the log could not give, and why.
    pub missing: Vec<Missing>,
}

/// A stretch of one flight mode.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ModeSegment {
    /// PX4's name (`Position`, `Mission`, `RTL`...; `Unknown` for a number PX4 does not name).
    pub mode: String,
    /// `nav_state` (255, a mode PX4 does not have, for a value no `uint8_t` holds: NaN or
    /// 2.5 in a crafted log's `float` field).
    pub mode_id: u8,
    /// µs (log time).
    pub start_us: u64,
    /// µs: the next mode's start, or the log's last row.
    pub end_us: u64,
    /// Seconds.
    pub duration_s: f64,
}

/// A stretch of one VTOL state.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct VtolSegment {
    /// `MC`, `FW` or `Transition`.
    pub state: String,
    /// µs.
    pub start_us: u64,
    /// µs.
    pub end_us: u64,
}

/// A time interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Interval {
    /// µs.
    pub start_us: u64,
    /// µs.
    pub end_us: u64,
}

/// Motion statistics (`null` when the log lacks what they come from).
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Motion {
    /// Path length, m: the 3-D distance between consecutive finite positions (not across
    /// time that runs back, in a damaged log or logs joined; the armed time's, not across
    /// a disarmed stretch).
    pub total_distance_m: Option<f64>,
    /// Highest minus lowest altitude, m.
    pub max_altitude_diff_m: Option<f64>,
    /// Largest 3-D speed, m/s.
    pub max_speed_m_s: Option<f64>,
    /// Largest horizontal speed, m/s.
    pub max_horizontal_speed_m_s: Option<f64>,
    /// Largest climb rate, m/s.
    pub max_speed_up_m_s: Option<f64>,
    /// Largest sink rate, m/s.
    pub max_speed_down_m_s: Option<f64>,
    /// Mean 3-D speed, m/s.
    pub avg_speed_m_s: Option<f64>,
    /// Largest tilt from level, degrees: `acos(1 - 2 (q1² + q2²) / |q|²)` of
    /// `vehicle_attitude.q` (a quaternion not of unit length stands for the rotation of the
    /// unit one along it; an all-zero one is skipped).
    pub max_tilt_deg: Option<f64>,
    /// Largest rotation rate, deg/s.
    pub max_rotation_speed_deg_s: Option<f64>,
}

/// Motion statistics over the whole log (flight-review-rs's `stats`) and restricted to the
/// armed time.
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Stats {
    /// Over every row.
    #[cfg_attr(feature = "serde", serde(flatten))]
    pub all: Motion,
    /// Over the rows while armed.
    pub armed: Motion,
}

/// One battery instance.
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct BatteryInstance {
    /// The instance.
    pub multi_id: u8,
    /// Mean current over valid readings, A.
    pub avg_current_a: Option<f64>,
    /// Largest current, A.
    pub max_current_a: Option<f64>,
    /// Charge drawn (the last valid reading), mAh; `None` also for a charge of 0 when no
    /// current reading was valid (PX4 integrates the charge from the current, and without a
    /// current sensor writes a charge of 0 throughout).
    pub discharged_mah: Option<f64>,
    /// Lowest voltage, V.
    pub min_voltage_v: Option<f64>,
    /// Cells: from the parameters (`BAT1_N_CELLS`...) or the `cell_count` field, else
    /// estimated from the highest voltage.
    pub cells: Option<u32>,
}

/// The batteries: instance 0's facts at the top (flight-review-rs's keys), every instance
/// in `instances`.
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Battery {
    /// Instance 0's mean current, A.
    pub avg_current_a: Option<f64>,
    /// Instance 0's largest current, A.
    pub max_current_a: Option<f64>,
    /// Instance 0's charge drawn, mAh.
    pub discharged_mah: Option<f64>,
    /// Instance 0's lowest voltage, V.
    pub min_voltage_v: Option<f64>,
    /// Every instance.
    pub instances: Vec<BatteryInstance>,
}

/// GPS quality (of the GPS topic's instance 0).
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct GpsQuality {
    /// Fewest satellites used.
    pub min_satellites: Option<u32>,
    /// Most satellites used.
    pub max_satellites: Option<u32>,
    /// Largest horizontal dilution of precision (over rows with a 3-D fix).
    pub max_hdop: Option<f64>,
    /// Largest horizontal position accuracy, m (over rows with a 3-D fix).
    pub max_eph_m: Option<f64>,
    /// Largest vertical position accuracy, m (over rows with a 3-D fix).
    pub max_epv_m: Option<f64>,
    /// Every `fix_type` seen, ascending.
    pub fix_types_seen: Vec<u8>,
    /// Largest `jamming_indicator` (0–255), where the topic has it.
    pub max_jamming_indicator: Option<f64>,
    /// Largest `noise_per_ms`, where the topic has it.
    pub max_noise_per_ms: Option<f64>,
    /// Every `jamming_state` seen (1 ok, 2 warning, 3 critical), where the topic has it.
    pub jamming_states_seen: Vec<u8>,
}

/// One IMU's vibration.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ImuVibration {
    /// The `vehicle_imu_status` instance.
    pub multi_id: u8,
    /// Mean, m/s².
    pub mean: f64,
    /// Largest, m/s².
    pub max: f64,
    /// `good`, `warning` or `critical`.
    pub status: String,
}

/// Vibration: every IMU pooled at the top (flight-review-rs's keys), each in `imus`. The
/// status is the worse of the mean's (good below 4.905 m/s², critical from 9.81) and the
/// largest value's (good below 9.81, critical from 19.62), PX4's thresholds.
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Vibration {
    /// Mean over every IMU, m/s².
    pub accel_vibe_mean: Option<f64>,
    /// Largest of every IMU, m/s².
    pub accel_vibe_max: Option<f64>,
    /// `good`, `warning`, `critical`, or empty without data.
    pub status: String,
    /// Every IMU.
    pub imus: Vec<ImuVibration>,
}

/// A parameter whose value is not the default the log gives.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct NonDefault {
    /// The parameter.
    pub name: String,
    /// Its value at the start (initial).
    pub value: f64,
    /// Its default (the system default, else the configuration's).
    pub default: f64,
}

/// A point of the GPS track.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct TrackPoint {
    /// Degrees north.
    pub lat_deg: f64,
    /// Degrees east.
    pub lon_deg: f64,
    /// Meters above mean sea level.
    pub alt_m: f64,
    /// µs.
    pub timestamp_us: u64,
    /// The flight mode (`nav_state`) then, if known.
    pub mode_id: Option<u8>,
}

/// One numeric field's statistics over one topic instance.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct FieldStat {
    /// The topic.
    pub topic: String,
    /// The instance.
    pub multi_id: u8,
    /// pyulog's field name (`q[0]`, `esc[3].esc_rpm`).
    pub field: String,
    /// Smallest finite value.
    pub min: f64,
    /// Largest finite value.
    pub max: f64,
    /// Mean of the finite values.
    pub mean: f64,
    /// Finite values.
    pub count: u64,
}

/// One axis's step response (see `spectral::StepResponse` in the source for the method).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct AxisResponse {
    /// `roll`, `pitch` or `yaw`.
    pub axis: String,
    /// The rate of the resampled signals, Hz.
    pub sample_rate_hz: f64,
    /// Time after the step, s.
    pub time_s: Vec<f64>,
    /// The response to setpoints up to 500 deg/s (1 is the setpoint).
    pub response: Option<Vec<f64>>,
    /// Windows averaged into it.
    pub window_count: usize,
    /// The response to setpoints above 500 deg/s, if there were enough.
    pub response_high: Option<Vec<f64>>,
    /// Windows averaged into that.
    pub window_count_high: usize,
}

/// A power spectral density of one sensor axis, in flight.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct SpectrumOf {
    /// `gyro` or `accel`.
    pub sensor: String,
    /// `x`, `y` or `z`.
    pub axis: String,
    /// The sensor's rate, Hz.
    pub sample_rate_hz: f64,
    /// Segments averaged.
    pub segments: usize,
    /// Frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// Densities: (rad/s)²/Hz for the gyro, (m/s²)²/Hz for the accelerometer.
    pub psd: Vec<f64>,
}

/// A fact the log could not give.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Missing {
    /// Which (`flight_modes`, `stats`, `battery`...).
    pub fact: String,
    /// Why: the topic or field it lacks, or the damage that hid it.
    pub reason: String,
}

/// A format's fields by name, made at the first question (a topic no consumer reads is
/// never indexed: a crafted log of many formats of 65,000 fields would take seconds).
pub(crate) struct LazyIndex<'s> {
    schema: &'s crate::schema::Schema,
    id: crate::schema::FormatId,
    made: std::cell::OnceCell<Option<std::sync::Arc<crate::columns::FieldIndex>>>,
}

impl LazyIndex<'_> {
    /// The leaf of a field (pyulog's name: `q[0]`, `esc[3].esc_rpm`).
    pub(crate) fn get(&self, name: &str) -> Option<crate::columns::Leaf> {
        self.made
            .get_or_init(|| {
                crate::columns::FieldIndex::of(self.schema, self.id).map(std::sync::Arc::new)
            })
            .as_ref()?
            .get(name)
    }
}

/// Most fields of the field indexes an [`Analyzer`] keeps for the formats it has seen
/// (about 100 bytes each); PX4's logs have a few thousand.
const MAX_INDEXED: usize = 200_000;

/// The analysis's consumers, fed the rows of one pass in file order: made empty
/// ([`Analyzer::new`]), given every event or row with the metadata read so far
/// ([`Analyzer::event`], [`Analyzer::row`]; the first row's metadata gives the initial
/// parameters), then [`Analyzer::finish`]ed.
#[derive(Default)]
pub struct Analyzer {
    state: state::FlightState,
    modes: modes::Modes,
    motion: motion::MotionStats,
    sensors: sensors::Sensors,
    fields: fields::FieldStats,
    diagnostics: diagnostics::Diagnostics,
    steps: motion::Steps,
    spectra: motion::Spectra,
    /// Per subscription: its topics' fields, bound at its first row.
    routes: Vec<Option<Box<Route>>>,
    /// Per subscription: 0 until its route is made, then 1 + whether any consumer takes
    /// its rows (one byte to look at for the rows no consumer wants).
    wanted: Vec<u8>,
    /// The field index of each format a route was made for: the instances of a format
    /// share it (made once, not once per instance: a format of 65,000 fields in 256
    /// instances took seconds).
    indexes: std::collections::HashMap<
        crate::schema::FormatId,
        std::sync::Arc<crate::columns::FieldIndex>,
    >,
    /// The fields of the indexes kept ([`MAX_INDEXED`]).
    indexed: usize,
    /// Bytes the reader skipped as damaged.
    damaged_bytes: u64,
    /// Whether the initial parameters were read (at the first row).
    started: bool,
    /// The consumers it runs.
    parts: Parts,
    /// The last row's time.
    last_timestamp: u64,
}

impl std::fmt::Debug for Analyzer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Analyzer").finish_non_exhaustive()
    }
}

/// Which consumers take a subscription's rows, and where their fields are.
struct Route {
    state: Option<state::Fields>,
    motion: Option<motion::Fields>,
    sensors: Option<sensors::Fields>,
    diagnostics: Option<diagnostics::Fields>,
    steps: Option<motion::SpectralFields>,
    spectra: Option<motion::SpectralFields>,
    fields: Option<usize>,
}

/// Which consumers an analyzer runs: all but the per-field statistics where those are taken
/// elsewhere (on another thread in [`Analysis::of_bytes`], from the columns in a conversion
/// to Parquet) and merged into its analysis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Parts {
    /// Modes, sensors, diagnostics, parameters.
    core: bool,
    /// Motion statistics.
    motion: bool,
    /// Step responses.
    steps: bool,
    /// Spectra.
    spectra: bool,
    /// Per-field statistics.
    fields: bool,
}

impl Default for Parts {
    fn default() -> Parts {
        Parts {
            core: true,
            motion: true,
            steps: true,
            spectra: true,
            fields: true,
        }
    }
}

impl Analyzer {
    /// An analyzer that has seen nothing.
    #[must_use]
    pub fn new() -> Analyzer {
        Analyzer::default()
    }

    /// An analyzer without the per-field statistics, which its caller takes from columns it
    /// makes anyway ([`Analyzer::finish_with_columns`]).
    #[cfg(feature = "parquet")]
    pub(crate) fn without_field_stats() -> Analyzer {
        Analyzer::of_parts(Parts {
            fields: false,
            ..Parts::default()
        })
    }

    /// [`Analyzer::finish`], the per-field statistics those of `columns`.
    #[cfg(feature = "parquet")]
    pub(crate) fn finish_with_columns(
        mut self,
        meta: &Metadata,
        columns: Vec<fields::ColumnStats>,
    ) -> Analysis {
        self.parts.fields = true;
        self.fields = fields::FieldStats::from_columns(columns);
        self.finish(meta)
    }

    /// An analyzer running only `parts`.
    fn of_parts(parts: Parts) -> Analyzer {
        Analyzer {
            parts,
            ..Analyzer::default()
        }
    }

    /// Takes one event of a pass over a log, in file order.
    #[inline]
    pub fn event(&mut self, meta: &Metadata, event: &Event<'_>) {
        match event {
            Event::Row(row) => self.row(meta, row),
            Event::Diagnostic(d) => self.diagnostic(d),
            _ => {}
        }
    }

    /// Takes a diagnostic of the pass (the analysis says how many bytes were damaged).
    pub(crate) fn diagnostic(&mut self, d: &crate::Diagnostic) {
        if let Some(r) = d.damaged_range() {
            self.damaged_bytes += r.end - r.start;
        }
    }

    /// Takes one row, in file order.
    #[inline(always)]
    pub fn row(&mut self, meta: &Metadata, row: &Row<'_>) {
        if !self.started {
            self.started = true;
            self.state.start(meta);
            self.diagnostics.start(meta);
        }
        let i = row.subscription.index();
        // The log's end: its last row (a topic whose timestamp means something else,
        // as `mission`'s, would stretch a maximum).
        self.last_timestamp = row.timestamp;
        // Only this much is inlined where rows are walked (most rows are of topics no
        // analysis reads): the rest is a call, so that the walk's loop stays small.
        match self.wanted.get(i) {
            Some(1) => {}
            Some(2) => self.routed(i, row),
            _ => self.first_row(i, row),
        }
    }

    /// Decides at a subscription's first row where its rows go, and takes the row there.
    #[cold]
    #[inline(never)]
    fn first_row(&mut self, i: usize, row: &Row<'_>) {
        if self.routes.len() <= i {
            self.routes.resize_with(i + 1, || None);
            self.wanted.resize(i + 1, 0);
        }
        let route = self.route(row.subscription, row.schema());
        let any = route.state.is_some()
            || route.fields.is_some()
            || route.motion.is_some()
            || route.sensors.is_some()
            || route.diagnostics.is_some()
            || route.steps.is_some()
            || route.spectra.is_some();
        self.wanted[i] = 1 + u8::from(any);
        self.routes[i] = Some(Box::new(route));
        if any {
            self.routed(i, row);
        }
    }

    /// Takes a row of subscription `i` into each analysis its route names.
    #[inline(never)]
    fn routed(&mut self, i: usize, row: &Row<'_>) {
        let route = self.routes[i].as_deref().expect("made with its byte");
        let t = row.timestamp;
        if let Some(f) = &route.state {
            self.state.row(f, row.data, t, &mut self.modes);
        }
        if let Some(k) = route.fields {
            self.fields.row(k, row.data);
        }
        if let Some(f) = &route.motion {
            self.motion.row(f, row.data, t, &self.state);
        }
        if let Some(f) = &route.sensors {
            self.sensors.row(f, row.data, t, &self.state);
        }
        if let Some(f) = &route.diagnostics {
            self.diagnostics.row(f, row.data, t, &self.state);
        }
        if let Some(f) = &route.steps {
            self.steps.row(f, row.data, t, &self.state);
        }
        if let Some(f) = &route.spectra {
            self.spectra.row(f, row.data, t, &self.state);
        }
    }

    fn route(&mut self, sub: &Subscription, schema: &crate::schema::Schema) -> Route {
        let Some(id) = sub.format() else {
            return Route {
                state: None,
                motion: None,
                sensors: None,
                diagnostics: None,
                steps: None,
                spectra: None,
                fields: None,
            };
        };
        // Made when a consumer asks for a field of a topic it reads, not for every topic.
        let index = LazyIndex {
            schema,
            id,
            made: std::cell::OnceCell::new(),
        };
        if let Some(kept) = self.indexes.get(&id) {
            let _ = index.made.set(Some(kept.clone()));
        }
        let name = sub.name.as_str();
        let Parts {
            core,
            motion,
            steps,
            spectra,
            fields,
        } = self.parts;
        let spectral = || motion::SpectralFields::bind(name, &index);
        let route = Route {
            state: if core || motion || steps || spectra {
                state::Fields::bind(name, &index)
            } else {
                None
            },
            motion: motion.then(|| motion::Fields::bind(name, &index)).flatten(),
            sensors: core
                .then(|| sensors::Fields::bind(name, sub.multi_id, &index))
                .flatten(),
            diagnostics: core
                .then(|| diagnostics::Fields::bind(name, sub.multi_id, &index))
                .flatten(),
            steps: steps.then(spectral).flatten(),
            spectra: spectra.then(spectral).flatten(),
            fields: if fields {
                self.fields.bind(sub, schema)
            } else {
                None
            },
        };
        // Kept for the format's other instances while the kept ones are few (a bound on
        // memory for a log of very wide formats, each then made for its instance alone).
        if let Some(Some(made)) = index.made.get()
            && !self.indexes.contains_key(&id)
            && self.indexed.saturating_add(made.len()) <= MAX_INDEXED
        {
            self.indexed += made.len();
            self.indexes.insert(id, made.clone());
        }
        route
    }

    /// The analysis, with what the log's metadata adds (parameters, defaults).
    pub fn finish(mut self, meta: &Metadata) -> Analysis {
        let end = self.last_timestamp;
        self.modes.sort_changes();
        let mut missing = Vec::new();
        let mut a = Analysis::default();
        if self.parts.core {
            (a.flight_modes, a.vtol_states, a.armed, a.flights) =
                self.modes.finish(end, &self.state, &mut missing);
        }
        if self.parts.motion {
            a.stats = self.motion.finish(&mut missing);
        }
        if self.parts.core {
            (a.battery, a.gps_quality, a.vibration, a.gps_track) =
                self.sensors.finish(meta, &self.modes, &mut missing);
            a.diagnostics = self.diagnostics.finish(end, &mut missing);
            a.non_default_params = params::non_default(meta, &mut missing);
            if self.damaged_bytes > 0 {
                missing.push(Missing {
                    fact: "every fact".to_owned(),
                    reason: format!(
                        "{} damaged bytes of the log were skipped: the rows in them are not \
                         counted",
                        self.damaged_bytes
                    ),
                });
            }
        }
        if self.parts.steps {
            a.step_response = self.steps.finish(&mut missing);
        }
        if self.parts.spectra {
            a.spectra = self.spectra.finish(&mut missing);
        }
        if self.parts.fields {
            a.field_stats = self.fields.finish(&mut missing);
        }
        a.missing = missing;
        a
    }
}

impl Analysis {
    /// The analysis of a log read as a stream (one pass, memory bounded by the analysis,
    /// not by the log).
    pub fn of_reader(input: impl Read) -> Result<Analysis, ReadError> {
        let mut reader = StreamReader::new(input)?;
        let mut analyzer = Analyzer::new();
        reader.for_each_message(|meta, event, _| {
            analyzer.event(meta, &event);
            Ok::<(), ReadError>(())
        })?;
        Ok(analyzer.finish(reader.metadata()))
    }

    /// The analysis of a whole-file log: the same as [`Analysis::of_reader`] gives, in
    /// the passes of [`Analysis::of_bytes`] over the log's bytes.
    pub fn of_log(log: &Log<'_>) -> Analysis {
        // The bytes were read once as a log: they walk again the same way.
        Analysis::of_bytes(log.bytes()).unwrap_or_else(|e| Analysis {
            missing: vec![Missing {
                fact: "every fact".to_owned(),
                reason: e.to_string(),
            }],
            ..Analysis::default()
        })
    }

    /// The analysis of a whole file's bytes (a memory map, say): the same as
    /// [`Analysis::of_reader`] gives, without a row index. On a machine of more than one
    /// core, the per-field statistics are taken on another thread, in a walk of their own
    /// beside the one of the other analyses (about as much work each: on a 400 MB log,
    /// moving the motion statistics from the fields' walk to the other one took a seventh
    /// off the wall time).
    ///
    /// ```no_run
    /// # fn main() -> Result<(), ulog_runtime::ReadError> {
    /// use ulog_runtime::{analysis::Analysis, read::MappedFile};
    /// let file = MappedFile::open("flight.ulg")?;
    /// let analysis = Analysis::of_bytes(&file)?;
    /// println!("{} flight modes", analysis.flight_modes.len());
    /// # Ok(()) }
    /// ```
    pub fn of_bytes(bytes: &[u8]) -> Result<Analysis, ReadError> {
        let single = std::thread::available_parallelism().map_or(1, NonZero::get) < 2;
        let (summary, mut analyzer) = if single {
            visit_rows(bytes, Analyzer::new(), 1)?
        } else {
            let rest = Parts {
                fields: false,
                ..Parts::default()
            };
            let (rest, beside) = std::thread::scope(|s| {
                let beside = s.spawn(|| visit_rows(bytes, fields::FieldStats::default(), 1));
                let rest = visit_rows(bytes, Analyzer::of_parts(rest), 1);
                (
                    rest,
                    beside
                        .join()
                        .unwrap_or_else(|p| std::panic::resume_unwind(p)),
                )
            });
            let (summary, mut analyzer) = rest?;
            let (_, beside) = beside?;
            analyzer.parts.fields = true;
            analyzer.fields = beside;
            (summary, analyzer)
        };
        for d in &summary.diagnostics {
            analyzer.diagnostic(d);
        }
        Ok(analyzer.finish(&summary.metadata))
    }
}

/// A walk's rows to an analyzer, on one thread (its consumers need the rows in file order).
/// Only an analyzer of the per-field statistics alone could be walked in parts on several
/// threads (`fork`, `append`); [`Analysis::of_bytes`] walks `fields::FieldStats` itself.
impl RowVisitor for Analyzer {
    #[inline]
    fn row(&mut self, meta: &Metadata, row: &Row<'_>) {
        Analyzer::row(self, meta, row);
    }

    fn fork(&self) -> Analyzer {
        Analyzer::of_parts(self.parts)
    }

    fn append(&mut self, other: Analyzer) {
        debug_assert!(
            !self.parts.core && !self.parts.motion && !self.parts.steps && !self.parts.spectra,
            "only the per-field statistics are taken in parts"
        );
        self.fields.merge(other.fields);
        self.damaged_bytes += other.damaged_bytes;
        self.last_timestamp = self.last_timestamp.max(other.last_timestamp);
    }
}

#[cfg(test)]
pub(crate) mod tests;
