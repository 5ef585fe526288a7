//! Battery, GPS and vibration: per-instance statistics of `battery_status`,
//! `vehicle_gps_position` (or `sensor_gps`, the old `lat`/`lon` int32 1e-7° and the new
//! `latitude_deg`/`longitude_deg`), the GPS track at 1 Hz, and
//! `vehicle_imu_status.accel_vibration_metric` against PX4's thresholds.

use super::modes::Modes;
use super::state::FlightState;
use super::{Battery, BatteryInstance, GpsQuality, ImuVibration, Missing, TrackPoint, Vibration};
use crate::analysis::LazyIndex;
use crate::columns::Leaf;
use crate::read::Metadata;

/// Where a sensor topic's fields are.
pub(super) enum Fields {
    Battery {
        multi_id: u8,
        voltage: Option<Leaf>,
        current: Option<Leaf>,
        discharged: Option<Leaf>,
        cell_count: Option<Leaf>,
    },
    Gps {
        /// Whether this is `vehicle_gps_position` (preferred) or `sensor_gps`.
        vehicle: bool,
        multi_id: u8,
        fix: Option<Leaf>,
        sats: Option<Leaf>,
        hdop: Option<Leaf>,
        eph: Option<Leaf>,
        epv: Option<Leaf>,
        jamming: Option<Leaf>,
        jamming_state: Option<Leaf>,
        noise: Option<Leaf>,
        /// Latitude, longitude, altitude, and the scale to degrees and meters.
        position: Option<([Leaf; 3], f64, f64)>,
    },
    Imu {
        multi_id: u8,
        vibration: Leaf,
    },
}

/// The position fields of a GPS topic: `latitude_deg`, `longitude_deg`, `altitude_msl_m`
/// (degrees, meters) or `lat`, `lon`, `alt` (int32: 1e-7°, mm).
pub(crate) fn gps_position(index: &LazyIndex<'_>) -> Option<([Leaf; 3], f64, f64)> {
    if let (Some(a), Some(b), Some(c)) = (
        index.get("latitude_deg"),
        index.get("longitude_deg"),
        index.get("altitude_msl_m"),
    ) {
        return Some(([a, b, c], 1.0, 1.0));
    }
    let (a, b, c) = (index.get("lat")?, index.get("lon")?, index.get("alt")?);
    let int = matches!(a, Leaf::Value(_, crate::schema::Primitive::Int32));
    Some((
        [a, b, c],
        if int { 1e-7 } else { 1.0 },
        if int { 1e-3 } else { 1.0 },
    ))
}

impl Fields {
    pub(super) fn bind(topic: &str, multi_id: u8, index: &LazyIndex<'_>) -> Option<Fields> {
        match topic {
            "battery_status" => Some(Fields::Battery {
                multi_id,
                voltage: index
                    .get("voltage_v")
                    .or_else(|| index.get("voltage_filtered_v")),
                current: index
                    .get("current_a")
                    .or_else(|| index.get("current_filtered_a")),
                discharged: index.get("discharged_mah"),
                cell_count: index.get("cell_count"),
            }),
            "vehicle_gps_position" | "sensor_gps" => Some(Fields::Gps {
                vehicle: topic == "vehicle_gps_position",
                multi_id,
                fix: index.get("fix_type"),
                sats: index.get("satellites_used"),
                hdop: index.get("hdop"),
                eph: index.get("eph"),
                epv: index.get("epv"),
                jamming: index.get("jamming_indicator"),
                jamming_state: index.get("jamming_state"),
                noise: index.get("noise_per_ms"),
                position: gps_position(index),
            }),
            "vehicle_imu_status" => Some(Fields::Imu {
                multi_id,
                vibration: index.get("accel_vibration_metric")?,
            }),
            _ => None,
        }
    }
}

