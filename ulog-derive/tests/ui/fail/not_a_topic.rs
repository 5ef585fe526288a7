use ulog_runtime::{ULog, Writer, WriterOptions};

// No `timestamp`: this type can only be nested.
#[derive(ULog)]
struct EscReport {
    esc_rpm: i32,
}

fn main() {
    let mut w = Writer::new(Vec::new(), WriterOptions::default()).unwrap();
    let _ = w.topic::<EscReport>(0);
}
