//! Anonymizing a log ([`Anonymize`]): where it was flown, when, and by which vehicle.
//!
//! - **Positions.** Every latitude/longitude pair of every topic (found by field name and
//!   type, nested types included) goes through one rotation of the sphere that takes the
//!   log's reference point (its first valid position) to the target. A rotation keeps every
//!   great-circle distance and angle, so tracks keep their shape, size and headings (north
//!   stays north at the reference). Values are stored back at the field's own resolution:
//!   `int32_t` 1e-7° fields move by at most half a step (0.56 cm). Absolute altitudes (AMSL
//!   and ellipsoid, barometric included) move by one offset.
//! - **Times.** UTC times and a clock that is an absolute date (the header's start, and then
//!   every time field and logged string of the log) move by one offset (unless
//!   `keep_time`); dates and times in text and the log file's date in PX4's
//!   `logger_open_file_time` event move or become zeros.
//! - **Identifiers.** `sys_uuid`, the boot console output (with the board's GUID), hard
//!   fault dumps, serial numbers, addresses and other aircraft's ids are left out or made
//!   zeros, and topics of raw bytes that embed positions (receiver traffic, corrections,
//!   streams) are dropped.
//!
//! `rules` lists every field, topic, key and parameter; geometry and dates are in
//! `geo`, free text in `text`.

mod geo;
mod rules;
mod text;

use crate::read::{KeyValue, Message, Metadata, Subscription};
use crate::schema::{Primitive, Schema};
use crate::value::{Scalar, Value};

use super::RewriteError;
use crate::columns::{FieldIndex, Leaf};
use geo::Rotation;

/// Where the positions of an anonymized log go.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// The log's reference point (its first valid position) goes to this latitude and
    /// longitude (degrees); the altitude and time offsets are drawn from the two.
    Origin {
        /// Degrees north.
        lat: f64,
        /// Degrees east.
        lon: f64,
    },
    /// A place, an altitude offset and a time offset drawn from this seed: the same seed
    /// gives the same transform.
    Seed(u64),
}

