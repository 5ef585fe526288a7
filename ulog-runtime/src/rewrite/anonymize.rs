//! Anonymizing a log ([`Anonymize`]): where it was flown, when, and by which vehicle.
//!
//! - **Positions.** Every latitude/longitude pair of every topic (found by field name and
//!   type, nested types included: see [`Anonymize`]) goes through one rotation of the
//!   sphere that takes the log's reference point (its first valid position) to the target.
//!   A rotation keeps every great-circle distance and angle, so tracks keep their shape,
//!   size and headings (north stays north at the reference). Values are stored back at the
//!   field's own resolution: `int32` 1e-7° fields move by at most half a step (0.56 cm).
//!   Absolute altitudes (AMSL and ellipsoid, barometric included) move by one offset.
//! - **Times.** UTC times (`time_utc_usec`...) and a header start time that is an absolute
//!   date move by one offset (unless `keep_time`); dates and times in logged strings and
//!   file names are replaced by zeros; the info values that give the time zone or a date
//!   are left out.
//! - **Identifiers.** Info values that identify the vehicle or its parts (`sys_uuid`,
//!   serial numbers...) and every multi info value but the events metadata (boot console
//!   output, hardware lists, performance counters name devices) are left out; topics of
//!   raw receiver bytes (`gps_dump`, `gps_inject_data`: they hold positions in the
//!   receiver's own protocol) are dropped.

use crate::read::{KeyValue, Message, Metadata, Subscription};
use crate::schema::{Primitive, Schema};
use crate::value::{Scalar, Value};

use super::RewriteError;
use super::fields::{FieldIndex, Leaf};

/// Where the positions of an anonymized log go.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// The log's reference point (its first valid position) goes to this latitude and
    /// longitude (degrees); altitudes and times move by offsets drawn from the two.
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
/// anonymize`), as the [module docs](self) say. The fields it changes, by name and type in
/// any topic and nested type:
///
/// | what | fields | types |
/// |---|---|---|
/// | positions (pairs) | `lat`/`lon`, `latitude_deg`/`longitude_deg`, `ref_lat`/`ref_lon`, and any `<x>lat`/`<x>lon` pair | `int32_t` (1e-7°), `float`, `double` (°) |
/// | altitudes | `alt`, `alt_ellipsoid`, `altitude_msl_m`, `altitude_ellipsoid_m`, `ref_alt`, `baro_alt_meter`, and `alt` beside a position pair | `int32_t` (mm), `float`, `double` (m) |
/// | UTC times | `time_utc_usec`, `utc_time_usec` | `uint64_t` (µs) |
/// | topics dropped | `gps_dump`, `gps_inject_data` | raw receiver bytes |
/// | info left out | `sys_uuid`, any key holding `uuid`, `serial`, `_sn`, `mac`, `time_ref_utc`, and dates (`*_date*`) | |
/// | multi info left out | every key but `metadata_events` | |
/// | logged strings | dates (`2024-05-01`, `2024/05/01`), times of day (`12:30:45`, `12_30_45` in file names) become zeros | |
///
/// A latitude and longitude of 0 (no fix) and values that are not finite stay as they are.
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
    /// Every field changed: topic, field (pyulog's name), rows.
    pub fields: Vec<(String, String, usize)>,
}

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

/// How a value of a position field is stored.
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
        match self {
            Stored::Scaled(at, scale) => {
                let raw = (v / scale).round();
                if !(f64::from(i32::MIN)..=f64::from(i32::MAX)).contains(&raw) {
                    return false;
                }
                if let Some(d) = row.get_mut(at..at + 4) {
                    d.copy_from_slice(&(raw as i32).to_le_bytes());
                }
            }
            Stored::Float(at, Primitive::Float) => {
                if let Some(d) = row.get_mut(at..at + 4) {
                    d.copy_from_slice(&(v as f32).to_le_bytes());
                }
            }
            Stored::Float(at, _) => {
                if let Some(d) = row.get_mut(at..at + 8) {
                    d.copy_from_slice(&v.to_le_bytes());
                }
            }
        }
        true
    }
}

/// The fields of one subscription to change, and per field the rows changed.
struct Plan {
    topic: String,
    /// Latitude, longitude; the index into `names`.
    pairs: Vec<(Stored, Stored, usize)>,
    altitudes: Vec<(Stored, usize)>,
    times: Vec<(usize, usize)>,
    /// Field names (for the report): per entry (name, rows changed).
    names: Vec<(String, usize)>,
}

