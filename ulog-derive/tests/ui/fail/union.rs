use ulog_runtime::ULog;

#[derive(ULog)]
union Bits {
    f: f32,
    u: u32,
}

fn main() {}
