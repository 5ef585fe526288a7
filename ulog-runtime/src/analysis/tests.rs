//! The analysis on flights written with the writer: a normal one (which must report
//! nothing wrong, though its outputs drop to idle before the disarm is logged), and the
//! same with each fault injected.

use super::*;
use crate::read::ParamValue;
use crate::{Log, ULog, Writer, WriterOptions};

#[derive(ULog)]
struct VehicleStatus {
    timestamp: u64,
    nav_state: u8,
    arming_state: u8,
    vehicle_type: u8,
    is_vtol: bool,
    in_transition_mode: bool,
}

#[derive(ULog)]
struct VehicleLandDetected {
    timestamp: u64,
    landed: bool,
}

#[derive(ULog)]
struct VehicleLocalPosition {
    timestamp: u64,
    x: f32,
    y: f32,
    z: f32,
    vx: f32,
    vy: f32,
    vz: f32,
}

#[derive(ULog)]
struct VehicleAttitude {
    timestamp: u64,
    q: [f32; 4],
}

#[derive(ULog)]
struct VehicleAngularVelocity {
    timestamp: u64,
    xyz: [f32; 3],
}

#[derive(ULog)]
struct VehicleRatesSetpoint {
    timestamp: u64,
    roll: f32,
    pitch: f32,
    yaw: f32,
}

#[derive(ULog)]
struct BatteryStatus {
    timestamp: u64,
    voltage_v: f32,
    current_a: f32,
    discharged_mah: f32,
}

#[derive(ULog)]
struct VehicleGpsPosition {
    timestamp: u64,
    lat: i32,
    lon: i32,
    alt: i32,
    eph: f32,
    epv: f32,
    fix_type: u8,
    satellites_used: u8,
    jamming_state: u8,
}

#[derive(ULog)]
struct VehicleImuStatus {
    timestamp: u64,
    accel_vibration_metric: f32,
}

#[derive(ULog)]
struct EstimatorStatus {
    timestamp: u64,
    vel_test_ratio: f32,
    pos_test_ratio: f32,
    hgt_test_ratio: f32,
}

#[derive(ULog)]
struct ActuatorOutputs {
    timestamp: u64,
    noutputs: u32,
    output: [f32; 8],
}

#[derive(ULog)]
struct InputRc {
    timestamp: u64,
    rc_lost: bool,
}

/// Faults to inject into the flight.
#[derive(Default, Clone, Copy)]
pub(crate) struct Faults {
    pub(crate) brownout: bool,
    pub(crate) ekf: bool,
    pub(crate) gps: bool,
    pub(crate) motor: bool,
    pub(crate) rc: bool,
    pub(crate) steps: bool,
    /// Roll rates of 1000 deg/s out of flight (a vehicle turned by hand on the ground).
    pub(crate) ground_spin: bool,
    /// The position innovation failing from 45 s to the end of the log (past the landing).
    pub(crate) ekf_to_the_end: bool,
    /// A battery without a current sensor: current -1 ("unknown") and a charge drawn of 0
    /// throughout, as PX4 writes them.
    pub(crate) no_current_sensor: bool,
    /// A battery that counts its charge drawn itself but reports no current (-1).
    pub(crate) charge_without_current: bool,
}

const S: u64 = 1_000_000;

