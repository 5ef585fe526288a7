#![no_main]
//! See `ulog_fuzz::format_roundtrip`.
libfuzzer_sys::fuzz_target!(|data: &[u8]| ulog_fuzz::format_roundtrip(data));
