//! Generates the examples' topic types (`OUT_DIR/topics.rs`, included by `src/lib.rs`) from
//! `topics.toml` and a format string, with the runtime's build-script generator.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    ulog_runtime::codegen::Builder::new()
        .toml("topics.toml")
        .format("vehicle_attitude:uint64_t timestamp;float[4] q;float[3] delta_q_reset;uint8_t quat_reset_counter;uint8_t[3] _padding0;")
        .derive("Copy")
        .generate("topics.rs")?;
    Ok(())
}
