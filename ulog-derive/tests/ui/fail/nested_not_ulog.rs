use ulog_runtime::ULog;

struct Wheel {
    rpm: f32,
}

#[derive(ULog)]
struct Rover {
    timestamp: u64,
    wheels: [Wheel; 4],
    front: Wheel,
}

fn main() {}
