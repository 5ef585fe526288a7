use ulog_runtime::ULog;

#[derive(ULog)]
struct Report {
    rpm: i32,
    #[ulog(padding)]
    _pad: [u16; 2],
}

fn main() {}
