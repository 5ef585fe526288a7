//! GPS interference: once a GPS instance (`vehicle_gps_position`; in a log without it,
//! `sensor_gps`) has held a 3-D fix for 10 rows, while armed, any of: the horizontal
//! accuracy `eph` above three times its baseline and 5 m more; the vertical `epv` above
//! three times its baseline and 8 m more; the satellites used below half their baseline;
//! `jamming_state` 2 (warning; PX4 1.17 names it mitigated) or 3 (critical; 1.17:
//! detected); the fix lost; for at least 1 s. The baselines are moving averages over
//! the rows without any of these. Critical when the fix was lost, `eph` passed 10 m or
//! jamming was critical; a warning otherwise. A log that never gets a fix reports nothing.

use super::{Diagnostic, Episode, Evidence, Severity, secs};
use crate::analysis::LazyIndex;
use crate::analysis::state::FlightState;
use crate::columns::Leaf;

/// Rows of fix before anything is judged.
pub const SETTLE_ROWS: u32 = 10;
/// How long a condition must last, µs.
pub const MIN_DURATION_US: u64 = 1_000_000;

/// Where the GPS topic's fields are, and whether the topic is `sensor_gps` (read only in
/// a log without `vehicle_gps_position`).
pub(crate) struct Fields {
    sensor: bool,
    multi_id: u8,
    fix: Leaf,
    eph: Option<Leaf>,
    epv: Option<Leaf>,
    sats: Option<Leaf>,
    jamming_state: Option<Leaf>,
    jamming: Option<Leaf>,
    noise: Option<Leaf>,
}

impl Fields {
    pub(crate) fn bind(topic: &str, multi_id: u8, index: &LazyIndex<'_>) -> Option<Fields> {
        Some(Fields {
            sensor: topic == "sensor_gps",
            multi_id,
            fix: index.get("fix_type")?,
            eph: index.get("eph"),
            epv: index.get("epv"),
            sats: index.get("satellites_used"),
            jamming_state: index.get("jamming_state"),
            jamming: index.get("jamming_indicator"),
            noise: index.get("noise_per_ms"),
        })
    }
}

#[derive(Debug, Clone, Default)]
struct Receiver {
    fixed_rows: u32,
    eph: f64,
    epv: f64,
    sats: f64,
    episode: Episode,
    worst: Option<Worst>,
}

#[derive(Debug, Clone)]
struct Worst {
    eph: f64,
    epv: f64,
    sats: u32,
    baseline_eph: f64,
    baseline_sats: f64,
    jamming: Option<f64>,
    noise: Option<f64>,
    reasons: Vec<&'static str>,
    critical: bool,
}

/// Every receiver's state, and the episodes found.
#[derive(Debug, Clone, Default)]
pub(crate) struct Interference {
    /// Per (`sensor_gps`?, instance).
    receivers: Vec<((bool, u8), Receiver)>,
    found: Vec<((bool, u8), u64, u64, Worst)>,
}