/// 60 s: disarmed on the ground to 5 s, armed on the ground to 10 s, flying a circle of
/// 10 m radius at 2 m/s and 5 m up to 50 s, landed, disarmed at 55 s (the outputs drop to
/// their disarmed value 50 ms before the disarm is logged, as PX4 logs it). Position mode
/// to 30 s, Mission after. A 4S battery from 16.4 V down to 15.2 V at 10 A while flying.
pub(crate) fn flight(faults: Faults) -> Vec<u8> {
    let mut w = Writer::new(
        Vec::new(),
        WriterOptions {
            start_timestamp: 0,
            default_parameters: true,
        },
    )
    .unwrap();
    w.parameter("BAT1_N_CELLS", ParamValue::Int32(4)).unwrap();
    w.parameter("MC_ROLL_P", ParamValue::Float(7.0)).unwrap();
    w.parameter("MC_PITCH_P", ParamValue::Float(6.5)).unwrap();
    w.default_parameter("MC_ROLL_P", ParamValue::Float(6.5), 1)
        .unwrap();
    w.default_parameter("MC_PITCH_P", ParamValue::Float(6.5), 1)
        .unwrap();
    let status = w.topic::<VehicleStatus>(0).unwrap();
    let land = w.topic::<VehicleLandDetected>(0).unwrap();
    let local = w.topic::<VehicleLocalPosition>(0).unwrap();
    let attitude = w.topic::<VehicleAttitude>(0).unwrap();
    let rates = w.topic::<VehicleAngularVelocity>(0).unwrap();
    let setpoint = w.topic::<VehicleRatesSetpoint>(0).unwrap();
    let battery = w.topic::<BatteryStatus>(0).unwrap();
    let gps = w.topic::<VehicleGpsPosition>(0).unwrap();
    let imu = w.topic::<VehicleImuStatus>(0).unwrap();
    let estimator = w.topic::<EstimatorStatus>(0).unwrap();
    let outputs = w.topic::<ActuatorOutputs>(0).unwrap();
    let rc = w.topic::<InputRc>(0).unwrap();
    let in_air = |t: u64| (10 * S..50 * S).contains(&t);
    let armed = |t: u64| (5 * S..55 * S).contains(&t);
    let within = |t: u64, a: u64, b: u64| (a * S..b * S).contains(&t);
    // The measured roll rate: a first-order lag of 20 ms behind the setpoint.
    let mut roll = 0.0f64;
    // 200 Hz; each topic at its rate.
    for i in 0..60 * 200u64 {
        let t = i * 5_000 + 1;
        let ts = t as f64 / 1e6;
        let every = |hz: u64| i % (200 / hz) == 0;
        if every(10) {
            w.write(
                &status,
                &VehicleStatus {
                    timestamp: t,
                    nav_state: if ts < 30.0 { 2 } else { 3 },
                    arming_state: if armed(t) { 2 } else { 1 },
                    vehicle_type: 1,
                    is_vtol: false,
                    in_transition_mode: false,
                },
            )
            .unwrap();
            w.write(
                &land,
                &VehicleLandDetected {
                    timestamp: t,
                    landed: !in_air(t),
                },
            )
            .unwrap();
            let flying = in_air(t);
            let mut v = if flying {
                16.4 - 1.2 * (ts - 10.0) / 40.0
            } else {
                16.4
            };
            if faults.brownout && within(t, 30, 35) {
                v = 12.5;
            }
            w.write(
                &battery,
                &BatteryStatus {
                    timestamp: t,
                    voltage_v: v as f32,
                    current_a: if faults.no_current_sensor || faults.charge_without_current {
                        -1.0
                    } else if flying {
                        10.0
                    } else {
                        0.5
                    },
                    discharged_mah: if faults.no_current_sensor {
                        0.0
                    } else {
                        (ts * 50.0) as f32
                    },
                },
            )
            .unwrap();
            w.write(
                &imu,
                &VehicleImuStatus {
                    timestamp: t,
                    accel_vibration_metric: 2.0,
                },
            )
            .unwrap();
            let bad = (faults.ekf && within(t, 20, 27)) || (faults.ekf_to_the_end && t >= 45 * S);
            w.write(
                &estimator,
                &EstimatorStatus {
                    timestamp: t,
                    vel_test_ratio: 0.2,
                    pos_test_ratio: if bad { 1.5 } else { 0.3 },
                    hgt_test_ratio: 0.1,
                },
            )
            .unwrap();
            w.write(
                &rc,
                &InputRc {
                    timestamp: t,
                    rc_lost: faults.rc && within(t, 35, 38),
                },
            )
            .unwrap();
        }
        let phase = if in_air(t) { (ts - 10.0) * 0.2 } else { 0.0 };
        if every(50) {
            let (x, y) = (10.0 * phase.cos(), 10.0 * phase.sin());
            let (vx, vy) = if in_air(t) {
                (-2.0 * phase.sin(), 2.0 * phase.cos())
            } else {
                (0.0, 0.0)
            };
            w.write(
                &local,
                &VehicleLocalPosition {
                    timestamp: t,
                    x: x as f32,
                    y: y as f32,
                    z: if in_air(t) { -5.0 } else { 0.0 },
                    vx: vx as f32,
                    vy: vy as f32,
                    vz: 0.0,
                },
            )
            .unwrap();
            // A tilt of 10 degrees about x in flight.
            let half = if in_air(t) { 5f64.to_radians() } else { 0.0 };
            w.write(
                &attitude,
                &VehicleAttitude {
                    timestamp: t,
                    q: [half.cos() as f32, half.sin() as f32, 0.0, 0.0],
                },
            )
            .unwrap();
            let motor = |k: usize| -> f32 {
                if !armed(t) || t >= 55 * S - 50_000 {
                    900.0
                } else if !in_air(t) || (faults.motor && k == 2 && within(t, 40, 42)) {
                    // Idle: on the ground, or the motor that quits.
                    1100.0
                } else {
                    1500.0 + 10.0 * k as f32
                }
            };
            let mut output = [900.0f32; 8];
            for (k, o) in output.iter_mut().enumerate().take(4) {
                *o = motor(k);
            }
            w.write(
                &outputs,
                &ActuatorOutputs {
                    timestamp: t,
                    noutputs: 8,
                    output,
                },
            )
            .unwrap();
        }
        if every(5) {
            let jam = faults.gps && within(t, 25, 30);
            w.write(
                &gps,
                &VehicleGpsPosition {
                    timestamp: t,
                    lat: 473_977_420 + (phase.sin() * 900.0) as i32,
                    lon: 85_455_940 + (phase.cos() * 1300.0) as i32,
                    alt: 488_000,
                    eph: if jam { 12.0 } else { 1.0 },
                    epv: 1.5,
                    fix_type: 3,
                    satellites_used: if jam { 4 } else { 12 },
                    jamming_state: if jam { 3 } else { 1 },
                },
            )
            .unwrap();
        }
        // Rates at 200 Hz: steps of ±100 deg/s on roll every 0.25 s, a 20 ms lag.
        let step = if faults.steps && in_air(t) {
            if ((ts * 4.0) as u64).is_multiple_of(2) {
                100f64
            } else {
                -100.0
            }
        } else {
            0.0
        };
        w.write(
            &setpoint,
            &VehicleRatesSetpoint {
                timestamp: t,
                roll: step.to_radians() as f32,
                pitch: 0.0,
                yaw: 0.0,
            },
        )
        .unwrap();
        roll += (step - roll) * (1.0 - (-0.005f64 / 0.02).exp());
        let measured = if faults.ground_spin && !in_air(t) {
            1000f64
        } else {
            roll
        };
        w.write(
            &rates,
            &VehicleAngularVelocity {
                timestamp: t,
                xyz: [measured.to_radians() as f32, 0.0, 0.0],
            },
        )
        .unwrap();
    }
    w.into_inner()
}

fn analysis(faults: Faults) -> Analysis {
    let bytes = flight(faults);
    let from_log = Analysis::of_log(&Log::from_slice(&bytes).unwrap());
    let streamed = Analysis::of_reader(&bytes[..]).unwrap();
    assert_eq!(
        from_log, streamed,
        "the whole-file and the streaming pass agree"
    );
    from_log
}

/// The flight modes: name, start and end.
fn modes(a: &Analysis) -> Vec<(&str, u64, u64)> {
    a.flight_modes
        .iter()
        .map(|m| (m.mode.as_str(), m.start_us, m.end_us))
        .collect()
}

fn ids(a: &Analysis) -> Vec<&str> {
    a.diagnostics.iter().map(|d| d.id.as_str()).collect()
}

