use ulog_runtime::ULog;

#[derive(ULog)]
struct Heartbeat;

fn main() {}
