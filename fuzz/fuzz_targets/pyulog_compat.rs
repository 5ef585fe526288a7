#![no_main]
//! See `ulog_fuzz::pyulog_compat`.
libfuzzer_sys::fuzz_target!(|data: &[u8]| ulog_fuzz::pyulog_compat(data));
