use ulog_runtime::ULog;

#[derive(ULog)]
#[ulog(topic = "attitude")]
struct Attitude {
    timestamp: u64,
    #[ulog(skip)]
    roll: f32,
}

fn main() {}
