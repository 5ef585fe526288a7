//! Types from PX4 `.msg` files: `examples/build.rs` turns the `.msg` files of
//! `examples/msg` into Rust structs laid out exactly as PX4's logger writes them (fields
//! sorted by size, `_paddingN` inserted), with the files' constants and `# TOPICS`. This
//! program writes a log with them, under both topic names, and reads it back.
//!
//! ```text
//! cargo run -p examples --example from_msg
//! ```

use examples::rover::{RoverStatus, WheelReport};
use ulog_runtime::{Log, ULog, Writer, WriterOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The layout PX4 would log: largest types first, padding before the nested wheels.
    println!("{}", RoverStatus::FORMAT.to_format());
    println!("{}", WheelReport::FORMAT.to_format());
    println!("topics: {:?}", RoverStatus::FORMAT.topics);
    println!(
        "constants: MODE_MISSION = {}, MAX_SPEED_M_S = {}",
        RoverStatus::MODE_MISSION,
        RoverStatus::MAX_SPEED_M_S
    );

    let path = std::env::temp_dir().join("from_msg.ulg");
    let mut w = Writer::create(&path, WriterOptions::default())?;
    let status = w.topic::<RoverStatus>(0)?;
    let backup = w.topic_as::<RoverStatus>("rover_status_backup", 0)?;
    for step in 0..3u64 {
        let wheel = WheelReport {
            rpm: 120 * step as i32,
            current_a: 1.5,
            fault_flags: 0,
            _padding0: [0; 7],
        };
        let row = RoverStatus {
            timestamp: 1_000_000 + step * 100_000,
            speed_m_s: 0.5 * step as f32,
            mode: RoverStatus::MODE_MISSION,
            armed: true,
            _padding0: [0; 2],
            wheels: [wheel; 4],
        };
        w.write(&status, &row)?;
        w.write(&backup, &row)?;
    }
    w.flush()?;
    drop(w);
    println!("wrote {}", path.display());

    let log = Log::open(&path)?;
    for topic in RoverStatus::FORMAT.topics {
        let rows: Vec<RoverStatus> = log.topic_as::<RoverStatus>(topic)?.instance(0)?.collect();
        let last = rows.last().ok_or("no rows")?;
        println!(
            "{topic}: {} rows, last at {} µs: {} m/s, wheel 0 at {} rpm",
            rows.len(),
            last.timestamp,
            last.speed_m_s,
            last.wheels[0].rpm
        );
    }
    Ok(())
}