/// Names of absolute altitude fields (meters, or millimeters as `int32_t`).
const ALTITUDES: [&str; 6] = [
    "alt",
    "alt_ellipsoid",
    "altitude_msl_m",
    "altitude_ellipsoid_m",
    "ref_alt",
    "baro_alt_meter",
];

/// Names of UTC time fields (µs since 1970).
const UTC_TIMES: [&str; 2] = ["time_utc_usec", "utc_time_usec"];

/// Topics of raw receiver bytes.
const RAW_TOPICS: [&str; 2] = ["gps_dump", "gps_inject_data"];

/// The longitude field that goes with a latitude field's last name part, if any.
fn longitude_of(base: &str) -> Option<String> {
    if let Some(i) = base.find("latitude") {
        return Some(format!(
            "{}longitude{}",
            &base[..i],
            &base[i + "latitude".len()..]
        ));
    }
    base.strip_suffix("lat").map(|x| format!("{x}lon"))
}

/// The rotation taking one point of the sphere to another, north kept at the point.
#[derive(Debug, Clone, Copy)]
struct Rotation {
    m: [[f64; 3]; 3],
}

impl Rotation {
    fn unit(lat: f64, lon: f64) -> [f64; 3] {
        let (lat, lon) = (lat.to_radians(), lon.to_radians());
        [lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin()]
    }

    /// Rz(lon1) · Ry(lat1 - lat0) · Rz(-lon0): to the reference's meridian, along it, then
    /// around the axis to the target's.
    fn new(from: (f64, f64), to: (f64, f64)) -> Rotation {
        let rz = |a: f64| {
            let (s, c) = a.to_radians().sin_cos();
            [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
        };
        // A rotation about the y axis raising the latitude of a point on the 0° meridian.
        let ry = |a: f64| {
            let (s, c) = a.to_radians().sin_cos();
            [[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]]
        };
        let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
            let mut m = [[0.0; 3]; 3];
            for (i, row) in m.iter_mut().enumerate() {
                for (j, v) in row.iter_mut().enumerate() {
                    *v = (0..3).map(|k| a[i][k] * b[k][j]).sum();
                }
            }
            m
        };
        Rotation {
            m: mul(rz(to.1), mul(ry(to.0 - from.0), rz(-from.1))),
        }
    }

    fn apply(&self, lat: f64, lon: f64) -> (f64, f64) {
        let p = Rotation::unit(lat, lon);
        let q: Vec<f64> = self
            .m
            .iter()
            .map(|r| r[0] * p[0] + r[1] * p[1] + r[2] * p[2])
            .collect();
        (
            q[2].clamp(-1.0, 1.0).asin().to_degrees(),
            q[1].atan2(q[0]).to_degrees(),
        )
    }
}

/// The anonymizing pass's state.
pub(super) struct Anonymizer {
    rules: Anonymize,
    target: (f64, f64),
    altitude_offset_m: f64,
    time_offset_us: i64,
    rotation: Option<Rotation>,
    plans: Vec<Plan>,
}

impl Anonymizer {
    pub(super) fn new(rules: Anonymize) -> Anonymizer {
        let seed = match rules.target {
            Target::Seed(s) => s,
            Target::Origin { lat, lon } => lat.to_bits() ^ lon.to_bits().rotate_left(17),
        };
        let mut mix = Mix(seed);
        let drawn = (
            mix.uniform(-0.85, 0.85).asin().to_degrees(),
            mix.uniform(-180.0, 180.0),
        );
        let target = match rules.target {
            Target::Origin { lat, lon } => (lat, lon),
            Target::Seed(_) => drawn,
        };
        let altitude_offset_m = mix.uniform(-500.0, 500.0).round();
        // Up to ten years either way, never near zero.
        let years = mix.uniform(1.0, 10.0) * if mix.next() & 1 == 0 { 1.0 } else { -1.0 };
        #[allow(clippy::cast_possible_truncation)]
        let time_offset_us = if rules.keep_time {
            0
        } else {
            (years * 365.25 * 86_400e6).round() as i64
        };
        Anonymizer {
            rules,
            target,
            altitude_offset_m,
            time_offset_us,
            rotation: None,
            plans: Vec::new(),
        }
    }

    /// Reads what the header says before the first message.
    pub(super) fn start(&mut self, _meta: &Metadata) {}

    /// The header's start time: moved like UTC times when it is an absolute date.
    pub(super) fn header_start(&self, start: u64) -> u64 {
        // Boot times are far below 2000-01-01 in µs.
        const Y2000_US: u64 = 946_684_800_000_000;
        if start >= Y2000_US {
            start.saturating_add_signed(self.time_offset_us)
        } else {
            start
        }
    }

