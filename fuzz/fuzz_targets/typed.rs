#![no_main]
//! See `ulog_fuzz::typed`.
libfuzzer_sys::fuzz_target!(|data: &[u8]| ulog_fuzz::typed(data));
