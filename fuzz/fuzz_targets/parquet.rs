#![no_main]
//! See `ulog_fuzz::parquet`.
libfuzzer_sys::fuzz_target!(|data: &[u8]| ulog_fuzz::parquet(data));
