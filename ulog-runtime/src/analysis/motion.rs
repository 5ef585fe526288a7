//! How the vehicle moved: path length, altitude range and speeds from
//! `vehicle_local_position` (NED), tilt from `vehicle_attitude`'s quaternion, rotation rate
//! from `vehicle_angular_velocity` (older logs: `vehicle_attitude`'s rates or
//! `sensor_combined`'s gyro), over the whole log and while armed; and the spectral
//! analyses of the rates and accelerations in flight.

use super::spectral::{StepResponse, Welch};
use super::state::FlightState;
use super::{AxisResponse, Missing, Motion, SpectrumOf, Stats};
use crate::analysis::LazyIndex;
use crate::columns::Leaf;

/// Where a motion topic's fields are.
pub(super) enum Fields {
    Local {
        pos: [Leaf; 3],
        vel: Option<[Leaf; 3]>,
    },
    Attitude {
        q: [Leaf; 4],
    },
    /// Body rates in rad/s, and whether they are the preferred source.
    Rates {
        xyz: [Leaf; 3],
        preferred: bool,
    },
}

fn three(index: &LazyIndex<'_>, names: [&str; 3]) -> Option<[Leaf; 3]> {
    Some([
        index.get(names[0])?,
        index.get(names[1])?,
        index.get(names[2])?,
    ])
}

impl Fields {
    pub(super) fn bind(topic: &str, index: &LazyIndex<'_>) -> Option<Fields> {
        match topic {
            "vehicle_local_position" => Some(Fields::Local {
                pos: three(index, ["x", "y", "z"])?,
                vel: three(index, ["vx", "vy", "vz"]),
            }),
            "vehicle_attitude" => {
                let q = Some([
                    index.get("q[0]")?,
                    index.get("q[1]")?,
                    index.get("q[2]")?,
                    index.get("q[3]")?,
                ]);
                q.map(|q| Fields::Attitude { q })
            }
            "vehicle_angular_velocity" => Some(Fields::Rates {
                xyz: three(index, ["xyz[0]", "xyz[1]", "xyz[2]"])?,
                preferred: true,
            }),
            "sensor_combined" => Some(Fields::Rates {
                xyz: three(index, ["gyro_rad[0]", "gyro_rad[1]", "gyro_rad[2]"])?,
                preferred: false,
            }),
            _ => None,
        }
    }
}

/// Accumulates one [`Motion`].
#[derive(Debug, Clone, Default)]
struct Acc {
    last_pos: Option<[f64; 3]>,
    distance: Option<f64>,
    z: Option<(f64, f64)>,
    max_speed: Option<f64>,
    max_h: Option<f64>,
    max_up: Option<f64>,
    max_down: Option<f64>,
    speed_sum: f64,
    speed_n: u64,
    /// The smallest cosine of the tilt (the largest tilt, without an `acos` a row).
    min_cos_tilt: Option<f64>,
    /// The largest squared rotation rates, (rad/s)².
    max_rate2: Option<f64>,
    max_rate2_other: Option<f64>,
}

fn max(a: &mut Option<f64>, v: f64) {
    if v.is_finite() {
        *a = Some(a.map_or(v, |x| x.max(v)));
    }
}

impl Acc {
    fn local(&mut self, pos: Option<[f64; 3]>, vel: Option<[f64; 3]>) {
        if let Some(p) = pos {
            if let Some(l) = self.last_pos {
                let d =
                    ((p[0] - l[0]).powi(2) + (p[1] - l[1]).powi(2) + (p[2] - l[2]).powi(2)).sqrt();
                *self.distance.get_or_insert(0.0) += d;
            } else {
                self.distance.get_or_insert(0.0);
            }
            self.last_pos = Some(p);
            // Altitude is -z (NED).
            let z = -p[2];
            self.z = Some(self.z.map_or((z, z), |(lo, hi)| (lo.min(z), hi.max(z))));
        }
        if let Some(v) = vel {
            // Speeds of vehicles: no overflow for `hypot` to guard against.
            let h2 = v[0] * v[0] + v[1] * v[1];
            let h = h2.sqrt();
            let s = (h2 + v[2] * v[2]).sqrt();
            max(&mut self.max_speed, s);
            max(&mut self.max_h, h);
            max(&mut self.max_up, if v[2] < 0.0 { -v[2] } else { 0.0 });
            max(&mut self.max_down, v[2].max(0.0));
            self.speed_sum += s;
            self.speed_n += 1;
        }
    }

