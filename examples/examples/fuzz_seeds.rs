//! Writes seed inputs for the fuzz targets (`fuzz/`), made by the writer and from the
//! project's own example definitions, never from the corpus logs:
//!
//! ```text
//! cargo run -p examples --example fuzz_seeds -- fuzz/corpus
//! ```
//! One folder per target: logs for `whole_file` and `codegen_log`, chunk sizes and a log for
//! `stream_chunks`, format strings for `format_roundtrip` and `layout`, a format and a row for
//! `typed`, TOML and `.msg` text for `codegen_text`, operation bytes for `writer_ops`.

use std::path::Path;

use ulog_runtime::read::ParamValue;
use ulog_runtime::{Scalar, Value, Writer, WriterOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "fuzz/corpus".to_owned());
    let root = Path::new(&root);
    let put = |target: &str, name: &str, bytes: &[u8]| -> std::io::Result<()> {
        let dir = root.join(target);
        std::fs::create_dir_all(&dir)?;
        std::fs::write(dir.join(name), bytes)
    };
    let logs = [("small", log(3, false)?), ("rich", log(40, true)?)];
    for (name, bytes) in &logs {
        put("whole_file", name, bytes)?;
        put("codegen_log", name, bytes)?;
        for (k, sizes) in [[0u8, 1, 2], [7, 200, 3]].iter().enumerate() {
            let mut seed = vec![sizes.len() as u8];
            seed.extend_from_slice(sizes);
            seed.extend_from_slice(bytes);
            put("stream_chunks", &format!("{name}{k}"), &seed)?;
        }
    }
    let formats = [
        "vehicle_attitude:uint64_t timestamp;float[4] q;uint8_t[4] _padding0;",
        "esc_report:int32_t esc_rpm;float esc_voltage;uint8_t[4] _padding0;",
        "esc_status:uint64_t timestamp;uint8_t esc_count;uint8_t[7] _padding0;esc_report[8] esc;",
        "t:char[10] name;bool b;double d;int64_t i;uint16_t[2] u;",
    ];
    for (i, f) in formats.iter().enumerate() {
        put("format_roundtrip", &format!("f{i}"), f.as_bytes())?;
    }
    put("layout", "nested", formats.join("\n").as_bytes())?;
    let mut typed = b"cell:int16_t v;uint8_t[2] _padding0;float t;|fuzz_topic:uint64_t timestamp;cell[3] cells;char[5] name;bool ok;double[2] q;uint32_t extra;\n".to_vec();
    typed.extend((0..80u8).map(|b| b.wrapping_mul(37)));
    put("typed", "row", &typed)?;
    let examples = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut toml = vec![0u8];
    toml.extend(std::fs::read(examples.join("topics.toml"))?);
    put("codegen_text", "topics.toml", &toml)?;
    for entry in std::fs::read_dir(examples.join("msg"))? {
        let path = entry?.path();
        let mut msg = vec![1u8];
        msg.extend(std::fs::read(&path)?);
        put(
            "codegen_text",
            &path.file_name().unwrap().to_string_lossy(),
            &msg,
        )?;
    }
    for (i, ops) in [
        &[0u8, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 0, 20, 1, 2, 3][..],
        &[
            9, 9, 9, 9, 9, 9, 9, 9, 4, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 2, 6, 5, 30, 7, 2, 5,
            b'h', b'e',
        ],
    ]
    .iter()
    .enumerate()
    {
        put("writer_ops", &format!("ops{i}"), ops)?;
    }
    println!("seeds written under {}", root.display());
    Ok(())
}

/// A log with every kind of message the writer writes, `rows` rows per topic.
fn log(rows: u64, rich: bool) -> Result<Vec<u8>, ulog_runtime::WriteError> {
    let mut w = Writer::new(
        Vec::new(),
        WriterOptions {
            start_timestamp: 1_000,
            default_parameters: rich,
        },
    )?;
    w.format("esc_report:int32_t esc_rpm;float esc_voltage;uint8_t[4] _padding0;")?;
    w.format("esc_status:uint64_t timestamp;uint8_t esc_count;uint8_t[7] _padding0;esc_report[2] esc;char[4] name;")?;
    w.format("event:uint64_t timestamp;uint32_t id;uint16_t event_sequence;uint8_t[25] arguments;uint8_t log_levels;")?;
    w.info("sys_name", &Value::String("PX4".into()))?;
    w.info(
        "ver_sw_release",
        &Value::Scalar(Scalar::UInt32(0x010F_01FF)),
    )?;
    w.multi_info("boot", &Value::String("part one ".into()), false)?;
    w.multi_info("boot", &Value::String("part two".into()), true)?;
    w.parameter("MC_ROLL_P", ParamValue::Float(6.5))?;
    w.parameter("SYS_AUTOSTART", ParamValue::Int32(4001))?;
    if rich {
        w.default_parameter("MC_ROLL_P", ParamValue::Float(7.0), 1)?;
    }
    let esc = w.subscribe("esc_status", 0)?;
    let esc1 = w.subscribe("esc_status", 1)?;
    let event = w.subscribe("event", 0)?;
    for i in 0..rows {
        for id in [esc, esc1] {
            let mut row = (1_000 + i * 10_000).to_le_bytes().to_vec();
            row.extend_from_slice(&[2, 0, 0, 0, 0, 0, 0, 0]);
            for e in 0..2i32 {
                row.extend_from_slice(&(1000 * e + i as i32).to_le_bytes());
                row.extend_from_slice(&(0.5f32 * i as f32).to_le_bytes());
                row.extend_from_slice(&[0; 4]);
            }
            row.extend_from_slice(b"ab\0\0");
            w.data(id, &row)?;
        }
        if i % 5 == 0 {
            let mut row = (1_000 + i * 10_000).to_le_bytes().to_vec();
            row.extend_from_slice(&((1u32 << 24) | 5).to_le_bytes());
            row.extend_from_slice(&(i as u16).to_le_bytes());
            row.extend_from_slice(&[i as u8; 25]);
            row.push(0x66);
            w.data(event, &row)?;
        }
        if rich && i == 7 {
            w.log(b'4', 1_000 + i * 10_000, "low battery")?;
            w.log_tagged(b'6', 3, 1_000 + i * 10_000, "tagged")?;
            w.parameter("MC_ROLL_P", ParamValue::Float(6.75))?;
            w.dropout(25)?;
            w.sync()?;
        }
    }
    Ok(w.into_inner())
}