#[test]
fn a_normal_flight_reports_its_facts_and_nothing_wrong() {
    let a = analysis(Faults::default());
    assert_eq!(ids(&a), Vec::<&str>::new(), "{:#?}", a.diagnostics);
    // Every diagnostic had its topics: none is said unchecked.
    let unchecked: Vec<&str> = a
        .missing
        .iter()
        .map(|m| m.fact.as_str())
        .filter(|f| {
            f.ends_with("_failure")
                || f.starts_with("battery_")
                || f.ends_with("_loss")
                || f == &"gps_interference"
        })
        .collect();
    assert!(unchecked.is_empty(), "{unchecked:?}");
    assert_eq!(
        modes(&a),
        [
            ("Position", 1, 30 * S + 1),
            ("Mission", 30 * S + 1, 60 * S - 5_000 + 1)
        ]
    );
    assert_eq!(
        a.armed,
        [Interval {
            start_us: 5 * S + 1,
            end_us: 55 * S + 1
        }]
    );
    assert_eq!(
        a.flights,
        [Interval {
            start_us: 10 * S + 1,
            end_us: 50 * S + 1
        }]
    );
    let s = &a.stats.all;
    // 40 s at 2 m/s on a circle (chords of 50 Hz samples), the 5 m jump up at take-off,
    // and the jump from the circle's last point (phase 8 rad, 5 m up) back to the start.
    let path = s.total_distance_m.unwrap();
    let landing = ((10.0 - 10.0 * 8f64.cos()).powi(2) + (10.0 * 8f64.sin()).powi(2) + 25.0).sqrt();
    assert!((path - (80.0 + 5.0 + landing)).abs() < 0.2, "{path}");
    assert_eq!(s.max_altitude_diff_m, Some(5.0));
    assert!((s.max_speed_m_s.unwrap() - 2.0).abs() < 1e-3);
    assert!((s.max_tilt_deg.unwrap() - 10.0).abs() < 1e-3);
    assert_eq!(s.max_speed_up_m_s, Some(0.0));
    assert_eq!(
        a.stats.armed.total_distance_m, s.total_distance_m,
        "all of it armed"
    );
    let b = &a.battery;
    assert!((b.min_voltage_v.unwrap() - 15.2).abs() < 0.05);
    assert_eq!(b.max_current_a, Some(10.0));
    assert_eq!(b.instances[0].cells, Some(4), "from BAT1_N_CELLS");
    // The last battery row, at 59.9 s, says 50 mAh a second.
    assert!((b.discharged_mah.unwrap() - 2995.0).abs() < 0.01);
    let g = &a.gps_quality;
    assert_eq!((g.min_satellites, g.max_satellites), (Some(12), Some(12)));
    assert_eq!(g.fix_types_seen, [3]);
    assert_eq!(g.jamming_states_seen, [1]);
    assert_eq!(a.gps_track.len(), 60, "one point a second");
    assert_eq!(a.gps_track[40].mode_id, Some(3), "Mission at 40 s");
    assert!((a.gps_track[0].lat_deg - 47.397_742).abs() < 1e-6);
    assert_eq!(a.vibration.status, "good");
    assert_eq!(a.vibration.accel_vibe_mean, Some(2.0));
    let non_default: Vec<(&str, f64, f64)> = a
        .non_default_params
        .iter()
        .map(|p| (p.name.as_str(), p.value, p.default))
        .collect();
    assert_eq!(non_default, [("MC_ROLL_P", 7.0, 6.5)]);
    assert!(
        a.to_string().contains("\nNon-default parameters: 1\n"),
        "{a}"
    );
    let z = a
        .field_stats
        .iter()
        .find(|f| f.topic == "vehicle_local_position" && f.field == "z")
        .unwrap();
    assert_eq!((z.min, z.max, z.count), (-5.0, 0.0, 3000));
    assert!(!a.field_stats.iter().any(|f| f.field == "timestamp"));
    assert!(a.missing.iter().any(|m| m.fact == "step_response"));
    // The gyro's spectrum in flight.
    let gyro_x = a
        .spectra
        .iter()
        .find(|s| s.sensor == "gyro" && s.axis == "x")
        .unwrap();
    assert_eq!(gyro_x.sample_rate_hz, 200.0);
}

/// A battery without a current sensor (current -1, a charge of 0 throughout): its current
/// and charge drawn are unknown, in the facts and in the summary, not "0.00 mAh"; its
/// voltage is still read, and it makes no diagnostic.
#[test]
fn a_battery_without_a_current_sensor_has_no_charge_drawn() {
    let a = analysis(Faults {
        no_current_sensor: true,
        ..Faults::default()
    });
    let b = &a.battery;
    assert_eq!(
        (b.avg_current_a, b.max_current_a, b.discharged_mah),
        (None, None, None)
    );
    assert_eq!(b.instances[0].discharged_mah, None);
    assert!((b.min_voltage_v.unwrap() - 15.2).abs() < 0.05);
    assert!(a.diagnostics.is_empty(), "{:#?}", a.diagnostics);
    let text = a.to_string();
    assert!(text.contains("current mean - max -, drawn -, 4S"), "{text}");
    // With a current sensor, the same flight's charge is the last reading.
    let with = analysis(Faults::default());
    assert!((with.battery.discharged_mah.unwrap() - 2995.0).abs() < 0.01);
    // A battery that counts its charge itself (above 0) without a current: the count is
    // kept.
    let counted = analysis(Faults {
        charge_without_current: true,
        ..Faults::default()
    });
    assert_eq!(counted.battery.avg_current_a, None);
    assert!((counted.battery.discharged_mah.unwrap() - 2995.0).abs() < 0.01);
}

/// The one diagnostic a fault makes: its id, severity, start and end (µs, to 0.2 s).
fn one(a: &Analysis) -> (&str, Severity, f64, f64) {
    assert_eq!(a.diagnostics.len(), 1, "{:#?}", a.diagnostics);
    let d = &a.diagnostics[0];
    (
        d.id.as_str(),
        d.severity,
        (d.timestamp_us as f64 / 1e6 * 5.0).round() / 5.0,
        (d.end_timestamp_us.unwrap() as f64 / 1e6 * 5.0).round() / 5.0,
    )
}

