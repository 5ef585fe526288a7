use ulog_runtime::ULog;

#[derive(ULog)]
struct Attitude {
    timestamp: f64,
    roll: f32,
}

fn main() {}
