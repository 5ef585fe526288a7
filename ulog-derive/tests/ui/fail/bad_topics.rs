use ulog_runtime::ULog;

#[derive(ULog)]
#[ulog(topics("vehicle_attitude", "estimator attitude", "vehicle_attitude", "float"))]
struct VehicleAttitude {
    timestamp: u64,
    q: [f32; 4],
}

#[derive(ULog)]
#[ulog(topics())]
struct Empty {
    timestamp: u64,
}

fn main() {}