#[test]
fn each_fault_is_found_with_its_time_and_severity() {
    let brownout = analysis(Faults {
        brownout: true,
        ..Faults::default()
    });
    assert_eq!(
        one(&brownout),
        ("battery_brownout", Severity::Critical, 30.0, 35.0)
    );
    match &brownout.diagnostics[0].evidence {
        Evidence::BatteryBrownout {
            cells, cells_from, ..
        } => assert_eq!((*cells, cells_from.as_str()), (4, "parameter")),
        e => panic!("{e:?}"),
    }
    let ekf = analysis(Faults {
        ekf: true,
        ..Faults::default()
    });
    assert_eq!(one(&ekf), ("ekf_failure", Severity::Critical, 20.0, 27.0));
    // Failing past the landing: the episode ends at the landing (the first row out of
    // flight), not at the end of the log.
    let landing = analysis(Faults {
        ekf_to_the_end: true,
        ..Faults::default()
    });
    assert_eq!(
        one(&landing),
        ("ekf_failure", Severity::Critical, 45.0, 50.0)
    );
    let gps = analysis(Faults {
        gps: true,
        ..Faults::default()
    });
    assert_eq!(
        one(&gps),
        ("gps_interference", Severity::Critical, 25.0, 30.0)
    );
    match &gps.diagnostics[0].evidence {
        Evidence::GpsInterference { reasons, .. } => {
            assert_eq!(reasons, &["eph spike", "satellites lost", "jamming"]);
        }
        e => panic!("{e:?}"),
    }
    let motor = analysis(Faults {
        motor: true,
        ..Faults::default()
    });
    assert_eq!(
        one(&motor),
        ("motor_failure", Severity::Critical, 40.0, 42.0)
    );
    match &motor.diagnostics[0].evidence {
        Evidence::MotorFailure {
            motor_index,
            failure_mode,
            flight_mode,
            ..
        } => assert_eq!(
            (*motor_index, failure_mode.as_str(), flight_mode.as_str()),
            (2, "drop_to_zero", "Mission")
        ),
        e => panic!("{e:?}"),
    }
    let rc = analysis(Faults {
        rc: true,
        ..Faults::default()
    });
    assert_eq!(one(&rc), ("rc_loss", Severity::Warning, 35.0, 38.0));
}

#[test]
fn roll_steps_give_the_loops_step_response() {
    let a = analysis(Faults {
        steps: true,
        ..Faults::default()
    });
    let roll = a.step_response.iter().find(|r| r.axis == "roll").unwrap();
    assert_eq!(roll.sample_rate_hz, 200.0);
    let step = roll.response.as_ref().unwrap();
    // A first-order lag of 20 ms: 1 - e^{-t/0.02}.
    for s in [0.02, 0.05, 0.1, 0.3] {
        let want = 1.0 - (-s / 0.02f64).exp();
        let got = step[(s * 200.0) as usize];
        assert!((got - want).abs() < 0.12, "{s}: {got} vs {want}");
    }
    assert!(
        a.step_response.iter().all(|r| r.axis == "roll"),
        "the other axes did not move"
    );
}

/// The step response and the spectra take only samples in flight: rates of 1000 deg/s on
/// the ground, up to the takeoff's sample, change neither (a run starts at its first sample
/// in flight, not at the last one before it).
#[test]
fn rates_out_of_flight_change_no_step_response_or_spectrum() {
    let calm = analysis(Faults {
        steps: true,
        ..Faults::default()
    });
    let spun = analysis(Faults {
        steps: true,
        ground_spin: true,
        ..Faults::default()
    });
    assert!(!calm.step_response.is_empty() && !calm.spectra.is_empty());
    assert_eq!(calm.step_response, spun.step_response);
    assert_eq!(calm.spectra, spun.spectra);
    // The spin is in the log: the rotation rate over the whole log has it.
    let deg_s = |a: &Analysis| a.stats.all.max_rotation_speed_deg_s.unwrap();
    assert!(deg_s(&spun) > 999.0 && deg_s(&calm) < 200.0);
}

#[test]
fn what_a_log_lacks_is_said() {
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let sub = w.topic::<VehicleAttitude>(0).unwrap();
    w.write(
        &sub,
        &VehicleAttitude {
            timestamp: 1,
            q: [1.0, 0.0, 0.0, 0.0],
        },
    )
    .unwrap();
    let a = Analysis::of_log(&Log::from_vec(w.into_inner()).unwrap());
    assert_eq!(a.stats.all.max_tilt_deg, Some(0.0));
    assert_eq!(a.stats.all.total_distance_m, None);
    let facts: Vec<&str> = a.missing.iter().map(|m| m.fact.as_str()).collect();
    for fact in [
        "flight_modes, vtol_states, armed",
        "battery",
        "gps_quality, gps_track",
        "vibration",
        // No finding where nothing could be checked: said, not silent.
        "battery_brownout",
        "ekf_failure",
        "gps_interference",
        "motor_failure",
        "rc_loss",
    ] {
        assert!(facts.contains(&fact), "{fact}: {facts:?}");
    }
    assert!(a.diagnostics.is_empty());
}

#[test]
fn the_last_mode_lasts_until_the_last_status_even_when_an_older_row_ends_the_log() {
    // A cut log whose last row is an old one of another topic (seen on `sample.ulg` cut
    // in half: a `commander_state` row from before the log's start ended it).
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let status = w.topic::<VehicleStatus>(0).unwrap();
    let attitude = w.topic::<VehicleAttitude>(0).unwrap();
    for (t, nav) in [(10_000_000, 0u8), (20_000_000, 2), (30_000_000, 2)] {
        let s = VehicleStatus {
            timestamp: t,
            nav_state: nav,
            arming_state: 1,
            vehicle_type: 1,
            is_vtol: false,
            in_transition_mode: false,
        };
        w.write(&status, &s).unwrap();
    }
    let old = VehicleAttitude {
        timestamp: 2_000_000,
        q: [1.0, 0.0, 0.0, 0.0],
    };
    w.write(&attitude, &old).unwrap();
    let a = Analysis::of_log(&Log::from_vec(w.into_inner()).unwrap());
    assert_eq!(
        modes(&a),
        [
            ("Manual", 10_000_000, 20_000_000),
            ("Position", 20_000_000, 30_000_000)
        ]
    );
}

