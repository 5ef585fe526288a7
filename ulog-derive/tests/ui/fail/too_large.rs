use ulog_runtime::ULog;

#[derive(ULog)]
struct Block {
    samples: [f64; 4096],
}

#[derive(ULog)]
struct Huge {
    timestamp: u64,
    blocks: [Block; 3],
}

fn main() {}
