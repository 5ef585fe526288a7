use ulog_runtime::ULog;

#[derive(ULog)]
struct Telemetry {
    timestamp: u64,
    name: String,
    samples: Vec<f32>,
    count: usize,
    letter: char,
    label: &'static str,
}

fn main() {}