#[derive(ULog)]
struct Mixed {
    timestamp: u64,
    a: [f32; 3],
    n: u32,
    e: [f32; 5],
    p: [f32; 2],
    f: u64,
    d: [i16; 6],
    g: u8,
}

#[test]
fn field_statistics_equal_each_fields_own_over_its_finite_values() {
    // Floats side by side are folded four at a time (`a` with the bits of `n` beside it,
    // NaN as a float; `e` and `p` across a field boundary), with a NaN, infinities and a
    // negative zero among them; 64-bit integers beyond 2^40, negative 16-bit ones; more
    // rows than a stage holds, an odd count.
    let rows: Vec<Mixed> = (0..5_001u64)
        .map(|i| {
            let x = i as f32;
            let mut m = Mixed {
                timestamp: i,
                a: [x.sin(), -x * 0.5, if i == 7 { -0.0 } else { x.cos() + 2.0 }],
                n: u32::MAX - (i as u32 % 3),
                e: [x, x * 1e-3, -x, x * x, 1.0 / (x + 1.0)],
                p: [x - 2_500.0, 3.0],
                f: (1 << 41) + i * 1_000_003,
                d: [-(i as i16 % 300), 1, 2, 3, 4, i as i16 % 7],
                g: (i % 251) as u8,
            };
            match i {
                100 => m.e[1] = f32::NAN,
                2_000 => m.e[4] = f32::INFINITY,
                3_000 => m.p[1] = f32::NEG_INFINITY,
                4_999 => m.a[0] = f32::NAN,
                _ => {}
            }
            m
        })
        .collect();
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let sub = w.topic::<Mixed>(0).unwrap();
    for r in &rows {
        w.write(&sub, r).unwrap();
    }
    let bytes = w.into_inner();
    // Each field's finite values as f64: (name, values, exact integer sum if an integer).
    let mut fields: Vec<(String, Vec<f64>, Option<i128>)> = Vec::new();
    let mut float = |name: String, v: Vec<f32>| {
        let v: Vec<f64> = v
            .into_iter()
            .map(f64::from)
            .filter(|x| x.is_finite())
            .collect();
        fields.push((name, v, None));
    };
    for k in 0..3 {
        float(format!("a[{k}]"), rows.iter().map(|r| r.a[k]).collect());
    }
    for k in 0..5 {
        float(format!("e[{k}]"), rows.iter().map(|r| r.e[k]).collect());
    }
    for k in 0..2 {
        float(format!("p[{k}]"), rows.iter().map(|r| r.p[k]).collect());
    }
    let mut int = |name: String, v: Vec<i128>| {
        let sum = v.iter().sum();
        fields.push((name, v.iter().map(|&x| x as f64).collect(), Some(sum)));
    };
    int("n".into(), rows.iter().map(|r| i128::from(r.n)).collect());
    int("f".into(), rows.iter().map(|r| i128::from(r.f)).collect());
    for k in 0..6 {
        int(
            format!("d[{k}]"),
            rows.iter().map(|r| i128::from(r.d[k])).collect(),
        );
    }
    int("g".into(), rows.iter().map(|r| i128::from(r.g)).collect());
    let log = Log::from_vec(bytes.clone()).unwrap();
    for (how, a) in [
        ("two walks", Analysis::of_log(&log)),
        ("one pass", Analysis::of_reader(&bytes[..]).unwrap()),
    ] {
        assert_eq!(a.field_stats.len(), fields.len(), "{how}");
        for (name, values, sum) in &fields {
            let s = a
                .field_stats
                .iter()
                .find(|s| s.field == *name)
                .unwrap_or_else(|| panic!("{how}: {name}"));
            let min = values.iter().copied().fold(f64::INFINITY, f64::min);
            let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let mean = match sum {
                Some(sum) => *sum as f64 / values.len() as f64,
                None => values.iter().sum::<f64>() / values.len() as f64,
            };
            assert_eq!(s.count, values.len() as u64, "{how}: {name}");
            assert_eq!((s.min, s.max), (min, max), "{how}: {name}");
            assert!(
                (s.mean - mean).abs() <= 1e-12 * mean.abs().max(1.0),
                "{how}: {name} mean {} against {mean}",
                s.mean
            );
        }
    }
}

/// A log without default parameters cannot say which parameters differ from them: the text
/// gives no count (not 0), and names the fact under "Not in the log".
#[test]
fn without_defaults_the_non_default_parameters_are_unknown_not_none() {
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    w.parameter("MC_ROLL_P", ParamValue::Float(7.0)).unwrap();
    let log = Log::from_vec(w.into_inner()).unwrap();
    let a = Analysis::of_log(&log);
    let text = a.to_string();
    assert!(text.contains("\nNon-default parameters: -\n"), "{text}");
    assert!(text.contains("non_default_params"), "{text}");
}

/// The tilt of a quaternion not of unit length is that of the rotation it stands for; an
/// all-zero one stands for none.
#[test]
fn a_quaternion_of_any_length_gives_its_rotations_tilt() {
    let tilt = |qs: &[[f32; 4]]| {
        let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
        let att = w.topic::<VehicleAttitude>(0).unwrap();
        for (i, q) in qs.iter().enumerate() {
            let timestamp = i as u64 * 1_000 + 1;
            w.write(&att, &VehicleAttitude { timestamp, q: *q })
                .unwrap();
        }
        let bytes = w.into_inner();
        let a = Analysis::of_log(&Log::from_slice(&bytes).unwrap());
        assert_eq!(a, Analysis::of_reader(&bytes[..]).unwrap());
        a.stats.all.max_tilt_deg
    };
    let close = |t: Option<f64>, deg: f64| t.is_some_and(|t| (t - deg).abs() < 1e-4);
    // (1, 1, 1, 1) is (0.5, 0.5, 0.5, 0.5): a tilt of 90°, not the 180° of taking it as a
    // unit quaternion.
    assert!(close(tilt(&[[1.0; 4]]), 90.0), "{:?}", tilt(&[[1.0; 4]]));
    assert!(close(tilt(&[[0.5; 4]]), 90.0));
    // 30° of roll at twice the length.
    let (s, c) = (15f32.to_radians().sin(), 15f32.to_radians().cos());
    assert!(close(tilt(&[[2.0 * c, 2.0 * s, 0.0, 0.0]]), 30.0));
    // An all-zero quaternion says nothing: no tilt, not 0°.
    assert_eq!(tilt(&[[0.0; 4]]), None);
    assert!(close(tilt(&[[0.0; 4], [1.0, 0.0, 0.0, 0.0]]), 0.0));
}