    fn finish(&self) -> Motion {
        Motion {
            total_distance_m: self.distance,
            max_altitude_diff_m: self.z.map(|(lo, hi)| hi - lo),
            max_speed_m_s: self.max_speed,
            max_horizontal_speed_m_s: self.max_h,
            max_speed_up_m_s: self.max_up,
            max_speed_down_m_s: self.max_down,
            avg_speed_m_s: (self.speed_n > 0).then(|| self.speed_sum / self.speed_n as f64),
            max_tilt_deg: self.min_cos_tilt.map(|c| c.acos().to_degrees()),
            max_rotation_speed_deg_s: self
                .max_rate2
                .or(self.max_rate2_other)
                .map(|r2| r2.sqrt().to_degrees()),
        }
    }
}

/// The statistics over every row and over the armed rows.
#[derive(Debug, Clone, Default)]
pub(super) struct MotionStats {
    all: Acc,
    armed: Acc,
    /// The last `vehicle_local_position` row's time.
    last_local_t: Option<u64>,
    seen_local: bool,
    seen_attitude: bool,
    seen_rates: bool,
}

/// Finite values of three leaves. Inlined: returned through memory, the three values were
/// written as three `f64`s and read back as a pair and one, which the processor cannot
/// forward from its stores (a quarter of `MotionStats::row`'s time went to that stall).
#[inline(always)]
fn read3(data: &[u8], leaves: &[Leaf; 3]) -> Option<[f64; 3]> {
    use crate::schema::Primitive::Float;
    let v = match *leaves {
        // The common case, `float[3]` (or three floats in a row): one bounds check.
        [
            Leaf::Value(a, Float),
            Leaf::Value(b, Float),
            Leaf::Value(c, Float),
        ] if b == a + 4 && c == a + 8 => {
            let (xyz, _) = data.get(a..)?.split_first_chunk::<12>()?;
            let (x, yz) = xyz.split_at(4);
            let (y, z) = yz.split_at(4);
            let f = |b: &[u8]| f64::from(f32::from_le_bytes(b.try_into().expect("4 bytes")));
            [f(x), f(y), f(z)]
        }
        _ => read3_any(data, leaves)?,
    };
    v.iter().all(|x| x.is_finite()).then_some(v)
}

/// [`read3`] of leaves of any type, anywhere in the row.
#[inline(never)]
fn read3_any(data: &[u8], leaves: &[Leaf; 3]) -> Option<[f64; 3]> {
    Some([
        leaves[0].f64(data)?,
        leaves[1].f64(data)?,
        leaves[2].f64(data)?,
    ])
}

impl MotionStats {
    pub(super) fn row(&mut self, f: &Fields, data: &[u8], t: u64, state: &FlightState) {
        if let Fields::Local { .. } = f {
            // The path joins consecutive positions: not across time that ran back (a
            // damaged log, logs joined), nor, for the armed time's, across a disarmed stretch.
            if self.last_local_t.replace(t).is_some_and(|prev| t < prev) {
                self.all.last_pos = None;
                self.armed.last_pos = None;
            }
            if !state.armed {
                self.armed.last_pos = None;
            }
        }
        let accs: &mut [&mut Acc] = if state.armed {
            &mut [&mut self.all, &mut self.armed]
        } else {
            &mut [&mut self.all]
        };
        match f {
            Fields::Local { pos, vel } => {
                self.seen_local = true;
                let p = read3(data, pos);
                let v = vel.as_ref().and_then(|v| read3(data, v));
                for a in accs.iter_mut() {
                    a.local(p, v);
                }
            }
            Fields::Attitude { q } => {
                self.seen_attitude = true;
                let (Some(q0), Some(q1), Some(q2), Some(q3)) = (
                    q[0].f64(data),
                    q[1].f64(data),
                    q[2].f64(data),
                    q[3].f64(data),
                ) else {
                    return;
                };
                // The cosine of the angle between the body's z axis and the vertical, of the
                // rotation the quaternion stands for at any length (an all-zero one stands
                // for none).
                let norm2 = q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3;
                let cos = (1.0 - 2.0 * (q1 * q1 + q2 * q2) / norm2).clamp(-1.0, 1.0);
                if norm2 > 0.0 && cos.is_finite() {
                    for a in accs.iter_mut() {
                        a.min_cos_tilt = Some(a.min_cos_tilt.map_or(cos, |c| c.min(cos)));
                    }
                }
            }
            Fields::Rates { xyz, preferred } => {
                self.seen_rates = true;
                // The fallback's rates count only where the preferred source has none.
                if !*preferred && accs.iter().all(|a| a.max_rate2.is_some()) {
                    return;
                }
                if let Some(r) = read3(data, xyz) {
                    let rate2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
                    for a in accs.iter_mut() {
                        if *preferred {
                            max(&mut a.max_rate2, rate2);
                        } else {
                            max(&mut a.max_rate2_other, rate2);
                        }
                    }
                }
            }
        }
    }

