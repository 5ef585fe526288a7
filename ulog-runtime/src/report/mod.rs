//! A flight report (feature `report`): one self-contained HTML file (no script, no network
//! at view time) with SVG plots drawn by plotters, what Flight Review shows of a log:
//! altitude and speeds, attitude and rates with their setpoints per axis, actuator outputs,
//! battery voltage and current, GPS quality, vibration, the gyro's power spectral density,
//! the rate controllers' step responses, the GPS track, the flight modes behind every time
//! plot and as a timeline; the analysis's summary and diagnostics, non-default and changed
//! parameters and the logged messages as tables. A plot the log cannot give is listed with
//! why.
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let log = ulog_runtime::Log::open("flight.ulg")?;
//! let report = ulog_runtime::report::Report::of_log(&log, "flight.ulg")?;
//! std::fs::write("flight.html", report.html())?;
//! # Ok(()) }
//! ```

mod html;
mod plot;
mod series;

use crate::Log;
use crate::analysis::Analysis;
use plot::Band;
use series::{Series, Table, euler_deg};

/// Why a report could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReportError {
    /// A plot could not be drawn.
    #[error("plot `{plot}`: {reason}")]
    Plot {
        /// The plot's id.
        plot: String,
        /// Why.
        reason: String,
    },
}

/// One plot of a report.
#[derive(Debug, Clone)]
pub struct Plot {
    /// Its id (`altitude`, `rate_roll`...), the `id` of its HTML element.
    pub id: String,
    /// Its title.
    pub title: String,
    /// The SVG.
    pub svg: String,
}

/// A report of one log ([module docs](self)).
#[derive(Debug, Clone)]
pub struct Report {
    /// The log's file name.
    pub file_name: String,
    /// The analysis the report shows.
    pub analysis: Analysis,
    /// The plots drawn, in page order.
    pub plots: Vec<Plot>,
    /// The plots the log could not give: (title, why).
    pub left_out: Vec<(String, String)>,
    /// Header facts: (key, value), as `ulog info` names them.
    pub facts: Vec<(String, String)>,
    /// Parameter changes after the start: (time s, name, value).
    pub parameter_changes: Vec<(f64, String, String)>,
    /// Logged messages: (time s, level, text).
    pub messages: Vec<(f64, String, String)>,
}

/// The plots being made.
struct Plots<'l> {
    log: &'l Log<'l>,
    t0: u64,
    bands: Vec<Band>,
    plots: Vec<Plot>,
    left_out: Vec<(String, String)>,
}

impl Report {
    /// The report of a whole-file log (its analysis made here).
    pub fn of_log(log: &Log<'_>, file_name: &str) -> Result<Report, ReportError> {
        Report::with_analysis(log, file_name, Analysis::of_log(log))
    }

    /// The report of a log whose analysis is already made.
    pub fn with_analysis(
        log: &Log<'_>,
        file_name: &str,
        analysis: Analysis,
    ) -> Result<Report, ReportError> {
        // Times since boot, as the analysis, pyulog and the tables give them.
        let t0 = 0;
        let secs = |t: u64| (t as f64 - t0 as f64) / 1e6;
        let bands: Vec<Band> = analysis
            .flight_modes
            .iter()
            .map(|m| Band {
                start_s: secs(m.start_us),
                end_s: secs(m.end_us),
                label: m.mode.clone(),
            })
            .collect();
        let mut p = Plots {
            log,
            t0,
            bands,
            plots: Vec::new(),
            left_out: Vec::new(),
        };
        p.timeline(log)?;
        p.altitude_and_speed()?;
        p.attitude()?;
        p.rates()?;
        p.outputs()?;
        p.battery()?;
        p.gps()?;
        p.vibration()?;
        p.spectra(&analysis)?;
        p.steps(&analysis)?;
        p.track(&analysis)?;
        let meta = log.metadata();
        let mut facts = vec![("file".to_owned(), file_name.to_owned())];
        for key in ["sys_name", "ver_hw", "ver_sw", "sys_uuid"] {
            if let Some(v) = meta.info_value(key) {
                // Text as it is, not quoted.
                let text = v.as_str().map_or_else(|| v.to_string(), str::to_owned);
                facts.push((key.to_owned(), text));
            }
        }
        // `ver_sw_release` as `ulog info` gives it.
        match (meta.software_version(), meta.version_info()) {
            (Some(v), _) => facts.push(("software".to_owned(), v)),
            (None, Some(v)) => facts.push((
                "software".to_owned(),
                format!(
                    "a development build (ver_sw_release {}.{}.{})",
                    v.major, v.minor, v.patch
                ),
            )),
            (None, None) => {}
        }
        if let Some(utc) = log.header().start_utc() {
            facts.push(("start (UTC)".to_owned(), utc.to_string()));
        }
        let parameter_changes = log
            .parameter_changes()
            .iter()
            .map(|c| (secs(c.timestamp), c.name.clone(), c.value.to_string()))
            .collect();
        let messages = log
            .logged_messages()
            .iter()
            .map(|m| {
                let level = m
                    .level()
                    .map_or_else(|| m.level_byte.to_string(), |l| format!("{l:?}"));
                (secs(m.timestamp), level, m.text.clone())
            })
            .collect();
        Ok(Report {
            file_name: file_name.to_owned(),
            analysis,
            plots: p.plots,
            left_out: p.left_out,
            facts,
            parameter_changes,
            messages,
        })
    }