/// A `nav_state` no `uint8_t` holds (a crafted log's `float` field) is a mode PX4 does not
/// have, not the one a cast would make of it (NaN as 0, "Manual").
#[test]
fn a_nav_state_that_is_not_a_byte_is_an_unknown_mode() {
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    w.format("vehicle_status:uint64_t timestamp;float nav_state;uint8_t arming_state;")
        .unwrap();
    let status = w.subscribe("vehicle_status", 0).unwrap();
    for (t, nav) in [
        (1_000u64, f32::NAN),
        (2_000, 2.5),
        (3_000, -1.0),
        (4_000, 3.0),
    ] {
        let mut row = t.to_le_bytes().to_vec();
        row.extend(nav.to_le_bytes());
        row.push(2);
        w.data(status, &row).unwrap();
    }
    let bytes = w.into_inner();
    let a = Analysis::of_log(&Log::from_slice(&bytes).unwrap());
    let names: Vec<&str> = a.flight_modes.iter().map(|m| m.mode.as_str()).collect();
    assert_eq!(names, ["Unknown", "Mission"]);
}

/// A damaged log whose time runs back: no mode segment lasts longer than the log, and no
/// episode of a diagnostic ends before it begins (the fuzzer's log gave a "Manual" segment
/// of 18,446,744,073,689 s in a release build, and a panic in a debug one).
#[test]
fn time_that_runs_back_gives_no_segment_longer_than_the_log() {
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    w.format("vehicle_status:uint64_t timestamp;uint8_t nav_state;uint8_t arming_state;")
        .unwrap();
    w.format("input_rc:uint64_t timestamp;bool rc_lost;")
        .unwrap();
    let status = w.subscribe("vehicle_status", 0).unwrap();
    let rc = w.subscribe("input_rc", 0).unwrap();
    // Armed, a mode change, then time back to before the first row; the RC lost meanwhile.
    for (t, nav, lost) in [
        (20_000_000u64, 0u8, false),
        (21_000_000, 0, true),
        (22_000_000, 3, true),
        (1_000, 2, false),
        (2_000, 2, false),
    ] {
        let mut row = t.to_le_bytes().to_vec();
        row.extend([nav, 2]);
        w.data(status, &row).unwrap();
        let mut row = t.to_le_bytes().to_vec();
        row.push(u8::from(lost));
        w.data(rc, &row).unwrap();
    }
    let bytes = w.into_inner();
    let a = Analysis::of_log(&Log::from_slice(&bytes).unwrap());
    assert!(!a.flight_modes.is_empty());
    for m in &a.flight_modes {
        assert!(m.end_us >= m.start_us, "{m:?}");
        assert!(m.duration_s <= 22.0, "{m:?}");
    }
    for d in &a.diagnostics {
        assert!(
            d.end_timestamp_us.is_none_or(|e| e >= d.timestamp_us),
            "{d:?}"
        );
    }
}

/// Field statistics stop at `MAX_FIELDS` fields, the instances past it said in `missing`:
/// a 30-byte definition (`uint8_t[65000]`) in many instances cannot take gigabytes.
#[test]
fn field_statistics_past_their_limit_are_said_missing() {
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    w.format("big:uint64_t timestamp;uint8_t[65000] a;")
        .unwrap();
    let subs: Vec<_> = (0..4).map(|m| w.subscribe("big", m).unwrap()).collect();
    for (m, sub) in subs.iter().enumerate() {
        let mut row = 1_000u64.to_le_bytes().to_vec();
        row.resize(8 + 65_000, m as u8);
        w.data(*sub, &row).unwrap();
    }
    let bytes = w.into_inner();
    let a = Analysis::of_log(&Log::from_slice(&bytes).unwrap());
    // Three instances of 65,000 fields fit in 250,000; the fourth does not.
    assert_eq!(a.field_stats.len(), 3 * 65_000);
    assert!(a.field_stats.iter().all(|f| f.multi_id < 3));
    let said = a.missing.iter().find(|m| m.fact == "field_stats").unwrap();
    assert!(
        said.reason
            .starts_with("1 topic instance left out, their columns past the limit of 250000")
            && said.reason.contains("`big` #3 (65001 columns)"),
        "{}",
        said.reason
    );
}

/// A topic's rows: each one's timestamp and the bytes after it.
type Rows = Vec<(u64, Vec<u8>)>;

/// A log of raw rows: each format and its rows, with `ver_sw_release` when given.
fn raw_log(version: Option<u32>, topics: &[(&str, Rows)]) -> Analysis {
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    if let Some(v) = version {
        w.info(
            "ver_sw_release",
            &crate::Value::Scalar(crate::value::Scalar::UInt32(v)),
        )
        .unwrap();
    }
    for (format, _) in topics {
        w.format(format).unwrap();
    }
    let subs: Vec<_> = topics
        .iter()
        .map(|(format, _)| w.subscribe(format.split(':').next().unwrap(), 0).unwrap())
        .collect();
    // The rows of every topic in time order (file order where times are equal).
    let mut rows: Vec<(u64, usize, &[u8])> = topics
        .iter()
        .enumerate()
        .flat_map(|(k, (_, rows))| rows.iter().map(move |(t, r)| (*t, k, r.as_slice())))
        .collect();
    rows.sort_by_key(|&(t, k, _)| (t, k));
    for (t, k, rest) in rows {
        let mut row = t.to_le_bytes().to_vec();
        row.extend_from_slice(rest);
        w.data(subs[k], &row).unwrap();
    }
    let bytes = w.into_inner();
    Analysis::of_log(&Log::from_slice(&bytes).unwrap())
}

const STATUS: &str = "vehicle_status:uint64_t timestamp;uint8_t nav_state;uint8_t arming_state;";

