use ulog_runtime::ULog;

#[derive(ULog)]
struct Sample<T> {
    timestamp: u64,
    value: T,
}

fn main() {}
