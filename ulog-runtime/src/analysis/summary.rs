//! The analysis as text for people: what `ulog analyze` prints.

use std::fmt;

use super::{Analysis, Motion};

/// Armed and in-air intervals listed one by one up to this many; beyond, the first three,
/// the last two and the count.
const SHOWN_INTERVALS: usize = 6;

fn opt(v: Option<f64>, unit: &str) -> String {
    v.map_or_else(
        || "-".to_owned(),
        // `+ 0.0`: a negative zero (a battery's current of -0.0 A) shown as 0.00.
        |v| format!("{:.2} {unit}", v + 0.0).trim_end().to_owned(),
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
            let list = |v: &[super::Interval]| {
                v.iter()
                    .map(|i| format!("{:.1}-{:.1} s", secs(i.start_us), secs(i.end_us)))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            // A long log of many flights: the first and last ones, and how many in all.
            if v.len() <= SHOWN_INTERVALS {
                return list(v);
            }
            let total: u64 = v.iter().map(|i| i.end_us.saturating_sub(i.start_us)).sum();
            format!(
                "{}, ..., {} ({} intervals, {:.1} s in all; --json lists each)",
                list(&v[..3]),
                list(&v[v.len() - 2..]),
                v.len(),
                secs(total)
            )
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
        // Unknown (not 0) when the log has no defaults to compare with.
        if self.missing.iter().any(|m| m.fact == "non_default_params") {
            writeln!(f, "Non-default parameters: -")?;
        } else {
            writeln!(
                f,
                "Non-default parameters: {}",
                self.non_default_params.len()
            )?;
        }
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

#[cfg(test)]
mod tests {
    use super::super::{Analysis, Interval};

    fn intervals(n: u64) -> Vec<Interval> {
        (0..n)
            .map(|k| Interval {
                start_us: k * 10_000_000,
                end_us: k * 10_000_000 + 2_000_000,
            })
            .collect()
    }

    fn line<'a>(text: &'a str, head: &str) -> &'a str {
        text.lines().find(|l| l.starts_with(head)).unwrap()
    }

    #[test]
    fn many_intervals_are_summed_up_and_a_few_listed_whole() {
        let few = Analysis {
            armed: intervals(6),
            ..Analysis::default()
        };
        assert_eq!(
            line(&few.to_string(), "Armed: "),
            "Armed: 0.0-2.0 s, 10.0-12.0 s, 20.0-22.0 s, 30.0-32.0 s, 40.0-42.0 s, 50.0-52.0 s"
        );
        let many = Analysis {
            armed: intervals(47),
            flights: intervals(7),
            ..Analysis::default()
        };
        let text = many.to_string();
        assert_eq!(
            line(&text, "Armed: "),
            "Armed: 0.0-2.0 s, 10.0-12.0 s, 20.0-22.0 s, ..., 450.0-452.0 s, 460.0-462.0 s \
             (47 intervals, 94.0 s in all; --json lists each)"
        );
        assert_eq!(
            line(&text, "In the air: "),
            "In the air: 0.0-2.0 s, 10.0-12.0 s, 20.0-22.0 s, ..., 50.0-52.0 s, 60.0-62.0 s \
             (7 intervals, 14.0 s in all; --json lists each)"
        );
    }
}