    pub(super) fn finish(&self, missing: &mut Vec<Missing>) -> Stats {
        for (seen, fact, topic) in [
            (
                self.seen_local,
                "stats: distance, altitude, speeds",
                "vehicle_local_position",
            ),
            (
                self.seen_attitude,
                "stats.max_tilt_deg",
                "vehicle_attitude (with q)",
            ),
            (
                self.seen_rates,
                "stats.max_rotation_speed_deg_s",
                "vehicle_angular_velocity or sensor_combined",
            ),
        ] {
            if !seen {
                missing.push(Missing {
                    fact: fact.to_owned(),
                    reason: format!("the log has no {topic} rows"),
                });
            }
        }
        Stats {
            all: self.all.finish(),
            armed: self.armed.finish(),
        }
    }
}

/// Where the spectral analyses' signals are.
pub(super) enum SpectralFields {
    /// Rate setpoints, rad/s.
    Setpoint([Leaf; 3]),
    /// Measured rates, rad/s; raw sensor or controller input.
    Gyro { xyz: [Leaf; 3], raw: bool },
    /// Accelerations, m/s²; raw sensor or filtered.
    Accel { xyz: [Leaf; 3], raw: bool },
    /// Both, of `sensor_combined`.
    Combined { gyro: [Leaf; 3], accel: [Leaf; 3] },
}

impl SpectralFields {
    /// The fields, if numbers (a sample out of flight is skipped unread: a field that is not
    /// a number, text in a crafted log, would never be read at all).
    pub(super) fn bind(topic: &str, index: &LazyIndex<'_>) -> Option<SpectralFields> {
        let three = |index: &LazyIndex<'_>, names: [&str; 3]| {
            three(index, names).filter(|l| l.iter().all(|l| matches!(l, Leaf::Value(..))))
        };
        let xyz = || three(index, ["xyz[0]", "xyz[1]", "xyz[2]"]);
        match topic {
            "vehicle_rates_setpoint" => Some(SpectralFields::Setpoint(three(
                index,
                ["roll", "pitch", "yaw"],
            )?)),
            "vehicle_angular_velocity" => Some(SpectralFields::Gyro {
                xyz: xyz()?,
                raw: false,
            }),
            "vehicle_acceleration" => Some(SpectralFields::Accel {
                xyz: xyz()?,
                raw: false,
            }),
            "sensor_combined" => Some(SpectralFields::Combined {
                gyro: three(index, ["gyro_rad[0]", "gyro_rad[1]", "gyro_rad[2]"])?,
                accel: three(
                    index,
                    [
                        "accelerometer_m_s2[0]",
                        "accelerometer_m_s2[1]",
                        "accelerometer_m_s2[2]",
                    ],
                )?,
            }),
            _ => None,
        }
    }
}

/// The rate controllers' step responses, fed in flight.
#[derive(Debug, Clone, Default)]
pub(super) struct Steps {
    /// Per axis: from the controller's measured rate, and from the raw gyro (older logs).
    steps: [StepResponse; 3],
    steps_raw: [StepResponse; 3],
    seen_setpoint: bool,
}

impl Steps {
    pub(super) fn row(&mut self, f: &SpectralFields, data: &[u8], t: u64, state: &FlightState) {
        let keep = state.flying();
        let (xyz, raw) = match f {
            SpectralFields::Setpoint(xyz) => {
                self.seen_setpoint = true;
                for (k, leaf) in xyz.iter().enumerate() {
                    if let Some(v) = leaf.f64(data) {
                        self.steps[k].setpoint(v.to_degrees());
                        self.steps_raw[k].setpoint(v.to_degrees());
                    }
                }
                return;
            }
            SpectralFields::Gyro { xyz, raw } => (xyz, *raw),
            SpectralFields::Combined { gyro, .. } => (gyro, true),
            SpectralFields::Accel { .. } => return,
        };
        // Steps from the controller's rates, else the raw gyro's: the fallback is fed only
        // until the controller's rates give a response (from then on it would not be used).
        if !self.seen_setpoint || (raw && self.steps.iter().all(StepResponse::has_response)) {
            return;
        }
        let steps = if raw {
            &mut self.steps_raw
        } else {
            &mut self.steps
        };
        if !keep {
            for s in steps {
                s.skip(t);
            }
            return;
        }
        for (k, leaf) in xyz.iter().enumerate() {
            if let Some(v) = leaf.f64(data) {
                steps[k].gyro(t, v.to_degrees(), true);
            }
        }
    }

