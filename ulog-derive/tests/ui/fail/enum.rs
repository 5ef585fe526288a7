use ulog_runtime::ULog;

#[derive(ULog)]
enum Mode {
    Manual,
    Auto,
}

fn main() {}