/// The anonymizing rule set ([`Rewrite::anonymize`](super::Rewrite::anonymize), `ulog
/// anonymize`), as the [module docs](self) say. What it changes, in any topic and nested
/// type (pyulog's field names):
///
/// | what | fields | how |
/// |---|---|---|
/// | positions | pairs `lat`/`lon` as a word of the name (`lat`, `ref_lat`, `lat_est`), `latitude`/`longitude` (`latitude_deg`, `operator_latitude`), of `int32_t` (1e-7°), `float` or `double` (°); `observation[0..2]` of `estimator_aid_src_{gnss_pos,fake_pos,aux_global_position}`; `x`/`y` of `orbit_status` (frame 0) and `figure_eight_status` (frame 5); `param5`/`param6` of `vehicle_command`, `gimbal_v1_command`, `vehicle_command_mode_executor` for the MAVLink commands that carry a position | one rotation of the sphere |
/// | altitudes | `alt`, `alt_ellipsoid`, `terrain_alt`, `pressure_alt`, `ref_alt`, `altitude_msl_m`, `altitude_ellipsoid_m`, `baro_alt_meter`, `baro1_alt_meter`, `alt_est`, `operator_altitude_geo`, `altitudeSp`; `tecs_status.altitude_{sp,reference,filtered}`, `transponder_report.altitude`, `sensor_baro.altitude`, `fixed_wing_longitudinal_setpoint.altitude`, `orbit_status.z`, `figure_eight_status.z`, `navigator_mission_item.altitude` (when not relative), the commands' `param7`; `observation` of `estimator_aid_src_{baro,gnss,fake}_hgt` (minus the altitude) | one offset (m; `int32_t` in mm) |
/// | UTC times | `time_utc_usec`, `timestamp_utc`, `rtc_timestamp`, `remote_timestamp`; info `boot_time_utc_us`, `time_start_utc`; with an absolute clock (header at or after 2000) also every `uint64_t` time field (`timestamp*`, `*_timestamp`, `time_*`, `*_time`, not `*_relative`) at or after 2000, and logged strings' times | one offset (0 stays 0) |
/// | identifiers | `battery_status.{serial_number,manufacture_date}`, `transponder_report.{icao_address,callsign,uas_id}`, `sensor_uwb.{mac,mac_dest,sessionid}` | zeros |
/// | events | `logger_open_file_time` (the date), `vrtl_return_at` and `rtl_mission_land_climb` (an altitude), `navigator_traffic*` (an ICAO address) | moved, or zeros |
/// | text | logged strings, `log_message.text`, `mavlink_log.text`: log file paths, dates, times of day, `PX4GUID`, the log's `sys_uuid`, IPv4 and MAC addresses, serial numbers; the altitude in `RTL: start return at N m` | zeros, `log.ulg`, moved |
/// | topics dropped | `gps_dump`, `gps_inject_data`, `ulog_stream`, `ulog_stream_ack`, `mavlink_tunnel`, `esc_serial_passthru`, `dataman_request`, `dataman_response`, `voxl2_io_data`, `qshell_req`, `satellite_info`, `cellular_status`, `open_drone_id_{operator_id,self_id,arm_status}`, `device_information`, `battery_info`, `gimbal_device_information` | not written |
/// | info | `sys_uuid`, `replay` left out; `time_ref_utc` (the time zone) 0 | |
/// | multi info | all but `metadata_events`, `excluded_optional_topics`, `perf_counter_*`, `perf_top_*` left out (the boot console output names the board, its GUID and log paths; hard fault logs dump memory) | |
/// | parameters | `LPE_LAT`, `LPE_LON`, `NAV_AH_{LAT,LON,ALT}`, `NAV_DLL_CH_{LAT,LON,ALT}`, `EKF2_MAG_DECL`, `SDLOG_UTC_OFFSET`, `COM_FLIGHT_UUID`, `LND_FLIGHT_T_{HI,LO}` (initial, changed, defaults) | 0 |
///
/// A latitude and longitude of 0 (no fix), values that are not finite, and positions
/// within 0.001° of 0,0 in the estimator's aid sources (no origin) stay as they are.
///
/// Not changed, and still hinting at a place: the geoid separation (ellipsoid minus MSL
/// altitude), magnetic field values, barometric pressure, the local positions (meters
/// from the reference), coordinates written as text in logged messages (`Home: lat
/// 47.3977419 lon 8.5455938`: a number in text is not known to be a coordinate; dates,
/// times, paths, GUIDs and addresses in text are zeroed) and what other writers store
/// under names outside these rules.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Anonymize {
    /// Where positions go.
    pub target: Target,
    /// Keep absolute times as they are.
    pub keep_time: bool,
}

impl Anonymize {
    /// Positions to a place drawn from `seed`, times shifted.
    pub fn seed(seed: u64) -> Anonymize {
        Anonymize {
            target: Target::Seed(seed),
            keep_time: false,
        }
    }

    /// Positions to this latitude and longitude, times shifted.
    pub fn origin(lat: f64, lon: f64) -> Anonymize {
        Anonymize {
            target: Target::Origin { lat, lon },
            keep_time: false,
        }
    }
}

/// What anonymizing changed ([`Report::anonymized`](super::Report::anonymized)).
#[derive(Debug, Clone, Default, PartialEq)]
#[non_exhaustive]
pub struct Anonymized {
    /// Where the log's reference point went (degrees), once it had one.
    pub target: Option<(f64, f64)>,
    /// Meters added to every absolute altitude.
    pub altitude_offset_m: f64,
    /// Microseconds added to every UTC time (0 with `keep_time`).
    pub time_offset_us: i64,
    /// Whether the log's clock is an absolute date (then every time moved).
    pub absolute_clock: bool,
    /// Every field changed: topic, field (pyulog's name), rows.
    pub fields: Vec<(String, String, usize)>,
    /// Parameters written as 0 (initial, changed and default values).
    pub parameters: Vec<String>,
}

/// 2000-01-01 in µs: times before are boot times (or 0, unknown).
const Y2000_US: u64 = 946_684_800_000_000;

/// SplitMix64: the seed's stream of numbers.
struct Mix(u64);