    pub(super) fn finish(self, missing: &mut Vec<Missing>) -> Vec<AxisResponse> {
        let mut responses = Vec::new();
        let names = ["roll", "pitch", "yaw"];
        for (k, (ctrl, raw)) in self.steps.into_iter().zip(self.steps_raw).enumerate() {
            // The controller's input when it gives a response, the raw gyro otherwise.
            if let Some(r) = ctrl.finish().or_else(|| raw.finish()) {
                responses.push(AxisResponse {
                    axis: names[k].to_owned(),
                    sample_rate_hz: r.sample_rate_hz,
                    time_s: r.time_s,
                    window_count: r.low.as_ref().map_or(0, |l| l.0),
                    response: r.low.map(|l| l.1),
                    window_count_high: r.high.as_ref().map_or(0, |h| h.0),
                    response_high: r.high.map(|h| h.1),
                });
            }
        }
        if responses.is_empty() {
            missing.push(Missing {
                fact: "step_response".to_owned(),
                reason: if self.seen_setpoint {
                    "no axis had 10 one-second windows in flight with a rate setpoint above 20 deg/s"
                } else {
                    "the log has no vehicle_rates_setpoint rows"
                }
                .to_owned(),
            });
        }
        responses
    }
}

/// The gyro's and the accelerometer's spectra, fed in flight.
#[derive(Debug, Clone, Default)]
pub(super) struct Spectra {
    gyro_raw: [Welch; 3],
    gyro: [Welch; 3],
    accel_raw: [Welch; 3],
    accel: [Welch; 3],
}

impl Spectra {
    pub(super) fn row(&mut self, f: &SpectralFields, data: &[u8], t: u64, state: &FlightState) {
        let keep = state.flying();
        // Spectra from the raw sensors, else the controller's rates and the filtered
        // accelerations: a fallback is fed only until its preferred source has an estimate
        // (from then on it would not be used).
        let feed = |welch: &mut [Welch; 3], xyz: &[Leaf; 3]| {
            for (w, leaf) in welch.iter_mut().zip(xyz) {
                if !keep {
                    w.skip(t);
                } else if let Some(v) = leaf.f64(data) {
                    w.push(t, v, true);
                }
            }
        };
        match f {
            SpectralFields::Setpoint(_) => {}
            SpectralFields::Gyro { xyz, raw: true } => feed(&mut self.gyro_raw, xyz),
            SpectralFields::Gyro { xyz, raw: false } => {
                if !self.gyro_raw.iter().all(Welch::has_estimate) {
                    feed(&mut self.gyro, xyz);
                }
            }
            SpectralFields::Accel { xyz, raw: true } => feed(&mut self.accel_raw, xyz),
            SpectralFields::Accel { xyz, raw: false } => {
                if !self.accel_raw.iter().all(Welch::has_estimate) {
                    feed(&mut self.accel, xyz);
                }
            }
            SpectralFields::Combined { gyro, accel } => {
                feed(&mut self.gyro_raw, gyro);
                feed(&mut self.accel_raw, accel);
            }
        }
    }

    pub(super) fn finish(self, missing: &mut Vec<Missing>) -> Vec<SpectrumOf> {
        let mut spectra = Vec::new();
        for (sensor, raw, other) in [
            ("gyro", self.gyro_raw, self.gyro),
            ("accel", self.accel_raw, self.accel),
        ] {
            for (k, (r, o)) in raw.into_iter().zip(other).enumerate() {
                // The raw sensor when the log has it (filter tuning needs what it filters).
                if let Some(s) = r.finish().or_else(|| o.finish()) {
                    spectra.push(SpectrumOf {
                        sensor: sensor.to_owned(),
                        axis: ["x", "y", "z"][k].to_owned(),
                        sample_rate_hz: s.sample_rate_hz,
                        segments: s.segments,
                        freq_hz: s.freq_hz,
                        psd: s.density,
                    });
                }
            }
        }
        if spectra.is_empty() {
            missing.push(Missing {
                fact: "spectra".to_owned(),
                reason: "no gyro or accelerometer run in flight as long as a segment".to_owned(),
            });
        }
        spectra
    }
}
