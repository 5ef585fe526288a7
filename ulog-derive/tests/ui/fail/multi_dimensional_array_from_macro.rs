use ulog_runtime::ULog;

// A type given to a macro (`$t:ty`) reaches the derive wrapped in an invisible group: still
// one error, the derive's.
macro_rules! topic {
    ($t:ty) => {
        #[derive(ULog)]
        struct Covariance {
            timestamp: u64,
            matrix: $t,
        }
    };
}

topic!([[f32; 3]; 3]);

fn main() {}