    pub(super) fn drops_topic(&self, name: &str) -> bool {
        RAW_TOPICS.contains(&name)
    }

    /// Whether an info (`I`) or multi info (`M`) key is left out.
    pub(super) fn drops_info(&self, name: &str, ty: u8) -> bool {
        if ty == b'M' {
            return name != "metadata_events";
        }
        let lower = name.to_ascii_lowercase();
        let identifies = ["uuid", "serial", "_sn", "mac"]
            .iter()
            .any(|p| lower.contains(p));
        let dates = !self.rules.keep_time
            && (lower == "time_ref_utc" || lower.contains("date") || lower.contains("utc"));
        identifies || dates
    }

    /// A replacement for an info value, if one is needed.
    pub(super) fn info(&mut self, _name: &str, _kv: KeyValue<'_>) -> Option<Value> {
        None
    }

    pub(super) fn prepare(
        &mut self,
        schema: &Schema,
        sub: &Subscription,
    ) -> Result<Option<usize>, RewriteError> {
        let Some(index) = sub.format().and_then(|id| FieldIndex::of(schema, id)) else {
            return Ok(None);
        };
        let mut plan = Plan {
            topic: sub.name.clone(),
            pairs: Vec::new(),
            altitudes: Vec::new(),
            times: Vec::new(),
            names: Vec::new(),
        };
        let name_slot = |plan: &mut Plan, name: &str| {
            plan.names.push((name.to_owned(), 0));
            plan.names.len() - 1
        };
        for (name, leaf) in index.iter() {
            let (prefix, base) = match name.rfind('.') {
                Some(i) => (&name[..=i], &name[i + 1..]),
                None => ("", name),
            };
            if let Some(lon_base) = longitude_of(base)
                && let Some(lon_leaf) = index.get(&format!("{prefix}{lon_base}"))
                && let (Some(lat), Some(lon)) = (Stored::of(leaf, 1e-7), Stored::of(lon_leaf, 1e-7))
            {
                let slot = name_slot(&mut plan, &format!("{prefix}{base}/{lon_base}"));
                plan.pairs.push((lat, lon, slot));
                continue;
            }
            if ALTITUDES.contains(&base)
                && let Some(alt) = Stored::of(leaf, 1e-3)
            {
                let slot = name_slot(&mut plan, name);
                plan.altitudes.push((alt, slot));
                continue;
            }
            if !self.rules.keep_time
                && UTC_TIMES.contains(&base)
                && let Leaf::Value(at, Primitive::UInt64) = leaf
            {
                let slot = name_slot(&mut plan, name);
                plan.times.push((at, slot));
            }
        }
        if plan.pairs.is_empty() && plan.altitudes.is_empty() && plan.times.is_empty() {
            return Ok(None);
        }
        self.plans.push(plan);
        Ok(Some(self.plans.len() - 1))
    }

    pub(super) fn apply(&mut self, slot: usize, row: &mut [u8], _timestamp: u64) {
        let plan = &mut self.plans[slot];
        for &(lat_f, lon_f, name) in &plan.pairs {
            let (Some(lat), Some(lon)) = (lat_f.read(row), lon_f.read(row)) else {
                continue;
            };
            let valid = lat.is_finite()
                && lon.is_finite()
                && (lat != 0.0 || lon != 0.0)
                && lat.abs() <= 90.0
                && lon.abs() <= 360.0;
            if !valid {
                continue;
            }
            let rotation = *self
                .rotation
                .get_or_insert_with(|| Rotation::new((lat, lon), self.target));
            let (lat2, lon2) = rotation.apply(lat, lon);
            if lat_f.write(row, lat2) && lon_f.write(row, lon2) {
                plan.names[name].1 += 1;
            }
        }
        for &(alt_f, name) in &plan.altitudes {
            if let Some(alt) = alt_f.read(row)
                && alt.is_finite()
                && alt_f.write(row, alt + self.altitude_offset_m)
            {
                plan.names[name].1 += 1;
            }
        }
        for &(at, name) in &plan.times {
            if let Some(b) = row.get_mut(at..at + 8) {
                let t = u64::from_le_bytes(b.try_into().expect("8 bytes"));
                // 0: no time known.
                if t != 0 {
                    b.copy_from_slice(&t.saturating_add_signed(self.time_offset_us).to_le_bytes());
                    plan.names[name].1 += 1;
                }
            }
        }
    }

    /// A logged string's message with its dates and times replaced, if it has any.
    pub(super) fn logged(&mut self, ty: u8, payload: &[u8]) -> Option<Vec<u8>> {
        if self.rules.keep_time {
            return None;
        }
        let Ok(Message::Logging { text, .. }) = Message::parse(ty, payload) else {
            return None;
        };
        let redacted = redact_dates(text)?;
        let mut out = payload[..payload.len() - text.len()].to_vec();
        out.extend_from_slice(&redacted);
        Some(out)
    }

