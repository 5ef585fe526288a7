use ulog_runtime::ULog;

#[derive(ULog)]
#[ulog(padding)]
struct Report {
    #[ulog(exact)]
    rpm: i32,
}

fn main() {}