    /// The report as one HTML document.
    pub fn html(&self) -> String {
        html::page(self)
    }
}

impl Plots<'_> {
    fn table(&self, topic: &str, multi_id: u8) -> Option<Table> {
        Table::read(self.log, topic, multi_id, self.t0)
    }

    fn add(
        &mut self,
        id: &str,
        title: &str,
        svg: Result<String, String>,
    ) -> Result<(), ReportError> {
        let svg = svg.map_err(|reason| ReportError::Plot {
            plot: id.to_owned(),
            reason,
        })?;
        self.plots.push(Plot {
            id: id.to_owned(),
            title: title.to_owned(),
            svg,
        });
        Ok(())
    }

    fn lack(&mut self, title: &str, why: impl Into<String>) {
        self.left_out.push((title.to_owned(), why.into()));
    }

    /// A time plot of non-empty series, or why there is none.
    fn time(
        &mut self,
        id: &str,
        title: &str,
        unit: &str,
        series: Vec<Series>,
        levels: &[(f64, &str)],
        lacking: &str,
    ) -> Result<(), ReportError> {
        let series: Vec<Series> = series
            .into_iter()
            .filter(|s| !s.points.is_empty())
            .collect();
        if series.is_empty() {
            self.lack(title, lacking);
            return Ok(());
        }
        let svg = plot::time_plot(title, unit, &series, &self.bands, levels);
        self.add(id, title, svg)
    }

    fn timeline(&mut self, log: &Log<'_>) -> Result<(), ReportError> {
        if self.bands.is_empty() {
            self.lack("Flight modes", "the log has no vehicle_status rows");
            return Ok(());
        }
        let secs = |r: crate::Row<'_>| (r.timestamp as f64 - self.t0 as f64) / 1e6;
        let end = log.data().next_back().map_or(0.0, secs);
        // The span of the log's rows, as the time plots show it (not from boot: a log that
        // starts an hour after boot would squeeze its modes to the right edge).
        let first = log.data().next().map_or(f64::INFINITY, secs);
        let start = self.bands.first().map_or(0.0, |b| b.start_s).min(first);
        let svg = plot::mode_timeline(
            &self.bands,
            start,
            end.max(self.bands.last().map_or(0.0, |b| b.end_s)),
        );
        self.add("modes", "Flight modes", svg)
    }

    fn altitude_and_speed(&mut self) -> Result<(), ReportError> {
        let Some(t) = self.table("vehicle_local_position", 0) else {
            self.lack("Altitude", "the log has no vehicle_local_position rows");
            self.lack("Speed", "the log has no vehicle_local_position rows");
            return Ok(());
        };
        let alt: Vec<f64> = t
            .field("z")
            .unwrap_or_default()
            .iter()
            .map(|z| -z)
            .collect();
        let altitude = vec![t.series("altitude (-z)", &alt)];
        self.time(
            "altitude",
            "Altitude",
            "m",
            altitude,
            &[],
            "no finite z in vehicle_local_position",
        )?;
        let (vx, vy, vz) = (t.field("vx"), t.field("vy"), t.field("vz"));
        let mut speed = Vec::new();
        if let (Some(vx), Some(vy)) = (&vx, &vy) {
            let h: Vec<f64> = vx.iter().zip(vy).map(|(x, y)| x.hypot(*y)).collect();
            speed.push(t.series("horizontal", &h));
        }
        if let Some(vz) = &vz {
            let up: Vec<f64> = vz.iter().map(|v| -v).collect();
            speed.push(t.series("up (-vz)", &up));
        }
        self.time(
            "speed",
            "Speed",
            "m/s",
            speed,
            &[],
            "no finite vx, vy or vz in vehicle_local_position",
        )
    }

    fn attitude(&mut self) -> Result<(), ReportError> {
        let q = |t: &Table, prefix: &str| -> Option<[Vec<f64>; 4]> {
            Some([
                t.field(&format!("{prefix}[0]"))?,
                t.field(&format!("{prefix}[1]"))?,
                t.field(&format!("{prefix}[2]"))?,
                t.field(&format!("{prefix}[3]"))?,
            ])
        };
        let Some((att, qa)) = self
            .table("vehicle_attitude", 0)
            .and_then(|t| q(&t, "q").map(|q| (t, q)))
        else {
            for axis in ["Roll", "Pitch", "Yaw"] {
                self.lack(
                    &format!("{axis} angle"),
                    "the log has no vehicle_attitude rows with q",
                );
            }
            return Ok(());
        };
        let angles = euler_deg([&qa[0], &qa[1], &qa[2], &qa[3]]);
        let sp = self.table("vehicle_attitude_setpoint", 0);
        let sp_angles: Option<(Table, [Vec<f64>; 3])> = sp.and_then(|t| {
            if let Some(qd) = q(&t, "q_d") {
                let a = euler_deg([&qd[0], &qd[1], &qd[2], &qd[3]]);
                Some((t, a))
            } else {
                let body = |n: &str| {
                    t.field(n)
                        .map(|v| v.iter().map(|r| r.to_degrees()).collect())
                };
                let a = [body("roll_body")?, body("pitch_body")?, body("yaw_body")?];
                Some((t, a))
            }
        });
        for (k, axis) in ["roll", "pitch", "yaw"].iter().enumerate() {
            let mut series = vec![att.series("estimated", &angles[k])];
            if let Some((t, a)) = &sp_angles {
                series.push(t.series("setpoint", &a[k]));
            }
            let title = format!("{} angle", capitalized(axis));
            self.time(
                &format!("attitude_{axis}"),
                &title,
                "deg",
                series,
                &[],
                "no finite angle in vehicle_attitude.q or its setpoint",
            )?;
        }
        Ok(())
    }

    fn rates(&mut self) -> Result<(), ReportError> {
        let measured = self
            .table("vehicle_angular_velocity", 0)
            .and_then(|t| {
                let v = [t.field("xyz[0]")?, t.field("xyz[1]")?, t.field("xyz[2]")?];
                Some((t, v))
            })
            .or_else(|| {
                let t = self.table("sensor_combined", 0)?;
                let v = [
                    t.field("gyro_rad[0]")?,
                    t.field("gyro_rad[1]")?,
                    t.field("gyro_rad[2]")?,
                ];
                Some((t, v))
            });
        let Some((t, rates)) = measured else {
            for axis in ["Roll", "Pitch", "Yaw"] {
                self.lack(
                    &format!("{axis} rate"),
                    "the log has no vehicle_angular_velocity or sensor_combined rows",
                );
            }
            return Ok(());
        };
        let sp = self.table("vehicle_rates_setpoint", 0);
        for (k, axis) in ["roll", "pitch", "yaw"].iter().enumerate() {
            let deg: Vec<f64> = rates[k].iter().map(|r| r.to_degrees()).collect();
            let mut series = vec![t.series("measured", &deg)];
            if let Some(s) = &sp
                && let Some(v) = s.field(axis)
            {
                let deg: Vec<f64> = v.iter().map(|r| r.to_degrees()).collect();
                series.push(s.series("setpoint", &deg));
            }
            let title = format!("{} rate", capitalized(axis));
            self.time(
                &format!("rate_{axis}"),
                &title,
                "deg/s",
                series,
                &[],
                "no finite rate measured or set",
            )?;
        }
        Ok(())
    }

    fn outputs(&mut self) -> Result<(), ReportError> {
        let title = "Actuator outputs";
        let mut series = Vec::new();
        if let Some(t) = self.table("actuator_outputs", 0) {
            let n = t
                .field("noutputs")
                .and_then(|n| {
                    n.iter()
                        .copied()
                        .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))))
                })
                .unwrap_or(16.0) as usize;
            for k in 0..n.min(16) {
                if let Some(v) = t.field(&format!("output[{k}]")) {
                    series.push(t.series(&format!("output[{k}]"), &v));
                }
            }
        } else if let Some(t) = self.table("actuator_motors", 0) {
            for k in 0..12 {
                if let Some(v) = t.field(&format!("control[{k}]"))
                    && v.iter().any(|x| x.is_finite())
                {
                    series.push(t.series(&format!("control[{k}]"), &v));
                }
            }
        }
        // Channels that never move (unused ones) say nothing.
        series.retain(|s| {
            let lo = s.points.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
            let hi = s
                .points
                .iter()
                .map(|p| p.1)
                .fold(f64::NEG_INFINITY, f64::max);
            hi > lo
        });
        series.truncate(8);
        self.time(
            "outputs",
            title,
            "output",
            series,
            &[],
            "the log has no actuator_outputs or actuator_motors rows that change",
        )
    }

    fn battery(&mut self) -> Result<(), ReportError> {
        let mut voltage = Vec::new();
        let mut current = Vec::new();
        let mut any = false;
        for m in 0..4u8 {
            let Some(t) = self.table("battery_status", m) else {
                continue;
            };
            any = true;
            if let Some(v) = t.first_field(&["voltage_v", "voltage_filtered_v"]) {
                voltage.push(t.series(&format!("battery {m}"), &v));
            }
            if let Some(c) = t.first_field(&["current_a", "current_filtered_a"]) {
                current.push(t.series(&format!("battery {m}"), &c));
            }
        }
        let lacking = |what: &'static str| {
            if any {
                what
            } else {
                "the log has no battery_status rows"
            }
        };
        self.time(
            "battery_voltage",
            "Battery voltage",
            "V",
            voltage,
            &[],
            lacking("no finite voltage_v or voltage_filtered_v in battery_status"),
        )?;
        self.time(
            "battery_current",
            "Battery current",
            "A",
            current,
            &[],
            lacking("no finite current_a or current_filtered_a in battery_status"),
        )
    }

    fn gps(&mut self) -> Result<(), ReportError> {
        let t = self
            .table("vehicle_gps_position", 0)
            .or_else(|| self.table("sensor_gps", 0));
        let mut series = Vec::new();
        if let Some(t) = &t {
            for (name, label) in [
                ("satellites_used", "satellites"),
                ("eph", "eph (m)"),
                ("epv", "epv (m)"),
                ("hdop", "hdop"),
            ] {
                if let Some(v) = t.field(name) {
                    series.push(t.series(label, &v));
                }
            }
        }
        self.time(
            "gps",
            "GPS quality",
            "",
            series,
            &[],
            if t.is_some() {
                "no finite satellites_used, eph, epv or hdop"
            } else {
                "the log has no vehicle_gps_position or sensor_gps rows"
            },
        )
    }

    fn vibration(&mut self) -> Result<(), ReportError> {
        let mut series = Vec::new();
        for m in 0..4u8 {
            if let Some(t) = self.table("vehicle_imu_status", m)
                && let Some(v) = t.field("accel_vibration_metric")
            {
                series.push(t.series(&format!("IMU {m}"), &v));
            }
        }
        let levels = [
            (crate::analysis::VIBRATION_GOOD_MEAN, "good below"),
            (crate::analysis::VIBRATION_CRITICAL_MEAN, "critical from"),
        ];
        if series.is_empty() {
            self.lack(
                "Vibration",
                "the log has no vehicle_imu_status rows with accel_vibration_metric",
            );
            return Ok(());
        }
        self.time(
            "vibration",
            "Vibration (accelerometer)",
            "m/s²",
            series,
            &levels,
            "no finite accel_vibration_metric",
        )
    }

    fn spectra(&mut self, analysis: &Analysis) -> Result<(), ReportError> {
        let series: Vec<Series> = analysis
            .spectra
            .iter()
            .filter(|s| s.sensor == "gyro")
            .map(|s| Series {
                name: s.axis.clone(),
                points: s
                    .freq_hz
                    .iter()
                    .copied()
                    .zip(s.psd.iter().copied())
                    .collect(),
            })
            .collect();
        if series.is_empty() {
            self.lack(
                "Gyro power spectral density",
                "no gyro spectrum (see the analysis's missing facts)",
            );
            return Ok(());
        }
        let svg = plot::xy_plot(
            "Gyro power spectral density",
            "frequency (Hz)",
            "(rad/s)²/Hz",
            &series,
            true,
        );
        self.add("gyro_psd", "Gyro power spectral density", svg)
    }

    fn steps(&mut self, analysis: &Analysis) -> Result<(), ReportError> {
        let series: Vec<Series> = analysis
            .step_response
            .iter()
            .filter_map(|r| {
                let response = r.response.as_ref().or(r.response_high.as_ref())?;
                Some(Series {
                    name: r.axis.clone(),
                    points: r
                        .time_s
                        .iter()
                        .copied()
                        .zip(response.iter().copied())
                        .collect(),
                })
            })
            .collect();
        if series.is_empty() {
            self.lack(
                "Step response",
                "no axis had enough rate-setpoint windows in flight",
            );
            return Ok(());
        }
        let svg = plot::xy_plot(
            "Rate controller step response",
            "time (s)",
            "response",
            &series,
            false,
        );
        self.add("step_response", "Step response", svg)
    }

    fn track(&mut self, analysis: &Analysis) -> Result<(), ReportError> {
        let Some(first) = analysis.gps_track.first() else {
            self.lack("GPS track", "the log has no GPS position with a fix");
            return Ok(());
        };
        // Metres east and north of the start (equirectangular: fine over a flight).
        const R: f64 = 6_371_000.0;
        let (lat0, lon0) = (first.lat_deg.to_radians(), first.lon_deg.to_radians());
        let points = analysis
            .gps_track
            .iter()
            .map(|p| {
                let (lat, lon) = (p.lat_deg.to_radians(), p.lon_deg.to_radians());
                ((lon - lon0) * lat0.cos() * R, (lat - lat0) * R)
            })
            // A latitude of 1e308° is finite and its metres are not.
            .filter(|(x, y): &(f64, f64)| x.is_finite() && y.is_finite())
            .collect();
        let svg = plot::track_plot(
            "GPS track",
            &[Series {
                name: "track".to_owned(),
                points,
            }],
        );
        self.add("track", "GPS track", svg)
    }
}