    pub(super) fn report(&self) -> Anonymized {
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
            fields,
        }
    }
}

/// The text with every date (`2024-05-01`, `2024/05/01`, `2024_05_01`) and time of day
/// (`12:30:45`, `12_30_45`, `12-30-45`) made zeros; `None` if it has none.
fn redact_dates(text: &[u8]) -> Option<Vec<u8>> {
    let mut out = text.to_vec();
    let mut changed = false;
    let digits = |s: &[u8]| s.iter().all(u8::is_ascii_digit);
    let mut i = 0;
    while i < out.len() {
        // yyyy?mm?dd
        if i + 10 <= out.len()
            && digits(&out[i..i + 4])
            && matches!(out[i + 4], b'-' | b'/' | b'_')
            && digits(&out[i + 5..i + 7])
            && out[i + 7] == out[i + 4]
            && digits(&out[i + 8..i + 10])
            && (i == 0 || !out[i - 1].is_ascii_digit())
            && out.get(i + 10).is_none_or(|c| !c.is_ascii_digit())
        {
            for k in [0, 1, 2, 3, 5, 6, 8, 9] {
                out[i + k] = b'0';
            }
            changed = true;
            i += 10;
            continue;
        }
        // hh?mm?ss
        if i + 8 <= out.len()
            && digits(&out[i..i + 2])
            && matches!(out[i + 2], b':' | b'_' | b'-')
            && digits(&out[i + 3..i + 5])
            && out[i + 5] == out[i + 2]
            && digits(&out[i + 6..i + 8])
            && (i == 0 || !out[i - 1].is_ascii_digit())
            && out.get(i + 8).is_none_or(|c| !c.is_ascii_digit())
        {
            for k in [0, 1, 3, 4, 6, 7] {
                out[i + k] = b'0';
            }
            changed = true;
            i += 8;
            continue;
        }
        i += 1;
    }
    changed.then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rotation_keeps_distances_and_north() {
        let r = Rotation::new((47.397_742, 8.545_594), (-33.9, 151.2));
        let (lat, lon) = r.apply(47.397_742, 8.545_594);
        assert!((lat + 33.9).abs() < 1e-9 && (lon - 151.2).abs() < 1e-9);
        // A point 100 m north stays 100 m north.
        let north = r.apply(47.397_742 + 100.0 / 111_195.0, 8.545_594);
        assert!((north.1 - 151.2).abs() < 1e-9, "{north:?}");
        // The angle between two points, as atan2(|p × q|, p · q) (precise at small angles).
        let dist = |a: (f64, f64), b: (f64, f64)| {
            let (p, q) = (Rotation::unit(a.0, a.1), Rotation::unit(b.0, b.1));
            let dot: f64 = (0..3).map(|i| p[i] * q[i]).sum();
            let cross = [
                p[1] * q[2] - p[2] * q[1],
                p[2] * q[0] - p[0] * q[2],
                p[0] * q[1] - p[1] * q[0],
            ];
            let norm = cross.iter().map(|c| c * c).sum::<f64>().sqrt();
            norm.atan2(dot) * 6_371_000.0
        };
        for (a, b) in [
            ((47.39, 8.54), (47.41, 8.56)),
            ((47.39, 8.54), (47.390_01, 8.540_01)),
        ] {
            let d = dist(a, b);
            let moved = dist(r.apply(a.0, a.1), r.apply(b.0, b.1));
            assert!((d - moved).abs() < 1e-4, "{d} vs {moved}");
        }
    }

    #[test]
    fn dates_and_times_become_zeros() {
        let text = b"[logger] file: /fs/microsd/log/2019-04-25/12_30_05.ulg at 10:11:12, 1234-5";
        let out = redact_dates(text).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "[logger] file: /fs/microsd/log/0000-00-00/00_00_00.ulg at 00:00:00, 1234-5"
        );
        assert!(redact_dates(b"battery 12.3 V").is_none());
    }

    #[test]
    fn latitude_fields_find_their_longitude() {
        assert_eq!(longitude_of("lat").as_deref(), Some("lon"));
        assert_eq!(longitude_of("ref_lat").as_deref(), Some("ref_lon"));
        assert_eq!(
            longitude_of("latitude_deg").as_deref(),
            Some("longitude_deg")
        );
        assert_eq!(longitude_of("lat_lon_reset_counter"), None);
    }
}
