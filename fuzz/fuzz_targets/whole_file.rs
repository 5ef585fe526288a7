#![no_main]
//! See `ulog_fuzz::whole_file`.
libfuzzer_sys::fuzz_target!(|data: &[u8]| ulog_fuzz::whole_file(data));