impl Mix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// How a value of a position or altitude field is stored.
#[derive(Debug, Clone, Copy)]
enum Stored {
    /// `int32_t`: 1e-7 degrees (positions) or millimeters (altitudes).
    Scaled(usize, f64),
    /// A float or double in degrees or meters.
    Float(usize, Primitive),
}

impl Stored {
    fn of(leaf: Leaf, int_scale: f64) -> Option<Stored> {
        match leaf {
            Leaf::Value(at, Primitive::Int32) => Some(Stored::Scaled(at, int_scale)),
            Leaf::Value(at, p @ (Primitive::Float | Primitive::Double)) => {
                Some(Stored::Float(at, p))
            }
            _ => None,
        }
    }

    fn read(self, row: &[u8]) -> Option<f64> {
        match self {
            Stored::Scaled(at, scale) => {
                Some(f64::from(i32::from_le_bytes(row.get(at..at + 4)?.try_into().ok()?)) * scale)
            }
            Stored::Float(at, p) => {
                Scalar::decode(p, row.get(at..at + p.size())?).map(Scalar::as_f64)
            }
        }
    }

    /// Writes `v`; false if it does not fit (`int32_t` out of range).
    #[allow(clippy::cast_possible_truncation)]
    fn write(self, row: &mut [u8], v: f64) -> bool {
        let (at, bytes): (usize, Vec<u8>) = match self {
            Stored::Scaled(at, scale) => {
                let raw = (v / scale).round();
                if !(f64::from(i32::MIN)..=f64::from(i32::MAX)).contains(&raw) {
                    return false;
                }
                (at, (raw as i32).to_le_bytes().to_vec())
            }
            Stored::Float(at, Primitive::Float) => (at, (v as f32).to_le_bytes().to_vec()),
            Stored::Float(at, _) => (at, v.to_le_bytes().to_vec()),
        };
        match row.get_mut(at..at + bytes.len()) {
            Some(d) => {
                d.copy_from_slice(&bytes);
                true
            }
            None => false,
        }
    }
}

/// When a field holds what its rule says.
#[derive(Debug, Clone, Copy)]
enum When {
    Always,
    /// This field's value is one of the position commands.
    Command(Leaf),
    /// This field's value equals this (a frame, a "relative" flag).
    Equals(Leaf, f64),
}

impl When {
    fn holds(self, row: &[u8]) -> bool {
        let value = |leaf: Leaf| match leaf {
            Leaf::Value(at, p) => row
                .get(at..at + p.size())
                .and_then(|b| Scalar::decode(p, b))
                .map(Scalar::as_f64),
            Leaf::Text(..) => None,
        };
        match self {
            When::Always => true,
            #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
            When::Command(leaf) => value(leaf)
                .is_some_and(|c| rules::POSITION_COMMANDS.contains(&(c as u32)) && c >= 0.0),
            When::Equals(leaf, v) => value(leaf) == Some(v),
        }
    }
}

struct Pair {
    lat: Stored,
    lon: Stored,
    when: When,
    /// Positions near 0,0 are "no origin" (the estimator's aid sources).
    skip_near_zero: bool,
    slot: usize,
}

struct Altitude {
    stored: Stored,
    /// -1 for a field that holds minus the altitude.
    sign: f64,
    when: When,
    slot: usize,
}

/// Where an `event` row's id and arguments are.
#[derive(Debug, Clone, Copy)]
struct EventFields {
    id: usize,
    args: usize,
    len: usize,
}

/// The fields of one subscription to change, and per field the rows changed.
struct Plan {
    topic: String,
    pairs: Vec<Pair>,
    altitudes: Vec<Altitude>,
    /// UTC times: offset, slot.
    utc: Vec<(usize, usize)>,
    /// Time fields of an absolute clock: offset, slot.
    clock: Vec<(usize, usize)>,
    /// Bytes made zeros: offset, length, slot.
    zeros: Vec<(usize, usize, usize)>,
    /// `char[N]` sentences: offset, length, slot.
    texts: Vec<(usize, usize, usize)>,
    event: Option<(EventFields, usize)>,
    /// Field names (for the report) and rows changed.
    names: Vec<(String, usize)>,
}