fn capitalized(s: &str) -> String {
    let mut c = s.chars();
    c.next()
        .map(|f| f.to_uppercase().chain(c).collect())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::tests::{Faults, flight};

    #[test]
    fn the_mode_timeline_spans_the_logs_rows_not_the_time_since_boot() {
        // A log that starts an hour after boot, as a log started on arming does.
        let mut w = crate::Writer::new(Vec::new(), crate::WriterOptions::default()).unwrap();
        w.format("vehicle_status:uint64_t timestamp;uint8_t nav_state;uint8_t arming_state;")
            .unwrap();
        let sub = w.subscribe("vehicle_status", 0).unwrap();
        for (k, nav) in [(0u64, 2u8), (5, 3), (10, 3)] {
            let mut row = (3_600_000_000 + k * 1_000_000).to_le_bytes().to_vec();
            row.extend([nav, 2]);
            w.data(sub, &row).unwrap();
        }
        let log = Log::from_vec(w.into_inner()).unwrap();
        let r = Report::of_log(&log, "late.ulg").unwrap();
        let modes = &r.plots.iter().find(|p| p.id == "modes").unwrap().svg;
        // The x axis' tick labels: every one within the rows' 3600 to 3610 s.
        let ticks: Vec<f64> = modes
            .split("<text")
            .filter_map(|t| t.split('>').nth(1)?.split('<').next()?.trim().parse().ok())
            .collect();
        assert!(ticks.len() >= 3, "{modes}");
        assert!(
            ticks.iter().all(|t| (3600.0..=3610.0).contains(t)),
            "{ticks:?}"
        );
    }

    #[test]
    fn a_flight_gives_its_plots_and_says_which_it_cannot() {
        let bytes = flight(Faults {
            steps: true,
            ..Faults::default()
        });
        let log = Log::from_slice(&bytes).unwrap();
        let r = Report::of_log(&log, "flight.ulg").unwrap();
        let ids: Vec<&str> = r.plots.iter().map(|p| p.id.as_str()).collect();
        assert_eq!(
            ids,
            [
                "modes",
                "altitude",
                "speed",
                "attitude_roll",
                "attitude_pitch",
                "attitude_yaw",
                "rate_roll",
                "rate_pitch",
                "rate_yaw",
                "outputs",
                "battery_voltage",
                "battery_current",
                "gps",
                "vibration",
                "gyro_psd",
                "step_response",
                "track"
            ]
        );
        assert!(r.left_out.is_empty(), "{:?}", r.left_out);
        // The flight's modes name the bands, in the timeline's text.
        let modes = &r.plots[0].svg;
        assert!(modes.contains("Position") && modes.contains("Mission"));
        let html = r.html();
        assert!(html.starts_with("<!DOCTYPE html>"));
        assert_eq!(html.matches("<svg").count(), ids.len());
        // A log without those topics: nothing plotted, every plot said why.
        let mut w = crate::Writer::new(Vec::new(), crate::WriterOptions::default()).unwrap();
        w.info("sys_name", &crate::Value::String("PX4".to_owned()))
            .unwrap();
        // v1.15.1, a release.
        w.info(
            "ver_sw_release",
            &crate::Value::Scalar(crate::value::Scalar::UInt32(0x010f_01ff)),
        )
        .unwrap();
        w.log(crate::LogLevel::Info, 1, "<b>odd</b> & text")
            .unwrap();
        let empty = Log::from_vec(w.into_inner()).unwrap();
        let r = Report::of_log(&empty, "empty.ulg").unwrap();
        assert_eq!(
            r.facts[1..],
            [
                ("sys_name".to_owned(), "PX4".to_owned()),
                ("software".to_owned(), "v1.15.1".to_owned())
            ]
        );
        assert!(r.plots.is_empty());
        assert_eq!(r.left_out.len(), 17);
        let html = r.html();
        assert!(html.contains("&lt;b&gt;odd&lt;/b&gt; &amp; text"));
        assert!(!html.contains("<b>odd"));
    }
}

