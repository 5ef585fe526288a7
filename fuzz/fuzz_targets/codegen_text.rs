#![no_main]
//! See `ulog_fuzz::codegen_text`.
libfuzzer_sys::fuzz_target!(|data: &[u8]| ulog_fuzz::codegen_text(data));
