//! By hand: lays out a small ULog file in memory, message by message as the specification
//! describes them (a nested, padded format included), then reads it back two ways.
//!
//! ```text
//! cargo run -p examples --example by_hand
//! ```

use ulog_runtime::read::{FileHeader, FlagBits, KeyValue, Message};
use ulog_runtime::{Event, Log, StreamReader};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let bytes = build_log()?;
    println!("built a {}-byte log in memory\n", bytes.len());

    // 1. The whole-file view: zero-copy over the bytes (or `Log::open(path)` for a memory map).
    let log = Log::from_slice(&bytes)?;
    let meta = log.metadata();
    println!(
        "version {}, started at {} µs",
        log.header().version,
        log.header().start_timestamp
    );
    for info in meta.info() {
        println!("info  {} ({}) = {}", info.key, info.type_name, info.value);
    }
    for p in meta.initial_parameters() {
        println!("param {} = {}", p.name, p.value);
    }
    for format in meta.schema().formats() {
        println!("format {format}");
    }
    for sub in log.subscriptions() {
        println!(
            "\n{} (multi_id {}, msg_id {}):",
            sub.name, sub.multi_id, sub.msg_id
        );
        for row in log.rows(sub) {
            let value = row.value().ok_or("row does not decode")?;
            println!("  t={:>7} µs  {value}", row.timestamp);
        }
        if let Some(row) = log.rows(sub).next() {
            let plan = row.plan().ok_or("no plan")?;
            let names: Vec<String> = plan
                .columns(row.schema())
                .into_iter()
                .map(|c| c.name)
                .collect();
            println!("  columns: {}", names.join(", "));
        }
    }
    for m in log.logged_messages() {
        println!(
            "\nlogged [{}] {}",
            m.level().map_or("?", |l| l.name()),
            m.text
        );
    }

    // 2. Streaming over any `io::Read`, with memory bounded by a few messages.
    let mut reader = StreamReader::new(&bytes[..])?;
    let mut rows = 0;
    while let Some(event) = reader.next_event()? {
        match event {
            Event::Row(_) => rows += 1,
            Event::Diagnostic(d) => println!("diagnostic: {d}"),
            _ => {}
        }
    }
    println!(
        "streamed {rows} rows; diagnostics: {}",
        log.diagnostics().len()
    );
    Ok(())
}

/// A version-1 log: flag bits, two formats (`esc_report` is nested in `esc_status`, with
/// inner and trailing padding), info, a parameter, a subscription, three rows, a logged string.
fn build_log() -> Result<Vec<u8>, Box<dyn std::error::Error>> {
    let mut out = FileHeader {
        version: 1,
        start_timestamp: 1_000_000,
    }
    .to_bytes()
    .to_vec();
    let mut put = |m: Message<'_>| m.encode(&mut out);
    put(Message::FlagBits(FlagBits::default()))?;
    // A nested type may be used before it is defined.
    put(Message::Format(
        b"esc_status:uint64_t timestamp;uint8_t esc_count;uint8_t[7] _padding0;esc_report[2] esc;",
    ))?;
    put(Message::Format(
        b"esc_report:int32_t esc_rpm;float esc_voltage;uint8_t esc_state;uint8_t[3] _padding0;",
    ))?;
    put(Message::Info(KeyValue {
        key: b"char[8] sys_name",
        value: b"quickrov",
    }))?;
    put(Message::Parameter(KeyValue {
        key: b"float MPC_XY_VEL_MAX",
        value: &12.0f32.to_le_bytes(),
    }))?;
    put(Message::Subscribe {
        multi_id: 0,
        msg_id: 0,
        name: b"esc_status",
    })?;
    for step in 0..3u32 {
        let mut row = (1_000_000 + u64::from(step) * 10_000)
            .to_le_bytes()
            .to_vec();
        row.push(2); // esc_count
        row.extend_from_slice(&[0; 7]); // padding
        for esc in 0..2u32 {
            let rpm = 1000 * (esc as i32 + 1) + step as i32 * 10;
            row.extend_from_slice(&rpm.to_le_bytes());
            row.extend_from_slice(&(15.0f32 + 0.25 * esc as f32).to_le_bytes());
            row.push(1); // esc_state
            row.extend_from_slice(&[0; 3]); // padding inside the nested type
        }
        put(Message::Data {
            msg_id: 0,
            data: &row,
        })?;
    }
    put(Message::Logging {
        level: b'6',
        tag: None,
        timestamp: 1_030_000,
        text: b"takeoff",
    })?;
    Ok(out)
}
