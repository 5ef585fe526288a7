//! Typed topics end to end: derive `ULog` for a few structs (nested, arrays, padding), write a
//! log file with them, read it back checked against the file's own formats, and see what a
//! struct that does not match the file gets.
//!
//! ```text
//! cargo run -p examples --example typed_roundtrip
//! ```

use ulog_runtime::read::ParamValue;
use ulog_runtime::{Chars, Log, ULog, Value, Writer, WriterOptions};

/// One ESC's report: nested only (no timestamp), with padding as PX4 aligns it.
#[derive(ULog, Debug, Clone, Copy, Default)]
struct EscReport {
    esc_rpm: i32,
    esc_voltage: f32,
    esc_state: u8,
    #[ulog(padding)]
    _pad: [u8; 3],
}

/// A topic: `timestamp` first, then an array of nested reports.
#[derive(ULog, Debug, Clone)]
#[ulog(name = "esc_status")]
struct EscStatus {
    timestamp: u64,
    esc_count: u8,
    #[ulog(padding)]
    _pad: [u8; 3],
    esc: [EscReport; 4],
}

/// Another topic; its name defaults to the struct name in snake case (`vehicle_attitude`).
#[derive(ULog, Debug, Clone, PartialEq)]
struct VehicleAttitude {
    timestamp: u64,
    q: [f32; 4],
    /// Read from files that have it, `None` from those that do not.
    yawspeed: Option<f32>,
    #[ulog(rename = "source")]
    estimator: Chars<8>,
}

/// Reads `esc_status` with the wrong type for `esc_rpm`.
#[derive(ULog, Debug)]
#[ulog(name = "esc_report")]
struct WrongReport {
    esc_rpm: f32,
}

#[derive(ULog, Debug)]
#[ulog(name = "esc_status")]
struct WrongStatus {
    timestamp: u64,
    esc: [WrongReport; 4],
    temperature: f32,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::temp_dir().join(format!("typed_roundtrip_{}.ulg", std::process::id()));

    // Writing: formats (nested ones included, each once) come from the types.
    let mut w = Writer::create(&path, WriterOptions::default())?;
    w.info("sys_name", &Value::String("typed-rover".into()))?;
    w.parameter("MC_ROLL_P", ParamValue::Float(6.5))?;
    w.define::<EscStatus>()?;
    w.define::<VehicleAttitude>()?;
    let esc = [w.topic::<EscStatus>(0)?, w.topic::<EscStatus>(1)?];
    let attitude = w.topic::<VehicleAttitude>(0)?;
    for i in 0..5u64 {
        let t = 1_000_000 + i * 20_000;
        for (k, sub) in esc.iter().enumerate() {
            let report = |m: i32| EscReport {
                esc_rpm: 1_200 + 100 * m + i as i32 + 1_000 * k as i32,
                esc_voltage: 15.9 - i as f32 * 0.01,
                esc_state: 2,
                _pad: [0; 3],
            };
            let status = EscStatus {
                timestamp: t + k as u64,
                esc_count: 4,
                _pad: [0; 3],
                esc: [report(0), report(1), report(2), report(3)],
            };
            w.write(sub, &status)?;
        }
        let half = std::f32::consts::FRAC_1_SQRT_2;
        let value = VehicleAttitude {
            timestamp: t + 10,
            q: [half, 0.0, 0.0, half],
            yawspeed: Some(0.1 * i as f32),
            estimator: Chars::new("ekf2").ok_or("text too long")?,
        };
        w.write(&attitude, &value)?;
    }
    w.flush()?;
    drop(w);

    // Reading: each struct is checked against the file's format of its name, once.
    let log = Log::open(&path)?;
    for format in log.metadata().schema().formats() {
        println!("format {format}");
    }
    let topic = log.topic::<EscStatus>()?;
    println!("\nesc_status instances: {:?}", topic.multi_ids());
    for status in topic.instance(1)? {
        let rpm: Vec<i32> = status.esc.iter().map(|e| e.esc_rpm).collect();
        println!("  t={} esc_rpm={rpm:?}", status.timestamp);
    }
    println!("\nall instances in file order:");
    for (multi_id, status) in topic.rows().take(4) {
        println!("  [{multi_id}] t={}", status.timestamp);
    }
    let attitudes: Vec<VehicleAttitude> = log.topic::<VehicleAttitude>()?.instance(0)?.collect();
    let last = attitudes.last().ok_or("no attitude rows")?;
    println!(
        "\nvehicle_attitude: {} rows, last q={:?} yawspeed={:?} source={}",
        attitudes.len(),
        last.q,
        last.yawspeed,
        last.estimator
    );

    // A struct that does not match is an error naming every difference, before any row.
    match log.topic::<WrongStatus>() {
        Ok(_) => return Err("WrongStatus should not match".into()),
        Err(e) => println!("\nWrongStatus: {e}"),
    }
    std::fs::remove_file(&path)?;
    Ok(())
}