impl Interference {
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    pub(crate) fn row(&mut self, f: &Fields, data: &[u8], t: u64, state: &FlightState) {
        let get = |l: Option<Leaf>| l.and_then(|l| l.f64(data)).filter(|v| v.is_finite());
        let key = (f.sensor, f.multi_id);
        let r = match self.receivers.iter().position(|(k, _)| *k == key) {
            Some(i) => &mut self.receivers[i].1,
            None => {
                self.receivers.push((key, Receiver::default()));
                &mut self.receivers.last_mut().expect("pushed").1
            }
        };
        let fix = get(Some(f.fix)).unwrap_or(0.0);
        let (eph, epv, sats) = (get(f.eph), get(f.epv), get(f.sats));
        let jamming_state = get(f.jamming_state).unwrap_or(0.0);
        if r.fixed_rows < SETTLE_ROWS {
            if fix >= 3.0 {
                // The first baselines: the mean of the settling rows.
                let n = f64::from(r.fixed_rows);
                r.eph = (r.eph * n + eph.unwrap_or(0.0)) / (n + 1.0);
                r.epv = (r.epv * n + epv.unwrap_or(0.0)) / (n + 1.0);
                r.sats = (r.sats * n + sats.unwrap_or(0.0)) / (n + 1.0);
                r.fixed_rows += 1;
            }
            return;
        }
        let mut reasons = Vec::new();
        if fix < 3.0 {
            reasons.push("fix lost");
        }
        if eph.is_some_and(|e| e > (3.0 * r.eph).max(r.eph + 5.0)) {
            reasons.push("eph spike");
        }
        if epv.is_some_and(|e| e > (3.0 * r.epv).max(r.epv + 8.0)) {
            reasons.push("epv spike");
        }
        if sats.is_some_and(|s| r.sats > 0.0 && s < 0.5 * r.sats) {
            reasons.push("satellites lost");
        }
        if jamming_state >= 2.0 {
            reasons.push("jamming");
        }
        let bad = state.armed && !reasons.is_empty();
        if bad {
            let critical = fix < 3.0 || eph.is_some_and(|e| e > 10.0) || jamming_state >= 3.0;
            let w = r.worst.get_or_insert_with(|| Worst {
                eph: 0.0,
                epv: 0.0,
                sats: u32::MAX,
                baseline_eph: r.eph,
                baseline_sats: r.sats,
                jamming: None,
                noise: None,
                reasons: Vec::new(),
                critical: false,
            });
            w.eph = w.eph.max(eph.unwrap_or(0.0));
            w.epv = w.epv.max(epv.unwrap_or(0.0));
            w.sats = w.sats.min(sats.map_or(u32::MAX, |s| s as u32));
            if let Some(j) = get(f.jamming) {
                w.jamming = Some(w.jamming.map_or(j, |x: f64| x.max(j)));
            }
            if let Some(n) = get(f.noise) {
                w.noise = Some(w.noise.map_or(n, |x: f64| x.max(n)));
            }
            for reason in reasons {
                if !w.reasons.contains(&reason) {
                    w.reasons.push(reason);
                }
            }
            w.critical |= critical;
        } else if reasons.is_empty() {
            // Baselines follow the good rows.
            const A: f64 = 0.02;
            r.eph += A * (eph.unwrap_or(r.eph) - r.eph);
            r.epv += A * (epv.unwrap_or(r.epv) - r.epv);
            r.sats += A * (sats.unwrap_or(r.sats) - r.sats);
        }
        if let Some((start, end)) = r.episode.see(bad, t)
            && let Some(w) = r.worst.take()
            && end - start >= MIN_DURATION_US
        {
            self.found.push((key, start, end, w));
        }
    }

    /// Whether any GPS row was seen.
    pub(crate) fn seen(&self) -> bool {
        !self.receivers.is_empty()
    }

    pub(crate) fn finish(mut self, end: u64) -> Vec<Diagnostic> {
        // The best source the log has, as the RC loss picks its own: `sensor_gps` (true)
        // only in a log without `vehicle_gps_position` (false).
        let best = self.receivers.iter().map(|((sensor, _), _)| *sensor).min();
        for (m, r) in &mut self.receivers {
            if let Some((start, stop)) = r.episode.close(end)
                && let Some(w) = r.worst.take()
                && stop - start >= MIN_DURATION_US
            {
                self.found.push((*m, start, stop, w));
            }
        }
        self.found
            .into_iter()
            .filter(|((s, _), ..)| Some(*s) == best)
            .map(|((sensor, multi_id), start, end, w)| Diagnostic {
                id: "gps_interference".to_owned(),
                summary: format!(
                    "GPS {multi_id} degraded for {:.1} s from {:.1} s ({}): eph up to {:.1} m \
                     (baseline {:.1} m), {} satellites (baseline {:.0})",
                    secs(end - start),
                    secs(start),
                    w.reasons.join(", "),
                    w.eph,
                    w.baseline_eph,
                    if w.sats == u32::MAX { 0 } else { w.sats },
                    w.baseline_sats
                ),
                severity: if w.critical {
                    Severity::Critical
                } else {
                    Severity::Warning
                },
                timestamp_us: start,
                end_timestamp_us: Some(end),
                evidence: Evidence::GpsInterference {
                    source: if sensor {
                        "sensor_gps"
                    } else {
                        "vehicle_gps_position"
                    }
                    .to_owned(),
                    multi_id,
                    eph_m: w.eph,
                    epv_m: w.epv,
                    num_satellites: if w.sats == u32::MAX { 0 } else { w.sats },
                    baseline_eph_m: w.baseline_eph,
                    baseline_satellites: w.baseline_sats,
                    jamming_indicator: w.jamming,
                    noise_level: w.noise,
                    reasons: w.reasons.iter().map(|r| (*r).to_owned()).collect(),
                },
            })
            .collect()
    }
}
