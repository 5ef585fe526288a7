//! Generates the examples' topic types with the runtime's build-script generator:
//! `OUT_DIR/topics.rs` from `topics.toml` and a format string, and `OUT_DIR/rover.rs` from
//! the PX4 `.msg` files of `msg/` (both included by `src/lib.rs`).

fn main() -> Result<(), Box<dyn std::error::Error>> {
    ulog_runtime::codegen::Builder::new()
        .toml("topics.toml")
        // PX4's `vehicle_attitude` as `pyulog/sample_log_small.ulg` defines it.
        .format("vehicle_attitude:uint64_t timestamp;float[4] q;float[4] delta_q_reset;uint8_t quat_reset_counter;uint8_t[7] _padding0;")
        .derive("Copy")
        .generate("topics.rs")?;
    ulog_runtime::codegen::Builder::new()
        .msg_dir("msg")
        .derive("Copy")
        .generate("rover.rs")?;
    Ok(())
}
