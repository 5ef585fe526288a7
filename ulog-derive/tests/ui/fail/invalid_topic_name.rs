use ulog_runtime::ULog;

#[derive(ULog)]
#[ulog(name = "vehicle attitude")]
struct Attitude {
    timestamp: u64,
}

#[derive(ULog)]
#[ulog(name = "float")]
struct Basic {
    timestamp: u64,
}

fn main() {}