impl Plan {
    fn slot(&mut self, name: &str) -> usize {
        self.names.push((name.to_owned(), 0));
        self.names.len() - 1
    }

    fn is_empty(&self) -> bool {
        self.pairs.is_empty()
            && self.altitudes.is_empty()
            && self.utc.is_empty()
            && self.clock.is_empty()
            && self.zeros.is_empty()
            && self.texts.is_empty()
            && self.event.is_none()
    }
}

/// The anonymizing pass's state.
pub(in crate::rewrite) struct Anonymizer {
    rules: Anonymize,
    target: (f64, f64),
    altitude_offset_m: f64,
    time_offset_us: i64,
    absolute_clock: bool,
    rotation: Option<Rotation>,
    plans: Vec<Plan>,
    /// The log's identifiers, removed from text wherever they appear.
    identifiers: Vec<String>,
    parameters: Vec<String>,
}

impl Anonymizer {
    pub(in crate::rewrite) fn new(rules: Anonymize) -> Anonymizer {
        let seed = match rules.target {
            Target::Seed(s) => s,
            Target::Origin { lat, lon } => lat.to_bits() ^ lon.to_bits().rotate_left(17),
        };
        let mut mix = Mix(seed);
        // A latitude drawn uniformly over the area between 58°S and 58°N.
        let drawn = (
            mix.uniform(-0.85, 0.85).asin().to_degrees(),
            mix.uniform(-180.0, 180.0),
        );
        let target = match rules.target {
            Target::Origin { lat, lon } => (lat, lon),
            Target::Seed(_) => drawn,
        };
        let altitude_offset_m = mix.uniform(-500.0, 500.0).round();
        // One to ten years either way.
        let years = mix.uniform(1.0, 10.0) * if mix.next() & 1 == 0 { 1.0 } else { -1.0 };
        #[allow(clippy::cast_possible_truncation)]
        let time_offset_us = if rules.keep_time {
            0
        } else {
            // Whole seconds: dates in text and events move by the same offset.
            (years * 365.25 * 86_400.0).round() as i64 * 1_000_000
        };
        Anonymizer {
            rules,
            target,
            altitude_offset_m,
            time_offset_us,
            absolute_clock: false,
            rotation: None,
            plans: Vec::new(),
            identifiers: Vec::new(),
            parameters: Vec::new(),
        }
    }

    /// Learns what the header says.
    pub(in crate::rewrite) fn start(&mut self, meta: &Metadata) {
        self.absolute_clock = !self.rules.keep_time && meta.header().start_timestamp >= Y2000_US;
    }

    fn shift_time(&self, t: u64) -> u64 {
        t.saturating_add_signed(self.time_offset_us)
    }

    /// The header's start time: moved when it is an absolute date.
    pub(in crate::rewrite) fn header_start(&self, start: u64) -> u64 {
        if self.absolute_clock {
            self.shift_time(start)
        } else {
            start
        }
    }

    pub(in crate::rewrite) fn drops_topic(&self, name: &str) -> bool {
        rules::DROPPED_TOPICS.contains(&name)
    }

    /// Sees every info value before it is written (to learn the log's identifiers).
    pub(in crate::rewrite) fn observe_info(&mut self, name: &str, kv: KeyValue<'_>) {
        if name == "sys_uuid" {
            let (text, _) = crate::read::text_of(kv.value);
            if !text.is_empty() && !self.identifiers.contains(&text) {
                self.identifiers.push(text);
            }
        }
    }

    /// Whether an info (`I`) or multi info (`M`) key is left out.
    pub(in crate::rewrite) fn drops_info(&self, name: &str, ty: u8) -> bool {
        if ty == b'M' {
            return !rules::keeps_multi_info(name);
        }
        rules::DROPPED_INFO.contains(&name)
    }

    /// A replacement for an info value, if one is needed.
    pub(in crate::rewrite) fn info(&mut self, name: &str, kv: KeyValue<'_>) -> Option<Value> {
        match name {
            "time_ref_utc" if !self.rules.keep_time => Some(Value::Scalar(Scalar::Int32(0))),
            "boot_time_utc_us" | "time_start_utc" if !self.rules.keep_time => {
                let t = u64::from_le_bytes(kv.value.get(..8)?.try_into().ok()?);
                Some(Value::Scalar(Scalar::UInt64(if t == 0 {
                    0
                } else {
                    self.shift_time(t)
                })))
            }
            _ => None,
        }
    }