#[derive(Debug, Clone, Default)]
struct BatteryAcc {
    current_sum: f64,
    current_n: u64,
    max_current: Option<f64>,
    discharged: Option<f64>,
    min_voltage: Option<f64>,
    max_voltage: Option<f64>,
    cell_count: Option<u32>,
}

#[derive(Debug, Clone, Default)]
struct GpsAcc {
    rows: u64,
    min_sats: Option<u32>,
    max_sats: Option<u32>,
    max_hdop: Option<f64>,
    max_eph: Option<f64>,
    max_epv: Option<f64>,
    fix_types: Vec<u8>,
    max_jamming: Option<f64>,
    max_noise: Option<f64>,
    jamming_states: Vec<u8>,
    track: Vec<(f64, f64, f64, u64)>,
    last_point: Option<u64>,
}

#[derive(Debug, Clone, Default)]
struct ImuAcc {
    sum: f64,
    n: u64,
    max: f64,
}

/// Every sensor instance seen, by `multi_id`.
#[derive(Debug, Clone, Default)]
pub(super) struct Sensors {
    batteries: Vec<(u8, BatteryAcc)>,
    /// (vehicle_gps_position?, multi_id)
    gps: Vec<((bool, u8), GpsAcc)>,
    imus: Vec<(u8, ImuAcc)>,
}

fn entry<K: PartialEq + Copy, V: Default>(v: &mut Vec<(K, V)>, k: K) -> &mut V {
    match v.iter().position(|(x, _)| *x == k) {
        Some(i) => &mut v[i].1,
        None => {
            v.push((k, V::default()));
            &mut v.last_mut().expect("just pushed").1
        }
    }
}

fn keep_max(a: &mut Option<f64>, v: f64) {
    if v.is_finite() {
        *a = Some(a.map_or(v, |x| x.max(v)));
    }
}

fn keep_min(a: &mut Option<f64>, v: f64) {
    if v.is_finite() {
        *a = Some(a.map_or(v, |x| x.min(v)));
    }
}

/// `accel_vibration_metric` (m/s²) whose mean is good below this (PX4's).
pub const VIBRATION_GOOD_MEAN: f64 = 4.905;
/// ... critical from this.
pub const VIBRATION_CRITICAL_MEAN: f64 = 9.81;
/// Its peak: good below this.
pub const VIBRATION_GOOD_PEAK: f64 = 9.81;
/// ... critical from this.
pub const VIBRATION_CRITICAL_PEAK: f64 = 19.62;

/// PX4's vibration classes of `accel_vibration_metric`: the mean's and the peak's, the
/// worse of the two.
pub(crate) fn vibration_status(mean: f64, max: f64) -> &'static str {
    let class = |v: f64, warn: f64, crit: f64| u8::from(v >= warn) + u8::from(v >= crit);
    match class(mean, VIBRATION_GOOD_MEAN, VIBRATION_CRITICAL_MEAN).max(class(
        max,
        VIBRATION_GOOD_PEAK,
        VIBRATION_CRITICAL_PEAK,
    )) {
        0 => "good",
        1 => "warning",
        _ => "critical",
    }
}

