use ulog_runtime::ULog;

// A field is in a file or not: an `Option` inside an `Option` has no form there (its inner
// `None` would be written as zeros and read back as `Some(Some(0.0))`).
#[derive(ULog)]
struct Reading {
    timestamp: u64,
    maybe: Option<Option<f32>>,
    fine: Option<[u16; 2]>,
}

fn main() {}