    /// A parameter (`P`) or default parameter (`Q`) message with its value made 0, if its
    /// parameter is one the rules zero.
    pub(in crate::rewrite) fn parameter(&mut self, ty: u8, payload: &[u8]) -> Option<Vec<u8>> {
        let kv = match Message::parse(ty, payload) {
            Ok(Message::Parameter(kv)) => kv,
            Ok(Message::DefaultParameter { entry, .. }) => entry,
            _ => return None,
        };
        let name = crate::read::key_name(kv);
        if !rules::ZEROED_PARAMETERS.contains(&name.as_str()) || kv.value.iter().all(|&b| b == 0) {
            return None;
        }
        if !self.parameters.contains(&name) {
            self.parameters.push(name);
        }
        let mut out = payload.to_vec();
        let n = kv.value.len();
        let len = out.len();
        out[len - n..].fill(0);
        Some(out)
    }

    pub(in crate::rewrite) fn prepare(
        &mut self,
        schema: &Schema,
        sub: &Subscription,
    ) -> Result<Option<usize>, RewriteError> {
        let Some(index) = sub.format().and_then(|id| FieldIndex::of(schema, id)) else {
            return Ok(None);
        };
        let topic = sub.name.as_str();
        let mut plan = Plan {
            topic: topic.to_owned(),
            pairs: Vec::new(),
            altitudes: Vec::new(),
            utc: Vec::new(),
            clock: Vec::new(),
            zeros: Vec::new(),
            texts: Vec::new(),
            event: None,
            names: Vec::new(),
        };
        let field = |name: &str| index.get(name);
        // Conditions of the rules that depend on another field of the row.
        let command = rules::COMMAND_TOPICS
            .contains(&topic)
            .then(|| field("command"))
            .flatten();
        let frame = rules::FRAMED_POSITIONS
            .iter()
            .find(|(t, _)| *t == topic)
            .and_then(|&(_, v)| Some(When::Equals(field("frame")?, f64::from(v))));
        if let Some(when) = frame
            && let (Some(x), Some(y)) = (field("x"), field("y"))
            && let (Some(lat), Some(lon)) = (Stored::of(x, 1e-7), Stored::of(y, 1e-7))
        {
            let slot = plan.slot("x/y");
            plan.pairs.push(Pair {
                lat,
                lon,
                when,
                skip_near_zero: false,
                slot,
            });
        }
        if rules::OBSERVED_POSITIONS.contains(&topic)
            && let (Some(a @ Leaf::Value(_, Primitive::Double)), Some(b)) =
                (field("observation[0]"), field("observation[1]"))
            && let (Some(lat), Some(lon)) = (Stored::of(a, 1e-7), Stored::of(b, 1e-7))
        {
            let slot = plan.slot("observation[0]/observation[1]");
            plan.pairs.push(Pair {
                lat,
                lon,
                when: When::Always,
                skip_near_zero: true,
                slot,
            });
        }
        if let Some(leaf) = command
            && let (Some(p5), Some(p6)) = (field("param5"), field("param6"))
            && let (Some(lat), Some(lon)) = (Stored::of(p5, 1e-7), Stored::of(p6, 1e-7))
        {
            let slot = plan.slot("param5/param6");
            let when = When::Command(leaf);
            plan.pairs.push(Pair {
                lat,
                lon,
                when,
                skip_near_zero: false,
                slot,
            });
            if let Some(stored) = field("param7").and_then(|l| Stored::of(l, 1e-3)) {
                let slot = plan.slot("param7");
                plan.altitudes.push(Altitude {
                    stored,
                    sign: 1.0,
                    when,
                    slot,
                });
            }
        }
        if rules::NEGATED_ALTITUDE_TOPICS.contains(&topic)
            && let Some(stored) = field("observation").and_then(|l| Stored::of(l, 1e-3))
        {
            let slot = plan.slot("observation");
            plan.altitudes.push(Altitude {
                stored,
                sign: -1.0,
                when: When::Always,
                slot,
            });
        }
        if topic == "navigator_mission_item"
            && let Some(stored) = field("altitude").and_then(|l| Stored::of(l, 1e-3))
        {
            let when = field("altitude_is_relative").map_or(When::Always, |l| When::Equals(l, 0.0));
            let slot = plan.slot("altitude");
            plan.altitudes.push(Altitude {
                stored,
                sign: 1.0,
                when,
                slot,
            });
        }
        if topic == "event"
            && let (
                Some(Leaf::Value(id, Primitive::UInt32)),
                Some(Leaf::Value(args, Primitive::UInt8)),
            ) = (field("id"), field("arguments[0]"))
        {
            let len = (0..)
                .take_while(|k| field(&format!("arguments[{k}]")).is_some())
                .count();
            let slot = plan.slot("arguments");
            plan.event = Some((EventFields { id, args, len }, slot));
        }
        for (name, leaf) in index.iter() {
            let (prefix, base) = match name.rfind('.') {
                Some(i) => (&name[..=i], &name[i + 1..]),
                None => ("", name),
            };
            if let Some(lon_base) = rules::longitude_of(base)
                && let Some(lon_leaf) = field(&format!("{prefix}{lon_base}"))
                && let (Some(lat), Some(lon)) = (Stored::of(leaf, 1e-7), Stored::of(lon_leaf, 1e-7))
            {
                let slot = plan.slot(&format!("{name}/{prefix}{lon_base}"));
                plan.pairs.push(Pair {
                    lat,
                    lon,
                    when: When::Always,
                    skip_near_zero: false,
                    slot,
                });
                continue;
            }
            let altitude =
                rules::ALTITUDES.contains(&base) || rules::TOPIC_ALTITUDES.contains(&(topic, name));
            if altitude && let Some(stored) = Stored::of(leaf, 1e-3) {
                let slot = plan.slot(name);
                plan.altitudes.push(Altitude {
                    stored,
                    sign: 1.0,
                    when: When::Always,
                    slot,
                });
                continue;
            }
            if let Leaf::Value(at, Primitive::UInt64) = leaf
                && !self.rules.keep_time
            {
                if rules::UTC_TIMES.contains(&base) {
                    let slot = plan.slot(name);
                    plan.utc.push((at, slot));
                    continue;
                }
                if self.absolute_clock && rules::is_time_name(base) {
                    let slot = plan.slot(name);
                    plan.clock.push((at, slot));
                    continue;
                }
            }
            if rules::IDENTIFIER_FIELDS.contains(&(topic, base))
                || rules::IDENTIFIER_FIELDS.contains(&(topic, name))
            {
                let (at, len) = match leaf {
                    Leaf::Value(at, p) => (at, p.size()),
                    Leaf::Text(at, len) => (at, len),
                };
                let slot = plan.slot(name);
                plan.zeros.push((at, len, slot));
                continue;
            }
            // `uas_id[0]`, `uas_id[1]`...: array elements of an identifier.
            if let Some(array) = name.split('[').next()
                && array != name
                && rules::IDENTIFIER_FIELDS.contains(&(topic, array))
                && let Leaf::Value(at, p) = leaf
            {
                let slot = plan.slot(name);
                plan.zeros.push((at, p.size(), slot));
                continue;
            }
            if rules::TEXT_TOPICS.contains(&topic)
                && name == "text"
                && let Leaf::Text(at, len) = leaf
            {
                let slot = plan.slot(name);
                plan.texts.push((at, len, slot));
            }
        }
        if plan.is_empty() {
            return Ok(None);
        }
        self.plans.push(plan);
        Ok(Some(self.plans.len() - 1))
    }

