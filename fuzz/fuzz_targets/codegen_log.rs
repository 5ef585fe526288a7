#![no_main]
//! See `ulog_fuzz::codegen_log`.
libfuzzer_sys::fuzz_target!(|data: &[u8]| ulog_fuzz::codegen_log(data));
