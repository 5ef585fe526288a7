use ulog_runtime::ULog;

#[derive(ULog)]
struct Gps {
    timestamp: u64,
    alt: f32,
    #[ulog(rename = "alt")]
    altitude_ellipsoid: f32,
}

fn main() {}