    pub(in crate::rewrite) fn apply(&mut self, slot: usize, row: &mut [u8], _timestamp: u64) {
        let text_rules = text::TextRules {
            times: !self.rules.keep_time,
            altitude_offset_m: self.altitude_offset_m,
            identifiers: &self.identifiers,
        };
        let plan = &mut self.plans[slot];
        let changed = |plan: &mut Plan, slot: usize| plan.names[slot].1 += 1;
        for k in 0..plan.pairs.len() {
            let p = &plan.pairs[k];
            if !p.when.holds(row) {
                continue;
            }
            let (Some(lat), Some(lon)) = (p.lat.read(row), p.lon.read(row)) else {
                continue;
            };
            let valid = lat.is_finite()
                && lon.is_finite()
                && (lat != 0.0 || lon != 0.0)
                && !(p.skip_near_zero && lat.abs() < 1e-3 && lon.abs() < 1e-3)
                && lat.abs() <= 90.0
                && lon.abs() <= 360.0;
            if !valid {
                continue;
            }
            let rotation = *self
                .rotation
                .get_or_insert_with(|| Rotation::new((lat, lon), self.target));
            let (lat2, lon2) = rotation.apply(lat, lon);
            let (lat_f, lon_f, s) = (p.lat, p.lon, p.slot);
            if lat_f.write(row, lat2) && lon_f.write(row, lon2) {
                changed(plan, s);
            }
        }
        for k in 0..plan.altitudes.len() {
            let a = &plan.altitudes[k];
            if !a.when.holds(row) {
                continue;
            }
            let (stored, sign, s) = (a.stored, a.sign, a.slot);
            if let Some(alt) = stored.read(row)
                && alt.is_finite()
                && stored.write(row, alt + sign * self.altitude_offset_m)
            {
                changed(plan, s);
            }
        }
        let offset = self.time_offset_us;
        for &(at, s) in &plan.utc {
            if let Some(b) = row.get_mut(at..at + 8) {
                let t = u64::from_le_bytes(b.try_into().expect("8 bytes"));
                // 0: no time known.
                if t != 0 {
                    b.copy_from_slice(&t.saturating_add_signed(offset).to_le_bytes());
                    plan.names[s].1 += 1;
                }
            }
        }
        for &(at, s) in &plan.clock {
            if let Some(b) = row.get_mut(at..at + 8) {
                let t = u64::from_le_bytes(b.try_into().expect("8 bytes"));
                if t >= Y2000_US {
                    b.copy_from_slice(&t.saturating_add_signed(offset).to_le_bytes());
                    plan.names[s].1 += 1;
                }
            }
        }
        for &(at, len, s) in &plan.zeros {
            if let Some(b) = row.get_mut(at..at + len)
                && b.iter().any(|&x| x != 0)
            {
                b.fill(0);
                plan.names[s].1 += 1;
            }
        }
        for &(at, len, s) in &plan.texts {
            if let Some(b) = row.get_mut(at..at + len) {
                let end = b.iter().position(|&x| x == 0).unwrap_or(len);
                if let Some(new) = text::redact(&b[..end], &text_rules) {
                    let n = new.len().min(len);
                    b.fill(0);
                    b[..n].copy_from_slice(&new[..n]);
                    plan.names[s].1 += 1;
                }
            }
        }
        if let Some((e, s)) = plan.event
            && let (Some(id), Some(args)) = (
                row.get(e.id..e.id + 4)
                    .map(|b| u32::from_le_bytes(b.try_into().expect("4"))),
                row.get_mut(e.args..e.args + e.len),
            )
            && event_args(id, args, offset, self.altitude_offset_m)
        {
            plan.names[s].1 += 1;
        }
    }

