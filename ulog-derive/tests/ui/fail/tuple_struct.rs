use ulog_runtime::ULog;

#[derive(ULog)]
struct Position(u64, f32, f32);

fn main() {}
