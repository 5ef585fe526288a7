use ulog_runtime::ULog;

#[derive(ULog)]
struct Gps {
    timestamp: u64,
    #[ulog(rename = "alt.msl")]
    alt: f32,
    _padding0: u8,
}

fn main() {}