    /// A logged string's message with its text anonymized, and its time moved with an
    /// absolute clock, if anything changes.
    pub(in crate::rewrite) fn logged(&mut self, ty: u8, payload: &[u8]) -> Option<Vec<u8>> {
        let Ok(Message::Logging { text: t, tag, .. }) = Message::parse(ty, payload) else {
            return None;
        };
        let rules = text::TextRules {
            times: !self.rules.keep_time,
            altitude_offset_m: self.altitude_offset_m,
            identifiers: &self.identifiers,
        };
        let redacted = text::redact(t, &rules);
        if redacted.is_none() && !self.absolute_clock {
            return None;
        }
        let head = payload.len() - t.len();
        let mut out = payload[..head].to_vec();
        if self.absolute_clock {
            // The time after the level (and the tag of a `C`).
            let at = 1 + if tag.is_some() { 2 } else { 0 };
            let time = u64::from_le_bytes(out[at..at + 8].try_into().expect("8 bytes"));
            if time >= Y2000_US {
                out[at..at + 8].copy_from_slice(&self.shift_time(time).to_le_bytes());
            }
        }
        out.extend_from_slice(redacted.as_deref().unwrap_or(t));
        (out != payload).then_some(out)
    }

    pub(in crate::rewrite) fn report(&self) -> Anonymized {
        let mut fields: Vec<(String, String, usize)> = Vec::new();
        for plan in &self.plans {
            for (name, rows) in &plan.names {
                match fields
                    .iter_mut()
                    .find(|(t, n, _)| *t == plan.topic && n == name)
                {
                    Some(f) => f.2 += rows,
                    None => fields.push((plan.topic.clone(), name.clone(), *rows)),
                }
            }
        }
        fields.retain(|f| f.2 > 0);
        Anonymized {
            target: self.rotation.map(|_| self.target),
            altitude_offset_m: self.altitude_offset_m,
            time_offset_us: self.time_offset_us,
            absolute_clock: self.absolute_clock,
            fields,
            parameters: self.parameters.clone(),
        }
    }
}