impl Sensors {
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    pub(super) fn row(&mut self, f: &Fields, data: &[u8], t: u64, _state: &FlightState) {
        let get = |l: &Option<Leaf>| l.and_then(|l| l.f64(data)).filter(|v| v.is_finite());
        match f {
            Fields::Battery {
                multi_id,
                voltage,
                current,
                discharged,
                cell_count,
            } => {
                let b = entry(&mut self.batteries, *multi_id);
                if let Some(v) = get(voltage).filter(|v| *v > 0.0) {
                    keep_min(&mut b.min_voltage, v);
                    keep_max(&mut b.max_voltage, v);
                }
                // PX4 writes -1 for "unknown".
                if let Some(c) = get(current).filter(|c| *c >= 0.0) {
                    b.current_sum += c;
                    b.current_n += 1;
                    keep_max(&mut b.max_current, c);
                }
                if let Some(d) = get(discharged).filter(|d| *d >= 0.0) {
                    b.discharged = Some(d);
                }
                if let Some(n) = get(cell_count).filter(|n| *n > 0.0 && *n < 64.0) {
                    b.cell_count = Some(n as u32);
                }
            }
            Fields::Gps {
                vehicle,
                multi_id,
                fix,
                sats,
                hdop,
                eph,
                epv,
                jamming,
                jamming_state,
                noise,
                position,
            } => {
                let g = entry(&mut self.gps, (*vehicle, *multi_id));
                g.rows += 1;
                let fix = get(fix).map(|f| f as u8);
                if let Some(f) = fix
                    && !g.fix_types.contains(&f)
                {
                    g.fix_types.push(f);
                }
                if let Some(s) = get(sats) {
                    let s = s as u32;
                    g.min_sats = Some(g.min_sats.map_or(s, |m| m.min(s)));
                    g.max_sats = Some(g.max_sats.map_or(s, |m| m.max(s)));
                }
                let fixed = fix.is_none_or(|f| f >= 3);
                if fixed {
                    if let Some(v) = get(hdop) {
                        keep_max(&mut g.max_hdop, v);
                    }
                    if let Some(v) = get(eph) {
                        keep_max(&mut g.max_eph, v);
                    }
                    if let Some(v) = get(epv) {
                        keep_max(&mut g.max_epv, v);
                    }
                }
                if let Some(v) = get(jamming) {
                    keep_max(&mut g.max_jamming, v);
                }
                if let Some(v) = get(noise) {
                    keep_max(&mut g.max_noise, v);
                }
                if let Some(s) = get(jamming_state).map(|s| s as u8)
                    && !g.jamming_states.contains(&s)
                {
                    g.jamming_states.push(s);
                }
                if let Some((leaves, deg, m)) = position
                    && fix.is_none_or(|f| f >= 3)
                    // A point a second, and one where time ran back (logs joined).
                    && g.last_point
                        .is_none_or(|last| t >= last.saturating_add(1_000_000) || t < last)
                    && let (Some(lat), Some(lon), Some(alt)) = (
                        leaves[0].f64(data),
                        leaves[1].f64(data),
                        leaves[2].f64(data),
                    )
                    && (lat != 0.0 || lon != 0.0)
                    && lat.is_finite()
                    && lon.is_finite()
                {
                    g.track.push((lat * deg, lon * deg, alt * m, t));
                    g.last_point = Some(t);
                }
            }
            Fields::Imu {
                multi_id,
                vibration,
            } => {
                if let Some(v) = vibration.f64(data).filter(|v| v.is_finite() && *v >= 0.0) {
                    let i = entry(&mut self.imus, *multi_id);
                    i.sum += v;
                    i.n += 1;
                    i.max = i.max.max(v);
                }
            }
        }
    }

    /// Cells of battery `multi_id`: the parameter `BAT<n>_N_CELLS` (older PX4:
    /// `BAT_N_CELLS`), else the topic's `cell_count`, else estimated from the highest
    /// voltage (a cell holds at most 4.35 V).
    fn cells(meta: &Metadata, multi_id: u8, b: &BatteryAcc) -> Option<u32> {
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        super::diagnostics::brownout::cells_parameter(meta, multi_id)
            .or(b.cell_count)
            .or_else(|| b.max_voltage.map(|v| (v / 4.35).ceil().max(1.0) as u32))
    }

