use ulog_runtime::ULog;

#[derive(ULog)]
#[ulog(exact, widen)]
struct Battery {
    timestamp: u64,
    #[ulog(widen)]
    cell_count: i32,
    #[ulog(padding, widen)]
    _pad: [u8; 4],
}

fn main() {}