/// Changes the arguments of an event that carry a date, an altitude or an identifier;
/// whether anything changed.
fn event_args(id: u32, args: &mut [u8], time_offset_us: i64, altitude_offset_m: f64) -> bool {
    if id == rules::events::OPEN_FILE_TIME && args.len() >= 7 {
        let year = i64::from(u16::from_le_bytes([args[0], args[1]]));
        let date = (
            year,
            u32::from(args[2]),
            u32::from(args[3]),
            u32::from(args[4]),
            u32::from(args[5]),
            u32::from(args[6]),
        );
        let (y, mo, d, h, mi, s) = if (1..=12).contains(&date.1) && (1..=31).contains(&date.2) {
            geo::shift_civil(date, time_offset_us)
        } else {
            (0, 0, 0, 0, 0, 0)
        };
        let year = u16::try_from(y).unwrap_or(0);
        args[..2].copy_from_slice(&year.to_le_bytes());
        for (k, v) in [mo, d, h, mi, s].into_iter().enumerate() {
            args[2 + k] = u8::try_from(v).unwrap_or(0);
        }
        return true;
    }
    if rules::events::ALTITUDE_FIRST.contains(&id) && args.len() >= 4 {
        let alt = i32::from_le_bytes(args[..4].try_into().expect("4 bytes"));
        #[allow(clippy::cast_possible_truncation)]
        let moved = alt.saturating_add(altitude_offset_m.round() as i32);
        args[..4].copy_from_slice(&moved.to_le_bytes());
        return moved != alt;
    }
    if rules::events::ICAO_FIRST.contains(&id) && args.len() >= 4 && args[..4] != [0; 4] {
        args[..4].fill(0);
        return true;
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_carry_the_moved_date_and_altitude() {
        // 2026-03-04 11:55:42 plus a day.
        let mut args = [0u8; 25];
        args[..2].copy_from_slice(&2026u16.to_le_bytes());
        args[2..7].copy_from_slice(&[3, 4, 11, 55, 42]);
        assert!(event_args(
            rules::events::OPEN_FILE_TIME,
            &mut args,
            86_400_000_000,
            0.0
        ));
        assert_eq!(
            (u16::from_le_bytes([args[0], args[1]]), &args[2..7]),
            (2026, &[3, 5, 11, 55, 42][..])
        );
        let mut args = [0u8; 25];
        args[..4].copy_from_slice(&491i32.to_le_bytes());
        args[4..8].copy_from_slice(&3i32.to_le_bytes());
        assert!(event_args(22_161_044, &mut args, 0, 100.0));
        assert_eq!(i32::from_le_bytes(args[..4].try_into().unwrap()), 591);
        assert_eq!(
            i32::from_le_bytes(args[4..8].try_into().unwrap()),
            3,
            "relative: kept"
        );
        assert!(
            !event_args(1, &mut args, 0, 100.0),
            "other events are left alone"
        );
    }
}
