use ulog_runtime::ULog;

#[derive(ULog)]
struct Covariance {
    timestamp: u64,
    matrix: [[f32; 3]; 3],
}

fn main() {}