    #[allow(clippy::type_complexity)]
    pub(super) fn finish(
        &self,
        meta: &Metadata,
        modes: &Modes,
        missing: &mut Vec<Missing>,
    ) -> (Battery, GpsQuality, Vibration, Vec<TrackPoint>) {
        let mut batteries = self.batteries.clone();
        batteries.sort_by_key(|(m, _)| *m);
        let instances: Vec<BatteryInstance> = batteries
            .iter()
            .map(|(m, b)| BatteryInstance {
                multi_id: *m,
                avg_current_a: (b.current_n > 0).then(|| b.current_sum / b.current_n as f64),
                max_current_a: b.max_current,
                // PX4 integrates the charge drawn from the current: with no current
                // reading (a battery without a current sensor writes -1 and a charge of
                // 0 throughout), a charge of 0 is unknown, not a measurement; a charge
                // above 0 (a smart battery's own count) is kept.
                discharged_mah: b.discharged.filter(|d| b.current_n > 0 || *d > 0.0),
                min_voltage_v: b.min_voltage,
                cells: Sensors::cells(meta, *m, b),
            })
            .collect();
        let first = instances
            .iter()
            .find(|b| b.multi_id == 0)
            .cloned()
            .unwrap_or_default();
        if instances.is_empty() {
            missing.push(Missing {
                fact: "battery".to_owned(),
                reason: "the log has no battery_status rows".to_owned(),
            });
        }
        let battery = Battery {
            avg_current_a: first.avg_current_a,
            max_current_a: first.max_current_a,
            discharged_mah: first.discharged_mah,
            min_voltage_v: first.min_voltage_v,
            instances,
        };
        // vehicle_gps_position #0, else sensor_gps #0.
        let gps = self
            .gps
            .iter()
            .find(|(k, _)| *k == (true, 0))
            .or_else(|| self.gps.iter().find(|(k, _)| *k == (false, 0)))
            .map(|(_, g)| g);
        let (quality, track) = match gps {
            Some(g) => {
                let mut fix_types = g.fix_types.clone();
                fix_types.sort_unstable();
                let mut jamming_states = g.jamming_states.clone();
                jamming_states.sort_unstable();
                (
                    GpsQuality {
                        min_satellites: g.min_sats,
                        max_satellites: g.max_sats,
                        max_hdop: g.max_hdop,
                        max_eph_m: g.max_eph,
                        max_epv_m: g.max_epv,
                        fix_types_seen: fix_types,
                        max_jamming_indicator: g.max_jamming,
                        max_noise_per_ms: g.max_noise,
                        jamming_states_seen: jamming_states,
                    },
                    g.track
                        .iter()
                        .map(|&(lat, lon, alt, t)| TrackPoint {
                            lat_deg: lat,
                            lon_deg: lon,
                            alt_m: alt,
                            timestamp_us: t,
                            mode_id: modes.mode_at(t),
                        })
                        .collect(),
                )
            }
            None => {
                missing.push(Missing {
                    fact: "gps_quality, gps_track".to_owned(),
                    reason: "the log has no vehicle_gps_position or sensor_gps rows".to_owned(),
                });
                (GpsQuality::default(), Vec::new())
            }
        };
        let mut imus = self.imus.clone();
        imus.sort_by_key(|(m, _)| *m);
        let (sum, n, max) = imus.iter().fold((0.0, 0, 0.0f64), |(s, n, m), (_, i)| {
            (s + i.sum, n + i.n, m.max(i.max))
        });
        let vibration = if n > 0 {
            let mean = sum / n as f64;
            Vibration {
                accel_vibe_mean: Some(mean),
                accel_vibe_max: Some(max),
                status: vibration_status(mean, max).to_owned(),
                imus: imus
                    .iter()
                    .filter(|(_, i)| i.n > 0)
                    .map(|(m, i)| {
                        let mean = i.sum / i.n as f64;
                        ImuVibration {
                            multi_id: *m,
                            mean,
                            max: i.max,
                            status: vibration_status(mean, i.max).to_owned(),
                        }
                    })
                    .collect(),
            }
        } else {
            missing.push(Missing {
                fact: "vibration".to_owned(),
                reason: "the log has no vehicle_imu_status.accel_vibration_metric".to_owned(),
            });
            Vibration::default()
        };
        (battery, quality, vibration, track)
    }
}