/// The report of logs whose plotted values are any a `double` can hold.
#[cfg(test)]
mod extreme {
    use super::*;

    /// A log of the topics the report plots, every measured field a `double` taking the
    /// extremes of the type in turn.
    fn extreme_log(values: &[f64]) -> Vec<u8> {
        let topics: &[(&str, &str)] = &[
            (
                "vehicle_local_position",
                "double x;double y;double z;double vx;double vy;double vz;",
            ),
            ("vehicle_attitude", "double[4] q;"),
            ("vehicle_attitude_setpoint", "double[4] q_d;"),
            ("vehicle_angular_velocity", "double[3] xyz;"),
            (
                "vehicle_rates_setpoint",
                "double roll;double pitch;double yaw;",
            ),
            ("actuator_outputs", "double[16] output;"),
            (
                "battery_status",
                "double voltage_v;double current_a;double discharged_mah;",
            ),
            (
                "vehicle_gps_position",
                "double lat;double lon;double alt;double eph;double epv;double hdop;uint8_t fix_type;uint8_t satellites_used;",
            ),
            ("vehicle_imu_status", "double accel_vibration_metric;"),
            (
                "sensor_combined",
                "double[3] gyro_rad;double[3] accelerometer_m_s2;",
            ),
        ];
        let mut w = crate::Writer::new(Vec::new(), crate::WriterOptions::default()).unwrap();
        w.format("vehicle_status:uint64_t timestamp;uint8_t nav_state;uint8_t arming_state;")
            .unwrap();
        for (name, fields) in topics {
            w.format(&format!("{name}:uint64_t timestamp;{fields}"))
                .unwrap();
        }
        let status = w.subscribe("vehicle_status", 0).unwrap();
        let subs: Vec<_> = topics
            .iter()
            .map(|(name, _)| {
                (
                    w.subscribe(name, 0).unwrap(),
                    w.schema()
                        .resolved(w.schema().id(name).unwrap())
                        .unwrap()
                        .size,
                )
            })
            .collect();
        for i in 0..4000u64 {
            let t = i * 1000;
            let mut row = t.to_le_bytes().to_vec();
            row.extend([(i / 500 % 20) as u8, 2]);
            w.data(status, &row).unwrap();
            for (k, (sub, size)) in subs.iter().enumerate() {
                let mut row = t.to_le_bytes().to_vec();
                let mut j = i as usize + k;
                while row.len() + 8 <= *size {
                    row.extend(values[j % values.len()].to_le_bytes());
                    j += 1;
                }
                row.resize(*size, 3);
                w.data(*sub, &row).unwrap();
            }
        }
        w.into_inner()
    }

