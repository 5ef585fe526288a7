#![no_main]
//! See `ulog_fuzz::layout`.
libfuzzer_sys::fuzz_target!(|data: &[u8]| ulog_fuzz::layout(data));
