//! Quickstart: write a small flight log from typed topics (to `quickstart.ulg` in the
//! system's temporary folder, path printed), then read it back three ways: typed, dynamic,
//! and streaming. No input file needed.
//!
//! The topic types come from two places: `BatteryStatus` (with a nested `BatteryCell`) and
//! `VehicleAttitude` are generated at build time from `examples/topics.toml` and a format
//! string (see `examples/build.rs`); `Gps` is a struct with `#[derive(ULog)]`.
//!
//! ```text
//! cargo run -p examples --example quickstart
//! ```

use examples::topics::{BatteryCell, BatteryStatus, VehicleAttitude};
use ulog_runtime::read::ParamValue;
use ulog_runtime::{Event, Log, LogLevel, StreamReader, ULog, Value, Writer, WriterOptions};

/// A topic written by hand: the derive makes it a ULog format named `gps`.
#[derive(ULog, Debug, Clone, PartialEq)]
struct Gps {
    timestamp: u64,
    lat_deg: f64,
    lon_deg: f64,
    alt_m: f32,
    satellites: u8,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // 1. Write: formats (nested ones included) come from the types; declare every topic
    // before the first row.
    let path = std::env::temp_dir().join("quickstart.ulg");
    let mut w = Writer::create(&path, WriterOptions::default())?;
    w.info("sys_name", &Value::String("quickrover".into()))?;
    w.parameter("BAT_N_CELLS", ParamValue::Int32(4))?;
    let battery = w.topic::<BatteryStatus>(0)?;
    let attitude = w.topic::<VehicleAttitude>(0)?;
    let gps = w.topic::<Gps>(0)?;
    for step in 0..5u64 {
        let t = 1_000_000 + step * 100_000;
        let cell = BatteryCell {
            voltage_v: 4.1 - step as f32 * 0.01,
            temperature: 215,
            _padding0: [0; 2],
        };
        w.write(
            &battery,
            &BatteryStatus {
                timestamp: t,
                voltage_v: cell.voltage_v * 4.0,
                current_a: 12.5,
                remaining: 0.9 - step as f32 * 0.01,
                cell_count: 4,
                connected: true,
                _padding0: [0; 2],
                cells: [cell; 4],
            },
        )?;
        let yaw = step as f32 * 0.1;
        w.write(
            &attitude,
            &VehicleAttitude {
                timestamp: t + 10,
                q: [(yaw / 2.0).cos(), 0.0, 0.0, (yaw / 2.0).sin()],
                delta_q_reset: [0.0; 4],
                quat_reset_counter: 0,
                _padding0: [0; 7],
            },
        )?;
        w.write(
            &gps,
            &Gps {
                timestamp: t + 20,
                lat_deg: 47.397742 + step as f64 * 1e-5,
                lon_deg: 8.545594,
                alt_m: 488.0,
                satellites: 14,
            },
        )?;
    }
    w.log(LogLevel::Info, 1_450_000, "landed")?;
    w.flush()?;
    drop(w);
    let bytes = std::fs::read(&path)?;
    println!(
        "wrote a {}-byte log to {} (try `ulog info` on it)\n",
        bytes.len(),
        path.display()
    );

    // 2. Read typed: each type is checked against the file's own format, once.
    let log = Log::from_slice(&bytes)?;
    for format in log.metadata().schema().formats() {
        println!("format {format}");
    }
    println!();
    for b in log.topic::<BatteryStatus>()?.instance(0)? {
        println!(
            "battery  t={} {:.2} V, cell 0 {:.2} V at {:.1} °C, {:.0}% left",
            b.timestamp,
            b.voltage_v,
            b.cells[0].voltage_v,
            f32::from(b.cells[0].temperature) / 10.0,
            b.remaining * 100.0
        );
    }
    let last: Gps = log
        .topic::<Gps>()?
        .instance(0)?
        .last()
        .ok_or("no gps rows")?;
    println!("last gps fix: {last:?}");

    // 3. Read dynamically: any format, values by name.
    let sub = log
        .subscription("vehicle_attitude", 0)
        .ok_or("no attitude")?;
    for row in log.rows(sub).take(2) {
        let q = row.value().ok_or("row does not decode")?;
        println!(
            "attitude t={} q={}",
            row.timestamp,
            q.field("q").ok_or("no q")?
        );
    }
    for m in log.logged_messages() {
        println!(
            "logged [{}] {}",
            m.level().map_or("?", |l| l.name()),
            m.text
        );
    }

    // 4. Stream over any `io::Read`, memory bounded by a few messages, decoding one topic typed.
    let mut reader = StreamReader::new(&bytes[..])?;
    let mut decoder = None;
    let mut fixes = 0;
    while let Some(event) = reader.next_event()? {
        match event {
            Event::Subscription(s) if s.name == "gps" => decoder = Some(reader.typed::<Gps>()?),
            Event::Row(row) => {
                fixes += usize::from(decoder.as_ref().and_then(|d| d.decode_row(&row)).is_some());
            }
            Event::Diagnostic(d) => println!("diagnostic: {d}"),
            _ => {}
        }
    }
    println!("streamed {fixes} gps fixes");
    Ok(())
}
