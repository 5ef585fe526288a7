#![no_main]
//! See `ulog_fuzz::rewrite`.
libfuzzer_sys::fuzz_target!(|data: &[u8]| ulog_fuzz::rewrite(data));