/// `vehicle_status` rows every 100 ms from `from` s to `to` s: armed, in one mode.
fn armed_status(from: u64, to: u64, nav: u8) -> Rows {
    (from * 10..to * 10)
        .map(|k| (k * 100_000, vec![nav, 2]))
        .collect()
}

/// Rows of one `bool` (or `uint8_t`) every 100 ms from 1 s to 20 s: 1 from 8 s to 12 s.
fn flag_rows() -> Rows {
    (10..200u64)
        .map(|k| (k * 100_000, vec![u8::from((80..120).contains(&k))]))
        .collect()
}

/// The version's `ver_sw_release`: a release.
fn release(major: u32, minor: u32) -> Option<u32> {
    Some((major << 24) | (minor << 16) | 0xff)
}

#[test]
fn mode_names_follow_the_firmware_version_where_px4_reused_a_number() {
    let names = |version: Option<u32>| {
        let navs = [6u8, 7, 8, 9, 16, 23, 30, 31];
        let rows: Rows = navs
            .iter()
            .enumerate()
            .map(|(k, &n)| (1_000_000 * (k as u64 + 1), vec![n, 1]))
            .collect();
        let a = raw_log(version, &[(STATUS, rows)]);
        a.flight_modes
            .iter()
            .map(|m| m.mode.clone())
            .collect::<Vec<_>>()
    };
    let always = [
        "Return to groundstation",
        "Land (GPS fail)",
        "Rattitude",
        "External 1",
        "External 8",
        "Unknown",
    ];
    let with = |six: &str, eight: &str| {
        let mut v = vec![six.to_owned(), always[0].to_owned(), eight.to_owned()];
        v.extend(always[1..].iter().map(|s| (*s).to_owned()));
        v
    };
    assert_eq!(
        names(release(1, 14)),
        with("RC Recovery", "Land (engine fail)")
    );
    assert_eq!(
        names(release(1, 15)),
        with("Position Slow", "Land (engine fail)")
    );
    assert_eq!(
        names(release(1, 17)),
        with("Position Slow", "Altitude Cruise")
    );
    assert_eq!(names(None), with("Unknown", "Unknown"));
    // A build that writes 0 says no version.
    assert_eq!(names(Some(0)), with("Unknown", "Unknown"));
}

#[test]
fn the_heading_test_ratio_counts_where_the_magnetometer_ratio_is_gone() {
    let ratios = |fields: &str| {
        let format = format!("estimator_status:uint64_t timestamp;{fields}");
        let n = fields.matches(';').count();
        // Every ratio 2.0 from 8 s to 12 s, 0.5 otherwise.
        let rows = (10..200u64)
            .map(|k| {
                let r: f32 = if (80..120).contains(&k) { 2.0 } else { 0.5 };
                (k * 100_000, r.to_le_bytes().repeat(n))
            })
            .collect();
        let a = raw_log(
            release(1, 16),
            &[(STATUS, armed_status(0, 21, 2)), (&format, rows)],
        );
        a.diagnostics
            .iter()
            .map(|d| match &d.evidence {
                Evidence::EkfFailure { innovation, .. } => innovation.clone(),
                e => panic!("{e:?}"),
            })
            .collect::<Vec<_>>()
    };
    // PX4 1.16's estimator_status.
    assert_eq!(ratios("float hdg_test_ratio;"), ["heading"]);
    // Where both are, the magnetometer's (the heading's would repeat it).
    assert_eq!(
        ratios("float mag_test_ratio;float hdg_test_ratio;"),
        ["magnetometer"]
    );
}

#[test]
fn rc_loss_is_read_from_rc_failsafe_and_from_the_topics_of_other_px4_versions() {
    let found = |topics: &[(&str, Rows)]| {
        let mut all = vec![(STATUS, armed_status(0, 21, 2))];
        all.extend(topics.iter().cloned());
        let a = raw_log(release(1, 15), &all);
        let sources: Vec<String> = a
            .diagnostics
            .iter()
            .map(|d| match &d.evidence {
                Evidence::RcLoss {
                    source,
                    signal_lost_duration_ms,
                    ..
                } => {
                    assert_eq!(*signal_lost_duration_ms, 4_000, "{d:?}");
                    source.clone()
                }
                e => panic!("{e:?}"),
            })
            .collect();
        let unchecked = a.missing.iter().any(|m| m.fact == "rc_loss");
        (sources, unchecked)
    };
    // A receiver that keeps sending frames in failsafe: rc_lost stays 0.
    let failsafe_only: Rows = flag_rows()
        .into_iter()
        .map(|(t, f)| (t, vec![0, f[0]]))
        .collect();
    assert_eq!(
        found(&[(
            "input_rc:uint64_t timestamp;bool rc_lost;bool rc_failsafe;",
            failsafe_only
        )]),
        (vec!["input_rc".to_owned()], false)
    );
    assert_eq!(
        found(&[(
            "failsafe_flags:uint64_t timestamp;bool manual_control_signal_lost;",
            flag_rows()
        )]),
        (vec!["failsafe_flags".to_owned()], false)
    );
    let old_status = "vehicle_status:uint64_t timestamp;uint8_t nav_state;uint8_t arming_state;bool rc_signal_lost;";
    let old_rows: Rows = flag_rows()
        .into_iter()
        .map(|(t, f)| (t, vec![2, 2, f[0]]))
        .collect();
    let a = raw_log(None, &[(old_status, old_rows.clone())]);
    assert_eq!(a.diagnostics.len(), 1, "{:?}", a.diagnostics);
    assert!(
        matches!(&a.diagnostics[0].evidence, Evidence::RcLoss { source, .. } if source == "vehicle_status")
    );
    // Where `input_rc` is, the others are not read: its signal was never lost.
    let steady: Rows = flag_rows().into_iter().map(|(t, _)| (t, vec![0])).collect();
    let a = raw_log(
        None,
        &[
            (old_status, old_rows),
            ("input_rc:uint64_t timestamp;bool rc_lost;", steady),
        ],
    );
    assert!(a.diagnostics.is_empty(), "{:?}", a.diagnostics);
    // Without any source, the check is said not made.
    assert_eq!(found(&[]), (vec![], true));
}

