use ulog_runtime::ULog;

#[derive(ULog)]
#[ulog(name = "attitude")]
#[ulog(name = "vehicle_attitude")]
struct Attitude {
    timestamp: u64,
    #[ulog(rename = "r", rename = "roll_rad")]
    roll: f32,
}

fn main() {}
