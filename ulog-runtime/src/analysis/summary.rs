//! The analysis as text for people: what `ulog analyze` prints.

use std::fmt;

use super::{Analysis, Motion};

fn opt(v: Option<f64>, unit: &str) -> String {
    v.map_or_else(
        || "-".to_owned(),
        |v| format!("{v:.2} {unit}").trim_end().to_owned(),
    )
}

fn secs(us: u64) -> f64 {
    us as f64 / 1e6
}

fn motion(f: &mut fmt::Formatter<'_>, label: &str, m: &Motion) -> fmt::Result {
    writeln!(
        f,
        "  {label:<8} distance {}, altitude range {}, max speed {} (horizontal {}, up {}, down {}), mean speed {}, max tilt {}, max rotation {}",
        opt(m.total_distance_m, "m"),
        opt(m.max_altitude_diff_m, "m"),
        opt(m.max_speed_m_s, "m/s"),
        opt(m.max_horizontal_speed_m_s, "m/s"),
        opt(m.max_speed_up_m_s, "m/s"),
        opt(m.max_speed_down_m_s, "m/s"),
        opt(m.avg_speed_m_s, "m/s"),
        opt(m.max_tilt_deg, "deg"),
        opt(m.max_rotation_speed_deg_s, "deg/s"),
    )
}

impl fmt::Display for Analysis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "Flight modes:")?;
        if self.flight_modes.is_empty() {
            writeln!(f, "  none")?;
        }
        for m in &self.flight_modes {
            writeln!(
                f,
                "  {:>9.1} s - {:>9.1} s  {:<15} ({:.1} s)",
                secs(m.start_us),
                secs(m.end_us),
                m.mode,
                m.duration_s
            )?;
        }
        for v in &self.vtol_states {
            writeln!(
                f,
                "  VTOL {} {:.1} s - {:.1} s",
                v.state,
                secs(v.start_us),
                secs(v.end_us)
            )?;
        }
        let intervals = |v: &[super::Interval]| {
            v.iter()
                .map(|i| format!("{:.1}-{:.1} s", secs(i.start_us), secs(i.end_us)))
                .collect::<Vec<_>>()
                .join(", ")
        };
        writeln!(
            f,
            "Armed: {}",
            if self.armed.is_empty() {
                "never".to_owned()
            } else {
                intervals(&self.armed)
            }
        )?;
        if !self.flights.is_empty() {
            writeln!(f, "In the air: {}", intervals(&self.flights))?;
        }
        writeln!(f, "Statistics:")?;
        motion(f, "all", &self.stats.all)?;
        motion(f, "armed", &self.stats.armed)?;
        writeln!(f, "Battery:")?;
        if self.battery.instances.is_empty() {
            writeln!(f, "  none")?;
        }
        for b in &self.battery.instances {
            writeln!(
                f,
                "  #{}: min {}, current mean {} max {}, drawn {}, {}",
                b.multi_id,
                opt(b.min_voltage_v, "V"),
                opt(b.avg_current_a, "A"),
                opt(b.max_current_a, "A"),
                opt(b.discharged_mah, "mAh"),
                b.cells
                    .map_or_else(|| "cells unknown".to_owned(), |c| format!("{c}S"))
            )?;
        }
        let g = &self.gps_quality;
        writeln!(
            f,
            "GPS: satellites {}, max hdop {}, max eph {}, max epv {}, fix types {:?}{}",
            match (g.min_satellites, g.max_satellites) {
                (Some(lo), Some(hi)) => format!("{lo}-{hi}"),
                _ => "-".to_owned(),
            },
            opt(g.max_hdop, ""),
            opt(g.max_eph_m, "m"),
            opt(g.max_epv_m, "m"),
            g.fix_types_seen,
            g.max_jamming_indicator
                .map_or(String::new(), |j| format!(", max jamming indicator {j:.0}"))
        )?;
        writeln!(f, "GPS track: {} points", self.gps_track.len())?;
        let v = &self.vibration;
        match (v.accel_vibe_mean, v.accel_vibe_max) {
            (Some(mean), Some(max)) => writeln!(
                f,
                "Vibration: mean {mean:.2} m/s², max {max:.2} m/s²: {}",
                v.status
            )?,
            _ => writeln!(f, "Vibration: -")?,
        }
        writeln!(
            f,
            "Non-default parameters: {}",
            self.non_default_params.len()
        )?;
        for r in &self.step_response {
            let at = |s: f64| {
                r.response
                    .as_ref()
                    .and_then(|v| v.get((s * r.sample_rate_hz) as usize))
                    .copied()
            };
            writeln!(
                f,
                "Step response {}: {} windows, {} at 50 ms, {} at 200 ms",
                r.axis,
                r.window_count,
                at(0.05).map_or("-".to_owned(), |v| format!("{v:.2}")),
                at(0.2).map_or("-".to_owned(), |v| format!("{v:.2}"))
            )?;
        }
        writeln!(f, "Diagnostics:")?;
        if self.diagnostics.is_empty() {
            writeln!(f, "  none")?;
        }
        for d in &self.diagnostics {
            writeln!(f, "  {:?}: {}", d.severity, d.summary)?;
        }
        if !self.missing.is_empty() {
            writeln!(f, "Not in the log:")?;
            for m in &self.missing {
                writeln!(f, "  {}: {}", m.fact, m.reason)?;
            }
        }
        Ok(())
    }
}