#[test]
fn gps_interference_is_read_from_sensor_gps_in_a_log_without_vehicle_gps_position() {
    let gps = |topic: &str| {
        (
            format!("{topic}:uint64_t timestamp;uint8_t fix_type;float eph;"),
            (10..200u64)
                .map(|k| {
                    let eph: f32 = if (80..120).contains(&k) { 30.0 } else { 1.0 };
                    let mut r = vec![3u8];
                    r.extend(eph.to_le_bytes());
                    (k * 100_000, r)
                })
                .collect::<Vec<_>>(),
        )
    };
    let (sensor, rows) = gps("sensor_gps");
    let a = raw_log(
        None,
        &[(STATUS, armed_status(0, 21, 2)), (&sensor, rows.clone())],
    );
    assert_eq!(a.diagnostics.len(), 1, "{:?}", a.diagnostics);
    assert!(matches!(&a.diagnostics[0].evidence,
        Evidence::GpsInterference { source, .. } if source == "sensor_gps"));
    // Beside a steady vehicle_gps_position, the receiver's own topic is not judged.
    let (vehicle, _) = gps("vehicle_gps_position");
    let steady: Rows = rows
        .iter()
        .map(|(t, _)| {
            let mut r = vec![3u8];
            r.extend(1.0f32.to_le_bytes());
            (*t, r)
        })
        .collect();
    let a = raw_log(
        None,
        &[
            (STATUS, armed_status(0, 21, 2)),
            (&sensor, rows),
            (&vehicle, steady),
        ],
    );
    assert!(a.diagnostics.is_empty(), "{:?}", a.diagnostics);
}

/// Parts of logs joined (time runs back twice, as in the corpus's
/// `corrupt_format_not_utf8.ulg`): the path does not jump back between the parts, each part
/// has its own mode segment and armed interval, and the GPS track has points in each.
#[test]
fn time_that_runs_back_starts_new_segments_and_a_new_path() {
    let local = "vehicle_local_position:uint64_t timestamp;float x;float y;float z;";
    let gps = "vehicle_gps_position:uint64_t timestamp;int32_t lat;int32_t lon;int32_t alt;uint8_t fix_type;";
    // Three parts, in file order: 50-60 s, 20-30 s, 5-10 s; each moves 1 m a second
    // along x from its own far-away start.
    let parts = [
        (50u64, 60u64, 1_000.0f32),
        (20, 30, -2_000.0),
        (5, 10, 5_000.0),
    ];
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    for f in [STATUS, local, gps] {
        w.format(f).unwrap();
    }
    let status = w.subscribe("vehicle_status", 0).unwrap();
    let position = w.subscribe("vehicle_local_position", 0).unwrap();
    let fix = w.subscribe("vehicle_gps_position", 0).unwrap();
    for (from, to, x0) in parts {
        for k in from * 10..=to * 10 {
            let t = k * 100_000;
            let mut row = t.to_le_bytes().to_vec();
            row.extend([2u8, 2]);
            w.data(status, &row).unwrap();
            let x = x0 + (k - from * 10) as f32 / 10.0;
            let mut row = t.to_le_bytes().to_vec();
            for v in [x, 0.0, -10.0] {
                row.extend(v.to_le_bytes());
            }
            w.data(position, &row).unwrap();
            let mut row = t.to_le_bytes().to_vec();
            for v in [473_977_000i32, 85_456_000, 500_000] {
                row.extend(v.to_le_bytes());
            }
            row.push(3);
            w.data(fix, &row).unwrap();
        }
    }
    let bytes = w.into_inner();
    let a = Analysis::of_log(&Log::from_slice(&bytes).unwrap());
    // 10 + 10 + 5 m, not the kilometres between the parts.
    let d = a.stats.all.total_distance_m.unwrap();
    assert!((d - 25.0).abs() < 1e-3, "{d}");
    assert_eq!(
        modes(&a),
        [
            ("Position", 5_000_000, 10_000_000),
            ("Position", 20_000_000, 30_000_000),
            ("Position", 50_000_000, 60_000_000)
        ]
    );
    let armed: Vec<(u64, u64)> = a.armed.iter().map(|i| (i.start_us, i.end_us)).collect();
    assert_eq!(
        armed,
        [
            (5_000_000, 10_000_000),
            (20_000_000, 30_000_000),
            (50_000_000, 60_000_000)
        ]
    );
    // A point a second in each part (11 + 11 + 6), each with the part's mode.
    assert_eq!(a.gps_track.len(), 28);
    assert!(a.gps_track.iter().all(|p| p.mode_id == Some(2)));
}

#[test]
fn a_vtol_of_unknown_type_has_no_vtol_state() {
    let format = "vehicle_status:uint64_t timestamp;uint8_t nav_state;uint8_t arming_state;uint8_t vehicle_type;bool is_vtol;bool in_transition_mode;";
    let rows = |vehicle_type: u8| -> Rows {
        (1..20u64)
            .map(|k| (k * 100_000, vec![2, 2, vehicle_type, 1, 0]))
            .collect()
    };
    let states =
        |a: &Analysis| -> Vec<String> { a.vtol_states.iter().map(|v| v.state.clone()).collect() };
    assert_eq!(states(&raw_log(None, &[(format, rows(2))])), ["FW"]);
    assert_eq!(states(&raw_log(None, &[(format, rows(1))])), ["MC"]);
    assert!(states(&raw_log(None, &[(format, rows(0))])).is_empty());
}

/// A current sensor that reads -0.0 A (seen on a real log's idle battery): 0.00 A in the
/// summary, not "-0.00".
#[test]
fn a_negative_zero_current_reads_as_zero() {
    let rows: Rows = (1..20u64)
        .map(|k| {
            let mut r = 16.0f32.to_le_bytes().to_vec();
            r.extend((-0.0f32).to_le_bytes());
            (k * 100_000, r)
        })
        .collect();
    let a = raw_log(
        None,
        &[(
            "battery_status:uint64_t timestamp;float voltage_v;float current_a;",
            rows,
        )],
    );
    let text = a.to_string();
    assert!(text.contains("current mean 0.00 A max 0.00 A"), "{text}");
}