    /// Plotters loops for ever on an infinite axis, panics on a NaN one and overflows its
    /// pixel arithmetic on a point far outside: a log's values must reach it as none of
    /// those, whatever they are.
    #[test]
    fn a_log_of_extreme_values_gets_its_report() {
        let cases: [&[f64]; 5] = [
            &[f64::MAX, -f64::MAX, 0.0, f64::NAN, f64::INFINITY, 5e-324],
            &[1e308, 1e308, 1e308],
            &[5e-324, -5e-324],
            &[1e300, 1e300 * (1.0 + f64::EPSILON)],
            &[-1e200, 3e-200, 1e200, f64::NEG_INFINITY],
        ];
        for values in cases {
            let log = Log::from_vec(extreme_log(values)).unwrap();
            // A hang fails the test instead of stalling the suite.
            let (tx, rx) = std::sync::mpsc::channel();
            std::thread::spawn(move || {
                let r = Report::of_log(&log, "x.ulg").map(|r| (r.html(), r));
                let _ = tx.send(r.map_err(|e| e.to_string()));
            });
            let (html, r) = rx
                .recv_timeout(std::time::Duration::from_secs(120))
                .unwrap_or_else(|e| match e {
                    std::sync::mpsc::RecvTimeoutError::Timeout => {
                        panic!("no report within 2 minutes for {values:?}")
                    }
                    std::sync::mpsc::RecvTimeoutError::Disconnected => {
                        panic!("the report panicked for {values:?} (see its message above)")
                    }
                })
                .unwrap_or_else(|e| panic!("{values:?}: {e}"));
            let ids: Vec<&str> = r.plots.iter().map(|p| p.id.as_str()).collect();
            for id in [
                "modes",
                "altitude",
                "battery_voltage",
                "gps",
                "vibration",
                "track",
            ] {
                assert!(ids.contains(&id), "{values:?}: no {id} plot: {ids:?}");
            }
            for p in &r.plots {
                // Every plot but the mode timeline draws lines.
                assert!(
                    p.id == "modes" || p.svg.contains("<polyline"),
                    "{values:?}: {} draws no line",
                    p.id
                );
                assert!(
                    !p.svg.contains("NaN") && !p.svg.contains("inf"),
                    "{values:?}: {} has {}",
                    p.id,
                    p.svg
                );
            }
            for (title, why) in &r.left_out {
                assert!(
                    !why.is_empty(),
                    "{values:?}: {title} left out for no reason given"
                );
            }
            assert_eq!(html.matches("<svg").count(), r.plots.len());
        }
    }
}
